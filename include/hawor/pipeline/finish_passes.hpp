// hawor/pipeline/finish_passes.hpp — Pipeline's passes over the recorded frames: the hands fitted
// again at the refined focal, each side's camera-frame arrays, the wrist tracks the hand cues read,
// and the metric scale from the cues at hand. Member functions of Pipeline (pipeline/pipeline.hpp:
// the class, its state and the overview); included at the end of that header.
#pragma once

#include "hawor/pipeline/pipeline.hpp"

namespace hawor {

/// The hands fitted again at the refined focal, frame by frame as the first time.
template <typename Scalar>
void Pipeline<Scalar>::refit() {
  const auto t0 = Clock::now();
  PinholeCamera<Scalar> K = opt_.camera;
  K.fx = focal_.fx, K.fy = focal_.fy;
  for (int s = 0; s < 2; ++s) {
    havePrevious_[s] = false;
    bool prevOk = false;
    for (Observed& f : frames_) {
      Side& o = f.side[s];
      if (!o.detected) {
        if (prevOk) havePrevious_[s] = false;
        prevOk = false;
        continue;
      }
      o.fitted = fitSide(s, o, K, false);
      prevOk = o.fitted;
    }
  }
  addTime("refit", t0);
}

/// Side s's camera-frame arrays (NaN where not observed).
template <typename Scalar>
void Pipeline<Scalar>::collectCameraFrame(int s, PipelineHand<Scalar>& h) const {
  const Eigen::Index T = static_cast<Eigen::Index>(frames_.size());
  const Eigen::Index P = 3 * (models_[s]->numJoints() - 1), B = models_[s]->numBetas();
  const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
  h.valid.assign(static_cast<std::size_t>(T), 0);
  h.camera.rot = Sequence<Scalar>::Constant(T, 3, nan);
  h.camera.trans = Sequence<Scalar>::Constant(T, 3, nan);
  h.camera.handPose = Sequence<Scalar>::Constant(T, P, nan);
  h.camera.betas = Sequence<Scalar>::Constant(T, B, nan);
  h.jointsCam = Sequence<Scalar>::Constant(T, 3 * kKeypoints, nan);
  h.keypoints2d = Sequence<Scalar>::Constant(T, 2 * kKeypoints, nan);
  h.reprojRmsPx.assign(static_cast<std::size_t>(T), nan);
  for (Eigen::Index t = 0; t < T; ++t) {
    const Side& o = frames_[static_cast<std::size_t>(t)].side[s];
    if (o.detected) h.keypoints2d.row(t) = Eigen::Map<const Eigen::Matrix<Scalar, 1, 2 * kKeypoints>>(o.keypoints2d.data());
    if (!o.fitted) continue;
    h.valid[static_cast<std::size_t>(t)] = 1;
    h.camera.rot.row(t) = o.pose.rot.transpose();
    h.camera.trans.row(t) = o.pose.trans.transpose();
    h.camera.handPose.row(t) = Eigen::Map<const Eigen::Matrix<Scalar, 1, Eigen::Dynamic>>(o.pose.handPose.data(), P);
    const Eigen::Index nb = std::min<Eigen::Index>(B, o.pose.betas.size());
    if (nb > 0) h.camera.betas.row(t).head(nb) = o.pose.betas.head(nb).transpose();
    h.jointsCam.row(t) = Eigen::Map<const Eigen::Matrix<Scalar, 1, 3 * kKeypoints>>(o.keypoints.data());
    h.reprojRmsPx[static_cast<std::size_t>(t)] = o.reprojRmsPx;
  }
  h.camera.valid = h.valid;
  h.present = std::any_of(h.valid.begin(), h.valid.end(), [](std::uint8_t v) { return v != 0; });
}

/// Each seen hand's camera-frame wrist over the frames so far (the hand cues' input).
template <typename Scalar>
std::vector<HandTrack<Scalar>> Pipeline<Scalar>::wristTracks() const {
  std::vector<HandTrack<Scalar>> wrists;
  for (int s = 0; s < 2; ++s) {
    HandTrack<Scalar> track;
    bool any = false;
    for (const Observed& f : frames_) {
      const Side& o = f.side[s];
      track.positionCam.push_back(o.fitted ? Vec3<Scalar>(o.keypoints.row(0).transpose()) : Vec3<Scalar>(0, 0, 1));
      track.valid.push_back(o.fitted ? 1 : 0);
      any = any || o.fitted;
    }
    if (!any) continue;
    if (opt_.handScaleSmooth > 0) smoothHandTrack(track, opt_.handScaleSmooth);
    wrists.push_back(std::move(track));
  }
  return wrists;
}

/// The metric scale from the cues at hand; res.scale is 1 with method "none" when none gave one.
template <typename Scalar>
void Pipeline<Scalar>::metricScale(PipelineResult<Scalar>& res, const std::vector<const float*>& depthMaps) {
  const std::vector<HandTrack<Scalar>> wrists = wristTracks();
  std::vector<KeyframeDepthPairs<Scalar>> keyframes;
  if (!depthMaps.empty()) {
    const auto& kd = slam_result_.keyframeDepths;
    if (depthMaps.size() != kd.size()) {
      throw Error("pipeline: " + std::to_string(depthMaps.size()) + " depth maps for " + std::to_string(kd.size()) + " keyframes");
    }
    for (std::size_t k = 0; k < kd.size(); ++k) {
      std::vector<Scalar> uv;
      for (const auto& p : kd[k].uv) uv.insert(uv.end(), {p(0), p(1)});
      const Mask* m = opt_.depthMasks ? &depthMasks_[static_cast<std::size_t>(kd[k].frame)] : nullptr;
      keyframes.push_back(pairKeyframeDepths(uv.data(), kd[k].depth.data(), kd[k].depth.size(), depthMaps[k], slamCam_.width, slamCam_.height,
                                             m && !m->data.empty() ? m->data.data() : nullptr));
    }
  }
  const bool havePoints = opt_.groundScale && !slam_result_.points.empty();
  bool got = false;
  if (slam_result_.initialised && (!wrists.empty() || !keyframes.empty() || havePoints)) {
    MetricScaleOptions<Scalar> mo;
    mo.setFps(timelineFps());
    mo.ground.eyeHeight = opt_.eyeHeight;
    const std::vector<Vec3<Scalar>> none;
    try {
      res.scaleCues = estimateMetricScale(keyframes, slam_result_.poses, wrists, mo, havePoints ? &slam_result_.points : &none);
      got = res.scaleCues.fused.ok();
    } catch (const std::exception& e) {
      warnings_.push_back(std::string("metric scale: ") + e.what());
    }
  }
  if (got && std::isfinite(double(res.scaleCues.fused.scale)) && res.scaleCues.fused.scale > Scalar(0)) {
    res.scale = res.scaleCues.fused.scale;
    res.scaleMethod = res.scaleCues.fused.method;
    res.scaleConfidence = res.scaleCues.fused.confidence;
    for (const FusedScale<Scalar>* f : {&res.scaleCues.noDepth, &res.scaleCues.fused}) {
      for (const std::string& c : f->leftOut) warnings_.push_back("metric scale: the " + c + " cue disagreed with the more confident one beyond both their errors and was left out");
    }
    if (res.scaleConfidence < Scalar(0.4)) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "the metric scale is uncertain (method %s, confidence %.2f)", res.scaleMethod.c_str(), double(res.scaleConfidence));
      warnings_.push_back(buf);
    }
  } else {
    // No metric cue: the SLAM's own units, flagged (the trajectory's shape is still right).
    res.scale = Scalar(1);
    res.scaleMethod = "none";
    res.scaleConfidence = Scalar(0);
    if (slam_result_.initialised) {
      warnings_.push_back("no metric scale could be estimated (no depth model, no usable hand cue, no floor in the map): the camera trajectory is in the SLAM's arbitrary units");
    }
  }
}

}  // namespace hawor
