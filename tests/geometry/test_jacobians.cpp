// Every analytic Jacobian of SO3, SE3 and Sim3 against central differences (double), at
// generic angles, near identity (1e-9, 1e-5, around the series thresholds) and near π.
#include <catch2/catch.hpp>

#include "geometry_test_utils.hpp"

using namespace hawor;

namespace {

using V3 = Eigen::Matrix<double, 3, 1>;
using V6 = Eigen::Matrix<double, 6, 1>;
using V7 = Eigen::Matrix<double, 7, 1>;

// Finite-difference step: small enough that a perturbation never pushes an angle past π
// (where log wraps), large enough to keep rounding (~1e-16/h) small.
double stepFor(double angle) {
  return std::min(1e-6, (geo_test::pi() - angle) / 10.0);
}
double tolFor(double angle) {
  return 1e-16 / stepFor(angle) * 1e3 + 1e-9;
}

}  // namespace

TEST_CASE("SO3 Jacobians match central differences", "[geometry][so3][jacobian]") {
  geo_test::Rng rng(21);
  using G = SO3d;
  for (double angle : geo_test::specialAngles()) {
    for (int rep = 0; rep < 3; ++rep) {
      const V3 phi = angle * rng.unitVector();
      const V3 p = rng.vec3(2);
      const double h = stepFor(angle), t = tolFor(angle);
      INFO("angle " << angle << " phi " << phi.transpose());
      const G R = G::exp(phi);
      const Eigen::Matrix3d Jl = G::leftJacobian(phi), Jr = G::rightJacobian(phi);
      // exp(φ+δ) ≈ exp(J_l δ)·exp(φ) ≈ exp(φ)·exp(J_r δ)
      auto fl = [&](const V3& d) -> V3 { return (G::exp(phi + d) * R.inverse()).log(); };
      auto fr = [&](const V3& d) -> V3 { return (R.inverse() * G::exp(phi + d)).log(); };
      CHECK((geo_test::numericJacobian<3, 3>(fl, V3::Zero(), 1e-6) - Jl).norm() <= 1e-8);
      CHECK((geo_test::numericJacobian<3, 3>(fr, V3::Zero(), 1e-6) - Jr).norm() <= 1e-8);
      // log(exp(δ)·exp(φ)) ≈ φ + J_l⁻¹ δ,  log(exp(φ)·exp(δ)) ≈ φ + J_r⁻¹ δ
      auto gl = [&](const V3& d) -> V3 { return (G::exp(d) * R).log(); };
      auto gr = [&](const V3& d) -> V3 { return (R * G::exp(d)).log(); };
      const Eigen::Matrix3d Jli = G::leftJacobianInverse(phi), Jri = G::rightJacobianInverse(phi);
      CHECK((geo_test::numericJacobian<3, 3>(gl, V3::Zero(), h) - Jli).norm() <= t);
      CHECK((geo_test::numericJacobian<3, 3>(gr, V3::Zero(), h) - Jri).norm() <= t);
      CHECK((Jl * Jli - Eigen::Matrix3d::Identity()).norm() <= 1e-13);
      CHECK((Jr * Jri - Eigen::Matrix3d::Identity()).norm() <= 1e-13);
      CHECK((Jl - Jr.transpose()).norm() <= 1e-15);
      // Action Jacobians.
      auto al = [&](const V3& d) -> V3 { return G::exp(d) * R * Vec3<double>(p); };
      auto ar = [&](const V3& d) -> V3 { return R * G::exp(d) * Vec3<double>(p); };
      auto ap = [&](const V3& q) -> V3 { return R * Vec3<double>(q); };
      CHECK((geo_test::numericJacobian<3, 3>(al, V3::Zero()) - R.actJacobianLeft(p)).norm() <=
            1e-8);
      CHECK((geo_test::numericJacobian<3, 3>(ar, V3::Zero()) - R.actJacobianRight(p)).norm() <=
            1e-8);
      CHECK((geo_test::numericJacobian<3, 3>(ap, p) - R.actJacobianPoint()).norm() <= 1e-8);
    }
  }
}

TEST_CASE("SE3 Jacobians match central differences", "[geometry][se3][jacobian]") {
  geo_test::Rng rng(22);
  using G = SE3d;
  for (double angle : geo_test::specialAngles()) {
    for (int rep = 0; rep < 3; ++rep) {
      V6 xi;
      xi << rng.vec3(1.5), angle * rng.unitVector();
      const V3 p = rng.vec3(2);
      const double h = stepFor(angle), t = tolFor(angle) * 10;
      INFO("angle " << angle << " xi " << xi.transpose());
      const G T = G::exp(xi);
      const Eigen::Matrix<double, 6, 6> Jl = G::leftJacobian(xi), Jr = G::rightJacobian(xi);
      auto fl = [&](const V6& d) -> V6 { return (G::exp(xi + d) * T.inverse()).log(); };
      auto fr = [&](const V6& d) -> V6 { return (T.inverse() * G::exp(xi + d)).log(); };
      CHECK((geo_test::numericJacobian<6, 6>(fl, V6::Zero(), 1e-6) - Jl).norm() <= 1e-8);
      CHECK((geo_test::numericJacobian<6, 6>(fr, V6::Zero(), 1e-6) - Jr).norm() <= 1e-8);
      auto gl = [&](const V6& d) -> V6 { return (G::exp(d) * T).log(); };
      auto gr = [&](const V6& d) -> V6 { return (T * G::exp(d)).log(); };
      const Eigen::Matrix<double, 6, 6> Jli = G::leftJacobianInverse(xi),
                                        Jri = G::rightJacobianInverse(xi);
      CHECK((geo_test::numericJacobian<6, 6>(gl, V6::Zero(), h) - Jli).norm() <= t);
      CHECK((geo_test::numericJacobian<6, 6>(gr, V6::Zero(), h) - Jri).norm() <= t);
      CHECK((Jl * Jli - Eigen::Matrix<double, 6, 6>::Identity()).norm() <= 1e-12);
      CHECK((Jr * Jri - Eigen::Matrix<double, 6, 6>::Identity()).norm() <= 1e-12);
      auto al = [&](const V6& d) -> V3 { return G::exp(d) * T * Vec3<double>(p); };
      auto ar = [&](const V6& d) -> V3 { return T * G::exp(d) * Vec3<double>(p); };
      auto ap = [&](const V3& q) -> V3 { return T * Vec3<double>(q); };
      CHECK((geo_test::numericJacobian<3, 6>(al, V6::Zero()) - T.actJacobianLeft(p)).norm() <=
            1e-8);
      CHECK((geo_test::numericJacobian<3, 6>(ar, V6::Zero()) - T.actJacobianRight(p)).norm() <=
            1e-8);
      CHECK((geo_test::numericJacobian<3, 3>(ap, p) - T.actJacobianPoint()).norm() <= 1e-8);
    }
  }
}

TEST_CASE("Sim3 Jacobians match central differences", "[geometry][sim3][jacobian]") {
  geo_test::Rng rng(23);
  using G = Sim3d;
  for (double angle : geo_test::specialAngles()) {
    for (int rep = 0; rep < 3; ++rep) {
      V7 xi;
      xi << rng.vec3(1.5), angle * rng.unitVector(), rng.uniform(-1, 1);
      const V3 p = rng.vec3(2);
      INFO("angle " << angle << " xi " << xi.transpose());
      const G T = G::exp(xi);
      auto al = [&](const V7& d) -> V3 { return G::exp(d) * T * Vec3<double>(p); };
      auto ar = [&](const V7& d) -> V3 { return T * G::exp(d) * Vec3<double>(p); };
      auto ap = [&](const V3& q) -> V3 { return T * Vec3<double>(q); };
      CHECK((geo_test::numericJacobian<3, 7>(al, V7::Zero()) - T.actJacobianLeft(p)).norm() <=
            1e-8);
      CHECK((geo_test::numericJacobian<3, 7>(ar, V7::Zero()) - T.actJacobianRight(p)).norm() <=
            1e-8);
      CHECK((geo_test::numericJacobian<3, 3>(ap, p) - T.actJacobianPoint()).norm() <= 1e-8);
    }
  }
}

TEST_CASE("Sim3 exp is smooth across its series/closed-form switch", "[geometry][sim3]") {
  // W(σ, φ) switches at |σ + iθ| = 0.1; both sides must agree with the reference matrix
  // exponential, including when only one of σ, θ is small.
  geo_test::Rng rng(24);
  const std::vector<double> sigmas = {0.0, 1e-12, -1e-9, 1e-5, -0.0707, 0.0999, -0.1001, 0.5, -2.0};
  const std::vector<double> thetas = {0.0, 1e-12, 1e-9, 1e-5, 0.0707, 0.0999, 0.1001, 1.0, 3.1};
  for (double sigma : sigmas) {
    for (double theta : thetas) {
      V7 xi;
      xi << rng.vec3(1.5), theta * rng.unitVector(), sigma;
      const Eigen::Matrix4d ref = geo_test::expm(Sim3d::hat(xi));
      INFO("sigma " << sigma << " theta " << theta);
      CHECK((Sim3d::exp(xi).matrix() - ref).norm() <= 1e-14 * ref.norm());
      if (theta < 3.0) CHECK((Sim3d::exp(xi).log() - xi).norm() <= 1e-14 * xi.norm() + 1e-300);
    }
  }
}
