// Rasteriser properties (float and double): fill rule, watertightness, z-buffer, near-plane
// clipping, perspective-correct barycentrics, degenerate input.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <type_traits>
#include <vector>

#include "hawor/render/image.hpp"
#include "hawor/render/rasterizer.hpp"
#include "render_test_util.hpp"

template struct hawor::Image<unsigned char>;
template struct hawor::Image<float>;
template struct hawor::Image<int>;
template class hawor::Rasterizer<float>;
template class hawor::Rasterizer<double>;
template struct hawor::Fragment<float>;
template struct hawor::Fragment<double>;
template struct hawor::RasterOptions<float>;
template struct hawor::RasterOptions<double>;

namespace {

using hawor::Fragment;
using hawor::Image;
using hawor::PinholeCamera;
using hawor::Points3;
using hawor::Rasterizer;
using hawor::TriangleList;
using hawor::Vec3;

template <typename S>
PinholeCamera<S> smallCamera(int w = 64, int h = 48, S f = S(50)) {
  PinholeCamera<S> c;
  c.fx = f;
  c.fy = f * S(1.1);
  c.cx = S(w - 1) / 2 + S(0.25);
  c.cy = S(h - 1) / 2 - S(0.3);
  c.width = w;
  c.height = h;
  return c;
}

/// Camera-frame point that projects to pixel (u, v) at depth z.
template <typename S>
Vec3<S> at(const PinholeCamera<S>& c, double u, double v, double z) {
  return Vec3<S>(S((u - double(c.cx)) / double(c.fx) * z), S((v - double(c.cy)) / double(c.fy) * z),
                 S(z));
}

/// Per-pixel count of fragments.
template <typename S>
struct Counter {
  Image<int>* img;
  void operator()(const Fragment<S>& f) const { ++img->at(f.x, f.y); }
};

template <typename S>
Image<int> countMesh(const PinholeCamera<S>& cam, const Points3<S>& V, const TriangleList& F,
                     const hawor::RasterOptions<S>& opt = {}) {
  Image<int> img(cam.width, cam.height, 1, 0);
  Rasterizer<S> r(cam, opt);
  r.drawMesh(V, F, Counter<S>{&img});
  return img;
}

/// A rectangle [u0,u1]×[v0,v1] (pixels) as an irregular triangulated grid: interior vertices
/// jittered (some snapped onto pixel centres to force exact ties), random diagonals, random
/// vertex order (winding) per triangle, random depth per vertex. Displacements stay below a
/// quarter cell (jitter 0.15 cell + snap ≤ 0.125 px on ≥ 2 px cells), so every quad stays
/// convex and the triangles tile the rectangle without folds.
template <typename S>
void randomGrid(const PinholeCamera<S>& cam, double u0, double u1, double v0, double v1, int nx,
                int ny, std::mt19937& rng, Points3<S>& V, TriangleList& F) {
  std::uniform_real_distribution<double> jit(-0.15, 0.15), depth(0.5, 3.0), coin(0, 1);
  V.resize((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      double u = u0 + (u1 - u0) * i / nx, v = v0 + (v1 - v0) * j / ny;
      const double cu = (u1 - u0) / nx, cv = (v1 - v0) / ny;
      if (i > 0 && i < nx) u += jit(rng) * cu;
      if (j > 0 && j < ny) v += jit(rng) * cv;
      if (coin(rng) < 0.3) {  // onto a pixel centre or a quarter position, keeping boundaries
        if (i > 0 && i < nx) u = std::round(u * 4) / 4;
        if (j > 0 && j < ny) v = std::round(v * 4) / 4;
      }
      V.row(j * (nx + 1) + i) = at(cam, u, v, depth(rng)).transpose();
    }
  }
  F.resize(2 * nx * ny, 3);
  int f = 0;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      int t[2][3];
      if (coin(rng) < 0.5) {
        t[0][0] = a, t[0][1] = b, t[0][2] = d, t[1][0] = a, t[1][1] = d, t[1][2] = c;
      } else {
        t[0][0] = a, t[0][1] = b, t[0][2] = c, t[1][0] = b, t[1][1] = d, t[1][2] = c;
      }
      for (auto& tri : t) {
        if (coin(rng) < 0.5) std::swap(tri[1], tri[2]);
        F.row(f++) << tri[0], tri[1], tri[2];
      }
    }
  }
}

template <typename S>
double bTol() {
  return std::is_same<S, float>::value ? 2e-3 : 1e-8;
}

}  // namespace

TEMPLATE_TEST_CASE("image: layout, resize, bad sizes", "[render][image]", float, double) {
  Image<TestType> img(3, 2, 2, TestType(7));
  REQUIRE(img.data.size() == 12u);
  img.at(2, 1, 1) = TestType(5);
  CHECK(img.data[(1 * 3 + 2) * 2 + 1] == TestType(5));
  CHECK(img.row(1)[2 * 2 + 1] == TestType(5));
  CHECK(img.consistent());
  CHECK(img.contains(2, 1));
  CHECK_FALSE(img.contains(3, 1));
  img.fill(TestType(1));
  CHECK(img.at(0, 0, 0) == TestType(1));
  img.resize(0, 0);
  CHECK(img.empty());
  CHECK_THROWS_AS(img.resize(-1, 2), hawor::Error);
  CHECK_THROWS_AS(img.resize(2, 2, 0), hawor::Error);
  CHECK_THROWS_AS(Image<TestType>(1 << 20, 1 << 20, 1), hawor::Error);
}

TEMPLATE_TEST_CASE("raster: a square of two triangles covers exactly its top-left-rule pixels",
                   "[render][raster]", float, double) {
  using S = TestType;
  const auto cam = smallCamera<S>();
  // Corners on pixel centres (ties on all four sides) and at fractional positions.
  const double boxes[3][4] = {{4, 20, 6, 18}, {3.5, 11.25, 2.75, 9.5}, {-3, 5, 40, 52}};
  for (const auto& b : boxes) {
    for (int diag = 0; diag < 2; ++diag) {
      for (int wind = 0; wind < 2; ++wind) {
        const double z = 1.5 + diag;  // the depth does not change the projection
        Points3<S> V(4, 3);
        V.row(0) = at(cam, b[0], b[2], z).transpose();
        V.row(1) = at(cam, b[1], b[2], z).transpose();
        V.row(2) = at(cam, b[1], b[3], z).transpose();
        V.row(3) = at(cam, b[0], b[3], z).transpose();
        TriangleList F(2, 3);
        if (diag == 0) {
          F << 0, 1, 2, 0, 2, 3;
        } else {
          F << 0, 1, 3, 1, 2, 3;
        }
        if (wind) F.col(1).swap(F.col(2));
        const Image<int> n = countMesh(cam, V, F);
        int bad = 0;
        for (int y = 0; y < cam.height; ++y) {
          for (int x = 0; x < cam.width; ++x) {
            // Pixel centre inside [u0, u1) × [v0, v1): left and top edges included.
            const int expected = (x >= b[0] && x < b[1] && y >= b[2] && y < b[3]) ? 1 : 0;
            bad += n.at(x, y) != expected;
          }
        }
        CHECK(bad == 0);
      }
    }
  }
}

TEMPLATE_TEST_CASE("raster: a dense random triangulation covers every pixel exactly once",
                   "[render][raster]", float, double) {
  using S = TestType;
  const auto cam = smallCamera<S>();
  std::mt19937 rng(7);
  // Inside the image with integer boundaries, and overlapping the image borders.
  // {u0, u1, v0, v1, nx, ny}: cells of at least 2 px.
  const double rects[3][6] = {
      {2, 60, 3, 40, 23, 17}, {-5.5, 70.25, -3.75, 52.5, 23, 17}, {10.5, 30.5, 0, 47, 8, 17}};
  for (const auto& rc : rects) {
    for (int rep = 0; rep < 4; ++rep) {
      Points3<S> V;
      TriangleList F;
      randomGrid(cam, rc[0], rc[1], rc[2], rc[3], int(rc[4]), int(rc[5]), rng, V, F);
      const Image<int> n = countMesh(cam, V, F);
      // The span interface (masks) covers exactly the same pixels.
      Image<int> spans(cam.width, cam.height, 1, 0);
      Rasterizer<S> r(cam);
      r.drawMeshSpans(V, F, [&spans](int y, int x0, int x1) {
        for (int x = x0; x < x1; ++x) ++spans.at(x, y);
      });
      CHECK(spans.data == n.data);
      int bad = 0, covered = 0;
      for (int y = 0; y < cam.height; ++y) {
        for (int x = 0; x < cam.width; ++x) {
          const int expected = (x >= rc[0] && x < rc[1] && y >= rc[2] && y < rc[3]) ? 1 : 0;
          bad += n.at(x, y) != expected;
          covered += n.at(x, y);
        }
      }
      CHECK(bad == 0);
      CHECK(covered > 0);
    }
  }
}

TEMPLATE_TEST_CASE("raster: the z-buffer keeps the nearest surface", "[render][raster]", float,
                   double) {
  using S = TestType;
  const auto cam = smallCamera<S>();
  // Two planes that interpenetrate: depth along the image x axis rises for one, falls for
  // the other, so the nearest changes in the middle of the overlap.
  auto plane = [&](double zl, double zr, Points3<S>& V, TriangleList& F) {
    V.resize(4, 3);
    V.row(0) = at(cam, -10, -10, zl).transpose();
    V.row(1) = at(cam, 80, -10, zr).transpose();
    V.row(2) = at(cam, 80, 60, zr).transpose();
    V.row(3) = at(cam, -10, 60, zl).transpose();
    F.resize(2, 3);
    F << 0, 1, 2, 0, 2, 3;
  };
  Points3<S> A, B;
  TriangleList FA, FB;
  plane(1.0, 3.0, A, FA);
  plane(2.5, 1.2, B, FB);
  for (int order = 0; order < 2; ++order) {
    Rasterizer<S> r(cam);
    Image<float> depth;
    r.clearDepth(depth);
    r.setDepthBuffer(&depth);
    Image<int> id(cam.width, cam.height, 1, -1);
    for (int k = 0; k < 2; ++k) {
      const bool first = (k == 0) == (order == 0);
      const int label = first ? 0 : 1;
      r.drawMesh(first ? A : B, first ? FA : FB,
                 [&](const Fragment<S>& f) { id.at(f.x, f.y) = label; });
    }
    int bad = 0;
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        const double za = render_test::nearestHit(cam, A.template cast<double>(), FA, x, y, 1e-3);
        const double zb = render_test::nearestHit(cam, B.template cast<double>(), FB, x, y, 1e-3);
        const double zmin = std::min(za, zb);
        bad += std::abs(depth.at(x, y) - zmin) > 1e-4 * zmin;
        if (std::abs(za - zb) > 1e-3) bad += id.at(x, y) != (za < zb ? 0 : 1);
      }
    }
    CHECK(bad == 0);
  }
}

TEMPLATE_TEST_CASE("raster: perspective-correct barycentrics match ray–plane intersection",
                   "[render][raster]", float, double) {
  using S = TestType;
  const auto cam = smallCamera<S>();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uu(-20, 84), vv(-15, 63), zz(0.3, 6.0);
  int fragments = 0;
  double worstB = 0, worstZ = 0;
  for (int rep = 0; rep < 40; ++rep) {
    const Vec3<S> p[3] = {at(cam, uu(rng), vv(rng), zz(rng)), at(cam, uu(rng), vv(rng), zz(rng)),
                          at(cam, uu(rng), vv(rng), zz(rng))};
    const Eigen::Vector3d a = p[0].template cast<double>(), b = p[1].template cast<double>(),
                          c = p[2].template cast<double>();
    Rasterizer<S> r(cam);
    r.drawTriangle(p[0], p[1], p[2], [&](const Fragment<S>& f) {
      double t = 0, u = 0, v = 0;
      REQUIRE(render_test::rayPlane(render_test::pixelRay(cam, f.x, f.y), a, b, c, t, u, v));
      const Vec3<S> bary = f.barycentric();
      worstB = std::max({worstB, std::abs(bary(0) - (1 - u - v)), std::abs(bary(1) - u),
                         std::abs(bary(2) - v)});
      worstZ = std::max(worstZ, std::abs(double(f.depth()) - t) / t);
      ++fragments;
    }, rep);
  }
  CHECK(fragments > 1000);
  CHECK(worstB <= bTol<S>());
  CHECK(worstZ <= bTol<S>());
}

TEMPLATE_TEST_CASE("raster: triangles crossing the near plane are clipped, not dropped",
                   "[render][raster]", float, double) {
  using S = TestType;
  const auto cam = smallCamera<S>();
  const double zNear = 0.2;
  hawor::RasterOptions<S> opt;
  opt.nearPlane = S(zNear);

  SECTION("single triangles with one or two vertices behind the camera") {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> xy(-1.5, 1.5), zf(0.25, 3.0), zb(-2.0, 0.15);
    int checked = 0;
    for (int rep = 0; rep < 30; ++rep) {
      const int behind = 1 + rep % 2;
      Points3<double> V(3, 3);
      for (int k = 0; k < 3; ++k) V.row(k) << xy(rng), xy(rng), k < behind ? zb(rng) : zf(rng);
      TriangleList F(1, 3);
      F << 0, 1, 2;
      const Points3<S> Vs = V.cast<S>();
      Image<int> n(cam.width, cam.height, 1, 0);
      Rasterizer<S> r(cam, opt);
      double worstZ = 0, minDepth = INFINITY;
      r.drawMesh(Vs, F, [&](const Fragment<S>& f) {
        ++n.at(f.x, f.y);
        double t = 0, u = 0, v = 0;
        render_test::rayPlane(render_test::pixelRay(cam, f.x, f.y), V.row(0).transpose(),
                              V.row(1).transpose(), V.row(2).transpose(), t, u, v);
        worstZ = std::max(worstZ, std::abs(double(f.depth()) - t) / t);
        minDepth = std::min(minDepth, double(f.depth()));
      });
      int bad = 0;
      for (int y = 0; y < cam.height; ++y) {
        for (int x = 0; x < cam.width; ++x) {
          const int c = render_test::classify(cam, V, F, x, y, zNear);
          if (c >= 0) bad += n.at(x, y) != c;
          bad += n.at(x, y) > 1;
          checked += c > 0;
        }
      }
      CHECK(bad == 0);
      CHECK(worstZ <= bTol<S>());
      CHECK(minDepth >= zNear * (1 - 1e-3));
    }
    CHECK(checked > 500);
  }

  SECTION("a triangulated plane through the near plane stays watertight") {
    // Rectangle spanned by corner O and edges E1, E2; tilted so it runs from behind the camera
    // to 3 m ahead. Interior grid points jittered inside the plane.
    const Eigen::Vector3d O(-1.2, 0.3, -0.8), E1(2.4, 0, 0), E2(0, -0.9, 3.8);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> jit(-0.35, 0.35), coin(0, 1);
    const int nx = 19, ny = 23;
    Points3<double> V((nx + 1) * (ny + 1), 3);
    for (int j = 0; j <= ny; ++j) {
      for (int i = 0; i <= nx; ++i) {
        double s = double(i) / nx, t = double(j) / ny;
        if (i > 0 && i < nx) s += jit(rng) / nx;
        if (j > 0 && j < ny) t += jit(rng) / ny;
        V.row(j * (nx + 1) + i) = (O + s * E1 + t * E2).transpose();
      }
    }
    TriangleList F(2 * nx * ny, 3);
    int f = 0;
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
        if (coin(rng) < 0.5) {
          F.row(f++) << a, b, d;
          F.row(f++) << a, d, c;
        } else {
          F.row(f++) << a, b, c;
          F.row(f++) << b, d, c;
        }
      }
    }
    const Image<int> n = countMesh<S>(cam, V.cast<S>(), F, opt);
    int bad = 0, covered = 0, undecided = 0;
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        // Analytic: the ray meets the rectangle's plane at z ≥ near inside the rectangle.
        auto hit = [&](double u, double v) {
          const Eigen::Vector3d d = render_test::pixelRay(cam, u, v);
          const Eigen::Vector3d nrm = E1.cross(E2);
          const double t = nrm.dot(O) / nrm.dot(d);
          const Eigen::Vector3d p = t * d - O;
          const double s = p.dot(E1) / E1.squaredNorm(), r = p.dot(E2) / E2.squaredNorm();
          return t >= zNear && s >= 0 && s <= 1 && r >= 0 && r <= 1;
        };
        int h = 0;
        for (double du : {-0.01, 0.01}) {
          for (double dv : {-0.01, 0.01}) h += hit(x + du, y + dv);
        }
        bad += n.at(x, y) > 1;
        if (h == 4) bad += n.at(x, y) != 1;
        if (h == 0) bad += n.at(x, y) != 0;
        undecided += h > 0 && h < 4;
        covered += n.at(x, y);
      }
    }
    CHECK(bad == 0);
    CHECK(covered > 500);
    CHECK(undecided < 200);
  }
}

TEMPLATE_TEST_CASE("raster: back-face culling follows det[P0 P1 P2]", "[render][raster]", float,
                   double) {
  using S = TestType;
  const auto cam = smallCamera<S>();
  // Normal (P1−P0)×(P2−P0) = +z, away from the camera: a back face.
  const Vec3<S> p0 = at(cam, 10, 10, 2), p1 = at(cam, 30, 10, 2), p2 = at(cam, 10, 30, 2);
  auto count = [&](hawor::CullMode mode, bool flip) {
    hawor::RasterOptions<S> opt;
    opt.cull = mode;
    Rasterizer<S> r(cam, opt);
    int n = 0;
    if (flip) {
      r.drawTriangle(p0, p2, p1, [&](const Fragment<S>&) { ++n; });
    } else {
      r.drawTriangle(p0, p1, p2, [&](const Fragment<S>&) { ++n; });
    }
    return n;
  };
  const int all = count(hawor::CullMode::None, false);
  CHECK(all > 100);
  CHECK(count(hawor::CullMode::None, true) == all);
  CHECK(count(hawor::CullMode::Back, false) == 0);
  CHECK(count(hawor::CullMode::Front, false) == all);
  CHECK(count(hawor::CullMode::Back, true) == all);
  CHECK(count(hawor::CullMode::Front, true) == 0);
}

TEMPLATE_TEST_CASE("raster: degenerate input is skipped, never crashes", "[render][raster]",
                   float, double) {
  using S = TestType;
  const auto cam = smallCamera<S>();
  const S nan = std::numeric_limits<S>::quiet_NaN();
  const S inf = std::numeric_limits<S>::infinity();
  auto fragments = [&](const Points3<S>& V, const TriangleList& F) {
    Image<int> n(cam.width, cam.height, 1, 0);
    Rasterizer<S> r(cam);
    r.drawMesh(V, F, Counter<S>{&n});
    int total = 0;
    for (int v : n.data) total += v;
    return total;
  };
  TriangleList one(1, 3);
  one << 0, 1, 2;

  SECTION("zero area: repeated vertex, collinear points, edge-on plane, repeated index") {
    Points3<S> V(3, 3);
    V << at(cam, 5, 5, 1).transpose(), at(cam, 5, 5, 1).transpose(), at(cam, 30, 20, 1).transpose();
    CHECK(fragments(V, one) == 0);
    V << at(cam, 5, 5, 1).transpose(), at(cam, 15, 10, 2).transpose(), at(cam, 25, 15, 1).transpose();
    CHECK(fragments(V, one) == 0);
    V << S(0), S(0), S(1), S(0.5), S(0), S(1), S(0.2), S(0), S(3);  // plane y = 0 (edge-on)
    CHECK(fragments(V, one) == 0);
    TriangleList same(1, 3);
    same << 1, 1, 1;
    CHECK(fragments(V, same) == 0);
  }

  SECTION("NaN and Inf vertices skip their triangles only") {
    Points3<S> V(6, 3);
    V << at(cam, 2, 2, 1).transpose(), at(cam, 20, 2, 1).transpose(), at(cam, 2, 20, 1).transpose(),
        nan, S(0), S(1), S(0), inf, S(1), S(0), S(0), -inf;
    TriangleList F(4, 3);
    F << 0, 1, 2, 0, 1, 3, 4, 1, 2, 5, 0, 2;
    TriangleList good(1, 3);
    good << 0, 1, 2;
    const int expected = fragments(V, good);
    CHECK(expected > 100);
    CHECK(fragments(V, F) == expected);
    Rasterizer<S> r(cam);
    int n = 0;
    r.drawTriangle(Vec3<S>(nan, nan, nan), V.row(1).transpose(), V.row(2).transpose(),
                   [&](const Fragment<S>&) { ++n; });
    CHECK(n == 0);
  }

  SECTION("entirely behind the camera or behind the near plane") {
    Points3<S> V(3, 3);
    V << S(-1), S(-1), S(-1), S(1), S(-1), S(-2), S(0), S(1), S(-0.5);
    CHECK(fragments(V, one) == 0);
    V.col(2).setConstant(S(5e-4));  // in front of the camera, behind the default near plane
    CHECK(fragments(V, one) == 0);
    V.col(2).setConstant(S(0));
    CHECK(fragments(V, one) == 0);
  }

  SECTION("huge coordinates: a giant triangle covers the whole image at the right depth") {
    for (const double big : {1e4, 1e8, 1e30}) {
      Points3<S> V(3, 3);
      V << S(-big), S(-big), S(2), S(3 * big), S(-big), S(2), S(-big), S(3 * big), S(2);
      Rasterizer<S> r(cam);
      Image<float> depth;
      r.clearDepth(depth);
      r.setDepthBuffer(&depth);
      Image<int> n(cam.width, cam.height, 1, 0);
      r.drawMesh(V, one, Counter<S>{&n});
      int bad = 0;
      for (std::size_t i = 0; i < n.data.size(); ++i) {
        bad += n.data[i] != 1 || std::abs(depth.data[i] - 2.0f) > 1e-4f;
      }
      CHECK(bad == 0);
    }
    // A ground plane y = 1 spanning ±1e7 m, also far behind the camera: only rows below the
    // horizon (v > cy) are covered, at depth z = fy / (v − cy).
    const S big = S(1e7);
    Points3<S> G(4, 3);
    G << -big, S(1), -big, big, S(1), -big, big, S(1), big, -big, S(1), big;
    TriangleList F(2, 3);
    F << 0, 1, 2, 0, 2, 3;
    Rasterizer<S> r(cam);
    Image<float> depth;
    r.clearDepth(depth);
    r.setDepthBuffer(&depth);
    Image<int> n(cam.width, cam.height, 1, 0);
    r.drawMesh(G, F, Counter<S>{&n});
    int bad = 0;
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        const double dv = y - double(cam.cy);
        if (dv > 0) {
          const double z = double(cam.fy) / dv;
          bad += n.at(x, y) != 1 || std::abs(depth.at(x, y) - z) > 1e-4 * z;
        } else {
          bad += n.at(x, y) != 0;
        }
      }
    }
    CHECK(bad == 0);
  }

  SECTION("bad faces, cameras and buffers throw hawor::Error") {
    Points3<S> V(3, 3);
    V << at(cam, 5, 5, 1).transpose(), at(cam, 20, 5, 1).transpose(), at(cam, 5, 20, 1).transpose();
    TriangleList F(2, 3);
    F << 0, 1, 2, 0, 1, 3;
    Rasterizer<S> r(cam);
    int n = 0;
    CHECK_THROWS_AS(r.drawMesh(V, F, [&](const Fragment<S>&) { ++n; }), hawor::Error);
    CHECK(n == 0);  // nothing drawn before the check
    F << 0, 1, 2, -1, 1, 2;
    CHECK_THROWS_AS(r.drawMesh(V, F, [&](const Fragment<S>&) { ++n; }), hawor::Error);
    auto bad = cam;
    bad.fx = S(0);
    CHECK_THROWS_AS(Rasterizer<S>(bad), hawor::Error);
    bad = cam;
    bad.width = 100000;
    CHECK_THROWS_AS(Rasterizer<S>(bad), hawor::Error);
    hawor::RasterOptions<S> opt;
    opt.nearPlane = S(0);
    CHECK_THROWS_AS(Rasterizer<S>(cam, opt), hawor::Error);
    opt.nearPlane = nan;
    CHECK_THROWS_AS(Rasterizer<S>(cam, opt), hawor::Error);
    Image<float> depth(cam.width + 1, cam.height, 1);
    CHECK_THROWS_AS(r.setDepthBuffer(&depth), hawor::Error);
    r.clearDepth(depth);
    r.setDepthBuffer(&depth);
    depth.resize(3, 3);  // resized behind the rasteriser's back
    CHECK_THROWS_AS(r.drawMesh(V, F.topRows(1), [&](const Fragment<S>&) { ++n; }), hawor::Error);
    r.setDepthBuffer(nullptr);
    // Empty meshes are fine.
    CHECK_NOTHROW(r.drawMesh(Points3<S>(0, 3), TriangleList(0, 3), [&](const Fragment<S>&) { ++n; }));
    CHECK(n == 0);
  }
}
