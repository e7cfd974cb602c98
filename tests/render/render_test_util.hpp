// Shared helpers of the render tests: mesh generators and brute-force references written
// independently of the rasteriser (ray–triangle intersection in double).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "hawor/geometry/camera.hpp"
#include "hawor/render/rasterizer.hpp"

namespace render_test {

using hawor::Points3;
using hawor::TriangleList;

/// Unit icosphere (outward, counter-clockwise winding seen from outside) after `levels`
/// midpoint subdivisions: 12·4^0 … (levels 3: 642 vertices, 1280 faces).
inline void icosphere(int levels, Points3<double>& V, TriangleList& F) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> v = {
      {-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
      {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {
      {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : v) {
    const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (auto& c : p) c /= n;
  }
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      std::array<double, 3> p;
      for (int c = 0; c < 3; ++c) p[c] = 0.5 * (v[a][c] + v[b][c]);
      const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      for (auto& c : p) c /= n;
      v.push_back(p);
      mid[key] = static_cast<int>(v.size()) - 1;
      return static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]),
                c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f.swap(g);
  }
  V.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) {
    for (int c = 0; c < 3; ++c) V(static_cast<Eigen::Index>(i), c) = v[i][c];
  }
  F.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) {
    // Make every face wind counter-clockwise seen from outside: normal · centroid > 0.
    Eigen::Vector3d p0 = V.row(f[i][0]).transpose(), p1 = V.row(f[i][1]).transpose(),
                    p2 = V.row(f[i][2]).transpose();
    const bool outward = (p1 - p0).cross(p2 - p0).dot(p0 + p1 + p2) > 0;
    F(static_cast<Eigen::Index>(i), 0) = f[i][0];
    F(static_cast<Eigen::Index>(i), 1) = outward ? f[i][1] : f[i][2];
    F(static_cast<Eigen::Index>(i), 2) = outward ? f[i][2] : f[i][1];
  }
}

/// Radially deformed (star-shaped, so still closed and outward-wound), scaled by `radius`
/// (and `stretch` per axis) and translated to `centre`.
inline Points3<double> deform(const Points3<double>& unit, double radius,
                              const Eigen::Vector3d& stretch, const Eigen::Vector3d& centre,
                              double bump) {
  Points3<double> out(unit.rows(), 3);
  for (Eigen::Index i = 0; i < unit.rows(); ++i) {
    const Eigen::Vector3d p = unit.row(i).transpose();
    const double r = 1.0 + bump * std::sin(3.0 * p.x() + 1.0) * std::cos(2.0 * p.y() - 0.5) +
                     0.5 * bump * std::sin(5.0 * p.z());
    out.row(i) = (centre + radius * r * stretch.cwiseProduct(p)).transpose();
  }
  return out;
}

/// Möller–Trumbore: ray o + t·d against triangle (a, b, c); returns true with t, u, v
/// (barycentrics (1−u−v, u, v)) when the ray meets the triangle's plane (no inside test).
inline bool rayPlane(const Eigen::Vector3d& d, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                     const Eigen::Vector3d& c, double& t, double& u, double& v) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-300) return false;
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = -a;  // ray origin at the camera centre
  u = s.dot(p) * inv;
  const Eigen::Vector3d q = s.cross(e1);
  v = d.dot(q) * inv;
  t = e2.dot(q) * inv;
  return std::isfinite(t);
}

/// Ray through pixel (u, v) of a camera, in double.
template <typename Scalar>
Eigen::Vector3d pixelRay(const hawor::PinholeCamera<Scalar>& cam, double u, double v) {
  return Eigen::Vector3d((u - double(cam.cx)) / double(cam.fx), (v - double(cam.cy)) / double(cam.fy),
                         1.0);
}

/// Nearest hit (depth z = t since d.z = 1) of the ray through (u, v) with the mesh, beyond
/// zNear; returns +inf for no hit. Optionally the hit face. Barycentrics within 1e−9 of the
/// triangle count as inside (a ray through a shared edge hits one of the two triangles).
template <typename Scalar>
double nearestHit(const hawor::PinholeCamera<Scalar>& cam, const Points3<double>& V,
                  const TriangleList& F, double u, double v, double zNear, int* face = nullptr) {
  const Eigen::Vector3d d = pixelRay(cam, u, v);
  double best = INFINITY;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    double t, a, b;
    if (!rayPlane(d, V.row(F(f, 0)).transpose(), V.row(F(f, 1)).transpose(),
                  V.row(F(f, 2)).transpose(), t, a, b)) {
      continue;
    }
    if (a >= -1e-9 && b >= -1e-9 && a + b <= 1 + 1e-9 && t >= zNear && t < best) {
      best = t;
      if (face) *face = static_cast<int>(f);
    }
  }
  return best;
}

/// Classification of a pixel centre by brute force: 1 hit, 0 miss, −1 undecided (the rays
/// through (u ± δ, v ± δ) disagree: the centre lies within δ px of a silhouette edge).
template <typename Scalar>
int classify(const hawor::PinholeCamera<Scalar>& cam, const Points3<double>& V,
             const TriangleList& F, int x, int y, double zNear, double delta = 0.01) {
  const double off[5][2] = {{0, 0}, {delta, delta}, {-delta, delta}, {delta, -delta}, {-delta, -delta}};
  int hits = 0;
  for (const auto& o : off) hits += std::isfinite(nearestHit(cam, V, F, x + o[0], y + o[1], zNear));
  return hits == 5 ? 1 : hits == 0 ? 0 : -1;
}

template <typename Scalar>
Points3<Scalar> castPoints(const Points3<double>& p) {
  return p.cast<Scalar>();
}

}  // namespace render_test
