// Unit/property tests of the infilling: motion/spline_infill.hpp (the data-free spline),
// motion/motion_noise.hpp, motion/local_poly.hpp, motion/smooth.hpp, motion/infill.hpp (the
// per-hand pipeline) and motion/infill_window.hpp (windows, features, the infiller interface).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "hawor/motion/motion.hpp"

template struct hawor::SplineInfillOptions<float>;
template struct hawor::SplineInfillOptions<double>;
template struct hawor::SmoothOptions<float>;
template struct hawor::SmoothOptions<double>;
template struct hawor::InfillOptions<float>;
template struct hawor::InfillOptions<double>;
template struct hawor::InfillResult<float>;
template struct hawor::InfillResult<double>;
template struct hawor::InfillWindow<float>;
template struct hawor::InfillWindow<double>;
template class hawor::SplineWindowInfiller<float>;
template class hawor::SplineWindowInfiller<double>;

namespace infill_test {

using Eigen::Index;

template <typename S>
S tolOf(double f, double d) {
  return std::is_same<S, float>::value ? S(f) : S(d);
}

/// Mask of length T with the given missing ranges [a, b).
inline hawor::ValidMask maskWithGaps(Index T, std::initializer_list<std::pair<Index, Index>> gaps) {
  hawor::ValidMask v(static_cast<size_t>(T), 1);
  for (const auto& g : gaps)
    for (Index t = g.first; t < g.second; ++t) v[static_cast<size_t>(t)] = 0;
  return v;
}

/// NaN in every missing row (the fills must not read them).
template <typename S>
void poisonMissing(hawor::HandMotion<S>& m) {
  const S nan = std::numeric_limits<S>::quiet_NaN();
  for (Index t = 0; t < m.frames(); ++t) {
    if (m.valid[static_cast<size_t>(t)]) continue;
    m.rot.row(t).setConstant(nan);
    m.trans.row(t).setConstant(nan);
    m.handPose.row(t).setConstant(nan);
    m.betas.row(t).setConstant(nan);
  }
}

/// A smooth hand motion: sums of sinusoids (periods 40–150 frames) for translation (±0.2 m),
/// the global rotation vector (±1.2 rad) and K joint rotation vectors (±0.5 rad); betas linear.
template <typename S>
hawor::HandMotion<S> smoothHand(Index T, Index K, Index B, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  hawor::HandMotion<S> m;
  m.rot.resize(T, 3);
  m.trans.resize(T, 3);
  m.handPose.resize(T, 3 * K);
  m.betas.resize(T, B);
  auto wave = [&](hawor::Sequence<S>& q, Index c, double amp) {
    const double p1 = 40 + 110 * U(rng), p2 = 40 + 110 * U(rng), f1 = 6.28 * U(rng), f2 = 6.28 * U(rng);
    const double a1 = amp * (0.4 + 0.6 * U(rng)), a2 = amp * 0.5 * U(rng);
    for (Index t = 0; t < T; ++t)
      q(t, c) = S(a1 * std::sin(6.283185307 * double(t) / p1 + f1) + a2 * std::sin(6.283185307 * double(t) / p2 + f2));
  };
  for (Index c = 0; c < 3; ++c) wave(m.trans, c, 0.2);
  for (Index c = 0; c < 3; ++c) wave(m.rot, c, 0.7);
  for (Index c = 0; c < 3 * K; ++c) wave(m.handPose, c, 0.3);
  for (Index c = 0; c < B; ++c)
    for (Index t = 0; t < T; ++t) m.betas(t, c) = S(0.5 - 0.01 * double(c) + 1e-3 * double(t));
  m.valid.assign(static_cast<size_t>(T), 1);
  return m;
}

template <typename S>
bool rowsBitEqual(const hawor::Sequence<S>& a, const hawor::Sequence<S>& b, Index t) {
  return a.cols() == b.cols() &&
         std::memcmp(a.row(t).data(), b.row(t).data(), sizeof(S) * size_t(a.cols())) == 0;
}

template <typename S>
bool framesBitEqual(const hawor::HandMotion<S>& a, const hawor::HandMotion<S>& b, Index t) {
  return rowsBitEqual(a.rot, b.rot, t) && rowsBitEqual(a.trans, b.trans, t) &&
         rowsBitEqual(a.handPose, b.handPose, t) && rowsBitEqual(a.betas, b.betas, t);
}

template <typename S>
hawor::Mat3<S> rotAt(const hawor::Sequence<S>& q, Index t, Index col = 0) {
  const hawor::Vec3<S> a = q.row(t).template segment<3>(col).transpose();
  return hawor::axisAngleToMatrix(a);
}

/// Largest rotation distance (Frobenius) between two rotation sequences over the given frames.
template <typename S>
S maxRotDiff(const hawor::Sequence<S>& a, const hawor::Sequence<S>& b) {
  S m(0);
  for (Index t = 0; t < a.rows(); ++t)
    for (Index c = 0; c < a.cols(); c += 3) m = std::max(m, S((rotAt(a, t, c) - rotAt(b, t, c)).norm()));
  return m;
}

}  // namespace infill_test

using namespace infill_test;

TEMPLATE_TEST_CASE("spline: linear translation and constant angular velocity are exact",
                   "[motion][infill][spline]", float, double) {
  using S = TestType;
  const Index T = 400;
  hawor::HandMotion<S> m = hawor::HandMotion<S>::zeros(T);
  const hawor::Vec3<S> p0(S(0.1), S(-0.2), S(0.4)), v(S(0.002), S(-0.001), S(0.0015));
  const hawor::Vec3<S> w(S(0.004), S(-0.006), S(0.003));  // rad / frame: |300·w| < π
  const hawor::Mat3<S> R0 = hawor::axisAngleToMatrix(hawor::Vec3<S>(S(0.3), S(1.1), S(-0.4)));
  for (Index t = 0; t < T; ++t) {
    m.trans.row(t).template head<3>() = (p0 + S(t) * v).transpose();
    const hawor::Vec3<S> wt = S(t) * w;
    const hawor::Mat3<S> Rt = R0 * hawor::axisAngleToMatrix(wt);
    m.rot.row(t).template head<3>() = hawor::matrixToAxisAngle(Rt).transpose();
    for (Index j = 0; j < 15; ++j) {  // R_j(t) = R_j0·exp(t·ω_j)
      const hawor::Vec3<S> r0(S(0.05) * S(j), S(-0.3), S(0.1));
      const hawor::Vec3<S> wj = S(t) * S(0.1 * double(j + 1)) * hawor::Vec3<S>(w(1), w(2), w(0));
      const hawor::Mat3<S> Rj = hawor::axisAngleToMatrix(r0) * hawor::axisAngleToMatrix(wj);
      m.handPose.row(t).template segment<3>(3 * j) = hawor::matrixToAxisAngle(Rj).transpose();
    }
  }
  const hawor::HandMotion<S> truth = m;
  // gaps of 1, 12, 45, 90 frames and one longer than the horizon (deviation eased), plus ends
  m.valid = maskWithGaps(T, {{0, 5}, {20, 21}, {40, 52}, {70, 115}, {130, 220}, {230, 380}, {395, 400}});
  poisonMissing(m);
  const hawor::HandMotion<S> f = hawor::fillSpline(m);
  const S tol = tolOf<S>(2e-4, 1e-10);
  for (Index t = 5; t < 395; ++t) {
    CHECK((f.trans.row(t) - truth.trans.row(t)).norm() < tol);
    CHECK((rotAt(f.rot, t) - rotAt(truth.rot, t)).norm() < tol);
  }
  hawor::Sequence<S> pose_in = truth.handPose.middleRows(5, 390), pose_out = f.handPose.middleRows(5, 390);
  CHECK(maxRotDiff(pose_in, pose_out) < tol);
  // the ends hold the nearest valid frame
  CHECK(rowsBitEqual(f.trans, m.trans, 5));
  for (Index t = 0; t < 5; ++t) CHECK(f.trans.row(t) == m.trans.row(5));
  for (Index t = 395; t < 400; ++t) CHECK(f.rot.row(t) == m.rot.row(394));
}

TEMPLATE_TEST_CASE("spline with degree-3 fits reproduces a cubic motion", "[motion][infill][spline]",
                   float, double) {
  using S = TestType;
  const Index T = 140;
  hawor::Sequence<S> x(T, 3);
  for (Index t = 0; t < T; ++t) {
    const double s = double(t) / 100.0;
    x(t, 0) = S(0.1 + 0.3 * s - 0.5 * s * s + 0.4 * s * s * s);
    x(t, 1) = S(-0.2 + 0.1 * s * s * s);
    x(t, 2) = S(0.05 - 0.2 * s + 0.3 * s * s);
  }
  const hawor::ValidMask valid = maskWithGaps(T, {{10, 25}, {40, 95}, {110, 112}});
  hawor::SplineInfillOptions<S> o;
  o.degree = 3;
  const hawor::Sequence<S> f = hawor::fillSplineVectors(x, valid, o);
  const S tol = tolOf<S>(1e-4, 1e-11);
  for (Index t = 0; t < T; ++t) CHECK((f.row(t) - x.row(t)).norm() < tol);
  // the default quadratic fits are close but not exact on a cubic: the test can fail
  const hawor::Sequence<S> g = hawor::fillSplineVectors(x, valid);
  S worst(0);
  for (Index t = 40; t < 95; ++t) worst = std::max(worst, S((g.row(t) - x.row(t)).norm()));
  CHECK(worst < S(1e-4));
  if (std::is_same<S, double>::value) CHECK(worst > S(1e-9));
}

TEMPLATE_TEST_CASE("spline: hermiteEase and the deviation bound for long gaps",
                   "[motion][infill][spline]", float, double) {
  using S = TestType;
  const S L(30);
  CHECK(hawor::hermiteEase(S(0), L) == S(0));
  CHECK(hawor::hermiteEase(L, L) == S(0));
  CHECK(hawor::hermiteEase(S(45), L) == S(0));
  CHECK(hawor::hermiteEase(S(-1), L) == S(0));
  const S h = S(1e-3);
  CHECK(std::abs((hawor::hermiteEase(h, L) - hawor::hermiteEase(S(0), L)) / h - S(1)) < S(1e-3));
  CHECK(std::abs(hawor::hermiteEase(L / S(3), L) - S(4) / S(27) * L) < tolOf<S>(1e-5, 1e-12));
  // A fast motion before a 300-frame gap, static after it: the fill leaves the boundary with the
  // boundary velocity but stays within 4/27·horizon·|d| of the chord.
  const Index T = 400;
  hawor::Sequence<S> x = hawor::Sequence<S>::Zero(T, 3);
  for (Index t = 0; t < 50; ++t) x(t, 0) = S(0.01) * S(t - 50);  // 1 cm per frame, up to 0 at 50
  const hawor::ValidMask valid = maskWithGaps(T, {{50, 350}});
  const hawor::Sequence<S> f = hawor::fillSplineVectors(x, valid);
  // chord: from x(49) = −0.01 to 0; velocity mismatch ≈ 0.01 m / frame
  S worst(0);
  for (Index t = 50; t < 350; ++t) worst = std::max(worst, std::abs(f(t, 0) - x(49, 0) * S(350 - t) / S(301)));
  const S bound = S(4) / S(27) * S(60) * S(0.0101);
  CHECK(worst <= bound);
  CHECK(worst > S(0.5) * bound);  // the boundary velocity is used, not dropped
  for (Index t = 110; t < 290; ++t) CHECK(std::abs(f(t, 0) - x(49, 0) * S(350 - t) / S(301)) < S(1e-6));
}

TEMPLATE_TEST_CASE("spline: observed frames are bit for bit untouched", "[motion][infill][spline]",
                   float, double) {
  using S = TestType;
  const Index T = 260;
  hawor::HandMotion<S> m = smoothHand<S>(T, 15, 10, 7);
  m.valid = maskWithGaps(T, {{0, 3}, {30, 31}, {50, 90}, {100, 102}, {150, 240}, {255, 260}});
  poisonMissing(m);
  const hawor::HandMotion<S> f = hawor::fillSpline(m);
  for (Index t = 0; t < T; ++t) {
    if (m.valid[size_t(t)]) {
      CHECK(framesBitEqual(f, m, t));
    } else {
      CHECK(f.rot.row(t).allFinite());
      CHECK(f.trans.row(t).allFinite());
      CHECK(f.handPose.row(t).allFinite());
      CHECK(f.betas.row(t).allFinite());
    }
  }
  CHECK(f.valid == m.valid);
  // the pipeline: also bit for bit, and the filled mask is the missing frames
  hawor::Points3<S> J0(1, 3);
  J0 << S(0.09), S(0.006), S(0.005);
  for (auto method : {hawor::InfillMethod::LastPose, hawor::InfillMethod::Lerp, hawor::InfillMethod::Spline}) {
    hawor::InfillOptions<S> o;
    o.method = method;
    const hawor::InfillResult<S> r = hawor::infillHand(m, J0, o);
    for (Index t = 0; t < T; ++t) {
      CHECK(bool(r.filled[size_t(t)]) == !m.valid[size_t(t)]);
      if (m.valid[size_t(t)]) CHECK(framesBitEqual(r.motion, m, t));
    }
    CHECK(r.motion.valid == m.valid);
  }
}

TEMPLATE_TEST_CASE("spline: infilled frames are continuous at the gap boundaries",
                   "[motion][infill][spline]", float, double) {
  using S = TestType;
  const Index T = 300;
  const hawor::HandMotion<S> truth = smoothHand<S>(T, 15, 10, 11);
  hawor::HandMotion<S> m = truth;
  m.valid = maskWithGaps(T, {{40, 52}, {90, 150}, {200, 290}});
  poisonMissing(m);
  const hawor::HandMotion<S> f = hawor::fillSpline(m);
  const hawor::HandMotion<S> l = hawor::fillInterpolate(m);
  // Largest second difference of the true translation (per frame²) and its velocity bound.
  S acc(0), vel(0);
  for (Index t = 1; t + 1 < T; ++t) {
    acc = std::max(acc, S((truth.trans.row(t - 1) - S(2) * truth.trans.row(t) + truth.trans.row(t + 1)).norm()));
    vel = std::max(vel, S((truth.trans.row(t + 1) - truth.trans.row(t)).norm()));
  }
  for (Index a : {Index(39), Index(52), Index(89), Index(150), Index(199), Index(290)}) {
    // frames a−1, a, a+1 straddle a boundary: no jump (step ≲ the true step), no kink
    for (Index t : {a, a + 1}) CHECK((f.trans.row(t) - f.trans.row(t - 1)).norm() < S(1.5) * vel);
    const S d2 = (f.trans.row(a - 1) - S(2) * f.trans.row(a) + f.trans.row(a + 1)).norm();
    const S d2lerp = (l.trans.row(a - 1) - S(2) * l.trans.row(a) + l.trans.row(a + 1)).norm();
    CHECK(d2 < S(4) * acc);
    CHECK(d2 < d2lerp);  // LERP has a kink there, the spline not
    // rotations: the step across the boundary is of the size of the true one
    const S step = (rotAt(f.rot, a + 1) - rotAt(f.rot, a)).norm();
    const S true_step = (rotAt(truth.rot, a + 1) - rotAt(truth.rot, a)).norm();
    CHECK(step < S(1.5) * true_step + S(1e-3));
  }
  // and the spline beats LERP on this smooth motion
  S err_s(0), err_l(0);
  for (Index t = 0; t < T; ++t) {
    if (m.valid[size_t(t)]) continue;
    err_s += (f.trans.row(t) - truth.trans.row(t)).norm();
    err_l += (l.trans.row(t) - truth.trans.row(t)).norm();
  }
  CHECK(err_s < err_l);
}

TEMPLATE_TEST_CASE("noise estimate and shrinkage", "[motion][infill][spline]", float, double) {
  using S = TestType;
  const Index T = 600;
  std::mt19937 rng(5);
  std::normal_distribution<double> N01(0.0, 1.0);
  const double sigma = 2e-3;
  hawor::Sequence<S> x(T, 3), cubic(T, 3), rots(T, 3);
  for (Index t = 0; t < T; ++t) {
    const double s = double(t) / 300.0;
    for (Index c = 0; c < 3; ++c) {
      x(t, c) = S(0.1 * double(c) + sigma * N01(rng));
      cubic(t, c) = S(0.2 * s * s * s - 0.1 * s + 0.05 * double(c));
    }
    const hawor::Vec3<S> r(S(0.5 + sigma * N01(rng)), S(-0.3 + sigma * N01(rng)), S(0.2 + sigma * N01(rng)));
    rots.row(t).template head<3>() = r.transpose();
  }
  hawor::ValidMask valid = maskWithGaps(T, {{100, 140}, {300, 302}});
  const S est = hawor::estimateVectorNoise(x, 0, valid);
  CHECK(est > S(0.85 * sigma));
  CHECK(est < S(1.15 * sigma));
  const S est_r = hawor::estimateRotationNoise(rots, 0, valid);
  CHECK(est_r > S(0.8 * sigma));
  CHECK(est_r < S(1.2 * sigma));
  CHECK(hawor::estimateVectorNoise(cubic, 0, valid) < tolOf<S>(1e-6, 1e-12));
  // too short runs: 0
  CHECK(hawor::estimateVectorNoise(x, 0, hawor::ValidMask(size_t(T), 0)) == S(0));
  // Pure noise around a constant: the gap stays near the chord with shrinkage; without it the
  // noisy boundary velocities swing the curve further.
  hawor::SplineInfillOptions<S> o;
  const hawor::Sequence<S> f = hawor::fillSplineVectors(x, valid, o);
  o.shrink = false;
  o.iciGamma = S(1e-6);  // and no ICI widening: the shortest (noisiest) fits
  const hawor::Sequence<S> g = hawor::fillSplineVectors(x, valid, o);
  S dev_f(0), dev_g(0);
  for (Index t = 100; t < 140; ++t) {
    const S u = S(t - 99) / S(41);
    const Eigen::Matrix<S, 1, 3> chord = x.row(99) + u * (x.row(140) - x.row(99));
    dev_f = std::max(dev_f, S((f.row(t) - chord).norm()));
    dev_g = std::max(dev_g, S((g.row(t) - chord).norm()));
  }
  CHECK(dev_f < S(4 * sigma));
  CHECK(dev_f < dev_g);
}

TEMPLATE_TEST_CASE("local polynomial fits", "[motion][infill]", float, double) {
  using S = TestType;
  std::vector<S> tau = {S(0), S(-1), S(-2), S(-3), S(-4), S(-5)};
  std::vector<hawor::Vec3<S>> y;
  for (S t : tau) y.emplace_back(S(1) + S(2) * t + S(0.5) * t * t, S(-t), S(3));
  const auto f = hawor::fitLocalPolynomial(tau.data(), y.data(), static_cast<const S*>(nullptr), 6, 2);
  REQUIRE(f.ok);
  const S tol = tolOf<S>(1e-4, 1e-12);
  CHECK((f.value - hawor::Vec3<S>(S(1), S(0), S(3))).norm() < tol);
  CHECK((f.slope - hawor::Vec3<S>(S(2), S(-1), S(0))).norm() < tol);
  CHECK(f.slopeVariance > S(0));
  // more data, smaller variance; weights keep exactness
  const auto g = hawor::fitLocalPolynomial(tau.data(), y.data(), static_cast<const S*>(nullptr), 4, 2);
  CHECK(g.slopeVariance > f.slopeVariance);
  std::vector<S> w = {S(1), S(0.8), S(0.5), S(0.3), S(0.2), S(0.1)};
  const auto h = hawor::fitLocalPolynomial(tau.data(), y.data(), w.data(), 6, 2);
  CHECK((h.slope - f.slope).norm() < tol);
  CHECK_FALSE(hawor::fitLocalPolynomial(tau.data(), y.data(), static_cast<const S*>(nullptr), 2, 2).ok);
}

TEMPLATE_TEST_CASE("infillHand: no valid, one valid and all valid frames", "[motion][infill]",
                   float, double) {
  using S = TestType;
  const Index T = 30;
  hawor::Points3<S> J0 = hawor::Points3<S>::Zero(1, 3);
  hawor::HandMotion<S> m = smoothHand<S>(T, 15, 10, 3);
  // all valid: unchanged, nothing filled
  auto r = hawor::infillHand(m, J0);
  for (Index t = 0; t < T; ++t) CHECK(framesBitEqual(r.motion, m, t));
  CHECK(hawor::countValid(r.filled) == 0);
  // one valid frame: every frame holds it
  hawor::HandMotion<S> one = m;
  one.valid.assign(size_t(T), 0);
  one.valid[12] = 1;
  poisonMissing(one);
  for (auto method : {hawor::InfillMethod::LastPose, hawor::InfillMethod::Lerp, hawor::InfillMethod::Spline}) {
    hawor::InfillOptions<S> o;
    o.method = method;
    r = hawor::infillHand(one, J0, o);
    const S tol = tolOf<S>(1e-5, 1e-12);
    for (Index t = 0; t < T; ++t) {
      CHECK((r.motion.trans.row(t) - m.trans.row(12)).norm() < tol);
      CHECK((rotAt(r.motion.rot, t) - rotAt(m.rot, 12)).norm() < tol);
      CHECK((r.motion.handPose.row(t) - m.handPose.row(12)).norm() < S(10) * tol);
      CHECK((r.motion.betas.row(t) - m.betas.row(12)).norm() < tol);
      CHECK(bool(r.filled[size_t(t)]) == (t != 12));
    }
  }
  // no valid frame: unchanged (NaN stays NaN), nothing filled
  hawor::HandMotion<S> none = m;
  none.valid.assign(size_t(T), 0);
  poisonMissing(none);
  r = hawor::infillHand(none, J0);
  CHECK(hawor::countValid(r.filled) == 0);
  CHECK(framesBitEqual(r.motion, none, 4));
  // the bare fills throw instead
  CHECK_THROWS_WITH(hawor::fillSpline(none), Catch::Contains("no valid frame"));
}

TEMPLATE_TEST_CASE("infillHand equals the world-space fills (canonical round trip)",
                   "[motion][infill]", float, double) {
  using S = TestType;
  const Index T = 200;
  hawor::HandMotion<S> m = smoothHand<S>(T, 15, 10, 19);
  m.valid = maskWithGaps(T, {{0, 4}, {20, 33}, {60, 130}, {170, 200}});
  poisonMissing(m);
  hawor::Points3<S> J0(T, 3);  // per-frame J0
  for (Index t = 0; t < T; ++t) J0.row(t) << S(0.09), S(0.005 + 1e-5 * double(t)), S(-0.004);
  const S tol = tolOf<S>(5e-4, 1e-10);
  hawor::InfillOptions<S> o;
  o.method = hawor::InfillMethod::Lerp;
  auto r = hawor::infillHand(m, J0, o);
  auto w = hawor::fillInterpolate(m);
  CHECK(maxRotDiff(r.motion.rot, w.rot) < tol);
  CHECK(maxRotDiff(r.motion.handPose, w.handPose) < tol);
  CHECK((r.motion.betas - w.betas).norm() < tol);
  // trans: with a shape-dependent J0 the canonical LERP is of the root, not of trans, so compare
  // the root joints (trans + J0) of frames with a constant J0 nearby: use a constant J0 instead
  hawor::Points3<S> J0c = J0.topRows(1);
  r = hawor::infillHand(m, J0c, o);
  CHECK((r.motion.trans - w.trans).cwiseAbs().maxCoeff() < tol);
  o.method = hawor::InfillMethod::Spline;
  r = hawor::infillHand(m, J0c, o);
  auto s = hawor::fillSpline(m);
  CHECK((r.motion.trans - s.trans).cwiseAbs().maxCoeff() < S(10) * tol);
  CHECK(maxRotDiff(r.motion.rot, s.rot) < S(10) * tol);
  CHECK(maxRotDiff(r.motion.handPose, s.handPose) < S(10) * tol);
  o.method = hawor::InfillMethod::LastPose;
  r = hawor::infillHand(m, J0c, o);
  auto lp = hawor::fillLastPose(m);
  CHECK((r.motion.trans - lp.trans).cwiseAbs().maxCoeff() < tol);
  CHECK(maxRotDiff(r.motion.rot, lp.rot) < tol);
}

TEMPLATE_TEST_CASE("infill: malformed input gives clear errors", "[motion][infill]", float, double) {
  using S = TestType;
  const Index T = 20;
  const hawor::Points3<S> J0 = hawor::Points3<S>::Zero(1, 3);
  hawor::HandMotion<S> m = smoothHand<S>(T, 15, 10, 1);
  m.valid[5] = 0;
  auto a = m;
  a.handPose = hawor::Sequence<S>::Zero(T, 44);
  CHECK_THROWS_WITH(hawor::infillHand(a, J0), Catch::Contains("handPose"));
  auto b = m;
  b.valid.pop_back();
  CHECK_THROWS_WITH(hawor::infillHand(b, J0), Catch::Contains("validity mask"));
  auto c = m;
  c.trans(7, 2) = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_WITH(hawor::infillHand(c, J0), Catch::Contains("trans") && Catch::Contains("frame 7"));
  auto d = m;
  d.trans = hawor::Sequence<S>::Zero(T - 1, 3);
  CHECK_THROWS_WITH(hawor::infillHand(d, J0), Catch::Contains("trans"));
  hawor::Points3<S> J0bad = hawor::Points3<S>::Zero(3, 3);
  CHECK_THROWS_WITH(hawor::infillHand(m, J0bad), Catch::Contains("J0"));
  hawor::InfillOptions<S> o;
  o.spline.degree = 0;
  CHECK_THROWS_WITH(hawor::infillHand(m, J0, o), Catch::Contains("degree"));
  o.spline.degree = 2;
  o.spline.horizon = S(0);
  CHECK_THROWS_WITH(hawor::infillHand(m, J0, o), Catch::Contains("horizon"));
  CHECK_THROWS_WITH(hawor::parseInfillMethod("cubic"), Catch::Contains("last, lerp or spline"));
  CHECK(hawor::parseInfillMethod("spline") == hawor::InfillMethod::Spline);
  CHECK(std::string(hawor::infillMethodName(hawor::InfillMethod::LastPose)) == "last");
  // other hand models: 24 joints and no betas are fine
  hawor::HandMotion<S> x = smoothHand<S>(T, 24, 0, 2);
  x.valid[3] = x.valid[4] = 0;
  CHECK_NOTHROW(hawor::infillHand(x, J0));
}

TEMPLATE_TEST_CASE("smoothObserved: bounded, removes jitter, keeps clean motion",
                   "[motion][infill][smooth]", float, double) {
  using S = TestType;
  const Index T = 240;
  const hawor::HandMotion<S> truth = smoothHand<S>(T, 15, 10, 23);
  hawor::HandMotion<S> m = truth;
  m.valid = maskWithGaps(T, {{60, 80}, {150, 152}});
  poisonMissing(m);
  // clean motion: (almost) nothing moves (the bound is 3σ, and σ of this smooth, fast motion
  // is ~1e-5 m: its 4th differences)
  hawor::HandMotion<S> s = hawor::smoothObserved(m);
  const S sigma_clean = hawor::estimateVectorNoise(m.trans, 0, m.valid);
  CHECK(sigma_clean < S(2e-5));
  for (Index t = 0; t < T; ++t) {
    if (!m.valid[size_t(t)]) {
      CHECK(std::isnan(double(s.trans(t, 0))));  // missing frames untouched
      continue;
    }
    CHECK((s.trans.row(t) - m.trans.row(t)).norm() <= S(3.0001) * sigma_clean + tolOf<S>(1e-6, 1e-15));
  }
  // jittery motion: every change within the bound, and closer to the truth on average
  std::mt19937 rng(9);
  std::normal_distribution<double> N01(0.0, 1.0);
  hawor::HandMotion<S> noisy = m;
  const double st = 3e-3, sr = 0.02;
  for (Index t = 0; t < T; ++t) {
    if (!m.valid[size_t(t)]) continue;
    for (Index c = 0; c < 3; ++c) noisy.trans(t, c) += S(st * N01(rng));
    const hawor::Vec3<S> e(S(sr * N01(rng)), S(sr * N01(rng)), S(sr * N01(rng)));
    const hawor::Mat3<S> Rn = rotAt(m.rot, t) * hawor::axisAngleToMatrix(e);
    noisy.rot.row(t).template head<3>() = hawor::matrixToAxisAngle(Rn).transpose();
  }
  hawor::SmoothOptions<S> o;
  s = hawor::smoothObserved(noisy, o);
  S before(0), after(0), rbefore(0), rafter(0);
  for (Index t = 0; t < T; ++t) {
    if (!m.valid[size_t(t)]) continue;
    CHECK((s.trans.row(t) - noisy.trans.row(t)).norm() <= o.maxTranslation * S(1.0001));
    CHECK((rotAt(s.rot, t) - rotAt(noisy.rot, t)).norm() <= S(1.5) * o.maxAngle);
    before += (noisy.trans.row(t) - truth.trans.row(t)).norm();
    after += (s.trans.row(t) - truth.trans.row(t)).norm();
    rbefore += (rotAt(noisy.rot, t) - rotAt(truth.rot, t)).norm();
    rafter += (rotAt(s.rot, t) - rotAt(truth.rot, t)).norm();
  }
  CHECK(after < S(0.75) * before);
  CHECK(rafter < S(0.75) * rbefore);
  // a tight cap holds every frame near its evidence
  o.maxTranslation = S(1e-4);
  s = hawor::smoothObserved(noisy, o);
  for (Index t = 0; t < T; ++t)
    if (m.valid[size_t(t)]) CHECK((s.trans.row(t) - noisy.trans.row(t)).norm() <= S(1.0001e-4));
  o.halfWindow = 0;
  CHECK_THROWS_WITH(hawor::smoothObserved(noisy, o), Catch::Contains("halfWindow"));
}

namespace infill_test {

/// Records the windows it is given and answers with a fixed feature row for every frame.
template <typename S>
class RecordingInfiller : public hawor::WindowInfiller<S> {
 public:
  mutable std::vector<hawor::InfillWindow<S>> seen;
  hawor::Sequence<S> answer;  // 1 × 2F
  hawor::Sequence<S> infillWindow(const hawor::InfillWindow<S>& w) const override {
    seen.push_back(w);
    hawor::Sequence<S> y(w.features.rows(), answer.cols());
    for (Index r = 0; r < y.rows(); ++r) y.row(r) = answer.row(0);
    return y;
  }
};

}  // namespace infill_test

TEMPLATE_TEST_CASE("infillWindowed: windows, padding, canonical features, write-back",
                   "[motion][infill][window]", float, double) {
  using S = TestType;
  const Index T = 250;  // windows [0,120), [120,240), [240,250) padded to 120
  std::array<hawor::HandMotion<S>, 2> hands = {smoothHand<S>(T, 15, 10, 31), smoothHand<S>(T, 15, 10, 32)};
  hands[0].valid = maskWithGaps(T, {{0, 6}, {50, 70}, {130, 250}});
  hands[1].valid = maskWithGaps(T, {{100, 140}, {249, 250}});
  for (auto& h : hands) poisonMissing(h);
  hawor::Points3<S> J0(1, 3);
  J0 << S(0.09), S(0.006), S(0.005);
  const std::array<hawor::Points3<S>, 2> j0 = {J0, J0};
  const hawor::HandFeatureLayout layout = hawor::HandFeatureLayout::of(hands[0]);
  REQUIRE(layout.size() == 109);
  RecordingInfiller<S> rec;
  rec.answer = hawor::Sequence<S>::Zero(1, 218);
  for (Index h = 0; h < 2; ++h) {  // identity rotations, a fixed canonical translation and betas
    rec.answer(0, h * 109 + 0) = S(0.01);
    rec.answer.block(0, h * 109 + 3, 1, 10).setConstant(S(0.25));
    for (Index j = 0; j < 16; ++j) {
      rec.answer(0, h * 109 + 13 + 6 * j + 0) = S(1);
      rec.answer(0, h * 109 + 13 + 6 * j + 3) = S(1);
    }
  }
  std::array<hawor::ValidMask, 2> filled;
  const auto out = hawor::infillWindowed(hands, j0, rec, hawor::kInfillWindow, &filled);
  REQUIRE(rec.seen.size() == 3);
  for (size_t k = 0; k < 3; ++k) {
    const auto& w = rec.seen[k];
    CHECK(w.features.rows() == 120);
    CHECK(w.features.cols() == 218);
    CHECK(w.start == Index(120 * k));
    CHECK(w.frames == (k < 2 ? 120 : 10));
    CHECK(w.features.allFinite());
  }
  // last window: padding repeats the last real frame, features and validity
  const auto& last = rec.seen[2];
  for (Index r = 10; r < 120; ++r) {
    CHECK(last.features.row(r) == last.features.row(9));
    CHECK(last.valid[1][size_t(r)] == last.valid[1][9]);
  }
  CHECK(last.valid[1][9] == 0);  // frame 249 missing for the right hand
  // canonical frame: the first valid frame of the hand in each window has identity rot6d and
  // zero translation (window 0, left hand: frame 6; window 1, right hand: frame 140 → row 20)
  const hawor::Vec6<S> I6 = hawor::matrixToRot6d(hawor::Mat3<S>::Identity());
  const S tol = tolOf<S>(1e-5, 1e-12);
  CHECK((rec.seen[0].features.row(6).segment(13, 6).transpose() - I6).norm() < tol);
  CHECK(rec.seen[0].features.row(6).segment(0, 3).norm() < tol);
  CHECK((rec.seen[1].features.row(20).segment(109 + 13, 6).transpose() - I6).norm() < tol);
  CHECK(rec.seen[1].features.row(20).segment(109, 3).norm() < tol);
  // window 2 has no valid left frame: all missing for the left hand
  CHECK(hawor::countValid(last.valid[0]) == 0);
  // write-back: observed frames bit for bit; missing ones hold the answer mapped to world
  for (int h = 0; h < 2; ++h) {
    for (Index t = 0; t < T; ++t) {
      const bool missing = !hands[size_t(h)].valid[size_t(t)];
      CHECK(bool(filled[size_t(h)][size_t(t)]) == missing);
      if (!missing) {
        CHECK(framesBitEqual(out[size_t(h)], hands[size_t(h)], t));
      } else {
        CHECK(out[size_t(h)].betas.row(t).isApproxToConstant(S(0.25)));
        CHECK(out[size_t(h)].handPose.row(t).norm() < tol);
      }
    }
  }
  // a hand with no valid frame at all is left unchanged
  auto none = hands;
  none[0].valid.assign(size_t(T), 0);
  poisonMissing(none[0]);
  const auto out2 = hawor::infillWindowed(none, j0, rec, hawor::kInfillWindow, &filled);
  CHECK(hawor::countValid(filled[0]) == 0);
  CHECK(std::isnan(double(out2[0].trans(3, 0))));
  // mismatched hands / bad output size
  auto bad = hands;
  bad[1].handPose = hawor::Sequence<S>::Zero(T, 72);
  CHECK_THROWS_WITH(hawor::infillWindowed(bad, j0, rec), Catch::Contains("differ"));
  rec.answer = hawor::Sequence<S>::Zero(1, 200);
  CHECK_THROWS(hawor::infillWindowed(hands, j0, rec));
}

TEMPLATE_TEST_CASE("infillWindowed with the spline window infiller matches the sequence spline",
                   "[motion][infill][window]", float, double) {
  using S = TestType;
  const Index T = 240;
  std::array<hawor::HandMotion<S>, 2> hands = {smoothHand<S>(T, 15, 10, 41), smoothHand<S>(T, 15, 10, 42)};
  // gaps well inside the windows [0,120) and [120,240), with context on both sides
  hands[0].valid = maskWithGaps(T, {{30, 60}, {150, 200}});
  hands[1].valid = maskWithGaps(T, {{10, 12}, {70, 110}, {125, 126}});
  for (auto& h : hands) poisonMissing(h);
  const hawor::Points3<S> J0 = hawor::Points3<S>::Zero(1, 3);
  const hawor::SplineWindowInfiller<S> spline;
  const auto out = hawor::infillWindowed(hands, {J0, J0}, spline);
  // Reference: the sequence-level spline run on each window's frames alone (the windowed spline
  // sees only its window: context and noise estimate), so only the window machinery differs.
  const S tol = tolOf<S>(2e-3, 1e-9);
  for (int h = 0; h < 2; ++h) {
    hawor::HandMotion<S> ref = hands[size_t(h)];
    for (Index w0 = 0; w0 < T; w0 += 120) {
      const hawor::HandMotion<S> part = hawor::window_detail::sliceFrames(hands[size_t(h)], w0, 120);
      const hawor::HandMotion<S> f = hawor::infillHand(part, J0).motion;
      ref.rot.middleRows(w0, 120) = f.rot;
      ref.trans.middleRows(w0, 120) = f.trans;
      ref.handPose.middleRows(w0, 120) = f.handPose;
      ref.betas.middleRows(w0, 120) = f.betas;
    }
    CHECK((out[size_t(h)].trans - ref.trans).cwiseAbs().maxCoeff() < tol);
    CHECK(maxRotDiff(out[size_t(h)].rot, ref.rot) < tol);
    CHECK(maxRotDiff(out[size_t(h)].handPose, ref.handPose) < tol);
    CHECK((out[size_t(h)].betas - ref.betas).cwiseAbs().maxCoeff() < tol);
  }
  // and close to the whole-sequence spline (same gaps, longer context for the noise estimate)
  for (int h = 0; h < 2; ++h) {
    const hawor::HandMotion<S> whole = hawor::infillHand(hands[size_t(h)], J0).motion;
    CHECK((out[size_t(h)].trans - whole.trans).cwiseAbs().maxCoeff() < S(1e-3));
  }
}

TEMPLATE_TEST_CASE("canonicalFrameAt: any origin frame; round trip", "[motion][infill][canonical]",
                   float, double) {
  using S = TestType;
  const Index T = 30;
  hawor::HandMotion<S> m = smoothHand<S>(T, 15, 10, 51);
  m.valid[0] = m.valid[1] = 0;
  hawor::Points3<S> J0(1, 3);
  J0 << S(0.09), S(0.006), S(0.005);
  const S tol = tolOf<S>(1e-5, 1e-12);
  // the first valid frame by default; any frame on request (valid or not)
  CHECK(hawor::canonicalFrame(m, J0).origin == 2);
  for (Index o : {Index(0), Index(2), Index(17)}) {
    const hawor::CanonicalFrame<S> c = hawor::canonicalFrameAt(m, J0, o);
    const hawor::HandMotion<S> can = hawor::worldToCanonical(m, c, J0);
    CHECK(can.rot.row(o).norm() < tol);
    CHECK(can.trans.row(o).norm() < tol);
    const hawor::HandMotion<S> back = hawor::canonicalToWorld(can, c, J0);
    CHECK((back.trans - m.trans).cwiseAbs().maxCoeff() < tol);
    CHECK(maxRotDiff(back.rot, m.rot) < tol);
    CHECK(back.handPose == m.handPose);
  }
  CHECK_THROWS_WITH(hawor::canonicalFrameAt(m, J0, T), Catch::Contains("outside"));
  m.trans(5, 0) = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_WITH(hawor::canonicalFrameAt(m, J0, 5), Catch::Contains("not finite"));
}

TEMPLATE_TEST_CASE("spline: given noise levels replace the estimates", "[motion][infill][spline]",
                   float, double) {
  using S = TestType;
  const Index T = 120;
  hawor::HandMotion<S> m = smoothHand<S>(T, 15, 10, 61);
  m.valid = maskWithGaps(T, {{20, 40}, {70, 100}});
  poisonMissing(m);
  const hawor::HandNoise<S> est = hawor::estimateHandNoise(m);
  CHECK(est.joints.size() == 15);
  // the estimates themselves: same result as without
  const hawor::HandMotion<S> a = hawor::fillSpline(m), b = hawor::fillSpline(m, {}, &est);
  CHECK((a.trans - b.trans).cwiseAbs().maxCoeff() == S(0));
  CHECK((a.handPose - b.handPose).cwiseAbs().maxCoeff() == S(0));
  // huge noise: every boundary deviation is shrunk away, the fill is the chord (LERP / SLERP)
  hawor::HandNoise<S> loud = est;
  loud.trans = S(10);
  loud.rot = S(10);
  for (S& j : loud.joints) j = S(10);
  const hawor::HandMotion<S> c = hawor::fillSpline(m, {}, &loud);
  const hawor::HandMotion<S> l = hawor::fillInterpolate(m);
  const S tol = tolOf<S>(1e-5, 1e-12);
  CHECK((c.trans - l.trans).cwiseAbs().maxCoeff() < tol);
  CHECK(maxRotDiff(c.rot, l.rot) < tol);
  CHECK(maxRotDiff(c.handPose, l.handPose) < tol);
  hawor::HandNoise<S> wrong = est;
  wrong.joints.pop_back();
  CHECK_THROWS_WITH(hawor::fillSpline(m, {}, &wrong), Catch::Contains("noise levels"));
  wrong = est;
  wrong.trans = S(-1);
  CHECK_THROWS_WITH(hawor::fillSpline(m, {}, &wrong), Catch::Contains("noise levels"));
}
