// hawor/slam/mono_slam/relocalisation.hpp — MonoSlam's relocalisation and place search: the lost
// map, revisits of old keyframes, segment links across a broken rotation chain.
// Member functions of MonoSlam (slam/mono_slam.hpp: the class, its state and the overview);
// included at the end of that header.
#pragma once

#include "../mono_slam.hpp"

namespace hawor {

/// SlamOptions::reloc.enabled: the points of the kept keyframes searched under the frame's guess
/// (frames_.back().T: rotation from the rays, position held), then PnP-RANSAC on every mapped
/// track. Success: the frame is Relocalised in the old segment (a reset without a new map is
/// undone) and becomes a keyframe. Failure: the tracks the search added are dropped again.
template <typename Scalar>
bool MonoSlam<Scalar>::relocalise(int f) {
  Frame& fr = frames_.back();
  if (!opt_.reloc.enabled || relocPyr_.empty()) return false;
  // The guess's rotation is the rays' when the ray chain is unbroken since the last posed frame;
  // otherwise (every track died: a hand over the lens, a black frame) it is only held.
  bool chain = true;
  for (int g = f; g > 0 && chain && !frames_[static_cast<std::size_t>(g)].posed; --g) {
    chain = frames_[static_cast<std::size_t>(g)].rotationKnown;
  }
  const std::size_t before = tracks_.size();
  searchMapPoints(f, relocPyr_, fr.T, opt_.reloc.maxShiftPx, opt_.reloc.maxPoints, "relocalisation");
  std::vector<V3> X;
  std::vector<V2> uv;
  std::vector<int> ti;
  mappedTracks(X, uv, ti);
  bool ok = false;
  PnPRansacResult<Scalar> r;
  if (static_cast<int>(X.size()) >= opt_.reloc.minInliers) {
    PnPRansacOptions<Scalar> po = opt_.pnp;
    po.seed = opt_.pnp.seed + 0x5bd1e995u + static_cast<std::uint32_t>(f);
    po.minInliers = opt_.reloc.minInliers;
    r = solvePnPRansac(X, uv, cam_, po);
    // The rays' rotation is near-exact over a short loss: a pose that disagrees with it is a
    // wrong match set (measured: right ones agree within 0.42°, wrong ones are 1-10° off).
    // Without the chain, or when the chain disagrees (its rotation drifts in a fast turn: the
    // rays' pure-rotation fit absorbs the neck's translation, up to 1° a frame), two consecutive
    // relocalisations must agree with the rays' rotation between them instead.
    ok = r.ok() && r.numInliers >= opt_.reloc.minInliers;
    if (ok && chain && rotationAngleDeg(fr.T, r.T_w_c) <= opt_.reloc.maxRotationDeg) {
      ok = true;
    } else if (ok) {
      const SE3T& prevGuess = frames_[static_cast<std::size_t>(f - 1)].T;
      const bool agree = relocCandidateFrame_ == f - 1 && fr.rotationKnown &&
                         rotationAngleDeg(SE3T(relocCandidate_.inverse() * r.T_w_c), SE3T(prevGuess.inverse() * fr.T)) <=
                             opt_.reloc.maxRotationDeg;
      relocCandidateFrame_ = f;
      relocCandidate_ = r.T_w_c;
      ok = agree;
    }
  }
  if (opt_.log) {
    opt_.log("frame " + std::to_string(f) + ": relocalisation: " + std::to_string(X.size()) + " mapped tracks, " +
             std::to_string(r.ok() ? r.numInliers : 0) + " inliers" +
             (r.ok() ? ": rotation " + std::to_string(double(rotationAngleDeg(fr.T, r.T_w_c))) + " deg from the " +
                           (chain ? "rays'" : "held one") + ", moved " +
                       std::to_string(double((r.T_w_c.translation() - fr.T.translation()).norm() / std::max(lastMedianDepth_, Scalar(1e-9)))) +
                       " scene depths" + (ok ? ": relocalised" : ": rejected")
                 : std::string()));
  }
  if (!ok) {
    removeTracksFrom(before);
    return false;
  }
  fr.T = r.T_w_c;
  fr.posed = true;
  fr.inliers = r.numInliers;
  fr.status = SlamStatus::Relocalised;
  dropOutlierTracks(ti, r.inliers);
  if (state_ == State::Initialising) undoReset(f);  // the old segment goes on
  afterLoss_ = false;
  lost_ = 0;
  ++relocalisations_;
  insertKeyframe(f);
  return true;
}

/// Frame f put back into a map before the reset built one: the reset is undone. The segment is
/// the lost one again (the last keyframe's), and so are the frames since the reset; their masks
/// kept for the initialisation go. Returns that segment.
template <typename Scalar>
int MonoSlam<Scalar>::undoReset(int f) {
  --resets_;
  segment_ = keyframes_.back().segment;
  for (int g = segmentStart_; g < f; ++g) frames_[static_cast<std::size_t>(g)].segment = segment_;
  for (int g = std::max(0, std::min(segmentStart_, refFrame_)); g <= f; ++g) frames_[static_cast<std::size_t>(g)].mask = CoarseMask();
  for (Track& t : tracks_) t.fromRef = false;
  state_ = State::Tracking;
  return segment_;
}

/// Map points of the keyframe pyramids `store` (newest first) that no live track follows,
/// projected under `pose` and searched by KLT from the keyframe's image (forward-backward
/// checked), accepted within maxShiftPx of their projection; the found points become mapped
/// tracks.
template <typename Scalar>
void MonoSlam<Scalar>::searchMapPoints(int f, const std::vector<KeyframePyramid>& store, const SE3T& pose,
    Scalar maxShiftPx, int maxPoints, const char* what, const std::vector<char>* use) {
  if (store.empty()) return;
  std::vector<char> tried(points_.size(), 0);
  for (const Track& t : tracks_) {
    if (t.point >= 0) tried[static_cast<std::size_t>(t.point)] = 1;
  }
  const SE3T Tcw = pose.inverse();
  const SE3T Tpw = frames_[static_cast<std::size_t>(f - 1)].T.inverse();
  const float margin = float(opt_.klt.halfWindow + 2);
  const bool withPrev = prevUv_.size() == tracks_.size();
  int attempts = 0, found = 0;
  std::vector<Vec2f> from, to, guess;
  std::vector<int> pids;
  std::vector<char> ok;
  for (auto it = store.rbegin(); it != store.rend() && attempts < maxPoints; ++it) {
    if (use && !(*use)[static_cast<std::size_t>(store.rend() - it - 1)]) continue;
    const int k = it->kf;
    from.clear(), to.clear(), pids.clear();
    for (int pid : keyframes_[static_cast<std::size_t>(k)].points) {
      if (attempts >= maxPoints) break;
      if (tried[static_cast<std::size_t>(pid)]) continue;
      const MapPoint& p = points_[static_cast<std::size_t>(pid)];
      if (!p.valid) continue;
      const Obs* o = nullptr;
      for (const Obs& ob : p.obs) {
        if (ob.kf == k) {
          o = &ob;
          break;
        }
      }
      if (!o) continue;
      const V3 Xc = Tcw * p.X;
      if (!(Xc(2) > Scalar(0))) continue;
      const V2 q = cam_.project(Xc);
      const Vec2f g(float(q(0)), float(q(1)));
      const Vec2f u0(float(o->uv(0)), float(o->uv(1)));
      if (!std::isfinite(g(0)) || !std::isfinite(g(1)) || !insideImage(g, margin) || masked(g) || !insideImage(u0, margin)) continue;
      tried[static_cast<std::size_t>(pid)] = 1;
      from.push_back(u0);
      to.push_back(g);
      pids.push_back(pid);
      ++attempts;
    }
    if (from.empty()) continue;
    guess = to;
    trackKlt(it->pyr, curPyr_, from, to, ok, opt_.klt);
    const float maxShift2 = float(maxShiftPx * maxShiftPx);
    for (std::size_t i = 0; i < from.size(); ++i) {
      const float dx = to[i](0) - guess[i](0), dy = to[i](1) - guess[i](1);
      if (!ok[i] || dx * dx + dy * dy > maxShift2 || !insideImage(to[i], margin) || masked(to[i])) continue;
      Track t;
      t.id = static_cast<int>(trackPoint_.size());
      trackPoint_.push_back(pids[i]);
      t.px = to[i];
      t.uv = rollingShutterShift(to[i], Scalar(1));
      t.point = pids[i];
      if (withPrev) {
        // Its position in the previous frame (for the ray rotation): the projection there.
        const V3 Xp = Tpw * points_[static_cast<std::size_t>(pids[i])].X;
        const V2 qp = Xp(2) > Scalar(0) ? V2(cam_.project(Xp)) : V2(Scalar(to[i](0)), Scalar(to[i](1)));
        prevUv_.push_back(Vec2f(float(qp(0)), float(qp(1))));
      }
      tracks_.push_back(std::move(t));
      ++found;
    }
  }
  if (opt_.log && attempts > 0) {
    opt_.log("frame " + std::to_string(f) + ": " + what + ": " + std::to_string(attempts) + " map points tried, " +
             std::to_string(found) + " found");
  }
}

/// SlamOptions::revisit.enabled: the head looks back at a place it mapped a while ago (a standing
/// person looking around, a table worked at for minutes). The points of the kept keyframes of
/// this segment at least revisit.minFrames old whose view is within revisit.maxAngleDeg of the
/// current one are searched under the current pose (searchMapPoints); when PnP-RANSAC on the
/// found points alone has revisit.minInliers inliers and a rotation within revisit.maxRotationDeg
/// of the tracked pose, its inliers become tracks of those old points. The keyframe then
/// observes them: the bundle adjustments tie the current map to the old one (with the old
/// keyframes fixed in the local window) instead of letting the scale drift turn after turn.
template <typename Scalar>
void MonoSlam<Scalar>::searchRevisits(int f) {
  const Frame& fr = frames_.back();
  std::vector<char> use(relocPyr_.size(), 0);
  const V3 z = fr.T.rotationMatrix().col(2);
  const Scalar cosMax = std::cos(opt_.revisit.maxAngleDeg * Constants<Scalar>::pi() / Scalar(180));
  int any = 0;
  for (std::size_t i = 0; i < relocPyr_.size(); ++i) {
    const Keyframe& kf = keyframes_[static_cast<std::size_t>(relocPyr_[i].kf)];
    if (kf.segment != segment_ || f - kf.frame < opt_.revisit.minFrames) continue;
    if (V3(kf.T.rotationMatrix().col(2)).dot(z) < cosMax) continue;
    use[i] = 1;
    ++any;
  }
  if (!any) return;
  const std::size_t before = tracks_.size();
  searchMapPoints(f, relocPyr_, fr.T, opt_.revisit.maxShiftPx, opt_.revisit.maxPoints, "revisit", &use);
  std::vector<V3> X;
  std::vector<V2> uv;
  foundCorrespondences(before, X, uv);
  bool ok = false;
  PnPRansacResult<Scalar> r;
  if (static_cast<int>(X.size()) >= opt_.revisit.minInliers) {
    PnPRansacOptions<Scalar> po = opt_.pnp;
    po.seed = opt_.pnp.seed + 0x2545f491u + static_cast<std::uint32_t>(f);
    po.minInliers = opt_.revisit.minInliers;
    r = solvePnPRansac(X, uv, cam_, po);
    ok = r.ok() && r.numInliers >= opt_.revisit.minInliers && rotationAngleDeg(fr.T, r.T_w_c) <= opt_.revisit.maxRotationDeg;
  }
  std::vector<char> drop(tracks_.size(), 0);
  int kept = 0;
  for (std::size_t i = before; i < tracks_.size(); ++i) {
    drop[i] = !ok || !r.inliers[i - before];
    kept += drop[i] ? 0 : 1;
  }
  removeTracks(drop);
  revisitPoints_ += kept;
  if (opt_.log) {
    opt_.log("frame " + std::to_string(f) + ": revisit: " + std::to_string(X.size()) + " old points found, " +
             std::to_string(ok ? r.numInliers : 0) + " PnP inliers" +
             (r.ok() ? ", rotation " + std::to_string(double(rotationAngleDeg(fr.T, r.T_w_c))) + " deg from the tracked pose, moved " +
                           std::to_string(double((r.T_w_c.translation() - fr.T.translation()).norm() / std::max(lastMedianDepth_, Scalar(1e-9)))) +
                           " scene depths"
                     : std::string()) +
             (ok ? ": kept " + std::to_string(kept) : ": none kept"));
  }
}

/// A frame that breaks the rotation chain: no rotation, or one only carried on (coastRotation;
/// right within a few degrees in a steady turn, far off when the turn changes under it).
template <typename Scalar>
bool MonoSlam<Scalar>::chainBreak(int f) const {
  const Frame& fr = frames_[static_cast<std::size_t>(f)];
  return !fr.rotationKnown || fr.coasted;
}

/// The first frame of frame f's rotation chain: the frame after the last break before it
/// (0: unbroken since the start).
template <typename Scalar>
int MonoSlam<Scalar>::chainStart(int f) const {
  for (int g = f; g > 0; --g) {
    if (chainBreak(g)) return g + 1;
  }
  return 0;
}

/// SlamOptions::link.enabled: frame f (a keyframe, or every link.everyFrames-th frame without a
/// map pose) whose rotation chain starts after the kept images of the segment before the break
/// (linkPyr_): each image is tried as the current view (its points searched by KLT around where
/// it saw them), and a PnP pose in that segment's world with link.minInliers inliers is kept as
/// a link. Its tracks are not kept: the worlds differ.
template <typename Scalar>
void MonoSlam<Scalar>::searchSegmentLinks(int f) {
  if (linkPyr_.empty() || chainBreak(f)) return;
  const int start = chainStart(f);
  int linked = 0;
  for (const SegmentLink& l : links_) linked += l.frame >= start ? 1 : 0;
  if (linked >= opt_.link.enough) {  // enough to agree on: the images go
    std::vector<KeyframePyramid>().swap(linkPyr_);
    return;
  }
  for (std::size_t i = 0; i < linkPyr_.size(); ++i) {
    const Keyframe& kk = keyframes_[static_cast<std::size_t>(linkPyr_[i].kf)];
    std::vector<char> use(linkPyr_.size(), 0);
    use[i] = 1;
    // The guesses: the kept keyframe's own view, then turned by ±link.yawStepDeg, ±2·… about
    // its camera's vertical axis (a head turns mostly about it; KLT reaches about 8° from a
    // guess at 640×480).
    PnPRansacResult<Scalar> r;
    std::size_t found = 0;
    bool ok = false;
    for (int h = 0; h <= 2 * opt_.link.yawSteps && !ok; ++h) {
      const Scalar yaw = Scalar((h + 1) / 2 * (h % 2 == 1 ? 1 : -1)) * opt_.link.yawStepDeg * Constants<Scalar>::pi() / Scalar(180);
      const SE3T guess = kk.T * SE3T(SO3<Scalar>::exp(V3(Scalar(0), yaw, Scalar(0))), V3::Zero());
      const std::size_t before = tracks_.size();
      searchMapPoints(f, linkPyr_, guess, opt_.link.maxShiftPx, opt_.link.maxPoints, "segment link", &use);
      std::vector<V3> X;
      std::vector<V2> uv;
      foundCorrespondences(before, X, uv);
      removeTracksFrom(before);
      found = std::max(found, X.size());
      if (static_cast<int>(X.size()) < opt_.link.minInliers) continue;
      PnPRansacOptions<Scalar> po = opt_.pnp;
      po.seed = opt_.pnp.seed + 0x68e31da4u + static_cast<std::uint32_t>(f);
      po.minInliers = opt_.link.minInliers;
      r = solvePnPRansac(X, uv, cam_, po);
      ok = r.ok() && r.numInliers >= opt_.link.minInliers;
    }
    if (opt_.log) {
      opt_.log("frame " + std::to_string(f) + ": segment link to keyframe " + std::to_string(linkPyr_[i].kf) + " (frame " +
               std::to_string(kk.frame) + "): at most " + std::to_string(found) + " points found" +
               (ok ? ", " + std::to_string(r.numInliers) + " PnP inliers, rotation " +
                         std::to_string(double(rotationAngleDeg(frames_[static_cast<std::size_t>(f)].T, r.T_w_c))) + " deg from the frame's: kept"
                   : std::string(": none")));
    }
    if (ok) links_.push_back(SegmentLink{f, kk.frame, r.T_w_c, r.numInliers});
  }
}

/// SlamOptions::link.enabled: the first frame that link l's correction applies to. After the
/// last frame without a rotation between its kept image and it; when there is none (only
/// rotations carried on: coastRotation), after the first run of carried-on frames.
template <typename Scalar>
int MonoSlam<Scalar>::linkChainStart(const SegmentLink& l) const {
  for (int g = l.frame; g > l.oldFrame; --g) {
    if (!frames_[static_cast<std::size_t>(g)].rotationKnown) return g + 1;
  }
  int g = l.oldFrame + 1;
  while (g <= l.frame && !chainBreak(g)) ++g;
  while (g <= l.frame && chainBreak(g)) ++g;
  return g;
}

/// SlamOptions::link.enabled, in finish() before the joins. The links are grouped by the frame
/// their correction starts at (linkChainStart); for each group, in order, the corrections
/// C = R_old(f)·R(f)ᵀ (R_old with the corrections already made to the older frames) must
/// agree, two at different frames within link.agreeDeg; the best-supported one (then the most
/// inliers) rotates the frames from the start on (keyframes and points with them) about the
/// start frame's position. The joins then place and scale the segments.
template <typename Scalar>
void MonoSlam<Scalar>::applySegmentLinks() {
  if (links_.empty()) return;
  const int n = static_cast<int>(frames_.size());
  const Scalar agreeRad = opt_.link.agreeDeg * Constants<Scalar>::pi() / Scalar(180);
  std::vector<int> starts(links_.size());
  for (std::size_t i = 0; i < links_.size(); ++i) starts[i] = linkChainStart(links_[i]);
  std::vector<int> order = starts;
  std::sort(order.begin(), order.end());
  order.erase(std::unique(order.begin(), order.end()), order.end());
  std::vector<std::pair<int, Mat3<Scalar>>> made;  // (first frame, rotation) of each correction
  for (int S : order) {
    if (S >= n) continue;
    std::vector<Mat3<Scalar>> C;
    std::vector<const SegmentLink*> L;
    for (std::size_t i = 0; i < links_.size(); ++i) {
      const SegmentLink& l = links_[i];
      if (starts[i] != S || l.frame < S) continue;
      Mat3<Scalar> Rold = l.T_old.rotationMatrix();
      for (const auto& m : made) {
        if (m.first <= l.oldFrame) Rold = m.second * Rold;
      }
      C.push_back(Mat3<Scalar>(Rold * frames_[static_cast<std::size_t>(l.frame)].T.rotationMatrix().transpose()));
      L.push_back(&l);
    }
    int best = -1, bestSupport = 0;
    for (std::size_t i = 0; i < C.size(); ++i) {
      int support = 0;
      for (std::size_t j = 0; j < C.size(); ++j) {
        if (L[j]->frame != L[i]->frame && SO3<Scalar>::fromMatrix(Mat3<Scalar>(C[i].transpose() * C[j])).log().norm() <= agreeRad) ++support;
      }
      if (support > bestSupport || (support > 0 && support == bestSupport && L[i]->inliers > L[static_cast<std::size_t>(best)]->inliers)) {
        best = static_cast<int>(i), bestSupport = support;
      }
    }
    if (opt_.log && !C.empty()) {
      opt_.log("rotation chain from frame " + std::to_string(S) + ": " + std::to_string(C.size()) + " links" +
               (best >= 0 ? ", the best agreed by " + std::to_string(bestSupport) + ": rotated by " +
                                std::to_string(double(SO3<Scalar>::fromMatrix(C[static_cast<std::size_t>(best)]).log().norm() * Scalar(180) /
                                                      Constants<Scalar>::pi())) + " deg"
                          : std::string(", none agree")));
    }
    if (best < 0) continue;
    const Mat3<Scalar> R = C[static_cast<std::size_t>(best)];
    const V3 c = frames_[static_cast<std::size_t>(S)].T.translation();
    auto move = [&](const SE3T& T) {
      return SE3T(SO3<Scalar>::fromMatrix(Mat3<Scalar>(R * T.rotationMatrix())), V3(R * (T.translation() - c) + c));
    };
    // From S on, in S's segment and the ones started from it (not a segment re-entered later).
    const int seg = frames_[static_cast<std::size_t>(S)].segment;
    for (int g = S; g < n; ++g) {
      if (inSegment(frames_[static_cast<std::size_t>(g)].segment, seg)) frames_[static_cast<std::size_t>(g)].T = move(frames_[static_cast<std::size_t>(g)].T);
    }
    for (Keyframe& kf : keyframes_) {
      if (kf.frame >= S && inSegment(kf.segment, seg)) kf.T = move(kf.T);
    }
    for (MapPoint& p : points_) {
      if (p.obs.empty()) continue;
      const Keyframe& k0 = keyframes_[static_cast<std::size_t>(p.obs.front().kf)];
      if (k0.frame >= S && inSegment(k0.segment, seg)) p.X = V3(R * (p.X - c) + c);
    }
    made.emplace_back(S, R);
  }
}

}  // namespace hawor
