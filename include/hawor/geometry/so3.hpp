// hawor/geometry/so3.hpp — the rotation group SO(3) (after Sophus' SO3 and manif's SO3).
//
// Storage: a unit quaternion (Eigen's (w, x, y, z), unaligned so the class is safe as a member
// in WASM). Tangent: the rotation vector φ ∈ R³, exp(φ) = rotation by |φ| about φ/|φ|.
//
// Perturbation conventions (both are provided; names say which):
//   left:   R ⊕ δ = exp(δ)·R      (δ in the world / outer frame)
//   right:  R ⊕ δ = R·exp(δ)      (δ in the body / inner frame)
//   J_r(φ): exp(φ + δ) ≈ exp(φ)·exp(J_r(φ)·δ)   J_l(φ): exp(φ + δ) ≈ exp(J_l(φ)·δ)·exp(φ)
//   J_l(φ) = J_r(−φ) = J_r(φ)ᵀ,  Adj = R (R·exp(δ)·Rᵀ = exp(R·δ)).
// A value type: thread-safe to read concurrently.
#pragma once

#include <Eigen/Geometry>
#include <cmath>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"

namespace hawor {

template <typename Scalar_>
class SO3 {
 public:
  using Scalar = Scalar_;
  using Tangent = Vec3<Scalar>;
  using Point = Vec3<Scalar>;
  using Matrix = Mat3<Scalar>;
  using Quaternion = Eigen::Quaternion<Scalar>;
  static constexpr int DoF = 3;

  /// Identity rotation.
  SO3() : q_(Scalar(1), Scalar(0), Scalar(0), Scalar(0)) {}

  /// exp(φ): rotation by angle |φ| about φ/|φ| (series near 0, any |φ|).
  static SO3 exp(const Tangent& phi) { return SO3(axisAngleToQuaternion(phi), NoCheck{}); }

  /// log(R) = rotation vector with angle in [0, π] (the shortest).
  Tangent log() const { return quaternionToAxisAngle(q_); }

  /// Rotation angle in [0, π].
  Scalar angle() const { return log().norm(); }

  SO3 inverse() const { return SO3(Quaternion(q_.w(), -q_.x(), -q_.y(), -q_.z()), NoCheck{}); }

  /// Composition (this·other). The product is renormalised so long chains do not drift.
  SO3 operator*(const SO3& other) const {
    Quaternion q = Quaternion(q_) * Quaternion(other.q_);
    q.normalize();
    return SO3(q, NoCheck{});
  }
  SO3& operator*=(const SO3& other) { return *this = *this * other; }

  /// Action on a point: R·p.
  Point operator*(const Point& p) const { return Quaternion(q_)._transformVector(p); }

  Matrix matrix() const { return Quaternion(q_).toRotationMatrix(); }
  /// Unit quaternion (w, x, y, z); its sign is whatever the construction produced.
  Quaternion quaternion() const { return Quaternion(q_); }

  /// From a rotation matrix (Shepperd's method; assumes R is orthonormal up to rounding: use
  /// projectToSO3 first for a noisy matrix). Throws hawor::Error for a non-finite matrix.
  static SO3 fromMatrix(const Matrix& R) { return SO3(matrixToQuaternion(R), NoCheck{}); }
  /// From any non-zero quaternion (normalised here). Throws hawor::Error for zero/non-finite.
  template <typename Derived>
  static SO3 fromQuaternion(const Eigen::QuaternionBase<Derived>& q) {
    const Scalar n = q.norm();
    if (!(n > Scalar(0)) || !std::isfinite(n)) {
      throw Error("SO3::fromQuaternion: quaternion is zero or not finite");
    }
    return SO3(Quaternion(q.w() / n, q.x() / n, q.y() / n, q.z() / n), NoCheck{});
  }
  /// exp of a rotation vector (alias of exp, for readability at call sites).
  static SO3 fromAxisAngle(const Tangent& w) { return exp(w); }

  /// Adjoint: R·exp(δ)·Rᵀ = exp(Adj·δ), Adj = R.
  Matrix Adj() const { return matrix(); }

  static Matrix hat(const Tangent& v) { return ::hawor::hat(v); }
  static Tangent vee(const Matrix& m) { return ::hawor::vee(m); }

  /// J_l(φ) = I + (1−cos θ)/θ²·φ^ + (θ−sin θ)/θ³·φ^²  (exp(φ+δ) ≈ exp(J_l δ)·exp(φ)).
  static Matrix leftJacobian(const Tangent& phi) {
    const detail::RotationCoefficients<Scalar> k(phi.squaredNorm());
    const Matrix K = hat(phi);
    return Matrix::Identity() + k.B * K + k.C * (K * K);
  }
  /// J_r(φ) = J_l(−φ)  (exp(φ+δ) ≈ exp(φ)·exp(J_r δ)).
  static Matrix rightJacobian(const Tangent& phi) { return leftJacobian(-phi); }
  /// J_l(φ)⁻¹ = I − φ^/2 + (1/θ² − (1+cos θ)/(2θ sin θ))·φ^²; singular only at θ = 2π.
  static Matrix leftJacobianInverse(const Tangent& phi) {
    const detail::RotationCoefficients<Scalar> k(phi.squaredNorm());
    const Matrix K = hat(phi);
    return Matrix::Identity() - Scalar(0.5) * K + k.E * (K * K);
  }
  /// J_r(φ)⁻¹ = J_l(−φ)⁻¹.
  static Matrix rightJacobianInverse(const Tangent& phi) { return leftJacobianInverse(-phi); }

  /// d(exp(δ)·R·p)/dδ at δ = 0 = −(R p)^  (left perturbation of the rotation).
  Matrix actJacobianLeft(const Point& p) const { return -hat((*this) * p); }
  /// d(R·exp(δ)·p)/dδ at δ = 0 = −R·p^  (right perturbation of the rotation).
  Matrix actJacobianRight(const Point& p) const { return -matrix() * hat(p); }
  /// d(R·p)/dp = R.
  Matrix actJacobianPoint() const { return matrix(); }

  template <typename T>
  SO3<T> cast() const {
    return SO3<T>::fromQuaternion(Eigen::Quaternion<T>(q_.template cast<T>()));
  }

  /// True when the rotations agree up to tol in angle (q and −q are the same rotation).
  bool isApprox(const SO3& other, Scalar tol) const {
    return (inverse() * other).angle() <= tol;
  }

 private:
  struct NoCheck {};
  template <typename Derived>
  SO3(const Eigen::QuaternionBase<Derived>& unit_q, NoCheck) : q_(unit_q) {}

  Eigen::Quaternion<Scalar, Eigen::DontAlign> q_;
};

using SO3f = SO3<float>;
using SO3d = SO3<double>;

}  // namespace hawor
