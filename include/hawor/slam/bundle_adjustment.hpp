// hawor/slam/bundle_adjustment.hpp — sparse bundle adjustment: N camera poses and M points seen
// through one fixed pinhole camera, Levenberg–Marquardt with the Schur complement on the points
// (Triggs et al. 2000, "Bundle adjustment — a modern synthesis", §6; Lourakis & Argyros, SBA).
//
// The problem (poses, points, observations, priors), its options, report and residuals are in
// ba_problem.hpp: r_i = π(R_cw·X + t_cw) − uv, F = Σ w_i ρ(‖r_i‖²/σ²) + priors; the linear
// solvers of the reduced camera system in ba_reduced_solver.hpp. This header holds the
// optimiser: BundleAdjuster (one problem's variables, structure, linearisation and LM loop) and
// bundleAdjust(), which runs one.
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
//   When points are seen by hundreds of cameras (a clip that keeps revisiting one place: one
//   point, 300 keyframes, 45,000 blocks), S's blocks grow with the square of the observations
//   (10 minutes of a kitchen: 3,400 keyframes, > 2 GB); from `implicitMinPairsPerObservation`
//   camera pairs an observation, S is never formed: CG applies S·x = H_cc·x − Σ_p W_p H_pp⁻¹ W_pᵀx
//   point by point, memory and work per product linear in the observations (the "implicit
//   Schur" of Agarwal et al. 2010), preconditioned by S's diagonal blocks as before.
// Gauge: a monocular problem has 7 gauge freedoms (pose and scale). Fix at least one pose
//   (poseFixed); fix the scale with a second fixed pose or a BAScalePrior between two cameras.
//   Without them the free directions are held only by the damping (no error, slow convergence).
// Points (and poses) can be fixed: with all points fixed the problem is a motion-only BA.
// Not thread-safe for one problem; distinct problems may be solved concurrently.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "hawor/slam/ba_problem.hpp"
#include "hawor/slam/ba_reduced_solver.hpp"

namespace hawor {

/// Levenberg–Marquardt over one BAProblem (the file comment), optimised in place by run(). The
/// constructor validates the problem and chooses the used observations and the free variables;
/// run() builds the reduced camera system's block structure once, then iterates: linearise
/// (IRLS weights, robust curvature), solveStep (Schur complement on the points, the reduced
/// system by ReducedCameraSolver, back-substitution), and the step accepted or damped.
template <typename Scalar>
class BundleAdjuster {
 public:
  /// Throws hawor::Error for malformed input (indices out of range, non-finite values, negative
  /// weights, flag vectors of the wrong size, bad options).
  BundleAdjuster(BAProblem<Scalar>& problem, const BAOptions<Scalar>& options)
      : P_(problem), opt_(options), cam_(problem.camera), nC_(static_cast<int>(problem.poses.size())),
        nP_(static_cast<int>(problem.points.size())) {
    ba_detail::validate(problem, options);
    invS2_ = Scalar(1) / (opt_.sigmaPx * opt_.sigmaPx);
    Rcw_.resize(static_cast<std::size_t>(nC_));
    tcw_.resize(static_cast<std::size_t>(nC_));
    cachePoses(P_.poses);
    selectVariables();
  }

  /// Runs LM to a tolerance, the iteration limit, or no progress; the problem holds the result.
  BAReport<Scalar> run();

 private:
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

  static std::size_t z(int i) { return static_cast<std::size_t>(i); }
  const BAObservation<Scalar>& usedObs(int a) const { return P_.observations[z(used_[z(a)])]; }
  void cachePoses(const std::vector<SE3<Scalar>>& poses);
  void selectVariables();
  double cost(const std::vector<SE3<Scalar>>& poses, const std::vector<Vec3<Scalar>>& points, double* sumSq) const;
  void buildStructure();
  int blockOf(int ci, int cj) const {
    return static_cast<int>(std::lower_bound(keys_.begin(), keys_.end(), blockKey(ci, cj)) - keys_.begin());
  }
  void linearise();
  bool solveStep(ReducedCameraSolver<Scalar>& solver, Scalar lambda, Scalar& predicted);
  Scalar stateNorm() const;

  BAProblem<Scalar>& P_;
  const BAOptions<Scalar> opt_;  // a copy: the caller's may be a temporary
  const PinholeCamera<Scalar>& cam_;
  const int nC_, nP_;
  Scalar invS2_ = Scalar(1);
  BAReport<Scalar> rep_;
  // World-to-camera matrices of the poses being evaluated.
  std::vector<SM3> Rcw_;
  std::vector<S3> tcw_;
  // Used observations (weight > 0, in front at the start) and variables (−1: fixed or unused).
  std::vector<int> used_;
  int nU_ = 0, nVC_ = 0, nVP_ = 0;
  std::vector<int> poseVar_, pointVar_;
  std::vector<const BAScalePrior<Scalar>*> priors_;
  // Structure of the reduced camera system (buildStructure).
  std::vector<int> ptStart_, ptObs_, obsPoseVar_, obsPointVar_, ptSchurCount_, pairBlock_, diagBlock_;
  std::vector<std::uint64_t> keys_;
  std::size_t maxList_ = 0;
  ReducedSolverMethod method_ = ReducedSolverMethod::Dense;
  // Linearisation and the step.
  std::vector<SM6> Hcc_;
  std::vector<S6> gc_;
  std::vector<SM3> Hpp_;
  std::vector<S3> gp_;
  std::vector<SM63> Wcp_;      // H_cp of used_ observation a (free pose & point)
  std::vector<SM6> priorOff_;  // prior contributions to off-diagonal blocks
  std::vector<SM6> S_;     // S's stored blocks (implicit: the damped H_cc and the priors' only)
  std::vector<SM6> Sdiag_;  // implicit: S's diagonal blocks (the preconditioner)
  bool implicit_ = false;
  std::vector<SM3> HppInv_;
  std::vector<SM63> Y_;
  VecX<Scalar> rhs_, dc_;
  std::vector<S3> dp_;
  Scalar gradMax_ = Scalar(0);
};

template <typename Scalar>
void BundleAdjuster<Scalar>::cachePoses(const std::vector<SE3<Scalar>>& poses) {
  for (int c = 0; c < nC_; ++c) {
    const SE3<Scalar> Tcw = poses[z(c)].inverse();
    Rcw_[z(c)] = Tcw.rotationMatrix();
    tcw_[z(c)] = Tcw.translation();
  }
}

/// The used_ observations (weight > 0 and in front of their camera now) and the free variables:
/// poses and points not fixed and used_ by an observation (or, poses, a scale prior).
template <typename Scalar>
void BundleAdjuster<Scalar>::selectVariables() {
  used_.reserve(P_.observations.size());
  for (std::size_t k = 0; k < P_.observations.size(); ++k) {
    const auto& o = P_.observations[k];
    if (!(o.weight > Scalar(0))) continue;
    V2 r;
    if (ba_detail::reprojection<Scalar>(cam_, Rcw_[z(o.pose)], tcw_[z(o.pose)], P_.points[z(o.point)], o.uv,
                                        opt_.minDepth, r, nullptr, nullptr)) {
      used_.push_back(static_cast<int>(k));
    } else {
      ++rep_.behindObservations;
    }
  }
  rep_.usedObservations = static_cast<int>(used_.size());
  nU_ = rep_.usedObservations;

  poseVar_.assign(z(nC_), -1);
  pointVar_.assign(z(nP_), -1);
  std::vector<int> poseUses(z(nC_), 0), pointUses(z(nP_), 0);
  for (int a = 0; a < nU_; ++a) {
    const auto& o = usedObs(a);
    ++poseUses[z(o.pose)];
    ++pointUses[z(o.point)];
  }
  for (const auto& s : P_.scalePriors) {
    if (s.weight > Scalar(0)) {
      priors_.push_back(&s);
      ++poseUses[z(s.poseA)];
      ++poseUses[z(s.poseB)];
    }
  }
  for (int c = 0; c < nC_; ++c) {
    const bool fixed = !P_.poseFixed.empty() && P_.poseFixed[z(c)];
    if (!fixed && poseUses[z(c)] > 0) poseVar_[z(c)] = nVC_++;
  }
  for (int j = 0; j < nP_; ++j) {
    const bool fixed = !P_.pointFixed.empty() && P_.pointFixed[z(j)];
    if (!fixed && pointUses[z(j)] > 0) pointVar_[z(j)] = nVP_++;
  }
  rep_.freePoses = nVC_;
  rep_.freePoints = nVP_;
}

/// F of the file comment at (poses, points), with Rcw_/tcw_ cached for `poses`; +∞ when a used_
/// observation is at depth ≤ minDepth. Also returns the plain sum of squared pixel residuals.
/// Sums are kept in double whatever Scalar is: in float, rounding of a sum over thousands of
/// terms would hide the last decreases and make LM reject good steps.
template <typename Scalar>
double BundleAdjuster<Scalar>::cost(const std::vector<SE3<Scalar>>& poses, const std::vector<Vec3<Scalar>>& points,
                                    double* sumSq) const {
  double F = 0.0, ss = 0.0;
  for (int a = 0; a < nU_; ++a) {
    const auto& o = usedObs(a);
    V2 r;
    if (!ba_detail::reprojection<Scalar>(cam_, Rcw_[z(o.pose)], tcw_[z(o.pose)], points[z(o.point)], o.uv,
                                         opt_.minDepth, r, nullptr, nullptr)) {
      return std::numeric_limits<double>::infinity();
    }
    const Scalar r2 = r.squaredNorm();
    ss += double(r2);
    F += double(o.weight * robustCost(opt_.loss, r2 * invS2_, opt_.robustScale));
  }
  for (const auto* s : priors_) {
    const Scalar e = baScalePriorResidual(poses[z(s->poseA)], poses[z(s->poseB)], s->distance);
    F += double(s->weight * e * e);
  }
  for (const auto& q : P_.positionPriors) {
    F += double(q.weight * (poses[z(q.pose)].translation() - q.position).squaredNorm());
  }
  if (sumSq) *sumSq = ss;
  return F;
}

/// The block structure of the reduced camera system, fixed for the whole run: per free point its
/// used_ observations (CSR), those with a free pose first, sorted by pose; the blocks (ci ≤ cj) of
/// S (diagonal blocks, co-observing pairs, prior pairs) and the block of every pair in the order
/// solveStep visits them; the linear solver.
template <typename Scalar>
void BundleAdjuster<Scalar>::buildStructure() {
  ptStart_.assign(z(nVP_) + 1, 0);
  for (int a = 0; a < nU_; ++a) {
    const int pv = pointVar_[z(usedObs(a).point)];
    if (pv >= 0) ++ptStart_[z(pv) + 1];
  }
  for (int j = 0; j < nVP_; ++j) ptStart_[z(j) + 1] += ptStart_[z(j)];
  ptObs_.assign(z(ptStart_[z(nVP_)]), 0);
  {
    std::vector<int> fill(ptStart_.begin(), ptStart_.end() - 1);
    for (int a = 0; a < nU_; ++a) {
      const int pv = pointVar_[z(usedObs(a).point)];
      if (pv >= 0) ptObs_[z(fill[z(pv)]++)] = a;
    }
  }
  // obsPoseVar_[a]: free-pose index of used_ observation a (−1 if the pose is fixed).
  obsPoseVar_.assign(z(nU_), 0);
  obsPointVar_.assign(z(nU_), 0);
  for (int a = 0; a < nU_; ++a) {
    const auto& o = usedObs(a);
    obsPoseVar_[z(a)] = poseVar_[z(o.pose)];
    obsPointVar_[z(a)] = pointVar_[z(o.point)];
  }
  // Within each point, order observations with a free pose first, sorted by pose; count them.
  ptSchurCount_.assign(z(nVP_), 0);
  for (int j = 0; j < nVP_; ++j) {
    auto b = ptObs_.begin() + ptStart_[z(j)];
    auto e = ptObs_.begin() + ptStart_[z(j) + 1];
    std::sort(b, e, [&](int x, int y) {
      const int cx = obsPoseVar_[z(x)], cy = obsPoseVar_[z(y)];
      const int kx = cx < 0 ? std::numeric_limits<int>::max() : cx;
      const int ky = cy < 0 ? std::numeric_limits<int>::max() : cy;
      return kx < ky || (kx == ky && x < y);
    });
    int cnt = 0;
    for (auto it = b; it != e; ++it) cnt += obsPoseVar_[z(*it)] >= 0 ? 1 : 0;
    ptSchurCount_[z(j)] = cnt;
  }
  // S applied implicitly (ImplicitSchur) where forming it would visit many camera pairs per
  // observation: Σ_p m_p(m_p − 1)/2 pairs for m_p free-pose observations of point p.
  double pairs = 0.0;
  for (int j = 0; j < nVP_; ++j) {
    const double m = ptSchurCount_[z(j)];
    pairs += 0.5 * m * (m - 1.0);
    maxList_ = std::max(maxList_, z(ptSchurCount_[z(j)]));
  }
  implicit_ = nVC_ > 0 && (opt_.solver == BALinearSolver::ImplicitSchur ||
                           (opt_.solver == BALinearSolver::Auto && nVC_ >= opt_.iterativeMinPoses &&
                            pairs > double(opt_.implicitMinPairsPerObservation) * double(std::max(nU_, 1))));
  // Blocks (ci ≤ cj) of S_: diagonal blocks, co-observing pairs (not when implicit), prior pairs.
  for (int c = 0; c < nVC_; ++c) keys_.push_back(blockKey(c, c));
  for (int j = 0; j < nVP_ && !implicit_; ++j) {
    const int s0 = ptStart_[z(j)], m = ptSchurCount_[z(j)];
    for (int u = 0; u < m; ++u) {
      for (int v = u + 1; v < m; ++v) {
        const int cu = obsPoseVar_[z(ptObs_[z(s0 + u)])], cv = obsPoseVar_[z(ptObs_[z(s0 + v)])];
        if (cu != cv) keys_.push_back(blockKey(cu, cv));  // sorted: cu < cv
      }
    }
  }
  for (const auto* s : priors_) {
    const int ca = poseVar_[z(s->poseA)], cb = poseVar_[z(s->poseB)];
    if (ca >= 0 && cb >= 0) keys_.push_back(blockKey(std::min(ca, cb), std::max(ca, cb)));
  }
  std::sort(keys_.begin(), keys_.end());
  keys_.erase(std::unique(keys_.begin(), keys_.end()), keys_.end());
  // Block index of every off-diagonal pair (u < v, distinct poses) in the loop order of solveStep.
  for (int j = 0; j < nVP_ && !implicit_; ++j) {
    const int s0 = ptStart_[z(j)], m = ptSchurCount_[z(j)];
    for (int u = 0; u < m; ++u) {
      for (int v = u + 1; v < m; ++v) {
        const int cu = obsPoseVar_[z(ptObs_[z(s0 + u)])], cv = obsPoseVar_[z(ptObs_[z(s0 + v)])];
        if (cu != cv) pairBlock_.push_back(blockOf(cu, cv));
      }
    }
  }
  diagBlock_.assign(z(nVC_), 0);
  for (int c = 0; c < nVC_; ++c) diagBlock_[z(c)] = blockOf(c, c);
  const bool iterative = implicit_ || opt_.solver == BALinearSolver::Iterative ||
                         (opt_.solver == BALinearSolver::Auto && nVC_ >= opt_.iterativeMinPoses &&
                          keys_.size() >= z(opt_.iterativeMinBlocksPerPose) * z(nVC_));
  const bool sparse = !iterative && (opt_.solver == BALinearSolver::Sparse ||
                                     (opt_.solver == BALinearSolver::Auto && nVC_ > opt_.denseMaxPoses));
  method_ = implicit_ ? ReducedSolverMethod::ImplicitSchur
            : iterative ? ReducedSolverMethod::Iterative
            : sparse ? ReducedSolverMethod::Sparse : ReducedSolverMethod::Dense;
  rep_.sparseSolver = sparse && nVC_ > 0;
  rep_.iterativeSolver = iterative && nVC_ > 0;
  rep_.implicitSchur = implicit_;

  Hcc_.resize(z(nVC_));
  gc_.resize(z(nVC_));
  Hpp_.resize(z(nVP_));
  gp_.resize(z(nVP_));
  Wcp_.resize(z(nU_));
  priorOff_.resize(keys_.size());
  S_.resize(keys_.size());
  if (implicit_) Sdiag_.resize(z(nVC_));
  HppInv_.resize(z(nVP_));
  Y_.resize(maxList_);
  rhs_.resize(6 * nVC_);
  dc_.resize(6 * nVC_);
  dp_.resize(z(nVP_));
}

/// g = Σ w Jᵀr and H = Σ w J̃ᵀJ̃ (the file comment) at the problem's state: per free pose and
/// point blocks, H_cp per observation, the priors_' blocks; and the largest gradient entry.
template <typename Scalar>
void BundleAdjuster<Scalar>::linearise() {
  for (auto& m : Hcc_) m.setZero();
  for (auto& v : gc_) v.setZero();
  for (auto& m : Hpp_) m.setZero();
  for (auto& v : gp_) v.setZero();
  for (auto& m : priorOff_) m.setZero();
  for (int a = 0; a < nU_; ++a) {
    const auto& o = usedObs(a);
    const int cv = obsPoseVar_[z(a)], pv = obsPointVar_[z(a)];
    V2 r;
    M26 Jc;
    M23 Jp;
    if (!ba_detail::reprojection<Scalar>(cam_, Rcw_[z(o.pose)], tcw_[z(o.pose)], P_.points[z(o.point)], o.uv,
                                         opt_.minDepth, r, cv >= 0 ? &Jc : nullptr, pv >= 0 ? &Jp : nullptr)) {
      continue;  // cannot happen: states with such observations are rejected
    }
    const Scalar s = r.squaredNorm() * invS2_;
    const Scalar w = o.weight * invS2_ * robustWeight(opt_.loss, s, opt_.robustScale);
    const Scalar alpha = ba_detail::robustCurvatureAlpha(opt_.loss, s, opt_.robustScale, opt_.minRadialCurvature);
    const V2 wr = w * r;
    M26 wJc;
    M23 wJp;
    if (cv >= 0) {
      gc_[z(cv)].noalias() += Jc.transpose() * wr;
      ba_detail::applyRobustCorrection(r, alpha, Jc);
      wJc = w * Jc;
      Hcc_[z(cv)].noalias() += Jc.transpose() * wJc;
    }
    if (pv >= 0) {
      gp_[z(pv)].noalias() += Jp.transpose() * wr;
      ba_detail::applyRobustCorrection(r, alpha, Jp);
      wJp = w * Jp;
      Hpp_[z(pv)].noalias() += Jp.transpose() * wJp;
    }
    if (cv >= 0 && pv >= 0) Wcp_[z(a)].noalias() = Jc.transpose() * wJp;
  }
  for (const auto* s : priors_) {
    const int ca = poseVar_[z(s->poseA)], cb = poseVar_[z(s->poseB)];
    Eigen::Matrix<Scalar, 1, 6> Ja, Jb;
    const Scalar e = baScalePriorResidual(P_.poses[z(s->poseA)], P_.poses[z(s->poseB)], s->distance, &Ja, &Jb);
    const Scalar w = s->weight;
    if (ca >= 0) {
      Hcc_[z(ca)].noalias() += w * Ja.transpose() * Ja;
      gc_[z(ca)].noalias() += w * e * Ja.transpose();
    }
    if (cb >= 0) {
      Hcc_[z(cb)].noalias() += w * Jb.transpose() * Jb;
      gc_[z(cb)].noalias() += w * e * Jb.transpose();
    }
    if (ca >= 0 && cb >= 0) {
      if (ca < cb) {
        priorOff_[z(blockOf(ca, cb))].noalias() += w * Ja.transpose() * Jb;
      } else {
        priorOff_[z(blockOf(cb, ca))].noalias() += w * Jb.transpose() * Ja;
      }
    }
  }
  // Position priors_: r = c − p, ∂r/∂δ = [R_w_c, 0] (right perturbation, translation first).
  for (const auto& q : P_.positionPriors) {
    const int cq = poseVar_[z(q.pose)];
    if (cq < 0 || !(q.weight > Scalar(0))) continue;
    const SE3<Scalar>& T = P_.poses[z(q.pose)];
    const Mat3<Scalar> R = T.rotationMatrix();
    const Vec3<Scalar> e = T.translation() - q.position;
    Hcc_[z(cq)].template topLeftCorner<3, 3>().noalias() += q.weight * R.transpose() * R;
    gc_[z(cq)].template head<3>().noalias() += q.weight * R.transpose() * e;
  }
  gradMax_ = Scalar(0);
  for (const auto& v : gc_) gradMax_ = std::max(gradMax_, v.cwiseAbs().maxCoeff());
  for (const auto& v : gp_) gradMax_ = std::max(gradMax_, v.cwiseAbs().maxCoeff());
  gradMax_ *= Scalar(2);  // ∇F = 2g
}

/// Solves the damped system (dc_, dp_); returns false when a factorisation fails. Also returns the
/// predicted decrease −gᵀδ + λ·δᵀDδ of the model F + 2gᵀδ + δᵀHδ.
template <typename Scalar>
bool BundleAdjuster<Scalar>::solveStep(ReducedCameraSolver<Scalar>& solver, Scalar lambda, Scalar& predicted) {
  Scalar dDd = Scalar(0), gd = Scalar(0);
  // Point blocks: damped inverse.
  for (int j = 0; j < nVP_; ++j) {
    M3 H = Hpp_[z(j)];
    for (int k = 0; k < 3; ++k) H(k, k) += lambda * ba_detail::clampDiag(H(k, k));
    // Closed-form inverse; positive definiteness by Sylvester's criterion (leading minors).
    const Scalar m2 = H(0, 0) * H(1, 1) - H(0, 1) * H(1, 0);
    const Scalar det = H.determinant();
    if (!(H(0, 0) > Scalar(0)) || !(m2 > Scalar(0)) || !(det > Scalar(0))) return false;
    HppInv_[z(j)] = H.inverse();
  }
  for (std::size_t b = 0; b < keys_.size(); ++b) S_[b] = priorOff_[b];
  for (int c = 0; c < nVC_; ++c) {
    M6 H = Hcc_[z(c)];
    for (int k = 0; k < 6; ++k) H(k, k) += lambda * ba_detail::clampDiag(H(k, k));
    S_[z(diagBlock_[z(c)])] = H;
    rhs_.template segment<6>(6 * c) = -gc_[z(c)];
  }
  if (implicit_) {
    for (int c = 0; c < nVC_; ++c) Sdiag_[z(c)] = S_[z(diagBlock_[z(c)])];
  }
  // Schur complement of the point blocks (implicit: only its diagonal blocks, into Sdiag_).
  std::vector<SM6>& diagOut = implicit_ ? Sdiag_ : S_;
  const auto diagIndex = [&](int c) { return implicit_ ? z(c) : z(diagBlock_[z(c)]); };
  std::size_t pi = 0;
  for (int j = 0; j < nVP_; ++j) {
    const int s0 = ptStart_[z(j)], m = ptSchurCount_[z(j)];
    const M3 Hi = HppInv_[z(j)];
    const V3 g = gp_[z(j)];
    for (int u = 0; u < m; ++u) {
      const int a = ptObs_[z(s0 + u)];
      const int cu = obsPoseVar_[z(a)];
      const M63 W = Wcp_[z(a)];
      const M63 Yu = W * Hi;
      Y_[z(u)] = Yu;
      rhs_.template segment<6>(6 * cu).noalias() += Yu * g;
    }
    for (int u = 0; u < m; ++u) {
      const int au = ptObs_[z(s0 + u)];
      const int cu = obsPoseVar_[z(au)];
      const M63 Yu = Y_[z(u)];
      diagOut[diagIndex(cu)].noalias() -= Yu * Wcp_[z(au)].transpose();
      for (int v = u + 1; v < m; ++v) {
        const int av = ptObs_[z(s0 + v)];
        const int cv = obsPoseVar_[z(av)];
        if (cv == cu) {  // the same point observed twice by one pose
          const M6 Bm = Yu * Wcp_[z(av)].transpose();
          diagOut[diagIndex(cu)].noalias() -= Bm + Bm.transpose();
        } else if (!implicit_) {
          S_[z(pairBlock_[pi++])].noalias() -= Yu * Wcp_[z(av)].transpose();
        }
      }
    }
  }
  // Solve S·δc = rhs_. Implicit: S·x = (damped H_cc + priors)·x − Σ_p W_p·H_pp⁻¹·(W_pᵀ·x), one
  // point at a time (W_p: the point's H_cp blocks, one per free-pose observation).
  if (nVC_ > 0 && implicit_) {
    const auto apply = [&](const VecX<Scalar>& x, VecX<Scalar>& y) {
      solver.multiply(S_, x, y);
      for (int j = 0; j < nVP_; ++j) {
        const int s0 = ptStart_[z(j)], m = ptSchurCount_[z(j)];
        V3 t = V3::Zero();
        for (int u = 0; u < m; ++u) {
          const int a = ptObs_[z(s0 + u)];
          t.noalias() += Wcp_[z(a)].transpose() * x.template segment<6>(6 * obsPoseVar_[z(a)]);
        }
        const V3 h = HppInv_[z(j)] * t;
        for (int u = 0; u < m; ++u) {
          const int a = ptObs_[z(s0 + u)];
          y.template segment<6>(6 * obsPoseVar_[z(a)]).noalias() -= Wcp_[z(a)] * h;
        }
      }
    };
    if (!solver.conjugateGradients([&](int c) -> const SM6& { return Sdiag_[z(c)]; }, rhs_, dc_, apply)) return false;
  } else if (nVC_ > 0 && !solver.solve(S_, rhs_, dc_)) {
    return false;
  }
  // Back-substitution for the points.
  for (int j = 0; j < nVP_; ++j) {
    const int s0 = ptStart_[z(j)], m = ptSchurCount_[z(j)];
    V3 b = -gp_[z(j)];
    for (int u = 0; u < m; ++u) {
      const int a = ptObs_[z(s0 + u)];
      b.noalias() -= Wcp_[z(a)].transpose() * dc_.template segment<6>(6 * obsPoseVar_[z(a)]);
    }
    const V3 d = HppInv_[z(j)] * b;
    if (!d.allFinite()) return false;
    dp_[z(j)] = d;
    const M3& H = Hpp_[z(j)];
    for (int k = 0; k < 3; ++k) dDd += ba_detail::clampDiag(H(k, k)) * d(k) * d(k);
    gd += gp_[z(j)].dot(d);
  }
  for (int c = 0; c < nVC_; ++c) {
    const V6 d = dc_.template segment<6>(6 * c);
    const M6 H = Hcc_[z(c)];
    for (int k = 0; k < 6; ++k) dDd += ba_detail::clampDiag(H(k, k)) * d(k) * d(k);
    gd += gc_[z(c)].dot(d);
  }
  predicted = -gd + lambda * dDd;
  return true;
}

/// ‖(free camera centres, free points)‖, the scale of the parameter tolerance.
template <typename Scalar>
Scalar BundleAdjuster<Scalar>::stateNorm() const {
  Scalar s = Scalar(0);
  for (int c = 0; c < nC_; ++c) {
    if (poseVar_[z(c)] >= 0) s += P_.poses[z(c)].translation().squaredNorm();
  }
  for (int j = 0; j < nP_; ++j) {
    if (pointVar_[z(j)] >= 0) s += P_.points[z(j)].squaredNorm();
  }
  return std::sqrt(s);
}

template <typename Scalar>
BAReport<Scalar> BundleAdjuster<Scalar>::run() {
  double sumSq = 0.0;
  double F = cost(P_.poses, P_.points, &sumSq);
  rep_.initialCost = rep_.finalCost = Scalar(F);
  rep_.initialRmsPx = rep_.finalRmsPx = nU_ > 0 ? Scalar(std::sqrt(sumSq / nU_)) : Scalar(0);
  if (nVC_ == 0 && nVP_ == 0) {
    rep_.termination = BATermination::NoVariables;
    rep_.converged = true;
    return rep_;
  }
  if (!std::isfinite(F)) {
    throw Error("bundleAdjust: the initial cost is not finite (coordinates too large?)");
  }
  buildStructure();
  ReducedCameraSolver<Scalar> solver(method_, nVC_, keys_, diagBlock_, opt_.cgTolerance, opt_.cgMaxIterations);

  // Candidate state.
  std::vector<SE3<Scalar>> newPoses = P_.poses;
  std::vector<Vec3<Scalar>> newPoints = P_.points;
  Scalar lambda = opt_.initialLambda, nu = Scalar(2);
  rep_.termination = BATermination::MaxIterations;
  bool linearised = false;  // linearised lazily: no wasted linearisation after the last step
  while (rep_.iterations < opt_.maxIterations) {
    if (!linearised) {
      linearise();
      linearised = true;
      if (gradMax_ <= opt_.gradientTolerance) {
        rep_.termination = BATermination::GradientTolerance;
        rep_.converged = true;
        break;
      }
    }
    ++rep_.iterations;
    Scalar predicted = Scalar(0);
    if (!solveStep(solver, lambda, predicted)) {
      lambda *= nu;
      nu *= Scalar(2);
      if (lambda > opt_.maxLambda) {
        rep_.termination = BATermination::NoProgress;
        break;
      }
      continue;
    }
    const Scalar stepNorm = std::sqrt(dc_.squaredNorm() + [&] {
      Scalar s = Scalar(0);
      for (const auto& d : dp_) s += d.squaredNorm();
      return s;
    }());
    if (stepNorm <= opt_.parameterTolerance * (stateNorm() + opt_.parameterTolerance)) {
      rep_.termination = BATermination::ParameterTolerance;
      rep_.converged = true;
      break;
    }
    // Candidate: T_w_c·exp(δ) and X + δX.
    for (int c = 0; c < nC_; ++c) {
      const int cv = poseVar_[z(c)];
      newPoses[z(c)] = cv >= 0 ? P_.poses[z(c)] * SE3<Scalar>::exp(Vec6<Scalar>(dc_.template segment<6>(6 * cv)))
                               : P_.poses[z(c)];
    }
    for (int j = 0; j < nP_; ++j) {
      const int pv = pointVar_[z(j)];
      newPoints[z(j)] = pv >= 0 ? Vec3<Scalar>(P_.points[z(j)] + dp_[z(pv)]) : P_.points[z(j)];
    }
    cachePoses(newPoses);
    double newSumSq = 0.0;
    const double Fn = cost(newPoses, newPoints, &newSumSq);
    if (std::isfinite(Fn) && Fn < F && predicted > Scalar(0)) {
      const Scalar rho = Scalar((F - Fn) / double(predicted));
      const double relDecrease = (F - Fn) / std::max(F, std::numeric_limits<double>::min());
      std::swap(P_.poses, newPoses);
      std::swap(P_.points, newPoints);
      F = Fn;
      sumSq = newSumSq;
      ++rep_.successfulSteps;
      const Scalar t = Scalar(2) * rho - Scalar(1);
      lambda *= std::max(Scalar(1) / Scalar(3), Scalar(1) - t * t * t);
      nu = Scalar(2);
      if (relDecrease <= double(opt_.functionTolerance)) {
        rep_.termination = BATermination::FunctionTolerance;
        rep_.converged = true;
        break;
      }
      linearised = false;
    } else {
      cachePoses(P_.poses);  // restore the cache of the current state
      lambda *= nu;
      nu *= Scalar(2);
      if (lambda > opt_.maxLambda) {
        rep_.termination = BATermination::NoProgress;
        break;
      }
    }
  }
  rep_.finalCost = Scalar(F);
  rep_.finalRmsPx = nU_ > 0 ? Scalar(std::sqrt(sumSq / nU_)) : Scalar(0);
  rep_.lambda = lambda;
  return rep_;
}

/// Levenberg–Marquardt bundle adjustment of the file comment; optimises `problem` in place.
/// Throws hawor::Error for malformed input (indices out of range, non-finite values, negative
/// weights, flag vectors of the wrong size, bad options).
template <typename Scalar>
BAReport<Scalar> bundleAdjust(BAProblem<Scalar>& problem, const BAOptions<Scalar>& opt = {}) {
  return BundleAdjuster<Scalar>(problem, opt).run();
}

}  // namespace hawor
