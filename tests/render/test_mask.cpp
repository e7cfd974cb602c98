// Hand-mask properties: closed-mesh silhouettes against brute-force ray casting (float and
// double), multi-mesh union and labels, disc dilation and the resize rules against brute force.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "hawor/render/mask.hpp"
#include "render_test_util.hpp"

template struct hawor::MaskMesh<float>;
template struct hawor::MaskMesh<double>;
template float hawor::maskCoverage<float>(const hawor::Mask&);
template double hawor::maskCoverage<double>(const hawor::Mask&);

namespace {

using hawor::Mask;
using hawor::PinholeCamera;
using hawor::Points3;
using hawor::TriangleList;

template <typename S>
PinholeCamera<S> maskCamera() {
  PinholeCamera<S> c;
  c.fx = S(70);
  c.fy = S(72);
  c.cx = S(39.3);
  c.cy = S(29.6);
  c.width = 80;
  c.height = 60;
  return c;
}

/// Compares a mask with brute-force ray casting over every pixel centre; pixels within 0.01 px
/// of a silhouette edge (exact-edge ties) are not judged. Returns the number of mismatches.
template <typename S>
int compareWithRays(const PinholeCamera<S>& cam, const Points3<double>& V, const TriangleList& F,
                    const Mask& m, double zNear, int* hits = nullptr, int* undecided = nullptr) {
  // Pixels outside the projected bounding box of the part in front of the camera cannot be hit;
  // for a mesh crossing the near plane every pixel is tested.
  bool allFront = true;
  double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    allFront = allFront && V(i, 2) > zNear;
    const double u = double(cam.fx) * V(i, 0) / V(i, 2) + double(cam.cx);
    const double v = double(cam.fy) * V(i, 1) / V(i, 2) + double(cam.cy);
    u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
  }
  int bad = 0;
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const bool set = m.at(x, y) != 0;
      if (allFront && (x < u0 - 1 || x > u1 + 1 || y < v0 - 1 || y > v1 + 1)) {
        bad += set;
        continue;
      }
      const int c = render_test::classify(cam, V, F, x, y, zNear);
      if (c >= 0) bad += set != (c == 1);
      if (hits) *hits += c == 1;
      if (undecided) *undecided += c < 0;
    }
  }
  return bad;
}

}  // namespace

TEMPLATE_TEST_CASE("mask: closed mesh silhouette equals brute-force ray casting", "[render][mask]",
                   float, double) {
  using S = TestType;
  const auto cam = maskCamera<S>();
  Points3<double> unit;
  TriangleList F;
  render_test::icosphere(3, unit, F);
  REQUIRE(unit.rows() == 642);
  REQUIRE(F.rows() == 1280);

  struct Case {
    Eigen::Vector3d centre, stretch;
    double radius, bump, zNear;
  };
  const Case cases[] = {
      {{0.05, -0.03, 1.2}, {1.0, 1.4, 0.8}, 0.3, 0.15, 1e-3},  // inside the image
      {{0.6, 0.35, 1.0}, {1.0, 1.0, 1.0}, 0.35, 0.1, 1e-3},    // cut by the image border
      {{0.35, 0.0, 0.25}, {1.0, 1.0, 1.0}, 0.3, 0.05, 0.1},    // crosses z = near, partly behind
  };
  for (const Case& c : cases) {
    const Points3<double> V = render_test::deform(unit, c.radius, c.stretch, c.centre, c.bump);
    hawor::RasterOptions<S> opt;
    opt.nearPlane = S(c.zNear);
    Mask m;
    hawor::renderMask(V.cast<S>(), F, cam, m, 255, opt);
    REQUIRE(m.width == cam.width);
    REQUIRE(m.height == cam.height);
    int hits = 0, undecided = 0;
    CHECK(compareWithRays(cam, V, F, m, c.zNear, &hits, &undecided) == 0);
    CHECK(hits > 300);
    CHECK(undecided < hits / 10);
    for (const auto v : m.data) REQUIRE((v == 0 || v == 255));
    // For a closed mesh back faces add nothing to the silhouette, and neither do front faces.
    for (const auto mode : {hawor::CullMode::Back, hawor::CullMode::Front}) {
      opt.cull = mode;
      Mask mc;
      hawor::renderMask(V.cast<S>(), F, cam, mc, 255, opt);
      CHECK(mc.data == m.data);
    }
  }
}

TEMPLATE_TEST_CASE("mask: a convex closed mesh is covered once by front and once by back faces",
                   "[render][mask]", float, double) {
  using S = TestType;
  const auto cam = maskCamera<S>();
  Points3<double> unit;
  TriangleList F;
  render_test::icosphere(3, unit, F);
  const Points3<S> V =
      render_test::deform(unit, 0.4, Eigen::Vector3d(1.2, 1, 1), Eigen::Vector3d(0.1, 0.05, 1.3), 0)
          .cast<S>();
  for (const auto mode : {hawor::CullMode::None, hawor::CullMode::Back, hawor::CullMode::Front}) {
    hawor::RasterOptions<S> opt;
    opt.cull = mode;
    hawor::Rasterizer<S> r(cam, opt);
    hawor::Image<int> n(cam.width, cam.height, 1, 0);
    r.drawMesh(V, F, [&](const hawor::Fragment<S>& f) { ++n.at(f.x, f.y); });
    const int expected = mode == hawor::CullMode::None ? 2 : 1;
    int bad = 0, covered = 0;
    for (const int k : n.data) {
      bad += k != 0 && k != expected;
      covered += k != 0;
    }
    CHECK(bad == 0);
    CHECK(covered > 500);
  }
}

TEMPLATE_TEST_CASE("mask: several meshes (both hands) into one mask", "[render][mask]", float,
                   double) {
  using S = TestType;
  const auto cam = maskCamera<S>();
  Points3<double> unit;
  TriangleList F;
  render_test::icosphere(2, unit, F);
  const Points3<double> A =
      render_test::deform(unit, 0.25, Eigen::Vector3d(1, 1.3, 1), Eigen::Vector3d(-0.12, 0, 1.0), 0.1);
  const Points3<double> B =
      render_test::deform(unit, 0.3, Eigen::Vector3d(1.2, 1, 1), Eigen::Vector3d(0.15, 0.05, 1.3), 0.1);
  const Points3<S> As = A.cast<S>(), Bs = B.cast<S>();

  // Union: equals the OR of the single masks, and does not depend on the order.
  Mask ma, mb, uni, uni2;
  hawor::renderMask(As, F, cam, ma);
  hawor::renderMask(Bs, F, cam, mb);
  hawor::renderMask<S>({{&As, &F, 255}, {&Bs, &F, 255}}, cam, uni);
  hawor::renderMask<S>({{&Bs, &F, 255}, {&As, &F, 255}}, cam, uni2);
  int bad = 0, overlap = 0;
  for (std::size_t i = 0; i < uni.data.size(); ++i) {
    bad += uni.data[i] != ((ma.data[i] | mb.data[i]) ? 255 : 0);
    overlap += ma.data[i] && mb.data[i];
  }
  CHECK(bad == 0);
  CHECK(overlap > 50);
  CHECK(uni2.data == uni.data);
  // drawMask accumulates in the same way.
  Mask acc(cam.width, cam.height, 1, 0);
  hawor::drawMask(As, F, cam, acc);
  hawor::drawMask(Bs, F, cam, acc);
  CHECK(acc.data == uni.data);

  // Labels: the nearest surface's value wins, whatever the order.
  for (int order = 0; order < 2; ++order) {
    Mask lab;
    if (order == 0) {
      hawor::renderMask<S>({{&As, &F, 1}, {&Bs, &F, 2}}, cam, lab);
    } else {
      hawor::renderMask<S>({{&Bs, &F, 2}, {&As, &F, 1}}, cam, lab);
    }
    int wrong = 0, both = 0;
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        const int ca = render_test::classify(cam, A, F, x, y, 1e-3);
        const int cb = render_test::classify(cam, B, F, x, y, 1e-3);
        if (ca < 0 || cb < 0) continue;
        int expected = ca ? 1 : cb ? 2 : 0;
        if (ca && cb) {
          ++both;
          const double za = render_test::nearestHit(cam, A, F, x, y, 1e-3);
          const double zb = render_test::nearestHit(cam, B, F, x, y, 1e-3);
          if (std::abs(za - zb) < 1e-3) continue;
          expected = za < zb ? 1 : 2;
        }
        wrong += lab.at(x, y) != expected;
      }
    }
    CHECK(wrong == 0);
    CHECK(both > 50);
  }

  CHECK_THROWS_AS(hawor::renderMask<S>({{nullptr, &F, 1}}, cam, uni), hawor::Error);
  Mask small(cam.width - 1, cam.height, 1, 0);
  CHECK_THROWS_AS(hawor::drawMask(As, F, cam, small), hawor::Error);
  Mask rgb(cam.width, cam.height, 3, 0);
  CHECK_THROWS_AS(hawor::drawMask(As, F, cam, rgb), hawor::Error);
  TriangleList badF = F;
  badF(3, 1) = static_cast<int>(A.rows());
  CHECK_THROWS_AS(hawor::renderMask(As, badF, cam, ma), hawor::Error);
}

TEST_CASE("mask: disc dilation equals brute force", "[render][mask]") {
  std::mt19937 rng(1);
  const int sizes[][2] = {{1, 1}, {1, 9}, {13, 1}, {17, 11}, {40, 23}, {97, 7}};
  for (const auto& sz : sizes) {
    for (const double density : {0.002, 0.03, 0.3}) {
      std::bernoulli_distribution on(density);
      Mask in(sz[0], sz[1], 1, 0);
      for (auto& v : in.data) v = on(rng) ? static_cast<unsigned char>(1 + rng() % 255) : 0;
      if (sz[0] * sz[1] > 100) in.at(0, 0) = 9;  // a set pixel on the border
      for (const int r : {0, 1, 2, 3, 4, 7, 30}) {
        Mask out;
        hawor::dilateMask(in, r, out, 200);
        REQUIRE(out.width == in.width);
        REQUIRE(out.height == in.height);
        int bad = 0;
        for (int y = 0; y < in.height; ++y) {
          for (int x = 0; x < in.width; ++x) {
            bool any = false;
            for (int qy = 0; qy < in.height && !any; ++qy) {
              for (int qx = 0; qx < in.width && !any; ++qx) {
                any = in.at(qx, qy) && (qx - x) * (qx - x) + (qy - y) * (qy - y) <= r * r;
              }
            }
            bad += out.at(x, y) != (any ? 200 : 0);
          }
        }
        CHECK(bad == 0);
        Mask same = in;
        hawor::dilateMask(same, r, same, 200);  // in place
        CHECK(same.data == out.data);
      }
    }
  }
  // The disc, not the square: one pixel, radius 3 → 29 pixels (|dx|² + |dy|² ≤ 9).
  Mask dot(9, 9, 1, 0);
  dot.at(4, 4) = 1;
  Mask d;
  hawor::dilateMask(dot, 3, d);
  CHECK(hawor::maskCoverage(d) * 81 == Approx(29));
  CHECK(d.at(1, 4) == 255);
  CHECK(d.at(2, 2) == 255);
  CHECK(d.at(1, 2) == 0);
  CHECK_THROWS_AS(hawor::dilateMask(dot, -1, d), hawor::Error);
}

TEST_CASE("mask: resize rules (nearest, area ≥ 0.5) equal brute force", "[render][mask]") {
  std::mt19937 rng(2);
  std::bernoulli_distribution on(0.45);
  const int shapes[][4] = {{8, 6, 4, 3},   {13, 7, 5, 4},  {7, 5, 13, 9},
                           {10, 10, 10, 10}, {16, 9, 3, 2}, {5, 8, 12, 3}};
  const int shapes2[][4] = {{70, 40, 33, 17}, {41, 37, 90, 50}};  // wider than a 32-px block
  std::vector<std::array<int, 4>> all;
  for (const auto& s : shapes) all.push_back({s[0], s[1], s[2], s[3]});
  for (const auto& s : shapes2) all.push_back({s[0], s[1], s[2], s[3]});
  for (const auto& s : all) {
    const int W = s[0], H = s[1], w = s[2], h = s[3];
    for (int rep = 0; rep < 8; ++rep) {
      Mask in(W, H, 1, 0);
      if (rep < 5) {
        for (auto& v : in.data) v = on(rng) ? static_cast<unsigned char>(1 + rng() % 3) : 0;
      } else if (rep == 5) {
        in.at(W - 1, H / 2) = 1;  // one pixel at the right border: sparse-row shortcuts
      } else if (rep == 6) {
        for (int x = W / 3; x < W / 2 + 1; ++x) in.at(x, H - 1) = 7;  // one run on the last row
      }  // rep 7: empty
      Mask nn, area;
      hawor::resizeMask(in, w, h, nn, hawor::MaskResize::Nearest);
      hawor::resizeMask(in, w, h, area, hawor::MaskResize::Area, 255);
      int bad = 0;
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          // Nearest: the source pixel containing the output pixel's centre.
          const int sx = static_cast<int>(std::floor((x + 0.5) * W / w));
          const int sy = static_cast<int>(std::floor((y + 0.5) * H / h));
          bad += nn.at(x, y) != in.at(sx, sy);
          // Area: count set cells of the (W·w) × (H·h) common refinement in the footprint.
          long covered = 0;
          for (int fy = y * H; fy < (y + 1) * H; ++fy) {
            for (int fx = x * W; fx < (x + 1) * W; ++fx) covered += in.at(fx / w, fy / h) != 0;
          }
          bad += area.at(x, y) != (2 * covered >= long(W) * H ? 255 : 0);
        }
      }
      CHECK(bad == 0);
      Mask same = in;
      hawor::resizeMask(same, w, h, same, hawor::MaskResize::Area, 255);  // in place
      CHECK(same.data == area.data);
    }
  }
  // 4×4 → 2×2: a 2×2 block with 1, 2, 3, 4 set pixels → 0, set (exactly half), set, set.
  Mask in(4, 4, 1, 0);
  in.at(0, 0) = 1;
  in.at(2, 0) = in.at(3, 1) = 1;
  in.at(0, 2) = in.at(1, 2) = in.at(0, 3) = 1;
  in.at(2, 2) = in.at(3, 2) = in.at(2, 3) = in.at(3, 3) = 1;
  Mask out;
  hawor::resizeMask(in, 2, 2, out);
  CHECK(out.at(0, 0) == 0);
  CHECK(out.at(1, 0) == 255);
  CHECK(out.at(0, 1) == 255);
  CHECK(out.at(1, 1) == 255);
  CHECK_THROWS_AS(hawor::resizeMask(in, 0, 2, out), hawor::Error);
  CHECK_THROWS_AS(hawor::resizeMask(Mask(), 2, 2, out), hawor::Error);
}

TEST_CASE("mask: coverage fraction", "[render][mask]") {
  Mask m(10, 5, 1, 0);
  for (int i = 0; i < 7; ++i) m.data[i * 3] = static_cast<unsigned char>(i + 1);
  CHECK(hawor::maskCoverage(m) == Approx(7.0 / 50));
  CHECK(hawor::maskCoverage<float>(m) == Approx(7.0 / 50));
  CHECK_THROWS_AS(hawor::maskCoverage(Mask()), hawor::Error);
  Mask broken(10, 5, 1, 0);
  broken.data.pop_back();
  CHECK_THROWS_AS(hawor::maskCoverage(broken), hawor::Error);
}
