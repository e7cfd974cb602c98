// hawor/scale/hand_smoothness_scale.hpp — the smoothness cue of the hand-anchored scale (the
// fallback of hand_scale.hpp when no hand holds still), no depth network needed: the hands are metric (a fitted hand has a metric size, so its camera-frame position is
// in metres), and the world-space hand track depends on the unknown trajectory scale α linearly:
//   p_t(α) = R_t·h_t + α·c_t        (R_t, c_t: SLAM camera-to-world rotation and centre, map
//                                   units; h_t: the hand's camera-frame position, metres).
// A wrong α adds (α − α*)·c_t to the true world motion: the camera's own motion, which makes the
// hands move implausibly in the world. α is chosen so that the world-space hand motion is as
// smooth as possible — least second differences at a lag of L frames,
//   a_t(α) = p_{t+L} − 2p_t + p_{t−L} = A_t + α·B_t,
//   A_t = Δ²_L(R h)_t,  B_t = Δ²_L(c)_t,
// α = argmin Σ_t w_t ρ(|A_t + α·B_t|²) — a 1-D weighted least-squares problem with the closed
// form α = −Σ w A·B / Σ w |B|², made robust by IRLS with Cauchy weights (scale: 2× the median
// residual) — plus, with a weight restWeight, the velocities v_t(α) = (p_{t+K} − p_t)/K (K =
// restLag, long enough to average out the fit's per-frame noise) on the frames where the hand is
// found resting (world speed below restSpeed at the current α: a hand on a table is a strong
// metric cue). Several lags can be combined (each its own residual set).
// Uses only frames where the hand is valid at every frame a difference touches.
// Confidence: the relative standard error of α from the residuals and Σ w|B|² (how much the
// camera accelerated: a camera moving at constant velocity cannot reveal its scale this way),
// mapped to (0, 1] as 1 / (1 + (e / 0.05)²).
// Limit: hands that move with the head (the body carries both) share its accelerations and pull α
// low; the prior needs hands that move with some independence from the head. On the synthetic
// presets it is biased by 15–60 % (bench_scale.py), which is why hand_scale.hpp prefers the
// holds of hand_hold_scale.hpp and uses this only when there are none.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/scale/hand_track.hpp"

namespace hawor {

template <typename Scalar>
struct HandSmoothnessOptions {
  std::vector<int> lags = {2, 4};   ///< second-difference lags (frames)
  int irlsIterations = 10;
  Scalar cauchyFactor = Scalar(2);  ///< Cauchy scale = factor × median residual norm
  Scalar restSpeed = Scalar(0.03);  ///< m per second below which a hand counts as resting
  Scalar restWeight = Scalar(4);    ///< weight of a resting frame's velocity residual
  int restLag = 6;                  ///< frames over which a resting hand's velocity is measured
  Scalar fps = Scalar(30);
  int minResiduals = 10;
};

/// The smoothness scale (file comment) from camera-to-world poses (map units) and any number of
/// hand tracks (metres, camera frame), all of the same length T. Throws on mismatched lengths or
/// invalid options; returns a result that is not ok() when too little motion is usable.
template <typename Scalar>
HandScaleResult<Scalar> handSmoothnessScale(const std::vector<SE3<Scalar>>& T_w_c, const std::vector<HandTrack<Scalar>>& hands,
                                            const HandSmoothnessOptions<Scalar>& opt = {}) {
  using V3 = Vec3<Scalar>;
  const std::size_t T = T_w_c.size();
  scale_detail::checkTracks("handSmoothnessScale", T_w_c, hands);
  if (opt.lags.empty() || opt.irlsIterations < 1 || !(opt.cauchyFactor > Scalar(0)) || !(opt.fps > Scalar(0)) ||
      !(opt.restWeight >= Scalar(0)) || !(opt.restSpeed >= Scalar(0)) || opt.restLag < 1) {
    throw Error("handSmoothnessScale: invalid options");
  }
  for (int L : opt.lags) {
    if (L < 1) throw Error("handSmoothnessScale: lags must be >= 1");
  }
  // Residual terms A + α·B (3-vectors), with a base weight.
  struct Term {
    V3 A, B;
    Scalar w;
    int hand, t;
  };
  std::vector<Term> acc;
  std::vector<V3> rh(T);
  for (std::size_t h = 0; h < hands.size(); ++h) {
    const HandTrack<Scalar>& H = hands[h];
    for (std::size_t t = 0; t < T; ++t) {
      rh[t] = (H.valid[t] && H.positionCam[t].allFinite()) ? V3(T_w_c[t].rotation() * H.positionCam[t]) : V3::Zero();
    }
    auto ok = [&](std::ptrdiff_t t) {
      return t >= 0 && t < static_cast<std::ptrdiff_t>(T) && H.valid[static_cast<std::size_t>(t)] &&
             H.positionCam[static_cast<std::size_t>(t)].allFinite() &&
             T_w_c[static_cast<std::size_t>(t)].translation().allFinite();
    };
    for (int L : opt.lags) {
      for (std::ptrdiff_t t = L; t + L < static_cast<std::ptrdiff_t>(T); ++t) {
        if (!ok(t - L) || !ok(t) || !ok(t + L)) continue;
        const std::size_t a = static_cast<std::size_t>(t - L), b = static_cast<std::size_t>(t), c = static_cast<std::size_t>(t + L);
        Term k;
        k.A = rh[c] - Scalar(2) * rh[b] + rh[a];
        k.B = T_w_c[c].translation() - Scalar(2) * T_w_c[b].translation() + T_w_c[a].translation();
        // Second differences grow with L²: divide so every lag measures acceleration alike.
        const Scalar n = Scalar(1) / Scalar(L * L);
        k.A *= n, k.B *= n;
        k.w = Scalar(1);
        k.hand = static_cast<int>(h), k.t = static_cast<int>(t);
        acc.push_back(k);
      }
    }
  }
  HandScaleResult<Scalar> res;
  res.residuals = static_cast<int>(acc.size());
  res.method = "smoothness";
  if (static_cast<int>(acc.size()) < opt.minResiduals) return res;

  auto solve = [](const std::vector<Term>& terms, const std::vector<Scalar>& w) {
    double num = 0, den = 0;
    for (std::size_t i = 0; i < terms.size(); ++i) {
      num += double(w[i]) * double(terms[i].A.dot(terms[i].B));
      den += double(w[i]) * double(terms[i].B.squaredNorm());
    }
    return den > 0 ? Scalar(-num / den) : std::numeric_limits<Scalar>::quiet_NaN();
  };
  std::vector<Term> all = acc;
  std::vector<Scalar> w(all.size(), Scalar(1));
  Scalar alpha = solve(all, w);
  if (!std::isfinite(double(alpha))) return res;
  for (int it = 0; it < opt.irlsIterations; ++it) {
    // Resting frames at the current α: velocity residuals join the problem.
    all = acc;
    int rest = 0;
    if (opt.restWeight > Scalar(0)) {
      for (std::size_t h = 0; h < hands.size(); ++h) {
        const HandTrack<Scalar>& H = hands[h];
        const std::size_t K = static_cast<std::size_t>(opt.restLag);
        for (std::size_t t = 0; t + K < T; ++t) {
          if (!H.valid[t] || !H.valid[t + K] || !H.positionCam[t].allFinite() || !H.positionCam[t + K].allFinite()) continue;
          Term k;
          const Scalar inv = Scalar(1) / Scalar(K);
          k.A = (V3(T_w_c[t + K].rotation() * H.positionCam[t + K]) - V3(T_w_c[t].rotation() * H.positionCam[t])) * inv;
          k.B = (T_w_c[t + K].translation() - T_w_c[t].translation()) * inv;
          if (!k.A.allFinite() || !k.B.allFinite()) continue;
          const Scalar speed = (k.A + alpha * k.B).norm() * opt.fps;
          if (!(speed < opt.restSpeed)) continue;
          // Both kinds of residual are per-frame differences of positions (metres).
          k.w = opt.restWeight;
          k.hand = static_cast<int>(h), k.t = static_cast<int>(t);
          all.push_back(k);
          ++rest;
        }
      }
    }
    res.restFrames = rest;
    // Cauchy IRLS weights at the current α.
    std::vector<Scalar> r(all.size());
    for (std::size_t i = 0; i < all.size(); ++i) r[i] = (all[i].A + alpha * all[i].B).norm();
    std::vector<Scalar> tmp = r;
    std::nth_element(tmp.begin(), tmp.begin() + static_cast<std::ptrdiff_t>(tmp.size() / 2), tmp.end());
    const Scalar c = std::max(opt.cauchyFactor * tmp[tmp.size() / 2], Scalar(1e-12));
    w.assign(all.size(), Scalar(0));
    for (std::size_t i = 0; i < all.size(); ++i) w[i] = all[i].w / (Scalar(1) + (r[i] / c) * (r[i] / c));
    const Scalar next = solve(all, w);
    if (!std::isfinite(double(next))) break;
    const bool done = std::abs(next - alpha) <= Scalar(1e-9) * (std::abs(alpha) + Scalar(1e-12));
    alpha = next;
    if (done) break;
  }
  // Standard error of α (weighted least squares): σ² = Σ w r² / (n − 1) / Σ w |B|².
  double rss = 0, bb = 0, ws = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    rss += double(w[i]) * double((all[i].A + alpha * all[i].B).squaredNorm());
    bb += double(w[i]) * double(all[i].B.squaredNorm());
    ws += double(w[i]);
  }
  const double n = double(all.size());
  if (alpha > Scalar(0) && bb > 0 && n > 1 && ws > 0) {
    const double se = std::sqrt(rss / (n - 1) / bb);
    res.scale = alpha;
    res.relativeStdError = Scalar(se / double(alpha));
    const double e = se / double(alpha) / 0.05;
    res.confidence = Scalar(1.0 / (1.0 + e * e));
  }
  return res;
}

}  // namespace hawor
