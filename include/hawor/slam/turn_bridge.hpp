// hawor/slam/turn_bridge.hpp — the pose of a frame whose map has left the view in a fast head
// turn, from the previous frame's pose, the tracks between the two and points triangulated from
// the frames just before.
//
// In a fast turn (10–20° a frame) the mapped points leave the view within two or three frames,
// faster than new ones reach the parallax to be triangulated at keyframes; PnP then has too few
// points, the map is reset and the new segment's scale is a guess. The neck's lever arm moves
// the eye by 2·r·sin(θ/2) a frame (r ≈ 9 cm: 1.4 cm at 9°), sideways, but that step leaves only
// 0.6–0.9 px of parallax once a rotation has absorbed what it can: the epipolar geometry of two
// frames alone cannot tell it from a forward step (measured: it picks the optical axis). So:
//   1. the step's direction from a head sphere: the eye rides a sphere about the neck, c = n + r·z
//      (z the optical axis in the world), so c₂ − c₁ ∝ z₂ − z₁, i.e. in camera 2
//      t ∝ −R_c2w·(z₂ − z₁) for X2 = R·X1 + t;
//   2. the rotation R (camera 1 → camera 2) by Gauss–Newton on the tracks' Sampson errors under
//      that direction (Huber at inlierPx), started from the rays' rotation (Kabsch), which is
//      biased by the absorbed step (1–1.5° in a fast turn);
//   3. the step's length s (c₂ = c₁ + s·b̂, b̂ = −R_w1·Rᵀ·t̂): each point X (a map point still
//      tracked, or one triangulated by the caller from the two frames before) seen at y in the
//      current frame gives s in closed form (least squares of its projection, linear in s); the
//      median, with at least minPoints of them (and minPointRatio) within pointInlierPx at that
//      length, and within maxLengthRatio of the caller's prediction where it has one (the last
//      step's radius |c₁ − c₀| / (2·sin(θ₀₁/2)) times 2·sin(θ/2)).
// Fails (ok = false, `why`) rather than guess: too few tracks or points, too little turn for the
// direction (minStepDeg), the points or the prediction disagreeing.
// Pure function, thread-safe. Computed in double.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/slam/two_view.hpp"

namespace hawor {

template <typename Scalar>
struct TurnBridgeOptions {
  int minTracks = 40;                     ///< tracks between the two frames, at least
  Scalar inlierPx = Scalar(1);            ///< Sampson distance of an inlier (pixels; Huber width)
  Scalar minInlierRatio = Scalar(0.6);    ///< of the tracks, under the final (R, t̂)
  Scalar minStepDeg = Scalar(2);          ///< the view must turn by this much (the direction)
  int minPoints = 8;                      ///< points that fix the step's length
  /// Of the points, within pointInlierPx at that length (the ones triangulated from two frames
  /// 1–2 cm apart scatter; measured on fast_turns seeds 1–8: 0.3 better than 0.4 and 0.5).
  Scalar minPointRatio = Scalar(0.3);
  Scalar pointInlierPx = Scalar(2);
  /// Against the caller's predicted length (stepLength > 0): at most this factor apart.
  Scalar maxLengthRatio = Scalar(3);
};

template <typename Scalar>
struct TurnBridgeResult {
  bool ok = false;
  SE3<Scalar> T_w_c;           ///< the current frame (camera-to-world)
  int inliers = 0;             ///< tracks within inlierPx of the epipolar geometry
  int pointInliers = 0;        ///< points within pointInlierPx at the chosen length
  Scalar rotationChangeDeg = 0;  ///< the refinement's change of the rays' rotation
  Scalar length = 0;           ///< |c₂ − c₁|
  std::string why;             ///< what failed (empty when ok)
};

namespace turn_bridge_detail {

/// exp of so(3) by Eigen's angle-axis. hawor::axisAngleToMatrix is the same map, but its rounding
/// differs. Through the central-difference Jacobian below, that difference moved
/// fast_turns seed 7 unmasked from 1.98 to 3.29 % (a sequence that is chaotic in the front end's
/// choices). The published figures were measured with this one.
inline Eigen::Matrix3d expSO3(const Eigen::Vector3d& w) {
  const double th = w.norm();
  if (th < 1e-12) return Eigen::Matrix3d::Identity() + hat(w);
  return Eigen::AngleAxisd(th, w / th).toRotationMatrix();
}

inline double angleDeg(const Eigen::Matrix3d& R) { return matrixToAxisAngle(R).norm() * 180.0 / 3.14159265358979323846; }

/// Signed Sampson distance (normalised units) of a ↔ b under E.
inline double sampson(const Eigen::Matrix3d& E, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d Ea = E * a, Etb = E.transpose() * b;
  const double den = Ea(0) * Ea(0) + Ea(1) * Ea(1) + Etb(0) * Etb(0) + Etb(1) * Etb(1);
  return den > 0 ? b.dot(Ea) / std::sqrt(den) : 1e9;
}

/// The head-sphere direction t̂ (camera 2) of the motion R (camera 1 → 2) from the pose Rw1.
inline bool sphereDirection(const Eigen::Matrix3d& Rw1, const Eigen::Matrix3d& R, Eigen::Vector3d& t) {
  const Eigen::Matrix3d Rw2 = Rw1 * R.transpose();
  const Eigen::Vector3d dz = Rw2.col(2) - Rw1.col(2);
  if (!(dz.norm() > 1e-9)) return false;
  t = -(Rw2.transpose() * dz).normalized();
  return true;
}

}  // namespace turn_bridge_detail

/// The bridge (file comment). x1/x2: the tracks in the previous and the current frame
/// (normalised coordinates); X/y: points (world) and their normalised observations in the
/// current frame; focalPx converts the pixel thresholds. Throws hawor::Error for mismatched
/// sizes or a non-positive focal length.
template <typename Scalar>
TurnBridgeResult<Scalar> bridgeTurnPose(const SE3<Scalar>& T_w_prev, const std::vector<Vec2<Scalar>>& x1,
                                        const std::vector<Vec2<Scalar>>& x2, const std::vector<Vec3<Scalar>>& X,
                                        const std::vector<Vec2<Scalar>>& y, Scalar focalPx, Scalar stepLength,
                                        const TurnBridgeOptions<Scalar>& opt = {}) {
  using namespace turn_bridge_detail;
  using V3d = Eigen::Vector3d;
  using M3d = Eigen::Matrix3d;
  if (x1.size() != x2.size() || X.size() != y.size()) throw Error("bridgeTurnPose: correspondence lists differ in length");
  if (!(focalPx > Scalar(0))) throw Error("bridgeTurnPose: focal length must be positive");
  TurnBridgeResult<Scalar> res;
  const std::size_t n = x1.size();
  if (static_cast<int>(n) < opt.minTracks) {
    res.why = "too few tracks";
    return res;
  }
  std::vector<V3d> a(n), b(n);
  for (std::size_t i = 0; i < n; ++i) {
    a[i] = V3d(double(x1[i](0)), double(x1[i](1)), 1.0);
    b[i] = V3d(double(x2[i](0)), double(x2[i](1)), 1.0);
  }
  const double f = double(focalPx), thr = double(opt.inlierPx) / f;
  // Rays' rotation (pure-rotation hypothesis), one 3° re-weighting pass.
  Mat3<Scalar> Rs;
  two_view_detail::rotationFromRaysReweighted(x1, x2, Scalar(3), Rs);
  M3d R = Rs.template cast<double>();
  const M3d Rrays = R;
  const M3d Rw1 = T_w_prev.rotationMatrix().template cast<double>();
  if (angleDeg(R) < double(opt.minStepDeg)) {
    res.why = "too little turn for the direction";
    return res;
  }
  // Gauss–Newton on ω (R ← exp(ω)·R), t̂ = sphereDirection(R), Huber-weighted Sampson errors.
  auto residual = [&](const M3d& Rm, std::size_t i, const V3d& t) { return sampson(hat(t) * Rm, a[i], b[i]); };  // E = [t]×·R
  auto cost = [&](const M3d& Rm) {
    V3d t;
    if (!sphereDirection(Rw1, Rm, t)) return 1e300;
    double c = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double r = std::abs(residual(Rm, i, t));
      c += r <= thr ? r * r : 2 * thr * r - thr * thr;
    }
    return c;
  };
  double lambda = 1e-4;
  for (int it = 0; it < 10; ++it) {
    V3d t0;
    if (!sphereDirection(Rw1, R, t0)) break;
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    V3d g = V3d::Zero();
    const double h = 1e-7;
    M3d Rp[3], Rm[3];
    V3d tp[3], tm[3];
    bool okd = true;
    for (int k = 0; k < 3; ++k) {
      V3d w = V3d::Zero();
      w(k) = h;
      Rp[k] = expSO3(w) * R, Rm[k] = expSO3(-w) * R;
      okd = okd && sphereDirection(Rw1, Rp[k], tp[k]) && sphereDirection(Rw1, Rm[k], tm[k]);
    }
    if (!okd) break;
    for (std::size_t i = 0; i < n; ++i) {
      const double r0 = residual(R, i, t0);
      const double wgt = std::abs(r0) <= thr ? 1.0 : thr / std::abs(r0);
      V3d J;
      for (int k = 0; k < 3; ++k) J(k) = (residual(Rp[k], i, tp[k]) - residual(Rm[k], i, tm[k])) / (2 * h);
      H.noalias() += wgt * J * J.transpose();
      g.noalias() += wgt * J * r0;
    }
    const double c0 = cost(R);
    bool improved = false;
    for (int tries = 0; tries < 6 && !improved; ++tries) {
      Eigen::Matrix3d A = H;
      A.diagonal() *= (1 + lambda);
      const V3d d = A.ldlt().solve(-g);
      if (!d.allFinite()) break;
      const M3d Rn = expSO3(d) * R;
      if (cost(Rn) < c0) {
        R = Rn, lambda = std::max(lambda * 0.3, 1e-9), improved = true;
        if (d.norm() < 1e-9) it = 10;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) break;
  }
  V3d t;
  if (!sphereDirection(Rw1, R, t)) {
    res.why = "no step direction";
    return res;
  }
  res.rotationChangeDeg = Scalar(angleDeg(R * Rrays.transpose()));
  for (std::size_t i = 0; i < n; ++i) res.inliers += std::abs(residual(R, i, t)) <= thr ? 1 : 0;
  if (Scalar(res.inliers) < opt.minInlierRatio * Scalar(n)) {
    res.why = "too few epipolar inliers";
    return res;
  }
  // The step's length along b̂ (world). Each point: Xc = A − s·B (A = R_cw·(X − c₁),
  // B = R_cw·b̂); its projection y gives s·(B_x − y_x·B_z) = A_x − y_x·A_z and the same in y.
  const V3d c1 = T_w_prev.translation().template cast<double>();
  const M3d Rw2 = Rw1 * R.transpose(), Rcw = Rw2.transpose();
  const V3d bh = -(Rw1 * (R.transpose() * t));
  const V3d B = Rcw * bh;
  std::vector<double> s;
  std::vector<std::size_t> idx;
  for (std::size_t j = 0; j < X.size(); ++j) {
    const V3d A = Rcw * (X[j].template cast<double>() - c1);
    const double yx = double(y[j](0)), yy = double(y[j](1));
    const double px = B(0) - yx * B(2), py = B(1) - yy * B(2), qx = A(0) - yx * A(2), qy = A(1) - yy * A(2);
    const double den = px * px + py * py;
    if (!(den > 1e-18) || !std::isfinite(qx * px + qy * py)) continue;
    s.push_back((qx * px + qy * py) / den);
    idx.push_back(j);
  }
  if (static_cast<int>(s.size()) < opt.minPoints) {
    res.why = "too few points for the step's length";
    return res;
  }
  const double sm = median(s);
  std::vector<double> good;
  for (std::size_t k = 0; k < idx.size(); ++k) {
    const V3d Xc = Rcw * (X[idx[k]].template cast<double>() - c1) - sm * B;
    if (!(Xc(2) > 0)) continue;
    const double ex = Xc(0) / Xc(2) - double(y[idx[k]](0)), ey = Xc(1) / Xc(2) - double(y[idx[k]](1));
    if (f * std::sqrt(ex * ex + ey * ey) <= double(opt.pointInlierPx)) good.push_back(s[k]);
  }
  res.pointInliers = static_cast<int>(good.size());
  if (static_cast<int>(good.size()) < opt.minPoints || Scalar(good.size()) < opt.minPointRatio * Scalar(s.size())) {
    res.why = "the points disagree on the step's length";
    return res;
  }
  const double len = median(good);
  res.length = Scalar(len);
  if (!(len > 0) || !std::isfinite(len)) {
    res.why = "no forward step";
    return res;
  }
  const double pred = double(stepLength), k = double(opt.maxLengthRatio);
  if (pred > 0 && (len > k * pred || pred > k * len)) {
    res.why = "the length is far from the predicted one";
    return res;
  }
  res.T_w_c = SE3<Scalar>(Mat3<Scalar>(Rw2.template cast<Scalar>()), Vec3<Scalar>((c1 + len * bh).template cast<Scalar>()));
  res.ok = true;
  return res;
}

}  // namespace hawor
