// AdaSM metric scale (scale/robust_scale.hpp): the 1-D Geman–McClure fit against a brute-force
// minimisation of the same objective, robustness to outliers and bias on generated depth pairs,
// the adaptive window against the plain median, and degenerate input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "hawor/scale/robust_scale.hpp"

namespace {

/// Pairs (d, D) with D = s·d·(1 + noise), a fraction of outliers, metric depths in [0.2, 3] m.
template <typename S>
void makePairs(std::mt19937& rng, int n, double s, double noise, double outliers, std::vector<S>& d, std::vector<S>& D) {
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> N(0, 1);
  d.clear(), D.clear();
  for (int i = 0; i < n; ++i) {
    const double truth = 0.2 + 2.8 * U(rng);
    double m = truth * (1 + noise * N(rng));
    if (U(rng) < outliers) m = 0.05 + 4 * U(rng);
    d.push_back(S(truth / s));
    D.push_back(S(m));
  }
}

}  // namespace

TEMPLATE_TEST_CASE("GMoF scale fit reaches the brute-force minimum", "[scale]", float, double) {
  using S = TestType;
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<S> d, D;
    const double s = std::exp(std::uniform_real_distribution<double>(-3, 3)(rng));
    makePairs<S>(rng, 200, s, 0.05, 0.3, d, D);
    const S sigma = S(0.5);
    const S a = hawor::minimiseGmofScale(d, D, sigma, S(s / 20), S(s * 20));
    REQUIRE(std::isfinite(double(a)));
    // Brute force: a fine log grid over the same interval, in double.
    double best = 0, fbest = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= 200000; ++k) {
      const double x = s / 20 * std::pow(400.0, k / 200000.0);
      double f = 0;
      for (std::size_t i = 0; i < d.size(); ++i) {
        const double r = x * double(d[i]) - double(D[i]);
        f += 0.25 * r * r / (0.25 + r * r);
      }
      f /= double(d.size());
      if (f < fbest) fbest = f, best = x;
    }
    const double fa = double(hawor::gmofObjective(d, D, a, sigma));
    const double tol = std::is_same<S, float>::value ? 1e-6 : 1e-12;
    CHECK(fa <= fbest + tol * (1 + fbest));
    CHECK(double(a) == Approx(best).epsilon(std::is_same<S, float>::value ? 1e-3 : 1e-4));
  }
}

namespace {

/// 30 keyframes of 400 pixels: many near points and a tail of far ones; the depth network's error
/// grows with distance (5 % + 3 % per metre); 10 % of the pixels on a hand (metric depth half the
/// scene's: the hand in front), 10 % uniform outliers in [0.1, 5.1] m; optionally a global bias per
/// keyframe uniform in ±10 %.
void makeKeyframes(std::uint32_t seed, bool bias, double s, std::vector<std::vector<double>>& d,
                   std::vector<std::vector<double>>& D, std::vector<std::vector<char>>& hand) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> N(0, 1);
  d.clear(), D.clear(), hand.clear();
  for (int k = 0; k < 30; ++k) {
    std::vector<double> dk, Dk;
    std::vector<char> hk;
    const double b = bias ? 1 + 0.1 * (2 * U(rng) - 1) : 1.0;
    for (int i = 0; i < 400; ++i) {
      const double truth = 0.25 + 3.0 * U(rng) * U(rng);
      double m = truth * b * (1 + (0.05 + 0.03 * truth) * N(rng));
      const bool isHand = U(rng) < 0.1;
      if (isHand) m = 0.5 * truth;
      if (U(rng) < 0.1) m = 0.1 + 5 * U(rng);
      dk.push_back(truth / s);
      Dk.push_back(m);
      hk.push_back(isHand ? 1 : 0);
    }
    d.push_back(dk), D.push_back(Dk), hand.push_back(hk);
  }
}

}  // namespace

TEST_CASE("AdaSM: outliers and distance-dependent noise, against the plain median", "[scale]") {
  const double s = 0.37;
  std::vector<std::vector<double>> d, D;
  std::vector<std::vector<char>> hand;
  for (std::uint32_t seed = 1; seed <= 5; ++seed) {
    makeKeyframes(seed, false, s, d, D, hand);
    const hawor::SequenceScale<double> ada = hawor::adaptiveScale(d, D, &hand);
    const hawor::SequenceScale<double> med = hawor::medianScale(d, D, &hand);
    REQUIRE(ada.ok());
    REQUIRE(med.ok());
    CHECK(ada.fitted == 30);
    CHECK(std::abs(ada.scale / s - 1) < 0.01);  // (std distributions differ between libstdc++ and libc++)
    CHECK(std::abs(ada.scale / s - 1) < std::abs(med.scale / s - 1));
    CHECK(ada.relativeSpread < 0.05);
  }
  // With a ±10 % bias per keyframe, the median over 30 keyframes still lands within a few %.
  makeKeyframes(11, true, s, d, D, hand);
  const hawor::SequenceScale<double> ada = hawor::adaptiveScale(d, D, &hand);
  CHECK(std::abs(ada.scale / s - 1) < 0.03);
  CHECK(ada.relativeSpread > 0.03);  // the keyframes disagree: the spread shows it
}

TEST_CASE("AdaSM: sampling on the SLAM depth removes the truncation bias of sparse windows", "[scale]") {
  // Sparse keyframes like a SLAM's: 150 points, depth density growing with distance (few in the
  // 0.4–0.7 m window, so it widens), 8 % noise, no outliers, no bias. Selecting on the noisy
  // metric depth keeps the points whose noise pushed them inside the window: D/d low on average.
  const double s = 2.3;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> N(0, 1);
  double errOfficial = 0, errSlam = 0;
  const int trials = 40;
  for (int trial = 0; trial < trials; ++trial) {
    std::vector<std::vector<double>> d(20), D(20);
    for (int k = 0; k < 20; ++k) {
      for (int i = 0; i < 150; ++i) {
        const double truth = 0.5 + 3.5 * std::sqrt(U(rng));
        d[k].push_back(truth / s);
        D[k].push_back(truth * (1 + 0.08 * N(rng)));
      }
    }
    hawor::AdaptiveScaleOptions<double> o;
    errOfficial += hawor::adaptiveScale(d, D, nullptr, o).scale / s - 1;
    o.sampling = hawor::AdaSmSampling::SlamDepth;
    errSlam += hawor::adaptiveScale(d, D, nullptr, o).scale / s - 1;
  }
  errOfficial /= trials, errSlam /= trials;
  INFO("mean relative error: official sampling " << errOfficial << ", SLAM-depth sampling " << errSlam);
  CHECK(errOfficial < -0.01);             // the bias the variant removes (negative: D truncated)
  CHECK(std::abs(errSlam) < 0.005);
  CHECK(std::abs(errSlam) < 0.3 * std::abs(errOfficial));
}

TEST_CASE("AdaSM: widening per keyframe, degenerate input never gives a NaN scale silently", "[scale]") {
  hawor::AdaptiveScaleOptions<double> opt;
  // Everything at 1.95 m metric depth: outside [0.4, 0.7] until far has grown to 2.0 (13 steps).
  std::vector<double> d(100, 4.0), D(100, 1.95);
  const hawor::KeyframeScale<double> k = hawor::adaptiveKeyframeScale(d, D, nullptr, opt);
  REQUIRE(k.ok());
  CHECK(k.scale == Approx(1.95 / 4).epsilon(1e-6));
  CHECK(k.widenings == 13);
  // The next keyframe starts from the default window again (reset per keyframe).
  std::vector<double> d2(100, 1.0), D2(100, 0.55);
  const hawor::KeyframeScale<double> k2 = hawor::adaptiveKeyframeScale(d2, D2, nullptr, opt);
  CHECK(k2.widenings == 0);
  CHECK(k2.nearM == Approx(0.4));
  // No usable pixel: NaN per keyframe, and the sequence reports not ok.
  std::vector<double> bad = {std::nan(""), -1.0, 0.0, std::numeric_limits<double>::infinity()};
  std::vector<double> badD = {1.0, 1.0, 1.0, 1.0};
  CHECK_FALSE(hawor::adaptiveKeyframeScale(bad, badD).ok());
  std::vector<char> allMasked(100, 1);
  CHECK_FALSE(hawor::adaptiveKeyframeScale(d2, D2, &allMasked).ok());
  const hawor::SequenceScale<double> none = hawor::adaptiveScale<double>({bad}, {badD});
  CHECK_FALSE(none.ok());
  CHECK(none.fitted == 0);
  // Mismatched lengths and invalid options throw.
  std::vector<double> shorter(50, 1.0);
  CHECK_THROWS_AS(hawor::adaptiveKeyframeScale(d, shorter, nullptr, opt), hawor::Error);
  opt.farM = 0.3;
  CHECK_THROWS_AS(hawor::adaptiveKeyframeScale(d, D, nullptr, opt), hawor::Error);
}

TEST_CASE("common median and percentile: order statistics of shuffled data", "[scale]") {
  std::mt19937 rng(4);
  for (int n : {1, 2, 3, 10, 11}) {
    std::vector<double> v(n);
    for (int i = 0; i < n; ++i) v[static_cast<std::size_t>(i)] = double(i * i);  // sorted: i²
    std::shuffle(v.begin(), v.end(), rng);
    const double med = n % 2 ? double((n / 2) * (n / 2)) : 0.5 * double((n / 2 - 1) * (n / 2 - 1) + (n / 2) * (n / 2));
    CHECK(hawor::median(v) == med);
    CHECK(hawor::percentile(v, 0.0) == 0.0);
    CHECK(hawor::percentile(v, 1.0) == double((n - 1) * (n - 1)));
    // q = 0.25: position 0.25·(n−1) between i² and (i+1)².
    const double pos = 0.25 * (n - 1);
    const int i = static_cast<int>(pos);
    const double expect = i + 1 < n ? i * i + (pos - i) * ((i + 1) * (i + 1) - i * i) : double(i * i);
    CHECK(hawor::percentile(v, 0.25) == Approx(expect));
  }
  CHECK(std::isnan(hawor::median(std::vector<float>{})));
  CHECK(hawor::percentile({}, 0.5) == 0.0);
  // madSigma: 1.4826 × the median absolute deviation, brute force over the sorted deviations;
  // about σ for Gaussian samples.
  const std::vector<double> w = {3.0, -1.0, 7.5, 2.0, 2.0, 40.0};
  std::vector<double> dev;
  for (double x : w) dev.push_back(std::abs(x - 2.5));
  std::sort(dev.begin(), dev.end());
  CHECK(hawor::madSigma(w, 2.5) == Approx(1.4826 * 0.5 * (dev[2] + dev[3])));
  std::normal_distribution<double> N(0.0, 0.3);
  std::vector<double> g(20001);
  for (double& x : g) x = 5.0 + N(rng);
  CHECK(hawor::madSigma(g, 5.0) == Approx(0.3).epsilon(0.03));
  CHECK(std::isnan(hawor::madSigma(std::vector<float>{}, 0.0f)));
}

TEMPLATE_TEST_CASE("huberLocation minimises the Huber loss (brute force)", "[scale]", float, double) {
  using S = TestType;
  std::mt19937 rng(17);
  std::normal_distribution<double> N(0, 1);
  std::uniform_real_distribution<double> U(0, 1);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<S> x;
    const int n = 5 + trial * 3;
    for (int i = 0; i < n; ++i) x.push_back(S(U(rng) < 0.2 ? 5 + 3 * N(rng) : 0.1 * N(rng)));
    const S mu = hawor::huberLocation(x);
    // the same objective on a fine grid, with the same σ (1.4826·MAD about the median)
    std::vector<double> xd(x.begin(), x.end()), dev;
    std::vector<double> sorted = xd;
    std::sort(sorted.begin(), sorted.end());
    const double med = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
    for (double v : xd) dev.push_back(std::abs(v - med));
    std::sort(dev.begin(), dev.end());
    const double sigma = 1.4826 * (n % 2 ? dev[n / 2] : 0.5 * (dev[n / 2 - 1] + dev[n / 2]));
    const double c = 1.345 * sigma;
    const auto loss = [&](double m) {
      double L = 0;
      for (double v : xd) {
        const double r = std::abs(v - m);
        L += r <= c ? 0.5 * r * r : c * r - 0.5 * c * c;
      }
      return L;
    };
    double best = med, bestL = loss(med);
    for (int i = 0; i <= 200000; ++i) {
      const double m = sorted.front() + (sorted.back() - sorted.front()) * i / 200000.0;
      if (loss(m) < bestL) bestL = loss(m), best = m;
    }
    INFO("trial " << trial << " n " << n);
    CHECK(loss(double(mu)) <= bestL * (1 + (std::is_same<S, float>::value ? 1e-5 : 1e-9)) + 1e-12);
    CHECK(std::abs(double(mu) - best) < (std::is_same<S, float>::value ? 1e-3 : 1e-4));
  }
  CHECK(std::isnan(hawor::huberLocation(std::vector<S>{})));
  CHECK(hawor::huberLocation(std::vector<S>{S(2), S(2), S(2), S(9)}) == S(2));  // MAD 0: the median
}

TEST_CASE("AdaSM: the Huber combine beats the median over keyframes under per-keyframe bias",
          "[scale]") {
  // 30 keyframes per draw, each biased by U(−10 %, +10 %) (a depth network's per-frame scale
  // error, as in bench_scale.py), 3 of them wild (×0.5 or ×2): over 200 draws the Huber estimate
  // of the log-scales has a clearly smaller error than their median, and ignores the wild ones.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-0.1, 0.1);
  double errMedian = 0, errHuber = 0, worstHuber = 0;
  for (int draw = 0; draw < 200; ++draw) {
    hawor::SequenceScale<double> a, b;
    for (int k = 0; k < 30; ++k) {
      double s = 0.37 * (1 + U(rng));
      if (k < 3) s *= (k % 2) ? 2.0 : 0.5;
      a.perKeyframe.push_back(s);
    }
    b.perKeyframe = a.perKeyframe;
    hawor::scale_detail::summarise(a, hawor::KeyframeCombine::Median);
    hawor::scale_detail::summarise(b, hawor::KeyframeCombine::Huber);
    errMedian += std::abs(a.scale / 0.37 - 1) / 200;
    errHuber += std::abs(b.scale / 0.37 - 1) / 200;
    worstHuber = std::max(worstHuber, std::abs(b.scale / 0.37 - 1));
  }
  INFO("mean |error|: median " << errMedian << ", Huber " << errHuber);
  CHECK(errHuber < 0.8 * errMedian);
  CHECK(worstHuber < 0.05);
}
