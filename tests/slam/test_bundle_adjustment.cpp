// Bundle adjustment (slam/bundle_adjustment.hpp): analytic Jacobians against central differences;
// the LM + Schur solver against an independent dense Gauss–Newton written here (full numeric
// Jacobian, no Schur, no damping) for least squares, Huber and Cauchy, with weights, fixed poses,
// fixed points and a scale prior, dense and sparse reduced systems; gross outliers with Cauchy;
// zero-weight observations; float; bad input.
#include <catch2/catch.hpp>

#include <Eigen/QR>

#include "estimation_test_utils.hpp"
#include "hawor/slam/bundle_adjustment.hpp"

using namespace hawor;
using est_test::Rng;

namespace {

using V6 = Eigen::Matrix<double, 6, 1>;

struct Scene {
  PinholeCamera<double> cam = est_test::vgaCamera<double>();
  std::vector<SE3<double>> poses;   // truth, T_w_c
  std::vector<Vec3<double>> points; // truth
  BAProblem<double> problem;        // noisy observations, perturbed start
};

// Cameras on a short sideways track looking down +z at points 4–8 m away; every point is
// observed by every camera that sees it (at most maxObs of them).
Scene makeScene(Rng& rng, int nPoses, int nPoints, double noisePx, double rotPerturb,
                double transPerturb, double pointPerturb, int maxObs = 1000) {
  const double halfTrack = 0.125 * nPoses;
  Scene s;
  for (int i = 0; i < nPoses; ++i) {
    const Eigen::Matrix3d R = rng.rotation(0.0, 0.08);
    const Eigen::Vector3d d = rng.uniform3(-0.05, 0.05, -0.1, 0.1, -0.1, 0.1);
    const Vec3<double> c(0.25 * i - halfTrack + d(0), d(1), d(2));
    s.poses.emplace_back(Mat3<double>(R), c);
  }
  s.problem.camera = s.cam;
  while (static_cast<int>(s.points.size()) < nPoints) {
    const Vec3<double> X(rng.uniform3(-2 - halfTrack, 2 + halfTrack, -2, 2, 4, 8));
    std::vector<BAObservation<double>> obs;
    for (int i = 0; i < nPoses && static_cast<int>(obs.size()) < maxObs; ++i) {
      const Vec3<double> Xc = s.poses[static_cast<std::size_t>(i)].inverse() * X;
      if (!s.cam.isVisible(Xc, 2.0)) continue;
      BAObservation<double> o;
      o.pose = i;
      o.point = static_cast<int>(s.points.size());
      const Vec2<double> uv = s.cam.project(Xc);
      o.uv = Vec2<double>(uv + noisePx * rng.normal2());
      obs.push_back(o);
    }
    if (obs.size() < 2) continue;
    s.points.push_back(X);
    for (const auto& o : obs) s.problem.observations.push_back(o);
  }
  for (const auto& T : s.poses) {
    V6 d;
    d.head<3>() = transPerturb * rng.unitVector();
    d.tail<3>() = rotPerturb * rng.unitVector();
    s.problem.poses.push_back(T * SE3<double>::exp(Vec6<double>(d)));
  }
  for (const auto& X : s.points) s.problem.points.push_back(X + pointPerturb * rng.unitVector());
  return s;
}

// --- the independent dense Gauss–Newton reference --------------------------------------------
// State: the free poses (right-perturbed, T·exp(δ)) and free points (X + δ), packed in order.
struct Reference {
  const BAProblem<double>& P;
  RobustLoss loss;
  double sigma, k;
  std::vector<int> freePose, freePoint;  // indices into P.poses / P.points

  Reference(const BAProblem<double>& p, RobustLoss l, double s, double kk) : P(p), loss(l), sigma(s), k(kk) {
    std::vector<int> poseUsed(P.poses.size(), 0), pointUsed(P.points.size(), 0);
    for (const auto& o : P.observations) {
      if (o.weight > 0) {
        poseUsed[o.pose] = 1;
        pointUsed[o.point] = 1;
      }
    }
    for (const auto& pr : P.scalePriors) poseUsed[pr.poseA] = poseUsed[pr.poseB] = 1;
    for (const auto& pr : P.positionPriors) poseUsed[pr.pose] = 1;
    for (std::size_t i = 0; i < P.poses.size(); ++i) {
      if (poseUsed[i] && !(P.poseFixed.size() && P.poseFixed[i])) freePose.push_back(int(i));
    }
    for (std::size_t j = 0; j < P.points.size(); ++j) {
      if (pointUsed[j] && !(P.pointFixed.size() && P.pointFixed[j])) freePoint.push_back(int(j));
    }
  }
  int dim() const { return 6 * int(freePose.size()) + 3 * int(freePoint.size()); }

  void apply(std::vector<SE3<double>>& poses, std::vector<Vec3<double>>& points,
             const Eigen::VectorXd& d) const {
    for (std::size_t a = 0; a < freePose.size(); ++a) {
      poses[freePose[a]] = poses[freePose[a]] * SE3<double>::exp(Vec6<double>(d.segment<6>(6 * a)));
    }
    const int off = 6 * int(freePose.size());
    for (std::size_t b = 0; b < freePoint.size(); ++b) {
      points[freePoint[b]] = points[freePoint[b]] + Vec3<double>(d.segment<3>(off + 3 * b));
    }
  }

  // Raw residuals (pixels for observations, metres for priors), observations first.
  Eigen::VectorXd residuals(const std::vector<SE3<double>>& poses,
                            const std::vector<Vec3<double>>& points) const {
    std::vector<double> r;
    for (const auto& o : P.observations) {
      if (!(o.weight > 0)) continue;
      const Vec3<double> Xc = poses[o.pose].inverse() * points[o.point];
      r.push_back(P.camera.fx * Xc.x() / Xc.z() + P.camera.cx - o.uv(0));
      r.push_back(P.camera.fy * Xc.y() / Xc.z() + P.camera.cy - o.uv(1));
    }
    for (const auto& pr : P.scalePriors) {
      r.push_back((poses[pr.poseB].translation() - poses[pr.poseA].translation()).norm() - pr.distance);
    }
    for (const auto& pr : P.positionPriors) {
      for (int a = 0; a < 3; ++a) r.push_back(poses[pr.pose].translation()(a) - pr.position(a));
    }
    return Eigen::Map<Eigen::VectorXd>(r.data(), Eigen::Index(r.size()));
  }

  // F = Σ w ρ(‖r‖²/σ²) + Σ w_p r_p², written from the definitions.
  double cost(const Eigen::VectorXd& r) const {
    double F = 0;
    int i = 0;
    for (const auto& o : P.observations) {
      if (!(o.weight > 0)) continue;
      const double s = (r(i) * r(i) + r(i + 1) * r(i + 1)) / (sigma * sigma);
      double rho = s;
      if (loss == RobustLoss::Huber) rho = s <= k * k ? s : 2 * k * std::sqrt(s) - k * k;
      if (loss == RobustLoss::Cauchy) rho = k * k * std::log1p(s / (k * k));
      F += o.weight * rho;
      i += 2;
    }
    for (const auto& pr : P.scalePriors) {
      F += pr.weight * r(i) * r(i);
      ++i;
    }
    for (const auto& pr : P.positionPriors) {
      F += pr.weight * r.segment<3>(i).squaredNorm();
      i += 3;
    }
    return F;
  }

  // IRLS weights ω (per residual row): w·ρ'(s)/σ² for observations, w_p for priors.
  Eigen::VectorXd weights(const Eigen::VectorXd& r) const {
    Eigen::VectorXd w(r.size());
    int i = 0;
    for (const auto& o : P.observations) {
      if (!(o.weight > 0)) continue;
      const double s = (r(i) * r(i) + r(i + 1) * r(i + 1)) / (sigma * sigma);
      double d = 1;
      if (loss == RobustLoss::Huber) d = s <= k * k ? 1 : k / std::sqrt(s);
      if (loss == RobustLoss::Cauchy) d = 1 / (1 + s / (k * k));
      w(i) = w(i + 1) = o.weight * d / (sigma * sigma);
      i += 2;
    }
    for (const auto& pr : P.scalePriors) w(i++) = pr.weight;
    for (const auto& pr : P.positionPriors) {
      for (int a = 0; a < 3; ++a) w(i++) = pr.weight;
    }
    return w;
  }

  // Plain (undamped) Gauss–Newton with a numeric Jacobian, solved by QR on Ω^½J.
  void solve(std::vector<SE3<double>>& poses, std::vector<Vec3<double>>& points, int iters) const {
    const int n = dim();
    for (int it = 0; it < iters; ++it) {
      const Eigen::VectorXd r = residuals(poses, points);
      Eigen::MatrixXd J(r.size(), n);
      for (int c = 0; c < n; ++c) {
        const double h = 1e-6;
        Eigen::VectorXd d = Eigen::VectorXd::Zero(n);
        auto pp = poses;
        auto qp = points;
        d(c) = h;
        apply(pp, qp, d);
        auto pm = poses;
        auto qm = points;
        d(c) = -h;
        apply(pm, qm, d);
        J.col(c) = (residuals(pp, qp) - residuals(pm, qm)) / (2 * h);
      }
      const Eigen::VectorXd sw = weights(r).cwiseSqrt();
      const Eigen::MatrixXd A = sw.asDiagonal() * J;
      const Eigen::VectorXd b = -(sw.asDiagonal() * r);
      const Eigen::VectorXd step = A.colPivHouseholderQr().solve(b);
      apply(poses, points, step);
      if (step.norm() < 1e-11) break;
    }
  }
};

double maxPoseDiff(const std::vector<SE3<double>>& a, const std::vector<SE3<double>>& b) {
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    m = std::max(m, (a[i].inverse() * b[i]).log().norm());
  }
  return m;
}
double maxPointDiff(const std::vector<Vec3<double>>& a, const std::vector<Vec3<double>>& b) {
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, (a[i] - b[i]).norm());
  return m;
}

BAOptions<double> tightOptions(RobustLoss loss, double sigma, double k) {
  BAOptions<double> o;
  o.loss = loss;
  o.sigmaPx = sigma;
  o.robustScale = k;
  o.maxIterations = 100;
  o.functionTolerance = 1e-16;
  o.parameterTolerance = 1e-13;
  o.gradientTolerance = 1e-11;
  return o;
}

}  // namespace

TEST_CASE("bundle adjustment Jacobians match central differences", "[slam][ba][jacobian]") {
  Rng rng(31);
  const auto cam = est_test::vgaCamera<double>();
  for (int trial = 0; trial < 40; ++trial) {
    const double angle = trial < 5 ? 1e-9 * trial : (trial < 35 ? rng.uniform(0, 3.0) : est_test::pi() - 1e-4);
    const SE3<double> T(SO3<double>::exp(Vec3<double>(angle * rng.unitVector())),
                        Vec3<double>(rng.scaledUnit(0, 3)));
    const Vec3<double> X = T * Vec3<double>(rng.uniform3(-2, 2, -2, 2, 0.5, 6));
    const Vec2<double> uv(rng.uniform2(0, 639, 0, 479));
    Eigen::Vector2d r;
    Eigen::Matrix<double, 2, 6> Jc;
    Eigen::Matrix<double, 2, 3> Jp;
    REQUIRE(baReprojectionResidual(cam, T, X, uv, r, &Jc, &Jp));
    auto fPose = [&](const V6& d) -> Eigen::Vector2d {
      Eigen::Vector2d out;
      baReprojectionResidual(cam, T * SE3<double>::exp(Vec6<double>(d)), X, uv, out);
      return out;
    };
    auto fPoint = [&](const Eigen::Vector3d& d) -> Eigen::Vector2d {
      Eigen::Vector2d out;
      baReprojectionResidual(cam, T, Vec3<double>(X + d), uv, out);
      return out;
    };
    const double scale = 1.0 + Jc.norm();
    INFO("trial " << trial);
    CHECK((est_test::numericJacobian<2, 6>(fPose, V6::Zero()) - Jc).norm() <= 1e-6 * scale);
    CHECK((est_test::numericJacobian<2, 3>(fPoint, Eigen::Vector3d::Zero()) - Jp).norm() <= 1e-6 * scale);
    // The residual itself: π(T⁻¹X) − uv.
    const Vec3<double> Xc = T.inverse() * X;
    CHECK((r - (cam.project(Xc) - uv)).norm() < 1e-9);

    // Scale prior.
    const Vec3<double> phi2(rng.scaledUnit(0, 3));
    const SE3<double> T2(SO3<double>::exp(phi2), Vec3<double>(rng.scaledUnit(0.1, 3)));
    Eigen::Matrix<double, 1, 6> Ja, Jb;
    const double e = baScalePriorResidual(T, T2, 0.7, &Ja, &Jb);
    CHECK(std::abs(e - ((T2.translation() - T.translation()).norm() - 0.7)) < 1e-12);
    auto fa = [&](const V6& d) -> Eigen::Matrix<double, 1, 1> {
      return Eigen::Matrix<double, 1, 1>(baScalePriorResidual(T * SE3<double>::exp(Vec6<double>(d)), T2, 0.7));
    };
    auto fb = [&](const V6& d) -> Eigen::Matrix<double, 1, 1> {
      return Eigen::Matrix<double, 1, 1>(baScalePriorResidual(T, T2 * SE3<double>::exp(Vec6<double>(d)), 0.7));
    };
    CHECK((est_test::numericJacobian<1, 6>(fa, V6::Zero()) - Ja).norm() <= 1e-7);
    CHECK((est_test::numericJacobian<1, 6>(fb, V6::Zero()) - Jb).norm() <= 1e-7);
  }
  // Behind the camera: no residual.
  Eigen::Vector2d r;
  CHECK_FALSE(baReprojectionResidual(cam, SE3<double>(), Vec3<double>(0, 0, -1), Vec2<double>(1, 1), r));
}

TEST_CASE("bundleAdjust reaches the optimum of a dense Gauss-Newton reference", "[slam][ba]") {
  struct Case {
    const char* name;
    RobustLoss loss;
    double sigma, k;
    int variant;  // 0: poses 0,1 fixed; 1: + random weights incl. zeros, some fixed points;
                  // 2: pose 0 fixed + scale prior; 3: pose 0 fixed + position priors
    double minRadialCurvature;
  };
  const Case cases[] = {{"least squares", RobustLoss::None, 1.0, 1.0, 0, 1.0},
                        {"huber, weights, fixed points", RobustLoss::Huber, 1.0, 1.5, 1, 1.0},
                        {"cauchy, scale prior", RobustLoss::Cauchy, 1.0, 2.0, 2, 1.0},
                        {"least squares, scale prior", RobustLoss::None, 1.0, 1.0, 2, 1.0},
                        {"huber, curvature correction", RobustLoss::Huber, 1.0, 1.5, 0, 0.1},
                        {"huber, position priors", RobustLoss::Huber, 1.0, 1.5, 3, 1.0}};
  unsigned seed = 40;
  for (const Case& c : cases) {
    Rng rng(++seed);
    Scene s = makeScene(rng, 4, 16, 1.5, 0.01, 0.03, 0.1);  // small: the reference is dense
    BAProblem<double>& P = s.problem;
    P.poseFixed.assign(P.poses.size(), 0);
    P.poseFixed[0] = 1;
    if (c.variant < 2) P.poseFixed[1] = 1;
    if (c.variant == 1) {
      for (auto& o : P.observations) {
        const bool zero = rng.uniform(0, 1) < 0.1;
        o.weight = zero ? 0.0 : rng.uniform(0.5, 2.0);
      }
      P.pointFixed.assign(P.points.size(), 0);
      P.pointFixed[3] = P.pointFixed[7] = 1;
    }
    if (c.variant == 2) {
      BAScalePrior<double> sp;
      sp.poseA = 0;
      sp.poseB = 3;
      sp.distance = (s.poses[3].translation() - s.poses[0].translation()).norm();
      sp.weight = 100.0;
      P.scalePriors.push_back(sp);
    }
    if (c.variant == 3) {
      // Priors a few centimetres off the true centres (they compete with the images), one of
      // them with weight 0 (no effect).
      for (int v = 1; v < 4; ++v) {
        BAPositionPrior<double> pp;
        pp.pose = v;
        pp.position = s.poses[static_cast<std::size_t>(v)].translation() + 0.03 * rng.unitVector();
        pp.weight = v == 2 ? 0.0 : 400.0;
        P.positionPriors.push_back(pp);
      }
    }
    const Reference ref(P, c.loss, c.sigma, c.k);
    std::vector<SE3<double>> rp = P.poses;
    std::vector<Vec3<double>> rx = P.points;
    const double cost0 = ref.cost(ref.residuals(rp, rx));
    ref.solve(rp, rx, 300);
    const double costRef = ref.cost(ref.residuals(rp, rx));

    for (BALinearSolver solver : {BALinearSolver::Dense, BALinearSolver::Sparse, BALinearSolver::Iterative,
                                  BALinearSolver::ImplicitSchur}) {
      BAProblem<double> Q = P;
      BAOptions<double> opt = tightOptions(c.loss, c.sigma, c.k);
      opt.maxIterations = 1000;  // IRLS converges linearly in the last digits
      opt.minRadialCurvature = c.minRadialCurvature;
      opt.solver = solver;
      opt.cgTolerance = 1e-12;
      const BAReport<double> rep = bundleAdjust(Q, opt);
      const char* names[] = {"auto", "dense", "sparse", "iterative", "implicit Schur"};
      INFO(c.name << " " << names[int(solver)]
                  << ": cost " << rep.initialCost
                  << " -> " << rep.finalCost << " (reference " << costRef << "), iterations "
                  << rep.iterations << ", termination " << int(rep.termination));
      CHECK(rep.sparseSolver == (solver == BALinearSolver::Sparse));
      CHECK(rep.iterativeSolver == (solver == BALinearSolver::Iterative || solver == BALinearSolver::ImplicitSchur));
      CHECK(rep.implicitSchur == (solver == BALinearSolver::ImplicitSchur));
      CHECK(std::abs(rep.initialCost - cost0) <= 1e-10 * cost0);  // same cost definition
      CHECK(rep.converged);
      CHECK(rep.finalCost < rep.initialCost);
      CHECK(std::abs(rep.finalCost - costRef) <= 1e-9 * costRef);
      CHECK(std::abs(ref.cost(ref.residuals(Q.poses, Q.points)) - rep.finalCost) <= 1e-10 * costRef);
      CHECK(maxPoseDiff(Q.poses, rp) < 1e-6);  // (reference: IRLS converges linearly)
      CHECK(maxPointDiff(Q.points, rx) < 1e-5);  // points 4–8 m away: 2e-6 relative
      // Fixed parameters did not move at all.
      CHECK(Q.poses[0].translation() == P.poses[0].translation());
      CHECK(Q.poses[0].rotation().quaternion().coeffs() == P.poses[0].rotation().quaternion().coeffs());
      if (c.variant == 1) CHECK(Q.points[3] == P.points[3]);
    }
  }
}

TEST_CASE("bundleAdjust with Cauchy loss recovers the truth through 20 % gross outliers", "[slam][ba]") {
  Rng rng(77);
  Scene s = makeScene(rng, 8, 300, 0.5, 0.01, 0.03, 0.15);
  s.problem.poseFixed.assign(8, 0);
  s.problem.poseFixed[0] = s.problem.poseFixed[1] = 1;
  // The fixed poses define the gauge: put them at the truth.
  s.problem.poses[0] = s.poses[0];
  s.problem.poses[1] = s.poses[1];
  // Oracle: the same problem without the outliers, least squares.
  BAProblem<double> oracle = s.problem;
  // 20 % of the observations replaced by random pixels.
  int nOut = 0;
  for (std::size_t i = 0; i < s.problem.observations.size(); ++i) {
    if (i % 5 == 2) {
      s.problem.observations[i].uv = Vec2<double>(rng.uniform2(0, 639, 0, 479));
      oracle.observations[i].weight = 0.0;
      ++nOut;
    }
  }
  REQUIRE(nOut >= 0.19 * double(s.problem.observations.size()));

  BAProblem<double> robust = s.problem, plain = s.problem;
  BAOptions<double> opt;
  opt.sigmaPx = 0.5;
  opt.robustScale = 3.0;
  opt.maxIterations = 50;
  opt.loss = RobustLoss::None;
  bundleAdjust(oracle, opt);
  bundleAdjust(plain, opt);
  opt.loss = RobustLoss::Cauchy;
  const auto rep = bundleAdjust(robust, opt);
  auto medianPointDiff = [](const std::vector<Vec3<double>>& a, const std::vector<Vec3<double>>& b) {
    std::vector<double> e;
    for (std::size_t j = 0; j < a.size(); ++j) e.push_back((a[j] - b[j]).norm());
    std::sort(e.begin(), e.end());
    return e[e.size() / 2];
  };
  const double poseOracle = maxPoseDiff(robust.poses, oracle.poses);
  const double pointOracle = medianPointDiff(robust.points, oracle.points);
  const double poseTruth = maxPoseDiff(robust.poses, s.poses);
  const double pointTruth = medianPointDiff(robust.points, s.points);
  const double posePlain = maxPoseDiff(plain.poses, s.poses);
  const double oracleTruth = maxPoseDiff(oracle.poses, s.poses);
  INFO("cauchy vs oracle: pose " << poseOracle << ", point median " << pointOracle
       << "; vs truth: pose " << poseTruth << " (oracle " << oracleTruth << "), point median "
       << pointTruth << "; least squares vs truth: pose " << posePlain << "; iterations "
       << rep.iterations);
  CHECK(rep.converged);
  CHECK(poseOracle < 4e-3);   // the robust solution is the outlier-free one, up to noise
  CHECK(pointOracle < 5e-3);
  CHECK(poseTruth < 2 * oracleTruth + 1e-3);
  CHECK(pointTruth < 0.03);   // points 4–8 m away, 0.5 px noise, gauge from a 0.25 m baseline
  CHECK(posePlain > 5 * poseTruth);  // least squares is visibly pulled by the outliers
  // Flag outliers afterwards: the gross ones have large residuals, the rest small.
  const std::vector<double> e = baReprojectionErrors(robust);
  int caught = 0, falseAlarm = 0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    const bool big = !(e[i] < 3.0);
    if (i % 5 == 2) caught += big ? 1 : 0;
    else falseAlarm += big ? 1 : 0;
  }
  CHECK(caught >= 0.95 * nOut);
  CHECK(falseAlarm <= 0.01 * double(e.size()));
}

TEST_CASE("bundleAdjust: zero-weight observations have no effect", "[slam][ba]") {
  Rng rng(88);
  Scene s = makeScene(rng, 6, 80, 1.0, 0.01, 0.02, 0.1);
  s.problem.poseFixed.assign(6, 0);
  s.problem.poseFixed[0] = s.problem.poseFixed[1] = 1;
  BAProblem<double> withZeros = s.problem;
  // Garbage: far-off pixels, a point behind a camera, duplicates — all with weight 0.
  for (int k = 0; k < 50; ++k) {
    BAObservation<double> o;
    o.pose = rng.index(6);
    o.point = rng.index(80);
    o.uv = Vec2<double>(rng.uniform2(-1e5, 1e5, -1e5, 1e5));
    o.weight = 0.0;
    withZeros.observations.insert(withZeros.observations.begin() + rng.index(int(withZeros.observations.size())), o);
  }
  withZeros.points.push_back(Vec3<double>(0, 0, -50));  // only seen with weight 0
  BAObservation<double> behind;
  behind.pose = 2;
  behind.point = 80;
  behind.weight = 0.0;
  withZeros.observations.push_back(behind);
  // The original order of the weighted observations is kept, so the arithmetic is identical.
  const auto r1 = bundleAdjust(s.problem);
  const auto r2 = bundleAdjust(withZeros);
  CHECK(r1.usedObservations == r2.usedObservations);
  CHECK(r1.finalCost == r2.finalCost);
  CHECK(r1.iterations == r2.iterations);
  CHECK(maxPoseDiff(s.problem.poses, withZeros.poses) == 0.0);
  for (std::size_t j = 0; j < 80; ++j) CHECK(s.problem.points[j] == withZeros.points[j]);
  CHECK(withZeros.points[80] == Vec3<double>(0, 0, -50));  // unobserved: untouched
}

TEST_CASE("bundleAdjust: motion-only, no variables, points behind, sparse = dense", "[slam][ba]") {
  Rng rng(99);
  // Motion-only: all points fixed at the truth, exact observations: poses return to the truth.
  {
    Scene s = makeScene(rng, 5, 60, 0.0, 0.02, 0.05, 0.0);
    s.problem.points = s.points;
    s.problem.pointFixed.assign(s.points.size(), 1);
    const auto rep = bundleAdjust(s.problem, tightOptions(RobustLoss::Huber, 1.0, 2.0));
    CHECK(rep.freePoints == 0);
    CHECK(rep.freePoses == 5);
    CHECK(maxPoseDiff(s.problem.poses, s.poses) < 1e-9);
  }
  // Everything fixed: nothing to do.
  {
    Scene s = makeScene(rng, 3, 10, 0.5, 0.0, 0.0, 0.0);
    s.problem.poseFixed.assign(3, 1);
    s.problem.pointFixed.assign(s.problem.points.size(), 1);
    const auto rep = bundleAdjust(s.problem);
    CHECK(rep.termination == BATermination::NoVariables);
    CHECK(rep.iterations == 0);
  }
  // An observation behind its camera at the start is excluded and counted.
  {
    Scene s = makeScene(rng, 4, 30, 0.5, 0.0, 0.0, 0.01);
    s.problem.poseFixed.assign(4, 0);
    s.problem.poseFixed[0] = s.problem.poseFixed[1] = 1;
    s.problem.points.push_back(Vec3<double>(0, 0, -3));
    BAObservation<double> o;
    o.pose = 2;
    o.point = int(s.problem.points.size()) - 1;
    o.uv = Vec2<double>(300, 200);
    s.problem.observations.push_back(o);
    const auto rep = bundleAdjust(s.problem);
    CHECK(rep.behindObservations == 1);
    CHECK(rep.converged);
    CHECK(rep.finalRmsPx < 0.8);
  }
  // A longer trajectory: Auto picks the sparse solver; it agrees with the dense one.
  {
    Scene s = makeScene(rng, 70, 400, 0.5, 0.005, 0.01, 0.05, 6);
    s.problem.poseFixed.assign(70, 0);
    s.problem.poseFixed[0] = s.problem.poseFixed[1] = 1;
    s.problem.poses[0] = s.poses[0];  // the fixed poses define the gauge: at the truth
    s.problem.poses[1] = s.poses[1];
    BAProblem<double> dense = s.problem;
    const BAProblem<double> s0 = s.problem;
    BAOptions<double> opt;
    opt.maxIterations = 40;
    const auto rs = bundleAdjust(s.problem, opt);
    opt.solver = BALinearSolver::Dense;
    const auto rd = bundleAdjust(dense, opt);
    CHECK(rs.sparseSolver);
    CHECK_FALSE(rd.sparseSolver);
    CHECK(rs.converged);
    CHECK(rs.finalRmsPx < 0.75);  // 0.5 px noise per coordinate: E‖r‖ ≈ 0.5·√2 less the dof
    CHECK(std::abs(rs.finalCost - rd.finalCost) <= 1e-6 * rd.finalCost);
    CHECK(maxPoseDiff(s.problem.poses, dense.poses) < 1e-6);
    // With the thresholds lowered Auto picks conjugate gradients (block-Jacobi preconditioned),
    // and it reaches the same optimum.
    BAProblem<double> cg = s0;
    BAOptions<double> oc;
    oc.maxIterations = 40;
    oc.iterativeMinPoses = 50;
    oc.iterativeMinBlocksPerPose = 3;
    const auto ri = bundleAdjust(cg, oc);
    CHECK(ri.iterativeSolver);
    CHECK_FALSE(ri.sparseSolver);
    CHECK(ri.converged);
    CHECK(std::abs(ri.finalCost - rd.finalCost) <= 1e-6 * rd.finalCost);
    CHECK(maxPoseDiff(cg.poses, dense.poses) < 1e-5);
    CHECK_FALSE(ri.implicitSchur);  // a few cameras per point: S is formed
    // Every pair counted as many (implicitMinPairsPerObservation 0): S applied implicitly, the
    // same optimum.
    BAProblem<double> im = s0;
    oc.implicitMinPairsPerObservation = 0;
    const auto rm = bundleAdjust(im, oc);
    CHECK(rm.implicitSchur);
    CHECK(rm.converged);
    CHECK(std::abs(rm.finalCost - rd.finalCost) <= 1e-6 * rd.finalCost);
    CHECK(maxPoseDiff(im.poses, dense.poses) < 1e-5);
  }
}

TEST_CASE("bundleAdjust in float matches double", "[slam][ba]") {
  Rng rng(55);
  Scene s = makeScene(rng, 5, 60, 1.0, 0.01, 0.03, 0.1);
  s.problem.poseFixed.assign(5, 0);
  s.problem.poseFixed[0] = s.problem.poseFixed[1] = 1;
  s.problem.poses[0] = s.poses[0];  // the fixed poses define the gauge: at the truth
  s.problem.poses[1] = s.poses[1];
  BAProblem<float> pf;
  pf.camera = s.problem.camera.cast<float>();
  for (const auto& T : s.problem.poses) pf.poses.push_back(T.cast<float>());
  for (const auto& X : s.problem.points) pf.points.push_back(X.cast<float>());
  for (const auto& o : s.problem.observations) {
    BAObservation<float> q;
    q.pose = o.pose;
    q.point = o.point;
    q.uv = o.uv.cast<float>();
    q.weight = float(o.weight);
    pf.observations.push_back(q);
  }
  pf.poseFixed = s.problem.poseFixed;
  // The cost at the true poses and points: the optimum must be below it.
  BAProblem<double> atTruth = s.problem;
  atTruth.poses = s.poses;
  atTruth.points = s.points;
  BAOptions<double> evaluateOnly;
  evaluateOnly.maxIterations = 0;
  const double truthCost = bundleAdjust(atTruth, evaluateOnly).initialCost;
  BAOptions<float> of;
  of.maxIterations = 30;
  const auto rf = bundleAdjust(pf, of);
  BAOptions<double> od;
  od.maxIterations = 30;
  const auto rd = bundleAdjust(s.problem, od);
  INFO("float " << rf.initialCost << " -> " << rf.finalCost << ", double " << rd.finalCost << ", truth "
                << truthCost);
  CHECK(rf.converged);
  CHECK(rd.finalCost < truthCost);
  CHECK(std::abs(double(rf.finalCost) - rd.finalCost) <= 1e-3 * rd.finalCost + 1e-3);
  double dp = 0;
  for (std::size_t j = 0; j < pf.points.size(); ++j) {
    dp = std::max(dp, (pf.points[j].cast<double>() - s.problem.points[j]).norm());
  }
  CHECK(dp < 2e-3);  // metres, points 4–8 m away
}

TEST_CASE("bundleAdjust rejects malformed problems with hawor::Error", "[slam][ba]") {
  Rng rng(5);
  const Scene s = makeScene(rng, 3, 10, 0.5, 0.0, 0.0, 0.0);
  auto expectThrow = [&](auto mutate) {
    BAProblem<double> p = s.problem;
    mutate(p);
    CHECK_THROWS_AS(bundleAdjust(p), hawor::Error);
  };
  expectThrow([](BAProblem<double>& p) { p.observations[0].pose = 3; });
  expectThrow([](BAProblem<double>& p) { p.observations[0].point = -1; });
  expectThrow([](BAProblem<double>& p) { p.observations[1].weight = -1; });
  expectThrow([](BAProblem<double>& p) { p.observations[1].uv(0) = std::nan(""); });
  expectThrow([](BAProblem<double>& p) { p.points[2](1) = std::numeric_limits<double>::infinity(); });
  expectThrow([](BAProblem<double>& p) { p.poseFixed.assign(2, 1); });
  expectThrow([](BAProblem<double>& p) { p.pointFixed.assign(1, 1); });
  expectThrow([](BAProblem<double>& p) { p.camera.fx = 0; });
  expectThrow([](BAProblem<double>& p) {
    BAScalePrior<double> sp;
    sp.poseA = sp.poseB = 1;
    p.scalePriors.push_back(sp);
  });
  expectThrow([](BAProblem<double>& p) { p.positionPriors.push_back({3, Vec3<double>::Zero(), 1.0}); });
  expectThrow([](BAProblem<double>& p) { p.positionPriors.push_back({0, Vec3<double>(0, std::nan(""), 0), 1.0}); });
  expectThrow([](BAProblem<double>& p) { p.positionPriors.push_back({0, Vec3<double>::Zero(), -1.0}); });
  BAProblem<double> p = s.problem;
  BAOptions<double> bad;
  bad.sigmaPx = 0;
  CHECK_THROWS_AS(bundleAdjust(p, bad), hawor::Error);
  // An empty problem is fine.
  BAProblem<double> empty;
  empty.camera = s.cam;
  CHECK(bundleAdjust(empty).termination == BATermination::NoVariables);
}

TEST_CASE("addFarthestScalePrior: the distance to the farthest centre, by brute force", "[slam][ba]") {
  Rng rng(21);
  BAProblem<double> P;
  for (int i = 0; i < 7; ++i) P.poses.emplace_back(Mat3<double>::Identity(), Vec3<double>(rng.uniform3(-2, 2, -2, 2, -2, 2)));
  const int anchor = 3;
  int best = -1;
  double bestD = 0;
  for (int i = 0; i < 7; ++i) {
    const double d = std::sqrt((P.poses[i].translation() - P.poses[anchor].translation()).squaredNorm());
    if (d > bestD) bestD = d, best = i;
  }
  REQUIRE(addFarthestScalePrior(P, anchor, 100.0) == best);
  REQUIRE(P.scalePriors.size() == 1);
  CHECK(P.scalePriors[0].poseA == anchor);
  CHECK(P.scalePriors[0].poseB == best);
  CHECK(P.scalePriors[0].distance == Approx(bestD));
  CHECK(P.scalePriors[0].weight == Approx(100.0 / (bestD * bestD)));
  // every centre at the anchor's: nothing to hold
  BAProblem<double> Q;
  for (int i = 0; i < 3; ++i) Q.poses.emplace_back(Mat3<double>::Identity(), Vec3<double>(1, 2, 3));
  CHECK(addFarthestScalePrior(Q, 0) == -1);
  CHECK(Q.scalePriors.empty());
}
