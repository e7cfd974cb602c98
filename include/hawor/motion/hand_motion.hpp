// hawor/motion/hand_motion.hpp — one hand's MANO parameter sequence, and rigid motion of a hand.
//
// Units and frames: metres and radians; the frame (camera, world, canonical) is the caller's and
// is said by the function that produced the motion. Thread-safety: plain data.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/motion/sequence.hpp"

namespace hawor {

/// MANO parameters of one hand over T frames. Rows are frames. The fields are HandPose's
/// (hand/forward.hpp), one name per concept: files write them under the official output keys
/// rot, trans, hand_pose, betas.
///   rot        T×3   global orientation, axis-angle (rotation about joint 0, docs/design.md §3)
///   trans      T×3   MANO translation `transl` (joint 0 sits at trans + J0(β))
///   handPose  T×45  15 joint rotations, axis-angle, no PCA, no hands_mean (docs/design.md §3)
///   betas      T×10  shape
/// Other skinned hands with the same structure are accepted (zeros() makes MANO's sizes):
/// handPose T×3K for K joint rotations (the default WebXR hand: K = 24) and betas T×B for any
/// B ≥ 0 (the WebXR hand: B = 0).
///   valid      T     nonzero = observed frame; the content of missing frames is ignored by
///                    validate() and overwritten by the fills (it may be zeros or NaN).
template <typename Scalar>
struct HandMotion {
  static constexpr Eigen::Index kPoseDim = 45;
  static constexpr Eigen::Index kBetaDim = 10;

  Sequence<Scalar> rot;
  Sequence<Scalar> trans;
  Sequence<Scalar> handPose;
  Sequence<Scalar> betas;
  ValidMask valid;

  Eigen::Index frames() const { return rot.rows(); }

  /// T frames of zeros, every frame marked valid (or missing with `valid_value` = 0).
  static HandMotion zeros(Eigen::Index frames, std::uint8_t valid_value = 1) {
    if (frames < 0) throw Error("HandMotion::zeros: negative frame count");
    HandMotion m;
    m.rot = Sequence<Scalar>::Zero(frames, 3);
    m.trans = Sequence<Scalar>::Zero(frames, 3);
    m.handPose = Sequence<Scalar>::Zero(frames, kPoseDim);
    m.betas = Sequence<Scalar>::Zero(frames, kBetaDim);
    m.valid.assign(static_cast<size_t>(frames), valid_value);
    return m;
  }

  /// Throws hawor::Error naming the field when shapes disagree (row counts, 3 columns for rot and
  /// trans, a multiple of 3 for handPose) or a valid frame holds a non-finite value.
  void validate() const {
    const Eigen::Index T = rot.rows();
    auto shape = [T](const Sequence<Scalar>& m, Eigen::Index cols, const char* name) {
      if (m.rows() != T || m.cols() != cols)
        throw Error("HandMotion: " + std::string(name) + " is " + std::to_string(m.rows()) + "x" +
                    std::to_string(m.cols()) + ", expected " + std::to_string(T) + "x" +
                    std::to_string(cols));
    };
    shape(rot, 3, "rot");
    shape(trans, 3, "trans");
    if (handPose.cols() % 3 != 0)
      throw Error("HandMotion: handPose has " + std::to_string(handPose.cols()) +
                  " columns, not a multiple of 3 (axis-angle triples; MANO: " +
                  std::to_string(kPoseDim) + ")");
    shape(handPose, handPose.cols(), "handPose");
    shape(betas, betas.cols(), "betas");
    checkMask(valid, T, "HandMotion");
    for (Eigen::Index t = 0; t < T; ++t) {
      if (!valid[static_cast<size_t>(t)]) continue;
      const char* bad = !rot.row(t).allFinite()         ? "rot"
                        : !trans.row(t).allFinite()     ? "trans"
                        : !handPose.row(t).allFinite() ? "handPose"
                        : !betas.row(t).allFinite()     ? "betas"
                                                        : nullptr;
      if (bad)
        throw Error("HandMotion: non-finite " + std::string(bad) + " at valid frame " +
                    std::to_string(t));
    }
  }
};

/// Rest position of joint 0 for frame t: `J0` holds either one row (same shape for every frame)
/// or one row per frame (J0(β_t)). Throws on any other row count.
template <typename Scalar>
Vec3<Scalar> restRoot(const Points3<Scalar>& J0, Eigen::Index t, Eigen::Index frames) {
  if (J0.rows() == 1) return J0.row(0).transpose();
  if (J0.rows() != frames)
    throw Error("rest joint 0 (J0) has " + std::to_string(J0.rows()) + " rows; expected 1 or " +
                std::to_string(frames));
  return J0.row(t).transpose();
}

/// Moves frame t of a hand rigidly by x ↦ R·x + p (R a rotation). MANO rotates about joint 0, so
/// the root joint (trans + J0) is the point that moves:
///   R_hand' = R·R_hand,  root' = R·(trans + J0) + p,  trans' = root' − J0
/// (i.e. trans' = R·trans + p + (R − I)·J0; the offset transl − root = −J0 is unchanged).
/// handPose and betas are intrinsic and unchanged.
template <typename Scalar>
void transformHandFrame(HandMotion<Scalar>& m, Eigen::Index t, const Mat3<Scalar>& R,
                        const Vec3<Scalar>& p, const Vec3<Scalar>& J0) {
  const Vec3<Scalar> a = m.rot.row(t).transpose();
  const Mat3<Scalar> Rh = axisAngleToMatrix(a);
  const Mat3<Scalar> Rn = R * Rh;
  const Vec3<Scalar> root = m.trans.row(t).transpose() + J0;
  const Vec3<Scalar> root_n = R * root + p;
  m.rot.row(t).template head<3>() = matrixToAxisAngle(Rn).transpose();
  m.trans.row(t).template head<3>() = (root_n - J0).transpose();
}

}  // namespace hawor
