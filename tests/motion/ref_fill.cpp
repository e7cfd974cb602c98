// Cross-check of the gap fills (motion/sequence.hpp, motion/prefill.hpp) against a numpy/scipy
// implementation of the same rules (tests/ref/motion_fill.py).
#include <catch2/catch.hpp>

#include "ref_motion_util.hpp"

namespace {

double maxAbs(const hawor::Sequence<double>& a, const hawor::Sequence<double>& b) {
  REQUIRE(a.rows() == b.rows());
  REQUIRE(a.cols() == b.cols());
  return (a - b).cwiseAbs().maxCoeff();
}

// Largest rotation-matrix difference between two T×3K axis-angle sequences.
double maxRotDiff(const hawor::Sequence<double>& a, const hawor::Sequence<double>& b) {
  REQUIRE(a.rows() == b.rows());
  REQUIRE(a.cols() == b.cols());
  double worst = 0;
  for (Eigen::Index t = 0; t < a.rows(); ++t)
    for (Eigen::Index k = 0; k < a.cols(); k += 3) {
      const hawor::Vec3<double> x = a.row(t).segment(k, 3).transpose();
      const hawor::Vec3<double> y = b.row(t).segment(k, 3).transpose();
      worst = std::max(
          worst, (hawor::axisAngleToMatrix(x) - hawor::axisAngleToMatrix(y)).cwiseAbs().maxCoeff());
    }
  return worst;
}

}  // namespace

TEST_CASE("gap fills match the numpy/scipy reference", "[motion][sequence][ref]") {
  using hawor_test::toSeq;
  const auto ref = hawor_test::runReference("motion_fill.py", "motion_fill.txt");
  const hawor::ValidMask valid = hawor_test::toMask(ref["valid"]);
  const auto lin = toSeq(ref["lin"]);
  const auto rot = toSeq(ref["rot"]);
  CHECK(maxAbs(hawor::fillLinear(lin, valid), toSeq(ref["lin_linear"])) < 1e-12);
  CHECK(maxAbs(hawor::fillLastPose(lin, valid), toSeq(ref["lin_last"])) == 0.0);
  CHECK(maxRotDiff(hawor::fillRotations(rot, valid), toSeq(ref["rot_slerp"])) < 1e-12);
  CHECK(maxAbs(hawor::fillLastPose(rot, valid), toSeq(ref["rot_last"])) == 0.0);

  hawor::HandMotion<double> m;
  m.rot = toSeq(ref["h_rot"]);
  m.trans = toSeq(ref["h_trans"]);
  m.handPose = toSeq(ref["h_pose"]);
  m.betas = toSeq(ref["h_betas"]);
  m.valid = valid;
  const auto f = hawor::fillInterpolate(m);
  CHECK(maxRotDiff(f.rot, toSeq(ref["h_rot_fill"])) < 1e-12);
  CHECK(maxAbs(f.trans, toSeq(ref["h_trans_fill"])) < 1e-12);
  CHECK(maxRotDiff(f.handPose, toSeq(ref["h_pose_fill"])) < 1e-12);
  CHECK(maxAbs(f.betas, toSeq(ref["h_betas_fill"])) < 1e-12);
}
