// hawor/slam/ransac.hpp — generic adaptive RANSAC with MSAC scoring (Fischler & Bolles 1981;
// Torr & Zisserman 2000, "MLESAC", for the truncated-quadratic MSAC cost).
//
// The caller supplies two callbacks:
//   solve(const int* sample, std::vector<Model>& models)   fits 0..k models to `sampleSize`
//                                                          data indices (models arrives empty)
//   errorSq(const Model& m, int i) -> Scalar               squared residual e_i² of datum i
// A model's MSAC cost is C = Σ_i min(e_i², T²) (T = options.threshold; a non-finite e_i² counts
// as T²); the model with the lowest cost wins, its inliers are the data with e_i² < T².
// Adaptive stopping: after a new best model with inlier ratio w, the number of samples needed so
// that at least one is all-inlier with probability p is N = ⌈log(1 − p) / log(1 − w^s)⌉
// (s = sampleSize); the loop runs max(minIterations, min(N, maxIterations)) samples.
// Sampling is deterministic for a seed and identical natively and in WebAssembly: std::mt19937 is
// fully specified by the standard, and indices are drawn from its raw output by rejection (the
// std:: distributions are implementation-defined).
// Pure function of its inputs; thread-safe when the callbacks are.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "hawor/common.hpp"

namespace hawor {

template <typename Scalar>
struct RansacOptions {
  Scalar threshold = Scalar(1);       ///< inlier threshold T on the residual (not squared)
  Scalar confidence = Scalar(0.999);  ///< p of the stopping rule, in (0, 1)
  int minIterations = 0;              ///< samples drawn at least (unless no sample is possible)
  int maxIterations = 1000;           ///< hard cap on samples drawn
  std::uint32_t seed = 0x5eedu;       ///< engine seed: equal seeds give equal results
};

template <typename Model, typename Scalar>
struct RansacResult {
  bool found = false;          ///< a model with at least one inlier was found
  Model model{};               ///< the best model (lowest MSAC cost)
  std::vector<char> inliers;   ///< per datum: e_i² < T² under `model`
  int numInliers = 0;
  Scalar cost = std::numeric_limits<Scalar>::infinity();  ///< MSAC cost of `model`
  int iterations = 0;          ///< samples drawn
};

/// N = ⌈log(1 − p)/log(1 − w^s)⌉, clamped to [0, cap]: samples needed so that one is all-inlier
/// with probability p when a fraction w of the data are inliers (Fischler & Bolles).
template <typename Scalar>
int ransacRequiredIterations(Scalar inlierRatio, int sampleSize, Scalar confidence, int cap) {
  if (!(inlierRatio > Scalar(0))) return cap;
  if (inlierRatio >= Scalar(1)) return 0;
  const double ws = std::pow(static_cast<double>(inlierRatio), sampleSize);
  const double denom = std::log1p(-ws);  // log(1 − w^s) without cancellation for small w^s
  if (!(denom < 0.0)) return cap;
  const double n = std::ceil(std::log1p(-static_cast<double>(confidence)) / denom);
  if (!(n < static_cast<double>(cap))) return cap;
  return n < 0.0 ? 0 : static_cast<int>(n);
}

namespace ransac_detail {

/// Uniform integer in [0, n) from the raw engine output by rejection (no modulo bias).
inline int uniformIndex(std::mt19937& rng, int n) {
  const std::uint32_t un = static_cast<std::uint32_t>(n);
  const std::uint32_t limit = 0xFFFFFFFFu - (0xFFFFFFFFu % un);  // largest multiple of n, minus 1
  std::uint32_t r;
  do {
    r = static_cast<std::uint32_t>(rng());
  } while (r >= limit);
  return static_cast<int>(r % un);
}

/// s distinct indices in [0, n) (s is small: a linear duplicate check is the fastest).
inline void drawSample(std::mt19937& rng, int n, int s, int* out) {
  for (int k = 0; k < s; ++k) {
    int idx;
    bool dup;
    do {
      idx = uniformIndex(rng, n);
      dup = false;
      for (int j = 0; j < k; ++j) dup = dup || out[j] == idx;
    } while (dup);
    out[k] = idx;
  }
}

}  // namespace ransac_detail

/// Adaptive MSAC (file comment). numData < sampleSize gives found = false (no sample possible);
/// invalid options (sampleSize < 1, threshold not finite and > 0, confidence outside (0, 1),
/// maxIterations < 1) throw hawor::Error.
template <typename Model, typename Scalar, typename Solve, typename ErrorSq>
RansacResult<Model, Scalar> ransac(int numData, int sampleSize, Solve&& solve, ErrorSq&& errorSq,
                                   const RansacOptions<Scalar>& opt) {
  if (sampleSize < 1) throw Error("ransac: sampleSize must be >= 1");
  if (!(opt.threshold > Scalar(0)) || !std::isfinite(opt.threshold)) {
    throw Error("ransac: threshold must be finite and > 0");
  }
  if (!(opt.confidence > Scalar(0) && opt.confidence < Scalar(1))) {
    throw Error("ransac: confidence must be in (0, 1)");
  }
  if (opt.maxIterations < 1) throw Error("ransac: maxIterations must be >= 1");
  RansacResult<Model, Scalar> res;
  if (numData < sampleSize || numData <= 0) return res;

  const Scalar T2 = opt.threshold * opt.threshold;
  std::mt19937 rng(opt.seed);
  std::vector<int> sample(static_cast<std::size_t>(sampleSize));
  std::vector<Model> models;
  int needed = opt.maxIterations;

  for (int it = 0; it < opt.maxIterations; ++it) {
    if (it >= needed && it >= opt.minIterations) break;
    res.iterations = it + 1;
    ransac_detail::drawSample(rng, numData, sampleSize, sample.data());
    models.clear();
    solve(static_cast<const int*>(sample.data()), models);
    for (const Model& m : models) {
      // MSAC cost with early exit once it cannot beat the best so far.
      Scalar cost = Scalar(0);
      int inl = 0;
      bool beaten = false;
      for (int i = 0; i < numData; ++i) {
        const Scalar e2 = errorSq(m, i);
        if (e2 < T2) {  // false for NaN
          cost += e2;
          ++inl;
        } else {
          cost += T2;
        }
        if (cost >= res.cost) {
          beaten = true;
          break;
        }
      }
      if (beaten || inl == 0) continue;
      res.cost = cost;
      res.model = m;
      res.found = true;
      needed = ransacRequiredIterations(Scalar(inl) / Scalar(numData), sampleSize, opt.confidence,
                                        opt.maxIterations);
    }
  }
  if (!res.found) return res;
  res.inliers.assign(static_cast<std::size_t>(numData), 0);
  res.numInliers = 0;
  for (int i = 0; i < numData; ++i) {
    if (errorSq(res.model, i) < T2) {
      res.inliers[static_cast<std::size_t>(i)] = 1;
      ++res.numInliers;
    }
  }
  return res;
}

}  // namespace hawor
