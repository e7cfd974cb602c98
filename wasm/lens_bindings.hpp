// hawor_core's lens bindings (geometry/lens.hpp, geometry/camera_model.hpp, render/rectify.hpp,
// render/lens_crop.hpp), included at the end of bindings.cpp: one translation unit.
//
//   Lenses ("pinhole" | "opencv:k1,k2,p1,p2[,k3]" | "fisheye:k1,k2,k3,k4", geometry/lens.hpp):
//   parseLens(text) -> the canonical string (Lens::parse and its coefficient checks);
//   describeCamera(intrinsics, width, height, lens) -> {lens, pinhole, maxFieldAngleDeg,
//       foldAngleDeg} after CameraModel::validate (a lens folding inside the image throws);
//   cameraFromFov(width, height, lens, fovDeg) -> {fx, fy, cx, cy}: the diagonal field of view
//       through the lens (CameraModel::fromFov);
//   undistortPoints(intrinsics, lens, points: Float64Array (2N) pixels) -> Float64Array (2N): the
//       pixels of the pinhole camera with the same intrinsics seeing the same rays, NaN where the
//       lens cannot undistort (beyond its fold, fisheye rays >= 90 degrees off the axis);
//   new Rectifier(intrinsics, width, height, lens) (render/rectify.hpp, the virtual pinhole
//       camera = the same intrinsics and size): identity(), numOutside(), grey(Uint8Array(W*H)),
//       image(Uint8Array(W*H*c), c = 1, 3, 4) -> bilinear, mask(Uint8Array(W*H)) -> nearest,
//       slamMask(handMask Uint8Array(W*H) | null) -> Uint8Array | null (hand | the unseen border);
//   new LensCamera(intrinsics, width, height, lens) (render/lens_crop.hpp): cropMap({cx, cy, w, h,
//       rotation}, outW, outH) -> {map: Float32Array(2*outW*outH) source pixels (NaN outside),
//       rotation: Float64Array(9) row-major (virtual camera -> camera), focal}; cropToImage(roi,
//       Float64Array(2N) crop-normalised (u, v)) -> Float64Array(2N) source pixels (NaN outside);
//       letterboxMap(outW, outH) -> Float32Array(2*outW*outH): the letterboxed rectified frame
//       (the virtual pinhole camera with the same intrinsics) through the lens, for a detector
//       that looks at the whole frame; virtualToImage(Float64Array(2N) pixels of that camera) -> Float64Array(2N).
#pragma once

#include <emscripten/bind.h>
#include <emscripten/val.h>

#include <string>
#include <vector>

#include "hawor/geometry/camera_model.hpp"
#include "hawor/render/lens_crop.hpp"
#include "hawor/render/rectify.hpp"
#include "marshal.hpp"

using emscripten::val;
using namespace hawor_wasm;

namespace {


hawor::CameraModel<double> cameraModel(const val& intrinsics, int width, int height, const std::string& lens) {
  hawor::CameraModel<double> c{camera(intrinsics, width, height), hawor::Lens<double>::parse(lens)};
  c.validate();
  return c;
}

std::string parseLens(const std::string& text) {
  return guard("parseLens", [&] {
    const hawor::Lens<double> l = hawor::Lens<double>::parse(text);
    l.validate(0.0);
    return l.toString();
  });
}

val describeCamera(const val& intrinsics, int width, int height, const std::string& lens) {
  return guard("describeCamera", [&] {
    const hawor::CameraModel<double> c = cameraModel(intrinsics, width, height, lens);
    constexpr double deg = 180.0 / 3.14159265358979323846;
    val o = val::object();
    o.set("lens", c.lens.toString());
    o.set("pinhole", c.lens.isPinhole());
    o.set("maxFieldAngleDeg", c.maxFieldAngle() * deg);
    o.set("foldAngleDeg", c.lens.maxMonotonicAngle() * deg);
    return o;
  });
}

val cameraFromFov(int width, int height, const std::string& lens, double fovDeg) {
  return guard("cameraFromFov", [&] {
    const hawor::CameraModel<double> c =
        hawor::CameraModel<double>::fromFov(width, height, hawor::Lens<double>::parse(lens), fovDeg);
    val o = val::object();
    o.set("fx", c.intrinsics.fx);
    o.set("fy", c.intrinsics.fy);
    o.set("cx", c.intrinsics.cx);
    o.set("cy", c.intrinsics.cy);
    return o;
  });
}

val undistortPoints(const val& intrinsics, const std::string& lens, const val& points) {
  return guard("undistortPoints", [&] {
    // the size plays no part in undistortion: any valid one
    hawor::CameraModel<double> c{camera(intrinsics, 1, 1), hawor::Lens<double>::parse(lens)};
    c.lens.validate(0.0);
    std::vector<double> p = fromTyped<double>(points);
    if (p.size() % 2 != 0) throw hawor::Error("points: length " + std::to_string(p.size()) + " is not 2N");
    for (size_t i = 0; i < p.size(); i += 2) {
      hawor::Vec2<double> u;
      if (c.undistortPixel(hawor::Vec2<double>(p[i], p[i + 1]), u)) {
        p[i] = u(0), p[i + 1] = u(1);
      } else {
        p[i] = p[i + 1] = std::nan("");
      }
    }
    return f64(p.data(), p.size());
  });
}

/// Frames and masks of one video onto the virtual pinhole camera (one per run).
class Rectifier {
 public:
  explicit Rectifier(const hawor::CameraModel<double>& c) : map_(c) {}
  bool identity() const { return map_.identity(); }
  double numOutside() const { return static_cast<double>(map_.numOutside()); }
  val grey(const val& src) {
    return guard("Rectifier.grey", [&] { return remap(src, 1, true); });
  }
  val image(const val& src, int channels) {
    return guard("Rectifier.image", [&] { return remap(src, channels, true); });
  }
  val mask(const val& src) {
    return guard("Rectifier.mask", [&] { return remap(src, 1, false); });
  }
  val slamMask(const val& hand) {
    return guard("Rectifier.slamMask", [&] {
      const size_t n = static_cast<size_t>(map_.width()) * static_cast<size_t>(map_.height());
      std::vector<uint8_t> h;
      if (!absent(hand)) h = exactly<uint8_t>(hand, n, "hand mask (width*height)");
      const uint8_t* hp = absent(hand) ? nullptr : h.data();
      if (!map_.needsSlamMask(hp)) return val::null();
      out_.resize(n);
      map_.slamMask(hp, out_.data());
      return toTyped(out_.data(), n, "Uint8Array");
    });
  }

 private:
  val remap(const val& src, int channels, bool bilinear) {
    if (channels < 1 || channels > 4) throw hawor::Error("channels must be 1-4, not " + std::to_string(channels));
    const hawor::PinholeCamera<double>& s = map_.source().intrinsics;
    const size_t c = static_cast<size_t>(channels);
    in_ = exactly<uint8_t>(src, static_cast<size_t>(s.width) * static_cast<size_t>(s.height) * c,
                           "image (width*height*" + std::to_string(channels) + ")");
    out_.resize(static_cast<size_t>(map_.width()) * static_cast<size_t>(map_.height()) * c);
    if (bilinear) {
      map_.remapBilinear(in_.data(), channels, out_.data());
    } else {
      map_.remapNearest(in_.data(), channels, out_.data());
    }
    return toTyped(out_.data(), out_.size(), "Uint8Array");
  }
  hawor::RectifyMap<double> map_;
  std::vector<uint8_t> in_, out_;
};

Rectifier* newRectifier(const val& intrinsics, int width, int height, const std::string& lens) {
  return guard("Rectifier", [&] { return new Rectifier(cameraModel(intrinsics, width, height, lens)); });
}

/// Perspective crops of the full-resolution frames for the hand networks.
class LensCamera {
 public:
  explicit LensCamera(const hawor::CameraModel<double>& c) : cam_(c) {}
  val cropMap(const val& roi, int outW, int outH) {
    return guard("LensCamera.cropMap", [&] {
      if (outW <= 0 || outH <= 0 || outW > 4096 || outH > 4096) throw hawor::Error("crop size must be in 1..4096");
      const hawor::LensCrop<double> crop(cam_, roiFrom(roi));
      std::vector<float> map(2 * static_cast<size_t>(outW) * static_cast<size_t>(outH));
      crop.samplingMap(outW, outH, map.data());
      Eigen::Matrix<double, 3, 3, Eigen::RowMajor> R = crop.rotation();
      val o = val::object();
      o.set("map", toTyped(map.data(), map.size(), "Float32Array"));
      o.set("rotation", f64(R.data(), 9));
      o.set("focal", crop.focal());
      return o;
    });
  }
  val letterboxMap(int outW, int outH) {
    return guard("LensCamera.letterboxMap", [&] {
      if (outW <= 0 || outH <= 0 || outW > 4096 || outH > 4096) throw hawor::Error("crop size must be in 1..4096");
      std::vector<float> map(2 * static_cast<size_t>(outW) * static_cast<size_t>(outH));
      hawor::rectifiedLetterboxMap(cam_, outW, outH, map.data());
      return toTyped(map.data(), map.size(), "Float32Array");
    });
  }
  val virtualToImage(const val& points) {
    return guard("LensCamera.virtualToImage", [&] {
      std::vector<double> p = fromTyped<double>(points);
      if (p.size() % 2 != 0) throw hawor::Error("points: length " + std::to_string(p.size()) + " is not 2N");
      for (size_t i = 0; i < p.size(); i += 2) {
        hawor::Vec2<double> px;
        if (hawor::virtualToSource(cam_, hawor::Vec2<double>(p[i], p[i + 1]), px)) {
          p[i] = px(0), p[i + 1] = px(1);
        } else {
          p[i] = p[i + 1] = std::nan("");
        }
      }
      return f64(p.data(), p.size());
    });
  }
  val cropToImage(const val& roi, const val& points) {
    return guard("LensCamera.cropToImage", [&] {
      const hawor::LensCrop<double> crop(cam_, roiFrom(roi));
      std::vector<double> p = fromTyped<double>(points);
      if (p.size() % 2 != 0) throw hawor::Error("points: length " + std::to_string(p.size()) + " is not 2N");
      for (size_t i = 0; i < p.size(); i += 2) {
        hawor::Vec2<double> px;
        if (crop.toImage(p[i], p[i + 1], px)) {
          p[i] = px(0), p[i + 1] = px(1);
        } else {
          p[i] = p[i + 1] = std::nan("");
        }
      }
      return f64(p.data(), p.size());
    });
  }

 private:
  static hawor::CropRoi<double> roiFrom(const val& r) {
    if (absent(r)) throw hawor::Error("roi: missing");
    auto num = [&](const char* k) {
      if (absent(r[k])) throw hawor::Error(std::string("roi.") + k + ": missing");
      return r[k].as<double>();
    };
    return hawor::CropRoi<double>{num("cx"), num("cy"), num("w"), num("h"), num("rotation")};
  }
  hawor::CameraModel<double> cam_;
};

LensCamera* newLensCamera(const val& intrinsics, int width, int height, const std::string& lens) {
  return guard("LensCamera", [&] { return new LensCamera(cameraModel(intrinsics, width, height, lens)); });
}

}  // namespace

EMSCRIPTEN_BINDINGS(hawor_lens) {
  using emscripten::allow_raw_pointers;
  emscripten::class_<Rectifier>("Rectifier")
      .constructor(&newRectifier, allow_raw_pointers())
      .function("identity", &Rectifier::identity)
      .function("numOutside", &Rectifier::numOutside)
      .function("grey", &Rectifier::grey)
      .function("image", &Rectifier::image)
      .function("mask", &Rectifier::mask)
      .function("slamMask", &Rectifier::slamMask);
  emscripten::class_<LensCamera>("LensCamera")
      .constructor(&newLensCamera, allow_raw_pointers())
      .function("cropMap", &LensCamera::cropMap)
      .function("cropToImage", &LensCamera::cropToImage)
      .function("letterboxMap", &LensCamera::letterboxMap)
      .function("virtualToImage", &LensCamera::virtualToImage);
  emscripten::function("parseLens", &parseLens);
  emscripten::function("describeCamera", &describeCamera);
  emscripten::function("cameraFromFov", &cameraFromFov);
  emscripten::function("undistortPoints", &undistortPoints);
}
