// Turn radius (slam/turn_scale.hpp) on generated head motion: the eye 9 cm in front of a neck
// axis, turns of 60-150 degrees with fixations between them, two stretches at different map
// scales (their radius ratio is the scale ratio), noise on the poses; walking with head turns
// (the model does not hold: large spread); degenerate input.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "hawor/slam/turn_scale.hpp"

namespace {

/// T frames at 30 fps of a standing head: yaw turns of 1-2.5 rad over 15 frames every 40, a
/// slow pitch sway; the eye at `offset` (head frame) from the pivot; positions divided by
/// `mapScale` (metres per map unit) and perturbed by `noise` (map units); `walk` m/s forward.
std::vector<hawor::SE3<double>> headTurns(int T, double offset, double mapScale, double noise, double walk, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> N(0, 1);
  std::uniform_real_distribution<double> U(1.0, 2.5);
  std::vector<hawor::SE3<double>> out;
  double yaw = 0, target = 0;
  int turnStart = 0;
  double from = 0;
  for (int t = 0; t < T; ++t) {
    if (t % 40 == 10) from = yaw, target = yaw + (t % 80 == 10 ? 1 : -1) * U(rng), turnStart = t;
    if (t >= turnStart && t < turnStart + 15) {
      const double u = double(t - turnStart + 1) / 15, e = u * u * (3 - 2 * u);
      yaw = from + e * (target - from);
    }
    const double pitch = 0.15 * std::sin(0.05 * t);
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX())).toRotationMatrix();
    const Eigen::Vector3d pivot(0, 0, walk * t / 30.0);
    const Eigen::Vector3d eye = pivot + R * Eigen::Vector3d(0, -0.02, offset);
    out.emplace_back(hawor::SO3<double>::fromMatrix(R), Eigen::Vector3d(eye / mapScale + noise * Eigen::Vector3d(N(rng), N(rng), N(rng))));
  }
  return out;
}

}  // namespace

TEST_CASE("turnRadius: the eye's distance from the neck axis, in each stretch's map units", "[slam]") {
  const auto a = headTurns(240, 0.09, 0.05, 0.002, 0, 3);   // 1 map unit = 5 cm
  const auto b = headTurns(240, 0.09, 0.08, 0.002, 0, 4);   // 1 map unit = 8 cm
  const auto ra = hawor::turnRadius(a, {}, 0, 240), rb = hawor::turnRadius(b, {}, 0, 240);
  REQUIRE(ra.ok());
  REQUIRE(rb.ok());
  CHECK(ra.windows >= 30);
  // The chord of a turn about a vertical axis sees the eye's horizontal offset: 9 cm.
  CHECK(ra.radius * 0.05 == Approx(0.09).epsilon(0.05));
  CHECK(ra.radius / rb.radius == Approx(0.08 / 0.05).epsilon(0.03));  // the scale ratio
  CHECK(ra.spread < 0.2);
  // Flags: frames marked unusable are skipped; a range restricts the windows.
  std::vector<char> usable(240, 1);
  for (int t = 0; t < 120; ++t) usable[static_cast<std::size_t>(t)] = 0;
  const auto half = hawor::turnRadius(a, usable, 0, 240);
  CHECK(half.windows < ra.windows);
  CHECK(half.windows == hawor::turnRadius(a, {}, 120, 240).windows);
}

TEST_CASE("turnRadius: walking with head turns does not follow the neck model; degenerate input", "[slam]") {
  const auto w = headTurns(240, 0.09, 0.05, 0.002, 1.2, 5);
  const auto r = hawor::turnRadius(w, {}, 0, 240);
  REQUIRE(r.windows > 0);
  CHECK(r.spread > 0.35);  // the walking translation scatters the per-window radii
  // No turns: no windows.
  std::vector<hawor::SE3<double>> still(50, hawor::SE3<double>());
  CHECK_FALSE(hawor::turnRadius(still, {}, 0, 50).ok());
  CHECK(hawor::turnRadius(still, {}, 0, 50).windows == 0);
  CHECK_FALSE(hawor::turnRadius(still, {}, 40, 10).ok());  // empty range
  CHECK_THROWS_AS(hawor::turnRadius(still, std::vector<char>(3, 1), 0, 50), hawor::Error);
  CHECK_THROWS_AS(hawor::turnRadius(still, {}, 0, 50, 0), hawor::Error);
}
