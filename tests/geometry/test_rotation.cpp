// Rotation conversions (hawor/geometry/rotation.hpp): round trips, agreement with Eigen's
// AngleAxis, tiny and near-π angles, rot6d layout and Gram–Schmidt, projection to SO(3), errors.
#include <catch2/catch.hpp>

#include "geometry_test_utils.hpp"

using namespace hawor;
using geo_test::tol;

TEMPLATE_TEST_CASE("hat and vee", "[geometry][rotation]", float, double) {
  using S = TestType;
  geo_test::Rng rng(1);
  for (int i = 0; i < 20; ++i) {
    const Vec3<S> v = rng.vec3(2).cast<S>(), p = rng.vec3(2).cast<S>();
    const Mat3<S> K = hat(v);
    CHECK((K * p - v.cross(p)).norm() <= tol<S>(1e-15, 1e-6));
    CHECK((K + K.transpose()).norm() == S(0));
    CHECK((vee(K) - v).norm() == S(0));
    // hat accepts expressions, vee takes the skew part.
    CHECK((hat(v + p) - K - hat(p)).norm() <= tol<S>(1e-15, 1e-6));
    const Mat3<S> sym = Mat3<S>::Identity() + p * p.transpose();
    CHECK((vee(Mat3<S>(K + sym)) - v).norm() <= tol<S>(1e-15, 1e-6));
  }
}

TEMPLATE_TEST_CASE("axis-angle to matrix and quaternion agree with Eigen::AngleAxis",
                   "[geometry][rotation]", float, double) {
  using S = TestType;
  geo_test::Rng rng(2);
  for (double angle : geo_test::specialAngles()) {
    for (int i = 0; i < 5; ++i) {
      const Eigen::Vector3d axis = rng.unitVector();
      const Vec3<S> w = (angle * axis).cast<S>();
      const Mat3<S> R = axisAngleToMatrix(w);
      const Eigen::AngleAxis<S> aa(S(angle), axis.cast<S>());
      INFO("angle " << angle);
      CHECK((R - aa.toRotationMatrix()).norm() <= tol<S>(2e-15, 2e-6));
      CHECK((R * R.transpose() - Mat3<S>::Identity()).norm() <= tol<S>(2e-15, 2e-6));
      CHECK(R.determinant() == Approx(S(1)).margin(tol<S>(1e-14, 1e-5)));
      const Eigen::Quaternion<S> q = axisAngleToQuaternion(w);
      const Eigen::Quaternion<S> qe(aa);
      CHECK((q.coeffs() - qe.coeffs()).norm() <= tol<S>(1e-15, 4e-7));
      CHECK((quaternionToMatrix(q) - R).norm() <= tol<S>(2e-15, 2e-6));
    }
  }
}

TEMPLATE_TEST_CASE("matrix/quaternion to axis-angle inverts axis-angle, tiny to near pi",
                   "[geometry][rotation]", float, double) {
  using S = TestType;
  geo_test::Rng rng(3);
  for (double angle : geo_test::specialAngles()) {
    for (int i = 0; i < 5; ++i) {
      const Vec3<S> w = (angle * rng.unitVector()).cast<S>();
      INFO("angle " << angle);
      // Relative accuracy for tiny angles (series branches keep full precision).
      const S scale = std::max(S(angle), tol<S>(1e-300, 1e-30));
      const Vec3<S> w1 = matrixToAxisAngle(axisAngleToMatrix(w));
      const Vec3<S> w2 = quaternionToAxisAngle(axisAngleToQuaternion(w));
      if (angle < 1.0) {
        CHECK((w1 - w).norm() <= tol<S>(4e-16, 4e-7) * scale);
        CHECK((w2 - w).norm() <= tol<S>(4e-16, 4e-7) * scale);
      } else {
        // Near π the matrix → angle map has condition ~1; float keeps ~1e-6 absolute.
        CHECK((w1 - w).norm() <= tol<S>(4e-15, 4e-6));
        CHECK((w2 - w).norm() <= tol<S>(4e-15, 4e-6));
      }
    }
  }
}

TEST_CASE("matrixToAxisAngle near and at pi keeps full double precision", "[geometry][rotation]") {
  geo_test::Rng rng(4);
  for (double eps : {1e-4, 1e-7, 1e-10, 1e-13}) {
    for (int i = 0; i < 10; ++i) {
      const Eigen::Vector3d axis = rng.unitVector();
      const double angle = geo_test::pi() - eps;
      const Mat3<double> R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
      const Vec3<double> w = matrixToAxisAngle(R);
      INFO("eps " << eps);
      CHECK((w - angle * axis).norm() <= 1e-14);
    }
  }
  // Exactly π: either sign of the axis is correct; the angle is π.
  for (int i = 0; i < 10; ++i) {
    const Eigen::Vector3d axis = rng.unitVector();
    const Mat3<double> R = Mat3<double>(2.0 * axis * axis.transpose()) - Mat3<double>::Identity();
    const Vec3<double> w = matrixToAxisAngle(R);
    CHECK(w.norm() == Approx(geo_test::pi()).epsilon(1e-15));
    CHECK(std::min((w - geo_test::pi() * axis).norm(), (w + geo_test::pi() * axis).norm()) <=
          1e-14);
    CHECK((axisAngleToMatrix(w) - R).norm() <= 1e-14);
  }
}

TEMPLATE_TEST_CASE("axis-angle is the shortest; quaternion sign and norm do not matter",
                   "[geometry][rotation]", float, double) {
  using S = TestType;
  geo_test::Rng rng(5);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d axis = rng.unitVector();
    const double angle = rng.uniform(3.3, 6.0);  // beyond π: log returns angle 2π − angle
    const Vec3<S> w = (angle * axis).cast<S>();
    const Vec3<S> expect = ((angle - 2 * geo_test::pi()) * axis).cast<S>();
    CHECK((matrixToAxisAngle(axisAngleToMatrix(w)) - expect).norm() <= tol<S>(1e-14, 4e-6));
    const Eigen::Quaternion<S> q = axisAngleToQuaternion(w);
    CHECK(q.w() < S(0));
    CHECK((quaternionToAxisAngle(q) - expect).norm() <= tol<S>(1e-14, 4e-6));
    Eigen::Quaternion<S> q2 = q;
    q2.coeffs() *= S(-3.5);
    CHECK((quaternionToAxisAngle(q2) - expect).norm() <= tol<S>(1e-14, 4e-6));
  }
}

TEMPLATE_TEST_CASE("matrix <-> quaternion round trip (Shepperd branches)", "[geometry][rotation]",
                   float, double) {
  using S = TestType;
  geo_test::Rng rng(6);
  // Axes along x, y, z and generic, at angles near π, exercise all four branches.
  const std::vector<Eigen::Vector3d> axes = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                             Eigen::Vector3d::UnitZ(), rng.unitVector(),
                                             rng.unitVector()};
  for (const auto& axis : axes) {
    for (double angle : geo_test::specialAngles()) {
      const Mat3<S> R = Eigen::AngleAxis<S>(S(angle), axis.cast<S>()).toRotationMatrix();
      const Eigen::Quaternion<S> q = matrixToQuaternion(R);
      CHECK(q.w() >= S(0));
      CHECK(q.norm() == Approx(S(1)).epsilon(tol<S>(1e-15, 1e-6)));
      CHECK((quaternionToMatrix(q) - R).norm() <= tol<S>(4e-15, 4e-6));
      const Eigen::Quaternion<S> qe(Eigen::AngleAxis<S>(S(angle), axis.cast<S>()));
      CHECK(std::abs(std::abs(q.dot(qe)) - S(1)) <= tol<S>(1e-15, 1e-6));
    }
  }
}

TEMPLATE_TEST_CASE("rot6d layout, round trip and Gram-Schmidt", "[geometry][rotation]", float,
                   double) {
  using S = TestType;
  geo_test::Rng rng(7);
  for (int i = 0; i < 20; ++i) {
    const Mat3<S> R = axisAngleToMatrix(Vec3<S>(rng.rotvec().cast<S>()));
    const Vec6<S> r = matrixToRot6d(R);
    // docs/design.md §2: [R00, R01, R10, R11, R20, R21].
    CHECK(r(0) == R(0, 0));
    CHECK(r(1) == R(0, 1));
    CHECK(r(2) == R(1, 0));
    CHECK(r(3) == R(1, 1));
    CHECK(r(4) == R(2, 0));
    CHECK(r(5) == R(2, 1));
    CHECK((rot6dToMatrix(r) - R).norm() <= tol<S>(2e-15, 2e-6));

    // Scaled and skewed columns: first column direction kept, second orthogonalised.
    Vec6<S> r2 = r;
    const Vec3<S> a(r(0), r(2), r(4));
    const Vec3<S> b = Vec3<S>(r(1), r(3), r(5)) * S(0.3) + S(0.7) * a;
    r2 << S(2.5) * a(0), b(0), S(2.5) * a(1), b(1), S(2.5) * a(2), b(2);
    const Mat3<S> R2 = rot6dToMatrix(r2);
    CHECK((R2 - R).norm() <= tol<S>(1e-14, 4e-6));
  }
  Vec6<S> bad = Vec6<S>::Zero();
  CHECK_THROWS_AS(rot6dToMatrix(bad), Error);
  bad << S(1), S(2), S(0), S(0), S(0), S(0);  // parallel columns
  CHECK_THROWS_AS(rot6dToMatrix(bad), Error);
  bad << std::numeric_limits<S>::quiet_NaN(), S(0), S(0), S(1), S(0), S(0);
  CHECK_THROWS_AS(rot6dToMatrix(bad), Error);
}

TEMPLATE_TEST_CASE("projectToSO3 returns the nearest rotation", "[geometry][rotation]", float,
                   double) {
  using S = TestType;
  geo_test::Rng rng(8);
  for (int i = 0; i < 20; ++i) {
    const Mat3<S> R = axisAngleToMatrix(Vec3<S>(rng.rotvec().cast<S>()));
    CHECK((projectToSO3(R) - R).norm() <= tol<S>(4e-15, 4e-6));
    // Polar decomposition: R·P with P symmetric positive definite projects to R.
    const Mat3<S> A = Mat3<S>(rng.vec3(0.3).cast<S>().asDiagonal()) + Mat3<S>::Identity();
    const Mat3<S> Rot2 = axisAngleToMatrix(Vec3<S>(rng.rotvec().cast<S>()));
    const Mat3<S> P = Rot2 * A * Rot2.transpose();
    CHECK((projectToSO3(Mat3<S>(R * P)) - R).norm() <= tol<S>(4e-14, 1e-5));
    // Noisy input: a proper rotation, no farther from the input than R itself.
    const Mat3<S> M = R + Mat3<S>(Eigen::Matrix3d::Random().cast<S>() * S(0.05));
    const Mat3<S> Q = projectToSO3(M);
    CHECK((Q * Q.transpose() - Mat3<S>::Identity()).norm() <= tol<S>(1e-14, 4e-6));
    CHECK(Q.determinant() == Approx(S(1)).epsilon(tol<S>(1e-14, 1e-5)));
    CHECK((Q - M).norm() <= (R - M).norm() + tol<S>(1e-14, 1e-6));
  }
  // A reflection projects to a proper rotation.
  const Mat3<S> F = Mat3<S>(Eigen::Vector3d(1, 1, -1).cast<S>().asDiagonal());
  CHECK(projectToSO3(F).determinant() == Approx(S(1)));
  Mat3<S> bad = Mat3<S>::Identity();
  bad(1, 2) = std::numeric_limits<S>::infinity();
  CHECK_THROWS_AS(projectToSO3(bad), Error);
}

TEMPLATE_TEST_CASE("rotation conversions reject bad input", "[geometry][rotation]", float,
                   double) {
  using S = TestType;
  const Eigen::Quaternion<S> zero(S(0), S(0), S(0), S(0));
  CHECK_THROWS_AS(quaternionToAxisAngle(zero), Error);
  CHECK_THROWS_AS(quaternionToMatrix(zero), Error);
  Mat3<S> nan = Mat3<S>::Identity();
  nan(0, 0) = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_AS(matrixToQuaternion(nan), Error);
  CHECK_THROWS_AS(matrixToAxisAngle(nan), Error);
}

TEST_CASE("rotation coefficient series are continuous at their thresholds", "[geometry][rotation]") {
  // Just below the threshold the series is used, just above the closed form: both must agree
  // to rounding (a wrong series term or threshold shows up as a jump).
  const double thr = hawor::detail::rotationSeriesThreshold<double>();
  const hawor::detail::RotationCoefficients<double> lo(std::nextafter(thr * thr, 0.0)),
      hi(thr * thr);
  REQUIRE(lo.theta < thr);
  REQUIRE(hi.theta >= thr);
  CHECK(lo.A == Approx(hi.A).epsilon(1e-14));
  CHECK(lo.B == Approx(hi.B).epsilon(1e-14));
  CHECK(lo.C == Approx(hi.C).epsilon(1e-14));
  CHECK(lo.E == Approx(hi.E).epsilon(1e-14));
  CHECK(lo.D2 == Approx(hi.D2).epsilon(1e-14));
  CHECK(lo.D3 == Approx(hi.D3).epsilon(1e-13));
  const float t = hawor::detail::rotationSeriesThreshold<float>();
  const hawor::detail::RotationCoefficients<float> lf(std::nextafter(t * t, 0.0f)), hf(t * t);
  CHECK(lf.A == Approx(hf.A).epsilon(1e-6));
  CHECK(lf.B == Approx(hf.B).epsilon(1e-6));
  CHECK(lf.C == Approx(hf.C).epsilon(1e-5));
  CHECK(lf.E == Approx(hf.E).epsilon(1e-5));
  CHECK(lf.D2 == Approx(hf.D2).epsilon(1e-5));
  CHECK(lf.D3 == Approx(hf.D3).epsilon(1e-5));
}
