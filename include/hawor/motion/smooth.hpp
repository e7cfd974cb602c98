// hawor/motion/smooth.hpp — an optional, light temporal smoother for the OBSERVED frames of a
// hand (`hawor infill --smooth`), separate from the gap filling so that filling alone never
// changes an observed frame.
//
// Per valid frame t, inside its run of consecutive valid frames (never across a gap):
//   translation  x'_t = x_t + clamp(q(0) − x_t, b_x),  q = the weighted least-squares quadratic
//                through the run's frames t−h..t+h (Gaussian weights, σ_w = h/2) in time;
//   rotation     R'_t = R_t·exp(clamp(q(0), b_R)),  q fitted to r_j = log(R_tᵀR_j) (the tangent
//                space at R_t), for the global orientation and each joint rotation;
// clamp(v, b) shortens v to length b. The bound keeps every frame near its evidence:
//   b_x = min(maxSigmas·σ_x, maxTranslation),  b_R = min(maxSigmas·σ_R, maxAngle),
// σ the channel's noise estimated from the observed frames (motion_noise.hpp). On clean input
// σ ≈ 0, so the smoother changes (almost) nothing; on jittery input it removes jitter up to the
// bound. A quadratic (not a mean) keeps real accelerations: a motion that is quadratic in time
// over the window is left as it is. Runs shorter than 3 frames are left unchanged; betas and
// missing frames are not touched; the validity mask is kept.
// Thread-safety: pure function.
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

namespace hawor {

/// Settings of smoothObserved (file comment).
template <typename Scalar>
struct SmoothOptions {
  int halfWindow = 4;                       ///< h: frames on each side
  Scalar maxSigmas = Scalar(3);             ///< bound in units of the channel's noise σ
  Scalar maxTranslation = Scalar(0.01);     ///< metres, hard cap of a frame's displacement
  Scalar maxAngle = Scalar(0.05);           ///< radians, hard cap of a rotation's change

  void validate() const {
    if (halfWindow < 1) throw Error("smoothObserved: halfWindow must be at least 1");
    if (!(maxSigmas >= Scalar(0)) || !(maxTranslation >= Scalar(0)) || !(maxAngle >= Scalar(0)) ||
        !std::isfinite(maxSigmas) || !std::isfinite(maxTranslation) || !std::isfinite(maxAngle))
      throw Error("smoothObserved: bounds must be finite and non-negative");
  }
};

namespace smooth_detail {

/// v shortened to length b (unchanged when |v| <= b).
template <typename Scalar>
Vec3<Scalar> clampNorm(const Vec3<Scalar>& v, Scalar b) {
  const Scalar n = v.norm();
  return n > b ? Vec3<Scalar>(v * (b / n)) : v;
}

/// For every valid frame, the first and last frame of its run of consecutive valid frames.
inline void validRuns(const ValidMask& valid, std::vector<Eigen::Index>& first, std::vector<Eigen::Index>& last) {
  const Eigen::Index T = static_cast<Eigen::Index>(valid.size());
  first.assign(valid.size(), -1);
  last.assign(valid.size(), -1);
  for (Eigen::Index t = 0; t < T;) {
    if (!valid[static_cast<size_t>(t)]) {
      ++t;
      continue;
    }
    Eigen::Index e = t;
    while (e + 1 < T && valid[static_cast<size_t>(e + 1)]) ++e;
    for (Eigen::Index k = t; k <= e; ++k) {
      first[static_cast<size_t>(k)] = t;
      last[static_cast<size_t>(k)] = e;
    }
    t = e + 1;
  }
}

/// Smooths the 3-column group `col` of `seq` (rotations when `rotation`) into `out`.
template <typename Scalar>
void smoothChannel(const Sequence<Scalar>& seq, Eigen::Index col, const ValidMask& valid,
                   bool rotation, Scalar bound, int h, Sequence<Scalar>& out) {
  const Eigen::Index T = seq.rows();
  std::vector<Scalar> tau, w;
  std::vector<Vec3<Scalar>> y;
  std::vector<Eigen::Index> first, last;
  validRuns(valid, first, last);
  const Scalar sw = Scalar(h) / Scalar(2);
  for (Eigen::Index t = 0; t < T; ++t) {
    if (!valid[static_cast<size_t>(t)]) continue;
    const Eigen::Index lo = std::max(first[static_cast<size_t>(t)], t - h);
    const Eigen::Index hi = std::min(last[static_cast<size_t>(t)], t + h);
    const int n = static_cast<int>(hi - lo + 1);
    if (n < 3) continue;
    tau.clear();
    w.clear();
    y.clear();
    const Vec3<Scalar> at = seq.row(t).template segment<3>(col).transpose();
    const Mat3<Scalar> RtT = rotation ? Mat3<Scalar>(axisAngleToMatrix(at).transpose()) : Mat3<Scalar>::Identity();
    for (Eigen::Index j = lo; j <= hi; ++j) {
      const Scalar d = Scalar(j - t);
      tau.push_back(d);
      w.push_back(std::exp(-Scalar(0.5) * d * d / (sw * sw)));
      const Vec3<Scalar> v = seq.row(j).template segment<3>(col).transpose();
      y.push_back(rotation ? matrixToAxisAngle(Mat3<Scalar>(RtT * axisAngleToMatrix(v))) : Vec3<Scalar>(v - at));
    }
    const LocalPolyFit<Scalar> f = fitLocalPolynomial(tau.data(), y.data(), w.data(), n, 2);
    if (!f.ok) continue;
    const Vec3<Scalar> delta = clampNorm(f.value, bound);
    if (rotation) {
      const Mat3<Scalar> R = RtT.transpose() * axisAngleToMatrix(delta);
      out.row(t).template segment<3>(col) = matrixToAxisAngle(R).transpose();
    } else {
      out.row(t).template segment<3>(col) = (at + delta).transpose();
    }
  }
}

}  // namespace smooth_detail

/// The bounded smoother of the file comment applied to the observed frames of `m` (trans, rot,
/// every joint of handPose). Missing frames, betas and the mask are copied unchanged.
template <typename Scalar>
HandMotion<Scalar> smoothObserved(const HandMotion<Scalar>& m, const SmoothOptions<Scalar>& o = {}) {
  m.validate();
  o.validate();
  HandMotion<Scalar> out = m;
  const Scalar bt = std::min(o.maxSigmas * estimateVectorNoise(m.trans, 0, m.valid), o.maxTranslation);
  smooth_detail::smoothChannel(m.trans, 0, m.valid, false, bt, o.halfWindow, out.trans);
  const Scalar br = std::min(o.maxSigmas * estimateRotationNoise(m.rot, 0, m.valid), o.maxAngle);
  smooth_detail::smoothChannel(m.rot, 0, m.valid, true, br, o.halfWindow, out.rot);
  for (Eigen::Index c = 0; c < m.handPose.cols(); c += 3) {
    const Scalar bj = std::min(o.maxSigmas * estimateRotationNoise(m.handPose, c, m.valid), o.maxAngle);
    smooth_detail::smoothChannel(m.handPose, c, m.valid, true, bj, o.halfWindow, out.handPose);
  }
  return out;
}

}  // namespace hawor
