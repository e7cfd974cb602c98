// Textures (filtering against a direct reference, wrapping, mip levels) and the image statistics
// that tracking needs: enough corners outside the hands in every preset, low-texture walls that
// really are low-texture, smooth random signals.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "synth_test_util.hpp"

namespace {

using namespace synth_test;

/// Bilinear reference on level-0 bytes in double (weights quantised to 1/256 like the texture).
hs::Rgb bilinearRef(const hs::Texture& t, int L, double u, double v) {
  const int n = t.size() >> L;
  const double x = u - 0.5, y = v - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const int wx = static_cast<int>((x - fx) * 256), wy = static_cast<int>((y - fy) * 256);
  auto at = [&](int xx, int yy) { return t.texel(L, ((xx % n) + n) % n, ((yy % n) + n) % n); };
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  auto ch = [&](float a, float b, float c, float d) {
    const int top = (static_cast<int>(a) * (256 - wx) + static_cast<int>(b) * wx) >> 8;
    const int bot = (static_cast<int>(c) * (256 - wx) + static_cast<int>(d) * wx) >> 8;
    return static_cast<float>((top * (256 - wy) + bot * wy) >> 8);
  };
  const hs::Rgb a = at(x0, y0), b = at(x0 + 1, y0), c = at(x0, y0 + 1), d = at(x0 + 1, y0 + 1);
  return hs::Rgb(ch(a.r, b.r, c.r, d.r), ch(a.g, b.g, c.g, d.g), ch(a.b, b.b, c.b, d.b));
}

}  // namespace

TEST_CASE("synth texture: bilinear filtering, wrapping and mip levels", "[synth]") {
  const hs::Texture t = hs::mottledTexture(32, hs::Rgb(200, 120, 60), 3);
  REQUIRE(t.size() == 32);
  REQUIRE(t.numLevels() == 6);  // 32 … 1
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-100, 100);
  for (int k = 0; k < 500; ++k) {
    const double u = U(rng), v = U(rng);
    for (int L : {0, 1, 3}) {
      const hs::Rgb ref = bilinearRef(t, L, u, v);
      const hs::Rgb got = hs::Texture::unpack(t.bilinear(L, float(u), float(v)));
      // float coordinates vs double: the weight may differ by one 1/256 step.
      CHECK(std::abs(got.r - ref.r) <= 1.0f);
      CHECK(std::abs(got.g - ref.g) <= 1.0f);
      CHECK(std::abs(got.b - ref.b) <= 1.0f);
      // Period: the texture size at that level.
      const float n = float(32 >> L);
      const hs::Rgb w = hs::Texture::unpack(t.bilinear(L, float(u) + 4 * n, float(v) - 2 * n));
      CHECK(std::abs(w.r - got.r) <= 1.0f);
    }
  }
  // Texel centres return the texel; each mip texel is the rounded mean of its 2×2 block.
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) {
      const hs::Rgb a = hs::Texture::unpack(t.bilinear(0, x + 0.5f, y + 0.5f)), b = t.texel(0, x, y);
      CHECK((a.r == b.r && a.g == b.g && a.b == b.b));
    }
  }
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) {
      const float m = (t.texel(0, 2 * x, 2 * y).g + t.texel(0, 2 * x + 1, 2 * y).g + t.texel(0, 2 * x, 2 * y + 1).g +
                       t.texel(0, 2 * x + 1, 2 * y + 1).g) / 4.0f;
      CHECK(std::abs(t.texel(1, x, y).g - m) <= 0.5f);
    }
  }
  // Footprints: below 1 → level 0; 2^L exactly → level L; huge → the last level.
  CHECK(hs::Texture::unpack(t.bilinear(0, 3.3f, 7.1f)).r == t.sample(3.3f, 7.1f, 0.5f).r);
  CHECK(hs::Texture::unpack(t.bilinear(2, 3.3f / 4, 7.1f / 4)).g == t.sample(3.3f, 7.1f, 4.0f).g);
  const hs::Rgb last = t.texel(5, 0, 0);
  CHECK(t.sample(1.0f, 2.0f, 1e9f).b == last.b);
  // Between levels the sample lies between the two levels' samples.
  for (int k = 0; k < 100; ++k) {
    const float u = float(U(rng)), v = float(U(rng));
    const float a = hs::Texture::unpack(t.bilinear(1, u / 2, v / 2)).r, b = hs::Texture::unpack(t.bilinear(2, u / 4, v / 4)).r;
    const float s = t.sample(u, v, 3.0f).r;
    CHECK(s >= std::min(a, b) - 1);
    CHECK(s <= std::max(a, b) + 1);
  }
  // Packed lerp = per-byte (a·(256 − w) + b·w) >> 8.
  for (int k = 0; k < 1000; ++k) {
    const std::uint32_t a = rng() & 0xFFFFFFu, b = rng() & 0xFFFFFFu, w = rng() % 257;
    const std::uint32_t r = hs::Texture::lerp(a, b, w);
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t ac = (a >> (8 * c)) & 0xFF, bc = (b >> (8 * c)) & 0xFF;
      CHECK(((r >> (8 * c)) & 0xFF) == ((ac * (256 - w) + bc * w) >> 8));
    }
  }
  CHECK_THROWS_AS(hs::Texture::generate(48, [](int, int) { return hs::Rgb(); }), hawor::Error);
}

TEST_CASE("synth texture: plain walls are low-texture, posters and floors are not", "[synth]") {
  auto gradientEnergy = [](const hs::Texture& t) {
    double e = 0;
    const int n = t.size();
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const hs::Rgb a = t.texel(0, x, y), b = t.texel(0, (x + 1) % n, y), c = t.texel(0, x, (y + 1) % n);
        e += std::abs(a.g - b.g) + std::abs(a.g - c.g);
      }
    }
    return e / (n * n);
  };
  const double plain = gradientEnergy(hs::plainTexture(128, hs::Rgb(200, 200, 190), 0.05f, 1));
  CHECK(plain < 1.0);
  CHECK(gradientEnergy(hs::clutterTexture(128, 40, 1)) > 8 * plain + 2);
  CHECK(gradientEnergy(hs::planksTexture(128, hs::Rgb(160, 110, 70), 1)) > 8 * plain + 2);
  CHECK(gradientEnergy(hs::bricksTexture(128, hs::Rgb(150, 75, 55), hs::Rgb(190, 185, 175), 1)) > 8 * plain + 2);
}

TEST_CASE("synth: every tracking preset shows enough corners outside the hands", "[synth]") {
  const Hands<double>& h = syntheticHands<double>();
  for (const hs::SynthPreset& p : hs::synthPresets()) {
    hs::SynthOptions o = smallOptions(160);
    o.textureDivisor = 2;
    hs::SynthSequence<double> s(p, 21, h.left, h.right, o, sharedScene<double>(21, 2));
    hs::SynthFrame<double> fr;
    int worst = 1 << 30;
    double sumMean = 0;
    int frames = 0;
    for (int i = 0; i < s.numFrames(); i += 25) {
      s.renderFrame(i, fr);
      worst = std::min(worst, countCorners(fr.images.rgb, fr.images.mask, 400.0));
      double mean = 0;
      for (std::uint8_t v : fr.images.rgb.data) mean += v;
      sumMean += mean / double(fr.images.rgb.data.size());
      ++frames;
    }
    INFO(p.name << ": fewest corners in a frame " << worst);
    CHECK(worst >= 20);  // at 160x120, hands and low-texture walls in view
    // Exposure: neither dark nor washed out.
    CHECK(sumMean / frames > 60);
    CHECK(sumMean / frames < 200);
  }
}

TEST_CASE("synth: smooth signals are smooth, bounded and seeded", "[synth]") {
  hs::SynthRng r1(5, 1), r2(5, 1), r3(5, 2);
  const hawor::VecX<double> sigma = hawor::VecX<double>::Constant(2, 0.5);
  const hs::SmoothSignal<double> a(r1, 10, 0.5, 2, sigma), b(r2, 10, 0.5, 2, sigma), c(r3, 10, 0.5, 2, sigma);
  double maxStep = 0, maxAbs = 0, diff = 0;
  for (int i = 0; i <= 1000; ++i) {
    const double t = i * 0.01;
    CHECK(a(t, 1) == b(t, 1));
    diff = std::max(diff, std::abs(a(t, 0) - c(t, 0)));
    maxAbs = std::max(maxAbs, std::abs(a(t, 0)));
    if (i) maxStep = std::max(maxStep, std::abs(a(t, 0) - a(t - 0.01, 0)));
  }
  CHECK(diff > 0.05);
  CHECK(maxAbs < 0.5 * 5);
  CHECK(maxStep < 0.05);  // |ds/dt| < 5 per second for knots 0.5 s apart
  // Outside [0, duration] the value is clamped.
  CHECK(a(-5.0, 0) == a(0.0, 0));
  CHECK(std::isfinite(a(1e9, 1)));
  CHECK(hs::smoothstep(-1.0) == 0.0);
  CHECK(hs::smoothstep(2.0) == 1.0);
  CHECK(hs::smoothstep(0.5) == 0.5);
}
