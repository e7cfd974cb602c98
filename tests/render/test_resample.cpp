// Box-filter downscaling (render/resample.hpp) against a brute-force average in double written
// here: every output pixel the mean of the source pixels whose centres lie in its footprint
// (luma by the BT.601 integer weights for grey), within rounding; integer ratios as plain block
// means; grey and RGB(A) sources; bad sizes and channel counts.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "hawor/render/resample.hpp"

namespace {

/// The expected output of every pixel (channel k of pixel (x, y) at [(y·dw + x)·oc + k]): each
/// source pixel added to the output pixel its centre falls in, in double, then divided.
std::vector<double> reference(const std::vector<std::uint8_t>& src, int sw, int sh, int c, int dw, int dh, bool grey) {
  const int oc = grey ? 1 : 3;
  std::vector<double> sum(static_cast<std::size_t>(dw) * dh * oc, 0.0), n(static_cast<std::size_t>(dw) * dh, 0.0);
  for (int yy = 0; yy < sh; ++yy) {
    for (int xx = 0; xx < sw; ++xx) {
      // the source pixel's centre (xx + 0.5) in output units lies in [x, x + 1)
      const int x = static_cast<int>(std::floor((xx + 0.5) * dw / sw)), y = static_cast<int>(std::floor((yy + 0.5) * dh / sh));
      const std::uint8_t* p = &src[(static_cast<std::size_t>(yy) * sw + xx) * c];
      const double r = p[0], g = c == 1 ? p[0] : p[1], b = c == 1 ? p[0] : p[2];
      const std::size_t o = static_cast<std::size_t>(y) * dw + x;
      if (grey) {
        sum[o] += (77 * r + 150 * g + 29 * b) / 256;
      } else {
        sum[3 * o] += r, sum[3 * o + 1] += g, sum[3 * o + 2] += b;
      }
      n[o] += 1;
    }
  }
  for (std::size_t i = 0; i < sum.size(); ++i) sum[i] /= n[i / static_cast<std::size_t>(oc)];
  return sum;
}

}  // namespace

TEST_CASE("downscaleBox: every output pixel is the mean of its source pixels (brute force)", "[render]") {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> U(0, 255);
  const int cases[][5] = {{12, 9, 4, 3, 3}, {10, 7, 4, 3, 4}, {7, 5, 7, 5, 3}, {33, 17, 10, 6, 1},
                          {1920, 8, 640, 3, 4}, {13, 11, 1, 1, 3}, {640, 480, 639, 479, 3},
                          {9, 6, 9, 6, 4}, {5, 4, 5, 4, 1}};  // 1:1 too (a plain per-pixel conversion)
  for (const auto& cs : cases) {
    const int sw = cs[0], sh = cs[1], dw = cs[2], dh = cs[3], c = cs[4];
    std::vector<std::uint8_t> src(static_cast<std::size_t>(sw) * sh * c);
    for (auto& v : src) v = static_cast<std::uint8_t>(U(rng));
    for (const bool grey : {true, false}) {
      const int oc = grey ? 1 : 3;
      std::vector<std::uint8_t> out(static_cast<std::size_t>(dw) * dh * oc);
      hawor::downscaleBox(src.data(), sw, sh, c, dw, dh, grey, out.data());
      const std::vector<double> ref = reference(src, sw, sh, c, dw, dh, grey);
      int bad = 0;
      for (std::size_t i = 0; i < ref.size(); ++i) bad += std::abs(out[i] - ref[i]) > 0.5 + 1e-9;
      INFO(sw << "x" << sh << "x" << c << " -> " << dw << "x" << dh << (grey ? " grey" : " rgb"));
      CHECK(bad == 0);
    }
  }
}

TEST_CASE("downscaleBox: an integer ratio is a block mean; the image overload; bad input", "[render]") {
  hawor::ImageU8 img(4, 2, 3);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 4; ++x) img.at(x, y, 0) = static_cast<std::uint8_t>(10 * (x + 4 * y)), img.at(x, y, 1) = 200, img.at(x, y, 2) = 7;
  }
  const hawor::ImageU8 half = hawor::downscaleBox(img, 2, 1, false);
  REQUIRE((half.width == 2 && half.height == 1 && half.channels == 3));
  CHECK(int(half.at(0, 0, 0)) == 25);  // (0 + 10 + 40 + 50) / 4
  CHECK(int(half.at(1, 0, 0)) == 45);  // (20 + 30 + 60 + 70) / 4
  CHECK(int(half.at(0, 0, 1)) == 200);
  const hawor::ImageU8 grey = hawor::downscaleBox(img, 4, 2, true);  // same size: luma only
  CHECK(int(grey.at(0, 0)) == (77 * 0 + 150 * 200 + 29 * 7 + 128) / 256);

  std::vector<std::uint8_t> src(12, 1), out(12);
  CHECK_THROWS_WITH(hawor::downscaleBox(src.data(), 2, 2, 2, 1, 1, true, out.data()), Catch::Contains("channels"));
  CHECK_THROWS_WITH(hawor::downscaleBox(src.data(), 2, 2, 3, 3, 1, true, out.data()), Catch::Contains("not a downscale"));
  CHECK_THROWS_WITH(hawor::downscaleBox(src.data(), 2, 2, 3, 0, 1, true, out.data()), Catch::Contains("not a downscale"));
  CHECK_THROWS_WITH(hawor::downscaleBox(nullptr, 2, 2, 3, 1, 1, true, out.data()), Catch::Contains("empty"));
  CHECK_THROWS_AS(hawor::downscaleBox(hawor::ImageU8(), 1, 1, true), hawor::Error);
}
