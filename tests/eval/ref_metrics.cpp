// Cross-check of every metric of eval/ against the independent numpy implementation
// (tests/ref/metrics_np.py, driven by tests/ref/eval_metrics.py), relative 1e-9 in double.
#include <catch2/catch.hpp>

#include "../support/ref_data.hpp"
#include "hawor/eval/eval.hpp"

namespace {

hawor::JointSequence<double> toSeq(const hawor_test::RefArray& a) {
  const long rows = a.shape.at(0);
  hawor::JointSequence<double> m(rows, a.size() / rows);
  for (long i = 0; i < a.size(); ++i) m.data()[i] = a[i];
  return m;
}

hawor::Points3<double> toPoints(const hawor_test::RefArray& a) {
  hawor::Points3<double> m(a.shape.at(0), 3);
  for (long i = 0; i < a.size(); ++i) m.data()[i] = a[i];
  return m;
}

/// T×9 row-major rotation matrices (numpy's C order).
std::vector<hawor::Mat3<double>> toRotations(const hawor_test::RefArray& a) {
  std::vector<hawor::Mat3<double>> out(static_cast<size_t>(a.size() / 9));
  for (size_t t = 0; t < out.size(); ++t)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out[t](r, c) = a[static_cast<long>(9 * t + 3 * r + c)];
  return out;
}

void checkRel(double got, double expect, const char* what) {
  INFO(what << ": got " << got << ", numpy " << expect);
  CHECK(std::abs(got - expect) <= 1e-9 * std::max(1.0, std::abs(expect)));
}

}  // namespace

TEST_CASE("hand and camera metrics match the numpy reference", "[eval][ref]") {
  const auto ref = hawor_test::runReference("eval_metrics.py", "eval_metrics.txt");
  const auto gt_w = toSeq(ref["gt_w"]);
  const auto est_w = toSeq(ref["est_w"]);
  const auto gt_c = toSeq(ref["gt_c"]);
  const auto est_c = toSeq(ref["est_c"]);
  hawor::ValidMask valid;
  for (long i = 0; i < ref["valid"].size(); ++i) valid.push_back(ref["valid"][i] != 0.0);
  REQUIRE(gt_w.rows() == 250);
  REQUIRE(gt_w.cols() == 63);

  const auto all = hawor::evaluateHands(gt_w, est_w, gt_c, est_c);
  checkRel(all.pa_mpjpe, ref["pa_all"][0], "PA-MPJPE");
  checkRel(all.auc, ref["auc_all"][0], "AUC");
  checkRel(all.w_mpjpe, ref["w_all"][0], "W-MPJPE");
  checkRel(all.wa_mpjpe, ref["wa_all"][0], "WA-MPJPE");
  checkRel(all.rte, ref["rte_all"][0], "RTE");
  checkRel(all.accel, ref["accel_all"][0], "Accel");
  CHECK(all.n == 250);
  checkRel(hawor::accelError(gt_w, est_w, {}, 60.0), ref["accel_fps60"][0], "Accel 60 fps");

  const auto masked = hawor::evaluateHands(gt_w, est_w, gt_c, est_c, valid);
  checkRel(masked.pa_mpjpe, ref["pa_mask"][0], "PA-MPJPE (mask)");
  checkRel(masked.auc, ref["auc_mask"][0], "AUC (mask)");
  checkRel(masked.w_mpjpe, ref["w_mask"][0], "W-MPJPE (mask)");
  checkRel(masked.wa_mpjpe, ref["wa_mask"][0], "WA-MPJPE (mask)");
  checkRel(masked.rte, ref["rte_mask"][0], "RTE (mask)");
  checkRel(masked.accel, ref["accel_mask"][0], "Accel (mask)");
  const auto pa_err = hawor::paJointErrors(gt_c, est_c, valid);
  const auto pa_ref = toSeq(ref["pa_err_mask"]);
  REQUIRE(pa_err.rows() == pa_ref.rows());
  CHECK((pa_err - pa_ref).cwiseAbs().maxCoeff() < 1e-9);

  for (const char* tag : {"c250", "c201"}) {
    const std::string k(tag);
    const auto gp = toPoints(ref[k + "_gt"]);
    const auto ep = toPoints(ref[k + "_est"]);
    const auto cm = hawor::evaluateCameras(gp, ep);
    checkRel(cm.ate, ref[k + "_ate"][0], (k + " ATE").c_str());
    checkRel(cm.ate_s, ref[k + "_ate_s"][0], (k + " ATE-S").c_str());
    checkRel(cm.scale, ref[k + "_scale"][0], (k + " scale").c_str());
    const auto parts = hawor::alignCameraParts(gp, ep, 100);
    const auto aligned = hawor::alignJointsByParts(parts, toSeq(ref[k + "_pts"]));
    CHECK((aligned - toSeq(ref[k + "_pts_aligned"])).cwiseAbs().maxCoeff() < 1e-9);

    const auto gR = toRotations(ref[k + "_gR"]);
    const auto eR = toRotations(ref[k + "_eR"]);
    const auto re = hawor::rotationErrors(gR, eR);
    checkRel(re.mean_deg, ref[k + "_rot_mean"][0], (k + " rotation error mean").c_str());
    checkRel(re.max_deg, ref[k + "_rot_max"][0], (k + " rotation error max").c_str());
    CHECK((re.align - toRotations(ref[k + "_rot_align"])[0]).cwiseAbs().maxCoeff() < 1e-9);
  }
}
