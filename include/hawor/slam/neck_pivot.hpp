// hawor/slam/neck_pivot.hpp — the neck pivot of a head-worn camera: the eye rides on a sphere
// about the neck while a standing person turns the head, so its centre is
//   c_t = n + R_t·o,
// n the pivot (world), o the eye's offset from it in camera coordinates (≈ 8–10 cm up and ahead
// for an adult), R_t the camera-to-world rotation. Least squares over the usable frames in
// [begin, end) — linear in (n, o): J_t = [I  R_t], Σ J_tᵀJ_t·(n; o) = Σ J_tᵀc_t — with the
// rotations spread by at least minSpreadDeg (otherwise n and o are not separable). The residual
// RMS says whether the model holds (walking adds a translation it does not explain).
// Used by mono_slam.hpp to place the frames before the first map (their rotations known from the
// tracked rays): a fixation followed by a turn holds the eye 2 cm away from where the map starts.
// Thread-safety: pure function.
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"

namespace hawor {

template <typename Scalar>
struct NeckPivot {
  Vec3<Scalar> neck = Vec3<Scalar>::Zero();    ///< n (world)
  Vec3<Scalar> offset = Vec3<Scalar>::Zero();  ///< o (camera frame)
  Scalar rms = std::numeric_limits<Scalar>::quiet_NaN();  ///< residual RMS of c_t (world units)
  Scalar spreadDeg = Scalar(0);  ///< largest rotation angle from the first usable frame's
  int frames = 0;
  bool solved = false;
  /// The model explains the poses: solved, and the residual at most maxRelRms of |o|.
  bool holds(Scalar maxRelRms) const {
    return solved && offset.norm() > Scalar(0) && std::isfinite(double(rms)) && rms <= maxRelRms * offset.norm();
  }
  Vec3<Scalar> centre(const SO3<Scalar>& R) const { return neck + R.matrix() * offset; }
};

/// The neck pivot (file comment) of the camera-to-world poses over [begin, end), frames flagged
/// `usable` (may be empty: all usable). Not solved with fewer than 6 frames or a rotation spread
/// below minSpreadDeg.
template <typename Scalar>
NeckPivot<Scalar> fitNeckPivot(const std::vector<SE3<Scalar>>& T_w_c, const std::vector<char>& usable, int begin, int end,
                               Scalar minSpreadDeg = Scalar(10)) {
  if (!usable.empty() && usable.size() != T_w_c.size()) throw Error("fitNeckPivot: usable flags and poses differ in length");
  begin = std::max(begin, 0);
  end = std::min(end, static_cast<int>(T_w_c.size()));
  NeckPivot<Scalar> out;
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
  int first = -1;
  double spread = 0;
  for (int t = begin; t < end; ++t) {
    const std::size_t i = static_cast<std::size_t>(t);
    if (!usable.empty() && !usable[i]) continue;
    const Eigen::Matrix3d R = T_w_c[i].rotationMatrix().template cast<double>();
    const Eigen::Vector3d c = T_w_c[i].translation().template cast<double>();
    if (!R.allFinite() || !c.allFinite()) continue;
    if (first < 0) first = t;
    const Eigen::Matrix3d R0 = T_w_c[static_cast<std::size_t>(first)].rotationMatrix().template cast<double>();
    spread = std::max(spread, std::acos(std::max(-1.0, std::min(1.0, ((R0.transpose() * R).trace() - 1) / 2))));
    A.template block<3, 3>(0, 0) += Eigen::Matrix3d::Identity();
    A.template block<3, 3>(0, 3) += R;
    A.template block<3, 3>(3, 0) += R.transpose();
    A.template block<3, 3>(3, 3) += Eigen::Matrix3d::Identity();
    b.template head<3>() += c;
    b.template tail<3>() += R.transpose() * c;
    ++out.frames;
  }
  out.spreadDeg = Scalar(spread * 180.0 / M_PI);
  if (out.frames < 6 || !(out.spreadDeg >= minSpreadDeg)) return out;
  const Eigen::Matrix<double, 6, 1> x = A.ldlt().solve(b);
  if (!x.allFinite()) return out;
  out.neck = x.template head<3>().template cast<Scalar>();
  out.offset = x.template tail<3>().template cast<Scalar>();
  double ss = 0;
  for (int t = begin; t < end; ++t) {
    const std::size_t i = static_cast<std::size_t>(t);
    if (!usable.empty() && !usable[i]) continue;
    const Eigen::Vector3d c = T_w_c[i].translation().template cast<double>();
    const Eigen::Vector3d e = x.template head<3>() + T_w_c[i].rotationMatrix().template cast<double>() * x.template tail<3>() - c;
    if (e.allFinite()) ss += e.squaredNorm();
  }
  out.rms = Scalar(std::sqrt(ss / out.frames));
  out.solved = true;
  return out;
}

}  // namespace hawor
