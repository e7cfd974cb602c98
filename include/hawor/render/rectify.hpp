// hawor/render/rectify.hpp — rectification: a precomputed remap from a camera with a lens
// (geometry/camera_model.hpp) to a virtual pinhole camera with the same optical centre and the
// same axes, so that pinhole-only code (the SLAM, the hand masks) works on undistorted images
// and its poses are those of the real camera.
//
// For each pixel (x, y) of the virtual camera `target` (pixel centres at integers,
// docs/design.md §2):
//   ray  = ((x − cx)/fx, (y − cy)/fy, 1)         target intrinsics
//   uv   = source.project(ray)                    the lens, then the source intrinsics
// and the pixel is 'outside' when the ray is beyond the lens' fold angle
// (Lens::maxMonotonicAngle: there the lens model means nothing) or uv falls outside the source
// image [−0.5, W − 0.5] × [−0.5, H − 0.5].
//
// The default target is the source's own intrinsics and size: the image scale at the principal
// point is unchanged and the virtual camera keeps the source's pixel grid. What it implies:
//   - a barrel lens (fisheye, radial-tangential with k1 < 0) sees more than a pinhole with the
//     same focal: the virtual image is covered entirely, and the source's periphery beyond the
//     pinhole's field is cut (the Aria-like 150° diagonal fisheye at 640 × 480 keeps a 104°
//     diagonal view; its corners are stretched up to about 2.7× radially, so they are blurrier);
//   - a pincushion lens (k1 > 0) sees less: the virtual image's periphery is outside (black,
//     and in the SLAM's mask).
// Another target (a wider field at a smaller focal, another size) is the two-argument
// constructor; it must share the source's centre and axes, which is the only assumption.
//
// Remaps: bilinear for 8-bit grey/RGB/RGBA images (neighbours clamped to the source image, 11-bit
// fixed-point weights: within one grey level of the exact bilinear value), nearest for masks and
// labels (the source pixel whose centre is closest). Outside pixels read 0 in every channel.
// For the SLAM, slamMask() adds the outside region, grown by `borderPx`, to the hand mask: the
// corner detector (slam/corners.hpp) scores the black region's edge as corners and KLT windows
// straddling it follow the edge, so the border is masked as the hands are (MonoSlam grows masks
// by its own maskDilatePx, 6, on top: 6 + 6 = the 12 px that the corner detector keeps from the
// image's own border).
//
// A pinhole lens with the target equal to the source (identity()) is an exact no-op: no map is
// built, the remaps copy their input byte for byte, slamMask() passes the hand mask through.
// Cost: building is one lens projection per target pixel (about 10–20 ms at 640 × 480); a remap
// is one pass with precomputed offsets and weights. Thread-safety: const after construction.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/camera_model.hpp"
#include "hawor/render/image.hpp"

namespace hawor {

/// Default growth of the outside region in RectifyMap::slamMask (pixels).
constexpr int kRectifyBorderPx = 6;

template <typename Scalar>
class RectifyMap {
 public:
  static constexpr int kWeightBits = 11;  ///< fixed-point bits of the bilinear weights
  static constexpr std::int32_t kOutside = -1;

  RectifyMap() = default;

  /// The virtual camera is the source's own intrinsics and size.
  explicit RectifyMap(const CameraModel<Scalar>& source, int borderPx = kRectifyBorderPx)
      : RectifyMap(source, source.intrinsics, borderPx) {}

  /// Any virtual pinhole camera with the source's optical centre and axes. Throws hawor::Error
  /// for invalid intrinsics, a lens that folds inside the source image
  /// (CameraModel::validate), or borderPx < 0.
  RectifyMap(const CameraModel<Scalar>& source, const PinholeCamera<Scalar>& target,
             int borderPx = kRectifyBorderPx)
      : source_(source), target_(target), borderPx_(borderPx) {
    source_.validate();
    target_.validate();
    if (borderPx < 0) throw Error("RectifyMap: borderPx must be >= 0, got " + std::to_string(borderPx));
    const PinholeCamera<Scalar>& s = source_.intrinsics;
    identity_ = source_.lens.isPinhole() && s.fx == target.fx && s.fy == target.fy && s.cx == target.cx &&
                s.cy == target.cy && s.width == target.width && s.height == target.height;
    if (!identity_ && (s.width < 2 || s.height < 2)) {
      throw Error("RectifyMap: the source image must be at least 2x2 pixels, not " + std::to_string(s.width) + "x" +
                  std::to_string(s.height));
    }
    if (!identity_) build();
  }

  const CameraModel<Scalar>& source() const { return source_; }
  const PinholeCamera<Scalar>& target() const { return target_; }
  int width() const { return target_.width; }
  int height() const { return target_.height; }
  int borderPx() const { return borderPx_; }
  /// True for a pinhole lens and a target equal to the source: every remap is a copy.
  bool identity() const { return identity_; }
  /// Number of target pixels without a source pixel.
  std::size_t numOutside() const { return numOutside_; }
  bool anyOutside() const { return numOutside_ > 0; }

  /// The source pixel seen by target pixel (x, y) (inside the target image); false when outside.
  bool sourcePixel(int x, int y, Vec2<Scalar>& uv) const {
    checkPixel(x, y);
    if (identity_) {
      uv = Vec2<Scalar>(Scalar(x), Scalar(y));
      return true;
    }
    const std::size_t i = index(x, y);
    if (taps_[i].base == kOutside) return false;
    uv = Vec2<Scalar>(srcX_[i], srcY_[i]);
    return true;
  }

  /// 1 where a target pixel is outside, else 0 (target size; empty when identity()).
  const ImageU8& outsideMask() const { return outside_; }

  /// Bilinear remap of a source image (source size, `channels` 1–4 interleaved 8-bit samples)
  /// into dst (target size, same channels). Outside pixels are 0.
  void remapBilinear(const std::uint8_t* src, int channels, std::uint8_t* dst) const {
    checkChannels(channels, "remapBilinear");
    const std::size_t n = targetPixels();
    if (identity_) {
      std::memcpy(dst, src, n * static_cast<std::size_t>(channels));
      return;
    }
    switch (channels) {
      case 1: bilinear<1>(src, dst); break;
      case 3: bilinear<3>(src, dst); break;
      case 4: bilinear<4>(src, dst); break;
      default: bilinear<2>(src, dst); break;
    }
  }

  /// Nearest-pixel remap (masks, labels): dst pixel = the source pixel whose centre is closest
  /// to its source position; outside pixels 0.
  void remapNearest(const std::uint8_t* src, int channels, std::uint8_t* dst) const {
    checkChannels(channels, "remapNearest");
    const std::size_t n = targetPixels();
    if (identity_) {
      std::memcpy(dst, src, n * static_cast<std::size_t>(channels));
      return;
    }
    for (std::size_t i = 0; i < n; ++i) {
      std::uint8_t* o = dst + i * static_cast<std::size_t>(channels);
      const std::int32_t q = nearest_[i];
      if (q == kOutside) {
        for (int c = 0; c < channels; ++c) o[c] = 0;
        continue;
      }
      const std::uint8_t* p = src + static_cast<std::size_t>(q) * static_cast<std::size_t>(channels);
      for (int c = 0; c < channels; ++c) o[c] = p[c];
    }
  }

  ImageU8 remapBilinear(const ImageU8& src) const {
    checkSource(src, "remapBilinear");
    ImageU8 out(target_.width, target_.height, src.channels);
    remapBilinear(src.data.data(), src.channels, out.data.data());
    return out;
  }
  ImageU8 remapNearest(const ImageU8& src) const {
    checkSource(src, "remapNearest");
    ImageU8 out(target_.width, target_.height, src.channels);
    remapNearest(src.data.data(), src.channels, out.data.data());
    return out;
  }

  /// True when the SLAM needs a mask for a frame whose (target-size) hand mask is `hand` (null:
  /// no hand): a hand mask, or an outside region.
  bool needsSlamMask(const std::uint8_t* hand) const { return hand != nullptr || numOutside_ > 0; }

  /// The SLAM's mask at the target size: 255 where the hand mask (target size, one channel,
  /// non-zero = hand; may be null) is set or the outside region grown by borderPx() is, else 0.
  /// Without an outside region the hand mask is copied unchanged (null gives all 0: check
  /// needsSlamMask first to pass no mask at all).
  void slamMask(const std::uint8_t* hand, std::uint8_t* out) const {
    const std::size_t n = targetPixels();
    if (numOutside_ == 0) {
      if (hand) {
        std::memcpy(out, hand, n);
      } else {
        std::memset(out, 0, n);
      }
      return;
    }
    const std::uint8_t* b = border_.data.data();
    for (std::size_t i = 0; i < n; ++i) out[i] = (b[i] || (hand && hand[i])) ? 255 : 0;
  }

 private:
  std::size_t targetPixels() const {
    return static_cast<std::size_t>(target_.width) * static_cast<std::size_t>(target_.height);
  }
  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(target_.width) + static_cast<std::size_t>(x);
  }
  void checkPixel(int x, int y) const {
    if (x < 0 || y < 0 || x >= target_.width || y >= target_.height) {
      throw Error("RectifyMap: pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") is outside the " +
                  std::to_string(target_.width) + "x" + std::to_string(target_.height) + " target");
    }
  }
  static void checkChannels(int channels, const char* what) {
    if (channels < 1 || channels > 4) {
      throw Error(std::string("RectifyMap::") + what + ": " + std::to_string(channels) + " channels (expected 1-4)");
    }
  }
  void checkSource(const ImageU8& src, const char* what) const {
    if (!src.consistent() || src.width != source_.intrinsics.width || src.height != source_.intrinsics.height) {
      throw Error(std::string("RectifyMap::") + what + ": the image is " + std::to_string(src.width) + "x" +
                  std::to_string(src.height) + ", the source camera " + std::to_string(source_.intrinsics.width) +
                  "x" + std::to_string(source_.intrinsics.height));
    }
  }

  // The four taps of every inside pixel are base, base + 1, base + W, base + W + 1 (pixels): a
  // neighbour clamped onto its partner is folded into the weights when the map is built.
  template <int C>
  void bilinear(const std::uint8_t* src, std::uint8_t* dst) const {
    constexpr std::int32_t one = std::int32_t(1) << kWeightBits;
    constexpr std::int32_t half = std::int32_t(1) << (2 * kWeightBits - 1);
    const std::size_t n = targetPixels();
    const std::size_t sy = static_cast<std::size_t>(source_.intrinsics.width) * C;
    const Tap* tap = taps_.data();
    for (std::size_t i = 0; i < n; ++i, dst += C) {
      const Tap t = tap[i];
      if (t.base == kOutside) {
        for (int c = 0; c < C; ++c) dst[c] = 0;
        continue;
      }
      const std::int32_t wx = t.wx, wy = t.wy;
      const std::uint8_t* p = src + static_cast<std::size_t>(t.base) * C;
      for (int c = 0; c < C; ++c) {
        const std::int32_t top = p[c] * (one - wx) + p[c + C] * wx;
        const std::int32_t bot = p[c + sy] * (one - wx) + p[c + sy + C] * wx;
        dst[c] = static_cast<std::uint8_t>((top * (one - wy) + bot * wy + half) >> (2 * kWeightBits));
      }
    }
  }

  void build() {
    using std::atan2;
    using std::floor;
    using std::sqrt;
    const PinholeCamera<Scalar>& t = target_;
    const PinholeCamera<Scalar>& s = source_.intrinsics;
    const int W = s.width, H = s.height;
    const std::size_t n = targetPixels();
    const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
    srcX_.assign(n, nan);
    srcY_.assign(n, nan);
    taps_.assign(n, Tap{kOutside, 0, 0});
    nearest_.assign(n, kOutside);
    outside_.resize(t.width, t.height, 1, 0);
    // The lens means nothing beyond its fold angle (Lens::inDomain, with the angle found once).
    const Scalar fold = source_.lens.maxMonotonicAngle();
    const Scalar lo = Scalar(-0.5), hiX = Scalar(W) - Scalar(0.5), hiY = Scalar(H) - Scalar(0.5);
    const Scalar one = Scalar(std::int32_t(1) << kWeightBits);
    numOutside_ = 0;
    for (int y = 0; y < t.height; ++y) {
      const Scalar ry = (Scalar(y) - t.cy) / t.fy;
      for (int x = 0; x < t.width; ++x) {
        const std::size_t i = index(x, y);
        const Scalar rx = (Scalar(x) - t.cx) / t.fx;
        const Vec3<Scalar> ray(rx, ry, Scalar(1));
        bool inside = atan2(sqrt(rx * rx + ry * ry), Scalar(1)) < fold;
        Vec2<Scalar> uv;
        if (inside) {
          uv = source_.project(ray);
          inside = std::isfinite(uv(0)) && std::isfinite(uv(1)) && uv(0) >= lo && uv(1) >= lo && uv(0) <= hiX &&
                   uv(1) <= hiY;
        }
        if (!inside) {
          outside_.data[i] = 1;
          ++numOutside_;
          continue;
        }
        srcX_[i] = uv(0);
        srcY_[i] = uv(1);
        // Bilinear: the neighbours ⌊u⌋ and ⌊u⌋ + 1, each clamped to the image. Where both
        // clamp onto one pixel (u < 0 or u ≥ W − 1) that pixel gets the whole weight, as the
        // left (x = 0) or the right (x = W − 1) tap, so that every tap lies in the image.
        const Scalar fu = floor(uv(0)), fv = floor(uv(1));
        const auto axis = [one](Scalar u, Scalar fl, int size, int& first, std::uint16_t& w) {  // size >= 2
          const int x0 = static_cast<int>(fl);
          if (x0 < 0) {
            first = 0, w = 0;
          } else if (x0 >= size - 1) {
            first = size - 2, w = static_cast<std::uint16_t>(one);
          } else {
            first = x0, w = static_cast<std::uint16_t>(std::lround(static_cast<double>((u - fl) * one)));
          }
        };
        int xf = 0, yf = 0;
        std::uint16_t wx = 0, wy = 0;
        axis(uv(0), fu, W, xf, wx);
        axis(uv(1), fv, H, yf, wy);
        taps_[i] = Tap{static_cast<std::int32_t>(static_cast<std::int64_t>(yf) * W + xf), wx, wy};
        // Nearest: the pixel whose centre is closest (⌊u + ½⌋), clamped (u = W − ½ gives W).
        const int xn = std::min(static_cast<int>(floor(uv(0) + Scalar(0.5))), W - 1);
        const int yn = std::min(static_cast<int>(floor(uv(1) + Scalar(0.5))), H - 1);
        nearest_[i] = static_cast<std::int32_t>(static_cast<std::int64_t>(std::max(yn, 0)) * W + std::max(xn, 0));
      }
    }
    // The SLAM's border: the outside region grown by borderPx (a (2b+1)² square).
    if (numOutside_ > 0) {
      border_.resize(t.width, t.height, 1, 0);
      const int b = borderPx_, w = t.width, h = t.height;
      std::vector<std::uint8_t> rows(n, 0);
      for (int y = 0; y < h; ++y) {
        int last = -1000000;
        for (int x = 0; x < w; ++x) {
          if (outside_.data[index(x, y)]) last = x;
          if (x - last <= b) rows[index(x, y)] = 1;
        }
        last = 1000000;
        for (int x = w - 1; x >= 0; --x) {
          if (outside_.data[index(x, y)]) last = x;
          if (last - x <= b) rows[index(x, y)] = 1;
        }
      }
      for (int x = 0; x < w; ++x) {
        int last = -1000000;
        for (int y = 0; y < h; ++y) {
          if (rows[index(x, y)]) last = y;
          if (y - last <= b) border_.data[index(x, y)] = 255;
        }
        last = 1000000;
        for (int y = h - 1; y >= 0; --y) {
          if (rows[index(x, y)]) last = y;
          if (last - y <= b) border_.data[index(x, y)] = 255;
        }
      }
    }
  }

  CameraModel<Scalar> source_{};
  PinholeCamera<Scalar> target_{};
  int borderPx_ = kRectifyBorderPx;
  bool identity_ = true;
  std::size_t numOutside_ = 0;
  std::vector<Scalar> srcX_, srcY_;          ///< source position per target pixel (NaN outside)
  struct Tap {
    std::int32_t base;     ///< top-left tap (source pixel index) or kOutside
    std::uint16_t wx, wy;  ///< weights of the right / lower taps, 11-bit fixed point
  };
  std::vector<Tap> taps_;
  std::vector<std::int32_t> nearest_;        ///< nearest source pixel index or kOutside
  ImageU8 outside_;                          ///< 1 outside
  ImageU8 border_;                           ///< 255 in the outside region grown by borderPx (empty: none)
};

using RectifyMapf = RectifyMap<float>;
using RectifyMapd = RectifyMap<double>;

}  // namespace hawor
