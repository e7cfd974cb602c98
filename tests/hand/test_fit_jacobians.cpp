// Analytic Jacobians of the hand fit against central differences (double): the keypoints with
// respect to every parameter block (global rotation increment, translation, joint axis-angles
// through the kinematic chain, tip vertices through skinning and pose correctives, betas), and the
// whole energy's residuals (2D, centred 3D, pose prior, joint limits, fixed joints, shape prior,
// temporal terms). Models: a random MANO-sized model, the procedural MANO-structured hand and a
// random 25-joint model without shape space.
#include <catch2/catch.hpp>

#include "fit_test_util.hpp"
#include "hawor/hand/keypoint_jacobian.hpp"
#include "hawor/hand/synthetic_hand.hpp"

template struct hawor::HandKeypointModel<float>;
template struct hawor::HandKeypointModel<double>;
template struct hawor::HandKeypointWorkspace<float>;
template struct hawor::HandKeypointWorkspace<double>;
template struct hawor::JointLimits<float>;
template struct hawor::JointLimits<double>;
template class hawor::HandFitter<float>;
template class hawor::HandFitter<double>;

using namespace hawor;

namespace {

struct Params {
  Eigen::Matrix3d R0;
  Points3<double> w;
  VecX<double> beta;
  Eigen::Vector3d t;
};

// x ⊞ h·e_i in the parameter layout (right increment for the global rotation).
Params perturb(const Params& p, const HandParamLayout& L, int i, double h) {
  Params q = p;
  if (i < 3) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(i) = h;
    q.R0 = p.R0 * axisAngleToMatrix(d);
  } else if (i < 6) {
    q.t(i - 3) += h;
  } else if (i < L.betas()) {
    const int j = 1 + (i - 6) / 3, c = (i - 6) % 3;
    q.w(j - 1, c) += h;
  } else {
    q.beta(i - L.betas()) += h;
  }
  return q;
}

Points3<double> keypointsAt(const HandKeypointModel<double>& km, const Params& p) {
  HandKeypointWorkspace<double> ws;
  Points3<double> kp;
  evaluateHandKeypoints(km, Mat3<double>(p.R0), p.w, p.beta, Vec3<double>(p.t), ws, kp);
  return kp;
}

Params randomParams(const HandModel<double>& m, unsigned seed, double sigma) {
  std::mt19937 rng(seed);
  auto g = [](std::mt19937& r) { return standardNormal(r); };
  Params p;
  const double r0 = g(rng), r1 = g(rng), r2 = g(rng);
  p.R0 = axisAngleToMatrix(Eigen::Vector3d(r0, r1, r2));
  p.w.resize(m.numJoints() - 1, 3);
  for (Eigen::Index i = 0; i < p.w.size(); ++i) p.w.data()[i] = sigma * g(rng);
  p.beta.resize(m.numBetas());
  for (Eigen::Index i = 0; i < p.beta.size(); ++i) p.beta(i) = g(rng);
  const double tx = g(rng), ty = g(rng);
  p.t = Eigen::Vector3d(0.1 * tx, 0.1 * ty, 0.5);
  return p;
}

void checkKeypointJacobian(const HandModel<double>& m, const Params& p) {
  const HandKeypointModel<double> km(m);
  HandKeypointWorkspace<double> ws;
  Points3<double> kp;
  KeypointJacobian<double> Jac;
  evaluateHandKeypoints(km, Mat3<double>(p.R0), p.w, p.beta, Vec3<double>(p.t), ws, kp, &Jac);
  // The keypoints agree with the full forward pass.
  HandPose<double> pose = HandPose<double>::zero(m);
  pose.rot = matrixToAxisAngle(p.R0);
  pose.handPose = p.w;
  pose.betas = p.beta;
  pose.trans = p.t;
  const HandOutput<double> out = forward(m, pose);
  CHECK(fit_test::maxPointError(kp, out.keypoints) < 1e-12);
  const HandParamLayout& L = km.layout;
  REQUIRE(Jac.rows() == 3 * km.K);
  REQUIRE(Jac.cols() == L.size());
  const double h = 1e-6;
  double worst = 0.0;
  for (int i = 0; i < L.size(); ++i) {
    const Points3<double> a = keypointsAt(km, perturb(p, L, i, h));
    const Points3<double> b = keypointsAt(km, perturb(p, L, i, -h));
    for (int k = 0; k < km.K; ++k) {
      const Eigen::Vector3d num = (a.row(k) - b.row(k)).transpose() / (2 * h);
      const Eigen::Vector3d ana = Jac.block(3 * k, i, 3, 1);
      const double err = (num - ana).norm();
      worst = std::max(worst, err);
      if (err > 1e-7) {
        INFO("parameter " << i << " keypoint " << k << " numeric " << num.transpose() << " analytic " << ana.transpose());
        CHECK(err <= 1e-7);
      }
    }
  }
  CHECK(worst <= 1e-7);
}

}  // namespace

TEST_CASE("hand keypoint Jacobian: random MANO-sized model", "[hand][fit][jacobian]") {
  const HandModel<double> m = hand_test::randomModel<double>();
  for (double sigma : {1e-9, 0.3, 1.0, 2.5}) {
    INFO("joint angle scale " << sigma);
    checkKeypointJacobian(m, randomParams(m, 7, sigma));
  }
}

TEST_CASE("hand keypoint Jacobian: procedural MANO-structured hand", "[hand][fit][jacobian]") {
  const HandModel<double> m = makeSyntheticHand<double>();
  REQUIRE(m.numKeypoints() == 21);
  for (double sigma : {0.0, 0.5}) checkKeypointJacobian(m, randomParams(m, 11, sigma));
}

TEST_CASE("hand keypoint Jacobian: 25 joints, no shape space, no correctives", "[hand][fit][jacobian]") {
  const HandModel<double> m = fit_test::randomWebxrModel<double>();
  checkKeypointJacobian(m, randomParams(m, 5, 0.6));
}

TEST_CASE("hand keypoint Jacobian: a tip vertex skinned to several joints, joint keypoints only", "[hand][fit][jacobian]") {
  // Tip vertices blended over a joint and an unrelated branch exercise the W_j / Q_j sums.
  HandModel<double> m = hand_test::randomModel<double>(778, manoParents(), 4, true, 9);
  for (int t : m.tipVertices) {
    m.weights.row(t).setZero();
    m.weights(t, 3) = 0.5;
    m.weights(t, 14) = 0.3;
    m.weights(t, 0) = 0.2;
  }
  m.prepare();
  checkKeypointJacobian(m, randomParams(m, 3, 0.7));
  m.keypointMap = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};
  m.prepare();
  checkKeypointJacobian(m, randomParams(m, 4, 0.7));
}

namespace {

void checkEnergyJacobian(const HandModel<double>& m, unsigned seed, bool withPrevious) {
  std::mt19937 rng(seed);
  HandFitter<double> fitter(m);
  const PinholeCamera<double> cam = fit_test::camera<double>();
  const HandPose<double> truth = fit_test::randomHandPose(m, fitter.limits(), rng, 1.0);
  const HandObservation<double> obs = fit_test::observe(m, truth, cam, rng, 3.0, 0.01);
  // Evaluate away from the truth, with joints pushed outside their limits so that limit
  // residuals are active, and confidences that differ per keypoint.
  HandObservation<double> o2 = obs;
  for (int k = 0; k < o2.confidence2d.size(); ++k) {
    o2.confidence2d(k) = 0.3 + 0.7 * ((k * 37) % 11) / 10.0;
    o2.confidence3d(k) = 0.2 + 0.8 * ((k * 13) % 7) / 6.0;
  }
  o2.confidence2d(4) = 0.0;
  HandPose<double> at = truth;
  auto g = [](std::mt19937& r) { return standardNormal(r); };
  for (Eigen::Index i = 0; i < at.handPose.size(); ++i) at.handPose.data()[i] += 0.4 * g(rng);
  for (Eigen::Index i = 0; i < at.betas.size(); ++i) at.betas(i) += 0.3 * g(rng);
  at.rot += Eigen::Vector3d(0.1, -0.2, 0.05);
  at.trans += Eigen::Vector3d(0.01, 0.02, -0.03);
  HandPose<double> prev = truth;
  prev.rot += Eigen::Vector3d(-0.3, 0.1, 0.2);
  prev.trans += Eigen::Vector3d(0.02, 0.0, 0.01);
  for (Eigen::Index i = 0; i < prev.handPose.size(); ++i) prev.handPose.data()[i] += 0.2 * g(rng);
  for (Eigen::Index i = 0; i < prev.betas.size(); ++i) prev.betas(i) -= 0.2;
  HandFitOptions<double> opt;
  opt.loss = RobustLoss::None;  // IRLS weights are frozen in the Jacobian: compare without them
  const HandPose<double>* pp = withPrevious ? &prev : nullptr;
  VecX<double> r;
  MatX<double> Jr;
  fitter.residuals(at, o2, cam, opt, pp, r, Jr);
  CHECK(std::abs(r.squaredNorm() - fitter.energy(at, o2, cam, opt, pp)) <= 1e-9 * r.squaredNorm());
  const HandParamLayout& L = fitter.keypointModel().layout;
  const double h = 1e-6;
  auto shifted = [&](int i, double s) {
    HandPose<double> q = at;
    if (i < 3) {
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      d(i) = s;
      q.rot = matrixToAxisAngle(axisAngleToMatrix(at.rot) * axisAngleToMatrix(d));
    } else if (i < 6) {
      q.trans(i - 3) += s;
    } else if (i < L.betas()) {
      q.handPose((i - 6) / 3, (i - 6) % 3) += s;
    } else {
      q.betas(i - L.betas()) += s;
    }
    return q;
  };
  int active = 0;
  for (int j = 1; j < m.numJoints(); ++j)
    if (fitter.limits().limited(j)) active += (fitter.limits().violation(j, at.handPose.row(j - 1).transpose()).array() != 0.0).count();
  INFO("active limit residuals " << active);
  CHECK(active > 0);
  for (int i = 0; i < L.size(); ++i) {
    VecX<double> ra, rb;
    MatX<double> dummy;
    fitter.residuals(shifted(i, h), o2, cam, opt, pp, ra, dummy);
    fitter.residuals(shifted(i, -h), o2, cam, opt, pp, rb, dummy);
    REQUIRE(ra.size() == r.size());
    REQUIRE(rb.size() == r.size());
    const VecX<double> num = (ra - rb) / (2 * h);
    const double err = (num - Jr.col(i)).cwiseAbs().maxCoeff();
    const double scale = 1.0 + Jr.col(i).cwiseAbs().maxCoeff();
    INFO("parameter " << i);
    CHECK(err <= 2e-6 * scale);
  }
}

}  // namespace

TEST_CASE("hand fit energy Jacobian: every residual block", "[hand][fit][jacobian]") {
  SECTION("procedural MANO-structured hand, temporal terms") { checkEnergyJacobian(makeSyntheticHand<double>(), 1, true); }
  SECTION("procedural MANO-structured hand, single frame") { checkEnergyJacobian(makeSyntheticHand<double>(), 2, false); }
  SECTION("random MANO-sized model") { checkEnergyJacobian(hand_test::randomModel<double>(), 3, true); }
  SECTION("25-joint model") { checkEnergyJacobian(fit_test::randomWebxrModel<double>(), 4, true); }
}

TEST_CASE("hand fit normal equations: H = JᵀJ and g = Jᵀr with IRLS weights", "[hand][fit][jacobian]") {
  const HandModel<double> m = makeSyntheticHand<double>();
  HandFitter<double> fitter(m);
  const PinholeCamera<double> cam = fit_test::camera<double>();
  std::mt19937 rng(8);
  const HandPose<double> truth = fit_test::randomHandPose(m, fitter.limits(), rng);
  HandObservation<double> obs = fit_test::observe(m, truth, cam, rng, 2.0, 0.01);
  obs.keypoints2d(5, 0) += 40;  // an outlier: a small IRLS weight
  obs.confidence3d(7) = 0.0;
  HandPose<double> prev = truth;
  prev.trans(2) += 0.02;
  for (RobustLoss loss : {RobustLoss::None, RobustLoss::Huber, RobustLoss::Cauchy}) {
    for (bool fitShape : {true, false}) {
      HandFitOptions<double> opt;
      opt.loss = loss;
      opt.fitShape = fitShape;
      VecX<double> r, g;
      MatX<double> Jr, H;
      fitter.residuals(truth, obs, cam, opt, &prev, r, Jr);
      fitter.normalEquations(truth, obs, cam, opt, &prev, H, g);
      MatX<double> H2 = Jr.transpose() * Jr;
      VecX<double> g2 = Jr.transpose() * r;
      if (!fitShape) {  // β held: the solver decouples its columns
        const int b0 = fitter.keypointModel().layout.betas(), B = m.numBetas();
        H2.middleRows(b0, B).setZero();
        H2.middleCols(b0, B).setZero();
        H2.block(b0, b0, B, B).setIdentity();
        g2.segment(b0, B).setZero();
      }
      INFO("loss " << static_cast<int>(loss) << " fitShape " << fitShape);
      CHECK((H - H2).cwiseAbs().maxCoeff() <= 1e-10 * H2.cwiseAbs().maxCoeff());
      CHECK((g - g2).cwiseAbs().maxCoeff() <= 1e-10 * (1.0 + g2.cwiseAbs().maxCoeff()));
    }
  }
}
