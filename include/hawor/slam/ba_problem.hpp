// hawor/slam/ba_problem.hpp — the bundle-adjustment problem (bundle_adjustment.hpp): N camera
// poses and M points seen through one fixed pinhole camera, the priors, the options and the
// report, and the residuals with their Jacobians.
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
#pragma once

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

/// How the reduced camera system S·δ = b is solved (bundle_adjustment.hpp). Iterative: conjugate
/// gradients on S's stored 6×6 blocks. ImplicitSchur: conjugate gradients on S = H_cc − W·H_pp⁻¹·Wᵀ
/// applied one point at a time, S never formed (memory linear in the observations).
enum class BALinearSolver { Auto, Dense, Sparse, Iterative, ImplicitSchur };

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
  /// Auto, where conjugate gradients are chosen: S applied implicitly when forming it would
  /// visit more than this many camera pairs per observation (points seen by hundreds of
  /// cameras, a clip that revisits one place for minutes: S's blocks then grow with the square
  /// of the observations, the implicit product with the observations).
  int implicitMinPairsPerObservation = 64;
  Scalar cgTolerance = Scalar(1e-8);    ///< ‖S·δ − b‖ ≤ cgTolerance·‖b‖
  int cgMaxIterations = 500;
  /// Floor D_min of the radial curvature factor of the robust correction (bundle_adjustment.hpp), in (0, 1].
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
  bool implicitSchur = false;    ///< … with S applied implicitly (BALinearSolver::ImplicitSchur)
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
  if (opt.implicitMinPairsPerObservation < 0) throw Error("bundleAdjust: implicitMinPairsPerObservation must be >= 0");
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

}  // namespace hawor
