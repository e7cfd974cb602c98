// hawor/pipeline/world_frame.hpp — the output's world: gravity-aligned, metric, z up (as the
// synthetic generator's room frame and Blender), x, y horizontal with the first camera looking
// along +y, the origin on the floor below the first camera when the floor was found.
//
// Up comes from the floor plane the ground cue found in the SLAM's map (scale/ground_scale.hpp:
// the normal of the level below the cameras, refitted on its points). Without a plane, from the
// cameras themselves: a head-worn camera barely rolls, so its x axis (image right) stays nearly
// horizontal while the head turns and pitches; up is the direction most orthogonal to every
// frame's x axis (the smallest eigenvector of Σ x_t x_tᵀ), signed like the image's up (−y), its
// confidence the eigenvalue gap (a clip that never turns the head leaves up free about x: then
// the mean image up, orthogonalised to x, at low confidence).
#pragma once

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/scale/ground_scale.hpp"

namespace hawor {

template <typename Scalar>
struct WorldFrame {
  SE3<Scalar> fromFirstCamera;     ///< first-camera metric world → the gravity-aligned world
  std::string up = "none";         ///< "floor" (the map's floor plane), "camera" (the cameras' axes), "none"
  Scalar upConfidence = Scalar(0); ///< 0..1
  bool originOnFloor = false;      ///< the origin is on the floor below the first camera (else at it)
  Vec3<Scalar> upFirstCamera = Vec3<Scalar>::Zero();  ///< up in the first camera's world
};

/// Up from the cameras' x axes (camera-to-world rotations R_t): see the file comment.
template <typename Scalar>
Vec3<Scalar> upFromCameraAxes(const std::vector<SE3<Scalar>>& poses, Scalar& confidence) {
  Mat3<Scalar> C = Mat3<Scalar>::Zero();
  Vec3<Scalar> imageUp = Vec3<Scalar>::Zero();
  for (const SE3<Scalar>& P : poses) {
    const Mat3<Scalar> R = P.rotationMatrix();
    C += R.col(0) * R.col(0).transpose();
    imageUp -= R.col(1);
  }
  confidence = Scalar(0);
  if (poses.empty() || !(imageUp.norm() > Scalar(0))) return Vec3<Scalar>::UnitZ();
  imageUp.normalize();
  const Eigen::SelfAdjointEigenSolver<Mat3<Scalar>> es(C / Scalar(poses.size()));
  const Vec3<Scalar> ev = es.eigenvalues();  // ascending
  // The x axes must spread over the horizontal plane for up to be determined (the middle
  // eigenvalue well above the smallest).
  const Scalar gap = ev(1) > Scalar(0) ? Scalar(1) - ev(0) / ev(1) : Scalar(0);
  Vec3<Scalar> up = es.eigenvectors().col(0);
  if (up.dot(imageUp) < Scalar(0)) up = -up;
  if (!(gap > Scalar(0.5))) {
    // the head never turned: the mean image up, orthogonal to the mean x axis
    const Vec3<Scalar> x = es.eigenvectors().col(2);
    up = (imageUp - x * x.dot(imageUp)).normalized();
    confidence = Scalar(0.1);
    return up;
  }
  // a roll of a few degrees is common: even a perfect spread leaves that much doubt
  confidence = Scalar(0.5) * std::min(Scalar(1), (gap - Scalar(0.5)) / Scalar(0.4));
  return up;
}

/// The gravity-aligned world for metric camera poses in the first camera's world. ground: the
/// ground cue's result (map units) or null; scale: metres per map unit.
template <typename Scalar>
WorldFrame<Scalar> gravityAlignedWorld(const std::vector<SE3<Scalar>>& poses, const GroundScaleResult<Scalar>* ground, Scalar scale) {
  WorldFrame<Scalar> w;
  if (poses.empty()) return w;
  Vec3<Scalar> up;
  bool floor = false;
  if (ground && ground->ok() && ground->up.allFinite() && ground->up.norm() > Scalar(0.5)) {
    up = ground->up.normalized();
    w.up = "floor";
    w.upConfidence = ground->confidence;
    floor = !ground->ambiguous && std::isfinite(double(ground->floorLevel)) && std::isfinite(double(scale));
  } else {
    up = upFromCameraAxes(poses, w.upConfidence);
    w.up = "camera";
  }
  w.upFirstCamera = up;
  // Axes: z = up; y = the first camera's viewing direction made horizontal (its x axis × up
  // when it looks straight up or down); x = y × z.
  const Mat3<Scalar> R0 = poses.front().rotationMatrix();
  Vec3<Scalar> y = R0.col(2) - up * up.dot(R0.col(2));
  if (y.norm() < Scalar(1e-3)) y = up.cross(R0.col(0));
  y.normalize();
  const Vec3<Scalar> x = y.cross(up).normalized();
  Mat3<Scalar> G;
  G.row(0) = x.transpose();
  G.row(1) = y.transpose();
  G.row(2) = up.transpose();
  // Origin: the floor point below the first camera (the floor plane up·X = scale·floorLevel in
  // metres), else the first camera.
  const Vec3<Scalar> c0 = poses.front().translation();
  Vec3<Scalar> origin = c0;
  if (floor) {
    origin = c0 - up * (up.dot(c0) - scale * ground->floorLevel);
    w.originOnFloor = true;
  }
  w.fromFirstCamera = SE3<Scalar>(G, Vec3<Scalar>(-(G * origin)));
  return w;
}

}  // namespace hawor
