// hawor/eval/hand_metrics.hpp — hand pose metrics of the paper (docs/design.md §8, official choices).
//
// Inputs are joint sequences (eval/joint_sequence.hpp): T×3J row-major, metres, J = 21 keypoints.
// Lengths are returned in millimetres, RTE in percent, Accel in m/s², AUC in [0, 1].
// `valid` (optional, empty = every frame valid; nonzero = valid) restricts the frames:
//   PA-MPJPE, AUC  the valid frames.
//   W-MPJPE, WA    chunks of 100 frames in the ORIGINAL frame indexing; inside a chunk only its
//                  valid frames are used (W fits on the chunk's first two valid frames); a chunk
//                  without valid frames is skipped. The mean is over all joint errors of all
//                  chunks (errors concatenated, not a mean of chunk means); the last, partial
//                  chunk is included.
//   RTE            the valid frames form the root track (path length between consecutive valid
//                  frames).
//   Accel          the second difference centred on frame t counts only if frames t−1, t, t+1
//                  are all valid.
// A metric with no sample (or RTE with a zero ground-truth path length) is NaN, so one undefined
// metric does not hide the others. Reference: tests/ref/metrics_np.py.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/eval/joint_sequence.hpp"
#include "hawor/geometry/alignment.hpp"

namespace hawor {

/// Chunk length of W-MPJPE / WA-MPJPE (frames, official).
constexpr Eigen::Index kWorldMetricChunk = 100;
/// Metres → millimetres for the reported lengths.
constexpr double kMetresToMm = 1000.0;

/// All hand metrics of one sequence (see evaluateHands). `n` = number of valid frames used.
template <typename Scalar>
struct HandMetrics {
  Scalar pa_mpjpe = Scalar(0);  // mm
  Scalar auc = Scalar(0);       // [0, 1], PCK 0–50 mm
  Scalar w_mpjpe = Scalar(0);   // mm
  Scalar wa_mpjpe = Scalar(0);  // mm
  Scalar rte = Scalar(0);       // %
  Scalar accel = Scalar(0);     // m/s²
  Eigen::Index n = 0;
};

namespace detail {

template <typename Scalar>
Scalar quietNaN() {
  return std::numeric_limits<Scalar>::quiet_NaN();
}

/// Shapes equal, T×3J, mask sized (or empty), valid frames finite. Returns the full mask.
template <typename Scalar>
ValidMask checkJointPair(const JointSequence<Scalar>& gt, const JointSequence<Scalar>& est,
                         const ValidMask& valid, const char* what) {
  if (gt.rows() != est.rows() || gt.cols() != est.cols())
    throw Error(std::string(what) + ": ground truth is " + std::to_string(gt.rows()) + "x" +
                std::to_string(gt.cols()) + ", estimate " + std::to_string(est.rows()) + "x" +
                std::to_string(est.cols()));
  jointCount(gt);
  if (gt.cols() == 0) throw Error(std::string(what) + ": no joints");
  ValidMask mask = valid.empty() ? ValidMask(static_cast<size_t>(gt.rows()), 1) : valid;
  checkMask(mask, gt.rows(), what);
  for (Eigen::Index t = 0; t < gt.rows(); ++t) {
    if (!mask[static_cast<size_t>(t)]) continue;
    if (!gt.row(t).allFinite() || !est.row(t).allFinite())
      throw Error(std::string(what) + ": non-finite joint at valid frame " + std::to_string(t));
  }
  return mask;
}

/// Sum over points of ‖a_i − b_i‖.
template <typename Scalar>
Scalar sumPointErrors(const Points3<Scalar>& a, const Points3<Scalar>& b) {
  return (a - b).rowwise().norm().sum();
}

/// Rows of the frames `idx` of a joint sequence as one point set.
template <typename Scalar>
Points3<Scalar> gatherPoints(const JointSequence<Scalar>& seq, const std::vector<Eigen::Index>& idx,
                             size_t count) {
  const Eigen::Index J = seq.cols() / 3;
  Points3<Scalar> p(static_cast<Eigen::Index>(count) * J, 3);
  for (size_t k = 0; k < count; ++k)
    p.middleRows(static_cast<Eigen::Index>(k) * J, J) = framePoints(seq, idx[k], idx[k] + 1);
  return p;
}

/// W-MPJPE (first_two) or WA-MPJPE, in mm.
template <typename Scalar>
Scalar chunkedMpjpe(const JointSequence<Scalar>& gt, const JointSequence<Scalar>& est,
                    const ValidMask& valid, bool first_two, const char* what) {
  const ValidMask mask = checkJointPair(gt, est, valid, what);
  const Eigen::Index T = gt.rows();
  Scalar sum(0);
  Eigen::Index count = 0;
  std::vector<Eigen::Index> idx;
  for (Eigen::Index start = 0; start < T; start += kWorldMetricChunk) {
    idx.clear();
    const Eigen::Index end = std::min(T, start + kWorldMetricChunk);
    for (Eigen::Index t = start; t < end; ++t)
      if (mask[static_cast<size_t>(t)]) idx.push_back(t);
    if (idx.empty()) continue;
    const size_t n_fit = first_two ? std::min<size_t>(2, idx.size()) : idx.size();
    const SimilarityTransform<Scalar> sim =
        umeyama(gatherPoints(est, idx, n_fit), gatherPoints(gt, idx, n_fit), true);
    const Points3<Scalar> g = gatherPoints(gt, idx, idx.size());
    sum += sumPointErrors(sim.apply(gatherPoints(est, idx, idx.size())), g);
    count += g.rows();
  }
  if (count == 0) return quietNaN<Scalar>();
  return sum / Scalar(count) * Scalar(kMetresToMm);
}

}  // namespace detail

/// Per-joint errors (mm) after a per-frame similarity Procrustes of the estimate onto the ground
/// truth (umeyama with scale on the J joints of each valid frame): n_valid × J.
template <typename Scalar>
Sequence<Scalar> paJointErrors(const JointSequence<Scalar>& gt, const JointSequence<Scalar>& est,
                               const ValidMask& valid = {}) {
  const ValidMask mask = detail::checkJointPair(gt, est, valid, "paJointErrors");
  const Eigen::Index J = jointCount(gt);
  Sequence<Scalar> err(countValid(mask), J);
  Eigen::Index k = 0;
  for (Eigen::Index t = 0; t < gt.rows(); ++t) {
    if (!mask[static_cast<size_t>(t)]) continue;
    const Points3<Scalar> g = frameJoints(gt, t);
    const Points3<Scalar> e = frameJoints(est, t);
    const SimilarityTransform<Scalar> sim = umeyama(e, g, true);
    err.row(k++) = (sim.apply(e) - g).rowwise().norm().transpose() * Scalar(kMetresToMm);
  }
  return err;
}

/// PA-MPJPE (mm): mean of paJointErrors over joints and valid frames.
template <typename Scalar>
Scalar paMpjpe(const JointSequence<Scalar>& gt, const JointSequence<Scalar>& est,
               const ValidMask& valid = {}) {
  const Sequence<Scalar> e = paJointErrors(gt, est, valid);
  return e.size() ? e.mean() : detail::quietNaN<Scalar>();
}

/// AUC of a PCK curve from per-joint errors (n × J, mm): thresholds linspace(lo, hi, steps),
/// PCK(τ) = mean over joints of the fraction of frames with error ≤ τ (DexYCB/FreiHAND
/// convention), area by the trapezoid rule divided by (hi − lo) so that a perfect curve gives 1.
template <typename Scalar>
Scalar aucFromErrors(const Sequence<Scalar>& err, Scalar lo = Scalar(0), Scalar hi = Scalar(50),
                     int steps = 100) {
  if (steps < 2 || !(hi > lo)) throw Error("aucFromErrors: need steps >= 2 and hi > lo");
  if (err.size() == 0) return detail::quietNaN<Scalar>();
  const Scalar h = (hi - lo) / Scalar(steps - 1);
  Scalar area(0), prev(0);
  for (int i = 0; i < steps; ++i) {
    const Scalar tau = i == steps - 1 ? hi : lo + Scalar(i) * h;
    Scalar pck(0);
    for (Eigen::Index j = 0; j < err.cols(); ++j)
      pck += Scalar((err.col(j).array() <= tau).count()) / Scalar(err.rows());
    pck /= Scalar(err.cols());
    if (i > 0) area += Scalar(0.5) * h * (prev + pck);
    prev = pck;
  }
  return area / (hi - lo);
}

/// AUC of the PA-aligned joint errors over 0–50 mm in 100 steps (docs/design.md §8).
template <typename Scalar>
Scalar aucPck(const JointSequence<Scalar>& gt, const JointSequence<Scalar>& est,
              const ValidMask& valid = {}) {
  return aucFromErrors(paJointErrors(gt, est, valid));
}

/// W-MPJPE (mm): per 100-frame chunk, similarity (with scale) fitted on the first 2 (valid)
/// frames' joints, error over the whole chunk.
template <typename Scalar>
Scalar wMpjpe(const JointSequence<Scalar>& gt, const JointSequence<Scalar>& est,
              const ValidMask& valid = {}) {
  return detail::chunkedMpjpe(gt, est, valid, true, "wMpjpe");
}

/// WA-MPJPE (mm): per 100-frame chunk, similarity fitted on all the chunk's (valid) frames.
template <typename Scalar>
Scalar waMpjpe(const JointSequence<Scalar>& gt, const JointSequence<Scalar>& est,
               const ValidMask& valid = {}) {
  return detail::chunkedMpjpe(gt, est, valid, false, "waMpjpe");
}

/// RTE (%): the root (joint 0) track of the estimate is rigidly aligned (SE3, no scale, one
/// transform for the whole track) to the ground truth; per-frame error ‖R·p_t + t − g_t‖ divided
/// by the ground-truth path length Σ‖g_{k+1} − g_k‖, ×100, mean over frames. NaN when the path
/// length is zero (a static or single-frame track: the ratio is undefined).
template <typename Scalar>
Scalar rte(const JointSequence<Scalar>& gt, const JointSequence<Scalar>& est,
           const ValidMask& valid = {}) {
  const ValidMask mask = detail::checkJointPair(gt, est, valid, "rte");
  const Eigen::Index n = countValid(mask);
  Points3<Scalar> g(n, 3), p(n, 3);
  Eigen::Index k = 0;
  for (Eigen::Index t = 0; t < gt.rows(); ++t) {
    if (!mask[static_cast<size_t>(t)]) continue;
    g.row(k) = gt.row(t).template head<3>();
    p.row(k++) = est.row(t).template head<3>();
  }
  Scalar path(0);
  for (Eigen::Index i = 0; i + 1 < n; ++i) path += (g.row(i + 1) - g.row(i)).norm();
  if (!(path > Scalar(0))) return detail::quietNaN<Scalar>();
  const SimilarityTransform<Scalar> se3 = umeyama(p, g, false);
  const Scalar mean_err = detail::sumPointErrors(se3.apply(p), g) / Scalar(n);
  return mean_err / path * Scalar(100);
}

/// Accel error (m/s²): ‖(p_{t−1} − 2p_t + p_{t+1}) − (g_{t−1} − 2g_t + g_{t+1})‖ per joint, mean
/// over joints and over t = 1..T−2 (first and last frame dropped), × fps². NaN with no sample.
template <typename Scalar>
Scalar accelError(const JointSequence<Scalar>& gt, const JointSequence<Scalar>& est,
                  const ValidMask& valid = {}, Scalar fps = Scalar(30)) {
  const ValidMask mask = detail::checkJointPair(gt, est, valid, "accelError");
  if (!(fps > Scalar(0)) || !std::isfinite(fps)) throw Error("accelError: fps must be > 0");
  const Eigen::Index T = gt.rows();
  const Eigen::Index J = jointCount(gt);
  Scalar sum(0);
  Eigen::Index count = 0;
  for (Eigen::Index t = 1; t + 1 < T; ++t) {
    const size_t s = static_cast<size_t>(t);
    if (!mask[s - 1] || !mask[s] || !mask[s + 1]) continue;
    Scalar frame(0);
    for (Eigen::Index j = 0; j < J; ++j) {
      const auto d2 = [&](const JointSequence<Scalar>& q) {
        return Vec3<Scalar>((q.row(t - 1).segment(3 * j, 3) -
                             Scalar(2) * q.row(t).segment(3 * j, 3) +
                             q.row(t + 1).segment(3 * j, 3))
                                .transpose());
      };
      frame += (d2(est) - d2(gt)).norm();
    }
    sum += frame / Scalar(J);
    ++count;
  }
  if (count == 0) return detail::quietNaN<Scalar>();
  return sum / Scalar(count) * fps * fps;
}

/// Every hand metric of docs/design.md §8 for one hand sequence.
///   gt_world, est_world  world joints; the estimate already aligned per camera part
///                        (alignJointsByParts, eval/camera_metrics.hpp) when it comes from an
///                        estimated camera. W-MPJPE, WA-MPJPE, RTE and Accel use these.
///   gt_cam, est_cam      camera-space joints; PA-MPJPE and AUC use these (any frame works: the
///                        per-frame similarity removes it).
///   valid                empty = all frames valid (rules in the header comment).
/// Throws hawor::Error on mismatched shapes, non-finite valid frames or no valid frame.
template <typename Scalar>
HandMetrics<Scalar> evaluateHands(const JointSequence<Scalar>& gt_world,
                                  const JointSequence<Scalar>& est_world,
                                  const JointSequence<Scalar>& gt_cam,
                                  const JointSequence<Scalar>& est_cam, const ValidMask& valid = {},
                                  Scalar fps = Scalar(30)) {
  const ValidMask mask = detail::checkJointPair(gt_world, est_world, valid, "evaluateHands");
  detail::checkJointPair(gt_cam, est_cam, mask, "evaluateHands (camera joints)");
  if (gt_cam.rows() != gt_world.rows())
    throw Error("evaluateHands: camera and world joints differ in frame count");
  HandMetrics<Scalar> m;
  m.n = countValid(mask);
  if (m.n == 0) throw Error("evaluateHands: no valid frame");
  const Sequence<Scalar> pa = paJointErrors(gt_cam, est_cam, mask);
  m.pa_mpjpe = pa.mean();
  m.auc = aucFromErrors(pa);
  m.w_mpjpe = wMpjpe(gt_world, est_world, mask);
  m.wa_mpjpe = waMpjpe(gt_world, est_world, mask);
  m.rte = rte(gt_world, est_world, mask);
  m.accel = accelError(gt_world, est_world, mask, fps);
  return m;
}

}  // namespace hawor
