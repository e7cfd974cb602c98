// Unit/property tests of motion/hand_motion.hpp, motion/canonical.hpp and motion/prefill.hpp.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <limits>

#include "hawor/motion/motion.hpp"

template struct hawor::HandMotion<float>;
template struct hawor::HandMotion<double>;
template struct hawor::CanonicalFrame<float>;
template struct hawor::CanonicalFrame<double>;

namespace {

template <typename S>
S tol() {
  return std::is_same<S, float>::value ? S(2e-4) : S(1e-12);
}

template <typename S>
hawor::HandMotion<S> randomHand(Eigen::Index T, unsigned seed) {
  std::srand(seed);
  auto m = hawor::HandMotion<S>::zeros(T);
  m.rot = hawor::Sequence<S>::Random(T, 3) * S(2.5);
  m.trans = hawor::Sequence<S>::Random(T, 3) * S(0.3);
  m.handPose = hawor::Sequence<S>::Random(T, 45);
  m.betas = hawor::Sequence<S>::Random(T, 10);
  return m;
}

template <typename S>
void randomPoses(Eigen::Index T, unsigned seed, std::vector<hawor::Mat3<S>>& R,
                 std::vector<hawor::Vec3<S>>& t) {
  std::srand(seed);
  R.clear();
  t.clear();
  for (Eigen::Index i = 0; i < T; ++i) {
    const hawor::Vec3<S> w = hawor::Vec3<S>::Random() * S(2);
    R.push_back(hawor::axisAngleToMatrix(w));
    t.push_back(hawor::Vec3<S>::Random());
  }
}

template <typename S>
hawor::Points3<S> randomJ0(Eigen::Index rows, unsigned seed) {
  std::srand(seed);
  hawor::Points3<S> J0 = hawor::Points3<S>::Random(rows, 3) * S(0.03);
  J0.col(0).array() += S(0.09);
  return J0;
}

// Rest-pose point x of a rigid MANO hand (no articulation) placed by frame t's rot/trans:
// v = R_hand·(x − J0) + J0 + trans  (MANO rotates about joint 0).
template <typename S>
hawor::Vec3<S> handPoint(const hawor::HandMotion<S>& m, Eigen::Index t, const hawor::Vec3<S>& J0,
                         const hawor::Vec3<S>& x) {
  const hawor::Vec3<S> a = m.rot.row(t).transpose();
  return hawor::axisAngleToMatrix(a) * (x - J0) + J0 + m.trans.row(t).transpose();
}

template <typename S>
S rotDistance(const hawor::Sequence<S>& a, const hawor::Sequence<S>& b, Eigen::Index t) {
  const hawor::Vec3<S> x = a.row(t).transpose(), y = b.row(t).transpose();
  return (hawor::axisAngleToMatrix(x) - hawor::axisAngleToMatrix(y)).norm();
}

}  // namespace

TEMPLATE_TEST_CASE("transformHandFrame moves every point of the hand rigidly",
                   "[motion][canonical]", float, double) {
  using S = TestType;
  auto m = randomHand<S>(4, 1);
  const hawor::Vec3<S> J0(S(0.095), S(0.006), S(0.006));
  const hawor::Mat3<S> R = hawor::axisAngleToMatrix(hawor::Vec3<S>(S(0.3), S(-1.2), S(2.0)));
  const hawor::Vec3<S> p(S(0.5), S(-0.1), S(2.0));
  const hawor::Vec3<S> x1(S(0.01), S(0.02), S(-0.03)), x2(S(0.15), S(-0.02), S(0.01));
  const auto before = m;
  hawor::transformHandFrame(m, 2, R, p, J0);
  for (const auto& x : {x1, x2, J0}) {
    const hawor::Vec3<S> expect = R * handPoint(before, 2, J0, x) + p;
    CHECK((handPoint(m, 2, J0, x) - expect).norm() < tol<S>());
  }
  CHECK(m.handPose == before.handPose);
  CHECK(m.betas == before.betas);
  CHECK(m.rot.row(1) == before.rot.row(1));
}

TEMPLATE_TEST_CASE("HandMotion::validate names the bad field", "[motion][canonical]", float,
                   double) {
  using S = TestType;
  auto m = randomHand<S>(6, 2);
  CHECK_NOTHROW(m.validate());
  auto a = m;
  a.handPose = hawor::Sequence<S>::Zero(6, 44);
  CHECK_THROWS_WITH(a.validate(), Catch::Contains("handPose"));
  auto b = m;
  b.valid.pop_back();
  CHECK_THROWS_AS(b.validate(), hawor::Error);
  auto c = m;
  c.trans(3, 1) = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_WITH(c.validate(), Catch::Contains("trans") && Catch::Contains("frame 3"));
  c.valid[3] = 0;  // a missing frame may hold anything
  CHECK_NOTHROW(c.validate());
  auto d = m;
  d.betas = hawor::Sequence<S>::Zero(5, 10);
  CHECK_THROWS_WITH(d.validate(), Catch::Contains("betas"));
}

TEMPLATE_TEST_CASE("camera -> world follows the cam2world root/offset rule", "[motion][canonical]",
                   float, double) {
  using S = TestType;
  const Eigen::Index T = 7;
  const auto cam = randomHand<S>(T, 3);
  std::vector<hawor::Mat3<S>> R;
  std::vector<hawor::Vec3<S>> t;
  randomPoses<S>(T, 4, R, t);
  const auto J0 = randomJ0<S>(T, 5);
  const auto w = hawor::cameraToWorld(cam, R, t, J0);
  for (Eigen::Index i = 0; i < T; ++i) {
    const hawor::Vec3<S> j0 = J0.row(i).transpose();
    const hawor::Vec3<S> a = cam.rot.row(i).transpose();
    const hawor::Vec3<S> root = cam.trans.row(i).transpose() + j0;
    const hawor::Vec3<S> tw = R[size_t(i)] * root + t[size_t(i)] - j0;  // + offset (−J0)
    CHECK((w.trans.row(i).transpose() - tw).norm() < tol<S>());
    const hawor::Vec3<S> aw = w.rot.row(i).transpose();
    CHECK((hawor::axisAngleToMatrix(aw) - R[size_t(i)] * hawor::axisAngleToMatrix(a)).norm() <
          tol<S>());
    // any hand point moves as a rigid body point
    const hawor::Vec3<S> x(S(0.02), S(-0.05), S(0.04));
    CHECK(
        (handPoint(w, i, j0, x) - (R[size_t(i)] * handPoint(cam, i, j0, x) + t[size_t(i)])).norm() <
        tol<S>());
  }
  CHECK(w.handPose == cam.handPose);
  CHECK(w.valid == cam.valid);
  // errors
  std::vector<hawor::Vec3<S>> short_t(t.begin(), t.end() - 1);
  CHECK_THROWS_AS(hawor::cameraToWorld(cam, R, short_t, J0), hawor::Error);
  CHECK_THROWS_WITH(hawor::cameraToWorld(cam, R, t, randomJ0<S>(3, 1)), Catch::Contains("J0"));
}

TEMPLATE_TEST_CASE("world -> canonical: first valid frame is identity / zero; round trip",
                   "[motion][canonical]", float, double) {
  using S = TestType;
  const Eigen::Index T = 20;
  auto world = randomHand<S>(T, 6);
  world.valid[0] = world.valid[1] = 0;
  world.valid[9] = 0;
  for (const auto& J0 : {randomJ0<S>(1, 7), randomJ0<S>(T, 8)}) {
    hawor::CanonicalFrame<S> frame;
    const auto can = hawor::worldToCanonical(world, J0, &frame);
    CHECK(frame.origin == 2);
    CHECK(can.rot.row(2).norm() < tol<S>());
    CHECK(can.trans.row(2).norm() < tol<S>());
    // the root joint of the origin frame sits at J0 (the canonical origin is not the wrist)
    const hawor::Vec3<S> j0 = hawor::restRoot(J0, 2, T);
    CHECK((frame.R_w2can * (world.trans.row(2).transpose() + j0) + frame.t_w2can - j0).norm() <
          tol<S>());
    // exact inverse
    const auto back = hawor::canonicalToWorld(can, frame, J0);
    for (Eigen::Index i = 0; i < T; ++i) {
      CHECK((back.trans.row(i) - world.trans.row(i)).norm() < tol<S>());
      CHECK(rotDistance(back.rot, world.rot, i) < tol<S>());
    }
    CHECK(back.handPose == world.handPose);
    CHECK(back.betas == world.betas);
    // rigid: relative geometry between frames is kept
    const hawor::Vec3<S> x(S(0.03), S(0.01), S(-0.02));
    const hawor::Vec3<S> j5 = hawor::restRoot(J0, 5, T);
    const hawor::Vec3<S> j12 = hawor::restRoot(J0, 12, T);
    CHECK(std::abs((handPoint(can, 5, j5, x) - handPoint(can, 12, j12, x)).norm() -
                   (handPoint(world, 5, j5, x) - handPoint(world, 12, j12, x)).norm()) < tol<S>());
  }
  auto none = world;
  none.valid.assign(size_t(T), 0);
  CHECK_THROWS_WITH(hawor::worldToCanonical(none, randomJ0<S>(1, 1)),
                    Catch::Contains("no valid frame"));
}

TEST_CASE("world -> canonical -> world is the identity to 1e-12 in double", "[motion][canonical]") {
  using S = double;
  const Eigen::Index T = 50;
  auto world = randomHand<S>(T, 10);
  world.trans *= 10.0;  // metres-scale positions
  const auto J0 = randomJ0<S>(T, 11);
  hawor::CanonicalFrame<S> frame;
  const auto back = hawor::canonicalToWorld(hawor::worldToCanonical(world, J0, &frame), frame, J0);
  for (Eigen::Index i = 0; i < T; ++i) {
    CHECK((back.trans.row(i) - world.trans.row(i)).cwiseAbs().maxCoeff() < 1e-12);
    CHECK(rotDistance(back.rot, world.rot, i) < 1e-12);
  }
}

TEMPLATE_TEST_CASE("paper per-frame camera -> canonical agrees with camera -> world -> canonical",
                   "[motion][canonical]", float, double) {
  using S = TestType;
  const Eigen::Index T = 15;
  auto cam = randomHand<S>(T, 12);
  cam.valid[0] = 0;
  std::vector<hawor::Mat3<S>> R;
  std::vector<hawor::Vec3<S>> t;
  randomPoses<S>(T, 13, R, t);
  for (const auto& J0 : {randomJ0<S>(1, 14), randomJ0<S>(T, 15)}) {
    std::vector<hawor::Mat3<S>> Rp;
    std::vector<hawor::Vec3<S>> tp;
    const auto paper = hawor::cameraToCanonicalPaper(cam, R, t, J0, &Rp, &tp);
    const auto via_world = hawor::cameraToCanonical(cam, R, t, J0);
    REQUIRE(Rp.size() == size_t(T));
    for (Eigen::Index i = 0; i < T; ++i) {
      CHECK((paper.trans.row(i) - via_world.trans.row(i)).norm() < tol<S>() * 10);
      CHECK(rotDistance(paper.rot, via_world.rot, i) < tol<S>() * 10);
    }
    CHECK(paper.rot.row(1).norm() < tol<S>());
    CHECK(paper.trans.row(1).norm() < tol<S>());
  }
  // The subtlety documented in canonical.hpp: reading the paper's Γ as MANO transl (instead of
  // the root joint) ignores that MANO rotates about joint 0, and is off by A⁻¹(R_ct − R_c0)·J0.
  const auto J0 = randomJ0<S>(1, 16);
  const auto via_world = hawor::cameraToCanonical(cam, R, t, J0);
  const hawor::Vec3<S> phi0 = cam.rot.row(1).transpose();
  const hawor::Mat3<S> A_inv = (R[1] * hawor::axisAngleToMatrix(phi0)).transpose();
  const hawor::Vec3<S> g0 = cam.trans.row(1).transpose();
  const hawor::Vec3<S> gt = cam.trans.row(6).transpose();
  const hawor::Vec3<S> literal = A_inv * (R[6] * gt + t[6] - t[1] - R[1] * g0);
  const hawor::Vec3<S> j0 = J0.row(0).transpose();
  const hawor::Vec3<S> diff = via_world.trans.row(6).transpose() - literal;
  CHECK(diff.norm() > S(1e-3));
  CHECK((diff - A_inv * (R[6] - R[1]) * j0).norm() < tol<S>() * 10);
}

TEMPLATE_TEST_CASE("pre-fill of a HandMotion", "[motion][prefill]", float, double) {
  using S = TestType;
  const Eigen::Index T = 12;
  auto m = randomHand<S>(T, 20);
  m.valid = {0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 0};
  for (Eigen::Index i = 0; i < T; ++i)
    if (!m.valid[size_t(i)]) {
      m.rot.row(i).setConstant(std::numeric_limits<S>::quiet_NaN());
      m.betas.row(i).setConstant(std::numeric_limits<S>::quiet_NaN());
    }
  const auto f = hawor::fillInterpolate(m);
  const auto l = hawor::fillLastPose(m);
  CHECK(f.valid == m.valid);
  CHECK(l.valid == m.valid);
  CHECK(f.rot.allFinite());
  CHECK(f.betas.allFinite());
  for (Eigen::Index i = 0; i < T; ++i) {
    if (!m.valid[size_t(i)]) continue;
    CHECK(std::memcmp(f.rot.row(i).data(), m.rot.row(i).data(), 3 * sizeof(S)) == 0);
    CHECK(std::memcmp(f.handPose.row(i).data(), m.handPose.row(i).data(), 45 * sizeof(S)) == 0);
    CHECK(std::memcmp(l.trans.row(i).data(), m.trans.row(i).data(), 3 * sizeof(S)) == 0);
  }
  // betas and trans: LERP; rotations: SLERP per joint
  CHECK((f.betas.row(4) - (m.betas.row(2) + S(0.5) * (m.betas.row(6) - m.betas.row(2)))).norm() <
        tol<S>());
  CHECK((f.trans.row(3) - (m.trans.row(2) + S(0.25) * (m.trans.row(6) - m.trans.row(2)))).norm() <
        tol<S>());
  for (Eigen::Index k = 0; k < 45; k += 3) {
    const hawor::Vec3<S> a = m.handPose.row(7).segment(k, 3).transpose();
    const hawor::Vec3<S> b = m.handPose.row(9).segment(k, 3).transpose();
    const hawor::Vec3<S> e = hawor::slerpAxisAngle(a, b, S(0.5));
    CHECK((f.handPose.row(8).segment(k, 3).transpose() - e).norm() < tol<S>());
  }
  CHECK(f.rot.row(0) == m.rot.row(1));
  CHECK(f.trans.row(11) == m.trans.row(9));
  CHECK(l.rot.row(5) == m.rot.row(2));
  CHECK(l.betas.row(8) == m.betas.row(7));
  CHECK(l.handPose.row(0) == m.handPose.row(1));
  auto none = m;
  none.valid.assign(size_t(T), 0);
  CHECK_THROWS_AS(hawor::fillInterpolate(none), hawor::Error);
}
