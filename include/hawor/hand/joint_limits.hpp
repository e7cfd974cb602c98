// hawor/hand/joint_limits.hpp — anatomical joint frames, soft joint limits and the pose prior of
// the hand fit, built from any hand model's rest geometry (MANO's 16 joints, the 25-joint default
// hand, ...).
//
// Every local joint rotation of a MANO-style model acts about axes of the model's rest frame
// (the rest pose has identity joint frames), so an axis-angle w_j splits linearly into
//   a_j = F_j·w_j = (flexion, abduction, twist),   F_j rows = (e_flex, e_abd, e_twist),
// with e_twist = the bone direction d (joint → next keypoint of its finger, rest pose),
// e_flex = d × n⊥ (n⊥ = the volar direction made orthogonal to d), e_abd = e_twist × e_flex.
// The volar (palm-side) normal is n = (index MCP − wrist) × (pinky MCP − wrist) for a right
// hand, negated for a left one (HandModel::isLeft), so positive flexion curls a finger towards
// the palm (a small rotation about e_flex moves d by θ·n⊥). For the thumb, n is replaced by the
// mean of the volar direction and the direction from the joint to the middle-finger MCP, both
// made orthogonal to d (the thumb flexes across the palm).
//
// Roles come from the keypoint map when it has the 21 OpenPose/MediaPipe keypoints (docs/design.md §3:
// 0 wrist, 1–4 thumb CMC/MCP/IP/tip, then 4 per finger MCP/PIP/DIP/tip). Joints that are no
// keypoint (the default hand's finger metacarpals) or are tip keypoints, and joints whose rotation
// moves no keypoint at all, are Fixed (strong prior to zero: they cannot be observed). Without a
// 21-keypoint map every joint is Free (weak prior, no limits) unless it moves no keypoint.
//
// Default ranges (radians, lo..hi per axis: flexion; abduction; twist) — defaultJointRange():
//   finger MCP   −0.4..1.6;  ±0.35;  ±0.2
//   finger PIP   −0.1..1.9;  ±0.1;   ±0.1
//   finger DIP   −0.1..1.9;  ±0.1;   ±0.1
//   thumb CMC    −0.6..1.2;  ±0.6;   ±0.6   (wider: the thumb's frame is only approximate)
//   thumb MCP    −0.3..1.2;  ±0.3;   ±0.3
//   thumb IP     −0.3..1.6;  ±0.15;  ±0.15
// Prior scales (flexion, abduction, twist) multiply the weak zero prior: (1, 2, 3) for limited
// joints (sideways and twisting motion is rarer than flexion), (1, 1, 1) for Free joints.
// Thread-safety: a plain value, read-only after fromModel().
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/hand/portable_random.hpp"

namespace hawor {

enum class JointRole { Root, ThumbCmc, ThumbMcp, ThumbIp, FingerMcp, FingerPip, FingerDip, Free, Fixed };

/// Lower / upper bounds of (flexion, abduction, twist) in radians and the per-axis prior scale.
template <typename Scalar>
struct JointRange {
  Vec3<Scalar> lo = Vec3<Scalar>::Constant(-Scalar(1e3));
  Vec3<Scalar> hi = Vec3<Scalar>::Constant(Scalar(1e3));
  Vec3<Scalar> priorScale = Vec3<Scalar>::Ones();
};

/// The documented default ranges of a role (file comment). Root, Free and Fixed have no bounds.
template <typename Scalar>
JointRange<Scalar> defaultJointRange(JointRole role) {
  JointRange<Scalar> r;
  auto set = [&](double flo, double fhi, double abd, double tw) {
    r.lo = Vec3<Scalar>(Scalar(flo), Scalar(-abd), Scalar(-tw));
    r.hi = Vec3<Scalar>(Scalar(fhi), Scalar(abd), Scalar(tw));
    r.priorScale = Vec3<Scalar>(Scalar(1), Scalar(2), Scalar(3));
  };
  switch (role) {
    case JointRole::FingerMcp: set(-0.4, 1.6, 0.35, 0.2); break;
    case JointRole::FingerPip: set(-0.1, 1.9, 0.1, 0.1); break;
    case JointRole::FingerDip: set(-0.1, 1.9, 0.1, 0.1); break;
    case JointRole::ThumbCmc: set(-0.6, 1.2, 0.6, 0.6); break;
    case JointRole::ThumbMcp: set(-0.3, 1.2, 0.3, 0.3); break;
    case JointRole::ThumbIp: set(-0.3, 1.6, 0.15, 0.15); break;
    default: break;
  }
  return r;
}

/// True for the roles that have anatomical bounds.
inline bool jointRoleLimited(JointRole role) {
  return role != JointRole::Root && role != JointRole::Free && role != JointRole::Fixed;
}

template <typename Scalar>
struct JointLimits {
  std::vector<JointRole> roles;        ///< (J)
  std::vector<Mat3<Scalar>> frames;    ///< (J) rows e_flex, e_abd, e_twist (model rest frame)
  std::vector<JointRange<Scalar>> ranges;  ///< (J)

  int numJoints() const { return static_cast<int>(roles.size()); }
  bool limited(int j) const { return jointRoleLimited(roles[static_cast<std::size_t>(j)]); }
  /// (flexion, abduction, twist) = F_j·w of joint j's axis-angle w.
  Vec3<Scalar> anatomical(int j, const Vec3<Scalar>& w) const { return frames[static_cast<std::size_t>(j)] * w; }
  /// The axis-angle F_jᵀ·a with anatomical components a.
  Vec3<Scalar> axisAngle(int j, const Vec3<Scalar>& a) const {
    return frames[static_cast<std::size_t>(j)].transpose() * a;
  }
  /// Per-axis distance of w's anatomical angles outside joint j's range (0 inside), signed:
  /// a − hi above, a − lo below.
  Vec3<Scalar> violation(int j, const Vec3<Scalar>& w) const {
    const Vec3<Scalar> a = anatomical(j, w);
    const JointRange<Scalar>& r = ranges[static_cast<std::size_t>(j)];
    Vec3<Scalar> v;
    for (int c = 0; c < 3; ++c) v(c) = a(c) > r.hi(c) ? a(c) - r.hi(c) : (a(c) < r.lo(c) ? a(c) - r.lo(c) : Scalar(0));
    return v;
  }

  /// Roles, frames and default ranges from a prepared model's rest geometry (file comment).
  static JointLimits fromModel(const HandModel<Scalar>& model) {
    if (!model.prepared()) throw Error("joint limits: the model is not prepared (call prepare())");
    const int J = model.numJoints();
    const int K = model.numKeypoints();
    auto su = [](int i) { return static_cast<std::size_t>(i); };
    JointLimits L;
    L.roles.assign(su(J), JointRole::Free);
    L.roles[0] = JointRole::Root;
    L.frames.assign(su(J), Mat3<Scalar>::Identity());
    // Which joints move a keypoint: strict ancestors of joint keypoints, and every joint (with its
    // ancestors) that skins a tip-vertex keypoint.
    std::vector<unsigned char> moves(su(J), 0);
    auto markAncestorsFrom = [&](int j) {
      for (int a = j; a >= 0; a = model.parents[su(a)]) moves[su(a)] = 1;
    };
    for (int k = 0; k < K; ++k) {
      const int idx = model.keypointMap[su(k)];
      if (idx < J) {
        if (idx > 0) markAncestorsFrom(model.parents[su(idx)]);
      } else {
        const int v = model.tipVertices[su(idx - J)];
        for (int j = 0; j < J; ++j)
          if (model.weights(v, j) != Scalar(0)) markAncestorsFrom(j);
      }
    }
    if (K == 21) {
      const HandOutput<Scalar> rest = forward(model, HandPose<Scalar>::zero(model));
      auto kp = [&](int k) { return Vec3<Scalar>(rest.keypoints.row(k).transpose()); };
      for (int j = 1; j < J; ++j) L.roles[su(j)] = JointRole::Fixed;  // unmapped joints
      Vec3<Scalar> n = (kp(5) - kp(0)).cross(kp(17) - kp(0));
      if (model.isLeft) n = -n;
      const Scalar nn = n.norm();
      n = nn > Scalar(0) ? Vec3<Scalar>(n / nn) : Vec3<Scalar>::UnitZ();
      for (int k = 1; k < 21; ++k) {
        const int j = model.keypointMap[su(k)];
        if (j >= J || j == 0) continue;  // tip vertex, or a map that repeats the wrist
        const int finger = (k - 1) / 4, pos = (k - 1) % 4;
        if (pos == 3) continue;  // tip joint: stays Fixed
        static const JointRole thumb[3] = {JointRole::ThumbCmc, JointRole::ThumbMcp, JointRole::ThumbIp};
        static const JointRole other[3] = {JointRole::FingerMcp, JointRole::FingerPip, JointRole::FingerDip};
        L.roles[su(j)] = finger == 0 ? thumb[pos] : other[pos];
        // Bone direction to the next keypoint of the finger.
        Vec3<Scalar> d = kp(k + 1) - kp(k);
        const Scalar dn = d.norm();
        if (!(dn > Scalar(0))) {
          L.roles[su(j)] = JointRole::Free;
          continue;
        }
        d /= dn;
        auto perp = [&](const Vec3<Scalar>& a) { return Vec3<Scalar>(a - a.dot(d) * d); };
        Vec3<Scalar> volar = perp(n);
        if (finger == 0) {
          Vec3<Scalar> across = perp(kp(9) - kp(k));
          const Scalar an = across.norm();
          if (an > Scalar(0)) across /= an;
          const Scalar vn = volar.norm();
          if (vn > Scalar(0)) volar /= vn;
          volar = volar + across;
        }
        Scalar vn = volar.norm();
        if (!(vn > Scalar(1e-6))) {  // bone along the normal: any perpendicular will do
          volar = perp(std::abs(d(0)) < Scalar(0.9) ? Vec3<Scalar>::UnitX() : Vec3<Scalar>::UnitY());
          vn = volar.norm();
        }
        volar /= vn;
        const Vec3<Scalar> eFlex = d.cross(volar);
        const Vec3<Scalar> eAbd = d.cross(eFlex);
        Mat3<Scalar> F;
        F.row(0) = eFlex.transpose();
        F.row(1) = eAbd.transpose();
        F.row(2) = d.transpose();
        L.frames[su(j)] = F;
      }
    }
    for (int j = 1; j < J; ++j) {
      if (!moves[su(j)]) L.roles[su(j)] = JointRole::Fixed;
    }
    L.ranges.resize(su(J));
    for (int j = 0; j < J; ++j) L.ranges[su(j)] = defaultJointRange<Scalar>(L.roles[su(j)]);
    return L;
  }
};

/// A random plausible articulation: each limited joint's anatomical angles uniform in the middle
/// `fraction` of its range (fraction 1 = the whole range), mapped back to an axis-angle; other
/// joints zero. Returns the (J−1,3) handPose of HandPose. `rng` is any standard engine (the same
/// numbers on every platform, see portable_random.hpp).
template <typename Scalar, typename Rng>
Points3<Scalar> sampleJointPose(const JointLimits<Scalar>& limits, Rng& rng, double fraction = 1.0) {
  const int J = limits.numJoints();
  Points3<Scalar> w = Points3<Scalar>::Zero(J - 1, 3);
  for (int j = 1; j < J; ++j) {
    if (!limits.limited(j)) continue;
    const JointRange<Scalar>& r = limits.ranges[static_cast<std::size_t>(j)];
    Vec3<Scalar> a;
    for (int c = 0; c < 3; ++c) {
      const double lo = static_cast<double>(r.lo(c)), hi = static_cast<double>(r.hi(c));
      const double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo) * fraction;
      a(c) = static_cast<Scalar>(mid - half + 2.0 * half * uniform01(rng));
    }
    w.row(j - 1) = limits.axisAngle(j, a).transpose();
  }
  return w;
}

}  // namespace hawor
