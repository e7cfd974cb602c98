// hawor/scale/hand_scale.hpp — the hand-anchored metric scale: no depth network, only the hands.
// A fitted hand has a metric size, so its camera-frame position h_t is in metres, and the world
// hand R_t·h_t + α·c_t depends on the unknown scale α of the SLAM trajectory linearly.
// Two cues, in order of trust:
//   holds       a hand still in the world while the head moves (hand_hold_scale.hpp): α makes
//               the most windows still; exact when the hand really holds still;
//   smoothness  least world-space acceleration of the hands (hand_smoothness_scale.hpp): needs no
//               hold but is biased when the hands move with the head.
// The holds answer when they are confident enough (confidence ≥ minHoldConfidence); otherwise the
// smoothness cue does, its confidence capped at smoothnessConfidenceCap because its standard error
// does not show that bias.
#pragma once

#include <algorithm>
#include <vector>

#include "hawor/scale/hand_hold_scale.hpp"
#include "hawor/scale/hand_smoothness_scale.hpp"
#include "hawor/scale/hand_track.hpp"

namespace hawor {

template <typename Scalar>
struct HandScaleOptions {
  HandHoldOptions<Scalar> hold;
  HandSmoothnessOptions<Scalar> smoothness;
  Scalar minHoldConfidence = Scalar(0.1);
  /// 0.05 ≈ a 22 % relative error (confidence = 1 / (1 + (e / 0.05)²)): the cue's measured bias is
  /// 15–60 % on the synthetic presets, so it must not outweigh the ground cue (≈ 5 %) in fusion.
  Scalar smoothnessConfidenceCap = Scalar(0.05);
};

/// The hand-anchored scale (file comment) from camera-to-world poses (map units) and hand tracks
/// (metres, camera frame) of the same length. Throws on mismatched lengths or invalid options.
template <typename Scalar>
HandScaleResult<Scalar> handAnchoredScale(const std::vector<SE3<Scalar>>& T_w_c, const std::vector<HandTrack<Scalar>>& hands,
                                          const HandScaleOptions<Scalar>& opt = {}) {
  const HandScaleResult<Scalar> h = handHoldScale(T_w_c, hands, opt.hold);
  if (h.ok() && h.confidence >= opt.minHoldConfidence) return h;
  HandScaleResult<Scalar> s = handSmoothnessScale(T_w_c, hands, opt.smoothness);
  s.confidence = std::min(s.confidence, opt.smoothnessConfidenceCap);
  return s;
}

}  // namespace hawor
