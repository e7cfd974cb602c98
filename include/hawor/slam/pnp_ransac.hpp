// hawor/slam/pnp_ransac.hpp — absolute camera pose from 2D–3D correspondences with outliers:
// P3P (slam/p3p.hpp) inside adaptive MSAC (slam/ransac.hpp), then robust Levenberg–Marquardt on
// SE(3) over the inliers (refinePose), the tracking step of the SLAM.
//
// Pose: T_w_c, CAMERA-TO-WORLD (docs/design.md §2), refined by the right perturbation T_w_c ← T_w_c·exp(δ),
// exactly as a free pose of bundle_adjustment.hpp (same residual and Jacobian:
// r = π(T_w_c⁻¹·X) − uv in pixels, ∂r/∂δ = Jπ·[−I, X_c^]).
// Cost of the refinement: F = Σ_i c_i ρ(‖r_i‖²/σ²) (robust_loss.hpp; IRLS weights ρ', optional
// curvature correction as in bundle_adjustment.hpp), c_i the caller's weights (the RANSAC inlier
// mask in solvePnPRansac).
// Unlike geometry/pnp.hpp (metric hand PnP from a known rotation guess, no outliers), this solves
// the general problem without an initial guess. Pure functions, thread-safe.
#pragma once

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/robust_loss.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/slam/bundle_adjustment.hpp"
#include "hawor/slam/p3p.hpp"
#include "hawor/slam/ransac.hpp"

namespace hawor {

template <typename Scalar>
struct PoseRefineOptions {
  int maxIterations = 10;
  RobustLoss loss = RobustLoss::Huber;
  Scalar sigmaPx = Scalar(1);       ///< pixel noise scale σ
  Scalar robustScale = Scalar(2);   ///< loss scale k in units of σ
  Scalar minDepth = Scalar(1e-6);   ///< points at depth ≤ this are left out
  Scalar functionTolerance = Scalar(1e-8);  ///< stop on a relative cost decrease below this
  Scalar stepTolerance = Scalar(1e-10);     ///< stop on a step ‖δ‖ below this
  Scalar minRadialCurvature = Scalar(1);    ///< robust curvature floor (bundle_adjustment.hpp)
};

template <typename Scalar>
struct PoseRefineReport {
  Scalar initialCost = Scalar(0), finalCost = Scalar(0);
  int iterations = 0;
  int usedPoints = 0;       ///< weight > 0 and in front of the camera at the start
  bool converged = false;   ///< a tolerance was met (else the budget ran out or no progress)
};

enum class PnPStatus {
  Ok,
  TooFewPoints,      ///< fewer than 4 correspondences
  NoModel,           ///< RANSAC found no pose (degenerate data)
  NotEnoughInliers,  ///< a pose was found but with fewer than minInliers inliers
};

template <typename Scalar>
struct PnPRansacOptions {
  Scalar thresholdPx = Scalar(2.5);    ///< inlier threshold on the reprojection error
  Scalar confidence = Scalar(0.999);
  int maxIterations = 1000;
  int minIterations = 0;
  std::uint32_t seed = 0x5eedu;
  int minInliers = 6;
  bool refine = true;                  ///< robust LM on the inliers after RANSAC
  PoseRefineOptions<Scalar> refinement;
};

template <typename Scalar>
struct PnPRansacResult {
  PnPStatus status = PnPStatus::TooFewPoints;
  SE3<Scalar> T_w_c;                 ///< camera-to-world pose (valid unless TooFewPoints/NoModel)
  std::vector<char> inliers;         ///< per correspondence, reprojection error < thresholdPx
  int numInliers = 0;
  Scalar inlierRmsPx = Scalar(0);    ///< RMS reprojection error of the inliers
  int ransacIterations = 0;
  PoseRefineReport<Scalar> refinement;
  bool ok() const { return status == PnPStatus::Ok; }
};

namespace pnp_ransac_detail {

template <typename Scalar>
void checkInputs(const std::vector<Vec3<Scalar>>& X, const std::vector<Vec2<Scalar>>& uv,
                 const std::vector<Scalar>* w, const PinholeCamera<Scalar>& cam, const char* who) {
  const std::string m = std::string(who) + ": ";
  if (X.size() != uv.size()) {
    throw Error(m + std::to_string(X.size()) + " points but " + std::to_string(uv.size()) + " pixels");
  }
  if (w && w->size() != X.size()) {
    throw Error(m + std::to_string(w->size()) + " weights for " + std::to_string(X.size()) + " points");
  }
  for (std::size_t i = 0; i < X.size(); ++i) {
    if (!X[i].allFinite() || !uv[i].allFinite()) {
      throw Error(m + "correspondence " + std::to_string(i) + " is not finite");
    }
    if (w && (!((*w)[i] >= Scalar(0)) || !std::isfinite((*w)[i]))) {
      throw Error(m + "weight " + std::to_string(i) + " must be finite and >= 0");
    }
  }
  if (!(cam.fx > Scalar(0)) || !(cam.fy > Scalar(0)) || !std::isfinite(cam.fx) ||
      !std::isfinite(cam.fy) || !std::isfinite(cam.cx) || !std::isfinite(cam.cy)) {
    throw Error(m + "camera focal lengths must be finite and > 0, principal point finite");
  }
}

}  // namespace pnp_ransac_detail

/// Robust Levenberg–Marquardt refinement of T_w_c (file comment) from its current value, over the
/// correspondences with weight > 0 (weights = nullptr: all 1) in front of the camera at the start.
/// Throws hawor::Error on mismatched sizes, non-finite input or a bad camera.
template <typename Scalar>
PoseRefineReport<Scalar> refinePose(const std::vector<Vec3<Scalar>>& X,
                                    const std::vector<Vec2<Scalar>>& uv,
                                    const std::vector<Scalar>* weights,
                                    const PinholeCamera<Scalar>& cam, SE3<Scalar>& T_w_c,
                                    const PoseRefineOptions<Scalar>& opt = {}) {
  using V2 = Eigen::Matrix<Scalar, 2, 1>;
  using V3 = Eigen::Matrix<Scalar, 3, 1>;
  using M3 = Eigen::Matrix<Scalar, 3, 3>;
  using V6 = Eigen::Matrix<Scalar, 6, 1>;
  using M6 = Eigen::Matrix<Scalar, 6, 6>;
  pnp_ransac_detail::checkInputs(X, uv, weights, cam, "refinePose");
  if (!(opt.sigmaPx > Scalar(0)) || !(opt.robustScale > Scalar(0)) ||
      !(opt.minRadialCurvature > Scalar(0) && opt.minRadialCurvature <= Scalar(1))) {
    throw Error("refinePose: sigmaPx and robustScale must be > 0, minRadialCurvature in (0, 1]");
  }
  PoseRefineReport<Scalar> rep;
  const Scalar invS2 = Scalar(1) / (opt.sigmaPx * opt.sigmaPx);
  const int n = static_cast<int>(X.size());
  auto weightOf = [&](int i) { return weights ? (*weights)[static_cast<std::size_t>(i)] : Scalar(1); };
  SE3<Scalar> Tcw = T_w_c.inverse();
  M3 R = Tcw.rotationMatrix();
  V3 t = Tcw.translation();
  std::vector<int> used;
  used.reserve(X.size());
  for (int i = 0; i < n; ++i) {
    if (!(weightOf(i) > Scalar(0))) continue;
    V2 r;
    if (ba_detail::reprojection<Scalar>(cam, R, t, X[static_cast<std::size_t>(i)],
                                        uv[static_cast<std::size_t>(i)], opt.minDepth, r, nullptr,
                                        nullptr)) {
      used.push_back(i);
    }
  }
  rep.usedPoints = static_cast<int>(used.size());
  auto cost = [&](const M3& Rc, const V3& tc) {
    Scalar F = Scalar(0);
    for (const int i : used) {
      V2 r;
      if (!ba_detail::reprojection<Scalar>(cam, Rc, tc, X[static_cast<std::size_t>(i)],
                                           uv[static_cast<std::size_t>(i)], opt.minDepth, r,
                                           nullptr, nullptr)) {
        return std::numeric_limits<Scalar>::infinity();
      }
      F += weightOf(i) * robustCost(opt.loss, r.squaredNorm() * invS2, opt.robustScale);
    }
    return F;
  };
  Scalar F = cost(R, t);
  rep.initialCost = rep.finalCost = F;
  if (used.empty() || !std::isfinite(F)) return rep;
  Scalar lambda = Scalar(1e-4), nu = Scalar(2);
  M6 H;
  V6 g;
  auto linearise = [&]() {
    H.setZero();
    g.setZero();
    for (const int i : used) {
      V2 r;
      Eigen::Matrix<Scalar, 2, 6> J;
      if (!ba_detail::reprojection<Scalar>(cam, R, t, X[static_cast<std::size_t>(i)],
                                           uv[static_cast<std::size_t>(i)], opt.minDepth, r, &J,
                                           nullptr)) {
        continue;  // cannot happen: poses moving a used point behind the camera are rejected
      }
      const Scalar s = r.squaredNorm() * invS2;
      const Scalar w = weightOf(i) * invS2 * robustWeight(opt.loss, s, opt.robustScale);
      g.noalias() += w * J.transpose() * r;
      ba_detail::applyRobustCorrection(
          r, ba_detail::robustCurvatureAlpha(opt.loss, s, opt.robustScale, opt.minRadialCurvature), J);
      H.noalias() += w * J.transpose() * J;
    }
  };
  linearise();
  while (rep.iterations < opt.maxIterations) {
    ++rep.iterations;
    M6 A = H;
    for (int k = 0; k < 6; ++k) A(k, k) += lambda * ba_detail::clampDiag(H(k, k));
    const Eigen::LLT<M6> llt(A);
    V6 d = V6::Zero();
    bool ok = llt.info() == Eigen::Success;
    if (ok) {
      d = -llt.solve(g);
      ok = d.allFinite();
    }
    if (ok && d.norm() <= opt.stepTolerance) {
      rep.converged = true;
      break;
    }
    bool accepted = false;
    if (ok) {
      const SE3<Scalar> Tn = T_w_c * SE3<Scalar>::exp(Vec6<Scalar>(d));
      const SE3<Scalar> Tcn = Tn.inverse();
      const M3 Rn = Tcn.rotationMatrix();
      const V3 tn = Tcn.translation();
      const Scalar Fn = cost(Rn, tn);
      Scalar dDd = Scalar(0);
      for (int k = 0; k < 6; ++k) dDd += ba_detail::clampDiag(H(k, k)) * d(k) * d(k);
      const Scalar predicted = -g.dot(d) + lambda * dDd;
      if (std::isfinite(Fn) && Fn < F && predicted > Scalar(0)) {
        const Scalar rho = (F - Fn) / predicted, rel = (F - Fn) / F;
        T_w_c = Tn;
        R = Rn;
        t = tn;
        F = Fn;
        accepted = true;
        const Scalar tt = Scalar(2) * rho - Scalar(1);
        lambda *= std::max(Scalar(1) / Scalar(3), Scalar(1) - tt * tt * tt);
        nu = Scalar(2);
        if (rel <= opt.functionTolerance) {
          rep.converged = true;
          break;
        }
        linearise();
      }
    }
    if (!accepted) {
      lambda *= nu;
      nu *= Scalar(2);
      if (lambda > Scalar(1e16)) break;
    }
  }
  rep.finalCost = F;
  return rep;
}

/// PnP with outliers (file comment): P3P in adaptive MSAC on the reprojection error, then
/// refinePose over the inliers, the inliers recomputed with the refined pose (and the
/// refinement repeated once when they changed). Throws hawor::Error on mismatched sizes,
/// non-finite input, a bad camera or bad options; otherwise reports failure in `status`.
template <typename Scalar>
PnPRansacResult<Scalar> solvePnPRansac(const std::vector<Vec3<Scalar>>& X,
                                       const std::vector<Vec2<Scalar>>& uv,
                                       const PinholeCamera<Scalar>& cam,
                                       const PnPRansacOptions<Scalar>& opt = {}) {
  using V2 = Eigen::Matrix<Scalar, 2, 1>;
  using V3 = Eigen::Matrix<Scalar, 3, 1>;
  using M3 = Eigen::Matrix<Scalar, 3, 3>;
  pnp_ransac_detail::checkInputs<Scalar>(X, uv, nullptr, cam, "solvePnPRansac");
  PnPRansacResult<Scalar> res;
  const int n = static_cast<int>(X.size());
  if (n < 4) {
    res.status = PnPStatus::TooFewPoints;
    return res;
  }
  // Bearings (z = 1) of the pixels.
  std::vector<Vec3<Scalar>> f(X.size());
  for (std::size_t i = 0; i < X.size(); ++i) f[i] = cam.ray(uv[i]);
  struct Model {
    Mat3<Scalar> R = Mat3<Scalar>::Identity();  // world-to-camera
    Vec3<Scalar> t = Vec3<Scalar>::Zero();
  };
  const Scalar minDepth = opt.refinement.minDepth;
  std::vector<SE3<Scalar>> sols;
  auto solve = [&](const int* s, std::vector<Model>& models) {
    const Vec3<Scalar> b[3] = {f[static_cast<std::size_t>(s[0])], f[static_cast<std::size_t>(s[1])],
                               f[static_cast<std::size_t>(s[2])]};
    const Vec3<Scalar> P[3] = {X[static_cast<std::size_t>(s[0])], X[static_cast<std::size_t>(s[1])],
                               X[static_cast<std::size_t>(s[2])]};
    sols.clear();
    solveP3P(b, P, sols);
    for (const auto& T : sols) models.push_back(Model{T.rotationMatrix(), T.translation()});
  };
  auto errorSq = [&](const Model& m, int i) -> Scalar {
    V2 r;
    if (!ba_detail::reprojection<Scalar>(cam, M3(m.R), V3(m.t), X[static_cast<std::size_t>(i)],
                                         uv[static_cast<std::size_t>(i)], minDepth, r, nullptr,
                                         nullptr)) {
      return std::numeric_limits<Scalar>::infinity();
    }
    return r.squaredNorm();
  };
  RansacOptions<Scalar> ro;
  ro.threshold = opt.thresholdPx;
  ro.confidence = opt.confidence;
  ro.maxIterations = opt.maxIterations;
  ro.minIterations = opt.minIterations;
  ro.seed = opt.seed;
  const auto rr = ransac<Model, Scalar>(n, 3, solve, errorSq, ro);
  res.ransacIterations = rr.iterations;
  if (!rr.found) {
    res.status = PnPStatus::NoModel;
    return res;
  }
  res.T_w_c = SE3<Scalar>(rr.model.R, rr.model.t).inverse();
  res.inliers = rr.inliers;
  res.numInliers = rr.numInliers;
  const Scalar T2 = opt.thresholdPx * opt.thresholdPx;
  auto recount = [&]() {
    const SE3<Scalar> Tcw = res.T_w_c.inverse();
    Model m{Tcw.rotationMatrix(), Tcw.translation()};
    int cnt = 0;
    bool changed = false;
    for (int i = 0; i < n; ++i) {
      const char in = errorSq(m, i) < T2 ? 1 : 0;
      changed = changed || in != res.inliers[static_cast<std::size_t>(i)];
      res.inliers[static_cast<std::size_t>(i)] = in;
      cnt += in;
    }
    res.numInliers = cnt;
    return changed;
  };
  if (opt.refine && res.numInliers >= 4) {
    std::vector<Scalar> w(X.size());
    for (int round = 0; round < 2; ++round) {
      for (std::size_t i = 0; i < X.size(); ++i) w[i] = res.inliers[i] ? Scalar(1) : Scalar(0);
      const SE3<Scalar> before = res.T_w_c;
      const PoseRefineReport<Scalar> rep = refinePose(X, uv, &w, cam, res.T_w_c, opt.refinement);
      if (round == 0) {
        res.refinement = rep;
      } else {
        res.refinement.finalCost = rep.finalCost;
        res.refinement.iterations += rep.iterations;
        res.refinement.converged = rep.converged;
      }
      const bool changed = recount();
      if (res.numInliers < 4) {  // the refinement went wrong: keep the RANSAC pose
        res.T_w_c = before;
        recount();
        break;
      }
      if (!changed) break;
    }
  }
  // RMS of the inliers.
  {
    const SE3<Scalar> Tcw = res.T_w_c.inverse();
    const Model m{Tcw.rotationMatrix(), Tcw.translation()};
    Scalar ss = Scalar(0);
    for (int i = 0; i < n; ++i) {
      if (res.inliers[static_cast<std::size_t>(i)]) ss += errorSq(m, i);
    }
    res.inlierRmsPx = res.numInliers > 0 ? std::sqrt(ss / Scalar(res.numInliers)) : Scalar(0);
  }
  res.status = res.numInliers >= opt.minInliers ? PnPStatus::Ok : PnPStatus::NotEnoughInliers;
  return res;
}

}  // namespace hawor
