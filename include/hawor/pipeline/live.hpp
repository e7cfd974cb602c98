// hawor/pipeline/live.hpp — Pipeline's live mode: the causal world from the frames so far and
// the last frame in it. Member functions of Pipeline (pipeline/pipeline.hpp: the class, its state
// and the overview); included at the end of that header.
#pragma once

#include "hawor/pipeline/pipeline.hpp"

namespace hawor {

/// The causal world (live mode): the metric scale and the gravity-aligned world from the cues
/// of the frames so far (the tracker's poses and map, the fitted hands; no depth network), as
/// finish() computes them from the refined ones. Until a cue gives a scale: the SLAM's units
/// (method "none") in the first camera's frame. Costs a scale estimate: call every second or so.
template <typename Scalar>
const LiveWorld<Scalar>& Pipeline<Scalar>::updateLiveWorld() {
  if (cameraDone_) throw Error("pipeline: updateLiveWorld() after finishCamera()");
  const auto t0 = Clock::now();
  LiveWorld<Scalar> w;
  w.frames = frames();
  std::vector<SE3<Scalar>> poses;
  for (int f = 0; f < slam_->numFrames(); ++f) poses.push_back(slam_->livePose(f));
  const std::vector<Vec3<Scalar>> points = opt_.groundScale ? slam_->liveMapPoints() : std::vector<Vec3<Scalar>>();
  const std::vector<HandTrack<Scalar>> wrists = wristTracks();
  if (poses.size() >= 2 && (!wrists.empty() || !points.empty())) {
    MetricScaleOptions<Scalar> mo;
    mo.setFps(timelineFps());
    mo.ground.eyeHeight = opt_.eyeHeight;
    try {
      const MetricScaleResult<Scalar> r = estimateMetricScale({}, poses, wrists, mo, &points);
      if (r.fused.ok() && std::isfinite(double(r.fused.scale)) && r.fused.scale > Scalar(0)) {
        w.scale = r.fused.scale;
        w.scaleMethod = r.fused.method;
        w.scaleConfidence = r.fused.confidence;
        if (opt_.gravityAligned) {
          std::vector<SE3<Scalar>> metric;
          for (const SE3<Scalar>& P : poses) metric.emplace_back(P.rotation(), Vec3<Scalar>(w.scale * P.translation()));
          w.world = gravityAlignedWorld(metric, r.groundRan ? &r.ground : nullptr, w.scale);
        }
      }
    } catch (const std::exception&) {
      // too little of the clip yet (a cue's own checks): stay in the SLAM's units
    }
  }
  live_ = std::move(w);
  addTime("liveWorld", t0);
  return live_;
}

/// The last pushed frame in the live world (updateLiveWorld's latest; causal estimates).
template <typename Scalar>
LiveFrame<Scalar> Pipeline<Scalar>::live() const {
  LiveFrame<Scalar> l;
  const int f = frames() - 1;
  if (f < 0 || slam_->numFrames() != frames()) return l;
  l.frame = f;
  l.posed = slam_->livePosed(f);
  l.scale = live_.scale;
  const SE3<Scalar> P = slam_->livePose(f);
  l.cameraPose = live_.world.fromFirstCamera * SE3<Scalar>(P.rotation(), Vec3<Scalar>(live_.scale * P.translation()));
  for (int s = 0; s < 2; ++s) {
    const Side& o = frames_.back().side[s];
    l.valid[s] = o.fitted;
    if (!o.fitted) continue;
    l.joints[s].resize(kKeypoints, 3);
    for (int k = 0; k < kKeypoints; ++k) l.joints[s].row(k) = (l.cameraPose * Vec3<Scalar>(o.keypoints.row(k).transpose())).transpose();
  }
  return l;
}

}  // namespace hawor
