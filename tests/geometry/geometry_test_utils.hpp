// Shared helpers for the geometry tests: seeded random samples, per-scalar tolerances, a
// reference matrix exponential and central differences.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include "hawor/geometry/geometry.hpp"

namespace geo_test {

using hawor::Mat3;
using hawor::Vec3;

/// Per-scalar tolerance: `d` for double, `f` for float.
template <typename S>
S tol(double d, double f) {
  return static_cast<S>(sizeof(S) == sizeof(float) ? f : d);
}

inline double pi() { return 3.14159265358979323846; }

/// Deterministic generator (results are properties, so libc++/libstdc++ differences are fine).
struct Rng {
  std::mt19937 gen;
  explicit Rng(unsigned seed = 12345u) : gen(seed) {}
  double uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(gen);
  }
  Eigen::Vector3d unitVector() {
    Eigen::Vector3d v;
    do {
      v = Eigen::Vector3d(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    } while (v.norm() < 0.1 || v.norm() > 1.0);
    return v.normalized();
  }
  /// Rotation vector with angle uniform in [lo, hi].
  Eigen::Vector3d rotvec(double lo = 0.0, double hi = 3.0) { return uniform(lo, hi) * unitVector(); }
  Eigen::Vector3d vec3(double r) {
    return Eigen::Vector3d(uniform(-r, r), uniform(-r, r), uniform(-r, r));
  }
};

/// Rotation angles that exercise every branch: 0, tiny, around the series thresholds
/// (1e-2 double, 0.3 float), generic, and just below π.
inline std::vector<double> specialAngles() {
  return {0.0, 1e-12, 1e-9, 1e-5, 9.99e-3, 1.001e-2, 0.1, 0.299, 0.301, 1.0, 2.5,
          pi() - 1e-3, pi() - 1e-6};
}

/// Random tangent vectors of each group, with a given rotation angle.
template <typename G>
struct Sampler;

template <typename S>
struct Sampler<hawor::SO3<S>> {
  static typename hawor::SO3<S>::Tangent tangent(Rng& rng, double angle) {
    return (angle * rng.unitVector()).cast<S>();
  }
};
template <typename S>
struct Sampler<hawor::SE3<S>> {
  static typename hawor::SE3<S>::Tangent tangent(Rng& rng, double angle) {
    typename hawor::SE3<S>::Tangent xi;
    xi.template head<3>() = rng.vec3(1.5).cast<S>();
    xi.template tail<3>() = (angle * rng.unitVector()).cast<S>();
    return xi;
  }
};
template <typename S>
struct Sampler<hawor::Sim3<S>> {
  static typename hawor::Sim3<S>::Tangent tangent(Rng& rng, double angle) {
    typename hawor::Sim3<S>::Tangent xi;
    xi.template head<3>() = rng.vec3(1.5).cast<S>();
    xi.template segment<3>(3) = (angle * rng.unitVector()).cast<S>();
    xi(6) = static_cast<S>(rng.uniform(-1.0, 1.0));
    return xi;
  }
};

/// Reference matrix exponential (scaling and squaring with a long Taylor series), independent
/// of the closed forms under test.
inline Eigen::Matrix4d expm(const Eigen::Matrix4d& A) {
  int k = 0;
  double n = A.cwiseAbs().rowwise().sum().maxCoeff();
  while (n > 0.25) {
    n /= 2;
    ++k;
  }
  const Eigen::Matrix4d B = A / std::ldexp(1.0, k);
  Eigen::Matrix4d term = Eigen::Matrix4d::Identity(), sum = Eigen::Matrix4d::Identity();
  for (int i = 1; i < 30; ++i) {
    term = term * B / double(i);
    sum += term;
  }
  for (int i = 0; i < k; ++i) sum = sum * sum;
  return sum;
}

/// Central-difference Jacobian of f: R^n -> R^m at x (double).
template <int M, int N, typename F>
Eigen::Matrix<double, M, N> numericJacobian(F f, const Eigen::Matrix<double, N, 1>& x,
                                             double h = 1e-6) {
  Eigen::Matrix<double, M, N> J;
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp(i) += h;
    xm(i) -= h;
    const Eigen::Matrix<double, M, 1> fp = f(xp), fm = f(xm);
    J.col(i) = (fp - fm) / (2 * h);
  }
  return J;
}

}  // namespace geo_test
