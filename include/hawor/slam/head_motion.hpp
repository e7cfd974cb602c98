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
// the first map, a loss in a fast head turn, a fixation where no map can be built), it replaces
// the held or linearly interpolated positions of that gap:
//   c_t = n + M·z_t + e(t),  e = the fit's residuals at the posed frames bounding the gap,
//   interpolated linearly across it (held beyond the ends)
// so the positions stay continuous with the posed neighbours. Used only where the model explains
// the posed frames (the fraction of their position variance it explains, R², at least minR2, and
// of their motion over a few frames, Δc = M·Δz, at least minMotionR2, with z spread over at least
// minSpreadDeg), where it has the shape of a head (the eye in front of the neck along the view,
// M·z ∥ z, at a steady distance) and the head turns across the gap (minGapTurnDeg): walking, or
// a body that sways while the view wanders, fails and keeps the interpolation.
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
    const HeadModelFit<Scalar> fit = fitHeadModel(T, idx, opt);
    if (report) {
      *report += " gap " + std::to_string(a) + "-" + std::to_string(b - 1) + ": " + std::to_string(fit.frames) + " frames, R2 " +
                 std::to_string(double(fit.r2)) + ", motion R2 " + std::to_string(double(fit.motionR2)) + ", spread " +
                 std::to_string(double(fit.spreadDeg)) + " deg, front " + std::to_string(double(fit.frontCos)) +
                 ", radius spread " + std::to_string(double(fit.radiusSpread)) + ";";
    }
    if (fit.ok && fit.r2 >= opt.minR2 && fit.motionR2 >= opt.minMotionR2 && fit.spreadDeg >= opt.minSpreadDeg &&
        fit.frontCos >= opt.minFrontCos && fit.radiusSpread <= opt.maxRadiusSpread) {
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

/// Two map segments of one standing head (a monocular map re-initialised after a loss has a
/// scale of its own): segment B's positions mapped into segment A's units, s·c + t, such that
/// one head model explains both (rotations are continuous across the reset: the tracked rays).
template <typename Scalar>
struct HeadJoin {
  bool ok = false;            ///< solved and every test of the file comment passed
  Scalar s = Scalar(1);       ///< B's scale in A's units
  Vec3<Scalar> t = Vec3<Scalar>::Zero();
  HeadModelFit<Scalar> fit;   ///< the joint model (in A's units) and its quality
  Scalar spreadA = Scalar(0), spreadB = Scalar(0);  ///< each segment's view spread (degrees)
};

/// Joint least squares over x = (n, M, s, t) (16 unknowns, a ridge on M): rows c_i = n + M·z_i
/// for the frames idxA of segment A, and 0 = n + M·z_i − s·c_i − t for the frames idxB of
/// segment B. Accepted (ok) when the joint model passes the head tests of fillGapsByHeadModel
/// (R², motion R² within each segment, the eye in front, a steady radius), each segment's views
/// spread over minSpreadDeg (its own scale is then determined) and s is positive.
template <typename Scalar>
HeadJoin<Scalar> fitHeadJoin(const std::vector<SE3<Scalar>>& T, const std::vector<int>& idxA, const std::vector<int>& idxB,
                             const HeadModelOptions<Scalar>& opt = {}) {
  using V3 = Eigen::Matrix<Scalar, 3, 1>;
  using M16 = Eigen::Matrix<Scalar, 16, 16>;
  using V16 = Eigen::Matrix<Scalar, 16, 1>;
  HeadJoin<Scalar> J;
  if (static_cast<int>(idxA.size()) < opt.minFrames || static_cast<int>(idxB.size()) < opt.minFrames) return J;
  // Centre A's positions (conditioning); the offset is added back to t.
  V3 ca = V3::Zero(), cb = V3::Zero();
  for (int i : idxA) ca += T[static_cast<std::size_t>(i)].translation();
  for (int i : idxB) cb += T[static_cast<std::size_t>(i)].translation();
  ca /= Scalar(idxA.size());
  cb /= Scalar(idxB.size());
  M16 N = M16::Zero();
  V16 g = V16::Zero();
  Eigen::Matrix<Scalar, 3, 16> R;
  auto zOf = [&](int i) { return V3(T[static_cast<std::size_t>(i)].rotationMatrix().col(2)); };
  for (int i : idxA) {
    R.setZero();
    R.template leftCols<3>().setIdentity();
    const V3 z = zOf(i);
    for (int k = 0; k < 3; ++k) R.template block<1, 3>(k, 3 + 3 * k) = z.transpose();
    N += R.transpose() * R;
    g += R.transpose() * (V3(T[static_cast<std::size_t>(i)].translation()) - ca);
  }
  for (int i : idxB) {
    R.setZero();
    R.template leftCols<3>().setIdentity();
    const V3 z = zOf(i);
    for (int k = 0; k < 3; ++k) R.template block<1, 3>(k, 3 + 3 * k) = z.transpose();
    R.col(12) = -(V3(T[static_cast<std::size_t>(i)].translation()) - cb);
    R.template rightCols<3>() = -Eigen::Matrix<Scalar, 3, 3>::Identity();
    N += R.transpose() * R;
  }
  const Scalar nObs = Scalar(idxA.size() + idxB.size());
  for (int k = 3; k < 12; ++k) N(k, k) += opt.ridge * nObs;
  const Eigen::LDLT<M16> ldlt(N);
  if (ldlt.info() != Eigen::Success) return J;
  const V16 x = ldlt.solve(g);
  J.s = x(12);
  if (!x.allFinite() || !(x(12) > Scalar(0))) return J;
  // B's rows were written for s·(c − c̄_B) + t' = n' + M·z with n' = n − c̄_A: t = t' + c̄_A − s·c̄_B.
  J.t = V3(x.template tail<3>()) + ca - J.s * cb;
  // The joint model's quality on all frames in A's units (fitHeadModel's measures).
  std::vector<SE3<Scalar>> U(T.begin(), T.end());
  std::vector<int> all = idxA;
  for (int i : idxB) {
    U[static_cast<std::size_t>(i)] = SE3<Scalar>(T[static_cast<std::size_t>(i)].rotation(), V3(J.s * V3(T[static_cast<std::size_t>(i)].translation()) + J.t));
    all.push_back(i);
  }
  std::sort(all.begin(), all.end());
  J.fit = fitHeadModel(U, all, opt);
  // Motion R² within each segment only (the lag never straddles the reset).
  const HeadModelFit<Scalar> fa = fitHeadModel(U, idxA, opt), fb = fitHeadModel(U, idxB, opt);
  J.spreadA = fa.spreadDeg;
  J.spreadB = fb.spreadDeg;
  auto motion = [&](const std::vector<int>& idx) {
    Scalar dres = 0, dvar = 0;
    for (std::size_t a = 0, b = 0; a < idx.size(); ++a) {
      while (b < idx.size() && idx[b] < idx[a] + opt.lag) ++b;
      if (b >= idx.size() || idx[b] != idx[a] + opt.lag) continue;
      const V3 dc = V3(U[static_cast<std::size_t>(idx[b])].translation()) - V3(U[static_cast<std::size_t>(idx[a])].translation());
      const V3 dz = zOf(idx[b]) - zOf(idx[a]);
      dres += (dc - J.fit.M * dz).squaredNorm();
      dvar += dc.squaredNorm();
    }
    return dvar > Scalar(0) ? Scalar(1) - dres / dvar : Scalar(0);
  };
  J.fit.motionR2 = std::min(motion(idxA), motion(idxB));
  J.ok = J.fit.ok && J.fit.r2 >= opt.minR2 && J.fit.motionR2 >= opt.minMotionR2 && J.fit.frontCos >= opt.minFrontCos &&
         J.fit.radiusSpread <= opt.maxRadiusSpread && J.spreadA >= opt.minSpreadDeg && J.spreadB >= opt.minSpreadDeg;
  return J;
}

}  // namespace hawor
