// hawor/scale/confidence.hpp — the one mapping between a metric-scale cue's relative standard
// error e (of α, so of log α) and its confidence in [0, 1], shared by every cue (depth, hands,
// ground) so that fusion (fuse_scale.hpp) can compare them:
//   c = 1 / (1 + (e / 0.05)²)       e = 0.05·√(1/c − 1)
// (c = 0.5 at a 5 % error).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

namespace hawor {

/// The confidence of a relative standard error e ≥ 0 (file comment).
inline double scaleConfidence(double e) { return 1.0 / (1.0 + (e / 0.05) * (e / 0.05)); }

/// The relative standard error a confidence stands for (file comment); +inf for c <= 0.
inline double confidenceLogError(double c) {
  return c > 0 ? 0.05 * std::sqrt(std::max(0.0, 1.0 / std::min(c, 1.0) - 1.0)) : std::numeric_limits<double>::infinity();
}

/// Whether two positive scale readings a, b of confidences ca, cb agree within 3 standard errors
/// of their difference in log: |log(a/b)| ≤ 3·√(e_a² + e_b²).
inline bool scalesAgree(double a, double ca, double b, double cb) {
  const double ea = confidenceLogError(ca), eb = confidenceLogError(cb);
  return std::abs(std::log(a / b)) <= 3 * std::sqrt(ea * ea + eb * eb);
}

}  // namespace hawor
