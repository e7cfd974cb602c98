// hawor/hand/portable_random.hpp — uniform and normal variates computed the same way on every
// platform from a standard engine's raw output (the std:: distributions are implementation-
// defined: libstdc++ and Emscripten's libc++ give different numbers for one seed), so that
// procedural models, sampled poses and tests are identical natively and in WebAssembly.
// Pure functions of the engine state; thread-safe per engine.
#pragma once

#include <cmath>

namespace hawor {

/// Uniform in the open interval (0, 1) from one engine call: (x − min + ½)/(max − min + 1).
template <typename Rng>
double uniform01(Rng& rng) {
  const double span = static_cast<double>(Rng::max() - Rng::min()) + 1.0;
  return (static_cast<double>(rng() - Rng::min()) + 0.5) / span;
}

/// Standard normal variate by the Box–Muller transform (two engine calls per variate).
template <typename Rng>
double standardNormal(Rng& rng) {
  const double u1 = uniform01(rng), u2 = uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586476925 * u2);
}

}  // namespace hawor
