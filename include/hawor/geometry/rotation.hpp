// hawor/geometry/rotation.hpp — conversions between rotation representations.
//
// Axis-angle (rotation vector) w = θ·axis, 3x3 rotation matrices, unit quaternions (Eigen's
// (w, x, y, z), docs/design.md §2) and rot6d (first two columns of R flattened row-major,
// [R00, R01, R10, R11, R20, R21], docs/design.md §2 *official*). Every function is stable near θ = 0
// (Taylor branches) and near θ = π (the matrix → axis-angle path goes through a quaternion and
// atan2, never acos of the trace). Pure functions: thread-safe, no allocation.
#pragma once

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>

#include "hawor/common.hpp"

namespace hawor {
namespace detail {

/// Angle below which the rotation coefficient functions use their Taylor series. The closed
/// forms of C, E, D2, D3 cancel catastrophically for small θ (D3 loses ~60ε/θ⁴ relative), so
/// the series are used up to θ = 1 with enough terms that the truncation is below 1e-17 there;
/// above it every closed form is accurate to a few ulps.
template <typename Scalar>
inline Scalar rotationSeriesThreshold() {
  return Scalar(1);
}

/// The scalar functions of θ = |φ| that appear in SO(3)/SE(3) exp, log and Jacobians.
///   A = sin θ / θ                         (Rodrigues, first order)
///   B = (1 − cos θ) / θ²                  (Rodrigues, second order; J_l first order)
///   C = (θ − sin θ) / θ³                  (J_l second order)
///   E = 1/θ² − (1 + cos θ)/(2 θ sin θ)    (J_l⁻¹ second order; written with cot(θ/2) so it
///                                          stays finite at θ = π)
///   D2 = (θ² + 2 cos θ − 2) / (2 θ⁴),  D3 = (2θ − 3 sin θ + θ cos θ) / (2 θ⁵)
///                                         (the SE(3) Q(ρ, φ) block, Barfoot eq. 7.86)
/// Series (θ < 1):  A = Σ (−θ²)^k/(2k+1)!,  B = Σ (−θ²)^k/(2k+2)!,  C = Σ (−θ²)^k/(2k+3)!,
///   D2 = Σ (−θ²)^k/(2k+4)!,  D3 = Σ (k+1)(−θ²)^k/(2k+5)!,  E = Σ_{n≥1} |B_2n| θ^(2n−2)/(2n)!
///   (B_2n the Bernoulli numbers, from the Laurent series of cot).
/// Taylor coefficients in θ² of A, B, C, D2, D3, E (see RotationCoefficients), index k ↔ θ^{2k}.
struct SeriesTables {
  static constexpr int N = 12;
  double A[N], B[N], C[N], D2[N], D3[N], E[N];
};

inline constexpr SeriesTables makeSeriesTables() {
  SeriesTables t{};
  double f = 1.0;  // (2k+1)!
  double sign = 1.0;
  for (int k = 0; k < SeriesTables::N; ++k) {
    const double f2 = f * (2 * k + 2), f3 = f2 * (2 * k + 3), f4 = f3 * (2 * k + 4),
                 f5 = f4 * (2 * k + 5);
    t.A[k] = sign / f;
    t.B[k] = sign / f2;
    t.C[k] = sign / f3;
    t.D2[k] = sign / f4;
    t.D3[k] = sign * (k + 1) / f5;
    sign = -sign;
    f = f3;
  }
  // |B_2n|/(2n)! for n = 1..12 (ratio → 1/(2π)², so 12 terms reach 1e-19 at θ = 1).
  const double e[SeriesTables::N] = {1.0 / 12.0,
                                     1.0 / 720.0,
                                     1.0 / 30240.0,
                                     1.0 / 1209600.0,
                                     1.0 / 47900160.0,
                                     691.0 / 1307674368000.0,
                                     1.0 / 74724249600.0,
                                     3617.0 / 10670622842880000.0,
                                     43867.0 / 5109094217170944000.0,
                                     174611.0 / 802857662698291200000.0,
                                     77683.0 / 14101100039391805440000.0,
                                     236364091.0 / 1693824136731743669452800000.0};
  for (int k = 0; k < SeriesTables::N; ++k) t.E[k] = e[k];
  return t;
}

inline const SeriesTables& seriesTables() {
  static constexpr SeriesTables tables = makeSeriesTables();
  return tables;
}

/// Σ_k c[k]·x^k by Horner's rule.
template <typename Scalar>
inline Scalar horner(const double (&c)[SeriesTables::N], Scalar x) {
  Scalar r = Scalar(c[SeriesTables::N - 1]);
  for (int k = SeriesTables::N - 2; k >= 0; --k) r = r * x + Scalar(c[k]);
  return r;
}

template <typename Scalar>
struct RotationCoefficients {
  Scalar theta, A, B, C, E, D2, D3;

  explicit RotationCoefficients(Scalar theta_sq) {
    using std::cos;
    using std::sin;
    using std::sqrt;
    theta = sqrt(theta_sq);
    const Scalar t2 = theta_sq;
    if (theta < rotationSeriesThreshold<Scalar>()) {
      // Horner evaluation of fixed tables (11 terms: the first omitted term is below
      // 1/23! < 4e-23 at θ = 1). Independent chains, no loop-carried state shared between
      // them (clang 14's wasm -O3 -msimd128 miscompiled an interleaved-accumulator loop).
      const SeriesTables& T = seriesTables();
      A = horner(T.A, t2);
      B = horner(T.B, t2);
      C = horner(T.C, t2);
      D2 = horner(T.D2, t2);
      D3 = horner(T.D3, t2);
      E = horner(T.E, t2);
    } else {
      const Scalar s = sin(theta), c = cos(theta);
      const Scalar half_s = sin(theta / Scalar(2)), half_c = cos(theta / Scalar(2));
      A = s / theta;
      B = Scalar(2) * half_s * half_s / t2;  // 1 − cos θ = 2 sin²(θ/2), no cancellation
      C = (theta - s) / (t2 * theta);
      // (1 + cos θ)/sin θ = cot(θ/2): finite at θ = π (singular only at θ = 2π).
      E = Scalar(1) / t2 - half_c / (Scalar(2) * theta * half_s);
      D2 = (t2 - Scalar(4) * half_s * half_s) / (Scalar(2) * t2 * t2);
      D3 = (Scalar(2) * theta - Scalar(3) * s + theta * c) / (Scalar(2) * t2 * t2 * theta);
    }
  }
};

}  // namespace detail

/// Skew-symmetric matrix of v: hat(v)·p = v × p.
template <typename Derived>
Mat3<typename Derived::Scalar> hat(const Eigen::MatrixBase<Derived>& v) {
  EIGEN_STATIC_ASSERT_VECTOR_SPECIFIC_SIZE(Derived, 3);
  using S = typename Derived::Scalar;
  Mat3<S> m;
  m << S(0), -v(2), v(1),  //
      v(2), S(0), -v(0),   //
      -v(1), v(0), S(0);
  return m;
}

/// Inverse of hat: the vector of the skew-symmetric part of m, ((m21−m12)/2, (m02−m20)/2,
/// (m10−m01)/2). For an exactly skew m this is the exact inverse of hat.
template <typename Derived>
Vec3<typename Derived::Scalar> vee(const Eigen::MatrixBase<Derived>& m) {
  EIGEN_STATIC_ASSERT_MATRIX_SPECIFIC_SIZE(Derived, 3, 3);
  using S = typename Derived::Scalar;
  return Vec3<S>((m(2, 1) - m(1, 2)) / S(2), (m(0, 2) - m(2, 0)) / S(2),
                 (m(1, 0) - m(0, 1)) / S(2));
}

/// Rodrigues: R = I + A·hat(w) + B·hat(w)², A = sin θ/θ, B = (1−cos θ)/θ², θ = |w|.
template <typename Derived>
Mat3<typename Derived::Scalar> axisAngleToMatrix(const Eigen::MatrixBase<Derived>& w) {
  EIGEN_STATIC_ASSERT_VECTOR_SPECIFIC_SIZE(Derived, 3);
  using S = typename Derived::Scalar;
  const Vec3<S> v = w;
  const detail::RotationCoefficients<S> k(v.squaredNorm());
  const Mat3<S> K = hat(v);
  return Mat3<S>::Identity() + k.A * K + k.B * (K * K);
}

/// q = (cos(θ/2), sin(θ/2)/θ · w). The factor sin(θ/2)/θ uses its series near θ = 0.
template <typename Derived>
Eigen::Quaternion<typename Derived::Scalar> axisAngleToQuaternion(
    const Eigen::MatrixBase<Derived>& w) {
  EIGEN_STATIC_ASSERT_VECTOR_SPECIFIC_SIZE(Derived, 3);
  using S = typename Derived::Scalar;
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Vec3<S> v = w;
  const S t2 = v.squaredNorm();
  const S theta = sqrt(t2);
  S half_sinc, c;
  if (theta < S(1e-3)) {
    // sin(θ/2)/θ = 1/2 − θ²/48 + θ⁴/3840 − θ⁶/645120 (only to avoid 0/0: the closed form
    // has no cancellation)
    half_sinc = S(0.5) - t2 / S(48) + t2 * t2 / S(3840) - t2 * t2 * t2 / S(645120);
    c = cos(theta / S(2));
  } else {
    half_sinc = sin(theta / S(2)) / theta;
    c = cos(theta / S(2));
  }
  return Eigen::Quaternion<S>(c, half_sinc * v(0), half_sinc * v(1), half_sinc * v(2));
}

/// Shortest rotation vector of q (angle in [0, π]): q and −q give the same result, q need not
/// be normalised. θ = 2·atan2(|v|, |w|) is accurate at every angle (no acos).
/// Throws hawor::Error for a zero or non-finite quaternion.
template <typename Derived>
Vec3<typename Derived::Scalar> quaternionToAxisAngle(const Eigen::QuaternionBase<Derived>& q) {
  using S = typename Derived::Scalar;
  using std::atan2;
  using std::sqrt;
  const S n2 = q.vec().squaredNorm();
  const S w0 = q.w();
  if (!(n2 + w0 * w0 > S(0)) || !std::isfinite(n2 + w0 * w0)) {
    throw Error("quaternionToAxisAngle: quaternion is zero or not finite");
  }
  // Pick the representative with w >= 0 so that the angle is the short one.
  const S sign = w0 < S(0) ? S(-1) : S(1);
  const S w = sign * w0;
  const S n = sqrt(n2);
  S factor;  // θ / |v|, applied to sign·v
  if (n < S(1e-3) * w) {
    // 2·atan(x)/n with x = n/w: 2/w·(1 − x²/3 + x⁴/5 − x⁶/7); the closed form is accurate
    // for any n > 0, the series only avoids 0/0.
    const S x2 = n2 / (w * w);
    factor = S(2) / w * (S(1) - x2 / S(3) + x2 * x2 / S(5) - x2 * x2 * x2 / S(7));
  } else {
    factor = S(2) * atan2(n, w) / n;
  }
  return Vec3<S>(sign * factor * q.x(), sign * factor * q.y(), sign * factor * q.z());
}

/// Unit quaternion of a rotation matrix (Shepperd's method: the largest of w², x², y², z² is
/// taken from the diagonal, the rest from off-diagonal sums, so every angle is accurate).
/// The result has w >= 0 and is normalised; for a slightly non-orthonormal input it is the
/// quaternion of a nearby rotation (use projectToSO3 first for a badly non-orthonormal one).
template <typename Derived>
Eigen::Quaternion<typename Derived::Scalar> matrixToQuaternion(
    const Eigen::MatrixBase<Derived>& m) {
  EIGEN_STATIC_ASSERT_MATRIX_SPECIFIC_SIZE(Derived, 3, 3);
  using S = typename Derived::Scalar;
  using std::sqrt;
  const Mat3<S> R = m;
  if (!R.allFinite()) throw Error("matrixToQuaternion: matrix is not finite");
  const S tr = R.trace();
  S w, x, y, z;
  if (tr >= R(0, 0) && tr >= R(1, 1) && tr >= R(2, 2)) {
    const S r = sqrt(S(1) + tr);  // 2|w|
    const S f = S(0.5) / r;
    w = S(0.5) * r;
    x = (R(2, 1) - R(1, 2)) * f;
    y = (R(0, 2) - R(2, 0)) * f;
    z = (R(1, 0) - R(0, 1)) * f;
  } else if (R(0, 0) >= R(1, 1) && R(0, 0) >= R(2, 2)) {
    const S r = sqrt(S(1) + R(0, 0) - R(1, 1) - R(2, 2));  // 2|x|
    const S f = S(0.5) / r;
    x = S(0.5) * r;
    w = (R(2, 1) - R(1, 2)) * f;
    y = (R(0, 1) + R(1, 0)) * f;
    z = (R(0, 2) + R(2, 0)) * f;
  } else if (R(1, 1) >= R(2, 2)) {
    const S r = sqrt(S(1) - R(0, 0) + R(1, 1) - R(2, 2));  // 2|y|
    const S f = S(0.5) / r;
    y = S(0.5) * r;
    w = (R(0, 2) - R(2, 0)) * f;
    x = (R(0, 1) + R(1, 0)) * f;
    z = (R(1, 2) + R(2, 1)) * f;
  } else {
    const S r = sqrt(S(1) - R(0, 0) - R(1, 1) + R(2, 2));  // 2|z|
    const S f = S(0.5) / r;
    z = S(0.5) * r;
    w = (R(1, 0) - R(0, 1)) * f;
    x = (R(0, 2) + R(2, 0)) * f;
    y = (R(1, 2) + R(2, 1)) * f;
  }
  Eigen::Quaternion<S> q(w, x, y, z);
  const S n = q.norm();
  if (!(n > S(0)) || !std::isfinite(n)) {
    throw Error("matrixToQuaternion: matrix is not a rotation (degenerate)");
  }
  q.coeffs() /= (q.w() < S(0) ? -n : n);
  return q;
}

/// Rotation matrix of a quaternion (normalised first). Throws for a zero/non-finite quaternion.
template <typename Derived>
Mat3<typename Derived::Scalar> quaternionToMatrix(const Eigen::QuaternionBase<Derived>& q) {
  using S = typename Derived::Scalar;
  const S n = q.norm();
  if (!(n > S(0)) || !std::isfinite(n)) {
    throw Error("quaternionToMatrix: quaternion is zero or not finite");
  }
  const Eigen::Quaternion<S> u(q.w() / n, q.x() / n, q.y() / n, q.z() / n);
  return u.toRotationMatrix();
}

/// Rotation vector (angle in [0, π]) of a rotation matrix, via the quaternion: accurate near
/// 0 and near π, where acos((tr R − 1)/2) loses half the digits.
template <typename Derived>
Vec3<typename Derived::Scalar> matrixToAxisAngle(const Eigen::MatrixBase<Derived>& m) {
  return quaternionToAxisAngle(matrixToQuaternion(m));
}

/// rot6d of R: its first two columns flattened row-major, [R00, R01, R10, R11, R20, R21]
/// (docs/design.md §2, the official layout).
template <typename Derived>
Vec6<typename Derived::Scalar> matrixToRot6d(const Eigen::MatrixBase<Derived>& m) {
  EIGEN_STATIC_ASSERT_MATRIX_SPECIFIC_SIZE(Derived, 3, 3);
  using S = typename Derived::Scalar;
  Vec6<S> r;
  r << m(0, 0), m(0, 1), m(1, 0), m(1, 1), m(2, 0), m(2, 1);
  return r;
}

/// Rotation matrix from rot6d: Gram–Schmidt on the two columns a = (r0, r2, r4),
/// b = (r1, r3, r5): c0 = a/|a|, c1 = normalise(b − (c0·b)c0), c2 = c0 × c1.
/// Throws hawor::Error when a column is zero or the two are parallel (or non-finite).
template <typename Derived>
Mat3<typename Derived::Scalar> rot6dToMatrix(const Eigen::MatrixBase<Derived>& r) {
  EIGEN_STATIC_ASSERT_VECTOR_SPECIFIC_SIZE(Derived, 6);
  using S = typename Derived::Scalar;
  const Vec3<S> a(r(0), r(2), r(4));
  const Vec3<S> b(r(1), r(3), r(5));
  if (!a.allFinite() || !b.allFinite()) throw Error("rot6dToMatrix: input is not finite");
  const S na = a.norm();
  if (!(na > S(0))) throw Error("rot6dToMatrix: first column is zero");
  const Vec3<S> c0 = a / na;
  const Vec3<S> b_perp = b - c0.dot(b) * c0;
  const S nb = b_perp.norm();
  // Relative test: b must not be (numerically) parallel to a.
  if (!(nb > S(16) * std::numeric_limits<S>::epsilon() * b.norm())) {
    throw Error("rot6dToMatrix: columns are zero or parallel");
  }
  const Vec3<S> c1 = b_perp / nb;
  Mat3<S> R;
  R.col(0) = c0;
  R.col(1) = c1;
  R.col(2) = c0.cross(c1);
  return R;
}

/// Nearest rotation to m in the Frobenius norm: U·diag(1, 1, det(U Vᵀ))·Vᵀ from the SVD
/// m = U Σ Vᵀ. Throws hawor::Error for a non-finite matrix.
template <typename Derived>
Mat3<typename Derived::Scalar> projectToSO3(const Eigen::MatrixBase<Derived>& m) {
  EIGEN_STATIC_ASSERT_MATRIX_SPECIFIC_SIZE(Derived, 3, 3);
  using S = typename Derived::Scalar;
  const Eigen::Matrix<S, 3, 3> M = m;
  if (!M.allFinite()) throw Error("projectToSO3: matrix is not finite");
  const Eigen::JacobiSVD<Eigen::Matrix<S, 3, 3>> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix<S, 3, 3> U = svd.matrixU(), V = svd.matrixV();
  Eigen::Matrix<S, 3, 1> d(S(1), S(1), (U * V.transpose()).determinant() < S(0) ? S(-1) : S(1));
  return U * d.asDiagonal() * V.transpose();
}

}  // namespace hawor
