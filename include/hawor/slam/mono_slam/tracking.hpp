// hawor/slam/mono_slam/tracking.hpp — MonoSlam's tracking: PnP against the map, the turn bridge,
// losses and resets.
// Member functions of MonoSlam (slam/mono_slam.hpp: the class, its state and the overview);
// included at the end of that header.
#pragma once

#include "../mono_slam.hpp"

namespace hawor {

/// Angle of the relative rotation between two poses (degrees): acos((tr(R_aᵀR_b) − 1)/2).
template <typename Scalar>
Scalar MonoSlam<Scalar>::rotationAngleDeg(const SE3T& a, const SE3T& b) {
  const Scalar c = (Mat3<Scalar>(a.rotationMatrix().transpose() * b.rotationMatrix()).trace() - Scalar(1)) / Scalar(2);
  return std::acos(std::max(Scalar(-1), std::min(Scalar(1), c))) * Scalar(180) / Constants<Scalar>::pi();
}

/// The tracks that follow a map point: its position, the track's pixel, the track's index.
/// (A track never refers to an invalid point: cullObservations removes those tracks.)
template <typename Scalar>
void MonoSlam<Scalar>::mappedTracks(std::vector<V3>& X, std::vector<V2>& uv, std::vector<int>& ti) const {
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    if (tracks_[i].point < 0) continue;
    X.push_back(points_[static_cast<std::size_t>(tracks_[i].point)].X);
    uv.push_back(V2(Scalar(tracks_[i].uv(0)), Scalar(tracks_[i].uv(1))));
    ti.push_back(static_cast<int>(i));
  }
}

/// A frame's stored observations of valid map points (its tracks' points, as finish() and the
/// tracks followed back resect it): the point's position, the pixel, the point's index.
template <typename Scalar>
void MonoSlam<Scalar>::mappedObservations(const Frame& fr, std::vector<V3>& X, std::vector<V2>& uv, std::vector<int>& pids) const {
  for (std::size_t i = 0; i < fr.obsTrack.size(); ++i) {
    const int pid = trackPoint_[static_cast<std::size_t>(fr.obsTrack[i])];
    if (pid < 0 || !points_[static_cast<std::size_t>(pid)].valid) continue;
    X.push_back(points_[static_cast<std::size_t>(pid)].X);
    uv.push_back(V2(Scalar(fr.obsUv[i](0)), Scalar(fr.obsUv[i](1))));
    pids.push_back(pid);
  }
}

/// After PnP-RANSAC on mappedTracks: an outlier track has drifted off its point, so it is
/// dropped (a new corner replaces it).
template <typename Scalar>
void MonoSlam<Scalar>::dropOutlierTracks(const std::vector<int>& ti, const std::vector<char>& inliers) {
  std::vector<char> drop(tracks_.size(), 0);
  for (std::size_t j = 0; j < ti.size(); ++j) {
    if (!inliers[j]) drop[static_cast<std::size_t>(ti[j])] = 1;
  }
  removeTracks(drop);
}

template <typename Scalar>
int MonoSlam<Scalar>::countMapped() const {
  int n = 0;
  for (const Track& t : tracks_) n += t.point >= 0 ? 1 : 0;
  return n;
}

template <typename Scalar>
void MonoSlam<Scalar>::trackPose(int f) {
  Frame& fr = frames_.back();
  std::vector<V3> X;
  std::vector<V2> uv;
  std::vector<int> ti;
  mappedTracks(X, uv, ti);
  bool ok = false;
  // Rotation-checked tracking: while a head turn sweeps the map out of view, fewer than
  // minInliers map points may remain. A pose from as few as turn.minInliers is accepted when
  // its rotation agrees with the one of all tracked rays (hundreds of tracks, mapped or not;
  // near-exact for a rotation-dominant motion) and most of the points are inliers.
  const int needed = std::min(opt_.minInliers, opt_.turn.minInliers);
  Mat3<Scalar> dRays;
  const bool haveRays = turning_ && static_cast<int>(X.size()) < 2 * opt_.minInliers && rayRotation(dRays);
  if (static_cast<int>(X.size()) >= (haveRays ? needed : opt_.minInliers)) {
    PnPRansacOptions<Scalar> po = opt_.pnp;
    po.seed = opt_.pnp.seed + static_cast<std::uint32_t>(f);
    po.minInliers = haveRays ? needed : opt_.minInliers;
    const PnPRansacResult<Scalar> r = solvePnPRansac(X, uv, cam_, po);
    bool accept = r.ok();
    if (accept && r.numInliers < opt_.minInliers) {
      const SE3T& prev = frames_[static_cast<std::size_t>(f - 1)].T;
      const SE3T byRays(SO3<Scalar>::fromMatrix(Mat3<Scalar>(prev.rotationMatrix() * dRays)), prev.translation());
      accept = rotationAngleDeg(byRays, r.T_w_c) < opt_.turn.rotationAgreementDeg &&
               Scalar(r.numInliers) >= Scalar(0.8) * Scalar(X.size());
    }
    if (accept) {
      ok = true;
      fr.T = r.T_w_c;
      fr.inliers = r.numInliers;
      dropOutlierTracks(ti, r.inliers);
    }
  }
  if (opt_.log) {
    opt_.log("frame " + std::to_string(f) + ": pnp " + std::to_string(X.size()) + " mapped tracks, " +
             std::to_string(ok ? fr.inliers : 0) + " inliers, " + std::to_string(tracks_.size()) + " tracks");
  }
  if (ok) {
    bridged_ = 0;
  } else if (opt_.turn.bridge && turning_ && f >= 2 && frames_[static_cast<std::size_t>(f - 1)].posed &&
             frames_[static_cast<std::size_t>(f - 2)].posed && bridged_ < opt_.turn.maxBridgeFrames) {
    ok = bridgeTurn(f);
    bridged_ = ok ? bridged_ + 1 : 0;
  }
  if (ok) {
    fr.posed = true;
    fr.status = SlamStatus::Tracked;
    lost_ = 0;
    ++framesSinceKf_;
    // A keyframe when the map thins out, tracking is about to fail, a turn sweeps the view, or
    // after a maximum interval (keyframe_policy.hpp).
    KeyframeQuery<Scalar> q;
    q.mappedInliers = fr.inliers;
    q.lastKeyframeInliers = lastKfInliers_;
    q.framesSinceKeyframe = framesSinceKf_;
    q.trackingMinInliers = opt_.minInliers;
    q.turning = turning_;
    q.rotationSinceKeyframeDeg = turning_ ? rotationAngleDeg(keyframes_.back().T, fr.T) : Scalar(0);
    if (keyframeReason(q, opt_.keyframe) != KeyframeReason::None) insertKeyframe(f);
    return;
  }
  // Lost: rotation from the rays, position held; relocalisation against the map; after a few
  // frames, a new map segment.
  fr.posed = false;
  Mat3<Scalar> dR;
  const Frame& prev = frames_[static_cast<std::size_t>(f - 1)];
  if (rayRotation(dR)) {
    fr.T = SE3T(SO3<Scalar>::fromMatrix(Mat3<Scalar>(prev.T.rotationMatrix() * dR)), prev.T.translation());
  } else if (!coastRotation(f)) {
    fr.T = prev.T;
    fr.rotationKnown = false;
  }
  if (relocalise(f)) return;
  if (lost_ == 0) ++losses_;
  ++lost_;
  fr.status = SlamStatus::Lost;
  if (lost_ >= opt_.lostFramesBeforeReset) {
    state_ = State::Initialising;
    afterLoss_ = true;
    ++resets_;
    segmentParent_.push_back(segment_);
    segment_ = static_cast<int>(segmentParent_.size()) - 1;
    segmentStart_ = f;
    // The tracks go on, under new ids: their old observations keep mapping to the old points.
    for (Track& t : tracks_) {
      t.point = -1;
      t.kfObs.clear();
      const int oldId = t.id;
      t.id = static_cast<int>(trackPoint_.size());
      trackPoint_.push_back(-1);
      trackAlias_.resize(trackPoint_.size(), -1);
      trackAlias_.back() = oldId;
    }
    setReference(f);
  }
}

/// SlamOptions::turn.bridge (turn_bridge.hpp): the pose of frame f from frame f − 1 and the
/// tracks between them. The length's points: the map points still tracked and every other
/// track seen in frames f − 2 and f − 1 (both posed), triangulated from those two.
template <typename Scalar>
bool MonoSlam<Scalar>::bridgeTurn(int f) {
  Frame& fr = frames_.back();
  const Frame& p1 = frames_[static_cast<std::size_t>(f - 1)];
  const Frame& p2 = frames_[static_cast<std::size_t>(f - 2)];
  const SE3T T1cw = p1.T.inverse(), T2cw = p2.T.inverse();
  const Scalar cosMin = std::cos(opt_.turn.bridgeMinParallaxDeg * Constants<Scalar>::pi() / Scalar(180));
  std::vector<V2> x1, x2, y;
  std::vector<V3> X;
  x1.reserve(tracks_.size()), x2.reserve(tracks_.size());
  int fresh = 0;
  // (Tracks added after the KLT step, by re-finding, have no previous position: the first
  // prevUv_.size() are the tracked ones.)
  for (std::size_t i = 0; i < std::min(tracks_.size(), prevUv_.size()); ++i) {
    const Track& t = tracks_[i];
    x1.push_back(normalised(prevUv_[i]));
    x2.push_back(normalised(t.uv));
    if (t.point >= 0 && points_[static_cast<std::size_t>(t.point)].valid) {
      X.push_back(points_[static_cast<std::size_t>(t.point)].X);
      y.push_back(x2.back());
      continue;
    }
    // Its observation in frame f − 2 (observation lists are sorted by track id).
    const auto it = std::lower_bound(p2.obsTrack.begin(), p2.obsTrack.end(), t.id);
    if (it == p2.obsTrack.end() || *it != t.id) continue;
    const Vec2f& u2 = p2.obsUv[static_cast<std::size_t>(it - p2.obsTrack.begin())];
    const V2 x0 = normalised(u2);
    const V3 r0 = p2.T.rotationMatrix() * V3(x0(0), x0(1), Scalar(1));
    const V3 r1 = p1.T.rotationMatrix() * V3(x1.back()(0), x1.back()(1), Scalar(1));
    if (r0.normalized().dot(r1.normalized()) > cosMin) continue;
    V3 P;
    if (!triangulateDLT(T2cw, T1cw, x0, x1.back(), P)) continue;
    if (!((T2cw * P)(2) > Scalar(0)) || !((T1cw * P)(2) > Scalar(0))) continue;
    X.push_back(P);
    y.push_back(x2.back());
    ++fresh;
  }
  // Predicted length: the last step's radius, |c₁ − c₂| / (2·sin(θ₁₂/2)), times 2·sin(θ/2)
  // with θ the rays' rotation (none when the last step hardly turned).
  Scalar step = Scalar(-1);
  Mat3<Scalar> dR;
  const Scalar th12 = rotationAngleDeg(p2.T, p1.T) * Constants<Scalar>::pi() / Scalar(180);
  if (th12 > Scalar(2) * Constants<Scalar>::pi() / Scalar(180) && rayRotation(dR)) {
    const Scalar th = SO3<Scalar>::fromMatrix(dR).log().norm();
    step = (p1.T.translation() - p2.T.translation()).norm() / (Scalar(2) * std::sin(th12 / Scalar(2))) * Scalar(2) * std::sin(th / Scalar(2));
  }
  const TurnBridgeResult<Scalar> r = bridgeTurnPose(p1.T, x1, x2, X, y, cam_.fx, step, opt_.bridge);
  if (opt_.log) {
    opt_.log("frame " + std::to_string(f) + ": turn bridge, " + std::to_string(x1.size()) + " tracks, " +
             std::to_string(r.inliers) + " epipolar inliers, rotation moved " + std::to_string(double(r.rotationChangeDeg)) +
             " deg from the rays', length " + std::to_string(double(r.length)) + " (predicted " + std::to_string(double(step)) + ") from " + std::to_string(r.pointInliers) + " of " +
             std::to_string(X.size()) + " points (" + std::to_string(fresh) + " triangulated): " + (r.ok ? std::string("posed") : r.why));
  }
  if (!r.ok) return false;
  fr.T = r.T_w_c;
  fr.inliers = r.pointInliers;
  return true;
}

template <typename Scalar>
int MonoSlam<Scalar>::addPoint(MapPoint&& p, int trackId) {
  const int id = static_cast<int>(points_.size());
  for (const Obs& o : p.obs) keyframes_[static_cast<std::size_t>(o.kf)].points.push_back(id);
  points_.push_back(std::move(p));
  trackPoint_[static_cast<std::size_t>(trackId)] = id;
  return id;
}

}  // namespace hawor
