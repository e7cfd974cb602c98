// hawor/render/resample.hpp — box-filter downscaling of 8-bit images (the SLAM's and the depth
// network's input frames, from the video's size to the working size).
//
// Output pixel (x, y) of a dw × dh image is the mean of the source pixels whose centres fall in
// its footprint: source column xs goes to x = ⌊(xs + ½)·dw / sw⌋ (rows alike), so every source
// pixel counts exactly once and an integer ratio is a plain k × k block average. Grey output uses
// the BT.601 luma with integer weights, Y = (77 R + 150 G + 29 B) / 256 (the weights sum to 256),
// accumulated exactly in integers and rounded once; RGB output averages each channel. Sources with
// 1 channel are grey already; a fourth (alpha) channel is ignored.
// Cost: one pass over the source, O(sw·sh), with a row of dw accumulators (at 1:1, a plain
// per-pixel conversion).
// Thread-safety: pure functions.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/render/image.hpp"

namespace hawor {

/// Downscales src (sw × sh × channels, channels 1, 3 or 4, row-major) to dw × dh with
/// 1 ≤ dw ≤ sw, 1 ≤ dh ≤ sh, into out (dw·dh grey samples when toGrey, else dw·dh·3 RGB; a grey
/// source gives grey either way when toGrey, and R = G = B when not). Throws for bad sizes.
inline void downscaleBox(const std::uint8_t* src, int sw, int sh, int channels, int dw, int dh, bool toGrey,
                         std::uint8_t* out) {
  if (!src || !out || sw <= 0 || sh <= 0) throw Error("downscale: empty source image");
  if (channels != 1 && channels != 3 && channels != 4) {
    throw Error("downscale: " + std::to_string(channels) + " channels (expected 1, 3 or 4)");
  }
  if (dw < 1 || dh < 1 || dw > sw || dh > sh) {
    throw Error("downscale: " + std::to_string(sw) + "x" + std::to_string(sh) + " to " + std::to_string(dw) + "x" +
                std::to_string(dh) + " is not a downscale");
  }
  const int oc = toGrey ? 1 : 3;
  if (dw == sw && dh == sh) {
    // 1:1 (a grey conversion, e.g. before a rectification): each output pixel is its one source
    // pixel, the same numbers as the general path ((2s + 256) / 512 = (s + 128) >> 8), faster.
    const std::size_t n = static_cast<std::size_t>(sw) * static_cast<std::size_t>(sh);
    for (std::size_t i = 0; i < n; ++i, src += channels, out += oc) {
      const int r = src[0], g = channels == 1 ? src[0] : src[1], b = channels == 1 ? src[0] : src[2];
      if (toGrey) {
        out[0] = static_cast<std::uint8_t>((77 * r + 150 * g + 29 * b + 128) >> 8);
      } else {
        out[0] = static_cast<std::uint8_t>(r), out[1] = static_cast<std::uint8_t>(g), out[2] = static_cast<std::uint8_t>(b);
      }
    }
    return;
  }
  std::vector<int> ox(static_cast<std::size_t>(sw)), cw(static_cast<std::size_t>(dw), 0);
  for (int x = 0; x < sw; ++x) {
    ox[static_cast<std::size_t>(x)] = static_cast<int>((2LL * x + 1) * dw / (2LL * sw));  // ⌊(x + ½)·dw / sw⌋
    ++cw[static_cast<std::size_t>(ox[static_cast<std::size_t>(x)])];
  }
  std::vector<long long> acc(static_cast<std::size_t>(dw) * oc);
  int y = 0;
  for (int oy = 0; oy < dh; ++oy) {
    std::fill(acc.begin(), acc.end(), 0LL);
    int rows = 0;
    for (; y < sh && static_cast<int>((2LL * y + 1) * dh / (2LL * sh)) == oy; ++y, ++rows) {
      const std::uint8_t* p = src + static_cast<std::size_t>(y) * sw * channels;
      for (int x = 0; x < sw; ++x, p += channels) {
        long long* a = &acc[static_cast<std::size_t>(ox[static_cast<std::size_t>(x)]) * oc];
        const int r = p[0], g = channels == 1 ? p[0] : p[1], b = channels == 1 ? p[0] : p[2];
        if (toGrey) {
          a[0] += 77 * r + 150 * g + 29 * b;
        } else {
          a[0] += r, a[1] += g, a[2] += b;
        }
      }
    }
    // Every output row and column receives at least one source pixel when dw ≤ sw, dh ≤ sh.
    std::uint8_t* o = out + static_cast<std::size_t>(oy) * dw * oc;
    for (int x = 0; x < dw; ++x) {
      const long long n = static_cast<long long>(rows) * cw[static_cast<std::size_t>(x)] * (toGrey ? 256 : 1);
      for (int k = 0; k < oc; ++k) {
        const long long s = acc[static_cast<std::size_t>(x) * oc + static_cast<std::size_t>(k)];
        o[x * oc + k] = static_cast<std::uint8_t>(std::min<long long>(255, (2 * s + n) / (2 * n)));  // round half up
      }
    }
  }
}

/// The same on an image: a dw × dh grey (toGrey) or RGB image.
inline ImageU8 downscaleBox(const ImageU8& in, int dw, int dh, bool toGrey) {
  if (!in.consistent()) throw Error("downscale: inconsistent image");
  ImageU8 out(dw < 1 ? 0 : dw, dh < 1 ? 0 : dh, toGrey ? 1 : 3);
  downscaleBox(in.data.data(), in.width, in.height, in.channels, dw, dh, toGrey, out.data.data());
  return out;
}

}  // namespace hawor
