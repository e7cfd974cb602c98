// hawor/geometry/alignment.hpp — least-squares similarity / rigid alignment of point sets
// (Umeyama 1991, "Least-squares estimation of transformation parameters between two point
// patterns"), optionally weighted.
//
// Used by the metrics (docs/design.md §8): PA-MPJPE (similarity per frame), W-/WA-MPJPE (similarity
// on a chunk), RTE and ATE-S (rigid, no scale), ATE (similarity). Pure functions, thread-safe.
#pragma once

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/geometry/sim3.hpp"

namespace hawor {

/// dst ≈ s·R·src + t. Plain data; s = 1 for a rigid (SE3) alignment.
template <typename Scalar>
struct SimilarityTransform {
  Mat3<Scalar> R = Mat3<Scalar>::Identity();
  Vec3<Scalar> t = Vec3<Scalar>::Zero();
  Scalar s = Scalar(1);

  /// s·R·p + t
  Vec3<Scalar> apply(const Vec3<Scalar>& p) const { return s * (R * p) + t; }

  /// Row-wise s·R·p_i + t for an (N,3) array.
  Points3<Scalar> apply(const Points3<Scalar>& P) const {
    Points3<Scalar> out(P.rows(), 3);
    const Mat3<Scalar> sR = s * R;
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      out.row(i) = (sR * P.row(i).transpose() + t).transpose();
    }
    return out;
  }

  /// The same transform as a Sim3 group element (s must be > 0).
  Sim3<Scalar> toSim3() const { return Sim3<Scalar>(s, SO3<Scalar>::fromMatrix(R), t); }
  /// The rigid part as an SE3 (the scale is dropped).
  SE3<Scalar> toSE3() const { return SE3<Scalar>(SO3<Scalar>::fromMatrix(R), t); }
};

/// Umeyama alignment: the (s, R, t) minimising Σ_i w_i ‖dst_i − (s·R·src_i + t)‖².
///
/// With weights W = Σ w_i, means μ_x = Σ w_i src_i / W, μ_y likewise, covariance
/// Σ_xy = (1/W) Σ w_i (dst_i − μ_y)(src_i − μ_x)ᵀ = U D Vᵀ, variance σ_x² = (1/W) Σ w_i ‖src_i − μ_x‖²:
///   S = diag(1, 1, ±1) (−1 when det(U)·det(V) < 0: the reflection fix),
///   R = U S Vᵀ,  s = tr(D S)/σ_x²  (1 if !with_scale),  t = μ_y − s R μ_x.
/// weights: optional, one per point, >= 0, not all zero (nullptr: all 1).
/// Degenerate inputs that still have a unique answer are accepted (one point without scale:
/// R = I; collinear points: one of the optimal rotations). Throws hawor::Error on a size
/// mismatch, no points, non-finite input, negative/all-zero weights, and when with_scale is
/// set but the (weighted) source points all coincide (the scale is then undefined).
template <typename Scalar>
SimilarityTransform<Scalar> umeyama(const Points3<Scalar>& src, const Points3<Scalar>& dst,
                                    bool with_scale, const VecX<Scalar>* weights = nullptr) {
  using S = Scalar;
  const Eigen::Index n = src.rows();
  if (dst.rows() != n) {
    throw Error("umeyama: src has " + std::to_string(n) + " points but dst has " +
                std::to_string(dst.rows()));
  }
  if (n == 0) throw Error("umeyama: no points");
  if (weights && weights->size() != n) {
    throw Error("umeyama: " + std::to_string(weights->size()) + " weights for " +
                std::to_string(n) + " points");
  }
  if (!src.allFinite()) throw Error("umeyama: src points are not finite");
  if (!dst.allFinite()) throw Error("umeyama: dst points are not finite");
  S wsum = S(0);
  if (weights) {
    if (!weights->allFinite()) throw Error("umeyama: weights are not finite");
    if ((weights->array() < S(0)).any()) throw Error("umeyama: negative weight");
    wsum = weights->sum();
    if (!(wsum > S(0))) throw Error("umeyama: all weights are zero");
  } else {
    wsum = S(n);
  }
  auto w = [&](Eigen::Index i) { return weights ? (*weights)(i) : S(1); };

  // Weighted means (two-pass: centre before forming second moments, for accuracy).
  Eigen::Matrix<S, 3, 1> mu_x = Eigen::Matrix<S, 3, 1>::Zero(), mu_y = mu_x;
  for (Eigen::Index i = 0; i < n; ++i) {
    mu_x += w(i) * src.row(i).transpose();
    mu_y += w(i) * dst.row(i).transpose();
  }
  mu_x /= wsum;
  mu_y /= wsum;

  Eigen::Matrix<S, 3, 3> cov = Eigen::Matrix<S, 3, 3>::Zero();
  S var_x = S(0), max_abs = S(0);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Matrix<S, 3, 1> x = src.row(i).transpose() - mu_x;
    const Eigen::Matrix<S, 3, 1> y = dst.row(i).transpose() - mu_y;
    cov.noalias() += w(i) * y * x.transpose();
    var_x += w(i) * x.squaredNorm();
    if (w(i) > S(0)) max_abs = std::max(max_abs, src.row(i).cwiseAbs().maxCoeff());
  }
  cov /= wsum;
  var_x /= wsum;

  const Eigen::JacobiSVD<Eigen::Matrix<S, 3, 3>> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix<S, 3, 3>& U = svd.matrixU();
  const Eigen::Matrix<S, 3, 3>& V = svd.matrixV();
  Eigen::Matrix<S, 3, 1> d(S(1), S(1), S(1));
  if (U.determinant() * V.determinant() < S(0)) d(2) = S(-1);

  SimilarityTransform<S> out;
  out.R = U * d.asDiagonal() * V.transpose();
  if (with_scale) {
    // Source spread at the level of rounding noise: the scale is undefined.
    const S tiny = S(64) * std::numeric_limits<S>::epsilon() * std::max(max_abs, S(1e-30));
    if (!(std::sqrt(var_x) > tiny)) {
      throw Error("umeyama: source points coincide (zero variance), scale is undefined");
    }
    out.s = svd.singularValues().dot(d) / var_x;
  } else {
    out.s = S(1);
  }
  out.t = mu_y - out.s * (out.R * mu_x);
  return out;
}

/// Rigid (no scale) alignment as an SE3: dst ≈ T·src. See umeyama.
template <typename Scalar>
SE3<Scalar> alignSE3(const Points3<Scalar>& src, const Points3<Scalar>& dst,
                     const VecX<Scalar>* weights = nullptr) {
  return umeyama(src, dst, false, weights).toSE3();
}

/// Similarity alignment as a Sim3: dst ≈ T·src. See umeyama. Throws when the optimal scale is
/// not positive (dst collapsed to a point).
template <typename Scalar>
Sim3<Scalar> alignSim3(const Points3<Scalar>& src, const Points3<Scalar>& dst,
                       const VecX<Scalar>* weights = nullptr) {
  const SimilarityTransform<Scalar> T = umeyama(src, dst, true, weights);
  if (!(T.s > Scalar(0))) throw Error("alignSim3: optimal scale is zero (dst points coincide)");
  return T.toSim3();
}

}  // namespace hawor
