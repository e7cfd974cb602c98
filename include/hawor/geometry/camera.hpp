// hawor/geometry/camera.hpp — the pinhole camera model (no distortion).
//
// Frames and pixels (docs/design.md §2): OpenCV camera frame (x right, y down, z forward); pixel
// centres at integer coordinates, so the image covers [−0.5, width − 0.5] × [−0.5, height − 0.5]
// and the image centre is ((width − 1)/2, (height − 1)/2).
//   project:   u = fx·x/z + cx,  v = fy·y/z + cy
//   unproject: p = depth·((u − cx)/fx, (v − cy)/fy, 1)
// A plain aggregate (PinholeCamera<double>{fx, fy, cx, cy, width, height}); thread-safe to read.
#pragma once

#include <cmath>
#include <string>

#include "hawor/common.hpp"

namespace hawor {

template <typename Scalar>
struct PinholeCamera {
  Scalar fx = Scalar(0), fy = Scalar(0);  ///< focal lengths in pixels
  Scalar cx = Scalar(0), cy = Scalar(0);  ///< principal point in pixels
  int width = 0, height = 0;              ///< image size in pixels

  /// Pinhole projection of a camera-frame point. Meaningful only for points in front of the
  /// camera (inFront(p): z > 0); for z = 0 the result is not finite and for z < 0 it is the
  /// mirrored point, so check inFront/isVisible first. J (optional) receives d(u,v)/dp =
  /// [fx/z, 0, −fx·x/z²; 0, fy/z, −fy·y/z²].
  Vec2<Scalar> project(const Vec3<Scalar>& p, Eigen::Matrix<Scalar, 2, 3>* J = nullptr) const {
    const Scalar iz = Scalar(1) / p(2);
    const Scalar xn = p(0) * iz, yn = p(1) * iz;
    if (J) {
      *J << fx * iz, Scalar(0), -fx * xn * iz,  //
          Scalar(0), fy * iz, -fy * yn * iz;
    }
    return Vec2<Scalar>(fx * xn + cx, fy * yn + cy);
  }

  /// The camera-frame point at the given depth (z) along the ray through pixel uv.
  Vec3<Scalar> unproject(const Vec2<Scalar>& uv, Scalar depth) const {
    return depth * ray(uv);
  }

  /// The ray through pixel uv, normalised to z = 1 (not to unit length).
  Vec3<Scalar> ray(const Vec2<Scalar>& uv) const {
    return Vec3<Scalar>((uv(0) - cx) / fx, (uv(1) - cy) / fy, Scalar(1));
  }

  /// True when the point is in front of the camera by more than min_depth (metres).
  static bool inFront(const Vec3<Scalar>& p, Scalar min_depth = Scalar(0)) {
    return p(2) > min_depth;
  }

  /// True when pixel uv lies inside the image shrunk by margin pixels on each side
  /// (pixel centres at integers: the image spans [−0.5, w − 0.5] × [−0.5, h − 0.5]).
  bool inImage(const Vec2<Scalar>& uv, Scalar margin = Scalar(0)) const {
    const Scalar lo = Scalar(-0.5) + margin;
    return uv(0) >= lo && uv(1) >= lo && uv(0) <= Scalar(width) - Scalar(0.5) - margin &&
           uv(1) <= Scalar(height) - Scalar(0.5) - margin && std::isfinite(uv(0)) &&
           std::isfinite(uv(1));
  }

  /// In front of the camera (z > 0) and projecting inside the image (see inImage).
  bool isVisible(const Vec3<Scalar>& p, Scalar margin = Scalar(0)) const {
    return inFront(p) && inImage(project(p), margin);
  }

  /// K = [fx 0 cx; 0 fy cy; 0 0 1].
  Mat3<Scalar> K() const {
    Mat3<Scalar> k;
    k << fx, Scalar(0), cx, Scalar(0), fy, cy, Scalar(0), Scalar(0), Scalar(1);
    return k;
  }

  /// The same camera for an image resized by `factor` (e.g. the SLAM resolution). With pixel
  /// centres at integers: c' = (c + 0.5)·factor − 0.5, f' = f·factor; the size is rounded.
  PinholeCamera scaled(Scalar factor) const {
    if (!(factor > Scalar(0)) || !std::isfinite(factor)) {
      throw Error("PinholeCamera::scaled: factor must be finite and > 0");
    }
    PinholeCamera c;
    c.fx = fx * factor;
    c.fy = fy * factor;
    c.cx = (cx + Scalar(0.5)) * factor - Scalar(0.5);
    c.cy = (cy + Scalar(0.5)) * factor - Scalar(0.5);
    c.width = static_cast<int>(std::lround(static_cast<double>(width) * factor));
    c.height = static_cast<int>(std::lround(static_cast<double>(height) * factor));
    return c;
  }

  /// Square pixels, focal length from a field of view measured on the image diagonal:
  /// f = (√(w² + h²)/2) / tan(fov/2); principal point at the image centre ((w−1)/2, (h−1)/2).
  /// (docs/design.md §5: a better default than the official fixed 600 px.)
  static PinholeCamera fromFov(int width, int height, Scalar diagonal_fov_deg) {
    if (width <= 0 || height <= 0) {
      throw Error("PinholeCamera::fromFov: image size must be positive, got " +
                  std::to_string(width) + "x" + std::to_string(height));
    }
    if (!(diagonal_fov_deg > Scalar(0) && diagonal_fov_deg < Scalar(180))) {
      throw Error("PinholeCamera::fromFov: diagonal field of view must be in (0, 180) degrees");
    }
    using std::sqrt;
    using std::tan;
    const Scalar half = diagonal_fov_deg * Constants<Scalar>::pi() / Scalar(360);
    const Scalar diag = sqrt(Scalar(width) * Scalar(width) + Scalar(height) * Scalar(height));
    PinholeCamera c;
    c.fx = c.fy = diag / (Scalar(2) * tan(half));
    c.cx = (Scalar(width) - Scalar(1)) / Scalar(2);
    c.cy = (Scalar(height) - Scalar(1)) / Scalar(2);
    c.width = width;
    c.height = height;
    return c;
  }

  /// Diagonal field of view in degrees (inverse of fromFov, using fx).
  Scalar diagonalFovDeg() const {
    using std::atan;
    using std::sqrt;
    const Scalar diag = sqrt(Scalar(width) * Scalar(width) + Scalar(height) * Scalar(height));
    return Scalar(360) / Constants<Scalar>::pi() * atan(diag / (Scalar(2) * fx));
  }

  /// Throws hawor::Error unless fx, fy are finite and > 0, cx, cy finite and the size > 0.
  void validate() const {
    if (!(fx > Scalar(0)) || !(fy > Scalar(0)) || !std::isfinite(fx) || !std::isfinite(fy)) {
      throw Error("PinholeCamera: focal lengths must be finite and > 0 (fx=" +
                  std::to_string(static_cast<double>(fx)) +
                  ", fy=" + std::to_string(static_cast<double>(fy)) + ")");
    }
    if (!std::isfinite(cx) || !std::isfinite(cy)) {
      throw Error("PinholeCamera: principal point is not finite");
    }
    if (width <= 0 || height <= 0) {
      throw Error("PinholeCamera: image size must be positive, got " + std::to_string(width) +
                  "x" + std::to_string(height));
    }
  }

  template <typename T>
  PinholeCamera<T> cast() const {
    PinholeCamera<T> c;
    c.fx = static_cast<T>(fx);
    c.fy = static_cast<T>(fy);
    c.cx = static_cast<T>(cx);
    c.cy = static_cast<T>(cy);
    c.width = width;
    c.height = height;
    return c;
  }
};

using PinholeCameraf = PinholeCamera<float>;
using PinholeCamerad = PinholeCamera<double>;

}  // namespace hawor
