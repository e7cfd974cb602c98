// hawor/geometry/camera_model.hpp — a camera with a lens: pinhole intrinsics (camera.hpp) after
// a distortion model (lens.hpp).
//
//   project:  m = lens.project(p),  uv = (fx·m.x + cx, fy·m.y + cy)
//   bearing:  m = ((u − cx)/fx, (v − cy)/fy),  b = lens.unproject(m)
// Frames and pixels as in camera.hpp (docs/design.md §2): OpenCV camera frame, pixel centres at
// integer coordinates, the image spans [−0.5, width − 0.5] × [−0.5, height − 0.5]. With
// Lens::pinhole() every function equals PinholeCamera's. A plain aggregate
// (CameraModel<double>{intrinsics, lens}); thread-safe to read.
#pragma once

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/lens.hpp"

namespace hawor {

template <typename Scalar>
struct CameraModel {
  PinholeCamera<Scalar> intrinsics;
  Lens<Scalar> lens;

  /// Pixel of the camera-frame point p; J (optional) = d(u, v)/dp = diag(fx, fy)·dm/dp. Check
  /// isVisible (or lens.inDomain) first: outside the lens' domain the result is meaningless.
  Vec2<Scalar> project(const Vec3<Scalar>& p, Eigen::Matrix<Scalar, 2, 3>* J = nullptr) const {
    const Vec2<Scalar> m = lens.project(p, J);
    if (J) {
      J->row(0) *= intrinsics.fx;
      J->row(1) *= intrinsics.fy;
    }
    return Vec2<Scalar>(intrinsics.fx * m(0) + intrinsics.cx, intrinsics.fy * m(1) + intrinsics.cy);
  }

  /// Distorted normalised coordinates of pixel uv: ((u − cx)/fx, (v − cy)/fy).
  Vec2<Scalar> normalised(const Vec2<Scalar>& uv) const {
    return Vec2<Scalar>((uv(0) - intrinsics.cx) / intrinsics.fx,
                        (uv(1) - intrinsics.cy) / intrinsics.fy);
  }

  /// The unit ray through pixel uv. False (b untouched) where the lens cannot unproject uv
  /// (outside its monotonic domain, non-finite input).
  bool bearing(const Vec2<Scalar>& uv, Vec3<Scalar>& b) const {
    return lens.unproject(normalised(uv), b);
  }

  /// The pixel where a pinhole camera with the same intrinsics would see the ray through uv:
  /// (fx·x + cx, fy·y + cy) with (x, y) = lens.undistort(m). False (uvPinhole untouched) outside
  /// the lens' domain and for fisheye rays at 90° or more from the axis.
  bool undistortPixel(const Vec2<Scalar>& uv, Vec2<Scalar>& uvPinhole) const {
    Vec2<Scalar> xy;
    if (!lens.undistort(normalised(uv), xy)) return false;
    uvPinhole =
        Vec2<Scalar>(intrinsics.fx * xy(0) + intrinsics.cx, intrinsics.fy * xy(1) + intrinsics.cy);
    return true;
  }

  /// In the lens' domain (z > 0 for pinhole/radial-tangential, within the fold angle; see
  /// Lens::inDomain) and projecting inside the image shrunk by margin pixels.
  bool isVisible(const Vec3<Scalar>& p, Scalar margin = Scalar(0)) const {
    return lens.inDomain(p) && intrinsics.inImage(project(p), margin);
  }

  /// The same camera for an image resized by `factor`: intrinsics scaled (PinholeCamera::scaled),
  /// lens unchanged (it acts on normalised coordinates).
  CameraModel scaled(Scalar factor) const { return CameraModel{intrinsics.scaled(factor), lens}; }

  /// Largest angle from the optical axis over the four image corners (−0.5, −0.5) …
  /// (w − 0.5, h − 0.5), through bearing(); +∞ when a corner lies outside the lens' domain.
  /// For a radial model the farthest point of the image from the axis is a corner.
  Scalar maxFieldAngle() const {
    using std::atan2;
    using std::sqrt;
    Scalar best = Scalar(0);
    for (int i = 0; i < 4; ++i) {
      Vec3<Scalar> b;
      if (!bearing(corner(i), b)) return std::numeric_limits<Scalar>::infinity();
      best = std::max(best, atan2(sqrt(b(0) * b(0) + b(1) * b(1)), b(2)));
    }
    return best;
  }

  /// Throws hawor::Error naming the problem: invalid intrinsics (PinholeCamera::validate); a
  /// lens coefficient that is not finite; an image corner the lens cannot reach (beyond the
  /// fold, named with the fold angle); a model that folds before the angle of the farthest
  /// corner (Lens::validate).
  void validate() const {
    intrinsics.validate();
    lens.validate(Scalar(0));  // coefficients alone: finite, the ones the model uses
    using std::atan2;
    using std::sqrt;
    Scalar need = Scalar(0);
    for (int i = 0; i < 4; ++i) {
      const Vec2<Scalar> uv = corner(i);
      Vec3<Scalar> b;
      if (!bearing(uv, b)) {
        char buf[256];
        std::snprintf(
            buf, sizeof(buf),
            "camera model: the image corner (%.1f, %.1f) (distorted normalised radius "
            "%.4g) lies beyond what lens %s reaches: it folds at %.1f degrees from the "
            "optical axis",
            static_cast<double>(uv(0)), static_cast<double>(uv(1)),
            static_cast<double>(normalised(uv).norm()), lens.toString().c_str(),
            static_cast<double>(lens.maxMonotonicAngle()) * 180.0 / 3.14159265358979323846);
        throw Error(std::string(buf) +
                    " (an image larger than the calibrated field, wrong intrinsics or wrong "
                    "coefficients)");
      }
      need = std::max(need, atan2(sqrt(b(0) * b(0) + b(1) * b(1)), b(2)));
    }
    lens.validate(need);
  }

  /// A camera from intrinsics and a lens description (Lens::parse: "pinhole",
  /// "opencv:k1,k2,p1,p2[,k3]", "fisheye:k1,k2,k3,k4"), validated.
  static CameraModel fromString(const PinholeCamera<Scalar>& intrinsics, const std::string& lens) {
    CameraModel c{intrinsics, Lens<Scalar>::parse(lens)};
    c.validate();
    return c;
  }

  /// A width × height camera whose lens spans `diagonalFovDeg` across the image diagonal: square
  /// pixels, principal point at the image centre, f = (√(w² + h²)/2) / |m| with m the lens'
  /// projection of the ray at half the field of view along the diagonal (for a pinhole lens,
  /// PinholeCamera::fromFov; tangential terms move that point slightly off the diagonal, by a
  /// small fraction of a degree). Validated: throws hawor::Error when the lens folds before the
  /// corners or a pinhole-type lens is asked for 180° or more.
  static CameraModel fromFov(int width, int height, const Lens<Scalar>& lens, Scalar diagonalFovDeg) {
    using std::cos;
    using std::sin;
    using std::sqrt;
    if (!(diagonalFovDeg > Scalar(0) && diagonalFovDeg < Scalar(360))) {
      throw Error("CameraModel::fromFov: diagonal field of view must be in (0, 360) degrees");
    }
    if (lens.kind == LensKind::Pinhole) {
      CameraModel c{PinholeCamera<Scalar>::fromFov(width, height, diagonalFovDeg), lens};
      c.validate();
      return c;
    }
    const Scalar half = diagonalFovDeg * Constants<Scalar>::pi() / Scalar(360);
    lens.validate(half);
    CameraModel c{PinholeCamera<Scalar>::fromFov(width, height, Scalar(90)), lens};  // size, centre
    const Scalar diag = sqrt(Scalar(width) * Scalar(width) + Scalar(height) * Scalar(height));
    const Vec3<Scalar> p(sin(half) * Scalar(width) / diag, sin(half) * Scalar(height) / diag, cos(half));
    const Scalar m = lens.project(p).norm();
    c.intrinsics.fx = c.intrinsics.fy = Scalar(0.5) * diag / m;
    c.validate();
    return c;
  }

  template <typename T>
  CameraModel<T> cast() const {
    return CameraModel<T>{intrinsics.template cast<T>(), lens.template cast<T>()};
  }

 private:
  // Image corners 0..3: (−0.5, −0.5), (w − 0.5, −0.5), (−0.5, h − 0.5), (w − 0.5, h − 0.5).
  Vec2<Scalar> corner(int i) const {
    const Scalar x0 = Scalar(-0.5), y0 = Scalar(-0.5);
    const Scalar x1 = Scalar(intrinsics.width) - Scalar(0.5);
    const Scalar y1 = Scalar(intrinsics.height) - Scalar(0.5);
    return Vec2<Scalar>(i & 1 ? x1 : x0, i & 2 ? y1 : y0);
  }
};

using CameraModelf = CameraModel<float>;
using CameraModeld = CameraModel<double>;

}  // namespace hawor
