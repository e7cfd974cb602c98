// hawor/scale/hand_hold_scale.hpp — the hold cue of the hand-anchored metric scale: a hand that
// holds still in the world (resting on the table, holding an object) while the head moves.
//
// With the SLAM camera-to-world rotation R_t and centre c_t (map units) and the hand's metric
// camera-frame position h_t, the world hand is p_t(α) = x_t + α·c_t, x_t = R_t·h_t. Over a window
// w of W consecutive frames in which the hand is still, p_t(α*) = p_w up to the fit's noise.
// A hand fitted in one image is far less certain along its viewing ray (depth from the hand's
// size) than across it, so each frame's residual is weighted by its information matrix
//   Λ_t = I/σ_⊥² + (1/σ_∥² − 1/σ_⊥²)·u_t u_tᵀ,   u_t = x_t/|x_t| (the ray in the world frame),
// σ_∥, σ_⊥: the noise along and across the ray, each 1.4826·median|Δ²x·e| / √6 (the MAD of
// the second differences projected on the ray, resp. on two directions across it), floored at
// minNoise. The still point p_w is unknown; eliminating it (p_w = M⁻¹ Σ Λ_t y_t, M = Σ Λ_t,
// y_t = x_t + α c_t) leaves a quadratic in α,
//   RSS_w(α) = Σ y_tᵀΛ_t y_t − (Σ Λ_t y_t)ᵀ M⁻¹ (Σ Λ_t y_t) = xx_w + 2α·xc_w + α²·cc_w,
// and q_w(α) = RSS_w(α) / (3W − 3) ≈ 1 for a still hand at the right α (a generalised least-
// squares fit: with σ_∥ = σ_⊥ it is the plain fit with the window means removed). Holds are not
// known in advance, so α is the consensus of all windows:
//   α₀ = argmin_α Σ_w min(q_w(α), τ)            (a window explains at most τ; log-spaced scan)
// which makes as many windows still as possible; windows in which the camera hardly moves cost
// the same at every α and do not matter. Then, over the windows still at α (q_w < τ), the
// least-squares α = −Σ xc_w / Σ cc_w, re-selecting the windows three times. f has several local
// minima; they are tried best first, and the first whose fit pins α down (relative s.e. ≤ 25 %)
// answers: the small-α mode "the camera does not move" can win the count by a hair (every hand
// still in the camera frame is still there) but leaves α unconstrained.
// Standard error: √(W / Σ cc_w) (each frame lies in up to W overlapping windows); the
// confidence is 1 / (1 + (s.e./α / 0.05)²), zero without still windows that saw the camera move.
// Why the weighting: with isotropic weights the depth error (several mm, and slowly varying)
// dominates the windows; on bench_scale.py's fast_turns (short holds) the isotropic fit is
// biased 4 % low even on the true trajectory and fails outright in some draws.
// Carried hands: a window whose hand is still in the CAMERA frame (the same test on the
// camera-frame positions h_t with Λ there) is left out: such a hand moves with the head, says
// nothing about α, and looks still in the world at a small α. With a regressor's per-frame jitter
// (bench_world.py --hand-noise 5) the noise estimate grows, those windows passed τ and pulled α
// 2-10x low at a high confidence; a real hold while the head moves is not still in the camera.
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
  int maxModes = 8;                       ///< local minima of the scan tried, best first
  Scalar maxRelativeError = Scalar(0.25); ///< a mode answers when its relative s.e. is at most this
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
      opt.refinements < 0 || opt.minStillWindows < 1 || !(opt.minNoise > Scalar(0)) || opt.maxModes < 1 ||
      !(opt.maxRelativeError > Scalar(0))) {
    throw Error("handHoldScale: invalid options (window >= 3, tau > 0, scanSamples >= 10, minNoise > 0, maxModes >= 1, "
                "maxRelativeError > 0)");
  }
  HandScaleResult<Scalar> res;
  res.method = "holds";
  const std::size_t T = T_w_c.size(), W = static_cast<std::size_t>(opt.window);
  // Noise of x from second differences along and across the ray, then the windows' quadratics
  // (double accumulation).
  std::vector<double> dRay, dAcross;
  struct Win {
    double xx, xc, cc;
  };
  std::vector<Win> wins;
  // Per hand: usable frames, world-rotated positions x_t and rays u_t; the centres c_t.
  const std::size_t H = hands.size();
  std::vector<std::vector<char>> usable(H, std::vector<char>(T, 0));
  std::vector<std::vector<Eigen::Vector3d>> x(H, std::vector<Eigen::Vector3d>(T)), u = x, hc = x;
  std::vector<Eigen::Vector3d> c(T);
  for (std::size_t t = 0; t < T; ++t) c[t] = T_w_c[t].translation().template cast<double>();
  for (std::size_t h = 0; h < H; ++h) {
    for (std::size_t t = 0; t < T; ++t) {
      if (!(usable[h][t] = scale_detail::usableFrame(T_w_c, hands[h], t))) continue;
      hc[h][t] = hands[h].positionCam[t].template cast<double>();
      x[h][t] = T_w_c[t].rotation().template cast<double>() * hc[h][t];
      const double n = x[h][t].norm();
      u[h][t] = n > 0 ? Eigen::Vector3d(x[h][t] / n) : Eigen::Vector3d::Zero();
    }
    for (std::size_t t = 1; t + 1 < T; ++t) {
      if (!(usable[h][t - 1] && usable[h][t] && usable[h][t + 1]) || u[h][t].isZero()) continue;
      const Eigen::Vector3d a = x[h][t + 1] - 2 * x[h][t] + x[h][t - 1];
      // Two unit directions across the ray: any orthonormal pair (the noise is isotropic there).
      const Eigen::Vector3d e1 = u[h][t].unitOrthogonal(), e2 = u[h][t].cross(e1);
      dRay.push_back(std::abs(a.dot(u[h][t])));
      dAcross.push_back(std::abs(a.dot(e1)));
      dAcross.push_back(std::abs(a.dot(e2)));
    }
  }
  if (dRay.size() < 10) return res;
  // |Δ²x·e| about 0; a second difference of white noise has 6× its variance.
  auto noise = [&](const std::vector<double>& v) { return std::max(madSigma(v, 0.0) / std::sqrt(6.0), double(opt.minNoise)); };
  const double sRay = noise(dRay), sAcross = noise(dAcross);
  res.noiseAlongRay = Scalar(sRay);
  res.noiseAcrossRay = Scalar(sAcross);
  const double wAcross = 1 / (sAcross * sAcross), wRay = 1 / (sRay * sRay) - wAcross;
  const double norm = 1.0 / double(3 * W - 3);
  const double tau = double(opt.tau);
  // Λ of a frame whose unit ray is r (file comment).
  auto information = [&](const Eigen::Vector3d& r) -> Eigen::Matrix3d { return wAcross * Eigen::Matrix3d::Identity() + wRay * r * r.transpose(); };
  // RSS of points y_i about their Λ_i-weighted mean (the still point eliminated), Λ_i from rays r_i.
  auto stillRss = [&](const std::vector<Eigen::Vector3d>& y, const std::vector<Eigen::Vector3d>& r, std::size_t s, std::size_t t) {
    Eigen::Vector3d ym = Eigen::Vector3d::Zero();
    for (std::size_t i = s; i <= t; ++i) ym += y[i];
    ym /= double(t + 1 - s);
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    double yy = 0;
    for (std::size_t i = s; i <= t; ++i) {
      const Eigen::Matrix3d L = information(r[i]);
      const Eigen::Vector3d yt = y[i] - ym, Ly = L * yt;
      M += L, b += Ly, yy += yt.dot(Ly);
    }
    return yy - b.dot(Eigen::LDLT<Eigen::Matrix3d>(M).solve(b));
  };
  for (std::size_t h = 0; h < H; ++h) {
    std::vector<Eigen::Vector3d> rc(T, Eigen::Vector3d::Zero());  // the rays in the camera frame
    for (std::size_t t = 0; t < T; ++t) {
      if (usable[h][t] && hc[h][t].norm() > 0) rc[t] = hc[h][t].normalized();
    }
    const std::vector<char>& ok = usable[h];
    const std::vector<Eigen::Vector3d>& xh = x[h];
    const std::vector<Eigen::Vector3d>& uh = u[h];
    std::size_t run = 0;  // usable frames ending at t
    for (std::size_t t = 0; t < T; ++t) {
      run = ok[t] ? run + 1 : 0;
      if (run < W) continue;
      const std::size_t s = t + 1 - W;
      // A hand still in the camera frame (carried with the head) says nothing about α, but looks
      // still in the world at a small α: left out.
      if (stillRss(hc[h], rc, s, t) * norm < tau) {
        ++res.carriedWindows;
        continue;
      }
      // Centre on the plain means first (RSS is shift-invariant: p_w absorbs it) against
      // cancellation, then eliminate p_w with the Λ-weighted sums.
      Eigen::Vector3d xm = Eigen::Vector3d::Zero(), cm = Eigen::Vector3d::Zero();
      for (std::size_t i = s; i <= t; ++i) xm += xh[i], cm += c[i];
      xm /= double(W), cm /= double(W);
      Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
      Eigen::Vector3d bx = Eigen::Vector3d::Zero(), bc = Eigen::Vector3d::Zero();
      Win w{0, 0, 0};
      for (std::size_t i = s; i <= t; ++i) {
        const Eigen::Matrix3d L = information(uh[i]);
        const Eigen::Vector3d xt = xh[i] - xm, ct = c[i] - cm, Lx = L * xt, Lc = L * ct;
        M += L, bx += Lx, bc += Lc;
        w.xx += xt.dot(Lx), w.xc += xt.dot(Lc), w.cc += ct.dot(Lc);
      }
      const Eigen::LDLT<Eigen::Matrix3d> Mf(M);  // M is positive definite: W frames of Λ ≻ 0
      const Eigen::Vector3d mx = Mf.solve(bx), mc = Mf.solve(bc);
      w.xx -= bx.dot(mx), w.xc -= bx.dot(mc), w.cc -= bc.dot(mc);
      wins.push_back(w);
    }
  }
  res.residuals = static_cast<int>(wins.size());
  if (wins.empty()) return res;
  double sxx = 0, scc = 0;
  for (const Win& w : wins) sxx += w.xx, scc += w.cc;
  if (!(scc > 0) || !(sxx > 0)) return res;
  auto q = [&](const Win& w, double a) { return (w.xx + 2 * a * w.xc + a * a * w.cc) * norm; };
  // Consensus scan: f(α_k) on the log-spaced samples, then its local minima (the first sample of
  // a flat run), best first.
  const double ref = std::sqrt(sxx / scc), dec = double(opt.scanDecades) * std::log(10.0);
  const int K = opt.scanSamples;
  std::vector<double> as(static_cast<std::size_t>(K)), fs(static_cast<std::size_t>(K));
  for (int k = 0; k < K; ++k) {
    const double a = ref * std::exp(-dec + 2 * dec * double(k) / double(K - 1));
    double f = 0;
    for (const Win& w : wins) f += std::min(q(w, a), tau);
    as[static_cast<std::size_t>(k)] = a, fs[static_cast<std::size_t>(k)] = f;
  }
  std::vector<int> modes;
  for (int k = 0; k < K; ++k) {
    const std::size_t i = static_cast<std::size_t>(k);
    if ((k == 0 || fs[i] < fs[i - 1]) && (k == K - 1 || fs[i] <= fs[i + 1])) modes.push_back(k);
  }
  std::stable_sort(modes.begin(), modes.end(), [&](int l, int r) { return fs[static_cast<std::size_t>(l)] < fs[static_cast<std::size_t>(r)]; });
  if (modes.size() > static_cast<std::size_t>(opt.maxModes)) modes.resize(static_cast<std::size_t>(opt.maxModes));
  // Least squares over the still windows of a mode, re-selected; the first mode whose still windows
  // pin α down (relative s.e. ≤ maxRelativeError) answers, else the best mode. A mode at too small
  // an α, where the camera's translation hardly matters ("the camera does not move"), makes every
  // window with a hand that is still in the camera frame look still but leaves α unconstrained.
  bool have = false;
  for (const int k : modes) {
    HandScaleResult<Scalar> m = res;
    double alpha = as[static_cast<std::size_t>(k)], sumCc = 0;
    int still = 0;
    bool ok = true;
    for (int it = 0; it <= opt.refinements; ++it) {
      double num = 0, den = 0;
      still = 0;
      for (const Win& w : wins) {
        if (q(w, alpha) < tau) num += w.xc, den += w.cc, ++still;
      }
      if (!(den > 0)) {
        ok = false;
        break;
      }
      sumCc = den;
      if (it < opt.refinements) alpha = -num / den;
    }
    if (!ok) continue;
    m.restFrames = still;
    if (alpha > 0 && still >= opt.minStillWindows) {
      const double se = std::sqrt(double(W) / sumCc), e = se / alpha / 0.05;
      m.scale = Scalar(alpha);
      m.relativeStdError = Scalar(se / alpha);
      m.confidence = Scalar(1.0 / (1.0 + e * e));
    }
    if (!have) res = m, have = true;  // the best mode, whatever its precision
    if (m.ok() && m.relativeStdError <= opt.maxRelativeError) {
      res = m;
      break;
    }
  }
  return res;
}

}  // namespace hawor
