// Shared helpers for the tests of the SLAM's geometric estimation (RANSAC, two-view, PnP, BA):
// a platform-independent random source (hand/portable_random.hpp, so native and WASM draw the
// same numbers), synthetic scenes, error measures and central differences.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include "hawor/geometry/geometry.hpp"
#include "hawor/hand/portable_random.hpp"

namespace est_test {

inline double pi() { return 3.14159265358979323846; }
inline double deg(double rad) { return rad * 180.0 / pi(); }

/// Per-scalar tolerance: `d` for double, `f` for float.
template <typename S>
S tol(double d, double f) {
  return static_cast<S>(sizeof(S) == sizeof(float) ? f : d);
}

struct Rng {
  std::mt19937 gen;
  explicit Rng(unsigned seed) : gen(seed) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * hawor::uniform01(gen); }
  double normal() { return hawor::standardNormal(gen); }
  int index(int n) { return std::min(n - 1, static_cast<int>(uniform(0.0, 1.0) * n)); }
  // The helpers below draw their components in order (function arguments are evaluated in an
  // unspecified order: GCC and clang differ), so native and WASM builds see the same scenes.
  Eigen::Vector2d uniform2(double lo0, double hi0, double lo1, double hi1) {
    const double a = uniform(lo0, hi0);
    const double b = uniform(lo1, hi1);
    return Eigen::Vector2d(a, b);
  }
  Eigen::Vector3d uniform3(double lo0, double hi0, double lo1, double hi1, double lo2, double hi2) {
    const double a = uniform(lo0, hi0);
    const double b = uniform(lo1, hi1);
    const double c = uniform(lo2, hi2);
    return Eigen::Vector3d(a, b, c);
  }
  Eigen::Vector2d normal2() {
    const double a = normal();
    const double b = normal();
    return Eigen::Vector2d(a, b);
  }
  Eigen::Vector3d unitVector() {
    const double a = normal();
    const double b = normal();
    const double c = normal();
    return Eigen::Vector3d(a, b, c).normalized();
  }
  /// A random direction times a length uniform in [lo, hi].
  Eigen::Vector3d scaledUnit(double lo, double hi) {
    const Eigen::Vector3d u = unitVector();
    return u * uniform(lo, hi);
  }
  /// Rotation by an angle uniform in [lo, hi] (radians) about a random axis.
  Eigen::Matrix3d rotation(double lo, double hi) {
    const double angle = uniform(lo, hi);
    return Eigen::AngleAxisd(angle, unitVector()).toRotationMatrix();
  }
};

/// Angle of R1ᵀR2 in degrees (via the quaternion: accurate near 0, unlike acos of the trace).
inline double rotationErrorDeg(const Eigen::Matrix3d& R1, const Eigen::Matrix3d& R2) {
  const Eigen::Quaterniond q(R1.transpose() * R2);
  return deg(2.0 * std::atan2(q.vec().norm(), std::abs(q.w())));
}

/// Angle between two vectors in degrees (atan2 form: accurate near 0 and π).
inline double angleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return deg(std::atan2(a.cross(b).norm(), a.dot(b)));
}

/// Central differences of f: R^N → R^M at x.
template <int M, int N, typename F>
Eigen::Matrix<double, M, N> numericJacobian(F&& f, const Eigen::Matrix<double, N, 1>& x,
                                            double h = 1e-6) {
  Eigen::Matrix<double, M, N> J;
  for (int k = 0; k < N; ++k) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp(k) += h;
    xm(k) -= h;
    J.col(k) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return J;
}

/// A camera at 640×480 with f = 500 px (about 65° horizontal field of view).
template <typename S>
hawor::PinholeCamera<S> vgaCamera() {
  hawor::PinholeCamera<S> c;
  c.fx = c.fy = S(500);
  c.cx = S(319.5);
  c.cy = S(239.5);
  c.width = 640;
  c.height = 480;
  return c;
}

/// Two-view correspondences in normalised coordinates: true inliers from the scene points X1
/// (camera-1 frame) seen by camera 2 (X2 = R·X1 + t) with Gaussian pixel noise, then a fraction
/// of them replaced by random points of the image (outliers).
struct TwoViewScene {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // camera 1 → camera 2
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> X1;                  // true points (camera 1)
  std::vector<char> isInlier;
  std::vector<hawor::Vec2<double>> x1, x2;
};

/// kind 0: general 3D scene; 1: plane; 2: pure rotation (t = 0).
inline TwoViewScene makeTwoViewScene(Rng& rng, int kind, int n, double outlierRatio,
                                     double noisePx, double f = 500.0) {
  TwoViewScene s;
  s.R = rng.rotation(3.0 * pi() / 180.0, 10.0 * pi() / 180.0);
  if (kind != 2) {
    const double tx = rng.uniform(0.3, 0.6);
    const double sign = rng.uniform(0, 1) < 0.5 ? -1.0 : 1.0;
    const Eigen::Vector2d tyz = rng.uniform2(-0.2, 0.2, -0.2, 0.2);
    s.t = Eigen::Vector3d(sign * tx, tyz(0), tyz(1));
  }
  const Eigen::Vector2d pxy = rng.uniform2(-0.3, 0.3, -0.3, 0.3);
  const Eigen::Vector3d pn = Eigen::Vector3d(pxy(0), pxy(1), -1.0).normalized();
  const double pd = -rng.uniform(4.0, 6.0);  // plane pnᵀX = pd·(…) passing in front at z ≈ 4..6
  const double halfW = 320.0 / f, halfH = 240.0 / f;
  while (static_cast<int>(s.x1.size()) < n) {
    const double u = rng.uniform(-halfW, halfW) * 0.95;
    const double v = rng.uniform(-halfH, halfH) * 0.95;
    const Eigen::Vector3d ray(u, v, 1.0);
    double z;
    if (kind == 1) {
      z = pd / pn.dot(ray);  // intersection of the ray with the plane
    } else {
      z = rng.uniform(3.0, 8.0);
    }
    if (!(z > 0.5)) continue;
    const Eigen::Vector3d X = z * ray;
    const Eigen::Vector3d X2 = s.R * X + s.t;
    if (X2.z() < 0.5) continue;
    const double u2 = X2.x() / X2.z(), v2 = X2.y() / X2.z();
    if (std::abs(u2) > halfW || std::abs(v2) > halfH) continue;
    s.X1.push_back(X);
    s.isInlier.push_back(1);
    const Eigen::Vector2d n1 = rng.normal2(), n2 = rng.normal2();
    s.x1.emplace_back(u + noisePx / f * n1(0), v + noisePx / f * n1(1));
    s.x2.emplace_back(u2 + noisePx / f * n2(0), v2 + noisePx / f * n2(1));
  }
  const int nOut = static_cast<int>(std::lround(outlierRatio * n));
  for (int k = 0; k < nOut; ++k) {
    const std::size_t i = static_cast<std::size_t>(k * n / std::max(1, nOut));
    s.isInlier[i] = 0;
    s.x2[i] = rng.uniform2(-halfW, halfW, -halfH, halfH);
  }
  return s;
}

template <typename S>
std::vector<hawor::Vec2<S>> castPoints(const std::vector<hawor::Vec2<double>>& v) {
  std::vector<hawor::Vec2<S>> out;
  out.reserve(v.size());
  for (const auto& p : v) out.emplace_back(p.cast<S>());
  return out;
}

}  // namespace est_test
