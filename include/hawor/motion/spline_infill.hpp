// hawor/motion/spline_infill.hpp — the data-free gap filler ("spline"): cubic Hermite curves for
// translation and on SO(3) for every rotation, with boundary velocities from the visible context.
//
// An interior gap of missing frames between the valid frames a < b (N = b − a) is filled by the
// chord (LERP / SLERP, the pre-fill of docs/design.md §7) plus a deviation that makes the curve leave a
// and enter b with the velocities the hand had there:
//   translation  p(t) = p_a + u·(p_b − p_a) + δ(t),                 u = (t − a)/N
//   rotation     R(t) = R_a·exp(u·Ω)·exp(δ(t)),  Ω = log(R_aᵀR_b)   (body-frame deviation)
//   δ(t) = φ_L(t − a)·d_a − φ_L(b − t)·d_b,   φ_L(τ) = τ·(1 − τ/L)² for τ < L, 0 after,
//   d_a = v_a − c,  d_b = v_b − c,  c = the chord's velocity ((p_b − p_a)/N, or Ω/N),
// with v_a, v_b the velocities (per frame; body angular rates for rotations) at a and b. φ_L has
// φ(0) = 0, φ'(0) = 1 and vanishes with its slope at L, so the curve passes through the observed
// frames with their velocities (C¹ at the gap's ends). With L = N this is exactly the cubic
// Hermite curve through (p_a, v_a) and (p_b, v_b) (N·h10(u) = φ_N(t − a), N·h11(u) = −φ_N(b − t));
// each side's term never exceeds 4/27·L·|d|. Long gaps: L = min(N, horizon), so beyond the horizon
// the boundary velocities are eased into the chord over `horizon` frames instead of being
// extrapolated across the whole gap (no overshoot). Consequences: a motion that is linear in
// time (translation) or of constant angular velocity (rotation) is reproduced exactly (d = 0),
// and so is a cubic one within the horizon when the velocities are exact (degree-3 fits).
//
// Boundary velocities are estimated robustly from the valid frames next to the gap on its own
// side (the run of consecutive valid frames ending at a / starting at b, at most maxContext):
//   - a least-squares polynomial of degree `degree` in time through those samples (rotations:
//     through r_k = log(R_aᵀR_k), the tangent space at the boundary); its slope at the boundary;
//   - the number of frames is chosen per boundary by Lepski's rule (intersection of confidence
//     intervals) over 3, 4, 5, 6, 8, 10, 12, 16, … frames: the longest fit whose slope agrees
//     with every shorter one, |v_k − v_j| ≤ γ·√3·(σ_k + σ_j), where σ_k² = σ²·[(AᵀA)⁻¹]₁₁ is
//     the slope's variance from the channel's noise σ (short fits when the motion is clean and
//     curved, long ones when it is noisy);
//   - the deviation is shrunk towards the chord, d ← d·max(0, 1 − 3σ_v²/|d|²) (positive-part
//     James–Stein), so that noise in the context does not become a swing inside the gap.
// σ, the per-frame noise of a channel, is estimated from its observed runs by motion_noise.hpp
// (4th differences; clean input gives σ ≈ 0 and the shortest, exact fits).
// Frames before the first / after the last valid frame hold the nearest valid frame (as the
// pre-fill does); betas are interpolated linearly. Valid frames are copied bit for bit.
// The rule is equivariant under a fixed rigid motion of the world (translation: affine; rotation:
// body-frame quantities), so it gives the same result in world and in canonical space.
// Thread-safety: pure functions.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/motion/hand_motion.hpp"
#include "hawor/motion/local_poly.hpp"
#include "hawor/motion/motion_noise.hpp"
#include "hawor/motion/sequence.hpp"

namespace hawor {

/// Settings of the spline gap filler (see the file comment). Defaults are the benchmarked ones
/// (examples/bench_infill.py).
template <typename Scalar>
struct SplineInfillOptions {
  int degree = 2;            ///< degree of the local boundary fits (1..3; 3 reproduces cubics)
  int maxContext = 16;       ///< most valid frames a boundary fit uses (>= 2)
  Scalar iciGamma = Scalar(2);   ///< half-width of the ICI confidence intervals, in σ_v
  Scalar horizon = Scalar(60);   ///< frames; the deviation eases into the chord within this
  bool shrink = true;        ///< James–Stein shrink of the boundary deviations by their noise

  /// Throws hawor::Error for out-of-range settings.
  void validate() const {
    if (degree < 1 || degree > 3) throw Error("spline infill: degree must be 1, 2 or 3");
    if (maxContext < 2) throw Error("spline infill: maxContext must be at least 2 frames");
    if (!(iciGamma > Scalar(0)) || !std::isfinite(iciGamma))
      throw Error("spline infill: iciGamma must be positive");
    if (!(horizon >= Scalar(1)) || !std::isfinite(horizon))
      throw Error("spline infill: horizon must be at least 1 frame");
  }
};

/// A boundary velocity: `known` is false when the boundary has no valid neighbour on its side
/// (then the chord's velocity is used, i.e. no deviation). `variance` = σ_v² per component.
template <typename Scalar>
struct BoundaryVelocity {
  Vec3<Scalar> v = Vec3<Scalar>::Zero();
  Scalar variance = Scalar(0);
  int frames = 0;  ///< samples of the chosen fit (boundary frame included)
  bool known = false;
};

namespace spline_detail {

/// Context sizes tried by the ICI rule (capped by maxContext and by the run length).
inline constexpr int kContextLadder[] = {3, 4, 5, 6, 8, 10, 12, 16, 24, 32, 48, 64};

}  // namespace spline_detail

/// φ_L(τ) = τ·(1 − τ/L)² for 0 ≤ τ < L, else 0: the ease of a boundary velocity into the chord
/// (φ(0) = 0, φ'(0) = 1, φ(L) = φ'(L) = 0).
template <typename Scalar>
Scalar hermiteEase(Scalar tau, Scalar L) {
  if (!(tau >= Scalar(0)) || !(tau < L)) return Scalar(0);
  const Scalar r = Scalar(1) - tau / L;
  return tau * r * r;
}

/// Velocity at the valid frame `boundary` from the run of valid frames on side `direction`
/// (−1: frames before it, +1: after it), boundary included: sample(k) gives the channel's value
/// at frame k as a point of R³ (translation: the position; rotation: log(R_bᵀR_k)). The fit and
/// the ICI choice of its length are those of the file comment; σ is the channel noise.
template <typename Scalar, typename SampleFn>
BoundaryVelocity<Scalar> boundaryVelocity(const ValidMask& valid, Eigen::Index boundary,
                                          int direction, SampleFn sample, Scalar sigma,
                                          const SplineInfillOptions<Scalar>& o) {
  BoundaryVelocity<Scalar> out;
  const Eigen::Index T = static_cast<Eigen::Index>(valid.size());
  std::vector<Scalar> tau;
  std::vector<Vec3<Scalar>> y;
  for (Eigen::Index t = boundary; t >= 0 && t < T && valid[static_cast<size_t>(t)] &&
                                  static_cast<int>(tau.size()) < o.maxContext;
       t += direction) {
    tau.push_back(Scalar(t - boundary));
    y.push_back(sample(t));
  }
  const int n = static_cast<int>(tau.size());
  if (n < 2) return out;
  const Scalar s2 = sigma * sigma;
  const Scalar* const kNoWeights = nullptr;
  auto take = [&](const LocalPolyFit<Scalar>& f, int k) {
    out.v = f.slope;
    out.variance = s2 * f.slopeVariance;
    out.frames = k;
    out.known = true;
  };
  if (n <= o.degree) {  // too few samples for the degree: the interpolating polynomial
    const LocalPolyFit<Scalar> f = fitLocalPolynomial(tau.data(), y.data(), kNoWeights, n, n - 1);
    if (f.ok) take(f, n);
    return out;
  }
  // Lepski / ICI: accept longer fits while each agrees with every shorter accepted one,
  // |v_k − v_j| ≤ γ·√3·(σ_k + σ_j) (σ the per-component standard deviation of a slope; the
  // Euclidean norm keeps the rule independent of the frame of the channel).
  std::vector<Vec3<Scalar>> slopes;
  std::vector<Scalar> sds;
  const Scalar g = o.iciGamma * std::sqrt(Scalar(3));
  for (int k : spline_detail::kContextLadder) {
    if (k > n) break;
    if (k <= o.degree) continue;
    const LocalPolyFit<Scalar> f = fitLocalPolynomial(tau.data(), y.data(), kNoWeights, k, o.degree);
    if (!f.ok) break;
    const Scalar sd = std::sqrt(std::max(s2 * f.slopeVariance, Scalar(0)));
    bool agree = true;
    for (size_t j = 0; j < slopes.size() && agree; ++j)
      agree = (f.slope - slopes[j]).norm() <= g * (sd + sds[j]);
    if (!agree) break;
    slopes.push_back(f.slope);
    sds.push_back(sd);
    take(f, k);
  }
  return out;
}

namespace spline_detail {

/// The deviation velocity d = v − c of one boundary, shrunk (positive-part James–Stein) when
/// `shrink`; zero when the boundary velocity is unknown.
template <typename Scalar>
Vec3<Scalar> deviationVelocity(const BoundaryVelocity<Scalar>& b, const Vec3<Scalar>& chord,
                               bool shrink) {
  if (!b.known) return Vec3<Scalar>::Zero();
  Vec3<Scalar> d = b.v - chord;
  if (shrink && b.variance > Scalar(0)) {
    const Scalar n2 = d.squaredNorm();
    const Scalar f = n2 > Scalar(0) ? std::max(Scalar(0), Scalar(1) - Scalar(3) * b.variance / n2)
                                    : Scalar(0);
    d *= f;
  }
  return d;
}

/// Holds the nearest valid frame's columns [col, col+w) in a leading / trailing gap.
template <typename Scalar>
void holdEnds(Sequence<Scalar>& out, const Sequence<Scalar>& seq, const GapSegment& g,
              Eigen::Index col, Eigen::Index w) {
  const Eigen::Index src = g.before < 0 ? g.after : g.before;
  for (Eigen::Index t = g.start; t < g.end; ++t) out.row(t).segment(col, w) = seq.row(src).segment(col, w);
}

template <typename Scalar>
void checkSpline(const Sequence<Scalar>& seq, const ValidMask& valid,
                 const SplineInfillOptions<Scalar>& o, const char* what) {
  o.validate();
  checkMask(valid, seq.rows(), what);
  if (seq.cols() % 3 != 0)
    throw Error(std::string(what) + ": " + std::to_string(seq.cols()) +
                " columns is not a multiple of 3");
  if (countValid(valid) == 0)
    throw Error(std::string(what) + ": no valid frame to fill from (all " +
                std::to_string(seq.rows()) + " frames missing)");
  for (Eigen::Index t = 0; t < seq.rows(); ++t)
    if (valid[static_cast<size_t>(t)] && !seq.row(t).allFinite())
      throw Error(std::string(what) + ": non-finite value at valid frame " + std::to_string(t));
}

template <typename Scalar>
void checkSigmas(const std::vector<Scalar>* sigmas, Eigen::Index cols, const char* what) {
  if (!sigmas) return;
  if (static_cast<Eigen::Index>(sigmas->size()) * 3 != cols)
    throw Error(std::string(what) + ": " + std::to_string(sigmas->size()) + " noise levels for " +
                std::to_string(cols / 3) + " channels");
  for (Scalar v : *sigmas)
    if (!(v >= Scalar(0)) || !std::isfinite(v))
      throw Error(std::string(what) + ": noise levels must be finite and >= 0");
}

}  // namespace spline_detail

/// Spline fill of the missing frames of a T×3K sequence of K 3-vectors (e.g. translation, K = 1),
/// each 3-column group on its own (file comment). `sigmas` (optional, one per group) replaces the
/// noise levels estimated from `seq`. Valid frames are copied unchanged; leading / trailing gaps
/// hold the nearest valid frame. Throws if no frame is valid.
template <typename Scalar>
Sequence<Scalar> fillSplineVectors(const Sequence<Scalar>& seq, const ValidMask& valid,
                                   const SplineInfillOptions<Scalar>& o = {},
                                   const std::vector<Scalar>* sigmas = nullptr) {
  spline_detail::checkSpline(seq, valid, o, "fillSplineVectors");
  spline_detail::checkSigmas(sigmas, seq.cols(), "fillSplineVectors");
  Sequence<Scalar> out = seq;
  const std::vector<GapSegment> gaps = findGaps(valid);
  if (gaps.empty()) return out;
  for (Eigen::Index col = 0; col < seq.cols(); col += 3) {
    const Scalar sigma = sigmas ? (*sigmas)[static_cast<size_t>(col / 3)] : estimateVectorNoise(seq, col, valid);
    auto sample = [&](Eigen::Index k) { return Vec3<Scalar>(seq.row(k).template segment<3>(col).transpose()); };
    for (const GapSegment& g : gaps) {
      if (!g.interior()) {
        spline_detail::holdEnds(out, seq, g, col, 3);
        continue;
      }
      const Scalar N = Scalar(g.after - g.before);
      const Vec3<Scalar> pa = sample(g.before), pb = sample(g.after);
      const Vec3<Scalar> chord = (pb - pa) / N;
      const Vec3<Scalar> da = spline_detail::deviationVelocity(
          boundaryVelocity(valid, g.before, -1, sample, sigma, o), chord, o.shrink);
      const Vec3<Scalar> db = spline_detail::deviationVelocity(
          boundaryVelocity(valid, g.after, +1, sample, sigma, o), chord, o.shrink);
      const Scalar L = std::min(N, o.horizon);
      for (Eigen::Index t = g.start; t < g.end; ++t) {
        const Scalar u = Scalar(t - g.before) / N;
        const Vec3<Scalar> p = pa + u * (pb - pa) + hermiteEase(Scalar(t - g.before), L) * da -
                               hermiteEase(Scalar(g.after - t), L) * db;
        out.row(t).template segment<3>(col) = p.transpose();
      }
    }
  }
  return out;
}

/// Spline fill of the missing frames of a T×3K sequence of K axis-angle rotations (global
/// orientation, K = 1, or the joint rotations): R(t) = R_a·exp(u·Ω)·exp(δ(t)) per rotation (file
/// comment); results in axis-angle with angle in [0, π]. `sigmas` (optional, one per rotation)
/// replaces the estimated noise levels. Valid frames are copied unchanged; ends hold. Throws if
/// the column count is not a multiple of 3 or no frame is valid.
template <typename Scalar>
Sequence<Scalar> fillSplineRotations(const Sequence<Scalar>& seq, const ValidMask& valid,
                                     const SplineInfillOptions<Scalar>& o = {},
                                     const std::vector<Scalar>* sigmas = nullptr) {
  spline_detail::checkSpline(seq, valid, o, "fillSplineRotations");
  spline_detail::checkSigmas(sigmas, seq.cols(), "fillSplineRotations");
  Sequence<Scalar> out = seq;
  const std::vector<GapSegment> gaps = findGaps(valid);
  if (gaps.empty()) return out;
  for (Eigen::Index col = 0; col < seq.cols(); col += 3) {
    const Scalar sigma = sigmas ? (*sigmas)[static_cast<size_t>(col / 3)] : estimateRotationNoise(seq, col, valid);
    auto rotation = [&](Eigen::Index k) {
      const Vec3<Scalar> a = seq.row(k).template segment<3>(col).transpose();
      return Mat3<Scalar>(axisAngleToMatrix(a));
    };
    for (const GapSegment& g : gaps) {
      if (!g.interior()) {
        spline_detail::holdEnds(out, seq, g, col, 3);
        continue;
      }
      const Scalar N = Scalar(g.after - g.before);
      const Mat3<Scalar> Ra = rotation(g.before), Rb = rotation(g.after);
      const Mat3<Scalar> RaT = Ra.transpose(), RbT = Rb.transpose();
      const Vec3<Scalar> omega = matrixToAxisAngle(Mat3<Scalar>(RaT * Rb));
      const Vec3<Scalar> chord = omega / N;
      // Body rates at a and b from the tangent spaces there: r_k = log(R_bdᵀR_k).
      auto sample_a = [&](Eigen::Index k) { return matrixToAxisAngle(Mat3<Scalar>(RaT * rotation(k))); };
      auto sample_b = [&](Eigen::Index k) { return matrixToAxisAngle(Mat3<Scalar>(RbT * rotation(k))); };
      const Vec3<Scalar> da = spline_detail::deviationVelocity(
          boundaryVelocity(valid, g.before, -1, sample_a, sigma, o), chord, o.shrink);
      const Vec3<Scalar> db = spline_detail::deviationVelocity(
          boundaryVelocity(valid, g.after, +1, sample_b, sigma, o), chord, o.shrink);
      const Scalar L = std::min(N, o.horizon);
      for (Eigen::Index t = g.start; t < g.end; ++t) {
        const Scalar u = Scalar(t - g.before) / N;
        const Vec3<Scalar> uo = u * omega;
        const Vec3<Scalar> dev = hermiteEase(Scalar(t - g.before), L) * da -
                                 hermiteEase(Scalar(g.after - t), L) * db;
        const Mat3<Scalar> R = Ra * axisAngleToMatrix(uo) * axisAngleToMatrix(dev);
        out.row(t).template segment<3>(col) = matrixToAxisAngle(R).transpose();
      }
    }
  }
  return out;
}

/// The spline fill of a hand (file comment): trans by fillSplineVectors, rot and handPose by
/// fillSplineRotations, betas by LERP; valid frames and the mask unchanged. `noise` (optional)
/// gives the channels' noise levels instead of estimating them from `m` (e.g. those of the raw
/// observations when `m` was smoothed). Throws if no frame is valid (see infill.hpp for the
/// pipeline that handles that case).
template <typename Scalar>
HandMotion<Scalar> fillSpline(const HandMotion<Scalar>& m, const SplineInfillOptions<Scalar>& o = {},
                              const HandNoise<Scalar>* noise = nullptr) {
  m.validate();
  std::vector<Scalar> st, sr;
  if (noise) {
    st.assign(1, noise->trans);
    sr.assign(1, noise->rot);
  }
  HandMotion<Scalar> out;
  out.trans = fillSplineVectors(m.trans, m.valid, o, noise ? &st : nullptr);
  out.rot = fillSplineRotations(m.rot, m.valid, o, noise ? &sr : nullptr);
  out.handPose = fillSplineRotations(m.handPose, m.valid, o, noise ? &noise->joints : nullptr);
  out.betas = fillLinear(m.betas, m.valid);
  out.valid = m.valid;
  return out;
}

}  // namespace hawor
