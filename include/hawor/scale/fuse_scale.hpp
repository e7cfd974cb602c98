// hawor/scale/fuse_scale.hpp — one metric scale from several estimates: the
// depth-based (robust_scale.hpp), the hand-anchored (hand_scale.hpp), the ground-plane
// (ground_scale.hpp) one. A single estimate is the answer; several give the confidence-weighted
// mean in log space, log α = Σ c_k·log α_k / Σ c_k (scales multiply, so they average in log
// space), with the largest confidence.
// Every cue maps its relative standard error e to a confidence the same way (confidence.hpp),
// so e_k = 0.05·√(1/c_k − 1). Cues that disagree beyond their errors are not
// averaged: a cue whose |log α_k − log α_b| exceeds 3·√(e_k² + e_b²) against the most confident
// cue b is left out (and named in leftOut). A mean of two readings 10× apart is neither: a hand
// cue fooled by hands that move with the head, averaged with a floor reading, lands far from both.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/scale/confidence.hpp"
#include "hawor/scale/robust_scale.hpp"

namespace hawor {

/// Confidence of a depth-based sequence scale in [0, 1]: the fraction of keyframes fitted, damped
/// by the keyframes' disagreement (relative spread s: 1 / (1 + (s / 0.05)²)).
template <typename Scalar>
Scalar depthScaleConfidence(const SequenceScale<Scalar>& s) {
  if (!s.ok() || s.keyframes <= 0) return Scalar(0);
  const double spread = std::isfinite(double(s.relativeSpread)) ? double(s.relativeSpread) : 1.0;
  return Scalar(double(s.fitted) / double(s.keyframes) * scaleConfidence(spread));
}

template <typename Scalar>
struct FusedScale {
  Scalar scale = std::numeric_limits<Scalar>::quiet_NaN();
  Scalar confidence = Scalar(0);
  std::string method;  ///< the cue's name ("depth", "hands", "ground") or "fused"
  std::vector<std::string> leftOut;  ///< cues left out as inconsistent, each "NAME α (confidence c)"
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
  if (have.size() > 1) {  // left out: those inconsistent with the most confident
    const ScaleCue<Scalar>* best = *std::max_element(have.begin(), have.end(), [](const auto* a, const auto* b) { return a->confidence < b->confidence; });
    std::vector<const ScaleCue<Scalar>*> kept;
    for (const auto* c : have) {
      if (c == best || scalesAgree(double(c->scale), double(c->confidence), double(best->scale), double(best->confidence))) {
        kept.push_back(c);
      } else {
        char buf[96];
        std::snprintf(buf, sizeof buf, " %.4g (confidence %.2f)", double(c->scale), double(c->confidence));
        out.leftOut.push_back(c->name + buf);
      }
    }
    have = kept;
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
