// hawor/scale/robust_scale.hpp — metric scale of a monocular SLAM from metric depth: the official
// adaptive-sampling robust fit (AdaSM, docs/design.md §6, HaWoR's est_scale_hybrid) and the plain median
// baseline ("w/o AdaSM" in the paper's ablation: ATE-S 14.61 mm with AdaSM, 20.97 mm without).
//
// Per keyframe, SLAM depths d_i (map units, > 0) and metric depths D_i (metres) at the same pixels,
// hand pixels already dropped by the caller (or flagged in `masked`):
//   1. keep near < D_i < far (defaults 0.4 m, 0.7 m: the hands' working range, where a depth
//      network is most accurate for egocentric video); s ← median(D_i / d_i);
//   2. 10 times: keep near < D_i < far and 0 < s·d_i < far, s ← median(D_i / d_i);
//   3. α = argmin_α (1/n) Σ GMoF(α·d_i − D_i),  GMoF(r) = σ²r²/(σ² + r²),  σ = 0.5 m,
//      over the pixels kept in step 2, from s (the original runs BFGS from the median; here a
//      1-D global search — a log-spaced scan over [s/8, 8s] and golden-section refinement of the
//      best bracket — so a bad start cannot end in a far local minimum);
//   4. no pixel kept or a non-finite α: widen near −= 0.1 (not below 0), far += 0.1 and retry
//      from step 1, up to maxWidenings times. The widening is reset for every keyframe (the
//      original carries it over to all later keyframes, a bug not copied).
// The scale is the median of the keyframes' α (official), or (KeyframeCombine::Huber, an option)
// the Huber M-estimate of their log: μ = argmin Σ_k ρ_H((log α_k − μ)/σ), ρ_H(u) = u²/2 for
// |u| ≤ c, c|u| − c²/2 beyond, c = 1.345, σ = 1.4826·MAD of log α_k, solved by IRLS from the
// median. A depth network's per-frame bias makes the keyframes' α scatter about the truth; the
// median of n of them has about √(π/2) ≈ 1.25× the standard error of the mean for Gaussian
// scatter and √3 ≈ 1.7× for uniform scatter (its density at the centre is low), while the Huber
// estimate is within 5 % of the mean's efficiency there and still ignores a minority of wild
// keyframes. Pure functions, thread-safe.
//
// Sampling::SlamDepth (an option; Official is the default): steps 2–3 select the pixels by the
// SLAM depth, near < s·d_i < far, plus a gate symmetric about the prediction,
// |D_i / (s·d_i) − 1| < gate, instead of by the metric depth D_i. Selecting on the noisy D_i
// truncates its noise at the window's edges (a pixel whose D_i fell below `far` is kept, its twin
// that rose above is not), which biases D/d low wherever the window holds few points — the usual
// case with a sparse SLAM's depths, where the window is widened until it holds minPixels. d_i is
// independent of the depth network's noise, so selecting on it does not bias the ratio; the gate
// still drops the outliers the official D-window dropped (σ = 0.5 m alone barely does at these
// depths). With sparse depths use minPixels ≈ 30 ('hawor scale' does; bench_scale.py measures
// both samplings).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"

namespace hawor {

/// Geman–McClure robust penalty GMoF(r) = σ²r²/(σ² + r²) (bounded by σ²).
template <typename Scalar>
inline Scalar gmof(Scalar r, Scalar sigma) {
  const Scalar s2 = sigma * sigma, r2 = r * r;
  return s2 * r2 / (s2 + r2);
}

/// Mean GMoF(α·d_i − D_i) over the pairs (the objective of step 3).
template <typename Scalar>
Scalar gmofObjective(const std::vector<Scalar>& d, const std::vector<Scalar>& D, Scalar alpha, Scalar sigma) {
  if (d.empty()) return std::numeric_limits<Scalar>::quiet_NaN();
  double s = 0;
  for (std::size_t i = 0; i < d.size(); ++i) s += double(gmof(alpha * d[i] - D[i], sigma));
  return Scalar(s / double(d.size()));
}

/// The 1-D robust fit of step 3: argmin over α > 0 of gmofObjective, searched in [lo, hi]
/// (log-spaced scan of `samples` points, then golden-section search in the best point's
/// neighbouring interval to relative precision 1e-10). NaN for empty input or a bad interval.
template <typename Scalar>
Scalar minimiseGmofScale(const std::vector<Scalar>& d, const std::vector<Scalar>& D, Scalar sigma, Scalar lo, Scalar hi,
                         int samples = 256) {
  if (d.size() != D.size()) throw Error("minimiseGmofScale: " + std::to_string(d.size()) + " SLAM depths but " +
                                        std::to_string(D.size()) + " metric depths");
  if (d.empty() || !(lo > Scalar(0)) || !(hi > lo) || !std::isfinite(double(hi)) || !(sigma > Scalar(0)) || samples < 3) {
    return std::numeric_limits<Scalar>::quiet_NaN();
  }
  const double llo = std::log(double(lo)), lhi = std::log(double(hi));
  auto at = [&](int k) { return std::exp(llo + (lhi - llo) * double(k) / double(samples - 1)); };
  int best = 0;
  double fbest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < samples; ++k) {
    const double f = double(gmofObjective(d, D, Scalar(at(k)), sigma));
    if (f < fbest) fbest = f, best = k;
  }
  if (!std::isfinite(fbest)) return std::numeric_limits<Scalar>::quiet_NaN();
  // Golden-section search on [a, b] around the best sample (the objective is smooth).
  double a = at(std::max(best - 1, 0)), b = at(std::min(best + 1, samples - 1));
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = double(gmofObjective(d, D, Scalar(x1), sigma)), f2 = double(gmofObjective(d, D, Scalar(x2), sigma));
  for (int it = 0; it < 200 && (b - a) > 1e-10 * (std::abs(a) + std::abs(b)); ++it) {
    if (f1 <= f2) {
      b = x2, x2 = x1, f2 = f1;
      x1 = b - g * (b - a);
      f1 = double(gmofObjective(d, D, Scalar(x1), sigma));
    } else {
      a = x1, x1 = x2, f1 = f2;
      x2 = a + g * (b - a);
      f2 = double(gmofObjective(d, D, Scalar(x2), sigma));
    }
  }
  const double x = 0.5 * (a + b);
  return double(gmofObjective(d, D, Scalar(x), sigma)) <= fbest ? Scalar(x) : Scalar(at(best));
}

/// Which depth selects the pixels in AdaSM's re-selection and fit (file comment).
enum class AdaSmSampling { Official, SlamDepth };

/// How the keyframes' α become one scale (file comment): the median (official) or Huber.
enum class KeyframeCombine { Median, Huber };

template <typename Scalar>
struct AdaptiveScaleOptions {
  AdaSmSampling sampling = AdaSmSampling::Official;
  Scalar nearM = Scalar(0.4);   ///< adaptive sampling window (metres of metric depth)
  Scalar farM = Scalar(0.7);
  Scalar sigma = Scalar(0.5);   ///< GMoF scale (metres)
  int medianIterations = 10;
  int maxWidenings = 20;        ///< per keyframe: near −= 0.1, far += 0.1
  Scalar widenStep = Scalar(0.1);
  int minPixels = 10;           ///< fewer kept pixels than this counts as "nothing kept"
  Scalar gate = Scalar(0.25);   ///< SlamDepth sampling: keep |D/(s·d) − 1| < gate
  KeyframeCombine combine = KeyframeCombine::Median;  ///< over keyframes (adaptiveScale)
};

/// The result for one keyframe: α (NaN when nothing could be fitted), the median start, the
/// window finally used and the pixels kept.
template <typename Scalar>
struct KeyframeScale {
  Scalar scale = std::numeric_limits<Scalar>::quiet_NaN();
  Scalar medianScale = std::numeric_limits<Scalar>::quiet_NaN();
  Scalar nearM = Scalar(0), farM = Scalar(0);
  int kept = 0, widenings = 0;
  bool ok() const { return std::isfinite(double(scale)) && scale > Scalar(0); }
};

namespace scale_detail {

template <typename Scalar>
bool usable(Scalar d, Scalar D, const std::vector<char>* masked, std::size_t i) {
  return std::isfinite(double(d)) && std::isfinite(double(D)) && d > Scalar(0) && D > Scalar(0) &&
         !(masked && (*masked)[i]);
}

}  // namespace scale_detail

/// AdaSM for one keyframe (file comment). slamDepth and metricDepth are paired per pixel;
/// `masked` (optional, same length) flags hand pixels to drop. Non-finite or non-positive values
/// are skipped. Throws only on mismatched lengths or invalid options.
template <typename Scalar>
KeyframeScale<Scalar> adaptiveKeyframeScale(const std::vector<Scalar>& slamDepth, const std::vector<Scalar>& metricDepth,
                                            const std::vector<char>* masked = nullptr,
                                            const AdaptiveScaleOptions<Scalar>& opt = {}) {
  using hawor::median;
  if (slamDepth.size() != metricDepth.size() || (masked && masked->size() != slamDepth.size())) {
    throw Error("adaptiveKeyframeScale: SLAM depths, metric depths and mask differ in length");
  }
  if (!(opt.nearM >= Scalar(0)) || !(opt.farM > opt.nearM) || !(opt.sigma > Scalar(0)) || opt.medianIterations < 0 ||
      opt.maxWidenings < 0 || !(opt.widenStep > Scalar(0)) || opt.minPixels < 1 || !(opt.gate > Scalar(0))) {
    throw Error("adaptiveKeyframeScale: invalid options (need 0 <= near < far, sigma > 0)");
  }
  KeyframeScale<Scalar> out;
  Scalar nearM = opt.nearM, farM = opt.farM;
  const std::size_t n = slamDepth.size();
  std::vector<Scalar> ratio, dk, Dk;
  for (int w = 0; w <= opt.maxWidenings; ++w) {
    out.nearM = nearM, out.farM = farM, out.widenings = w;
    ratio.clear();
    for (std::size_t i = 0; i < n; ++i) {
      const Scalar d = slamDepth[i], D = metricDepth[i];
      if (scale_detail::usable(d, D, masked, i) && D > nearM && D < farM) ratio.push_back(D / d);
    }
    Scalar s = static_cast<int>(ratio.size()) >= opt.minPixels ? median(ratio) : std::numeric_limits<Scalar>::quiet_NaN();
    if (std::isfinite(double(s))) {
      out.medianScale = s;
      for (int it = 0; it <= opt.medianIterations; ++it) {
        ratio.clear(), dk.clear(), Dk.clear();
        for (std::size_t i = 0; i < n; ++i) {
          const Scalar d = slamDepth[i], D = metricDepth[i];
          if (!scale_detail::usable(d, D, masked, i)) continue;
          const Scalar ds = d * s;
          if (opt.sampling == AdaSmSampling::Official
                  ? !(D > nearM && D < farM && ds > Scalar(0) && ds < farM)
                  : !(ds > nearM && ds < farM && std::abs(D / ds - Scalar(1)) < opt.gate)) {
            continue;
          }
          ratio.push_back(D / d);
          dk.push_back(d);
          Dk.push_back(D);
        }
        if (static_cast<int>(ratio.size()) < opt.minPixels) {
          s = std::numeric_limits<Scalar>::quiet_NaN();
          break;
        }
        if (it < opt.medianIterations) s = median(ratio);
      }
      if (std::isfinite(double(s))) {
        out.kept = static_cast<int>(dk.size());
        const Scalar a = minimiseGmofScale(dk, Dk, opt.sigma, s / Scalar(8), s * Scalar(8));
        if (std::isfinite(double(a)) && a > Scalar(0)) {
          out.scale = a;
          return out;
        }
      }
    }
    nearM = std::max(Scalar(0), nearM - opt.widenStep);
    farM += opt.widenStep;
  }
  out.kept = 0;
  return out;
}

/// Scale over keyframes: the median (or Huber estimate) of the keyframes' α (those fitted).
template <typename Scalar>
struct SequenceScale {
  Scalar scale = std::numeric_limits<Scalar>::quiet_NaN();
  int keyframes = 0, fitted = 0;
  /// Robust spread of the keyframe scales: 1.4826·MAD / median (0 = all agree).
  Scalar relativeSpread = std::numeric_limits<Scalar>::quiet_NaN();
  std::vector<Scalar> perKeyframe;  ///< NaN where nothing could be fitted
  bool ok() const { return std::isfinite(double(scale)) && scale > Scalar(0); }
};

/// Huber M-estimate of location of x (file comment): IRLS weights w = min(1, c·σ/|x − μ|) from
/// μ = median, σ = 1.4826·MAD, until μ moves by less than 1e-12·(1 + |μ|). σ = 0 (at least half
/// the values equal) gives the median. NaN when x is empty.
template <typename Scalar>
Scalar huberLocation(const std::vector<Scalar>& x, Scalar c = Scalar(1.345), int iterations = 100) {
  if (x.empty()) return std::numeric_limits<Scalar>::quiet_NaN();
  Scalar mu = median(x);
  const Scalar sigma = madSigma(x, mu);
  if (!(sigma > Scalar(0))) return mu;
  for (int it = 0; it < iterations; ++it) {
    Scalar sw = 0, swx = 0;
    for (Scalar v : x) {
      const Scalar r = std::abs(v - mu);
      const Scalar w = r <= c * sigma ? Scalar(1) : c * sigma / r;
      sw += w;
      swx += w * v;
    }
    const Scalar next = swx / sw;
    const bool done = std::abs(next - mu) <= Scalar(1e-12) * (Scalar(1) + std::abs(mu));
    mu = next;
    if (done) break;
  }
  return mu;
}

namespace scale_detail {
template <typename Scalar>
void summarise(SequenceScale<Scalar>& out, KeyframeCombine combine = KeyframeCombine::Median) {
  std::vector<Scalar> good;
  for (Scalar s : out.perKeyframe) {
    if (std::isfinite(double(s)) && s > Scalar(0)) good.push_back(s);
  }
  out.fitted = static_cast<int>(good.size());
  if (good.empty()) return;
  const Scalar mid = median(good);
  if (combine == KeyframeCombine::Median) {
    out.scale = mid;
  } else {
    std::vector<Scalar> logs;
    for (Scalar s : good) logs.push_back(std::log(s));
    out.scale = std::exp(huberLocation(logs));
  }
  out.relativeSpread = madSigma(good, mid) / mid;
}
}  // namespace scale_detail

/// AdaSM over keyframes: depth pairs per keyframe (optional hand flags per keyframe).
template <typename Scalar>
SequenceScale<Scalar> adaptiveScale(const std::vector<std::vector<Scalar>>& slamDepth,
                                    const std::vector<std::vector<Scalar>>& metricDepth,
                                    const std::vector<std::vector<char>>* masked = nullptr,
                                    const AdaptiveScaleOptions<Scalar>& opt = {}) {
  if (slamDepth.size() != metricDepth.size() || (masked && masked->size() != slamDepth.size())) {
    throw Error("adaptiveScale: " + std::to_string(slamDepth.size()) + " keyframes of SLAM depth but " +
                std::to_string(metricDepth.size()) + " of metric depth");
  }
  SequenceScale<Scalar> out;
  out.keyframes = static_cast<int>(slamDepth.size());
  for (std::size_t k = 0; k < slamDepth.size(); ++k) {
    out.perKeyframe.push_back(
        adaptiveKeyframeScale(slamDepth[k], metricDepth[k], masked ? &(*masked)[k] : nullptr, opt).scale);
  }
  scale_detail::summarise(out, opt.combine);
  return out;
}

/// The "w/o AdaSM" baseline: per keyframe median(D/d) over all usable pixels, median over keyframes.
template <typename Scalar>
SequenceScale<Scalar> medianScale(const std::vector<std::vector<Scalar>>& slamDepth,
                                  const std::vector<std::vector<Scalar>>& metricDepth,
                                  const std::vector<std::vector<char>>* masked = nullptr) {
  if (slamDepth.size() != metricDepth.size() || (masked && masked->size() != slamDepth.size())) {
    throw Error("medianScale: keyframe counts of SLAM and metric depth differ");
  }
  SequenceScale<Scalar> out;
  out.keyframes = static_cast<int>(slamDepth.size());
  for (std::size_t k = 0; k < slamDepth.size(); ++k) {
    if (slamDepth[k].size() != metricDepth[k].size() || (masked && (*masked)[k].size() != slamDepth[k].size())) {
      throw Error("medianScale: keyframe " + std::to_string(k) + ": depth lists differ in length");
    }
    std::vector<Scalar> r;
    for (std::size_t i = 0; i < slamDepth[k].size(); ++i) {
      if (scale_detail::usable(slamDepth[k][i], metricDepth[k][i], masked ? &(*masked)[k] : nullptr, i)) {
        r.push_back(metricDepth[k][i] / slamDepth[k][i]);
      }
    }
    out.perKeyframe.push_back(hawor::median(r));
  }
  scale_detail::summarise(out);
  return out;
}

}  // namespace hawor
