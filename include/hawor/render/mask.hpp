// hawor/render/mask.hpp — binary hand masks: mesh silhouettes, dilation, resizing, coverage.
//
// The SLAM's dual masking (docs/design.md §5) needs, per frame, the union of both hands' rendered
// silhouettes at the SLAM resolution; the metric-scale fit (docs/design.md §6) drops pixels with mask
// ≥ 0.5. Masks are Image<uint8_t> with one channel; 0 = background, anything else = set.
// Pixel centres at integer coordinates (docs/design.md §2). No global state; thread-safe per call.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/render/image.hpp"
#include "hawor/render/rasterizer.hpp"

namespace hawor {

using Mask = Image<std::uint8_t>;

namespace render_detail {

template <typename T>
struct NoDeduce {
  using type = T;
};

/// p[0..n) = v. Spans of a hand mesh are a few pixels long, where a memset call costs more than
/// the stores: up to 16 bytes are written as two overlapping 1/2/4/8-byte stores.
inline void fillBytes(std::uint8_t* p, std::size_t n, std::uint8_t v) {
  const std::uint64_t pat = 0x0101010101010101ull * v;
  if (n >= 8) {
    if (n > 16) {
      std::memset(p, v, n);
      return;
    }
    std::memcpy(p, &pat, 8);
    std::memcpy(p + n - 8, &pat, 8);
  } else if (n >= 4) {
    const std::uint32_t p4 = static_cast<std::uint32_t>(pat);
    std::memcpy(p, &p4, 4);
    std::memcpy(p + n - 4, &p4, 4);
  } else if (n >= 2) {
    const std::uint16_t p2 = static_cast<std::uint16_t>(pat);
    std::memcpy(p, &p2, 2);
    std::memcpy(p + n - 2, &p2, 2);
  } else if (n == 1) {
    *p = v;
  }
}

/// Columns [c0, c1] that contain every nonzero byte of row[0..n), found in blocks of 32 (a
/// vectorised OR per block), so possibly wider than needed; false for an all-zero row.
inline bool nonzeroRange(const std::uint8_t* row, int n, int& c0, int& c1) {
  constexpr int kBlock = 32;
  auto blockAny = [row, n](int x0) {
    std::uint8_t m = 0;
    const int x1 = std::min(n, x0 + kBlock);
    for (int x = x0; x < x1; ++x) m |= row[x];
    return m != 0;
  };
  int first = 0;
  while (first < n && !blockAny(first)) first += kBlock;
  if (first >= n) return false;
  int last = (n - 1) / kBlock * kBlock;
  while (!blockAny(last)) last -= kBlock;
  c0 = first;
  c1 = std::min(n - 1, last + kBlock - 1);
  return true;
}

inline void requireMask(const Mask& m, const char* who) {
  if (!m.consistent() || m.channels != 1) {
    throw Error(std::string(who) + ": expected a one-channel mask with data of width×height, got " +
                std::to_string(m.width) + "x" + std::to_string(m.height) + "x" +
                std::to_string(m.channels) + " with " + std::to_string(m.data.size()) +
                " samples");
  }
}

}  // namespace render_detail

/// Draws a mesh's silhouette into an existing mask of the camera's size (set pixels get
/// `value`; others are left unchanged, so repeated calls form the union). vertices: (V,3) in
/// the camera frame (metres), faces: (F,3). No culling by default, so open meshes (MANO has
/// an open wrist) have no holes. Throws hawor::Error for a wrong mask size or bad faces.
template <typename Scalar>
void drawMask(const typename render_detail::NoDeduce<Eigen::Ref<const Points3<Scalar>>>::type& vertices,
              const Eigen::Ref<const TriangleList>& faces, const PinholeCamera<Scalar>& camera,
              Mask& mask, std::uint8_t value = 255,
              const RasterOptions<Scalar>& options = RasterOptions<Scalar>()) {
  render_detail::requireMask(mask, "drawMask");
  if (mask.width != camera.width || mask.height != camera.height) {
    throw Error("drawMask: mask is " + std::to_string(mask.width) + "x" +
                std::to_string(mask.height) + " but the camera is " + std::to_string(camera.width) +
                "x" + std::to_string(camera.height));
  }
  Rasterizer<Scalar> r(camera, options);
  std::uint8_t* px = mask.data.data();
  const int W = mask.width;
  r.drawMeshSpans(vertices, faces, [px, W, value](int y, int x0, int x1) {
    render_detail::fillBytes(px + static_cast<std::size_t>(y) * W + x0,
                             static_cast<std::size_t>(x1 - x0), value);
  });
}

/// The silhouette of one mesh: `out` becomes camera.width × camera.height, `value` inside,
/// 0 elsewhere (see drawMask).
template <typename Scalar>
void renderMask(const typename render_detail::NoDeduce<Eigen::Ref<const Points3<Scalar>>>::type& vertices,
                const Eigen::Ref<const TriangleList>& faces, const PinholeCamera<Scalar>& camera,
                Mask& out, std::uint8_t value = 255,
                const RasterOptions<Scalar>& options = RasterOptions<Scalar>()) {
  camera.validate();
  out.resize(camera.width, camera.height, 1, 0);
  drawMask<Scalar>(vertices, faces, camera, out, value, options);
}

/// One mesh of a multi-mesh mask (both hands). The pointed-to arrays must outlive the call.
template <typename Scalar>
struct MaskMesh {
  const Points3<Scalar>* vertices = nullptr;  ///< (V,3) camera frame, metres
  const TriangleList* faces = nullptr;        ///< (F,3)
  std::uint8_t value = 255;                   ///< label written where this mesh is visible
};

/// Several meshes into one mask of the camera's size. If all values are equal this is the
/// union of the silhouettes; otherwise (labelled masks, e.g. left = 1, right = 2) a z-buffer
/// decides, so each pixel carries the value of the nearest surface.
template <typename Scalar>
void renderMask(const std::vector<MaskMesh<Scalar>>& meshes, const PinholeCamera<Scalar>& camera,
                Mask& out, const RasterOptions<Scalar>& options = RasterOptions<Scalar>()) {
  camera.validate();
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    if (!meshes[i].vertices || !meshes[i].faces) {
      throw Error("renderMask: mesh " + std::to_string(i) + " has no vertices or faces");
    }
  }
  out.resize(camera.width, camera.height, 1, 0);
  bool labelled = false;
  for (const auto& m : meshes) labelled = labelled || m.value != meshes.front().value;
  if (!labelled) {
    for (const auto& m : meshes) drawMask<Scalar>(*m.vertices, *m.faces, camera, out, m.value, options);
    return;
  }
  Rasterizer<Scalar> r(camera, options);
  Image<float> depth;
  r.clearDepth(depth);
  r.setDepthBuffer(&depth);
  std::uint8_t* px = out.data.data();
  const int W = out.width;
  for (const auto& m : meshes) {
    const std::uint8_t value = m.value;
    r.drawMesh(*m.vertices, *m.faces, [px, W, value](const Fragment<Scalar>& f) {
      px[static_cast<std::size_t>(f.y) * W + f.x] = value;
    });
  }
}

namespace render_detail {

/// dilateMask's core for vertical distances of type G (uint8 for r ≤ 253: 16 lanes per SSE
/// register instead of 8).
template <typename G>
void dilateDisc(const Mask& in, int radius, Mask& out, std::uint8_t value) {
  const int W = in.width, H = in.height;
  const G cap = static_cast<G>(radius + 1);
  // g(x, y) = min(|dy| to a set pixel of column x, r + 1): one pass down, one pass up.
  std::vector<G> g(in.numPixels());
  for (int y = 0; y < H; ++y) {
    const std::uint8_t* m = in.row(y);
    G* gr = g.data() + static_cast<std::size_t>(y) * W;
    if (y == 0) {
      for (int x = 0; x < W; ++x) gr[x] = m[x] ? G(0) : cap;
    } else {
      const G* up = gr - W;
      for (int x = 0; x < W; ++x) {
        const G d = static_cast<G>(up[x] < cap ? up[x] + 1 : cap);
        gr[x] = m[x] ? G(0) : d;
      }
    }
  }
  for (int y = H - 2; y >= 0; --y) {
    G* gr = g.data() + static_cast<std::size_t>(y) * W;
    const G* dn = gr + W;
    for (int x = 0; x < W; ++x) {
      const G d = static_cast<G>(dn[x] + 1);
      gr[x] = d < gr[x] ? d : gr[x];
    }
  }
  // Chord half-heights h(dx) = ⌊√(r² − dx²)⌋ (integer square root, corrected after sqrt).
  std::vector<G> h(static_cast<std::size_t>(radius) + 1);
  const std::int64_t r2 = static_cast<std::int64_t>(radius) * radius;
  for (int dx = 0; dx <= radius; ++dx) {
    const std::int64_t t = r2 - static_cast<std::int64_t>(dx) * dx;
    std::int64_t sq = static_cast<std::int64_t>(std::sqrt(static_cast<double>(t)));
    while (sq * sq > t) --sq;
    while ((sq + 1) * (sq + 1) <= t) ++sq;
    h[dx] = static_cast<G>(sq);
  }
  if (&out != &in) out.resize(W, H, 1, 0);
  std::vector<std::uint8_t> acc(static_cast<std::size_t>(W));
  const G r = static_cast<G>(radius);
  for (int y = 0; y < H; ++y) {
    const G* gr = g.data() + static_cast<std::size_t>(y) * W;
    std::uint8_t* o = out.row(y);
    // Only columns within r of one with g ≤ r can be set; most rows of a hand mask have none.
    // [first, last] is found in blocks of 32 columns (a vectorised min per block), so it may be
    // wider than needed, never narrower.
    constexpr int kBlock = 32;
    auto blockHit = [gr, r, W](int x0) {
      G m = static_cast<G>(r + 1);
      const int x1 = std::min(W, x0 + kBlock);
      for (int x = x0; x < x1; ++x) m = gr[x] < m ? gr[x] : m;
      return m <= r;
    };
    int first = 0;
    while (first < W && !blockHit(first)) first += kBlock;
    if (first >= W) {
      std::memset(o, 0, static_cast<std::size_t>(W));
      continue;
    }
    int lastBlock = (W - 1) / kBlock * kBlock;
    while (!blockHit(lastBlock)) lastBlock -= kBlock;
    const int last = std::min(W - 1, lastBlock + kBlock - 1);
    const int xa = std::max(0, first - radius), xb = std::min(W - 1, last + radius);
    std::uint8_t* a = acc.data();
    std::memset(a + xa, 0, static_cast<std::size_t>(xb - xa + 1));
    for (int dx = -radius; dx <= radius; ++dx) {
      const G hd = h[dx < 0 ? -dx : dx];
      const int x0 = std::max(xa, -dx), x1 = std::min(xb + 1, W - dx);  // x + dx in [0, W)
      const G* src = gr + dx;
      for (int x = x0; x < x1; ++x) a[x] |= static_cast<std::uint8_t>(src[x] <= hd);
    }
    std::memset(o, 0, static_cast<std::size_t>(xa));
    for (int x = xa; x <= xb; ++x) o[x] = a[x] ? value : 0;
    std::memset(o + xb + 1, 0, static_cast<std::size_t>(W - 1 - xb));
  }
}

}  // namespace render_detail

/// Disc dilation: out(p) = value iff some set pixel q has |p − q|² ≤ r² (integer pixel
/// offsets, Euclidean; r = 0 binarises). Exact, in two steps: a vertical 1-D distance
/// transform g(x, y) = min |dy| to a set pixel of column x (one pass down, one up, capped at
/// r + 1), then the disc as a union of vertical chords: p is set iff g(x + dx, y) ≤ h(|dx|) for
/// some |dx| ≤ r with h(dx) = ⌊√(r² − dx²)⌋. O(W·H) for the distances plus (2r + 1) byte-wide
/// compares per pixel near the mask (vectorised; rows with no set pixel within r are skipped).
/// `out` may be `in`.
inline void dilateMask(const Mask& in, int radius, Mask& out, std::uint8_t value = 255) {
  render_detail::requireMask(in, "dilateMask");
  if (radius < 0 || radius > 65000) {
    throw Error("dilateMask: radius must be in [0, 65000], got " + std::to_string(radius));
  }
  if (radius <= 253) {
    render_detail::dilateDisc<std::uint8_t>(in, radius, out, value);
  } else {
    render_detail::dilateDisc<std::uint16_t>(in, radius, out, value);
  }
}

/// How resizeMask decides each output pixel.
enum class MaskResize {
  Nearest,  ///< copy the source pixel whose area contains the output pixel's centre
  Area      ///< `value` iff set source pixels cover ≥ ½ of the output pixel's footprint
};

/// Resizes a mask to width × height (e.g. the SLAM resolution). Pixel footprints follow the
/// integer-centre convention: output pixel x covers source [x·W/w, (x+1)·W/w) in "left edge"
/// coordinates. Nearest: source column ⌊(2x + 1)·W / (2w)⌋ (exact integer maths; values are
/// copied, so labels survive). Area: exact rational coverage of the footprint by nonzero source
/// pixels, set (to `value`) iff ≥ 0.5 — the "mask ≥ 0.5" rule of docs/design.md §6 applied to the
/// area-averaged mask. `out` may be `in`.
inline void resizeMask(const Mask& in, int width, int height, Mask& out,
                       MaskResize rule = MaskResize::Area, std::uint8_t value = 255) {
  render_detail::requireMask(in, "resizeMask");
  if (width <= 0 || height <= 0) {
    throw Error("resizeMask: output size must be positive, got " + std::to_string(width) + "x" +
                std::to_string(height));
  }
  if (in.width <= 0 || in.height <= 0) throw Error("resizeMask: the input mask is empty");
  const Mask* src = &in;
  Mask copy;
  if (&out == &in) {
    copy = in;
    src = &copy;
  }
  const std::int64_t W = src->width, H = src->height, w = width, h = height;
  out.resize(width, height, 1, 0);
  if (rule == MaskResize::Nearest) {
    std::vector<int> sxs(static_cast<std::size_t>(w));
    for (std::int64_t x = 0; x < w; ++x) sxs[x] = static_cast<int>(((2 * x + 1) * W) / (2 * w));
    for (std::int64_t y = 0; y < h; ++y) {
      const std::uint8_t* s = src->row(static_cast<int>(((2 * y + 1) * H) / (2 * h)));
      std::uint8_t* o = out.row(static_cast<int>(y));
      for (std::int64_t x = 0; x < w; ++x) o[x] = s[sxs[x]];
    }
    return;
  }
  // Area rule. In units of 1/w source pixels, output column x spans [x·W, (x+1)·W) and source
  // column s spans [s·w, (s+1)·w); the overlap lengths are integers (Σ over s = W). Same for
  // rows in units of 1/h. Covered area in units of 1/(w·h) px² against half the footprint W·H.
  struct Spans {
    std::vector<int> first, count, offset;
    std::vector<std::int32_t> weight;  // flattened overlaps, each ≤ min(W, w)
  };
  auto spans = [](std::int64_t nOut, std::int64_t nIn) {
    Spans sp;
    sp.first.resize(static_cast<std::size_t>(nOut));
    sp.count.resize(static_cast<std::size_t>(nOut));
    sp.offset.resize(static_cast<std::size_t>(nOut));
    for (std::int64_t x = 0; x < nOut; ++x) {
      const std::int64_t lo = x * nIn, hi = (x + 1) * nIn;
      sp.first[x] = static_cast<int>(lo / nOut);
      sp.offset[x] = static_cast<int>(sp.weight.size());
      for (std::int64_t k = lo / nOut; k * nOut < hi; ++k) {
        const std::int64_t a = std::max(lo, k * nOut), b = std::min(hi, (k + 1) * nOut);
        sp.weight.push_back(static_cast<std::int32_t>(b - a));
      }
      sp.count[x] = static_cast<int>(sp.weight.size()) - sp.offset[x];
    }
    return sp;
  };
  const Spans sx = spans(w, W), sy = spans(h, H);
  // Horizontal pass: rowSum(y, x) = Σ_s overlap(x, s)·[set(s, y)] ≤ W. Masks are mostly empty:
  // only output columns whose footprint meets the row's nonzero block range are summed.
  std::vector<std::int32_t> rowSum(static_cast<std::size_t>(H * w), 0);
  std::vector<char> rowEmpty(static_cast<std::size_t>(H), 1);
  for (std::int64_t y = 0; y < H; ++y) {
    const std::uint8_t* srow = src->row(static_cast<int>(y));
    int c0 = 0, c1 = 0;
    if (!render_detail::nonzeroRange(srow, static_cast<int>(W), c0, c1)) continue;
    rowEmpty[y] = 0;
    std::int32_t* rs = rowSum.data() + y * w;
    // Output columns whose footprint [x·W, (x+1)·W) meets [c0·w, (c1+1)·w).
    const std::int64_t x0 = c0 * w / W, x1 = std::min<std::int64_t>(w - 1, ((c1 + 1) * w - 1) / W);
    for (std::int64_t x = x0; x <= x1; ++x) {
      const std::uint8_t* sp = srow + sx.first[x];
      const std::int32_t* wk = sx.weight.data() + sx.offset[x];
      std::int32_t acc = 0;
      for (int k = 0; k < sx.count[x]; ++k) acc += sp[k] ? wk[k] : 0;
      rs[x] = acc;
    }
  }
  // Vertical pass.
  std::vector<std::int64_t> acc(static_cast<std::size_t>(w));
  const std::int64_t half = W * H;  // compare 2·covered with W·H
  for (std::int64_t y = 0; y < h; ++y) {
    std::uint8_t* o = out.row(static_cast<int>(y));
    bool any = false;
    for (int k = 0; k < sy.count[y]; ++k) any = any || !rowEmpty[sy.first[y] + k];
    if (!any) continue;  // out is already zero
    std::fill(acc.begin(), acc.end(), std::int64_t(0));
    for (int k = 0; k < sy.count[y]; ++k) {
      if (rowEmpty[sy.first[y] + k]) continue;
      const std::int32_t* rs = rowSum.data() + (sy.first[y] + k) * w;
      const std::int64_t wk = sy.weight[sy.offset[y] + k];
      std::int64_t* a = acc.data();
      for (std::int64_t x = 0; x < w; ++x) a[x] += wk * rs[x];
    }
    for (std::int64_t x = 0; x < w; ++x) o[x] = 2 * acc[x] >= half ? value : 0;
  }
}

/// Fraction of nonzero pixels, in [0, 1]. Throws for an empty mask.
template <typename Scalar = double>
Scalar maskCoverage(const Mask& mask) {
  render_detail::requireMask(mask, "maskCoverage");
  if (mask.data.empty()) throw Error("maskCoverage: the mask is empty");
  std::size_t n = 0;
  for (const std::uint8_t v : mask.data) n += v != 0;
  return static_cast<Scalar>(static_cast<double>(n) / static_cast<double>(mask.data.size()));
}

}  // namespace hawor
