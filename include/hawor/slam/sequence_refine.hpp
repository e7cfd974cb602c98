// hawor/slam/sequence_refine.hpp — full-sequence bundle adjustment over every frame's feature
// tracks: the offline refinement that follows the SLAM (what a global BA over all frames is to
// DROID-SLAM, or the final bundle adjustment of an incremental SfM).
//
// The SLAM's own global bundle adjustment sees the keyframes and the map points they made. Most
// of the evidence never reaches it: tracks followed over many frames but never triangulated at a
// keyframe (the map is thin while hands cover the view or the head turns), the frames before the
// first map, and tracks that live on across a map reset (the same physical point in two map
// segments). Here every frame with a pose guess is a camera and every track a candidate point:
//   1. Triangulation per track from all its observations: the DLT of the pair of rays with the
//      largest angle among a few spread pairs (first/last/middle observation), kept when the
//      parallax is ≥ minParallaxDeg and at least minObservations observations (and half of them)
//      reproject within maxReprojPx in front of their cameras; only those observations are used.
//   2. A frame is adjusted when it sees ≥ minFrameObservations such points; the others keep their
//      pose (the caller interpolates them).
//   3. Levenberg–Marquardt bundle adjustment (bundle_adjustment.hpp: Schur complement, Huber) of
//      the adjusted frames and the points. Gauge (7 freedoms): the adjusted frame with the most
//      observations among the first ones is fixed and a scale prior holds its distance to the
//      adjusted frame farthest from it.
//      A head that stands and turns (the adjusted frames pass head_motion.hpp's head tests: the
//      eye rides a sphere about the neck, c = n + M·z) adds a position prior on every adjusted
//      frame toward the model's prediction, σ = headPriorSigma × the fit's rms residual. Views
//      linked to each other only through a fast turn (a few tracks) otherwise keep a relative
//      scale and offset that the images barely determine; the model ties them to the rest as
//      a motion model ties frames in a filter. A walk, or a body that sways, fails the tests and
//      gets no prior.
//   4. rounds times: after each adjustment the inlier gate becomes 3σ̂ (σ̂ from the median
//      residual, within [minGatePx, maxReprojPx]) and every track is re-triangulated against the
//      new poses with it (a track that slid by a few pixels keeps one side of its jump; points
//      with too few observations left are dropped), then adjusted again.
// Input observations are in pixels (docs/design.md §2); poses camera-to-world (T_w_c). Pure function,
// thread-safe.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/slam/bundle_adjustment.hpp"
#include "hawor/slam/head_motion.hpp"
#include "hawor/slam/pnp_ransac.hpp"
#include "hawor/slam/triangulation.hpp"

namespace hawor {

/// One pixel observation of track `track` in one frame.
template <typename Scalar>
struct TrackObservation {
  int track = 0;
  Vec2<Scalar> uv = Vec2<Scalar>::Zero();
};

/// Adds a point's observations (frame, pixel) to P as point `point`, each frame through
/// poseOf (-1: not in the problem), when at least minFrames of its frames are in the problem.
/// Returns whether it added them (the caller then appends the point itself).
template <typename Scalar>
bool addTrackObservations(BAProblem<Scalar>& P, int point, const std::vector<std::pair<int, Vec2<Scalar>>>& obs,
                          const std::vector<int>& poseOf, int minFrames) {
  int n = 0;
  for (const auto& o : obs) n += poseOf[static_cast<std::size_t>(o.first)] >= 0 ? 1 : 0;
  if (n < minFrames) return false;
  for (const auto& o : obs) {
    const int v = poseOf[static_cast<std::size_t>(o.first)];
    if (v < 0) continue;
    BAObservation<Scalar> b;
    b.pose = v;
    b.point = point;
    b.uv = o.second;
    P.observations.push_back(b);
  }
  return true;
}

template <typename Scalar>
struct SequenceRefineOptions {
  Scalar minParallaxDeg = Scalar(1);  ///< largest ray angle of a track, at least
  int minObservations = 3;            ///< inlier observations of a point, at least
  Scalar maxReprojPx = Scalar(3);     ///< inlier gate of the first round (triangulation and culling)
  Scalar minGatePx = Scalar(0.75);    ///< the later rounds' gate (3σ̂ of the residuals), at least
  int minFrameObservations = 15;      ///< points a frame must see to be adjusted
  /// Frames in the bundle adjustment, at most: beyond it every k-th eligible frame is adjusted
  /// with the points, and the frames between get a motion-only refinement against the adjusted
  /// points (neighbouring frames add little but cost a 6×6 block each in the reduced system).
  int maxAdjustedFrames = 200;
  int denseMaxFrames = 400;           ///< dense reduced camera system up to this many frames
  /// A frame with a guessed position is resected when its rotation agrees with the guess's.
  Scalar maxResectionRotationDeg = Scalar(2);
  /// A frame whose translation is this many times less certain than the median frame's is not
  /// taken (see the conditioning step in refineSequence).
  Scalar maxTranslationStdRatio = Scalar(8);
  int rounds = 3;                     ///< adjust → cull → re-triangulate rounds
  int iterations = 10;                ///< LM iterations per round
  Scalar sigmaPx = Scalar(1);
  Scalar robustScale = Scalar(2);     ///< Huber scale in units of σ
  /// Step 3's head prior (file comment): on when the adjusted frames pass the head tests of
  /// `headModel`, with σ = headPriorSigma × the fit's rms residual.
  bool headPrior = true;
  Scalar headPriorSigma = Scalar(4);
  HeadModelOptions<Scalar> headModel;
};

template <typename Scalar>
struct SequenceRefineResult {
  std::vector<SE3<Scalar>> poses;        ///< T_w_c per frame (unchanged where not adjusted)
  std::vector<char> adjusted;            ///< per frame: took part in the adjustment
  /// Per frame: trusted but not adjusted (see the end of refineSequence), its pose carried along
  /// with its nearest adjusted frame.
  std::vector<char> carried;
  std::vector<Vec3<Scalar>> points;      ///< the triangulated tracks (world)
  std::vector<int> pointTrack;           ///< per point: its track id
  /// Per point: its inlier observations (frame, pixel).
  std::vector<std::vector<std::pair<int, Vec2<Scalar>>>> pointObs;
  /// Per frame: the translation's standard deviation in its worst direction at σ (world units;
  /// +inf where not adjusted).
  std::vector<Scalar> translationStd;
  Scalar gatePx = Scalar(0);             ///< the inlier gate after the last adjustment (px)
  int illConditioned = 0;                ///< frames not taken for their translation's uncertainty
  int observations = 0;                  ///< inlier observations in the last adjustment
  Scalar finalRmsPx = Scalar(0);
  int iterations = 0;
  int headPriorRounds = 0;               ///< adjustments that had the head prior
  Scalar headPriorRms = Scalar(0);       ///< its fit's rms residual in the last such round (world units)
};

namespace seqref_detail {

/// One observation of a track, 12 bytes: pixels in float (the tracker's own precision; 6e-5 px
/// at 1,000 px), a million observations over 3,000 frames, where double would cost 14 MB more.
template <typename Scalar>
struct TrackObs {
  int frame;
  float u, v;
  Vec2<Scalar> uv() const { return Vec2<Scalar>(Scalar(u), Scalar(v)); }
};

/// Triangulates one track from its observations under `poses` (see the file comment, step 1).
/// `inl` receives the inlier flags. False when no pair has the parallax or too few agree.
template <typename Scalar>
bool triangulateTrack(const PinholeCamera<Scalar>& cam, const std::vector<SE3<Scalar>>& Tcw,
                      const std::vector<TrackObs<Scalar>>& obs, const SequenceRefineOptions<Scalar>& o, Scalar gatePx,
                      Vec3<Scalar>& X, std::vector<char>& inl) {
  using V2 = Vec2<Scalar>;
  using V3 = Vec3<Scalar>;
  const int n = static_cast<int>(obs.size());
  if (n < o.minObservations) return false;
  auto norm = [&](const V2& uv) { return V2((uv(0) - cam.cx) / cam.fx, (uv(1) - cam.cy) / cam.fy); };
  auto ray = [&](int i) {
    const V2 x = norm(obs[static_cast<std::size_t>(i)].uv());
    return V3((Tcw[static_cast<std::size_t>(obs[static_cast<std::size_t>(i)].frame)].rotationMatrix().transpose() *
               V3(x(0), x(1), Scalar(1)))
                  .normalized());
  };
  const int cand[5] = {0, n / 4, n / 2, (3 * n) / 4, n - 1};
  const Scalar cosMin = std::cos(o.minParallaxDeg * Constants<Scalar>::pi() / Scalar(180));
  const Scalar thr2 = gatePx * gatePx;
  // Candidate pairs, widest first.
  std::vector<std::pair<Scalar, std::pair<int, int>>> pairs;
  for (int a = 0; a < 5; ++a) {
    for (int b = a + 1; b < 5; ++b) {
      if (cand[a] == cand[b]) continue;
      const Scalar c = ray(cand[a]).dot(ray(cand[b]));
      if (c <= cosMin) pairs.push_back({c, {cand[a], cand[b]}});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
  const int need = std::max(o.minObservations, (n + 1) / 2);
  for (std::size_t k = 0; k < pairs.size() && k < 3; ++k) {
    const int a = pairs[k].second.first, b = pairs[k].second.second;
    V3 Y;
    if (!triangulateDLT(Tcw[static_cast<std::size_t>(obs[static_cast<std::size_t>(a)].frame)],
                        Tcw[static_cast<std::size_t>(obs[static_cast<std::size_t>(b)].frame)],
                        norm(obs[static_cast<std::size_t>(a)].uv()), norm(obs[static_cast<std::size_t>(b)].uv()), Y)) {
      continue;
    }
    inl.assign(static_cast<std::size_t>(n), 0);
    int count = 0;
    for (int i = 0; i < n; ++i) {
      const V3 Xc = Tcw[static_cast<std::size_t>(obs[static_cast<std::size_t>(i)].frame)] * Y;
      if (!(Xc(2) > Scalar(0))) continue;
      if ((cam.project(Xc) - obs[static_cast<std::size_t>(i)].uv()).squaredNorm() <= thr2) {
        inl[static_cast<std::size_t>(i)] = 1;
        ++count;
      }
    }
    if (count >= need) {
      X = Y;
      return true;
    }
  }
  return false;
}

/// Step 3's head prior: the head model c = n + M·z (head_motion.hpp) fitted to the problem's
/// cameras; where it passes the head tests, a position prior on every camera toward its
/// prediction, weight 1/σ², σ = headPriorSigma × the fit's rms residual. Returns true when added.
template <typename Scalar>
bool addHeadPrior(BAProblem<Scalar>& P, const SequenceRefineOptions<Scalar>& opt, SequenceRefineResult<Scalar>& res) {
  std::vector<int> idx(P.poses.size());
  for (std::size_t v = 0; v < idx.size(); ++v) idx[v] = static_cast<int>(v);
  const HeadModelFit<Scalar> fit = fitHeadModel(P.poses, idx, opt.headModel);
  if (!passesHeadTests(fit, opt.headModel) || fit.spreadDeg < opt.headModel.minSpreadDeg) return false;
  Scalar ss = 0;
  for (const auto& T : P.poses) ss += (T.translation() - fit.predict(T)).squaredNorm();
  const Scalar rms = std::sqrt(ss / Scalar(P.poses.size()));
  const Scalar w = Scalar(1) / (opt.headPriorSigma * opt.headPriorSigma * rms * rms);
  if (!(rms > Scalar(0)) || !std::isfinite(w)) return false;
  for (std::size_t v = 0; v < P.poses.size(); ++v) {
    BAPositionPrior<Scalar> q;
    q.pose = static_cast<int>(v);
    q.position = fit.predict(P.poses[v]);
    q.weight = w;
    P.positionPriors.push_back(q);
  }
  ++res.headPriorRounds;
  res.headPriorRms = rms;
  return true;
}

}  // namespace seqref_detail

/// The refinement of the file comment. `frames[f]`: frame f's track observations (pixels);
/// `state[f]`: 2, frame f's pose in `poses` is trusted (posed by the map: it triangulates and
/// starts the adjustment); 1, only its rotation is (the position a guess: it is resected against
/// the points, its rotation a check); 0, not usable. Throws hawor::Error when the sizes disagree
/// or an input is not finite.
template <typename Scalar>
SequenceRefineResult<Scalar> refineSequence(const PinholeCamera<Scalar>& cam, const std::vector<SE3<Scalar>>& poses,
                                            const std::vector<char>& state,
                                            const std::vector<std::vector<TrackObservation<Scalar>>>& frames,
                                            const SequenceRefineOptions<Scalar>& opt = {}) {
  using TO = seqref_detail::TrackObs<Scalar>;
  const int nF = static_cast<int>(poses.size());
  if (static_cast<int>(state.size()) != nF || static_cast<int>(frames.size()) != nF) {
    throw Error("refineSequence: " + std::to_string(nF) + " poses but " + std::to_string(state.size()) +
                " frame states and " + std::to_string(frames.size()) + " observation lists");
  }
  if (!(opt.minParallaxDeg >= Scalar(0)) || opt.minObservations < 2 || !(opt.maxReprojPx > Scalar(0)) ||
      !(opt.minGatePx > Scalar(0) && opt.minGatePx <= opt.maxReprojPx) || opt.maxAdjustedFrames < 2 ||
      !(opt.maxTranslationStdRatio > Scalar(1)) || (opt.headPrior && !(opt.headPriorSigma > Scalar(0))) ||
      opt.minFrameObservations < 3 || opt.rounds < 1 || opt.iterations < 1) {
    throw Error("refineSequence: invalid options");
  }
  SequenceRefineResult<Scalar> res;
  res.poses = poses;
  res.adjusted.assign(static_cast<std::size_t>(nF), 0);
  res.carried.assign(static_cast<std::size_t>(nF), 0);
  res.translationStd.assign(static_cast<std::size_t>(nF), std::numeric_limits<Scalar>::infinity());
  // Tracks: every observation in a usable frame (state > 0), grouped by track id (frame order kept).
  int maxTrack = -1;
  for (int f = 0; f < nF; ++f) {
    if (!state[static_cast<std::size_t>(f)]) continue;
    if (!poses[static_cast<std::size_t>(f)].translation().allFinite()) {
      throw Error("refineSequence: pose " + std::to_string(f) + " is not finite");
    }
    for (const auto& o : frames[static_cast<std::size_t>(f)]) {
      if (o.track < 0 || !o.uv.allFinite()) {
        throw Error("refineSequence: frame " + std::to_string(f) + " has an invalid observation");
      }
      maxTrack = std::max(maxTrack, o.track);
    }
  }
  std::vector<std::vector<TO>> tracks(static_cast<std::size_t>(maxTrack + 1));
  for (int f = 0; f < nF; ++f) {
    if (!state[static_cast<std::size_t>(f)]) continue;
    for (const auto& o : frames[static_cast<std::size_t>(f)]) tracks[static_cast<std::size_t>(o.track)].push_back(TO{f, float(o.uv(0)), float(o.uv(1))});
  }
  std::vector<SE3<Scalar>> Tcw(static_cast<std::size_t>(nF));
  std::vector<char> inl;
  Scalar gate = opt.maxReprojPx;  // inlier gate (px): maxReprojPx, then 3σ̂ of the last adjustment
  std::vector<char> trusted(static_cast<std::size_t>(nF));
  for (int f = 0; f < nF; ++f) trusted[static_cast<std::size_t>(f)] = state[static_cast<std::size_t>(f)] >= 2 ? 1 : 0;
  for (int round = 0; round < opt.rounds; ++round) {
    for (int f = 0; f < nF; ++f) Tcw[static_cast<std::size_t>(f)] = res.poses[static_cast<std::size_t>(f)].inverse();
    // Triangulate every track from its observations in trusted frames; its inliers there
    // become BA observations.
    BAProblem<Scalar> P;
    P.camera = cam;
    std::vector<int> frameVar(static_cast<std::size_t>(nF), -1), frameOf;
    std::vector<int> frameCount(static_cast<std::size_t>(nF), 0);
    std::vector<int> pointTrack;
    std::vector<std::vector<std::pair<int, Vec2<Scalar>>>> pointObs;
    std::vector<int> pointOf(tracks.size(), -1);
    std::vector<TO> sub;
    for (std::size_t t = 0; t < tracks.size(); ++t) {
      sub.clear();
      for (const TO& o : tracks[t]) {
        if (trusted[static_cast<std::size_t>(o.frame)]) sub.push_back(o);
      }
      Vec3<Scalar> X;
      if (!seqref_detail::triangulateTrack(cam, Tcw, sub, opt, gate, X, inl)) continue;
      std::vector<std::pair<int, Vec2<Scalar>>> ob;
      for (std::size_t i = 0; i < sub.size(); ++i) {
        if (inl[i]) ob.push_back({sub[i].frame, sub[i].uv()});
      }
      pointOf[t] = static_cast<int>(P.points.size());
      P.points.push_back(X);
      pointTrack.push_back(static_cast<int>(t));
      for (const auto& o : ob) ++frameCount[static_cast<std::size_t>(o.first)];
      pointObs.push_back(std::move(ob));
    }
    // Frames with a guessed position only, and trusted frames that too few points agree with:
    // resected against those points (PnP-RANSAC); with enough inliers they are trusted from here
    // on and their inliers join the points.
    {
      std::vector<Vec3<Scalar>> X;
      std::vector<Vec2<Scalar>> uv;
      std::vector<int> pj;
      for (int f = 0; f < nF; ++f) {
        if (!state[static_cast<std::size_t>(f)] || frameCount[static_cast<std::size_t>(f)] >= opt.minFrameObservations) continue;
        X.clear(), uv.clear(), pj.clear();
        for (const auto& o : frames[static_cast<std::size_t>(f)]) {
          const int j = pointOf[static_cast<std::size_t>(o.track)];
          if (j < 0) continue;
          X.push_back(P.points[static_cast<std::size_t>(j)]);
          uv.push_back(o.uv);
          pj.push_back(j);
        }
        if (static_cast<int>(X.size()) < opt.minFrameObservations) continue;
        PnPRansacOptions<Scalar> po;
        po.thresholdPx = gate;
        po.minInliers = opt.minFrameObservations;
        po.seed = 0x7a3du + static_cast<std::uint32_t>(f);
        const PnPRansacResult<Scalar> r = solvePnPRansac(X, uv, cam, po);
        if (!r.ok() || r.numInliers < opt.minFrameObservations) continue;
        // The guess's rotation (from the tracked rays) is good where its position is not: a pose
        // that disagrees with it is a wrong resection (few, ill-conditioned points).
        const Mat3<Scalar> dR = res.poses[static_cast<std::size_t>(f)].rotationMatrix().transpose() * r.T_w_c.rotationMatrix();
        const Scalar cosA = std::max(Scalar(-1), std::min(Scalar(1), (dR.trace() - Scalar(1)) / Scalar(2)));
        if (std::acos(cosA) > opt.maxResectionRotationDeg * Constants<Scalar>::pi() / Scalar(180)) continue;
        res.poses[static_cast<std::size_t>(f)] = r.T_w_c;
        Tcw[static_cast<std::size_t>(f)] = r.T_w_c.inverse();
        trusted[static_cast<std::size_t>(f)] = 1;
        for (std::size_t i = 0; i < pj.size(); ++i) {
          if (!r.inliers[i]) continue;
          auto& po2 = pointObs[static_cast<std::size_t>(pj[i])];
          if (std::any_of(po2.begin(), po2.end(), [f](const auto& o) { return o.first == f; })) continue;
          po2.push_back({f, uv[i]});
          ++frameCount[static_cast<std::size_t>(f)];
        }
      }
    }
    // Frames with enough points (eligible); every stride-th of them is adjusted with the points.
    std::vector<int> eligible;
    for (int f = 0; f < nF; ++f) {
      if (frameCount[static_cast<std::size_t>(f)] >= opt.minFrameObservations) eligible.push_back(f);
    }
    if (eligible.size() < 2) return res;
    const int stride = std::max<int>(1, (static_cast<int>(eligible.size()) + opt.maxAdjustedFrames - 1) / opt.maxAdjustedFrames);
    for (std::size_t e = 0; e < eligible.size(); ++e) {
      if (static_cast<int>(e) % stride != 0 && e + 1 != eligible.size()) continue;
      const int f = eligible[e];
      frameVar[static_cast<std::size_t>(f)] = static_cast<int>(P.poses.size());
      P.poses.push_back(res.poses[static_cast<std::size_t>(f)]);
      frameOf.push_back(f);
    }
    std::vector<Vec3<Scalar>> pts;
    std::vector<int> ptTrack;
    for (std::size_t j = 0; j < P.points.size(); ++j) {
      if (!addTrackObservations(P, static_cast<int>(pts.size()), pointObs[j], frameVar, opt.minObservations)) continue;
      pts.push_back(P.points[j]);
      ptTrack.push_back(pointTrack[j]);
    }
    P.points = std::move(pts);
    // The observation lists are in P now; they and the last round's result (rebuilt below) are
    // not held through the adjustment (memory: about 50 bytes an observation each).
    decltype(pointObs)().swap(pointObs);
    decltype(res.pointObs)().swap(res.pointObs);
    // Gauge: fix the best-observed of the first adjusted frames; a scale prior to the farthest.
    std::vector<int> perPose(P.poses.size(), 0);
    for (const auto& b : P.observations) ++perPose[static_cast<std::size_t>(b.pose)];
    int fixedV = 0;
    for (int v = 0; v < std::min<int>(10, static_cast<int>(P.poses.size())); ++v) {
      if (perPose[static_cast<std::size_t>(v)] > perPose[static_cast<std::size_t>(fixedV)]) fixedV = v;
    }
    P.poseFixed.assign(P.poses.size(), 0);
    P.poseFixed[static_cast<std::size_t>(fixedV)] = 1;
    addFarthestScalePrior(P, fixedV);
    if (opt.headPrior) seqref_detail::addHeadPrior(P, opt, res);
    BAOptions<Scalar> bo;
    bo.maxIterations = opt.iterations;
    bo.loss = RobustLoss::Huber;
    bo.sigmaPx = opt.sigmaPx;
    bo.robustScale = opt.robustScale;
    bo.functionTolerance = Scalar(1e-6);
    bo.denseMaxPoses = opt.denseMaxFrames;
    const BAReport<Scalar> rep = bundleAdjust(P, bo);
    res.iterations += rep.iterations;
    res.finalRmsPx = rep.finalRmsPx;
    res.observations = rep.usedObservations;
    std::fill(res.adjusted.begin(), res.adjusted.end(), 0);
    // The frames between adjusted ones start from their pose moved with the nearest adjusted
    // frame before them (the adjustment may shift the whole map by more than the inlier gate).
    {
      int last = -1;
      SE3<Scalar> corr;
      std::vector<SE3<Scalar>> before(frameOf.size());
      for (std::size_t v = 0; v < frameOf.size(); ++v) before[v] = res.poses[static_cast<std::size_t>(frameOf[v])];
      std::size_t v = 0;
      for (int f = 0; f < nF; ++f) {
        if (v < frameOf.size() && frameOf[v] == f) {
          corr = P.poses[v] * before[v].inverse();
          last = f;
          ++v;
          res.poses[static_cast<std::size_t>(f)] = P.poses[v - 1];
        } else if (last >= 0 && state[static_cast<std::size_t>(f)]) {
          res.poses[static_cast<std::size_t>(f)] = corr * res.poses[static_cast<std::size_t>(f)];
        }
      }
    }
    std::vector<std::vector<std::pair<int, Vec2<Scalar>>>> extraObs(P.points.size());
    for (int f : eligible) res.adjusted[static_cast<std::size_t>(f)] = 1;
    if (stride > 1) {
      // The eligible frames between: their pose against the adjusted points (Huber, inliers of
      // the pose they start from), and their observations of those points for the caller.
      std::vector<int> pointOfTrack(tracks.size(), -1);
      for (std::size_t j = 0; j < P.points.size(); ++j) pointOfTrack[static_cast<std::size_t>(ptTrack[j])] = static_cast<int>(j);
      const Scalar thr2 = gate * gate;
      for (int f : eligible) {
        if (frameVar[static_cast<std::size_t>(f)] >= 0) continue;
        std::vector<Vec3<Scalar>> X;
        std::vector<Vec2<Scalar>> uv;
        std::vector<int> pj;
        for (const auto& o : frames[static_cast<std::size_t>(f)]) {
          const int j = pointOfTrack[static_cast<std::size_t>(o.track)];
          if (j < 0) continue;
          X.push_back(P.points[static_cast<std::size_t>(j)]);
          uv.push_back(o.uv);
          pj.push_back(j);
        }
        SE3<Scalar> T = res.poses[static_cast<std::size_t>(f)];
        std::vector<Scalar> w(X.size(), Scalar(0));
        int in = 0;
        for (std::size_t i = 0; i < X.size(); ++i) {
          const Vec3<Scalar> Xc = T.inverse() * X[i];
          if (Xc(2) > Scalar(0) && (cam.project(Xc) - uv[i]).squaredNorm() <= Scalar(4) * thr2) w[i] = Scalar(1), ++in;
        }
        if (in < opt.minFrameObservations && static_cast<int>(X.size()) >= opt.minFrameObservations) {
          PnPRansacOptions<Scalar> po;
          po.thresholdPx = gate;
          po.minInliers = opt.minFrameObservations;
          po.seed = 0x51f3u + static_cast<std::uint32_t>(f);
          const PnPRansacResult<Scalar> r = solvePnPRansac(X, uv, cam, po);
          if (r.ok()) {
            T = r.T_w_c;
            in = 0;
            for (std::size_t i = 0; i < X.size(); ++i) w[i] = r.inliers[i] ? Scalar(1) : Scalar(0), in += r.inliers[i] ? 1 : 0;
          }
        }
        if (in < opt.minFrameObservations) {
          res.adjusted[static_cast<std::size_t>(f)] = 0;
          continue;
        }
        PoseRefineOptions<Scalar> ro;
        ro.sigmaPx = opt.sigmaPx;
        ro.robustScale = opt.robustScale;
        refinePose(X, uv, &w, cam, T, ro);
        if (!T.translation().allFinite()) {
          res.adjusted[static_cast<std::size_t>(f)] = 0;
          continue;
        }
        res.poses[static_cast<std::size_t>(f)] = T;
        const SE3<Scalar> Tcw2 = T.inverse();
        for (std::size_t i = 0; i < X.size(); ++i) {
          const Vec3<Scalar> Xc = Tcw2 * X[i];
          if (Xc(2) > Scalar(0) && (cam.project(Xc) - uv[i]).squaredNorm() <= thr2) extraObs[static_cast<std::size_t>(pj[i])].push_back({f, uv[i]});
        }
      }
    }
    // The noise level of the adjusted observations (for a 2D Gaussian the median of ‖r‖ is
    // 1.1774σ) sets the next gate at 3σ̂ within [minGatePx, maxReprojPx]: a track that slid by a
    // couple of pixels keeps only the part on one side of its jump.
    const std::vector<Scalar> err = baReprojectionErrors(P);
    {
      std::vector<Scalar> e;
      for (Scalar v : err) {
        if (std::isfinite(v) && v <= gate) e.push_back(v);
      }
      if (e.size() >= 20) {
        const Scalar sigma = median(e) / Scalar(1.1774);
        gate = std::max(opt.minGatePx, std::min(opt.maxReprojPx, Scalar(3) * sigma));
      }
      res.gatePx = gate;
    }
    // Keep the adjusted points' inlier observations for the caller.
    std::vector<int> good(P.points.size(), 0);
    std::vector<std::vector<std::pair<int, Vec2<Scalar>>>> keptObs(P.points.size());
    for (std::size_t k = 0; k < P.observations.size(); ++k) {
      const auto& b = P.observations[k];
      if (std::isfinite(err[k]) && err[k] <= gate) {
        ++good[static_cast<std::size_t>(b.point)];
        keptObs[static_cast<std::size_t>(b.point)].push_back({frameOf[static_cast<std::size_t>(b.pose)], b.uv});
      }
    }
    res.points.clear(), res.pointTrack.clear(), res.pointObs.clear();
    for (std::size_t j = 0; j < P.points.size(); ++j) {
      if (good[j] < opt.minObservations) continue;
      res.points.push_back(P.points[j]);
      res.pointTrack.push_back(ptTrack[j]);
      keptObs[j].insert(keptObs[j].end(), extraObs[j].begin(), extraObs[j].end());
      std::sort(keptObs[j].begin(), keptObs[j].end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      res.pointObs.push_back(std::move(keptObs[j]));
    }
  }
  // Conditioning: each adjusted frame's translation standard deviation in its worst direction,
  // from the motion-only information (points held) at σ: the translation block's Schur
  // complement over the rotation, S = H_ρρ − H_ρφ·H_φφ⁻¹·H_φρ, σ_t = σ/√λ_min(S). A frame posed
  // from a few points in a narrow patch of the view (the last frames of a map running out) has
  // a translation far less certain than the rest; beyond maxTranslationStdRatio × the median it
  // is not taken as adjusted (the caller fills it like an unposed frame).
  using M6 = Eigen::Matrix<Scalar, 6, 6>;
  std::vector<M6> H(static_cast<std::size_t>(nF), M6::Zero());
  std::vector<SE3<Scalar>> Tc(static_cast<std::size_t>(nF));
  for (int f = 0; f < nF; ++f) Tc[static_cast<std::size_t>(f)] = res.poses[static_cast<std::size_t>(f)].inverse();
  for (std::size_t j = 0; j < res.points.size(); ++j) {
    for (const auto& o : res.pointObs[j]) {
      if (!res.adjusted[static_cast<std::size_t>(o.first)]) continue;
      const SE3<Scalar>& T = Tc[static_cast<std::size_t>(o.first)];
      Eigen::Matrix<Scalar, 2, 1> r;
      Eigen::Matrix<Scalar, 2, 6> J;
      if (ba_detail::reprojection<Scalar>(cam, Mat3<Scalar>(T.rotationMatrix()), Vec3<Scalar>(T.translation()), res.points[j],
                                          o.second, Scalar(1e-9), r, &J, nullptr)) {
        H[static_cast<std::size_t>(o.first)] += J.transpose() * J;
      }
    }
  }
  res.translationStd.assign(static_cast<std::size_t>(nF), std::numeric_limits<Scalar>::infinity());
  std::vector<Scalar> stds;
  for (int f = 0; f < nF; ++f) {
    if (!res.adjusted[static_cast<std::size_t>(f)]) continue;
    const M6& h = H[static_cast<std::size_t>(f)];
    const Eigen::Matrix<Scalar, 3, 3> Hpp = h.template bottomRightCorner<3, 3>();
    const Eigen::LDLT<Eigen::Matrix<Scalar, 3, 3>> ldlt(Hpp);
    if (ldlt.info() != Eigen::Success) continue;
    const Eigen::Matrix<Scalar, 3, 3> S = h.template topLeftCorner<3, 3>() - h.template topRightCorner<3, 3>() * ldlt.solve(h.template bottomLeftCorner<3, 3>());
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<Scalar, 3, 3>> es(S, Eigen::EigenvaluesOnly);
    const Scalar lmin = es.eigenvalues()(0);
    if (lmin > Scalar(0)) {
      res.translationStd[static_cast<std::size_t>(f)] = opt.sigmaPx / std::sqrt(lmin);
      stds.push_back(res.translationStd[static_cast<std::size_t>(f)]);
    }
  }
  std::vector<char> ill(static_cast<std::size_t>(nF), 0);
  if (!stds.empty()) {
    const Scalar med = median(stds);
    for (int f = 0; f < nF; ++f) {
      if (res.adjusted[static_cast<std::size_t>(f)] && !(res.translationStd[static_cast<std::size_t>(f)] <= opt.maxTranslationStdRatio * med)) {
        res.adjusted[static_cast<std::size_t>(f)] = 0;
        ill[static_cast<std::size_t>(f)] = 1;
        ++res.illConditioned;
      }
    }
  }
  // Trusted frames the refinement did not take (too few of their points adjusted in a long,
  // subsampled sequence), ill-conditioned ones excepted, keep their input pose moved with the
  // adjustment of the nearest adjusted frame in time (the one before on a tie; the nearest, not
  // the one before: the first frames after a loss would take the correction of the frames before
  // it, another part of the map): T' = T'_a·T_a⁻¹·T.
  res.carried.assign(static_cast<std::size_t>(nF), 0);
  std::vector<int> nextAdjusted(static_cast<std::size_t>(nF) + 1, -1);
  for (int f = nF - 1; f >= 0; --f) {
    nextAdjusted[static_cast<std::size_t>(f)] = res.adjusted[static_cast<std::size_t>(f)] ? f : nextAdjusted[static_cast<std::size_t>(f) + 1];
  }
  for (int f = 0, prev = -1; f < nF; ++f) {
    if (res.adjusted[static_cast<std::size_t>(f)]) {
      prev = f;
      continue;
    }
    if (state[static_cast<std::size_t>(f)] < 2 || ill[static_cast<std::size_t>(f)]) continue;
    const int next = nextAdjusted[static_cast<std::size_t>(f)];
    const int ref = prev < 0 ? next : next < 0 || f - prev <= next - f ? prev : next;
    if (ref < 0) continue;
    res.poses[static_cast<std::size_t>(f)] = res.poses[static_cast<std::size_t>(ref)] * poses[static_cast<std::size_t>(ref)].inverse() *
                                             poses[static_cast<std::size_t>(f)];
    res.carried[static_cast<std::size_t>(f)] = 1;
  }
  return res;
}

}  // namespace hawor
