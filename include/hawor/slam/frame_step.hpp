// hawor/slam/frame_step.hpp — tracking every k-th frame of a high-frame-rate video.
//
// The SLAM's thresholds were measured at 30 fps. At 60 fps the same motion tracked frame by
// frame came out worse even with its frame counts scaled to the rate (synthetic presets, seeds
// 1-8: geometric mean ATE 0.38 % of the path against 0.26 % at 30 fps), while the 30-fps
// rendering of a motion is exactly its 60-fps rendering with every other frame dropped. So
// MonoSlam tracks frames 0, k, 2k, … (SlamOptions::frameStep) and poses the frames between on
// the screw motion between their tracked neighbours, T(t) = T₀·exp(t·log(T₀⁻¹T₁)), t = r/k
// (geometry/interpolate.hpp): over 1/30 s a head's motion is close to a constant twist.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/interpolate.hpp"
#include "hawor/slam/slam_result.hpp"

namespace hawor {

/// The automatic frame step for a video at `fps`: the largest k whose tracked rate fps / k stays
/// at or above 25 fps (30, 50 and 60 fps → 1, 2, 2; 120 → 4), never below 1.
inline int autoFrameStep(double fps) {
  if (!(fps > 0.0) || !std::isfinite(fps)) throw Error("autoFrameStep: fps must be positive and finite");
  return std::max(1, static_cast<int>(std::floor(fps / 25.0 + 1e-9)));
}

/// Expands a result over the tracked frames 0, step, 2·step, … to all `numFrames` input frames.
/// A frame between two tracked ones takes their screw interpolation and the status Interpolated
/// (Lost when either neighbour was lost); frames after the last tracked one hold its pose. The
/// keyframe flags, the keyframe depths' and the place links' frame indices move to the input
/// frames; the counts (keyframes, losses, refined frames, …) stay those of the tracked frames.
template <typename Scalar>
SlamResult<Scalar> expandFrameStep(SlamResult<Scalar> tracked, int step, int numFrames) {
  if (step < 1) throw Error("expandFrameStep: step must be at least 1");
  const int m = static_cast<int>(tracked.poses.size());
  if (static_cast<int>(tracked.status.size()) != m || static_cast<int>(tracked.keyframe.size()) != m ||
      static_cast<int>(tracked.inliers.size()) != m) {
    throw Error("expandFrameStep: the per-frame arrays of the result differ in length");
  }
  if (m == 0 ? numFrames != 0 : (numFrames < (m - 1) * step + 1 || numFrames > m * step)) {
    throw Error("expandFrameStep: " + std::to_string(numFrames) + " input frames cannot hold " + std::to_string(m) +
                " tracked frames at a step of " + std::to_string(step));
  }
  if (step == 1) return tracked;
  SlamResult<Scalar> out = std::move(tracked);
  std::vector<SE3<Scalar>> poses(static_cast<std::size_t>(numFrames));
  std::vector<SlamStatus> status(static_cast<std::size_t>(numFrames), SlamStatus::Interpolated);
  std::vector<char> keyframe(static_cast<std::size_t>(numFrames), 0);
  std::vector<int> inliers(static_cast<std::size_t>(numFrames), 0);
  for (int f = 0; f < numFrames; ++f) {
    const int i0 = f / step, r = f % step;
    const std::size_t a = static_cast<std::size_t>(i0), u = static_cast<std::size_t>(f);
    if (r == 0) {
      poses[u] = out.poses[a];
      status[u] = out.status[a];
      keyframe[u] = out.keyframe[a];
      inliers[u] = out.inliers[a];
      continue;
    }
    const bool between = i0 + 1 < m;
    const std::size_t b = between ? a + 1 : a;
    poses[u] = between ? interpolate(out.poses[a], out.poses[b], Scalar(r) / Scalar(step)) : out.poses[a];
    if (out.status[a] == SlamStatus::Lost || out.status[b] == SlamStatus::Lost) status[u] = SlamStatus::Lost;
  }
  out.poses = std::move(poses);
  out.status = std::move(status);
  out.keyframe = std::move(keyframe);
  out.inliers = std::move(inliers);
  for (auto& d : out.keyframeDepths) d.frame *= step;
  for (auto& l : out.placeLinks) l.frame *= step, l.oldFrame *= step;
  return out;
}

}  // namespace hawor
