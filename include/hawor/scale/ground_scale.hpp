// hawor/scale/ground_scale.hpp — a metric scale from the camera's height above the floor, no
// depth network needed: a head-worn camera of a standing adult sits about eyeHeight ≈ 1.6 m above
// the floor, and the SLAM's map sees the floor (and work surfaces) as planes of points. The height
// H of the cameras above the floor plane in map units then gives α = eyeHeight / H. (Monocular
// visual odometry on cars recovers scale from the known camera height above the road the same
// way; here the prior is a person's, so its spread, ±5 %, bounds the accuracy.)
//
//   1. Up direction. Candidate planes by sequential RANSAC on the map points (3-point samples,
//      inlier distance tol = inlierFraction × the median camera-to-point distance). A horizontal
//      plane has its normal n (oriented towards the cameras) perpendicular to the cameras' x axes
//      (people hold their heads with little roll: |x_t·n| ≤ sin maxRollDeg for most frames) and
//      within 90° of their up axes (−y_t·n > 0). Among those the one with most inliers gives u.
//   2. Levels. The points' heights y_i = u·p_i; a level is a cluster of ≥ minLevelPoints heights
//      below the cameras' 10th-percentile height (a peak of their histogram, bin width tol, 3×
//      above the points around, with at least minLevelFraction of the best level's support).
//      The floor is the lowest level; its plane is refitted to the points within ±tol of it
//      (least squares: the normal is the smallest principal axis), which also refines u.
//   3. H = median over frames of u·c_t − floor, α = eyeHeight / H.
//   4. A second level between floor and cameras at a height fraction (y_s − floor) / H in
//      [0.35, 0.65] is a work surface (a table top 0.72–0.92 m high under a 1.6 m eye: 0.45–0.58): it confirms
//      the floor. With a single level the floor cannot in general be told from a table top seen
//      from above; the result is flagged `ambiguous`, carries the table-top reading as
//      `alternativeScale` ((eyeHeight − tableHeight) / H) and half the confidence; fusion with
//      the hand cue picks the reading nearer to the hands' (metric_scale.hpp). Unless the level
//      is too wide for a table: its footprint across its long axis (5–95 % of its points), in
//      camera heights w (scale-free), read as a table top is w·(eyeHeight − tableHeight) metres
//      across; above maxSurfaceWidth (2 m: counters are 0.6 m deep, tables and islands ≤ 1.5 m)
//      it is the floor (walking through a room: w ≈ 3, a 2.5 m "table"; the kitchen clip's table
//      top: w ≈ 1.6).
// Confidence: 1 / (1 + (e / 0.05)²) with the relative error e² = eyeHeightRelStd² + (spread of
// the per-frame heights, MAD / median)², scaled by min(1, floorPoints / 30), halved when ambiguous.
// Limits: a sitting wearer (set eyeHeight ≈ 1.2 m), a floor never in view, a map whose scale drifts
// between segments (the per-frame heights then spread, and the confidence drops).
// Thread-safety: pure functions (the RANSAC draws from its own seeded generator).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>

#include "hawor/common.hpp"
#include "hawor/scale/confidence.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/slam/ransac.hpp"

namespace hawor {

template <typename Scalar>
struct GroundScaleOptions {
  Scalar eyeHeight = Scalar(1.6);          ///< camera height above the floor (m), standing adult
  Scalar eyeHeightRelStd = Scalar(0.05);   ///< its relative spread over people
  Scalar tableHeight = Scalar(0.8);        ///< a work surface's height (m), for the ambiguous reading
  Scalar maxRollDeg = Scalar(20);          ///< head roll allowed by the horizontality test
  Scalar inlierFraction = Scalar(0.02);    ///< plane tolerance / median camera-to-point distance
  int ransacIterations = 300;              ///< per candidate plane
  int maxPlanes = 6;                       ///< candidate planes of the sequential RANSAC
  int minLevelPoints = 12;                 ///< points that make a level (and a candidate plane)
  Scalar minLevelFraction = Scalar(0.05);  ///< a level's support, at least this × the best level's
  Scalar maxSurfaceWidth = Scalar(2);      ///< a work surface's narrow side (m), at most
  std::uint32_t seed = 7;
};

template <typename Scalar>
struct GroundScaleResult {
  Scalar scale = std::numeric_limits<Scalar>::quiet_NaN();  ///< metres per map unit
  Scalar confidence = Scalar(0);
  Scalar height = std::numeric_limits<Scalar>::quiet_NaN();  ///< median camera height, map units
  Scalar heightSpread = std::numeric_limits<Scalar>::quiet_NaN();  ///< relative (MAD / median)
  Vec3<Scalar> up = Vec3<Scalar>::Zero();  ///< world up (unit), map frame
  Scalar floorLevel = std::numeric_limits<Scalar>::quiet_NaN();  ///< the floor plane up·X = floorLevel, map units
  int floorPoints = 0, levels = 0;
  Scalar surfaceHeight = std::numeric_limits<Scalar>::quiet_NaN();  ///< work surface (m), if seen
  bool ambiguous = false;                  ///< one level only: floor or table top
  Scalar alternativeScale = std::numeric_limits<Scalar>::quiet_NaN();  ///< the table-top reading
  /// The floor level's footprint: the 5–95 % range of its points across their long axis (their
  /// narrower horizontal extent), in camera heights above it (scale-free).
  Scalar floorWidth = std::numeric_limits<Scalar>::quiet_NaN();
  std::string reason;                      ///< why there is no scale (empty when ok)
  bool ok() const { return std::isfinite(double(scale)) && scale > Scalar(0); }
};

namespace ground_detail {

/// Least-squares plane through points: centroid and unit normal (smallest principal axis).
template <typename Scalar>
void fitPlane(const std::vector<Vec3<Scalar>>& p, Vec3<Scalar>& centroid, Vec3<Scalar>& normal) {
  centroid.setZero();
  for (const auto& x : p) centroid += x;
  centroid /= Scalar(p.size());
  Mat3<Scalar> C = Mat3<Scalar>::Zero();
  for (const auto& x : p) C += (x - centroid) * (x - centroid).transpose();
  Eigen::SelfAdjointEigenSolver<Mat3<Scalar>> es(C);
  normal = es.eigenvectors().col(0).normalized();
}

/// The 5–95 % range of the points along the horizontal axis across their long axis (up: unit
/// normal of the plane they lie in); NaN for fewer than 3 points.
template <typename Scalar>
Scalar narrowWidth(const std::vector<Vec3<Scalar>>& p, const Vec3<Scalar>& up) {
  if (p.size() < 3) return std::numeric_limits<Scalar>::quiet_NaN();
  using V2 = Eigen::Matrix<Scalar, 2, 1>;
  const Vec3<Scalar> e1 = up.unitOrthogonal(), e2 = up.cross(e1);
  std::vector<V2> q;  // horizontal coordinates, centred below
  q.reserve(p.size());
  V2 m = V2::Zero();
  for (const auto& x : p) q.emplace_back(e1.dot(x), e2.dot(x)), m += q.back();
  m /= Scalar(p.size());
  Eigen::Matrix<Scalar, 2, 2> C = Eigen::Matrix<Scalar, 2, 2>::Zero();
  for (V2& v : q) v -= m, C += v * v.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<Scalar, 2, 2>> es(C);
  const V2 minor = es.eigenvectors().col(0);  // smallest eigenvalue first
  std::vector<double> a;
  a.reserve(q.size());
  for (const V2& v : q) a.push_back(double(minor.dot(v)));
  return Scalar(percentile(a, 0.95) - percentile(a, 0.05));
}

}  // namespace ground_detail

/// The ground-plane scale (file comment) of a map: `points` in the world frame (map units),
/// `T_w_c` the camera-to-world pose of every frame. Never throws for data (non-finite points and
/// poses are skipped); a missing answer has ok() == false and a `reason`. Throws for bad options.
template <typename Scalar>
GroundScaleResult<Scalar> groundPlaneScale(const std::vector<Vec3<Scalar>>& points,
                                           const std::vector<SE3<Scalar>>& T_w_c,
                                           const GroundScaleOptions<Scalar>& opt = {}) {
  using V3 = Vec3<Scalar>;
  if (!(opt.eyeHeight > Scalar(0)) || !(opt.tableHeight >= Scalar(0)) || !(opt.tableHeight < opt.eyeHeight) ||
      !(opt.eyeHeightRelStd >= Scalar(0)) || !(opt.maxRollDeg > Scalar(0) && opt.maxRollDeg < Scalar(90)) ||
      !(opt.inlierFraction > Scalar(0)) || opt.ransacIterations < 1 || opt.maxPlanes < 1 || opt.minLevelPoints < 3 ||
      !(opt.minLevelFraction >= Scalar(0) && opt.minLevelFraction <= Scalar(1)) || !(opt.maxSurfaceWidth > Scalar(0))) {
    throw Error("ground scale: invalid options (eyeHeight > tableHeight >= 0, 0 < maxRollDeg < 90, minLevelFraction in [0, 1], ...)");
  }
  GroundScaleResult<Scalar> r;
  std::vector<V3> P, centres, xAxes, upAxes;
  for (const auto& p : points) {
    if (p.allFinite()) P.push_back(p);
  }
  for (const auto& T : T_w_c) {
    const Mat3<Scalar> R = T.rotationMatrix();
    if (!R.allFinite() || !T.translation().allFinite()) continue;
    centres.push_back(T.translation());
    xAxes.push_back(R.col(0));
    upAxes.push_back(-R.col(1));  // camera y points down in the image
  }
  if (centres.empty()) return r.reason = "no camera poses", r;
  if (static_cast<int>(P.size()) < 3 * opt.minLevelPoints) return r.reason = "too few map points", r;

  // Scene scale: the median distance from a camera to the points (cameras subsampled).
  std::vector<Scalar> dist;
  const std::size_t camStep = std::max<std::size_t>(1, centres.size() / 16);
  for (std::size_t t = 0; t < centres.size(); t += camStep) {
    for (const auto& p : P) dist.push_back((p - centres[t]).norm());
  }
  const Scalar tol = opt.inlierFraction * median(dist);
  if (!(tol > Scalar(0))) return r.reason = "degenerate map (all points at the cameras)", r;

  // 1. Candidate planes; the largest horizontal one gives u.
  const Scalar sinRoll = std::sin(opt.maxRollDeg * Scalar(M_PI / 180));
  std::mt19937 rng(opt.seed);
  std::vector<char> used(P.size(), 0);
  V3 up = V3::Zero();
  int bestHorizontal = 0;
  for (int plane = 0; plane < opt.maxPlanes; ++plane) {
    std::vector<int> free;
    for (std::size_t i = 0; i < P.size(); ++i) {
      if (!used[i]) free.push_back(static_cast<int>(i));
    }
    if (static_cast<int>(free.size()) < opt.minLevelPoints) break;
    int bestCount = 0;
    V3 bestN = V3::Zero();
    Scalar bestD = 0;
    int s[3];
    for (int it = 0; it < opt.ransacIterations; ++it) {
      ransac_detail::drawSample(rng, static_cast<int>(free.size()), 3, s);
      const V3 &a = P[static_cast<std::size_t>(free[static_cast<std::size_t>(s[0])])],
               &b = P[static_cast<std::size_t>(free[static_cast<std::size_t>(s[1])])],
               &c = P[static_cast<std::size_t>(free[static_cast<std::size_t>(s[2])])];
      V3 n = (b - a).cross(c - a);
      if (!(n.norm() > Scalar(0))) continue;
      n.normalize();
      const Scalar d = -n.dot(a);
      int count = 0;
      for (int i : free) count += std::abs(n.dot(P[static_cast<std::size_t>(i)]) + d) < tol;
      if (count > bestCount) bestCount = count, bestN = n, bestD = d;
    }
    if (bestCount < opt.minLevelPoints) break;
    for (int i : free) {
      if (std::abs(bestN.dot(P[static_cast<std::size_t>(i)]) + bestD) < tol) used[static_cast<std::size_t>(i)] = 1;
    }
    // Orient towards the cameras; test horizontality on the frames (most must pass).
    std::vector<Scalar> side;
    for (const auto& c : centres) side.push_back(bestN.dot(c) + bestD);
    if (median(side) < Scalar(0)) bestN = -bestN;
    int level = 0, upright = 0;
    for (std::size_t t = 0; t < centres.size(); ++t) {
      level += std::abs(xAxes[t].dot(bestN)) <= sinRoll;
      upright += upAxes[t].dot(bestN) > Scalar(0);
    }
    const bool horizontal = 10 * level >= 8 * static_cast<int>(centres.size()) &&
                            10 * upright >= 8 * static_cast<int>(centres.size());
    if (horizontal && bestCount > bestHorizontal) bestHorizontal = bestCount, up = bestN;
  }
  if (bestHorizontal == 0) return r.reason = "no horizontal surface in the map", r;

  // 2. Levels below the cameras along u, lowest = floor; refit the floor plane, refine u, redo.
  Scalar floorY = 0;
  std::vector<std::pair<Scalar, int>> levels;  // (height, support), ascending
  std::vector<V3> floorLevelPts;
  for (int pass = 0; pass < 2; ++pass) {
    // The cameras' height band: the 10th to 90th percentile of their heights, not the extremes,
    // so that a few wild poses (a segment the SLAM could not join, far below the rest) do not
    // move every surface "above the cameras".
    std::vector<double> camY;
    for (const auto& c : centres) camY.push_back(double(up.dot(c)));
    const Scalar camLow = Scalar(percentile(camY, 0.1)), camHigh = Scalar(percentile(camY, 0.9));
    // Levels from a histogram of bin width tol over all the points' heights (a level must be a
    // peak among its neighbours, also those at and above the cameras, so that the points' density
    // falling off below the cameras is no level): the support of bin b is the count of bins
    // b−1..b+1 (a ±1.5·tol window); a level is a bin with at least minLevelPoints support and no
    // more-supported bin within two bins (ties go to the lower), at the mean height of its window,
    // lower than the cameras by tol. Heights further than 20 scene distances from the cameras are
    // wild points, not surfaces.
    const Scalar reach = Scalar(20) * tol / opt.inlierFraction;
    std::vector<Scalar> y;
    for (const auto& p : P) {
      const Scalar v = up.dot(p);
      if (v >= camLow - reach && v <= camHigh + reach) y.push_back(v);
    }
    int below = 0;
    for (Scalar v : y) below += v < camLow - tol;
    if (below < opt.minLevelPoints) return r.reason = "no surface below the cameras", r;
    const Scalar y0 = *std::min_element(y.begin(), y.end());
    const int bins = static_cast<int>(std::ceil((*std::max_element(y.begin(), y.end()) - y0) / tol)) + 1;
    std::vector<int> count(static_cast<std::size_t>(bins), 0);
    std::vector<Scalar> sum(static_cast<std::size_t>(bins), Scalar(0));
    for (Scalar v : y) {
      const int b = std::min(bins - 1, static_cast<int>((v - y0) / tol));
      ++count[static_cast<std::size_t>(b)], sum[static_cast<std::size_t>(b)] += v;
    }
    auto window = [&](int b, Scalar* mean) {
      int n = 0;
      Scalar sy = 0;
      for (int k = std::max(0, b - 1); k <= std::min(bins - 1, b + 1); ++k) {
        n += count[static_cast<std::size_t>(k)], sy += sum[static_cast<std::size_t>(k)];
      }
      if (mean && n > 0) *mean = sy / Scalar(n);
      return n;
    };
    // A level must also stand out of the points around it (a random cloud has no levels): at
    // least 3× the median window count 4–10 bins away on either side (bins outside count as
    // empty; the median, so that another level nearby does not count as background).
    auto background = [&](int b) {
      std::vector<Scalar> ring;
      for (int k = b - 10; k <= b + 10; ++k) {
        if (std::abs(k - b) >= 4) ring.push_back(k >= 0 && k < bins ? Scalar(window(k, nullptr)) : Scalar(0));
      }
      return median(ring);
    };
    levels.clear();
    for (int b = 0; b < bins; ++b) {
      const int sb = window(b, nullptr);
      if (sb < opt.minLevelPoints || Scalar(sb) < Scalar(3) * background(b)) continue;
      bool peak = true;
      for (int k = std::max(0, b - 2); k <= std::min(bins - 1, b + 2) && peak; ++k) {
        const int sk = window(k, nullptr);
        if (k != b && (sk > sb || (sk == sb && k < b))) peak = false;
      }
      Scalar mean = 0;
      if (peak) window(b, &mean);
      if (peak && mean < camLow - tol) levels.emplace_back(mean, sb);
    }
    // A surface is seen from many keyframes: a level with under minLevelFraction of the best
    // level's support is a cluster of stray points (hands_cover seed 1: 20 points 1.7 floor
    // heights down, beside 2178 on the floor and 2329 on the table).
    int bestSupport = 0;
    for (const auto& L : levels) bestSupport = std::max(bestSupport, L.second);
    levels.erase(std::remove_if(levels.begin(), levels.end(),
                                [&](const std::pair<Scalar, int>& L) { return Scalar(L.second) < opt.minLevelFraction * Scalar(bestSupport); }),
                 levels.end());
    if (levels.empty()) return r.reason = "no surface below the cameras holds enough points", r;
    floorY = levels.front().first;
    std::vector<V3> floorPts;
    for (const auto& p : P) {
      if (std::abs(up.dot(p) - floorY) <= tol) floorPts.push_back(p);
    }
    r.floorPoints = static_cast<int>(floorPts.size());
    floorLevelPts = floorPts;
    if (pass == 1 || floorPts.size() < 3) break;
    V3 centroid, n;
    ground_detail::fitPlane(floorPts, centroid, n);
    if (n.dot(up) < Scalar(0)) n = -n;
    if (n.dot(up) < std::cos(Scalar(10 * M_PI / 180))) break;  // the refit tilts too far: keep u
    up = n;
  }

  // 3. Camera heights above the floor.
  std::vector<Scalar> h;
  for (const auto& c : centres) h.push_back(up.dot(c) - floorY);
  const Scalar H = median(h);
  if (!(H > Scalar(0))) return r.reason = "the cameras are not above the floor", r;
  r.height = H;
  r.heightSpread = madSigma(h, H) / H;
  r.up = up;
  r.floorLevel = floorY;
  r.levels = static_cast<int>(levels.size());
  r.scale = opt.eyeHeight / H;
  r.floorWidth = ground_detail::narrowWidth(floorLevelPts, up) / H;

  // 4. A work surface confirms the floor; one level alone is ambiguous.
  bool surface = false;
  for (std::size_t k = 1; k < levels.size() && !surface; ++k) {
    const Scalar f = (levels[k].first - floorY) / H;
    if (f >= Scalar(0.35) && f <= Scalar(0.65)) surface = true, r.surfaceHeight = f * opt.eyeHeight;
  }
  r.ambiguous = levels.size() == 1 &&
                !(r.floorWidth * (opt.eyeHeight - opt.tableHeight) > opt.maxSurfaceWidth);  // NaN width: ambiguous
  if (r.ambiguous) r.alternativeScale = (opt.eyeHeight - opt.tableHeight) / H;
  const Scalar e2 = opt.eyeHeightRelStd * opt.eyeHeightRelStd + r.heightSpread * r.heightSpread;
  Scalar conf = Scalar(1) / (Scalar(1) + e2 / Scalar(0.0025));
  conf *= std::min(Scalar(1), Scalar(r.floorPoints) / Scalar(30));
  if (r.ambiguous) conf *= Scalar(0.5);
  r.confidence = conf;
  return r;
}

/// The reading of `g` to fuse beside another scale estimate `near` of confidence `nearConfidence`
/// (e.g. the hands'): the floor reading, or when the level is ambiguous and the table-top reading
/// is nearer `near` in log and agrees with it within 3 standard errors (confidence.hpp's mapping
/// of confidences to errors), that one: a cue that agrees with neither reading cannot choose
/// between them. NaN when `g` has no scale; the floor reading when `near` is not a positive number.
template <typename Scalar>
Scalar groundReadingNear(const GroundScaleResult<Scalar>& g, Scalar near, Scalar nearConfidence = Scalar(1)) {
  if (!g.ok()) return std::numeric_limits<Scalar>::quiet_NaN();
  if (g.ambiguous && std::isfinite(double(near)) && near > Scalar(0) && g.alternativeScale > Scalar(0)) {
    const bool nearer = std::abs(std::log(double(g.alternativeScale / near))) < std::abs(std::log(double(g.scale / near)));
    if (nearer && scalesAgree(double(g.alternativeScale), double(g.confidence), double(near), double(nearConfidence))) return g.alternativeScale;
  }
  return g.scale;
}

}  // namespace hawor
