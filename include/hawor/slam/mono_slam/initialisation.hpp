// hawor/slam/mono_slam/initialisation.hpp — MonoSlam's initialisation: the two-view reference, the
// pair's attempt, the first map of a segment.
// Member functions of MonoSlam (slam/mono_slam.hpp: the class, its state and the overview);
// included at the end of that header.
#pragma once

#include "../mono_slam.hpp"

namespace hawor {

template <typename Scalar>
void MonoSlam<Scalar>::initialise(int f) {
  Frame& fr = frames_.back();
  // Rotation-only pose from the ray chain (position held).
  Mat3<Scalar> dR;
  if (rayRotation(dR)) {
    fr.T = SE3T(SO3<Scalar>::fromMatrix(Mat3<Scalar>(frames_[static_cast<std::size_t>(f - 1)].T.rotationMatrix() * dR)),
                frames_[static_cast<std::size_t>(f - 1)].T.translation());
    dropJumpedTracks(dR);
  } else if (!coastRotation(f)) {
    fr.rotationKnown = false;
  }
  fr.status = afterLoss_ ? SlamStatus::Lost : SlamStatus::Interpolated;
  placeWaiting_ = false;
  if (afterLoss_ && (relocalise(f) || relocaliseByPlace(f))) return;
  // Reference: the fixed reference frame (refFrame_, replaced when it has lost most of its
  // tracks), or any of the last init.maxGap frames (their tracks are in the per-frame
  // observations, their rotations from the rays): the oldest of them sharing init.minTracks
  // tracks. During a head turn the tracks live only a few frames, and while hands sweep over a
  // slowly moving view they die one by one: a fixed reference would lose them all before the
  // motion gives parallax (hands_cover seed 7 never initialised in 300 frames).
  fr.mask = hasMask_ ? CoarseMask(curMask_, opt_.maskBlock) : CoarseMask();
  const int window = f - opt_.init.maxGap;
  if (window - 1 >= 0 && window - 1 != refFrame_) frames_[static_cast<std::size_t>(window - 1)].mask = CoarseMask();
  const int oldest = std::max(segmentStart_, std::min(refFrame_, window));
  const int minTracks = afterLoss_ ? opt_.init.reinitMinTracks : opt_.init.minTracks;
  int bestG = -1, refAlive = 0;
  float bestFlow = -1;
  std::vector<int> bestIdx, bestOther;
  std::vector<int> idx, other;
  std::vector<float> flow;
  for (int g = f - 1; g >= oldest; --g) {
    const Frame& rf = frames_[static_cast<std::size_t>(g)];
    if (g != refFrame_ && (g < window || !rf.rotationKnown)) continue;
    // Common tracks: both observation lists are sorted by track id (ids only grow).
    idx.clear(), other.clear(), flow.clear();
    std::size_t a = 0;
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
      while (a < rf.obsTrack.size() && rf.obsTrack[a] < tracks_[i].id) ++a;
      if (a < rf.obsTrack.size() && rf.obsTrack[a] == tracks_[i].id) idx.push_back(static_cast<int>(i)), other.push_back(static_cast<int>(a));
    }
    if (g == refFrame_) refAlive = static_cast<int>(idx.size());
    if (static_cast<int>(idx.size()) < minTracks) continue;
    // Rotation-compensated flow: where the reference ray lands under the rotation alone.
    const Mat3<Scalar> Rcr = fr.T.rotationMatrix().transpose() * rf.T.rotationMatrix();
    for (std::size_t j = 0; j < idx.size(); ++j) {
      const V2 x1 = normalised(rf.obsUv[static_cast<std::size_t>(other[j])]);
      const V2 x2 = normalised(tracks_[static_cast<std::size_t>(idx[j])].uv);
      const V3 r = Rcr * V3(x1(0), x1(1), Scalar(1));
      if (!(r(2) > Scalar(0))) continue;
      const float du = float(cam_.fx * (r(0) / r(2) - x2(0))), dv = float(cam_.fy * (r(1) / r(2) - x2(1)));
      flow.push_back(std::sqrt(du * du + dv * dv));
    }
    if (flow.size() < 8) continue;
    std::nth_element(flow.begin(), flow.begin() + static_cast<std::ptrdiff_t>(flow.size() / 2), flow.end());
    // The oldest frame with enough common tracks: the longest baseline available.
    bestFlow = flow[flow.size() / 2], bestG = g, bestIdx = idx, bestOther = other;
  }
  // Try when the rotation-compensated flow is large enough, or after a large rotation: the
  // flow is compensated with the rays' rotation, which under a sideways head translation
  // absorbs most of the parallax (the rotation–translation ambiguity); the two-view decides.
  const Scalar turnedDeg = bestG >= 0 ? rotationAngleDeg(frames_[static_cast<std::size_t>(bestG)].T, fr.T) : Scalar(0);
  const bool fastTurn = bestG >= 0 && turning_ && turnedDeg >= opt_.init.minRotationDeg;
  // (Not while a place found for relocalisation waits for the next frame: the old map first.)
  const bool tryNow = bestG >= 0 && !placeWaiting_ && ((bestFlow >= float(opt_.init.minFlowPx) && f - lastInitAttempt_ >= opt_.init.everyFrames) ||
                                     (fastTurn && f - lastInitAttempt_ >= 2));
  if (tryNow) {
    lastInitAttempt_ = f;
    const Frame& rf = frames_[static_cast<std::size_t>(bestG)];
    std::vector<V2> x1, x2;
    for (std::size_t j = 0; j < bestIdx.size(); ++j) {
      x1.push_back(normalised(rf.obsUv[static_cast<std::size_t>(bestOther[j])]));
      x2.push_back(normalised(tracks_[static_cast<std::size_t>(bestIdx[j])].uv));
    }
    // Further views (the frames between, every second) settle a two-fold ambiguity
    // (two_view.hpp): the head's sway curves, and a view off the pair's line of motion fits
    // only the true plane.
    std::vector<std::vector<V2>> x3;
    if (opt_.init.thirdView) {
      const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
      for (int mid = bestG + 2; mid < f; mid += 2) {
        const Frame& mf = frames_[static_cast<std::size_t>(mid)];
        std::vector<V2> v;
        std::size_t a = 0;
        for (std::size_t j = 0; j < bestIdx.size(); ++j) {
          const int id = tracks_[static_cast<std::size_t>(bestIdx[j])].id;
          while (a < mf.obsTrack.size() && mf.obsTrack[a] < id) ++a;
          v.push_back(a < mf.obsTrack.size() && mf.obsTrack[a] == id ? normalised(mf.obsUv[a]) : V2(nan, nan));
        }
        x3.push_back(std::move(v));
      }
    }
    TwoViewOptions<Scalar> tvo = opt_.twoView;
    tvo.seed = opt_.twoView.seed + static_cast<std::uint32_t>(f);
    // In a fast turn the rotation dwarfs the translation: H (the rotation) is the model, and
    // E's extra inliers are noise read as parallax (fast_turns seed 8, frame 204).
    tvo.essentialOverPlane = opt_.twoView.essentialOverPlane && !turning_;
    const TwoViewResult<Scalar> tv = initializeTwoView(x1, x2, tvo, x3.empty() ? nullptr : &x3);
    if (opt_.log) {
      opt_.log("frame " + std::to_string(f) + ": two-view with reference " + std::to_string(bestG) + ", " +
               std::to_string(x1.size()) + " tracks, flow " + std::to_string(bestFlow) + " px: status " +
               std::to_string(int(tv.status)) + " model " + std::to_string(int(tv.model)) + " inliers " +
               std::to_string(tv.numInliers) + " triangulated " + std::to_string(tv.numTriangulated) +
               " parallax " + std::to_string(double(tv.medianParallaxDeg)) +
               (tv.essentialOverPlane ? " (E over GRIC's H)" : "") +
               (tv.thirdViewCandidates > 0 ? ", further views: " +
                                                 std::to_string(tv.thirdViewCandidates) + " candidates, costs " +
                                                 std::to_string(double(tv.thirdViewCost)) + " / " +
                                                 std::to_string(double(tv.thirdViewRunnerUp)) + " px2"
                                           : std::string()));
    }
    if (tv.ok()) {
      if (bestG != refFrame_ && refFrame_ < window) frames_[static_cast<std::size_t>(refFrame_)].mask = CoarseMask();
      refFrame_ = bestG;
      refMask_ = rf.mask;
      for (Track& t : tracks_) t.fromRef = false;
      for (std::size_t j = 0; j < bestIdx.size(); ++j) {
        Track& t = tracks_[static_cast<std::size_t>(bestIdx[j])];
        t.refUv = rf.obsUv[static_cast<std::size_t>(bestOther[j])];
        t.fromRef = true;
      }
      buildMap(f, tv, bestIdx);
      for (int g = oldest; g <= f; ++g) frames_[static_cast<std::size_t>(g)].mask = CoarseMask();
      return;
    }
  }
  // Too few reference tracks left: this frame becomes the reference (new corners first). New
  // corners also whenever the tracks thin out (they give the later frames a reference among
  // the recent ones).
  const int refTracks = static_cast<int>(frames_[static_cast<std::size_t>(refFrame_)].obsTrack.size());
  if (refAlive < std::max(minTracks, refTracks / 4)) {
    if (opt_.log) {
      opt_.log("frame " + std::to_string(f) + ": new initialisation reference (" + std::to_string(refAlive) + " tracks left)");
    }
    if (refFrame_ < window) frames_[static_cast<std::size_t>(refFrame_)].mask = CoarseMask();
    setReference(f);
  } else if (static_cast<int>(tracks_.size()) < opt_.maxFeatures * 7 / 10) {
    replenish();
  }
}

template <typename Scalar>
void MonoSlam<Scalar>::buildMap(int f, const TwoViewResult<Scalar>& tv, const std::vector<int>& idx) {
  SE3T Tref = frames_[static_cast<std::size_t>(refFrame_)].T;  // provisional world of the ref frame
  // The two-view map lives in the reference camera's frame with a unit baseline. Join it to
  // the existing world (first map: the reference frame's provisional pose, scale 1; after a
  // loss: the rotation from the rays, the position held and the scale from the median scene
  // depth of the last map, docs/design.md §5).
  Scalar s = Scalar(1);
  // A new segment: the old map is no longer the one tracked. Its kept images stay for the
  // place recognition when the rotation chain to it is broken (link.enabled; else the images
  // kept from an earlier break stay, for the same chain).
  if (opt_.link.enabled && !keyframes_.empty() && chainStart(f) > keyframes_.back().frame) {
    linkPyr_.swap(relocPyr_);
    // The segment's last keyframe too: a break comes in a turn, and the head often turns back.
    if (lastKfPyr_.kf >= 0 && std::none_of(linkPyr_.begin(), linkPyr_.end(), [&](const KeyframePyramid& e) { return e.kf == lastKfPyr_.kf; })) {
      linkPyr_.push_back(std::move(lastKfPyr_));
    }
  }
  relocPyr_.clear();
  lastKfPyr_ = KeyframePyramid();
  const int seg = segment_;
  if (everInitialised_ && lastMedianDepth_ > Scalar(0)) {
    std::vector<Scalar> d;
    for (std::size_t j = 0; j < idx.size(); ++j) {
      if (tv.triangulated[j] && tv.points[j](2) > Scalar(0)) d.push_back(tv.points[j](2));
    }
    if (!d.empty()) {
      std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
      s = lastMedianDepth_ / d[d.size() / 2];
      if (opt_.log) {
        opt_.log("frame " + std::to_string(f) + ": new segment scaled by the median depth: " + std::to_string(double(lastMedianDepth_)) +
                 " (last map) / " + std::to_string(double(d[d.size() / 2])) + " (two-view, " + std::to_string(d.size()) +
                 " points) = " + std::to_string(double(s)));
      }
    }
  }
  auto toWorld = [&](const V3& x) { return V3(Tref * V3(s * x)); };
  SE3T T1 = Tref * SE3T(tv.T_c1_c2.rotation(), V3(s * tv.T_c1_c2.translation()));
  const int k0 = static_cast<int>(keyframes_.size());
  keyframes_.push_back(Keyframe{refFrame_, Tref, refMask_, {}, seg, {}, {}, {}});
  keyframes_.push_back(Keyframe{f, T1, hasMask_ ? CoarseMask(curMask_, opt_.maskBlock) : CoarseMask(), {}, seg, {}, {}, {}});
  for (std::size_t j = 0; j < idx.size(); ++j) {
    Track& t = tracks_[static_cast<std::size_t>(idx[j])];
    const V2 u0(Scalar(t.refUv(0)), Scalar(t.refUv(1))), u1(Scalar(t.uv(0)), Scalar(t.uv(1)));
    if (tv.triangulated[j]) {
      MapPoint p;
      p.X = toWorld(tv.points[j]);
      p.obs = {Obs{k0, u0}, Obs{k0 + 1, u1}};
      t.point = addPoint(std::move(p), t.id);
    } else {
      t.kfObs = {Obs{k0, u0}, Obs{k0 + 1, u1}};
    }
  }
  for (Track& t : tracks_) t.fromRef = false;
  Frame& fr = frames_.back();
  fr.T = T1;
  fr.posed = true;
  fr.status = everInitialised_ ? SlamStatus::Relocalised : SlamStatus::Tracked;
  frames_[static_cast<std::size_t>(refFrame_)].T = Tref;
  frames_[static_cast<std::size_t>(refFrame_)].posed = true;
  // Frames between: interpolated for now (refined against the map in finish()).
  for (int g = refFrame_ + 1; g < f; ++g) {
    const Scalar a = Scalar(g - refFrame_) / Scalar(f - refFrame_);
    Frame& m = frames_[static_cast<std::size_t>(g)];
    m.T = SE3T(m.rotationKnown ? m.T.rotation() : interpolate(Tref.rotation(), T1.rotation(), a),
               V3((Scalar(1) - a) * Tref.translation() + a * T1.translation()));
  }
  state_ = State::Tracking;
  everInitialised_ = true;
  afterLoss_ = false;
  lost_ = 0;
  closeKeyframe(fr);
}

}  // namespace hawor
