// hawor/slam/slam_result.hpp — what MonoSlam::finish() returns: per-frame camera poses and
// statuses, keyframes and their sparse depths (the metric-scale step's input), the final map
// points, and what the passes over the sequence did.
#pragma once

#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/slam/focal_refine.hpp"

namespace hawor {

/// Per-frame status of the SLAM output.
enum class SlamStatus : int {
  Tracked = 0,       ///< pose from the frame's features against the map
  Interpolated = 1,  ///< no map pose: rotation from the tracked rays or interpolation, position held/interpolated
  Lost = 2,          ///< tracking was lost here; the pose is interpolated between good frames
  Relocalised = 3,   ///< put back into the lost map (relocalisation), or the first frame of a re-initialised segment
};

inline const char* slamStatusName(SlamStatus s) {
  switch (s) {
    case SlamStatus::Tracked: return "tracked";
    case SlamStatus::Interpolated: return "interpolated";
    case SlamStatus::Lost: return "lost";
    case SlamStatus::Relocalised: return "relocalised";
  }
  return "unknown";
}

/// Sparse depths of one keyframe for the scale step: pixels and depths along the optical axis
/// (map units), of the map points it observes outside the hand masks.
template <typename Scalar>
struct SlamKeyframeDepths {
  int frame = 0;
  std::vector<Vec2<Scalar>> uv;
  std::vector<Scalar> depth;
};

template <typename Scalar>
struct SlamResult {
  std::vector<SE3<Scalar>> poses;     ///< T_w_c per frame, world = first frame's camera
  std::vector<SlamStatus> status;     ///< per frame
  std::vector<char> keyframe;         ///< per frame
  std::vector<int> inliers;           ///< per frame: PnP inliers (0 without a map pose)
  std::vector<SlamKeyframeDepths<Scalar>> keyframeDepths;
  std::vector<Vec3<Scalar>> points;   ///< final map points (world)
  int numKeyframes = 0;
  int numAdjustedKeyframes = 0;       ///< keyframes in the final global bundle adjustment (the others redundant)
  int numLosses = 0;                  ///< tracking-loss events (runs of Lost frames)
  int numResets = 0;                  ///< map re-initialisations (a reset undone by relocalisation is not one)
  int numRelocalisations = 0;         ///< lost frames put back into the map they had lost
  int numPlaceRelocalisations = 0;    ///< lost frames put into a map (the lost one or an older one) by place recognition
  int numRevisitPoints = 0;           ///< old map points found again by the revisit search
  int numPlaceLinks = 0;              ///< keyframes linked to an older one of the same place (SlamOptions::place)
  /// Those links: keyframe `frame` saw the place keyframe `oldFrame` had seen, verified by a
  /// Sim(3) over `points` matched map points (mono_slam/place_links.hpp); in the order found.
  struct PlaceLink {
    int frame = 0, oldFrame = 0, points = 0;
  };
  std::vector<PlaceLink> placeLinks;
  int numPlacedSegments = 0;          ///< map segments moved into an earlier one's world by those links
  int numRefinedFrames = 0;           ///< frames adjusted by the sequence refinement (0: not run)
  int numHeadModelFrames = 0;         ///< unposed frames placed by the head model
  bool initialised = false;           ///< a map was ever built (false: rotation-only output)
  PinholeCamera<Scalar> camera;       ///< the intrinsics of the output (refined when focal.changed)
  bool focalAttempted = false;        ///< SlamOptions::finish.refineFocal ran (false: off, or no map)
  FocalRefineResult<Scalar> focal;    ///< its outcome (reason says why declined / not applied)
  int count(SlamStatus s) const {
    int n = 0;
    for (SlamStatus t : status) n += t == s ? 1 : 0;
    return n;
  }
};

}  // namespace hawor
