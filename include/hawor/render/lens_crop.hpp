// hawor/render/lens_crop.hpp — a locally perspective crop of an image taken through a lens: the
// view of a virtual pinhole camera turned toward a region of interest, for the hand networks,
// which were trained on perspective images.
//
// A ROI is { cx, cy, w, h, rotation } in source pixels and radians, as the perception uses it
// (web/src/perception/geometry.mjs): the crop's normalised point (u, v) ∈ [−½, ½]² is, for a
// pinhole camera, the image point c + Rot(rotation)·(u·w, v·h). Through a lens:
//   b      = camera.bearing(cx, cy)               the ROI centre's ray
//   R      = the smallest rotation taking the optical axis z to b (the virtual camera's axes
//            in the camera frame; for a radially symmetric lens the local image axes at the ROI
//            centre keep their directions, so the ROI's rotation carries over)
//   f      = √|det J|, J = ∂(pixel)/∂(t1, t2) at t = 0 for the ray R·(t1, t2, 1): the lens'
//            local scale at the ROI centre in pixels per unit of the virtual image plane, so
//            that the crop keeps the image's pixel density there and w, h keep their meaning
//   t      = Rot(rotation)·(u·w, v·h) / f          the point on the virtual image plane
//   pixel  = camera.project(R·(t1, t2, 1))
// A crop pixel (i, j) of an N × M crop has u = (i + ½)/N − ½, v = (j + ½)/M − ½ (edge to edge).
// With a pinhole lens and the ROI at the principal point this is exactly the affine crop (up to
// fx ≠ fy); off-centre it is the perspective view, not the affine one — callers keep the affine
// crop for pinhole cameras.
//
// Landmarks found in the crop map back through toImage (the same map); directions found in the
// crop's axes (world landmarks) map to the camera frame by rotation()·Rot_z(rotation).
//
// For a detector that looks at the whole frame (the palm detector), rectifiedLetterboxMap gives
// the letterboxed view of the virtual pinhole camera with the camera's own intrinsics (the
// rectified frame), and virtualToSource maps its detections back to source pixels.
// Thread-safety: const after construction.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Geometry>

#include "hawor/common.hpp"
#include "hawor/geometry/camera_model.hpp"

namespace hawor {

/// A rotated region of interest in image pixels (the perception's ROI).
template <typename Scalar>
struct CropRoi {
  Scalar cx = Scalar(0), cy = Scalar(0), w = Scalar(0), h = Scalar(0), rotation = Scalar(0);
};

template <typename Scalar>
class LensCrop {
 public:
  /// Throws hawor::Error for a ROI that is not finite or has w, h ≤ 0, and for a ROI centre
  /// outside the lens' domain (beyond its fold).
  LensCrop(const CameraModel<Scalar>& camera, const CropRoi<Scalar>& roi) : cam_(camera), roi_(roi) {
    using std::cos;
    using std::sin;
    using std::sqrt;
    if (!std::isfinite(roi.cx) || !std::isfinite(roi.cy) || !std::isfinite(roi.rotation) || !(roi.w > Scalar(0)) ||
        !(roi.h > Scalar(0)) || !std::isfinite(roi.w) || !std::isfinite(roi.h)) {
      throw Error("LensCrop: the ROI must be finite with w, h > 0");
    }
    Vec3<Scalar> b;
    if (!cam_.bearing(Vec2<Scalar>(roi.cx, roi.cy), b)) {
      throw Error("LensCrop: the ROI centre (" + std::to_string(double(roi.cx)) + ", " + std::to_string(double(roi.cy)) +
                  ") lies beyond what lens " + cam_.lens.toString() + " reaches");
    }
    const Eigen::Matrix<Scalar, 3, 1> z(Scalar(0), Scalar(0), Scalar(1)), bb(b(0), b(1), b(2));
    R_ = Eigen::Quaternion<Scalar>::FromTwoVectors(z, bb).toRotationMatrix();
    Eigen::Matrix<Scalar, 2, 3> Jp;
    cam_.project(Vec3<Scalar>(R_.col(2)), &Jp);
    const Eigen::Matrix<Scalar, 2, 2> J = Jp * R_.template leftCols<2>();
    f_ = sqrt(std::abs(J(0, 0) * J(1, 1) - J(0, 1) * J(1, 0)));
    if (!(f_ > Scalar(0)) || !std::isfinite(f_)) throw Error("LensCrop: the lens' local scale at the ROI centre is not positive");
    c_ = cos(roi.rotation);
    s_ = sin(roi.rotation);
  }

  const CropRoi<Scalar>& roi() const { return roi_; }
  /// The virtual camera's axes in the camera frame (virtual → camera).
  const Mat3<Scalar>& rotation() const { return R_; }
  /// Pixels per unit of the virtual image plane (the virtual camera's focal length).
  Scalar focal() const { return f_; }

  /// The ray (camera frame, not unit length) of the crop-normalised point (u, v).
  Vec3<Scalar> ray(Scalar u, Scalar v) const {
    const Scalar a = u * roi_.w, bb = v * roi_.h;
    const Scalar t1 = (a * c_ - bb * s_) / f_, t2 = (a * s_ + bb * c_) / f_;
    return Vec3<Scalar>(R_ * Vec3<Scalar>(t1, t2, Scalar(1)));
  }

  /// Crop-normalised (u, v) → source pixel; false (px untouched) when the ray is outside the
  /// lens' domain.
  bool toImage(Scalar u, Scalar v, Vec2<Scalar>& px) const {
    const Vec3<Scalar> p = ray(u, v);
    if (!cam_.lens.inDomain(p)) return false;
    px = cam_.project(p);
    return std::isfinite(px(0)) && std::isfinite(px(1));
  }

  /// Source pixel → crop-normalised (u, v) (the inverse of toImage); false when the pixel's ray
  /// cannot be unprojected or points away from the virtual camera.
  bool toCrop(const Vec2<Scalar>& px, Vec2<Scalar>& uv) const {
    Vec3<Scalar> b;
    if (!cam_.bearing(px, b)) return false;
    const Vec3<Scalar> q = R_.transpose() * b;
    if (!(q(2) > Scalar(0))) return false;
    const Scalar t1 = f_ * q(0) / q(2), t2 = f_ * q(1) / q(2);
    uv = Vec2<Scalar>((t1 * c_ + t2 * s_) / roi_.w, (-t1 * s_ + t2 * c_) / roi_.h);
    return true;
  }

  /// The sampling map of an outW × outH crop: xy[2·(j·outW + i)] and [+1] = the source pixel
  /// (x, y) of crop pixel (i, j); NaN where toImage fails.
  template <typename Out>
  void samplingMap(int outW, int outH, Out* xy) const {
    if (outW <= 0 || outH <= 0) throw Error("LensCrop::samplingMap: the crop size must be positive");
    const Out nan = std::numeric_limits<Out>::quiet_NaN();
    for (int j = 0; j < outH; ++j) {
      const Scalar v = (Scalar(j) + Scalar(0.5)) / Scalar(outH) - Scalar(0.5);
      for (int i = 0; i < outW; ++i) {
        const Scalar u = (Scalar(i) + Scalar(0.5)) / Scalar(outW) - Scalar(0.5);
        Vec2<Scalar> px;
        Out* o = xy + 2 * (static_cast<std::size_t>(j) * static_cast<std::size_t>(outW) + static_cast<std::size_t>(i));
        if (toImage(u, v, px)) {
          o[0] = static_cast<Out>(px(0));
          o[1] = static_cast<Out>(px(1));
        } else {
          o[0] = o[1] = nan;
        }
      }
    }
  }

 private:
  CameraModel<Scalar> cam_;
  CropRoi<Scalar> roi_;
  Mat3<Scalar> R_ = Mat3<Scalar>::Identity();
  Scalar f_ = Scalar(1), c_ = Scalar(1), s_ = Scalar(0);
};

/// The source pixel seen by pixel p of the virtual pinhole camera with the camera's own
/// intrinsics (the rectified frame of rectify.hpp's default target): p's ray through the lens.
/// False (px untouched) beyond the lens' domain.
template <typename Scalar>
bool virtualToSource(const CameraModel<Scalar>& camera, const Vec2<Scalar>& p, Vec2<Scalar>& px) {
  const Vec3<Scalar> ray = camera.intrinsics.ray(p);
  if (!camera.lens.inDomain(ray)) return false;
  px = camera.project(ray);
  return std::isfinite(px(0)) && std::isfinite(px(1));
}

/// The letterboxed whole view of that virtual pinhole camera as an outW × outH sampling map into
/// the source image (the palm detector's input): the square of side max(W, H) centred on the
/// image centre ((W − 1)/2, (H − 1)/2), crop pixel (i, j) at centre + side·((i + ½)/outW − ½,
/// (j + ½)/outH − ½) (web/src/perception/geometry.mjs' letterboxRoi); each such virtual pixel
/// through virtualToSource, NaN where it fails (read as black, as the letterbox bars are).
template <typename Scalar, typename Out>
void rectifiedLetterboxMap(const CameraModel<Scalar>& camera, int outW, int outH, Out* xy) {
  if (outW <= 0 || outH <= 0) throw Error("rectifiedLetterboxMap: the crop size must be positive");
  const PinholeCamera<Scalar>& k = camera.intrinsics;
  const Scalar side = Scalar(std::max(k.width, k.height));
  const Scalar cx = (Scalar(k.width) - Scalar(1)) / Scalar(2), cy = (Scalar(k.height) - Scalar(1)) / Scalar(2);
  const Out nan = std::numeric_limits<Out>::quiet_NaN();
  for (int j = 0; j < outH; ++j) {
    const Scalar y = cy + side * ((Scalar(j) + Scalar(0.5)) / Scalar(outH) - Scalar(0.5));
    for (int i = 0; i < outW; ++i) {
      const Scalar x = cx + side * ((Scalar(i) + Scalar(0.5)) / Scalar(outW) - Scalar(0.5));
      Out* o = xy + 2 * (static_cast<std::size_t>(j) * static_cast<std::size_t>(outW) + static_cast<std::size_t>(i));
      Vec2<Scalar> px;
      if (virtualToSource(camera, Vec2<Scalar>(x, y), px)) {
        o[0] = static_cast<Out>(px(0));
        o[1] = static_cast<Out>(px(1));
      } else {
        o[0] = o[1] = nan;
      }
    }
  }
}

}  // namespace hawor
