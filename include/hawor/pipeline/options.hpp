// hawor/pipeline/options.hpp — the options of the whole pipeline (pipeline.hpp), with the defaults
// the browser app, `node web/cli.mjs run` and `hawor world` use.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>
#include <string>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/motion/infill.hpp"
#include "hawor/pipeline/keypoint_flow.hpp"

namespace hawor {

template <typename Scalar>
struct PipelineOptions {
  // --- the video ---
  PinholeCamera<Scalar> camera;          ///< intrinsics at the video's size (width, height set)
  std::string lens = "pinhole";          ///< 'pinhole', 'opencv:k1,k2,p1,p2[,k3]' or 'fisheye:k1..k4' (geometry/lens.hpp)
  Scalar fps = Scalar(30);
  /// The frames come from a live source that drops frames while the pipeline is busy (a camera):
  /// fps stays the camera's (the rolling shutter's), but the frames given are already thinned,
  /// so the SLAM tracks every one of them (no SlamOptions::frameStep at a high camera rate).
  bool liveSource = false;
  /// Rolling shutter: seconds from the first row's exposure to the last's (0: global shutter; at
  /// most one frame interval; negative: rows read bottom to top).
  Scalar readout = Scalar(0);
  // --- SLAM ---
  int slamMaxSide = 640;                 ///< the SLAM and the hand masks run at this long side
  int maskDilatePx = 2;                  ///< hand masks grown by this many pixels (SLAM resolution)
  /// A hand the perception stops finding stays masked from the SLAM at its last fitted pose for
  /// this long (seconds; 0: off): a hand that vanishes was more often missed than gone.
  Scalar maskHoldSeconds = Scalar(0.5);
  bool refineFocal = true;               ///< the SLAM's final bundle adjustment refines the focal
  /// Std of log(f / guess) of the focal prior; NaN: 0.1 for a focal the user gave, else 0.3 (a
  /// field-of-view guess).
  Scalar focalPriorSigma = std::numeric_limits<Scalar>::quiet_NaN();
  bool userFocal = false;                ///< the focal came from the user (not a field-of-view guess)
  int focalMaxPasses = 4;                ///< SLAM passes at most while the refined focal moves
  /// The SLAM's frames and masks are kept up to this many bytes for those further passes (0:
  /// none; the focal is then refined in the final bundle adjustment only).
  std::size_t focalRerunBytes = std::size_t(256) << 20;
  std::string slamSet;                   ///< "NAME=VALUE,..." over SlamOptions (ablations; slam_option_table.hpp)
  // --- hands ---
  /// The keypoint flow (keypoint_flow.hpp): a hand's keypoints carried from the last frame by
  /// KLT stand in for the landmark network on up to flow.maxSkip frames in a row (0: off).
  KeypointFlowOptions<Scalar> flow;
  /// A fit is believed when its wrist lies this far in front of the camera (metres): behind the
  /// camera or absurdly far is not a hand.
  Scalar minHandDepth = Scalar(0.03), maxHandDepth = Scalar(5);
  InfillMethod infill = InfillMethod::Spline;
  int handScaleSmooth = 0;               ///< experiment: moving-average half-width of the wrists before the hand cue
  // --- the output ---
  /// The world: gravity-aligned, z up, the origin on the floor below the first camera
  /// (world_frame.hpp); false: the first camera's frame (x right, y down, z forward).
  bool gravityAligned = true;
  // --- metric scale ---
  bool groundScale = true;               ///< the ground cue: the cameras' height above the map's floor
  Scalar eyeHeight = Scalar(1.6);        ///< that height in metres (a standing adult's head camera)
  /// Keep every frame's hand mask for the depth cue (finish() is then given keyframe depth maps).
  bool depthMasks = false;

  /// Throws hawor::Error naming the first invalid option.
  void validate() const {
    camera.validate();
    if (!(fps > Scalar(0)) || !std::isfinite(double(fps))) throw Error("pipeline: fps must be finite and > 0, not " + std::to_string(double(fps)));
    if (!(std::abs(readout) <= Scalar(1) / fps)) {
      throw Error("pipeline: the rolling-shutter readout " + std::to_string(double(readout)) + " s must lie within one frame interval (±" +
                  std::to_string(double(Scalar(1) / fps)) + " s)");
    }
    if (slamMaxSide < 16) throw Error("pipeline: slamMaxSide must be >= 16");
    if (maskDilatePx < 0 || maskDilatePx > 64) throw Error("pipeline: maskDilatePx must be in [0, 64]");
    if (!(maskHoldSeconds >= Scalar(0) && maskHoldSeconds <= Scalar(10))) throw Error("pipeline: maskHoldSeconds must be in [0, 10] s");
    if (!std::isnan(double(focalPriorSigma)) && !(focalPriorSigma > Scalar(0))) throw Error("pipeline: focalPriorSigma must be > 0");
    if (focalMaxPasses < 1) throw Error("pipeline: focalMaxPasses must be >= 1");
    if (!(minHandDepth >= Scalar(0) && maxHandDepth > minHandDepth)) throw Error("pipeline: need 0 <= minHandDepth < maxHandDepth");
    if (handScaleSmooth < 0) throw Error("pipeline: handScaleSmooth must be >= 0");
    flow.validate();
    if (!(eyeHeight >= Scalar(0.8) && eyeHeight <= Scalar(3))) {
      throw Error("pipeline: the camera height above the floor must be between 0.8 and 3 m, not " + std::to_string(double(eyeHeight)));
    }
  }

  Scalar priorSigma() const { return std::isnan(double(focalPriorSigma)) ? (userFocal ? Scalar(0.1) : Scalar(0.3)) : focalPriorSigma; }
};

}  // namespace hawor
