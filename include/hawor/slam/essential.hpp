// hawor/slam/essential.hpp — the essential matrix: the 5-point minimal solver (Stewénius, Engels &
// Nistér 2006, "Recent developments on direct relative orientation": Gröbner-basis / action-matrix
// form of Nistér's constraints), the Sampson error, and the decomposition into (R, t).
//
// Convention: normalised image coordinates x = K⁻¹(u, v, 1) (z = 1), a point X1 in camera 1 maps
// to X2 = R·X1 + t in camera 2, E = [t]×·R and x2ᵀ·E·x1 = 0 (Hartley & Zisserman §9.6).
// (R, t) is therefore camera-1-to-camera-2, i.e. T_c2_c1; the camera-to-world pose of camera 2
// with camera 1 as world is its inverse.
//
// 5-point solver: the 5 epipolar equations leave E in a 4-dimensional null space
// E = x·X + y·Y + z·Z + W. The cubic constraints det(E) = 0 and 2·E·Eᵀ·E − tr(E·Eᵀ)·E = 0 give
// 10 equations in the 20 monomials of degree ≤ 3 in (x, y, z); eliminating the 10 cubic monomials
// (Gauss–Jordan) leaves a 10×10 action matrix of multiplication by x on the basis
// [x², xy, xz, y², yz, z², x, y, z, 1] whose real eigenvectors give the (up to 10) solutions.
// The polynomial elimination loses several digits, so it is always computed in double (the
// returned matrices are cast to Scalar).
// Pure functions, thread-safe.
#pragma once

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"

namespace hawor {

namespace essential_detail {

// Monomials of degree ≤ 3 in (x, y, z), in the column order of the elimination template:
// the 10 cubics first (eliminated), then the basis [x², xy, xz, y², yz, z², x, y, z, 1].
constexpr int kMonoExp[20][3] = {{3, 0, 0}, {2, 1, 0}, {2, 0, 1}, {1, 2, 0}, {1, 1, 1},
                                 {1, 0, 2}, {0, 3, 0}, {0, 2, 1}, {0, 1, 2}, {0, 0, 3},
                                 {2, 0, 0}, {1, 1, 0}, {1, 0, 1}, {0, 2, 0}, {0, 1, 1},
                                 {0, 0, 2}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}};

constexpr int monoIndex(int a, int b, int c) {
  for (int i = 0; i < 20; ++i) {
    if (kMonoExp[i][0] == a && kMonoExp[i][1] == b && kMonoExp[i][2] == c) return i;
  }
  return -1;
}

/// Index of the product of monomials i and j, or −1 when its degree exceeds 3.
constexpr int productIndex(int i, int j) {
  return monoIndex(kMonoExp[i][0] + kMonoExp[j][0], kMonoExp[i][1] + kMonoExp[j][1],
                   kMonoExp[i][2] + kMonoExp[j][2]);
}

/// A polynomial of degree ≤ 3 in (x, y, z): coefficients in the kMonoExp order. `lo` is the
/// first index that may be non-zero (16 for linear, 10 for quadratic): it bounds the products.
struct Poly {
  std::array<double, 20> c{};
  int lo = 19;
};

inline Poly mul(const Poly& a, const Poly& b) {
  Poly r;
  r.lo = 0;
  for (int i = a.lo; i < 20; ++i) {
    if (a.c[i] == 0.0) continue;
    for (int j = b.lo; j < 20; ++j) {
      const int k = productIndex(i, j);
      if (k >= 0) r.c[k] += a.c[i] * b.c[j];
    }
  }
  // the lowest possibly non-zero index of the product
  const int degA = a.lo >= 16 ? 1 : (a.lo >= 10 ? 2 : 3);
  const int degB = b.lo >= 16 ? 1 : (b.lo >= 10 ? 2 : 3);
  const int deg = degA + degB;
  r.lo = deg >= 3 ? 0 : (deg == 2 ? 10 : 16);
  return r;
}

inline Poly add(const Poly& a, const Poly& b, double sb = 1.0) {
  Poly r;
  for (int i = 0; i < 20; ++i) r.c[i] = a.c[i] + sb * b.c[i];
  r.lo = a.lo < b.lo ? a.lo : b.lo;
  return r;
}

inline Poly scaled(const Poly& a, double s) {
  Poly r = a;
  for (double& v : r.c) v *= s;
  return r;
}

}  // namespace essential_detail

/// The 5-point solver (file comment): every essential matrix (unit Frobenius norm) consistent with
/// the five correspondences x1[i] ↔ x2[i] (normalised coordinates), appended to `out` (0..10 of
/// them; none for a degenerate sample).
template <typename Scalar>
void essentialFivePoint(const Vec2<Scalar>* x1, const Vec2<Scalar>* x2,
                        std::vector<Mat3<Scalar>>& out) {
  using namespace essential_detail;
  using M3 = Eigen::Matrix3d;
  // Epipolar rows kron(x2, x1) · vec_rowmajor(E) = 0, transposed (9×5) for the QR null space.
  Eigen::Matrix<double, 9, 5> Qt;
  for (int i = 0; i < 5; ++i) {
    const Eigen::Vector3d a(double(x1[i](0)), double(x1[i](1)), 1.0);
    const Eigen::Vector3d b(double(x2[i](0)), double(x2[i](1)), 1.0);
    if (!a.allFinite() || !b.allFinite()) return;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) Qt(3 * r + c, i) = b(r) * a(c);
    }
  }
  const Eigen::HouseholderQR<Eigen::Matrix<double, 9, 5>> qr(Qt);
  const Eigen::Matrix<double, 9, 9> Qfull = qr.householderQ();
  // Rank check: the R factor's diagonal must not vanish (5 independent equations).
  const double r0 = std::abs(qr.matrixQR()(0, 0));
  for (int i = 0; i < 5; ++i) {
    if (!(std::abs(qr.matrixQR()(i, i)) > 1e-12 * r0)) return;
  }
  // Null-space basis X, Y, Z, W (columns 5..8), as 3×3 row-major matrices.
  M3 B[4];
  for (int k = 0; k < 4; ++k) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) B[k](r, c) = Qfull(3 * r + c, 5 + k);
    }
  }
  // E as linear polynomials: E_rc = x·X_rc + y·Y_rc + z·Z_rc + W_rc (monomials 16..19).
  Poly E[3][3];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      E[r][c].lo = 16;
      E[r][c].c[16] = B[0](r, c);
      E[r][c].c[17] = B[1](r, c);
      E[r][c].c[18] = B[2](r, c);
      E[r][c].c[19] = B[3](r, c);
    }
  }
  // E·Eᵀ (symmetric, quadratic) and its trace.
  Poly EEt[3][3];
  for (int r = 0; r < 3; ++r) {
    for (int c = r; c < 3; ++c) {
      Poly s = mul(E[r][0], E[c][0]);
      s = add(s, mul(E[r][1], E[c][1]));
      s = add(s, mul(E[r][2], E[c][2]));
      s.lo = 10;
      EEt[r][c] = s;
      EEt[c][r] = s;
    }
  }
  Poly tr = add(add(EEt[0][0], EEt[1][1]), EEt[2][2]);
  tr.lo = 10;
  Eigen::Matrix<double, 10, 20> A;
  // 2·E·Eᵀ·E − tr(E·Eᵀ)·E = 0: nine cubic equations.
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      Poly s = mul(EEt[r][0], E[0][c]);
      s = add(s, mul(EEt[r][1], E[1][c]));
      s = add(s, mul(EEt[r][2], E[2][c]));
      const Poly eq = add(scaled(s, 2.0), mul(tr, E[r][c]), -1.0);
      for (int k = 0; k < 20; ++k) A(3 * r + c, k) = eq.c[k];
    }
  }
  // det(E) = 0 by cofactors along the first row.
  {
    const Poly m0 = add(mul(E[1][1], E[2][2]), mul(E[1][2], E[2][1]), -1.0);
    const Poly m1 = add(mul(E[1][0], E[2][2]), mul(E[1][2], E[2][0]), -1.0);
    const Poly m2 = add(mul(E[1][0], E[2][1]), mul(E[1][1], E[2][0]), -1.0);
    Poly d = add(add(mul(E[0][0], m0), mul(E[0][1], m1), -1.0), mul(E[0][2], m2));
    for (int k = 0; k < 20; ++k) A(9, k) = d.c[k];
  }
  // Eliminate the cubic monomials: [C | D] → [I | C⁻¹D].
  const Eigen::Matrix<double, 10, 10> C = A.template leftCols<10>();
  const Eigen::FullPivLU<Eigen::Matrix<double, 10, 10>> lu(C);
  if (!lu.isInvertible()) return;
  const Eigen::Matrix<double, 10, 10> G = lu.solve(A.template rightCols<10>());
  if (!G.allFinite()) return;
  // Action matrix of multiplication by x on b = [x², xy, xz, y², yz, z², x, y, z, 1]:
  // x·b = [x³, x²y, x²z, xy², xyz, xz², x², xy, xz, x]; the first six are −G rows 0..5.
  Eigen::Matrix<double, 10, 10> M = Eigen::Matrix<double, 10, 10>::Zero();
  M.template topRows<6>() = -G.template topRows<6>();
  M(6, 0) = 1.0;
  M(7, 1) = 1.0;
  M(8, 2) = 1.0;
  M(9, 6) = 1.0;
  const Eigen::EigenSolver<Eigen::Matrix<double, 10, 10>> es(M, true);
  if (es.info() != Eigen::Success) return;
  const auto vals = es.eigenvalues();
  const auto vecs = es.eigenvectors();
  for (int k = 0; k < 10; ++k) {
    if (std::abs(vals(k).imag()) > 1e-9 * (1.0 + std::abs(vals(k).real()))) continue;
    const std::complex<double> v9 = vecs(9, k);
    if (!(std::abs(v9) > 1e-14)) continue;
    const double x = (vecs(6, k) / v9).real();
    const double y = (vecs(7, k) / v9).real();
    const double z = (vecs(8, k) / v9).real();
    M3 Ek = x * B[0] + y * B[1] + z * B[2] + B[3];
    const double n = Ek.norm();
    if (!(n > 0.0) || !Ek.allFinite()) continue;
    Ek /= n;
    out.push_back(Ek.cast<Scalar>());
  }
}

/// Squared Sampson distance of x1 ↔ x2 (normalised coordinates) to the epipolar geometry of E:
/// (x2ᵀEx1)² / ((Ex1)₀² + (Ex1)₁² + (Eᵀx2)₀² + (Eᵀx2)₁²), the first-order geometric error.
template <typename Scalar>
Scalar sampsonErrorSq(const Mat3<Scalar>& E, const Vec2<Scalar>& x1, const Vec2<Scalar>& x2) {
  const Eigen::Matrix<Scalar, 3, 1> a(x1(0), x1(1), Scalar(1)), b(x2(0), x2(1), Scalar(1));
  const Eigen::Matrix<Scalar, 3, 1> Ea = E * a, Etb = E.transpose() * b;
  const Scalar num = b.dot(Ea);
  const Scalar den = Ea(0) * Ea(0) + Ea(1) * Ea(1) + Etb(0) * Etb(0) + Etb(1) * Etb(1);
  return den > Scalar(0) ? num * num / den : std::numeric_limits<Scalar>::infinity();
}

/// Squared distances of x2 to the epipolar line E·x1 (image 2) and of x1 to Eᵀ·x2 (image 1),
/// normalised units (the per-image errors of ORB-SLAM's model-selection score).
template <typename Scalar>
void epipolarLineDistancesSq(const Mat3<Scalar>& E, const Vec2<Scalar>& x1,
                             const Vec2<Scalar>& x2, Scalar& d1Sq, Scalar& d2Sq) {
  const Eigen::Matrix<Scalar, 3, 1> a(x1(0), x1(1), Scalar(1)), b(x2(0), x2(1), Scalar(1));
  const Eigen::Matrix<Scalar, 3, 1> l2 = E * a, l1 = E.transpose() * b;
  const Scalar num = b.dot(l2);
  const Scalar n2 = l2(0) * l2(0) + l2(1) * l2(1), n1 = l1(0) * l1(0) + l1(1) * l1(1);
  const Scalar inf = std::numeric_limits<Scalar>::infinity();
  d2Sq = n2 > Scalar(0) ? num * num / n2 : inf;
  d1Sq = n1 > Scalar(0) ? num * num / n1 : inf;
}

/// E = [t]×·R (the essential matrix of the motion X2 = R·X1 + t).
template <typename Scalar>
Mat3<Scalar> essentialFromMotion(const Mat3<Scalar>& R, const Vec3<Scalar>& t) {
  return hat(t) * R;
}

/// The four motions (R, t), |t| = 1, with [t]×R ∝ E (Hartley & Zisserman Result 9.19):
/// E = U·diag(1, 1, 0)·Vᵀ with det U = det V = +1, W = [0 −1 0; 1 0 0; 0 0 1],
/// R ∈ {U W Vᵀ, U Wᵀ Vᵀ}, t = ±U₃. Exactly one of the four puts the scene in front of both cameras
/// (cheirality, checked by the caller). Returns false for a non-finite E.
template <typename Scalar>
bool decomposeEssential(const Mat3<Scalar>& E, Mat3<Scalar> R[4], Vec3<Scalar> t[4]) {
  if (!E.allFinite()) return false;
  const Eigen::Matrix3d Ed = E.template cast<double>();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(Ed, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
  if (U.determinant() < 0) U = -U;
  if (V.determinant() < 0) V = -V;
  Eigen::Matrix3d W;
  W << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Eigen::Matrix3d Ra = U * W * V.transpose(), Rb = U * W.transpose() * V.transpose();
  const Eigen::Vector3d u3 = U.col(2).normalized();
  R[0] = Ra.cast<Scalar>();
  t[0] = u3.cast<Scalar>();
  R[1] = Ra.cast<Scalar>();
  t[1] = (-u3).cast<Scalar>();
  R[2] = Rb.cast<Scalar>();
  t[2] = u3.cast<Scalar>();
  R[3] = Rb.cast<Scalar>();
  t[3] = (-u3).cast<Scalar>();
  return true;
}

}  // namespace hawor
