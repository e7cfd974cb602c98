// hawor/slam/homography.hpp — the plane-induced homography: the normalised DLT (Hartley &
// Zisserman Alg. 4.2), transfer errors, and the decomposition into motions (Faugeras & Lustman
// 1988, "Motion and structure from motion in a piecewise planar environment").
//
// Convention (as essential.hpp): normalised image coordinates (z = 1), X2 = R·X1 + t, and a plane
// nᵀ·X1 = d (d > 0, in camera 1) induces x2 ∝ H·x1 with H = R + t·nᵀ/d (up to scale).
// A homography also explains any scene under a pure rotation (t = 0: H = R) — the degenerate case
// the two-view initialisation has to recognise.
// Computations in double (the returned matrices are cast to Scalar). Pure functions, thread-safe.
#pragma once

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <limits>
#include <vector>

#include "hawor/common.hpp"

namespace hawor {

/// Normalised DLT: the H (unit Frobenius norm) minimising the algebraic error of x2 ∝ H·x1 over
/// the correspondences idx[0..n) (idx = nullptr: 0..n−1), n ≥ 4. Both point sets are first moved
/// to zero mean and mean distance √2 (Hartley's normalisation), which makes the 9×9 normal
/// matrix well conditioned. Returns false for n < 4, non-finite data or a degenerate
/// configuration (e.g. three of four points collinear, all points identical).
template <typename Scalar>
bool homographyDLT(const std::vector<Vec2<Scalar>>& x1, const std::vector<Vec2<Scalar>>& x2,
                   const int* idx, int n, Mat3<Scalar>& H) {
  if (n < 4) return false;
  auto at = [&](int k) { return idx ? idx[k] : k; };
  // Hartley normalisation of each point set.
  Eigen::Vector2d m1 = Eigen::Vector2d::Zero(), m2 = Eigen::Vector2d::Zero();
  for (int k = 0; k < n; ++k) {
    m1 += x1[static_cast<std::size_t>(at(k))].template cast<double>();
    m2 += x2[static_cast<std::size_t>(at(k))].template cast<double>();
  }
  m1 /= n;
  m2 /= n;
  double s1 = 0.0, s2 = 0.0;
  for (int k = 0; k < n; ++k) {
    s1 += (x1[static_cast<std::size_t>(at(k))].template cast<double>() - m1).norm();
    s2 += (x2[static_cast<std::size_t>(at(k))].template cast<double>() - m2).norm();
  }
  if (!(s1 > 0.0) || !(s2 > 0.0) || !std::isfinite(s1) || !std::isfinite(s2)) return false;
  s1 = std::sqrt(2.0) * n / s1;
  s2 = std::sqrt(2.0) * n / s2;
  // Accumulate AᵀA of the two DLT rows per correspondence (h = vec_rowmajor(H)):
  //   [0ᵀ, −a, y'·a] and [a, 0ᵀ, −x'·a] with a = (x, y, 1) normalised, (x', y') normalised.
  Eigen::Matrix<double, 9, 9> AtA = Eigen::Matrix<double, 9, 9>::Zero();
  Eigen::Matrix<double, 9, 1> r1, r2;
  for (int k = 0; k < n; ++k) {
    const std::size_t i = static_cast<std::size_t>(at(k));
    const Eigen::Vector2d p = s1 * (x1[i].template cast<double>() - m1);
    const Eigen::Vector2d q = s2 * (x2[i].template cast<double>() - m2);
    const Eigen::Vector3d a(p(0), p(1), 1.0);
    r1 << 0.0, 0.0, 0.0, -a(0), -a(1), -a(2), q(1) * a(0), q(1) * a(1), q(1) * a(2);
    r2 << a(0), a(1), a(2), 0.0, 0.0, 0.0, -q(0) * a(0), -q(0) * a(1), -q(0) * a(2);
    AtA.noalias() += r1 * r1.transpose() + r2 * r2.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> es(AtA);
  if (es.info() != Eigen::Success) return false;
  // A unique null vector needs the second-smallest eigenvalue clearly above the smallest.
  const auto ev = es.eigenvalues();
  if (!(ev(1) > 1e-12 * ev(8))) return false;
  const Eigen::Matrix<double, 9, 1> h = es.eigenvectors().col(0);
  Eigen::Matrix3d Hn;
  Hn << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  // Undo the normalisation: H = T2⁻¹·Hn·T1.
  Eigen::Matrix3d T1, T2inv;
  T1 << s1, 0, -s1 * m1(0), 0, s1, -s1 * m1(1), 0, 0, 1;
  T2inv << 1.0 / s2, 0, m2(0), 0, 1.0 / s2, m2(1), 0, 0, 1;
  Eigen::Matrix3d Hd = T2inv * Hn * T1;
  const double nrm = Hd.norm();
  if (!(nrm > 0.0) || !Hd.allFinite()) return false;
  H = (Hd / nrm).cast<Scalar>();
  return true;
}

/// Squared transfer errors: e2² = ‖x2 − π(H·x1)‖² (image 2) and e1² = ‖x1 − π(H⁻¹·x2)‖² (image 1),
/// π(p) = (p₀/p₂, p₁/p₂); +∞ where a point maps to infinity.
template <typename Scalar>
void homographyTransferErrorsSq(const Mat3<Scalar>& H, const Mat3<Scalar>& Hinv,
                                const Vec2<Scalar>& x1, const Vec2<Scalar>& x2, Scalar& e1Sq,
                                Scalar& e2Sq) {
  const Scalar inf = std::numeric_limits<Scalar>::infinity();
  const Eigen::Matrix<Scalar, 3, 1> p2 = H * Eigen::Matrix<Scalar, 3, 1>(x1(0), x1(1), Scalar(1));
  const Eigen::Matrix<Scalar, 3, 1> p1 =
      Hinv * Eigen::Matrix<Scalar, 3, 1>(x2(0), x2(1), Scalar(1));
  if (p2(2) != Scalar(0)) {
    const Scalar du = p2(0) / p2(2) - x2(0), dv = p2(1) / p2(2) - x2(1);
    e2Sq = du * du + dv * dv;
  } else {
    e2Sq = inf;
  }
  if (p1(2) != Scalar(0)) {
    const Scalar du = p1(0) / p1(2) - x1(0), dv = p1(1) / p1(2) - x1(1);
    e1Sq = du * du + dv * dv;
  } else {
    e1Sq = inf;
  }
}

/// Faugeras' decomposition of H ∝ R + t·nᵀ/d into up to 8 candidate motions (R, t, n) with |t| = 1
/// and |n| = 1 (the scale t/d is not observable). With H = U·diag(d1, d2, d3)·Vᵀ (d1 ≥ d2 ≥ d3),
/// s = det U·det V, x1 = ±√((d1²−d2²)/(d1²−d3²)), x3 = ±√((d2²−d3²)/(d1²−d3²)):
///   d' = +d2: R' = [cθ 0 −sθ; 0 1 0; sθ 0 cθ], sθ = (d1−d3)·x1·x3/d2, cθ = (d1·x3² + d3·x1²)/d2,
///             t' = (d1 − d3)·(x1, 0, −x3)
///   d' = −d2: R' = [cφ 0 sφ; 0 −1 0; sφ 0 −cφ], sφ = (d1+d3)·x1·x3/d2, cφ = (d3·x1² − d1·x3²)/d2,
///             t' = (d1 + d3)·(x1, 0, x3)
/// and R = s·U·R'·Vᵀ, t = U·t', n = V·(x1, 0, x3). The physical solution is the one that puts the
/// points in front of both cameras (checked by the caller). Returns the number of candidates:
/// 0 when H is not finite or two singular values coincide (d1 ≈ d2 or d2 ≈ d3, within relative
/// `tol`): then the motion is a pure rotation, or the plane passes through a centre, and the
/// decomposition is not unique.
template <typename Scalar>
int decomposeHomography(const Mat3<Scalar>& H, Mat3<Scalar> R[8], Vec3<Scalar> t[8],
                        Vec3<Scalar> n[8], double tol = 1e-5) {
  if (!H.allFinite()) return 0;
  const Eigen::Matrix3d Hd = H.template cast<double>();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(Hd, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
  const Eigen::Vector3d w = svd.singularValues();
  const double d1 = w(0), d2 = w(1), d3 = w(2);
  if (!(d3 > 0.0) || d1 / d2 < 1.0 + tol || d2 / d3 < 1.0 + tol) return 0;
  const double s = U.determinant() * V.determinant();
  const double a1 = std::sqrt((d1 * d1 - d2 * d2) / (d1 * d1 - d3 * d3));
  const double a3 = std::sqrt((d2 * d2 - d3 * d3) / (d1 * d1 - d3 * d3));
  const double e1[4] = {1, 1, -1, -1}, e3[4] = {1, -1, 1, -1};
  int k = 0;
  for (int i = 0; i < 4; ++i) {  // d' = +d2
    const double x1 = e1[i] * a1, x3 = e3[i] * a3;
    const double st = (d1 - d3) * x1 * x3 / d2, ct = (d1 * x3 * x3 + d3 * x1 * x1) / d2;
    Eigen::Matrix3d Rp;
    Rp << ct, 0, -st, 0, 1, 0, st, 0, ct;
    const Eigen::Vector3d tp = (d1 - d3) * Eigen::Vector3d(x1, 0, -x3);
    R[k] = (s * U * Rp * V.transpose()).cast<Scalar>();
    t[k] = (U * tp).normalized().cast<Scalar>();
    n[k] = (V * Eigen::Vector3d(x1, 0, x3)).normalized().cast<Scalar>();
    ++k;
  }
  for (int i = 0; i < 4; ++i) {  // d' = −d2
    const double x1 = e1[i] * a1, x3 = e3[i] * a3;
    const double sp = (d1 + d3) * x1 * x3 / d2, cp = (d3 * x1 * x1 - d1 * x3 * x3) / d2;
    Eigen::Matrix3d Rp;
    Rp << cp, 0, sp, 0, -1, 0, sp, 0, -cp;
    const Eigen::Vector3d tp = (d1 + d3) * Eigen::Vector3d(x1, 0, x3);
    R[k] = (s * U * Rp * V.transpose()).cast<Scalar>();
    t[k] = (U * tp).normalized().cast<Scalar>();
    n[k] = (V * Eigen::Vector3d(x1, 0, x3)).normalized().cast<Scalar>();
    ++k;
  }
  return k;
}

}  // namespace hawor
