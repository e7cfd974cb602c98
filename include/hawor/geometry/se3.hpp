// hawor/geometry/se3.hpp — rigid motions SE(3) (after Sophus' SE3; Jacobians after Barfoot,
// "State Estimation for Robotics", §7.1).
//
// T = (R, t) acts as p ↦ R·p + t. Poses are camera-to-world unless a name says otherwise
// (docs/design.md §2): T_w_c maps camera points to world points.
// Tangent ξ = (ρ, φ) ∈ R⁶: ρ (translation part) first, φ (rotation vector) second — Sophus'
// order. exp(ξ) = (exp(φ), J_l(φ)·ρ).
// Perturbations: left T ⊕ δ = exp(δ)·T, right T ⊕ δ = T·exp(δ); J_l/J_r as in so3.hpp
// (exp(ξ+δ) ≈ exp(J_l δ)·exp(ξ) ≈ exp(ξ)·exp(J_r δ)).
// A value type: thread-safe to read concurrently.
#pragma once

#include "hawor/common.hpp"
#include "hawor/geometry/so3.hpp"

namespace hawor {

template <typename Scalar_>
class SE3 {
 public:
  using Scalar = Scalar_;
  using Tangent = Vec6<Scalar>;
  using Point = Vec3<Scalar>;
  using Matrix = Mat4<Scalar>;
  using Mat6 = Eigen::Matrix<Scalar, 6, 6, Eigen::DontAlign>;
  using Mat36 = Eigen::Matrix<Scalar, 3, 6, Eigen::DontAlign>;
  static constexpr int DoF = 6;

  /// Identity.
  SE3() : R_(), t_(Point::Zero()) {}
  SE3(const SO3<Scalar>& R, const Point& t) : R_(R), t_(t) {}
  /// From a rotation matrix (orthonormal up to rounding) and a translation.
  SE3(const Mat3<Scalar>& R, const Point& t) : R_(SO3<Scalar>::fromMatrix(R)), t_(t) {}

  /// From a homogeneous 4x4 [R t; 0 1] (the last row is not checked).
  static SE3 fromMatrix(const Matrix& T) {
    return SE3(Mat3<Scalar>(T.template topLeftCorner<3, 3>()), Point(T.template topRightCorner<3, 1>()));
  }

  /// exp(ρ, φ) = (exp(φ), J_l(φ)·ρ).
  static SE3 exp(const Tangent& xi) {
    const Point rho = xi.template head<3>();
    const Point phi = xi.template tail<3>();
    return SE3(SO3<Scalar>::exp(phi), Point(SO3<Scalar>::leftJacobian(phi) * rho));
  }

  /// log(T) = (J_l(φ)⁻¹·t, φ) with φ = log(R), |φ| ≤ π.
  Tangent log() const {
    const Point phi = R_.log();
    Tangent xi;
    xi.template head<3>() = SO3<Scalar>::leftJacobianInverse(phi) * t_;
    xi.template tail<3>() = phi;
    return xi;
  }

  SE3 inverse() const {
    const SO3<Scalar> Ri = R_.inverse();
    return SE3(Ri, Point(-(Ri * t_)));
  }

  /// (R1, t1)·(R2, t2) = (R1 R2, R1 t2 + t1).
  SE3 operator*(const SE3& o) const { return SE3(R_ * o.R_, Point(R_ * o.t_ + t_)); }
  SE3& operator*=(const SE3& o) { return *this = *this * o; }

  /// R·p + t.
  Point operator*(const Point& p) const { return R_ * p + t_; }

  /// [R t; 0 1].
  Matrix matrix() const {
    Matrix T = Matrix::Identity();
    T.template topLeftCorner<3, 3>() = R_.matrix();
    T.template topRightCorner<3, 1>() = t_;
    return T;
  }

  /// Adjoint for (ρ, φ): T·exp(ξ)·T⁻¹ = exp(Adj·ξ), Adj = [R, t^R; 0, R].
  Mat6 Adj() const {
    const Mat3<Scalar> R = R_.matrix();
    Mat6 A = Mat6::Zero();
    A.template topLeftCorner<3, 3>() = R;
    A.template topRightCorner<3, 3>() = ::hawor::hat(t_) * R;
    A.template bottomRightCorner<3, 3>() = R;
    return A;
  }

  const SO3<Scalar>& rotation() const { return R_; }
  SO3<Scalar>& rotation() { return R_; }
  Mat3<Scalar> rotationMatrix() const { return R_.matrix(); }
  const Point& translation() const { return t_; }
  Point& translation() { return t_; }

  /// ξ^ = [φ^ ρ; 0 0] (4x4) and its inverse.
  static Matrix hat(const Tangent& xi) {
    Matrix m = Matrix::Zero();
    m.template topLeftCorner<3, 3>() = ::hawor::hat(xi.template tail<3>());
    m.template topRightCorner<3, 1>() = xi.template head<3>();
    return m;
  }
  static Tangent vee(const Matrix& m) {
    Tangent xi;
    xi.template head<3>() = m.template topRightCorner<3, 1>();
    xi.template tail<3>() = ::hawor::vee(m.template topLeftCorner<3, 3>());
    return xi;
  }

  /// Left Jacobian J_l(ξ) = [J_l(φ), Q(ρ, φ); 0, J_l(φ)] (Barfoot eq. 7.85–7.86).
  static Mat6 leftJacobian(const Tangent& xi) {
    const Point phi = xi.template tail<3>();
    const Mat3<Scalar> J = SO3<Scalar>::leftJacobian(phi);
    Mat6 out = Mat6::Zero();
    out.template topLeftCorner<3, 3>() = J;
    out.template bottomRightCorner<3, 3>() = J;
    out.template topRightCorner<3, 3>() = Q(xi);
    return out;
  }
  /// J_r(ξ) = J_l(−ξ).
  static Mat6 rightJacobian(const Tangent& xi) { return leftJacobian(-xi); }
  /// J_l(ξ)⁻¹ = [J⁻¹, −J⁻¹ Q J⁻¹; 0, J⁻¹] with J = J_l(φ).
  static Mat6 leftJacobianInverse(const Tangent& xi) {
    const Point phi = xi.template tail<3>();
    const Mat3<Scalar> Ji = SO3<Scalar>::leftJacobianInverse(phi);
    Mat6 out = Mat6::Zero();
    out.template topLeftCorner<3, 3>() = Ji;
    out.template bottomRightCorner<3, 3>() = Ji;
    out.template topRightCorner<3, 3>() = -Ji * Q(xi) * Ji;
    return out;
  }
  /// J_r(ξ)⁻¹ = J_l(−ξ)⁻¹.
  static Mat6 rightJacobianInverse(const Tangent& xi) { return leftJacobianInverse(-xi); }

  /// d(exp(δ)·T·p)/dδ at δ = 0 = [I, −(T p)^]  (3x6, left perturbation).
  Mat36 actJacobianLeft(const Point& p) const {
    Mat36 J;
    J.template leftCols<3>().setIdentity();
    J.template rightCols<3>() = -::hawor::hat((*this) * p);
    return J;
  }
  /// d(T·exp(δ)·p)/dδ at δ = 0 = R·[I, −p^]  (3x6, right perturbation).
  Mat36 actJacobianRight(const Point& p) const {
    const Mat3<Scalar> R = R_.matrix();
    Mat36 J;
    J.template leftCols<3>() = R;
    J.template rightCols<3>() = -R * ::hawor::hat(p);
    return J;
  }
  /// d(T·p)/dp = R.
  Mat3<Scalar> actJacobianPoint() const { return R_.matrix(); }

  template <typename T>
  SE3<T> cast() const {
    return SE3<T>(R_.template cast<T>(), t_.template cast<T>());
  }

  /// Rotations within tol (radians) and translations within tol (metres).
  bool isApprox(const SE3& o, Scalar tol) const {
    return R_.isApprox(o.R_, tol) && (t_ - o.t_).norm() <= tol;
  }

 private:
  /// Barfoot's Q(ρ, φ): the coupling block of the SE(3) left Jacobian.
  static Mat3<Scalar> Q(const Tangent& xi) {
    const Point rho = xi.template head<3>();
    const Point phi = xi.template tail<3>();
    const detail::RotationCoefficients<Scalar> k(phi.squaredNorm());
    const Mat3<Scalar> P = ::hawor::hat(phi), Rh = ::hawor::hat(rho);
    const Mat3<Scalar> PR = P * Rh, RP = Rh * P, PRP = PR * P, PPR = P * PR, RPP = RP * P;
    return Scalar(0.5) * Rh + k.C * (PR + RP + PRP) + k.D2 * (PPR + RPP - Scalar(3) * PRP) +
           k.D3 * (PRP * P + P * PRP);
  }

  SO3<Scalar> R_;
  Point t_;
};

using SE3f = SE3<float>;
using SE3d = SE3<double>;

}  // namespace hawor
