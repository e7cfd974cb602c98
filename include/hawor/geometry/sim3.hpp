// hawor/geometry/sim3.hpp — similarity transforms Sim(3): p ↦ s·R·p + t, s > 0.
//
// Used for up-to-scale SLAM trajectories and Umeyama alignment with scale (docs/design.md §6, §8).
// Storage: scale s, SO3 R, translation t (4x4 form [sR t; 0 1]).
// Tangent ξ = (ρ, φ, σ) ∈ R⁷: translation part, rotation vector, log-scale (s = e^σ).
// Lie algebra ξ^ = [φ^ + σI, ρ; 0 0]; exp(ξ) = (e^σ, exp(φ), W(σ, φ)·ρ) with
//   W = ∫₀¹ e^{στ} exp(τ φ^) dτ = a·I + b·φ^ + c·φ^²,
//   a = ∫ e^{στ} dτ,  b = ∫ e^{στ} sin(θτ)/θ dτ,  c = ∫ e^{στ} (1 − cos θτ)/θ² dτ,
// evaluated from closed forms rearranged to avoid cancellation (Sim3WCoefficients), so σ → 0,
// θ → 0 and both together are accurate to a few ulps.
// Perturbations: left T ⊕ δ = exp(δ)·T, right T ⊕ δ = T·exp(δ).
// A value type: thread-safe to read concurrently.
#pragma once

#include <Eigen/LU>
#include <cmath>

#include "hawor/common.hpp"
#include "hawor/geometry/so3.hpp"

namespace hawor {
namespace detail {

/// Coefficients of W(σ, φ) = a·I + b·φ^ + c·φ^² (see the file comment), θ² = |φ|².
///
/// With the moments of e^{στ}: a(σ) = ∫₀¹ e^{στ}dτ, g(σ) = ∫₀¹ τ e^{στ}dτ, h(σ) = ∫₀¹ τ²/2 e^{στ}dτ
/// (the values of a, b, c at θ = 0) and the SO(3) coefficients B, C, D2 of θ (rotation.hpp),
/// the closed forms b = (σ e^σ A − Re expm1(σ+iθ))/r², c = (a − Re(expm1(σ+iθ)/(σ+iθ)))/θ²
/// rearrange (using A = 1 − θ²C, B = 1/2 − θ²D2) into weighted means free of cancellation:
///   b = (σ²·g(σ) + θ²·e^σ (B − σC)) / r²,   c = (σ²·h(σ) + θ²·e^σ (C − σ·D2)) / r²,
/// r² = σ² + θ². σ = 0 gives the SO(3) J_l coefficients (B, C); θ = 0 gives (g, h).
template <typename Scalar>
struct Sim3WCoefficients {
  Scalar a, b, c;

  Sim3WCoefficients(Scalar sigma, Scalar theta_sq) {
    using S = Scalar;
    using std::exp;
    using std::expm1;
    S g, h;
    const S es = exp(sigma);
    if (std::abs(sigma) < S(1)) {
      // a = Σ σⁿ/(n+1)!,  g = Σ (n+1) σⁿ/(n+2)!,  h = Σ (n+1)(n+2)/2 · σⁿ/(n+3)!
      // (24 terms: the first omitted one is below 1/27! at |σ| = 1).
      a = g = h = S(0);
      S p = S(1);   // σⁿ
      S f = S(1);   // (n+1)!
      for (int n = 0; n < 24; ++n) {
        const S f2 = f * S(n + 2), f3 = f2 * S(n + 3);
        a += p / f;
        g += S(n + 1) * p / f2;
        h += S((n + 1) * (n + 2) / 2) * p / f3;
        p *= sigma;
        f = f2;
      }
    } else {
      // |σ| >= 1: the closed forms lose at most a factor ~10 to cancellation.
      const S em1 = expm1(sigma), s2 = sigma * sigma;
      a = em1 / sigma;
      g = (sigma * es - em1) / s2;
      h = (s2 * es / S(2) - sigma * es + em1) / (s2 * sigma);
    }
    const S s2 = sigma * sigma;
    const S r2 = s2 + theta_sq;
    if (!(r2 > S(0))) {  // σ = θ = 0 (or both underflow): the limits
      b = g;
      c = h;
      return;
    }
    const RotationCoefficients<S> k(theta_sq);
    b = (s2 * g + theta_sq * es * (k.B - sigma * k.C)) / r2;
    c = (s2 * h + theta_sq * es * (k.C - sigma * k.D2)) / r2;
  }
};

/// W(σ, φ) of the Sim(3) exponential (see the file comment).
template <typename Scalar>
Mat3<Scalar> sim3W(Scalar sigma, const Vec3<Scalar>& phi) {
  const Sim3WCoefficients<Scalar> k(sigma, phi.squaredNorm());
  const Mat3<Scalar> K = hat(phi);
  return k.a * Mat3<Scalar>::Identity() + k.b * K + k.c * (K * K);
}

}  // namespace detail

template <typename Scalar_>
class Sim3 {
 public:
  using Scalar = Scalar_;
  using Tangent = Vec7<Scalar>;
  using Point = Vec3<Scalar>;
  using Matrix = Mat4<Scalar>;
  using Mat7 = Eigen::Matrix<Scalar, 7, 7, Eigen::DontAlign>;
  using Mat37 = Eigen::Matrix<Scalar, 3, 7, Eigen::DontAlign>;
  static constexpr int DoF = 7;

  /// Identity.
  Sim3() : s_(Scalar(1)), R_(), t_(Point::Zero()) {}
  /// Throws hawor::Error unless s is finite and > 0.
  Sim3(Scalar s, const SO3<Scalar>& R, const Point& t) : s_(checkScale(s)), R_(R), t_(t) {}
  Sim3(Scalar s, const Mat3<Scalar>& R, const Point& t)
      : s_(checkScale(s)), R_(SO3<Scalar>::fromMatrix(R)), t_(t) {}

  /// From [sR t; 0 1]: s = cbrt(det(sR)), R = sR/s. Throws when det <= 0.
  static Sim3 fromMatrix(const Matrix& T) {
    const Mat3<Scalar> sR = T.template topLeftCorner<3, 3>();
    const Scalar det = sR.determinant();
    if (!(det > Scalar(0))) throw Error("Sim3::fromMatrix: det of the 3x3 block is not > 0");
    const Scalar s = std::cbrt(det);
    return Sim3(s, Mat3<Scalar>(sR / s), Point(T.template topRightCorner<3, 1>()));
  }

  /// exp(ρ, φ, σ) = (e^σ, exp(φ), W(σ, φ)·ρ).
  static Sim3 exp(const Tangent& xi) {
    const Point rho = xi.template head<3>();
    const Point phi = xi.template segment<3>(3);
    const Scalar sigma = xi(6);
    return Sim3(std::exp(sigma), SO3<Scalar>::exp(phi),
                Point(detail::sim3W(sigma, phi) * rho));
  }

  /// log(T) = (W(σ, φ)⁻¹ t, φ, σ), σ = ln s, |φ| ≤ π (W is invertible there).
  Tangent log() const {
    const Point phi = R_.log();
    const Scalar sigma = std::log(s_);
    const Mat3<Scalar> W = detail::sim3W(sigma, phi);
    Tangent xi;
    xi.template head<3>() = Eigen::Matrix<Scalar, 3, 3>(W).partialPivLu().solve(
        Eigen::Matrix<Scalar, 3, 1>(t_));
    xi.template segment<3>(3) = phi;
    xi(6) = sigma;
    return xi;
  }

  /// (1/s, Rᵀ, −Rᵀt/s).
  Sim3 inverse() const {
    const SO3<Scalar> Ri = R_.inverse();
    const Scalar si = Scalar(1) / s_;
    return Sim3(si, Ri, Point(-si * (Ri * t_)));
  }

  /// (s1, R1, t1)·(s2, R2, t2) = (s1 s2, R1 R2, s1 R1 t2 + t1).
  Sim3 operator*(const Sim3& o) const {
    return Sim3(s_ * o.s_, R_ * o.R_, Point(s_ * (R_ * o.t_) + t_));
  }
  Sim3& operator*=(const Sim3& o) { return *this = *this * o; }

  /// s·R·p + t.
  Point operator*(const Point& p) const { return s_ * (R_ * p) + t_; }

  /// [sR t; 0 1].
  Matrix matrix() const {
    Matrix T = Matrix::Identity();
    T.template topLeftCorner<3, 3>() = s_ * R_.matrix();
    T.template topRightCorner<3, 1>() = t_;
    return T;
  }

  /// Adjoint for (ρ, φ, σ): T·exp(ξ)·T⁻¹ = exp(Adj·ξ),
  /// Adj = [sR, t^R, −t; 0, R, 0; 0, 0, 1].
  Mat7 Adj() const {
    const Mat3<Scalar> R = R_.matrix();
    Mat7 A = Mat7::Zero();
    A.template block<3, 3>(0, 0) = s_ * R;
    A.template block<3, 3>(0, 3) = ::hawor::hat(t_) * R;
    A.template block<3, 1>(0, 6) = -t_;
    A.template block<3, 3>(3, 3) = R;
    A(6, 6) = Scalar(1);
    return A;
  }

  Scalar scale() const { return s_; }
  /// Throws hawor::Error unless s is finite and > 0.
  void setScale(Scalar s) { s_ = checkScale(s); }
  const SO3<Scalar>& rotation() const { return R_; }
  SO3<Scalar>& rotation() { return R_; }
  Mat3<Scalar> rotationMatrix() const { return R_.matrix(); }
  const Point& translation() const { return t_; }
  Point& translation() { return t_; }

  /// ξ^ = [φ^ + σI, ρ; 0 0] and its inverse.
  static Matrix hat(const Tangent& xi) {
    Matrix m = Matrix::Zero();
    m.template topLeftCorner<3, 3>() =
        ::hawor::hat(xi.template segment<3>(3)) + xi(6) * Mat3<Scalar>::Identity();
    m.template topRightCorner<3, 1>() = xi.template head<3>();
    return m;
  }
  static Tangent vee(const Matrix& m) {
    Tangent xi;
    xi.template head<3>() = m.template topRightCorner<3, 1>();
    xi.template segment<3>(3) = ::hawor::vee(m.template topLeftCorner<3, 3>());
    xi(6) = m.template topLeftCorner<3, 3>().trace() / Scalar(3);
    return xi;
  }

  /// d(exp(δ)·T·p)/dδ at δ = 0 = [I, −q^, q] with q = T·p  (3x7, left perturbation).
  Mat37 actJacobianLeft(const Point& p) const {
    const Point q = (*this) * p;
    Mat37 J;
    J.template leftCols<3>().setIdentity();
    J.template middleCols<3>(3) = -::hawor::hat(q);
    J.col(6) = q;
    return J;
  }
  /// d(T·exp(δ)·p)/dδ at δ = 0 = sR·[I, −p^, p]  (3x7, right perturbation).
  Mat37 actJacobianRight(const Point& p) const {
    const Mat3<Scalar> sR = s_ * R_.matrix();
    Mat37 J;
    J.template leftCols<3>() = sR;
    J.template middleCols<3>(3) = -sR * ::hawor::hat(p);
    J.col(6) = sR * p;
    return J;
  }
  /// d(T·p)/dp = sR.
  Mat3<Scalar> actJacobianPoint() const { return s_ * R_.matrix(); }

  template <typename T>
  Sim3<T> cast() const {
    return Sim3<T>(static_cast<T>(s_), R_.template cast<T>(), t_.template cast<T>());
  }

  /// Rotation within tol (radians), |ln s1 − ln s2| within tol, translation within tol.
  bool isApprox(const Sim3& o, Scalar tol) const {
    using std::abs;
    return R_.isApprox(o.R_, tol) && abs(std::log(s_ / o.s_)) <= tol &&
           (t_ - o.t_).norm() <= tol;
  }

 private:
  static Scalar checkScale(Scalar s) {
    if (!(s > Scalar(0)) || !std::isfinite(s)) {
      throw Error("Sim3: scale must be finite and > 0");
    }
    return s;
  }

  Scalar s_;
  SO3<Scalar> R_;
  Point t_;
};

using Sim3f = Sim3<float>;
using Sim3d = Sim3<double>;

}  // namespace hawor
