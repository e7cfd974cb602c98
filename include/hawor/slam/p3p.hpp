// hawor/slam/p3p.hpp — the minimal absolute-pose solver: camera pose from three 2D–3D
// correspondences (perspective-three-point), Grunert's formulation (Haralick et al. 1994,
// "Review and analysis of solutions of the three point perspective pose estimation problem").
//
// With unit bearings f_i (camera frame) of world points P_i, unknown depths λ_i > 0 satisfy the
// law of cosines  λ_i² + λ_j² − 2 λ_i λ_j c_ij = d_ij²  (c_ij = f_i·f_j, d_ij = ‖P_i − P_j‖).
// Grunert's substitution λ2 = x·λ1, λ3 = y·λ1 and division by d12² leave two conics in (x, y):
//   E1:  K1·x² − 2K1c12·x + K1 − 1 − y² + 2c13·y = 0          (K1 = d13²/d12²)
//   E2:  (K2 − 1)·x² + (2c23·y − 2K2c12)·x + K2 − y² = 0       (K2 = d23²/d12²)
// Seen as quadratics a_k x² + b_k(y) x + c_k(y) in x, their resultant
//   (a1c2 − a2c1)² − (a1b2 − a2b1)(b1c2 − b2c1)
// is a quartic in y (solved by the companion-matrix eigenvalues, polished by Newton steps), and
// x = (a1c2 − a2c1)/(a2b1 − a1b2) follows linearly. Then λ1 = d12/‖f1 − x·f2‖, and the rigid
// transform mapping P_i onto λ_i f_i (Kabsch/Umeyama without scale) is the pose.
// Up to 4 solutions. Computed in double whatever Scalar is (the elimination loses digits).
// Pure functions, thread-safe.
#pragma once

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"

namespace hawor {

namespace p3p_detail {

/// Real roots of c[0] + c[1]·t + ... + c[4]·t⁴ (leading zeros allowed), appended to `roots`.
inline void realQuarticRoots(const double (&c)[5], std::vector<double>& roots) {
  int deg = 4;
  const double scale = std::max({std::abs(c[0]), std::abs(c[1]), std::abs(c[2]), std::abs(c[3]),
                                 std::abs(c[4])});
  if (!(scale > 0.0) || !std::isfinite(scale)) return;
  while (deg > 0 && std::abs(c[deg]) <= 1e-14 * scale) --deg;
  if (deg == 0) return;
  // Companion matrix, at most 4×4 (fixed maximum size: no heap allocation).
  using Companion = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 4, 4>;
  Companion C = Companion::Zero(deg, deg);
  for (int k = 0; k < deg; ++k) C(0, k) = -c[deg - 1 - k] / c[deg];
  for (int k = 1; k < deg; ++k) C(k, k - 1) = 1.0;
  const Eigen::EigenSolver<Companion> es(C, false);
  if (es.info() != Eigen::Success) return;
  for (int k = 0; k < deg; ++k) {
    const std::complex<double> z = es.eigenvalues()(k);
    // Near-real roots (double roots split by rounding or noise) are kept: a spurious pose is
    // rejected by the caller's scoring, a missed one would lose the solution.
    if (std::abs(z.imag()) > 1e-4 * (1.0 + std::abs(z.real()))) continue;
    double t = z.real();
    for (int it = 0; it < 3; ++it) {  // Newton polishing
      double p = c[deg], dp = 0.0;
      for (int i = deg - 1; i >= 0; --i) {
        dp = dp * t + p;
        p = p * t + c[i];
      }
      if (!(std::abs(dp) > 0.0)) break;
      const double step = p / dp;
      if (!std::isfinite(step)) break;
      t -= step;
    }
    roots.push_back(t);
  }
}

/// Rigid (R, t) with Q_i ≈ R·P_i + t for three point pairs (Kabsch with the reflection fix).
inline bool rigidFrom3(const Eigen::Vector3d P[3], const Eigen::Vector3d Q[3], Eigen::Matrix3d& R,
                       Eigen::Vector3d& t) {
  const Eigen::Vector3d mp = (P[0] + P[1] + P[2]) / 3.0, mq = (Q[0] + Q[1] + Q[2]) / 3.0;
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i) H.noalias() += (Q[i] - mq) * (P[i] - mp).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) D(2, 2) = -1.0;
  R = svd.matrixU() * D * svd.matrixV().transpose();
  t = mq - R * mp;
  return R.allFinite() && t.allFinite();
}

}  // namespace p3p_detail

/// P3P (file comment): every world-to-camera pose T_c_w with f_i ∝ R·P_i + t for the bearings
/// f[0..2] (any non-zero length, camera frame, z forward) and world points P[0..2], appended to
/// `out` (0..4 poses; none for degenerate input: coincident or collinear points, parallel rays).
template <typename Scalar>
void solveP3P(const Vec3<Scalar>* bearings, const Vec3<Scalar>* world,
              std::vector<SE3<Scalar>>& out) {
  using V3 = Eigen::Vector3d;
  V3 f[3], P[3];
  for (int i = 0; i < 3; ++i) {
    f[i] = bearings[i].template cast<double>();
    P[i] = world[i].template cast<double>();
    const double n = f[i].norm();
    if (!(n > 0.0) || !std::isfinite(n) || !P[i].allFinite()) return;
    f[i] /= n;
  }
  const double d12s = (P[0] - P[1]).squaredNorm(), d13s = (P[0] - P[2]).squaredNorm(),
               d23s = (P[1] - P[2]).squaredNorm();
  const double big = std::max({d12s, d13s, d23s});
  // Collinear or coincident world points (the triangle's area vanishes).
  if (!(big > 0.0) || !((P[1] - P[0]).cross(P[2] - P[0]).squaredNorm() > 1e-12 * big * big)) return;
  // Parallel bearings.
  if (!(f[0].cross(f[1]).squaredNorm() > 1e-14) || !(f[0].cross(f[2]).squaredNorm() > 1e-14) ||
      !(f[1].cross(f[2]).squaredNorm() > 1e-14)) {
    return;
  }
  const double c12 = f[0].dot(f[1]), c13 = f[0].dot(f[2]), c23 = f[1].dot(f[2]);
  const double K1 = d13s / d12s, K2 = d23s / d12s;
  // Coefficients (index = power of y) of a1, b1, c1(y), a2, b2(y), c2(y).
  const double a1 = K1, b1 = -2.0 * K1 * c12;
  const double c1[3] = {K1 - 1.0, 2.0 * c13, -1.0};
  const double a2 = K2 - 1.0;
  const double b2[2] = {-2.0 * K2 * c12, 2.0 * c23};
  const double c2[3] = {K2, 0.0, -1.0};
  // Pp = a1c2 − a2c1 (deg 2), Qp = a1b2 − a2b1 (deg 1), Rp = b1c2 − b2c1 (deg 3).
  double Pp[3], Qp[2], Rp[4] = {0, 0, 0, 0};
  for (int k = 0; k < 3; ++k) Pp[k] = a1 * c2[k] - a2 * c1[k];
  Qp[0] = a1 * b2[0] - a2 * b1;
  Qp[1] = a1 * b2[1];
  for (int k = 0; k < 3; ++k) Rp[k] += b1 * c2[k];
  for (int i = 0; i < 2; ++i) {
    for (int k = 0; k < 3; ++k) Rp[i + k] -= b2[i] * c1[k];
  }
  double quartic[5] = {0, 0, 0, 0, 0};
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) quartic[i + k] += Pp[i] * Pp[k];
  }
  for (int i = 0; i < 2; ++i) {
    for (int k = 0; k < 4; ++k) {
      if (i + k <= 4) quartic[i + k] -= Qp[i] * Rp[k];
    }
  }
  std::vector<double> ys;
  ys.reserve(4);
  p3p_detail::realQuarticRoots(quartic, ys);
  for (const double y : ys) {
    if (!(y > 0.0)) continue;
    const double c1y = c1[0] + c1[1] * y + c1[2] * y * y;
    const double b2y = b2[0] + b2[1] * y;
    const double c2y = c2[0] + c2[2] * y * y;
    const double den = a2 * b1 - a1 * b2y;
    double xs[2];
    int nx = 0;
    if (std::abs(den) > 1e-10 * (std::abs(a2 * b1) + std::abs(a1 * b2y) + 1e-300)) {
      xs[nx++] = (a1 * c2y - a2 * c1y) / den;
    } else {
      // Linear elimination degenerate: solve E1 for x (a1 > 0) and keep roots satisfying E2.
      const double disc = b1 * b1 - 4.0 * a1 * c1y;
      if (disc < 0.0) continue;
      const double sq = std::sqrt(disc);
      xs[nx++] = (-b1 + sq) / (2.0 * a1);
      xs[nx++] = (-b1 - sq) / (2.0 * a1);
    }
    for (int k = 0; k < nx; ++k) {
      const double x = xs[k];
      if (!(x > 0.0)) continue;
      const double e2 = a2 * x * x + b2y * x + c2y;
      if (nx == 2 && std::abs(e2) > 1e-6 * (1.0 + std::abs(a2) + std::abs(b2y) + std::abs(c2y))) continue;
      const double nrm = (f[0] - x * f[1]).norm();
      if (!(nrm > 0.0)) continue;
      const double l1 = std::sqrt(d12s) / nrm;
      const V3 Q[3] = {l1 * f[0], x * l1 * f[1], y * l1 * f[2]};
      Eigen::Matrix3d R;
      V3 t;
      if (!p3p_detail::rigidFrom3(P, Q, R, t)) continue;
      out.emplace_back(Mat3<Scalar>(R.cast<Scalar>()), Vec3<Scalar>(t.cast<Scalar>()));
    }
  }
}

}  // namespace hawor
