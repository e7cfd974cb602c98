// Unit/property tests of eval/hand_metrics.hpp and eval/joint_sequence.hpp (native and WASM).
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "hawor/eval/eval.hpp"

template struct hawor::HandMetrics<float>;
template struct hawor::HandMetrics<double>;

namespace {

using hawor::JointSequence;

template <typename S>
S handTol() {
  return std::is_same<S, float>::value ? S(5e-3) : S(1e-8);  // in mm / % / m/s²
}

// A smoothly moving random hand: T frames × J joints, metres.
template <typename S>
JointSequence<S> handTrack(Eigen::Index T, Eigen::Index J, unsigned seed) {
  std::srand(seed);
  const hawor::Points3<S> shape = hawor::Points3<S>::Random(J, 3) * S(0.05);
  JointSequence<S> seq(T, 3 * J);
  for (Eigen::Index t = 0; t < T; ++t) {
    const S s = S(t) / S(30);
    const hawor::Vec3<S> w(S(0.5) * std::sin(S(0.3) * s), S(0.4) * std::cos(S(0.2) * s),
                           S(0.3) * s);
    const hawor::Vec3<S> root(S(0.3) * std::sin(S(0.7) * s), S(0.2) * std::cos(S(0.5) * s),
                              S(0.1) * s);
    hawor::SimilarityTransform<S> pose;
    pose.R = hawor::axisAngleToMatrix(w);
    pose.t = root;
    const hawor::Points3<S> p = pose.apply(shape);
    seq.row(t) = Eigen::Map<const Eigen::Matrix<S, 1, Eigen::Dynamic>>(p.data(), 3 * J);
  }
  return seq;
}

template <typename S>
hawor::SimilarityTransform<S> handSim(S scale, unsigned seed) {
  std::srand(seed);
  hawor::SimilarityTransform<S> x;
  x.R = hawor::axisAngleToMatrix(hawor::Vec3<S>(hawor::Vec3<S>::Random() * S(2)));
  x.t = hawor::Vec3<S>::Random();
  x.s = scale;
  return x;
}

// Applies x to frames [begin, end) of seq.
template <typename S>
void applyTo(JointSequence<S>& seq, const hawor::SimilarityTransform<S>& x, Eigen::Index begin,
             Eigen::Index end) {
  const Eigen::Index J = seq.cols() / 3;
  for (Eigen::Index t = begin; t < end; ++t) {
    const hawor::Points3<S> p = x.apply(hawor::frameJoints(seq, t));
    seq.row(t) = Eigen::Map<const Eigen::Matrix<S, 1, Eigen::Dynamic>>(p.data(), 3 * J);
  }
}

}  // namespace

TEMPLATE_TEST_CASE("joint sequence layout and converters", "[eval][joints]", float, double) {
  using S = TestType;
  std::vector<hawor::Points3<S>> frames;
  for (int t = 0; t < 4; ++t) frames.push_back(hawor::Points3<S>::Random(21, 3));
  const JointSequence<S> seq = hawor::toJointSequence(frames);
  REQUIRE(seq.rows() == 4);
  REQUIRE(seq.cols() == 63);
  CHECK(hawor::jointCount(seq) == 21);
  CHECK(seq(2, 3 * 5 + 1) == frames[2](5, 1));
  CHECK(hawor::frameJoints(seq, 3) == frames[3]);
  const auto block = hawor::framePoints(seq, 1, 3);
  CHECK(block.rows() == 42);
  CHECK(block.row(21 + 4) == frames[2].row(4));
  const JointSequence<S> sel = hawor::selectFrames(seq, {1, 0, 0, 1});
  CHECK(sel.rows() == 2);
  CHECK(sel.row(1) == seq.row(3));
  frames[1] = hawor::Points3<S>::Random(20, 3);
  CHECK_THROWS_AS(hawor::toJointSequence(frames), hawor::Error);
  CHECK_THROWS_AS(hawor::jointCount(JointSequence<S>(2, 62)), hawor::Error);
}

TEMPLATE_TEST_CASE("a similarity of the ground truth scores zero", "[eval][hands]", float, double) {
  using S = TestType;
  const JointSequence<S> gt = handTrack<S>(250, 21, 1);
  JointSequence<S> est = gt;
  applyTo(est, handSim<S>(S(1.3), 2), 0, 250);
  CHECK(hawor::paMpjpe(gt, est) < handTol<S>());
  // rounding-level errors are > 0 = the first threshold, so PCK(0) = 0 and the first trapezoid
  // is half: AUC = 1 − 0.5/99 (the convention; an exactly zero error would give 1)
  CHECK(hawor::aucPck(gt, est) == Approx(1.0 - 0.5 / 99.0).margin(1e-4));
  CHECK(hawor::wMpjpe(gt, est) < handTol<S>());
  CHECK(hawor::waMpjpe(gt, est) < handTol<S>());
  // rigid (no scale): RTE 0 too; with a scale RTE is not 0
  JointSequence<S> rigid = gt;
  applyTo(rigid, handSim<S>(S(1), 3), 0, 250);
  CHECK(hawor::rte(gt, rigid) < handTol<S>());
  CHECK(hawor::rte(gt, est) > S(1));
  // a constant offset has no acceleration error
  JointSequence<S> shifted = gt;
  shifted.rowwise() += Eigen::Matrix<S, 1, Eigen::Dynamic>::Constant(63, S(0.7));
  CHECK(hawor::accelError(gt, shifted) < handTol<S>());
  CHECK(hawor::accelError(gt, est) > S(0.01));
}

TEMPLATE_TEST_CASE("W/WA-MPJPE fit one similarity per 100-frame chunk", "[eval][hands]", float,
                   double) {
  using S = TestType;
  const JointSequence<S> gt = handTrack<S>(250, 21, 4);
  // a different similarity on each official chunk [0,100) [100,200) [200,250): still zero
  JointSequence<S> est = gt;
  applyTo(est, handSim<S>(S(0.8), 5), 0, 100);
  applyTo(est, handSim<S>(S(1.2), 6), 100, 200);
  applyTo(est, handSim<S>(S(1.5), 7), 200, 250);
  CHECK(hawor::wMpjpe(gt, est) < handTol<S>());
  CHECK(hawor::waMpjpe(gt, est) < handTol<S>());
  // a change inside a chunk is not absorbed
  JointSequence<S> bad = gt;
  applyTo(bad, handSim<S>(S(1.1), 8), 150, 250);
  CHECK(hawor::waMpjpe(gt, bad) > S(1));
  // W fits on the first two frames only: a change after them counts fully in W, less in WA
  JointSequence<S> late = gt;
  for (Eigen::Index t = 50; t < 100; ++t)
    for (Eigen::Index j = 0; j < 21; ++j) late(t, 3 * j) += S(0.01);  // 10 mm along x
  CHECK(hawor::wMpjpe(gt, late) == Approx(10.0 * 50.0 / 250.0).epsilon(1e-3));
  CHECK(hawor::waMpjpe(gt, late) < hawor::wMpjpe(gt, late));
}

TEMPLATE_TEST_CASE("hand-computed values", "[eval][hands]", float, double) {
  using S = TestType;
  // Accel: one joint, all-zero ground truth, the estimate displaced by d = 1 mm at frame 2 of 5:
  // second differences centred on frames 1, 2, 3 are d, −2d, d → mean 4/3 mm × 30² = 1.2 m/s².
  JointSequence<S> g = JointSequence<S>::Zero(5, 3);
  JointSequence<S> e = g;
  e(2, 0) = S(0.001);
  CHECK(hawor::accelError(g, e) == Approx(1.2).epsilon(1e-5));
  CHECK(hawor::accelError(g, e, {}, S(60)) == Approx(4.8).epsilon(1e-5));
  // frame 0 missing: samples centred on 2 and 3 → (2 + 1)/2 mm → 1.35 m/s²; frame 1 missing:
  // only the sample centred on 3 → 0.9 m/s²
  CHECK(hawor::accelError(g, e, {0, 1, 1, 1, 1}) == Approx(1.35).epsilon(1e-5));
  CHECK(hawor::accelError(g, e, {1, 0, 1, 1, 1}) == Approx(0.9).epsilon(1e-5));
  CHECK(std::isnan(hawor::accelError(g, e, {1, 1, 0, 1, 0})));
  // RTE: ground-truth root along x at 0, 1, 2, 3 m (path 3 m), estimate twice as far: after the
  // best rigid fit (centroids matched) the errors are 1.5, 0.5, 0.5, 1.5 → mean 1 m → 33.3 %.
  JointSequence<S> gr = JointSequence<S>::Zero(4, 3), er = gr;
  for (int t = 0; t < 4; ++t) {
    gr(t, 0) = S(t);
    er(t, 0) = S(2 * t);
  }
  CHECK(hawor::rte(gr, er) == Approx(100.0 / 3.0).epsilon(1e-4));
  // static ground truth: the ratio is undefined
  CHECK(std::isnan(hawor::rte(g, e)));
  // AUC of errors all exactly 10 mm: PCK steps from 0 to 1 between thresholds 19 and 20 (of
  // 0..99, spacing 50/99): area (0.5 + 79)·h / 50 = 79.5 / 99.
  hawor::Sequence<S> err = hawor::Sequence<S>::Constant(7, 21, S(10));
  CHECK(hawor::aucFromErrors(err) == Approx(79.5 / 99.0).epsilon(1e-6));
  CHECK(hawor::aucFromErrors(hawor::Sequence<S>(hawor::Sequence<S>::Zero(3, 21))) == Approx(1.0));
  CHECK(hawor::aucFromErrors(hawor::Sequence<S>(hawor::Sequence<S>::Constant(3, 21, S(60)))) ==
        Approx(0.0).margin(1e-12));
  // PA-MPJPE is invariant to a different similarity of the estimate in every frame
  const JointSequence<S> gp = handTrack<S>(6, 21, 9);
  std::srand(13);
  JointSequence<S> ep = gp + JointSequence<S>::Random(6, 63) * S(0.003);
  const S pa = hawor::paMpjpe(gp, ep);
  CHECK(pa > S(0.1));
  for (Eigen::Index t = 0; t < 6; ++t) applyTo(ep, handSim<S>(S(0.5 + 0.2 * t), 20 + t), t, t + 1);
  CHECK(hawor::paMpjpe(gp, ep) == Approx(pa).epsilon(std::is_same<S, float>::value ? 1e-3 : 1e-10));
}

TEMPLATE_TEST_CASE("validity masks", "[eval][hands]", float, double) {
  using S = TestType;
  const Eigen::Index T = 230;
  const JointSequence<S> gt = handTrack<S>(T, 21, 10);
  std::srand(11);
  JointSequence<S> est = gt + JointSequence<S>::Random(T, 63) * S(0.004);
  hawor::ValidMask valid(size_t(T), 1);
  for (Eigen::Index t = 40; t < 60; ++t) valid[size_t(t)] = 0;
  valid[0] = valid[150] = 0;
  const auto base = hawor::evaluateHands(gt, est, gt, est, valid);
  CHECK(base.n == T - 22);
  // garbage in invalid frames changes nothing
  JointSequence<S> est2 = est;
  for (Eigen::Index t = 0; t < T; ++t)
    if (!valid[size_t(t)]) est2.row(t).setConstant(std::numeric_limits<S>::quiet_NaN());
  const auto m2 = hawor::evaluateHands(gt, est2, gt, est2, valid);
  CHECK(m2.pa_mpjpe == base.pa_mpjpe);
  CHECK(m2.auc == base.auc);
  CHECK(m2.w_mpjpe == base.w_mpjpe);
  CHECK(m2.wa_mpjpe == base.wa_mpjpe);
  CHECK(m2.rte == base.rte);
  CHECK(m2.accel == base.accel);
  // PA-MPJPE over valid frames = PA-MPJPE of the selected frames
  CHECK(base.pa_mpjpe ==
        Approx(hawor::paMpjpe(hawor::selectFrames(gt, valid), hawor::selectFrames(est, valid))));
  CHECK(hawor::paJointErrors(gt, est, valid).rows() == T - 22);
  // a chunk with no valid frame is skipped
  hawor::ValidMask first_chunk_only(size_t(T), 0);
  for (int t = 0; t < 100; ++t) first_chunk_only[size_t(t)] = 1;
  CHECK(hawor::waMpjpe(gt, est, first_chunk_only) ==
        Approx(
            hawor::waMpjpe(JointSequence<S>(gt.topRows(100)), JointSequence<S>(est.topRows(100)))));
}

TEMPLATE_TEST_CASE("metric input errors", "[eval][hands]", float, double) {
  using S = TestType;
  const JointSequence<S> gt = handTrack<S>(10, 21, 12);
  CHECK_THROWS_AS(hawor::paMpjpe(gt, JointSequence<S>(gt.topRows(9))), hawor::Error);
  CHECK_THROWS_AS(hawor::wMpjpe(JointSequence<S>(2, 5), JointSequence<S>(2, 5)), hawor::Error);
  CHECK_THROWS_AS(hawor::rte(gt, gt, hawor::ValidMask(9, 1)), hawor::Error);
  CHECK_THROWS_AS(hawor::accelError(gt, gt, {}, S(0)), hawor::Error);
  JointSequence<S> nan = gt;
  nan(4, 7) = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_WITH(hawor::paMpjpe(gt, nan), Catch::Contains("frame 4"));
  CHECK_THROWS_WITH(hawor::evaluateHands(gt, gt, gt, gt, hawor::ValidMask(10, 0)),
                    Catch::Contains("no valid frame"));
  CHECK_THROWS_AS(hawor::evaluateHands(gt, gt, JointSequence<S>(gt.topRows(5)),
                                       JointSequence<S>(gt.topRows(5))),
                  hawor::Error);
}
