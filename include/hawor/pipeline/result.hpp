// hawor/pipeline/result.hpp — what the pipeline (pipeline.hpp) returns: the camera in metres, both
// hands in the camera and the world frame, the metric scale and how it was chosen, the focal, and
// what went wrong on the way. The exports (JSON, npz, glTF, TUM) and the viewer read it.
#pragma once

#include <array>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/motion/hand_motion.hpp"
#include "hawor/pipeline/world_frame.hpp"
#include "hawor/scale/metric_scale.hpp"
#include "hawor/slam/mono_slam.hpp"

namespace hawor {

/// One side's hand over the clip. Frames where the hand was not observed hold NaN in the
/// camera-frame arrays; the world motion is filled there (infilled).
template <typename Scalar>
struct PipelineHand {
  bool present = false;                  ///< observed (and believed) on at least one frame
  ValidMask valid;                       ///< (T) observed and believed
  ValidMask infilled;                    ///< (T) filled by the infiller
  HandMotion<Scalar> camera;             ///< camera frame, metres (NaN where not valid)
  HandMotion<Scalar> world;              ///< world frame, metres (filled; NaN where never seen)
  Sequence<Scalar> jointsCam;            ///< (T, 63) fitted keypoints, camera frame (NaN where not valid)
  Sequence<Scalar> jointsWorld;          ///< (T, 63) keypoints of the world motion
  Sequence<Scalar> keypoints2d;          ///< (T, 42) the detected image keypoints (NaN where not detected)
  std::vector<Scalar> reprojRmsPx;       ///< (T) the fit's rms reprojection error (NaN where not valid)
};

/// The focal the output uses and how it was decided (at the video's resolution).
template <typename Scalar>
struct PipelineFocal {
  Scalar fx = Scalar(0), fy = Scalar(0);   ///< the output's (refined when refined)
  bool refined = false;
  int passes = 1;                          ///< SLAM passes (2+: run again with the refined focal)
  Scalar stdLog = std::numeric_limits<Scalar>::quiet_NaN();      ///< posterior std of log f (NaN: none)
  Scalar estimateFx = std::numeric_limits<Scalar>::quiet_NaN();  ///< the SLAM's estimate even when not applied
  std::string reason;                      ///< why refined / kept / declined ("off" when not asked)
};

/// The causal world of live mode (Pipeline::updateLiveWorld): the scale and the gravity-aligned
/// world from the frames so far; scale 1, method "none" and the first camera's frame until a cue
/// gives one.
template <typename Scalar>
struct LiveWorld {
  int frames = 0;                   ///< the frames it was computed from
  Scalar scale = Scalar(1);         ///< metres per SLAM unit
  std::string scaleMethod = "none";
  Scalar scaleConfidence = Scalar(0);
  WorldFrame<Scalar> world;         ///< identity until a scale is known (and with gravityAligned off)
};

/// The last frame in the live world (Pipeline::live).
template <typename Scalar>
struct LiveFrame {
  int frame = -1;
  bool posed = false;                          ///< the tracker's map posed the camera (else held or guessed)
  Scalar scale = Scalar(1);                    ///< the live world's
  SE3<Scalar> cameraPose;                      ///< camera to world
  std::array<bool, 2> valid{false, false};     ///< left, right fitted on this frame
  std::array<Points3<Scalar>, 2> joints;       ///< (21, 3) world, where valid
};

template <typename Scalar>
struct PipelineResult {
  int frames = 0;
  Scalar fps = Scalar(30);
  std::vector<Scalar> times;        ///< (T) each frame's time in seconds (its stamp, else index / fps)
  PinholeCamera<Scalar> camera;            ///< the video's intrinsics (the focal refined when focal.refined)
  std::string lens = "pinhole";
  PipelineFocal<Scalar> focal;
  PinholeCamera<Scalar> slamCamera;        ///< the SLAM's virtual pinhole camera (its size, its focal)
  SlamResult<Scalar> slam;                 ///< in the SLAM's units (poses, points, keyframe depths, counts)
  MetricScaleResult<Scalar> scaleCues;     ///< every cue that ran
  Scalar scale = Scalar(1);                ///< metres per SLAM unit (1 with method "none")
  std::string scaleMethod = "none";        ///< depth | hands | ground | fused | none
  Scalar scaleConfidence = Scalar(0);
  WorldFrame<Scalar> world;                ///< the output's world and how it was found (up "none": the first camera's)
  std::vector<SE3<Scalar>> cameraPoses;    ///< camera-to-world, metres
  std::vector<Vec3<Scalar>> points;        ///< the SLAM's map, metres, in the output's world
  std::array<PipelineHand<Scalar>, 2> hands;  ///< left, right
  bool noHands = true;
  std::vector<std::string> warnings;
  std::map<std::string, double> timings;   ///< milliseconds per stage
};

}  // namespace hawor
