// The one-call metric scale (scale/metric_scale.hpp): pairing sparse keyframe depths with depth
// maps (nearest pixel, bounds, hand flags) by hand-computed cases, the depth cue on exact metric
// depth, the hand cue (a hand held still while the camera moves), their fusion, and errors.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "hawor/scale/metric_scale.hpp"

namespace {

/// A 4×3 depth map with value 10·y + x + 1 (metres) at (x, y).
std::vector<float> rampMap() {
  std::vector<float> m(12);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) m[static_cast<size_t>(4 * y + x)] = float(10 * y + x + 1);
  return m;
}

}  // namespace

TEST_CASE("pairKeyframeDepths: nearest pixel, out-of-map pixels dropped, hand flags", "[scale][metric_scale]") {
  const std::vector<float> map = rampMap();
  const std::vector<std::uint8_t> mask = {0, 0, 0, 0, 0, 9, 0, 0, 0, 0, 0, 0};  // (1, 1) is a hand
  const std::vector<double> uv = {0.4, 0.4, 1.6, 0.51, 3.49, 2.2, -0.6, 1.0, 2.0, 2.6, 1.2, 0.9};
  const std::vector<double> d = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  const hawor::KeyframeDepthPairs<double> p = hawor::pairKeyframeDepths(uv.data(), d.data(), 6, map.data(), 4, 3, mask.data());
  // (0,0) → 1; (2,1) → 13; (3,2) → 24; (−1,1) dropped; (2,3) dropped; (1,1) → 12, a hand pixel.
  REQUIRE(p.slam.size() == 4);
  CHECK(p.slam == std::vector<double>{0.1, 0.2, 0.3, 0.6});
  CHECK(p.metric == std::vector<double>{1, 13, 24, 12});
  CHECK(p.masked == std::vector<char>{0, 0, 0, 1});
  const hawor::KeyframeDepthPairs<double> q = hawor::pairKeyframeDepths(uv.data(), d.data(), 6, map.data(), 4, 3);
  CHECK(q.masked == std::vector<char>{0, 0, 0, 0});
  const std::vector<double> bad = {0.5, NAN};
  CHECK_THROWS_WITH(hawor::pairKeyframeDepths(bad.data(), d.data(), 1, map.data(), 4, 3), Catch::Contains("not finite"));
  CHECK_THROWS_WITH(hawor::pairKeyframeDepths(uv.data(), d.data(), 1, map.data(), 0, 3), Catch::Contains("empty"));
}

TEST_CASE("estimateMetricScale: depth cue, hand cue, fusion", "[scale][metric_scale]") {
  const double alpha = 2.5;  // metres per map unit
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0.3, 0.9);
  std::normal_distribution<double> N(0, 1);
  // Depth cue: 6 keyframes of 80 points whose metric depth is exactly alpha·d (hand pixels wrong).
  std::vector<hawor::KeyframeDepthPairs<double>> kf(6);
  for (auto& k : kf) {
    for (int i = 0; i < 80; ++i) {
      const double D = U(rng);
      const bool hand = i % 10 == 0;
      k.slam.push_back(D / alpha);
      k.metric.push_back(hand ? 0.3 * D : D);
      k.masked.push_back(hand ? 1 : 0);
    }
  }
  // Hand cue: a camera moving 1 m/s sideways (map units = metres / alpha) and a hand held still.
  const int T = 120;
  std::vector<hawor::SE3<double>> poses;
  hawor::HandTrack<double> hand;
  for (int t = 0; t < T; ++t) {
    const Eigen::Vector3d c(t / 30.0, 0.02 * std::sin(t / 5.0), 0);
    const hawor::SE3<double> Twc(hawor::SO3<double>::exp(Eigen::Vector3d(0, 0.1 * std::sin(t / 20.0), 0)), c);
    poses.emplace_back(Twc.rotation(), Eigen::Vector3d(c / alpha));
    const Eigen::Vector3d noise(N(rng), N(rng), N(rng));  // a fitted hand's error, 2 mm
    hand.positionCam.push_back(Twc.inverse() * Eigen::Vector3d(0.5, 0.2, 0.6) + 0.002 * noise);
    hand.valid.push_back(1);
  }
  hawor::MetricScaleOptions<double> opt;
  opt.setFps(30);
  CHECK(opt.hands.hold.window == 15);
  CHECK(opt.depth.sampling == hawor::AdaSmSampling::SlamDepth);

  const auto depthOnly = hawor::estimateMetricScale<double>(kf, poses, {}, opt);
  REQUIRE(depthOnly.fused.ok());
  CHECK(depthOnly.fused.method == "depth");
  CHECK(depthOnly.depthRan);
  CHECK_FALSE(depthOnly.handsRan);
  CHECK(depthOnly.fused.scale == Approx(alpha).epsilon(1e-6));
  CHECK(depthOnly.depth.fitted == 6);

  const auto handsOnly = hawor::estimateMetricScale<double>({}, poses, {hand}, opt);
  REQUIRE(handsOnly.fused.ok());
  INFO("hand cue " << handsOnly.hands.method << " scale " << handsOnly.hands.scale << " confidence "
                   << handsOnly.hands.confidence);
  CHECK(handsOnly.fused.method == "hands");
  CHECK(handsOnly.hands.method == "holds");
  CHECK(handsOnly.fused.scale == Approx(alpha).epsilon(0.01));
  // The same as the cue called directly.
  CHECK(handsOnly.fused.scale == hawor::handAnchoredScale(poses, {hand}, opt.hands).scale);

  const auto both = hawor::estimateMetricScale<double>(kf, poses, {hand}, opt);
  REQUIRE(both.fused.ok());
  CHECK(both.fused.method == "fused");
  const auto f = hawor::fuseScales(depthOnly.fused.scale, depthOnly.depthConfidence, handsOnly.fused.scale,
                                   handsOnly.fused.confidence);
  CHECK(both.fused.scale == Approx(f.scale).epsilon(1e-12));

  const auto none = hawor::estimateMetricScale<double>({}, poses, {}, opt);
  CHECK_FALSE(none.fused.ok());
  std::vector<hawor::KeyframeDepthPairs<double>> broken(1);
  broken[0].slam = {1.0};
  CHECK_THROWS_WITH(hawor::estimateMetricScale<double>(broken, poses, {}, opt), Catch::Contains("differ in length"));
  hawor::HandTrack<double> shortTrack = hand;
  shortTrack.valid.pop_back();
  CHECK_THROWS(hawor::estimateMetricScale<double>({}, poses, {shortTrack}, opt));
  CHECK_THROWS_WITH(opt.setFps(0), Catch::Contains("fps"));
}
