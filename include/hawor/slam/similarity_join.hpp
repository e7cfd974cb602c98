// hawor/slam/similarity_join.hpp — the similarity that joins a re-initialised monocular map to the
// old one (mono_slam.hpp, after a tracking loss): a new map point x (source frame: the new
// reference camera, the new map's units) must land on its rays in the old keyframes, or on its old
// map point.
//
// Unknowns: scale s, rotation R (started at R₀, the reference frame's rotation from the ray chain)
// and position c, X = s·R·x + c in the old world. With R = R₀·exp(ω) linearised and u = s·ω,
//   X ≈ s·R₀x − R₀[x]×u + c   is linear in (s, u, c) (7 unknowns);
// rows: [d]×(X − C) = 0 for an old observation (unit world ray d from the keyframe centre C), 2
// independent equations; X = X_old for an old point, 3. Each row is weighted by 1/distance so
// residuals are angles; a weak prior (relative to noiseRad) holds ω near 0 (priorRotationRad; the ray chain is good to a
// fraction of a degree frame to frame, a few degrees through a fast turn).
// Gauss–Newton (R₀ updated: R ← R·exp(ω)) inside RANSAC over minimal 4-candidate samples, then on
// the inliers: a candidate is an inlier when every one of its rows is within thresholdRad (and in
// front of the old camera; an old point also within ±20 % of its distance from c).
// The scale's relative standard deviation comes from the normal matrix at noiseRad: old keyframes
// whose centres are close to the new camera leave the scale unobservable (the caller then keeps
// a cruder join).
// Pure function, thread-safe.
#pragma once

#include <Eigen/LU>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/so3.hpp"

namespace hawor {

/// One constraint on a candidate's point: a ray of an old keyframe or an old map point.
template <typename Scalar>
struct SimJoinRow {
  Vec3<Scalar> C;  ///< keyframe centre (world), or the old point itself when `point`
  Vec3<Scalar> d = Vec3<Scalar>::Zero();  ///< unit world ray (unused when `point`)
  bool point = false;
};

/// A candidate: the point in the source frame and its old constraints (at least one).
template <typename Scalar>
struct SimJoinCandidate {
  Vec3<Scalar> x;
  std::vector<SimJoinRow<Scalar>> rows;
};

template <typename Scalar>
struct SimJoinOptions {
  Scalar thresholdRad = Scalar(0.006);     ///< per-row angular inlier threshold (3 px at f = 500)
  Scalar noiseRad = Scalar(0.002);         ///< measurement noise for the scale's std (1 px at f = 500)
  Scalar priorRotationRad = Scalar(0.035); ///< σ of the rotation prior around R₀ (2°)
  Scalar distanceGuess = Scalar(1);        ///< typical point distance in the old world (first weights)
  Scalar scaleGuess = Scalar(1);           ///< s guess (the prior's weight only)
  int iterations = 150;                    ///< RANSAC samples
  std::uint32_t seed = 0x9e3779b9u;
};

template <typename Scalar>
struct SimJoinResult {
  bool solved = false;        ///< a solution with at least 4 inliers was found
  Mat3<Scalar> R = Mat3<Scalar>::Identity();
  Scalar s = Scalar(0);
  Vec3<Scalar> c = Vec3<Scalar>::Zero();
  std::vector<char> inliers;  ///< per candidate
  int numInliers = 0;
  Scalar scaleRelStd = std::numeric_limits<Scalar>::infinity();
  Vec3<Scalar> apply(const Vec3<Scalar>& x) const { return s * (R * x) + c; }
};

namespace simjoin_detail {
template <typename Scalar>
Mat3<Scalar> skew(const Vec3<Scalar>& a) {
  Mat3<Scalar> m;
  m << Scalar(0), -a(2), a(1), a(2), Scalar(0), -a(0), -a(1), a(0), Scalar(0);
  return m;
}
}  // namespace simjoin_detail

/// The similarity (file comment) from candidates, started at rotation R0 and centre c0.
template <typename Scalar>
SimJoinResult<Scalar> estimateSimilarityJoin(const std::vector<SimJoinCandidate<Scalar>>& cands, const Mat3<Scalar>& R0,
                                             const Vec3<Scalar>& c0, const SimJoinOptions<Scalar>& opt = {}) {
  using V3 = Vec3<Scalar>;
  using M3 = Mat3<Scalar>;
  using M7 = Eigen::Matrix<Scalar, 7, 7>;
  using V7 = Eigen::Matrix<Scalar, 7, 1>;
  using M37 = Eigen::Matrix<Scalar, 3, 7>;
  using simjoin_detail::skew;
  struct Est {
    M3 R;
    Scalar s;
    V3 c;
  };
  SimJoinResult<Scalar> res;
  const int nc = static_cast<int>(cands.size());
  res.inliers.assign(cands.size(), 0);
  if (nc < 4) return res;
  const Scalar rho0 = opt.distanceGuess > Scalar(0) ? opt.distanceGuess : Scalar(1);
  const Scalar sg = opt.scaleGuess > Scalar(0) ? opt.scaleGuess : Scalar(1);
  // The rows are angles (unit weight); the prior on ω = u/s is in the same units relative to the
  // measurement noise: (noise/σ_ω)²/s².
  const Scalar wPrior = (opt.noiseRad * opt.noiseRad) / (sg * opt.priorRotationRad * sg * opt.priorRotationRad);
  // One Gauss–Newton step over `which` (weights 1/distance from e when `weighted`, else 1/rho0).
  auto step = [&](const std::vector<int>& which, Est& e, bool weighted, Scalar* relStd) {
    M7 N = M7::Zero();
    V7 b = V7::Zero();
    for (int k : which) {
      const SimJoinCandidate<Scalar>& cd = cands[static_cast<std::size_t>(k)];
      const V3 v = e.R * cd.x;
      const M3 B = -e.R * skew(cd.x);
      for (const SimJoinRow<Scalar>& w : cd.rows) {
        M37 A;
        V3 y;
        if (w.point) {
          A << v, B, M3::Identity();
          y = w.C;
        } else {
          const M3 S = skew(w.d);
          A << S * v, S * B, S;
          y = S * w.C;
        }
        Scalar rho = rho0;
        if (weighted) rho = std::max(Scalar(1e-3) * rho0, (V3(e.s * v + e.c) - (w.point ? e.c : w.C)).norm());
        const Scalar wt = Scalar(1) / (rho * rho);
        N += wt * A.transpose() * A;
        b += wt * A.transpose() * y;
      }
    }
    for (int q = 1; q <= 3; ++q) N(q, q) += wPrior;
    Eigen::FullPivLU<M7> lu(N);
    if (lu.rank() < 7) return false;
    const V7 x = lu.solve(b);
    if (!x.allFinite() || !(x(0) > Scalar(0))) return false;
    const V3 om = x.template segment<3>(1) / x(0);
    e.R = M3(e.R * SO3<Scalar>::exp(om).matrix());
    e.s = x(0);
    e.c = x.template tail<3>();
    if (relStd) *relStd = opt.noiseRad * std::sqrt(std::max(Scalar(0), Scalar(lu.inverse()(0, 0)))) / x(0);
    return true;
  };
  auto inlier = [&](int k, const Est& e) {
    const SimJoinCandidate<Scalar>& cd = cands[static_cast<std::size_t>(k)];
    const V3 X = e.s * (e.R * cd.x) + e.c;
    for (const SimJoinRow<Scalar>& w : cd.rows) {
      if (w.point) {
        const V3 a = X - e.c, bb = w.C - e.c;
        const Scalar na = a.norm(), nb = bb.norm();
        if (!(na > Scalar(0)) || !(nb > Scalar(0)) || std::abs(na / nb - Scalar(1)) > Scalar(0.2) ||
            a.cross(bb).norm() / (na * nb) > opt.thresholdRad) {
          return false;
        }
      } else {
        const V3 a = X - w.C;
        const Scalar na = a.norm();
        if (!(a.dot(w.d) > Scalar(0)) || a.cross(w.d).norm() / na > opt.thresholdRad) return false;
      }
    }
    return !cd.rows.empty();
  };
  const Est e0{R0, sg, c0};
  Est best = e0;
  std::vector<int> bestIn, cur, sample(4);
  std::uint32_t rng = opt.seed;
  for (int it = 0; it < opt.iterations; ++it) {
    for (int q = 0; q < 4; ++q) {
      rng = rng * 1664525u + 1013904223u;
      sample[static_cast<std::size_t>(q)] = static_cast<int>((rng >> 8) % static_cast<std::uint32_t>(nc));
    }
    Est e = e0;
    if (!step(sample, e, false, nullptr) || !step(sample, e, true, nullptr)) continue;
    cur.clear();
    for (int k = 0; k < nc; ++k) {
      if (inlier(k, e)) cur.push_back(k);
    }
    if (cur.size() > bestIn.size()) bestIn = cur, best = e;
  }
  Scalar relStd = std::numeric_limits<Scalar>::infinity();
  for (int round = 0; round < 4 && static_cast<int>(bestIn.size()) >= 4; ++round) {
    Est e = best;
    if (!step(bestIn, e, true, &relStd)) break;
    best = e;
    cur.clear();
    for (int k = 0; k < nc; ++k) {
      if (inlier(k, best)) cur.push_back(k);
    }
    bestIn = cur;
  }
  if (static_cast<int>(bestIn.size()) < 4) return res;
  res.solved = true;
  res.R = best.R;
  res.s = best.s;
  res.c = best.c;
  res.scaleRelStd = relStd;
  res.numInliers = static_cast<int>(bestIn.size());
  for (int k : bestIn) res.inliers[static_cast<std::size_t>(k)] = 1;
  return res;
}

}  // namespace hawor
