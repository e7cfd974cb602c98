// hawor/hand/fit/energy.hpp — HandFitter's energy, its residuals and the normal equations the
// solver assembles (the energy of hand/fit.hpp's file comment, per keypoint).
// Member functions of HandFitter (hand/fit.hpp: the class, its state and the overview);
// included at the end of that header.
#pragma once

#include "../fit.hpp"

namespace hawor {

// Energy of `s`; with `build`, also the lower triangle of H = JᵀJ and g = Jᵀr (IRLS weights
// at s). The data terms are accumulated per keypoint: with W_k = Σ (weights)·(∂r/∂K_k)ᵀ(∂r/∂K_k)
// (3×3: the 2D term's w·J_πᵀJ_π plus the 3D term's c·I) and J_k = ∂K_k/∂x,
//   H = Σ_k J_kᵀ W_k J_k − C·J̄ᵀJ̄,  g = Σ_k J_kᵀ (w J_πᵀ e_k + c r_k),
// where J̄ = Σ c_k J_k / C is the centroid's Jacobian (C = Σ c_k): the centred 3D residuals
// sum to zero, so Σ c_k (J_k − J̄)ᵀ(J_k − J̄) = Σ c_k J_kᵀJ_k − C J̄ᵀJ̄ and the J̄ᵀr term vanishes.
// Each J_k is non-zero only on its keypoint's columns (the root, its ancestors, β; every joint
// for a tip vertex with pose correctives), so each product runs over those columns only.
template <typename Scalar>
Scalar HandFitter<Scalar>::evaluate(const State& s, bool build) {
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
template <typename Scalar>
void HandFitter<Scalar>::accumulateKeypoint(int k, const Mat3<Scalar>& W, const Vec3<Scalar>& gk) {
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
template <typename Scalar>
void HandFitter<Scalar>::addLinear(Scalar& E, bool build, int c0, const Mat3<Scalar>& A, const Vec3<Scalar>& r3, Scalar is) {
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
template <typename Scalar>
template <typename RowT>
void HandFitter<Scalar>::addLinearRow(Scalar& E, bool build, int c0, const RowT& a, Scalar r, Scalar is) {
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
template <typename Scalar>
void HandFitter<Scalar>::addScalar(Scalar& E, bool build, int c, Scalar r, Scalar is) {
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
template <typename Scalar>
template <typename RowT>
void HandFitter<Scalar>::pushResidual(Scalar r, const RowT& row) {
  rAll_.push_back(r);
  for (Eigen::Index c = 0; c < row.size(); ++c) jAll_.push_back(row(c));
}

}  // namespace hawor
