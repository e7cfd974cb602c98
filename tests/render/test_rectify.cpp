// Rectification (render/rectify.hpp) and perspective crops through a lens (render/lens_crop.hpp)
// against brute-force per-pixel computations written here in double: every target pixel's ray
// projected through the lens (Lens::inDomain, CameraModel::project, the image bounds), bilinear
// sampling with clamped neighbours and nearest sampling at the map's positions, the SLAM border
// as a Chebyshev distance to the outside region; a pinhole lens as an exact copy; a smooth
// pattern of ray directions seen through a fisheye and rectified against the same pattern seen
// by the pinhole; the crop's rays, its inverse, its local scale and axes; bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "hawor/render/lens_crop.hpp"
#include "hawor/render/rectify.hpp"

namespace {

using hawor::CameraModel;
using hawor::Lens;
using hawor::PinholeCamera;
using hawor::RectifyMap;
constexpr double kPi = 3.14159265358979323846;

PinholeCamera<double> intrinsics(double f, int w, int h, double dcx = 0.0, double dcy = 0.0) {
  PinholeCamera<double> c;
  c.fx = f, c.fy = f * 1.01;
  c.cx = (w - 1) / 2.0 + dcx, c.cy = (h - 1) / 2.0 + dcy;
  c.width = w, c.height = h;
  return c;
}

/// The lenses of the tests, at 160 × 120: an Aria-like fisheye (150° diagonal), a GoPro-like
/// barrel radial-tangential lens, a pincushion one (its virtual pinhole sees beyond the source)
/// and the pinhole.
std::vector<CameraModel<double>> cameras() {
  return {
      {intrinsics(78.4, 160, 120, 1.3, -0.7), Lens<double>::parse("fisheye:-0.0036,0.0368,-0.0343,0.0052")},
      {intrinsics(82.0, 160, 120, -0.4, 0.9), Lens<double>::parse("opencv:-0.16,0.02,0.0004,-0.0003,-0.001")},
      {intrinsics(110.0, 160, 120, 0.5, 0.5), Lens<double>::parse("opencv:0.12,0.03,0.002,-0.001,0.01")},
      {intrinsics(100.0, 160, 120), Lens<double>::pinhole()},
  };
}

/// Brute force: the source pixel of target pixel (x, y), false when outside.
bool bruteSource(const CameraModel<double>& src, const PinholeCamera<double>& tgt, int x, int y, hawor::Vec2<double>& uv) {
  const hawor::Vec3<double> ray((x - tgt.cx) / tgt.fx, (y - tgt.cy) / tgt.fy, 1.0);
  if (!src.lens.inDomain(ray)) return false;
  uv = src.project(ray);
  return src.intrinsics.inImage(uv);
}

std::vector<std::uint8_t> randomImage(int w, int h, int c, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> d(0, 255);
  std::vector<std::uint8_t> v(static_cast<std::size_t>(w) * h * c);
  for (auto& b : v) b = static_cast<std::uint8_t>(d(rng));
  return v;
}

/// Bilinear in double with the neighbours ⌊u⌋, ⌊u⌋ + 1 clamped to the image.
double bilinear(const std::vector<std::uint8_t>& img, int w, int h, int c, int k, double u, double v) {
  const double fu = std::floor(u), fv = std::floor(v);
  const double a = u - fu, b = v - fv;
  auto px = [&](int x, int y) {
    x = std::clamp(x, 0, w - 1), y = std::clamp(y, 0, h - 1);
    return double(img[(static_cast<std::size_t>(y) * w + x) * c + k]);
  };
  const int x0 = int(fu), y0 = int(fv);
  return (1 - b) * ((1 - a) * px(x0, y0) + a * px(x0 + 1, y0)) + b * ((1 - a) * px(x0, y0 + 1) + a * px(x0 + 1, y0 + 1));
}

}  // namespace

TEMPLATE_TEST_CASE("RectifyMap: source positions and the outside region against a per-pixel brute force", "[rectify]",
                   float, double) {
  using S = TestType;
  const double tolPx = std::is_same<S, float>::value ? 2e-2 : 1e-9;
  for (const CameraModel<double>& cam : cameras()) {
    // the default target (the source's intrinsics) and a wider, smaller one
    PinholeCamera<double> wide = intrinsics(0.6 * cam.intrinsics.fx, 120, 90, 0.25, -0.25);
    for (const PinholeCamera<double>& tgt : {cam.intrinsics, wide}) {
      INFO(cam.lens.toString() << " target f=" << tgt.fx << " " << tgt.width << "x" << tgt.height);
      const RectifyMap<S> map(cam.template cast<S>(), tgt.template cast<S>());
      CHECK(map.width() == tgt.width);
      CHECK(map.height() == tgt.height);
      std::size_t outside = 0, mismatch = 0;
      double worst = 0;
      for (int y = 0; y < tgt.height; ++y) {
        for (int x = 0; x < tgt.width; ++x) {
          hawor::Vec2<double> ref;
          const bool in = bruteSource(cam, tgt, x, y, ref);
          hawor::Vec2<S> got;
          const bool gin = map.sourcePixel(x, y, got);
          outside += in ? 0 : 1;
          if (in != gin) {
            ++mismatch;  // float: pixels on the boundary, within rounding of it
            continue;
          }
          if (in) worst = std::max(worst, (got.template cast<double>() - ref).norm());
          if (!map.identity()) CHECK((map.outsideMask().at(x, y) != 0) == !gin);
        }
      }
      CHECK(worst <= tolPx);
      if (std::is_same<S, double>::value) {
        CHECK(mismatch == 0);
      } else {
        CHECK(mismatch <= 2);
      }
      CHECK(std::abs(double(map.numOutside()) - double(outside)) <= double(mismatch));
      const bool identity = cam.lens.isPinhole() && tgt.fx == cam.intrinsics.fx && tgt.width == cam.intrinsics.width;
      CHECK(map.identity() == identity);
    }
  }
  // What the default target keeps: a barrel lens covers the pinhole's view, a pincushion does not.
  const auto cams = cameras();
  CHECK(RectifyMap<S>(cams[0].template cast<S>()).numOutside() == 0);
  CHECK(RectifyMap<S>(cams[1].template cast<S>()).numOutside() == 0);
  CHECK(RectifyMap<S>(cams[2].template cast<S>()).numOutside() > 0);
}

TEMPLATE_TEST_CASE("RectifyMap: bilinear and nearest remaps against brute-force sampling at the map's positions",
                   "[rectify]", float, double) {
  using S = TestType;
  for (const CameraModel<double>& cam : cameras()) {
    if (cam.lens.isPinhole()) continue;
    const PinholeCamera<double> wide = intrinsics(0.7 * cam.intrinsics.fx, 150, 100);
    for (const PinholeCamera<double>& tgt : {cam.intrinsics, wide}) {
      const RectifyMap<S> map(cam.template cast<S>(), tgt.template cast<S>());
      const int W = cam.intrinsics.width, H = cam.intrinsics.height;
      for (int c : {1, 3, 4}) {
        INFO(cam.lens.toString() << " channels " << c << " target " << tgt.width);
        const std::vector<std::uint8_t> src = randomImage(W, H, c, 7u + unsigned(c));
        std::vector<std::uint8_t> bil(static_cast<std::size_t>(tgt.width) * tgt.height * c, 77);
        std::vector<std::uint8_t> nea(bil.size(), 77);
        map.remapBilinear(src.data(), c, bil.data());
        map.remapNearest(src.data(), c, nea.data());
        int worst = 0;
        std::size_t exact = 0, n = 0, nearestWrong = 0, outsideNonZero = 0;
        for (int y = 0; y < tgt.height; ++y) {
          for (int x = 0; x < tgt.width; ++x) {
            hawor::Vec2<S> uvS;
            const bool in = map.sourcePixel(x, y, uvS);
            const hawor::Vec2<double> uv = uvS.template cast<double>();
            for (int k = 0; k < c; ++k) {
              const std::size_t o = (static_cast<std::size_t>(y) * tgt.width + x) * c + k;
              if (!in) {
                outsideNonZero += (bil[o] != 0) + (nea[o] != 0);
                continue;
              }
              const double ref = bilinear(src, W, H, c, k, uv(0), uv(1));
              const int d = std::abs(int(bil[o]) - int(std::lround(ref)));
              worst = std::max(worst, d);
              exact += d == 0;
              ++n;
              const int xn = std::min(int(std::floor(uv(0) + 0.5)), W - 1), yn = std::min(int(std::floor(uv(1) + 0.5)), H - 1);
              nearestWrong += nea[o] != src[(static_cast<std::size_t>(std::max(yn, 0)) * W + std::max(xn, 0)) * c + k];
            }
          }
        }
        CHECK(worst <= 1);
        CHECK(double(exact) >= 0.98 * double(n));
        CHECK(nearestWrong == 0);
        CHECK(outsideNonZero == 0);
      }
      // the image forms agree with the pointer forms
      hawor::ImageU8 img(W, H, 3);
      img.data = randomImage(W, H, 3, 99u);
      const hawor::ImageU8 r = map.remapBilinear(img);
      std::vector<std::uint8_t> ref(r.data.size());
      map.remapBilinear(img.data.data(), 3, ref.data());
      CHECK(r.data == ref);
      CHECK(r.width == tgt.width);
      CHECK(r.height == tgt.height);
    }
  }
}

TEMPLATE_TEST_CASE("RectifyMap: a pinhole lens onto its own intrinsics is an exact copy", "[rectify]", float, double) {
  using S = TestType;
  const CameraModel<S> cam = CameraModel<double>{intrinsics(100.0, 160, 120), Lens<double>::pinhole()}.template cast<S>();
  const RectifyMap<S> map(cam);
  CHECK(map.identity());
  CHECK(map.numOutside() == 0);
  CHECK(map.outsideMask().empty());
  for (int c : {1, 3, 4}) {
    const std::vector<std::uint8_t> src = randomImage(160, 120, c, 3u);
    std::vector<std::uint8_t> a(src.size()), b(src.size());
    map.remapBilinear(src.data(), c, a.data());
    map.remapNearest(src.data(), c, b.data());
    CHECK(a == src);
    CHECK(b == src);
  }
  const std::vector<std::uint8_t> hand = randomImage(160, 120, 1, 5u);
  std::vector<std::uint8_t> m(hand.size());
  CHECK(map.needsSlamMask(hand.data()));
  CHECK_FALSE(map.needsSlamMask(nullptr));
  map.slamMask(hand.data(), m.data());
  CHECK(m == hand);
  hawor::Vec2<S> uv;
  CHECK(map.sourcePixel(17, 33, uv));
  CHECK(uv(0) == S(17));
  CHECK(uv(1) == S(33));
  // a radial-tangential lens with zero coefficients is a pinhole too
  const CameraModel<S> zero{cam.intrinsics, Lens<S>::radTan(0, 0, 0, 0, 0)};
  CHECK(RectifyMap<S>(zero).identity());
  // a fisheye with k = 0 is the equidistant model, not a pinhole
  const CameraModel<S> equi{cam.intrinsics, Lens<S>::fisheye(0, 0, 0, 0)};
  CHECK_FALSE(RectifyMap<S>(equi).identity());
}

TEST_CASE("RectifyMap: the SLAM mask is the hand mask and the outside region grown by borderPx", "[rectify]") {
  const CameraModel<double> cam = cameras()[2];  // pincushion: an outside periphery
  for (int border : {0, 3, 6}) {
    const RectifyMap<double> map(cam, border);
    REQUIRE(map.anyOutside());
    const int w = map.width(), h = map.height();
    std::vector<std::uint8_t> hand(static_cast<std::size_t>(w) * h, 0);
    for (int y = 50; y < 70; ++y)
      for (int x = 60; x < 90; ++x) hand[static_cast<std::size_t>(y) * w + x] = 128;
    std::vector<std::uint8_t> out(hand.size()), noHand(hand.size());
    CHECK(map.needsSlamMask(nullptr));
    map.slamMask(hand.data(), out.data());
    map.slamMask(nullptr, noHand.data());
    std::size_t wrong = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        bool near = false;  // Chebyshev distance <= border to an outside pixel
        for (int dy = -border; dy <= border && !near; ++dy)
          for (int dx = -border; dx <= border && !near; ++dx) {
            const int xx = x + dx, yy = y + dy;
            near = xx >= 0 && yy >= 0 && xx < w && yy < h && map.outsideMask().at(xx, yy);
          }
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        wrong += noHand[i] != (near ? 255 : 0);
        wrong += out[i] != ((near || hand[i]) ? 255 : 0);
      }
    }
    CHECK(wrong == 0);
  }
  // without an outside region the hand mask passes through unchanged, and no hand means no mask
  const RectifyMap<double> fish(cameras()[0]);
  REQUIRE_FALSE(fish.anyOutside());
  CHECK_FALSE(fish.needsSlamMask(nullptr));
  const std::vector<std::uint8_t> hand = randomImage(160, 120, 1, 11u);
  std::vector<std::uint8_t> out(hand.size());
  fish.slamMask(hand.data(), out.data());
  CHECK(out == hand);
}

TEST_CASE("RectifyMap: a smooth pattern of ray directions through a fisheye, rectified, is the pinhole's view of it",
          "[rectify]") {
  // grey(ray) = 128 + 60·sin(3·d.x)·cos(2·d.y) + 40·sin(5·d.y + 1) on the unit ray d: rendered
  // through the fisheye (source pixel → bearing) and through the virtual pinhole (target pixel
  // → ray); the rectified fisheye image must match the pinhole one up to interpolation.
  const CameraModel<double> cam{intrinsics(313.69, 640, 480), Lens<double>::parse("fisheye:-0.0036,0.0368,-0.0343,0.0052")};
  auto pattern = [](const hawor::Vec3<double>& r) {
    const hawor::Vec3<double> d = r.normalized();
    return 128.0 + 60.0 * std::sin(3 * d(0)) * std::cos(2 * d(1)) + 40.0 * std::sin(5 * d(1) + 1);
  };
  const int W = 640, H = 480;
  std::vector<std::uint8_t> fish(static_cast<std::size_t>(W) * H);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      hawor::Vec3<double> b;
      REQUIRE(cam.bearing(hawor::Vec2<double>(x, y), b));
      fish[static_cast<std::size_t>(y) * W + x] = static_cast<std::uint8_t>(std::lround(pattern(b)));
    }
  const RectifyMap<double> map(cam);
  CHECK(map.numOutside() == 0);
  std::vector<std::uint8_t> rect(fish.size());
  map.remapBilinear(fish.data(), 1, rect.data());
  double sum = 0, worst = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double ref = pattern(cam.intrinsics.ray(hawor::Vec2<double>(x, y)));
      const double d = std::abs(ref - rect[static_cast<std::size_t>(y) * W + x]);
      sum += d;
      worst = std::max(worst, d);
    }
  CHECK(sum / (W * H) < 0.7);  // rounding (0.25) and interpolation of a smooth pattern
  CHECK(worst <= 2.5);
  // the wrong model (no rectification) differs visibly away from the centre
  double wrong = 0;
  for (std::size_t i = 0; i < fish.size(); ++i) {
    const int x = int(i % W), y = int(i / W);
    wrong += std::abs(pattern(cam.intrinsics.ray(hawor::Vec2<double>(x, y))) - fish[i]);
  }
  CHECK(wrong / (W * H) > 5.0);
}

TEST_CASE("RectifyMap: bad input", "[rectify]") {
  // a lens that folds inside the image: CameraModel::validate's message
  const CameraModel<double> folds{intrinsics(100.0, 640, 480), Lens<double>::radTan(-0.6, 0.05, 0, 0, 0)};
  CHECK_THROWS_WITH(RectifyMap<double>(folds), Catch::Contains("folds") || Catch::Contains("beyond what lens"));
  const CameraModel<double> cam = cameras()[0];
  CHECK_THROWS_WITH(RectifyMap<double>(cam, -1), Catch::Contains("borderPx"));
  PinholeCamera<double> bad = cam.intrinsics;
  bad.fx = std::nan("");
  CHECK_THROWS_WITH(RectifyMap<double>(cam, bad), Catch::Contains("focal"));
  const RectifyMap<double> map(cam);
  std::vector<std::uint8_t> a(160 * 120 * 5), b(a.size());
  CHECK_THROWS_WITH(map.remapBilinear(a.data(), 5, b.data()), Catch::Contains("channels"));
  CHECK_THROWS_WITH(map.remapNearest(hawor::ImageU8(100, 100, 1)), Catch::Contains("100x100"));
  hawor::Vec2<double> uv;
  CHECK_THROWS_WITH(map.sourcePixel(160, 0, uv), Catch::Contains("outside"));
}

TEMPLATE_TEST_CASE("LensCrop: rays, inverse, local scale and axes of a perspective crop through a lens", "[lens_crop]",
                   float, double) {
  using S = TestType;
  const double tol = std::is_same<S, float>::value ? 2e-3 : 1e-9;
  // A pinhole camera with the ROI at the principal point: exactly the affine crop.
  {
    PinholeCamera<double> k = intrinsics(400.0, 640, 480);
    k.fy = k.fx;
    const CameraModel<S> pin = CameraModel<double>{k, Lens<double>::pinhole()}.template cast<S>();
    const hawor::CropRoi<S> roi{S(k.cx), S(k.cy), S(120), S(90), S(0.4)};
    const hawor::LensCrop<S> crop(pin, roi);
    CHECK(std::abs(double(crop.focal()) - 400.0) < 400.0 * tol);
    for (double u : {-0.5, -0.2, 0.0, 0.3, 0.5})
      for (double v : {-0.5, 0.1, 0.5}) {
        hawor::Vec2<S> px;
        REQUIRE(crop.toImage(S(u), S(v), px));
        const double c = std::cos(0.4), s = std::sin(0.4);
        const double ex = k.cx + u * 120 * c - v * 90 * s, ey = k.cy + u * 120 * s + v * 90 * c;
        CHECK(std::abs(double(px(0)) - ex) < 1e3 * tol);
        CHECK(std::abs(double(px(1)) - ey) < 1e3 * tol);
      }
  }
  // Through the fisheye and the barrel lens, off-centre ROIs.
  for (const CameraModel<double>& camD : {cameras()[0], cameras()[1]}) {
    CameraModel<double> big = camD;
    big.intrinsics = big.intrinsics.scaled(4.0);  // 640 × 480
    const CameraModel<S> cam = big.template cast<S>();
    for (const hawor::CropRoi<double>& r : {hawor::CropRoi<double>{100, 80, 150, 150, 0.3},
                                            hawor::CropRoi<double>{560, 300, 90, 110, -2.0},
                                            hawor::CropRoi<double>{330, 250, 200, 200, 1.0}}) {
      INFO(big.lens.toString() << " roi " << r.cx << "," << r.cy);
      const hawor::CropRoi<S> roi{S(r.cx), S(r.cy), S(r.w), S(r.h), S(r.rotation)};
      const hawor::LensCrop<S> crop(cam, roi);
      // the centre maps to the ROI centre; the virtual axis is the centre's bearing
      hawor::Vec2<S> c0;
      REQUIRE(crop.toImage(S(0), S(0), c0));
      CHECK(std::abs(double(c0(0)) - r.cx) < 1e3 * tol);
      CHECK(std::abs(double(c0(1)) - r.cy) < 1e3 * tol);
      hawor::Vec3<double> b;
      REQUIRE(big.bearing(hawor::Vec2<double>(r.cx, r.cy), b));
      CHECK((crop.rotation().col(2).template cast<double>() - b).norm() < 10 * tol);
      CHECK((crop.rotation().transpose() * crop.rotation()).template cast<double>().isIdentity(10 * tol));
      // brute force: each crop pixel's ray (virtual pinhole) projected through the lens
      const int N = 16;
      std::vector<S> map(2 * N * N);
      crop.samplingMap(N, N, map.data());
      const double f = double(crop.focal()), cr = std::cos(r.rotation), sr = std::sin(r.rotation);
      const hawor::Mat3<double> R = crop.rotation().template cast<double>();
      for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) {
          const double u = (i + 0.5) / N - 0.5, v = (j + 0.5) / N - 0.5;
          const double a = u * r.w, bb = v * r.h;
          const hawor::Vec3<double> ray = R * hawor::Vec3<double>((a * cr - bb * sr) / f, (a * sr + bb * cr) / f, 1.0);
          const hawor::Vec2<double> ref = big.project(ray);
          const std::size_t o = 2 * (static_cast<std::size_t>(j) * N + i);
          CHECK(std::abs(double(map[o]) - ref(0)) < 1e3 * tol);
          CHECK(std::abs(double(map[o + 1]) - ref(1)) < 1e3 * tol);
          // and back
          hawor::Vec2<S> uv;
          REQUIRE(crop.toCrop(hawor::Vec2<S>(map[o], map[o + 1]), uv));
          CHECK(std::abs(double(uv(0)) - u) < 100 * tol);
          CHECK(std::abs(double(uv(1)) - v) < 100 * tol);
        }
      // local scale: d(pixel)/d(u·w, v·h) at the centre has determinant 1 (the image's pixel
      // density) and, for a radially symmetric lens, no rotation part (the ROI's axes carry over)
      if (std::is_same<S, double>::value) {
        const double e = 1e-6;
        hawor::Vec2<S> pu, mu, pv, mv;
        REQUIRE(crop.toImage(S(e / r.w), S(0), pu));
        REQUIRE(crop.toImage(S(-e / r.w), S(0), mu));
        REQUIRE(crop.toImage(S(0), S(e / r.h), pv));
        REQUIRE(crop.toImage(S(0), S(-e / r.h), mv));
        Eigen::Matrix2d J;
        J.col(0) = (pu - mu).template cast<double>() / (2 * e);
        J.col(1) = (pv - mv).template cast<double>() / (2 * e);
        // undo the ROI rotation: J·Rot(r)ᵀ is the map from the virtual image plane's axes
        Eigen::Matrix2d Rr;
        Rr << cr, -sr, sr, cr;
        const Eigen::Matrix2d A = J * Rr.transpose();
        CHECK(std::abs(A.determinant() - 1.0) < 0.02);  // fy = 1.01 fx: √det is the geometric mean
        CHECK(std::abs(A(0, 1) - A(1, 0)) < 0.02 * A.norm());
      }
    }
  }
  // bad input
  const CameraModel<S> cam = cameras()[0].template cast<S>();
  CHECK_THROWS_WITH((hawor::LensCrop<S>(cam, hawor::CropRoi<S>{S(10), S(10), S(0), S(5), S(0)})), Catch::Contains("w, h > 0"));
  CHECK_THROWS_WITH((hawor::LensCrop<S>(cam, hawor::CropRoi<S>{S(1e7), S(10), S(5), S(5), S(0)})), Catch::Contains("beyond"));
}

TEMPLATE_TEST_CASE("CameraModel::fromFov: the diagonal field of view through the lens", "[rectify]", float, double) {
  using S = TestType;
  const double tol = std::is_same<S, float>::value ? 1e-4 : 1e-10;
  for (const char* spec : {"fisheye:-0.0036,0.0368,-0.0343,0.0052", "opencv:-0.16,0.02,0.0004,-0.0003,-0.001", "pinhole"}) {
    const Lens<S> lens = Lens<S>::parse(spec);
    for (double fov : {60.0, 100.0, 125.0}) {
      INFO(spec << " fov " << fov);
      const CameraModel<S> c = CameraModel<S>::fromFov(640, 480, lens, S(fov));
      CHECK(c.intrinsics.fx == c.intrinsics.fy);
      CHECK(c.intrinsics.cx == S(319.5));
      CHECK(c.intrinsics.cy == S(239.5));
      // the bottom-right corner (the diagonal's direction) is at half the field from the axis;
      // every corner is for a radially symmetric lens (the principal point is the centre)
      hawor::Vec3<S> b;
      REQUIRE(c.bearing(hawor::Vec2<S>(S(639.5), S(479.5)), b));
      const double a = std::atan2(std::hypot(double(b(0)), double(b(1))), double(b(2))) * 360 / kPi;
      // (tangential terms move the projected diagonal point off the diagonal: a small fraction of a degree)
      CHECK(std::abs(a - fov) < (c.lens.kind == hawor::LensKind::RadTan ? 0.01 : 1e3 * tol * fov));
      if (c.lens.kind != hawor::LensKind::RadTan) CHECK(std::abs(2 * double(c.maxFieldAngle()) * 180 / kPi - fov) < 1e3 * tol * fov);
    }
  }
  // the Aria-like capture profile of hawor synth: 150 degrees at 640 × 480 gives f = 313.6876...
  const CameraModel<S> aria = CameraModel<S>::fromFov(640, 480, Lens<S>::parse("fisheye:-0.0036,0.0368,-0.0343,0.0052"), S(150));
  CHECK(std::abs(double(aria.intrinsics.fx) - 313.6876484765642) < 1e4 * tol);
  CHECK(CameraModel<S>::fromFov(640, 480, Lens<S>::pinhole(), S(90)).intrinsics.fx == PinholeCamera<S>::fromFov(640, 480, S(90)).fx);
  CHECK_THROWS_WITH(CameraModel<S>::fromFov(640, 480, Lens<S>::pinhole(), S(200)), Catch::Contains("field of view"));
  CHECK_THROWS_WITH(CameraModel<S>::fromFov(640, 480, Lens<S>::radTan(S(-0.6), S(0.05), 0, 0, 0), S(120)), Catch::Contains("folds"));
}

TEMPLATE_TEST_CASE("rectifiedLetterboxMap and virtualToSource: the rectified frame's letterbox through the lens", "[lens_crop]",
                   float, double) {
  using S = TestType;
  const double tol = std::is_same<S, float>::value ? 2e-2 : 1e-9;
  for (const CameraModel<double>& camD : cameras()) {
    const CameraModel<S> cam = camD.template cast<S>();
    const RectifyMap<S> rect(cam);
    const int N = 48;
    std::vector<S> map(2 * N * N);
    hawor::rectifiedLetterboxMap(cam, N, N, map.data());
    const double side = 160, cx = 79.5, cy = 59.5;  // the 160 × 120 cameras' letterbox
    std::size_t inside = 0;
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i) {
        const double x = cx + side * ((i + 0.5) / N - 0.5), y = cy + side * ((j + 0.5) / N - 0.5);
        const hawor::Vec3<double> ray((x - camD.intrinsics.cx) / camD.intrinsics.fx, (y - camD.intrinsics.cy) / camD.intrinsics.fy, 1.0);
        const std::size_t o = 2 * (static_cast<std::size_t>(j) * N + i);
        INFO(camD.lens.toString() << " (" << i << ", " << j << ")");
        if (!camD.lens.inDomain(ray)) {
          CHECK(std::isnan(double(map[o])));
          continue;
        }
        const hawor::Vec2<double> ref = camD.project(ray);
        CHECK(std::abs(double(map[o]) - ref(0)) < tol * std::max(1.0, std::abs(ref(0))));
        CHECK(std::abs(double(map[o + 1]) - ref(1)) < tol * std::max(1.0, std::abs(ref(1))));
        // inside the rectified frame it is the rectifier's own source position
        const int xi = int(std::lround(x)), yi = int(std::lround(y));
        if (std::abs(x - xi) < 1e-9 && std::abs(y - yi) < 1e-9 && xi >= 0 && yi >= 0 && xi < 160 && yi < 120) {
          hawor::Vec2<S> uv;
          if (rect.sourcePixel(xi, yi, uv)) {
            ++inside;
            CHECK((uv.template cast<double>() - ref).norm() < 1e3 * tol);
          }
        }
        hawor::Vec2<S> px;
        REQUIRE(hawor::virtualToSource(cam, hawor::Vec2<S>(S(x), S(y)), px));
        CHECK((px.template cast<double>() - ref).norm() < 1e3 * tol);
      }
    (void)inside;
  }
  std::vector<float> m(8);
  CHECK_THROWS_WITH(hawor::rectifiedLetterboxMap(cameras()[0], 0, 2, m.data()), Catch::Contains("positive"));
}
