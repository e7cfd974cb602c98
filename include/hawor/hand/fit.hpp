// hawor/hand/fit.hpp — per-frame fit of a hand model (pose, shape, global rotation and METRIC
// camera-space translation) to 2D keypoints (pixels) and metric 3D keypoints (the MediaPipe
// landmark network's outputs, docs/design.md §4), by Levenberg–Marquardt with analytic Jacobians.
//
// Energy (every residual divided by its noise scale σ, so each term is in "σ² units"):
//   E = w2d Σ_k c_k ρ(‖π(K_k) − u_k‖²/σ_px²)                            2D keypoints, robust ρ
//     + w3d Σ_k d_k ‖(K_k − K̄) − (X_k − X̄)‖²/σ_3d²                     3D keypoints, centred
//     + Σ_j ‖s_j ∘ F_j w_j‖²/σ_pose²                                    weak prior towards zero
//     + Σ_j ‖dist(F_j w_j, [lo_j, hi_j])‖²/σ_limit²                     soft joint limits
//     + Σ_{j Fixed} ‖w_j‖²/σ_fixed²  + ‖β‖²/σ_shape²                    unobservable joints, shape
//     + ‖log(R_prevᵀR_0)‖²/σ_tr² + ‖t − t_prev‖²/σ_tt² + Σ_j‖w_j − w_j,prev‖²/σ_tp²
//       + ‖β − β_prev‖²/σ_ts²                                           temporal (previous frame)
// K = the model's keypoints (hand/keypoint_jacobian.hpp), π the pinhole projection, c_k and d_k
// the 2D / 3D confidences, K̄ and X̄ the d-weighted centroids (the 3D landmarks have an unknown
// origin, so only their shape counts), F_j, s_j, lo_j, hi_j the anatomical frame, prior scales
// and ranges of hand/joint_limits.hpp, ρ a robust loss (geometry/robust_loss.hpp, IRLS; Cauchy
// by default, so that a few wrong keypoints do not drag the weakly observed depth).
// Parameters: [right increment of R_0 (3), t (3), joint axis-angles (3(J−1)), β (B)].
//
// Cold start (no previous frame): (1) R_0 from a similarity (Umeyama) fit of the model's rest
// palm keypoints (wrist and finger MCPs) to the 3D landmarks; (2) metric PnP of the 3D landmarks
// onto the 2D keypoints (geometry/pnp.hpp; the landmarks are metric and camera-aligned, so the
// translation that projects them onto the pixels is metric: the depth comes from the hand's
// size); (3) swing-only inverse kinematics: each finger bone turned onto the landmarks' bone
// direction, root to tip; (4) t places the model's palm centroid on the landmarks'; (5) LM.
// Without 3D landmarks, (1)+(2) become a rotation-and-translation PnP of the rest palm from 24
// starting orientations. Warm start: from the previous solution; when its median reprojection
// error ends above HandFitOptions::coldRetryPx a cold fit is run too and the lower energy kept.
//
// Solver: LM (Nielsen's damping) on the normal equations, assembled per keypoint over the
// Jacobian columns that are non-zero for it, solved by an unblocked Cholesky factorisation.
//
// Thread-safety: a HandFitter owns its workspace (no allocation per LM iteration, and none per
// frame once sized): use one per thread / per hand.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/alignment.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/pnp.hpp"
#include "hawor/geometry/robust_loss.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/geometry/so3.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/hand/joint_limits.hpp"
#include "hawor/hand/keypoint_jacobian.hpp"

namespace hawor {

/// One hand's detections in one frame. K = the model's keypoint count (21 in MediaPipe order).
template <typename Scalar>
struct HandObservation {
  Pixels<Scalar> keypoints2d;   ///< (K,2) pixels (docs/design.md §2)
  VecX<Scalar> confidence2d;    ///< (K) in [0,1]; empty = all 1; 0 = not used
  Points3<Scalar> keypoints3d;  ///< (K,3) metres, camera-aligned axes, any origin; may be empty
  VecX<Scalar> confidence3d;    ///< (K) in [0,1]; empty = all 1; 0 = not used
};

/// Weights and scales of the energy (file comment) and solver settings. A σ that is <= 0 or
/// infinite switches its term off.
template <typename Scalar>
struct HandFitOptions {
  Scalar weight2d = Scalar(1);
  Scalar sigmaPx = Scalar(2);         ///< 2D keypoint noise (pixels)
  Scalar weight3d = Scalar(1);
  Scalar sigma3d = Scalar(0.008);     ///< 3D keypoint noise (metres)
  /// Robust loss on the 2D residuals. Cauchy by default: a wrong keypoint's pull vanishes (Huber's
  /// stays bounded but non-zero, and the depth, weakly constrained by the pixels, follows it).
  RobustLoss loss = RobustLoss::Cauchy;
  Scalar robustScale = Scalar(2.5);   ///< loss scale in units of σ_px
  Scalar sigmaPose = Scalar(1.5);     ///< weak zero prior on the anatomical angles (radians)
  Scalar sigmaLimit = Scalar(0.05);   ///< soft joint limits (radians beyond a bound)
  Scalar sigmaFixed = Scalar(0.01);   ///< joints that move no keypoint (radians)
  Scalar sigmaShape = Scalar(1);      ///< shape prior (β units; MANO's β are unit-variance PCA weights)
  Scalar sigmaTemporalRot = Scalar(0.2);     ///< radians per frame
  Scalar sigmaTemporalTransl = Scalar(0.03);  ///< metres per frame
  Scalar sigmaTemporalPose = Scalar(0.3);    ///< radians per frame
  Scalar sigmaTemporalShape = Scalar(0.05);  ///< β units per frame
  bool fitShape = true;        ///< estimate β (models with B > 0); else β = the previous / zero
  bool warmStart = true;       ///< start from the previous frame when one is given
  bool refinePnPRotation = false;  ///< let the cold-start PnP rotate the 3D landmarks too
  int maxIterations = 40;      ///< LM iterations, cold start
  int maxIterationsWarm = 15;  ///< LM iterations, warm start
  Scalar functionTolerance = Scalar(1e-4);  ///< stop when the relative energy decrease is below
  Scalar stepTolerance = Scalar(1e-7);      ///< stop when the step norm is below
  /// Warm fits whose MEDIAN keypoint error ends above this (pixels) are redone from a cold start
  /// (the median ignores a few wrong keypoints; a lost track moves most of them).
  Scalar coldRetryPx = Scalar(8);
};

template <typename Scalar>
struct HandFitResult {
  HandPose<Scalar> pose;         ///< camera-frame pose (transl in metres, docs/design.md §3 convention)
  Points3<Scalar> keypoints;     ///< (K,3) fitted keypoints, camera frame, metres
  Scalar cost = Scalar(0);       ///< final energy E
  int iterations = 0;            ///< LM iterations (of the fit that was kept)
  Scalar reprojRmsPx = Scalar(0);  ///< RMS pixel error over keypoints with c_k > 0
  Scalar reprojMedianPx = Scalar(0);  ///< median pixel error over keypoints with c_k > 0
  Scalar rms3d = Scalar(0);        ///< RMS centred 3D error (metres) over keypoints with d_k > 0
  bool converged = false;        ///< a tolerance was met before the iteration limit
  bool warmStarted = false;      ///< started from the previous frame (and kept that result)
};

namespace hand_detail {

/// Solves A x = b for symmetric positive definite A by an in-place right-looking Cholesky
/// factorisation of A's lower triangle (A is overwritten; its upper triangle is not read).
/// Unblocked: for the ~60×60 systems of the hand fit it beats a blocked factorisation, and it
/// allocates nothing. Returns false when A is not (numerically) positive definite.
template <typename Scalar>
bool choleskySolve(MatX<Scalar>& A, const VecX<Scalar>& b, VecX<Scalar>& x) {
  using std::sqrt;
  const Eigen::Index n = A.rows();
  Scalar* a = A.data();
  for (Eigen::Index k = 0; k < n; ++k) {
    Scalar* ck = a + k * n;
    const Scalar d = ck[k];
    if (!(d > Scalar(0)) || !std::isfinite(d)) return false;
    const Scalar s = sqrt(d);
    ck[k] = s;
    const Scalar inv = Scalar(1) / s;
    for (Eigen::Index i = k + 1; i < n; ++i) ck[i] *= inv;
    for (Eigen::Index j = k + 1; j < n; ++j) {
      Scalar* __restrict cj = a + j * n;
      const Scalar* __restrict ckr = ck;
      const Scalar f = ckr[j];
      for (Eigen::Index i = j; i < n; ++i) cj[i] -= ckr[i] * f;
    }
  }
  // L y = b, then Lᵀ x = y.
  x = b;
  Scalar* y = x.data();
  for (Eigen::Index k = 0; k < n; ++k) {
    const Scalar* ck = a + k * n;
    y[k] /= ck[k];
    const Scalar f = y[k];
    for (Eigen::Index i = k + 1; i < n; ++i) y[i] -= ck[i] * f;
  }
  for (Eigen::Index k = n - 1; k >= 0; --k) {
    const Scalar* ck = a + k * n;
    Scalar s = y[k];
    for (Eigen::Index i = k + 1; i < n; ++i) s -= ck[i] * y[i];
    y[k] = s / ck[k];
  }
  return true;
}

}  // namespace hand_detail

template <typename Scalar>
class HandFitter {
 public:
  /// Copies what it needs from a prepared model; joint limits from the model's rest geometry.
  explicit HandFitter(const HandModel<Scalar>& model)
      : HandFitter(model, JointLimits<Scalar>::fromModel(model)) {}

  HandFitter(const HandModel<Scalar>& model, const JointLimits<Scalar>& limits) : km_(model), limits_(limits) {
    if (limits_.numJoints() != km_.J) {
      throw Error("hand fit: joint limits for " + std::to_string(limits_.numJoints()) + " joints, the model has " +
                  std::to_string(km_.J));
    }
    const int K = km_.K, P = km_.layout.size(), J = km_.J;
    cur_.resize(J, km_.B);
    trial_.resize(J, km_.B);
    best_.resize(J, km_.B);
    kp_.resize(K, 3);
    jk_.resize(3 * K, P);
    jm_.resize(3, P);
    mc_.resize(static_cast<std::size_t>(3 * P));
    H_.resize(P, P);
    g_.resize(P);
    A_.resize(P, P);
    delta_.resize(P);
    hd_.resize(P);
    w2_.resize(K);
    errs_.resize(static_cast<std::size_t>(K));
    w3_.resize(K);
    X3_.resize(K, 3);
    // Rest keypoints (zero pose and shape, identity rotation, zero translation).
    Points3<Scalar> wz = Points3<Scalar>::Zero(J - 1, 3);
    VecX<Scalar> bz = VecX<Scalar>::Zero(km_.B);
    evaluateHandKeypoints(km_, Mat3<Scalar>(Mat3<Scalar>::Identity()), wz, bz, Vec3<Scalar>(Vec3<Scalar>::Zero()),
                          kws_, restKp_);
    // Non-zero Jacobian columns per keypoint, as ascending runs [first, second): root and
    // translation, the joints that move it (strict ancestors of a joint keypoint; for a tip vertex
    // the joints of its skinning weights and their ancestors, or every joint with pose
    // correctives), the shape coefficients.
    kpRunStart_.assign(1, 0);
    for (int k = 0; k < K; ++k) {
      std::vector<unsigned char> active(static_cast<std::size_t>(P), 0);
      for (int c = 0; c < 6; ++c) active[static_cast<std::size_t>(c)] = 1;
      for (int b = 0; b < km_.B; ++b) active[static_cast<std::size_t>(km_.layout.betas() + b)] = 1;
      auto markJoint = [&](int j) {
        for (int c = 0; c < 3; ++c) active[static_cast<std::size_t>(km_.layout.joint(j) + c)] = 1;
      };
      const int q = km_.kpJoint[static_cast<std::size_t>(k)];
      if (q >= 0) {
        for (int a = km_.parents[static_cast<std::size_t>(q)]; a > 0; a = km_.parents[static_cast<std::size_t>(a)]) markJoint(a);
      } else {
        const int t = km_.kpTip[static_cast<std::size_t>(k)];
        for (int s = km_.tipSkinStart[static_cast<std::size_t>(t)]; s < km_.tipSkinStart[static_cast<std::size_t>(t) + 1]; ++s)
          for (int a = km_.tipSkinJoint[static_cast<std::size_t>(s)]; a > 0; a = km_.parents[static_cast<std::size_t>(a)]) markJoint(a);
        if (km_.hasPosedirs)
          for (int j = 1; j < J; ++j) markJoint(j);
      }
      for (int c = 0; c < P;) {
        if (!active[static_cast<std::size_t>(c)]) {
          ++c;
          continue;
        }
        int e = c;
        while (e < P && active[static_cast<std::size_t>(e)]) ++e;
        kpRuns_.push_back({c, e});
        c = e;
      }
      kpRunStart_.push_back(static_cast<int>(kpRuns_.size()));
    }
    if (K == 21) {
      palm_ = {0, 5, 9, 13, 17};
    } else {
      for (int k = 0; k < K; ++k) palm_.push_back(k);
    }
    // Finger chains for the swing IK: (joint, keypoint, next keypoint) in root-to-tip order.
    if (K == 21) {
      for (int finger = 0; finger < 5; ++finger) {
        for (int pos = 0; pos < 3; ++pos) {
          const int k = 1 + 4 * finger + pos;
          const int j = km_.kpJoint[static_cast<std::size_t>(k)];
          if (j > 0 && limits_.limited(j)) ikChain_.push_back({j, k, k + 1});
        }
      }
      std::sort(ikChain_.begin(), ikChain_.end(), [](const IkLink& a, const IkLink& b) { return a.joint < b.joint; });
    }
  }

  const JointLimits<Scalar>& limits() const { return limits_; }
  const HandKeypointModel<Scalar>& keypointModel() const { return km_; }
  /// Keypoints of the zero pose (identity rotation, zero translation and shape).
  const Points3<Scalar>& restKeypoints() const { return restKp_; }

  /// Fits one frame (file comment). `previous`: the previous frame's solution for the same hand
  /// (warm start and temporal terms), or nullptr. Throws hawor::Error on inconsistent input
  /// (sizes, non-finite values, no usable 2D keypoint, a cold start without 3 usable keypoints).
  HandFitResult<Scalar> fit(const HandObservation<Scalar>& obs, const PinholeCamera<Scalar>& cam,
                            const HandFitOptions<Scalar>& opt = {}, const HandPose<Scalar>* previous = nullptr) {
    setup(obs, cam, opt, previous);
    HandFitResult<Scalar> res;
    bool warm = false;
    if (previous && opt.warmStart) {
      cur_.fromPose(*previous, km_.B);
      warm = true;
    } else {
      coldInit(obs, cam, opt);
    }
    Stats st = solve(warm ? opt.maxIterationsWarm : opt.maxIterations);
    if (warm && st.medianPx > opt.coldRetryPx) {
      best_.copyFrom(cur_);
      const Stats warmStats = st;
      coldInit(obs, cam, opt);
      st = solve(opt.maxIterations);
      if (warmStats.cost <= st.cost) {
        cur_.copyFrom(best_);
        st = warmStats;
      } else {
        warm = false;
      }
    }
    res.pose = zeroPose();
    cur_.toPose(res.pose);
    evaluateHandKeypoints(km_, cur_.R0, cur_.w, cur_.beta, cur_.t, kws_, res.keypoints);
    res.cost = st.cost;
    res.iterations = st.iterations;
    res.converged = st.converged;
    res.reprojRmsPx = st.rmsPx;
    res.reprojMedianPx = st.medianPx;
    res.rms3d = st.rms3d;
    res.warmStarted = warm;
    return res;
  }

  /// The cold-start initialisation alone (steps 1–4 of the file comment), for inspection.
  HandPose<Scalar> initialise(const HandObservation<Scalar>& obs, const PinholeCamera<Scalar>& cam,
                              const HandFitOptions<Scalar>& opt = {}) {
    setup(obs, cam, opt, nullptr);
    coldInit(obs, cam, opt);
    HandPose<Scalar> p = zeroPose();
    cur_.toPose(p);
    return p;
  }

  /// The energy of `pose` for this observation (the fit's objective), for tests and diagnostics.
  Scalar energy(const HandPose<Scalar>& pose, const HandObservation<Scalar>& obs, const PinholeCamera<Scalar>& cam,
                const HandFitOptions<Scalar>& opt = {}, const HandPose<Scalar>* previous = nullptr) {
    setup(obs, cam, opt, previous);
    trial_.fromPose(pose, km_.B);
    return evaluate(trial_, false);
  }

  /// Residuals r and Jacobian ∂r/∂parameters of the whole energy at `pose` (E = ‖r‖² with IRLS
  /// weights frozen at `pose`), columns as HandParamLayout; for tests of the analytic Jacobians.
  void residuals(const HandPose<Scalar>& pose, const HandObservation<Scalar>& obs, const PinholeCamera<Scalar>& cam,
                 const HandFitOptions<Scalar>& opt, const HandPose<Scalar>* previous, VecX<Scalar>& r,
                 MatX<Scalar>& Jr) {
    setup(obs, cam, opt, previous);
    trial_.fromPose(pose, km_.B);
    collectResiduals_ = true;
    rAll_.clear();
    jAll_.clear();
    evaluate(trial_, true);
    collectResiduals_ = false;
    const int P = km_.layout.size();
    const int n = static_cast<int>(rAll_.size());
    r.resize(n);
    Jr.resize(n, P);
    for (int i = 0; i < n; ++i) {
      r(i) = rAll_[static_cast<std::size_t>(i)];
      for (int c = 0; c < P; ++c) Jr(i, c) = jAll_[static_cast<std::size_t>(i) * static_cast<std::size_t>(P) + static_cast<std::size_t>(c)];
    }
  }

  /// The Gauss–Newton normal equations H = JᵀJ (full, symmetric) and g = Jᵀr at `pose` that the
  /// solver assembles (IRLS weights at `pose`), for tests against residuals().
  void normalEquations(const HandPose<Scalar>& pose, const HandObservation<Scalar>& obs,
                       const PinholeCamera<Scalar>& cam, const HandFitOptions<Scalar>& opt,
                       const HandPose<Scalar>* previous, MatX<Scalar>& H, VecX<Scalar>& g) {
    setup(obs, cam, opt, previous);
    trial_.fromPose(pose, km_.B);
    evaluate(trial_, true);
    H = H_.template selfadjointView<Eigen::Lower>();
    g = g_;
  }

 private:
  struct State {
    Mat3<Scalar> R0 = Mat3<Scalar>::Identity();
    Vec3<Scalar> t = Vec3<Scalar>::Zero();
    Points3<Scalar> w;
    VecX<Scalar> beta;
    void resize(int J, int B) {
      w = Points3<Scalar>::Zero(J - 1, 3);
      beta = VecX<Scalar>::Zero(B);
    }
    void copyFrom(const State& o) {
      R0 = o.R0;
      t = o.t;
      w = o.w;
      beta = o.beta;
    }
    void fromPose(const HandPose<Scalar>& p, int B) {
      if (p.handPose.rows() != w.rows() || p.handPose.cols() != 3) {
        throw Error("hand fit: pose has " + std::to_string(p.handPose.rows()) + " joint rotations, the model has " +
                    std::to_string(w.rows()));
      }
      if (p.betas.size() > B) throw Error("hand fit: pose has more shape coefficients than the model");
      if (!p.rot.allFinite() || !p.trans.allFinite() || !p.handPose.allFinite() || !p.betas.allFinite()) {
        throw Error("hand fit: pose is not finite");
      }
      R0 = axisAngleToMatrix(p.rot);
      t = p.trans;
      w = p.handPose;
      beta.setZero();
      beta.head(p.betas.size()) = p.betas;
    }
    void toPose(HandPose<Scalar>& p) const {
      p.rot = matrixToAxisAngle(R0);
      p.trans = t;
      p.handPose = w;
      p.betas = beta;
    }
  };
  struct Stats {
    Scalar cost = Scalar(0), rmsPx = Scalar(0), medianPx = Scalar(0), rms3d = Scalar(0);
    int iterations = 0;
    bool converged = false;
  };
  struct IkLink {
    int joint, kp, next;
  };
  HandPose<Scalar> zeroPose() const {
    HandPose<Scalar> p;
    p.handPose = Points3<Scalar>::Zero(km_.J - 1, 3);
    p.betas = VecX<Scalar>::Zero(km_.B);
    return p;
  }

  static Scalar invSq(Scalar sigma) {
    return (sigma > Scalar(0) && std::isfinite(sigma)) ? Scalar(1) / (sigma * sigma) : Scalar(0);
  }

  // Validates the input and caches weights and the centred 3D landmarks.
  void setup(const HandObservation<Scalar>& obs, const PinholeCamera<Scalar>& cam, const HandFitOptions<Scalar>& opt,
             const HandPose<Scalar>* previous) {
    const int K = km_.K;
    const std::string m = "hand fit: ";
    if (obs.keypoints2d.rows() != K) {
      throw Error(m + std::to_string(obs.keypoints2d.rows()) + " 2D keypoints, the model has " + std::to_string(K));
    }
    if (!obs.keypoints2d.allFinite()) throw Error(m + "2D keypoints are not finite");
    if (obs.confidence2d.size() != 0 && obs.confidence2d.size() != K) {
      throw Error(m + std::to_string(obs.confidence2d.size()) + " 2D confidences for " + std::to_string(K) + " keypoints");
    }
    const bool has3d = obs.keypoints3d.rows() > 0;
    if (has3d && obs.keypoints3d.rows() != K) {
      throw Error(m + std::to_string(obs.keypoints3d.rows()) + " 3D keypoints, the model has " + std::to_string(K));
    }
    if (has3d && !obs.keypoints3d.allFinite()) throw Error(m + "3D keypoints are not finite");
    if (obs.confidence3d.size() != 0 && obs.confidence3d.size() != K) {
      throw Error(m + std::to_string(obs.confidence3d.size()) + " 3D confidences for " + std::to_string(K) + " keypoints");
    }
    cam.validate();
    if (!(opt.sigmaPx > Scalar(0)) || !(opt.robustScale > Scalar(0))) {
      throw Error(m + "sigmaPx and robustScale must be > 0");
    }
    if (previous && (previous->handPose.rows() != km_.J - 1 || previous->betas.size() > km_.B)) {
      throw Error(m + "previous pose does not match the model");
    }
    int n2 = 0;
    for (int k = 0; k < K; ++k) {
      const Scalar c = obs.confidence2d.size() ? obs.confidence2d(k) : Scalar(1);
      if (!std::isfinite(c) || c < Scalar(0)) throw Error(m + "2D confidences must be finite and >= 0");
      w2_(k) = c;
      n2 += c > Scalar(0);
      const Scalar d = has3d ? (obs.confidence3d.size() ? obs.confidence3d(k) : Scalar(1)) : Scalar(0);
      if (!std::isfinite(d) || d < Scalar(0)) throw Error(m + "3D confidences must be finite and >= 0");
      w3_(k) = d;
    }
    if (n2 == 0) throw Error(m + "no 2D keypoint with confidence > 0");
    sum3_ = w3_.sum();
    n3_ = 0;
    for (int k = 0; k < K; ++k) n3_ += w3_(k) > Scalar(0);
    if (n3_ < 3) sum3_ = Scalar(0);  // too few landmarks for a shape term
    Vec3<Scalar> mean = Vec3<Scalar>::Zero();
    if (sum3_ > Scalar(0)) {
      for (int k = 0; k < K; ++k) mean += w3_(k) * obs.keypoints3d.row(k).transpose();
      mean /= sum3_;
      for (int k = 0; k < K; ++k) X3_.row(k) = obs.keypoints3d.row(k) - mean.transpose();
    }
    obs_ = &obs;
    cam_ = cam;
    opt_ = opt;
    prev_ = previous;
    if (previous) {
      prevR_ = axisAngleToMatrix(previous->rot);
      prevBeta_.setZero(km_.B);
      prevBeta_.head(previous->betas.size()) = previous->betas;
    }
  }

  // ---- energy, residuals and normal equations ------------------------------------------------

  // Energy of `s`; with `build`, also the lower triangle of H = JᵀJ and g = Jᵀr (IRLS weights
  // at s). The data terms are accumulated per keypoint: with W_k = Σ (weights)·(∂r/∂K_k)ᵀ(∂r/∂K_k)
  // (3×3: the 2D term's w·J_πᵀJ_π plus the 3D term's c·I) and J_k = ∂K_k/∂x,
  //   H = Σ_k J_kᵀ W_k J_k − C·J̄ᵀJ̄,  g = Σ_k J_kᵀ (w J_πᵀ e_k + c r_k),
  // where J̄ = Σ c_k J_k / C is the centroid's Jacobian (C = Σ c_k): the centred 3D residuals
  // sum to zero, so Σ c_k (J_k − J̄)ᵀ(J_k − J̄) = Σ c_k J_kᵀJ_k − C J̄ᵀJ̄ and the J̄ᵀr term vanishes.
  // Each J_k is non-zero only on its keypoint's columns (the root, its ancestors, β; every joint
  // for a tip vertex with pose correctives), so each product runs over those columns only.
  Scalar evaluate(const State& s, bool build) {
    const int K = km_.K, J = km_.J, B = km_.B;
    const HandParamLayout& L = km_.layout;
    const int P = L.size();
    evaluateHandKeypoints(km_, s.R0, s.w, s.beta, s.t, kws_, kp_, build ? &jk_ : nullptr);
    Scalar E = Scalar(0);
    if (build) {
      H_.setZero();
      g_.setZero();
    }
    const Scalar is2 = invSq(opt_.sigmaPx);
    const Scalar k2 = opt_.robustScale;
    const bool use3d = sum3_ > Scalar(0) && opt_.weight3d > Scalar(0) && invSq(opt_.sigma3d) > Scalar(0);
    const Scalar is3 = invSq(opt_.sigma3d);
    Vec3<Scalar> mean = Vec3<Scalar>::Zero();
    Scalar C3 = Scalar(0);
    if (use3d) {
      for (int k = 0; k < K; ++k) mean += w3_(k) * kp_.row(k).transpose();
      mean /= sum3_;
      if (build) {
        jm_.setZero();
        for (int k = 0; k < K; ++k)
          if (w3_(k) > Scalar(0)) jm_.noalias() += (w3_(k) / sum3_) * jk_.middleRows(3 * k, 3);
      }
    }
    for (int k = 0; k < K; ++k) {
      Mat3<Scalar> W = Mat3<Scalar>::Zero();
      Vec3<Scalar> gk = Vec3<Scalar>::Zero();
      bool any = false;
      const Vec3<Scalar> p = kp_.row(k).transpose();
      // 2D keypoint, robust.
      const Scalar c2 = opt_.weight2d * w2_(k);
      if (c2 > Scalar(0)) {
        if (p(2) < Scalar(1e-3)) {
          E += c2 * robustCost(opt_.loss, Scalar(1e8), k2);  // behind the camera: reject such steps
        } else {
          Eigen::Matrix<Scalar, 2, 3> Jp = Eigen::Matrix<Scalar, 2, 3>::Zero();
          const Vec2<Scalar> e = cam_.project(p, build ? &Jp : nullptr) - obs_->keypoints2d.row(k).transpose();
          const Scalar sq = e.squaredNorm() * is2;
          E += c2 * robustCost(opt_.loss, sq, k2);
          if (build) {
            const Scalar w = c2 * is2 * robustWeight(opt_.loss, sq, k2);
            W.noalias() += w * (Jp.transpose() * Jp);
            gk.noalias() += w * (Jp.transpose() * e);
            any = true;
            if (collectResiduals_) {
              const Scalar sw = std::sqrt(w);
              for (int a = 0; a < 2; ++a) {
                const Eigen::Matrix<Scalar, 1, Eigen::Dynamic> row = sw * (Jp.row(a) * jk_.middleRows(3 * k, 3));
                pushResidual(sw * e(a), row);
              }
            }
          }
        }
      }
      // 3D keypoint, centred.
      if (use3d && w3_(k) > Scalar(0)) {
        const Scalar c = opt_.weight3d * w3_(k) * is3;
        const Vec3<Scalar> r = p - mean - X3_.row(k).transpose();
        E += c * r.squaredNorm();
        if (build) {
          W.diagonal().array() += c;
          gk += c * r;
          C3 += c;
          any = true;
          if (collectResiduals_) {
            const Scalar sw = std::sqrt(c);
            for (int a = 0; a < 3; ++a) {
              const Eigen::Matrix<Scalar, 1, Eigen::Dynamic> row = sw * (jk_.row(3 * k + a) - jm_.row(a));
              pushResidual(sw * r(a), row);
            }
          }
        }
      }
      if (build && any) accumulateKeypoint(k, W, gk);
    }
    if (build && C3 > Scalar(0)) {
      // − C·J̄ᵀJ̄ on the lower triangle.
      const Scalar* __restrict q0 = jm_.data();
      const Scalar* __restrict q1 = q0 + P;
      const Scalar* __restrict q2 = q1 + P;
      for (int b = 0; b < P; ++b) {
        const Scalar a0 = C3 * q0[b], a1 = C3 * q1[b], a2 = C3 * q2[b];
        Scalar* __restrict Hcol = H_.data() + static_cast<Eigen::Index>(b) * P;
        for (int a = b; a < P; ++a) Hcol[a] -= q0[a] * a0 + q1[a] * a1 + q2[a] * a2;
      }
    }
    // Joint priors, limits, temporal terms: residuals linear in w_j, added as 3×3 blocks.
    const Scalar isPose = invSq(opt_.sigmaPose), isLim = invSq(opt_.sigmaLimit), isFix = invSq(opt_.sigmaFixed);
    const Scalar isTp = prev_ ? invSq(opt_.sigmaTemporalPose) : Scalar(0);
    for (int j = 1; j < J; ++j) {
      const int c0 = L.joint(j);
      const Vec3<Scalar> w = s.w.row(j - 1).transpose();
      const Mat3<Scalar>& F = limits_.frames[static_cast<std::size_t>(j)];
      const JointRole role = limits_.roles[static_cast<std::size_t>(j)];
      if (role == JointRole::Fixed) {
        addLinear(E, build, c0, Mat3<Scalar>::Identity(), w, isFix);
      } else {
        const Vec3<Scalar> sc = limits_.ranges[static_cast<std::size_t>(j)].priorScale;
        const Mat3<Scalar> SF = sc.asDiagonal() * F;
        addLinear(E, build, c0, SF, Vec3<Scalar>(SF * w), isPose);
        if (limits_.limited(j) && isLim > Scalar(0)) {
          const Vec3<Scalar> v = limits_.violation(j, w);
          for (int a = 0; a < 3; ++a) {
            if (v(a) == Scalar(0)) continue;
            addLinearRow(E, build, c0, F.row(a), v(a), isLim);
          }
        }
      }
      if (isTp > Scalar(0)) {
        addLinear(E, build, c0, Mat3<Scalar>::Identity(), Vec3<Scalar>(w - prev_->handPose.row(j - 1).transpose()),
                  isTp);
      }
    }
    const bool shapeFree = opt_.fitShape && B > 0;
    if (shapeFree) {
      const Scalar isS = invSq(opt_.sigmaShape);
      const Scalar isTs = prev_ ? invSq(opt_.sigmaTemporalShape) : Scalar(0);
      for (int b = 0; b < B; ++b) {
        const int c = L.betas() + b;
        if (isS > Scalar(0)) addScalar(E, build, c, s.beta(b), isS);
        if (isTs > Scalar(0)) addScalar(E, build, c, s.beta(b) - prevBeta_(b), isTs);
      }
    }
    if (prev_) {
      const Scalar isTr = invSq(opt_.sigmaTemporalRot), isTt = invSq(opt_.sigmaTemporalTransl);
      if (isTr > Scalar(0)) {
        const Mat3<Scalar> dR = prevR_.transpose() * s.R0;
        const Vec3<Scalar> phi = matrixToAxisAngle(dR);
        // log(R_prevᵀ R_0 exp(δ)) ≈ φ + J_r(φ)⁻¹ δ
        const Mat3<Scalar> Jinv = SO3<Scalar>::rightJacobianInverse(phi);
        addLinear(E, build, HandParamLayout::rot, Jinv, phi, isTr);
      }
      if (isTt > Scalar(0)) {
        addLinear(E, build, HandParamLayout::transl, Mat3<Scalar>::Identity(), Vec3<Scalar>(s.t - prev_->trans), isTt);
      }
    }
    if (build && !shapeFree && B > 0) {
      // Shape held fixed: decouple its columns (identity block, zero gradient).
      H_.middleRows(L.betas(), B).setZero();
      H_.middleCols(L.betas(), B).setZero();
      for (int b = 0; b < B; ++b) H_(L.betas() + b, L.betas() + b) = Scalar(1);
      g_.segment(L.betas(), B).setZero();
    }
    return E;
  }

  // H += J_kᵀ W J_k (lower triangle), g += J_kᵀ gk over keypoint k's non-zero column runs.
  // The inner loops run down contiguous columns of H and rows of the row-major J (vectorised).
  void accumulateKeypoint(int k, const Mat3<Scalar>& W, const Vec3<Scalar>& gk) {
    const int P = km_.layout.size();
    const Scalar* __restrict j0 = jk_.data() + static_cast<Eigen::Index>(3 * k) * P;
    const Scalar* __restrict j1 = j0 + P;
    const Scalar* __restrict j2 = j1 + P;
    Scalar* __restrict m0 = mc_.data();
    Scalar* __restrict m1 = m0 + P;
    Scalar* __restrict m2 = m1 + P;
    const int r0 = kpRunStart_[static_cast<std::size_t>(k)], r1 = kpRunStart_[static_cast<std::size_t>(k) + 1];
    Scalar* g = g_.data();
    for (int r = r0; r < r1; ++r) {
      for (int c = kpRuns_[static_cast<std::size_t>(r)].first; c < kpRuns_[static_cast<std::size_t>(r)].second; ++c) {
        m0[c] = W(0, 0) * j0[c] + W(0, 1) * j1[c] + W(0, 2) * j2[c];
        m1[c] = W(1, 0) * j0[c] + W(1, 1) * j1[c] + W(1, 2) * j2[c];
        m2[c] = W(2, 0) * j0[c] + W(2, 1) * j1[c] + W(2, 2) * j2[c];
        g[c] += j0[c] * gk(0) + j1[c] * gk(1) + j2[c] * gk(2);
      }
    }
    for (int rb = r0; rb < r1; ++rb) {
      for (int b = kpRuns_[static_cast<std::size_t>(rb)].first; b < kpRuns_[static_cast<std::size_t>(rb)].second; ++b) {
        const Scalar a0 = m0[b], a1 = m1[b], a2 = m2[b];
        Scalar* __restrict Hcol = H_.data() + static_cast<Eigen::Index>(b) * P;
        for (int ra = rb; ra < r1; ++ra) {
          const int e = kpRuns_[static_cast<std::size_t>(ra)].second;
          for (int a = std::max(b, kpRuns_[static_cast<std::size_t>(ra)].first); a < e; ++a) {
            Hcol[a] += j0[a] * a0 + j1[a] * a1 + j2[a] * a2;
          }
        }
      }
    }
  }

  // r = A·x-linear residual block of 3 rows with value `r3` and Jacobian A (3×3) at columns c0,
  // weight is (1/σ²): E += is‖r‖², H += is AᵀA, g += is Aᵀr.
  void addLinear(Scalar& E, bool build, int c0, const Mat3<Scalar>& A, const Vec3<Scalar>& r3, Scalar is) {
    if (!(is > Scalar(0))) return;
    E += is * r3.squaredNorm();
    if (!build) return;
    H_.template block<3, 3>(c0, c0) += is * (A.transpose() * A);
    g_.template segment<3>(c0) += is * (A.transpose() * r3);
    if (collectResiduals_) {
      const Scalar sq = std::sqrt(is);
      for (int a = 0; a < 3; ++a) {
        Eigen::Matrix<Scalar, 1, Eigen::Dynamic> row = Eigen::Matrix<Scalar, 1, Eigen::Dynamic>::Zero(km_.layout.size());
        row.template segment<3>(c0) = sq * A.row(a);
        pushResidual(sq * r3(a), row);
      }
    }
  }
  template <typename RowT>
  void addLinearRow(Scalar& E, bool build, int c0, const RowT& a, Scalar r, Scalar is) {
    E += is * r * r;
    if (!build) return;
    const Vec3<Scalar> av = a.transpose();
    H_.template block<3, 3>(c0, c0) += is * (av * av.transpose());
    g_.template segment<3>(c0) += is * r * av;
    if (collectResiduals_) {
      Eigen::Matrix<Scalar, 1, Eigen::Dynamic> row = Eigen::Matrix<Scalar, 1, Eigen::Dynamic>::Zero(km_.layout.size());
      row.template segment<3>(c0) = std::sqrt(is) * av.transpose();
      pushResidual(std::sqrt(is) * r, row);
    }
  }
  void addScalar(Scalar& E, bool build, int c, Scalar r, Scalar is) {
    E += is * r * r;
    if (!build) return;
    H_(c, c) += is;
    g_(c) += is * r;
    if (collectResiduals_) {
      Eigen::Matrix<Scalar, 1, Eigen::Dynamic> row = Eigen::Matrix<Scalar, 1, Eigen::Dynamic>::Zero(km_.layout.size());
      row(c) = std::sqrt(is);
      pushResidual(std::sqrt(is) * r, row);
    }
  }
  template <typename RowT>
  void pushResidual(Scalar r, const RowT& row) {
    rAll_.push_back(r);
    for (Eigen::Index c = 0; c < row.size(); ++c) jAll_.push_back(row(c));
  }

  // x ⊞ Δ: R_0 ← R_0 exp(Δ_rot), the rest additive.
  void applyStep(const State& from, const VecX<Scalar>& d, State& to) const {
    const HandParamLayout& L = km_.layout;
    const Vec3<Scalar> dr = d.template segment<3>(HandParamLayout::rot);
    to.R0 = from.R0 * axisAngleToMatrix(dr);
    to.t = from.t + d.template segment<3>(HandParamLayout::transl);
    for (int j = 1; j < km_.J; ++j) to.w.row(j - 1) = from.w.row(j - 1) + d.template segment<3>(L.joint(j)).transpose();
    for (int b = 0; b < km_.B; ++b) to.beta(b) = from.beta(b) + d(L.betas() + b);
  }

  // Levenberg–Marquardt from cur_ (Nielsen's damping update).
  Stats solve(int maxIterations) {
    Stats st;
    const int P = km_.layout.size();
    Scalar E = evaluate(cur_, true);
    Scalar lambda = Scalar(1e-4), nu = Scalar(2);
    for (int it = 0; it < maxIterations; ++it) {
      st.iterations = it + 1;
      bool accepted = false;
      Scalar Enew = E;
      for (int tries = 0; tries < 12 && !accepted; ++tries) {
        A_ = H_;
        for (int i = 0; i < P; ++i) A_(i, i) += lambda * std::max(H_(i, i), Scalar(1e-6)) + Scalar(1e-12);
        if (!hand_detail::choleskySolve(A_, g_, delta_)) {
          lambda *= nu;
          nu *= Scalar(2);
          continue;
        }
        delta_ = -delta_;
        if (!delta_.allFinite()) break;
        applyStep(cur_, delta_, trial_);
        Enew = evaluate(trial_, false);
        // Predicted decrease of the Gauss–Newton model ‖r + JΔ‖²: −(2Δᵀg + ΔᵀHΔ).
        hd_.noalias() = H_.template selfadjointView<Eigen::Lower>() * delta_;
        const Scalar pred = -(Scalar(2) * delta_.dot(g_) + delta_.dot(hd_));
        const Scalar rho = pred > Scalar(0) ? (E - Enew) / pred : Scalar(-1);
        if (Enew < E && rho > Scalar(0)) {
          accepted = true;
          const Scalar f = Scalar(2) * rho - Scalar(1);
          lambda *= std::max(Scalar(1) / Scalar(3), Scalar(1) - f * f * f);
          nu = Scalar(2);
        } else {
          lambda *= nu;
          nu *= Scalar(2);
        }
      }
      if (!accepted) {
        st.converged = true;  // no decrease possible from here: a (local) minimum to precision
        break;
      }
      const Scalar dE = E - Enew;
      const Scalar stepNorm = delta_.norm();
#ifdef HAWOR_FIT_TRACE
      std::printf("  it %d E %.6g -> %.6g lambda %.3g step %.3g\n", it, double(E), double(Enew), double(lambda), double(stepNorm));
#endif
      cur_.copyFrom(trial_);
      E = evaluate(cur_, true);
      if (dE <= opt_.functionTolerance * E || stepNorm <= opt_.stepTolerance) {
        st.converged = true;
        break;
      }
    }
    st.cost = E;
    // Diagnostics at the solution.
    evaluateHandKeypoints(km_, cur_.R0, cur_.w, cur_.beta, cur_.t, kws_, kp_);
    Scalar se = Scalar(0);
    int n = 0;
    for (int k = 0; k < km_.K; ++k) {
      if (!(w2_(k) > Scalar(0))) continue;
      const Vec3<Scalar> p = kp_.row(k).transpose();
      const Scalar e2 = (cam_.project(p) - obs_->keypoints2d.row(k).transpose()).squaredNorm();
      se += e2;
      errs_[static_cast<std::size_t>(n)] = e2;
      ++n;
    }
    st.rmsPx = n ? std::sqrt(se / Scalar(n)) : Scalar(0);
    if (n) {
      const auto mid = errs_.begin() + n / 2;
      std::nth_element(errs_.begin(), mid, errs_.begin() + n);
      st.medianPx = std::sqrt(*mid);
    }
    if (sum3_ > Scalar(0)) {
      Vec3<Scalar> mean = Vec3<Scalar>::Zero();
      for (int k = 0; k < km_.K; ++k) mean += w3_(k) * kp_.row(k).transpose();
      mean /= sum3_;
      Scalar s3 = Scalar(0);
      for (int k = 0; k < km_.K; ++k)
        if (w3_(k) > Scalar(0)) s3 += (kp_.row(k).transpose() - mean - X3_.row(k).transpose()).squaredNorm();
      st.rms3d = std::sqrt(s3 / Scalar(n3_));
    }
    return st;
  }

  // ---- cold start ------------------------------------------------------------------------------

  void coldInit(const HandObservation<Scalar>& obs, const PinholeCamera<Scalar>& cam, const HandFitOptions<Scalar>& opt) {
    const int K = km_.K;
    cur_.w.setZero();
    if (prev_) {
      cur_.beta = prevBeta_;
    } else {
      cur_.beta.setZero();
    }
    cur_.R0.setIdentity();
    cur_.t.setZero();
    PnPOptions<Scalar> po;
    po.loss = opt.loss == RobustLoss::None ? RobustLoss::Huber : opt.loss;
    po.sigmaPx = opt.sigmaPx;
    po.robustScale = opt.robustScale;
    // Points usable for the palm rotation: palm keypoints with 3D confidence.
    std::vector<int> palm;
    for (int k : palm_)
      if (w3_(k) > Scalar(0)) palm.push_back(k);
    const bool has3d = sum3_ > Scalar(0) && n3_ >= 3;
    if (has3d && palm.size() < 3) {
      palm.clear();
      for (int k = 0; k < K; ++k)
        if (w3_(k) > Scalar(0)) palm.push_back(k);
    }
    // Rest keypoints at the initial shape.
    evaluateHandKeypoints(km_, Mat3<Scalar>(Mat3<Scalar>::Identity()), cur_.w, cur_.beta,
                          Vec3<Scalar>(Vec3<Scalar>::Zero()), kws_, kp_);
    const Vec3<Scalar> J0 = kws_.gPos[0];
    if (has3d) {
      Points3<Scalar> src(static_cast<Eigen::Index>(palm.size()), 3), dst(static_cast<Eigen::Index>(palm.size()), 3);
      VecX<Scalar> wt(static_cast<Eigen::Index>(palm.size()));
      for (std::size_t i = 0; i < palm.size(); ++i) {
        src.row(static_cast<Eigen::Index>(i)) = kp_.row(palm[i]);
        dst.row(static_cast<Eigen::Index>(i)) = obs.keypoints3d.row(palm[i]);
        wt(static_cast<Eigen::Index>(i)) = w3_(palm[i]);
      }
      cur_.R0 = umeyama(src, dst, true, &wt).R;
      // Metric PnP of the landmarks (camera-aligned: R = I unless refined).
      Points3<Scalar> X(K, 3);
      Pixels<Scalar> uv(K, 2);
      VecX<Scalar> c(K);
      for (int k = 0; k < K; ++k) {
        X.row(k) = obs.keypoints3d.row(k);
        uv.row(k) = obs.keypoints2d.row(k);
        c(k) = (w3_(k) > Scalar(0)) ? w2_(k) : Scalar(0);
      }
      po.refineRotation = opt.refinePnPRotation;
      const PnPResult<Scalar> pr = solvePnPMetric(X, uv, &c, cam, Mat3<Scalar>(Mat3<Scalar>::Identity()), po);
      if (!pr.ok) throw Error("hand fit: cold start failed (metric PnP found no pose in front of the camera)");
      cur_.R0 = pr.R * cur_.R0;
      Y_.resize(K, 3);
      for (int k = 0; k < K; ++k) Y_.row(k) = (pr.R * obs.keypoints3d.row(k).transpose() + pr.t).transpose();
      swingIk();
      placeTranslation(palm);
    } else {
      // No 3D landmarks: rotation and translation PnP of the rest palm from 24 orientations.
      std::vector<int> pts;
      for (int k : palm_)
        if (w2_(k) > Scalar(0)) pts.push_back(k);
      if (pts.size() < 3) {
        pts.clear();
        for (int k = 0; k < K; ++k)
          if (w2_(k) > Scalar(0)) pts.push_back(k);
      }
      if (pts.size() < 3) throw Error("hand fit: cold start needs 3 keypoints with confidence > 0");
      Points3<Scalar> X(static_cast<Eigen::Index>(pts.size()), 3);
      Pixels<Scalar> uv(static_cast<Eigen::Index>(pts.size()), 2);
      VecX<Scalar> c(static_cast<Eigen::Index>(pts.size()));
      for (std::size_t i = 0; i < pts.size(); ++i) {
        X.row(static_cast<Eigen::Index>(i)) = kp_.row(pts[i]) - J0.transpose();
        uv.row(static_cast<Eigen::Index>(i)) = obs.keypoints2d.row(pts[i]);
        c(static_cast<Eigen::Index>(i)) = w2_(pts[i]);
      }
      po.refineRotation = true;
      po.maxIterations = 30;
      PnPResult<Scalar> best;
      Scalar bestRms = std::numeric_limits<Scalar>::infinity();
      const Scalar h = Constants<Scalar>::pi() / Scalar(2);
      const Vec3<Scalar> faces[6] = {Vec3<Scalar>(0, 0, 0), Vec3<Scalar>(h, 0, 0), Vec3<Scalar>(-h, 0, 0),
                                     Vec3<Scalar>(0, h, 0), Vec3<Scalar>(0, -h, 0), Vec3<Scalar>(2 * h, 0, 0)};
      for (const Vec3<Scalar>& f : faces) {
        for (int q = 0; q < 4; ++q) {
          const Mat3<Scalar> R = axisAngleToMatrix(Vec3<Scalar>(Scalar(0), Scalar(0), Scalar(q) * h)) * axisAngleToMatrix(f);
          const PnPResult<Scalar> pr = solvePnPMetric(X, uv, &c, cam, R, po);
          if (pr.ok && pr.rmsPx < bestRms) {
            bestRms = pr.rmsPx;
            best = pr;
          }
        }
      }
      if (!best.ok) throw Error("hand fit: cold start failed (no pose in front of the camera)");
      cur_.R0 = best.R;
      // p = R (x − J0) + t_pnp = R (x − J0) + J0 + transl.
      cur_.t = best.t - J0;
    }
  }

  // Swing-only IK on the camera-frame landmarks Y_: each bone (joint → next keypoint) is turned
  // by the smallest rotation that aligns it with the landmarks' bone, root to tip.
  void swingIk() {
    for (const IkLink& l : ikChain_) {
      if (!(w3_(l.kp) > Scalar(0)) || !(w3_(l.next) > Scalar(0))) continue;
      evaluateHandKeypoints(km_, cur_.R0, cur_.w, cur_.beta, cur_.t, kws_, kp_);
      const Vec3<Scalar> a = (kp_.row(l.next) - kp_.row(l.kp)).transpose();
      const Vec3<Scalar> b = (Y_.row(l.next) - Y_.row(l.kp)).transpose();
      const Scalar na = a.norm(), nb = b.norm();
      if (!(na > Scalar(0)) || !(nb > Scalar(0))) continue;
      const Vec3<Scalar> an = a / na, bn = b / nb;
      const Vec3<Scalar> axis = an.cross(bn);
      const Scalar s = axis.norm(), c = an.dot(bn);
      if (!(s > Scalar(1e-9))) continue;
      const Scalar ang = std::atan2(s, c);
      const Mat3<Scalar> Ralign = axisAngleToMatrix(Vec3<Scalar>(axis * (ang / s)));
      const std::size_t j = static_cast<std::size_t>(l.joint);
      const std::size_t p = static_cast<std::size_t>(km_.parents[j]);
      // New local rotation: Rg_pᵀ · R_align · Rg_j.
      const Mat3<Scalar> Rj = kws_.gRot[p].transpose() * Ralign * kws_.gRot[j];
      Vec3<Scalar> w = matrixToAxisAngle(Rj);
      // Keep the swing inside the joint's range (the LM refines; this only avoids a bad start).
      const JointRange<Scalar>& r = limits_.ranges[j];
      Vec3<Scalar> an3 = limits_.anatomical(l.joint, w);
      for (int q = 0; q < 3; ++q) an3(q) = std::min(std::max(an3(q), r.lo(q)), r.hi(q));
      w = limits_.axisAngle(l.joint, an3);
      cur_.w.row(l.joint - 1) = w.transpose();
    }
  }

  // t such that the model's palm centroid (current pose) lands on the landmarks' (Y_).
  void placeTranslation(const std::vector<int>& palm) {
    evaluateHandKeypoints(km_, cur_.R0, cur_.w, cur_.beta, Vec3<Scalar>(Vec3<Scalar>::Zero()), kws_, kp_);
    Vec3<Scalar> a = Vec3<Scalar>::Zero(), b = Vec3<Scalar>::Zero();
    Scalar ws = Scalar(0);
    for (int k : palm) {
      a += w3_(k) * kp_.row(k).transpose();
      b += w3_(k) * Y_.row(k).transpose();
      ws += w3_(k);
    }
    cur_.t = (b - a) / ws;
  }

  HandKeypointModel<Scalar> km_;
  JointLimits<Scalar> limits_;
  HandKeypointWorkspace<Scalar> kws_;
  State cur_, trial_, best_;
  Points3<Scalar> restKp_, kp_, X3_, Y_;
  KeypointJacobian<Scalar> jk_;
  Eigen::Matrix<Scalar, 3, Eigen::Dynamic, Eigen::RowMajor> jm_;  // ∂K̄/∂x
  MatX<Scalar> H_, A_;
  VecX<Scalar> g_, delta_, hd_, w2_, w3_, prevBeta_;
  std::vector<Scalar> mc_;                        // W·J_k of one keypoint, 3 rows of P
  std::vector<std::pair<int, int>> kpRuns_;       // non-zero Jacobian column runs per keypoint
  std::vector<int> kpRunStart_;                   // (K+1) CSR starts into kpRuns_
  std::vector<Scalar> errs_;
  std::vector<int> palm_;
  std::vector<IkLink> ikChain_;
  Scalar sum3_ = Scalar(0);
  int n3_ = 0;
  const HandObservation<Scalar>* obs_ = nullptr;
  PinholeCamera<Scalar> cam_;
  HandFitOptions<Scalar> opt_;
  const HandPose<Scalar>* prev_ = nullptr;
  Mat3<Scalar> prevR_ = Mat3<Scalar>::Identity();
  bool collectResiduals_ = false;
  std::vector<Scalar> rAll_, jAll_;
};

}  // namespace hawor
