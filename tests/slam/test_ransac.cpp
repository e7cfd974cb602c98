// Generic adaptive RANSAC (slam/ransac.hpp): line fitting with outliers, the stopping rule,
// determinism for a seed, and degenerate input.
#include <catch2/catch.hpp>

#include <array>

#include "estimation_test_utils.hpp"
#include "hawor/slam/ransac.hpp"

using namespace hawor;

namespace {

// y = a·x + b from 2 points; residual = vertical distance.
struct Line {
  double a = 0, b = 0;
};

struct LineData {
  std::vector<double> x, y;
  std::vector<char> truth;
};

LineData makeLine(est_test::Rng& rng, int n, double outliers, double a, double b, double noise) {
  LineData d;
  for (int i = 0; i < n; ++i) {
    const double x = rng.uniform(-10, 10);
    const bool out = rng.uniform(0, 1) < outliers;
    d.x.push_back(x);
    const double y = out ? rng.uniform(-30, 30) : a * x + b + noise * rng.normal();
    d.y.push_back(y);
    d.truth.push_back(out ? 0 : 1);
  }
  return d;
}

}  // namespace

TEST_CASE("ransac fits a line through 40 % outliers", "[slam][ransac]") {
  est_test::Rng rng(3);
  const LineData d = makeLine(rng, 200, 0.4, 1.5, -2.0, 0.05);
  auto solve = [&](const int* s, std::vector<Line>& m) {
    const double dx = d.x[s[1]] - d.x[s[0]];
    if (std::abs(dx) < 1e-9) return;
    Line l;
    l.a = (d.y[s[1]] - d.y[s[0]]) / dx;
    l.b = d.y[s[0]] - l.a * d.x[s[0]];
    m.push_back(l);
  };
  auto err = [&](const Line& l, int i) {
    const double r = d.y[i] - (l.a * d.x[i] + l.b);
    return r * r;
  };
  RansacOptions<double> opt;
  opt.threshold = 0.2;
  const auto res = ransac<Line, double>(200, 2, solve, err, opt);
  REQUIRE(res.found);
  CHECK(std::abs(res.model.a - 1.5) < 0.02);
  CHECK(std::abs(res.model.b + 2.0) < 0.1);
  int agree = 0, truthIn = 0;
  for (int i = 0; i < 200; ++i) {
    agree += (res.inliers[i] != 0) == (d.truth[i] != 0) ? 1 : 0;
    truthIn += d.truth[i];
  }
  CHECK(agree >= 196);
  CHECK(res.numInliers >= truthIn - 2);
  // Adaptive stopping: with ~60 % inliers and s = 2, about 16 samples suffice at p = 0.999.
  CHECK(res.iterations < 40);
  CHECK(res.cost <= 200 * 0.04);

  // Same seed, same result; the MSAC cost of the winner is what a direct evaluation gives.
  const auto again = ransac<Line, double>(200, 2, solve, err, opt);
  CHECK(again.model.a == res.model.a);
  CHECK(again.iterations == res.iterations);
  double c = 0;
  for (int i = 0; i < 200; ++i) c += std::min(err(res.model, i), opt.threshold * opt.threshold);
  CHECK(std::abs(c - res.cost) < 1e-9);
}

TEST_CASE("ransacRequiredIterations follows log(1-p)/log(1-w^s)", "[slam][ransac]") {
  CHECK(ransacRequiredIterations(0.5, 4, 0.99, 10000) == 72);   // log(.01)/log(1-1/16) = 71.4
  CHECK(ransacRequiredIterations(0.7, 5, 0.999, 10000) == 38);  // log(.001)/log(1-.16807) = 37.5
  CHECK(ransacRequiredIterations(1.0, 5, 0.999, 10000) == 0);
  CHECK(ransacRequiredIterations(0.0, 5, 0.999, 500) == 500);
  CHECK(ransacRequiredIterations(1e-3, 8, 0.999, 500) == 500);  // capped
  CHECK(ransacRequiredIterations(0.5f, 4, 0.99f, 10000) == 72);
}

TEST_CASE("ransac on degenerate input reports no model instead of failing", "[slam][ransac]") {
  auto none = [](const int*, std::vector<int>&) {};
  auto err = [](const int&, int) { return 0.0; };
  RansacOptions<double> opt;
  opt.maxIterations = 50;
  // Too few data for one sample.
  auto r0 = ransac<int, double>(2, 3, none, err, opt);
  CHECK_FALSE(r0.found);
  CHECK(r0.iterations == 0);
  // A solver that never produces a model: the budget is used, nothing found.
  auto r1 = ransac<int, double>(10, 3, none, err, opt);
  CHECK_FALSE(r1.found);
  CHECK(r1.iterations == 50);
  // Non-finite residuals count as outliers.
  auto one = [](const int*, std::vector<int>& m) { m.push_back(1); };
  auto nanErr = [](const int&, int) { return std::numeric_limits<double>::quiet_NaN(); };
  auto r2 = ransac<int, double>(10, 3, one, nanErr, opt);
  CHECK_FALSE(r2.found);
  // Bad options throw hawor::Error.
  RansacOptions<double> bad = opt;
  bad.threshold = 0;
  CHECK_THROWS_AS((ransac<int, double>(10, 3, one, err, bad)), hawor::Error);
  bad = opt;
  bad.confidence = 1.0;
  CHECK_THROWS_AS((ransac<int, double>(10, 3, one, err, bad)), hawor::Error);
  CHECK_THROWS_AS((ransac<int, double>(10, 0, one, err, opt)), hawor::Error);
}

TEST_CASE("ransac samples are distinct and cover the data", "[slam][ransac]") {
  std::vector<int> hits(7, 0);
  bool distinct = true;
  auto solve = [&](const int* s, std::vector<int>&) {
    for (int k = 0; k < 4; ++k) {
      ++hits[static_cast<std::size_t>(s[k])];
      for (int j = 0; j < k; ++j) distinct = distinct && s[j] != s[k];
    }
  };
  auto err = [](const int&, int) { return 0.0; };
  RansacOptions<float> opt;
  opt.maxIterations = 700;
  ransac<int, float>(7, 4, solve, err, opt);
  CHECK(distinct);
  for (int h : hits) CHECK(std::abs(h - 400) < 80);  // 700·4/7 = 400 each
}
