// hawor/motion/motion_noise.hpp — the per-frame noise level of a motion channel, from its
// observed frames, for the spline gap filler and the smoother.
//
// Smooth motion (and any polynomial of degree ≤ 3 in time) has 4th differences close to 0, while
// white noise of standard deviation σ per component gives Δ⁴ε ~ N(0, 70σ²) per component. For
// a 3-vector channel the norm |Δ⁴x| then follows σ·√70·χ₃, so
//   σ = median_t |Δ⁴x_t| / (√70 · 1.5382),   1.5382 = the median of the χ distribution with 3
// degrees of freedom. The median is robust to the motion's own occasional jerks, and the norm
// makes the estimate independent of the frame the channel is expressed in (world or canonical).
// Only runs of ≥ 5 consecutive valid frames contribute. Rotations use the per-frame body
// increments w_t = log(R_tᵀR_{t+1}) (first differences of the rotation), so Δ³w plays Δ⁴.
// Returns 0 when no run is long enough (then callers treat the channel as noise-free).
// Thread-safety: pure functions.
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/motion/hand_motion.hpp"
#include "hawor/motion/sequence.hpp"

namespace hawor {

namespace noise_detail {

/// median(|Δ⁴|) → σ for 3-vectors (file comment). 0 for none.
template <typename Scalar>
Scalar sigmaFromNorms(std::vector<Scalar>&& norms) {
  if (norms.empty()) return Scalar(0);
  return median(std::move(norms)) / (std::sqrt(Scalar(70)) * Scalar(1.5381722544550522));
}

}  // namespace noise_detail

/// Noise σ (units of the channel) of the 3-vector channel at columns [col, col+3) of `seq`.
template <typename Scalar>
Scalar estimateVectorNoise(const Sequence<Scalar>& seq, Eigen::Index col, const ValidMask& valid) {
  checkMask(valid, seq.rows(), "estimateVectorNoise");
  if (col < 0 || col + 3 > seq.cols()) throw Error("estimateVectorNoise: column out of range");
  std::vector<Scalar> d;
  Eigen::Index run = 0;
  for (Eigen::Index t = 0; t < seq.rows(); ++t) {
    run = valid[static_cast<size_t>(t)] ? run + 1 : 0;
    if (run < 5) continue;
    Scalar n2(0);
    for (Eigen::Index c = col; c < col + 3; ++c) {
      const Scalar e = seq(t - 4, c) - Scalar(4) * seq(t - 3, c) + Scalar(6) * seq(t - 2, c) -
                       Scalar(4) * seq(t - 1, c) + seq(t, c);
      n2 += e * e;
    }
    d.push_back(std::sqrt(n2));
  }
  return noise_detail::sigmaFromNorms(std::move(d));
}

/// Noise σ (radians) of the axis-angle rotation channel at columns [col, col+3) of `seq`.
template <typename Scalar>
Scalar estimateRotationNoise(const Sequence<Scalar>& seq, Eigen::Index col, const ValidMask& valid) {
  checkMask(valid, seq.rows(), "estimateRotationNoise");
  if (col < 0 || col + 3 > seq.cols()) throw Error("estimateRotationNoise: column out of range");
  std::vector<Scalar> d;
  Vec3<Scalar> w[4] = {Vec3<Scalar>::Zero(), Vec3<Scalar>::Zero(), Vec3<Scalar>::Zero(),
                       Vec3<Scalar>::Zero()};  // the last 4 increments
  Mat3<Scalar> prev = Mat3<Scalar>::Identity();
  Eigen::Index run = 0;
  for (Eigen::Index t = 0; t < seq.rows(); ++t) {
    if (!valid[static_cast<size_t>(t)]) {
      run = 0;
      continue;
    }
    const Vec3<Scalar> a = seq.row(t).template segment<3>(col).transpose();
    const Mat3<Scalar> cur = axisAngleToMatrix(a);
    if (run > 0) {
      for (int k = 0; k < 3; ++k) w[k] = w[k + 1];
      w[3] = matrixToAxisAngle(Mat3<Scalar>(prev.transpose() * cur));
    }
    prev = cur;
    if (++run < 5) continue;
    d.push_back((w[3] - Scalar(3) * w[2] + Scalar(3) * w[1] - w[0]).norm());
  }
  return noise_detail::sigmaFromNorms(std::move(d));
}

/// The noise levels of every channel of a hand (see estimateHandNoise).
template <typename Scalar>
struct HandNoise {
  Scalar trans = Scalar(0);    ///< metres
  Scalar rot = Scalar(0);      ///< radians, global orientation
  std::vector<Scalar> joints;  ///< radians, one per joint rotation of handPose
};

/// Noise σ of a hand's translation, global rotation and each joint rotation (observed frames).
/// Used to give the gap filler the noise of the raw observations when they were smoothed first
/// (smoothing removes the high frequencies this estimate sees, not the noise's slow part).
template <typename Scalar>
HandNoise<Scalar> estimateHandNoise(const HandMotion<Scalar>& m) {
  m.validate();
  HandNoise<Scalar> n;
  n.trans = estimateVectorNoise(m.trans, 0, m.valid);
  n.rot = estimateRotationNoise(m.rot, 0, m.valid);
  for (Eigen::Index c = 0; c < m.handPose.cols(); c += 3)
    n.joints.push_back(estimateRotationNoise(m.handPose, c, m.valid));
  return n;
}

}  // namespace hawor
