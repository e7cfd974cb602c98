// hawor/geometry/pnp.hpp — metric perspective-n-point: the camera-frame pose (R, t) of a rigid set
// of METRIC 3D points X_i (metres, any origin) from their pixels u_i, p_i = R·X_i + t.
//
// Because X is metric, t is metric too: the depth comes from the known size of the point set
// (for the hands, the MediaPipe world landmarks, docs/design.md §4). Two stages:
//   1. pnpTranslationLinear: t for a fixed R in closed form. With the normalised pixel
//      (x̂, ŷ) = ((u − cx)/fx, (v − cy)/fy) and a = R·X, the projection equations
//      a_x + t_x = x̂ (a_z + t_z),  a_y + t_y = ŷ (a_z + t_z) are linear in t: a 3×3 weighted
//      normal system (the algebraic error, i.e. the pixel error times depth/f).
//   2. solvePnPMetric: Gauss–Newton on the pixel error Σ_i c_i ρ(‖π(R X_i + t) − u_i‖²/σ²)
//      over t, and over R when asked (left increment R ← exp(δ)·R, d p/dδ = −[R X]×), with IRLS
//      weights of a robust loss so that a few wrong pixels do not move the pose.
// Pixels follow docs/design.md §2 (OpenCV camera, pixel centres at integers). Pure functions, thread-safe.
#pragma once

#include <Eigen/Cholesky>
#include <cmath>
#include <string>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/robust_loss.hpp"
#include "hawor/geometry/rotation.hpp"

namespace hawor {

/// (N,2) row-major pixel coordinates (u, v).
template <typename Scalar>
using Pixels = Eigen::Matrix<Scalar, Eigen::Dynamic, 2, Eigen::RowMajor>;

template <typename Scalar>
struct PnPOptions {
  int maxIterations = 20;
  bool refineRotation = false;     ///< also refine R (else R stays as given)
  RobustLoss loss = RobustLoss::Huber;
  Scalar sigmaPx = Scalar(2);      ///< pixel noise scale σ
  Scalar robustScale = Scalar(2);  ///< loss scale k in units of σ
  Scalar minDepth = Scalar(1e-3);  ///< points closer than this (metres) are left out of a step
  Scalar tolerance = Scalar(1e-10);  ///< stop when the step is below this (metres / radians)
};

template <typename Scalar>
struct PnPResult {
  Mat3<Scalar> R = Mat3<Scalar>::Identity();
  Vec3<Scalar> t = Vec3<Scalar>::Zero();
  Scalar rmsPx = Scalar(0);  ///< weighted RMS pixel error (weights c_i, not the robust ones)
  int iterations = 0;
  bool ok = false;           ///< false when too few usable points or all points behind the camera
};

namespace pnp_detail {

/// Keeps a parameter out of template argument deduction (so nullptr can be passed).
template <typename T>
struct Identity {
  using type = T;
};

template <typename Scalar>
void checkInputs(const Points3<Scalar>& X, const Pixels<Scalar>& uv, const VecX<Scalar>* w,
                 const PinholeCamera<Scalar>& cam, const char* who) {
  const std::string m = std::string(who) + ": ";
  if (uv.rows() != X.rows()) {
    throw Error(m + std::to_string(X.rows()) + " points but " + std::to_string(uv.rows()) + " pixels");
  }
  if (w && w->size() != X.rows()) {
    throw Error(m + std::to_string(w->size()) + " weights for " + std::to_string(X.rows()) + " points");
  }
  if (!X.allFinite() || !uv.allFinite()) throw Error(m + "points or pixels are not finite");
  if (w && (!w->allFinite() || (w->array() < Scalar(0)).any())) {
    throw Error(m + "weights must be finite and >= 0");
  }
  if (!(cam.fx > Scalar(0)) || !(cam.fy > Scalar(0)) || !std::isfinite(cam.fx) ||
      !std::isfinite(cam.fy) || !std::isfinite(cam.cx) || !std::isfinite(cam.cy)) {
    throw Error(m + "camera focal lengths must be finite and > 0");
  }
}

}  // namespace pnp_detail

/// Closed-form t for a fixed R (stage 1 of the file comment). Weights: one per point, >= 0
/// (nullptr: all 1). Returns false (t untouched) when the system is singular (fewer than two
/// weighted points, or all on one ray).
template <typename Scalar>
bool pnpTranslationLinear(const Points3<Scalar>& X, const Pixels<Scalar>& uv,
                          const typename pnp_detail::Identity<VecX<Scalar>>::type* weights,
                          const Mat3<Scalar>& R, const PinholeCamera<Scalar>& cam, Vec3<Scalar>& t) {
  pnp_detail::checkInputs(X, uv, weights, cam, "pnpTranslationLinear");
  Eigen::Matrix<Scalar, 3, 3> A = Eigen::Matrix<Scalar, 3, 3>::Zero();
  Eigen::Matrix<Scalar, 3, 1> b = Eigen::Matrix<Scalar, 3, 1>::Zero();
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    const Scalar c = weights ? (*weights)(i) : Scalar(1);
    if (!(c > Scalar(0))) continue;
    const Eigen::Matrix<Scalar, 3, 1> a = R * X.row(i).transpose();
    const Scalar xh = (uv(i, 0) - cam.cx) / cam.fx, yh = (uv(i, 1) - cam.cy) / cam.fy;
    // rows [1 0 −x̂] and [0 1 −ŷ], right-hand sides x̂ a_z − a_x and ŷ a_z − a_y
    const Eigen::Matrix<Scalar, 3, 1> r1(Scalar(1), Scalar(0), -xh), r2(Scalar(0), Scalar(1), -yh);
    A.noalias() += c * (r1 * r1.transpose() + r2 * r2.transpose());
    b.noalias() += c * (r1 * (xh * a(2) - a(0)) + r2 * (yh * a(2) - a(1)));
  }
  const Eigen::LDLT<Eigen::Matrix<Scalar, 3, 3>> ldlt(A);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > Scalar(1e-12) * (A.trace() + Scalar(1e-30)))) {
    return false;
  }
  const Eigen::Matrix<Scalar, 3, 1> sol = ldlt.solve(b);
  if (!sol.allFinite()) return false;
  t = sol;
  return true;
}

/// Metric PnP (file comment): linear t for R_init, then robust Gauss–Newton on the reprojection
/// error over t (and R if options.refineRotation). Throws hawor::Error on mismatched sizes or
/// non-finite input; returns ok = false when no pose can be found.
template <typename Scalar>
PnPResult<Scalar> solvePnPMetric(const Points3<Scalar>& X, const Pixels<Scalar>& uv,
                                 const typename pnp_detail::Identity<VecX<Scalar>>::type* weights,
                                 const PinholeCamera<Scalar>& cam, const Mat3<Scalar>& R_init,
                                 const PnPOptions<Scalar>& opt = {}) {
  using V3 = Eigen::Matrix<Scalar, 3, 1>;
  using M6 = Eigen::Matrix<Scalar, 6, 6>;
  using V6 = Eigen::Matrix<Scalar, 6, 1>;
  PnPResult<Scalar> res;
  res.R = R_init;
  if (!pnpTranslationLinear(X, uv, weights, R_init, cam, res.t)) return res;
  const Scalar inv_s2 = Scalar(1) / (opt.sigmaPx * opt.sigmaPx);
  const int n = static_cast<int>(X.rows());
  // Robust cost Σ c_i ρ(‖e_i‖²/σ²) of a pose; the count of points in front is returned too.
  auto cost = [&](const Mat3<Scalar>& R, const Vec3<Scalar>& t, int& front) {
    Scalar e = Scalar(0);
    front = 0;
    for (int i = 0; i < n; ++i) {
      const Scalar c = weights ? (*weights)(i) : Scalar(1);
      if (!(c > Scalar(0))) continue;
      const Vec3<Scalar> p = R * X.row(i).transpose() + t;
      if (p(2) < opt.minDepth) {
        e += c * robustCost(opt.loss, Scalar(1e6), opt.robustScale);  // a large fixed penalty
        continue;
      }
      ++front;
      const Scalar s = (cam.project(p) - uv.row(i).transpose()).squaredNorm() * inv_s2;
      e += c * robustCost(opt.loss, s, opt.robustScale);
    }
    return e;
  };
  int front = 0;
  Scalar E = cost(res.R, res.t, front);
  if (front == 0) return res;
  const int dof = opt.refineRotation ? 6 : 3;
  for (int it = 0; it < opt.maxIterations; ++it) {
    res.iterations = it + 1;
    M6 H = M6::Zero();
    V6 g = V6::Zero();
    for (int i = 0; i < n; ++i) {
      const Scalar c = weights ? (*weights)(i) : Scalar(1);
      if (!(c > Scalar(0))) continue;
      const V3 a = res.R * X.row(i).transpose();
      const Vec3<Scalar> p = a + res.t;
      if (p(2) < opt.minDepth) continue;
      Eigen::Matrix<Scalar, 2, 3> Jp;
      const Eigen::Matrix<Scalar, 2, 1> e = cam.project(p, &Jp) - uv.row(i).transpose();
      const Scalar w = c * inv_s2 * robustWeight(opt.loss, e.squaredNorm() * inv_s2, opt.robustScale);
      Eigen::Matrix<Scalar, 2, 6> Ji;
      Ji.template leftCols<3>() = Jp;                      // d/dt
      Ji.template rightCols<3>() = -Jp * hat(a);           // d/dδ, left increment of R
      H.noalias() += w * Ji.transpose() * Ji;
      g.noalias() += w * Ji.transpose() * e;
    }
    // Tiny Levenberg damping keeps a rank-deficient rotation block solvable; without rotation
    // refinement the rotation block is the identity with a zero gradient (a zero step).
    if (!opt.refineRotation) {
      H.template bottomRows<3>().setZero();
      H.template rightCols<3>().setZero();
      g.template tail<3>().setZero();
    }
    for (int k = dof; k < 6; ++k) H(k, k) = Scalar(1);
    for (int k = 0; k < dof; ++k) H(k, k) += Scalar(1e-9) * (Scalar(1) + H(k, k));
    const Eigen::LDLT<M6> ldlt(H);
    const V6 step = -ldlt.solve(g);
    if (!step.allFinite()) break;
    // Backtracking: halve the step until the robust cost does not increase.
    Scalar alpha = Scalar(1);
    bool accepted = false;
    for (int tries = 0; tries < 8; ++tries, alpha *= Scalar(0.5)) {
      const Vec3<Scalar> t_new = res.t + alpha * step.head(3);
      Mat3<Scalar> R_new = res.R;
      if (opt.refineRotation) {
        const V3 d = alpha * step.tail(3);
        R_new = axisAngleToMatrix(d) * res.R;
      }
      int f2 = 0;
      const Scalar E_new = cost(R_new, t_new, f2);
      if (E_new <= E) {
        res.t = t_new;
        res.R = R_new;
        E = E_new;
        accepted = true;
        break;
      }
    }
    if (!accepted || alpha * step.norm() < opt.tolerance) break;
  }
  // Weighted RMS pixel error of the final pose.
  Scalar se = Scalar(0), sw = Scalar(0);
  for (int i = 0; i < n; ++i) {
    const Scalar c = weights ? (*weights)(i) : Scalar(1);
    if (!(c > Scalar(0))) continue;
    const Vec3<Scalar> p = res.R * X.row(i).transpose() + res.t;
    if (p(2) < opt.minDepth) continue;
    se += c * (cam.project(p) - uv.row(i).transpose()).squaredNorm();
    sw += c;
  }
  res.rmsPx = sw > Scalar(0) ? std::sqrt(se / sw) : Scalar(0);
  res.ok = sw > Scalar(0) && res.t.allFinite();
  return res;
}

}  // namespace hawor
