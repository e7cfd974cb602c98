// Random weights of an infiller network (motion/infiller_weights.hpp) for tests: every tensor of
// a configuration, named as the file format names them, as float64 arrays in an Npz.
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "hawor/io/npz.hpp"
#include "hawor/motion/infiller_weights.hpp"

namespace hawor_test {

/// Matrices in ±1/√fan_in, LayerNorm gains 1 ± 0.25, offsets ±0.1 (a well-conditioned network).
inline hawor::Npz randomInfillerWeights(const hawor::InfillerConfig& c, unsigned seed) {
  std::mt19937 rng(seed);
  hawor::Npz npz;
  for (const auto& s : hawor::infillerTensorSpecs(c)) {
    if (s.optional) continue;
    size_t n = 1;
    for (size_t d : s.shape) n *= d;
    const bool norm = s.name.find("norm") != std::string::npos;
    const bool gain = norm && s.name.size() > 6 && s.name.substr(s.name.size() - 6) == "weight";
    const double fanIn = s.shape.size() == 2 ? double(s.shape[1]) : double(c.dModel);
    const double bound = norm ? (gain ? 0.25 : 0.1) : 1 / std::sqrt(fanIn);
    std::uniform_real_distribution<double> u(-bound, bound);
    std::vector<double> v(n);
    for (double& x : v) x = (gain ? 1.0 : 0.0) + u(rng);
    npz.set(s.name, hawor::NpyArray::fromData(v.data(), s.shape));
  }
  return npz;
}

}  // namespace hawor_test
