// hawor/slam/head_motion.hpp — positions for the frames the map could not pose, from a head
// model fitted to the frames it did pose.
//
// A head-worn camera that does not walk moves because the head turns: the eye sits a few
// centimetres in front of the neck and rides a sphere about it, so its position is a function of
// the head's orientation. Taken to first order in the viewing direction z_t (the camera's
// optical axis in the world, the third column of R_w_c):
//   c_t = n + M·z_t                                                        (n ∈ R³, M ∈ R³ˣ³)
// which holds a turn about a vertical neck (M = r·P_horizontal, the eye r in front of the
// axis), a nod about a horizontal one (M = r·I) and their mixtures; a roll about the optical axis
// leaves z_t and the eye in place. Fitted by least squares (a small ridge on M: directions of
// z the data never spans stay out of the prediction) to the posed frames within `window` frames
// of a gap (a run of frames without a map pose but with a rotation from the tracked rays: before
// the first map, a loss in a fast head turn, a fixation where no map can be built), or, where
// those fail the tests below (a fixation beside the gap: too little turning to fit), to all
// posed frames of the sequence, it replaces the held or linearly interpolated positions of that
// gap:
//   c_t = n + M·z_t + e(t),  e = the fit's residuals at the posed frames bounding the gap,
//   interpolated linearly across it (held beyond the ends)
// so the positions stay continuous with the posed neighbours. Used only where the model explains
// the posed frames (the fraction of their position variance it explains, R², at least minR2, and
// of their motion over a few frames, Δc = M·Δz, at least minMotionR2, with z spread over at least
// minSpreadDeg), where it has the shape of a head (the eye in front of the neck along the view,
// M·z ∥ z, at a steady distance) and the head turns across the gap (minGapTurnDeg): walking, or
// a body that sways while the view wanders, fails and keeps the interpolation.
// The same model joins map segments (a monocular map re-initialised after a loss has a scale and
// origin of its own): fitHeadJoinAll solves one model and each segment's similarity s_k·c + t_k
// together, linear in all unknowns; fitHeadJoin is its two-segment case.
// Pure functions, thread-safe.
#pragma once

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"

namespace hawor {

template <typename Scalar>
struct HeadModelOptions {
  int window = 90;                  ///< posed frames this close to a gap fit its model
  int minFrames = 30;               ///< posed frames needed for a fit
  Scalar minSpreadDeg = Scalar(20); ///< largest angle between two fitted viewing directions, at least
  Scalar minR2 = Scalar(0.9);       ///< fraction of the posed positions' variance explained, at least
  /// The same for their motion over `lag` frames, Δc = M·Δz (a walk along a curve can follow the
  /// heading in position, but not the head's own turns frame by frame).
  Scalar minMotionR2 = Scalar(0.8);
  int lag = 3;
  /// A head: the neck → eye offset M·z points along the view (mean cosine with z at least
  /// minFrontCos) with a steady length (relative spread at most maxRadiusSpread). A body swaying
  /// while the view wanders can correlate position and view without this shape.
  Scalar minFrontCos = Scalar(0.8);
  Scalar maxRadiusSpread = Scalar(0.3);
  Scalar ridge = Scalar(1e-5);      ///< on M, per frame (z is a unit vector): only keeps unspanned directions of z out
  /// A gap is filled only when the head turns across it by at least this much (largest angle of
  /// its viewing directions to those of the posed frames bounding it): over a short or straight
  /// gap the interpolation is as good, and a walk along a curve can mimic the model.
  Scalar minGapTurnDeg = Scalar(10);
  /// A gap whose window fails the tests is filled from the model of all posed frames when that
  /// one passes them.
  bool wholeSequenceFallback = true;
  /// fitHeadJoinAll's gate on the motion R² (instead of minMotionR2): the joint model's is the
  /// worst segment's, and a segment of narrow view spread moves little against its noise
  /// (fast_turns seed 4 masked, built without -march=native: 0.746 for a 27° segment whose
  /// scale the join gets within 13 %). The joint R² over all frames still has to reach minR2.
  Scalar joinMinMotionR2 = Scalar(0.7);
};

/// One fitted model c = n + M·z and its quality.
template <typename Scalar>
struct HeadModelFit {
  Vec3<Scalar> n = Vec3<Scalar>::Zero();
  Mat3<Scalar> M = Mat3<Scalar>::Zero();
  Scalar r2 = Scalar(0);          ///< explained variance fraction of the fitted positions
  Scalar motionR2 = Scalar(0);    ///< of their motion over `lag` frames (pairs of fitted frames)
  Scalar frontCos = Scalar(0);    ///< mean cosine between M·z (neck → eye) and z over the fitted frames
  Scalar radiusSpread = Scalar(0);  ///< relative standard deviation of ‖M·z‖ over them
  Scalar spreadDeg = Scalar(0);   ///< largest angle between two fitted viewing directions
  int frames = 0;
  bool ok = false;                ///< enough frames and a solvable system (quality not judged)
  Vec3<Scalar> predict(const SE3<Scalar>& T_w_c) const {
    return Vec3<Scalar>(n + M * Vec3<Scalar>(T_w_c.rotationMatrix().col(2)));
  }
};

/// The head tests of the file comment on a fit (view spread apart: a joint fit checks it per
/// segment): solved, R² ≥ minR2, motion R² ≥ minMotionR2, the eye in front, a steady radius.
template <typename Scalar>
bool passesHeadTests(const HeadModelFit<Scalar>& fit, const HeadModelOptions<Scalar>& opt) {
  return fit.ok && fit.r2 >= opt.minR2 && fit.motionR2 >= opt.minMotionR2 && fit.frontCos >= opt.minFrontCos &&
         fit.radiusSpread <= opt.maxRadiusSpread;
}

/// Least-squares fit of c = n + M·z to the poses `T` at the indices `idx` (file comment).
template <typename Scalar>
HeadModelFit<Scalar> fitHeadModel(const std::vector<SE3<Scalar>>& T, const std::vector<int>& idx,
                                  const HeadModelOptions<Scalar>& opt = {}) {
  using V3 = Eigen::Matrix<Scalar, 3, 1>;
  HeadModelFit<Scalar> fit;
  fit.frames = static_cast<int>(idx.size());
  if (fit.frames < std::max(opt.minFrames, 5)) return fit;
  // Centred: c − c̄ = M·(z − z̄), then n = c̄ − M·z̄. Per row k of M: min Σ (c_k − m_kᵀz)² + λ|m_k|².
  V3 cm = V3::Zero(), zm = V3::Zero();
  for (int i : idx) {
    cm += T[static_cast<std::size_t>(i)].translation();
    zm += T[static_cast<std::size_t>(i)].rotationMatrix().col(2);
  }
  cm /= Scalar(fit.frames);
  zm /= Scalar(fit.frames);
  Eigen::Matrix<Scalar, 3, 3> A = Eigen::Matrix<Scalar, 3, 3>::Zero(), B = Eigen::Matrix<Scalar, 3, 3>::Zero();
  Scalar varC = 0;
  for (int i : idx) {
    const V3 dz = V3(T[static_cast<std::size_t>(i)].rotationMatrix().col(2)) - zm;
    const V3 dc = V3(T[static_cast<std::size_t>(i)].translation()) - cm;
    A += dz * dz.transpose();
    B += dz * dc.transpose();
    varC += dc.squaredNorm();
  }
  if (!(varC > Scalar(0)) || !std::isfinite(varC)) return fit;
  A += opt.ridge * Scalar(fit.frames) * Eigen::Matrix<Scalar, 3, 3>::Identity();
  const Eigen::LLT<Eigen::Matrix<Scalar, 3, 3>> llt(A);
  if (llt.info() != Eigen::Success) return fit;
  const Eigen::Matrix<Scalar, 3, 3> Mt = llt.solve(B);  // Mᵀ
  fit.M = Mt.transpose();
  fit.n = cm - fit.M * zm;
  Scalar res = 0;
  for (int i : idx) res += (V3(T[static_cast<std::size_t>(i)].translation()) - V3(fit.predict(T[static_cast<std::size_t>(i)]))).squaredNorm();
  fit.r2 = Scalar(1) - res / varC;
  Scalar dres = 0, dvar = 0;
  for (std::size_t a = 0, b = 0; a < idx.size(); ++a) {
    while (b < idx.size() && idx[b] < idx[a] + opt.lag) ++b;
    if (b >= idx.size() || idx[b] != idx[a] + opt.lag) continue;
    const SE3<Scalar>& A = T[static_cast<std::size_t>(idx[a])];
    const SE3<Scalar>& B = T[static_cast<std::size_t>(idx[b])];
    const V3 dc = V3(B.translation()) - V3(A.translation());
    const V3 dz = V3(B.rotationMatrix().col(2)) - V3(A.rotationMatrix().col(2));
    dres += (dc - fit.M * dz).squaredNorm();
    dvar += dc.squaredNorm();
  }
  fit.motionR2 = dvar > Scalar(0) ? Scalar(1) - dres / dvar : Scalar(0);
  // A head: the eye sits in front of the neck, along the view (M·z ∥ z), at a steady distance.
  Scalar sc = 0, sr = 0, sr2 = 0;
  for (int i : idx) {
    const V3 z = T[static_cast<std::size_t>(i)].rotationMatrix().col(2);
    const V3 e = fit.M * z;
    const Scalar r = e.norm();
    sc += r > Scalar(0) ? e.dot(z) / r : Scalar(0);
    sr += r;
    sr2 += r * r;
  }
  const Scalar m = sr / Scalar(fit.frames);
  fit.frontCos = sc / Scalar(fit.frames);
  fit.radiusSpread = m > Scalar(0) ? std::sqrt(std::max(Scalar(0), sr2 / Scalar(fit.frames) - m * m)) / m : Scalar(1);
  Scalar minDot = Scalar(1);
  for (std::size_t a = 0; a < idx.size(); ++a) {
    const V3 za = T[static_cast<std::size_t>(idx[a])].rotationMatrix().col(2);
    for (std::size_t b = a + 1; b < idx.size(); b += 3) {
      minDot = std::min(minDot, za.dot(V3(T[static_cast<std::size_t>(idx[b])].rotationMatrix().col(2))));
    }
  }
  fit.spreadDeg = std::acos(std::max(Scalar(-1), std::min(Scalar(1), minDot))) * Scalar(180) / Constants<Scalar>::pi();
  fit.ok = fit.M.allFinite() && fit.n.allFinite();
  return fit;
}

/// Replaces the positions of the gaps' frames (`posed[f]` false, `rotationKnown[f]` true) by the
/// head model of the file comment where it explains the posed frames around the gap; rotations
/// are left as they are. Returns the number of frames changed; `report` (optional) gets a line
/// per gap with its fit's figures.
template <typename Scalar>
int fillGapsByHeadModel(std::vector<SE3<Scalar>>& T, const std::vector<char>& posed, const std::vector<char>& rotationKnown,
                        const HeadModelOptions<Scalar>& opt = {}, std::string* report = nullptr) {
  using V3 = Vec3<Scalar>;
  const int n = static_cast<int>(T.size());
  if (static_cast<int>(posed.size()) != n || static_cast<int>(rotationKnown.size()) != n) {
    throw Error("fillGapsByHeadModel: " + std::to_string(n) + " poses but " + std::to_string(posed.size()) + " posed and " +
                std::to_string(rotationKnown.size()) + " rotation flags");
  }
  int changed = 0;
  auto usable = [&](const HeadModelFit<Scalar>& f) { return passesHeadTests(f, opt) && f.spreadDeg >= opt.minSpreadDeg; };
  // The whole sequence's model (posed frames only: the same for every gap), fitted at most once.
  bool wholeFitted = false;
  HeadModelFit<Scalar> wholeFit;
  for (int a = 0; a < n;) {
    if (posed[static_cast<std::size_t>(a)]) {
      ++a;
      continue;
    }
    int b = a;  // the gap is [a, b)
    while (b < n && !posed[static_cast<std::size_t>(b)]) ++b;
    std::vector<int> idx;
    for (int f = std::max(0, a - opt.window); f < std::min(n, b + opt.window); ++f) {
      if (posed[static_cast<std::size_t>(f)]) idx.push_back(f);
    }
    // How far the head turns across the gap.
    Scalar turn = Scalar(0);
    for (int e : {a - 1, b}) {
      if (e < 0 || e >= n) continue;
      const V3 ze = T[static_cast<std::size_t>(e)].rotationMatrix().col(2);
      for (int f = a; f < b; ++f) {
        const Scalar c = ze.dot(V3(T[static_cast<std::size_t>(f)].rotationMatrix().col(2)));
        turn = std::max(turn, std::acos(std::max(Scalar(-1), std::min(Scalar(1), c))));
      }
    }
    if (turn * Scalar(180) / Constants<Scalar>::pi() < opt.minGapTurnDeg) {
      a = b;
      continue;
    }
    HeadModelFit<Scalar> fit = fitHeadModel(T, idx, opt);
    bool whole = false;
    if (opt.wholeSequenceFallback && !usable(fit)) {
      if (!wholeFitted) {
        std::vector<int> all;
        for (int f = 0; f < n; ++f) {
          if (posed[static_cast<std::size_t>(f)]) all.push_back(f);
        }
        wholeFit = fitHeadModel(T, all, opt);
        wholeFitted = true;
      }
      if (usable(wholeFit)) fit = wholeFit, whole = true;
    }
    if (report) {
      *report += " gap " + std::to_string(a) + "-" + std::to_string(b - 1) + ": " + std::to_string(fit.frames) +
                 (whole ? " frames (the whole sequence's model), R2 " : " frames, R2 ") +
                 std::to_string(double(fit.r2)) + ", motion R2 " + std::to_string(double(fit.motionR2)) + ", spread " +
                 std::to_string(double(fit.spreadDeg)) + " deg, front " + std::to_string(double(fit.frontCos)) +
                 ", radius spread " + std::to_string(double(fit.radiusSpread)) + ";";
    }
    if (usable(fit)) {
      const int left = a - 1, right = b < n ? b : -1;
      const V3 eL = left >= 0 ? V3(T[static_cast<std::size_t>(left)].translation() - fit.predict(T[static_cast<std::size_t>(left)])) : V3::Zero();
      const V3 eR = right >= 0 ? V3(T[static_cast<std::size_t>(right)].translation() - fit.predict(T[static_cast<std::size_t>(right)])) : V3::Zero();
      for (int f = a; f < b; ++f) {
        if (!rotationKnown[static_cast<std::size_t>(f)]) continue;
        V3 e;
        if (left >= 0 && right >= 0) {
          const Scalar w = Scalar(f - left) / Scalar(right - left);
          e = (Scalar(1) - w) * eL + w * eR;
        } else {
          e = left >= 0 ? eL : eR;
        }
        T[static_cast<std::size_t>(f)] = SE3<Scalar>(T[static_cast<std::size_t>(f)].rotation(), V3(fit.predict(T[static_cast<std::size_t>(f)]) + e));
        ++changed;
      }
    }
    a = b;
  }
  return changed;
}

/// Map segments of one standing head (a monocular map re-initialised after a loss has a scale of
/// its own): each segment k's positions mapped into the reference segment's units, s_k·c + t_k,
/// such that one head model explains them all (rotations are continuous across the resets: the
/// tracked rays). The reference has s = 1, t = 0.
template <typename Scalar>
struct HeadJoinAll {
  bool ok = false;                    ///< solved and every test of the file comment passed
  std::vector<Scalar> s;              ///< per segment, in the reference's units
  std::vector<Vec3<Scalar>> t;
  HeadModelFit<Scalar> fit;           ///< the joint model (reference units) and its quality
  std::vector<Scalar> spreadDeg;      ///< each segment's view spread
};

/// Joint least squares over x = (n, M, s_k, t_k for k ≠ ref) (12 + 4·(K − 1) unknowns, a ridge on
/// M): rows c_i = n + M·z_i for the frames groups[ref] of the reference segment and
/// 0 = n + M·z_i − s_k·c_i − t_k for the frames groups[k] of segment k. Accepted (ok) when the
/// joint model passes the head tests of fillGapsByHeadModel (R² over all frames, motion R² within
/// each segment at least joinMinMotionR2, the eye in front, a steady radius), each segment has opt.minFrames frames with
/// views spread over minSpreadDeg (its own scale is then determined) and every s_k is positive.
template <typename Scalar>
HeadJoinAll<Scalar> fitHeadJoinAll(const std::vector<SE3<Scalar>>& T, const std::vector<std::vector<int>>& groups, int ref,
                                   const HeadModelOptions<Scalar>& opt = {}) {
  using V3 = Eigen::Matrix<Scalar, 3, 1>;
  using MX = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  using VX = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  const int K = static_cast<int>(groups.size());
  HeadJoinAll<Scalar> J;
  J.s.assign(static_cast<std::size_t>(K), Scalar(1));
  J.t.assign(static_cast<std::size_t>(K), V3::Zero());
  J.spreadDeg.assign(static_cast<std::size_t>(K), Scalar(0));
  if (K < 2 || ref < 0 || ref >= K) return J;
  for (const std::vector<int>& g : groups) {
    if (static_cast<int>(g.size()) < opt.minFrames) return J;
  }
  auto cOf = [&](int i) { return V3(T[static_cast<std::size_t>(i)].translation()); };
  auto zOf = [&](int i) { return V3(T[static_cast<std::size_t>(i)].rotationMatrix().col(2)); };
  // Each segment's positions centred on its mean (conditioning); the offsets go back into t.
  std::vector<V3> mean(static_cast<std::size_t>(K), V3::Zero());
  for (int k = 0; k < K; ++k) {
    for (int i : groups[static_cast<std::size_t>(k)]) mean[static_cast<std::size_t>(k)] += cOf(i);
    mean[static_cast<std::size_t>(k)] /= Scalar(groups[static_cast<std::size_t>(k)].size());
  }
  std::vector<int> col(static_cast<std::size_t>(K), -1);  // first unknown (s_k) of segment k
  int nx = 12;
  for (int k = 0; k < K; ++k) {
    if (k != ref) col[static_cast<std::size_t>(k)] = nx, nx += 4;
  }
  MX N = MX::Zero(nx, nx);
  VX g = VX::Zero(nx);
  Eigen::Matrix<Scalar, 3, Eigen::Dynamic> R(3, nx);
  Scalar nObs = 0;
  for (int k = 0; k < K; ++k) {
    const int c0 = col[static_cast<std::size_t>(k)];
    for (int i : groups[static_cast<std::size_t>(k)]) {
      R.setZero();
      R.template leftCols<3>().setIdentity();
      const V3 z = zOf(i);
      for (int r = 0; r < 3; ++r) R.template block<1, 3>(r, 3 + 3 * r) = z.transpose();
      const V3 c = cOf(i) - mean[static_cast<std::size_t>(k)];
      if (k == ref) {
        g += R.transpose() * c;
      } else {
        R.col(c0) = -c;
        R.template block<3, 3>(0, c0 + 1) = -Eigen::Matrix<Scalar, 3, 3>::Identity();
      }
      N += R.transpose() * R;
      nObs += Scalar(1);
    }
  }
  for (int k = 3; k < 12; ++k) N(k, k) += opt.ridge * nObs;
  const Eigen::LDLT<MX> ldlt(N);
  if (ldlt.info() != Eigen::Success) return J;
  const VX x = ldlt.solve(g);
  if (!x.allFinite()) return J;
  // Segment k's rows were written for s·(c − c̄_k) + t' = n' + M·z with n' = n − c̄_ref:
  // t = t' + c̄_ref − s·c̄_k.
  for (int k = 0; k < K; ++k) {
    const int c0 = col[static_cast<std::size_t>(k)];
    if (c0 < 0) continue;
    J.s[static_cast<std::size_t>(k)] = x(c0);
    J.t[static_cast<std::size_t>(k)] = V3(x.template segment<3>(c0 + 1)) + mean[static_cast<std::size_t>(ref)] - x(c0) * mean[static_cast<std::size_t>(k)];
    if (!(x(c0) > Scalar(0))) return J;
  }
  // The joint model's quality on all frames in the reference's units (fitHeadModel's measures).
  std::vector<SE3<Scalar>> U(T.begin(), T.end());
  std::vector<int> all;
  for (int k = 0; k < K; ++k) {
    for (int i : groups[static_cast<std::size_t>(k)]) {
      U[static_cast<std::size_t>(i)] = SE3<Scalar>(T[static_cast<std::size_t>(i)].rotation(),
                                                   V3(J.s[static_cast<std::size_t>(k)] * cOf(i) + J.t[static_cast<std::size_t>(k)]));
      all.push_back(i);
    }
  }
  std::sort(all.begin(), all.end());
  J.fit = fitHeadModel(U, all, opt);
  // Motion R² within each segment only (the lag never straddles a reset); each one's spread.
  Scalar motion = Scalar(1), spread = Scalar(180);
  for (int k = 0; k < K; ++k) {
    const std::vector<int>& idx = groups[static_cast<std::size_t>(k)];
    J.spreadDeg[static_cast<std::size_t>(k)] = fitHeadModel(U, idx, opt).spreadDeg;
    spread = std::min(spread, J.spreadDeg[static_cast<std::size_t>(k)]);
    Scalar dres = 0, dvar = 0;
    for (std::size_t a = 0, b = 0; a < idx.size(); ++a) {
      while (b < idx.size() && idx[b] < idx[a] + opt.lag) ++b;
      if (b >= idx.size() || idx[b] != idx[a] + opt.lag) continue;
      const V3 dc = V3(U[static_cast<std::size_t>(idx[b])].translation()) - V3(U[static_cast<std::size_t>(idx[a])].translation());
      dres += (dc - J.fit.M * (zOf(idx[b]) - zOf(idx[a]))).squaredNorm();
      dvar += dc.squaredNorm();
    }
    motion = std::min(motion, dvar > Scalar(0) ? Scalar(1) - dres / dvar : Scalar(0));
  }
  J.fit.motionR2 = motion;
  HeadModelOptions<Scalar> gate = opt;
  gate.minMotionR2 = opt.joinMinMotionR2;
  J.ok = passesHeadTests(J.fit, gate) && spread >= opt.minSpreadDeg;
  return J;
}

/// Two map segments (fitHeadJoinAll with K = 2, A the reference): B's positions into A's units.
template <typename Scalar>
struct HeadJoin {
  bool ok = false;            ///< solved and every test of the file comment passed
  Scalar s = Scalar(1);       ///< B's scale in A's units
  Vec3<Scalar> t = Vec3<Scalar>::Zero();
  HeadModelFit<Scalar> fit;   ///< the joint model (in A's units) and its quality
  Scalar spreadA = Scalar(0), spreadB = Scalar(0);  ///< each segment's view spread (degrees)
};

template <typename Scalar>
HeadJoin<Scalar> fitHeadJoin(const std::vector<SE3<Scalar>>& T, const std::vector<int>& idxA, const std::vector<int>& idxB,
                             const HeadModelOptions<Scalar>& opt = {}) {
  const HeadJoinAll<Scalar> all = fitHeadJoinAll(T, {idxA, idxB}, 0, opt);
  HeadJoin<Scalar> J;
  J.ok = all.ok;
  J.s = all.s[1];
  J.t = all.t[1];
  J.fit = all.fit;
  J.spreadA = all.spreadDeg[0];
  J.spreadB = all.spreadDeg[1];
  return J;
}

/// The segments of one sequence joined by one head model (MonoSlam after its resets): per
/// segment its similarity s·c + t into the reference's units, or none (`group` −1) when it has
/// fewer than opt.minFrames posed frames or views spread under opt.minSpreadDeg (its own scale is
/// then undetermined; the caller may place its frames by the model, fillGapsByHeadModel).
template <typename Scalar>
struct SegmentsHeadJoin {
  bool ok = false;           ///< a model passed the head tests (one usable segment: its own model)
  std::vector<int> group;    ///< per segment: its index in join.s / join.t, −1 left out
  HeadJoinAll<Scalar> join;  ///< the usable segments' similarities (the longest one the reference)
  std::string report;        ///< per segment: frames, posed frames, view spread
};

/// Segment i spans the frames [first[i], first[i + 1]) of T (first has one entry more than the
/// segments, the last = T.size()); `posed` marks the frames whose positions are measured.
template <typename Scalar>
SegmentsHeadJoin<Scalar> joinSegmentsByHeadModel(const std::vector<SE3<Scalar>>& T, const std::vector<char>& posed,
                                                 const std::vector<int>& first, const HeadModelOptions<Scalar>& opt = {}) {
  SegmentsHeadJoin<Scalar> R;
  const std::size_t S = first.empty() ? 0 : first.size() - 1;
  if (posed.size() != T.size() || S == 0 || first.front() < 0 || first.back() != static_cast<int>(T.size())) {
    throw Error("joinSegmentsByHeadModel: " + std::to_string(T.size()) + " poses, " + std::to_string(posed.size()) +
                " posed flags, segment starts not ending at the pose count");
  }
  R.group.assign(S, -1);
  std::vector<std::vector<int>> groups;
  int ref = -1;
  for (std::size_t i = 0; i < S; ++i) {
    if (first[i + 1] < first[i]) throw Error("joinSegmentsByHeadModel: segment starts out of order");
    std::vector<int> idx;
    for (int f = first[i]; f < first[i + 1]; ++f) {
      if (posed[static_cast<std::size_t>(f)]) idx.push_back(f);
    }
    const HeadModelFit<Scalar> own = fitHeadModel(T, idx, opt);
    R.report += " " + std::to_string(first[i]) + "-" + std::to_string(first[i + 1] - 1) + ": " + std::to_string(idx.size()) +
                " posed, spread " + std::to_string(static_cast<int>(own.spreadDeg)) + " deg;";
    if (static_cast<int>(idx.size()) < opt.minFrames || own.spreadDeg < opt.minSpreadDeg) continue;
    R.group[i] = static_cast<int>(groups.size());
    if (ref < 0 || idx.size() > groups[static_cast<std::size_t>(ref)].size()) ref = static_cast<int>(groups.size());
    groups.push_back(std::move(idx));
  }
  if (groups.empty()) return R;
  if (groups.size() == 1) {
    // One usable segment: its own model, judged by the same tests.
    R.join.s.assign(1, Scalar(1));
    R.join.t.assign(1, Vec3<Scalar>::Zero());
    R.join.spreadDeg.assign(1, Scalar(0));
    R.join.fit = fitHeadModel(T, groups[0], opt);
    R.join.spreadDeg[0] = R.join.fit.spreadDeg;
    R.join.ok = passesHeadTests(R.join.fit, opt);
  } else {
    R.join = fitHeadJoinAll(T, groups, ref, opt);
  }
  R.ok = R.join.ok;
  return R;
}

}  // namespace hawor
