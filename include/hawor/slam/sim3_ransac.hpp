// hawor/slam/sim3_ransac.hpp — the similarity between two keyframes' views of the same points:
// the Sim(3) S with P₁ ≈ S·P₂ from matched 3D points in each camera's frame (each from its own
// map, in its own scale), for verifying a place-recognition candidate and joining the two maps.
//
// RANSAC (ransac.hpp, MSAC) over 3-point samples, each solved in closed form (Umeyama,
// alignment.hpp); a match is an inlier when both reprojections fit (ORB-SLAM's Sim3Solver test,
// Mur-Artal & Tardós 2017): ‖π(S·P₂) − u₁‖ and ‖π(S⁻¹·P₁) − u₂‖ below thresholdPx, with π the
// camera's projection and u the points' observed pixels (and, with maxDepthError, when the two
// positions agree in 3D). The winner is re-fitted on its inliers
// (Umeyama; 3D errors weighted by 1/depth², which turns them into image-plane errors) and its
// inliers recounted. A point behind either camera after the transform is no inlier.
// Pure function of its inputs; deterministic for a seed (the same natively and in WASM).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/alignment.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/sim3.hpp"
#include "hawor/slam/ransac.hpp"

namespace hawor {

template <typename Scalar>
struct Sim3RansacOptions {
  Scalar thresholdPx = Scalar(4);  ///< reprojection error of an inlier, in each view
  int maxIterations = 300;
  Scalar confidence = Scalar(0.999);
  int minInliers = 20;             ///< fewer: not found
  /// An inlier's two positions also agree in 3D: ‖S·P₂ − P₁‖ ≤ maxDepthError·z₁ (0: not checked).
  /// Reprojection alone does not see depth when the two cameras are near each other (a head
  /// looking around in place): two maps of little parallax match in the image whatever their
  /// depths, and their Sim(3)'s scale is then arbitrary.
  Scalar maxDepthError = Scalar(0);
  std::uint32_t seed = 0x51a3u;
};

template <typename Scalar>
struct Sim3RansacResult {
  bool found = false;
  Sim3<Scalar> S;              ///< P₁ ≈ S·P₂
  std::vector<char> inliers;   ///< per match
  int numInliers = 0;
};

/// P1[i], P2[i]: the i-th matched point in camera 1's and camera 2's frame; uv1[i], uv2[i]: its
/// observed pixels. All four the same size, or hawor::Error.
template <typename Scalar>
Sim3RansacResult<Scalar> solveSim3Ransac(const std::vector<Vec3<Scalar>>& P1, const std::vector<Vec3<Scalar>>& P2,
                                         const std::vector<Vec2<Scalar>>& uv1, const std::vector<Vec2<Scalar>>& uv2,
                                         const PinholeCamera<Scalar>& cam, const Sim3RansacOptions<Scalar>& opt = {}) {
  using V3 = Vec3<Scalar>;
  const std::size_t n = P1.size();
  if (P2.size() != n || uv1.size() != n || uv2.size() != n) throw Error("solveSim3Ransac: P1, P2, uv1 and uv2 must have one entry per match");
  if (!(opt.thresholdPx > Scalar(0)) || opt.minInliers < 3) throw Error("solveSim3Ransac: thresholdPx must be > 0 and minInliers >= 3");
  Sim3RansacResult<Scalar> res;
  if (static_cast<int>(n) < opt.minInliers) return res;
  const Scalar T2 = opt.thresholdPx * opt.thresholdPx;
  // Squared error of match i: the larger of the two reprojections (infinite behind a camera).
  auto errorSq = [&](const Sim3<Scalar>& S, const Sim3<Scalar>& Si, int i) {
    const V3 a = S * P2[static_cast<std::size_t>(i)];
    const V3 b = Si * P1[static_cast<std::size_t>(i)];
    if (!(a.z() > Scalar(0)) || !(b.z() > Scalar(0))) return std::numeric_limits<Scalar>::infinity();
    if (opt.maxDepthError > Scalar(0) && (a - P1[static_cast<std::size_t>(i)]).norm() > opt.maxDepthError * P1[static_cast<std::size_t>(i)].z()) {
      return std::numeric_limits<Scalar>::infinity();
    }
    const Scalar e1 = (cam.project(a) - uv1[static_cast<std::size_t>(i)]).squaredNorm();
    const Scalar e2 = (cam.project(b) - uv2[static_cast<std::size_t>(i)]).squaredNorm();
    return std::max(e1, e2);
  };
  struct Model {
    Sim3<Scalar> S, Si;
  };
  // Umeyama of P2 onto P1 over `idx` (weights 1/z₁²); false when degenerate.
  auto fit = [&](const int* idx, int m, Model& out) {
    Points3<Scalar> src(m, 3), dst(m, 3);
    VecX<Scalar> w(m);
    for (int k = 0; k < m; ++k) {
      const std::size_t i = static_cast<std::size_t>(idx[k]);
      src.row(k) = P2[i].transpose();
      dst.row(k) = P1[i].transpose();
      w(k) = Scalar(1) / std::max(P1[i].z() * P1[i].z(), Scalar(1e-12));
    }
    try {
      const SimilarityTransform<Scalar> t = umeyama(src, dst, true, &w);
      if (!(t.s > Scalar(0)) || !std::isfinite(double(t.s))) return false;
      out.S = t.toSim3();
      out.Si = out.S.inverse();
      return true;
    } catch (const Error&) {
      return false;
    }
  };
  RansacOptions<Scalar> ro;
  ro.threshold = opt.thresholdPx;
  ro.confidence = opt.confidence;
  ro.maxIterations = opt.maxIterations;
  ro.seed = opt.seed;
  const auto r = ransac<Model, Scalar>(
      static_cast<int>(n), 3,
      [&](const int* s, std::vector<Model>& models) {
        Model m;
        if (fit(s, 3, m)) models.push_back(m);
      },
      [&](const Model& m, int i) { return errorSq(m.S, m.Si, i); }, ro);
  if (!r.found || r.numInliers < opt.minInliers) return res;
  // re-fit on the inliers, recount
  std::vector<int> idx;
  for (std::size_t i = 0; i < n; ++i) {
    if (r.inliers[i]) idx.push_back(static_cast<int>(i));
  }
  Model m = r.model;
  Model refit;
  if (fit(idx.data(), static_cast<int>(idx.size()), refit)) {
    int cnt = 0;
    for (std::size_t i = 0; i < n; ++i) cnt += errorSq(refit.S, refit.Si, static_cast<int>(i)) < T2 ? 1 : 0;
    if (cnt >= r.numInliers) m = refit;
  }
  res.S = m.S;
  res.inliers.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (errorSq(m.S, m.Si, static_cast<int>(i)) < T2) {
      res.inliers[i] = 1;
      ++res.numInliers;
    }
  }
  res.found = res.numInliers >= opt.minInliers;
  return res;
}

}  // namespace hawor
