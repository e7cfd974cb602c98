// hawor/slam/binary_descriptor.hpp — 256-bit binary descriptors of image points for place
// recognition (BRIEF, Calonder et al. 2010, oriented as in ORB, Rublee et al. 2011), and their
// matching by Hamming distance.
//
//   tests:       256 pairs (p_i, q_i) of offsets drawn once from an isotropic Gaussian of
//                σ = 31/5 px (BRIEF's G II), kept inside a disc of radius 13 px, from a fixed
//                seed through portable_random.hpp (the same pattern natively and in WASM);
//   smoothing:   each test reads the mean of a 5×5 box around the offset (an integral image), as
//                ORB does, instead of a pre-blurred image;
//   orientation: θ = atan2(m01, m10), the intensity centroid's direction over a disc of radius
//                15 px (Rosin 1999); the pattern is rotated by θ, quantised to 30 steps of 12°
//                (precomputed), so that a rolled head's view of a place gives the same bits;
//   bit i:       1 when box(R_θ p_i) < box(R_θ q_i).
// A point closer than `border()` px to the image's edge has no descriptor.
// The distance of two descriptors is the number of differing bits (0..256): the same point seen
// again typically differs in 20–60 bits, unrelated points in about 128.
// BinaryDescriptorExtractor holds the pattern and one image's integral image; not thread-safe
// while setImage runs, const calls are.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/hand/portable_random.hpp"
#include "hawor/render/image.hpp"

namespace hawor {

/// 256 bits, bit i of test i in word i/64.
struct BinaryDescriptor {
  std::array<std::uint64_t, 4> bits{};
};

/// Number of set bits of a 64-bit word.
inline int popcount64(std::uint64_t x) {
#if defined(__GNUC__) || defined(__clang__)
  return __builtin_popcountll(x);
#else
  x = x - ((x >> 1) & 0x5555555555555555ull);
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return static_cast<int>((x * 0x0101010101010101ull) >> 56);
#endif
}

/// Hamming distance (0..256).
inline int hammingDistance(const BinaryDescriptor& a, const BinaryDescriptor& b) {
  return popcount64(a.bits[0] ^ b.bits[0]) + popcount64(a.bits[1] ^ b.bits[1]) +
         popcount64(a.bits[2] ^ b.bits[2]) + popcount64(a.bits[3] ^ b.bits[3]);
}

class BinaryDescriptorExtractor {
 public:
  static constexpr int kTests = 256;
  static constexpr int kAngles = 30;        ///< orientation steps of 12°
  static constexpr int kPatternRadius = 13;  ///< test offsets lie in this disc
  static constexpr int kBoxHalf = 2;         ///< 5×5 boxes
  static constexpr int kOrientRadius = 15;

  explicit BinaryDescriptorExtractor(std::uint32_t seed = 0xb41efu) {
    std::mt19937 rng(seed);
    const double sigma = 31.0 / 5.0;
    std::array<std::array<double, 2>, 2 * kTests> base{};
    for (auto& o : base) {
      do {
        o[0] = sigma * standardNormal(rng);
        o[1] = sigma * standardNormal(rng);
      } while (o[0] * o[0] + o[1] * o[1] > double(kPatternRadius * kPatternRadius));
    }
    for (int a = 0; a < kAngles; ++a) {
      const double th = 2.0 * 3.14159265358979323846 * a / kAngles;
      const double c = std::cos(th), s = std::sin(th);
      for (int k = 0; k < 2 * kTests; ++k) {
        pattern_[a][k][0] = static_cast<int>(std::lround(c * base[k][0] - s * base[k][1]));
        pattern_[a][k][1] = static_cast<int>(std::lround(s * base[k][0] + c * base[k][1]));
      }
    }
    // the orientation disc: for each row offset dy, the half-width of the disc
    for (int dy = -kOrientRadius; dy <= kOrientRadius; ++dy) {
      halfWidth_[dy + kOrientRadius] =
          static_cast<int>(std::floor(std::sqrt(double(kOrientRadius * kOrientRadius - dy * dy))));
    }
  }

  /// Points at least this far from every edge (px) have a descriptor.
  static constexpr int border() { return kPatternRadius + kBoxHalf + 2; }

  /// The image the next compute() calls read (grey, one channel): its integral image is built.
  void setImage(const ImageF& grey) {
    if (!grey.consistent() || grey.channels != 1 || grey.width <= 0 || grey.height <= 0) {
      throw Error("BinaryDescriptorExtractor: expected a non-empty one-channel image");
    }
    w_ = grey.width;
    h_ = grey.height;
    const std::size_t W = static_cast<std::size_t>(w_ + 1);
    integral_.assign(W * static_cast<std::size_t>(h_ + 1), 0.0);
    grey_ = &grey;
    for (int y = 0; y < h_; ++y) {
      const float* r = grey.row(y);
      double rowSum = 0.0;
      double* out = integral_.data() + static_cast<std::size_t>(y + 1) * W;
      const double* above = integral_.data() + static_cast<std::size_t>(y) * W;
      for (int x = 0; x < w_; ++x) {
        rowSum += double(r[x]);
        out[x + 1] = above[x + 1] + rowSum;
      }
    }
  }

  /// The descriptor of the point at pixel (x, y) (rounded to the nearest pixel) of the image set
  /// last; false when it is within border() px of an edge, or no image was set.
  bool compute(float x, float y, BinaryDescriptor& d) const {
    if (!grey_ || !std::isfinite(x) || !std::isfinite(y)) return false;
    const int cx = static_cast<int>(std::lround(x)), cy = static_cast<int>(std::lround(y));
    const int b = border();
    if (cx < b || cy < b || cx >= w_ - b || cy >= h_ - b) return false;
    // orientation from the intensity centroid (the disc fits: border() > kOrientRadius)
    double m10 = 0.0, m01 = 0.0;
    for (int dy = -kOrientRadius; dy <= kOrientRadius; ++dy) {
      const float* r = grey_->row(cy + dy);
      const int hw = halfWidth_[dy + kOrientRadius];
      for (int dx = -hw; dx <= hw; ++dx) {
        const double v = double(r[cx + dx]);
        m10 += dx * v;
        m01 += dy * v;
      }
    }
    double th = std::atan2(m01, m10);
    if (th < 0.0) th += 2.0 * 3.14159265358979323846;
    int a = static_cast<int>(std::lround(th / (2.0 * 3.14159265358979323846) * kAngles));
    if (a >= kAngles) a -= kAngles;
    const auto& pat = pattern_[a];
    d.bits = {0, 0, 0, 0};
    for (int i = 0; i < kTests; ++i) {
      const double vp = box(cx + pat[2 * i][0], cy + pat[2 * i][1]);
      const double vq = box(cx + pat[2 * i + 1][0], cy + pat[2 * i + 1][1]);
      if (vp < vq) d.bits[static_cast<std::size_t>(i >> 6)] |= std::uint64_t(1) << (i & 63);
    }
    return true;
  }

 private:
  /// Sum of the 5×5 box centred on (x, y) (inside the image: the caller's border).
  double box(int x, int y) const {
    const std::size_t W = static_cast<std::size_t>(w_ + 1);
    const int x0 = x - kBoxHalf, x1 = x + kBoxHalf + 1, y0 = y - kBoxHalf, y1 = y + kBoxHalf + 1;
    const double* I = integral_.data();
    return I[std::size_t(y1) * W + std::size_t(x1)] - I[std::size_t(y0) * W + std::size_t(x1)] -
           I[std::size_t(y1) * W + std::size_t(x0)] + I[std::size_t(y0) * W + std::size_t(x0)];
  }

  std::array<std::array<std::array<int, 2>, 2 * kTests>, kAngles> pattern_{};
  std::array<int, 2 * kOrientRadius + 1> halfWidth_{};
  std::vector<double> integral_;
  const ImageF* grey_ = nullptr;
  int w_ = 0, h_ = 0;
};

/// A match of query descriptor `query` to train descriptor `train` at Hamming `distance`.
struct DescriptorMatch {
  int query;
  int train;
  int distance;
};

/// Brute-force matching: each query descriptor's nearest train descriptor, kept when its distance
/// is at most maxDistance, below ratio × the second nearest's (Lowe's test on Hamming distances),
/// and the query is also that train descriptor's nearest (mutual). O(|query|·|train|).
inline std::vector<DescriptorMatch> matchBinaryDescriptors(const std::vector<BinaryDescriptor>& query,
                                                           const std::vector<BinaryDescriptor>& train,
                                                           int maxDistance = 64, double ratio = 0.8) {
  std::vector<DescriptorMatch> out;
  if (query.empty() || train.empty()) return out;
  std::vector<int> bestQ(train.size(), -1), bestQd(train.size(), std::numeric_limits<int>::max());
  std::vector<DescriptorMatch> cand;
  for (std::size_t i = 0; i < query.size(); ++i) {
    int b1 = std::numeric_limits<int>::max(), b2 = b1, j1 = -1;
    for (std::size_t j = 0; j < train.size(); ++j) {
      const int d = hammingDistance(query[i], train[j]);
      if (d < bestQd[j]) bestQd[j] = d, bestQ[j] = static_cast<int>(i);
      if (d < b1) {
        b2 = b1, b1 = d, j1 = static_cast<int>(j);
      } else if (d < b2) {
        b2 = d;
      }
    }
    if (j1 >= 0 && b1 <= maxDistance && (b2 == std::numeric_limits<int>::max() || double(b1) < ratio * double(b2))) {
      cand.push_back({static_cast<int>(i), j1, b1});
    }
  }
  for (const DescriptorMatch& m : cand) {
    if (bestQ[static_cast<std::size_t>(m.train)] == m.query) out.push_back(m);
  }
  return out;
}

}  // namespace hawor
