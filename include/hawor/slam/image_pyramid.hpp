// hawor/slam/image_pyramid.hpp — grey float images and the Gaussian image pyramid of the SLAM
// front end (corner detection on level 0, coarse-to-fine KLT over all levels).
//
//   grey:      Y = 0.299·R + 0.587·G + 0.114·B (ITU-R BT.601 luma), in grey levels [0, 255];
//              a one-channel input is taken as is.
//   level l+1: the level-l image blurred by the binomial kernel [1 4 6 4 1]/16 in x and y (a
//              Gaussian of σ ≈ 1, enough against aliasing for a factor 2), then every second
//              pixel: size ⌈w/2⌉ × ⌈h/2⌉, pixel (x, y) of level l+1 at (2x, 2y) of level l, so a
//              level-l coordinate is 2^l times the level-0 one (pixel centres at integers,
//              docs/design.md §2). Borders are replicated.
// Bilinear sampling with replicated borders for sub-pixel KLT patches.
// Pure value types; the build reuses buffers (no allocation for a repeated size).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/render/image.hpp"

namespace hawor {

/// Grey-level float image (0–255) of an 8-bit grey or RGB(A) image.
inline void toGrey(const ImageU8& in, ImageF& out) {
  if (!in.consistent() || in.width <= 0 || in.height <= 0) {
    throw Error("toGrey: empty or inconsistent image");
  }
  if (in.channels != 1 && in.channels != 3 && in.channels != 4) {
    throw Error("toGrey: " + std::to_string(in.channels) + " channels (expected 1, 3 or 4)");
  }
  if (!out.sameSize(in.width, in.height, 1)) out.resize(in.width, in.height, 1);
  const std::size_t n = in.numPixels();
  const unsigned char* s = in.data.data();
  float* d = out.data.data();
  if (in.channels == 1) {
    for (std::size_t i = 0; i < n; ++i) d[i] = float(s[i]);
  } else {
    const int c = in.channels;
    for (std::size_t i = 0; i < n; ++i, s += c) {
      d[i] = 0.299f * float(s[0]) + 0.587f * float(s[1]) + 0.114f * float(s[2]);
    }
  }
}

/// Bilinear sample at (x, y) with replicated borders (any finite x, y).
inline float sampleBilinear(const ImageF& im, float x, float y) {
  const float xc = std::min(std::max(x, 0.0f), float(im.width - 1));
  const float yc = std::min(std::max(y, 0.0f), float(im.height - 1));
  const int x0 = std::min(int(xc), im.width - 2 < 0 ? 0 : im.width - 2);
  const int y0 = std::min(int(yc), im.height - 2 < 0 ? 0 : im.height - 2);
  const int x1 = std::min(x0 + 1, im.width - 1), y1 = std::min(y0 + 1, im.height - 1);
  const float ax = xc - float(x0), ay = yc - float(y0);
  const float* r0 = im.row(y0);
  const float* r1 = im.row(y1);
  const float top = r0[x0] + ax * (r0[x1] - r0[x0]);
  const float bot = r1[x0] + ax * (r1[x1] - r1[x0]);
  return top + ay * (bot - top);
}

/// One 2× reduction: binomial blur [1 4 6 4 1]/16 (separable, replicated borders), decimation.
inline void pyramidDown(const ImageF& in, ImageF& out, std::vector<float>& tmp) {
  const int w = in.width, h = in.height;
  const int w2 = (w + 1) / 2, h2 = (h + 1) / 2;
  if (!out.sameSize(w2, h2, 1)) out.resize(w2, h2, 1);
  // Horizontal pass at the decimated columns only: tmp is h × w2.
  tmp.resize(static_cast<std::size_t>(h) * w2);
  auto cx = [w](int x) { return x < 0 ? 0 : (x >= w ? w - 1 : x); };
  for (int y = 0; y < h; ++y) {
    const float* r = in.row(y);
    float* t = tmp.data() + static_cast<std::size_t>(y) * w2;
    for (int x2 = 0; x2 < w2; ++x2) {
      const int x = 2 * x2;
      if (x >= 2 && x + 2 < w) {
        t[x2] = (r[x - 2] + r[x + 2] + 4.0f * (r[x - 1] + r[x + 1]) + 6.0f * r[x]) * (1.0f / 16);
      } else {
        t[x2] = (r[cx(x - 2)] + r[cx(x + 2)] + 4.0f * (r[cx(x - 1)] + r[cx(x + 1)]) + 6.0f * r[x]) *
                (1.0f / 16);
      }
    }
  }
  auto cy = [h](int y) { return y < 0 ? 0 : (y >= h ? h - 1 : y); };
  for (int y2 = 0; y2 < h2; ++y2) {
    const int y = 2 * y2;
    const float* a = tmp.data() + static_cast<std::size_t>(cy(y - 2)) * w2;
    const float* b = tmp.data() + static_cast<std::size_t>(cy(y - 1)) * w2;
    const float* c = tmp.data() + static_cast<std::size_t>(y) * w2;
    const float* d = tmp.data() + static_cast<std::size_t>(cy(y + 1)) * w2;
    const float* e = tmp.data() + static_cast<std::size_t>(cy(y + 2)) * w2;
    float* o = out.row(y2);
    for (int x2 = 0; x2 < w2; ++x2) {
      o[x2] = (a[x2] + e[x2] + 4.0f * (b[x2] + d[x2]) + 6.0f * c[x2]) * (1.0f / 16);
    }
  }
}

/// A Gaussian pyramid; level 0 is the full-resolution grey image.
struct ImagePyramid {
  std::vector<ImageF> levels;
  std::vector<float> tmp;

  int numLevels() const { return static_cast<int>(levels.size()); }
  const ImageF& level(int l) const { return levels[static_cast<std::size_t>(l)]; }

  /// Builds `numLevels` levels (≥ 1) from an 8-bit grey or RGB(A) image; levels stop early when
  /// the image would get smaller than 16 pixels on a side.
  void build(const ImageU8& image, int numLevels) {
    if (numLevels < 1 || numLevels > 12) {
      throw Error("ImagePyramid: numLevels " + std::to_string(numLevels) + " (expected 1..12)");
    }
    levels.resize(1);
    toGrey(image, levels[0]);
    extend(numLevels);
  }

  /// The same from a grey float image.
  void build(const ImageF& grey, int numLevels) {
    if (numLevels < 1 || numLevels > 12) {
      throw Error("ImagePyramid: numLevels " + std::to_string(numLevels) + " (expected 1..12)");
    }
    if (!grey.consistent() || grey.channels != 1 || grey.width <= 0 || grey.height <= 0) {
      throw Error("ImagePyramid: expected a non-empty one-channel image");
    }
    levels.resize(1);
    levels[0] = grey;
    extend(numLevels);
  }

 private:
  void extend(int numLevels) {
    for (int l = 1; l < numLevels; ++l) {
      const ImageF& prev = levels.back();
      if ((prev.width + 1) / 2 < 16 || (prev.height + 1) / 2 < 16) break;
      levels.emplace_back();
      pyramidDown(levels[levels.size() - 2], levels.back(), tmp);
    }
  }
};

}  // namespace hawor
