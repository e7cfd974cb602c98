// hawor/slam/bundle_adjustment.hpp — sparse bundle adjustment: N camera poses and M points seen
// through one fixed pinhole camera, Levenberg–Marquardt with the Schur complement on the points
// (Triggs et al. 2000, "Bundle adjustment — a modern synthesis", §6; Lourakis & Argyros, SBA).
//
// Parameters
//   poses:  T_w_c, CAMERA-TO-WORLD (docs/design.md §2), updated by the right perturbation
//           T_w_c ← T_w_c·exp(δ), δ = (ρ, φ) ∈ R⁶ in the camera (body) frame, SE3's tangent order.
//   points: Euclidean world points X ∈ R³, updated X ← X + δX. (No inverse depth: points very far
//           from every camera are weakly constrained along the ray; LM damping keeps them bounded.)
// Residual of observation i (pose c, point p, pixel uv, weight w_i ≥ 0):
//   X_c = R_cwX + t_cw (T_c_w = T_w_c⁻¹),  r_i = π(X_c) − uv  (pixels, docs/design.md §2 pixel centres),
//   ∂r/∂δ = Jπ·[−I, X_c^],  ∂r/∂X = Jπ·R_cw,  Jπ = [fx/z, 0, −fx·x/z²; 0, fy/z, −fy·y/z²]
//   (exp(−δ)·X_c ≈ X_c − ρ + X_c^·φ).
// Cost
//   F = Σ_i w_i ρ(‖r_i‖²/σ²) + Σ_priors w_k (‖c_b − c_a‖ − d_k)²
//   with ρ the robust loss of geometry/robust_loss.hpp (scale k = robustScale, in units of σ) and
//   c = translation of T_w_c (the camera centre). Observations with weight 0 are ignored entirely
//   (the hand-masked residuals of docs/design.md §5); observations at depth ≤ minDepth at the start are
//   excluded (counted in the report); a step that would move a used observation behind its camera
//   is rejected like a cost increase.
// Robust loss by IRLS: weights w_i ρ'(s_i)/σ² at the linearisation point give g = Σ w Jᵀr and
//   H = Σ w JᵀJ; F + 2gᵀδ + δᵀHδ is the model of F the step minimises. Optionally (option
//   minRadialCurvature < 1) the Hessian also follows the loss' curvature along each residual
//   (Triggs et al. 2000, §4.3): H = Σ w J̃ᵀJ̃, J̃ = (I − α r̂r̂ᵀ)J, α = 1 − √D, D = 1 + 2sρ''/ρ'
//   clamped to [minRadialCurvature, 1] (plain IRLS is D = 1).
// LM: (H + λD)δ = −g with D = diag(H) clamped to [1e-6, 1e32] (Marquardt scaling), λ updated by
//   Nielsen's rule (×max(1/3, 1 − (2ϱ − 1)³) on success, ×ν, ν ← 2ν on failure), ϱ = actual/
//   predicted decrease. Per iteration: the reduced camera system
//   S = H_cc − Σ_p H_cp H_pp⁻¹ H_pc,  S·δ_c = −g_c + Σ_p H_cp H_pp⁻¹ g_p,
//   δ_p = H_pp⁻¹(−g_p − H_pc δ_c), point blocks 3×3, camera blocks 6×6.
//   S is solved densely (LLT) for up to `denseMaxPoses` free poses (sliding windows) and by a
//   sparse Cholesky (Eigen's SimplicialLLT, AMD ordering) on the block pattern of co-observing
//   cameras beyond that (global BA over hundreds of keyframes). A long sequence whose old parts
//   are seen again (a head that keeps looking back at the same places) couples most cameras with
//   most others, and the Cholesky factor fills in to a dense one (3,000 frames, 461 keyframes,
//   59 blocks a camera: ~100 MB and 20 s): from `iterativeMinPoses` free poses with at least
//   `iterativeMinBlocksPerPose` blocks of S a pose, S is solved by conjugate gradients
//   preconditioned by the inverses of its 6×6 diagonal blocks (block Jacobi; the "iterative
//   Schur" of Agarwal et al. 2010), using only the blocks S already holds, to a relative residual
//   of cgTolerance within cgMaxIterations (an inexact step that LM accepts or damps like any).
// Gauge: a monocular problem has 7 gauge freedoms (pose and scale). Fix at least one pose
//   (poseFixed); fix the scale with a second fixed pose or a BAScalePrior between two cameras.
//   Without them the free directions are held only by the damping (no error, slow convergence).
// Points (and poses) can be fixed: with all points fixed the problem is a motion-only BA.
// Not thread-safe for one problem; distinct problems may be solved concurrently.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/robust_loss.hpp"
#include "hawor/geometry/se3.hpp"

namespace hawor {

/// One pixel observation of a point by a pose. weight 0 = ignore (e.g. inside a hand mask).
template <typename Scalar>
struct BAObservation {
  int pose = 0;
  int point = 0;
  Vec2<Scalar> uv = Vec2<Scalar>::Zero();  ///< pixel (docs/design.md §2: pixel centres at integers)
  Scalar weight = Scalar(1);               ///< w_i ≥ 0, multiplies the robust cost
};

/// Scale prior w·(‖c_b − c_a‖ − d)² on the distance between two camera centres (fixes the gauge
/// scale of a monocular problem without fixing a second pose).
template <typename Scalar>
struct BAScalePrior {
  int poseA = 0, poseB = 1;
  Scalar distance = Scalar(1);
  Scalar weight = Scalar(1e6);
};

/// Position prior w·‖c − p‖² on a camera centre c (T_w_c translation): a motion model's
/// prediction p for that camera (e.g. the head model of head_motion.hpp).
template <typename Scalar>
struct BAPositionPrior {
  int pose = 0;
  Vec3<Scalar> position = Vec3<Scalar>::Zero();
  Scalar weight = Scalar(1);
};

/// The problem, optimised in place by bundleAdjust. poseFixed / pointFixed: empty (nothing fixed)
/// or one flag per pose / point.
template <typename Scalar>
struct BAProblem {
  PinholeCamera<Scalar> camera;           ///< fx, fy, cx, cy (width/height unused)
  std::vector<SE3<Scalar>> poses;         ///< T_w_c, camera-to-world
  std::vector<Vec3<Scalar>> points;       ///< world points
  std::vector<BAObservation<Scalar>> observations;
  std::vector<char> poseFixed;
  std::vector<char> pointFixed;
  std::vector<BAScalePrior<Scalar>> scalePriors;
  std::vector<BAPositionPrior<Scalar>> positionPriors;
};

/// The scale gauge of a monocular problem whose pose `anchor` is fixed: a prior holding the
/// current distance d from the anchor's centre to the centre farthest from it, weight w / d²
/// (so w is in units of the relative distance). Nothing is added when every centre coincides
/// with the anchor's. Returns the farthest pose, or -1.
template <typename Scalar>
int addFarthestScalePrior(BAProblem<Scalar>& P, int anchor, Scalar w = Scalar(1e4)) {
  int farV = -1;
  Scalar farD = Scalar(0);
  for (int v = 0; v < static_cast<int>(P.poses.size()); ++v) {
    const Scalar d = (P.poses[static_cast<std::size_t>(v)].translation() - P.poses[static_cast<std::size_t>(anchor)].translation()).norm();
    if (d > farD) farD = d, farV = v;
  }
  if (farV < 0) return -1;
  BAScalePrior<Scalar> sp;
  sp.poseA = anchor;
  sp.poseB = farV;
  sp.distance = farD;
  sp.weight = w / (farD * farD);
  P.scalePriors.push_back(sp);
  return farV;
}

enum class BALinearSolver { Auto, Dense, Sparse, Iterative };

enum class BATermination {
  FunctionTolerance,   ///< relative cost decrease of an accepted step ≤ functionTolerance
  ParameterTolerance,  ///< ‖δ‖ ≤ parameterTolerance·(‖x‖ + parameterTolerance)
  GradientTolerance,   ///< max |∇F| ≤ gradientTolerance
  MaxIterations,       ///< the iteration budget ran out (not converged)
  NoProgress,          ///< λ exceeded maxLambda without a cost decrease (not converged)
  NoVariables,         ///< nothing to optimise (all fixed, or no usable observation)
};

template <typename Scalar>
struct BAOptions {
  int maxIterations = 20;               ///< LM iterations (successful or not)
  RobustLoss loss = RobustLoss::Huber;
  Scalar sigmaPx = Scalar(1);           ///< pixel noise scale σ
  Scalar robustScale = Scalar(2);       ///< loss scale k in units of σ
  Scalar minDepth = Scalar(1e-6);       ///< depth (world units) below which a projection is invalid
  Scalar initialLambda = Scalar(1e-4);
  Scalar maxLambda = Scalar(1e16);
  Scalar functionTolerance = Scalar(1e-6);
  Scalar parameterTolerance = Scalar(1e-8);
  Scalar gradientTolerance = Scalar(1e-10);
  BALinearSolver solver = BALinearSolver::Auto;
  int denseMaxPoses = 60;               ///< Auto: dense reduced system up to this many free poses
  int iterativeMinPoses = 300;          ///< Auto: conjugate gradients from this many free poses…
  int iterativeMinBlocksPerPose = 30;   ///< …with at least this many blocks of S a pose
  Scalar cgTolerance = Scalar(1e-8);    ///< ‖S·δ − b‖ ≤ cgTolerance·‖b‖
  int cgMaxIterations = 500;
  /// Floor D_min of the radial curvature factor of the robust correction (file comment), in (0, 1].
  /// 1 (default) is plain IRLS, the fastest from a poor start or with many outliers (measured:
  /// 6 vs 40 iterations with 20 % outliers and Cauchy); ~0.1 converges faster in the last digits
  /// when the residuals sit in the loss' tails (tight refinement of an inlier-dominated problem).
  Scalar minRadialCurvature = Scalar(1);
};

template <typename Scalar>
struct BAReport {
  Scalar initialCost = Scalar(0), finalCost = Scalar(0);  ///< F before / after
  Scalar initialRmsPx = Scalar(0), finalRmsPx = Scalar(0);  ///< plain RMS of the used residuals
  int iterations = 0;        ///< LM iterations (linear solves attempted)
  int successfulSteps = 0;   ///< accepted steps
  bool converged = false;    ///< a tolerance was met (function, parameter or gradient)
  BATermination termination = BATermination::MaxIterations;
  int usedObservations = 0;    ///< weight > 0 and in front of the camera at the start
  int behindObservations = 0;  ///< weight > 0 but at depth ≤ minDepth at the start (excluded)
  int freePoses = 0, freePoints = 0;
  bool sparseSolver = false;   ///< the reduced camera system was solved sparsely (Cholesky)
  bool iterativeSolver = false;  ///< the reduced camera system was solved by conjugate gradients
  Scalar lambda = Scalar(0);   ///< final LM damping
};

namespace ba_detail {

/// r = π(R_cw·X + t_cw) − uv and the Jacobians of the file comment; false when z ≤ minDepth.
/// Written out (a = fx/z, b = fy/z, x̂ = x/z, ŷ = y/z):
///   ∂r/∂δ = [−a, 0, a·x̂, fx·x̂ŷ, −fx(1 + x̂²), fx·ŷ;  0, −b, b·ŷ, fy(1 + ŷ²), −fy·x̂ŷ, −fy·x̂]
///   ∂r/∂X = [a·(R₀ − x̂R₂); b·(R₁ − ŷR₂)]  (R_k the rows of R_cw).
/// Templated on the argument expressions so that unaligned storage is read without copies.
template <typename Scalar, typename MR, typename MT, typename MX, typename MU>
inline bool reprojection(const PinholeCamera<Scalar>& cam, const Eigen::MatrixBase<MR>& Rcw,
                         const Eigen::MatrixBase<MT>& tcw, const Eigen::MatrixBase<MX>& X,
                         const Eigen::MatrixBase<MU>& uv, Scalar minDepth,
                         Eigen::Matrix<Scalar, 2, 1>& r, Eigen::Matrix<Scalar, 2, 6>* Jc,
                         Eigen::Matrix<Scalar, 2, 3>* Jp) {
  const Scalar px = Rcw(0, 0) * X(0) + Rcw(0, 1) * X(1) + Rcw(0, 2) * X(2) + tcw(0);
  const Scalar py = Rcw(1, 0) * X(0) + Rcw(1, 1) * X(1) + Rcw(1, 2) * X(2) + tcw(1);
  const Scalar pz = Rcw(2, 0) * X(0) + Rcw(2, 1) * X(1) + Rcw(2, 2) * X(2) + tcw(2);
  if (!(pz > minDepth)) return false;
  const Scalar iz = Scalar(1) / pz;
  const Scalar xn = px * iz, yn = py * iz;
  r(0) = cam.fx * xn + cam.cx - uv(0);
  r(1) = cam.fy * yn + cam.cy - uv(1);
  const Scalar a = cam.fx * iz, b = cam.fy * iz;
  if (Jc) {
    *Jc << -a, Scalar(0), a * xn, cam.fx * xn * yn, -cam.fx * (Scalar(1) + xn * xn), cam.fx * yn,
        Scalar(0), -b, b * yn, cam.fy * (Scalar(1) + yn * yn), -cam.fy * xn * yn, -cam.fy * xn;
  }
  if (Jp) {
    for (int k = 0; k < 3; ++k) {
      (*Jp)(0, k) = a * (Rcw(0, k) - xn * Rcw(2, k));
      (*Jp)(1, k) = b * (Rcw(1, k) - yn * Rcw(2, k));
    }
  }
  return true;
}

/// α = 1 − √D of the robust curvature correction, D = 1 + 2sρ''(s)/ρ'(s) clamped to [Dmin, 1]:
///   None: D = 1;  Huber: D = 1 (s ≤ k²), 0 (s > k²);  Cauchy: D = (1 − s/k²)/(1 + s/k²).
/// The block's Gauss–Newton Hessian w·JᵀJ becomes w·J̃ᵀJ̃ with J̃ = (I − α r̂r̂ᵀ)J, whose radial
/// curvature w·D matches the loss' own second derivative (Triggs et al. 2000, §4.3).
template <typename Scalar>
inline Scalar robustCurvatureAlpha(RobustLoss loss, Scalar s, Scalar k, Scalar Dmin) {
  Scalar D = Scalar(1);
  switch (loss) {
    case RobustLoss::Huber:
      D = s <= k * k ? Scalar(1) : Scalar(0);
      break;
    case RobustLoss::Cauchy: {
      const Scalar q = s / (k * k);
      D = (Scalar(1) - q) / (Scalar(1) + q);
      break;
    }
    case RobustLoss::None:
    default:
      D = Scalar(1);
      break;
  }
  D = std::min(Scalar(1), std::max(D, Dmin));
  return Scalar(1) - std::sqrt(D);
}

/// J ← (I − α r̂r̂ᵀ)·J for a 2-row Jacobian (r̂ = r/‖r‖; no change when r = 0 or α = 0).
template <typename Scalar, int N>
inline void applyRobustCorrection(const Eigen::Matrix<Scalar, 2, 1>& r, Scalar alpha,
                                  Eigen::Matrix<Scalar, 2, N>& J) {
  const Scalar n2 = r.squaredNorm();
  if (alpha == Scalar(0) || !(n2 > Scalar(0))) return;
  const Eigen::Matrix<Scalar, 2, 1> rh = r / std::sqrt(n2);
  J -= (alpha * rh) * (rh.transpose() * J);
}

template <typename Scalar>
inline Scalar clampDiag(Scalar d) {
  return std::min(std::max(d, Scalar(1e-6)), Scalar(1e32));
}

}  // namespace ba_detail

/// Reprojection residual of the file comment for one observation, with the optional Jacobians
/// ∂r/∂δ (2×6, right perturbation of T_w_c) and ∂r/∂X (2×3). Returns false (r unspecified)
/// when the point is at depth ≤ minDepth in the camera.
template <typename Scalar>
bool baReprojectionResidual(const PinholeCamera<Scalar>& cam, const SE3<Scalar>& T_w_c,
                            const Vec3<Scalar>& X, const Vec2<Scalar>& uv,
                            Eigen::Matrix<Scalar, 2, 1>& r,
                            Eigen::Matrix<Scalar, 2, 6>* J_pose = nullptr,
                            Eigen::Matrix<Scalar, 2, 3>* J_point = nullptr,
                            Scalar minDepth = Scalar(0)) {
  const SE3<Scalar> T_c_w = T_w_c.inverse();
  const Eigen::Matrix<Scalar, 3, 3> Rcw = T_c_w.rotationMatrix();
  const Eigen::Matrix<Scalar, 3, 1> tcw = T_c_w.translation();
  return ba_detail::reprojection<Scalar>(cam, Rcw, tcw, X, uv, minDepth, r, J_pose, J_point);
}

/// Scale-prior residual r = ‖c_b − c_a‖ − d (c = T_w_c translation) with the Jacobians wrt the
/// right perturbations of T_a and T_b: ∂r/∂δ_a = [−uᵀR_a, 0], ∂r/∂δ_b = [uᵀR_b, 0],
/// u = (c_b − c_a)/‖c_b − c_a‖ (zero Jacobians when the centres coincide).
template <typename Scalar>
Scalar baScalePriorResidual(const SE3<Scalar>& T_a, const SE3<Scalar>& T_b, Scalar distance,
                            Eigen::Matrix<Scalar, 1, 6>* J_a = nullptr,
                            Eigen::Matrix<Scalar, 1, 6>* J_b = nullptr) {
  const Eigen::Matrix<Scalar, 3, 1> dc = T_b.translation() - T_a.translation();
  const Scalar len = dc.norm();
  if (J_a) J_a->setZero();
  if (J_b) J_b->setZero();
  if (len > Scalar(0)) {
    const Eigen::Matrix<Scalar, 1, 3> u = (dc / len).transpose();
    if (J_a) J_a->template leftCols<3>() = -u * T_a.rotationMatrix();
    if (J_b) J_b->template leftCols<3>() = u * T_b.rotationMatrix();
  }
  return len - distance;
}

namespace ba_detail {

template <typename Scalar>
void validate(const BAProblem<Scalar>& P, const BAOptions<Scalar>& opt) {
  const auto& c = P.camera;
  if (!(c.fx > Scalar(0)) || !(c.fy > Scalar(0)) || !std::isfinite(c.fx) || !std::isfinite(c.fy) ||
      !std::isfinite(c.cx) || !std::isfinite(c.cy)) {
    throw Error("bundleAdjust: camera focal lengths must be finite and > 0, principal point finite");
  }
  const int nC = static_cast<int>(P.poses.size()), nP = static_cast<int>(P.points.size());
  for (int i = 0; i < nC; ++i) {
    const auto& T = P.poses[static_cast<std::size_t>(i)];
    if (!T.translation().allFinite() || !T.rotation().quaternion().coeffs().allFinite()) {
      throw Error("bundleAdjust: pose " + std::to_string(i) + " is not finite");
    }
  }
  for (int j = 0; j < nP; ++j) {
    if (!P.points[static_cast<std::size_t>(j)].allFinite()) {
      throw Error("bundleAdjust: point " + std::to_string(j) + " is not finite");
    }
  }
  for (std::size_t k = 0; k < P.observations.size(); ++k) {
    const auto& o = P.observations[k];
    if (o.pose < 0 || o.pose >= nC || o.point < 0 || o.point >= nP) {
      throw Error("bundleAdjust: observation " + std::to_string(k) + " refers to pose " +
                  std::to_string(o.pose) + " / point " + std::to_string(o.point) +
                  " (have " + std::to_string(nC) + " poses, " + std::to_string(nP) + " points)");
    }
    if (!o.uv.allFinite()) {
      throw Error("bundleAdjust: observation " + std::to_string(k) + " has a non-finite pixel");
    }
    if (!(o.weight >= Scalar(0)) || !std::isfinite(o.weight)) {
      throw Error("bundleAdjust: observation " + std::to_string(k) + " weight must be finite, >= 0");
    }
  }
  if (!P.poseFixed.empty() && static_cast<int>(P.poseFixed.size()) != nC) {
    throw Error("bundleAdjust: poseFixed has " + std::to_string(P.poseFixed.size()) +
                " flags for " + std::to_string(nC) + " poses");
  }
  if (!P.pointFixed.empty() && static_cast<int>(P.pointFixed.size()) != nP) {
    throw Error("bundleAdjust: pointFixed has " + std::to_string(P.pointFixed.size()) +
                " flags for " + std::to_string(nP) + " points");
  }
  for (std::size_t k = 0; k < P.scalePriors.size(); ++k) {
    const auto& s = P.scalePriors[k];
    if (s.poseA < 0 || s.poseA >= nC || s.poseB < 0 || s.poseB >= nC || s.poseA == s.poseB) {
      throw Error("bundleAdjust: scale prior " + std::to_string(k) + " needs two distinct poses");
    }
    if (!(s.distance >= Scalar(0)) || !std::isfinite(s.distance) || !(s.weight >= Scalar(0)) ||
        !std::isfinite(s.weight)) {
      throw Error("bundleAdjust: scale prior " + std::to_string(k) +
                  " needs a finite distance and weight >= 0");
    }
  }
  for (std::size_t k = 0; k < P.positionPriors.size(); ++k) {
    const auto& q = P.positionPriors[k];
    if (q.pose < 0 || q.pose >= nC || !q.position.allFinite() || !(q.weight >= Scalar(0)) || !std::isfinite(q.weight)) {
      throw Error("bundleAdjust: position prior " + std::to_string(k) + " needs a pose, a finite position and weight >= 0");
    }
  }
  if (opt.maxIterations < 0) throw Error("bundleAdjust: maxIterations must be >= 0");
  if (!(opt.sigmaPx > Scalar(0)) || !std::isfinite(opt.sigmaPx) || !(opt.robustScale > Scalar(0)) ||
      !(opt.initialLambda > Scalar(0)) || !std::isfinite(opt.initialLambda)) {
    throw Error("bundleAdjust: sigmaPx, robustScale and initialLambda must be finite and > 0");
  }
  if (!(opt.minRadialCurvature > Scalar(0) && opt.minRadialCurvature <= Scalar(1))) {
    throw Error("bundleAdjust: minRadialCurvature must be in (0, 1]");
  }
  if (!(opt.cgTolerance > Scalar(0)) || opt.cgMaxIterations < 1) {
    throw Error("bundleAdjust: cgTolerance must be > 0 and cgMaxIterations >= 1");
  }
}

}  // namespace ba_detail

/// Per-observation reprojection error ‖r_i‖ in pixels at the problem's current state (NaN where
/// the point is at depth ≤ minDepth). Useful to flag outliers after bundleAdjust.
template <typename Scalar>
std::vector<Scalar> baReprojectionErrors(const BAProblem<Scalar>& P,
                                         Scalar minDepth = Scalar(1e-6)) {
  std::vector<Scalar> out(P.observations.size(), std::numeric_limits<Scalar>::quiet_NaN());
  std::vector<Eigen::Matrix<Scalar, 3, 3, Eigen::DontAlign>> R(P.poses.size());
  std::vector<Eigen::Matrix<Scalar, 3, 1, Eigen::DontAlign>> t(P.poses.size());
  for (std::size_t i = 0; i < P.poses.size(); ++i) {
    const SE3<Scalar> Tcw = P.poses[i].inverse();
    R[i] = Tcw.rotationMatrix();
    t[i] = Tcw.translation();
  }
  for (std::size_t k = 0; k < P.observations.size(); ++k) {
    const auto& o = P.observations[k];
    if (o.pose < 0 || o.pose >= static_cast<int>(P.poses.size()) || o.point < 0 ||
        o.point >= static_cast<int>(P.points.size())) {
      continue;
    }
    Eigen::Matrix<Scalar, 2, 1> r;
    if (ba_detail::reprojection<Scalar>(P.camera, R[static_cast<std::size_t>(o.pose)],
                                        t[static_cast<std::size_t>(o.pose)],
                                        P.points[static_cast<std::size_t>(o.point)], o.uv,
                                        minDepth, r, nullptr, nullptr)) {
      out[k] = r.norm();
    }
  }
  return out;
}

/// Levenberg–Marquardt bundle adjustment of the file comment; optimises `problem` in place.
/// Throws hawor::Error for malformed input (indices out of range, non-finite values, negative
/// weights, flag vectors of the wrong size, bad options).
template <typename Scalar>
BAReport<Scalar> bundleAdjust(BAProblem<Scalar>& problem, const BAOptions<Scalar>& opt = {}) {
  using V2 = Eigen::Matrix<Scalar, 2, 1>;
  using V3 = Eigen::Matrix<Scalar, 3, 1>;
  using V6 = Eigen::Matrix<Scalar, 6, 1>;
  using M3 = Eigen::Matrix<Scalar, 3, 3>;
  using M6 = Eigen::Matrix<Scalar, 6, 6>;
  using M26 = Eigen::Matrix<Scalar, 2, 6>;
  using M23 = Eigen::Matrix<Scalar, 2, 3>;
  using M63 = Eigen::Matrix<Scalar, 6, 3>;
  // Unaligned storage types for std::vector (docs/design.md §2: no alignment assumptions).
  using S3 = Eigen::Matrix<Scalar, 3, 1, Eigen::DontAlign>;
  using S6 = Eigen::Matrix<Scalar, 6, 1, Eigen::DontAlign>;
  using SM3 = Eigen::Matrix<Scalar, 3, 3, Eigen::DontAlign>;
  using SM6 = Eigen::Matrix<Scalar, 6, 6, Eigen::DontAlign>;
  using SM63 = Eigen::Matrix<Scalar, 6, 3, Eigen::DontAlign>;

  ba_detail::validate(problem, opt);
  auto& P = problem;
  const PinholeCamera<Scalar>& cam = P.camera;
  const int nC = static_cast<int>(P.poses.size());
  const int nP = static_cast<int>(P.points.size());
  const Scalar invS2 = Scalar(1) / (opt.sigmaPx * opt.sigmaPx);
  BAReport<Scalar> rep;

  // --- current world-to-camera matrices -------------------------------------------------------
  std::vector<SM3> Rcw(static_cast<std::size_t>(nC));
  std::vector<S3> tcw(static_cast<std::size_t>(nC));
  auto cachePoses = [&](const std::vector<SE3<Scalar>>& poses) {
    for (int c = 0; c < nC; ++c) {
      const SE3<Scalar> Tcw = poses[static_cast<std::size_t>(c)].inverse();
      Rcw[static_cast<std::size_t>(c)] = Tcw.rotationMatrix();
      tcw[static_cast<std::size_t>(c)] = Tcw.translation();
    }
  };
  cachePoses(P.poses);

  // --- used observations and variables --------------------------------------------------------
  std::vector<int> used;
  used.reserve(P.observations.size());
  for (std::size_t k = 0; k < P.observations.size(); ++k) {
    const auto& o = P.observations[k];
    if (!(o.weight > Scalar(0))) continue;
    V2 r;
    if (ba_detail::reprojection<Scalar>(cam, Rcw[static_cast<std::size_t>(o.pose)],
                                        tcw[static_cast<std::size_t>(o.pose)],
                                        P.points[static_cast<std::size_t>(o.point)], o.uv,
                                        opt.minDepth, r, nullptr, nullptr)) {
      used.push_back(static_cast<int>(k));
    } else {
      ++rep.behindObservations;
    }
  }
  rep.usedObservations = static_cast<int>(used.size());
  const int nU = rep.usedObservations;

  std::vector<int> poseVar(static_cast<std::size_t>(nC), -1), pointVar(static_cast<std::size_t>(nP), -1);
  std::vector<int> poseUses(static_cast<std::size_t>(nC), 0), pointUses(static_cast<std::size_t>(nP), 0);
  for (int a = 0; a < nU; ++a) {
    const auto& o = P.observations[static_cast<std::size_t>(used[static_cast<std::size_t>(a)])];
    ++poseUses[static_cast<std::size_t>(o.pose)];
    ++pointUses[static_cast<std::size_t>(o.point)];
  }
  std::vector<const BAScalePrior<Scalar>*> priors;
  for (const auto& s : P.scalePriors) {
    if (s.weight > Scalar(0)) {
      priors.push_back(&s);
      ++poseUses[static_cast<std::size_t>(s.poseA)];
      ++poseUses[static_cast<std::size_t>(s.poseB)];
    }
  }
  int nVC = 0, nVP = 0;
  for (int c = 0; c < nC; ++c) {
    const bool fixed = !P.poseFixed.empty() && P.poseFixed[static_cast<std::size_t>(c)];
    if (!fixed && poseUses[static_cast<std::size_t>(c)] > 0) poseVar[static_cast<std::size_t>(c)] = nVC++;
  }
  for (int j = 0; j < nP; ++j) {
    const bool fixed = !P.pointFixed.empty() && P.pointFixed[static_cast<std::size_t>(j)];
    if (!fixed && pointUses[static_cast<std::size_t>(j)] > 0) pointVar[static_cast<std::size_t>(j)] = nVP++;
  }
  rep.freePoses = nVC;
  rep.freePoints = nVP;

  // --- cost ---------------------------------------------------------------------------------------
  // F of the file comment at (poses, points), with Rcw/tcw cached for `poses`; +∞ when a used
  // observation is at depth ≤ minDepth. Also returns the plain sum of squared pixel residuals.
  // Sums are kept in double whatever Scalar is: in float, rounding of a sum over thousands of
  // terms would hide the last decreases and make LM reject good steps.
  auto evalCost = [&](const std::vector<SE3<Scalar>>& poses, const std::vector<Vec3<Scalar>>& points,
                      double* sumSq) -> double {
    double F = 0.0, ss = 0.0;
    for (int a = 0; a < nU; ++a) {
      const auto& o = P.observations[static_cast<std::size_t>(used[static_cast<std::size_t>(a)])];
      V2 r;
      if (!ba_detail::reprojection<Scalar>(cam, Rcw[static_cast<std::size_t>(o.pose)],
                                           tcw[static_cast<std::size_t>(o.pose)],
                                           points[static_cast<std::size_t>(o.point)], o.uv,
                                           opt.minDepth, r, nullptr, nullptr)) {
        return std::numeric_limits<double>::infinity();
      }
      const Scalar r2 = r.squaredNorm();
      ss += double(r2);
      F += double(o.weight * robustCost(opt.loss, r2 * invS2, opt.robustScale));
    }
    for (const auto* s : priors) {
      const Scalar e = baScalePriorResidual(poses[static_cast<std::size_t>(s->poseA)],
                                            poses[static_cast<std::size_t>(s->poseB)], s->distance);
      F += double(s->weight * e * e);
    }
    for (const auto& q : P.positionPriors) {
      F += double(q.weight * (poses[static_cast<std::size_t>(q.pose)].translation() - q.position).squaredNorm());
    }
    if (sumSq) *sumSq = ss;
    return F;
  };

  double sumSq = 0.0;
  double F = evalCost(P.poses, P.points, &sumSq);
  rep.initialCost = rep.finalCost = Scalar(F);
  rep.initialRmsPx = rep.finalRmsPx = nU > 0 ? Scalar(std::sqrt(sumSq / nU)) : Scalar(0);
  if (nVC == 0 && nVP == 0) {
    rep.termination = BATermination::NoVariables;
    rep.converged = true;
    return rep;
  }
  if (!std::isfinite(F)) {
    throw Error("bundleAdjust: the initial cost is not finite (coordinates too large?)");
  }

  // --- structure of the reduced camera system -----------------------------------------------------
  // Per free point: its used observations (CSR), the ones with a free pose sorted by that pose.
  std::vector<int> ptStart(static_cast<std::size_t>(nVP) + 1, 0);
  for (int a = 0; a < nU; ++a) {
    const auto& o = P.observations[static_cast<std::size_t>(used[static_cast<std::size_t>(a)])];
    const int pv = pointVar[static_cast<std::size_t>(o.point)];
    if (pv >= 0) ++ptStart[static_cast<std::size_t>(pv) + 1];
  }
  for (int j = 0; j < nVP; ++j) ptStart[static_cast<std::size_t>(j) + 1] += ptStart[static_cast<std::size_t>(j)];
  std::vector<int> ptObs(static_cast<std::size_t>(ptStart[static_cast<std::size_t>(nVP)]));
  {
    std::vector<int> fill(ptStart.begin(), ptStart.end() - 1);
    for (int a = 0; a < nU; ++a) {
      const auto& o = P.observations[static_cast<std::size_t>(used[static_cast<std::size_t>(a)])];
      const int pv = pointVar[static_cast<std::size_t>(o.point)];
      if (pv >= 0) ptObs[static_cast<std::size_t>(fill[static_cast<std::size_t>(pv)]++)] = a;
    }
  }
  // obsPoseVar[a]: free-pose index of used observation a (−1 if the pose is fixed).
  std::vector<int> obsPoseVar(static_cast<std::size_t>(nU)), obsPointVar(static_cast<std::size_t>(nU));
  for (int a = 0; a < nU; ++a) {
    const auto& o = P.observations[static_cast<std::size_t>(used[static_cast<std::size_t>(a)])];
    obsPoseVar[static_cast<std::size_t>(a)] = poseVar[static_cast<std::size_t>(o.pose)];
    obsPointVar[static_cast<std::size_t>(a)] = pointVar[static_cast<std::size_t>(o.point)];
  }
  // Within each point, order observations with a free pose first, sorted by pose; count them.
  std::vector<int> ptSchurCount(static_cast<std::size_t>(nVP), 0);
  for (int j = 0; j < nVP; ++j) {
    auto b = ptObs.begin() + ptStart[static_cast<std::size_t>(j)];
    auto e = ptObs.begin() + ptStart[static_cast<std::size_t>(j) + 1];
    std::sort(b, e, [&](int x, int y) {
      const int cx = obsPoseVar[static_cast<std::size_t>(x)], cy = obsPoseVar[static_cast<std::size_t>(y)];
      const int kx = cx < 0 ? std::numeric_limits<int>::max() : cx;
      const int ky = cy < 0 ? std::numeric_limits<int>::max() : cy;
      return kx < ky || (kx == ky && x < y);
    });
    int cnt = 0;
    for (auto it = b; it != e; ++it) cnt += obsPoseVar[static_cast<std::size_t>(*it)] >= 0 ? 1 : 0;
    ptSchurCount[static_cast<std::size_t>(j)] = cnt;
  }
  // Blocks (ci ≤ cj) of S: diagonal blocks, co-observing pairs, prior pairs.
  auto key = [](int ci, int cj) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ci)) << 32) |
           static_cast<std::uint32_t>(cj);
  };
  std::vector<std::uint64_t> keys;
  for (int c = 0; c < nVC; ++c) keys.push_back(key(c, c));
  std::size_t maxList = 0;
  for (int j = 0; j < nVP; ++j) {
    const int s0 = ptStart[static_cast<std::size_t>(j)], m = ptSchurCount[static_cast<std::size_t>(j)];
    maxList = std::max(maxList, static_cast<std::size_t>(m));
    for (int u = 0; u < m; ++u) {
      for (int v = u + 1; v < m; ++v) {
        const int cu = obsPoseVar[static_cast<std::size_t>(ptObs[static_cast<std::size_t>(s0 + u)])];
        const int cv = obsPoseVar[static_cast<std::size_t>(ptObs[static_cast<std::size_t>(s0 + v)])];
        if (cu != cv) keys.push_back(key(cu, cv));  // sorted: cu < cv
      }
    }
  }
  for (const auto* s : priors) {
    const int ca = poseVar[static_cast<std::size_t>(s->poseA)], cb = poseVar[static_cast<std::size_t>(s->poseB)];
    if (ca >= 0 && cb >= 0) keys.push_back(key(std::min(ca, cb), std::max(ca, cb)));
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  auto blockOf = [&](int ci, int cj) {
    return static_cast<int>(std::lower_bound(keys.begin(), keys.end(), key(ci, cj)) - keys.begin());
  };
  // Block index of every off-diagonal pair (u < v, distinct poses) in the loop order used below.
  std::vector<int> pairBlock;
  for (int j = 0; j < nVP; ++j) {
    const int s0 = ptStart[static_cast<std::size_t>(j)], m = ptSchurCount[static_cast<std::size_t>(j)];
    for (int u = 0; u < m; ++u) {
      for (int v = u + 1; v < m; ++v) {
        const int cu = obsPoseVar[static_cast<std::size_t>(ptObs[static_cast<std::size_t>(s0 + u)])];
        const int cv = obsPoseVar[static_cast<std::size_t>(ptObs[static_cast<std::size_t>(s0 + v)])];
        if (cu != cv) pairBlock.push_back(blockOf(cu, cv));
      }
    }
  }
  std::vector<int> diagBlock(static_cast<std::size_t>(nVC));
  for (int c = 0; c < nVC; ++c) diagBlock[static_cast<std::size_t>(c)] = blockOf(c, c);
  const bool iterative = opt.solver == BALinearSolver::Iterative ||
                         (opt.solver == BALinearSolver::Auto && nVC >= opt.iterativeMinPoses &&
                          keys.size() >= static_cast<std::size_t>(opt.iterativeMinBlocksPerPose) * static_cast<std::size_t>(nVC));
  const bool sparse = !iterative && (opt.solver == BALinearSolver::Sparse ||
                                     (opt.solver == BALinearSolver::Auto && nVC > opt.denseMaxPoses));
  rep.sparseSolver = sparse && nVC > 0;
  rep.iterativeSolver = iterative && nVC > 0;

  // --- linearisation storage ---------------------------------------------------------------------
  std::vector<SM6> Hcc(static_cast<std::size_t>(nVC));
  std::vector<S6> gc(static_cast<std::size_t>(nVC));
  std::vector<SM3> Hpp(static_cast<std::size_t>(nVP));
  std::vector<S3> gp(static_cast<std::size_t>(nVP));
  std::vector<SM63> Wcp(static_cast<std::size_t>(nU));  // H_cp of observation a (free pose & point)
  std::vector<SM6> priorOff(keys.size());                // prior contributions to off-diagonal blocks
  std::vector<SM6> S(keys.size());
  std::vector<SM3> HppInv(static_cast<std::size_t>(nVP));
  std::vector<SM63> Y(maxList);
  VecX<Scalar> rhs(6 * nVC), dc(6 * nVC);
  std::vector<S3> dp(static_cast<std::size_t>(nVP));
  Scalar gradMax = Scalar(0);

  auto linearise = [&]() {
    for (auto& m : Hcc) m.setZero();
    for (auto& v : gc) v.setZero();
    for (auto& m : Hpp) m.setZero();
    for (auto& v : gp) v.setZero();
    for (auto& m : priorOff) m.setZero();
    for (int a = 0; a < nU; ++a) {
      const auto& o = P.observations[static_cast<std::size_t>(used[static_cast<std::size_t>(a)])];
      const int cv = obsPoseVar[static_cast<std::size_t>(a)], pv = obsPointVar[static_cast<std::size_t>(a)];
      V2 r;
      M26 Jc;
      M23 Jp;
      if (!ba_detail::reprojection<Scalar>(cam, Rcw[static_cast<std::size_t>(o.pose)],
                                           tcw[static_cast<std::size_t>(o.pose)],
                                           P.points[static_cast<std::size_t>(o.point)], o.uv,
                                           opt.minDepth, r, cv >= 0 ? &Jc : nullptr,
                                           pv >= 0 ? &Jp : nullptr)) {
        continue;  // cannot happen: states with such observations are rejected
      }
      const Scalar s = r.squaredNorm() * invS2;
      const Scalar w = o.weight * invS2 * robustWeight(opt.loss, s, opt.robustScale);
      const Scalar alpha =
          ba_detail::robustCurvatureAlpha(opt.loss, s, opt.robustScale, opt.minRadialCurvature);
      const V2 wr = w * r;
      M26 wJc;
      M23 wJp;
      if (cv >= 0) {
        gc[static_cast<std::size_t>(cv)].noalias() += Jc.transpose() * wr;
        ba_detail::applyRobustCorrection(r, alpha, Jc);
        wJc = w * Jc;
        Hcc[static_cast<std::size_t>(cv)].noalias() += Jc.transpose() * wJc;
      }
      if (pv >= 0) {
        gp[static_cast<std::size_t>(pv)].noalias() += Jp.transpose() * wr;
        ba_detail::applyRobustCorrection(r, alpha, Jp);
        wJp = w * Jp;
        Hpp[static_cast<std::size_t>(pv)].noalias() += Jp.transpose() * wJp;
      }
      if (cv >= 0 && pv >= 0) Wcp[static_cast<std::size_t>(a)].noalias() = Jc.transpose() * wJp;
    }
    for (const auto* s : priors) {
      const int ca = poseVar[static_cast<std::size_t>(s->poseA)], cb = poseVar[static_cast<std::size_t>(s->poseB)];
      Eigen::Matrix<Scalar, 1, 6> Ja, Jb;
      const Scalar e = baScalePriorResidual(P.poses[static_cast<std::size_t>(s->poseA)],
                                            P.poses[static_cast<std::size_t>(s->poseB)], s->distance, &Ja, &Jb);
      const Scalar w = s->weight;
      if (ca >= 0) {
        Hcc[static_cast<std::size_t>(ca)].noalias() += w * Ja.transpose() * Ja;
        gc[static_cast<std::size_t>(ca)].noalias() += w * e * Ja.transpose();
      }
      if (cb >= 0) {
        Hcc[static_cast<std::size_t>(cb)].noalias() += w * Jb.transpose() * Jb;
        gc[static_cast<std::size_t>(cb)].noalias() += w * e * Jb.transpose();
      }
      if (ca >= 0 && cb >= 0) {
        if (ca < cb) {
          priorOff[static_cast<std::size_t>(blockOf(ca, cb))].noalias() += w * Ja.transpose() * Jb;
        } else {
          priorOff[static_cast<std::size_t>(blockOf(cb, ca))].noalias() += w * Jb.transpose() * Ja;
        }
      }
    }
    // Position priors: r = c − p, ∂r/∂δ = [R_w_c, 0] (right perturbation, translation first).
    for (const auto& q : P.positionPriors) {
      const int cq = poseVar[static_cast<std::size_t>(q.pose)];
      if (cq < 0 || !(q.weight > Scalar(0))) continue;
      const SE3<Scalar>& T = P.poses[static_cast<std::size_t>(q.pose)];
      const Mat3<Scalar> R = T.rotationMatrix();
      const Vec3<Scalar> e = T.translation() - q.position;
      Hcc[static_cast<std::size_t>(cq)].template topLeftCorner<3, 3>().noalias() += q.weight * R.transpose() * R;
      gc[static_cast<std::size_t>(cq)].template head<3>().noalias() += q.weight * R.transpose() * e;
    }
    gradMax = Scalar(0);
    for (const auto& v : gc) gradMax = std::max(gradMax, v.cwiseAbs().maxCoeff());
    for (const auto& v : gp) gradMax = std::max(gradMax, v.cwiseAbs().maxCoeff());
    gradMax *= Scalar(2);  // ∇F = 2g
  };

  // Dense or sparse factorisation of S (the sparse pattern is analysed once).
  MatX<Scalar> Sd;
  Eigen::SparseMatrix<Scalar> Ss;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<Scalar>, Eigen::Lower, Eigen::AMDOrdering<int>> sparseLLT;
  bool patternAnalysed = false;
  std::vector<Eigen::Triplet<Scalar>> triplets;
  std::vector<SM6> blockInv;                // conjugate gradients: inverses of S's diagonal blocks
  VecX<Scalar> cgR, cgZ, cgP, cgQ;
  // y = S·x from the stored blocks (S[b] is block (ci, cj), ci ≤ cj; S symmetric).
  auto multiplyS = [&](const VecX<Scalar>& x, VecX<Scalar>& y) {
    y.setZero(6 * nVC);
    for (std::size_t b = 0; b < keys.size(); ++b) {
      const int ci = static_cast<int>(keys[b] >> 32), cj = static_cast<int>(keys[b] & 0xFFFFFFFFu);
      y.template segment<6>(6 * ci).noalias() += S[b] * x.template segment<6>(6 * cj);
      if (ci != cj) y.template segment<6>(6 * cj).noalias() += S[b].transpose() * x.template segment<6>(6 * ci);
    }
  };
  // Preconditioned conjugate gradients on S·dc = rhs from dc = 0; false when S shows itself not
  // positive definite (a diagonal block, or pᵀSp ≤ 0).
  auto solveCG = [&]() -> bool {
    blockInv.resize(static_cast<std::size_t>(nVC));
    for (int c = 0; c < nVC; ++c) {
      const M6 D = S[static_cast<std::size_t>(diagBlock[static_cast<std::size_t>(c)])];
      const Eigen::LLT<M6> l(D);
      if (l.info() != Eigen::Success) return false;
      blockInv[static_cast<std::size_t>(c)] = l.solve(M6::Identity());
    }
    auto precondition = [&](const VecX<Scalar>& r, VecX<Scalar>& z) {
      z.resize(6 * nVC);
      for (int c = 0; c < nVC; ++c) z.template segment<6>(6 * c).noalias() = blockInv[static_cast<std::size_t>(c)] * r.template segment<6>(6 * c);
    };
    dc.setZero(6 * nVC);
    cgR = rhs;
    const Scalar bNorm = rhs.norm();
    if (!(bNorm > Scalar(0))) return std::isfinite(double(bNorm));
    precondition(cgR, cgZ);
    cgP = cgZ;
    Scalar rz = cgR.dot(cgZ);
    for (int it = 0; it < opt.cgMaxIterations; ++it) {
      multiplyS(cgP, cgQ);
      const Scalar pq = cgP.dot(cgQ);
      if (!(pq > Scalar(0))) return false;
      const Scalar alpha = rz / pq;
      dc.noalias() += alpha * cgP;
      cgR.noalias() -= alpha * cgQ;
      if (cgR.norm() <= opt.cgTolerance * bNorm) break;
      precondition(cgR, cgZ);
      const Scalar rzNew = cgR.dot(cgZ);
      cgP = cgZ + (rzNew / rz) * cgP;
      rz = rzNew;
    }
    return true;
  };

  // Solves the damped system; returns false when a factorisation fails. Also returns the
  // predicted decrease −gᵀδ + λ·δᵀDδ of the model F + 2gᵀδ + δᵀHδ.
  auto solveStep = [&](Scalar lambda, Scalar& predicted) -> bool {
    Scalar dDd = Scalar(0), gd = Scalar(0);
    // Point blocks: damped inverse.
    for (int j = 0; j < nVP; ++j) {
      M3 H = Hpp[static_cast<std::size_t>(j)];
      for (int k = 0; k < 3; ++k) H(k, k) += lambda * ba_detail::clampDiag(H(k, k));
      // Closed-form inverse; positive definiteness by Sylvester's criterion (leading minors).
      const Scalar m2 = H(0, 0) * H(1, 1) - H(0, 1) * H(1, 0);
      const Scalar det = H.determinant();
      if (!(H(0, 0) > Scalar(0)) || !(m2 > Scalar(0)) || !(det > Scalar(0))) return false;
      HppInv[static_cast<std::size_t>(j)] = H.inverse();
    }
    for (std::size_t b = 0; b < keys.size(); ++b) S[b] = priorOff[b];
    for (int c = 0; c < nVC; ++c) {
      M6 H = Hcc[static_cast<std::size_t>(c)];
      for (int k = 0; k < 6; ++k) H(k, k) += lambda * ba_detail::clampDiag(H(k, k));
      S[static_cast<std::size_t>(diagBlock[static_cast<std::size_t>(c)])] = H;
      rhs.template segment<6>(6 * c) = -gc[static_cast<std::size_t>(c)];
    }
    // Schur complement of the point blocks.
    std::size_t pi = 0;
    for (int j = 0; j < nVP; ++j) {
      const int s0 = ptStart[static_cast<std::size_t>(j)], m = ptSchurCount[static_cast<std::size_t>(j)];
      const M3 Hi = HppInv[static_cast<std::size_t>(j)];
      const V3 g = gp[static_cast<std::size_t>(j)];
      for (int u = 0; u < m; ++u) {
        const int a = ptObs[static_cast<std::size_t>(s0 + u)];
        const int cu = obsPoseVar[static_cast<std::size_t>(a)];
        const M63 W = Wcp[static_cast<std::size_t>(a)];
        const M63 Yu = W * Hi;
        Y[static_cast<std::size_t>(u)] = Yu;
        rhs.template segment<6>(6 * cu).noalias() += Yu * g;
      }
      for (int u = 0; u < m; ++u) {
        const int au = ptObs[static_cast<std::size_t>(s0 + u)];
        const int cu = obsPoseVar[static_cast<std::size_t>(au)];
        const M63 Yu = Y[static_cast<std::size_t>(u)];
        S[static_cast<std::size_t>(diagBlock[static_cast<std::size_t>(cu)])].noalias() -=
            Yu * Wcp[static_cast<std::size_t>(au)].transpose();
        for (int v = u + 1; v < m; ++v) {
          const int av = ptObs[static_cast<std::size_t>(s0 + v)];
          const int cv = obsPoseVar[static_cast<std::size_t>(av)];
          if (cv == cu) {  // the same point observed twice by one pose
            const M6 Bm = Yu * Wcp[static_cast<std::size_t>(av)].transpose();
            S[static_cast<std::size_t>(diagBlock[static_cast<std::size_t>(cu)])].noalias() -= Bm + Bm.transpose();
          } else {
            S[static_cast<std::size_t>(pairBlock[pi++])].noalias() -=
                Yu * Wcp[static_cast<std::size_t>(av)].transpose();
          }
        }
      }
    }
    // Solve S·δc = rhs.
    if (nVC > 0) {
      if (iterative) {
        if (!solveCG()) return false;
      } else if (!sparse) {
        Sd.setZero(6 * nVC, 6 * nVC);
        for (std::size_t b = 0; b < keys.size(); ++b) {
          const int ci = static_cast<int>(keys[b] >> 32), cj = static_cast<int>(keys[b] & 0xFFFFFFFFu);
          Sd.template block<6, 6>(6 * ci, 6 * cj) = S[b];
          if (ci != cj) Sd.template block<6, 6>(6 * cj, 6 * ci) = S[b].transpose();
        }
        // In place (Sd is rebuilt for every step): no second n×n copy (11 MB at 200 poses).
        const Eigen::LLT<Eigen::Ref<MatX<Scalar>>> llt(Sd);
        if (llt.info() != Eigen::Success) return false;
        dc = llt.solve(rhs);
      } else {
        triplets.clear();
        for (std::size_t b = 0; b < keys.size(); ++b) {
          const int ci = static_cast<int>(keys[b] >> 32), cj = static_cast<int>(keys[b] & 0xFFFFFFFFu);
          // lower triangle: row block cj ≥ column block ci
          for (int c = 0; c < 6; ++c) {
            for (int r = (ci == cj ? c : 0); r < 6; ++r) {
              triplets.emplace_back(6 * cj + r, 6 * ci + c, S[b](c, r));
            }
          }
        }
        Ss.resize(6 * nVC, 6 * nVC);
        Ss.setFromTriplets(triplets.begin(), triplets.end());
        if (!patternAnalysed) {
          sparseLLT.analyzePattern(Ss);
          patternAnalysed = true;
        }
        sparseLLT.factorize(Ss);
        if (sparseLLT.info() != Eigen::Success) return false;
        dc = sparseLLT.solve(rhs);
      }
      if (!dc.allFinite()) return false;
    }
    // Back-substitution for the points.
    for (int j = 0; j < nVP; ++j) {
      const int s0 = ptStart[static_cast<std::size_t>(j)], m = ptSchurCount[static_cast<std::size_t>(j)];
      V3 b = -gp[static_cast<std::size_t>(j)];
      for (int u = 0; u < m; ++u) {
        const int a = ptObs[static_cast<std::size_t>(s0 + u)];
        b.noalias() -= Wcp[static_cast<std::size_t>(a)].transpose() *
                       dc.template segment<6>(6 * obsPoseVar[static_cast<std::size_t>(a)]);
      }
      const V3 d = HppInv[static_cast<std::size_t>(j)] * b;
      if (!d.allFinite()) return false;
      dp[static_cast<std::size_t>(j)] = d;
      const M3& H = Hpp[static_cast<std::size_t>(j)];
      for (int k = 0; k < 3; ++k) dDd += ba_detail::clampDiag(H(k, k)) * d(k) * d(k);
      gd += gp[static_cast<std::size_t>(j)].dot(d);
    }
    for (int c = 0; c < nVC; ++c) {
      const V6 d = dc.template segment<6>(6 * c);
      const M6 H = Hcc[static_cast<std::size_t>(c)];
      for (int k = 0; k < 6; ++k) dDd += ba_detail::clampDiag(H(k, k)) * d(k) * d(k);
      gd += gc[static_cast<std::size_t>(c)].dot(d);
    }
    predicted = -gd + lambda * dDd;
    return true;
  };

  // Candidate state.
  std::vector<SE3<Scalar>> newPoses = P.poses;
  std::vector<Vec3<Scalar>> newPoints = P.points;
  auto stateNorm = [&]() {
    Scalar s = Scalar(0);
    for (int c = 0; c < nC; ++c) {
      if (poseVar[static_cast<std::size_t>(c)] >= 0) s += P.poses[static_cast<std::size_t>(c)].translation().squaredNorm();
    }
    for (int j = 0; j < nP; ++j) {
      if (pointVar[static_cast<std::size_t>(j)] >= 0) s += P.points[static_cast<std::size_t>(j)].squaredNorm();
    }
    return std::sqrt(s);
  };

  Scalar lambda = opt.initialLambda, nu = Scalar(2);
  rep.termination = BATermination::MaxIterations;
  bool linearised = false;  // linearised lazily: no wasted linearisation after the last step
  while (rep.iterations < opt.maxIterations) {
    if (!linearised) {
      linearise();
      linearised = true;
      if (gradMax <= opt.gradientTolerance) {
        rep.termination = BATermination::GradientTolerance;
        rep.converged = true;
        break;
      }
    }
    ++rep.iterations;
    Scalar predicted = Scalar(0);
    if (!solveStep(lambda, predicted)) {
      lambda *= nu;
      nu *= Scalar(2);
      if (lambda > opt.maxLambda) {
        rep.termination = BATermination::NoProgress;
        break;
      }
      continue;
    }
    const Scalar stepNorm = std::sqrt(dc.squaredNorm() + [&] {
      Scalar s = Scalar(0);
      for (const auto& d : dp) s += d.squaredNorm();
      return s;
    }());
    if (stepNorm <= opt.parameterTolerance * (stateNorm() + opt.parameterTolerance)) {
      rep.termination = BATermination::ParameterTolerance;
      rep.converged = true;
      break;
    }
    // Candidate: T_w_c·exp(δ) and X + δX.
    for (int c = 0; c < nC; ++c) {
      const int cv = poseVar[static_cast<std::size_t>(c)];
      newPoses[static_cast<std::size_t>(c)] =
          cv >= 0 ? P.poses[static_cast<std::size_t>(c)] *
                        SE3<Scalar>::exp(Vec6<Scalar>(dc.template segment<6>(6 * cv)))
                  : P.poses[static_cast<std::size_t>(c)];
    }
    for (int j = 0; j < nP; ++j) {
      const int pv = pointVar[static_cast<std::size_t>(j)];
      newPoints[static_cast<std::size_t>(j)] =
          pv >= 0 ? Vec3<Scalar>(P.points[static_cast<std::size_t>(j)] + dp[static_cast<std::size_t>(pv)])
                  : P.points[static_cast<std::size_t>(j)];
    }
    cachePoses(newPoses);
    double newSumSq = 0.0;
    const double Fn = evalCost(newPoses, newPoints, &newSumSq);
    if (std::isfinite(Fn) && Fn < F && predicted > Scalar(0)) {
      const Scalar rho = Scalar((F - Fn) / double(predicted));
      const double relDecrease = (F - Fn) / std::max(F, std::numeric_limits<double>::min());
      std::swap(P.poses, newPoses);
      std::swap(P.points, newPoints);
      F = Fn;
      sumSq = newSumSq;
      ++rep.successfulSteps;
      const Scalar t = Scalar(2) * rho - Scalar(1);
      lambda *= std::max(Scalar(1) / Scalar(3), Scalar(1) - t * t * t);
      nu = Scalar(2);
      if (relDecrease <= double(opt.functionTolerance)) {
        rep.termination = BATermination::FunctionTolerance;
        rep.converged = true;
        break;
      }
      linearised = false;
    } else {
      cachePoses(P.poses);  // restore the cache of the current state
      lambda *= nu;
      nu *= Scalar(2);
      if (lambda > opt.maxLambda) {
        rep.termination = BATermination::NoProgress;
        break;
      }
    }
  }
  rep.finalCost = Scalar(F);
  rep.finalRmsPx = nU > 0 ? Scalar(std::sqrt(sumSq / nU)) : Scalar(0);
  rep.lambda = lambda;
  return rep;
}

}  // namespace hawor
