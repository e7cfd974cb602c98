// Shared helpers of the synth tests: hand models, small sequences, and brute-force references
// written independently of the renderer (ray–triangle intersection in double, a structure-tensor
// corner detector).
#pragma once

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "hawor/hand/default_hand.hpp"
#include "hawor/hand/load_model.hpp"
#include "hawor/hand/mirror.hpp"
#include "hawor/hand/synthetic_hand.hpp"
#include "hawor/synth/synth.hpp"

namespace synth_test {

using hawor::HandModel;
using hawor::Points3;
using hawor::Vec3;
namespace hs = hawor::synth;

/// The procedural right hand and its mirror image (always available, also in WASM).
template <typename S>
struct Hands {
  HandModel<S> left, right;
};

template <typename S>
const Hands<S>& syntheticHands() {
  static const Hands<S> h = [] {
    Hands<S> r;
    r.right = hawor::makeSyntheticHand<S>();
    r.left = hawor::mirrorHandModel(r.right);
    return r;
  }();
  return h;
}

/// The shipped default (WebXR) hands when their files are found ($HAWOR_HAND_DIR or the npm
/// package in the source tree); nullptr otherwise.
inline const Hands<double>* defaultHands() {
  static const std::unique_ptr<Hands<double>> h = []() -> std::unique_ptr<Hands<double>> {
    const std::vector<std::string> dirs = {
        std::string(HAWOR_SOURCE_DIR) + "/node_modules/@webxr-input-profiles/assets/dist/profiles/generic-hand"};
    try {
      auto r = std::make_unique<Hands<double>>();
      r->right = hawor::loadAnyHandModel<double>(hawor::findDefaultHandModel(hawor::HandSide::Right, dirs),
                                                 hawor::HandSide::Right)
                     .model;
      r->left = hawor::loadAnyHandModel<double>(hawor::findDefaultHandModel(hawor::HandSide::Left, dirs),
                                                hawor::HandSide::Left)
                    .model;
      return r;
    } catch (const hawor::Error&) {
      return nullptr;
    }
  }();
  return h.get();
}

/// Small, fast options: size w × 3w/4, coarse textures.
inline hs::SynthOptions smallOptions(int w, int frames = 0) {
  hs::SynthOptions o;
  o.width = w;
  o.height = w * 3 / 4;
  o.frames = frames;
  o.textureDivisor = 4;
  return o;
}

/// A scene per scalar type and seed, built once (scenes are read-only and shared).
template <typename S>
std::shared_ptr<const hawor::synth::IndoorScene<S>> sharedScene(std::uint64_t seed, int divisor = 4) {
  static std::vector<std::pair<std::uint64_t, std::shared_ptr<const hs::IndoorScene<S>>>> cache;
  const std::uint64_t key = seed * 8 + static_cast<std::uint64_t>(divisor);
  for (const auto& e : cache)
    if (e.first == key) return e.second;
  hs::SceneOptions so;
  so.textureDivisor = divisor;
  cache.emplace_back(key, std::make_shared<const hs::IndoorScene<S>>(hs::makeIndoorScene<S>(seed, so)));
  return cache.back().second;
}

/// Nearest intersection distance s > eps of the ray o + s·d with any triangle of the scene
/// (Möller–Trumbore in double), +inf when none.
template <typename S>
double castRay(const hs::IndoorScene<S>& scene, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double best = INFINITY;
  for (Eigen::Index f = 0; f < scene.faces.rows(); ++f) {
    const Eigen::Vector3d a = scene.vertices.row(scene.faces(f, 0)).transpose().template cast<double>();
    const Eigen::Vector3d b = scene.vertices.row(scene.faces(f, 1)).transpose().template cast<double>();
    const Eigen::Vector3d c = scene.vertices.row(scene.faces(f, 2)).transpose().template cast<double>();
    const Eigen::Vector3d e1 = b - a, e2 = c - a;
    const Eigen::Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-14) continue;
    const double inv = 1.0 / det;
    const Eigen::Vector3d tv = o - a;
    const double u = tv.dot(p) * inv;
    if (u < -1e-9 || u > 1 + 1e-9) continue;
    const Eigen::Vector3d q = tv.cross(e1);
    const double v = d.dot(q) * inv;
    if (v < -1e-9 || u + v > 1 + 1e-9) continue;
    const double s = e2.dot(q) * inv;
    if (s > 1e-6 && s < best) best = s;
  }
  return best;
}

/// Grey value (0..255) of an RGB image.
inline std::vector<float> grey(const hawor::ImageU8& rgb) {
  std::vector<float> g(static_cast<std::size_t>(rgb.width) * static_cast<std::size_t>(rgb.height));
  for (int y = 0; y < rgb.height; ++y) {
    for (int x = 0; x < rgb.width; ++x) {
      const std::uint8_t* p = rgb.row(y) + 3 * x;
      g[static_cast<std::size_t>(y * rgb.width + x)] = 0.299f * p[0] + 0.587f * p[1] + 0.114f * p[2];
    }
  }
  return g;
}

/// Corners by the smallest eigenvalue of the 5×5 structure tensor of central-difference
/// gradients (Shi–Tomasi), above `threshold`, local maxima in a 7×7 window, and not within
/// `maskMargin` pixels of a non-zero mask pixel.
inline int countCorners(const hawor::ImageU8& rgb, const hawor::ImageU8& mask, double threshold, int maskMargin = 3) {
  const int W = rgb.width, H = rgb.height;
  const std::vector<float> g = grey(rgb);
  std::vector<double> gx(g.size(), 0), gy(g.size(), 0), lmin(g.size(), 0);
  for (int y = 1; y + 1 < H; ++y) {
    for (int x = 1; x + 1 < W; ++x) {
      const std::size_t i = static_cast<std::size_t>(y * W + x);
      gx[i] = 0.5 * (g[i + 1] - g[i - 1]);
      gy[i] = 0.5 * (g[i + static_cast<std::size_t>(W)] - g[i - static_cast<std::size_t>(W)]);
    }
  }
  for (int y = 3; y + 3 < H; ++y) {
    for (int x = 3; x + 3 < W; ++x) {
      double a = 0, b = 0, c = 0;
      for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
          const std::size_t i = static_cast<std::size_t>((y + dy) * W + x + dx);
          a += gx[i] * gx[i];
          b += gx[i] * gy[i];
          c += gy[i] * gy[i];
        }
      }
      lmin[static_cast<std::size_t>(y * W + x)] = 0.5 * (a + c) - std::sqrt(0.25 * (a - c) * (a - c) + b * b);
    }
  }
  int n = 0;
  for (int y = 3; y + 3 < H; ++y) {
    for (int x = 3; x + 3 < W; ++x) {
      const double v = lmin[static_cast<std::size_t>(y * W + x)];
      if (v < threshold) continue;
      bool isMax = true, nearMask = false;
      for (int dy = -3; dy <= 3 && isMax; ++dy) {
        for (int dx = -3; dx <= 3; ++dx) {
          if ((dx || dy) && lmin[static_cast<std::size_t>((y + dy) * W + x + dx)] > v) {
            isMax = false;
            break;
          }
        }
      }
      for (int dy = -maskMargin; dy <= maskMargin && !nearMask; ++dy) {
        for (int dx = -maskMargin; dx <= maskMargin; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx >= 0 && yy >= 0 && xx < W && yy < H && mask.at(xx, yy) != 0) {
            nearMask = true;
            break;
          }
        }
      }
      if (isMax && !nearMask) ++n;
    }
  }
  return n;
}

/// The temporary folder of the test build (native and WASM alike).
inline std::string tempDir(const std::string& name) { return std::string(HAWOR_REF_DIR) + "/synth_" + name; }

}  // namespace synth_test
