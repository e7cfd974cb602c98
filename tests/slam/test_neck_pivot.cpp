// Neck pivot (slam/neck_pivot.hpp) on generated head motion: the eye at a known offset from a
// known pivot, random head rotations, noise on the positions; recovered against that truth. A
// walking head (the pivot moves) leaves a residual far above the noise; too little rotation,
// too few frames and NaN poses give no solution.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "hawor/slam/neck_pivot.hpp"

namespace {

template <typename S>
std::vector<hawor::SE3<S>> headOnNeck(int T, double maxAngle, double noise, double walk, const Eigen::Vector3d& neck,
                                      const Eigen::Vector3d& offset, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> N(0, 1);
  std::uniform_real_distribution<double> U(-1, 1);
  std::vector<hawor::SE3<S>> out;
  for (int t = 0; t < T; ++t) {
    const Eigen::Vector3d w(0.4 * maxAngle * U(rng), maxAngle * U(rng), 0.2 * maxAngle * U(rng));  // pitch, yaw, roll
    const Eigen::Matrix3d R = hawor::SO3<double>::exp(w).matrix();
    const Eigen::Vector3d c = neck + Eigen::Vector3d(walk * t, 0, 0) + R * offset + noise * Eigen::Vector3d(N(rng), N(rng), N(rng));
    out.emplace_back(hawor::SO3<S>::fromMatrix(R.template cast<S>()), c.template cast<S>());
  }
  return out;
}

}  // namespace

TEMPLATE_TEST_CASE("fitNeckPivot recovers the pivot and the eye's offset of a turning head", "[slam][neck]", float, double) {
  using S = TestType;
  const Eigen::Vector3d neck(0.3, -1.2, 2.0), offset(0.0, -0.05, 0.08);
  for (std::uint32_t seed = 1; seed <= 4; ++seed) {
    const auto T = headOnNeck<S>(40, 0.8, 0.002, 0, neck, offset, seed);
    const auto p = hawor::fitNeckPivot(T, {}, 0, 40);
    INFO("seed " << seed << " spread " << p.spreadDeg << " rms " << p.rms);
    REQUIRE(p.solved);
    CHECK(p.frames == 40);
    CHECK((p.neck.template cast<double>() - neck).norm() < 0.004);
    CHECK((p.offset.template cast<double>() - offset).norm() < 0.004);
    CHECK(double(p.rms) == Approx(0.002 * std::sqrt(3.0)).epsilon(0.35));  // the noise, 3 axes
    CHECK(p.holds(S(0.2)));
    // The fitted model puts a frame left out of the fit where the truth does.
    const Eigen::Matrix3d R = hawor::SO3<double>::exp(Eigen::Vector3d(0.1, -0.5, 0.02)).matrix();
    const Eigen::Vector3d c = p.centre(hawor::SO3<S>::fromMatrix(R.template cast<S>())).template cast<double>();
    CHECK((c - (neck + R * offset)).norm() < 0.005);
  }
}

TEST_CASE("fitNeckPivot: walking, little rotation, few frames, unusable frames, NaN", "[slam][neck]") {
  const Eigen::Vector3d neck(0, 0, 0), offset(0, -0.05, 0.08);
  // Walking at 1.2 m/s (4 cm a frame): the fit is solved but the model does not hold.
  const auto walk = hawor::fitNeckPivot(headOnNeck<double>(40, 0.8, 0.002, 0.04, neck, offset, 5), {}, 0, 40);
  REQUIRE(walk.solved);
  CHECK_FALSE(walk.holds(0.2));
  // Rotations within ±3°: n and o are not separable.
  const auto still = hawor::fitNeckPivot(headOnNeck<double>(40, 0.05, 0.002, 0, neck, offset, 6), {}, 0, 40);
  CHECK_FALSE(still.solved);
  CHECK(still.spreadDeg < 10);
  // Five frames, or only five usable ones.
  auto T = headOnNeck<double>(40, 0.8, 0.002, 0, neck, offset, 7);
  CHECK_FALSE(hawor::fitNeckPivot(T, {}, 10, 15).solved);
  std::vector<char> usable(40, 0);
  for (int i = 0; i < 5; ++i) usable[static_cast<std::size_t>(3 * i)] = 1;
  CHECK_FALSE(hawor::fitNeckPivot(T, usable, 0, 40).solved);
  CHECK_THROWS_AS(hawor::fitNeckPivot(T, std::vector<char>(3, 1), 0, 40), hawor::Error);
  // A NaN pose is skipped.
  T[4] = hawor::SE3<double>(T[4].rotation(), Eigen::Vector3d(std::nan(""), 0, 0));
  const auto p = hawor::fitNeckPivot(T, {}, 0, 40);
  REQUIRE(p.solved);
  CHECK(p.frames == 39);
  CHECK((p.offset - offset).norm() < 0.004);
}
