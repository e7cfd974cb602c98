// hawor/motion/local_poly.hpp — local polynomial fits of a 3-vector channel over a few frames.
//
// Used for the boundary velocities of the spline gap filler (spline_infill.hpp) and by the
// observed-frame smoother (smooth.hpp). Samples are (τ_i, y_i), τ in frames relative to the
// frame of interest (τ = 0), y_i ∈ R³ (a position, or a rotation's tangent vector there).
// Thread-safety: pure functions.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "hawor/common.hpp"

namespace hawor {

/// Result of fitLocalPolynomial: the polynomial's value and slope at τ = 0, and the variance of
/// that slope (and of the value) per unit noise variance of the samples.
template <typename Scalar>
struct LocalPolyFit {
  Vec3<Scalar> value = Vec3<Scalar>::Zero();
  Vec3<Scalar> slope = Vec3<Scalar>::Zero();  ///< per frame
  Scalar slopeVariance = Scalar(0);  ///< Var(slope component) / σ² (white sample noise σ)
  Scalar valueVariance = Scalar(0);  ///< Var(value component) / σ²
  bool ok = false;                   ///< false: fewer samples than coefficients, or singular
};

/// Weighted least-squares polynomial of degree `deg` through the n samples (τ_i, y_i) with
/// weights w_i (nullptr = all 1):  min Σ w_i‖Σ_j c_j τ_i^j − y_i‖²,  value = c_0, slope = c_1.
/// Variances from the sandwich (AᵀWA)⁻¹AᵀW²A(AᵀWA)⁻¹ (= (AᵀA)⁻¹ unweighted). τ is scaled by its
/// largest magnitude before solving, so the normal equations stay well conditioned in float.
template <typename Scalar>
LocalPolyFit<Scalar> fitLocalPolynomial(const Scalar* tau, const Vec3<Scalar>* y, const Scalar* w,
                                        int n, int deg) {
  using Mat = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  LocalPolyFit<Scalar> f;
  if (deg < 0 || n < deg + 1) return f;
  Scalar span(0);
  for (int i = 0; i < n; ++i) span = std::max(span, std::abs(tau[i]));
  if (deg > 0 && !(span > Scalar(0))) return f;
  if (!(span > Scalar(0))) span = Scalar(1);
  Mat A(n, deg + 1), WA(n, deg + 1), Y(n, 3);
  for (int i = 0; i < n; ++i) {
    const Scalar s = tau[i] / span;
    const Scalar wi = w ? w[i] : Scalar(1);
    Scalar p(1);
    for (int j = 0; j <= deg; ++j, p *= s) {
      A(i, j) = p;
      WA(i, j) = wi * p;
    }
    Y.row(i) = y[i].transpose();
  }
  const Mat N = WA.transpose() * A;  // AᵀWA
  const Eigen::LDLT<Mat> ldlt(N);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > Scalar(0))) return f;
  const Mat C = ldlt.solve(WA.transpose() * Y);
  const Mat Ninv = ldlt.solve(Mat::Identity(deg + 1, deg + 1));
  const Mat cov = w ? Mat(Ninv * (WA.transpose() * WA) * Ninv) : Ninv;
  f.value = C.row(0).transpose();
  f.valueVariance = cov(0, 0);
  if (deg >= 1) {
    f.slope = C.row(1).transpose() / span;
    f.slopeVariance = cov(1, 1) / (span * span);
  }
  f.ok = f.value.allFinite() && f.slope.allFinite();
  return f;
}

}  // namespace hawor
