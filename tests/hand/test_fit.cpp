// Hand fit (hand/fit.hpp) and joint limits (hand/joint_limits.hpp): anatomical frames, cold-start
// initialisation, exact recovery from noise-free data, robustness to outliers, warm starts over a
// sequence, 2D-only fits, bad input. Float and double where it matters.
#include <catch2/catch.hpp>

#include <random>

#include "fit_test_util.hpp"
#include "hawor/geometry/alignment.hpp"
#include "hawor/hand/mirror.hpp"
#include "hawor/hand/synthetic_hand.hpp"

template struct hawor::HandObservation<float>;
template struct hawor::HandObservation<double>;
template struct hawor::HandFitOptions<float>;
template struct hawor::HandFitOptions<double>;
template struct hawor::HandFitResult<float>;
template struct hawor::HandFitResult<double>;

using namespace hawor;

namespace {

template <typename Scalar>
bool isFloat() {
  return std::is_same<Scalar, float>::value;
}

}  // namespace

TEST_CASE("joint limits: roles and anatomical frames of the MANO-structured hand", "[hand][fit][limits]") {
  const HandModel<double> m = makeSyntheticHand<double>();
  const JointLimits<double> L = JointLimits<double>::fromModel(m);
  REQUIRE(L.numJoints() == 16);
  CHECK(L.roles[0] == JointRole::Root);
  for (int j : {1, 4, 7, 10}) CHECK(L.roles[static_cast<std::size_t>(j)] == JointRole::FingerMcp);
  for (int j : {2, 5, 8, 11}) CHECK(L.roles[static_cast<std::size_t>(j)] == JointRole::FingerPip);
  for (int j : {3, 6, 9, 12}) CHECK(L.roles[static_cast<std::size_t>(j)] == JointRole::FingerDip);
  CHECK(L.roles[13] == JointRole::ThumbCmc);
  CHECK(L.roles[14] == JointRole::ThumbMcp);
  CHECK(L.roles[15] == JointRole::ThumbIp);
  for (int j = 1; j < 16; ++j) {
    const Eigen::Matrix3d F = L.frames[static_cast<std::size_t>(j)];
    CHECK((F * F.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-12);
    CHECK(F.determinant() == Approx(1.0));
  }
  // The default ranges of the brief.
  CHECK(L.ranges[1].lo(0) == Approx(-0.4));
  CHECK(L.ranges[1].hi(0) == Approx(1.6));
  CHECK(L.ranges[1].hi(1) == Approx(0.35));
  CHECK(L.ranges[2].hi(0) == Approx(1.9));
  // Positive flexion of every finger joint moves the fingertip towards the palm (−y here).
  const HandOutput<double> rest = forward(m, HandPose<double>::zero(m));
  const int tipKp[4] = {8, 12, 20, 16};  // index, middle, pinky, ring (MANO chain order)
  for (int c = 0; c < 4; ++c) {
    for (int s = 0; s < 3; ++s) {
      const int j = 1 + 3 * c + s;
      HandPose<double> p = HandPose<double>::zero(m);
      p.handPose.row(j - 1) = L.axisAngle(j, Eigen::Vector3d(0.3, 0, 0)).transpose();
      const HandOutput<double> o = forward(m, p);
      INFO("joint " << j);
      CHECK(o.keypoints(tipKp[c], 1) < rest.keypoints(tipKp[c], 1) - 1e-3);
    }
  }
  // Mirrored (left) model (x negated): the palm still faces −y and flexion still curls towards it.
  const HandModel<double> left = mirrorHandModel(m);
  REQUIRE(left.isLeft);
  const JointLimits<double> LL = JointLimits<double>::fromModel(left);
  const HandOutput<double> lrest = forward(left, HandPose<double>::zero(left));
  HandPose<double> p = HandPose<double>::zero(left);
  p.handPose.row(4 - 1) = LL.axisAngle(4, Eigen::Vector3d(0.3, 0, 0)).transpose();
  CHECK(forward(left, p).keypoints(12, 1) < lrest.keypoints(12, 1) - 1e-3);
}

TEST_CASE("joint limits: 25-joint layout fixes metacarpals and tips", "[hand][fit][limits]") {
  const HandModel<double> m = fit_test::randomWebxrModel<double>();
  const JointLimits<double> L = JointLimits<double>::fromModel(m);
  for (int j : {5, 10, 15, 20}) CHECK(L.roles[static_cast<std::size_t>(j)] == JointRole::Fixed);  // metacarpals
  for (int j : {4, 9, 14, 19, 24}) CHECK(L.roles[static_cast<std::size_t>(j)] == JointRole::Fixed);  // tips
  CHECK(L.roles[1] == JointRole::ThumbCmc);
  CHECK(L.roles[6] == JointRole::FingerMcp);
  CHECK(L.roles[8] == JointRole::FingerDip);
  // Without a 21-keypoint map: Free joints, except those that move no keypoint.
  HandModel<double> m2 = m;
  m2.keypointMap = {0, 1, 2, 3, 4};
  m2.prepare();
  const JointLimits<double> L2 = JointLimits<double>::fromModel(m2);
  CHECK(L2.roles[1] == JointRole::Free);
  CHECK(L2.roles[4] == JointRole::Fixed);  // the thumb tip moves nothing
  CHECK(L2.roles[7] == JointRole::Fixed);
}

TEST_CASE("joint limits: violation and sampling", "[hand][fit][limits]") {
  const HandModel<double> m = makeSyntheticHand<double>();
  const JointLimits<double> L = JointLimits<double>::fromModel(m);
  std::mt19937 rng(3);
  for (int rep = 0; rep < 20; ++rep) {
    const Points3<double> w = sampleJointPose(L, rng, 1.0);
    for (int j = 1; j < 16; ++j) CHECK(L.violation(j, w.row(j - 1).transpose()).norm() == 0.0);
  }
  const Eigen::Vector3d over = L.axisAngle(2, Eigen::Vector3d(2.0, -0.3, 0.05));
  const Eigen::Vector3d v = L.violation(2, over);
  CHECK(v(0) == Approx(0.1));
  CHECK(v(1) == Approx(-0.2));
  CHECK(v(2) == Approx(0.0).margin(1e-12));
}

TEMPLATE_TEST_CASE("hand fit: initialisation with exact data recovers rotation and translation", "[hand][fit]", float,
                   double) {
  using S = TestType;
  const HandModel<S> m = makeSyntheticHand<S>();
  HandFitter<S> fitter(m);
  const PinholeCamera<S> cam = fit_test::camera<S>();
  std::mt19937 rng(17);
  for (int rep = 0; rep < 5; ++rep) {
    HandPose<S> truth = fit_test::randomHandPose(m, fitter.limits(), rng);
    truth.handPose.setZero();  // rigid hand: the initialisation alone is exact
    truth.betas.setZero();
    const HandObservation<S> obs = fit_test::observe(m, truth, cam, rng);
    const HandPose<S> init = fitter.initialise(obs, cam);
    const double tol = isFloat<S>() ? 2e-4 : 1e-8;
    CHECK((axisAngleToMatrix(init.rot) - axisAngleToMatrix(truth.rot)).norm() <= tol);
    CHECK((init.trans - truth.trans).norm() <= tol);
    CHECK(init.handPose.cwiseAbs().maxCoeff() <= (isFloat<S>() ? 1e-3 : 1e-6));
  }
  // Articulated hand: the swing IK starts every bone close to the truth.
  for (int rep = 0; rep < 5; ++rep) {
    const HandPose<S> truth = fit_test::randomHandPose(m, fitter.limits(), rng);
    HandPose<S> t0 = truth;
    t0.betas.setZero();
    const HandObservation<S> obs = fit_test::observe(m, t0, cam, rng);
    const HandPose<S> init = fitter.initialise(obs, cam);
    const HandOutput<S> a = forward(m, init), b = forward(m, t0);
    CHECK(fit_test::maxPointError(a.keypoints, b.keypoints) < 0.02);
  }
}

TEMPLATE_TEST_CASE("hand fit: noise-free data is fitted exactly (MANO-structured hand)", "[hand][fit]", float, double) {
  using S = TestType;
  const HandModel<S> m = makeSyntheticHand<S>();
  HandFitter<S> fitter(m);
  const PinholeCamera<S> cam = fit_test::camera<S>();
  std::mt19937 rng(23);
  HandFitOptions<S> opt = fit_test::exactOptions<S>();
  for (int rep = 0; rep < 6; ++rep) {
    const HandPose<S> truth = fit_test::randomHandPose(m, fitter.limits(), rng);
    const HandObservation<S> obs = fit_test::observe(m, truth, cam, rng);
    const HandFitResult<S> r = fitter.fit(obs, cam, opt);
    const HandOutput<S> gt = forward(m, truth);
    INFO("rep " << rep << " iterations " << r.iterations << " rms " << r.reprojRmsPx);
    CHECK(fit_test::maxPointError(r.keypoints, gt.keypoints) <= (isFloat<S>() ? 5e-4 : 1e-6));
    CHECK(r.reprojRmsPx <= (isFloat<S>() ? 0.05 : 1e-4));
    CHECK((r.pose.trans - truth.trans).norm() <= (isFloat<S>() ? 1e-3 : 1e-6));
    CHECK(r.converged);
  }
}

TEST_CASE("hand fit: noise-free data, random MANO-sized model and 25-joint model", "[hand][fit]") {
  const PinholeCamera<double> cam = fit_test::camera<double>();
  std::mt19937 rng(29);
  HandFitOptions<double> opt = fit_test::exactOptions<double>();
  for (int which = 0; which < 2; ++which) {
    const HandModel<double> m = which == 0 ? hand_test::randomModel<double>() : fit_test::randomWebxrModel<double>();
    HandFitter<double> fitter(m);
    for (int rep = 0; rep < 3; ++rep) {
      const HandPose<double> truth = fit_test::randomHandPose(m, fitter.limits(), rng, 0.5);
      const HandObservation<double> obs = fit_test::observe(m, truth, cam, rng);
      const HandFitResult<double> r = fitter.fit(obs, cam, opt);
      INFO("model " << which << " rep " << rep << " iterations " << r.iterations << " rms " << r.reprojRmsPx);
      CHECK(fit_test::maxPointError(r.keypoints, forward(m, truth).keypoints) <= 1e-5);
    }
  }
}

TEST_CASE("hand fit: noisy data with default options stays accurate", "[hand][fit]") {
  const HandModel<double> m = makeSyntheticHand<double>();
  HandFitter<double> fitter(m);
  const PinholeCamera<double> cam = fit_test::camera<double>();
  std::mt19937 rng(31);
  HandFitOptions<double> opt;
  opt.sigmaPx = 1.5;
  opt.sigma3d = 0.005;
  double sumRoot = 0;
  const int reps = 6;
  for (int rep = 0; rep < reps; ++rep) {
    const HandPose<double> truth = fit_test::randomHandPose(m, fitter.limits(), rng);
    const HandObservation<double> obs = fit_test::observe(m, truth, cam, rng, 1.5, 0.005);
    const HandFitResult<double> r = fitter.fit(obs, cam, opt);
    const HandOutput<double> gt = forward(m, truth);
    // PA-MPJPE (similarity-aligned, docs/design.md §8) and the wrist's camera-frame error.
    const Points3<double> aligned = umeyama(r.keypoints, gt.keypoints, true).apply(r.keypoints);
    const double pa = (aligned - gt.keypoints).rowwise().norm().mean();
    const double rootErr = (r.keypoints.row(0) - gt.keypoints.row(0)).norm();
    INFO("rep " << rep << " PA-MPJPE " << pa << " root error " << rootErr);
    CHECK(pa < 0.006);
    CHECK(rootErr < 0.06);
    CHECK(r.reprojMedianPx < 4.0);
    sumRoot += rootErr;
  }
  CHECK(sumRoot / reps < 0.02);
}

TEMPLATE_TEST_CASE("hand fit: robust loss survives 3 outliers out of 21", "[hand][fit]", float, double) {
  using S = TestType;
  const HandModel<S> m = makeSyntheticHand<S>();
  HandFitter<S> fitter(m);
  const PinholeCamera<S> cam = fit_test::camera<S>();
  std::mt19937 rng(37);
  double sumPlain = 0, sumHuber = 0, sumDiff = 0;
  for (int rep = 0; rep < 4; ++rep) {
    const HandPose<S> truth = fit_test::randomHandPose(m, fitter.limits(), rng);
    HandObservation<S> obs = fit_test::observe(m, truth, cam, rng, 1.0, 0.0);
    const HandObservation<S> clean = obs;
    const int bad[3] = {static_cast<int>(rng() % 21), static_cast<int>(rng() % 21), static_cast<int>(rng() % 21)};
    for (int k : bad) {
      obs.keypoints2d(k, 0) += S(50 + 30 * (rep % 2));
      obs.keypoints2d(k, 1) -= S(40);
    }
    const HandOutput<S> gt = forward(m, truth);
    auto rootError = [&](const HandFitResult<S>& r) { return (r.keypoints.row(0) - gt.keypoints.row(0)).norm(); };
    HandFitOptions<S> opt;  // default: Cauchy
    opt.sigmaPx = S(1);
    REQUIRE(opt.loss == RobustLoss::Cauchy);
    // With the outliers the fit stays where it is without them (up to the few millimetres that
    // losing three keypoints costs the depth).
    const HandFitResult<S> ref = fitter.fit(clean, cam, opt);
    const HandFitResult<S> r = fitter.fit(obs, cam, opt);
    const double diff = (r.keypoints - ref.keypoints).rowwise().norm().maxCoeff();
    INFO("rep " << rep << " largest keypoint change " << diff << " root error " << rootError(r));
    CHECK(diff < 0.025);
    sumDiff += diff;
    // The same fit without a robust loss is far off; Huber (bounded but non-zero influence) is
    // in between: the depth, weakly held by the pixels, follows its constant pull.
    opt.loss = RobustLoss::None;
    sumPlain += rootError(fitter.fit(obs, cam, opt));
    opt.loss = RobustLoss::Huber;
    sumHuber += rootError(fitter.fit(obs, cam, opt));
  }
  CHECK(sumDiff / 4 < 0.012);
  INFO("summed root errors: least squares " << sumPlain << ", Huber " << sumHuber);
  CHECK(sumPlain > 0.1);
  CHECK(sumHuber < sumPlain);
}

TEMPLATE_TEST_CASE("hand fit: warm start over a smooth sequence", "[hand][fit]", float, double) {
  using S = TestType;
  const HandModel<S> m = makeSyntheticHand<S>();
  HandFitter<S> fitter(m);
  const PinholeCamera<S> cam = fit_test::camera<S>();
  std::mt19937 rng(41);
  const HandPose<S> a = fit_test::randomHandPose(m, fitter.limits(), rng, 0.6);
  HandPose<S> b = fit_test::randomHandPose(m, fitter.limits(), rng, 0.6);
  b.betas = a.betas;
  b.rot = a.rot + Vec3<S>(S(0.3), S(-0.2), S(0.25));
  b.trans = a.trans + Vec3<S>(S(0.05), S(-0.03), S(0.1));
  HandFitOptions<S> opt;
  opt.sigmaPx = S(1);
  opt.sigma3d = S(0.002);  // matched to the landmark noise below: the size (hence depth) comes from it
  HandPose<S> prev;
  int warmIterations = 0;
  double sumRoot = 0;
  const int frames = 12;
  for (int f = 0; f < frames; ++f) {
    const S u = S(f) / S(frames - 1);
    HandPose<S> truth = a;
    truth.rot = (S(1) - u) * a.rot + u * b.rot;
    truth.trans = (S(1) - u) * a.trans + u * b.trans;
    truth.handPose = (S(1) - u) * a.handPose + u * b.handPose;
    const HandObservation<S> obs = fit_test::observe(m, truth, cam, rng, 1.0, 0.001);
    const HandFitResult<S> r = fitter.fit(obs, cam, opt, f == 0 ? nullptr : &prev);
    if (f > 0) {
      CHECK(r.warmStarted);
      warmIterations += r.iterations;
    }
    const HandOutput<S> gt = forward(m, truth);
    INFO("frame " << f << " iterations " << r.iterations);
    // Per frame the depth is the least certain part (about 1–2 % of it with 1 px noise: the
    // pixels fix the hand's projected size only up to a trade against its orientation and
    // articulation); over the sequence the mean error is well below a centimetre.
    const double rootErr = (r.keypoints.row(0) - gt.keypoints.row(0)).norm();
    CHECK(rootErr < 0.03);
    CHECK((r.keypoints - gt.keypoints).rowwise().norm().mean() < 0.03);
    sumRoot += rootErr;
    prev = r.pose;
  }
  CHECK(sumRoot / frames < 0.01);
  CHECK(warmIterations <= 8 * (frames - 1));
}

TEST_CASE("hand fit: a bad previous frame triggers a cold retry", "[hand][fit]") {
  const HandModel<double> m = makeSyntheticHand<double>();
  HandFitter<double> fitter(m);
  const PinholeCamera<double> cam = fit_test::camera<double>();
  std::mt19937 rng(43);
  const HandPose<double> truth = fit_test::randomHandPose(m, fitter.limits(), rng);
  const HandObservation<double> obs = fit_test::observe(m, truth, cam, rng, 1.0, 0.003);
  HandPose<double> wrong = truth;
  wrong.rot = matrixToAxisAngle(Eigen::Matrix3d(axisAngleToMatrix(Eigen::Vector3d(3.0, 0, 0)) *
                                                         axisAngleToMatrix(truth.rot)));
  wrong.trans(0) += 0.3;
  HandFitOptions<double> opt;
  opt.sigmaTemporalRot = 0;  // a wrong previous frame must not hold the solution back
  opt.sigmaTemporalTransl = 0;
  opt.sigmaTemporalPose = 0;
  opt.maxIterationsWarm = 5;
  const HandFitResult<double> r = fitter.fit(obs, cam, opt, &wrong);
  CHECK((r.keypoints.row(0) - forward(m, truth).keypoints.row(0)).norm() < 0.02);
  CHECK(r.reprojRmsPx < 4.0);
}

TEST_CASE("hand fit: 2D keypoints only (no landmarks)", "[hand][fit]") {
  const HandModel<double> m = makeSyntheticHand<double>();
  HandFitter<double> fitter(m);
  const PinholeCamera<double> cam = fit_test::camera<double>();
  std::mt19937 rng(47);
  int good = 0;
  for (int rep = 0; rep < 4; ++rep) {
    HandPose<double> truth = fit_test::randomHandPose(m, fitter.limits(), rng, 0.3);
    truth.betas.setZero();
    HandObservation<double> obs = fit_test::observe(m, truth, cam, rng, 0.5, 0.0);
    obs.keypoints3d.resize(0, 3);
    obs.confidence3d.resize(0);
    HandFitOptions<double> opt;
    opt.fitShape = false;
    const HandFitResult<double> r = fitter.fit(obs, cam, opt);
    INFO("rep " << rep << " median " << r.reprojMedianPx);
    CHECK(std::isfinite(r.reprojMedianPx));
    good += r.reprojMedianPx < 5.0 && (r.keypoints.row(0) - forward(m, truth).keypoints.row(0)).norm() < 0.03;
  }
  CHECK(good >= 2);  // monocular 2D-only fits may settle in a mirrored pose (no landmarks to tell)
}

TEST_CASE("hand fit: bad input throws hawor::Error", "[hand][fit]") {
  const HandModel<double> m = makeSyntheticHand<double>();
  HandFitter<double> fitter(m);
  const PinholeCamera<double> cam = fit_test::camera<double>();
  std::mt19937 rng(53);
  const HandPose<double> truth = fit_test::randomHandPose(m, fitter.limits(), rng);
  const HandObservation<double> obs = fit_test::observe(m, truth, cam, rng);
  HandObservation<double> o = obs;
  o.keypoints2d.conservativeResize(20, 2);
  CHECK_THROWS_AS(fitter.fit(o, cam), Error);
  o = obs;
  o.keypoints2d(3, 1) = std::numeric_limits<double>::infinity();
  CHECK_THROWS_AS(fitter.fit(o, cam), Error);
  o = obs;
  o.confidence2d.setZero();
  CHECK_THROWS_AS(fitter.fit(o, cam), Error);
  o = obs;
  o.confidence3d(2) = -1;
  CHECK_THROWS_AS(fitter.fit(o, cam), Error);
  o = obs;
  o.keypoints3d.conservativeResize(5, 3);
  CHECK_THROWS_AS(fitter.fit(o, cam), Error);
  PinholeCamera<double> c0 = cam;
  c0.fy = -1;
  CHECK_THROWS_AS(fitter.fit(obs, c0), Error);
  HandPose<double> badPrev = truth;
  badPrev.handPose.conservativeResize(3, 3);
  CHECK_THROWS_AS(fitter.fit(obs, cam, {}, &badPrev), Error);
  HandModel<double> unprepared;
  CHECK_THROWS_AS(HandFitter<double>(unprepared), Error);
}
