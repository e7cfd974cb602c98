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
// finish(), before the sequence refinement: a segment linked to an earlier one (after a reset: a
// map of its own, joined to the old one by guesses — the median depth, the head model) is moved
// into the earlier one's world by one similarity of its linked points' present positions
// (placeSegmentsByLinks), and everything after it with it, so that it takes the scale of the place
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
      if (keyframes_[static_cast<std::size_t>(l.kf)].segment != seg || keyframes_[static_cast<std::size_t>(l.oldKf)].segment >= seg) continue;
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
