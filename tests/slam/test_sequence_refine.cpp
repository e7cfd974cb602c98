// refineSequence (slam/sequence_refine.hpp) on a generated sequence with known truth: recovery of
// every pose from perturbed ones (Sim(3)-aligned against the truth), frames with a guessed
// position resected, drifting tracks cut at their jump, the translation uncertainty against a
// dense brute-force information matrix from central differences, an ill-conditioned frame left
// out, and bad input.
#include <catch2/catch.hpp>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <vector>

#include "estimation_test_utils.hpp"
#include "hawor/eval/camera_metrics.hpp"
#include "hawor/slam/sequence_refine.hpp"

namespace seqref_test {

using est_test::Rng;

struct SeqScene {
  std::vector<hawor::SE3<double>> truth;                          // T_w_c
  std::vector<Eigen::Vector3d> points;                            // world
  std::vector<std::vector<hawor::TrackObservation<double>>> obs;  // per frame
  std::vector<char> badTrack;                                     // jumps 6 px half-way
  std::vector<int> jumpFrame;
};

/// 60 frames along an arc (0.6 m, the view turning by 20°) before 400 points 2-6 m away, seen
/// with 0.3 px noise; 10 % of the tracks jump by 6 px half-way through their life (a KLT track
/// that slid along an edge). With `narrowLast`, one more frame sees only 16 points in a 24 px
/// patch of the image.
SeqScene makeScene(Rng& rng, bool narrowLast) {
  SeqScene s;
  const int n = 60;
  const hawor::PinholeCamera<double> cam = est_test::vgaCamera<double>();
  for (int f = 0; f < n; ++f) {
    const double a = 0.35 * f / (n - 1) - 0.175;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                              Eigen::AngleAxisd(0.05 * std::sin(0.2 * f), Eigen::Vector3d::UnitX()).toRotationMatrix();
    const Eigen::Vector3d c(0.6 * f / (n - 1), 0.02 * std::sin(0.3 * f), 0.1 * std::sin(0.05 * f));
    s.truth.push_back(hawor::SE3<double>(hawor::SO3<double>::fromMatrix(hawor::Mat3<double>(R)), hawor::Vec3<double>(c)));
  }
  for (int i = 0; i < 400; ++i) s.points.push_back(rng.uniform3(-2.5, 3.0, -1.5, 1.5, 2.0, 6.0));
  s.badTrack.resize(s.points.size());
  s.jumpFrame.assign(s.points.size(), -1);
  for (std::size_t i = 0; i < s.points.size(); ++i) s.badTrack[i] = rng.uniform(0, 1) < 0.1 ? 1 : 0;
  s.obs.resize(n);
  std::vector<int> firstSeen(s.points.size(), -1), lastSeen(s.points.size(), -1);
  for (int f = 0; f < n; ++f) {
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      const Eigen::Vector3d Xc = s.truth[static_cast<std::size_t>(f)].inverse() * hawor::Vec3<double>(s.points[i]);
      if (Xc(2) < 0.5) continue;
      const hawor::Vec2<double> q = cam.project(hawor::Vec3<double>(Xc));
      if (q(0) < 5 || q(1) < 5 || q(0) > 634 || q(1) > 474) continue;
      if (firstSeen[i] < 0) firstSeen[i] = f;
      lastSeen[i] = f;
    }
  }
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    if (s.badTrack[i] && firstSeen[i] >= 0) s.jumpFrame[i] = (firstSeen[i] + lastSeen[i]) / 2;
  }
  for (int f = 0; f < n; ++f) {
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      if (firstSeen[i] < 0 || f < firstSeen[i] || f > lastSeen[i]) continue;
      const Eigen::Vector3d Xc = s.truth[static_cast<std::size_t>(f)].inverse() * hawor::Vec3<double>(s.points[i]);
      hawor::Vec2<double> q = cam.project(hawor::Vec3<double>(Xc));
      const Eigen::Vector2d e = 0.3 * rng.normal2();
      q += hawor::Vec2<double>(e);
      if (s.badTrack[i] && f >= s.jumpFrame[i]) q(1) += 6.0;
      s.obs[static_cast<std::size_t>(f)].push_back({static_cast<int>(i), q});
    }
  }
  if (narrowLast) {
    // A frame that sees 16 points of one small patch (the points placed for it).
    const hawor::SE3<double> T = s.truth.back();
    s.truth.push_back(T);
    s.obs.emplace_back();
    for (int k = 0; k < 16; ++k) {
      const hawor::Vec2<double> q(300 + 6 * (k % 4), 220 + 6 * (k / 4));
      const double d = 4.0;
      const Eigen::Vector3d Xc((q(0) - cam.cx) / cam.fx * d, (q(1) - cam.cy) / cam.fy * d, d);
      const int id = static_cast<int>(s.points.size());
      s.points.push_back(T * hawor::Vec3<double>(Xc));
      s.badTrack.push_back(0);
      s.jumpFrame.push_back(-1);
      s.obs.back().push_back({id, q});
      // Seen also by the previous frames (so that it is triangulated).
      for (int f = static_cast<int>(s.truth.size()) - 12; f < static_cast<int>(s.truth.size()) - 1; ++f) {
        const Eigen::Vector3d Xf = s.truth[static_cast<std::size_t>(f)].inverse() * hawor::Vec3<double>(s.points.back());
        s.obs[static_cast<std::size_t>(f)].push_back({id, cam.project(hawor::Vec3<double>(Xf))});
      }
    }
  }
  return s;
}

double ate(const std::vector<hawor::SE3<double>>& truth, const std::vector<hawor::SE3<double>>& est) {
  std::vector<hawor::Vec3<double>> g, e;
  for (std::size_t i = 0; i < truth.size(); ++i) g.push_back(truth[i].translation()), e.push_back(est[i].translation());
  return hawor::ateSim3(hawor::cameraPositions(g), hawor::cameraPositions(e)) / 1000.0;
}

}  // namespace seqref_test

using namespace seqref_test;

TEST_CASE("refineSequence recovers every pose from perturbed ones and resects guessed frames", "[slam][sequence]") {
  Rng rng(41);
  const SeqScene s = makeScene(rng, false);
  const int n = static_cast<int>(s.truth.size());
  const hawor::PinholeCamera<double> cam = est_test::vgaCamera<double>();
  std::vector<hawor::SE3<double>> init;
  std::vector<char> state(static_cast<std::size_t>(n), 2);
  for (int f = 0; f < n; ++f) {
    const hawor::SE3<double>& T = s.truth[static_cast<std::size_t>(f)];
    const Eigen::Matrix3d dR = rng.rotation(0.002, 0.006);
    const Eigen::Vector3d dt = rng.scaledUnit(0.01, 0.03);
    init.push_back(hawor::SE3<double>(hawor::SO3<double>::fromMatrix(hawor::Mat3<double>(T.rotationMatrix() * dR)),
                                      hawor::Vec3<double>(T.translation() + dt)));
  }
  // Frames 0-7: a rotation from the rays (near exact) and a held position (that of frame 8).
  for (int f = 0; f < 8; ++f) {
    state[static_cast<std::size_t>(f)] = 1;
    init[static_cast<std::size_t>(f)] = hawor::SE3<double>(s.truth[static_cast<std::size_t>(f)].rotation(), s.truth[8].translation());
  }
  // Frame 40 keeps 10 observations: too few to be adjusted or resected; its pose is carried.
  std::vector<std::vector<hawor::TrackObservation<double>>> obs = s.obs;
  obs[40].resize(10);
  const double before = ate(s.truth, init);
  hawor::SequenceRefineOptions<double> opt;
  opt.maxAdjustedFrames = 25;  // every other frame in the adjustment, the rest motion-only
  const hawor::SequenceRefineResult<double> r = hawor::refineSequence(cam, init, state, obs, opt);
  CHECK_FALSE(r.adjusted[40]);
  CHECK(r.carried[40]);
  // Carried with frame 39's correction: the relative pose 39 → 40 is the input's.
  const hawor::SE3<double> relIn = init[39].inverse() * init[40], relOut = r.poses[39].inverse() * r.poses[40];
  CHECK((relIn.translation() - relOut.translation()).norm() < 1e-9);
  int adjusted = 0;
  std::string missing;
  for (int f = 0; f < n; ++f) {
    adjusted += r.adjusted[static_cast<std::size_t>(f)];
    if (!r.adjusted[static_cast<std::size_t>(f)] && f != 40) missing += " " + std::to_string(f);
  }
  INFO("not adjusted:" << missing);
  CHECK(adjusted == n - 1);
  const double after = ate(s.truth, r.poses);
  INFO("ATE before " << before << " m, after " << after << " m; rms " << r.finalRmsPx << " px");
  CHECK(after < 0.002);
  CHECK(after < before / 10);
  CHECK(r.finalRmsPx < 0.5);
  // The guessed frames were resected: their positions follow the truth, not the held one.
  std::vector<hawor::SE3<double>> headT(s.truth.begin(), s.truth.begin() + 8), headE(r.poses.begin(), r.poses.begin() + 8);
  std::vector<hawor::Vec3<double>> g, e;
  for (int f = 0; f < n; ++f) g.push_back(s.truth[static_cast<std::size_t>(f)].translation()), e.push_back(r.poses[static_cast<std::size_t>(f)].translation());
  double scale = 0;
  hawor::ateSim3(hawor::cameraPositions(g), hawor::cameraPositions(e), &scale);
  const double firstStep = (r.poses[0].translation() - r.poses[7].translation()).norm() * scale;
  CHECK(firstStep == Approx((s.truth[0].translation() - s.truth[7].translation()).norm()).epsilon(0.05));
  // The jumped tracks keep no observation on both sides of their jump.
  int mixed = 0, badPoints = 0;
  for (std::size_t j = 0; j < r.points.size(); ++j) {
    const int t = r.pointTrack[j];
    if (!s.badTrack[static_cast<std::size_t>(t)]) continue;
    ++badPoints;
    bool pre = false, post = false;
    for (const auto& o : r.pointObs[j]) (o.first < s.jumpFrame[static_cast<std::size_t>(t)] ? pre : post) = true;
    mixed += pre && post ? 1 : 0;
  }
  INFO(badPoints << " jumped tracks triangulated");
  CHECK(mixed == 0);
}

TEST_CASE("refineSequence: translation uncertainty against a dense brute-force information matrix", "[slam][sequence]") {
  Rng rng(7);
  const SeqScene s = makeScene(rng, true);
  const int n = static_cast<int>(s.truth.size());
  const hawor::PinholeCamera<double> cam = est_test::vgaCamera<double>();
  std::vector<char> state(static_cast<std::size_t>(n), 2);
  hawor::SequenceRefineOptions<double> opt;
  const hawor::SequenceRefineResult<double> r = hawor::refineSequence(cam, s.truth, state, s.obs, opt);
  // The last frame sees 16 points of a 24 px patch: left out for its uncertain translation.
  CHECK(r.illConditioned >= 1);
  CHECK_FALSE(r.adjusted[static_cast<std::size_t>(n - 1)]);
  CHECK(r.translationStd[static_cast<std::size_t>(n - 1)] > 8 * r.translationStd[30]);
  // Brute force for frames 10, 30, the last: the residuals' Jacobian w.r.t. T·exp(δ) by central
  // differences, H = JᵀJ (σ = 1 px), the full 6×6 covariance H⁻¹, its translation block's
  // largest eigenvalue.
  for (int f : {10, 30, n - 1}) {
    std::vector<Eigen::Vector3d> X;
    std::vector<Eigen::Vector2d> uv;
    for (std::size_t j = 0; j < r.points.size(); ++j) {
      for (const auto& o : r.pointObs[j]) {
        if (o.first == f) X.push_back(Eigen::Vector3d(r.points[j])), uv.push_back(Eigen::Vector2d(o.second));
      }
    }
    REQUIRE(X.size() >= 10);
    const hawor::SE3<double> T = r.poses[static_cast<std::size_t>(f)];
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    for (std::size_t i = 0; i < X.size(); ++i) {
      auto res = [&](const Eigen::Matrix<double, 6, 1>& d) {
        const hawor::SE3<double> Td = T * hawor::SE3<double>::exp(hawor::Vec6<double>(d));
        const Eigen::Vector3d Xc = Td.inverse() * hawor::Vec3<double>(X[i]);
        return Eigen::Vector2d(cam.fx * Xc(0) / Xc(2) + cam.cx, cam.fy * Xc(1) / Xc(2) + cam.cy);
      };
      const Eigen::Matrix<double, 2, 6> J = est_test::numericJacobian<2, 6>(res, Eigen::Matrix<double, 6, 1>::Zero().eval(), 1e-7);
      H += J.transpose() * J;
    }
    const Eigen::Matrix<double, 6, 6> C = H.inverse();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C.topLeftCorner<3, 3>().eval());
    const double sigma = std::sqrt(es.eigenvalues()(2));
    INFO("frame " << f);
    CHECK(r.translationStd[static_cast<std::size_t>(f)] == Approx(sigma).epsilon(1e-4));
  }
}

TEST_CASE("refineSequence: bad input", "[slam][sequence]") {
  const hawor::PinholeCamera<double> cam = est_test::vgaCamera<double>();
  std::vector<hawor::SE3<double>> poses(3);
  std::vector<std::vector<hawor::TrackObservation<double>>> obs(3);
  CHECK_THROWS_AS(hawor::refineSequence(cam, poses, std::vector<char>(2, 2), obs), hawor::Error);
  hawor::SequenceRefineOptions<double> bad;
  bad.rounds = 0;
  CHECK_THROWS_AS(hawor::refineSequence(cam, poses, std::vector<char>(3, 2), obs, bad), hawor::Error);
  obs[1].push_back({0, hawor::Vec2<double>(std::nan(""), 1.0)});
  CHECK_THROWS_AS(hawor::refineSequence(cam, poses, std::vector<char>(3, 2), obs), hawor::Error);
  obs[1].clear();
  obs[1].push_back({-1, hawor::Vec2<double>(1.0, 1.0)});
  CHECK_THROWS_AS(hawor::refineSequence(cam, poses, std::vector<char>(3, 2), obs), hawor::Error);
  // Nothing to triangulate: the poses come back unchanged, nothing adjusted.
  obs[1].clear();
  const auto r = hawor::refineSequence(cam, poses, std::vector<char>(3, 2), obs);
  CHECK(r.points.empty());
  REQUIRE(r.adjusted.size() == 3);
  REQUIRE(r.carried.size() == 3);
  REQUIRE(r.translationStd.size() == 3);
  for (char a : r.adjusted) CHECK(a == 0);
  for (char a : r.carried) CHECK(a == 0);
}

TEST_CASE("refineSequence<float> runs the same pipeline", "[slam][sequence]") {
  Rng rng(5);
  const SeqScene s = makeScene(rng, false);
  const hawor::PinholeCamera<float> cam = est_test::vgaCamera<float>();
  std::vector<hawor::SE3<float>> init;
  std::vector<std::vector<hawor::TrackObservation<float>>> obs(s.obs.size());
  for (const auto& T : s.truth) init.push_back(T.cast<float>());
  for (std::size_t f = 0; f < s.obs.size(); ++f) {
    for (const auto& o : s.obs[f]) obs[f].push_back({o.track, o.uv.cast<float>()});
  }
  const auto r = hawor::refineSequence(cam, init, std::vector<char>(init.size(), 2), obs);
  int adjusted = 0;
  for (char a : r.adjusted) adjusted += a;
  CHECK(adjusted >= static_cast<int>(init.size()) - 2);
  CHECK(r.finalRmsPx < 0.6f);
}

namespace seqref_test {

/// A head that stands and looks around: 90 frames, the view swinging ±60° in yaw and ±10° in
/// pitch, the eye 9 cm in front of a fixed neck point (c = 0.09·z, the head model exactly), 600
/// points 2.5–5 m away all around; with `walk`, the neck also moves 0.8 m along x (not a head).
SeqScene makeHeadScene(Rng& rng, bool walk) {
  SeqScene s;
  const int n = 90;
  const double pi = est_test::pi();
  const hawor::PinholeCamera<double> cam = est_test::vgaCamera<double>();
  for (int f = 0; f < n; ++f) {
    const double yaw = pi / 3 * std::sin(2 * pi * f / n), pitch = pi / 18 * std::sin(4 * pi * f / n);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                              Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()).toRotationMatrix();
    Eigen::Vector3d c = 0.09 * R.col(2);
    if (walk) c.x() += 0.8 * f / (n - 1);
    s.truth.push_back(hawor::SE3<double>(hawor::SO3<double>::fromMatrix(hawor::Mat3<double>(R)), hawor::Vec3<double>(c)));
  }
  for (int i = 0; i < 600; ++i) {
    const double az = rng.uniform(-1.75, 1.75), d = rng.uniform(2.5, 5.0);
    s.points.push_back(Eigen::Vector3d(d * std::sin(az), rng.uniform(-1.0, 1.0), d * std::cos(az)));
  }
  s.badTrack.assign(s.points.size(), 0);
  s.jumpFrame.assign(s.points.size(), -1);
  s.obs.resize(n);
  for (int f = 0; f < n; ++f) {
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      const Eigen::Vector3d Xc = s.truth[static_cast<std::size_t>(f)].inverse() * hawor::Vec3<double>(s.points[i]);
      if (Xc(2) < 0.5) continue;
      hawor::Vec2<double> q = cam.project(hawor::Vec3<double>(Xc));
      if (q(0) < 5 || q(1) < 5 || q(0) > 634 || q(1) > 474) continue;
      q += hawor::Vec2<double>(Eigen::Vector2d(0.3 * rng.normal2()));
      s.obs[static_cast<std::size_t>(f)].push_back({static_cast<int>(i), q});
    }
  }
  return s;
}

std::vector<hawor::SE3<double>> perturbed(Rng& rng, const std::vector<hawor::SE3<double>>& truth) {
  std::vector<hawor::SE3<double>> init;
  for (const auto& T : truth) {
    const Eigen::Matrix3d dR = rng.rotation(0.002, 0.006);
    const Eigen::Vector3d dt = rng.scaledUnit(0.005, 0.015);
    init.push_back(hawor::SE3<double>(hawor::SO3<double>::fromMatrix(hawor::Mat3<double>(T.rotationMatrix() * dR)),
                                      hawor::Vec3<double>(T.translation() + dt)));
  }
  return init;
}

}  // namespace seqref_test

TEST_CASE("refineSequence: the head prior on a standing head, none on a walk", "[slam][sequence]") {
  const hawor::PinholeCamera<double> cam = est_test::vgaCamera<double>();
  for (bool walk : {false, true}) {
    Rng rng(walk ? 12 : 11);
    const SeqScene s = makeHeadScene(rng, walk);
    const std::vector<hawor::SE3<double>> init = perturbed(rng, s.truth);
    const std::vector<char> state(s.truth.size(), 2);
    hawor::SequenceRefineOptions<double> on, off;
    off.headPrior = false;
    const auto a = hawor::refineSequence(cam, init, state, s.obs, on);
    const auto b = hawor::refineSequence(cam, init, state, s.obs, off);
    const double ateOn = ate(s.truth, a.poses), ateOff = ate(s.truth, b.poses), before = ate(s.truth, init);
    INFO((walk ? "walk" : "head") << ": ATE before " << before << " m, with the prior " << ateOn << " m (" << a.headPriorRounds
                                  << " rounds, fit rms " << a.headPriorRms << "), without " << ateOff << " m");
    CHECK(b.headPriorRounds == 0);
    if (walk) {
      // Not a head: no prior, the same result.
      CHECK(a.headPriorRounds == 0);
      for (std::size_t f = 0; f < s.truth.size(); ++f) CHECK((a.poses[f].translation() - b.poses[f].translation()).norm() == 0.0);
    } else {
      // The model holds: the prior once the poses show it (the first round's input, centimetres
      // off on a 9 cm radius, may fail the motion test), and it does not pull them off the truth.
      CHECK(a.headPriorRounds >= 1);
      CHECK(a.headPriorRms > 0);
      CHECK(ateOn < 0.002);
      CHECK(ateOn <= 1.2 * ateOff + 1e-4);
    }
    CHECK(ateOff < before / 3);
  }
  hawor::SequenceRefineOptions<double> bad;
  bad.headPriorSigma = 0;
  CHECK_THROWS_AS(hawor::refineSequence(cam, std::vector<hawor::SE3<double>>(3), std::vector<char>(3, 2),
                                        std::vector<std::vector<hawor::TrackObservation<double>>>(3), bad),
                  hawor::Error);
}
