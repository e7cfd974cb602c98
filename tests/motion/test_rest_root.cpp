// restRootJoints (motion/rest_root.hpp): J0(β) against the forward pass's joint 0 at zero pose
// and zero translation, per frame, with missing frames taking interpolated betas.
#include <catch2/catch.hpp>

#include <cmath>

#include "hawor/hand/synthetic_hand.hpp"
#include "hawor/motion/rest_root.hpp"

TEST_CASE("restRootJoints: joint 0 of the shaped rest hand, per frame", "[motion][rest_root]") {
  const hawor::HandModel<double> m = hawor::makeSyntheticHand<double>(6);
  REQUIRE(m.numBetas() > 0);
  const int B = m.numBetas();
  hawor::HandMotion<double> mo;
  const int T = 5;
  mo.rot = hawor::Sequence<double>::Zero(T, 3);
  mo.trans = hawor::Sequence<double>::Zero(T, 3);
  mo.handPose = hawor::Sequence<double>::Zero(T, 3 * (m.numJoints() - 1));
  mo.betas = hawor::Sequence<double>::Zero(T, B);
  for (int b = 0; b < B; ++b) mo.betas(0, b) = 0.5 + b, mo.betas(4, b) = -1.0 + 0.3 * b;
  for (int t = 1; t < 4; ++t) mo.betas.row(t).setConstant(NAN);  // missing frames
  mo.valid = {1, 0, 0, 0, 1};
  const hawor::Points3<double> J0 = hawor::restRootJoints(m, mo);
  REQUIRE(J0.rows() == T);
  for (int t = 0; t < T; ++t) {
    hawor::HandPose<double> p = hawor::HandPose<double>::zero(m);
    p.betas = (mo.betas.row(0) + (mo.betas.row(4) - mo.betas.row(0)) * (t / 4.0)).transpose();
    const hawor::Vec3<double> want = hawor::forward(m, p).joints.row(0).transpose();
    CHECK((J0.row(t).transpose() - want).norm() < 1e-12);
  }
  mo.valid.assign(T, 0);  // no observed frame: the mean shape, one row
  const hawor::Points3<double> J0mean = hawor::restRootJoints(m, mo);
  REQUIRE(J0mean.rows() == 1);
  CHECK((J0mean.row(0) - hawor::forward(m, hawor::HandPose<double>::zero(m)).joints.row(0)).norm() < 1e-12);
  hawor::Sequence<double> tooMany = hawor::Sequence<double>::Zero(1, B + 1);
  CHECK_THROWS_WITH(hawor::restRootJoints(m, tooMany), Catch::Contains("betas"));
}
