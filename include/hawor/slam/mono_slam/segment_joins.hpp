// hawor/slam/mono_slam/segment_joins.hpp — MonoSlam's joining map segments after resets: by the
// head model, pairwise and all at once.
// Member functions of MonoSlam (slam/mono_slam.hpp: the class, its state and the overview);
// included at the end of that header.
#pragma once

#include "../mono_slam.hpp"

namespace hawor {

/// Applies the position map `g` (a similarity; `R`, when given, its rotation, else none) to
/// segment `seg` and the segments started from it (inSegment: their worlds were joined to its;
/// they continue its scale): their frames from f1 on, the frames before f1 that its map posed
/// (lost frames resected against it: their poses are in its world, where the unposed frames'
/// guesses before f1 are in the world before it), keyframes and points.
template <typename Scalar>
template <typename G>
void MonoSlam<Scalar>::transformFrom(int f1, int seg, const G& g, const SO3<Scalar>* R) {
  auto move = [&](const SE3T& T) { return SE3T(R ? SO3<Scalar>(*R * T.rotation()) : T.rotation(), g(V3(T.translation()))); };
  auto moves = [&](std::size_t f) { return (static_cast<int>(f) >= f1 || frames_[f].posed) && inSegment(frames_[f].segment, seg); };
  for (std::size_t f = 0; f < frames_.size(); ++f) {
    if (moves(f)) frames_[f].T = move(frames_[f].T);
  }
  for (Keyframe& kf : keyframes_) {
    if (inSegment(kf.segment, seg)) kf.T = move(kf.T);
  }
  for (MapPoint& p : points_) {
    if (!p.obs.empty() && inSegment(keyframes_[static_cast<std::size_t>(p.obs.front().kf)].segment, seg)) p.X = g(V3(p.X));
  }
  // The sequence refinement's points (after it ran) by their first observation.
  for (std::size_t j = 0; j < seqPoints_.size(); ++j) {
    if (seqPointObs_[j].empty()) continue;
    const int f = seqPointObs_[j].front().first;
    if (moves(static_cast<std::size_t>(f))) seqPoints_[j] = g(V3(seqPoints_[j]));
  }
}

/// The first keyframe of each map segment, in the order the segments were started (a segment
/// re-entered later is listed once).
template <typename Scalar>
std::vector<int> MonoSlam<Scalar>::segmentFirstKeyframes() const {
  std::vector<int> first;
  std::vector<char> seen(segmentParent_.size(), 0);
  for (std::size_t k = 0; k < keyframes_.size(); ++k) {
    char& s = seen[static_cast<std::size_t>(keyframes_[k].segment)];
    if (!s) first.push_back(static_cast<int>(k));
    s = 1;
  }
  return first;
}

/// SlamOptions::join.headModel: each later segment joined to the one before it by one head model
/// fitted to the posed frames on both sides of the reset (head_motion.hpp fitHeadJoin: B's
/// positions into A's units, scale and offset), where the model explains them; everything after
/// it moves with it (later segments continue its scale); frames before its first keyframe (lost,
/// not posed) are filled in later.
template <typename Scalar>
void MonoSlam<Scalar>::joinSegmentPairsByHead() {
  const std::vector<int> segFirstKf = segmentFirstKeyframes();
  if (segFirstKf.size() < 2) return;
  const int n = static_cast<int>(frames_.size());
  std::vector<SE3T> T(static_cast<std::size_t>(n));
  std::vector<char> usable(static_cast<std::size_t>(n));
  for (std::size_t i = 1; i < segFirstKf.size(); ++i) {
    for (int f = 0; f < n; ++f) {
      T[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].T;
      usable[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].posed;
    }
    const int f0 = keyframes_[static_cast<std::size_t>(segFirstKf[i - 1])].frame;
    const int f1 = keyframes_[static_cast<std::size_t>(segFirstKf[i])].frame;
    const int f2 = i + 1 < segFirstKf.size() ? keyframes_[static_cast<std::size_t>(segFirstKf[i + 1])].frame : n;
    std::vector<int> idxA, idxB;
    // A: the segment it was started from, before it; B: its own frames.
    const int seg = keyframes_[static_cast<std::size_t>(segFirstKf[i])].segment;
    const int parent = segmentParent_[static_cast<std::size_t>(seg)];
    for (int f = std::max(f0, f1 - opt_.headModel.window); f < f1; ++f) {
      if (usable[static_cast<std::size_t>(f)] && frames_[static_cast<std::size_t>(f)].segment == parent) idxA.push_back(f);
    }
    for (int f = f1; f < std::min(f2, f1 + opt_.headModel.window); ++f) {
      if (usable[static_cast<std::size_t>(f)] && frames_[static_cast<std::size_t>(f)].segment == seg) idxB.push_back(f);
    }
    const HeadJoin<Scalar> hj = fitHeadJoin(T, idxA, idxB, opt_.headModel);
    if (opt_.log) {
      opt_.log("segment starting at frame " + std::to_string(f1) + ": head model over " + std::to_string(idxA.size()) + " + " +
               std::to_string(idxB.size()) + " frames: scale " + std::to_string(double(hj.s)) + ", R2 " +
               std::to_string(double(hj.fit.r2)) + ", motion R2 " + std::to_string(double(hj.fit.motionR2)) + ", front " +
               std::to_string(double(hj.fit.frontCos)) + ", radius spread " + std::to_string(double(hj.fit.radiusSpread)) +
               ", view spreads " + std::to_string(double(hj.spreadA)) + "/" + std::to_string(double(hj.spreadB)) + " deg" +
               (hj.ok ? ": joined" : ": not used"));
    }
    if (hj.ok) transformFrom(f1, seg, [&](const V3& x) { return V3(hj.s * x + hj.t); });
  }
}

/// SlamOptions::join.headModelAll: the segments (first keyframes segFirstKf; segment i spans
/// the frames from its first keyframe to the next one's) with enough posed frames and turn
/// joined by one head model (fitHeadJoinAll, the longest segment the reference). True when it
/// passed the tests and was applied; a segment left out moves with the one before it, and with
/// placeShort (SlamOptions::join.placeShort also on) its frames are placed by the model.
template <typename Scalar>
bool MonoSlam<Scalar>::joinAllSegmentsByHead(bool placeShort) {
  const std::vector<int> segFirstKf = segmentFirstKeyframes();
  const int n = static_cast<int>(frames_.size());
  const std::size_t S = segFirstKf.size();
  if (S < 2) return false;
  std::vector<SE3T> T(static_cast<std::size_t>(n));
  std::vector<char> usable(static_cast<std::size_t>(n));
  std::vector<int> first(S + 1, n), segOf(S);
  for (std::size_t i = 0; i < S; ++i) {
    first[i] = i == 0 ? 0 : keyframes_[static_cast<std::size_t>(segFirstKf[i])].frame;
    segOf[i] = keyframes_[static_cast<std::size_t>(segFirstKf[i])].segment;
  }
  // Segment i's frames: its range [first[i], first[i + 1]) less the frames of segments
  // re-entered inside it (they are in another world).
  for (std::size_t i = 0; i < S; ++i) {
    for (int f = first[i]; f < first[i + 1]; ++f) {
      const Frame& fr = frames_[static_cast<std::size_t>(f)];
      T[static_cast<std::size_t>(f)] = fr.T;
      usable[static_cast<std::size_t>(f)] = fr.posed && fr.segment == segOf[i];
    }
  }
  const SegmentsHeadJoin<Scalar> R = joinSegmentsByHeadModel(T, usable, first, opt_.headModel);
  const HeadJoinAll<Scalar>& J = R.join;
  if (opt_.log) {
    std::string sc;
    for (std::size_t k = 0; k < J.s.size(); ++k) sc += (k ? "/" : "") + std::to_string(double(J.s[k]));
    opt_.log("segments joined by one head model:" + R.report + " scales " + sc + ", R2 " + std::to_string(double(J.fit.r2)) +
             ", motion R2 " + std::to_string(double(J.fit.motionR2)) + ", front " + std::to_string(double(J.fit.frontCos)) +
             ", radius spread " + std::to_string(double(J.fit.radiusSpread)) + (R.ok ? ": joined" : ": not used"));
  }
  if (!R.ok) return false;
  const std::vector<int>& groupOf = R.group;
  // Segment by segment, in order: transformFrom moves a segment with the ones started from it,
  // so each joined segment gets its own similarity composed with the inverse of the one applied
  // to the segment it was started from (x ↦ a·x + b); one left out keeps that one.
  std::vector<Scalar> a(segmentParent_.size(), Scalar(1));
  std::vector<V3> b(segmentParent_.size(), V3::Zero());
  for (std::size_t i = 0; i < S; ++i) {
    const std::size_t sg = static_cast<std::size_t>(segOf[i]);
    const int parent = segmentParent_[sg];
    const Scalar ap = parent >= 0 ? a[static_cast<std::size_t>(parent)] : Scalar(1);
    const V3 bp = parent >= 0 ? b[static_cast<std::size_t>(parent)] : V3::Zero();
    a[sg] = ap, b[sg] = bp;
    if (groupOf[i] < 0) continue;
    const Scalar s = J.s[static_cast<std::size_t>(groupOf[i])];
    const V3 t = J.t[static_cast<std::size_t>(groupOf[i])];
    transformFrom(first[i], segOf[i], [&](const V3& x) { return V3(s * (x - bp) / ap + t); });
    a[sg] = s, b[sg] = t;
  }
  // A segment too short to fix its own scale: its frames are placed by the head model instead
  // (fillGapsByHeadModel), like lost ones.
  if (opt_.join.placeShort && placeShort) {
    for (std::size_t i = 0; i < S; ++i) {
      if (groupOf[i] >= 0) continue;
      placedRanges_.push_back({first[i], first[i + 1], segOf[i]});
      for (int f = first[i]; f < first[i + 1]; ++f) {
        Frame& fr = frames_[static_cast<std::size_t>(f)];
        if (!fr.posed || fr.segment != segOf[i]) continue;
        fr.posed = false;
        fr.rotationKnown = true;
        fr.status = SlamStatus::Interpolated;
      }
      // Interpolated from the joined frames around it (its own positions are in its own
      // scale); the head model's gap filling replaces them where its tests pass.
      fillUnposed(first[i], first[i + 1]);
    }
  }
  return true;
}

}  // namespace hawor
