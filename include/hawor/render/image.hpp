// hawor/render/image.hpp — a minimal owning image: width × height × channels samples of T.
//
// Layout (docs/design.md §2): row-major, origin top-left, channels interleaved, no padding and no
// alignment assumption: sample (x, y, c) lives at data[(y·width + x)·channels + c]. Pixel centres
// are at integer coordinates, so pixel (x, y) covers [x − ½, x + ½] × [y − ½, y + ½].
// A plain value type; thread-safe to read, one writer at a time.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "hawor/common.hpp"

namespace hawor {

template <typename T>
struct Image {
  int width = 0, height = 0, channels = 1;
  std::vector<T> data;  ///< (height, width, channels) row-major

  Image() = default;
  /// A width × height × channels image with every sample set to `fill`.
  Image(int w, int h, int c = 1, const T& fill = T()) { resize(w, h, c, fill); }

  /// Resizes to w × h × c (sizes ≥ 0, c ≥ 1) and sets every sample to `fill`. Reuses the
  /// existing buffer when it is large enough (no allocation for a repeated size).
  void resize(int w, int h, int c = 1, const T& fill = T()) {
    if (w < 0 || h < 0 || c < 1) {
      throw Error("Image: invalid size " + std::to_string(w) + "x" + std::to_string(h) + "x" +
                  std::to_string(c));
    }
    if (static_cast<double>(w) * h * c > 1e10) {
      throw Error("Image: size " + std::to_string(w) + "x" + std::to_string(h) + "x" +
                  std::to_string(c) + " is too large");
    }
    width = w;
    height = h;
    channels = c;
    data.assign(static_cast<std::size_t>(w) * h * c, fill);
  }

  /// Sets every sample to v.
  void fill(const T& v) { data.assign(data.size(), v); }

  bool empty() const { return data.empty(); }
  std::size_t numPixels() const { return static_cast<std::size_t>(width) * height; }
  /// True when the sizes agree with the buffer (a struct can be edited by hand).
  bool consistent() const {
    return width >= 0 && height >= 0 && channels >= 1 &&
           data.size() == static_cast<std::size_t>(width) * height * channels;
  }
  bool sameSize(int w, int h, int c = 1) const {
    return width == w && height == h && channels == c && consistent();
  }

  /// Unchecked access to sample (x, y, c).
  T& at(int x, int y, int c = 0) {
    return data[(static_cast<std::size_t>(y) * width + x) * channels + c];
  }
  const T& at(int x, int y, int c = 0) const {
    return data[(static_cast<std::size_t>(y) * width + x) * channels + c];
  }
  /// Pointer to the first sample of row y.
  T* row(int y) { return data.data() + static_cast<std::size_t>(y) * width * channels; }
  const T* row(int y) const { return data.data() + static_cast<std::size_t>(y) * width * channels; }

  bool contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
};

using ImageU8 = Image<unsigned char>;
using ImageF = Image<float>;

}  // namespace hawor
