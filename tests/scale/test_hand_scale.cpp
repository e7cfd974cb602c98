// Hand-anchored metric scale (scale/hand_scale.hpp) on generated motion: a walking camera with
// head bob, hands that move smoothly in the world (resting, reaching), the SLAM trajectory at an
// arbitrary scale, camera-frame hand positions with noise; and the degenerate cases.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "hawor/scale/hand_scale.hpp"

namespace {

struct Scene {
  std::vector<hawor::SE3<double>> slam;  // camera-to-world, map units
  std::vector<hawor::HandTrack<double>> hands;
};

/// T frames at 30 fps; the camera walks at `speed` m/s with a vertical head bob of `bob` m at
/// 2 Hz and yaw sway; hand 0 rests on a table then reaches; hand 1 moves along a slow arc.
/// The SLAM trajectory is the true one divided by `alpha` (so the true scale is alpha).
Scene makeScene(int T, double speed, double bob, double alpha, double noise, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> N(0, 1);
  Scene s;
  s.hands.resize(2);
  for (int t = 0; t < T; ++t) {
    const double time = t / 30.0;
    const Eigen::Vector3d c(speed * time, 0.05 * std::sin(2 * M_PI * 0.5 * time), 1.6 + bob * std::sin(2 * M_PI * 2 * time));
    const Eigen::Vector3d phi(0.1 * std::sin(2 * M_PI * 0.3 * time), 0.05 * std::sin(2 * M_PI * 1.0 * time), 0.2 * time);
    const hawor::SE3<double> Twc(hawor::SO3<double>::exp(phi), c);
    s.slam.push_back(hawor::SE3<double>(Twc.rotation(), Eigen::Vector3d(c / alpha)));
    // World hand positions: smooth (low acceleration), independent of the head.
    Eigen::Vector3d p0, p1;
    if (time < 2.0) {
      p0 = Eigen::Vector3d(0.6, 0.2, 0.9);  // resting on a table
    } else {
      const double u = std::min(1.0, (time - 2.0) / 2.0), e = u * u * (3 - 2 * u);
      p0 = Eigen::Vector3d(0.6 + e * (speed * time + 0.3 - 0.6), 0.2 - 0.1 * e, 0.9 + 0.4 * e);
    }
    p1 = Eigen::Vector3d(speed * time + 0.35 + 0.1 * std::cos(0.8 * time), -0.2 + 0.05 * std::sin(0.6 * time), 1.2);
    const Eigen::Vector3d h0 = Twc.inverse() * p0, h1 = Twc.inverse() * p1;
    s.hands[0].positionCam.push_back(h0 + noise * Eigen::Vector3d(N(rng), N(rng), N(rng)));
    s.hands[1].positionCam.push_back(h1 + noise * Eigen::Vector3d(N(rng), N(rng), N(rng)));
    s.hands[0].valid.push_back(1);
    s.hands[1].valid.push_back((t / 45) % 3 != 2 ? 1 : 0);  // out of view now and then
  }
  return s;
}

}  // namespace

TEST_CASE("hand-anchored scale recovers the trajectory scale from smooth world hand motion", "[scale]") {
  for (double alpha : {0.05, 1.0, 7.0}) {
    const Scene s = makeScene(300, 1.0, 0.03, alpha, 0.003, 3);
    const hawor::HandScaleResult<double> r = hawor::handAnchoredScale(s.slam, s.hands);
    REQUIRE(r.ok());
    INFO("alpha " << alpha << " estimate " << r.scale << " rel. s.e. " << r.relativeStdError);
    CHECK(std::abs(r.scale / alpha - 1) < 0.05);
    CHECK(r.confidence > 0.5);
    CHECK(r.restFrames > 20);
  }
}

TEST_CASE("hand-anchored scale: degenerate input", "[scale]") {
  Scene s = makeScene(120, 1.0, 0.03, 1.0, 0.003, 5);
  SECTION("no valid hand frame") {
    for (auto& h : s.hands) std::fill(h.valid.begin(), h.valid.end(), 0);
    const hawor::HandScaleResult<double> r = hawor::handAnchoredScale(s.slam, s.hands);
    CHECK_FALSE(r.ok());
    CHECK(r.residuals == 0);
  }
  SECTION("a camera that never accelerates has no observable scale") {
    for (std::size_t t = 0; t < s.slam.size(); ++t) {
      s.slam[t] = hawor::SE3<double>(s.slam[t].rotation(), Eigen::Vector3d(0.01 * double(t), 0, 0));
    }
    const hawor::HandScaleResult<double> r = hawor::handAnchoredScale(s.slam, s.hands);
    CHECK((!r.ok() || r.confidence < 0.1));
  }
  SECTION("NaN positions are skipped, mismatched lengths throw") {
    s.hands[0].positionCam[10] = Eigen::Vector3d::Constant(std::nan(""));
    const hawor::HandScaleResult<double> r = hawor::handAnchoredScale(s.slam, s.hands);
    CHECK(std::isfinite(r.scale));
    s.hands[1].valid.pop_back();
    CHECK_THROWS_AS(hawor::handAnchoredScale(s.slam, s.hands), hawor::Error);
  }
}
