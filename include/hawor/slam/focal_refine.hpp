// hawor/slam/focal_refine.hpp — self-calibration of a shared focal length (fx, fy scaled by one
// factor, principal point fixed) from a bundle-adjustment problem: the focal of docs/design.md §5
// "refined by the SLAM where possible".
//
// Method: the PROFILE of the bundle-adjustment cost over u = log(f / f_guess),
//   F(u) = min over poses and points of the BA cost (bundle_adjustment.hpp) with the camera's
//          focal lengths scaled by e^u,
// evaluated by continuation (each BA warm-started from its neighbour's solution) on a grid of
// gridPerOctave steps per octave over [searchMin, searchMax] × f_guess, then refined by two
// parabola fits around the grid minimum. With F ≈ Σ‖r‖²/σ² (Huber's inlier branch, σ = 1 px of
// BAOptions) the negative log-likelihood is F/(2ŝ²), ŝ² = F(û)/(2·nObs − nParams) (the residual
// variance in units of σ², estimated at the optimum), and a Gaussian prior on u of std
// priorSigmaLog around the guess is added. The profile's curvature gives the posterior std of u
// (≈ the relative std of f): for a Gaussian likelihood the curvature of the profile equals the
// inverse marginal variance of the profiled parameter.
// Observability: the focal is not determined by pure translation (scaling f, the points' and the
// cameras' x, y leaves every projection unchanged) nor by rotation about the optical axis; it is by
// rotation about other axes and by translation with depth variation. The refinement is DECLINED,
// with a reason, when the problem is too small, the minimum lies at the edge of the search range,
// or the data-only std of u exceeds maxStdLog (the profile is too flat). An accepted estimate is
// APPLIED (changed = true) only when it differs from the guess by more than minChange and by more
// than 2 posterior stds, so a right guess is kept.
// On return the problem holds the BA solution at the chosen focal (the guess when not applied)
// and its camera that focal.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "hawor/slam/bundle_adjustment.hpp"

namespace hawor {

template <typename Scalar>
struct FocalRefineOptions {
  Scalar priorSigmaLog = Scalar(0.3);  ///< prior std of log(f/f_guess) (a FOV guess: ±30 %)
  /// The prior's centre f_guess in pixels; 0: P.camera.fx. Set it when P.camera already holds an
  /// earlier estimate (a second refinement), so the prior stays on the user's guess instead of
  /// following each estimate (which would let a weak profile walk the focal away step by step).
  Scalar priorFx = Scalar(0);
  Scalar searchMin = Scalar(0.5), searchMax = Scalar(2);  ///< search range, × f_guess
  int gridPerOctave = 4;               ///< coarse grid density (log spacing)
  Scalar maxStdLog = Scalar(0.05);     ///< decline when the data-only std of log f exceeds this
  Scalar minChange = Scalar(0.01);     ///< apply only a relative change above this...
  Scalar minChangeStds = Scalar(2);    ///< ...and above this many posterior stds
  /// Floor of the reported std of log f. The profile's curvature treats every residual as
  /// independent; a KLT track's errors in nearby frames are not, so with many frames the
  /// curvature std comes out far below the real scatter (on table_work, estimates from re-selected
  /// points of the same clip spread by 2-3 % while each claimed 0.05-0.5 %).
  Scalar minStdLog = Scalar(0);
  int minPoses = 3;                    ///< free + fixed poses with observations
  int minObservations = 60;
  int rounds = 3;                      ///< profile searches, each re-centred at the last estimate
  BAOptions<Scalar> ba;                ///< per profile evaluation
};

template <typename Scalar>
struct FocalRefineResult {
  bool accepted = false;  ///< the focal was observable and the estimate is valid
  bool changed = false;   ///< the problem's camera now has the refined focal
  Scalar guessFx = Scalar(0), fx = Scalar(0), fy = Scalar(0);  ///< guess; chosen (refined or guess)
  Scalar estimateFx = Scalar(0);  ///< the estimate (even when not applied; 0 when none)
  Scalar stdLog = std::numeric_limits<Scalar>::infinity();      ///< posterior std of log f
  Scalar dataStdLog = std::numeric_limits<Scalar>::infinity();  ///< without the prior
  Scalar rmsGuessPx = Scalar(0), rmsPx = Scalar(0);             ///< BA RMS at the guess / estimate
  int evaluations = 0;                                          ///< bundle adjustments run
  std::vector<std::pair<Scalar, Scalar>> profile;               ///< (f/f_guess, F) evaluated
  std::string reason;  ///< why declined / not applied / applied
};

namespace focal_detail {

template <typename Scalar>
struct State {
  std::vector<SE3<Scalar>> poses;
  std::vector<Vec3<Scalar>> points;
};

/// Parabola through (x_i, y_i), i = 0..2: vertex and second derivative (NaN when degenerate).
template <typename Scalar>
void parabola(const Scalar x[3], const Scalar y[3], Scalar& vertex, Scalar& curvature) {
  const Scalar d01 = (y[1] - y[0]) / (x[1] - x[0]), d12 = (y[2] - y[1]) / (x[2] - x[1]);
  const Scalar a = (d12 - d01) / (x[2] - x[0]);  // y = a x² + b x + c
  curvature = Scalar(2) * a;
  const Scalar b = d01 - a * (x[0] + x[1]);
  vertex = a > Scalar(0) ? -b / (Scalar(2) * a) : std::numeric_limits<Scalar>::quiet_NaN();
}

}  // namespace focal_detail

namespace focal_detail {

/// One profile search centred at P.camera (the prior centred at u = priorCentre relative to it).
template <typename Scalar>
FocalRefineResult<Scalar> refineFocalOnce(BAProblem<Scalar>& P, const FocalRefineOptions<Scalar>& opt, Scalar priorCentre) {
  using focal_detail::State;
  FocalRefineResult<Scalar> res;
  const PinholeCamera<Scalar> cam0 = P.camera;
  res.guessFx = res.fx = cam0.fx;
  res.fy = cam0.fy;
  // Size of the problem.
  std::vector<char> poseSeen(P.poses.size(), 0);
  int nObs = 0;
  for (const auto& o : P.observations) {
    if (!(o.weight > Scalar(0))) continue;
    ++nObs;
    poseSeen[static_cast<std::size_t>(o.pose)] = 1;
  }
  int nPoses = 0, nFreePoses = 0;
  for (std::size_t i = 0; i < P.poses.size(); ++i) {
    nPoses += poseSeen[i];
    if (poseSeen[i] && !(i < P.poseFixed.size() && P.poseFixed[i])) ++nFreePoses;
  }
  if (nPoses < opt.minPoses || nObs < opt.minObservations) {
    res.reason = "too small a problem to observe the focal (" + std::to_string(nPoses) + " keyframes, " +
                 std::to_string(nObs) + " observations)";
    return res;
  }
  const Scalar lo = std::log(opt.searchMin), hi = std::log(opt.searchMax);
  const Scalar h = std::log(Scalar(2)) / Scalar(std::max(1, opt.gridPerOctave));
  const int kLo = static_cast<int>(std::ceil(lo / h - Scalar(1e-9))), kHi = static_cast<int>(std::floor(hi / h + Scalar(1e-9)));
  if (kLo > -1 || kHi < 1) {
    res.reason = "search range too narrow";
    return res;
  }
  const State<Scalar> start{P.poses, P.points};
  auto solveAt = [&](Scalar u, const State<Scalar>& from, State<Scalar>& out, Scalar& rms) -> Scalar {
    P.poses = from.poses;
    P.points = from.points;
    P.camera = cam0;
    P.camera.fx = cam0.fx * std::exp(u);
    P.camera.fy = cam0.fy * std::exp(u);
    const BAReport<Scalar> rep = bundleAdjust(P, opt.ba);
    ++res.evaluations;
    out.poses = P.poses;
    out.points = P.points;
    rms = rep.finalRmsPx;
    res.profile.emplace_back(std::exp(u), rep.finalCost);
    return std::isfinite(double(rep.finalCost)) ? rep.finalCost : std::numeric_limits<Scalar>::infinity();
  };
  auto restore = [&](const State<Scalar>& s, Scalar u) {
    P.poses = s.poses;
    P.points = s.points;
    P.camera = cam0;
    P.camera.fx = cam0.fx * std::exp(u);
    P.camera.fy = cam0.fy * std::exp(u);
  };
  // Coarse grid by continuation outward from the guess.
  const int nGrid = kHi - kLo + 1;
  std::vector<Scalar> F(static_cast<std::size_t>(nGrid));
  std::vector<State<Scalar>> S(static_cast<std::size_t>(nGrid));
  std::vector<Scalar> rmsGrid(static_cast<std::size_t>(nGrid));
  const int i0 = -kLo;
  F[static_cast<std::size_t>(i0)] = solveAt(Scalar(0), start, S[static_cast<std::size_t>(i0)], rmsGrid[static_cast<std::size_t>(i0)]);
  for (int i = i0 + 1; i < nGrid; ++i) {
    F[static_cast<std::size_t>(i)] = solveAt(h * Scalar(i + kLo), S[static_cast<std::size_t>(i - 1)], S[static_cast<std::size_t>(i)], rmsGrid[static_cast<std::size_t>(i)]);
  }
  for (int i = i0 - 1; i >= 0; --i) {
    F[static_cast<std::size_t>(i)] = solveAt(h * Scalar(i + kLo), S[static_cast<std::size_t>(i + 1)], S[static_cast<std::size_t>(i)], rmsGrid[static_cast<std::size_t>(i)]);
  }
  res.rmsGuessPx = res.rmsPx = rmsGrid[static_cast<std::size_t>(i0)];
  auto keepGuess = [&](const std::string& why) {
    restore(S[static_cast<std::size_t>(i0)], Scalar(0));
    res.fx = P.camera.fx, res.fy = P.camera.fy;
    res.reason = why;
    return res;
  };
  if (!std::isfinite(double(F[static_cast<std::size_t>(i0)]))) return keepGuess("the bundle adjustment failed at the guess");
  // Residual variance (units of σ²) at the guess's solution; the estimate's is taken below.
  const int nParams = 6 * nFreePoses + 3 * static_cast<int>(P.points.size()) + 1;
  const int dof = std::max(1, 2 * nObs - nParams);
  const Scalar priorW = Scalar(1) / (Scalar(2) * opt.priorSigmaLog * opt.priorSigmaLog);
  int best = 0;
  for (int i = 1; i < nGrid; ++i) {
    if (F[static_cast<std::size_t>(i)] < F[static_cast<std::size_t>(best)]) best = i;
  }
  if (best == 0 || best == nGrid - 1) {
    return keepGuess("the cost is least at the edge of the search range (" +
                     std::to_string(double(std::exp(h * Scalar(best + kLo)))) + " × the guess): focal not observable");
  }
  // Parabola on the coarse grid, then a finer one around its vertex (data term only; the prior
  // is added analytically).
  Scalar x[3], y[3], vertex, curv;
  for (int j = 0; j < 3; ++j) {
    x[j] = h * Scalar(best - 1 + j + kLo);
    y[j] = F[static_cast<std::size_t>(best - 1 + j)];
  }
  focal_detail::parabola(x, y, vertex, curv);
  if (!std::isfinite(double(vertex))) vertex = x[1];
  vertex = std::min(std::max(vertex, x[0]), x[2]);
  const Scalar hf = h / Scalar(3);
  State<Scalar> Sf[3];
  Scalar Ff[3], rmsF[3];
  const State<Scalar>& seed = S[static_cast<std::size_t>(best)];
  for (int j = 0; j < 3; ++j) {
    x[j] = vertex + hf * Scalar(j - 1);
    Ff[j] = solveAt(x[j], j == 0 ? seed : Sf[j - 1], Sf[j], rmsF[j]);
    y[j] = Ff[j];
  }
  focal_detail::parabola(x, y, vertex, curv);
  const Scalar s2 = std::max(*std::min_element(Ff, Ff + 3) / Scalar(dof), Scalar(1e-12));
  // NLL(u) = F(u) / (2 s2) + priorW u²  → curvature F''/(2 s2) + 2 priorW.
  const Scalar dataCurv = curv / (Scalar(2) * s2);
  if (!(dataCurv > Scalar(0)) || !std::isfinite(double(vertex))) {
    return keepGuess("the cost has no minimum in the focal: focal not observable");
  }
  res.dataStdLog = Scalar(1) / std::sqrt(dataCurv);
  const Scalar postCurv = dataCurv + Scalar(2) * priorW;
  res.stdLog = std::max(Scalar(1) / std::sqrt(postCurv), opt.minStdLog);
  const Scalar uHat = (dataCurv * vertex + Scalar(2) * priorW * priorCentre) / postCurv;  // the prior's pull
  res.estimateFx = cam0.fx * std::exp(uHat);
  if (res.dataStdLog > opt.maxStdLog) {
    return keepGuess("focal not observable from this motion (std " + std::to_string(double(100 * res.dataStdLog)) +
                     " %, more than " + std::to_string(double(100 * opt.maxStdLog)) + " %)");
  }
  res.accepted = true;
  if (std::abs(uHat) <= opt.minChange || std::abs(uHat) <= opt.minChangeStds * res.stdLog) {
    keepGuess("the estimate agrees with the guess within its uncertainty");
    res.accepted = true;
    return res;
  }
  // Final solve at the estimate, warm-started from the nearest fine point.
  int near = 0;
  for (int j = 1; j < 3; ++j) {
    if (std::abs(x[j] - uHat) < std::abs(x[near] - uHat)) near = j;
  }
  State<Scalar> fin;
  Scalar rmsFin;
  const Scalar Ffin = solveAt(uHat, Sf[near], fin, rmsFin);
  if (!std::isfinite(double(Ffin))) {
    res.accepted = false;
    return keepGuess("the bundle adjustment failed at the estimate");
  }
  restore(fin, uHat);
  res.changed = true;
  res.fx = P.camera.fx, res.fy = P.camera.fy;
  res.rmsPx = rmsFin;
  res.reason = "refined by the bundle adjustment";
  return res;
}

}  // namespace focal_detail

/// Refines the shared focal of `P.camera` (see the header). P must have its gauge set (fixed
/// poses / a scale prior) like any BA problem. The profile search is repeated, re-centred at the
/// last estimate, up to opt.rounds times while the estimate still moves by more than minChange:
/// a map built with a wrong focal needs more BA iterations far from the guess than one profile
/// evaluation gives it, which biases a single search toward the guess.
template <typename Scalar>
FocalRefineResult<Scalar> refineFocal(BAProblem<Scalar>& P, const FocalRefineOptions<Scalar>& opt = {}) {
  const Scalar guessFx = P.camera.fx;
  const Scalar priorFx = opt.priorFx > Scalar(0) ? opt.priorFx : guessFx;
  FocalRefineResult<Scalar> total;
  std::vector<std::pair<Scalar, Scalar>> profile;
  int evaluations = 0;
  for (int round = 0; round < std::max(1, opt.rounds); ++round) {
    const Scalar centre = std::log(priorFx / P.camera.fx);  // the prior's centre relative to P.camera
    FocalRefineResult<Scalar> r = focal_detail::refineFocalOnce(P, opt, centre);
    for (const auto& q : r.profile) profile.emplace_back(q.first * r.guessFx / guessFx, q.second);
    evaluations += r.evaluations;
    if (round == 0) {
      total = r;
    } else if (r.accepted) {
      const bool changedBefore = total.changed;
      const Scalar rmsGuess = total.rmsGuessPx;
      total = r;
      total.rmsGuessPx = rmsGuess;
      total.changed = changedBefore || r.changed;
      if (!r.changed) total.reason = "refined by the bundle adjustment";
    } else {
      break;  // keep the previous round's estimate (P is at it: a declined round restores its guess)
    }
    if (!r.changed) break;
  }
  total.guessFx = guessFx;
  total.fx = P.camera.fx;
  total.fy = P.camera.fy;
  total.profile = std::move(profile);
  total.evaluations = evaluations;
  if (total.changed && total.fx == guessFx) total.changed = false;
  return total;
}

}  // namespace hawor
