// Cross-check of motion/slerp.hpp against scipy's Slerp (tests/ref/motion_slerp.py).
#include <catch2/catch.hpp>

#include "ref_motion_util.hpp"

TEST_CASE("slerp matches scipy Slerp", "[motion][slerp][ref]") {
  const auto ref = hawor_test::runReference("motion_slerp.py", "motion_slerp.txt");
  const auto& q0 = ref["q0"];
  const auto& q1 = ref["q1"];
  const auto& t = ref["t"];
  const long n = t.size();
  REQUIRE(n > 50);
  double worst_q = 0, worst_a = 0;
  for (long i = 0; i < n; ++i) {
    const Eigen::Quaterniond a(q0[4 * i], q0[4 * i + 1], q0[4 * i + 2], q0[4 * i + 3]);
    const Eigen::Quaterniond b(q1[4 * i], q1[4 * i + 1], q1[4 * i + 2], q1[4 * i + 3]);
    const hawor::Mat3<double> expect = hawor_test::matAt(ref["expected"], i);
    const hawor::Mat3<double> got = hawor::quaternionToMatrix(hawor::slerp(a, b, t[i]));
    worst_q = std::max(worst_q, (got - expect).cwiseAbs().maxCoeff());
    const hawor::Vec3<double> r = hawor::slerpAxisAngle(hawor_test::vecAt(ref["a0"], i),
                                                        hawor_test::vecAt(ref["a1"], i), t[i]);
    worst_a = std::max(worst_a, (hawor::axisAngleToMatrix(r) - expect).cwiseAbs().maxCoeff());
  }
  CHECK(worst_q < 1e-12);
  CHECK(worst_a < 1e-12);
}
