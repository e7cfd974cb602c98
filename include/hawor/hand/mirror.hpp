// hawor/hand/mirror.hpp — left/right hand conventions (docs/design.md §3).
//
// The left MANO model is the mirror image of the right one under M = diag(−1, 1, 1) (x negated).
// Mirroring a rotation conjugates it, R_L = M·R_R·M, and for an axis-angle w that is
// M·R(w)·M = R(−M·w) (a reflection reverses the sense of rotation), i.e. w_L = (w_x, −w_y, −w_z):
// the official pipeline runs a left hand through the right-hand network on a flipped image and
// then negates the y and z components of every axis-angle. With translations mirrored too
// (t_L = M·t_R) the left model reproduces the mirrored right hand exactly:
//   leftModel(mirrorPose(p)) = M · rightModel(p)      (vertices, joints, keypoints).
#pragma once

#include "hawor/common.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/hand_model.hpp"

namespace hawor {

/// Axis-angle of the mirrored rotation: (x, y, z) → (x, −y, −z).
template <typename Scalar>
Vec3<Scalar> mirrorAxisAngle(const Vec3<Scalar>& w) {
  return Vec3<Scalar>(w.x(), -w.y(), -w.z());
}

/// Right-hand parameters → the left-hand parameters of the mirror image (and back: the map is an
/// involution). Negates y and z of the global orientation and of every joint axis-angle and x of
/// the translation; the shape coefficients are unchanged.
template <typename Scalar>
HandPose<Scalar> mirrorPose(const HandPose<Scalar>& p) {
  HandPose<Scalar> m = p;
  m.rot = mirrorAxisAngle<Scalar>(p.rot);
  m.handPose.col(1) = -p.handPose.col(1);
  m.handPose.col(2) = -p.handPose.col(2);
  m.trans.x() = -p.trans.x();
  return m;
}

/// Reverses the winding of every triangle ([0,1,2] → [0,2,1]): the left model shares the right
/// one's face list, so its outward normals need the opposite winding.
inline Faces flipFaceWinding(const Faces& f) {
  Faces out = f;
  out.col(1) = f.col(2);
  out.col(2) = f.col(1);
  return out;
}

/// The known bug of the released MANO_LEFT file (docs/design.md §3): its shape directions were not
/// mirrored in x. Applies `shapedirs[:, 0, :] *= −1` (the x rows of the (3V, B) matrix).
template <typename Scalar>
void fixLeftShapedirs(HandModel<Scalar>& model) {
  for (Eigen::Index v = 0; v < model.shapedirs.rows() / 3; ++v) model.shapedirs.row(3 * v) *= Scalar(-1);
}

/// The exact mirror image of a model under M = diag(−1, 1, 1): template and shape directions get
/// x negated, the pose correctives P become M_v·P·K with K the sign of the (R − I) feature
/// (r, c) under R → M·R·M (that is m_r·m_c), the face winding is reversed, everything else is
/// shared. Mirroring a right model gives a left model that satisfies the file comment's identity.
/// The result is prepared.
template <typename Scalar>
HandModel<Scalar> mirrorHandModel(const HandModel<Scalar>& in) {
  HandModel<Scalar> out = in;
  const Eigen::Index V = in.vTemplate.rows();
  out.vTemplate.col(0) = -in.vTemplate.col(0);
  for (Eigen::Index v = 0; v < V && in.shapedirs.cols() > 0; ++v) out.shapedirs.row(3 * v) = -in.shapedirs.row(3 * v);
  if (in.posedirs.size() > 0) {
    for (Eigen::Index f = 0; f < in.posedirs.cols(); ++f) {
      const int r = static_cast<int>(f % 9) / 3;
      const int c = static_cast<int>(f % 9) % 3;
      const Scalar k = ((r == 0) != (c == 0)) ? Scalar(-1) : Scalar(1);  // m_r·m_c
      for (Eigen::Index v = 0; v < V; ++v) {
        out.posedirs(3 * v + 0, f) = -k * in.posedirs(3 * v + 0, f);
        out.posedirs(3 * v + 1, f) = k * in.posedirs(3 * v + 1, f);
        out.posedirs(3 * v + 2, f) = k * in.posedirs(3 * v + 2, f);
      }
    }
  }
  out.faces = flipFaceWinding(in.faces);
  out.isLeft = !in.isLeft;
  out.prepare();
  return out;
}

}  // namespace hawor
