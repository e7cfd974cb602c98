// hawor/slam/mono_slam/place_links.hpp — MonoSlam's place recognition between keyframes and the
// joins it makes (SlamOptions::place).
// Member functions of MonoSlam (slam/mono_slam.hpp: the class, its state and the overview);
// included at the end of that header.
//
// At each keyframe (while its image is at hand): its map points' pixels are described
// (binary_descriptor.hpp) and the index of the older keyframes (place_index.hpp) is asked for the
// same place; the best candidates are verified by matching the descriptors and fitting a Sim(3)
// to the matched map points (sim3_ransac.hpp: both reprojections within place.thresholdPx). A
// verified pair is a PLACE LINK: its matched points are one physical point, in two maps or two
// parts of one map. Then the keyframe is indexed. Nothing changes while tracking.
// After a loss, before a new map is built, the same index relocalises the frame into the segment
// that has its place (relocaliseByPlace, SlamOptions::reloc.byPlace), the lost one or an older one.
// finish(), before the sequence refinement: a segment linked to an earlier one (after a reset: a
// map of its own, joined to the old one by guesses — the median depth, the head model) is moved
// into the earlier one's world by one similarity of its linked points' present positions
// (placeSegmentsByLinks), and the segments started from it with it, so that it takes the scale of the place
// it returned to; then the two points of every link (across segments or within one) become one
// track in the sequence refinement, which adjusts the whole clip as one map: the loop is closed
// by that bundle adjustment. (A Sim(3) pose graph over the keyframes, pose_graph.hpp, in place of
// the placement measured worse: docs/experiments.md.)
#pragma once

#include "../mono_slam.hpp"

namespace hawor {

/// The current keyframe's descriptors (its map points at their pixels in this frame), the place
/// search against the index, then the keyframe joins the index.
template <typename Scalar>
void MonoSlam<Scalar>::describeAndLinkKeyframe(int k) {
  Keyframe& kf = keyframes_[static_cast<std::size_t>(k)];
  describer_.setImage(curPyr_.level(0));
  for (int pid : kf.points) {
    const MapPoint& p = points_[static_cast<std::size_t>(pid)];
    if (!p.valid) continue;
    for (const Obs& o : p.obs) {
      if (o.kf != k) continue;
      BinaryDescriptor d;
      if (describer_.compute(float(o.uv(0)), float(o.uv(1)), d)) {
        kf.desc.push_back(d);
        kf.descPoint.push_back(pid);
        kf.descUv.push_back(o.uv);
      }
      break;
    }
  }
  if (kf.desc.empty()) return;
  const std::vector<PlaceCandidate> cand = placeIndex_.query(kf.desc, opt_.place.minVotes, [&](int c) {
    const Keyframe& kc = keyframes_[static_cast<std::size_t>(c)];
    return kc.segment != kf.segment || kf.frame - kc.frame >= opt_.place.minFramesApart;
  });
  for (std::size_t i = 0; i < cand.size() && static_cast<int>(i) < opt_.place.candidates; ++i) {
    if (verifyPlaceLink(k, cand[i].entry, cand[i].votes)) break;
  }
  placeIndex_.add(k, kf.desc);
}

/// Keyframe k against the older keyframe c: descriptor matches between their map points (two
/// different points: the same point tracked into both says nothing new), a Sim(3) over them in
/// their cameras' frames; true when verified (the link is kept).
template <typename Scalar>
bool MonoSlam<Scalar>::verifyPlaceLink(int k, int c, int votes) {
  const Keyframe& kk = keyframes_[static_cast<std::size_t>(k)];
  const Keyframe& kc = keyframes_[static_cast<std::size_t>(c)];
  const std::vector<DescriptorMatch> m = matchBinaryDescriptors(kk.desc, kc.desc, opt_.place.maxDistance, double(opt_.place.ratio));
  std::vector<V3> Pc, Pk;
  std::vector<V2> uc, uk;
  std::vector<std::pair<int, int>> pairs;  // (point of k, point of c)
  const SE3T Tkw = kk.T.inverse(), Tcw = kc.T.inverse();
  for (const DescriptorMatch& d : m) {
    const int pk = kk.descPoint[static_cast<std::size_t>(d.query)];
    const int pc = kc.descPoint[static_cast<std::size_t>(d.train)];
    if (pk == pc || !points_[static_cast<std::size_t>(pk)].valid || !points_[static_cast<std::size_t>(pc)].valid) continue;
    Pk.push_back(Tkw * points_[static_cast<std::size_t>(pk)].X);
    Pc.push_back(Tcw * points_[static_cast<std::size_t>(pc)].X);
    uk.push_back(kk.descUv[static_cast<std::size_t>(d.query)]);
    uc.push_back(kc.descUv[static_cast<std::size_t>(d.train)]);
    pairs.emplace_back(pk, pc);
  }
  Sim3RansacOptions<Scalar> so;
  so.thresholdPx = opt_.place.thresholdPx;
  so.minInliers = opt_.place.minInliers;
  so.maxDepthError = opt_.place.maxDepthError;
  so.seed = 0x51a3u + static_cast<std::uint32_t>(k);
  const Sim3RansacResult<Scalar> r = solveSim3Ransac(Pc, Pk, uc, uk, cam_, so);
  if (opt_.log) {
    opt_.log("frame " + std::to_string(kk.frame) + ": place candidate frame " + std::to_string(kc.frame) + " (segment " +
             std::to_string(kc.segment) + ", " + std::to_string(votes) + " votes): " + std::to_string(m.size()) + " matches, " +
             std::to_string(pairs.size()) + " of other points, " + std::to_string(r.numInliers) + " Sim(3) inliers" +
             (r.found ? ", scale " + std::to_string(double(r.S.scale())) + ": linked" : ": rejected"));
  }
  if (!r.found) return false;
  PlaceLink link{k, c, {}};
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (r.inliers[i]) link.pairs.push_back(pairs[i]);
  }
  placeLinks_.push_back(std::move(link));
  return true;
}

/// SlamOptions::reloc.byPlace: after a reset, until a new map is built (and when relocalise()
/// found nothing), the frame's live tracks are described and the place index is asked for
/// keyframes of the same place in any segment; descriptor matches to a candidate's map points,
/// PnP-RANSAC with place.minInliers inliers (the best of place.candidates candidates), as many
/// as a place link's. The pose
/// is believed when the next frame's, in the same segment, agrees with the rays' rotation between
/// the two within reloc.placeAgreeDeg (two independent PnPs; the ray chain itself is in the lost
/// segment's world, so its absolute rotation says nothing about another one's). Then the frame
/// goes on in that segment: its matched tracks follow those map points, the reset is undone (no
/// new map, no new scale) and the frame becomes a keyframe. A place re-entered after a loss (the
/// head whipped away and back, the wearer came back to the table) joins the map that has it,
/// instead of a new segment tied to it afterwards by guesses. While a first pose waits for the
/// next frame's (placeWaiting_), no new map is built from this frame.
template <typename Scalar>
bool MonoSlam<Scalar>::relocaliseByPlace(int f) {
  placeWaiting_ = false;
  if (!opt_.reloc.enabled || !opt_.reloc.byPlace || placeIndex_.size() == 0) return false;
  Frame& fr = frames_.back();
  describer_.setImage(curPyr_.level(0));
  std::vector<BinaryDescriptor> desc;
  std::vector<int> ti;  // track of each descriptor
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    BinaryDescriptor d;
    if (describer_.compute(tracks_[i].px(0), tracks_[i].px(1), d)) {
      desc.push_back(d);
      ti.push_back(static_cast<int>(i));
    }
  }
  if (static_cast<int>(desc.size()) < opt_.place.minInliers) return false;
  const std::vector<PlaceCandidate> cand = placeIndex_.query(desc, opt_.place.minVotes, [](int) { return true; });
  PnPRansacResult<Scalar> best;
  int bestKf = -1;
  std::vector<std::pair<int, int>> bestPairs;  // (track index, map point) of its inliers
  for (std::size_t c = 0; c < cand.size() && static_cast<int>(c) < opt_.place.candidates; ++c) {
    const Keyframe& kc = keyframes_[static_cast<std::size_t>(cand[c].entry)];
    const std::vector<DescriptorMatch> m = matchBinaryDescriptors(desc, kc.desc, opt_.place.maxDistance, double(opt_.place.ratio));
    std::vector<V3> X;
    std::vector<V2> uv;
    std::vector<std::pair<int, int>> pairs;
    for (const DescriptorMatch& d : m) {
      const int pid = kc.descPoint[static_cast<std::size_t>(d.train)];
      if (!points_[static_cast<std::size_t>(pid)].valid) continue;
      const Track& t = tracks_[static_cast<std::size_t>(ti[static_cast<std::size_t>(d.query)])];
      X.push_back(points_[static_cast<std::size_t>(pid)].X);
      uv.push_back(V2(Scalar(t.uv(0)), Scalar(t.uv(1))));
      pairs.emplace_back(ti[static_cast<std::size_t>(d.query)], pid);
    }
    if (static_cast<int>(X.size()) < opt_.place.minInliers) continue;
    PnPRansacOptions<Scalar> po = opt_.pnp;
    po.seed = opt_.pnp.seed + 0x7f4a7c15u + static_cast<std::uint32_t>(f);
    po.minInliers = opt_.place.minInliers;
    const PnPRansacResult<Scalar> r = solvePnPRansac(X, uv, cam_, po);
    if (!r.ok() || r.numInliers < opt_.place.minInliers || r.numInliers <= best.numInliers) continue;
    best = r;
    bestKf = cand[c].entry;
    bestPairs.clear();
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      if (r.inliers[i]) bestPairs.push_back(pairs[i]);
    }
  }
  const int seg = bestKf >= 0 ? keyframes_[static_cast<std::size_t>(bestKf)].segment : -1;
  const Scalar off = placeCandFrame_ == f - 1 && placeCandSegment_ == seg && fr.rotationKnown
                        ? rotationAngleDeg(SE3T(placeCand_.inverse() * best.T_w_c), SE3T(frames_[static_cast<std::size_t>(f - 1)].T.inverse() * fr.T))
                        : Scalar(-1);
  const bool agree = bestKf >= 0 && off >= Scalar(0) && off <= opt_.reloc.placeAgreeDeg;
  if (opt_.log && bestKf >= 0) {
    opt_.log("frame " + std::to_string(f) + ": relocalisation by place: " + std::to_string(cand.size()) + " candidates, the best frame " +
             std::to_string(keyframes_[static_cast<std::size_t>(bestKf)].frame) + " (segment " + std::to_string(seg) + "), " +
             std::to_string(best.numInliers) + " PnP inliers" + (off >= Scalar(0) ? ", " + std::to_string(double(off)) + " deg from the last frame's and the rays'" : std::string()) +
             (agree ? ": relocalised" : off >= Scalar(0) ? ": rejected" : ": waits for the next frame"));
  }
  placeWaiting_ = bestKf >= 0 && off < Scalar(0);
  const SE3T prevPose = placeCand_;
  const int prevInliers = placeCandInliers_;
  placeCandFrame_ = bestKf >= 0 ? f : -1;
  placeCand_ = best.T_w_c;
  placeCandInliers_ = best.numInliers;
  placeCandSegment_ = seg;
  if (!agree) return false;
  fr.T = best.T_w_c;
  fr.posed = true;
  fr.inliers = best.numInliers;
  fr.status = SlamStatus::Relocalised;
  for (const auto& pr : bestPairs) {
    Track& t = tracks_[static_cast<std::size_t>(pr.first)];
    t.point = pr.second;
    t.kfObs.clear();
    trackPoint_[static_cast<std::size_t>(t.id)] = pr.second;
  }
  // The reset built no map: undone; the frames since it stay in the lost segment's world.
  const int lostSeg = undoReset(f);
  // The frame before, posed by the PnP it agreed with, is in the new world too: the next frame's
  // motion prediction (the last step carried on) must not span two worlds.
  Frame& pr = frames_[static_cast<std::size_t>(f - 1)];
  pr.T = prevPose;
  pr.posed = true;
  pr.inliers = prevInliers;
  pr.rotationKnown = true;
  pr.status = SlamStatus::Relocalised;
  pr.segment = seg;
  if (seg != lostSeg) {
    // The kept images are the lost segment's: another world.
    std::vector<KeyframePyramid>().swap(relocPyr_);
    std::vector<KeyframePyramid>().swap(linkPyr_);
    lastKfPyr_ = KeyframePyramid();
  }
  segment_ = seg;
  afterLoss_ = false;
  lost_ = 0;
  placeCandFrame_ = -1;
  ++placeRelocalisations_;
  searchPlaceByProjection(f, bestKf);
  insertKeyframe(f);
  return true;
}

/// After a relocalisation by place into keyframe `centre`'s segment: the described map points of
/// it and of up to 4 keyframes of that segment either side (in keyframe order) that no track
/// follows are projected under the frame's pose and looked for around their projection (±3 px:
/// the descriptor at each pixel against theirs, the nearest within place.maxDistance); the found
/// ones become mapped tracks, and the pose is solved again on all of them (PnP-RANSAC, outliers
/// dropped). One keyframe's matches are too few to track on (the map behind them is not).
template <typename Scalar>
void MonoSlam<Scalar>::searchPlaceByProjection(int f, int centre) {
  Frame& fr = frames_.back();
  const int seg = keyframes_[static_cast<std::size_t>(centre)].segment;
  std::vector<char> tried(points_.size(), 0);
  for (const Track& t : tracks_) {
    if (t.point >= 0) tried[static_cast<std::size_t>(t.point)] = 1;
  }
  std::vector<int> kfs{centre};
  for (int dir = -1; dir <= 1; dir += 2) {
    int got = 0;
    for (int k = centre + dir; k >= 0 && k < static_cast<int>(keyframes_.size()) && got < 4; k += dir) {
      if (keyframes_[static_cast<std::size_t>(k)].segment != seg) continue;
      kfs.push_back(k);
      ++got;
    }
  }
  const SE3T Tcw = fr.T.inverse();
  const int b = BinaryDescriptorExtractor::border() + 3;
  int found = 0;
  for (int k : kfs) {
    const Keyframe& kf = keyframes_[static_cast<std::size_t>(k)];
    for (std::size_t j = 0; j < kf.desc.size(); ++j) {
      const int pid = kf.descPoint[j];
      if (tried[static_cast<std::size_t>(pid)] || !points_[static_cast<std::size_t>(pid)].valid) continue;
      tried[static_cast<std::size_t>(pid)] = 1;
      const V3 Xc = Tcw * points_[static_cast<std::size_t>(pid)].X;
      if (!(Xc(2) > Scalar(0))) continue;
      const V2 q = cam_.project(Xc);
      if (!(q(0) >= Scalar(b) && q(1) >= Scalar(b) && q(0) < Scalar(width_ - b) && q(1) < Scalar(height_ - b))) continue;
      const int cx = static_cast<int>(std::lround(double(q(0)))), cy = static_cast<int>(std::lround(double(q(1))));
      if (masked(Vec2f(float(cx), float(cy)))) continue;
      int best = opt_.place.maxDistance + 1, bx = 0, by = 0;
      BinaryDescriptor d;
      for (int dy = -3; dy <= 3; ++dy) {
        for (int dx = -3; dx <= 3; ++dx) {
          if (!describer_.compute(float(cx + dx), float(cy + dy), d)) continue;
          const int h = hammingDistance(d, kf.desc[j]);
          if (h < best) best = h, bx = cx + dx, by = cy + dy;
        }
      }
      if (best > opt_.place.maxDistance) continue;
      Track t;
      t.id = static_cast<int>(trackPoint_.size());
      trackPoint_.push_back(pid);
      t.px = Vec2f(float(bx), float(by));
      t.uv = rollingShutterShift(t.px, Scalar(1));
      t.point = pid;
      tracks_.push_back(std::move(t));
      ++found;
    }
  }
  std::vector<V3> X;
  std::vector<V2> uv;
  std::vector<int> ti;
  mappedTracks(X, uv, ti);
  PnPRansacOptions<Scalar> po = opt_.pnp;
  po.seed = opt_.pnp.seed + 0x1b873593u + static_cast<std::uint32_t>(f);
  po.minInliers = opt_.place.minInliers;
  const PnPRansacResult<Scalar> r = solvePnPRansac(X, uv, cam_, po);
  if (opt_.log) {
    opt_.log("frame " + std::to_string(f) + ": relocalisation by place: " + std::to_string(found) + " more points found around their projections in " +
             std::to_string(kfs.size()) + " keyframes; " + std::to_string(r.ok() ? r.numInliers : 0) + " of " + std::to_string(X.size()) + " PnP inliers");
  }
  if (!r.ok() || r.numInliers <= fr.inliers) return;
  fr.T = r.T_w_c;
  fr.inliers = r.numInliers;
  dropOutlierTracks(ti, r.inliers);
}

/// finish(): each segment linked to earlier ones moved into their world, in order, by one
/// similarity of all its linked points' present positions (Umeyama, the worst third dropped and
/// refitted), and everything after it with it. Returns the segments moved.
template <typename Scalar>
int MonoSlam<Scalar>::placeSegmentsByLinks() {
  int moved = 0;
  const std::vector<int> segFirstKf = segmentFirstKeyframes();
  for (std::size_t i = 1; i < segFirstKf.size(); ++i) {
    const int seg = keyframes_[static_cast<std::size_t>(segFirstKf[i])].segment;
    std::vector<std::pair<int, int>> use;  // (point in seg, point in an earlier segment)
    for (const PlaceLink& l : placeLinks_) {
      if (keyframes_[static_cast<std::size_t>(l.kf)].segment != seg || inSegment(keyframes_[static_cast<std::size_t>(l.oldKf)].segment, seg)) continue;
      for (const auto& p : l.pairs) {
        if (points_[static_cast<std::size_t>(p.first)].valid && points_[static_cast<std::size_t>(p.second)].valid) use.push_back(p);
      }
    }
    if (static_cast<int>(use.size()) < opt_.place.minInliers) continue;
    auto fit = [&](const std::vector<std::pair<int, int>>& q) {
      Points3<Scalar> src(static_cast<Eigen::Index>(q.size()), 3), dst(static_cast<Eigen::Index>(q.size()), 3);
      for (std::size_t j = 0; j < q.size(); ++j) {
        src.row(static_cast<Eigen::Index>(j)) = points_[static_cast<std::size_t>(q[j].first)].X.transpose();
        dst.row(static_cast<Eigen::Index>(j)) = points_[static_cast<std::size_t>(q[j].second)].X.transpose();
      }
      return umeyama(src, dst, true);
    };
    SimilarityTransform<Scalar> G;
    try {
      G = fit(use);
      std::vector<std::pair<Scalar, std::size_t>> err(use.size());
      for (std::size_t j = 0; j < use.size(); ++j) {
        err[j] = {(G.apply(points_[static_cast<std::size_t>(use[j].first)].X) - points_[static_cast<std::size_t>(use[j].second)].X).norm(), j};
      }
      std::sort(err.begin(), err.end());
      std::vector<std::pair<int, int>> best;
      for (std::size_t j = 0; j < err.size() - err.size() / 3; ++j) best.push_back(use[err[j].second]);
      G = fit(best);
    } catch (const Error&) {
      continue;
    }
    if (!(G.s > Scalar(0)) || !std::isfinite(double(G.s))) continue;
    const int f1 = keyframes_[static_cast<std::size_t>(segFirstKf[i])].frame;
    if (opt_.log) {
      opt_.log("segment starting at frame " + std::to_string(f1) + ": placed by " + std::to_string(use.size()) +
               " linked points, scale " + std::to_string(double(G.s)) + ", rotation " +
               std::to_string(double(SO3<Scalar>::fromMatrix(G.R).log().norm() * Scalar(180) / Constants<Scalar>::pi())) + " deg");
    }
    const Sim3<Scalar> S = G.toSim3();
    transformFrom(f1, seg, [&](const V3& x) { return V3(S * x); }, &S.rotation());
    ++moved;
  }
  return moved;
}

}  // namespace hawor
