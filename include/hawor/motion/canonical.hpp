// hawor/motion/canonical.hpp — camera → world → canonical space of a hand sequence (docs/design.md §3, §7).
//
// Every transform moves the hand rigidly about its root joint (joint 0), because MANO rotates
// about joint 0 (transformHandFrame): root = trans + J0, offset = trans − root = −J0, where J0 is
// joint 0 of the shaped rest template (J_regressor[0]·(v_template + shapedirs·β)), given per frame
// (T×3) or once (1×3). Camera poses are camera-to-world (R_c2w, t_c2w), one per frame.
#pragma once

#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/motion/hand_motion.hpp"

namespace hawor {

namespace detail {
template <typename Scalar>
void checkPoses(const std::vector<Mat3<Scalar>>& R, const std::vector<Vec3<Scalar>>& t,
                Eigen::Index frames, const char* what) {
  if (static_cast<Eigen::Index>(R.size()) != frames ||
      static_cast<Eigen::Index>(t.size()) != frames)
    throw Error(std::string(what) + ": " + std::to_string(R.size()) + " rotations and " +
                std::to_string(t.size()) + " translations for " + std::to_string(frames) +
                " frames");
}

inline Eigen::Index firstValid(const ValidMask& valid, const char* what) {
  for (size_t i = 0; i < valid.size(); ++i)
    if (valid[i]) return static_cast<Eigen::Index>(i);
  throw Error(std::string(what) + ": no valid frame (the canonical frame is the first valid one)");
}
}  // namespace detail

/// Camera-space hand → world space, per frame t (official cam2world, docs/design.md §3):
///   R_w = R_c2w(t)·R_c,  root_w = R_c2w(t)·(trans_c + J0) + t_c2w(t),  trans_w = root_w − J0
/// i.e. world translation = R_c2w·root + t_c2w + offset with offset = −J0. Every frame is
/// transformed (missing ones too); validity, handPose and betas are copied.
template <typename Scalar>
HandMotion<Scalar> cameraToWorld(const HandMotion<Scalar>& cam,
                                 const std::vector<Mat3<Scalar>>& R_c2w,
                                 const std::vector<Vec3<Scalar>>& t_c2w,
                                 const Points3<Scalar>& J0) {
  cam.validate();
  const Eigen::Index T = cam.frames();
  detail::checkPoses(R_c2w, t_c2w, T, "cameraToWorld");
  HandMotion<Scalar> w = cam;
  for (Eigen::Index t = 0; t < T; ++t)
    transformHandFrame(w, t, R_c2w[static_cast<size_t>(t)], t_c2w[static_cast<size_t>(t)],
                       restRoot(J0, t, T));
  return w;
}

/// Rigid transform from world to a hand's canonical space: x_can = R_w2can·x_w + t_w2can.
/// `origin` is the (first valid) frame whose hand pose defines the canonical frame.
template <typename Scalar>
struct CanonicalFrame {
  Mat3<Scalar> R_w2can = Mat3<Scalar>::Identity();
  Vec3<Scalar> t_w2can = Vec3<Scalar>::Zero();
  Eigen::Index origin = 0;

  Mat3<Scalar> R_can2w() const { return R_w2can.transpose(); }
  Vec3<Scalar> t_can2w() const { return -(R_w2can.transpose() * t_w2can); }
};

/// The canonical frame (rule of canonicalFrame below) defined by frame `origin` of the sequence,
/// valid or not (its values must be finite: e.g. a pre-filled frame of a window without valid
/// frames). Throws if `origin` is out of range or not finite.
template <typename Scalar>
CanonicalFrame<Scalar> canonicalFrameAt(const HandMotion<Scalar>& world, const Points3<Scalar>& J0,
                                        Eigen::Index origin) {
  const Eigen::Index T = world.frames();
  if (origin < 0 || origin >= T)
    throw Error("canonicalFrameAt: frame " + std::to_string(origin) + " outside [0, " +
                std::to_string(T) + ")");
  if (!world.rot.row(origin).allFinite() || !world.trans.row(origin).allFinite())
    throw Error("canonicalFrameAt: frame " + std::to_string(origin) + " is not finite");
  CanonicalFrame<Scalar> c;
  c.origin = origin;
  const Vec3<Scalar> j0 = restRoot(J0, c.origin, T);
  const Vec3<Scalar> a = world.rot.row(c.origin).transpose();
  c.R_w2can = axisAngleToMatrix(a).transpose();
  const Vec3<Scalar> root = world.trans.row(c.origin).transpose() + j0;
  c.t_w2can = -(c.R_w2can * root) + j0;  // − offset = + J0
  return c;
}

/// Canonical frame of a world-space hand sequence (official, docs/design.md §7), from its first valid
/// frame 0':
///   R_w2can = R_root(0')ᵀ,  t_w2can = −R_w2can·root(0') − offset(0'),  offset = −J0(0')
/// Applied with transformHandFrame this gives frame 0' the identity rotation (R_w2can·R_root(0'))
/// and a zero MANO translation:
///   root_can(0') = R_w2can·root(0') + t_w2can = −offset = J0,  trans_can(0') = root_can − J0 = 0.
/// Subtlety: the canonical ORIGIN is therefore not the wrist; the wrist of frame 0' sits at J0(β)
/// in canonical coordinates (the −offset term), so t_w2can depends on the frame-0' shape. With
/// per-frame J0 the other frames use their own J0(t) for the root ↔ trans conversion (their
/// trans_can is then not exactly "root displacement"; for a constant shape it is).
template <typename Scalar>
CanonicalFrame<Scalar> canonicalFrame(const HandMotion<Scalar>& world, const Points3<Scalar>& J0) {
  world.validate();
  return canonicalFrameAt(world, J0, detail::firstValid(world.valid, "canonicalFrame"));
}

/// Applies a canonical frame's world → canonical transform to every frame of a world-space hand.
template <typename Scalar>
HandMotion<Scalar> worldToCanonical(const HandMotion<Scalar>& world,
                                    const CanonicalFrame<Scalar>& c, const Points3<Scalar>& J0) {
  world.validate();
  HandMotion<Scalar> out = world;
  const Eigen::Index T = world.frames();
  for (Eigen::Index t = 0; t < T; ++t)
    transformHandFrame(out, t, c.R_w2can, c.t_w2can, restRoot(J0, t, T));
  return out;
}

/// World → canonical with the canonical frame of the sequence's own first valid frame.
template <typename Scalar>
HandMotion<Scalar> worldToCanonical(const HandMotion<Scalar>& world, const Points3<Scalar>& J0,
                                    CanonicalFrame<Scalar>* frame_out = nullptr) {
  const CanonicalFrame<Scalar> c = canonicalFrame(world, J0);
  if (frame_out) *frame_out = c;
  return worldToCanonical(world, c, J0);
}

/// Canonical → world, the exact inverse of worldToCanonical for the same frame and J0:
///   R_can2w = R_w2canᵀ,  t_can2w = −R_w2canᵀ·t_w2can.
template <typename Scalar>
HandMotion<Scalar> canonicalToWorld(const HandMotion<Scalar>& can, const CanonicalFrame<Scalar>& c,
                                    const Points3<Scalar>& J0) {
  can.validate();
  HandMotion<Scalar> out = can;
  const Mat3<Scalar> R = c.R_can2w();
  const Vec3<Scalar> p = c.t_can2w();
  const Eigen::Index T = can.frames();
  for (Eigen::Index t = 0; t < T; ++t) transformHandFrame(out, t, R, p, restRoot(J0, t, T));
  return out;
}

/// Per-frame camera → canonical transforms of the paper (supplementary, docs/design.md §7), with 0 the
/// first valid frame, A = R_c0·Φ_0:
///   R^{c_t→cano} = A⁻¹·R_{c_t},   t^{c_t→cano} = A⁻¹·(t_{c_t} − t_{c0} − R_{c0}·Γ_0)
///   Φ^cano_t = R^{c_t→cano}·Φ_t,   Γ^cano_t = R^{c_t→cano}·Γ_t + t^{c_t→cano}.
/// Γ must be read as the camera-space ROOT JOINT (trans_c + J0), not as MANO transl: then
/// Γ^cano_t = A⁻¹(root_w(t) − root_w(0)) = root_can(t) − J0(0), which is the canonical MANO
/// translation of the official rule up to J0(0) − J0(t) (zero for a constant shape). Read with
/// Γ = transl, the formula would be off by A⁻¹(R_{c_t} − R_{c0})·J0: it would ignore that MANO
/// rotates about joint 0. This function returns the canonical motion with
/// trans_can = Γ^cano_t + J0(0) − J0(t), and the per-frame transforms if asked.
template <typename Scalar>
HandMotion<Scalar> cameraToCanonicalPaper(const HandMotion<Scalar>& cam,
                                          const std::vector<Mat3<Scalar>>& R_c2w,
                                          const std::vector<Vec3<Scalar>>& t_c2w,
                                          const Points3<Scalar>& J0,
                                          std::vector<Mat3<Scalar>>* R_c2can = nullptr,
                                          std::vector<Vec3<Scalar>>* t_c2can = nullptr) {
  cam.validate();
  const Eigen::Index T = cam.frames();
  detail::checkPoses(R_c2w, t_c2w, T, "cameraToCanonicalPaper");
  const Eigen::Index o = detail::firstValid(cam.valid, "cameraToCanonicalPaper");
  const size_t so = static_cast<size_t>(o);
  const Vec3<Scalar> j0o = restRoot(J0, o, T);
  const Vec3<Scalar> phi0 = cam.rot.row(o).transpose();
  const Mat3<Scalar> A_inv = (R_c2w[so] * axisAngleToMatrix(phi0)).transpose();
  const Vec3<Scalar> gamma0 = cam.trans.row(o).transpose() + j0o;
  if (R_c2can) R_c2can->resize(static_cast<size_t>(T));
  if (t_c2can) t_c2can->resize(static_cast<size_t>(T));
  HandMotion<Scalar> out = cam;
  for (Eigen::Index t = 0; t < T; ++t) {
    const size_t st = static_cast<size_t>(t);
    const Mat3<Scalar> Rt = A_inv * R_c2w[st];
    const Vec3<Scalar> pt = A_inv * (t_c2w[st] - t_c2w[so] - R_c2w[so] * gamma0);
    const Vec3<Scalar> j0 = restRoot(J0, t, T);
    const Vec3<Scalar> phi = cam.rot.row(t).transpose();
    const Vec3<Scalar> gamma = cam.trans.row(t).transpose() + j0;
    const Mat3<Scalar> Rh = Rt * axisAngleToMatrix(phi);
    out.rot.row(t).template head<3>() = matrixToAxisAngle(Rh).transpose();
    out.trans.row(t).template head<3>() = (Rt * gamma + pt + j0o - j0).transpose();
    if (R_c2can) (*R_c2can)[st] = Rt;
    if (t_c2can) (*t_c2can)[st] = pt;
  }
  return out;
}

/// Camera space → canonical space via world (cameraToWorld then worldToCanonical).
template <typename Scalar>
HandMotion<Scalar> cameraToCanonical(const HandMotion<Scalar>& cam,
                                     const std::vector<Mat3<Scalar>>& R_c2w,
                                     const std::vector<Vec3<Scalar>>& t_c2w,
                                     const Points3<Scalar>& J0,
                                     CanonicalFrame<Scalar>* frame_out = nullptr) {
  return worldToCanonical(cameraToWorld(cam, R_c2w, t_c2w, J0), J0, frame_out);
}

}  // namespace hawor
