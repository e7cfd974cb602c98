// PnP with outliers (slam/pnp_ransac.hpp): P3P + MSAC + robust LM on 2D–3D correspondences with
// 30 % outliers and 1 px noise; the refinement's Jacobian; degenerate input.
#include <catch2/catch.hpp>

#include "estimation_test_utils.hpp"
#include "hawor/slam/pnp_ransac.hpp"

using namespace hawor;
using est_test::Rng;

namespace {

struct PnPScene {
  SE3<double> T_w_c;
  std::vector<Vec3<double>> X;
  std::vector<Vec2<double>> uv;
  std::vector<char> isInlier;
};

// Points in front of a camera with pose T_w_c, projected with noise; a fraction become outliers.
PnPScene makePnPScene(Rng& rng, int n, double outliers, double noisePx) {
  const auto cam = est_test::vgaCamera<double>();
  PnPScene s;
  const Mat3<double> R(rng.rotation(0, 3.0));
  s.T_w_c = SE3<double>(R, Vec3<double>(rng.scaledUnit(0, 5)));
  for (int i = 0; i < n; ++i) {
    const Vec2<double> px(rng.uniform2(0, 639, 0, 479));
    const Vec3<double> Xc = cam.unproject(px, rng.uniform(1.0, 6.0));
    s.X.push_back(s.T_w_c * Xc);
    s.uv.emplace_back(px + noisePx * rng.normal2());
    s.isInlier.push_back(1);
  }
  const int nOut = static_cast<int>(std::lround(outliers * n));
  for (int k = 0; k < nOut; ++k) {
    const std::size_t i = static_cast<std::size_t>(k * n / nOut);
    s.isInlier[i] = 0;
    s.uv[i] = Vec2<double>(rng.uniform2(0, 639, 0, 479));
  }
  return s;
}

template <typename S>
std::vector<Vec3<S>> cast3(const std::vector<Vec3<double>>& v) {
  std::vector<Vec3<S>> o;
  for (const auto& p : v) o.emplace_back(p.cast<S>());
  return o;
}

}  // namespace

TEMPLATE_TEST_CASE("solvePnPRansac recovers the pose through 30 % outliers and 1 px noise",
                   "[slam][pnp]", float, double) {
  using S = TestType;
  const auto cam = est_test::vgaCamera<S>();
  for (unsigned seed : {1u, 2u, 3u, 4u, 5u}) {
    Rng rng(500 + seed);
    const PnPScene sc = makePnPScene(rng, 200, 0.3, 1.0);
    const auto r = solvePnPRansac(cast3<S>(sc.X), est_test::castPoints<S>(sc.uv), cam, PnPRansacOptions<S>{});
    INFO("seed " << seed);
    REQUIRE(r.status == PnPStatus::Ok);
    const double rot = est_test::rotationErrorDeg(r.T_w_c.rotationMatrix().template cast<double>(),
                                                  sc.T_w_c.rotationMatrix());
    const double trans = (r.T_w_c.translation().template cast<double>() - sc.T_w_c.translation()).norm();
    int flagged = 0, missed = 0, inl = 0;
    for (std::size_t i = 0; i < sc.X.size(); ++i) {
      inl += sc.isInlier[i];
      flagged += (!sc.isInlier[i] && r.inliers[i]) ? 1 : 0;
      missed += (sc.isInlier[i] && !r.inliers[i]) ? 1 : 0;
    }
    INFO("rot " << rot << " deg, trans " << trans << " m, flagged " << flagged << ", missed " << missed
                << ", rms " << r.inlierRmsPx << ", ransac its " << r.ransacIterations);
    CHECK(rot < 0.1);
    CHECK(trans < 0.01);  // scene depth 1–6 m
    CHECK(flagged <= 3);
    CHECK(missed <= 0.1 * inl);  // 2.5 px threshold at 1 px noise: P(miss) = e^-3.1 = 4.4 %
    CHECK(r.inlierRmsPx < S(1.6));
    CHECK(r.ransacIterations < 200);
  }
}

TEMPLATE_TEST_CASE("refinePose converges from a perturbed pose and ignores zero weights",
                   "[slam][pnp]", float, double) {
  using S = TestType;
  const auto cam = est_test::vgaCamera<S>();
  Rng rng(600);
  const PnPScene sc = makePnPScene(rng, 100, 0.0, 0.0);
  auto X = cast3<S>(sc.X);
  auto uv = est_test::castPoints<S>(sc.uv);
  std::vector<S> w(X.size(), S(1));
  // Garbage observations with zero weight.
  for (int k = 0; k < 10; ++k) {
    X.push_back(X[static_cast<std::size_t>(k)]);
    uv.push_back(Vec2<S>(S(1e4), S(-1e4)));
    w.push_back(S(0));
  }
  Vec6<S> d;
  d << S(0.05), S(-0.03), S(0.04), S(0.02), S(-0.03), S(0.01);
  SE3<S> T = sc.T_w_c.template cast<S>() * SE3<S>::exp(d);
  PoseRefineOptions<S> opt;
  opt.maxIterations = 30;
  const auto rep = refinePose(X, uv, &w, cam, T, opt);
  CHECK(rep.usedPoints == 100);
  CHECK(rep.finalCost < rep.initialCost);
  CHECK(rep.converged);
  CHECK(est_test::rotationErrorDeg(T.rotationMatrix().template cast<double>(), sc.T_w_c.rotationMatrix()) <
        est_test::tol<S>(1e-6, 2e-3));
  CHECK((T.translation().template cast<double>() - sc.T_w_c.translation()).norm() <
        est_test::tol<S>(1e-7, 1e-4));
}

TEST_CASE("solvePnPRansac: degenerate input gives a status or hawor::Error", "[slam][pnp]") {
  const auto cam = est_test::vgaCamera<double>();
  std::vector<Vec3<double>> X(3, Vec3<double>(0, 0, 5));
  std::vector<Vec2<double>> uv(3, Vec2<double>(320, 240));
  CHECK(solvePnPRansac(X, uv, cam).status == PnPStatus::TooFewPoints);
  // All identical: no pose.
  X.assign(50, Vec3<double>(0.1, 0.2, 4));
  uv.assign(50, Vec2<double>(300, 200));
  const auto r = solvePnPRansac(X, uv, cam);
  CHECK(r.status == PnPStatus::NoModel);
  CHECK_FALSE(r.ok());
  // Random garbage: no crash, not enough inliers.
  Rng rng(9);
  for (std::size_t i = 0; i < X.size(); ++i) {
    X[i] = Vec3<double>(rng.uniform3(-1, 1, -1, 1, 2, 5));
    uv[i] = Vec2<double>(rng.uniform2(0, 639, 0, 479));
  }
  PnPRansacOptions<double> opt;
  opt.minInliers = 10;
  CHECK_FALSE(solvePnPRansac(X, uv, cam, opt).ok());
  // NaN, size mismatch, bad camera: hawor::Error.
  X[5](0) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(solvePnPRansac(X, uv, cam), hawor::Error);
  X[5](0) = 0.0;
  uv.pop_back();
  CHECK_THROWS_AS(solvePnPRansac(X, uv, cam), hawor::Error);
  uv.push_back(Vec2<double>(1, 1));
  auto badCam = cam;
  badCam.fx = 0;
  CHECK_THROWS_AS(solvePnPRansac(X, uv, badCam), hawor::Error);
  SE3<double> T;
  std::vector<double> w(X.size() - 1, 1.0);
  CHECK_THROWS_AS(refinePose(X, uv, &w, cam, T), hawor::Error);
}
