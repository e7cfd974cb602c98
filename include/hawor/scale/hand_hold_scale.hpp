// hawor/scale/hand_hold_scale.hpp — the hold cue of the hand-anchored metric scale: a hand that
// holds still in the world (resting on the table, holding an object) while the head moves.
//
// With the SLAM camera-to-world rotation R_t and centre c_t (map units) and the hand's metric
// camera-frame position h_t, the world hand is p_t(α) = x_t + α·c_t, x_t = R_t·h_t. Over a window
// w of W consecutive frames in which the hand is still, p_t(α*) = p̄ up to the fit's noise; with
// the window means removed (the still point is unknown),
//   RSS_w(α) = Σ_t |x̃_t + α·c̃_t|² = xx_w + 2α·xc_w + α²·cc_w,   x̃ = x − x̄,  c̃ = c − c̄,
// a quadratic in α, and q_w(α) = RSS_w(α) / (σ²·(3W − 3)) ≈ 1 for a still hand at the right α
// (σ: the per-axis noise of x, estimated from the data as 1.4826·median|Δ²x| / √6, the MAD of
// second differences, floored at minNoise). Holds are not known in advance, so α is the consensus of all windows:
//   α₀ = argmin_α Σ_w min(q_w(α), τ)            (a window explains at most τ; log-spaced scan)
// which makes as many windows still as possible; windows in which the camera hardly moves cost
// the same at every α and do not matter. Then, over the windows still at α (q_w < τ), the
// least-squares α = −Σ xc_w / Σ cc_w, re-selecting the windows three times.
// Standard error: σ·√(W / Σ cc_w) (each frame lies in up to W overlapping windows); the
// confidence is 1 / (1 + (s.e./α / 0.05)²), zero without still windows that saw the camera move.
// Limits: a hand carried by a body that moves with the camera at low frequency looks still at too
// small an α; windows shorter than a real hold and τ ≈ 3 keep that small (bench_scale.py).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/scale/hand_track.hpp"

namespace hawor {

template <typename Scalar>
struct HandHoldOptions {
  int window = 15;                ///< W frames (0.5 s at 30 fps: shorter than a hold)
  Scalar tau = Scalar(3);         ///< a window is "still" when q_w < τ
  int scanSamples = 4000;         ///< log-spaced samples of the consensus scan
  Scalar scanDecades = Scalar(3); ///< scan α_ref·10^±decades, α_ref = √(Σ xx / Σ cc)
  int refinements = 3;
  int minStillWindows = 3;
  /// Floor of σ (metres): well below a fitted hand's noise (1–2 mm or more), so it never binds on
  /// real data, but noise-free input (synthetic, a camera moving on a straight line: every
  /// second difference of x is 0) still gets a scale instead of σ = 0.
  Scalar minNoise = Scalar(5e-4);
};

/// The hold scale (file comment). Throws on mismatched lengths or invalid options; the result is
/// not ok() when no window of W usable frames saw the camera move while the hand was still.
template <typename Scalar>
HandScaleResult<Scalar> handHoldScale(const std::vector<SE3<Scalar>>& T_w_c, const std::vector<HandTrack<Scalar>>& hands,
                                      const HandHoldOptions<Scalar>& opt = {}) {
  scale_detail::checkTracks("handHoldScale", T_w_c, hands);
  if (opt.window < 3 || !(opt.tau > Scalar(0)) || opt.scanSamples < 10 || !(opt.scanDecades > Scalar(0)) ||
      opt.refinements < 0 || opt.minStillWindows < 1 || !(opt.minNoise > Scalar(0))) {
    throw Error("handHoldScale: invalid options (window >= 3, tau > 0, scanSamples >= 10, minNoise > 0)");
  }
  HandScaleResult<Scalar> res;
  res.method = "holds";
  const std::size_t T = T_w_c.size(), W = static_cast<std::size_t>(opt.window);
  // Noise of x from second differences, and the windows' quadratics (double accumulation).
  std::vector<double> d2;
  struct Win {
    double xx, xc, cc;
  };
  std::vector<Win> wins;
  std::vector<Eigen::Vector3d> x(T), c(T);
  for (const HandTrack<Scalar>& H : hands) {
    std::vector<char> ok(T);
    for (std::size_t t = 0; t < T; ++t) {
      ok[t] = scale_detail::usableFrame(T_w_c, H, t);
      if (!ok[t]) continue;
      x[t] = (T_w_c[t].rotation() * H.positionCam[t]).template cast<double>();
      c[t] = T_w_c[t].translation().template cast<double>();
    }
    for (std::size_t t = 1; t + 1 < T; ++t) {
      if (ok[t - 1] && ok[t] && ok[t + 1]) {
        const Eigen::Vector3d a = x[t + 1] - 2 * x[t] + x[t - 1];
        for (int k = 0; k < 3; ++k) d2.push_back(std::abs(a(k)));
      }
    }
    std::size_t run = 0;  // usable frames ending at t
    for (std::size_t t = 0; t < T; ++t) {
      run = ok[t] ? run + 1 : 0;
      if (run < W) continue;
      const std::size_t s = t + 1 - W;
      Eigen::Vector3d xm = Eigen::Vector3d::Zero(), cm = Eigen::Vector3d::Zero();
      for (std::size_t i = s; i <= t; ++i) xm += x[i], cm += c[i];
      xm /= double(W), cm /= double(W);
      Win w{0, 0, 0};
      for (std::size_t i = s; i <= t; ++i) {
        const Eigen::Vector3d xt = x[i] - xm, ct = c[i] - cm;
        w.xx += xt.squaredNorm(), w.xc += xt.dot(ct), w.cc += ct.squaredNorm();
      }
      wins.push_back(w);
    }
  }
  res.residuals = static_cast<int>(wins.size());
  if (wins.empty() || d2.size() < 10) return res;
  std::nth_element(d2.begin(), d2.begin() + static_cast<std::ptrdiff_t>(d2.size() / 2), d2.end());
  const double sigma = std::max(1.4826 * d2[d2.size() / 2] / std::sqrt(6.0), double(opt.minNoise));
  double sxx = 0, scc = 0;
  for (const Win& w : wins) sxx += w.xx, scc += w.cc;
  if (!(sigma > 0) || !(scc > 0) || !(sxx > 0)) return res;
  const double norm = 1.0 / (sigma * sigma * double(3 * W - 3));
  const double tau = double(opt.tau);
  auto q = [&](const Win& w, double a) { return (w.xx + 2 * a * w.xc + a * a * w.cc) * norm; };
  // Consensus scan.
  const double ref = std::sqrt(sxx / scc), dec = double(opt.scanDecades) * std::log(10.0);
  double best = std::numeric_limits<double>::quiet_NaN(), fbest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < opt.scanSamples; ++k) {
    const double a = ref * std::exp(-dec + 2 * dec * double(k) / double(opt.scanSamples - 1));
    double f = 0;
    for (const Win& w : wins) f += std::min(q(w, a), tau);
    if (f < fbest) fbest = f, best = a;
  }
  // Least squares over the still windows, re-selected.
  double alpha = best, sumCc = 0;
  int still = 0;
  for (int it = 0; it <= opt.refinements; ++it) {
    double num = 0, den = 0;
    still = 0;
    for (const Win& w : wins) {
      if (q(w, alpha) < tau) num += w.xc, den += w.cc, ++still;
    }
    if (!(den > 0)) return res;
    sumCc = den;
    if (it < opt.refinements) alpha = -num / den;
  }
  res.restFrames = still;
  if (!(alpha > 0) || still < opt.minStillWindows) return res;
  const double se = sigma * std::sqrt(double(W) / sumCc);
  res.scale = Scalar(alpha);
  res.relativeStdError = Scalar(se / alpha);
  const double e = se / alpha / 0.05;
  res.confidence = Scalar(1.0 / (1.0 + e * e));
  return res;
}

}  // namespace hawor
