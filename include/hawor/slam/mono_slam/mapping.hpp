// hawor/slam/mono_slam/mapping.hpp — MonoSlam's mapping: keyframes, their kept images,
// triangulation, the local and global bundle adjustment.
// Member functions of MonoSlam (slam/mono_slam.hpp: the class, its state and the overview);
// included at the end of that header.
#pragma once

#include "../mono_slam.hpp"

namespace hawor {

/// Appends the current pyramid as keyframe k's to `store`, at most `capacity` entries of its
/// kind (`anchor`) there (the oldest entry of that kind goes, its buffers reused); the store
/// stays sorted by keyframe.
template <typename Scalar>
void MonoSlam<Scalar>::keepPyramid(std::vector<KeyframePyramid>& store, int capacity, int k, bool anchor) {
  auto ofKind = [anchor](const KeyframePyramid& e) { return e.anchor == anchor; };
  const auto oldest = std::find_if(store.begin(), store.end(), ofKind);
  if (oldest != store.end() && std::count_if(store.begin(), store.end(), ofKind) >= capacity) {
    std::rotate(oldest, oldest + 1, store.end());  // to the back, its buffers reused
  } else {
    store.emplace_back();
  }
  store.back().kf = k;
  store.back().pyr = curPyr_;
  store.back().anchor = anchor;
}

/// relocPyr_: keyframe k joins as an anchor when no anchor of the segment looks within
/// reloc.anchorDeg of its direction from within reloc.anchorDepths median scene depths, else as
/// a recent one; each kind drops its oldest beyond its capacity (keepPyramid).
template <typename Scalar>
void MonoSlam<Scalar>::keepRelocPyramid(int k) {
  const Keyframe& kk = keyframes_[static_cast<std::size_t>(k)];
  const V3 z = kk.T.rotationMatrix().col(2);
  const Scalar cosMax = std::cos(opt_.reloc.anchorDeg * Constants<Scalar>::pi() / Scalar(180));
  const Scalar maxDist = opt_.reloc.anchorDepths * lastMedianDepth_;
  const bool anchor = opt_.reloc.anchors > 0 && lastMedianDepth_ > Scalar(0) &&
                      std::none_of(relocPyr_.begin(), relocPyr_.end(), [&](const KeyframePyramid& e) {
                        const Keyframe& ka = keyframes_[static_cast<std::size_t>(e.kf)];
                        return e.anchor && ka.segment == kk.segment && V3(ka.T.rotationMatrix().col(2)).dot(z) >= cosMax &&
                               (ka.T.translation() - kk.T.translation()).norm() <= maxDist;
                      });
  keepPyramid(relocPyr_, anchor ? opt_.reloc.anchors : opt_.reloc.keyframes, k, anchor);
}

/// After a keyframe's points are in: sliding-window bundle adjustment, the frame takes the
/// adjusted pose, new corners fill the grid (their first keyframe observation is this one).
template <typename Scalar>
void MonoSlam<Scalar>::closeKeyframe(Frame& fr) {
  const int k = static_cast<int>(keyframes_.size()) - 1;
  adjust(lastWindow(), opt_.localIterations, false);
  fr.T = keyframes_.back().T;
  const bool current = keyframes_.back().frame == static_cast<int>(frames_.size()) - 1;
  // The current frame's pyramid, for finding this keyframe's points again later.
  if (opt_.link.enabled && current) {
    lastKfPyr_.kf = k;
    lastKfPyr_.pyr.levels = curPyr_.levels;  // (buffers reused)
  }
  if (opt_.reloc.enabled && opt_.reloc.keyframes > 0 && current &&
      (relocPyr_.empty() ||
       keyframes_.back().frame - keyframes_[static_cast<std::size_t>(relocPyr_.back().kf)].frame >= opt_.reloc.spacing)) {
    keepRelocPyramid(k);
  }
  if (opt_.place.enabled && current) describeAndLinkKeyframe(k);
  lastKfInliers_ = countMapped();
  framesSinceKf_ = 0;
  replenish();
  for (Track& t : tracks_) {
    if (t.point < 0 && t.kfObs.empty()) t.kfObs = {Obs{k, V2(Scalar(t.uv(0)), Scalar(t.uv(1)))}};
  }
  updateMedianDepth();
}

template <typename Scalar>
void MonoSlam<Scalar>::insertKeyframe(int f) {
  if (opt_.revisit.enabled && opt_.reloc.enabled) searchRevisits(f);
  if (opt_.link.enabled) searchSegmentLinks(f);
  Frame& fr = frames_.back();
  const int k = static_cast<int>(keyframes_.size());
  keyframes_.push_back(Keyframe{f, fr.T, hasMask_ ? CoarseMask(curMask_, opt_.maskBlock) : CoarseMask(), {}, segment_, {}, {}, {}});
  const SE3T Tcw = fr.T.inverse();
  const Scalar cosMin = std::cos(opt_.minTriangulationDeg * Constants<Scalar>::pi() / Scalar(180));
  const Scalar maxErr2 = opt_.maxReprojPx * opt_.maxReprojPx;
  int triCand = 0, triParallax = 0, triNew = 0, triBehind = 0, triReproj = 0;
  for (Track& t : tracks_) {
    const V2 u(Scalar(t.uv(0)), Scalar(t.uv(1)));
    if (t.point >= 0) {
      points_[static_cast<std::size_t>(t.point)].obs.push_back(Obs{k, u});
      keyframes_.back().points.push_back(t.point);
      continue;
    }
    t.kfObs.push_back(Obs{k, u});
    if (t.kfObs.size() < 2) continue;
    // Triangulate from the first keyframe observation and this one.
    const Obs& o0 = t.kfObs.front();
    const SE3T T0cw = keyframes_[static_cast<std::size_t>(o0.kf)].T.inverse();
    const V2 x0 = normalised(Vec2f(float(o0.uv(0)), float(o0.uv(1))));
    const V2 x1 = normalised(t.uv);
    const V3 r0 = keyframes_[static_cast<std::size_t>(o0.kf)].T.rotationMatrix() * V3(x0(0), x0(1), Scalar(1));
    const V3 r1 = fr.T.rotationMatrix() * V3(x1(0), x1(1), Scalar(1));
    ++triCand;
    if (r0.normalized().dot(r1.normalized()) > cosMin) continue;  // not enough parallax yet
    ++triParallax;
    V3 X;
    if (!triangulateDLT(T0cw, Tcw, x0, x1, X)) continue;
    bool good = true;
    for (const Obs& o : t.kfObs) {
      const V3 Xc = keyframes_[static_cast<std::size_t>(o.kf)].T.inverse() * X;
      if (!(Xc(2) > Scalar(0))) {
        good = false;
        ++triBehind;
        break;
      }
      if ((cam_.project(Xc) - o.uv).squaredNorm() > maxErr2) {
        good = false;
        ++triReproj;
        break;
      }
    }
    if (!good) continue;
    ++triNew;
    MapPoint p;
    p.X = X;
    p.obs = t.kfObs;
    t.point = addPoint(std::move(p), t.id);
    t.kfObs.clear();
  }
  const int before = countMapped();
  closeKeyframe(fr);
  if (opt_.log) {
    opt_.log("frame " + std::to_string(f) + ": keyframe " + std::to_string(k) + ", mapped tracks " +
             std::to_string(before) + " -> " + std::to_string(lastKfInliers_) + " after bundle adjustment; " +
             "triangulation: " + std::to_string(triCand) + " candidates, " + std::to_string(triParallax) +
             " with parallax, " + std::to_string(triNew) + " new points (" + std::to_string(triBehind) +
             " behind a camera, " + std::to_string(triReproj) + " off in a keyframe)");
  }
}

template <typename Scalar>
void MonoSlam<Scalar>::updateMedianDepth() {
  const Keyframe& kf = keyframes_.back();
  const SE3T Tcw = kf.T.inverse();
  std::vector<Scalar> d;
  for (int pid : kf.points) {
    const MapPoint& p = points_[static_cast<std::size_t>(pid)];
    if (!p.valid) continue;
    const V3 Xc = Tcw * p.X;
    if (Xc(2) > Scalar(0)) d.push_back(Xc(2));
  }
  if (d.size() >= 10) {
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
    lastMedianDepth_ = d[d.size() / 2];
  }
}

template <typename Scalar>
std::vector<int> MonoSlam<Scalar>::lastWindow() const {
  std::vector<int> w;
  for (int k = static_cast<int>(keyframes_.size()) - 1; k >= 0 && static_cast<int>(w.size()) < opt_.windowKeyframes; --k) {
    if (keyframes_[static_cast<std::size_t>(k)].segment != segment_) break;
    w.push_back(k);
  }
  std::reverse(w.begin(), w.end());
  return w;
}

/// The map's bundle-adjustment settings (keyframe windows, the global BA, the focal profile):
/// Huber at 2σ with σ = 1 px.
template <typename Scalar>
BAOptions<Scalar> MonoSlam<Scalar>::mapBAOptions(int iterations) {
  BAOptions<Scalar> bo;
  bo.maxIterations = iterations;
  bo.loss = RobustLoss::Huber;
  bo.sigmaPx = Scalar(1);
  bo.robustScale = Scalar(2);
  bo.functionTolerance = Scalar(1e-5);
  return bo;
}

/// Bundle adjustment of the keyframes `window` (free) and their points; keyframes outside the
/// window that see those points are fixed. Gauge: the first keyframe of each segment is fixed
/// and its first baseline held by a scale prior when no other fixed keyframe anchors the scale.
template <typename Scalar>
BAReport<Scalar> MonoSlam<Scalar>::adjust(const std::vector<int>& window, int iterations, bool global, bool withFocal,
                                          const std::vector<char>* leftOut) {
  const auto out = [&](int k) { return leftOut && (*leftOut)[static_cast<std::size_t>(k)]; };
  BAReport<Scalar> rep;
  if (window.empty()) return rep;
  std::vector<int> kfVar(keyframes_.size(), -1), ptVar(points_.size(), -1);
  BAProblem<Scalar> P;
  P.camera = cam_;
  std::vector<int> kfOf, ptOf;
  auto addKf = [&](int k, bool fixed) {
    if (kfVar[static_cast<std::size_t>(k)] >= 0) return;
    kfVar[static_cast<std::size_t>(k)] = static_cast<int>(P.poses.size());
    P.poses.push_back(keyframes_[static_cast<std::size_t>(k)].T);
    P.poseFixed.push_back(fixed ? 1 : 0);
    kfOf.push_back(k);
  };
  for (int k : window) addKf(k, false);
  for (int k : window) {
    for (int pid : keyframes_[static_cast<std::size_t>(k)].points) {
      if (!points_[static_cast<std::size_t>(pid)].valid || ptVar[static_cast<std::size_t>(pid)] >= 0) continue;
      ptVar[static_cast<std::size_t>(pid)] = static_cast<int>(P.points.size());
      P.points.push_back(points_[static_cast<std::size_t>(pid)].X);
      ptOf.push_back(pid);
    }
  }
  if (P.points.empty()) return rep;
  for (int pid : ptOf) {
    for (const Obs& o : points_[static_cast<std::size_t>(pid)].obs) {
      if (kfVar[static_cast<std::size_t>(o.kf)] < 0 && !out(o.kf)) addKf(o.kf, true);
    }
  }
  // Gauge, per segment (docs/design.md §5: monocular, 7 freedoms). Local: the keyframes outside the
  // window that see its points are fixed; when fewer than two of a segment's are, its oldest
  // free keyframe is fixed too, and with none at all its first baseline is held by a scale
  // prior. Global: each segment's first keyframe fixed, a scale prior on its first baseline.
  std::vector<int> segs;
  for (int k : kfOf) {
    const int seg = keyframes_[static_cast<std::size_t>(k)].segment;
    if (std::find(segs.begin(), segs.end(), seg) == segs.end()) segs.push_back(seg);
  }
  for (int seg : segs) {
    std::vector<int> freeV;  // problem indices of the segment's free keyframes, oldest first
    int fixedInSeg = 0;
    for (std::size_t v = 0; v < kfOf.size(); ++v) {
      if (keyframes_[static_cast<std::size_t>(kfOf[v])].segment != seg) continue;
      if (P.poseFixed[v]) {
        ++fixedInSeg;
      } else {
        freeV.push_back(static_cast<int>(v));
      }
    }
    std::sort(freeV.begin(), freeV.end(), [&](int a, int b) { return kfOf[static_cast<std::size_t>(a)] < kfOf[static_cast<std::size_t>(b)]; });
    if (freeV.empty()) continue;
    if (global || fixedInSeg == 0) {
      P.poseFixed[static_cast<std::size_t>(freeV[0])] = 1;
      if (freeV.size() >= 2) {
        BAScalePrior<Scalar> sp;
        sp.poseA = freeV[0];
        sp.poseB = freeV[1];
        sp.distance = (P.poses[static_cast<std::size_t>(sp.poseA)].translation() -
                       P.poses[static_cast<std::size_t>(sp.poseB)].translation()).norm();
        sp.weight = Scalar(1e4) / std::max(sp.distance * sp.distance, Scalar(1e-12));
        if (sp.distance > Scalar(0)) P.scalePriors.push_back(sp);
      }
    } else if (fixedInSeg == 1) {
      P.poseFixed[static_cast<std::size_t>(freeV[0])] = 1;
    }
  }
  // Observations, masked residuals at weight 0 (back-end masking).
  for (std::size_t j = 0; j < ptOf.size(); ++j) {
    const MapPoint& p = points_[static_cast<std::size_t>(ptOf[j])];
    for (const Obs& o : p.obs) {
      if (out(o.kf)) continue;
      BAObservation<Scalar> ob;
      ob.pose = kfVar[static_cast<std::size_t>(o.kf)];
      ob.point = static_cast<int>(j);
      ob.uv = o.uv;
      const Keyframe& kf = keyframes_[static_cast<std::size_t>(o.kf)];
      if (opt_.useMasks && !kf.mask.bits.empty()) {
        const V3 Xc = kf.T.inverse() * p.X;
        const V2 q = Xc(2) > Scalar(0) ? cam_.project(Xc) : o.uv;
        if (kf.mask.test(o.uv(0), o.uv(1)) || kf.mask.test(q(0), q(1))) ob.weight = Scalar(0);
      }
      P.observations.push_back(ob);
    }
  }
  const BAOptions<Scalar> bo = mapBAOptions(iterations);
  if (withFocal) {
    FocalRefineOptions<Scalar> fo = opt_.focal;
    fo.ba = bo;
    focal_ = refineFocal(P, fo);
    focalAttempted_ = true;
    if (focal_.changed) {
      cam_ = P.camera;
      opt_.twoView.focalPx = Scalar(0.5) * (cam_.fx + cam_.fy);
    }
    if (opt_.log) {
      opt_.log("focal: " + std::string(focal_.changed ? "refined " : "kept ") + std::to_string(double(cam_.fx)) +
               " px (guess " + std::to_string(double(focal_.guessFx)) + ", std " +
               std::to_string(double(100 * focal_.stdLog)) + " %, " + std::to_string(focal_.evaluations) +
               " BAs): " + focal_.reason);
    }
  } else {
    rep = bundleAdjust(P, bo);
  }
  for (std::size_t v = 0; v < kfOf.size(); ++v) {
    if (!P.poseFixed[v]) keyframes_[static_cast<std::size_t>(kfOf[v])].T = P.poses[v];
  }
  for (std::size_t j = 0; j < ptOf.size(); ++j) points_[static_cast<std::size_t>(ptOf[j])].X = P.points[j];
  cullObservations(ptOf, leftOut);
  return rep;
}

/// Drops observations whose reprojection error exceeds maxReprojPx (or that are behind the
/// camera); a point left with fewer than two observations is invalid, and its track unmapped.
/// Observations by `leftOut` keyframes (not adjusted: their poses are stale) are kept.
template <typename Scalar>
void MonoSlam<Scalar>::cullObservations(const std::vector<int>& pts, const std::vector<char>* leftOut) {
  const Scalar maxErr2 = Scalar(4) * opt_.maxReprojPx * opt_.maxReprojPx;
  for (int pid : pts) {
    MapPoint& p = points_[static_cast<std::size_t>(pid)];
    std::size_t w = 0;
    for (std::size_t i = 0; i < p.obs.size(); ++i) {
      if (leftOut && (*leftOut)[static_cast<std::size_t>(p.obs[i].kf)]) {
        p.obs[w++] = p.obs[i];
        continue;
      }
      const Keyframe& kf = keyframes_[static_cast<std::size_t>(p.obs[i].kf)];
      const V3 Xc = kf.T.inverse() * p.X;
      if (Xc(2) > Scalar(0) && (cam_.project(Xc) - p.obs[i].uv).squaredNorm() <= maxErr2) p.obs[w++] = p.obs[i];
    }
    p.obs.resize(w);
    if (w < 2) p.valid = false;
  }
  std::vector<char> drop(tracks_.size(), 0);
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    const Track& t = tracks_[i];
    if (t.point >= 0 && !points_[static_cast<std::size_t>(t.point)].valid) drop[i] = 1;
  }
  removeTracks(drop);
}

/// The map points and pixels of the tracks from index `before` on (those a searchMapPoints just
/// added), for PnP.
template <typename Scalar>
void MonoSlam<Scalar>::foundCorrespondences(std::size_t before, std::vector<V3>& X, std::vector<V2>& uv) const {
  for (std::size_t i = before; i < tracks_.size(); ++i) {
    X.push_back(points_[static_cast<std::size_t>(tracks_[i].point)].X);
    uv.push_back(V2(Scalar(tracks_[i].uv(0)), Scalar(tracks_[i].uv(1))));
  }
}

/// Drops the tracks from index `before` on (a search's finds that were not kept).
template <typename Scalar>
void MonoSlam<Scalar>::removeTracksFrom(std::size_t before) {
  std::vector<char> drop(tracks_.size(), 0);
  for (std::size_t i = before; i < tracks_.size(); ++i) drop[i] = 1;
  removeTracks(drop);
}

/// Removes the flagged tracks (keeping prevUv_ aligned with tracks_).
template <typename Scalar>
void MonoSlam<Scalar>::removeTracks(const std::vector<char>& drop) {
  std::size_t w = 0;
  const bool withPrev = prevUv_.size() == tracks_.size();
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    if (drop[i]) continue;
    if (withPrev) prevUv_[w] = prevUv_[i];
    if (w != i) tracks_[w] = std::move(tracks_[i]);
    ++w;
  }
  tracks_.resize(w);
  if (withPrev) prevUv_.resize(w);
}

}  // namespace hawor
