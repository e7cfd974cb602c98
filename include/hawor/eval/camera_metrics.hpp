// hawor/eval/camera_metrics.hpp — camera trajectory metrics and the camera alignment used before
// the world hand metrics (docs/design.md §8).
//
// Camera positions are T×3 (Points3, metres): the camera centres t_c2w of the camera-to-world
// poses (docs/design.md §2). ATE / ATE-S are returned in millimetres, rotation errors in degrees.
// Reference: tests/ref/metrics_np.py.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/eval/hand_metrics.hpp"
#include "hawor/eval/joint_sequence.hpp"
#include "hawor/geometry/alignment.hpp"
#include "hawor/geometry/rotation.hpp"

namespace hawor {

/// Part length (frames) of the rigid camera alignment before world metrics (official).
constexpr Eigen::Index kCameraAlignPart = 1000;

/// Camera metrics of one trajectory. `scale` is the Sim(3) scale mapping the estimate onto the
/// ground truth (1 for a perfect metric scale); `n` the number of frames.
template <typename Scalar>
struct CameraMetrics {
  Scalar ate = Scalar(0);    // mm, after Sim(3) alignment
  Scalar ate_s = Scalar(0);  // mm, after SE(3) alignment (tests the metric scale)
  Scalar scale = Scalar(1);
  Eigen::Index n = 0;
};

/// Camera centres of camera-to-world poses as a T×3 point set.
template <typename Scalar>
Points3<Scalar> cameraPositions(const std::vector<Vec3<Scalar>>& t_c2w) {
  Points3<Scalar> p(static_cast<Eigen::Index>(t_c2w.size()), 3);
  for (size_t i = 0; i < t_c2w.size(); ++i)
    p.row(static_cast<Eigen::Index>(i)) = t_c2w[i].transpose();
  return p;
}

namespace detail {
template <typename Scalar>
void checkPositions(const Points3<Scalar>& gt, const Points3<Scalar>& est, const char* what) {
  if (gt.rows() != est.rows())
    throw Error(std::string(what) + ": " + std::to_string(gt.rows()) + " ground-truth and " +
                std::to_string(est.rows()) + " estimated camera positions");
  if (gt.rows() < 3)
    throw Error(std::string(what) + ": need at least 3 camera positions to align, got " +
                std::to_string(gt.rows()));
  if (!gt.allFinite() || !est.allFinite())
    throw Error(std::string(what) + ": non-finite camera position");
}

template <typename Scalar>
Scalar alignedMeanError(const Points3<Scalar>& gt, const Points3<Scalar>& est, bool with_scale,
                        Scalar* scale_out) {
  const SimilarityTransform<Scalar> sim = umeyama(est, gt, with_scale);
  if (scale_out) *scale_out = sim.s;
  return sumPointErrors(sim.apply(est), gt) / Scalar(gt.rows()) * Scalar(kMetresToMm);
}
}  // namespace detail

/// ATE (mm): mean ‖s·R·p_t + t − g_t‖ after Umeyama Sim(3) alignment (with scale) of the estimated
/// camera positions onto the ground truth; the fitted scale s goes to `scale_out`.
template <typename Scalar>
Scalar ateSim3(const Points3<Scalar>& gt, const Points3<Scalar>& est, Scalar* scale_out = nullptr) {
  detail::checkPositions(gt, est, "ateSim3");
  return detail::alignedMeanError(gt, est, true, scale_out);
}

/// ATE-S (mm): the same after SE(3) alignment (no scale), so a wrong metric scale shows.
template <typename Scalar>
Scalar ateSE3(const Points3<Scalar>& gt, const Points3<Scalar>& est) {
  detail::checkPositions(gt, est, "ateSE3");
  return detail::alignedMeanError(gt, est, false, static_cast<Scalar*>(nullptr));
}

/// ATE, ATE-S and the Sim(3) scale of one trajectory.
template <typename Scalar>
CameraMetrics<Scalar> evaluateCameras(const Points3<Scalar>& gt, const Points3<Scalar>& est) {
  CameraMetrics<Scalar> m;
  m.ate = ateSim3(gt, est, &m.scale);
  m.ate_s = ateSE3(gt, est);
  m.n = gt.rows();
  return m;
}

/// Camera rotation error after the best global rotation: the estimate's world is rotated by
/// A = argmin_A Σ‖A·E_t − G_t‖²_F = proj_SO(3)(Σ G_t·E_tᵀ) (chordal L2 mean; Hartley et al. 2013,
/// "Rotation averaging" §5.3), and e_t = ‖log(G_tᵀ·A·E_t)‖ is frame t's angle. Needs no positions,
/// so it is defined for rotation-only trajectories (near-pure rotation) where ATE is not.
template <typename Scalar>
struct RotationErrors {
  Scalar mean_deg = Scalar(0);
  Scalar max_deg = Scalar(0);
  Mat3<Scalar> align = Mat3<Scalar>::Identity();  ///< A: estimate world → ground-truth world
};

/// Rotation errors of camera-to-world rotations `est` against `gt` (same length, ≥ 1 frame).
template <typename Scalar>
RotationErrors<Scalar> rotationErrors(const std::vector<Mat3<Scalar>>& gt, const std::vector<Mat3<Scalar>>& est) {
  if (gt.size() != est.size())
    throw Error("rotationErrors: " + std::to_string(gt.size()) + " ground-truth and " + std::to_string(est.size()) +
                " estimated rotations");
  if (gt.empty()) throw Error("rotationErrors: no rotations");
  Mat3<Scalar> M = Mat3<Scalar>::Zero();
  for (size_t t = 0; t < gt.size(); ++t) {
    if (!gt[t].allFinite() || !est[t].allFinite())
      throw Error("rotationErrors: non-finite rotation at frame " + std::to_string(t));
    M += gt[t] * est[t].transpose();
  }
  RotationErrors<Scalar> r;
  r.align = projectToSO3(M);
  const Scalar toDeg = Scalar(180) / Scalar(EIGEN_PI);
  Scalar sum(0);
  for (size_t t = 0; t < gt.size(); ++t) {
    const Scalar e = matrixToAxisAngle(Mat3<Scalar>(gt[t].transpose() * r.align * est[t])).norm() * toDeg;
    sum += e;
    r.max_deg = std::max(r.max_deg, e);
  }
  r.mean_deg = sum / Scalar(gt.size());
  return r;
}

/// Rigid (SE3, s = 1) alignments of the estimated camera positions onto the ground truth, one per
/// part of `part_length` frames (parts [0, L), [L, 2L), ...). A trailing part shorter than 3 frames
/// (too few to fix a rotation) uses the transform of the part before it.
template <typename Scalar>
struct PartAlignment {
  std::vector<SimilarityTransform<Scalar>> parts;
  Eigen::Index part_length = kCameraAlignPart;
  Eigen::Index frames = 0;

  /// Transform to apply to frame t's estimated world points.
  const SimilarityTransform<Scalar>& forFrame(Eigen::Index t) const {
    if (t < 0 || t >= frames)
      throw Error("PartAlignment: frame " + std::to_string(t) + " out of range");
    const size_t k = static_cast<size_t>(t / part_length);
    return parts[std::min(k, parts.size() - 1)];
  }
};

/// Fits the per-part rigid camera alignment used before the world metrics (docs/design.md §8).
template <typename Scalar>
PartAlignment<Scalar> alignCameraParts(const Points3<Scalar>& gt, const Points3<Scalar>& est,
                                       Eigen::Index part_length = kCameraAlignPart) {
  detail::checkPositions(gt, est, "alignCameraParts");
  if (part_length < 3) throw Error("alignCameraParts: part length must be at least 3 frames");
  PartAlignment<Scalar> a;
  a.part_length = part_length;
  a.frames = gt.rows();
  for (Eigen::Index start = 0; start < gt.rows(); start += part_length) {
    const Eigen::Index n = std::min(part_length, gt.rows() - start);
    if (n < 3) break;  // merged into the previous part (forFrame clamps)
    const Points3<Scalar> e = est.middleRows(start, n);
    const Points3<Scalar> g = gt.middleRows(start, n);
    a.parts.push_back(umeyama(e, g, false));
  }
  return a;
}

/// Applies a part alignment to the estimated world joints (T×3J), frame by frame.
template <typename Scalar>
JointSequence<Scalar> alignJointsByParts(const PartAlignment<Scalar>& a,
                                         const JointSequence<Scalar>& est) {
  if (est.rows() != a.frames)
    throw Error("alignJointsByParts: " + std::to_string(est.rows()) + " frames, alignment has " +
                std::to_string(a.frames));
  const Eigen::Index J = jointCount(est);
  JointSequence<Scalar> out(est.rows(), est.cols());
  for (Eigen::Index t = 0; t < est.rows(); ++t) {
    const Points3<Scalar> p = a.forFrame(t).apply(frameJoints(est, t));
    out.row(t) = Eigen::Map<const Eigen::Matrix<Scalar, 1, Eigen::Dynamic>>(p.data(), 3 * J);
  }
  return out;
}

/// Applies a part alignment to T estimated positions (e.g. the camera centres themselves).
template <typename Scalar>
Points3<Scalar> alignPositionsByParts(const PartAlignment<Scalar>& a, const Points3<Scalar>& est) {
  if (est.rows() != a.frames)
    throw Error("alignPositionsByParts: " + std::to_string(est.rows()) +
                " positions, alignment has " + std::to_string(a.frames));
  Points3<Scalar> out(est.rows(), 3);
  for (Eigen::Index t = 0; t < est.rows(); ++t) {
    const Vec3<Scalar> p = est.row(t).transpose();
    out.row(t) = a.forFrame(t).apply(p).transpose();
  }
  return out;
}

}  // namespace hawor
