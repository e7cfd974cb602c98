// hawor/common.hpp — constants, tolerances and the error type shared by every module.
//
// Conventions (docs/design.md §2): metres, seconds, radians; OpenCV camera frame (x right, y down,
// z forward); poses stored camera-to-world; quaternions are Eigen's (w, x, y, z).
// Nothing here assumes 16-byte alignment: every fixed-size Eigen member in the library is
// declared with Eigen::DontAlign or lives on the stack (WASM has no static alignment).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace hawor {

/// Library error: thrown for bad input (malformed files, wrong shapes, NaNs). The message names
/// what is wrong and where, so a CLI can print it as is.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error("hawor: " + what) {}
};

/// Per-scalar tolerances in one place (after Sophus' Constants<Scalar>).
template <typename Scalar>
struct Constants {
  /// Threshold below which angle-based formulas switch to their Taylor expansions.
  static Scalar epsilon() { return Scalar(1e-10); }
  /// Angle under which SLERP falls back to normalised LERP.
  static Scalar slerpEpsilon() { return Scalar(1e-6); }
  static Scalar pi() { return Scalar(3.14159265358979323846264338327950288); }
};

template <>
struct Constants<float> {
  static float epsilon() { return 1e-5f; }
  static float slerpEpsilon() { return 1e-4f; }
  static float pi() { return 3.14159265358979323846f; }
};

/// Unaligned fixed-size Eigen aliases, safe as struct members in WASM and native alike.
template <typename Scalar>
using Vec2 = Eigen::Matrix<Scalar, 2, 1, Eigen::DontAlign>;
template <typename Scalar>
using Vec3 = Eigen::Matrix<Scalar, 3, 1, Eigen::DontAlign>;
template <typename Scalar>
using Vec4 = Eigen::Matrix<Scalar, 4, 1, Eigen::DontAlign>;
template <typename Scalar>
using Vec6 = Eigen::Matrix<Scalar, 6, 1, Eigen::DontAlign>;
template <typename Scalar>
using Vec7 = Eigen::Matrix<Scalar, 7, 1, Eigen::DontAlign>;
template <typename Scalar>
using Mat3 = Eigen::Matrix<Scalar, 3, 3, Eigen::DontAlign>;
template <typename Scalar>
using Mat4 = Eigen::Matrix<Scalar, 4, 4, Eigen::DontAlign>;
template <typename Scalar>
using MatX = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
template <typename Scalar>
using VecX = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
/// (N,3) row-major point arrays, the layout of numpy (T,21,3) slices.
template <typename Scalar>
using Points3 = Eigen::Matrix<Scalar, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// True when every coefficient is finite (no NaN, no Inf).
template <typename Derived>
bool allFinite(const Eigen::MatrixBase<Derived>& m) {
  return m.allFinite();
}

/// Median of the values (mean of the two middle ones for an even count); NaN when empty.
template <typename Scalar>
Scalar median(std::vector<Scalar> v) {
  if (v.empty()) return std::numeric_limits<Scalar>::quiet_NaN();
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  if (v.size() % 2) return v[m];
  const Scalar hi = v[m];
  const Scalar lo = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m));
  return Scalar(0.5) * (lo + hi);
}

/// Robust standard deviation of the values about `centre`: 1.4826·median|v − centre| (the MAD,
/// scaled to σ for Gaussian data); NaN when empty.
template <typename Scalar>
Scalar madSigma(const std::vector<Scalar>& v, Scalar centre) {
  std::vector<Scalar> dev;
  dev.reserve(v.size());
  for (Scalar x : v) dev.push_back(std::abs(x - centre));
  return Scalar(1.4826) * median(std::move(dev));
}

/// The q-quantile (q in [0, 1]) with linear interpolation between order statistics (numpy's
/// default); 0 when empty (timing summaries).
inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = std::min(std::max(q, 0.0), 1.0) * double(v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(pos);
  const double a = pos - double(i);
  return i + 1 < v.size() ? v[i] * (1 - a) + v[i + 1] * a : v[i];
}

}  // namespace hawor
