// hawor/synth/random.hpp — the random numbers of the synthetic sequences, identical on every
// platform for a seed: a standard engine (std::mt19937_64, whose output sequence the C++
// standard fixes) read through hand/portable_random.hpp (the std:: distributions are
// implementation-defined), integer hashes for per-texel / per-pixel values (no state, no libm),
// and smooth random signals (uniform cubic B-splines through random knots: C² and arithmetic
// only, so they evaluate bit-identically natively and in WebAssembly).
// Thread-safety: SynthRng is a per-thread value; the rest are pure functions or read-only values.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/hand/portable_random.hpp"

namespace hawor {
namespace synth {

/// 32-bit integer hash with good avalanche (the "lowbias32" finaliser: xor-shift-multiply).
inline std::uint32_t hash32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

/// Hash of several integers (order matters): h = hash32(h ^ (v + golden ratio + mixing)).
inline std::uint32_t hashCombine(std::uint32_t a, std::uint32_t b) {
  return hash32(a ^ (b + 0x9e3779b9U + (a << 6) + (a >> 2)));
}
inline std::uint32_t hash3(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  return hashCombine(hashCombine(hash32(a), b), c);
}

/// A hashed value in [0, 1) from 24 of its bits (exact in float and double).
inline float hashUnit(std::uint32_t h) { return static_cast<float>(h >> 8) * (1.0f / 16777216.0f); }

/// Seeded random numbers for the generators. Streams are derived from (seed, stream id) so that
/// adding draws to one part (e.g. the left hand) never shifts the numbers of another.
class SynthRng {
 public:
  using Engine = std::mt19937_64;
  SynthRng(std::uint64_t seed, std::uint64_t stream) : engine_(splitmix64(seed ^ splitmix64(stream + 1))) {}

  /// SplitMix64's output function: a bijective 64-bit mix (distinct inputs, distinct seeds).
  static std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ULL;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
    return x ^ (x >> 31);
  }

  /// Uniform in (0, 1).
  double uniform() { return uniform01(engine_); }
  /// Uniform in (a, b).
  double uniform(double a, double b) { return a + (b - a) * uniform01(engine_); }
  /// Standard normal (Box–Muller).
  double normal() { return standardNormal(engine_); }
  /// Uniform integer in [0, n) (n >= 1), by scaling a uniform (no modulo bias worth noting).
  int index(int n) {
    const int k = static_cast<int>(uniform01(engine_) * n);
    return k < n ? k : n - 1;
  }
  /// True with probability p.
  bool chance(double p) { return uniform01(engine_) < p; }
  /// A raw 32-bit value (for hash seeds).
  std::uint32_t bits() { return static_cast<std::uint32_t>(engine_() >> 32); }
  Engine& engine() { return engine_; }

 private:
  Engine engine_;
};

/// Uniform cubic B-spline basis at local parameter u ∈ [0, 1) (weights of knots k−1, k, k+1, k+2).
template <typename Scalar>
inline void bsplineWeights(Scalar u, Scalar w[4]) {
  const Scalar u2 = u * u, u3 = u2 * u;
  const Scalar s = Scalar(1) / Scalar(6);
  const Scalar omu = Scalar(1) - u;
  w[0] = omu * omu * omu * s;
  w[1] = (Scalar(3) * u3 - Scalar(6) * u2 + Scalar(4)) * s;
  w[2] = (Scalar(-3) * u3 + Scalar(3) * u2 + Scalar(3) * u + Scalar(1)) * s;
  w[3] = u3 * s;
}

/// A smooth random signal s(t) of `dims` components: a uniform cubic B-spline with knots every
/// `spacing` seconds and knot values normal with standard deviation `sigma` (per component).
/// C² in t; |s| stays below ≈ sigma·4 (a convex combination of the knots). Evaluation outside
/// [0, duration] clamps t.
template <typename Scalar>
class SmoothSignal {
 public:
  SmoothSignal() = default;
  SmoothSignal(SynthRng& rng, double duration, double spacing, int dims, const VecX<Scalar>& sigma)
      : spacing_(spacing), dims_(dims) {
    if (!(spacing > 0) || dims < 1 || sigma.size() != dims || !(duration >= 0)) {
      throw Error("SmoothSignal: spacing must be > 0, dims >= 1, sigma of size dims, duration >= 0");
    }
    knots_ = static_cast<int>(duration / spacing) + 4;
    values_.resize(static_cast<std::size_t>(knots_) * dims);
    for (int k = 0; k < knots_; ++k) {
      for (int d = 0; d < dims; ++d) values_[static_cast<std::size_t>(k * dims + d)] = Scalar(rng.normal()) * sigma(d);
    }
  }
  int dims() const { return dims_; }

  /// Component d of s(t).
  Scalar operator()(double t, int d = 0) const {
    if (values_.empty()) return Scalar(0);
    double x = t / spacing_;
    if (x < 0) x = 0;
    const double xmax = static_cast<double>(knots_ - 3) - 1e-9;
    if (x > xmax) x = xmax;
    const int k = static_cast<int>(x);
    Scalar w[4];
    bsplineWeights(Scalar(x - k), w);
    Scalar s = Scalar(0);
    for (int i = 0; i < 4; ++i) s += w[i] * values_[static_cast<std::size_t>((k + i) * dims_ + d)];
    return s;
  }
  /// The first three components as a vector (dims >= 3).
  Vec3<Scalar> vec3(double t) const { return Vec3<Scalar>((*this)(t, 0), (*this)(t, 1), (*this)(t, 2)); }

 private:
  double spacing_ = 1;
  int dims_ = 1;
  int knots_ = 0;
  std::vector<Scalar> values_;
};

/// Smoothstep 3s² − 2s³ of s clamped to [0, 1] (zero slope at both ends).
template <typename Scalar>
inline Scalar smoothstep(Scalar s) {
  if (s <= Scalar(0)) return Scalar(0);
  if (s >= Scalar(1)) return Scalar(1);
  return s * s * (Scalar(3) - Scalar(2) * s);
}

}  // namespace synth
}  // namespace hawor
