// hawor/hand/keypoint_jacobian.hpp — the hand model's keypoints (only) and their analytic
// Jacobian with respect to the fit parameters, for a hand model with any number of joints J,
// shape coefficients B and tip vertices (MANO: J = 16, B = 10; the 25-joint default hand: B = 0).
//
// Same model as hand/forward.hpp, evaluated only where keypoints are: the J posed joints and the
// few tip vertices (no full-mesh skinning, so a Gauss–Newton iteration costs microseconds).
//   J(β) = J_T + J_S β,  G_0 = [R_0 | J_0],  G_j = G_p(j)·[R_j | J_j − J_p(j)] = [Rg_j | g_j]
//   joint keypoint:  K = g_q + t
//   tip vertex v:    K = Σ_i w_i q_i + t,  q_i = Rg_i (v_p − J_i) + g_i,
//                    v_p = T_v + S_v β + P_v f,  f = [vec(R_j − I)]_{j≥1} (row-major vec)
//
// Parameters (HandParamLayout): [δ (3): right increment of the global rotation R_0 ← R_0·exp(δ),
// t (3), w_1..w_{J−1} (3 each): joint axis-angles, R_j = exp(w_j), β (B)].
//
// Jacobians (derivation): a right perturbation ε_j of joint j (R_j ← R_j·exp(ε_j), or R_0 for
// j = 0) turns every point attached to a bone of j's subtree rigidly about g_j in its frame:
//   p(ε) = g_j + Rg_j exp(ε) y  ⇒  ∂p/∂ε_j = −Rg_j [y]× = [g_j − p]× Rg_j.
// So ∂g_q/∂ε_j = [g_j − g_q]× Rg_j for every strict ancestor j of q (g_j itself does not move),
// and for a tip vertex Σ_{i∈sub(j)} w_i [g_j − q_i]× Rg_j = [W_j g_j − Q_j]× Rg_j with
// W_j = Σ_{i∈sub(j)} w_i, Q_j = Σ_{i∈sub(j)} w_i q_i; the pose correctives add
// M·P_{v,j}·∂vec(R_j)/∂ε_j with M = Σ_i w_i Rg_i and ∂R_j/∂ε_a = R_j [e_a]×. The axis-angle
// parameter enters through the SO(3) right Jacobian: exp(w + dw) ≈ exp(w)·exp(J_r(w) dw), so
// ∂K/∂w_j = ∂K/∂ε_j · J_r(w_j). Shape: ∂g_0/∂β = J_S,0, ∂g_j/∂β = ∂g_p/∂β + Rg_p (J_S,j − J_S,p),
// and ∂v/∂β = M S_v + Σ_i w_i (∂g_i/∂β − Rg_i J_S,i). Translation: I.
//
// Thread-safety: HandKeypointModel is read-only after construction (share it); one
// HandKeypointWorkspace per thread. Repeated evaluations do not allocate once sized.
#pragma once

#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/hand/hand_model.hpp"

namespace hawor {

/// Column offsets of the fit parameter vector (see the file comment).
struct HandParamLayout {
  int numJoints = 1;
  int numBetas = 0;
  static constexpr int rot = 0;     ///< 3: right increment of the global rotation
  static constexpr int transl = 3;  ///< 3: translation (metres)
  /// First column of joint j's axis-angle (j >= 1).
  int joint(int j) const { return 6 + 3 * (j - 1); }
  /// First column of the shape coefficients.
  int betas() const { return 6 + 3 * (numJoints - 1); }
  /// Number of parameters, 6 + 3(J−1) + B.
  int size() const { return betas() + numBetas; }
};

/// ∂keypoints/∂parameters, (3K, P) row-major: the three rows of a keypoint are contiguous.
template <typename Scalar>
using KeypointJacobian = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// What the keypoint evaluation needs from a prepared HandModel, copied (so it owns its data).
template <typename Scalar>
struct HandKeypointModel {
  int J = 0, B = 0, K = 0, T = 0;
  bool hasPosedirs = false;
  HandParamLayout layout;
  std::vector<int> parents;
  Points3<Scalar> jTemplate;      ///< (J,3)
  MatX<Scalar> jShapedirs;        ///< (3J,B)
  std::vector<int> kpJoint;       ///< per keypoint: its joint, or −1
  std::vector<int> kpTip;         ///< per keypoint: its tip index, or −1
  Points3<Scalar> tipTemplate;    ///< (T,3) template position of each tip vertex
  MatX<Scalar> tipShapedirs;      ///< (3T,B)
  /// (3T,9(J−1)) row-major (a tip coordinate's correctives are contiguous); empty without them
  Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> tipPosedirs;
  std::vector<int> tipSkinStart;  ///< (T+1) CSR starts into tipSkinJoint / tipSkinWeight
  std::vector<int> tipSkinJoint;
  std::vector<Scalar> tipSkinWeight;
  std::vector<unsigned char> subtree;  ///< (J×J): subtree[j·J + i] = 1 when i is j or below j

  HandKeypointModel() = default;

  /// Copies the keypoint-related data of a prepared model. Throws hawor::Error when the model is
  /// not prepared or has no keypoints.
  explicit HandKeypointModel(const HandModel<Scalar>& m) {
    if (!m.prepared()) throw Error("hand keypoints: the model is not prepared (call prepare())");
    J = m.numJoints();
    B = m.numBetas();
    K = m.numKeypoints();
    T = static_cast<int>(m.tipVertices.size());
    if (K == 0) throw Error("hand keypoints: the model has no keypoints (empty keypointMap)");
    layout.numJoints = J;
    layout.numBetas = B;
    hasPosedirs = m.numPoseFeatures() > 0;
    parents = m.parents;
    jTemplate = m.jTemplate;
    jShapedirs = m.jShapedirs;
    kpJoint.assign(static_cast<std::size_t>(K), -1);
    kpTip.assign(static_cast<std::size_t>(K), -1);
    for (int k = 0; k < K; ++k) {
      const int idx = m.keypointMap[static_cast<std::size_t>(k)];
      if (idx < J) {
        kpJoint[static_cast<std::size_t>(k)] = idx;
      } else {
        kpTip[static_cast<std::size_t>(k)] = idx - J;
      }
    }
    tipTemplate.resize(T, 3);
    tipShapedirs.resize(3 * T, B);
    if (hasPosedirs) tipPosedirs.resize(3 * T, m.numPoseFeatures());
    tipSkinStart.assign(1, 0);
    tipSkinJoint.clear();
    tipSkinWeight.clear();
    for (int t = 0; t < T; ++t) {
      const int v = m.tipVertices[static_cast<std::size_t>(t)];
      tipTemplate.row(t) = m.vTemplate.row(v);
      if (B > 0) tipShapedirs.middleRows(3 * t, 3) = m.shapedirs.middleRows(3 * v, 3);
      if (hasPosedirs) tipPosedirs.middleRows(3 * t, 3) = m.posedirs.middleRows(3 * v, 3);
      for (int j = 0; j < J; ++j) {
        if (m.weights(v, j) != Scalar(0)) {
          tipSkinJoint.push_back(j);
          tipSkinWeight.push_back(m.weights(v, j));
        }
      }
      tipSkinStart.push_back(static_cast<int>(tipSkinJoint.size()));
    }
    subtree.assign(static_cast<std::size_t>(J) * static_cast<std::size_t>(J), 0);
    for (int i = 0; i < J; ++i) {
      for (int a = i; a >= 0; a = parents[static_cast<std::size_t>(a)]) {
        subtree[static_cast<std::size_t>(a) * static_cast<std::size_t>(J) + static_cast<std::size_t>(i)] = 1;
      }
    }
  }

  bool inSubtree(int j, int i) const {
    return subtree[static_cast<std::size_t>(j) * static_cast<std::size_t>(J) + static_cast<std::size_t>(i)] != 0;
  }
};

/// Scratch state of evaluateHandKeypoints (reuse across calls: no allocation once sized).
template <typename Scalar>
struct HandKeypointWorkspace {
  std::vector<Mat3<Scalar>> rot;   ///< R_j (R_0 = global)
  std::vector<Mat3<Scalar>> jr;    ///< J_r(w_j)
  std::vector<Mat3<Scalar>> gRot;  ///< Rg_j
  std::vector<Vec3<Scalar>> gPos;  ///< g_j
  Points3<Scalar> jRest;           ///< (J,3) J(β)
  MatX<Scalar> dgdb;               ///< (3J,B) ∂g_j/∂β
  VecX<Scalar> feature;            ///< 9(J−1) pose features
  std::vector<Vec3<Scalar>> tipQ;  ///< per skinning joint of a tip: q_i

  void resize(const HandKeypointModel<Scalar>& km) {
    const std::size_t J = static_cast<std::size_t>(km.J);
    rot.resize(J);
    jr.resize(J);
    gRot.resize(J);
    gPos.resize(J);
    jRest.resize(km.J, 3);
    dgdb.resize(3 * km.J, km.B);
    feature.resize(km.hasPosedirs ? 9 * (km.J - 1) : 0);
  }
};

namespace hand_detail {

/// R = exp(w) and, if wanted, J_r(w) from one set of coefficients:
/// R = I + A[w]× + B[w]×², J_r = I − B[w]× + C[w]×², A = sin θ/θ, B = (1 − cos θ)/θ²,
/// C = (θ − sin θ)/θ³. Below θ = 0.1 the series to θ⁶ (truncation < 3e-14 relative) avoid the
/// cancellation of the closed forms; rotation.hpp's RotationCoefficients computes more terms than
/// this inner loop needs.
template <typename Scalar>
void expAndRightJacobian(const Vec3<Scalar>& w, Mat3<Scalar>& R, Mat3<Scalar>* Jr) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Scalar t2 = w.squaredNorm();
  Scalar A, B, C;
  if (t2 < Scalar(0.01)) {
    const Scalar t4 = t2 * t2, t6 = t4 * t2;
    A = Scalar(1) - t2 / Scalar(6) + t4 / Scalar(120) - t6 / Scalar(5040);
    B = Scalar(0.5) - t2 / Scalar(24) + t4 / Scalar(720) - t6 / Scalar(40320);
    C = Scalar(1) / Scalar(6) - t2 / Scalar(120) + t4 / Scalar(5040) - t6 / Scalar(362880);
  } else {
    const Scalar t = sqrt(t2), st = sin(t), sh = sin(t / Scalar(2));
    A = st / t;
    B = Scalar(2) * sh * sh / t2;
    C = (t - st) / (t2 * t);
  }
  const Mat3<Scalar> W = hat(w);
  const Mat3<Scalar> W2 = W * W;
  R = Mat3<Scalar>::Identity() + A * W + B * W2;
  if (Jr) *Jr = Mat3<Scalar>::Identity() - B * W + C * W2;
}

/// C = P·∂vec(R)/∂ε for a right perturbation R·exp(ε): column a = P·vec(R[e_a]×), with P (3×9)
/// acting on the row-major vec, given as 3 rows of `stride` scalars starting at `p`.
/// (R[e_0]×) has columns (0, R₂, −R₁), (R[e_1]×) (−R₂, 0, R₀), (R[e_2]×) (R₁, −R₀, 0), R_c the
/// columns of R.
template <typename Scalar>
Mat3<Scalar> posedirRotationDerivative(const Scalar* p, Eigen::Index stride, const Mat3<Scalar>& R) {
  Mat3<Scalar> C;
  for (int c = 0; c < 3; ++c) {
    const Scalar* q = p + c * stride;  // q[3r + m] = P(c, (r, m))
    Scalar x = Scalar(0), y = Scalar(0), z = Scalar(0);
    for (int r = 0; r < 3; ++r) {
      const Scalar q0 = q[3 * r], q1 = q[3 * r + 1], q2 = q[3 * r + 2];
      x += q1 * R(r, 2) - q2 * R(r, 1);
      y += q2 * R(r, 0) - q0 * R(r, 2);
      z += q0 * R(r, 1) - q1 * R(r, 0);
    }
    C(c, 0) = x;
    C(c, 1) = y;
    C(c, 2) = z;
  }
  return C;
}

}  // namespace hand_detail

/// Keypoints (K,3) of the pose (R_0, jointPose (J−1,3) axis-angles, β, t) in metres, and, when
/// `jacobian` is given, ∂keypoints/∂parameters as a (3K, layout.size()) row-major matrix, rows 3k..3k+2 for
/// keypoint k, columns as HandParamLayout (see the file comment for the formulas).
/// β may be shorter than B (the rest are zero). Throws hawor::Error on wrong sizes.
template <typename Scalar>
void evaluateHandKeypoints(const HandKeypointModel<Scalar>& km, const Mat3<Scalar>& R0,
                           const Points3<Scalar>& jointPose, const VecX<Scalar>& betas,
                           const Vec3<Scalar>& transl, HandKeypointWorkspace<Scalar>& ws,
                           Points3<Scalar>& keypoints, KeypointJacobian<Scalar>* jacobian = nullptr) {
  const int J = km.J, B = km.B, K = km.K;
  if (jointPose.rows() != J - 1) {
    throw Error("hand keypoints: jointPose has " + std::to_string(jointPose.rows()) + " rows, the model has " +
                std::to_string(J - 1) + " non-root joints");
  }
  const int nb = static_cast<int>(betas.size());
  if (nb > B) {
    throw Error("hand keypoints: " + std::to_string(nb) + " shape coefficients given, the model has " +
                std::to_string(B));
  }
  if (static_cast<int>(ws.gRot.size()) != J || ws.dgdb.cols() != B) ws.resize(km);
  const bool jac = jacobian != nullptr;
  auto su = [](int i) { return static_cast<std::size_t>(i); };

  // Rest joints for β.
  for (int j = 0; j < J; ++j) {
    for (int c = 0; c < 3; ++c) {
      Scalar s = km.jTemplate(j, c);
      for (int k = 0; k < nb; ++k) s += km.jShapedirs(3 * j + c, k) * betas(k);
      ws.jRest(j, c) = s;
    }
  }
  // Local rotations, their right Jacobians, forward kinematics.
  ws.rot[0] = R0;
  for (int j = 1; j < J; ++j) {
    const Vec3<Scalar> w = jointPose.row(j - 1).transpose();
    hand_detail::expAndRightJacobian(w, ws.rot[su(j)], jac ? &ws.jr[su(j)] : nullptr);
  }
  for (int j = 0; j < J; ++j) {
    const Vec3<Scalar> Jj = ws.jRest.row(j).transpose();
    if (j == 0) {
      ws.gRot[0] = ws.rot[0];
      ws.gPos[0] = Jj;
    } else {
      const int p = km.parents[su(j)];
      ws.gRot[su(j)] = ws.gRot[su(p)] * ws.rot[su(j)];
      ws.gPos[su(j)] = ws.gRot[su(p)] * (Jj - ws.jRest.row(p).transpose()) + ws.gPos[su(p)];
    }
  }
  if (km.hasPosedirs) {
    for (int j = 1; j < J; ++j) {
      Scalar* f = ws.feature.data() + 9 * (j - 1);
      const Mat3<Scalar>& R = ws.rot[su(j)];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) f[3 * r + c] = R(r, c) - (r == c ? Scalar(1) : Scalar(0));
    }
  }
  // ∂g_j/∂β along the tree.
  if (jac && B > 0) {
    for (int j = 0; j < J; ++j) {
      if (j == 0) {
        ws.dgdb.middleRows(0, 3) = km.jShapedirs.middleRows(0, 3);
      } else {
        const int p = km.parents[su(j)];
        ws.dgdb.middleRows(3 * j, 3) = ws.dgdb.middleRows(3 * p, 3);
        for (int k = 0; k < B; ++k) {
          const Vec3<Scalar> d(km.jShapedirs(3 * j, k) - km.jShapedirs(3 * p, k),
                               km.jShapedirs(3 * j + 1, k) - km.jShapedirs(3 * p + 1, k),
                               km.jShapedirs(3 * j + 2, k) - km.jShapedirs(3 * p + 2, k));
          ws.dgdb.block(3 * j, k, 3, 1) += ws.gRot[su(p)] * d;
        }
      }
    }
  }

  keypoints.resize(K, 3);
  const HandParamLayout& L = km.layout;
  if (jac) {
    jacobian->resize(3 * K, L.size());
    jacobian->setZero();
  }
  for (int k = 0; k < K; ++k) {
    const int q = km.kpJoint[su(k)];
    if (q >= 0) {
      const Vec3<Scalar> g = ws.gPos[su(q)];
      keypoints.row(k) = (g + transl).transpose();
      if (!jac) continue;
      KeypointJacobian<Scalar>& Jm = *jacobian;
      Jm.block(3 * k, HandParamLayout::transl, 3, 3).setIdentity();
      // Strict ancestors (the root's rotation included) move g_q; g_q's own rotation does not.
      for (int j = km.parents[su(q)]; j >= 0; j = km.parents[su(j)]) {
        const Mat3<Scalar> D = hat(Vec3<Scalar>(ws.gPos[su(j)] - g)) * ws.gRot[su(j)];
        if (j == 0) {
          Jm.block(3 * k, HandParamLayout::rot, 3, 3) = D;
        } else {
          Jm.block(3 * k, L.joint(j), 3, 3) = D * ws.jr[su(j)];
        }
      }
      if (B > 0) Jm.block(3 * k, L.betas(), 3, B) = ws.dgdb.middleRows(3 * q, 3);
      continue;
    }
    // Tip vertex.
    const int t = km.kpTip[su(k)];
    Vec3<Scalar> vp = km.tipTemplate.row(t).transpose();
    for (int b = 0; b < nb; ++b) vp += km.tipShapedirs.block(3 * t, b, 3, 1) * betas(b);
    if (km.hasPosedirs) {
      for (int c = 0; c < 3; ++c) vp(c) += km.tipPosedirs.row(3 * t + c).dot(ws.feature.transpose());
    }
    const int s0 = km.tipSkinStart[su(t)], s1 = km.tipSkinStart[su(t + 1)];
    Vec3<Scalar> v = Vec3<Scalar>::Zero();
    Mat3<Scalar> M = Mat3<Scalar>::Zero();  // Σ w_i Rg_i
    for (int s = s0; s < s1; ++s) {
      const int i = km.tipSkinJoint[su(s)];
      const Scalar w = km.tipSkinWeight[su(s)];
      v += w * (ws.gRot[su(i)] * (vp - ws.jRest.row(i).transpose()) + ws.gPos[su(i)]);
      M += w * ws.gRot[su(i)];
    }
    keypoints.row(k) = (v + transl).transpose();
    if (!jac) continue;
    KeypointJacobian<Scalar>& Jm = *jacobian;
    Jm.block(3 * k, HandParamLayout::transl, 3, 3).setIdentity();
    // q_i of every skinning joint, once.
    ws.tipQ.resize(static_cast<std::size_t>(s1 - s0));
    for (int s = s0; s < s1; ++s) {
      const int i = km.tipSkinJoint[su(s)];
      ws.tipQ[su(s - s0)] = ws.gRot[su(i)] * (vp - ws.jRest.row(i).transpose()) + ws.gPos[su(i)];
    }
    for (int j = 0; j < J; ++j) {
      Scalar Wj = Scalar(0);
      Vec3<Scalar> Qj = Vec3<Scalar>::Zero();
      for (int s = s0; s < s1; ++s) {
        if (!km.inSubtree(j, km.tipSkinJoint[su(s)])) continue;
        const Scalar w = km.tipSkinWeight[su(s)];
        Wj += w;
        Qj += w * ws.tipQ[su(s - s0)];
      }
      const bool corrective = j > 0 && km.hasPosedirs;
      if (Wj == Scalar(0) && !corrective) continue;
      Mat3<Scalar> D = hat(Vec3<Scalar>(Wj * ws.gPos[su(j)] - Qj)) * ws.gRot[su(j)];
      if (corrective) {
        // M · P_{v,j} · ∂vec(R_j)/∂ε
        const Scalar* p = km.tipPosedirs.data() + static_cast<Eigen::Index>(3 * t) * km.tipPosedirs.cols() + 9 * (j - 1);
        D.noalias() += M * hand_detail::posedirRotationDerivative(p, km.tipPosedirs.cols(), ws.rot[su(j)]);
      }
      if (j == 0) {
        Jm.block(3 * k, HandParamLayout::rot, 3, 3) = D;
      } else {
        Jm.block(3 * k, L.joint(j), 3, 3) = D * ws.jr[su(j)];
      }
    }
    if (B > 0) {
      auto Jb = Jm.block(3 * k, L.betas(), 3, B);
      Jb.noalias() = M * km.tipShapedirs.middleRows(3 * t, 3);
      for (int s = s0; s < s1; ++s) {
        const int i = km.tipSkinJoint[su(s)];
        const Scalar w = km.tipSkinWeight[su(s)];
        Jb += w * ws.dgdb.middleRows(3 * i, 3);
        Jb.noalias() -= (w * ws.gRot[su(i)]) * km.jShapedirs.middleRows(3 * i, 3);
      }
    }
  }
}

}  // namespace hawor
