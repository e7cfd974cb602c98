// hawor/scale/fuse_scale.hpp — one metric scale from the depth-based (robust_scale.hpp) and the
// hand-anchored (hand_scale.hpp) estimates (issue 5, item 3): the depth scale when only it
// exists, the hand scale when only it exists, and with both the confidence-weighted mean in log
// space, log α = (c_d·log α_d + c_h·log α_h) / (c_d + c_h) (scales multiply, so they average in
// log space).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

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
  std::string method;  ///< "depth", "hands" or "fused"
  bool ok() const { return std::isfinite(double(scale)) && scale > Scalar(0); }
};

/// Fuses the two estimates (file comment); a NaN or non-positive scale counts as absent. Not ok()
/// when neither exists.
template <typename Scalar>
FusedScale<Scalar> fuseScales(Scalar depthScale, Scalar depthConfidence, Scalar handScale, Scalar handConfidence) {
  FusedScale<Scalar> out;
  const bool d = std::isfinite(double(depthScale)) && depthScale > Scalar(0);
  const bool h = std::isfinite(double(handScale)) && handScale > Scalar(0);
  const Scalar cd = std::max(Scalar(0), depthConfidence), ch = std::max(Scalar(0), handConfidence);
  if (d && h && cd + ch > Scalar(0)) {
    out.scale = std::exp((cd * std::log(depthScale) + ch * std::log(handScale)) / (cd + ch));
    out.confidence = std::max(cd, ch);
    out.method = "fused";
  } else if (d) {
    out.scale = depthScale, out.confidence = cd, out.method = "depth";
  } else if (h) {
    out.scale = handScale, out.confidence = ch, out.method = "hands";
  }
  return out;
}

}  // namespace hawor
