// hawor/synth/texture.hpp — procedural RGB textures for the synthetic indoor scene, and their
// filtered sampling.
//
// A Texture is a square, power-of-two RGB8 image that tiles (wraps) in both directions, stored
// with its mip pyramid (2×2 box averages), texels packed as 32-bit words 0x00bbggrr. Sampling is trilinear: the level follows the pixel's
// footprint in level-0 texels (bilinear inside a level, linear between two levels), so distant
// surfaces do not alias into flickering noise that no real camera would see.
// Coordinates are in level-0 texels: texel i covers [i, i + 1), its centre is i + ½.
//
// Generators (all periodic, so tiles join seamlessly; deterministic for a seed: integer hashes
// and float arithmetic only, no libm, so the bytes are the same on every platform):
//   plainTexture    almost uniform colour with faint low-frequency mottling (low-texture walls)
//   planksTexture   wooden floor boards: per-board colour, grain, dark joints, staggered ends
//   bricksTexture   running-bond bricks with mortar
//   tilesTexture    square tiles with grout and a few decorated tiles
//   woodTexture     a wooden surface with grain and knots
//   clutterTexture  posters / printed packaging: overlapping rectangles, discs and bars in strong
//                   colours (many corners: what feature trackers need)
//   paperTexture    printed pages: lines of word-like blocks, a title and a figure
//   rugTexture      a woven pattern of diamonds and stripes
//   stripesTexture  book spines: bands of labels
//   mottledTexture  blotchy colour variation (fruit, ceramics, fabric)
// Colours are sRGB byte values; the generators keep them in [20, 235] so shading rarely clips.
// Texture coordinates are float and filtering is integer on purpose: it is colour, not geometry
// (any Scalar renders the same images), and packed-integer filtering is what makes the renderer
// fast.
// Thread-safety: a generated Texture is read-only.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/render/image.hpp"
#include "hawor/synth/random.hpp"

namespace hawor {
namespace synth {

/// An RGB colour with float components (byte scale, 0..255).
struct Rgb {
  float r = 0, g = 0, b = 0;
  Rgb() = default;
  Rgb(float r_, float g_, float b_) : r(r_), g(g_), b(b_) {}
  Rgb operator*(float s) const { return Rgb(r * s, g * s, b * s); }
  Rgb operator+(const Rgb& o) const { return Rgb(r + o.r, g + o.g, b + o.b); }
  Rgb mul(const Rgb& o) const { return Rgb(r * o.r, g * o.g, b * o.b); }
};

/// Linear interpolation a + (b − a)·t of colours.
inline Rgb mix(const Rgb& a, const Rgb& b, float t) {
  return Rgb(a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t);
}

class Texture {
 public:
  Texture() = default;

  /// A size × size texture (size a power of two in [4, 4096]) from fn(x, y) → Rgb for every
  /// texel (x, y integers); values are rounded and clamped to bytes; the mip pyramid is built.
  template <typename Fn>
  static Texture generate(int size, Fn fn) {
    if (size < 4 || size > 4096 || (size & (size - 1)) != 0) {
      throw Error("Texture: size must be a power of two in [4, 4096], got " + std::to_string(size));
    }
    Texture t;
    t.levels_.emplace_back(static_cast<std::size_t>(size) * static_cast<std::size_t>(size));
    std::uint32_t* base = t.levels_[0].data();
    for (int y = 0; y < size; ++y) {
      for (int x = 0; x < size; ++x) {
        const Rgb c = fn(x, y);
        base[static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x)] =
            pack(toByte(c.r), toByte(c.g), toByte(c.b));
      }
    }
    t.size_ = size;
    t.buildMips();
    return t;
  }

  int size() const { return size_; }
  int numLevels() const { return static_cast<int>(levels_.size()); }
  /// Texel (x, y) of level L (size >> L) as bytes r, g, b.
  Rgb texel(int L, int x, int y) const {
    const int n = size_ >> L;
    const std::uint32_t t = levels_[static_cast<std::size_t>(L)][static_cast<std::size_t>(y) * static_cast<std::size_t>(n) +
                                                               static_cast<std::size_t>(x)];
    return unpack(t);
  }

  /// Trilinear sample at level-0 texel coordinates (u, v) for a pixel covering `footprint`
  /// level-0 texels (< 1: bilinear on level 0; else linear between levels ⌊log2⌋ and ⌊log2⌋ + 1). Wraps in both directions; coordinates must stay
  /// within ±2^30 texels. Bytes (0..255) per channel; weights in 1/256 steps (integer maths, so
  /// every platform gives the same bits).
  Rgb sample(float u, float v, float footprint) const {
    const int last = numLevels() - 1;
    if (!(footprint >= 1.0f) || last == 0) return unpack(bilinear(0, u, v));
    // footprint = 2^L·(1 + m), m ∈ [0, 1): L from the float's exponent, the blend weight between
    // levels L and L+1 from the top 8 bits of its mantissa (exact, branch-free, no libm).
    std::uint32_t bits;
    std::memcpy(&bits, &footprint, sizeof bits);
    int L = static_cast<int>((bits >> 23) & 0xFFu) - 127;
    if (L >= last) return unpack(bilinear(last, u / static_cast<float>(1 << last), v / static_cast<float>(1 << last)));
    const std::uint32_t w = (bits >> 15) & 0xFFu;
    const float inv = 1.0f / static_cast<float>(1 << L);
    const std::uint32_t a = bilinear(L, u * inv, v * inv);
    const std::uint32_t b = bilinear(L + 1, u * inv * 0.5f, v * inv * 0.5f);
    return unpack(lerp(a, b, w));
  }

  /// Bilinear sample of level L at that level's texel coordinates (wrapping), packed bytes.
  std::uint32_t bilinear(int L, float u, float v) const {
    const int n = size_ >> L, mask = n - 1;
    const float x = u - 0.5f, y = v - 0.5f;
    // ⌊x⌋ without libm (std::floor is a call on baseline x86-64): truncate, then fix negatives.
    int xi = static_cast<int>(x), yi = static_cast<int>(y);
    xi -= static_cast<float>(xi) > x ? 1 : 0;
    yi -= static_cast<float>(yi) > y ? 1 : 0;
    const std::uint32_t wx = static_cast<std::uint32_t>((x - static_cast<float>(xi)) * 256.0f);
    const std::uint32_t wy = static_cast<std::uint32_t>((y - static_cast<float>(yi)) * 256.0f);
    // Power-of-two size: & wraps negative integers too (two's complement).
    const std::size_t x0 = static_cast<std::size_t>(xi & mask), x1 = static_cast<std::size_t>((xi + 1) & mask);
    const std::uint32_t* img = levels_[static_cast<std::size_t>(L)].data();
    const std::uint32_t* r0 = img + static_cast<std::size_t>(yi & mask) * static_cast<std::size_t>(n);
    const std::uint32_t* r1 = img + static_cast<std::size_t>((yi + 1) & mask) * static_cast<std::size_t>(n);
    return lerp(lerp(r0[x0], r0[x1], wx), lerp(r1[x0], r1[x1], wx), wy);
  }

  /// Bytes r, g, b packed as 0x00bbggrr.
  static std::uint32_t pack(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
    return static_cast<std::uint32_t>(r) | (static_cast<std::uint32_t>(g) << 8) | (static_cast<std::uint32_t>(b) << 16);
  }
  static Rgb unpack(std::uint32_t t) {
    return Rgb(static_cast<float>(t & 0xFFu), static_cast<float>((t >> 8) & 0xFFu), static_cast<float>((t >> 16) & 0xFFu));
  }
  /// Per byte (a·(256 − w) + b·w) / 256 for w in [0, 256], two bytes per 32-bit lane pair
  /// (red and blue together, then green): no byte overflows into its neighbour.
  static std::uint32_t lerp(std::uint32_t a, std::uint32_t b, std::uint32_t w) {
    const std::uint32_t iw = 256u - w;
    const std::uint32_t rb = (((a & 0x00FF00FFu) * iw + (b & 0x00FF00FFu) * w) >> 8) & 0x00FF00FFu;
    const std::uint32_t g = (((a >> 8) & 0xFFu) * iw + ((b >> 8) & 0xFFu) * w) & 0xFF00u;
    return rb | g;
  }

 private:
  static std::uint8_t toByte(float v) {
    const float c = v < 0.0f ? 0.0f : (v > 255.0f ? 255.0f : v);
    return static_cast<std::uint8_t>(c + 0.5f);
  }

  void buildMips() {
    int n = size_;
    while (n > 1) {
      const std::vector<std::uint32_t>& src = levels_.back();
      const int m = n / 2;
      std::vector<std::uint32_t> dst(static_cast<std::size_t>(m) * static_cast<std::size_t>(m));
      for (int y = 0; y < m; ++y) {
        for (int x = 0; x < m; ++x) {
          const std::size_t i0 = static_cast<std::size_t>(2 * y) * static_cast<std::size_t>(n) + static_cast<std::size_t>(2 * x);
          const std::uint32_t t[4] = {src[i0], src[i0 + 1], src[i0 + static_cast<std::size_t>(n)],
                                      src[i0 + static_cast<std::size_t>(n) + 1]};
          std::uint32_t out = 0;
          for (int c = 0; c < 3; ++c) {
            std::uint32_t s = 2;
            for (std::uint32_t v : t) s += (v >> (8 * c)) & 0xFFu;
            out |= (s / 4) << (8 * c);
          }
          dst[static_cast<std::size_t>(y) * static_cast<std::size_t>(m) + static_cast<std::size_t>(x)] = out;
        }
      }
      levels_.push_back(std::move(dst));
      n = m;
    }
  }

  int size_ = 0;
  std::vector<std::vector<std::uint32_t>> levels_;  ///< per level (size >> L)² packed texels
};

// --- building blocks -----------------------------------------------------------------------------

/// Periodic value noise in [0, 1): hashed values on the integer lattice (periods px, py),
/// smoothstep-interpolated. x, y in lattice units.
inline float valueNoise(float x, float y, int px, int py, std::uint32_t seed) {
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
  auto wrap = [](int i, int p) { return static_cast<std::uint32_t>(((i % p) + p) % p); };
  const std::uint32_t x0 = wrap(ix, px), x1 = wrap(ix + 1, px), y0 = wrap(iy, py), y1 = wrap(iy + 1, py);
  const float v00 = hashUnit(hash3(seed, x0, y0)), v10 = hashUnit(hash3(seed, x1, y0));
  const float v01 = hashUnit(hash3(seed, x0, y1)), v11 = hashUnit(hash3(seed, x1, y1));
  const float sx = tx * tx * (3.0f - 2.0f * tx), sy = ty * ty * (3.0f - 2.0f * ty);
  const float a = v00 + (v10 - v00) * sx, b = v01 + (v11 - v01) * sx;
  return a + (b - a) * sy;
}

/// Fractal sum of `octaves` value-noise layers over a texture of `size` texels, tileable: the
/// first layer has cx × cy lattice cells across the texture, each next one twice as many and
/// half the amplitude. (x, y) may be fractional texel coordinates. Result in [0, 1).
inline float fbm(float x, float y, int size, int cx, int cy, int octaves, std::uint32_t seed) {
  float sum = 0.0f, amp = 1.0f, norm = 0.0f;
  for (int o = 0; o < octaves; ++o) {
    const float sx = static_cast<float>(cx) / static_cast<float>(size);
    const float sy = static_cast<float>(cy) / static_cast<float>(size);
    sum += amp * valueNoise((x + 0.5f) * sx, (y + 0.5f) * sy, cx, cy, hashCombine(seed, static_cast<std::uint32_t>(o)));
    norm += amp;
    amp *= 0.5f;
    cx *= 2;
    cy *= 2;
  }
  return sum / norm;
}

/// Isotropic fbm at texel (x, y) with `cells` lattice cells across the texture.
inline float fbm(int x, int y, int size, int cells, int octaves, std::uint32_t seed) {
  return fbm(static_cast<float>(x), static_cast<float>(y), size, cells, cells, octaves, seed);
}

/// A random colour near `base`: each channel scaled by (1 ± spread), from hash h.
inline Rgb jitterColour(const Rgb& base, float spread, std::uint32_t h) {
  const float a = 1.0f + spread * (2.0f * hashUnit(hash32(h)) - 1.0f);
  const float b = spread * 0.4f * (2.0f * hashUnit(hash32(h + 1)) - 1.0f);
  const float c = spread * 0.4f * (2.0f * hashUnit(hash32(h + 2)) - 1.0f);
  return Rgb(base.r * (a + b), base.g * a, base.b * (a + c));
}

/// One of a palette of strong, distinct colours.
inline Rgb paletteColour(std::uint32_t h) {
  static const float p[12][3] = {{200, 40, 40},  {40, 120, 200}, {230, 190, 40}, {40, 160, 80},
                                 {220, 110, 30}, {120, 60, 160}, {30, 30, 40},   {225, 225, 215},
                                 {20, 90, 110},  {190, 80, 140}, {110, 70, 40},  {150, 200, 60}};
  const float* c = p[h % 12];
  return Rgb(c[0], c[1], c[2]);
}

/// Wrapped difference d = a − b in (−n/2, n/2] (for tileable shapes).
inline int wrapDelta(int a, int b, int n) {
  int d = (a - b) % n;
  if (d > n / 2) d -= n;
  if (d <= -n / 2) d += n;
  return d;
}

// --- generators ----------------------------------------------------------------------------------

/// Almost uniform colour: base·(1 + amplitude·(noise − ½)) with very low-frequency noise.
inline Texture plainTexture(int size, const Rgb& base, float amplitude, std::uint32_t seed) {
  return Texture::generate(size, [&](int x, int y) {
    const float n = fbm(x, y, size, 3, 2, seed) - 0.5f;
    return base * (1.0f + amplitude * n);
  });
}

/// Floor boards: 8 boards across v, each of random length along u, with grain and dark joints.
inline Texture planksTexture(int size, const Rgb& base, std::uint32_t seed) {
  const int board = size / 8;
  return Texture::generate(size, [&](int x, int y) {
    const int row = y / board;
    const int shift = static_cast<int>(hash3(seed, 7, static_cast<std::uint32_t>(row)) % static_cast<std::uint32_t>(size));
    const int xs = (x + shift) % size;
    const int plankLen = size / 2;
    const int col = xs / plankLen;
    const std::uint32_t id = hash3(seed, static_cast<std::uint32_t>(row), static_cast<std::uint32_t>(col));
    Rgb c = jitterColour(base, 0.18f, id);
    // Grain: noise stretched along the board (u), fine across it.
    const float g = fbm(float(x), float(y), size, 4, 64, 3, seed + 11);
    const float streak = fbm(float(x), float(y), size, 2, 16, 2, seed + 29);
    c = c * (0.82f + 0.3f * g + 0.12f * streak);
    const int yin = y % board;
    const int xin = xs % plankLen;
    if (yin < 2 || xin < 2) c = c * 0.45f;  // joints
    return c;
  });
}

/// Running-bond bricks (16 courses, 8 bricks per course) with light mortar.
inline Texture bricksTexture(int size, const Rgb& brick, const Rgb& mortar, std::uint32_t seed) {
  const int course = size / 16, len = size / 8, joint = std::max(2, size / 128);
  return Texture::generate(size, [&](int x, int y) {
    const int row = y / course;
    const int xs = (x + (row % 2) * len / 2) % size;
    const int col = xs / len;
    const float n = fbm(x, y, size, 32, 2, seed + 3);
    if (y % course < joint || xs % len < joint) return mortar * (0.9f + 0.2f * n);
    const std::uint32_t id = hash3(seed, static_cast<std::uint32_t>(row), static_cast<std::uint32_t>(col));
    return jitterColour(brick, 0.2f, id) * (0.85f + 0.3f * n);
  });
}

/// Square tiles (8 × 8) with grout; about one tile in six carries a diagonal motif.
inline Texture tilesTexture(int size, const Rgb& tile, const Rgb& grout, std::uint32_t seed) {
  const int cell = size / 8, joint = std::max(2, size / 96);
  return Texture::generate(size, [&](int x, int y) {
    const int cx = x / cell, cy = y / cell, ix = x % cell, iy = y % cell;
    if (ix < joint || iy < joint) return grout;
    const std::uint32_t id = hash3(seed, static_cast<std::uint32_t>(cx), static_cast<std::uint32_t>(cy));
    Rgb c = jitterColour(tile, 0.08f, id);
    if (id % 6 == 0) {
      const int d = std::abs(ix - iy), e = std::abs(ix + iy - cell);
      if (d < cell / 10 || e < cell / 10) c = paletteColour(id >> 8) * 0.8f;
    }
    return c * (0.95f + 0.1f * fbm(x, y, size, 16, 2, seed + 5));
  });
}

/// A wooden surface: grain along u, growth rings, a few dark knots.
inline Texture woodTexture(int size, const Rgb& base, std::uint32_t seed) {
  struct Knot {
    int x, y, r;
  };
  std::vector<Knot> knots;
  for (std::uint32_t k = 0; k < 5; ++k) {
    const std::uint32_t h = hash3(seed, 99, k);
    knots.push_back({static_cast<int>(h % static_cast<std::uint32_t>(size)),
                     static_cast<int>((h >> 12) % static_cast<std::uint32_t>(size)), size / 48 + static_cast<int>(h % 5)});
  }
  return Texture::generate(size, [&](int x, int y) {
    const float warp = fbm(x, y, size, 4, 2, seed + 1);
    const float rings = fbm(float(x), float(y) + 40.0f * warp, size, 2, 16, 3, seed + 2);
    const float band = rings * 6.0f - std::floor(rings * 6.0f);
    Rgb c = base * (0.78f + 0.22f * band + 0.12f * fbm(x, y, size, 64, 1, seed + 4));
    for (const Knot& k : knots) {
      const int dx = wrapDelta(x, k.x, size), dy = wrapDelta(y, k.y, size);
      const int d2 = dx * dx / 4 + dy * dy;
      if (d2 < k.r * k.r) c = c * (0.55f + 0.35f * static_cast<float>(d2) / static_cast<float>(k.r * k.r));
    }
    return c;
  });
}

/// Posters and packaging: `shapes` overlapping rectangles, discs and bars in palette colours
/// on a light background, with dark outlines on some (tileable).
inline Texture clutterTexture(int size, int shapes, std::uint32_t seed) {
  struct Shape {
    int kind, x, y, w, h, outline;
    Rgb c;
  };
  std::vector<Shape> list;
  for (int i = 0; i < shapes; ++i) {
    const std::uint32_t h = hash3(seed, 17, static_cast<std::uint32_t>(i));
    const std::uint32_t g = hash32(h);
    Shape s;
    s.kind = static_cast<int>(h % 3);
    s.x = static_cast<int>(g % static_cast<std::uint32_t>(size));
    s.y = static_cast<int>((g >> 12) % static_cast<std::uint32_t>(size));
    const int maxDim = std::max(4, size / 5);
    s.w = 3 + static_cast<int>(hash32(g) % static_cast<std::uint32_t>(maxDim));
    s.h = 3 + static_cast<int>(hash32(g + 7) % static_cast<std::uint32_t>(maxDim));
    if (s.kind == 2) s.h = std::max(2, s.h / 6);  // bars
    s.outline = (hash32(g + 3) % 3 == 0) ? std::max(1, size / 200) : 0;
    s.c = paletteColour(hash32(g + 9));
    list.push_back(s);
  }
  const Rgb background = jitterColour(Rgb(215, 210, 195), 0.06f, seed);
  // Paint the shapes in order over their (wrapped) bounding boxes: later ones cover earlier ones.
  std::vector<Rgb> canvas(static_cast<std::size_t>(size) * static_cast<std::size_t>(size), background);
  for (const Shape& s : list) {
    const int x0 = s.kind == 1 ? s.x - s.w / 2 : s.x, y0 = s.kind == 1 ? s.y - s.w / 2 : s.y;
    const int w = s.kind == 1 ? s.w + 1 : s.w, h = s.kind == 1 ? s.w + 1 : s.h;
    for (int yy = y0; yy < y0 + h; ++yy) {
      for (int xx = x0; xx < x0 + w; ++xx) {
        const int dx = xx - s.x, dy = yy - s.y;
        bool in = false, edge = false;
        if (s.kind == 1) {
          const int r = s.w / 2;
          const int d2 = dx * dx + dy * dy;
          in = d2 <= r * r;
          edge = in && s.outline > 0 && d2 >= (r - s.outline) * (r - s.outline);
        } else {
          in = true;
          edge = s.outline > 0 && (dx < s.outline || dy < s.outline || dx >= s.w - s.outline || dy >= s.h - s.outline);
        }
        if (!in) continue;
        const int px = ((xx % size) + size) % size, py = ((yy % size) + size) % size;
        canvas[static_cast<std::size_t>(py) * static_cast<std::size_t>(size) + static_cast<std::size_t>(px)] =
            edge ? Rgb(25, 25, 30) : s.c;
      }
    }
  }
  return Texture::generate(size, [&](int x, int y) {
    return canvas[static_cast<std::size_t>(y) * static_cast<std::size_t>(size) + static_cast<std::size_t>(x)];
  });
}

/// Printed pages: a title bar, lines of word blocks and a figure box.
inline Texture paperTexture(int size, std::uint32_t seed) {
  const int margin = size / 12, line = std::max(4, size / 28), glyph = std::max(2, line / 2);
  const int figX = size / 2, figY = size / 2, figW = size / 3, figH = size / 4;
  const Rgb ink(35, 35, 45), paper(232, 228, 218);
  const Rgb fig = paletteColour(hash32(seed));
  return Texture::generate(size, [&](int x, int y) {
    if (x < margin || x >= size - margin || y < margin || y >= size - margin) return paper;
    if (x >= figX && x < figX + figW && y >= figY && y < figY + figH) {
      const int fx = x - figX, fy = y - figY;
      return (fx / 8 + fy / 8) % 2 ? fig : fig * 0.6f;
    }
    const int row = (y - margin) / line, inRow = (y - margin) % line;
    if (row == 0) return inRow < line - 1 ? Rgb(150, 40, 40) : paper;  // title bar
    if (inRow >= glyph) return paper;
    // Words: runs of "ink" whose lengths come from a hash of (row, position).
    const int pos = x - margin;
    const std::uint32_t h = hash3(seed, static_cast<std::uint32_t>(row), static_cast<std::uint32_t>(pos / (glyph * 6)));
    const int wordLen = glyph * (2 + static_cast<int>(h % 4));
    return (pos % (glyph * 6)) < wordLen ? ink : paper;
  });
}

/// A rug: diamonds in a two-colour field with border stripes, plus weave noise.
inline Texture rugTexture(int size, std::uint32_t seed) {
  const Rgb a = paletteColour(hash32(seed)), b = paletteColour(hash32(seed + 1) + 3), field(180, 160, 120);
  const int cell = size / 8;
  return Texture::generate(size, [&](int x, int y) {
    const int ix = x % cell - cell / 2, iy = y % cell - cell / 2;
    const int d = std::abs(ix) + std::abs(iy);
    Rgb c = field;
    if (d < cell / 3) c = ((x / cell + y / cell) % 2) ? a : b;
    if (d >= cell / 3 && d < cell / 3 + std::max(1, cell / 16)) c = Rgb(40, 30, 30);
    if ((y % (cell * 4)) < std::max(2, cell / 8)) c = b * 0.8f;
    return c * (0.88f + 0.24f * hashUnit(hash3(seed, static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y))));
  });
}

/// Book spines: light and dark bands with label blocks (tinted per book by the material).
inline Texture stripesTexture(int size, std::uint32_t seed) {
  return Texture::generate(size, [&](int x, int y) {
    const int band = y * 16 / size;
    const std::uint32_t h = hash3(seed, 5, static_cast<std::uint32_t>(band));
    float v = 0.75f + 0.25f * hashUnit(h);
    if (h % 4 == 0) v = 0.35f;
    const int xin = x % (size / 4);
    if (h % 3 == 1 && xin > size / 32 && xin < size / 6) v = 1.0f;  // label blocks
    return Rgb(220, 220, 220) * v;
  });
}

/// Blotchy variation around `base` (fruit skins, glazes, fabric).
inline Texture mottledTexture(int size, const Rgb& base, std::uint32_t seed) {
  return Texture::generate(size, [&](int x, int y) {
    const float n = fbm(x, y, size, 8, 3, seed);
    const float m = fbm(x, y, size, 32, 2, seed + 1);
    return base * (0.7f + 0.5f * n + 0.15f * m);
  });
}

}  // namespace synth
}  // namespace hawor
