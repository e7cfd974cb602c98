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
  // weighted least-squares still point over them, computed here as one dense problem over all the
  // unknowns (α and one still point p_w per window, no elimination): min Σ_w Σ_t |x_t + α c_t −
  // p_w|²_Λt with Λ_t built from the noise levels the cue reports.
  CHECK(r.restFrames == 46);
  const double sR = double(r.noiseAlongRay), sA = double(r.noiseAcrossRay);
  REQUIRE(sR > 0);
  REQUIRE(sA > 0);
  const int nw = 100 - 15 - 40 + 1, n = 1 + 3 * nw;
  Eigen::MatrixXd Nm = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  for (int w = 0; w < nw; ++w) {
    for (int t = 40 + w; t < 40 + w + 15; ++t) {
      const Eigen::Vector3d x = (slam[t].rotation() * hands[0].positionCam[t]).template cast<double>();
      const Eigen::Vector3d ct = slam[t].translation().template cast<double>(), ray = x.normalized();
      const Eigen::Matrix3d L = Eigen::Matrix3d::Identity() / (sA * sA) + (1 / (sR * sR) - 1 / (sA * sA)) * ray * ray.transpose();
      // residual r = x + α c − p_w = x + J [α; p_w], J = [c, −I]
      Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, n);
      J.col(0) = ct;
      J.block<3, 3>(0, 1 + 3 * w) = -Eigen::Matrix3d::Identity();
      Nm += J.transpose() * L * J;
      g -= J.transpose() * L * x;
    }
  }
  const double ref = Nm.ldlt().solve(g)(0);
  CHECK(double(r.scale) == Approx(ref).epsilon(std::is_same<S, float>::value ? 1e-4 : 1e-10));
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
  const hawor::FusedScale<double> f = hawor::fuseScales(2.0, 0.75, 2.2, 0.25);
  CHECK(f.method == "fused");
  CHECK(f.scale == Approx(std::pow(2.0, 0.75) * std::pow(2.2, 0.25)));  // geometric weighting
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

TEST_CASE("hand hold scale: depth-dominated hand noise is estimated along the ray and weighted down", "[scale]") {
  // A fitted hand's error lies mostly along its viewing ray (depth from hand size). Hand 0 holds
  // still for 2 s while the camera moves sideways; noise 8 mm along the ray, 1 mm across it. The
  // cue must report both levels, and its weighted fit must beat the unweighted least-squares
  // still point over the true hold windows (the estimator before the weighting), over 20 draws.
  const double alpha = 2.5, sRay = 0.008, sAcross = 0.001;
  std::vector<double> errW, errPlain, along, across;
  for (std::uint32_t seed = 1; seed <= 20; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> N(0, 1);
    std::vector<hawor::SE3<double>> slam;
    std::vector<hawor::HandTrack<double>> hands(1);
    for (int t = 0; t < 90; ++t) {
      const double u = t / 30.0;
      const Eigen::Vector3d cw(0.25 * u + 0.05 * std::sin(3 * u), 0.03 * std::sin(5 * u), 1.6);
      const hawor::SO3<double> R = hawor::SO3<double>::exp(Eigen::Vector3d(0.6, 0.15 * std::sin(2 * u), 0.05));
      const hawor::SE3<double> Twc(R, cw);
      const Eigen::Vector3d h = Twc.inverse() * Eigen::Vector3d(0.3, 0.9, 1.2), ray = h.normalized();
      const Eigen::Vector3d e1 = ray.unitOrthogonal(), e2 = ray.cross(e1);
      hands[0].positionCam.push_back(h + sRay * N(rng) * ray + sAcross * (N(rng) * e1 + N(rng) * e2));
      hands[0].valid.push_back(1);
      slam.emplace_back(R, Eigen::Vector3d(cw / alpha));
    }
    const hawor::HandScaleResult<double> r = hawor::handHoldScale(slam, hands);
    REQUIRE(r.ok());
    // Second differences of a still hand seen by a moving camera are the noise's plus the
    // rotation of the ray. A MAD over ~88 differences has a relative s.e. near 18 %, so each draw
    // is held to 50 % and the median over the draws to 12 %. (std::normal_distribution differs
    // between libstdc++ and libc++: the draws are not the same natively and in WASM.)
    CHECK(r.noiseAlongRay == Approx(sRay).epsilon(0.5));
    CHECK(r.noiseAcrossRay == Approx(sAcross).epsilon(0.5));
    along.push_back(r.noiseAlongRay), across.push_back(r.noiseAcrossRay);
    errW.push_back(std::abs(r.scale / alpha - 1));
    double num = 0, den = 0;
    for (int s0 = 0; s0 + 15 <= 90; ++s0) {
      Eigen::Vector3d xm = Eigen::Vector3d::Zero(), cm = Eigen::Vector3d::Zero();
      for (int t = s0; t < s0 + 15; ++t) xm += slam[t].rotation() * hands[0].positionCam[t], cm += slam[t].translation();
      xm /= 15, cm /= 15;
      for (int t = s0; t < s0 + 15; ++t) {
        const Eigen::Vector3d xt = slam[t].rotation() * hands[0].positionCam[t] - xm, ct = slam[t].translation() - cm;
        num += xt.dot(ct), den += ct.squaredNorm();
      }
    }
    errPlain.push_back(std::abs(-num / den / alpha - 1));
  }
  std::sort(along.begin(), along.end());
  std::sort(across.begin(), across.end());
  INFO("noise along the ray " << along.front() << " .. " << along.back() << ", across " << across.front() << " .. " << across.back());
  CHECK(along[10] == Approx(sRay).epsilon(0.12));
  CHECK(across[10] == Approx(sAcross).epsilon(0.12));
  std::sort(errW.begin(), errW.end());
  std::sort(errPlain.begin(), errPlain.end());
  INFO("median error weighted " << errW[10] << ", unweighted " << errPlain[10]);
  CHECK(errW[10] < 0.5 * errPlain[10]);
  CHECK(errW[10] < 0.005);
}

TEST_CASE("hand hold scale: a hand carried with the head does not outvote a real hold", "[scale]") {
  // The camera translates without turning. Hand 0 is carried (fixed in the camera frame) for 100
  // frames: still in the world only if the camera does not move (α → 0). Hand 1 holds still in
  // the room for the last 50 frames. The carried hand's windows are left out (still in the camera
  // frame), so the scan's best mode alone is the hold.
  const double alpha = 0.8;
  std::mt19937 rng(21);
  std::normal_distribution<double> N(0, 1);
  std::vector<hawor::SE3<double>> slam;
  std::vector<hawor::HandTrack<double>> hands(2);
  const hawor::SO3<double> R = hawor::SO3<double>::exp(Eigen::Vector3d(0.5, 0.1, 0.0));
  for (int t = 0; t < 150; ++t) {
    const double u = t / 30.0;
    const Eigen::Vector3d cw(0.3 * u, 0.05 * std::sin(2 * u), 1.6 + 0.02 * std::sin(4 * u));
    const hawor::SE3<double> Twc(R, cw);
    slam.emplace_back(R, Eigen::Vector3d(cw / alpha));
    const bool carried = t < 100, held = t >= 100;
    hands[0].positionCam.push_back(Eigen::Vector3d(0.1, 0.2, 0.4) + 0.002 * Eigen::Vector3d(N(rng), N(rng), N(rng)));
    hands[0].valid.push_back(carried ? 1 : 0);
    hands[1].positionCam.push_back(Twc.inverse() * Eigen::Vector3d(1.4, 0.9, 1.0) + 0.002 * Eigen::Vector3d(N(rng), N(rng), N(rng)));
    hands[1].valid.push_back(held ? 1 : 0);
  }
  hawor::HandHoldOptions<double> one;
  one.maxModes = 1;  // the best mode only
  const hawor::HandScaleResult<double> first = hawor::handHoldScale(slam, hands, one);
  INFO("best mode alone: scale " << first.scale << ", rel. s.e. " << first.relativeStdError << ", carried windows " << first.carriedWindows);
  CHECK(first.carriedWindows >= 80);  // of the carried hand's 86
  REQUIRE(first.ok());
  CHECK(std::abs(first.scale / alpha - 1) < 0.02);
  const hawor::HandScaleResult<double> r = hawor::handHoldScale(slam, hands);
  REQUIRE(r.ok());
  CHECK(std::abs(r.scale / alpha - 1) < 0.02);
  CHECK(r.relativeStdError < 0.05);
  CHECK(r.restFrames >= 30);
  const hawor::HandScaleResult<double> a = hawor::handAnchoredScale(slam, hands);
  CHECK(a.method == "holds");
  CHECK(std::abs(a.scale / alpha - 1) < 0.02);
  hawor::HandHoldOptions<double> bad;
  bad.maxModes = 0;
  CHECK_THROWS_AS(hawor::handHoldScale(slam, hands, bad), hawor::Error);
  bad = {};
  bad.maxRelativeError = std::nan("");
  CHECK_THROWS_AS(hawor::handHoldScale(slam, hands, bad), hawor::Error);
}
