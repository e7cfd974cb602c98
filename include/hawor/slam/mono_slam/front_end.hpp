// hawor/slam/mono_slam/front_end.hpp — MonoSlam's front end: prediction, KLT tracking with the hand
// masks, corners, the rays' rotation.
// Member functions of MonoSlam (slam/mono_slam.hpp: the class, its state and the overview);
// included at the end of that header.
#pragma once

#include "../mono_slam.hpp"

namespace hawor {

template <typename Scalar>
auto MonoSlam<Scalar>::normalised(const Vec2f& uv) const -> V2 {
  return V2((Scalar(uv(0)) - cam_.cx) / cam_.fx, (Scalar(uv(1)) - cam_.cy) / cam_.fy);
}

template <typename Scalar>
bool MonoSlam<Scalar>::masked(const Vec2f& uv) const {
  if (!hasMask_) return false;
  const int x = int(std::floor(uv(0) + 0.5f)), y = int(std::floor(uv(1) + 0.5f));
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return false;
  return curMask_.at(x, y) != 0;
}

template <typename Scalar>
bool MonoSlam<Scalar>::insideImage(const Vec2f& uv, float margin) const {
  return uv(0) >= margin && uv(1) >= margin && uv(0) <= float(width_ - 1) - margin &&
         uv(1) <= float(height_ - 1) - margin;
}

/// SlamOptions::rollingShutter: image pixel → the middle row's time (sign +1), or back (−1,
/// the inverse to first order). The identity for a global shutter or without a rotation rate.
template <typename Scalar>
auto MonoSlam<Scalar>::rollingShutterShift(const Vec2f& p, Scalar sign) const -> Vec2f {
  if (opt_.rollingShutter == Scalar(0) || rsOmega_.isZero(Scalar(0))) return p;
  const Scalar d = sign * opt_.rollingShutter * ((Scalar(p(1)) - Scalar(0.5) * Scalar(height_ - 1)) / Scalar(height_));
  const V3 b((Scalar(p(0)) - cam_.cx) / cam_.fx, (Scalar(p(1)) - cam_.cy) / cam_.fy, Scalar(1));
  const V3 r = SO3<Scalar>::exp(V3(rsOmega_ * d)) * b;
  if (!(r(2) > Scalar(0))) return p;
  return Vec2f(float(cam_.fx * r(0) / r(2) + cam_.cx), float(cam_.fy * r(1) / r(2) + cam_.cy));
}

/// The camera's rotation over the last frame from the raw pixels KLT just tracked (from_ → to_,
/// ok_), as a rotation vector in camera axes (R(t+1) = R(t)·exp(ω)); zero for a global shutter
/// or with fewer than 8 rays. The rolling shutter's shear is the same in both frames under a
/// steady turn, so the raw rays' best rotation is the middle rows' one.
template <typename Scalar>
auto MonoSlam<Scalar>::rsRate() -> V3 {
  if (opt_.rollingShutter == Scalar(0)) return V3::Zero();
  std::vector<V2> a, b;
  for (std::size_t i = 0; i < from_.size(); ++i) {
    if (!ok_[i]) continue;
    a.push_back(normalised(from_[i]));
    b.push_back(normalised(to_[i]));
  }
  Mat3<Scalar> R21;
  if (a.size() < 8 || two_view_detail::rotationFromRaysReweighted(a, b, Scalar(3), R21) < 8) return V3::Zero();
  return SO3<Scalar>::fromMatrix(Mat3<Scalar>(R21.transpose())).log();
}

template <typename Scalar>
void MonoSlam<Scalar>::trackFeatures(int f) {
  // Prediction (c2w). Rotation: constant angular velocity, R_pred = R1·(R2ᵀ·R1), from the last
  // two frames' rotations, known from the map or from the tracked rays (a fast head turn moves
  // the image by up to 20° ≈ 140 px a frame, far beyond the pyramid's range without a guess).
  // Translation: constant velocity when both frames have a map pose, else held.
  const Frame& p1 = frames_[static_cast<std::size_t>(f - 1)];
  const bool rot2 = f >= 2 && frames_[static_cast<std::size_t>(f - 2)].rotationKnown && p1.rotationKnown;
  // Turn mode: the last rotation increment is at least turn.rateDeg a frame (a fast head
  // turn; slow looking around stays far below), held for turn.holdFrames after (deceleration).
  if (rot2 && rotationAngleDeg(frames_[static_cast<std::size_t>(f - 2)].T, p1.T) >= opt_.turn.rateDeg) {
    turnUntil_ = f + opt_.turn.holdFrames;
  }
  turning_ = f <= turnUntil_;
  havePrediction_ = state_ == State::Tracking && f >= 2 && frames_[static_cast<std::size_t>(f - 2)].posed && p1.posed;
  if (havePrediction_) {
    const Frame& p2 = frames_[static_cast<std::size_t>(f - 2)];
    predicted_ = p1.T * (p2.T.inverse() * p1.T);
  } else if (rot2 && turning_) {
    predicted_ = rotationCarriedOn(f);
  } else {
    predicted_ = p1.T;
  }
  // Camera-1 → predicted-camera rotation for directions (the infinite homography K·Rpc·K⁻¹:
  // exact for distant points, a few pixels off for near ones under the small head translation).
  const Mat3<Scalar> Rpc = predicted_.rotationMatrix().transpose() * p1.T.rotationMatrix();
  // The rolling shutter's angular velocity for this frame: the last step's, measured on the raw
  // pixels (rsRate, below), so that the compensation never feeds back into its own rate.
  rsOmega_ = rsOmegaNext_;
  from_.resize(tracks_.size());
  to_.resize(tracks_.size());
  const SE3T Tcw = predicted_.inverse();
  std::vector<char> guessed(tracks_.size(), 0);
  float sdx = 0, sdy = 0;
  int npred = 0;
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    const Track& t = tracks_[i];
    from_[i] = t.px;
    to_[i] = t.uv;
    if (turning_) {
      const V2 x = normalised(t.uv);
      const V3 d = Rpc * V3(x(0), x(1), Scalar(1));
      const Vec2f h(float(cam_.fx * d(0) / d(2) + cam_.cx), float(cam_.fy * d(1) / d(2) + cam_.cy));
      if (d(2) > Scalar(0) && std::isfinite(h(0)) && std::isfinite(h(1))) to_[i] = h;
    }
    if (t.point >= 0 && (havePrediction_ || (turning_ && state_ == State::Tracking))) {
      // A mapped track: its point projected under the predicted pose.
      const V3 Xc = Tcw * points_[static_cast<std::size_t>(t.point)].X;
      if (Xc(2) > Scalar(0)) {
        const V2 q = cam_.project(Xc);
        const Vec2f g(float(q(0)), float(q(1)));
        if (std::isfinite(g(0)) && std::isfinite(g(1)) && insideImage(g, -50.0f)) {
          sdx += g(0) - to_[i](0), sdy += g(1) - to_[i](1);
          ++npred;
          to_[i] = g;
          guessed[i] = 1;
        }
      }
    }
  }
  // Unmapped tracks: the mean shift of the mapped ones' guesses (in a turn: on top of the
  // rotation guess, i.e. the mean translation-induced shift).
  if (npred > 0) {
    const float mx = sdx / float(npred), my = sdy / float(npred);
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
      if (!guessed[i]) to_[i] = Vec2f(to_[i](0) + mx, to_[i](1) + my);
    }
  }
  // The guesses are geometric positions; KLT looks in the image.
  for (std::size_t i = 0; i < tracks_.size(); ++i) to_[i] = rollingShutterShift(to_[i], Scalar(-1));
  trackKlt(prevPyr_, curPyr_, from_, to_, ok_, opt_.klt);
  std::size_t w = 0;
  const float margin = float(opt_.klt.halfWindow + 1);
  prevUv_.clear();
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    if (!ok_[i] || !insideImage(to_[i], margin) || masked(to_[i])) continue;
    prevUv_.push_back(tracks_[i].uv);
    if (w != i) tracks_[w] = std::move(tracks_[i]);  // (a self-move would empty kfObs)
    tracks_[w].px = to_[i];
    tracks_[w].uv = rollingShutterShift(to_[i], Scalar(1));
    ++w;
  }
  tracks_.resize(w);
  rsOmegaNext_ = rsRate();
}

/// New tracks in the empty cells of the bucketing grid (never on the dilated hand mask).
template <typename Scalar>
void MonoSlam<Scalar>::replenish() {
  const int want = opt_.maxFeatures - static_cast<int>(tracks_.size());
  if (want <= 0) return;
  existing_.clear();
  for (const Track& t : tracks_) existing_.push_back(t.px);
  fresh_.clear();
  detectCorners(curPyr_.level(0), hasMask_ ? &curMask_ : nullptr, existing_, want, opt_.corners, fresh_, cornerScratch_);
  for (const Vec2f& p : fresh_) {
    Track t;
    t.id = static_cast<int>(trackPoint_.size());
    trackPoint_.push_back(-1);
    t.px = p;
    t.uv = rollingShutterShift(p, Scalar(1));
    tracks_.push_back(std::move(t));
  }
}

/// Frame f becomes the reference of the two-view initialisation (tracks replenished first).
template <typename Scalar>
void MonoSlam<Scalar>::setReference(int f) {
  replenish();
  refFrame_ = f;
  refMask_ = hasMask_ ? CoarseMask(curMask_, opt_.maskBlock) : CoarseMask();
  frames_[static_cast<std::size_t>(f)].mask = refMask_;
  for (Track& t : tracks_) {
    t.refUv = t.uv;
    t.fromRef = true;
  }
}

template <typename Scalar>
void MonoSlam<Scalar>::recordObservations(Frame& fr) {
  fr.obsTrack.resize(tracks_.size());
  fr.obsUv.resize(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    fr.obsTrack[i] = tracks_[i].id;
    fr.obsUv[i] = tracks_[i].uv;
  }
  fr.obsTrack.shrink_to_fit();
  fr.obsUv.shrink_to_fit();
}

/// Rotation of the current frame relative to the previous one from the tracked rays (Kabsch
/// with one re-weighting pass that drops rays more than 3° off), as a c2w increment.
template <typename Scalar>
bool MonoSlam<Scalar>::rayRotation(Mat3<Scalar>& Rprev_cur) {
  std::vector<V2> a, b;
  a.reserve(tracks_.size());
  b.reserve(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    a.push_back(normalised(prevUv_[i]));
    b.push_back(normalised(tracks_[i].uv));
  }
  if (a.size() < 8) return false;
  Mat3<Scalar> R;
  if (two_view_detail::rotationFromRaysReweighted(a, b, Scalar(3), R) < 8) return false;
  // rotationFromRays gives R21 (f2 ≈ R21·f1): camera 1 → camera 2 for directions, so
  // R_c1_c2 (c2w increment) = R21ᵀ.
  Rprev_cur = R.transpose();
  return true;
}

/// Frame f's pose at the last step's angular velocity, position held: R_f = R_{f−1}·(R_{f−2}ᵀ·R_{f−1})
/// (KLT's guess in a turn, and coastRotation).
template <typename Scalar>
auto MonoSlam<Scalar>::rotationCarriedOn(int f) const -> SE3T {
  const SE3T& T1 = frames_[static_cast<std::size_t>(f - 1)].T;
  const Mat3<Scalar> R1 = T1.rotationMatrix(), R2 = frames_[static_cast<std::size_t>(f - 2)].T.rotationMatrix();
  return SE3T(SO3<Scalar>::fromMatrix(Mat3<Scalar>(R1 * (R2.transpose() * R1))), T1.translation());
}

/// SlamOptions::turn.coastFrames: frame f's rotation when the tracked rays give none, in turn mode:
/// the last step carried on, R_f = R_{f−1}·(R_{f−2}ᵀ·R_{f−1}) (constant angular velocity),
/// position held; at most turn.coastFrames frames in a row and only from a step of at most
/// turn.coastMaxStepDeg. A head turning onto a bare wall keeps turning while no track survives;
/// holding the rotation instead loses the whole turn (fast_turns seed 8: 66° over frames 88–91)
/// and every later frame, posed or not, keeps that offset.
template <typename Scalar>
bool MonoSlam<Scalar>::coastRotation(int f) {
  Frame& fr = frames_.back();
  if (opt_.turn.coastFrames <= 0 || !turning_ || f < 2) return false;
  const Frame& p1 = frames_[static_cast<std::size_t>(f - 1)];
  const Frame& p2 = frames_[static_cast<std::size_t>(f - 2)];
  if (!p1.rotationKnown || !p2.rotationKnown) return false;
  int run = 0;
  while (run < f && frames_[static_cast<std::size_t>(f - 1 - run)].coasted) ++run;
  if (run >= opt_.turn.coastFrames) return false;
  if (rotationAngleDeg(p2.T, p1.T) > opt_.turn.coastMaxStepDeg) return false;
  fr.T = rotationCarriedOn(f);
  fr.rotationKnown = true;
  fr.coasted = true;
  if (opt_.log) opt_.log("frame " + std::to_string(f) + ": no rotation from the rays, the last step's carried on");
  return true;
}

/// Before a map: a track whose ray is more than maxRayJumpDeg off the frame's rotation from
/// the rays (f2 ≈ dRᵀ·f1) jumped — KLT locked onto a repeated or weak texture one period off
/// at the onset of a turn, where the prediction lags — and is dropped: such tracks move
/// together and give the two-view a coherent wrong motion (fast_turns seed 6 frame 25: 37 of 85
/// tracks 40–160 px off). A frame's parallax from the head's translation is a few pixels.
template <typename Scalar>
void MonoSlam<Scalar>::dropJumpedTracks(const Mat3<Scalar>& dR) {
  if (!(opt_.maxRayJumpDeg > Scalar(0)) || prevUv_.size() != tracks_.size()) return;
  const Scalar cosMax = std::cos(opt_.maxRayJumpDeg * Constants<Scalar>::pi() / Scalar(180));
  const Mat3<Scalar> R21 = dR.transpose();
  std::vector<char> drop(tracks_.size(), 0);
  int n = 0;
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    if (two_view_detail::rotatedRayCos(R21, normalised(prevUv_[i]), normalised(tracks_[i].uv)) < cosMax) drop[i] = 1, ++n;
  }
  if (n == 0) return;
  if (opt_.log) opt_.log("frame " + std::to_string(frames_.size() - 1) + ": " + std::to_string(n) + " tracks jumped off the rays' rotation, dropped");
  removeTracks(drop);
}

/// SlamOptions::backTrackFrames: after process() of frame f. An unposed frame's pyramid and hand
/// mask are kept after a loss (the last backTrackFrames of them); the first posed frame after
/// such frames follows the map's tracks back through them and lets them go.
template <typename Scalar>
void MonoSlam<Scalar>::keepForTracksBack(int f) {
  if (opt_.backTrackFrames <= 0 || opt_.rollingShutter != Scalar(0)) return;
  if (frames_[static_cast<std::size_t>(f)].posed) {
    if (!backPyr_.empty()) followTracksBack(f);
    backPyr_.clear();
    return;
  }
  // Not before the first map: the frames there are placed by the first map's own passes, and
  // posing them from it measured worse (docs/experiments.md).
  if (!everInitialised_) return;
  BackFrame k;
  if (static_cast<int>(backPyr_.size()) >= opt_.backTrackFrames) {
    k = std::move(backPyr_.front());  // (its buffers reused)
    backPyr_.pop_front();
  }
  k.frame = f;
  k.pyr.levels = curPyr_.levels;
  k.mask = hasMask_ ? CoarseMask(curMask_, opt_.maskBlock) : CoarseMask();
  backPyr_.push_back(std::move(k));
}

/// Frame f is posed after the unposed frames in backPyr_ (consecutive, up to f − 1): each track
/// of f on a valid map point whose first observation is at frame b is tracked back by KLT from b
/// to b − 1, b − 2, ... (forward-backward checked, started where the frames' rotations from the
/// rays carry it, off the hand masks kept for those frames) while it holds, and recorded as an
/// observation of those frames. Track ids only grow, so every id added to a frame is above its
/// own and the per-frame lists stay sorted. finish() then poses those frames against the map
/// (refineAllFrames' resection, the sequence refinement) where they would otherwise be
/// interpolated: the frames between a loss and the new map (or the old map found again).
template <typename Scalar>
void MonoSlam<Scalar>::followTracksBack(int f) {
  const int oldest = backPyr_.front().frame;
  if (backPyr_.back().frame != f - 1) return;  // not the frames just before f
  auto observes = [&](const Frame& fr, int id) {
    return std::binary_search(fr.obsTrack.begin(), fr.obsTrack.end(), id);
  };
  auto positionIn = [&](const Frame& fr, int id) {
    const auto it = std::lower_bound(fr.obsTrack.begin(), fr.obsTrack.end(), id);
    return fr.obsUv[static_cast<std::size_t>(it - fr.obsTrack.begin())];
  };
  // (first observed frame, track id) of the mapped tracks first seen after the oldest kept frame
  std::vector<std::pair<int, int>> born;
  for (const int id : frames_[static_cast<std::size_t>(f)].obsTrack) {
    const int pid = trackPoint_[static_cast<std::size_t>(id)];
    if (pid < 0 || !points_[static_cast<std::size_t>(pid)].valid) continue;
    int b = f;
    while (b - 1 >= oldest && observes(frames_[static_cast<std::size_t>(b - 1)], id)) --b;
    if (b - 1 >= oldest) born.emplace_back(b, id);
  }
  if (born.empty()) return;
  std::sort(born.begin(), born.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::size_t next = 0;
  std::vector<int> ids;
  std::vector<Vec2f> from, to;
  std::vector<char> ok;
  const float margin = float(opt_.klt.halfWindow + 1);
  int added = 0, reached = f;
  // A map just built from the pair (refFrame_, f) poses frames before its reference by
  // extrapolating its baseline: at most backTrackBaselines times the pair's gap back from it.
  int lowest = oldest;
  if (refFrame_ >= oldest && refFrame_ < f && frames_[static_cast<std::size_t>(refFrame_)].posed) {
    lowest = std::max(oldest, refFrame_ - opt_.backTrackBaselines * (f - refFrame_));
  }
  for (int g = f - 1; g >= lowest; --g) {
    // the tracks first seen at g + 1 join those followed back to it
    const Frame& src = frames_[static_cast<std::size_t>(g + 1)];
    for (; next < born.size() && born[next].first == g + 1; ++next) {
      ids.push_back(born[next].second);
      from.push_back(positionIn(src, born[next].second));
    }
    if (ids.empty()) continue;
    Frame& dst = frames_[static_cast<std::size_t>(g)];
    // start where the rotation between the frames moves each ray (the position held)
    to = from;
    if (src.rotationKnown && dst.rotationKnown) {
      const Mat3<Scalar> R = dst.T.rotationMatrix().transpose() * src.T.rotationMatrix();
      for (std::size_t i = 0; i < from.size(); ++i) {
        const V2 x = normalised(from[i]);
        const V3 r = R * V3(x(0), x(1), Scalar(1));
        if (r(2) > Scalar(0)) to[i] = Vec2f(float(cam_.fx * r(0) / r(2) + cam_.cx), float(cam_.fy * r(1) / r(2) + cam_.cy));
      }
    }
    const ImagePyramid& p1 = g + 1 == f ? curPyr_ : backPyr_[static_cast<std::size_t>(g + 1 - oldest)].pyr;
    const BackFrame& b0 = backPyr_[static_cast<std::size_t>(g - oldest)];
    trackKlt(p1, b0.pyr, from, to, ok, opt_.klt);
    std::vector<std::pair<int, Vec2f>> kept;
    for (std::size_t i = 0; i < ids.size(); ++i) {
      if (ok[i] && insideImage(to[i], margin) && !b0.mask.test(to[i](0), to[i](1))) kept.emplace_back(ids[i], to[i]);
    }
    std::sort(kept.begin(), kept.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const std::size_t before = dst.obsTrack.size();
    for (const auto& k : kept) {
      dst.obsTrack.push_back(k.first);
      dst.obsUv.push_back(k.second);
    }
    // The frame must be posed by the map through them (PnP-RANSAC on all its map points):
    // tracks followed onto the wrong texture end the walk back here.
    std::vector<V3> X;
    std::vector<V2> uv;
    std::vector<int> pids;
    mappedObservations(dst, X, uv, pids);
    bool posed = false;
    if (static_cast<int>(X.size()) >= opt_.minInliers) {
      PnPRansacOptions<Scalar> po = opt_.pnp;
      po.minInliers = opt_.minInliers;
      posed = solvePnPRansac(X, uv, cam_, po).ok();
    }
    if (!posed) {
      dst.obsTrack.resize(before);
      dst.obsUv.resize(before);
      break;
    }
    ids.clear(), from.clear();
    for (const auto& k : kept) {
      ids.push_back(k.first);
      from.push_back(k.second);
    }
    added += static_cast<int>(kept.size());
    reached = g;
  }
  if (opt_.log) {
    opt_.log("frame " + std::to_string(f) + ": tracks followed back over frames " + std::to_string(oldest) + "-" +
             std::to_string(f - 1) + ": " + std::to_string(born.size()) + " map tracks, " + std::to_string(added) +
             " observations added, back to frame " + std::to_string(reached));
  }
}

}  // namespace hawor
