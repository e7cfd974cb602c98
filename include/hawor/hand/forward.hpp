// hawor/hand/forward.hpp — the MANO forward pass: shape blend, joint regression, pose correctives,
// forward kinematics and linear blend skinning (docs/design.md §3; the `lbs` / `lrotmin` model of the
// official MANO files, full axis-angle pose, NO PCA and NO hands_mean).
//
//   v_shaped = T + S·β                                  (3V)
//   J        = J_reg · v_shaped                         (J×3, from HandModel's precomputed parts)
//   f        = [vec(R_1 − I), …, vec(R_{J−1} − I)]      (9(J−1), row-major vec, as `lrotmin`)
//   v_posed  = v_shaped + P·f
//   G_0 = [R_0 | J_0],  G_j = G_{p(j)} · [R_j | J_j − J_{p(j)}]        (R_0 = global orientation)
//   v_i      = Σ_j w_ij · G_j · [I | −J_j] · [v_posed,i; 1] + transl
//   joints_j = translation of G_j + transl;  keypoints = joints ∪ tip vertices (HandModel map)
//
// The rotation happens about joint 0 (the wrist), so transl is not the wrist position:
// wrist = J_0(β) + transl (docs/design.md §3 "MANO rotates about joint 0").
//
// Repeated calls with one HandWorkspace and one HandOutput do not allocate once their sizes are
// set (Eigen's matrix–vector product uses the caller's buffers). shapeHand() and poseHand() split
// the pass so that a sequence with fixed β pays for the shape blend once; forwardBatch() runs many
// frames with one matrix–matrix product for the pose correctives (the single-frame pass is bound by
// reading the 3V × 9(J−1) corrective matrix).
// Thread-safety: one workspace and output per thread; the model is only read.
#pragma once

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/hand/hand_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace hawor {

/// MANO parameters of one hand in one frame. Angles in radians (axis-angle = axis·angle),
/// translation in metres.
template <typename Scalar>
struct HandPose {
  Vec3<Scalar> rot = Vec3<Scalar>::Zero();  ///< axis-angle of joint 0 (wrist): the global orientation
  Points3<Scalar> handPose;  ///< (J−1)×3 axis-angles of joints 1..J−1, relative to their parent
  VecX<Scalar> betas;        ///< shape coefficients; may be shorter than B (the rest are 0)
  Vec3<Scalar> trans = Vec3<Scalar>::Zero();  ///< added to every output point

  /// Zero pose, zero shape, zero translation for `model` (handPose sized J−1, betas sized B).
  static HandPose zero(const HandModel<Scalar>& model) {
    HandPose p;
    p.handPose = Points3<Scalar>::Zero(model.numJoints() - 1, 3);
    p.betas = VecX<Scalar>::Zero(model.numBetas());
    return p;
  }
};

/// Result of the forward pass (metres, in the frame of the model / of transl).
template <typename Scalar>
struct HandOutput {
  Points3<Scalar> vertices;   ///< (V,3)
  Points3<Scalar> joints;     ///< (J,3) posed joints, in the model's joint order
  Points3<Scalar> keypoints;  ///< (K,3) via HandModel::keypointMap (MANO: 21, OpenPose order)
};

/// Scratch buffers of the forward pass (reuse across calls to avoid allocation).
template <typename Scalar>
struct HandWorkspace {
  VecX<Scalar> vShaped;      ///< 3V, T + S·β
  Points3<Scalar> jRest;     ///< (J,3) rest-pose joints for the current β
  VecX<Scalar> poseFeature;  ///< 9(J−1) (R_j − I) features
  VecX<Scalar> vPosed;       ///< 3V, v_shaped + P·f
  std::vector<Mat3<Scalar>> rot;   ///< local rotations R_j (R_0 = global orientation)
  std::vector<Mat3<Scalar>> gRot;  ///< rotation of the global joint frame G_j
  std::vector<Vec3<Scalar>> gPos;  ///< translation of G_j (= posed joint before transl)
  std::vector<Scalar> skin;        ///< J × 12: G_j·[I | −J_j] as row-major 3×4
  int shapedVertices = -1;         ///< V and J of the last shapeHand(), to catch misuse
  int shapedJoints = -1;
  // The model (address and prepare() count) and β of the last shapeHand(): a call with the same
  // three is skipped, so a sequence with fixed β pays for the shape blend once (exact reuse).
  const void* shapedModel = nullptr;
  std::uint64_t shapedRevision = 0;
  VecX<Scalar> shapedBetas;
};

namespace hand_detail {

// The model was prepared, and its sizes have not changed since (a cheap guard against editing
// fields without calling prepare() again).
template <typename Scalar>
void requirePrepared(const HandModel<Scalar>& model) {
  if (!model.prepared()) throw Error("hand forward: the model is not prepared (call prepare())");
  if (model.jTemplate.rows() != model.numJoints() || model.jShapedirs.cols() != model.numBetas() ||
      model.skinStart.size() != static_cast<std::size_t>(model.numVertices()) + 1) {
    throw Error("hand forward: the model's sizes changed since prepare() (call it again)");
  }
}

}  // namespace hand_detail

namespace hand_detail {

// Y(rows × n, column stride ldy) += A(rows × cols, column-major) · X(cols × n, column stride ldx).
// Where Eigen vectorises (SSE/AVX/NEON) its own kernels are used; Eigen 3.4 has no WebAssembly
// SIMD back end, so there these plain loops run instead, written for the compiler's loop
// vectoriser (simd128 without SLP): rows in tiles of kTile, so that the tile of A (kTile × cols)
// stays in cache while every group of 4 frames passes over it and the 4 output tiles stay in L1;
// A is thus read from memory once for all n frames. Same sums as Eigen's up to order.
#if defined(__GNUC__) || defined(__clang__)
#define HAWOR_RESTRICT __restrict
#else
#define HAWOR_RESTRICT
#endif
// One row tile of G frames: the G output tiles are distinct columns of Y and never overlap A or
// X, which HAWOR_RESTRICT tells the vectoriser.
template <typename Scalar>
void addProductTile4(const Scalar* HAWOR_RESTRICT A, Eigen::Index rows, Eigen::Index cols,
                     const Scalar* HAWOR_RESTRICT X, Eigen::Index ldx, Scalar* HAWOR_RESTRICT y0,
                     Scalar* HAWOR_RESTRICT y1, Scalar* HAWOR_RESTRICT y2, Scalar* HAWOR_RESTRICT y3,
                     Eigen::Index len) {
  for (Eigen::Index k = 0; k < cols; ++k) {
    const Scalar b0 = X[k], b1 = X[ldx + k], b2 = X[2 * ldx + k], b3 = X[3 * ldx + k];
    const Scalar* HAWOR_RESTRICT a = A + k * rows;
    for (Eigen::Index i = 0; i < len; ++i) {
      const Scalar ai = a[i];
      y0[i] += ai * b0;
      y1[i] += ai * b1;
      y2[i] += ai * b2;
      y3[i] += ai * b3;
    }
  }
}
template <typename Scalar>
void addProductTile1(const Scalar* HAWOR_RESTRICT A, Eigen::Index rows, Eigen::Index cols,
                     const Scalar* HAWOR_RESTRICT x, Scalar* HAWOR_RESTRICT y, Eigen::Index len) {
  Eigen::Index k = 0;
  for (; k + 4 <= cols; k += 4) {
    const Scalar b0 = x[k], b1 = x[k + 1], b2 = x[k + 2], b3 = x[k + 3];
    const Scalar* HAWOR_RESTRICT a0 = A + k * rows;
    const Scalar* HAWOR_RESTRICT a1 = a0 + rows;
    const Scalar* HAWOR_RESTRICT a2 = a1 + rows;
    const Scalar* HAWOR_RESTRICT a3 = a2 + rows;
    for (Eigen::Index i = 0; i < len; ++i) y[i] += a0[i] * b0 + a1[i] * b1 + a2[i] * b2 + a3[i] * b3;
  }
  for (; k < cols; ++k) {
    const Scalar b = x[k];
    const Scalar* HAWOR_RESTRICT a = A + k * rows;
    for (Eigen::Index i = 0; i < len; ++i) y[i] += a[i] * b;
  }
}
#undef HAWOR_RESTRICT

template <typename Scalar>
void addProductLoops(const Scalar* A, Eigen::Index rows, Eigen::Index cols, const Scalar* X, Eigen::Index ldx,
                     Eigen::Index n, Scalar* Y, Eigen::Index ldy) {
  constexpr Eigen::Index kTile = 128;
  for (Eigen::Index i0 = 0; i0 < rows; i0 += kTile) {
    const Eigen::Index len = rows - i0 < kTile ? rows - i0 : kTile;
    Eigen::Index j = 0;
    for (; j + 4 <= n; j += 4) {
      Scalar* y = Y + j * ldy + i0;
      addProductTile4(A + i0, rows, cols, X + j * ldx, ldx, y, y + ldy, y + 2 * ldy, y + 3 * ldy, len);
    }
    for (; j < n; ++j) addProductTile1(A + i0, rows, cols, X + j * ldx, Y + j * ldy + i0, len);
  }
}

// Y += A·X for Eigen blocks (A plain column-major, X and Y column-major with inner stride 1).
template <typename Scalar, typename DerivedX, typename DerivedY>
void addProduct(const MatX<Scalar>& A, const Eigen::MatrixBase<DerivedX>& X, Eigen::MatrixBase<DerivedY>& Y) {
#if defined(EIGEN_VECTORIZE)
  Y.noalias() += A * X;
#else
  addProductLoops(A.data(), A.rows(), A.cols(), X.derived().data(), X.outerStride(), X.cols(),
                  Y.derived().data(), Y.outerStride());
#endif
}

}  // namespace hand_detail

/// Shape stage: v_shaped = T + S·β and the rest joints J(β). β may be shorter than B (missing
/// coefficients are zero) but not longer.
template <typename Scalar, typename Derived>
void shapeHand(const HandModel<Scalar>& model, const Eigen::MatrixBase<Derived>& betas,
               HandWorkspace<Scalar>& ws) {
  hand_detail::requirePrepared(model);
  const Eigen::Index V = model.numVertices();
  const Eigen::Index J = model.numJoints();
  const Eigen::Index n = betas.size();
  if (n > model.numBetas()) {
    throw Error("hand forward: " + std::to_string(n) + " shape coefficients given, the model has " +
                std::to_string(model.numBetas()));
  }
  if (!betas.allFinite()) throw Error("hand forward: non-finite shape coefficients");
  if (ws.shapedModel == &model && ws.shapedRevision == model.revision() && ws.shapedVertices == V &&
      ws.shapedJoints == J && ws.shapedBetas.size() == n && (n == 0 || ws.shapedBetas == betas)) {
    return;  // same model and β as the last call: v_shaped and J(β) are still in ws
  }
  // Template plus the used shape directions, as a matrix–vector product over the first n columns.
  ws.vShaped = Eigen::Map<const VecX<Scalar>>(model.vTemplate.data(), 3 * V);
  if (n > 0) {
    const auto S = model.shapedirs.leftCols(n);
    auto out = ws.vShaped.leftCols(1);
#if defined(EIGEN_VECTORIZE)
    out.noalias() += S * betas;
#else
    hand_detail::addProductLoops(S.data(), S.rows(), n, betas.derived().data(), n, 1, out.data(), out.rows());
#endif
  }
  ws.jRest.resize(J, 3);
  for (Eigen::Index j = 0; j < J; ++j) {
    for (int c = 0; c < 3; ++c) {
      Scalar s = model.jTemplate(j, c);
      for (Eigen::Index k = 0; k < n; ++k) s += model.jShapedirs(3 * j + c, k) * betas(k);
      ws.jRest(j, c) = s;
    }
  }
  ws.shapedVertices = static_cast<int>(V);
  ws.shapedJoints = static_cast<int>(J);
  ws.shapedModel = &model;
  ws.shapedRevision = model.revision();
  ws.shapedBetas = betas;
}

namespace hand_detail {

// The row-major (R_j − I) features of joints 1..J−1 (the `lrotmin` pose map), into f[0, 9(J−1)).
template <typename Scalar>
void poseFeatures(int J, const Mat3<Scalar>* rotations, Scalar* f) {
  for (int j = 1; j < J; ++j) {
    const Mat3<Scalar>& R = rotations[j];
    Scalar* fj = f + 9 * (j - 1);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) fj[3 * r + c] = R(r, c) - (r == c ? Scalar(1) : Scalar(0));
    }
  }
}

template <typename Scalar>
void requireShaped(const HandModel<Scalar>& model, const HandWorkspace<Scalar>& ws) {
  if (ws.shapedVertices != model.numVertices() || ws.shapedJoints != model.numJoints()) {
    throw Error("hand forward: the workspace was not shaped for this model (call shapeHand())");
  }
}

// Forward kinematics, skinning of ws.vPosed, joints and keypoints (the tail of poseHand()).
template <typename Scalar>
void kinematicsAndSkinning(const HandModel<Scalar>& model, const Mat3<Scalar>* rotations,
                           const Vec3<Scalar>& transl, HandWorkspace<Scalar>& ws, HandOutput<Scalar>& out) {
  const int V = model.numVertices();
  const int J = model.numJoints();
  // Forward kinematics along the parent table (parents precede children).
  ws.gRot.resize(static_cast<std::size_t>(J));
  ws.gPos.resize(static_cast<std::size_t>(J));
  ws.skin.resize(static_cast<std::size_t>(J) * 12);
  for (int j = 0; j < J; ++j) {
    const std::size_t sj = static_cast<std::size_t>(j);
    const Vec3<Scalar> Jj = ws.jRest.row(j).transpose();
    if (j == 0) {
      ws.gRot[0] = rotations[0];
      ws.gPos[0] = Jj;
    } else {
      const std::size_t p = static_cast<std::size_t>(model.parents[sj]);
      const Vec3<Scalar> Jp = ws.jRest.row(static_cast<Eigen::Index>(p)).transpose();
      ws.gRot[sj] = ws.gRot[p] * rotations[j];
      ws.gPos[sj] = ws.gRot[p] * (Jj - Jp) + ws.gPos[p];
    }
    // A_j = G_j · [I | −J_j]: moves a rest-pose point attached to joint j to its posed place.
    const Vec3<Scalar> t = ws.gPos[sj] - ws.gRot[sj] * Jj;
    Scalar* A = ws.skin.data() + 12 * sj;
    for (int r = 0; r < 3; ++r) {
      A[4 * r + 0] = ws.gRot[sj](r, 0);
      A[4 * r + 1] = ws.gRot[sj](r, 1);
      A[4 * r + 2] = ws.gRot[sj](r, 2);
      A[4 * r + 3] = t(r);
    }
  }
  // Linear blend skinning over each vertex's non-zero weights.
  out.vertices.resize(V, 3);
  const Scalar* vp = ws.vPosed.data();
  const Scalar* skin = ws.skin.data();
  using Vec12 = Eigen::Matrix<Scalar, 12, 1>;  // a local: kept in registers, no alignment assumed
  for (int v = 0; v < V; ++v) {
    // T = Σ_j w_vj A_j as one 12-vector (a fixed-size Eigen accumulator vectorises cleanly; a
    // plain array of 12 floats stalls on store forwarding).
    Vec12 T = Vec12::Zero();
    const int e = model.skinStart[static_cast<std::size_t>(v) + 1];
    for (int k = model.skinStart[static_cast<std::size_t>(v)]; k < e; ++k) {
      T.noalias() += model.skinWeight[static_cast<std::size_t>(k)] *
                     Eigen::Map<const Vec12>(skin + 12 * model.skinJoint[static_cast<std::size_t>(k)]);
    }
    const Scalar x = vp[3 * v], y = vp[3 * v + 1], z = vp[3 * v + 2];
    for (int r = 0; r < 3; ++r) {
      out.vertices(v, r) = T(4 * r) * x + T(4 * r + 1) * y + T(4 * r + 2) * z + T(4 * r + 3) + transl(r);
    }
  }
  out.joints.resize(J, 3);
  for (int j = 0; j < J; ++j) out.joints.row(j) = (ws.gPos[static_cast<std::size_t>(j)] + transl).transpose();
  const int K = model.numKeypoints();
  out.keypoints.resize(K, 3);
  for (int k = 0; k < K; ++k) {
    const int idx = model.keypointMap[static_cast<std::size_t>(k)];
    if (idx < J) {
      out.keypoints.row(k) = out.joints.row(idx);
    } else {
      out.keypoints.row(k) = out.vertices.row(model.tipVertices[static_cast<std::size_t>(idx - J)]);
    }
  }
}

}  // namespace hand_detail

/// Pose stage: correctives, forward kinematics and skinning for local rotations
/// `rotations[0..J−1]` (rotations[0] = global orientation), after shapeHand() on `ws`.
template <typename Scalar>
void poseHand(const HandModel<Scalar>& model, const Mat3<Scalar>* rotations,
              const Vec3<Scalar>& transl, HandWorkspace<Scalar>& ws, HandOutput<Scalar>& out) {
  hand_detail::requirePrepared(model);
  hand_detail::requireShaped(model, ws);
  const int J = model.numJoints();
  // Pose correctives v_posed = v_shaped + P·f: the dominant cost (a 3V × 9(J−1) product).
  if (model.numPoseFeatures() > 0) {
    ws.poseFeature.resize(9 * (J - 1));
    hand_detail::poseFeatures(J, rotations, ws.poseFeature.data());
    ws.vPosed = ws.vShaped;
    auto y = ws.vPosed.leftCols(1);
    hand_detail::addProduct(model.posedirs, ws.poseFeature.leftCols(1), y);
  } else {
    ws.vPosed = ws.vShaped;
  }
  hand_detail::kinematicsAndSkinning(model, rotations, transl, ws, out);
}

namespace hand_detail {

// Checks one frame's parameters against the model and converts its axis-angles to rotations.
template <typename Scalar>
void poseRotations(const HandModel<Scalar>& model, const HandPose<Scalar>& pose, std::vector<Mat3<Scalar>>& rot) {
  const int J = model.numJoints();
  if (pose.handPose.rows() != J - 1) {
    throw Error("hand forward: handPose has " + std::to_string(pose.handPose.rows()) +
                " rows, the model has " + std::to_string(J - 1) + " non-root joints");
  }
  if (!pose.rot.allFinite() || !pose.handPose.allFinite() || !pose.trans.allFinite()) {
    throw Error("hand forward: non-finite pose or translation");
  }
  rot.resize(static_cast<std::size_t>(J));
  rot[0] = axisAngleToMatrix(pose.rot);
  for (int j = 1; j < J; ++j) {
    rot[static_cast<std::size_t>(j)] = axisAngleToMatrix(pose.handPose.row(j - 1).transpose());
  }
}

}  // namespace hand_detail

/// Full forward pass from axis-angle parameters (see the file comment).
template <typename Scalar>
void forward(const HandModel<Scalar>& model, const HandPose<Scalar>& pose, HandWorkspace<Scalar>& ws,
             HandOutput<Scalar>& out) {
  hand_detail::requirePrepared(model);
  hand_detail::poseRotations(model, pose, ws.rot);
  shapeHand(model, pose.betas, ws);
  poseHand(model, ws.rot.data(), pose.trans, ws, out);
}

/// Scratch buffers of forwardBatch().
template <typename Scalar>
struct HandBatchWorkspace {
  HandWorkspace<Scalar> frame;     ///< per-frame buffers
  std::vector<Mat3<Scalar>> rot;   ///< J local rotations of each frame of the current block
  MatX<Scalar> features;           ///< 9(J−1) × block pose features
  MatX<Scalar> correctives;        ///< 3V × block pose correctives
  std::vector<Scalar> apack;       ///< A packing of matmulPacked (no Eigen SIMD kernels)
};

/// The forward pass of n frames: outs[i] = forward(model, poses[i]). The pose correctives of a
/// block of frames are one matrix–matrix product, which reads the 3V × 9(J−1) matrix once per
/// block instead of once per frame: for MANO in double that read (2.5 MB, more than the cache a
/// core can stream from at full speed) bounds the single-frame pass. Blocks of 64 frames amortise
/// it (fewer run the product below the speed of Eigen's matrix kernels). A frame with the β of
/// the frame before reuses its shape blend. Results equal forward()'s up to rounding.
template <typename Scalar>
void forwardBatch(const HandModel<Scalar>& model, const HandPose<Scalar>* poses, int n,
                  HandBatchWorkspace<Scalar>& ws, HandOutput<Scalar>* outs) {
  hand_detail::requirePrepared(model);
  if (n < 0) throw Error("hand forward: negative frame count");
  const int J = model.numJoints();
  const int P = model.numPoseFeatures();
  constexpr int kBlock = 64;
  const std::size_t nJ = static_cast<std::size_t>(J);
  ws.rot.resize(nJ * kBlock);
  for (int b0 = 0; b0 < n; b0 += kBlock) {
    const int m = n - b0 < kBlock ? n - b0 : kBlock;
    for (int i = 0; i < m; ++i) {
      // Rotations of the block's frames (validated here, before any output is written).
      hand_detail::poseRotations(model, poses[b0 + i], ws.frame.rot);
      std::copy(ws.frame.rot.begin(), ws.frame.rot.end(), ws.rot.begin() + static_cast<std::ptrdiff_t>(nJ * i));
    }
    if (P > 0) {
      // Buffers sized for a full block once (a shorter last block uses their left columns).
      if (ws.features.rows() != P || ws.features.cols() != kBlock) ws.features.resize(P, kBlock);
      if (ws.correctives.rows() != model.posedirs.rows() || ws.correctives.cols() != kBlock) {
        ws.correctives.resize(model.posedirs.rows(), kBlock);
      }
      for (int i = 0; i < m; ++i) {
        hand_detail::poseFeatures(J, ws.rot.data() + nJ * i, ws.features.col(i).data());
      }
#if defined(EIGEN_VECTORIZE)
      ws.correctives.leftCols(m).setZero();
      auto C = ws.correctives.leftCols(m);
      hand_detail::addProduct(model.posedirs, ws.features.leftCols(m), C);
#else
      // Cᵀ (m × 3V, row-major = C column-major) = Fᵀ (m × P, row-major = F) · posedirsᵀ, with
      // the register-blocked kernel (f64x2 / f32x4 tiles): about twice the plain loops' speed.
      ws.apack.resize(static_cast<std::size_t>(packedScratchSize(kBlock, P)));
      matmulPacked(ws.features.data(), Eigen::Index(P), Eigen::Index(m), model.posedirsPacked,
                   ws.correctives.data(), ws.correctives.rows(), static_cast<const Scalar*>(nullptr),
                   ws.apack.data());
#endif
    }
    for (int i = 0; i < m; ++i) {
      const HandPose<Scalar>& pose = poses[b0 + i];
      shapeHand(model, pose.betas, ws.frame);
      if (P > 0) {
        ws.frame.vPosed.noalias() = ws.frame.vShaped + ws.correctives.col(i);
      } else {
        ws.frame.vPosed = ws.frame.vShaped;
      }
      hand_detail::kinematicsAndSkinning(model, ws.rot.data() + nJ * i, pose.trans, ws.frame, outs[b0 + i]);
    }
  }
}

/// Convenience overload that allocates its own workspace and output.
template <typename Scalar>
HandOutput<Scalar> forward(const HandModel<Scalar>& model, const HandPose<Scalar>& pose) {
  HandWorkspace<Scalar> ws;
  HandOutput<Scalar> out;
  forward(model, pose, ws, out);
  return out;
}

}  // namespace hawor
