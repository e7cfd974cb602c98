// hawor/motion/slerp.hpp — spherical and linear interpolation of rotations and vectors.
//
// Used by the pre-fill of missing frames (docs/design.md §7: LERP for translation and betas, SLERP for
// global and joint rotations). Quaternions are Eigen's (w, x, y, z), assumed unit (normalised
// here anyway so that a slightly drifted input still gives a unit result).
#pragma once

#include <Eigen/Geometry>
#include <cmath>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"

namespace hawor {

/// Spherical linear interpolation on the shortest arc between two unit quaternions:
///   slerp(q0, q1, t) = sin((1-t)θ)/sinθ · q0 + sin(tθ)/sinθ · q1,   θ = ∠(q0, ±q1) ∈ [0, π/2]
/// where q1 is negated first when q0·q1 < 0 (q and -q are the same rotation: the short path).
/// θ is computed as 2·atan2(|q0-q1|, |q0+q1|), accurate for small angles. When θ is below
/// Constants<Scalar>::slerpEpsilon() it falls back to normalised LERP (as Eigen's slerp does),
/// which agrees with SLERP to O(θ³). t outside [0,1] extrapolates. The rotation angle moves at a
/// constant rate in t: angle(q0⁻¹·slerp(t)) = t·angle(q0⁻¹·q1). Throws for a zero or
/// non-finite quaternion.
template <typename Scalar>
Eigen::Quaternion<Scalar> slerp(const Eigen::Quaternion<Scalar>& q0,
                                const Eigen::Quaternion<Scalar>& q1, Scalar t) {
  using Vec4Plain = Eigen::Matrix<Scalar, 4, 1, Eigen::DontAlign>;
  const Scalar n0 = q0.coeffs().norm(), n1 = q1.coeffs().norm();
  if (!(n0 > Scalar(0)) || !(n1 > Scalar(0)) || !std::isfinite(n0) || !std::isfinite(n1))
    throw Error("slerp: quaternion is zero or not finite");
  const Vec4Plain a = q0.coeffs().normalized();
  Vec4Plain b = q1.coeffs().normalized();
  if (a.dot(b) < Scalar(0)) b = -b;
  const Scalar theta = Scalar(2) * std::atan2((a - b).norm(), (a + b).norm());
  Vec4Plain r;
  if (theta < Constants<Scalar>::slerpEpsilon()) {
    r = ((Scalar(1) - t) * a + t * b).normalized();
  } else {
    const Scalar s = std::sin(theta);
    r = (std::sin((Scalar(1) - t) * theta) / s) * a + (std::sin(t * theta) / s) * b;
  }
  Eigen::Quaternion<Scalar> q;
  q.coeffs() = r;  // coeffs() order is (x, y, z, w) for both a, b and q
  return q;
}

/// SLERP between two rotations given as axis-angle vectors (angle = norm, radians); the result is
/// the axis-angle of the interpolated rotation (angle in [0, π], as quaternionToAxisAngle gives).
template <typename Scalar>
Vec3<Scalar> slerpAxisAngle(const Vec3<Scalar>& a0, const Vec3<Scalar>& a1, Scalar t) {
  const Eigen::Quaternion<Scalar> q0 = axisAngleToQuaternion(a0);
  const Eigen::Quaternion<Scalar> q1 = axisAngleToQuaternion(a1);
  return quaternionToAxisAngle(slerp(q0, q1, t));
}

/// Linear interpolation a + t·(b − a) of two Eigen vectors (or matrices) of the same size.
template <typename DerivedA, typename DerivedB, typename Scalar>
typename DerivedA::PlainObject lerp(const Eigen::MatrixBase<DerivedA>& a,
                                    const Eigen::MatrixBase<DerivedB>& b, Scalar t) {
  using S = typename DerivedA::Scalar;
  if (a.rows() != b.rows() || a.cols() != b.cols()) throw Error("lerp: operands differ in size");
  return a + S(t) * (b - a);
}

}  // namespace hawor
