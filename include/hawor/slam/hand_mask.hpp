// hawor/slam/hand_mask.hpp — the hand masks of the SLAM's dual masking (docs/design.md §5; the paper
// masks the hands out of DROID-SLAM's flow and its bundle adjustment alike).
//
// A mask is an 8-bit image of the frame's size, hand pixels non-zero (any channel layout: a pixel
// is masked when any of its channels is non-zero). The front end uses it dilated by r pixels
// (square structuring element, separable running max): a corner or KLT window touching a hand
// edge would follow the hand, not the scene. Keyframes keep a compact copy (CoarseMask: one bit
// of "any hand pixel" per s × s block) to zero-weight bundle-adjustment residuals that land on a
// hand, at 1/s² of the memory (3,000 frames of 640×480 masks at s = 4: 57 MB → 3.6 MB).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/render/image.hpp"

namespace hawor {

/// Binary (0/1) one-channel mask of `mask` (hand where any channel is non-zero); throws when the
/// size differs from width × height.
inline void binaryHandMask(const ImageU8& mask, int width, int height, ImageU8& out) {
  if (!mask.consistent()) throw Error("hand mask: inconsistent image buffer");
  if (mask.width != width || mask.height != height) {
    throw Error("hand mask is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) +
                " but the frame is " + std::to_string(width) + "x" + std::to_string(height));
  }
  if (!out.sameSize(width, height, 1)) out.resize(width, height, 1);
  const int c = mask.channels;
  const unsigned char* s = mask.data.data();
  for (std::size_t i = 0, n = mask.numPixels(); i < n; ++i, s += c) {
    unsigned char v = 0;
    for (int k = 0; k < c; ++k) v |= s[k];
    out.data[i] = v ? 1 : 0;
  }
}

/// Dilates a binary mask in place by r pixels (a (2r+1)² square, the SLAM's margin), O(1) per
/// pixel and pass; render/mask.hpp's dilateMask grows by a disc (the rendered hand masks).
inline void dilateSquare(ImageU8& m, int r, std::vector<unsigned char>& tmp) {
  if (r <= 0 || m.empty()) return;
  const int w = m.width, h = m.height;
  tmp.resize(m.data.size());
  // Horizontal: distance to the nearest set pixel on the left and right, by two sweeps.
  for (int y = 0; y < h; ++y) {
    const unsigned char* s = m.row(y);
    unsigned char* t = tmp.data() + static_cast<std::size_t>(y) * w;
    int last = -1000000;
    for (int x = 0; x < w; ++x) {
      if (s[x]) last = x;
      t[x] = (x - last <= r) ? 1 : 0;
    }
    last = 1000000;
    for (int x = w - 1; x >= 0; --x) {
      if (s[x]) last = x;
      if (last - x <= r) t[x] = 1;
    }
  }
  // Vertical, from tmp back into m.
  for (int x = 0; x < w; ++x) {
    int last = -1000000;
    for (int y = 0; y < h; ++y) {
      if (tmp[static_cast<std::size_t>(y) * w + x]) last = y;
      m.at(x, y) = (y - last <= r) ? 1 : 0;
    }
    last = 1000000;
    for (int y = h - 1; y >= 0; --y) {
      if (tmp[static_cast<std::size_t>(y) * w + x]) last = y;
      if (last - y <= r) m.at(x, y) = 1;
    }
  }
}

/// Fraction of set pixels of a binary mask.
inline double maskCoverage(const ImageU8& m) {
  if (m.empty()) return 0.0;
  std::size_t n = 0;
  for (unsigned char v : m.data) n += v ? 1 : 0;
  return double(n) / double(m.data.size());
}

/// One bit per s × s block: set when any pixel of the block is set.
struct CoarseMask {
  int width = 0, height = 0, block = 4;  ///< full-resolution size, block size
  int bw = 0, bh = 0;
  std::vector<unsigned char> bits;       ///< bw × bh, 0/1 (empty: nothing masked)

  CoarseMask() = default;
  CoarseMask(const ImageU8& binary, int s) : width(binary.width), height(binary.height), block(s) {
    if (s < 1) throw Error("CoarseMask: block size must be >= 1");
    bw = (width + s - 1) / s;
    bh = (height + s - 1) / s;
    bool any = false;
    for (unsigned char v : binary.data) any = any || v;
    if (!any) return;  // no hand: store nothing
    bits.assign(static_cast<std::size_t>(bw) * bh, 0);
    for (int y = 0; y < height; ++y) {
      const unsigned char* r = binary.row(y);
      unsigned char* b = bits.data() + static_cast<std::size_t>(y / s) * bw;
      for (int x = 0; x < width; ++x) b[x / s] |= r[x] ? 1 : 0;
    }
  }
  /// True when pixel (u, v) (rounded) is in a masked block; false outside the image.
  template <typename Scalar>
  bool test(Scalar u, Scalar v) const {
    if (bits.empty()) return false;
    const double x = std::floor(double(u) + 0.5), y = std::floor(double(v) + 0.5);
    if (!(x >= 0 && y >= 0 && x < width && y < height)) return false;
    return bits[static_cast<std::size_t>(int(y) / block) * bw + static_cast<std::size_t>(int(x) / block)] != 0;
  }
  std::size_t bytes() const { return bits.size(); }
};

}  // namespace hawor
