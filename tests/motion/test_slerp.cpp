// Unit/property tests of motion/slerp.hpp (native and WASM).
#include <catch2/catch.hpp>
#include <cmath>

#include "hawor/motion/slerp.hpp"

namespace {

template <typename S>
S slerpTol() {
  return std::is_same<S, float>::value ? S(2e-5) : S(1e-12);
}

// Geodesic angle between the rotations of two unit quaternions, in [0, π].
template <typename S>
S rotationAngle(const Eigen::Quaternion<S>& a, const Eigen::Quaternion<S>& b) {
  const Eigen::Quaternion<S> d = a.conjugate() * b;
  return S(2) * std::atan2(d.vec().norm(), std::abs(d.w()));
}

template <typename S>
Eigen::Quaternion<S> randomQuat(std::uint32_t seed) {
  std::srand(seed);
  Eigen::Matrix<S, 4, 1> v = Eigen::Matrix<S, 4, 1>::Random();
  Eigen::Quaternion<S> q;
  q.coeffs() = v.normalized();
  return q;
}

template <typename S>
Eigen::Quaternion<S> rotAbout(const Eigen::Quaternion<S>& q, S angle, std::uint32_t seed) {
  std::srand(seed);
  const hawor::Vec3<S> axis = hawor::Vec3<S>::Random().normalized();
  const hawor::Vec3<S> aa = angle * axis;
  return q * hawor::axisAngleToQuaternion(aa);
}

}  // namespace

TEMPLATE_TEST_CASE("slerp endpoints", "[motion][slerp]", float, double) {
  using S = TestType;
  for (std::uint32_t seed = 1; seed < 30; ++seed) {
    const auto q0 = randomQuat<S>(seed);
    const auto q1 = randomQuat<S>(seed + 100);
    CHECK(rotationAngle(hawor::slerp(q0, q1, S(0)), q0) < slerpTol<S>() * 10);
    CHECK(rotationAngle(hawor::slerp(q0, q1, S(1)), q1) < slerpTol<S>() * 10);
    CHECK(std::abs(hawor::slerp(q0, q1, S(0.3)).norm() - S(1)) < slerpTol<S>());
  }
}

TEMPLATE_TEST_CASE("slerp takes the short path", "[motion][slerp]", float, double) {
  using S = TestType;
  for (std::uint32_t seed = 1; seed < 30; ++seed) {
    const auto q0 = randomQuat<S>(seed);
    auto q1 = randomQuat<S>(seed + 7);
    if (q0.coeffs().dot(q1.coeffs()) > S(0)) q1.coeffs() = -q1.coeffs();  // force dot < 0
    Eigen::Quaternion<S> q1n;
    q1n.coeffs() = -q1.coeffs();
    const S total = rotationAngle(q0, q1);  // <= π: the short arc
    for (S t : {S(0.25), S(0.5), S(0.8)}) {
      const auto a = hawor::slerp(q0, q1, t);
      const auto b = hawor::slerp(q0, q1n, t);
      CHECK(rotationAngle(a, b) < slerpTol<S>() * 10);
      CHECK(std::abs(rotationAngle(q0, a) - t * total) < slerpTol<S>() * 20);
      CHECK(std::abs(rotationAngle(a, q1) - (S(1) - t) * total) < slerpTol<S>() * 20);
    }
  }
}

TEMPLATE_TEST_CASE("slerp has constant angular speed", "[motion][slerp]", float, double) {
  using S = TestType;
  const auto q0 = randomQuat<S>(3);
  for (S angle : {S(0.01), S(1.0), S(2.5), S(3.1)}) {
    const auto q1 = rotAbout(q0, angle, 5);
    for (int i = 0; i <= 10; ++i) {
      const S t = S(i) / S(10);
      CHECK(std::abs(rotationAngle(q0, hawor::slerp(q0, q1, t)) - t * angle) < slerpTol<S>() * 50);
    }
    // extrapolation keeps the rate
    CHECK(std::abs(rotationAngle(q0, hawor::slerp(q0, q1, S(-0.1))) - S(0.1) * angle) <
          slerpTol<S>() * 50);
  }
}

TEMPLATE_TEST_CASE("slerp near-identical quaternions falls back to normalised lerp",
                   "[motion][slerp]", float, double) {
  using S = TestType;
  const auto q0 = randomQuat<S>(11);
  // identical: exact q0
  const auto same = hawor::slerp(q0, q0, S(0.4));
  CHECK((same.coeffs() - q0.coeffs()).norm() < slerpTol<S>());
  // below and above the fallback threshold: still unit, still at the right angle
  for (S angle :
       {S(0.1) * hawor::Constants<S>::slerpEpsilon(), S(3) * hawor::Constants<S>::slerpEpsilon()}) {
    const auto q1 = rotAbout(q0, angle, 13);
    for (S t : {S(0.1), S(0.5), S(0.9)}) {
      const auto q = hawor::slerp(q0, q1, t);
      REQUIRE(q.coeffs().allFinite());
      CHECK(std::abs(q.norm() - S(1)) < slerpTol<S>());
      CHECK(rotationAngle(q0, q) <= angle * S(1.01) + slerpTol<S>());
    }
  }
  // antipodal representation of the same rotation: no NaN, same rotation
  Eigen::Quaternion<S> neg;
  neg.coeffs() = -q0.coeffs();
  const auto q = hawor::slerp(q0, neg, S(0.5));
  REQUIRE(q.coeffs().allFinite());
  CHECK(rotationAngle(q, q0) < slerpTol<S>() * 10);
  Eigen::Quaternion<S> zero(S(0), S(0), S(0), S(0));
  CHECK_THROWS_AS(hawor::slerp(q0, zero, S(0.5)), hawor::Error);
}

TEMPLATE_TEST_CASE("slerpAxisAngle", "[motion][slerp]", float, double) {
  using S = TestType;
  using V = hawor::Vec3<S>;
  const V a0(S(0.1), S(-0.2), S(0.3));
  const V a1(S(-1.0), S(0.5), S(2.0));
  CHECK((hawor::slerpAxisAngle(a0, a1, S(0)) - a0).norm() < slerpTol<S>() * 10);
  CHECK((hawor::slerpAxisAngle(a0, a1, S(1)) - a1).norm() < slerpTol<S>() * 10);
  // same axis: the angle interpolates linearly
  const V axis = V(S(1), S(2), S(-2)).normalized();
  const V r = hawor::slerpAxisAngle(V(S(0.2) * axis), V(S(1.4) * axis), S(0.25));
  CHECK((r - S(0.5) * axis).norm() < slerpTol<S>() * 10);
  // zero to zero stays zero
  CHECK(hawor::slerpAxisAngle(V(V::Zero()), V(V::Zero()), S(0.5)).norm() < slerpTol<S>());
  // near π on both sides: the short way through π, not back through zero
  const V p0 = (hawor::Constants<S>::pi() - S(0.05)) * axis;
  const V p1 = -(hawor::Constants<S>::pi() - S(0.05)) * axis;  // 0.1 rad away through π
  const V mid = hawor::slerpAxisAngle(p0, p1, S(0.5));
  CHECK(std::abs(mid.norm() - hawor::Constants<S>::pi()) < S(1e-3));
}

TEMPLATE_TEST_CASE("lerp", "[motion][slerp]", float, double) {
  using S = TestType;
  Eigen::Matrix<S, 3, 1> a(S(1), S(2), S(3)), b(S(3), S(2), S(-1));
  const Eigen::Matrix<S, 3, 1> m = hawor::lerp(a, b, S(0.25));
  CHECK((m - Eigen::Matrix<S, 3, 1>(S(1.5), S(2), S(2))).norm() < slerpTol<S>());
  CHECK(hawor::lerp(a, b, S(0)) == a);
  Eigen::Matrix<S, Eigen::Dynamic, 1> x(4), y(3);
  x.setZero();
  y.setZero();
  CHECK_THROWS_AS(hawor::lerp(x, y, S(0.5)), hawor::Error);
}
