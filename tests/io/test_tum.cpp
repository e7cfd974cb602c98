// TUM trajectories: field order (x y z w in the file, Eigen's w x y z inside), normalisation,
// exact write/read round trips in float and double, malformed lines reported with their line
// numbers, and timestamp association against a brute-force version of TUM's associate.py.
#include <catch2/catch.hpp>

#include <hawor/io/tum.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "io_test_util.hpp"

using io_test::errorOf;

template struct hawor::TumPose<float>;
template struct hawor::TumPose<double>;
template std::vector<hawor::TumPose<float>> hawor::parseTum<float>(const std::string&, const std::string&);
template std::vector<hawor::TumPose<double>> hawor::parseTum<double>(const std::string&, const std::string&);
template std::string hawor::formatTum<float>(const std::vector<hawor::TumPose<float>>&);
template std::string hawor::formatTum<double>(const std::vector<hawor::TumPose<double>>&);

namespace {

template <typename Scalar>
std::vector<hawor::TumPose<Scalar>> randomTrajectory(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> dt(1e-3, 0.1);
  std::vector<hawor::TumPose<Scalar>> out(n);
  double t = 1305031102.175304;  // a TUM-style epoch timestamp
  for (auto& p : out) {
    t += dt(rng);
    p.t = t;
    p.p = hawor::Vec3<Scalar>(Scalar(g(rng) * 3), Scalar(g(rng) * 1e-4), Scalar(g(rng) * 1e3));
    Eigen::Quaternion<Scalar, Eigen::DontAlign> q(Scalar(g(rng)), Scalar(g(rng)), Scalar(g(rng)),
                                                  Scalar(g(rng)));
    q.normalize();
    p.q = q;
  }
  return out;
}

// TUM associate.py, literally: every pair within max_dt, sorted by |difference|, greedy.
std::vector<std::pair<size_t, size_t>> bruteAssociate(const std::vector<double>& a,
                                                      const std::vector<double>& b, double max_dt) {
  std::vector<std::tuple<double, size_t, size_t>> all;
  for (size_t i = 0; i < a.size(); ++i) {
    for (size_t j = 0; j < b.size(); ++j) {
      if (std::fabs(a[i] - b[j]) <= max_dt) all.emplace_back(std::fabs(a[i] - b[j]), i, j);
    }
  }
  std::sort(all.begin(), all.end());
  std::vector<bool> ua(a.size()), ub(b.size());
  std::vector<std::pair<size_t, size_t>> m;
  for (const auto& c : all) {
    const size_t i = std::get<1>(c), j = std::get<2>(c);
    if (ua[i] || ub[j]) continue;
    ua[i] = ub[j] = true;
    m.emplace_back(i, j);
  }
  std::sort(m.begin(), m.end());
  return m;
}

}  // namespace

TEMPLATE_TEST_CASE("tum field order and normalisation", "[io][tum]", float, double) {
  using S = TestType;
  const std::string text =
      "# timestamp tx ty tz qx qy qz qw\n"
      "1.0 1 2 3 0 0 0 1\n"
      "\n"
      "   # indented comment\n"
      "2.5\t-1\t0.5\t4e2\t1 0 0 0\r\n"
      "3 0 0 0 0 0 0 2\n"
      "4 0 0 0 0 3 0 4";  // no final newline
  const auto p = hawor::parseTum<S>(text, "t.txt");
  REQUIRE(p.size() == 4);
  CHECK(p[0].t == 1.0);
  CHECK(p[0].p == hawor::Vec3<S>(1, 2, 3));
  CHECK(p[0].q.w() == S(1));
  CHECK(p[0].q.vec().isZero());
  CHECK(p[1].t == 2.5);
  CHECK(p[1].p == hawor::Vec3<S>(-1, S(0.5), 400));
  CHECK(p[1].q.x() == S(1));  // file qx -> Eigen x
  CHECK(p[1].q.w() == S(0));
  CHECK(p[2].q.w() == S(1));  // normalised from (0, 0, 0, 2)
  CHECK(p[3].q.y() == Approx(0.6).epsilon(1e-6));
  CHECK(p[3].q.w() == Approx(0.8).epsilon(1e-6));
  CHECK(hawor::parseTum<S>("", "empty.txt").empty());
  CHECK(hawor::parseTum<S>("# only a comment\n\n", "c.txt").empty());
}

TEMPLATE_TEST_CASE("tum write/read round trip is exact", "[io][tum]", float, double) {
  using S = TestType;
  const auto poses = randomTrajectory<S>(300, 42);
  const std::string path = io_test::tempPath(std::string("traj_") + (sizeof(S) == 4 ? "f" : "d") + ".txt");
  hawor::writeTum(path, poses);
  const auto back = hawor::readTum<S>(path);
  REQUIRE(back.size() == poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    CAPTURE(i);
    REQUIRE(back[i].t == poses[i].t);  // shortest round-trip formatting: bit-exact
    REQUIRE(back[i].p == poses[i].p);
    // Normalised again on read: equal up to the last bit of a re-normalisation.
    REQUIRE((back[i].q.coeffs() - poses[i].q.coeffs()).cwiseAbs().maxCoeff() <=
            4 * std::numeric_limits<S>::epsilon());
  }
  // The text is short: TUM timestamps keep their 6 decimals, not 17 significant digits.
  std::vector<hawor::TumPose<S>> one(1);
  one[0].t = 1305031102.175304;
  one[0].p = hawor::Vec3<S>(S(0.5), S(-2), S(0.125));
  CHECK(hawor::formatTum(one) == "# timestamp tx ty tz qx qy qz qw\n1305031102.175304 0.5 -2 0.125 0 0 0 1\n");
  // Relative accuracy of 1e-9 or better on every value through text, as the design requires.
  const auto reparsed = hawor::parseTum<double>(hawor::formatTum(randomTrajectory<double>(50, 7)), "x");
  const auto orig = randomTrajectory<double>(50, 7);
  for (size_t i = 0; i < orig.size(); ++i) {
    CHECK(std::fabs(reparsed[i].p.z() - orig[i].p.z()) <= 1e-9 * std::fabs(orig[i].p.z()));
  }
}

TEMPLATE_TEST_CASE("tum rejects malformed lines naming file and line", "[io][tum]", float, double) {
  using S = TestType;
  const std::string good = "# header\n0 0 0 0 0 0 0 1\n";
  struct Bad {
    std::string line;
    std::string expect;
  };
  const std::vector<Bad> bad = {
      {"1 0 0 0 0 0 1", "expected 8 fields"},
      {"1 0 0 0 0 0 0 1 9", "found 9"},
      {"1 0 0 abc 0 0 0 1", "field 4 ('abc')"},
      {"1 0 0 nan 0 0 0 1", "not a finite number"},
      {"1 0 0 0 0 0 0 inf", "field 8"},
      {"1 0 0 -inf 0 0 0 1", "not a finite number"},
      {"1 0 0 1e999 0 0 0 1", "not a finite number"},
      {"1 0 0 0x10 0 0 0 1", "not a finite number"},
      {"1 0 0 1.2.3 0 0 0 1", "not a finite number"},
      {"1 0 0 1e 0 0 0 1", "not a finite number"},
      {"1 0 0 . 0 0 0 1", "not a finite number"},
      {"1,0 0 0 0 0 0 0 1", "field 1 ('1,0')"},
      {"1 0 0 0 0 0 0 0", "quaternion is zero"},
      {"0 0 0 0 0 0 0 1", "not greater than"},
      {"-1 0 0 0 0 0 0 1", "timestamps must increase"},
      {"1 0 0 0 1e308 1e308 1e308 1e308", "<no error>"},  // huge but valid quaternion
  };
  for (const auto& b : bad) {
    CAPTURE(b.line);
    const std::string msg = errorOf([&] { hawor::parseTum<S>(good + b.line + "\n", "traj.txt"); });
    if (b.expect == "<no error>") {
      CHECK(msg == b.expect);
    } else {
      CHECK_THAT(msg, Catch::Contains("traj.txt:3") && Catch::Contains(b.expect));
    }
  }
  if (sizeof(S) == sizeof(float)) {
    CHECK_THAT(errorOf([&] { hawor::parseTum<S>("1 1e39 0 0 0 0 0 1", "f.txt"); }),
               Catch::Contains("out of range"));
  }
  CHECK_THAT(errorOf([&] { hawor::readTum<S>(io_test::tempPath("nope.txt")); }), Catch::Contains("nope.txt"));
}

TEMPLATE_TEST_CASE("tum writer refuses what it could not read back", "[io][tum]", float, double) {
  using S = TestType;
  auto poses = randomTrajectory<S>(3, 1);
  auto p = poses;
  p[1].t = p[0].t;
  CHECK_THAT(errorOf([&] { hawor::formatTum(p); }), Catch::Contains("increase"));
  p = poses;
  p[2].p.x() = std::numeric_limits<S>::quiet_NaN();
  CHECK_THAT(errorOf([&] { hawor::formatTum(p); }), Catch::Contains("non-finite"));
  p = poses;
  p[0].q.coeffs().setZero();
  CHECK_THAT(errorOf([&] { hawor::formatTum(p); }), Catch::Contains("zero"));
  // Unnormalised quaternions are written normalised.
  p = poses;
  p[0].q.coeffs() *= S(3);
  const auto back = hawor::parseTum<S>(hawor::formatTum(p), "n");
  CHECK((back[0].q.coeffs() - poses[0].q.coeffs()).norm() <= 8 * std::numeric_limits<S>::epsilon());
}

TEST_CASE("tum timestamp association", "[io][tum]") {
  const std::vector<double> a = {0.0, 1.0, 2.0, 3.0};
  const std::vector<double> b = {0.02, 0.98, 1.01, 2.5, 3.04};
  const auto m = hawor::associateTimestamps(a, b, 0.05);
  // 1.0 takes 1.01 (closer than 0.98); 2.0 has none within 0.05.
  const std::vector<std::pair<size_t, size_t>> expect = {{0, 0}, {1, 2}, {3, 4}};
  CHECK(m == expect);
  CHECK(hawor::associateTimestamps(a, b, 0.0).empty());
  CHECK(hawor::associateTimestamps(a, {1.0}, 0.0) == std::vector<std::pair<size_t, size_t>>{{1, 0}});
  CHECK(hawor::associateTimestamps({}, b, 1.0).empty());
  CHECK_THAT(errorOf([&] { hawor::associateTimestamps(a, b, -1); }), Catch::Contains("max_dt"));
  CHECK_THAT(errorOf([&] { hawor::associateTimestamps(a, b, std::nan("")); }), Catch::Contains("max_dt"));
  CHECK_THAT(errorOf([&] { hawor::associateTimestamps({std::nan("")}, b, 1); }), Catch::Contains("non-finite"));

  // Property: equals the brute-force greedy matching of associate.py on random unsorted data.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 10);
  for (int trial = 0; trial < 60; ++trial) {
    std::vector<double> ta(5 + rng() % 40), tb(5 + rng() % 40);
    for (auto& t : ta) t = std::round(u(rng) * 50) / 50;  // ties are likely
    for (auto& t : tb) t = std::round(u(rng) * 50) / 50;
    const double max_dt = (rng() % 4) * 0.05;
    CAPTURE(trial, max_dt);
    REQUIRE(hawor::associateTimestamps(ta, tb, max_dt) == bruteAssociate(ta, tb, max_dt));
  }
  // Trajectory overload.
  const auto ta = randomTrajectory<float>(20, 8);
  auto tb = ta;
  for (auto& p : tb) p.t += 0.001;
  const auto mt = hawor::associateByTimestamp(ta, tb, 0.002);
  REQUIRE(mt.size() == 20);
  for (size_t i = 0; i < mt.size(); ++i) CHECK(mt[i] == std::make_pair(i, i));
}
