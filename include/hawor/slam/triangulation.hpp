// hawor/slam/triangulation.hpp — two-view triangulation of a point from normalised image
// coordinates, and the checks a new map point has to pass (depths, parallax, reprojection).
//
// Poses here are WORLD-TO-CAMERA (T_c_w: X_c = R·X_w + t), the projection matrices [R | t] of
// Hartley & Zisserman; x = (X_c.x/X_c.z, X_c.y/X_c.z) are normalised coordinates (K⁻¹ applied).
//   DLT (H&Z §12.2): the 4×4 system x·P₃ − P₁ = 0, y·P₃ − P₂ = 0 for both views, solved by the
//     right singular vector of the smallest singular value (homogeneous, so far points are fine).
//   Midpoint: the point halfway between the closest points of the two viewing rays (cheap; equal
//     to DLT for noise-free data).
// Pure functions, thread-safe.
#pragma once

#include <Eigen/SVD>
#include <cmath>
#include <limits>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"

namespace hawor {

/// Depths, parallax and reprojection errors of a triangulated point (see triangulationQuality).
template <typename Scalar>
struct TriangulationQuality {
  Scalar depth1 = Scalar(0), depth2 = Scalar(0);  ///< z in camera 1 and camera 2
  Scalar cosParallax = Scalar(1);  ///< cosine of the angle between the two viewing rays at X
  Scalar err1Sq = Scalar(0), err2Sq = Scalar(0);  ///< squared reprojection errors (normalised)

  /// Parallax angle in degrees.
  Scalar parallaxDeg() const {
    using std::acos;
    const Scalar c = cosParallax > Scalar(1) ? Scalar(1)
                     : (cosParallax < Scalar(-1) ? Scalar(-1) : cosParallax);
    return acos(c) * Scalar(180) / Constants<Scalar>::pi();
  }
};

/// DLT triangulation (file comment) of x1 (view T_c1_w) ↔ x2 (view T_c2_w) into the world point X.
/// Returns false when the solution is at infinity (parallel rays) or not finite.
template <typename Scalar>
bool triangulateDLT(const SE3<Scalar>& T_c1_w, const SE3<Scalar>& T_c2_w, const Vec2<Scalar>& x1,
                    const Vec2<Scalar>& x2, Vec3<Scalar>& X) {
  using M34 = Eigen::Matrix<Scalar, 3, 4>;
  using M4 = Eigen::Matrix<Scalar, 4, 4>;
  M34 P1, P2;
  P1.template leftCols<3>() = T_c1_w.rotationMatrix();
  P1.col(3) = T_c1_w.translation();
  P2.template leftCols<3>() = T_c2_w.rotationMatrix();
  P2.col(3) = T_c2_w.translation();
  M4 A;
  A.row(0) = x1(0) * P1.row(2) - P1.row(0);
  A.row(1) = x1(1) * P1.row(2) - P1.row(1);
  A.row(2) = x2(0) * P2.row(2) - P2.row(0);
  A.row(3) = x2(1) * P2.row(2) - P2.row(1);
  for (int r = 0; r < 4; ++r) {  // equilibrate the rows (each is an independent equation)
    const Scalar nr = A.row(r).norm();
    if (nr > Scalar(0)) A.row(r) /= nr;
  }
  if (!A.allFinite()) return false;
  const Eigen::JacobiSVD<M4> svd(A, Eigen::ComputeFullV);
  const Eigen::Matrix<Scalar, 4, 1> h = svd.matrixV().col(3);
  const Scalar hmax = h.template head<3>().cwiseAbs().maxCoeff();
  if (!(std::abs(h(3)) > Scalar(64) * std::numeric_limits<Scalar>::epsilon() * hmax)) return false;
  X = h.template head<3>() / h(3);
  return X.allFinite();
}

/// Midpoint triangulation (file comment). Returns false for (near-)parallel rays.
template <typename Scalar>
bool triangulateMidpoint(const SE3<Scalar>& T_c1_w, const SE3<Scalar>& T_c2_w,
                         const Vec2<Scalar>& x1, const Vec2<Scalar>& x2, Vec3<Scalar>& X) {
  using V3 = Eigen::Matrix<Scalar, 3, 1>;
  const Mat3<Scalar> R1t = T_c1_w.rotationMatrix().transpose();
  const Mat3<Scalar> R2t = T_c2_w.rotationMatrix().transpose();
  const V3 c1 = -(R1t * T_c1_w.translation()), c2 = -(R2t * T_c2_w.translation());
  const V3 d1 = R1t * V3(x1(0), x1(1), Scalar(1)), d2 = R2t * V3(x2(0), x2(1), Scalar(1));
  const V3 b = c2 - c1;
  // Closest points c1 + s·d1 and c2 + u·d2 (cross-product form, no cancellation for small angles):
  // s = ((b × d2)·n)/|n|², u = ((b × d1)·n)/|n|², n = d1 × d2.
  const V3 nrm = d1.cross(d2);
  const Scalar den = nrm.squaredNorm();
  if (!(den > Scalar(16) * std::numeric_limits<Scalar>::epsilon() * d1.squaredNorm() * d2.squaredNorm())) {
    return false;
  }
  const Scalar s = b.cross(d2).dot(nrm) / den;
  const Scalar u = b.cross(d1).dot(nrm) / den;
  X = Scalar(0.5) * ((c1 + s * d1) + (c2 + u * d2));
  return X.allFinite();
}

/// Depths, parallax angle (between the rays from the two centres to X) and squared normalised
/// reprojection errors of the world point X in the two views.
template <typename Scalar>
TriangulationQuality<Scalar> triangulationQuality(const SE3<Scalar>& T_c1_w,
                                                  const SE3<Scalar>& T_c2_w,
                                                  const Vec2<Scalar>& x1, const Vec2<Scalar>& x2,
                                                  const Vec3<Scalar>& X) {
  using V3 = Eigen::Matrix<Scalar, 3, 1>;
  TriangulationQuality<Scalar> q;
  const V3 p1 = T_c1_w * X, p2 = T_c2_w * X;
  q.depth1 = p1(2);
  q.depth2 = p2(2);
  // Rays from the centres: in camera frames they are p1 and p2; rotate both into the world.
  const V3 r1 = T_c1_w.rotation().inverse() * Vec3<Scalar>(p1);
  const V3 r2 = T_c2_w.rotation().inverse() * Vec3<Scalar>(p2);
  const Scalar nn = r1.norm() * r2.norm();
  q.cosParallax = nn > Scalar(0) ? r1.dot(r2) / nn : Scalar(1);
  const Scalar inf = std::numeric_limits<Scalar>::infinity();
  using V2 = Eigen::Matrix<Scalar, 2, 1>;
  q.err1Sq = p1(2) != Scalar(0) ? (V2(p1(0) / p1(2), p1(1) / p1(2)) - V2(x1)).squaredNorm() : inf;
  q.err2Sq = p2(2) != Scalar(0) ? (V2(p2(0) / p2(2), p2(1) / p2(2)) - V2(x2)).squaredNorm() : inf;
  return q;
}

}  // namespace hawor
