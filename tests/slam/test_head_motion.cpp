// The head model of slam/head_motion.hpp: its least-squares fit against a dense normal-equation
// solve of the same 12 unknowns, the gap filling on a standing head turning about a vertical neck
// (the eye 9 cm in front of it) against the truth, and the gates that keep it off a walk and off
// gaps without a turn.
#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "estimation_test_utils.hpp"
#include "hawor/slam/head_motion.hpp"

namespace head_test {

using est_test::Rng;

/// Camera-to-world pose looking along yaw/pitch (world z up; camera x right, y down, z forward).
hawor::SE3<double> lookPose(double yaw, double pitch, const Eigen::Vector3d& c) {
  const Eigen::Vector3d f(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch));
  const Eigen::Vector3d right = f.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = f.cross(right);
  Eigen::Matrix3d R;
  R.col(0) = right;
  R.col(1) = down;
  R.col(2) = f;
  return hawor::SE3<double>(hawor::SO3<double>::fromMatrix(hawor::Mat3<double>(R)), hawor::Vec3<double>(c));
}

/// A standing head: yaw sweeps of ±70° with fixations, pitch within −30..5°; the eye 9 cm in
/// front of a vertical neck axis at `neck` (it moves with the yaw only: the synthetic presets'
/// head) or, with `nod`, of a neck joint it pivots about in both yaw and pitch (c = n + r·z), plus
/// 1 mm noise.
std::vector<hawor::SE3<double>> standingTurns(Rng& rng, int n, const Eigen::Vector3d& neck, bool nod = false) {
  std::vector<hawor::SE3<double>> T;
  for (int i = 0; i < n; ++i) {
    const double t = i / 30.0;
    const double yaw = 1.2 * std::sin(0.9 * t) + 0.3 * std::sin(2.3 * t);
    const double pitch = -0.22 + 0.2 * std::sin(0.7 * t + 1.0);
    const Eigen::Vector3d h(std::cos(yaw), std::sin(yaw), 0.0);
    const Eigen::Vector3d z(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch));
    T.push_back(lookPose(yaw, pitch, neck + 0.09 * (nod ? z : h) + rng.scaledUnit(0.0, 0.001)));
  }
  return T;
}

}  // namespace head_test

using namespace head_test;

TEST_CASE("fitHeadModel against the dense least-squares solution", "[slam][head]") {
  Rng rng(3);
  const std::vector<hawor::SE3<double>> T = standingTurns(rng, 150, Eigen::Vector3d(1.0, -2.0, 1.6));
  std::vector<int> idx;
  for (int i = 0; i < 150; i += 2) idx.push_back(i);
  hawor::HeadModelOptions<double> opt;
  opt.ridge = 0;  // plain least squares, the reference's problem
  const hawor::HeadModelFit<double> fit = hawor::fitHeadModel(T, idx, opt);
  REQUIRE(fit.ok);
  // Reference: all 12 unknowns (n, M row-major) in one dense system, solved by QR.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(3 * static_cast<Eigen::Index>(idx.size()), 12);
  Eigen::VectorXd b(3 * static_cast<Eigen::Index>(idx.size()));
  for (std::size_t r = 0; r < idx.size(); ++r) {
    const Eigen::Vector3d z = T[static_cast<std::size_t>(idx[r])].rotationMatrix().col(2);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Index row = 3 * static_cast<Eigen::Index>(r) + k;
      A(row, k) = 1.0;
      A.block(row, 3 + 3 * k, 1, 3) = z.transpose();
      b(row) = T[static_cast<std::size_t>(idx[r])].translation()(k);
    }
  }
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  // The vertical column of M is nearly unobservable (z's vertical part varies little); compare
  // the predictions, which is what the model is used for, and n + M·z̄.
  double worst = 0;
  for (int i = 0; i < 150; ++i) {
    const Eigen::Vector3d z = T[static_cast<std::size_t>(i)].rotationMatrix().col(2);
    Eigen::Vector3d ref = x.head<3>();
    for (int k = 0; k < 3; ++k) ref(k) += x.segment<3>(3 + 3 * k).dot(z);
    worst = std::max(worst, (ref - Eigen::Vector3d(fit.predict(T[static_cast<std::size_t>(i)]))).norm());
  }
  CHECK(worst < 1e-9);
  CHECK(fit.r2 > 0.99);
  CHECK(fit.spreadDeg > 60);
}

TEST_CASE("fillGapsByHeadModel: a standing head's turns across gaps, against the truth", "[slam][head]") {
  Rng rng(11);
  const int n = 240;
  const std::vector<hawor::SE3<double>> truth = standingTurns(rng, n, Eigen::Vector3d(0.5, 0.2, 1.6));
  std::vector<char> posed(static_cast<std::size_t>(n), 1), rot(static_cast<std::size_t>(n), 1);
  std::vector<hawor::SE3<double>> T = truth;
  // A lead-in gap (frames 0-24) and one inside (120-149): position held, rotation known.
  for (int i = 0; i < 25; ++i) posed[static_cast<std::size_t>(i)] = 0, T[static_cast<std::size_t>(i)] = hawor::SE3<double>(truth[static_cast<std::size_t>(i)].rotation(), truth[25].translation());
  for (int i = 120; i < 150; ++i) posed[static_cast<std::size_t>(i)] = 0, T[static_cast<std::size_t>(i)] = hawor::SE3<double>(truth[static_cast<std::size_t>(i)].rotation(), truth[119].translation());
  double heldErr = 0;
  for (int i = 0; i < n; ++i) heldErr += (T[static_cast<std::size_t>(i)].translation() - truth[static_cast<std::size_t>(i)].translation()).norm();
  const int changed = hawor::fillGapsByHeadModel(T, posed, rot);
  CHECK(changed == 55);
  double err = 0, worst = 0;
  for (int i = 0; i < n; ++i) {
    const double e = (T[static_cast<std::size_t>(i)].translation() - truth[static_cast<std::size_t>(i)].translation()).norm();
    err += e;
    worst = std::max(worst, e);
    if (posed[static_cast<std::size_t>(i)]) CHECK(e == 0.0);
  }
  INFO("mean error held " << heldErr / n << " m, head model " << err / n << " m, worst " << worst << " m");
  CHECK(worst < 0.012);           // the model's own misfit (pitch does not move the eye here)
  CHECK(err < heldErr / 4);
  // A frame without a rotation is left alone.
  std::vector<char> rot2 = rot;
  rot2[130] = 0;
  std::vector<hawor::SE3<double>> T2 = truth;
  T2[130] = hawor::SE3<double>(truth[130].rotation(), truth[119].translation());
  for (int i = 120; i < 150; ++i) T2[static_cast<std::size_t>(i)] = hawor::SE3<double>(truth[static_cast<std::size_t>(i)].rotation(), truth[119].translation());
  std::vector<char> posed2(static_cast<std::size_t>(n), 1);
  for (int i = 120; i < 150; ++i) posed2[static_cast<std::size_t>(i)] = 0;
  hawor::fillGapsByHeadModel(T2, posed2, rot2);
  CHECK((T2[130].translation() - truth[119].translation()).norm() == 0.0);
}

TEST_CASE("fillGapsByHeadModel leaves a walk and gaps without a turn alone", "[slam][head]") {
  Rng rng(5);
  const int n = 200;
  // Walking a curve (1.2 m/s, the heading following the path) while looking around a little.
  std::vector<hawor::SE3<double>> walk;
  for (int i = 0; i < n; ++i) {
    const double t = i / 30.0;
    const double heading = 0.4 * t;
    const Eigen::Vector3d c(3.0 * std::sin(heading), 3.0 * (1 - std::cos(heading)), 1.6 + 0.02 * std::sin(11 * t));
    walk.push_back(lookPose(heading + 0.2 * std::sin(1.7 * t), -0.2 + 0.1 * std::sin(1.1 * t), c));
  }
  std::vector<char> posed(static_cast<std::size_t>(n), 1), rot(static_cast<std::size_t>(n), 1);
  for (int i = 90; i < 120; ++i) posed[static_cast<std::size_t>(i)] = 0;
  std::vector<hawor::SE3<double>> T = walk;
  CHECK(hawor::fillGapsByHeadModel(T, posed, rot) == 0);
  // A standing head whose gap is a fixation (no turn across it): left to the interpolation.
  const std::vector<hawor::SE3<double>> stand = standingTurns(rng, n, Eigen::Vector3d::Zero());
  std::vector<hawor::SE3<double>> S = stand;
  std::vector<char> posedS(static_cast<std::size_t>(n), 1);
  for (int i = 100; i < 103; ++i) posedS[static_cast<std::size_t>(i)] = 0;
  CHECK(hawor::fillGapsByHeadModel(S, posedS, rot) == 0);
  // Size mismatch.
  CHECK_THROWS_AS(hawor::fillGapsByHeadModel(S, std::vector<char>(3, 1), rot), hawor::Error);
}

TEST_CASE("fillGapsByHeadModel<float>", "[slam][head]") {
  Rng rng(2);
  const std::vector<hawor::SE3<double>> truth = standingTurns(rng, 150, Eigen::Vector3d(0, 0, 1.6));
  std::vector<hawor::SE3<float>> T;
  for (const auto& p : truth) T.push_back(p.cast<float>());
  std::vector<char> posed(150, 1), rot(150, 1);
  for (int i = 60; i < 90; ++i) posed[static_cast<std::size_t>(i)] = 0, T[static_cast<std::size_t>(i)] = hawor::SE3<float>(T[static_cast<std::size_t>(i)].rotation(), T[59].translation());
  CHECK(hawor::fillGapsByHeadModel(T, posed, rot) == 30);
  for (int i = 60; i < 90; ++i) CHECK((T[static_cast<std::size_t>(i)].translation().cast<double>() - truth[static_cast<std::size_t>(i)].translation()).norm() < 0.015);
}

TEST_CASE("fitHeadJoin: a second map segment's scale and offset from one head model", "[slam][head]") {
  // Segment B (frames 120-209) in a map of its own: positions (c − o)/s_true (a re-initialised
  // monocular map: another scale and origin), rotations continuous.
  const double sTrue = 2.7;
  const Eigen::Vector3d o(0.5, 0.1, -0.2);
  auto split = [&](const std::vector<hawor::SE3<double>>& truth, std::vector<int>& idxA, std::vector<int>& idxB) {
    std::vector<hawor::SE3<double>> T = truth;
    idxA.clear(), idxB.clear();
    for (int i = 30; i < 120; ++i) idxA.push_back(i);
    for (int i = 120; i < 210; ++i) {
      idxB.push_back(i);
      T[static_cast<std::size_t>(i)] = hawor::SE3<double>(truth[static_cast<std::size_t>(i)].rotation(),
                                                          hawor::Vec3<double>((Eigen::Vector3d(truth[static_cast<std::size_t>(i)].translation()) - o) / sTrue));
    }
    return T;
  };
  Rng rng(19);
  std::vector<int> idxA, idxB;
  // A head nodding and turning about one neck joint (c = n + r·z: the model holds exactly).
  const std::vector<hawor::SE3<double>> truth = standingTurns(rng, 240, Eigen::Vector3d(0.3, -0.4, 1.6), true);
  const std::vector<hawor::SE3<double>> T = split(truth, idxA, idxB);
  const hawor::HeadJoin<double> j = hawor::fitHeadJoin(T, idxA, idxB);
  REQUIRE(j.ok);
  CHECK(j.s == Approx(sTrue).epsilon(0.02));
  // B's frames mapped back (s·c + t) land on the truth.
  double worst = 0;
  for (int i : idxB) {
    const Eigen::Vector3d back = j.s * Eigen::Vector3d(T[static_cast<std::size_t>(i)].translation()) + Eigen::Vector3d(j.t);
    worst = std::max(worst, (back - Eigen::Vector3d(truth[static_cast<std::size_t>(i)].translation())).norm());
  }
  CHECK(worst < 0.005);
  // Against the dense solve of the same 16 unknowns (ridge as in the options), by QR.
  const hawor::HeadModelOptions<double> opt;
  const int rows = 3 * static_cast<int>(idxA.size() + idxB.size()) + 9;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, 16);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(rows);
  int r = 0;
  for (int pass = 0; pass < 2; ++pass) {
    for (int i : pass == 0 ? idxA : idxB) {
      const Eigen::Vector3d z = T[static_cast<std::size_t>(i)].rotationMatrix().col(2);
      const Eigen::Vector3d c = T[static_cast<std::size_t>(i)].translation();
      for (int k = 0; k < 3; ++k, ++r) {
        A(r, k) = 1.0;
        A.block(r, 3 + 3 * k, 1, 3) = z.transpose();
        if (pass == 0) {
          b(r) = c(k);
        } else {
          A(r, 12) = -c(k);
          A(r, 13 + k) = -1.0;
        }
      }
    }
  }
  const double lam = std::sqrt(opt.ridge * double(idxA.size() + idxB.size()));
  for (int k = 0; k < 9; ++k, ++r) A(r, 3 + k) = lam;
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  CHECK(j.s == Approx(x(12)).epsilon(1e-6));
  CHECK((Eigen::Vector3d(j.t) - x.tail<3>()).norm() < 1e-6);
  // The synthetic presets' head (the eye turns about a vertical axis only; pitch leaves it in
  // place): the linear model's misfit (the eye's offset is z's horizontal part normalised, here
  // 1/cos(pitch) up to 1.1 of the linear term) biases the scale a little.
  std::vector<int> idxA2, idxB2;
  const std::vector<hawor::SE3<double>> T2 = split(standingTurns(rng, 240, Eigen::Vector3d(0.3, -0.4, 1.6), false), idxA2, idxB2);
  const hawor::HeadJoin<double> j2 = hawor::fitHeadJoin(T2, idxA2, idxB2);
  INFO("yaw-only neck: scale " << j2.s << " for " << sTrue);
  CHECK(std::abs(j2.s / sTrue - 1.0) < 0.1);
  // Too few frames, or segment B without a turn (its scale undetermined): not used.
  CHECK_FALSE(hawor::fitHeadJoin(T, std::vector<int>(idxA.begin(), idxA.begin() + 10), idxB).ok);
  std::vector<int> still;
  for (int i = 0; i < 40; ++i) still.push_back(120);
  CHECK_FALSE(hawor::fitHeadJoin(T, idxA, still).ok);
}

TEST_CASE("fitHeadJoinAll: three map segments at once, the reference in the middle", "[slam][head]") {
  // Frames 0-89, 90-179 (the reference), 180-269: the outer two in maps of their own
  // ((c − o_k)/s_k), rotations continuous; a head pivoting about one neck joint (the model holds).
  Rng rng(23);
  const std::vector<hawor::SE3<double>> truth = standingTurns(rng, 270, Eigen::Vector3d(-0.6, 0.2, 1.5), true);
  const double sTrue[3] = {0.45, 1.0, 3.2};
  const Eigen::Vector3d oTrue[3] = {Eigen::Vector3d(0.2, -0.1, 0.3), Eigen::Vector3d::Zero(), Eigen::Vector3d(-1.0, 0.4, 0.0)};
  std::vector<hawor::SE3<double>> T = truth;
  std::vector<std::vector<int>> groups(3);
  for (int i = 0; i < 270; ++i) {
    const int k = i / 90;
    groups[static_cast<std::size_t>(k)].push_back(i);
    T[static_cast<std::size_t>(i)] = hawor::SE3<double>(
        truth[static_cast<std::size_t>(i)].rotation(),
        hawor::Vec3<double>((Eigen::Vector3d(truth[static_cast<std::size_t>(i)].translation()) - oTrue[k]) / sTrue[k]));
  }
  const hawor::HeadJoinAll<double> j = hawor::fitHeadJoinAll(T, groups, 1);
  REQUIRE(j.ok);
  REQUIRE(j.s.size() == 3);
  CHECK(j.s[1] == 1.0);
  CHECK(Eigen::Vector3d(j.t[1]).norm() == 0.0);
  for (int k : {0, 2}) {
    CHECK(j.s[static_cast<std::size_t>(k)] == Approx(sTrue[k]).epsilon(0.02));
    double worst = 0;
    for (int i : groups[static_cast<std::size_t>(k)]) {
      const Eigen::Vector3d back = j.s[static_cast<std::size_t>(k)] * Eigen::Vector3d(T[static_cast<std::size_t>(i)].translation()) +
                                   Eigen::Vector3d(j.t[static_cast<std::size_t>(k)]);
      worst = std::max(worst, (back - Eigen::Vector3d(truth[static_cast<std::size_t>(i)].translation())).norm());
    }
    INFO("segment " << k);
    CHECK(worst < 0.005);
  }
  // Against the dense solve of the same 20 unknowns (n, M, then s, t of segments 0 and 2), QR.
  const hawor::HeadModelOptions<double> opt;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(3 * 270 + 9, 20);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(3 * 270 + 9);
  int r = 0;
  for (int k = 0; k < 3; ++k) {
    for (int i : groups[static_cast<std::size_t>(k)]) {
      const Eigen::Vector3d z = T[static_cast<std::size_t>(i)].rotationMatrix().col(2);
      const Eigen::Vector3d c = T[static_cast<std::size_t>(i)].translation();
      for (int d = 0; d < 3; ++d, ++r) {
        A(r, d) = 1.0;
        A.block(r, 3 + 3 * d, 1, 3) = z.transpose();
        if (k == 1) {
          b(r) = c(d);
        } else {
          const int c0 = k == 0 ? 12 : 16;
          A(r, c0) = -c(d);
          A(r, c0 + 1 + d) = -1.0;
        }
      }
    }
  }
  const double lam = std::sqrt(opt.ridge * 270.0);
  for (int k = 0; k < 9; ++k, ++r) A(r, 3 + k) = lam;
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  CHECK(j.s[0] == Approx(x(12)).epsilon(1e-6));
  CHECK(j.s[2] == Approx(x(16)).epsilon(1e-6));
  CHECK((Eigen::Vector3d(j.t[0]) - x.segment<3>(13)).norm() < 1e-6);
  CHECK((Eigen::Vector3d(j.t[2]) - x.segment<3>(17)).norm() < 1e-6);
  // A segment without a turn (its scale undetermined), one too short, a bad reference: not used.
  std::vector<std::vector<int>> still = groups;
  still[2].assign(40, 200);
  CHECK_FALSE(hawor::fitHeadJoinAll(T, still, 1).ok);
  std::vector<std::vector<int>> shortSeg = groups;
  shortSeg[0].resize(10);
  CHECK_FALSE(hawor::fitHeadJoinAll(T, shortSeg, 1).ok);
  CHECK_FALSE(hawor::fitHeadJoinAll(T, groups, 3).ok);
  CHECK_FALSE(hawor::fitHeadJoinAll(T, {groups[0]}, 0).ok);
  // A walk (the position follows no head model): the tests refuse the joint model.
  std::vector<hawor::SE3<double>> W = T;
  for (int i = 0; i < 270; ++i) {
    W[static_cast<std::size_t>(i)] = hawor::SE3<double>(T[static_cast<std::size_t>(i)].rotation(),
                                                        hawor::Vec3<double>(0.03 * i + 0.1 * std::sin(0.05 * i), 0.5 * std::sin(0.02 * i), 1.6));
  }
  CHECK_FALSE(hawor::fitHeadJoinAll(W, groups, 1).ok);
}

TEST_CASE("fitHeadJoinAll<float>", "[slam][head]") {
  Rng rng(29);
  const std::vector<hawor::SE3<double>> truth = standingTurns(rng, 180, Eigen::Vector3d(0.4, 0.2, 1.6), true);
  std::vector<hawor::SE3<float>> T;
  std::vector<std::vector<int>> groups(2);
  for (int i = 0; i < 180; ++i) {
    Eigen::Vector3d c = truth[static_cast<std::size_t>(i)].translation();
    if (i >= 90) c = c / 2.0;
    groups[static_cast<std::size_t>(i / 90)].push_back(i);
    T.push_back(hawor::SE3<float>(hawor::SO3<float>::fromMatrix(hawor::Mat3<float>(truth[static_cast<std::size_t>(i)].rotationMatrix().cast<float>())),
                                  hawor::Vec3<float>(c.cast<float>())));
  }
  const hawor::HeadJoinAll<float> j = hawor::fitHeadJoinAll(T, groups, 0);
  REQUIRE(j.ok);
  CHECK(j.s[1] == Approx(2.0f).epsilon(0.03));
}

TEST_CASE("joinSegmentsByHeadModel: usable segments joined, a short one left out, a walk refused", "[slam][head]") {
  // Segments [0, 120), [120, 130) (10 frames: too few for its own scale), [130, 240), each in a
  // map of its own; frames 60-69 unposed (a loss inside the first segment).
  Rng rng(31);
  const std::vector<hawor::SE3<double>> truth = standingTurns(rng, 240, Eigen::Vector3d(0.1, 0.3, 1.7), true);
  const std::vector<int> first = {0, 120, 130, 240};
  const double sTrue[3] = {1.0, 0.2, 1.8};
  std::vector<hawor::SE3<double>> T = truth;
  std::vector<char> posed(240, 1);
  for (int f = 60; f < 70; ++f) posed[static_cast<std::size_t>(f)] = 0;
  for (int i = 0; i < 240; ++i) {
    const int k = i < 120 ? 0 : (i < 130 ? 1 : 2);
    T[static_cast<std::size_t>(i)] = hawor::SE3<double>(truth[static_cast<std::size_t>(i)].rotation(),
                                                        hawor::Vec3<double>(Eigen::Vector3d(truth[static_cast<std::size_t>(i)].translation()) / sTrue[k] +
                                                                            Eigen::Vector3d(0.1 * k, 0.0, -0.2 * k)));
  }
  const hawor::SegmentsHeadJoin<double> j = hawor::joinSegmentsByHeadModel(T, posed, first);
  INFO(j.report);
  REQUIRE(j.ok);
  REQUIRE(j.group.size() == 3);
  CHECK(j.group[0] >= 0);
  CHECK(j.group[1] == -1);
  REQUIRE(j.group[2] >= 0);
  // Segment 2 in segment 0's units (the longest, the reference: its scale is the truth's).
  const double s2 = j.join.s[static_cast<std::size_t>(j.group[2])] / j.join.s[static_cast<std::size_t>(j.group[0])];
  CHECK(s2 == Approx(sTrue[2]).epsilon(0.02));
  // Only the first segment usable (the third cut to 20 frames): its own model, accepted.
  const std::vector<int> first2 = {0, 120, 130, 150};
  const std::vector<hawor::SE3<double>> T2(T.begin(), T.begin() + 150);
  const std::vector<char> posed2(posed.begin(), posed.begin() + 150);
  const hawor::SegmentsHeadJoin<double> one = hawor::joinSegmentsByHeadModel(T2, posed2, first2);
  CHECK(one.ok);
  CHECK(one.group == std::vector<int>({0, -1, -1}));
  // A walk: no model, nothing joined.
  std::vector<hawor::SE3<double>> W = T;
  for (int i = 0; i < 240; ++i) {
    W[static_cast<std::size_t>(i)] = hawor::SE3<double>(T[static_cast<std::size_t>(i)].rotation(),
                                                        hawor::Vec3<double>(0.03 * i, 0.4 * std::sin(0.03 * i), 1.6));
  }
  CHECK_FALSE(hawor::joinSegmentsByHeadModel(W, posed, first).ok);
  // Bad input: a clear error.
  CHECK_THROWS_AS(hawor::joinSegmentsByHeadModel(T, posed, std::vector<int>{0, 120}), hawor::Error);
  CHECK_THROWS_AS(hawor::joinSegmentsByHeadModel(T, posed, std::vector<int>{0, 130, 120, 240}), hawor::Error);
  CHECK_THROWS_AS(hawor::joinSegmentsByHeadModel(T, std::vector<char>(3, 1), first), hawor::Error);
}

TEST_CASE("fillGapsByHeadModel: a gap beside a fixation takes the whole sequence's model", "[slam][head]") {
  // Frames 0-24 turn from yaw −0.8 to 0 (the gap: no map yet), 25-129 fixate (yaw within ±1°:
  // the window's posed frames cannot fit a model), 130-329 turn widely. The eye 9 cm in front of
  // a vertical neck, 1 mm noise.
  Rng rng(41);
  const int n = 330;
  const Eigen::Vector3d neck(0.4, -0.3, 1.6);
  std::vector<hawor::SE3<double>> truth;
  for (int i = 0; i < n; ++i) {
    const double t = i / 30.0;
    double yaw;
    if (i < 25) {
      yaw = -0.8 * (1.0 - i / 25.0);
    } else if (i < 130) {
      yaw = 0.015 * std::sin(3.0 * t);
    } else {
      yaw = 1.1 * std::sin(0.9 * (t - 130.0 / 30.0));
    }
    const double pitch = -0.2 + 0.1 * std::sin(0.7 * t);
    const Eigen::Vector3d h(std::cos(yaw), std::sin(yaw), 0.0);
    truth.push_back(lookPose(yaw, pitch, neck + 0.09 * h + rng.scaledUnit(0.0, 0.001)));
  }
  std::vector<char> posed(static_cast<std::size_t>(n), 1), rot(static_cast<std::size_t>(n), 1);
  std::vector<hawor::SE3<double>> held = truth;
  for (int i = 0; i < 25; ++i) {
    posed[static_cast<std::size_t>(i)] = 0;
    held[static_cast<std::size_t>(i)] = hawor::SE3<double>(truth[static_cast<std::size_t>(i)].rotation(), truth[25].translation());
  }
  // The window's own fit fails (views spread ~2°): without the fallback the gap keeps its positions.
  hawor::HeadModelOptions<double> noFallback;
  noFallback.wholeSequenceFallback = false;
  std::vector<hawor::SE3<double>> T0 = held;
  CHECK(hawor::fillGapsByHeadModel(T0, posed, rot, noFallback) == 0);
  std::vector<hawor::SE3<double>> T = held;
  std::string report;
  CHECK(hawor::fillGapsByHeadModel(T, posed, rot, hawor::HeadModelOptions<double>(), &report) == 25);
  INFO(report);
  CHECK(report.find("whole sequence") != std::string::npos);
  double heldErr = 0, err = 0;
  for (int i = 0; i < 25; ++i) {
    heldErr += (held[static_cast<std::size_t>(i)].translation() - truth[static_cast<std::size_t>(i)].translation()).norm();
    err += (T[static_cast<std::size_t>(i)].translation() - truth[static_cast<std::size_t>(i)].translation()).norm();
  }
  INFO("gap mean error held " << heldErr / 25 << " m, whole-sequence model " << err / 25 << " m");
  CHECK(err < heldErr / 3);
  CHECK(err / 25 < 0.01);
  // A walk beside the same gap: the whole sequence fails the tests too, nothing changes.
  std::vector<hawor::SE3<double>> W = held;
  for (int i = 25; i < n; ++i) {
    W[static_cast<std::size_t>(i)] = hawor::SE3<double>(truth[static_cast<std::size_t>(i)].rotation(),
                                                        hawor::Vec3<double>(0.04 * i, 0.5 * std::sin(0.02 * i), 1.6));
  }
  CHECK(hawor::fillGapsByHeadModel(W, posed, rot) == 0);
}

TEST_CASE("fitHeadJoinAll: a short segment of narrow view spread is joined at a lower motion R²", "[slam][head]") {
  // Segment 0 (frames 0-59): the head turns over ~23° only, positions with 2 mm noise, so the
  // motion over 3 frames is small against it; segment 1 (60-299, the reference) turns widely.
  // Segment 0 in a map of its own (c − o)/s.
  Rng rng(43);
  const int n = 300;
  const Eigen::Vector3d neck(-0.2, 0.5, 1.6);
  const double sTrue = 0.4;
  const Eigen::Vector3d o(0.3, -0.2, 0.1);
  std::vector<hawor::SE3<double>> truth, T;
  std::vector<std::vector<int>> groups(2);
  for (int i = 0; i < n; ++i) {
    const double t = i / 30.0;
    const double yaw = i < 60 ? 0.24 * std::sin(2.0 * t) : 1.2 * std::sin(0.9 * t) + 0.3 * std::sin(2.3 * t);
    const double pitch = -0.22 + 0.1 * std::sin(0.7 * t + 1.0);
    const Eigen::Vector3d h(std::cos(yaw), std::sin(yaw), 0.0);
    truth.push_back(lookPose(yaw, pitch, neck + 0.09 * h + rng.scaledUnit(0.0, 0.002)));
    Eigen::Vector3d c = truth.back().translation();
    if (i < 60) c = (c - o) / sTrue;
    T.push_back(hawor::SE3<double>(truth.back().rotation(), hawor::Vec3<double>(c)));
    groups[i < 60 ? 0 : 1].push_back(i);
  }
  hawor::HeadModelOptions<double> strict;
  strict.joinMinMotionR2 = strict.minMotionR2;
  const hawor::HeadJoinAll<double> refused = hawor::fitHeadJoinAll(T, groups, 1, strict);
  const hawor::HeadJoinAll<double> j = hawor::fitHeadJoinAll(T, groups, 1);
  INFO("motion R2 " << j.fit.motionR2 << ", R2 " << j.fit.r2 << ", spreads " << j.spreadDeg[0] << "/" << j.spreadDeg[1] << " deg, scale "
                    << j.s[0] << " for " << sTrue);
  CHECK(j.fit.motionR2 < strict.minMotionR2);
  CHECK_FALSE(refused.ok);
  REQUIRE(j.ok);
  CHECK(j.s[0] == Approx(sTrue).epsilon(0.03));
}
