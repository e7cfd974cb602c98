// hawor/slam/mono_slam/finish.hpp — MonoSlam's finish(): the passes over the whole sequence (global
// bundle adjustment, every frame against the final map, the sequence refinement, the focal, the
// head model) and the result.
// Member functions of MonoSlam (slam/mono_slam.hpp: the class, its state and the overview);
// included at the end of that header.
#pragma once

#include "../mono_slam.hpp"

namespace hawor {

/// The keyframes the global bundle adjustment leaves out (finish.maxAdjustedKeyframes,
/// finish.redundantShare): while more than the budget are kept, newest first, a keyframe at least
/// that share of whose valid map points is seen by 3 other keyframes still kept; a segment's
/// first keyframe (its gauge) is always kept.
template <typename Scalar>
std::vector<char> MonoSlam<Scalar>::redundantKeyframes() const {
  const std::size_t nk = keyframes_.size();
  std::vector<char> out(nk, 0);
  if (!(opt_.finish.redundantShare <= Scalar(1)) || nk <= static_cast<std::size_t>(opt_.finish.maxAdjustedKeyframes)) return out;
  // Per keyframe its distinct valid points; per point the keyframes kept that see it.
  std::vector<std::vector<int>> seen(nk);
  std::vector<int> count(points_.size(), 0), stamp(nk, -1);
  for (std::size_t pid = 0; pid < points_.size(); ++pid) {
    if (!points_[pid].valid) continue;
    for (const Obs& o : points_[pid].obs) {
      int& st = stamp[static_cast<std::size_t>(o.kf)];
      if (st == static_cast<int>(pid)) continue;
      st = static_cast<int>(pid);
      seen[static_cast<std::size_t>(o.kf)].push_back(static_cast<int>(pid));
      ++count[pid];
    }
  }
  const std::vector<int> firsts = segmentFirstKeyframes();
  std::size_t kept = nk;
  for (std::size_t k = nk; k-- > 0 && kept > static_cast<std::size_t>(opt_.finish.maxAdjustedKeyframes);) {
    if (seen[k].empty() || std::find(firsts.begin(), firsts.end(), static_cast<int>(k)) != firsts.end()) continue;
    std::size_t covered = 0;
    for (int pid : seen[k]) covered += count[static_cast<std::size_t>(pid)] >= 4 ? 1 : 0;
    if (Scalar(covered) < opt_.finish.redundantShare * Scalar(seen[k].size())) continue;
    out[k] = 1;
    --kept;
    for (int pid : seen[k]) --count[static_cast<std::size_t>(pid)];
  }
  return out;
}

/// After the global bundle adjustment (keyframe poses `before` it): every adjusted keyframe's
/// frame takes its adjusted pose, and every other posed frame (a left-out keyframe's included)
/// moves with the adjusted keyframe before it, T ← T'_k·T_k⁻¹·T (its pose relative to that
/// keyframe kept, as tracking made it). The adjustment may reshape a segment by more than
/// refineAllFrames' gate (a segment rebuilt from a short pair, tied to the rest of the map by
/// revisits: metres in the kitchen passes); a frame left at its old pose would keep the old
/// shape, off its own keyframes. A frame whose keyframe before it is in another segment (the
/// frame before a relocalisation by place, posed in the segment it re-entered) moves with the
/// next keyframe of its own segment. `kept`: the adjusted keyframes, in order.
template <typename Scalar>
void MonoSlam<Scalar>::carryFramesWithKeyframes(const std::vector<SE3T>& before, const std::vector<int>& kept) {
  if (kept.empty()) return;
  std::size_t i = 0;  // index into kept
  for (std::size_t f = 0; f < frames_.size(); ++f) {
    while (i + 1 < kept.size() && keyframes_[static_cast<std::size_t>(kept[i + 1])].frame <= static_cast<int>(f)) ++i;
    const std::size_t k = static_cast<std::size_t>(kept[i]);
    if (keyframes_[k].frame > static_cast<int>(f)) continue;  // before the first keyframe
    Frame& fr = frames_[f];
    if (keyframes_[k].frame == static_cast<int>(f)) {
      fr.T = keyframes_[k].T;
      continue;
    }
    if (!fr.posed) continue;
    std::size_t c = i;
    while (c < kept.size() && keyframes_[static_cast<std::size_t>(kept[c])].segment != fr.segment) ++c;
    if (c == kept.size()) continue;
    const std::size_t kc = static_cast<std::size_t>(kept[c]);
    fr.T = keyframes_[kc].T * before[kc].inverse() * fr.T;
  }
}

template <typename Scalar>
void MonoSlam<Scalar>::refineAllFrames() {
  for (Frame& fr : frames_) {
    std::vector<V3> X;
    std::vector<V2> uv;
    std::vector<int> pids;
    mappedObservations(fr, X, uv, pids);
    if (static_cast<int>(X.size()) < opt_.minInliers) continue;
    PnPRansacOptions<Scalar> po = opt_.pnp;
    po.minInliers = opt_.minInliers;
    if (fr.posed) {
      SE3T T = fr.T;
      std::vector<Scalar> w(X.size(), Scalar(1));
      const SE3T Tcw = T.inverse();
      int used = 0;
      for (std::size_t i = 0; i < X.size(); ++i) {
        const V3 Xc = Tcw * X[i];
        const bool in = Xc(2) > Scalar(0) && (cam_.project(Xc) - uv[i]).norm() < Scalar(3) * po.thresholdPx;
        w[i] = in ? Scalar(1) : Scalar(0);
        used += in ? 1 : 0;
      }
      if (used >= opt_.minInliers) {
        PoseRefineOptions<Scalar> ro = po.refinement;
        ro.maxIterations = 10;
        refinePose(X, uv, &w, cam_, T, ro);
        if (T.translation().allFinite()) fr.T = T;
      }
    } else {
      const PnPRansacResult<Scalar> r = solvePnPRansac(X, uv, cam_, po);
      if (r.ok()) {
        fr.T = r.T_w_c;
        fr.posed = true;
        fr.inliers = r.numInliers;
        if (fr.status == SlamStatus::Interpolated) fr.status = SlamStatus::Tracked;
        // Posed in the world of the points it was resected on (a lost frame before a
        // relocalisation by place saw the segment re-entered): it moves with that segment.
        std::vector<int> votes(segmentParent_.size(), 0);
        for (std::size_t i = 0; i < pids.size(); ++i) {
          const Obs* o = points_[static_cast<std::size_t>(pids[i])].obs.empty() ? nullptr : &points_[static_cast<std::size_t>(pids[i])].obs.front();
          if (r.inliers[i] && o) ++votes[static_cast<std::size_t>(keyframes_[static_cast<std::size_t>(o->kf)].segment)];
        }
        fr.segment = static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
      }
    }
  }
}

/// SlamOptions::finish.sequenceRefine: every frame's observations, with the tracks that are one
/// physical point joined (a track renamed at a reset, tracks that follow the same map point),
/// adjusted together (sequence_refine.hpp). Frames it adjusts are posed from it; the others are
/// left to fillUnposed. False when it found nothing to adjust.
template <typename Scalar>
bool MonoSlam<Scalar>::refineWholeSequence() {
  const int n = static_cast<int>(frames_.size());
  const int nt = static_cast<int>(trackPoint_.size());
  std::vector<int> parent(static_cast<std::size_t>(nt));
  for (int i = 0; i < nt; ++i) parent[static_cast<std::size_t>(i)] = i;
  auto find = [&](int i) {
    while (parent[static_cast<std::size_t>(i)] != i) {
      parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
      i = parent[static_cast<std::size_t>(i)];
    }
    return i;
  };
  auto unite = [&](int a, int b) {
    a = find(a), b = find(b);
    if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
  };
  for (std::size_t i = 0; i < trackAlias_.size(); ++i) {
    if (trackAlias_[i] >= 0) unite(static_cast<int>(i), trackAlias_[i]);
  }
  std::vector<int> firstTrack(points_.size(), -1);
  for (int i = 0; i < nt; ++i) {
    const int pid = trackPoint_[static_cast<std::size_t>(i)];
    if (pid < 0 || !points_[static_cast<std::size_t>(pid)].valid) continue;
    if (firstTrack[static_cast<std::size_t>(pid)] < 0) {
      firstTrack[static_cast<std::size_t>(pid)] = i;
    } else {
      unite(i, firstTrack[static_cast<std::size_t>(pid)]);
    }
  }
  // Place links (SlamOptions::place): the two points of a link are one physical point.
  for (const PlaceLink& l : placeLinks_) {
    for (const auto& pr : l.pairs) {
      const int a = firstTrack[static_cast<std::size_t>(pr.first)], b = firstTrack[static_cast<std::size_t>(pr.second)];
      if (a >= 0 && b >= 0) unite(a, b);
    }
  }
  std::vector<SE3T> poses(static_cast<std::size_t>(n));
  std::vector<char> usable(static_cast<std::size_t>(n));
  std::vector<std::vector<TrackObservation<Scalar>>> obs(static_cast<std::size_t>(n));
  for (int f = 0; f < n; ++f) {
    const Frame& fr = frames_[static_cast<std::size_t>(f)];
    poses[static_cast<std::size_t>(f)] = fr.T;
    usable[static_cast<std::size_t>(f)] = fr.posed ? 2 : (fr.rotationKnown ? 1 : 0);
    auto& o = obs[static_cast<std::size_t>(f)];
    o.resize(fr.obsTrack.size());
    for (std::size_t i = 0; i < fr.obsTrack.size(); ++i) {
      o[i].track = find(fr.obsTrack[i]);
      o[i].uv = V2(Scalar(fr.obsUv[i](0)), Scalar(fr.obsUv[i](1)));
    }
  }
  SequenceRefineResult<Scalar> r = refineSequence(cam_, poses, usable, obs, opt_.sequence);
  if (opt_.log) {
    int adj = 0;
    for (char a : r.adjusted) adj += a;
    opt_.log("sequence refinement: " + std::to_string(adj) + " of " + std::to_string(n) + " frames, " +
             std::to_string(r.points.size()) + " points, " + std::to_string(r.observations) + " observations, rms " +
             std::to_string(double(r.finalRmsPx)) + " px, " + std::to_string(r.iterations) + " iterations, " +
             std::to_string(r.illConditioned) + " frames ill-conditioned" +
             (r.headPriorRounds > 0 ? ", head prior in " + std::to_string(r.headPriorRounds) + " rounds (fit rms " +
                                          std::to_string(double(r.headPriorRms)) + ")"
                                    : std::string()));
  }
  if (r.points.empty()) return false;
  refinedFrames_ = 0;  // the last refinement's count (it runs again after a focal change)
  for (char a : r.adjusted) refinedFrames_ += a;
  for (int f = 0; f < n; ++f) {
    Frame& fr = frames_[static_cast<std::size_t>(f)];
    if (r.adjusted[static_cast<std::size_t>(f)]) {
      fr.T = r.poses[static_cast<std::size_t>(f)];
      fr.posed = true;
      fr.rotationKnown = true;
      if (fr.status == SlamStatus::Interpolated) fr.status = SlamStatus::Tracked;
    } else if (r.carried[static_cast<std::size_t>(f)] && fr.inliers >= 2 * opt_.minInliers) {
      // Tracked on plenty of points but not adjusted (a long sequence is subsampled): its pose
      // moves with its neighbours'. A weakly tracked one (a head turn running out of map) is
      // left to the gap filling below.
      fr.T = r.poses[static_cast<std::size_t>(f)];
    } else {
      fr.posed = false;
      if (fr.status == SlamStatus::Tracked) fr.status = SlamStatus::Interpolated;
    }
  }
  fillUnposed();
  seqPoints_ = std::move(r.points);
  seqPointObs_ = std::move(r.pointObs);
  return true;
}

/// SlamOptions::finish.refineFocal with the sequence refinement: the focal profile (focal_refine.hpp)
/// on a bundle-adjustment problem of the refined points and at most finish.focalMaxFrames of the
/// adjusted frames (evenly spaced, finish.focalFrameSpacing apart at least; each profile step is one
/// adjustment). True when the focal
/// changed (the caller refines the sequence again with it).
template <typename Scalar>
bool MonoSlam<Scalar>::refineFocalOnSequence() {
  std::vector<int> posedFrames;
  for (int f = 0; f < static_cast<int>(frames_.size()); ++f) {
    if (frames_[static_cast<std::size_t>(f)].posed) posedFrames.push_back(f);
  }
  focalAttempted_ = true;
  if (posedFrames.size() < 3) {
    focal_ = FocalRefineResult<Scalar>();
    focal_.guessFx = focal_.fx = cam_.fx;
    focal_.fy = cam_.fy;
    focal_.reason = "too few posed frames for the focal";
    return false;
  }
  const std::size_t step = std::max<std::size_t>(static_cast<std::size_t>(std::max(1, opt_.finish.focalFrameSpacing)),
                                                 (posedFrames.size() + opt_.finish.focalMaxFrames - 1) / static_cast<std::size_t>(std::max(1, opt_.finish.focalMaxFrames)));
  BAProblem<Scalar> P;
  P.camera = cam_;
  std::vector<int> poseOf(frames_.size(), -1);
  for (std::size_t i = 0; i < posedFrames.size(); i += std::max<std::size_t>(1, step)) {
    poseOf[static_cast<std::size_t>(posedFrames[i])] = static_cast<int>(P.poses.size());
    P.poses.push_back(frames_[static_cast<std::size_t>(posedFrames[i])].T);
  }
  for (std::size_t j = 0; j < seqPoints_.size(); ++j) {
    if (addTrackObservations(P, static_cast<int>(P.points.size()), seqPointObs_[j], poseOf, 2)) P.points.push_back(seqPoints_[j]);
  }
  P.poseFixed.assign(P.poses.size(), 0);
  P.poseFixed[0] = 1;
  addFarthestScalePrior(P, 0);
  FocalRefineOptions<Scalar> fo = opt_.focal;
  fo.minStdLog = std::max(fo.minStdLog, opt_.finish.focalMinStd);
  fo.ba = mapBAOptions(opt_.globalIterations);
  focal_ = refineFocal(P, fo);
  if (opt_.log) {
    opt_.log("focal (sequence, " + std::to_string(P.poses.size()) + " frames, " + std::to_string(P.points.size()) + " points): " +
             std::string(focal_.changed ? "refined " : "kept ") + std::to_string(double(P.camera.fx)) + " px (guess " +
             std::to_string(double(focal_.guessFx)) + ", std " + std::to_string(double(100 * focal_.stdLog)) + " %, " +
             std::to_string(focal_.evaluations) + " BAs): " + focal_.reason);
  }
  if (!focal_.changed) return false;
  cam_ = P.camera;
  opt_.twoView.focalPx = Scalar(0.5) * (cam_.fx + cam_.fy);
  // The problem holds the adjustment at the new focal: its frames take those poses, the other
  // posed frames move with the nearest of them (T' = T'_a·T_a⁻¹·T), so that the next refinement
  // starts from poses that fit the new focal.
  std::vector<SE3T> before(frames_.size());
  for (std::size_t f = 0; f < frames_.size(); ++f) before[f] = frames_[f].T;
  for (std::size_t f = 0; f < frames_.size(); ++f) {
    if (poseOf[f] >= 0) frames_[f].T = P.poses[static_cast<std::size_t>(poseOf[f])];
  }
  for (std::size_t f = 0, last = frames_.size(); f < frames_.size(); ++f) {
    if (poseOf[f] >= 0) {
      last = f;
      continue;
    }
    std::size_t ref = last;
    for (std::size_t g = f + 1; ref == frames_.size() && g < frames_.size(); ++g) ref = poseOf[g] >= 0 ? g : ref;
    if (ref < frames_.size()) frames_[f].T = frames_[ref].T * before[ref].inverse() * before[f];
  }
  return true;
}

/// Frames without a map pose: translation (and rotation where the rays gave none) interpolated
/// between the nearest posed frames; held at the ends. A lost frame keeps the rays' rotation:
/// a SLERP between the posed frames around a loss cuts a fast turn inside it short (fast_turns
/// seed 4: lost frames 33° off on average, 1.0° with the rays).
/// Only the frames in [from, to) (all by default) are changed.
template <typename Scalar>
void MonoSlam<Scalar>::fillUnposed(int from, int to) {
  const int n = static_cast<int>(frames_.size());
  if (to < 0) to = n;
  int prev = -1;
  for (int i = 0; i < to; ++i) {
    if (frames_[static_cast<std::size_t>(i)].posed) {
      prev = i;
      continue;
    }
    if (i < from) continue;
    int next = i + 1;
    while (next < n && !frames_[static_cast<std::size_t>(next)].posed) ++next;
    Frame& fr = frames_[static_cast<std::size_t>(i)];
    if (prev < 0 && next >= n) continue;  // nothing posed at all: rotation-only output
    if (prev < 0) {
      fr.T = SE3T(fr.rotationKnown ? fr.T.rotation() : frames_[static_cast<std::size_t>(next)].T.rotation(),
                  frames_[static_cast<std::size_t>(next)].T.translation());
    } else if (next >= n) {
      fr.T = SE3T(fr.rotationKnown ? fr.T.rotation() : frames_[static_cast<std::size_t>(prev)].T.rotation(),
                  frames_[static_cast<std::size_t>(prev)].T.translation());
    } else {
      const Scalar a = Scalar(i - prev) / Scalar(next - prev);
      const SE3T& A = frames_[static_cast<std::size_t>(prev)].T;
      const SE3T& B = frames_[static_cast<std::size_t>(next)].T;
      fr.T = SE3T(fr.rotationKnown ? fr.T.rotation() : interpolate(A.rotation(), B.rotation(), a),
                  V3((Scalar(1) - a) * A.translation() + a * B.translation()));
    }
  }
}

/// Global bundle adjustment, per-frame refinement, interpolation of the remaining frames, and
/// the result in the first frame's world. Call once, after the last frame.
template <typename Scalar>
SlamResult<Scalar> MonoSlam<Scalar>::finish() {
  if (finished_) throw Error("MonoSlam: finish() called twice");
  finished_ = true;
  // No frame comes after finish(): the images kept for tracking, re-finding and relocalisation
  // (up to 20 pyramids, about 30 MB at 640×480) go before the sequence refinement needs its
  // memory.
  prevPyr_ = ImagePyramid();
  curPyr_ = ImagePyramid();
  std::deque<BackFrame>().swap(backPyr_);
  std::vector<KeyframePyramid>().swap(relocPyr_);
  std::vector<KeyframePyramid>().swap(linkPyr_);
  lastKfPyr_ = KeyframePyramid();
  curMask_ = ImageU8();
  std::vector<unsigned char>().swap(maskTmp_);
  SlamResult<Scalar> res;
  const int n = static_cast<int>(frames_.size());
  if (n == 0) return res;
  if (opt_.link.enabled && resets_ > 0) applySegmentLinks();
  if (opt_.join.headModel && resets_ > 0) joinSegmentPairsByHead();
  if (opt_.finish.globalBundleAdjustment && keyframes_.size() >= 2) {
    const std::vector<char> leftOut = redundantKeyframes();
    std::vector<int> kept;
    for (std::size_t k = 0; k < keyframes_.size(); ++k) {
      if (!leftOut[k]) kept.push_back(static_cast<int>(k));
    }
    // With the sequence refinement on, the focal is refined on its problem instead (every
    // frame's tracks, far more of the motion that determines the focal than the keyframes').
    std::vector<SE3T> before(keyframes_.size());
    for (std::size_t k = 0; k < keyframes_.size(); ++k) before[k] = keyframes_[k].T;
    const BAReport<Scalar> rep = adjust(kept, opt_.globalIterations, true, opt_.finish.refineFocal && !opt_.finish.sequenceRefine, &leftOut);
    carryFramesWithKeyframes(before, kept);
    // a left-out keyframe takes its frame's carried pose
    for (std::size_t k = 0; k < keyframes_.size(); ++k) {
      if (leftOut[k]) keyframes_[k].T = frames_[static_cast<std::size_t>(keyframes_[k].frame)].T;
    }
    adjustedKeyframes_ = static_cast<int>(kept.size());
    if (opt_.log) {
      opt_.log("finish: global bundle adjustment of " + std::to_string(kept.size()) + " of " +
               std::to_string(keyframes_.size()) + " keyframes (the others redundant), " +
               std::to_string(rep.usedObservations) + " observations, " + std::to_string(rep.iterations) +
               " iterations, " + (rep.implicitSchur ? "implicit Schur" : rep.iterativeSolver ? "conjugate gradients" :
                                  rep.sparseSolver ? "sparse Cholesky" : "dense Cholesky"));
    }
  }
  if (opt_.finish.refineFrames && !points_.empty()) refineAllFrames();
  fillUnposed();
  if (opt_.finish.sequenceRefine && opt_.join.headModel && opt_.join.headModelAll && opt_.join.beforeRefine && resets_ > 0) {
    joinAllSegmentsByHead(false);
  }
  if (opt_.place.enabled && resets_ > 0) placedSegments_ = placeSegmentsByLinks();
  bool sequenceDone = opt_.finish.sequenceRefine && everInitialised_ && refineWholeSequence();
  // The refinement's points and inliers were chosen at the old focal: repeat while it moves
  // (at most 3 times); the result reports the first guess and the last estimate.
  if (sequenceDone && opt_.finish.refineFocal) {
    const Scalar guess = cam_.fx;
    bool changed = false;
    for (int round = 0; sequenceDone && round < 3 && refineFocalOnSequence(); ++round) {
      changed = true;
      sequenceDone = refineWholeSequence();
    }
    if (changed) {
      // the last round's own reason (it may have kept its guess, the previous round's estimate)
      focal_.reason = "refined by the bundle adjustment of the sequence" +
                      (focal_.changed ? std::string() : " (last round: " + focal_.reason + ")");
      focal_.guessFx = guess;
      focal_.changed = true;
      focal_.accepted = true;
      focal_.fx = cam_.fx;
      focal_.fy = cam_.fy;
    }
  }
  if (opt_.join.headModel && opt_.join.headModelAll && resets_ > 0) joinAllSegmentsByHead();
  if (opt_.finish.headModelFill && everInitialised_) {
    std::vector<SE3T> T(static_cast<std::size_t>(n));
    std::vector<char> posed(static_cast<std::size_t>(n)), rot(static_cast<std::size_t>(n));
    std::string headLog;
    for (int f = 0; f < n; ++f) {
      T[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].T;
      posed[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].posed;
      rot[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].rotationKnown;
    }
    const int changed = fillGapsByHeadModel(T, posed, rot, opt_.headModel, opt_.log ? &headLog : nullptr);
    headModelFrames_ = changed;
    for (int f = 0; f < n; ++f) frames_[static_cast<std::size_t>(f)].T = T[static_cast<std::size_t>(f)];
    if (opt_.log) opt_.log("head model: " + std::to_string(changed) + " unposed frames placed;" + headLog);
  }
  // Express everything in the first frame's camera.
  const SE3T T0inv = frames_[0].T.inverse();
  res.poses.resize(static_cast<std::size_t>(n));
  res.status.resize(static_cast<std::size_t>(n));
  res.keyframe.resize(static_cast<std::size_t>(n), 0);
  res.inliers.resize(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i) {
    const Frame& fr = frames_[static_cast<std::size_t>(i)];
    res.poses[static_cast<std::size_t>(i)] = T0inv * fr.T;
    res.status[static_cast<std::size_t>(i)] = fr.status;
    res.inliers[static_cast<std::size_t>(i)] = fr.inliers;
  }
  for (const Keyframe& kf : keyframes_) res.keyframe[static_cast<std::size_t>(kf.frame)] = 1;
  if (sequenceDone) {
    for (std::size_t j = 0; j < seqPoints_.size(); ++j) {
      if (seqPointObs_[j].empty() || !placedFrame(seqPointObs_[j].front().first)) res.points.push_back(T0inv * seqPoints_[j]);
    }
  } else {
    for (const MapPoint& p : points_) {
      if (p.valid && (p.obs.empty() || !placedFrame(keyframes_[static_cast<std::size_t>(p.obs.front().kf)].frame))) res.points.push_back(T0inv * p.X);
    }
  }
  // Keyframe depths (camera z does not depend on the world frame).
  if (sequenceDone) {
    // From the refined points: each keyframe's observations of them, off its hand mask.
    std::vector<int> kfOfFrame(static_cast<std::size_t>(n), -1);
    for (std::size_t k = 0; k < keyframes_.size(); ++k) kfOfFrame[static_cast<std::size_t>(keyframes_[k].frame)] = static_cast<int>(k);
    res.keyframeDepths.resize(keyframes_.size());
    for (std::size_t k = 0; k < keyframes_.size(); ++k) res.keyframeDepths[k].frame = keyframes_[k].frame;
    for (std::size_t j = 0; j < seqPoints_.size(); ++j) {
      for (const auto& o : seqPointObs_[j]) {
        const int k = kfOfFrame[static_cast<std::size_t>(o.first)];
        if (k < 0 || placedFrame(o.first) || keyframes_[static_cast<std::size_t>(k)].mask.test(o.second(0), o.second(1))) continue;
        const V3 Xc = frames_[static_cast<std::size_t>(o.first)].T.inverse() * seqPoints_[j];
        if (!(Xc(2) > Scalar(0))) continue;
        res.keyframeDepths[static_cast<std::size_t>(k)].uv.push_back(o.second);
        res.keyframeDepths[static_cast<std::size_t>(k)].depth.push_back(Xc(2));
      }
    }
  }
  for (std::size_t k = 0; k < keyframes_.size() && !sequenceDone; ++k) {
    SlamKeyframeDepths<Scalar> d;
    d.frame = keyframes_[k].frame;
    const SE3T Tcw = keyframes_[k].T.inverse();
    for (int pid : placedFrame(d.frame) ? std::vector<int>() : keyframes_[k].points) {
      const MapPoint& p = points_[static_cast<std::size_t>(pid)];
      if (!p.valid) continue;
      for (const Obs& o : p.obs) {
        if (o.kf != static_cast<int>(k)) continue;
        if (keyframes_[k].mask.test(o.uv(0), o.uv(1))) break;
        const V3 Xc = Tcw * p.X;
        if (Xc(2) > Scalar(0)) {
          d.uv.push_back(o.uv);
          d.depth.push_back(Xc(2));
        }
        break;
      }
    }
    res.keyframeDepths.push_back(std::move(d));
  }
  res.numKeyframes = static_cast<int>(keyframes_.size());
  res.numAdjustedKeyframes = adjustedKeyframes_;
  res.numLosses = losses_;
  res.numResets = resets_;
  res.numRelocalisations = relocalisations_;
  res.numPlaceRelocalisations = placeRelocalisations_;
  res.numRevisitPoints = revisitPoints_;
  res.numPlaceLinks = static_cast<int>(placeLinks_.size());
  for (const PlaceLink& l : placeLinks_) {
    res.placeLinks.push_back({keyframes_[static_cast<std::size_t>(l.kf)].frame, keyframes_[static_cast<std::size_t>(l.oldKf)].frame,
                              static_cast<int>(l.pairs.size())});
  }
  res.numPlacedSegments = placedSegments_;
  res.numRefinedFrames = refinedFrames_;
  res.numHeadModelFrames = headModelFrames_;
  res.initialised = everInitialised_;
  res.camera = cam_;
  res.focalAttempted = focalAttempted_;
  res.focal = focal_;
  if (!focalAttempted_) {
    res.focal.guessFx = res.focal.fx = cam_.fx;
    res.focal.fy = cam_.fy;
    res.focal.reason = opt_.finish.refineFocal ? "no map for the global bundle adjustment" : "off";
  }
  return expandFrameStep(std::move(res), opt_.frameStep, inputFrames_);  // the frames between tracked ones
}

}  // namespace hawor
