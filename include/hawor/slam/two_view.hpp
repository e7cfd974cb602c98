// hawor/slam/two_view.hpp — robust two-view initialisation of a monocular map: relative pose and
// first 3D points from normalised correspondences, in the manner of ORB-SLAM's initializer
// (Mur-Artal et al. 2015, §IV) with the 5-point essential matrix in place of the 8-point
// fundamental matrix.
//
//  1. Essential matrix (5-point, essential.hpp) and homography (4-point normalised DLT,
//     homography.hpp, refitted on its inliers) are each estimated by MSAC (ransac.hpp) on the
//     squared distance in the joint image space: the Sampson error for E, (e1² + e2²)/4 for H
//     (e_k the transfer error into image k; each mixes the noise of both images).
//  2. Model selection by the geometry: Torr's GRIC (Torr 1998, "Geometric motion segmentation and
//     model selection"), r = 4 (two 2D points), λ1 = ln 4, λ2 = ln(4n), λ3 = 2:
//       GRIC = Σ_i min(e_i²/σ², λ3·(r − d)) + λ1·d·n + λ2·k,   E: d = 3, k = 5;  H: d = 2, k = 8,
//     e² the squared distance to the model in the joint image space (E: Sampson error; H: the
//     mean of the two transfer errors over 2), σ the pixel noise. The sum runs over the points
//     that are inliers to E or to H (points that fit neither carry no information about the
//     choice and would only add the dimension penalty). The lower GRIC wins: a planar scene or a
//     pure rotation is explained by H with one dimension less per point, a 3D scene is not.
//     Except (essentialOverPlane): when H wins but E has essentialOverPlaneInliers × its inliers
//     and one of E's motions (3.) triangulates more good points than any of H's, E is taken: at
//     low parallax a scene only nearly planar can win GRIC for H, whose decompositions are then
//     approximations that leave the points off the plane unexplained.
//  3. Motions: 4 from E (decomposeEssential), up to 8 from H (decomposeHomography). Each is scored
//     by triangulating the inliers (DLT, triangulation.hpp): a point is good when it is in front
//     of both cameras, reprojects within maxReprojPx in both views and has a parallax of at least
//     minPointParallaxDeg. The best motion needs minTriangulated good points and must beat the
//     second best clearly (second ≤ ambiguityRatio × best), else Ambiguous — unless further
//     views of the correspondences are given (x3, optional): then every candidate within the
//     ratio resects each further view against its points (PnP-RANSAC) and is scored by the MSAC
//     cost per observation, Σ min(e², T²)/n, of the reprojection errors there (T = thresholdPx),
//     averaged over the views. A planar scene (a table top seen from above) gives a homography
//     with two valid decompositions (the plane normal and the translation swap roles, Faugeras &
//     Lustman 1988) that no two-view test can tell apart; a camera position off the pair's line
//     of motion generally fits only the true plane. The candidate whose cost is at most
//     ambiguityRatio × the next one's wins; otherwise Ambiguous.
//  4. In front: at least minInFrontRatio of the model's inliers must be in front of both cameras
//     and reproject under the best motion (any parallax; ORB-SLAM's 0.9·N), else NotEnoughInliers
//     with the rays' rotation: a group of tracks that jumped together can make a wrong motion the
//     best-scoring one, with its own large parallax and depths of a few baselines.
//     Parallax: the median parallax of the best motion's points (all in front, any parallax) must
//     reach minParallaxDeg, else NotEnoughParallax. When no motion triangulates enough points,
//     the rotation-compensated ray angle ∠(x1, R21ᵀ·x2) (the triangulation angle for exact data)
//     is taken at the median over the inliers for each rotation the model allows (for H also the
//     rotation nearest to H itself: the pure-rotation explanation): below minParallaxDeg the
//     status is NotEnoughParallax, else NotEnoughInliers. With NotEnoughParallax the pose holds
//     the rotation that best aligns the inlier rays (Kabsch on unit rays) and t = 0: the rotation
//     of a rotation-only motion is still usable.
//  5. Refinement (optional): bundle adjustment (bundle_adjustment.hpp) of the second pose and the
//     good points, first camera fixed, Huber loss, rescaled so that |t| = 1; then the inliers are
//     re-classified by the Sampson error of the refined motion (new ones triangulated) and, if
//     they changed, the adjustment is run once more.
// Output frame: camera 1 is the world (docs/design.md §2: the first keyframe); T_c1_c2 is the camera-to-
// world pose of camera 2 with ‖t‖ = 1 (monocular scale); points are in camera-1 coordinates.
// Inputs are normalised coordinates x = K⁻¹(u, v, 1); pixel thresholds are converted with focalPx.
// Pure function, thread-safe.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/slam/bundle_adjustment.hpp"
#include "hawor/slam/essential.hpp"
#include "hawor/slam/homography.hpp"
#include "hawor/slam/pnp_ransac.hpp"
#include "hawor/slam/ransac.hpp"
#include "hawor/slam/triangulation.hpp"

namespace hawor {

enum class TwoViewStatus {
  Ok,
  TooFewPoints,       ///< fewer than 8 correspondences
  Degenerate,         ///< no model could be fitted (e.g. all points identical)
  NotEnoughParallax,  ///< rotation-only or too small a baseline: R is set, t = 0, no points
  NotEnoughInliers,   ///< too few points could be triangulated
  Ambiguous,          ///< two motions explain the data about equally well
};

enum class TwoViewModel { None, Essential, Homography };

template <typename Scalar>
struct TwoViewOptions {
  Scalar focalPx = Scalar(500);        ///< focal length converting pixel thresholds to normalised
  Scalar sigmaPx = Scalar(1);          ///< pixel noise σ (model-selection scores, refinement)
  /// RANSAC threshold on the joint-image-space distance: E (Sampson, 1 dof) uses it as is, H (2 dof)
  /// ×√(5.99/3.84), the same χ² confidence (2 px ≈ 95 % of inliers at σ = 1 px).
  Scalar thresholdPx = Scalar(2);
  Scalar confidence = Scalar(0.999);
  int maxIterations = 500;             ///< per model
  std::uint32_t seed = 0x5eedu;
  Scalar minParallaxDeg = Scalar(1);       ///< median ray parallax needed to initialise
  Scalar minPointParallaxDeg = Scalar(0.5);  ///< parallax of a point to be triangulated
  Scalar maxReprojPx = Scalar(2);          ///< per-view reprojection error of a triangulated point
  int minTriangulated = 30;
  /// Inliers in front of both cameras and reprojecting (any parallax) under the best motion, at
  /// least this fraction of the model's inliers (ORB-SLAM: 0.9, with a looser reprojection test).
  Scalar minInFrontRatio = Scalar(0.7);
  Scalar ambiguityRatio = Scalar(0.75);
  int minThirdView = 20;                ///< observations of a candidate's points a further view needs to score it
  /// H chosen by GRIC, but one of E's motions triangulates more good points than any of H's: E
  /// instead (a scene only nearly planar at low parallax).
  bool essentialOverPlane = true;
  Scalar essentialOverPlaneInliers = Scalar(1.15);  ///< … when E has at least this × H's inliers (points off the plane)
  bool refine = true;
  int refineIterations = 15;
};

template <typename Scalar>
struct TwoViewResult {
  TwoViewStatus status = TwoViewStatus::TooFewPoints;
  TwoViewModel model = TwoViewModel::None;
  SE3<Scalar> T_c1_c2;                 ///< camera 2 → camera 1 (= world), ‖t‖ = 1 (0: no parallax)
  std::vector<char> inliers;           ///< inliers of the selected model
  int numInliers = 0;
  std::vector<Vec3<Scalar>> points;    ///< camera-1 frame; meaningful where triangulated[i]
  std::vector<char> triangulated;
  int numTriangulated = 0;
  int numInFront = 0;                  ///< inliers in front of both cameras and reprojecting, any parallax (best motion)
  /// Median parallax (degrees): of the triangulated points when a motion was found; otherwise the
  /// median over the inliers of the rotation-compensated ray angle ∠(x1, R21ᵀx2).
  Scalar medianParallaxDeg = Scalar(0);
  Scalar gricEssential = Scalar(0);   ///< GRIC of E (lower is better; 0 if E was not found)
  Scalar gricHomography = Scalar(0);  ///< GRIC of H (lower is better; 0 if H was not found)
  Mat3<Scalar> E = Mat3<Scalar>::Zero();    ///< essential matrix (x2ᵀ E x1 = 0), if estimated
  Mat3<Scalar> H = Mat3<Scalar>::Zero();    ///< homography (x2 ∝ H x1), if estimated
  /// Further views: candidates scored (0: none) and the winner's / runner-up's MSAC costs per
  /// observation (px², averaged over the views).
  int thirdViewCandidates = 0;
  Scalar thirdViewCost = Scalar(0), thirdViewRunnerUp = Scalar(0);
  bool essentialOverPlane = false;     ///< GRIC chose H, E taken instead (TwoViewOptions::essentialOverPlane)
  bool ok() const { return status == TwoViewStatus::Ok; }
};

namespace two_view_detail {

template <typename Scalar>
Scalar upperMedian(std::vector<Scalar>& v) {  // in place; 0 when empty (hawor::median averages the middle two)
  if (v.empty()) return Scalar(0);
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  return v[m];
}

/// Median over the inliers of ∠(x1, R21ᵀ·x2) in degrees.
template <typename Scalar>
Scalar medianRayAngleDeg(const std::vector<Vec2<Scalar>>& x1, const std::vector<Vec2<Scalar>>& x2,
                         const std::vector<char>& inl, const Mat3<Scalar>& R21) {
  using V3 = Eigen::Matrix<Scalar, 3, 1>;
  std::vector<Scalar> a;
  a.reserve(x1.size());
  const Mat3<Scalar> Rt = R21.transpose();
  for (std::size_t i = 0; i < x1.size(); ++i) {
    if (!inl[i]) continue;
    const V3 f1 = V3(x1[i](0), x1[i](1), Scalar(1)).normalized();
    const V3 f2 = (Rt * V3(x2[i](0), x2[i](1), Scalar(1))).normalized();
    const Scalar c = std::min(Scalar(1), std::max(Scalar(-1), f1.dot(f2)));
    a.push_back(std::acos(c) * Scalar(180) / Constants<Scalar>::pi());
  }
  return upperMedian(a);
}

/// The rotation R21 minimising Σ_inliers ‖f2 − R·f1‖² over unit rays f = (x, 1)/‖(x, 1)‖ (Kabsch):
/// the motion under the pure-rotation hypothesis. `fallback` is returned for degenerate input.
template <typename Scalar>
Mat3<Scalar> rotationFromRays(const std::vector<Vec2<Scalar>>& x1, const std::vector<Vec2<Scalar>>& x2,
                              const std::vector<char>& inl, const Mat3<Scalar>& fallback) {
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  int m = 0;
  for (std::size_t i = 0; i < x1.size(); ++i) {
    if (!inl[i]) continue;
    const Eigen::Vector3d f1 = Eigen::Vector3d(double(x1[i](0)), double(x1[i](1)), 1.0).normalized();
    const Eigen::Vector3d f2 = Eigen::Vector3d(double(x2[i](0)), double(x2[i](1)), 1.0).normalized();
    C.noalias() += f2 * f1.transpose();
    ++m;
  }
  if (m < 2 || !C.allFinite()) return fallback;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(C, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (!(svd.singularValues()(1) > 1e-9 * svd.singularValues()(0))) return fallback;
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) D(2, 2) = -1.0;
  return (svd.matrixU() * D * svd.matrixV().transpose()).cast<Scalar>();
}

/// cos ∠(R·f1, f2) of unit rays f = (x, 1)/‖(x, 1)‖: how far a match is from the rotation R.
template <typename Scalar>
Scalar rotatedRayCos(const Mat3<Scalar>& R, const Vec2<Scalar>& x1, const Vec2<Scalar>& x2) {
  const Vec3<Scalar> f1 = (R * Vec3<Scalar>(x1(0), x1(1), Scalar(1))).normalized();
  const Vec3<Scalar> f2 = Vec3<Scalar>(x2(0), x2(1), Scalar(1)).normalized();
  return f1.dot(f2);
}

/// The rays' rotation with one re-weighting pass: Kabsch on all of them, then again on those whose
/// rotated ray is within maxDeg of its match (a tracking error or the parallax of a near point
/// would pull the fit). R = R21 (f2 ≈ R21·f1); returns how many rays the second fit kept.
template <typename Scalar>
int rotationFromRaysReweighted(const std::vector<Vec2<Scalar>>& x1, const std::vector<Vec2<Scalar>>& x2, Scalar maxDeg,
                               Mat3<Scalar>& R) {
  std::vector<char> inl(x1.size(), 1);
  R = rotationFromRays(x1, x2, inl, Mat3<Scalar>(Mat3<Scalar>::Identity()));
  const Scalar cosT = std::cos(maxDeg * Constants<Scalar>::pi() / Scalar(180));
  int kept = 0;
  for (std::size_t i = 0; i < x1.size(); ++i) {
    inl[i] = rotatedRayCos(R, x1[i], x2[i]) >= cosT ? 1 : 0;
    kept += inl[i];
  }
  R = rotationFromRays(x1, x2, inl, R);
  return kept;
}

template <typename Scalar>
struct MotionScore {
  int good = 0;                     ///< in front, reprojecting, parallax ≥ minPointParallaxDeg
  std::vector<Vec3<Scalar>> X;
  std::vector<char> ok;
  std::vector<Scalar> parallaxDeg;  ///< of every point in front and reprojecting
};

}  // namespace two_view_detail

/// Two-view initialisation (file comment) from normalised correspondences x1[i] ↔ x2[i]; x3
/// (optional): the same correspondences in further views, one vector per view (normalised,
/// non-finite where not seen), used only to resolve an ambiguity. Throws hawor::Error for mismatched sizes,
/// non-finite coordinates in x1/x2 or invalid options; every other failure is a status.
template <typename Scalar>
TwoViewResult<Scalar> initializeTwoView(const std::vector<Vec2<Scalar>>& x1,
                                        const std::vector<Vec2<Scalar>>& x2,
                                        const TwoViewOptions<Scalar>& opt = {},
                                        const std::vector<std::vector<Vec2<Scalar>>>* x3 = nullptr) {
  using M3 = Eigen::Matrix<Scalar, 3, 3>;
  using namespace two_view_detail;
  if (x1.size() != x2.size()) {
    throw Error("initializeTwoView: " + std::to_string(x1.size()) + " points in view 1 but " +
                std::to_string(x2.size()) + " in view 2");
  }
  for (std::size_t v = 0; x3 && v < x3->size(); ++v) {
    if ((*x3)[v].size() != x1.size()) {
      throw Error("initializeTwoView: " + std::to_string(x1.size()) + " points in view 1 but " +
                  std::to_string((*x3)[v].size()) + " in further view " + std::to_string(v));
    }
  }
  for (std::size_t i = 0; i < x1.size(); ++i) {
    if (!x1[i].allFinite() || !x2[i].allFinite()) {
      throw Error("initializeTwoView: correspondence " + std::to_string(i) + " is not finite");
    }
  }
  if (!(opt.focalPx > Scalar(0)) || !(opt.sigmaPx > Scalar(0)) || !(opt.thresholdPx > Scalar(0)) ||
      !(opt.maxReprojPx > Scalar(0)) || !std::isfinite(opt.focalPx) || !std::isfinite(opt.sigmaPx) ||
      !std::isfinite(opt.thresholdPx) || !std::isfinite(opt.maxReprojPx)) {
    throw Error("initializeTwoView: focalPx, sigmaPx, thresholdPx and maxReprojPx must be finite and > 0");
  }
  TwoViewResult<Scalar> res;
  const int n = static_cast<int>(x1.size());
  if (n < 8) return res;  // TooFewPoints

  // All points (nearly) identical in one view: nothing can be estimated.
  {
    Scalar s1 = Scalar(0), s2 = Scalar(0);
    for (int i = 1; i < n; ++i) {
      s1 = std::max(s1, (x1[static_cast<std::size_t>(i)] - x1[0]).cwiseAbs().maxCoeff());
      s2 = std::max(s2, (x2[static_cast<std::size_t>(i)] - x2[0]).cwiseAbs().maxCoeff());
    }
    const Scalar tiny = opt.sigmaPx / opt.focalPx;
    if (!(s1 > tiny) || !(s2 > tiny)) {
      res.status = TwoViewStatus::Degenerate;
      return res;
    }
  }
  const Scalar f = opt.focalPx;
  const Scalar thrE = opt.thresholdPx / f;
  const Scalar thrH = opt.thresholdPx * std::sqrt(Scalar(5.99) / Scalar(3.84)) / f;

  // --- 1. E and H by MSAC -------------------------------------------------------------------------
  RansacOptions<Scalar> ro;
  ro.confidence = opt.confidence;
  ro.maxIterations = opt.maxIterations;
  ro.seed = opt.seed;
  ro.threshold = thrE;
  auto solveE = [&](const int* s, std::vector<Mat3<Scalar>>& models) {
    Vec2<Scalar> a[5], b[5];
    for (int k = 0; k < 5; ++k) {
      a[k] = x1[static_cast<std::size_t>(s[k])];
      b[k] = x2[static_cast<std::size_t>(s[k])];
    }
    essentialFivePoint(a, b, models);
  };
  auto errE = [&](const Mat3<Scalar>& E, int i) {
    return sampsonErrorSq(E, x1[static_cast<std::size_t>(i)], x2[static_cast<std::size_t>(i)]);
  };
  const auto rE = ransac<Mat3<Scalar>, Scalar>(n, 5, solveE, errE, ro);

  struct HModel {
    Mat3<Scalar> H = Mat3<Scalar>::Identity(), Hinv = Mat3<Scalar>::Identity();
  };
  auto makeH = [](const Mat3<Scalar>& H, HModel& m) {
    const Eigen::FullPivLU<M3> lu{M3(H)};
    if (!lu.isInvertible()) return false;
    m.H = H;
    m.Hinv = lu.inverse();
    return m.Hinv.allFinite();
  };
  auto solveH = [&](const int* s, std::vector<HModel>& models) {
    Mat3<Scalar> H;
    HModel m;
    if (homographyDLT(x1, x2, s, 4, H) && makeH(H, m)) models.push_back(m);
  };
  auto errH = [&](const HModel& m, int i) {
    Scalar e1, e2;
    homographyTransferErrorsSq(m.H, m.Hinv, x1[static_cast<std::size_t>(i)],
                               x2[static_cast<std::size_t>(i)], e1, e2);
    return Scalar(0.25) * (e1 + e2);  // ≈ squared distance in the joint image space
  };
  ro.threshold = thrH;
  ro.seed = opt.seed ^ 0x9e3779b9u;
  auto rH = ransac<HModel, Scalar>(n, 4, solveH, errH, ro);
  // Refit H on its inliers (normalised DLT), re-classify, repeat while the MSAC cost drops: the
  // minimal-sample model misses inliers near the threshold (a local optimisation in the manner
  // of LO-RANSAC).
  for (int round = 0; round < 3 && rH.found && rH.numInliers >= 8; ++round) {
    std::vector<int> idx;
    for (int i = 0; i < n; ++i) {
      if (rH.inliers[static_cast<std::size_t>(i)]) idx.push_back(i);
    }
    Mat3<Scalar> H;
    HModel m;
    if (!homographyDLT(x1, x2, idx.data(), static_cast<int>(idx.size()), H) || !makeH(H, m)) break;
    const Scalar T2 = thrH * thrH;
    Scalar cost = Scalar(0);
    std::vector<char> in(static_cast<std::size_t>(n), 0);
    int cnt = 0;
    for (int i = 0; i < n; ++i) {
      const Scalar e = errH(m, i);
      if (e < T2) {
        cost += e;
        in[static_cast<std::size_t>(i)] = 1;
        ++cnt;
      } else {
        cost += T2;
      }
    }
    if (!(cost < rH.cost)) break;
    rH.model = m;
    rH.cost = cost;
    rH.inliers = in;
    rH.numInliers = cnt;
  }
  if (!rE.found && !rH.found) {
    res.status = TwoViewStatus::Degenerate;
    return res;
  }
  if (rE.found) res.E = rE.model;
  if (rH.found) res.H = rH.model.H;

  // --- 2. model selection (GRIC) ---------------------------------------------------------------
  {
    const Scalar is2 = (f * f) / (opt.sigmaPx * opt.sigmaPx);  // 1/σ² in normalised units
    Scalar sumE = Scalar(0), sumH = Scalar(0);
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(i);
      const bool inE = rE.found && rE.inliers[k], inH = rH.found && rH.inliers[k];
      if (!inE && !inH) continue;
      ++m;
      if (rE.found) {
        const Scalar e2 = sampsonErrorSq(rE.model, x1[k], x2[k]) * is2;
        sumE += std::isfinite(e2) ? std::min(e2, Scalar(2)) : Scalar(2);  // λ3·(r − d_E) = 2
      }
      if (rH.found) {
        const Scalar e = errH(rH.model, i) * is2;
        sumH += std::isfinite(e) ? std::min(e, Scalar(4)) : Scalar(4);  // λ3·(r − d_H) = 4
      }
    }
    const Scalar l1 = std::log(Scalar(4)), l2 = std::log(Scalar(4) * Scalar(std::max(m, 1)));
    if (rE.found) res.gricEssential = sumE + l1 * Scalar(3) * Scalar(m) + l2 * Scalar(5);
    if (rH.found) res.gricHomography = sumH + l1 * Scalar(2) * Scalar(m) + l2 * Scalar(8);
    const bool useH = !rE.found || (rH.found && res.gricHomography < res.gricEssential);
    res.model = useH ? TwoViewModel::Homography : TwoViewModel::Essential;
    res.inliers = useH ? rH.inliers : rE.inliers;
    res.numInliers = useH ? rH.numInliers : rE.numInliers;
  }
  const std::vector<char>& inl = res.inliers;

  // --- 3./4. candidate motions, scored by triangulation; the parallax test ---------------------
  const Scalar maxErr2 = (opt.maxReprojPx / f) * (opt.maxReprojPx / f);
  const Scalar cosMinPar = std::cos(opt.minPointParallaxDeg * Constants<Scalar>::pi() / Scalar(180));
  const SE3<Scalar> Tid;
  // A model's motions (4 from E, up to 8 from H), each scored on the model's inliers.
  auto candidates = [&](TwoViewModel model, const std::vector<char>& in, Mat3<Scalar>* R, Vec3<Scalar>* t,
                        std::vector<MotionScore<Scalar>>& scores) {
    int count = 0;
    if (model == TwoViewModel::Essential) {
      if (decomposeEssential(rE.model, R, t)) count = 4;
    } else {
      Vec3<Scalar> nrm[8];
      count = decomposeHomography(rH.model.H, R, t, nrm);
    }
    scores.assign(static_cast<std::size_t>(count), MotionScore<Scalar>());
    for (int k = 0; k < count; ++k) {
      auto& sc = scores[static_cast<std::size_t>(k)];
      sc.X.assign(static_cast<std::size_t>(n), Vec3<Scalar>::Zero());
      sc.ok.assign(static_cast<std::size_t>(n), 0);
      const SE3<Scalar> T21(SO3<Scalar>::fromMatrix(R[k]), t[k]);
      for (int i = 0; i < n; ++i) {
        if (!in[static_cast<std::size_t>(i)]) continue;
        Vec3<Scalar> X;
        const auto& a = x1[static_cast<std::size_t>(i)];
        const auto& b = x2[static_cast<std::size_t>(i)];
        if (!triangulateDLT(Tid, T21, a, b, X)) continue;
        const TriangulationQuality<Scalar> q = triangulationQuality(Tid, T21, a, b, X);
        if (!(q.depth1 > Scalar(0)) || !(q.depth2 > Scalar(0))) continue;
        if (!(q.err1Sq <= maxErr2) || !(q.err2Sq <= maxErr2)) continue;
        sc.parallaxDeg.push_back(q.parallaxDeg());  // every point in front, any parallax
        if (!(q.cosParallax <= cosMinPar)) continue;
        sc.X[static_cast<std::size_t>(i)] = X;
        sc.ok[static_cast<std::size_t>(i)] = 1;
        ++sc.good;
      }
    }
    return count;
  };
  auto mostGood = [](const std::vector<MotionScore<Scalar>>& scores) {
    int g = 0;
    for (const auto& sc : scores) g = std::max(g, sc.good);
    return g;
  };
  Mat3<Scalar> Rc[8];
  Vec3<Scalar> tc[8];
  std::vector<MotionScore<Scalar>> scores;
  int nc = candidates(res.model, inl, Rc, tc, scores);
  // H chosen, but a motion of E triangulates more good points than any of H's: E instead. At low
  // parallax GRIC's dimension penalty can prefer H for a scene that is only nearly planar; its
  // decompositions are then approximations, and the points off the plane (E's extra inliers)
  // are explained by neither (walk seed 4, hands masked, frame 6: H 69 inliers, E 83; H's
  // motions 25° and 78° off in the direction of travel, E's 4°).
  if (res.model == TwoViewModel::Homography && rE.found && opt.essentialOverPlane &&
      Scalar(rE.numInliers) >= opt.essentialOverPlaneInliers * Scalar(rH.numInliers)) {
    Mat3<Scalar> RE[8];
    Vec3<Scalar> tE[8];
    std::vector<MotionScore<Scalar>> scoresE;
    const int ne = candidates(TwoViewModel::Essential, rE.inliers, RE, tE, scoresE);
    if (mostGood(scoresE) > mostGood(scores)) {
      res.model = TwoViewModel::Essential;
      res.inliers = rE.inliers;
      res.numInliers = rE.numInliers;
      res.essentialOverPlane = true;
      nc = ne;
      for (int k = 0; k < ne; ++k) Rc[k] = RE[k], tc[k] = tE[k];
      scores.swap(scoresE);
    }
  }
  int best = -1, second = 0;
  for (int k = 0; k < nc; ++k) {
    if (best < 0 || scores[static_cast<std::size_t>(k)].good > scores[static_cast<std::size_t>(best)].good) best = k;
  }
  for (int k = 0; k < nc; ++k) {
    if (k != best) second = std::max(second, scores[static_cast<std::size_t>(k)].good);
  }
  bool resolved = false;  // an ambiguity settled by the further views
  if (x3 && !x3->empty() && best >= 0 && scores[static_cast<std::size_t>(best)].good >= opt.minTriangulated &&
      Scalar(second) > opt.ambiguityRatio * Scalar(scores[static_cast<std::size_t>(best)].good)) {
    // Further views: each resected against each close candidate's points; the MSAC cost decides.
    PinholeCamera<Scalar> cam3;
    cam3.fx = cam3.fy = f;
    cam3.cx = cam3.cy = Scalar(0);
    const Scalar T2 = opt.thresholdPx * opt.thresholdPx;
    std::vector<std::pair<Scalar, int>> costs;
    for (int k = 0; k < nc; ++k) {
      const auto& sc = scores[static_cast<std::size_t>(k)];
      if (!(Scalar(sc.good) > opt.ambiguityRatio * Scalar(scores[static_cast<std::size_t>(best)].good))) continue;
      Scalar total = Scalar(0);
      int views = 0;
      for (const auto& view : *x3) {
        std::vector<Vec3<Scalar>> X;
        std::vector<Vec2<Scalar>> uv;
        for (int i = 0; i < n; ++i) {
          const auto& y = view[static_cast<std::size_t>(i)];
          if (!sc.ok[static_cast<std::size_t>(i)] || !y.allFinite()) continue;
          X.push_back(sc.X[static_cast<std::size_t>(i)]);
          uv.push_back(f * y);
        }
        if (static_cast<int>(X.size()) < opt.minThirdView) continue;
        PnPRansacOptions<Scalar> po;
        po.thresholdPx = opt.thresholdPx;
        po.seed = opt.seed ^ (0x3d1eu + static_cast<std::uint32_t>(views));
        const PnPRansacResult<Scalar> r = solvePnPRansac(X, uv, cam3, po);
        Scalar cost = T2;
        if ((r.status == PnPStatus::Ok || r.status == PnPStatus::NotEnoughInliers) && r.T_w_c.translation().allFinite()) {
          const SE3<Scalar> Tcw = r.T_w_c.inverse();
          cost = Scalar(0);
          for (std::size_t i = 0; i < X.size(); ++i) {
            const Vec3<Scalar> Xc = Tcw * X[i];
            const Scalar e2 = Xc(2) > Scalar(0) ? (cam3.project(Xc) - uv[i]).squaredNorm() : T2;
            cost += std::min(std::isfinite(e2) ? e2 : T2, T2);
          }
          cost /= Scalar(X.size());  // per observation: candidates see different subsets
        }
        total += cost;
        ++views;
      }
      if (views > 0) costs.push_back({total / Scalar(views), k});
    }
    std::sort(costs.begin(), costs.end());
    res.thirdViewCandidates = static_cast<int>(costs.size());
    if (costs.size() >= 2 && std::isfinite(costs[0].first)) {
      res.thirdViewCost = costs[0].first;
      res.thirdViewRunnerUp = costs[1].first;
      if (costs[0].first <= opt.ambiguityRatio * costs[1].first) {
        best = costs[0].second;
        resolved = true;
      }
    }
  }
  if (best < 0 || scores[static_cast<std::size_t>(best)].good < opt.minTriangulated) {
    // No motion triangulates enough points. Too little parallax when some rotation (one the
    // model allows, for H the one nearest to H, or the Kabsch fit of the rays) aligns the rays
    // to within minParallaxDeg; the pose then holds the best-aligning one.
    Scalar bestAngle = std::numeric_limits<Scalar>::infinity();
    Mat3<Scalar> bestR = Mat3<Scalar>::Identity();
    auto consider = [&](const Mat3<Scalar>& R) {
      const Scalar a = medianRayAngleDeg(x1, x2, inl, R);
      if (a < bestAngle) {
        bestAngle = a;
        bestR = R;
      }
    };
    if (res.model == TwoViewModel::Homography) {
      const Scalar det = M3(rH.model.H).determinant();
      if (std::isfinite(det) && det != Scalar(0)) {
        consider(projectToSO3(M3(rH.model.H / std::cbrt(det))));
      }
    }
    for (int k = 0; k < nc; ++k) consider(Rc[k]);
    consider(rotationFromRays(x1, x2, inl, bestR));  // the best pure-rotation explanation
    if (!std::isfinite(bestAngle)) {
      res.status = TwoViewStatus::Degenerate;
      return res;
    }
    res.medianParallaxDeg = bestAngle;
    res.status = bestAngle < opt.minParallaxDeg ? TwoViewStatus::NotEnoughParallax
                                                : TwoViewStatus::NotEnoughInliers;
    res.T_c1_c2 = SE3<Scalar>(SO3<Scalar>::fromMatrix(Mat3<Scalar>(bestR.transpose())), Vec3<Scalar>::Zero());
    return res;
  }
  auto& B = scores[static_cast<std::size_t>(best)];
  res.numInFront = static_cast<int>(B.parallaxDeg.size());
  res.medianParallaxDeg = two_view_detail::upperMedian(B.parallaxDeg);
  // Most inliers behind a camera or off their rays under the best motion: a wrong motion
  // (ORB-SLAM's 0.9·N test). A translation below the rotation's noise gives such a motion its own
  // fake parallax, with depths a few baselines deep (fast_turns, 1-2 cm steps at 3 m). Refused,
  // like too little parallax, with the rays' rotation and no translation.
  const bool behind = Scalar(res.numInFront) < opt.minInFrontRatio * Scalar(res.numInliers);
  if (behind || res.medianParallaxDeg < opt.minParallaxDeg) {
    res.status = behind ? TwoViewStatus::NotEnoughInliers : TwoViewStatus::NotEnoughParallax;
    const Mat3<Scalar> R = rotationFromRays(x1, x2, inl, Rc[best]);
    res.T_c1_c2 = SE3<Scalar>(SO3<Scalar>::fromMatrix(Mat3<Scalar>(R.transpose())), Vec3<Scalar>::Zero());
    return res;
  }
  res.T_c1_c2 = SE3<Scalar>(SO3<Scalar>::fromMatrix(Rc[best]), tc[best]).inverse();
  res.points = B.X;
  res.triangulated = B.ok;
  res.numTriangulated = B.good;
  if (!resolved && Scalar(second) > opt.ambiguityRatio * Scalar(B.good)) {
    res.status = TwoViewStatus::Ambiguous;
    return res;
  }

  // --- 5. refinement: two-view bundle adjustment, then the inliers re-classified with the refined
  // motion (the minimal-sample model misses inliers near the threshold), once -------------------
  for (int round = 0; opt.refine && round < 2; ++round) {
    BAProblem<Scalar> ba;
    ba.camera.fx = ba.camera.fy = f;
    ba.camera.cx = ba.camera.cy = Scalar(0);
    ba.poses = {SE3<Scalar>(), res.T_c1_c2};
    ba.poseFixed = {1, 0};
    std::vector<int> ids;
    for (int i = 0; i < n; ++i) {
      if (!res.triangulated[static_cast<std::size_t>(i)]) continue;
      const int k = static_cast<int>(ba.points.size());
      ids.push_back(i);
      ba.points.push_back(res.points[static_cast<std::size_t>(i)]);
      BAObservation<Scalar> o;
      o.pose = 0;
      o.point = k;
      o.uv = f * x1[static_cast<std::size_t>(i)];
      ba.observations.push_back(o);
      o.pose = 1;
      o.uv = f * x2[static_cast<std::size_t>(i)];
      ba.observations.push_back(o);
    }
    BAScalePrior<Scalar> sp;  // |t| = 1 (the result is rescaled exactly below)
    sp.poseA = 0;
    sp.poseB = 1;
    sp.distance = Scalar(1);
    sp.weight = Scalar(1e4) * Scalar(ba.observations.size());
    ba.scalePriors.push_back(sp);
    BAOptions<Scalar> bo;
    bo.maxIterations = opt.refineIterations;
    bo.loss = RobustLoss::Huber;
    bo.sigmaPx = opt.sigmaPx;
    bo.robustScale = Scalar(2);
    bundleAdjust(ba, bo);
    const Scalar len = ba.poses[1].translation().norm();
    if (!(len > Scalar(0)) || !std::isfinite(len) || !ba.poses[1].translation().allFinite()) break;
    res.T_c1_c2 = SE3<Scalar>(ba.poses[1].rotation(), Vec3<Scalar>(ba.poses[1].translation() / len));
    const SE3<Scalar> T21 = res.T_c1_c2.inverse();
    for (std::size_t k = 0; k < ids.size(); ++k) {
      res.points[static_cast<std::size_t>(ids[k])] = Vec3<Scalar>(ba.points[k] / len);
    }
    // Re-classify: inliers by the Sampson error of the refined E; new inliers triangulated.
    const Mat3<Scalar> Eref = essentialFromMotion(Mat3<Scalar>(T21.rotationMatrix()), T21.translation());
    const Scalar T2 = thrE * thrE;
    bool changed = false;
    int cnt = 0, ninl = 0;
    for (int i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(i);
      const char in = sampsonErrorSq(Eref, x1[k], x2[k]) < T2 ? 1 : 0;
      changed = changed || in != res.inliers[k];
      res.inliers[k] = in;
      ninl += in;
      char good = 0;
      if (in) {
        Vec3<Scalar> X = res.points[k];
        bool ok = res.triangulated[k] != 0;
        if (!ok) ok = triangulateDLT(Tid, T21, x1[k], x2[k], X);
        if (ok) {
          const TriangulationQuality<Scalar> q = triangulationQuality(Tid, T21, x1[k], x2[k], X);
          good = q.depth1 > Scalar(0) && q.depth2 > Scalar(0) && q.err1Sq <= maxErr2 &&
                         q.err2Sq <= maxErr2 && (res.triangulated[k] || q.cosParallax <= cosMinPar)
                     ? 1
                     : 0;
        }
        res.points[k] = good ? X : Vec3<Scalar>(Vec3<Scalar>::Zero());
      }
      changed = changed || good != res.triangulated[k];
      res.triangulated[k] = good;
      cnt += good;
    }
    res.numInliers = ninl;
    res.numTriangulated = cnt;
    {
      std::vector<Scalar> par;
      for (int i = 0; i < n; ++i) {
        const std::size_t k = static_cast<std::size_t>(i);
        if (res.triangulated[k]) {
          par.push_back(triangulationQuality(Tid, T21, x1[k], x2[k], res.points[k]).parallaxDeg());
        }
      }
      res.medianParallaxDeg = two_view_detail::upperMedian(par);
    }
    if (!changed) break;
  }
  res.status = res.numTriangulated >= opt.minTriangulated ? TwoViewStatus::Ok
                                                          : TwoViewStatus::NotEnoughInliers;
  return res;
}

}  // namespace hawor
