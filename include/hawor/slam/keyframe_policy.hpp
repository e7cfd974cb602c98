// hawor/slam/keyframe_policy.hpp — when a tracked frame becomes a keyframe (MonoSlam's mapping
// step): a pure function of the frame's tracking figures, testable on its own.
//
// A keyframe is taken, the first reason that holds:
//   MaxInterval  framesSinceKeyframe ≥ maxInterval (the map keeps up with slow motion);
//   Thin         the mapped inliers fall below minInliers or below inlierRatio × the last
//                keyframe's, and framesSinceKeyframe ≥ minInterval (the map thins out);
//   NearlyLost   fewer than 2 × trackingMinInliers mapped inliers (tracking is about to fail)
//                and framesSinceKeyframe ≥ thinInterval;
//   Swept        in turn mode, the rotation since the last keyframe exceeds maxRotationDeg: a
//                head turn sweeps the map out of view within a few frames and new corners are
//                only detected at keyframes, so a keyframe every maxRotationDeg keeps the
//                leading edge of the view seeded (its tracks are triangulated once the neck's
//                translation gives them parallax).
// Thread-safety: pure function.
#pragma once

#include "../common.hpp"

namespace hawor {

template <typename Scalar>
struct KeyframePolicyOptions {
  Scalar inlierRatio = Scalar(0.7);
  int minInliers = 60;
  int maxInterval = 10;
  int minInterval = 3;
  int thinInterval = 1;              ///< frames between keyframes while nearly lost (2: mixed)
  Scalar maxRotationDeg = Scalar(12);  ///< in turn mode: a keyframe after this much rotation

  /// Throws hawor::Error naming the first bad field.
  void validate() const {
    if (!(inlierRatio >= Scalar(0) && inlierRatio <= Scalar(1))) throw Error("keyframe.inlierRatio must lie in [0, 1]");
    if (minInliers < 0) throw Error("keyframe.minInliers must be >= 0");
    if (maxInterval < 1) throw Error("keyframe.maxInterval must be >= 1");
    if (minInterval < 0 || thinInterval < 0) throw Error("keyframe.minInterval and keyframe.thinInterval must be >= 0");
    if (!(maxRotationDeg > Scalar(0))) throw Error("keyframe.maxRotationDeg must be > 0");
  }
};

/// A tracked frame's figures the policy reads.
template <typename Scalar>
struct KeyframeQuery {
  int mappedInliers = 0;             ///< PnP inliers of the frame (mapped tracks)
  int lastKeyframeInliers = 0;       ///< the same at the last keyframe
  int framesSinceKeyframe = 0;       ///< this frame included
  int trackingMinInliers = 25;       ///< inliers below which tracking fails (SlamOptions::minInliers)
  bool turning = false;              ///< turn mode
  Scalar rotationSinceKeyframeDeg = Scalar(0);
};

enum class KeyframeReason { None = 0, MaxInterval, Thin, NearlyLost, Swept };

inline const char* keyframeReasonName(KeyframeReason r) {
  switch (r) {
    case KeyframeReason::None: return "none";
    case KeyframeReason::MaxInterval: return "max-interval";
    case KeyframeReason::Thin: return "thin";
    case KeyframeReason::NearlyLost: return "nearly-lost";
    case KeyframeReason::Swept: return "swept";
  }
  return "unknown";
}

/// Why the frame becomes a keyframe (None: it does not).
template <typename Scalar>
KeyframeReason keyframeReason(const KeyframeQuery<Scalar>& q, const KeyframePolicyOptions<Scalar>& o) {
  const int n = q.framesSinceKeyframe;
  if (n >= o.maxInterval) return KeyframeReason::MaxInterval;
  const bool thin = q.mappedInliers < o.minInliers || Scalar(q.mappedInliers) < o.inlierRatio * Scalar(q.lastKeyframeInliers);
  if (thin && n >= o.minInterval) return KeyframeReason::Thin;
  if (q.mappedInliers < 2 * q.trackingMinInliers && n >= o.thinInterval) return KeyframeReason::NearlyLost;
  if (q.turning && q.rotationSinceKeyframeDeg > o.maxRotationDeg) return KeyframeReason::Swept;
  return KeyframeReason::None;
}

}  // namespace hawor
