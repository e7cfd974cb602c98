// hawor/scale/fuse_scale.hpp — one metric scale from several estimates: the
// depth-based (robust_scale.hpp), the hand-anchored (hand_scale.hpp), the ground-plane
// (ground_scale.hpp) one. A single estimate is the answer; several give the confidence-weighted
// mean in log space, log α = Σ c_k·log α_k / Σ c_k (scales multiply, so they average in log
// space), with the largest confidence.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/scale/robust_scale.hpp"

namespace hawor {

/// Confidence of a depth-based sequence scale in [0, 1]: the fraction of keyframes fitted, damped
/// by the keyframes' disagreement (relative spread s: 1 / (1 + (s / 0.05)²)).
template <typename Scalar>
Scalar depthScaleConfidence(const SequenceScale<Scalar>& s) {
  if (!s.ok() || s.keyframes <= 0) return Scalar(0);
  const double spread = std::isfinite(double(s.relativeSpread)) ? double(s.relativeSpread) : 1.0;
  return Scalar(double(s.fitted) / double(s.keyframes) / (1.0 + (spread / 0.05) * (spread / 0.05)));
}

template <typename Scalar>
struct FusedScale {
  Scalar scale = std::numeric_limits<Scalar>::quiet_NaN();
  Scalar confidence = Scalar(0);
  std::string method;  ///< the cue's name ("depth", "hands", "ground") or "fused"
  bool ok() const { return std::isfinite(double(scale)) && scale > Scalar(0); }
};

/// One estimate for fuseScaleCues: a NaN or non-positive scale, or a zero confidence with other
/// cues present, counts as absent.
template <typename Scalar>
struct ScaleCue {
  Scalar scale, confidence;
  std::string name;
};

/// Fuses the estimates (file comment). Not ok() when none exists.
template <typename Scalar>
FusedScale<Scalar> fuseScaleCues(const std::vector<ScaleCue<Scalar>>& cues) {
  FusedScale<Scalar> out;
  std::vector<const ScaleCue<Scalar>*> have;
  for (const auto& c : cues) {
    if (std::isfinite(double(c.scale)) && c.scale > Scalar(0)) have.push_back(&c);
  }
  if (have.empty()) return out;
  if (have.size() > 1) {  // several: only those with a confidence take part
    std::vector<const ScaleCue<Scalar>*> weighted;
    for (const auto* c : have) {
      if (c->confidence > Scalar(0)) weighted.push_back(c);
    }
    if (!weighted.empty()) have = weighted;
    else have.resize(1);
  }
  if (have.size() == 1) {
    out.scale = have[0]->scale, out.confidence = std::max(Scalar(0), have[0]->confidence), out.method = have[0]->name;
    return out;
  }
  Scalar sw = 0, sl = 0;
  for (const auto* c : have) {
    sw += c->confidence, sl += c->confidence * std::log(c->scale);
    out.confidence = std::max(out.confidence, c->confidence);
  }
  out.scale = std::exp(sl / sw);
  out.method = "fused";
  return out;
}

/// The depth and hand estimates (fuseScaleCues with those two).
template <typename Scalar>
FusedScale<Scalar> fuseScales(Scalar depthScale, Scalar depthConfidence, Scalar handScale, Scalar handConfidence) {
  return fuseScaleCues<Scalar>({{depthScale, depthConfidence, "depth"}, {handScale, handConfidence, "hands"}});
}

}  // namespace hawor
