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

  // ---- energy, residuals and normal equations (hand/fit/energy.hpp) -------------------------

  Scalar evaluate(const State& s, bool build);
  void accumulateKeypoint(int k, const Mat3<Scalar>& W, const Vec3<Scalar>& gk);
  void addLinear(Scalar& E, bool build, int c0, const Mat3<Scalar>& A, const Vec3<Scalar>& r3, Scalar is);
  template <typename RowT>
  void addLinearRow(Scalar& E, bool build, int c0, const RowT& a, Scalar r, Scalar is);
  void addScalar(Scalar& E, bool build, int c, Scalar r, Scalar is);
  template <typename RowT>
  void pushResidual(Scalar r, const RowT& row);

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

  // ---- cold start (hand/fit/cold_start.hpp) --------------------------------------------------

  void coldInit(const HandObservation<Scalar>& obs, const PinholeCamera<Scalar>& cam, const HandFitOptions<Scalar>& opt);
  void swingIk();
  void placeTranslation(const std::vector<int>& palm);


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

#include "hawor/hand/fit/cold_start.hpp"
#include "hawor/hand/fit/energy.hpp"
