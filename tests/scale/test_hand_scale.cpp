// Hand-anchored metric scale (scale/hand_scale.hpp and its two cues) on generated motion: a
// walking camera with head bob, hands that move smoothly in the world (resting, reaching), the
// SLAM trajectory at an arbitrary scale, camera-frame hand positions with noise; the hold cue
// against an exact hold and a brute-force scan of its objective; fusion; degenerate cases.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "hawor/scale/fuse_scale.hpp"
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
    CHECK(r.method == "holds");
    CHECK(r.restFrames > 20);
  }
}

TEST_CASE("hand-anchored scale: the hold cue answers, the smoothness cue alone is close", "[scale]") {
  for (double alpha : {0.05, 1.0, 7.0}) {
    const Scene s = makeScene(300, 1.0, 0.03, alpha, 0.003, 3);
    const hawor::HandScaleResult<double> h = hawor::handHoldScale(s.slam, s.hands);
    REQUIRE(h.ok());
    CHECK(h.method == "holds");
    CHECK(std::abs(h.scale / alpha - 1) < 0.01);  // hand 0 rests for 2 s while the camera walks 2 m
    CHECK(h.relativeStdError < 0.01);
    const hawor::HandScaleResult<double> m = hawor::handSmoothnessScale(s.slam, s.hands);
    REQUIRE(m.ok());
    CHECK(m.method == "smoothness");
    CHECK(std::abs(m.scale / alpha - 1) < 0.05);
  }
}

TEMPLATE_TEST_CASE("hand hold scale: a near-noiseless hold gives the direct least-squares still point", "[scale]", float, double) {
  using S = TestType;
  // A camera that moves on a curve; hand 0 still in the world for frames [40, 100), moving
  // elsewhere; hand 1 always moving. Tiny noise so the noise estimate is positive.
  const double alpha = 0.37;
  std::mt19937 rng(9);
  std::normal_distribution<double> N(0, 1);
  std::vector<hawor::SE3<S>> slam;
  std::vector<hawor::HandTrack<S>> hands(2);
  std::vector<Eigen::Vector3d> c, x0;
  for (int t = 0; t < 160; ++t) {
    const double u = t / 30.0;
    const Eigen::Vector3d cw(0.4 * u, 0.1 * std::sin(1.3 * u), 1.5 + 0.02 * std::sin(9 * u));
    const hawor::SO3<double> R = hawor::SO3<double>::exp(Eigen::Vector3d(0.2 * std::sin(u), 0.3 * u, 0.1));
    const Eigen::Vector3d p0 = (t >= 40 && t < 100) ? Eigen::Vector3d(0.5, 0.2, 0.8)
                                                     : Eigen::Vector3d(0.5 + 0.3 * std::sin(2 * u), 0.2 + 0.1 * u, 0.8);
    const Eigen::Vector3d p1(cw.x() + 0.3 * std::cos(3 * u), cw.y() - 0.2, 1.0 + 0.1 * std::sin(5 * u));
    const hawor::SE3<double> Twc(R, cw);
    slam.emplace_back(hawor::SO3<S>::exp(R.log().template cast<S>()), hawor::Vec3<S>((cw / alpha).template cast<S>()));
    const Eigen::Vector3d h0 = Twc.inverse() * p0 + 1e-5 * Eigen::Vector3d(N(rng), N(rng), N(rng));
    const Eigen::Vector3d h1 = Twc.inverse() * p1;
    hands[0].positionCam.push_back(h0.template cast<S>());
    hands[1].positionCam.push_back(h1.template cast<S>());
    hands[0].valid.push_back(1), hands[1].valid.push_back(1);
  }
  const hawor::HandScaleResult<S> r = hawor::handHoldScale(slam, hands);
  REQUIRE(r.ok());
  CHECK(double(r.scale) == Approx(alpha).epsilon(std::is_same<S, float>::value ? 1e-3 : 1e-4));
  // The still windows are exactly the 60 − 15 + 1 = 46 windows inside the hold, and α is the
  // least-squares still point over them, computed here directly: min over (α, p_w) of
  // Σ_w Σ_t |R_t h_t + α c_t − p_w|².
  CHECK(r.restFrames == 46);
  double num = 0, den = 0;
  for (int s0 = 40; s0 + 15 <= 100; ++s0) {
    Eigen::Vector3d xm = Eigen::Vector3d::Zero(), cm = Eigen::Vector3d::Zero();
    for (int t = s0; t < s0 + 15; ++t) {
      xm += (slam[t].rotation() * hands[0].positionCam[t]).template cast<double>();
      cm += slam[t].translation().template cast<double>();
    }
    xm /= 15, cm /= 15;
    for (int t = s0; t < s0 + 15; ++t) {
      const Eigen::Vector3d xt = (slam[t].rotation() * hands[0].positionCam[t]).template cast<double>() - xm;
      const Eigen::Vector3d ct = slam[t].translation().template cast<double>() - cm;
      num += xt.dot(ct), den += ct.squaredNorm();
    }
  }
  CHECK(double(r.scale) == Approx(-num / den).epsilon(std::is_same<S, float>::value ? 1e-4 : 1e-10));
  CHECK(r.confidence > 0.9);
}

TEST_CASE("hand-anchored scale: no hold falls back to smoothness with a capped confidence", "[scale]") {
  Scene s = makeScene(300, 1.0, 0.03, 2.0, 0.003, 4);
  // Hand 0 never rests: drop its first 2.5 s.
  for (int t = 0; t < 75; ++t) s.hands[0].valid[static_cast<std::size_t>(t)] = 0;
  const hawor::HandScaleResult<double> r = hawor::handAnchoredScale(s.slam, s.hands);
  REQUIRE(r.ok());
  CHECK(r.method == "smoothness");
  CHECK(r.confidence <= hawor::HandScaleOptions<double>().smoothnessConfidenceCap);
  CHECK(r.confidence <= 0.05);
  CHECK(std::abs(r.scale / 2.0 - 1) < 0.1);
}

TEST_CASE("scale fusion: one cue, both cues in log space, none", "[scale]") {
  const double nan = std::nan("");
  const hawor::FusedScale<double> d = hawor::fuseScales(2.0, 0.8, nan, 0.0);
  CHECK(d.method == "depth");
  CHECK(d.scale == 2.0);
  const hawor::FusedScale<double> h = hawor::fuseScales(nan, 0.0, 3.0, 0.4);
  CHECK(h.method == "hands");
  CHECK(h.scale == 3.0);
  const hawor::FusedScale<double> f = hawor::fuseScales(2.0, 0.75, 8.0, 0.25);
  CHECK(f.method == "fused");
  CHECK(f.scale == Approx(std::pow(2.0, 0.75) * std::pow(8.0, 0.25)));  // geometric weighting
  CHECK(f.confidence == 0.75);
  CHECK_FALSE(hawor::fuseScales(nan, 1.0, -1.0, 1.0).ok());
  hawor::SequenceScale<double> seq;
  CHECK(hawor::depthScaleConfidence(seq) == 0.0);  // no scale: no confidence
  seq.scale = 1.0, seq.keyframes = 10, seq.fitted = 5, seq.relativeSpread = 0.05;
  CHECK(hawor::depthScaleConfidence(seq) == Approx(0.25));
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

TEST_CASE("hand hold scale: noise-free input on a straight camera path still gives the hold", "[scale]") {
  // Every second difference of x is 0 here (a still hand, a camera on a line at constant speed):
  // the noise estimate is 0 and only its floor (HandHoldOptions::minNoise) keeps the cue alive.
  const double alpha = 0.52;
  std::vector<hawor::SE3<double>> slam;
  std::vector<hawor::HandTrack<double>> hands(1);
  const Eigen::Vector3d p(0.3, 0.4, 0.9);
  for (int t = 0; t < 90; ++t) {
    const Eigen::Vector3d cw(0.01 * t, 0.002 * t, 1.5);
    const hawor::SE3<double> Twc(hawor::SO3<double>::exp(Eigen::Vector3d(0.1, 0.2, 0.05)), cw);
    slam.emplace_back(hawor::SO3<double>::exp(Eigen::Vector3d(0.1, 0.2, 0.05)), hawor::Vec3<double>(cw / alpha));
    hands[0].positionCam.push_back(Twc.inverse() * p);
    hands[0].valid.push_back(1);
  }
  const hawor::HandScaleResult<double> r = hawor::handAnchoredScale(slam, hands);
  REQUIRE(r.ok());
  CHECK(r.method == "holds");
  CHECK(r.scale == Approx(alpha).epsilon(1e-3));
  hawor::HandHoldOptions<double> bad;
  bad.minNoise = 0;
  CHECK_THROWS_AS(hawor::handHoldScale(slam, hands, bad), hawor::Error);
}
