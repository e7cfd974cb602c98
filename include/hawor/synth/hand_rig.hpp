// hawor/synth/hand_rig.hpp — places and articulates any 21-keypoint hand model (MANO, the
// default WebXR hand, the procedural hand) in terms a motion planner can use: where the wrist
// is, where the fingers point, which way the palm faces, how much each finger curls.
//
// Hand frame of a model (from its rest pose, zero β): a = the unit direction from the wrist
// (keypoint 0) to the middle-finger MCP (keypoint 9), the "finger direction"; n = the volar
// (palm-side) normal (index MCP − wrist) × (pinky MCP − wrist), negated for a left hand (as in
// hand/joint_limits.hpp), made orthogonal to a; F_model = [a, n, a × n] (columns).
// A target frame (finger direction A, volar normal N, in any frame) gives the global orientation
// R = F_target·F_modelᵀ, F_target = [A, N⊥, A × N⊥]; MANO rotates about joint 0, so the wrist lands
// at p when transl = p − J_0(β) (docs/design.md §3).
// Articulation: a Gesture holds a curl in [0, 1] per finger (thumb, index, middle, ring, pinky)
// and a spread in [−1, 1]; each limited joint of JointLimits gets the anatomical angles
//   flexion = lo + (hi − lo)·(0.2 + 0.65·curl),  abduction = spread·s_f·hi (MCP / thumb CMC only),
//   twist = 0,
// with s_f a fixed per-finger factor (fingers fan out), mapped back to an axis-angle by the
// joint's anatomical frame. Joints without limits stay at zero.
// Thread-safety: a built rig is read-only; it keeps a pointer to its model (keep the model alive).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/hand/joint_limits.hpp"

namespace hawor {
namespace synth {

/// Finger curls (thumb, index, middle, ring, pinky; 0 open … 1 fist) and spread (−1 … 1).
template <typename Scalar>
struct Gesture {
  std::array<Scalar, 5> curl{{Scalar(0.2), Scalar(0.2), Scalar(0.2), Scalar(0.2), Scalar(0.2)}};
  Scalar spread = Scalar(0);

  /// a + (b − a)·s, component-wise.
  static Gesture lerp(const Gesture& a, const Gesture& b, Scalar s) {
    Gesture g;
    for (std::size_t i = 0; i < 5; ++i) g.curl[i] = a.curl[i] + (b.curl[i] - a.curl[i]) * s;
    g.spread = a.spread + (b.spread - a.spread) * s;
    return g;
  }
};

template <typename Scalar>
class HandRig {
 public:
  /// Requires a prepared model with the 21 keypoints (docs/design.md §3 order).
  explicit HandRig(const HandModel<Scalar>& model) : model_(&model) {
    if (!model.prepared()) throw Error("synth hand rig: the hand model is not prepared (call prepare())");
    if (model.numKeypoints() != 21) {
      throw Error("synth hand rig: the hand model has " + std::to_string(model.numKeypoints()) +
                  " keypoints; synthetic sequences need the 21 keypoints (wrist, 4 per finger)");
    }
    limits_ = JointLimits<Scalar>::fromModel(model);
    const HandOutput<Scalar> rest = forward(model, HandPose<Scalar>::zero(model));
    auto kp = [&](int k) { return Vec3<Scalar>(rest.keypoints.row(k).transpose()); };
    Vec3<Scalar> a = kp(9) - kp(0);
    Vec3<Scalar> n = (kp(5) - kp(0)).cross(kp(17) - kp(0));
    if (model.isLeft) n = -n;
    if (!(a.norm() > Scalar(1e-6)) || !(n.norm() > Scalar(1e-9))) {
      throw Error("synth hand rig: degenerate rest keypoints (wrist, index / middle / pinky MCP)");
    }
    modelFrame_ = frame(a, n);
    // Joint → finger (0 thumb … 4 pinky) from the keypoint map: keypoint k = 1 + 4·finger + pos.
    const int J = model.numJoints();
    finger_.assign(static_cast<std::size_t>(J), -1);
    for (int k = 1; k < 21; ++k) {
      const int j = model.keypointMap[static_cast<std::size_t>(k)];
      if (j > 0 && j < J) finger_[static_cast<std::size_t>(j)] = (k - 1) / 4;
    }
  }

  const HandModel<Scalar>& model() const { return *model_; }
  const JointLimits<Scalar>& limits() const { return limits_; }
  bool isLeft() const { return model_->isLeft; }
  /// F_model of the file comment.
  const Mat3<Scalar>& modelFrame() const { return modelFrame_; }

  /// [A, N⊥, A × N⊥] for a finger direction A and a volar normal N (any lengths, not parallel).
  static Mat3<Scalar> frame(const Vec3<Scalar>& fingerDir, const Vec3<Scalar>& volar) {
    const Vec3<Scalar> A = fingerDir.normalized();
    Vec3<Scalar> N = volar - volar.dot(A) * A;
    const Scalar nn = N.norm();
    if (!(nn > Scalar(1e-9))) {
      N = (std::abs(A.x()) < Scalar(0.9) ? Vec3<Scalar>::UnitX() : Vec3<Scalar>::UnitY());
      N = (N - N.dot(A) * A).normalized();
    } else {
      N /= nn;
    }
    Mat3<Scalar> F;
    F.col(0) = A;
    F.col(1) = N;
    F.col(2) = A.cross(N);
    return F;
  }

  /// Global orientation (model → target frame) that points the fingers along A with the palm
  /// facing N: R = frame(A, N)·F_modelᵀ.
  Mat3<Scalar> orientation(const Vec3<Scalar>& fingerDir, const Vec3<Scalar>& volar) const {
    return frame(fingerDir, volar) * modelFrame_.transpose();
  }

  /// The (J−1, 3) joint axis-angles of a gesture (file comment).
  Points3<Scalar> jointPose(const Gesture<Scalar>& g) const {
    static const Scalar spreadFactor[5] = {Scalar(0.6), Scalar(0.8), Scalar(0.15), Scalar(-0.5), Scalar(-0.9)};
    const int J = model_->numJoints();
    Points3<Scalar> w = Points3<Scalar>::Zero(J - 1, 3);
    for (int j = 1; j < J; ++j) {
      const int f = finger_[static_cast<std::size_t>(j)];
      if (!limits_.limited(j) || f < 0) continue;
      const JointRange<Scalar>& r = limits_.ranges[static_cast<std::size_t>(j)];
      const JointRole role = limits_.roles[static_cast<std::size_t>(j)];
      const Scalar curl = std::min(Scalar(1), std::max(Scalar(0), g.curl[static_cast<std::size_t>(f)]));
      Vec3<Scalar> a = Vec3<Scalar>::Zero();
      a(0) = r.lo(0) + (r.hi(0) - r.lo(0)) * (Scalar(0.2) + Scalar(0.65) * curl);
      if (role == JointRole::FingerMcp || role == JointRole::ThumbCmc) {
        const Scalar sp = std::min(Scalar(1), std::max(Scalar(-1), g.spread));
        a(1) = sp * spreadFactor[f] * r.hi(1);
      }
      w.row(j - 1) = limits_.axisAngle(j, a).transpose();
    }
    return w;
  }

  /// MANO parameters that put the wrist at `wrist` with orientation R (both in the target
  /// frame), the gesture, and shape β: transl = wrist − J_0(β).
  HandPose<Scalar> pose(const Vec3<Scalar>& wrist, const Mat3<Scalar>& R, const Gesture<Scalar>& g,
                        const VecX<Scalar>& betas, HandWorkspace<Scalar>& ws) const {
    HandPose<Scalar> p;
    p.rot = matrixToAxisAngle(R);
    p.handPose = jointPose(g);
    p.betas = betas;
    shapeHand(*model_, betas, ws);
    p.trans = wrist - Vec3<Scalar>(ws.jRest.row(0).transpose());
    return p;
  }

 private:
  const HandModel<Scalar>* model_;
  JointLimits<Scalar> limits_;
  Mat3<Scalar> modelFrame_;
  std::vector<int> finger_;
};

}  // namespace synth
}  // namespace hawor
