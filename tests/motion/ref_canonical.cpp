// Cross-check of motion/canonical.hpp against a numpy implementation of docs/design.md §3/§7
// (tests/ref/motion_canonical.py).
#include <catch2/catch.hpp>

#include "ref_motion_util.hpp"

TEST_CASE("camera -> world -> canonical matches the numpy reference", "[motion][canonical][ref]") {
  using hawor_test::matAt;
  using hawor_test::toSeq;
  using hawor_test::vecAt;
  const auto ref = hawor_test::runReference("motion_canonical.py", "motion_canonical.txt");
  hawor::HandMotion<double> cam;
  cam.rot = toSeq(ref["rot_c"]);
  cam.trans = toSeq(ref["trans_c"]);
  cam.handPose = toSeq(ref["pose"]);
  cam.betas = toSeq(ref["betas"]);
  cam.valid = hawor_test::toMask(ref["valid"]);
  const Eigen::Index T = cam.frames();
  std::vector<hawor::Mat3<double>> R;
  std::vector<hawor::Vec3<double>> t;
  for (Eigen::Index i = 0; i < T; ++i) {
    R.push_back(matAt(ref["R_c2w"], i));
    t.push_back(vecAt(ref["t_c2w"], i));
  }
  const hawor::Sequence<double> j0seq = toSeq(ref["J0"]);
  const hawor::Points3<double> J0 = j0seq;

  const auto world = hawor::cameraToWorld(cam, R, t, J0);
  hawor::CanonicalFrame<double> frame;
  const auto can = hawor::worldToCanonical(world, J0, &frame);
  const auto trans_w = toSeq(ref["trans_w"]);
  const auto trans_can = toSeq(ref["trans_can"]);
  double e_w = 0, e_can = 0, e_Rw = 0, e_Rcan = 0;
  for (Eigen::Index i = 0; i < T; ++i) {
    const hawor::Vec3<double> aw = world.rot.row(i).transpose();
    const hawor::Vec3<double> ac = can.rot.row(i).transpose();
    e_Rw =
        std::max(e_Rw, (hawor::axisAngleToMatrix(aw) - matAt(ref["Rw"], i)).cwiseAbs().maxCoeff());
    e_Rcan = std::max(e_Rcan,
                      (hawor::axisAngleToMatrix(ac) - matAt(ref["Rcan"], i)).cwiseAbs().maxCoeff());
    e_w = std::max(e_w, (world.trans.row(i) - trans_w.row(i)).cwiseAbs().maxCoeff());
    e_can = std::max(e_can, (can.trans.row(i) - trans_can.row(i)).cwiseAbs().maxCoeff());
  }
  CHECK(e_Rw < 1e-12);
  CHECK(e_Rcan < 1e-12);
  CHECK(e_w < 1e-12);
  CHECK(e_can < 1e-12);
  CHECK(frame.origin == 3);
  CHECK((frame.R_w2can - matAt(ref["R_w2can"], 0)).cwiseAbs().maxCoeff() < 1e-12);
  CHECK((frame.t_w2can - vecAt(ref["t_w2can"], 0)).cwiseAbs().maxCoeff() < 1e-12);

  // paper per-frame form with one J0 (that of the canonical frame)
  const hawor::Points3<double> J0o = J0.row(frame.origin);
  const auto paper = hawor::cameraToCanonicalPaper(cam, R, t, J0o);
  const auto paper_trans = toSeq(ref["paper_trans"]);
  double e_pt = 0, e_pR = 0;
  for (Eigen::Index i = 0; i < T; ++i) {
    const hawor::Vec3<double> a = paper.rot.row(i).transpose();
    e_pR = std::max(e_pR,
                    (hawor::axisAngleToMatrix(a) - matAt(ref["paper_R"], i)).cwiseAbs().maxCoeff());
    e_pt = std::max(e_pt, (paper.trans.row(i) - paper_trans.row(i)).cwiseAbs().maxCoeff());
  }
  CHECK(e_pR < 1e-12);
  CHECK(e_pt < 1e-12);
}
