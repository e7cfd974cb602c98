// Turn bridge (slam/turn_bridge.hpp) on generated head turns: the eye 9 cm in front of a vertical
// neck axis turning 6-12 degrees a frame, points 0.8-3 m away; tracks with 0.3 px noise and
// outliers, points with depth errors and outliers. Checked against the generating poses: the
// rotation (which the rays' pure-rotation fit gets wrong by the absorbed step) and the position.
// Failure modes: too few tracks, no turn, a prediction far from the points' length, bad sizes.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "hawor/slam/turn_bridge.hpp"

namespace {

struct TbTurnPair {
  hawor::SE3<double> T1, T2;  // camera-to-world (world: y up... any frame; x right, z forward)
  std::vector<hawor::Vec2<double>> x1, x2, y;  // normalised
  std::vector<hawor::Vec3<double>> X;
};

hawor::SE3<double> tbHeadPose(double yaw, double pitch, double r) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX())).toRotationMatrix();
  const Eigen::Vector3d neck(0.3, -0.1, 0.2);
  return hawor::SE3<double>(hawor::SO3<double>::fromMatrix(R), Eigen::Vector3d(neck + r * R.col(2)));
}

/// Two frames of a turn by `stepDeg` (yaw), `tracks` tracks (a fraction `outliers` random) and
/// `points` points (depth error `depthErr` relative, a fraction `pointOutliers` random).
TbTurnPair tbMakeTurn(std::uint32_t seed, double stepDeg, int tracks, double outliers, int points, double depthErr,
                  double pointOutliers, double noisePx = 0.3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> N(0, 1);
  const double f = 400, deg = 3.14159265358979323846 / 180;
  const double yaw = U(rng) * 6.28, pitch = (U(rng) - 0.7) * 0.5;
  TbTurnPair P;
  P.T1 = tbHeadPose(yaw, pitch, 0.09);
  P.T2 = tbHeadPose(yaw + stepDeg * deg, pitch, 0.09);
  const hawor::SE3<double> C1 = P.T1.inverse(), C2 = P.T2.inverse();
  auto visible = [&](const Eigen::Vector3d& Xw, const hawor::SE3<double>& C, Eigen::Vector2d& x) {
    const Eigen::Vector3d Xc = C * Xw;
    if (!(Xc(2) > 0.1)) return false;
    x = Xc.head<2>() / Xc(2);
    return std::abs(x(0)) < 0.8 && std::abs(x(1)) < 0.6;
  };
  auto sample = [&](Eigen::Vector3d& Xw, Eigen::Vector2d& a, Eigen::Vector2d& b) {
    for (int tries = 0; tries < 1000; ++tries) {
      // A point in camera 1's view, 0.8-3 m away.
      const Eigen::Vector3d ray((U(rng) - 0.5) * 1.6, (U(rng) - 0.5) * 1.2, 1.0);
      Xw = P.T1 * Eigen::Vector3d(ray * (0.8 + 2.2 * U(rng)));
      if (visible(Xw, C1, a) && visible(Xw, C2, b)) return true;
    }
    return false;
  };
  for (int i = 0; i < tracks; ++i) {
    Eigen::Vector3d Xw;
    Eigen::Vector2d a, b;
    REQUIRE(sample(Xw, a, b));
    a += noisePx / f * Eigen::Vector2d(N(rng), N(rng));
    b += noisePx / f * Eigen::Vector2d(N(rng), N(rng));
    if (U(rng) < outliers) b = Eigen::Vector2d((U(rng) - 0.5) * 1.6, (U(rng) - 0.5) * 1.2);
    P.x1.push_back(a);
    P.x2.push_back(b);
  }
  for (int j = 0; j < points; ++j) {
    Eigen::Vector3d Xw;
    Eigen::Vector2d a, b;
    REQUIRE(sample(Xw, a, b));
    // Depth error along camera 1's ray (a point triangulated from a short baseline).
    const Eigen::Vector3d c1 = P.T1.translation();
    Eigen::Vector3d Xn = c1 + (Xw - c1) * (1 + depthErr * N(rng));
    if (U(rng) < pointOutliers) Xn = c1 + (Xw - c1) * (0.3 + 2 * U(rng));
    P.X.push_back(Xn);
    P.y.push_back(b + noisePx / f * Eigen::Vector2d(N(rng), N(rng)));
  }
  return P;
}

double tbRotErrDeg(const hawor::SE3<double>& A, const hawor::SE3<double>& B) {
  const Eigen::Matrix3d D = A.rotationMatrix().transpose() * B.rotationMatrix();
  return std::acos(std::max(-1.0, std::min(1.0, (D.trace() - 1) / 2))) * 180 / 3.14159265358979323846;
}

template <typename S>
std::vector<hawor::Vec2<S>> tbCast2(const std::vector<hawor::Vec2<double>>& v) {
  std::vector<hawor::Vec2<S>> o;
  for (const auto& x : v) o.push_back(x.cast<S>());
  return o;
}
template <typename S>
std::vector<hawor::Vec3<S>> tbCast3(const std::vector<hawor::Vec3<double>>& v) {
  std::vector<hawor::Vec3<S>> o;
  for (const auto& x : v) o.push_back(x.cast<S>());
  return o;
}

}  // namespace

TEMPLATE_TEST_CASE("turn bridge: poses a head-turn frame from the previous one", "[slam][turn_bridge]", float, double) {
  using S = TestType;
  int better = 0, n = 0;
  std::vector<double> relErr;
  for (std::uint32_t seed = 1; seed <= 12; ++seed) {
    const double step = 6 + (seed % 4) * 2;  // 6-12 degrees a frame
    const TbTurnPair P = tbMakeTurn(seed, step, 200, 0.15, 40, 0.08, 0.2);
    const hawor::SE3<S> T1(hawor::SO3<S>::fromMatrix(P.T1.rotationMatrix().cast<S>()), P.T1.translation().cast<S>());
    const auto r = hawor::bridgeTurnPose<S>(T1, tbCast2<S>(P.x1), tbCast2<S>(P.x2), tbCast3<S>(P.X), tbCast2<S>(P.y), S(400), S(-1));
    INFO("seed " << seed << " step " << step << ": " << r.why);
    REQUIRE(r.ok);
    const hawor::SE3<double> T2(hawor::SO3<double>::fromMatrix(r.T_w_c.rotationMatrix().template cast<double>()),
                                r.T_w_c.translation().template cast<double>());
    const double trueLen = (P.T2.translation() - P.T1.translation()).norm();
    const double posErr = (T2.translation() - P.T2.translation()).norm();
    // The rays' pure-rotation fit, for comparison (the bias the bridge removes).
    std::vector<char> all(P.x1.size(), 1);
    const Eigen::Matrix3d R21 = hawor::two_view_detail::rotationFromRays(P.x1, P.x2, all, hawor::Mat3<double>(hawor::Mat3<double>::Identity()));
    const hawor::SE3<double> byRays(hawor::SO3<double>::fromMatrix(Eigen::Matrix3d(P.T1.rotationMatrix() * R21.transpose())), P.T1.translation());
    const double eBridge = tbRotErrDeg(T2, P.T2), eRays = tbRotErrDeg(byRays, P.T2);
    INFO("rotation error " << eBridge << " deg (rays " << eRays << "), position error " << posErr << " of a " << trueLen << " m step");
    CHECK(eBridge < 0.2);
    // A 0.1° rotation error moves a point 2 m away by 0.7 px, a third of a 1 cm step's parallax:
    // the length is as good as the rotation, per draw.
    CHECK(posErr < 0.5 * trueLen);
    relErr.push_back(posErr / trueLen);
    better += eBridge < eRays ? 1 : 0;
    ++n;
  }
  // The step is what the rays' rotation absorbs: the bridge's rotation is the closer one on most draws.
  CHECK(better >= n - 2);
  std::sort(relErr.begin(), relErr.end());
  INFO("relative position errors, median " << relErr[relErr.size() / 2] << ", largest " << relErr.back());
  CHECK(relErr[relErr.size() / 2] < 0.15);
}

TEMPLATE_TEST_CASE("turn bridge: says why it declines", "[slam][turn_bridge]", float, double) {
  using S = TestType;
  const TbTurnPair P = tbMakeTurn(5, 9, 200, 0.1, 40, 0.05, 0.1);
  const hawor::SE3<S> T1(hawor::SO3<S>::fromMatrix(P.T1.rotationMatrix().cast<S>()), P.T1.translation().cast<S>());
  const auto x1 = tbCast2<S>(P.x1), x2 = tbCast2<S>(P.x2), y = tbCast2<S>(P.y);
  const auto X = tbCast3<S>(P.X);
  const double trueLen = (P.T2.translation() - P.T1.translation()).norm();
  {
    // A prediction 5x the points' length.
    const auto r = hawor::bridgeTurnPose<S>(T1, x1, x2, X, y, S(400), S(5 * trueLen));
    CHECK_FALSE(r.ok);
    CHECK(r.why.find("predicted") != std::string::npos);
    // Within the factor: accepted.
    CHECK(hawor::bridgeTurnPose<S>(T1, x1, x2, X, y, S(400), S(1.5 * trueLen)).ok);
  }
  {
    // Too few tracks.
    const std::vector<hawor::Vec2<S>> a(x1.begin(), x1.begin() + 20), b(x2.begin(), x2.begin() + 20);
    const auto r = hawor::bridgeTurnPose<S>(T1, a, b, X, y, S(400), S(-1));
    CHECK_FALSE(r.ok);
    CHECK(r.why == "too few tracks");
  }
  {
    // Too few points for the length.
    const std::vector<hawor::Vec3<S>> X3(X.begin(), X.begin() + 3);
    const std::vector<hawor::Vec2<S>> y3(y.begin(), y.begin() + 3);
    const auto r = hawor::bridgeTurnPose<S>(T1, x1, x2, X3, y3, S(400), S(-1));
    CHECK_FALSE(r.ok);
    CHECK(r.why.find("too few points") != std::string::npos);
  }
  {
    // No turn (the same view twice): no direction for the step.
    const auto r = hawor::bridgeTurnPose<S>(T1, x1, x1, X, y, S(400), S(-1));
    CHECK_FALSE(r.ok);
    CHECK(r.why.find("too little turn") != std::string::npos);
  }
  // Mismatched sizes and a bad focal length throw.
  const std::vector<hawor::Vec2<S>> shorter(x2.begin(), x2.end() - 1);
  CHECK_THROWS_AS(hawor::bridgeTurnPose<S>(T1, x1, shorter, X, y, S(400), S(-1)), hawor::Error);
  CHECK_THROWS_AS(hawor::bridgeTurnPose<S>(T1, x1, x2, X, y, S(0), S(-1)), hawor::Error);
}
