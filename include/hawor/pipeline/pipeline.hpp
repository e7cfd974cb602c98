// hawor/pipeline/pipeline.hpp — the whole method on a stream of frames, in one place that every
// driver calls (the browser app and `node web/cli.mjs run` through the WebAssembly core, `hawor
// world` natively): the perception (or another regressor) gives hands per frame, this object
// holds the policy that turns them and the frames into world-space hands and a metric camera.
//
// Per frame (push):
//   1. Sides (sides.hpp): which detection is the left hand and which the right.
//   2. The fit (hand/fit.hpp) of each side's model to its 2D keypoints (and metric 3D keypoints
//      when the network gives them), warm-started from the previous frame; through a lens the
//      keypoints are undistorted to the virtual pinhole camera first. A fit is believed when its
//      wrist lies minHandDepth..maxHandDepth in front of the camera and its error is finite.
//      pushHands instead takes camera-frame hands from any regressor (HaMeR, WiLoR, HaWoR's own
//      network): no fit; pushJoints takes camera-frame 3D joints: the fit to them, kept at their
//      depth.
//   3. The believed hands' silhouettes at the SLAM's resolution (render/hand_masks.hpp), grown by
//      maskDilatePx: the SLAM's dual masking (docs/design.md §5).
//   4. The frame downscaled to grey at slamMaxSide (through a lens: rectified to the virtual
//      pinhole camera, whose unseen part joins the mask), and the SLAM (slam/mono_slam.hpp).
// finishCamera(): the SLAM's finishing passes; while its bundle adjustment moves the focal (and
// the frames were kept: focalRerunBytes), the SLAM runs again from the start with the refined
// focal (a map built with a wrong focal biases each pass's estimate toward its start), at most
// focalMaxPasses times; with a refined focal the hands are fitted again.
// finish(depth maps of the keyframes, optional): the metric scale from every cue available
// (scale/metric_scale.hpp: a depth network on the keyframes, the hands, the floor under the
// cameras), the camera and the map in metres, each hand's camera-frame motion taken to the world
// (motion/canonical.hpp), the unseen frames filled (motion/infill.hpp), and the keypoints of the
// world motion. The world is gravity-aligned (world_frame.hpp: z up, the origin on the floor
// below the first camera when the floor was found), or the first camera's (gravityAligned off).
// Not thread-safe; one object per video. The hand models must outlive it.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/camera_model.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/hand/fit.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/motion/infill.hpp"
#include "hawor/pipeline/hand_world.hpp"
#include "hawor/pipeline/keypoint_flow.hpp"
#include "hawor/pipeline/options.hpp"
#include "hawor/pipeline/result.hpp"
#include "hawor/pipeline/sides.hpp"
#include "hawor/pipeline/world_frame.hpp"
#include "hawor/render/hand_masks.hpp"
#include "hawor/render/rectify.hpp"
#include "hawor/render/resample.hpp"
#include "hawor/scale/metric_scale.hpp"
#include "hawor/slam/mono_slam.hpp"
#include "hawor/slam/slam_option_table.hpp"

namespace hawor {

/// The SLAM's frame size for a video: the long side at most maxSide, the aspect kept.
inline std::array<int, 2> pipelineSlamSize(int width, int height, int maxSide) {
  const double s = std::min(1.0, double(maxSide) / double(std::max(width, height)));
  return {std::max(16, static_cast<int>(std::lround(width * s))), std::max(16, static_cast<int>(std::lround(height * s)))};
}

template <typename Scalar>
class Pipeline {
 public:
  /// What push() reports about a frame: the SLAM's status and, per side, the detection it was
  /// given (-1: none) and whether its hand was believed.
  struct FrameInfo {
    SlamStatus slamStatus = SlamStatus::Lost;
    std::array<int, 2> detection{-1, -1};
    std::array<bool, 2> valid{false, false};
  };

  Pipeline(const PipelineOptions<Scalar>& options, const HandModel<Scalar>& left, const HandModel<Scalar>& right)
      : opt_(options), models_{&left, &right}, fitters_{HandFitter<Scalar>(left), HandFitter<Scalar>(right)}, flow_(options.flow) {
    opt_.validate();
    for (int s = 0; s < 2; ++s) {
      if (models_[s]->numKeypoints() != kKeypoints) {
        throw Error(std::string("pipeline: the ") + sideName(s) + " hand model gives " + std::to_string(models_[s]->numKeypoints()) +
                    " keypoints, not 21");
      }
    }
    const PinholeCamera<Scalar>& c = opt_.camera;
    lens_ = CameraModel<Scalar>{c, Lens<Scalar>::parse(opt_.lens)};
    lens_.validate();
    withLens_ = !lens_.lens.isPinhole();
    const std::array<int, 2> ss = pipelineSlamSize(c.width, c.height, opt_.slamMaxSide);
    const Scalar sx = Scalar(ss[0]) / Scalar(c.width), sy = Scalar(ss[1]) / Scalar(c.height);
    // The SLAM image's pixel u' covers source pixels u = (u' + 0.5) / s − 0.5.
    slamCam_.fx = c.fx * sx, slamCam_.fy = c.fy * sy;
    slamCam_.cx = (c.cx + Scalar(0.5)) * sx - Scalar(0.5), slamCam_.cy = (c.cy + Scalar(0.5)) * sy - Scalar(0.5);
    slamCam_.width = ss[0], slamCam_.height = ss[1];
    if (withLens_) rectify_ = std::make_unique<RectifyMap<Scalar>>(CameraModel<Scalar>{slamCam_, lens_.lens});
    slam_ = std::make_unique<MonoSlam<Scalar>>(slamCam_, slamOptions());
    keepSlam_ = opt_.refineFocal && opt_.focalRerunBytes > 0;
  }

  const PipelineOptions<Scalar>& options() const { return opt_; }
  const PinholeCamera<Scalar>& slamCamera() const { return slamCam_; }
  /// The options the SLAM runs with (its first pass; a further pass with a refined focal adds
  /// that focal as its prior).
  SlamOptions<Scalar> slamOptions() const { return slamOptions(Scalar(-1)); }
  int frames() const { return static_cast<int>(frames_.size()); }

  /// Called with what the SLAM is given on each frame, just before it runs: the frame at the
  /// SLAM's size (grey or rectified; the video's own RGB(A) where that is already the SLAM's
  /// size) and the hand mask (null on a frame without hands). For recording and inspecting the
  /// SLAM's inputs (examples/bench_real_slam.mjs replays them through `hawor slam`).
  using SlamInputObserver = std::function<void(const ImageU8& frame, const ImageU8* mask)>;
  void observeSlamInputs(SlamInputObserver observer) { slamInputObserver_ = std::move(observer); }

  /// The next frame's hands predicted from the last frame's by the keypoint flow
  /// (keypoint_flow.hpp), before the perception runs on it: those marked trusted may stand in
  /// for the landmark network (given back to push() with `flow` set). Call with the image that
  /// push() then gets; push() reuses its grey frame. Empty when the flow is off.
  const std::vector<KeypointPrediction<Scalar>>& predict(const ImageU8& image) {
    static const std::vector<KeypointPrediction<Scalar>> none;
    if (!flow_.enabled()) return none;
    checkFrame(image, true);
    const auto t0 = Clock::now();
    const int index = frames();
    const bool slamGrey = image.channels == 1 && image.width == slamCam_.width && image.height == slamCam_.height;
    if (!slamGrey) makeGrey(image, index);
    flow_.setFrame(slamGrey ? image : grey_, index, Scalar(slamCam_.width) / Scalar(opt_.camera.width));
    predictedFor_ = index;
    const auto& p = flow_.predict();
    addTime("flow", t0);
    return p;
  }

  /// A frame with the perception's detections. `image`: the video frame (the options' size; grey,
  /// RGB or RGBA) or its grey plane at the SLAM's size.
  FrameInfo push(const ImageU8& image, const std::vector<HandDetection<Scalar>>& detections) {
    FrameInfo info = observe(image, detections);
    info.slamStatus = trackFrame(image);
    return info;
  }

  /// push() in two steps, so that the perception of the next frame can run (elsewhere: a worker)
  /// while this one's SLAM does: pushDeferred() assigns the sides and fits the hands (what
  /// predict() on the next frame needs) and keeps the SLAM's input; trackPending() then runs the
  /// masks and the SLAM on it, before the next push. The result is push()'s exactly.
  FrameInfo pushDeferred(const ImageU8& image, const std::vector<HandDetection<Scalar>>& detections) {
    FrameInfo info = observe(image, detections);
    // the SLAM's input as trackFrame would make it: the grey frame at the SLAM's size (predict()'s
    // of the next frame overwrites grey_), or the frame itself at that size
    const bool atSlamSize = image.width == slamCam_.width && image.height == slamCam_.height;
    if (!atSlamSize || (withLens_ && image.channels != 1)) {
      if (greyFor_ != frames() - 1) makeGrey(image, frames() - 1);
      pending_ = grey_;
    } else {
      pending_ = image;
    }
    hasPending_ = true;
    return info;
  }

  /// The SLAM step of the frame pushDeferred() took (see there).
  SlamStatus trackPending() {
    if (!hasPending_) throw Error("pipeline: trackPending() without a frame from pushDeferred()");
    hasPending_ = false;
    return trackFrame(pending_);
  }

  /// A frame with camera-frame hands from another regressor (null: that side not seen); they are
  /// believed as a fit would be (in front of the camera, finite), and projected through the lens
  /// for keypoints2d.
  FrameInfo pushHands(const ImageU8& image, const std::array<const HandPose<Scalar>*, 2>& hands) {
    checkFrame(image);
    for (int s = 0; s < 2; ++s) {
      if (hands[s]) checkPose(*hands[s], s);
    }
    frames_.emplace_back();
    handsGiven_ = true;
    FrameInfo info;
    Observed& f = frames_.back();
    for (int s = 0; s < 2; ++s) {
      if (!hands[s]) continue;
      Side& o = f.side[s];
      const HandPose<Scalar>& p = *hands[s];
      o.detected = true;
      o.pose = p;
      o.keypoints = forward(*models_[s], p).keypoints;
      o.keypoints2d = Pixels<Scalar>::Constant(kKeypoints, 2, std::numeric_limits<Scalar>::quiet_NaN());
      for (int k = 0; k < kKeypoints; ++k) {
        const Vec3<Scalar> X = o.keypoints.row(k).transpose();
        if (X(2) > Scalar(0)) o.keypoints2d.row(k) = lens_.project(X).transpose();
      }
      o.reprojRmsPx = Scalar(0);
      o.fitted = believable(o);
      info.detection[s] = s;
      info.valid[s] = o.fitted;
    }
    info.slamStatus = trackFrame(image);
    return info;
  }

  /// A frame with camera-frame 3D hand joints from another regressor (21 × 3, metres, the
  /// MediaPipe / OpenPose order; null: that side not seen). The model is fitted to them (their
  /// projection through the lens as 2D keypoints, their shape as 3D keypoints), then moved so that
  /// its keypoints' centroid is theirs: the regressor's depth is kept, not re-estimated from the
  /// hand's size. A side with a joint less than 1 cm in front of the camera is not believed.
  FrameInfo pushJoints(const ImageU8& image, const std::array<const Points3<Scalar>*, 2>& joints) {
    checkFrame(image);
    for (int s = 0; s < 2; ++s) {
      if (joints[s] && (joints[s]->rows() != kKeypoints || joints[s]->cols() != 3 || !joints[s]->allFinite())) {
        throw Error("pipeline: frame " + std::to_string(frames_.size()) + ", the " + sideName(s) + " hand: joints must be 21 finite 3D points");
      }
    }
    frames_.emplace_back();
    handsGiven_ = true;
    FrameInfo info;
    const auto t0 = Clock::now();
    for (int s = 0; s < 2; ++s) {
      if (!joints[s]) {
        havePrevious_[s] = false;
        continue;
      }
      Side& o = frames_.back().side[s];
      const Points3<Scalar>& X = *joints[s];
      info.detection[s] = s;
      if (X.col(2).minCoeff() < Scalar(0.01)) {
        havePrevious_[s] = false;
        continue;
      }
      o.detected = true;
      o.keypoints2d.resize(kKeypoints, 2);
      for (int k = 0; k < kKeypoints; ++k) o.keypoints2d.row(k) = lens_.project(Vec3<Scalar>(X.row(k).transpose())).transpose();
      o.keypoints3d = X;
      if (!o.keypoints2d.allFinite() || !fitSide(s, o, opt_.camera, true)) continue;
      const Vec3<Scalar> shift = (X.colwise().mean() - o.keypoints.colwise().mean()).transpose();
      o.pose.trans += shift;
      o.keypoints.rowwise() += shift.transpose();
      previous_[s] = o.pose;
      o.fitted = believable(o);
      info.valid[s] = o.fitted;
    }
    addTime("fit", t0);
    info.slamStatus = trackFrame(image);
    return info;
  }

  /// The capture time (seconds) of the frame just pushed, for a source that drops frames (a live
  /// camera hands over the newest frame whenever the pipeline is ready): the result's times and
  /// the hand cues' frame rate (the frames' mean rate) then come from the stamps instead of the
  /// options' fps, which stays the camera's (the rolling shutter's). Every frame or none;
  /// increasing.
  void stampFrame(Scalar seconds) {
    const int f = frames() - 1;
    if (f < 0) throw Error("pipeline: stampFrame() before the first frame");
    if (!std::isfinite(double(seconds))) throw Error("pipeline: frame " + std::to_string(f) + "'s time is not finite");
    if (static_cast<int>(times_.size()) != f) {
      throw Error("pipeline: frame " + std::to_string(f) + " stamped but frame " + std::to_string(times_.size()) + " was not (stamp every frame or none)");
    }
    if (f > 0 && !(seconds > times_.back())) {
      throw Error("pipeline: frame " + std::to_string(f) + "'s time " + std::to_string(double(seconds)) + " s is not after frame " +
                  std::to_string(f - 1) + "'s " + std::to_string(double(times_.back())) + " s");
    }
    times_.push_back(seconds);
  }

  /// The frames' rate on the timeline: the stamps' mean rate when every frame was stamped, else
  /// the options' fps.
  Scalar timelineFps() const {
    const int T = frames();
    if (T >= 2 && static_cast<int>(times_.size()) == T) return Scalar(T - 1) / (times_.back() - times_.front());
    return opt_.fps;
  }

  /// The causal world (live mode): the metric scale and the gravity-aligned world from the cues
  /// of the frames so far (the tracker's poses and map, the fitted hands; no depth network), as
  /// finish() computes them from the refined ones. Until a cue gives a scale: the SLAM's units
  /// (method "none") in the first camera's frame. Costs a scale estimate: call every second or so.
  /// (pipeline/live.hpp)
  const LiveWorld<Scalar>& updateLiveWorld();

  /// The last pushed frame in the live world (updateLiveWorld's latest; causal estimates).
  LiveFrame<Scalar> live() const;

  /// The SLAM's finishing passes, the further passes with a refined focal, and the hands fitted
  /// again with it. Call once, after the last frame.
  const SlamResult<Scalar>& finishCamera() {
    if (cameraDone_) throw Error("pipeline: finishCamera() called twice");
    if (hasPending_) throw Error("pipeline: trackPending() must follow pushDeferred() before finishCamera()");
    if (frames_.empty()) throw Error("pipeline: the video has no frames");
    cameraDone_ = true;
    auto t0 = Clock::now();
    slam_result_ = slam_->finish();
    slam_.reset();
    addTime("slamFinish", t0);
    const FocalRefineResult<Scalar> first = slam_result_.focal;
    int passes = 1;
    t0 = Clock::now();
    const bool allKept = keepSlam_ && keptFrames_.size() == frames_.size();
    while (slam_result_.focal.changed && allKept && passes < opt_.focalMaxPasses) {
      PinholeCamera<Scalar> c = slamCam_;
      c.fx = slam_result_.camera.fx, c.fy = slam_result_.camera.fy;
      MonoSlam<Scalar> again(c, slamOptions(slamCam_.fx));
      for (std::size_t t = 0; t < keptFrames_.size(); ++t) again.process(keptFrames_[t], keptMasks_[t].data.empty() ? nullptr : &keptMasks_[t]);
      SlamResult<Scalar> r = again.finish();
      if (!r.initialised && slam_result_.initialised) break;  // keep the previous pass
      slam_result_ = std::move(r);
      ++passes;
    }
    std::vector<ImageU8>().swap(keptFrames_);
    std::vector<ImageU8>().swap(keptMasks_);
    const Scalar sx = Scalar(slamCam_.width) / Scalar(opt_.camera.width), sy = Scalar(slamCam_.height) / Scalar(opt_.camera.height);
    const FocalRefineResult<Scalar>& f = slam_result_.focal;
    PipelineFocal<Scalar>& out = focal_;
    out.passes = passes;
    out.fx = opt_.camera.fx, out.fy = opt_.camera.fy;
    bool changed = f.changed, accepted = f.accepted;
    Scalar stdLog = f.stdLog, estimate = f.estimateFx;
    std::string reason = f.reason;
    if (passes > 1) {
      addTime("slamRerun", t0);
      changed = accepted = true;
      stdLog = f.accepted ? f.stdLog : first.stdLog;
      estimate = f.estimateFx > Scalar(0) ? f.estimateFx : slam_result_.camera.fx;
      reason = first.reason + " (" + std::to_string(passes) + " SLAM passes)";
    }
    out.stdLog = accepted && std::isfinite(double(stdLog)) ? stdLog : std::numeric_limits<Scalar>::quiet_NaN();
    out.estimateFx = estimate > Scalar(0) ? estimate / sx : std::numeric_limits<Scalar>::quiet_NaN();
    out.reason = !opt_.refineFocal ? std::string("off") : reason;
    if (changed) {
      out.fx = slam_result_.camera.fx / sx;
      out.fy = slam_result_.camera.fy / sy;
      out.refined = true;
    }
    if (fitFailures_ > 0) warnings_.push_back("the hand fit failed on " + std::to_string(fitFailures_) + " detections (those frames count as unobserved)");
    if (!slam_result_.initialised) {
      warnings_.push_back(frames_.size() < 2 ? "a single frame: no camera motion can be estimated (identity pose)"
                                             : "the SLAM did not initialise (too little camera translation or texture): the camera is held at the first pose");
    }
    if (out.refined && !handsGiven_) refit();
    const int lost = slam_result_.count(SlamStatus::Lost);
    if (lost > 0) warnings_.push_back("the camera was lost on " + std::to_string(lost) + " of " + std::to_string(frames_.size()) + " frames (their poses are interpolated or held)");
    return slam_result_;
  }

  /// The frames of the SLAM's keyframes (after finishCamera): where a depth network runs.
  std::vector<int> keyframeFrames() const {
    std::vector<int> f;
    for (const auto& d : slam_result_.keyframeDepths) f.push_back(d.frame);
    return f;
  }

  /// The result. depthMaps: none, or one metric depth map per keyframe (keyframeFrames() order)
  /// at the SLAM's size (metres, non-finite unknown; through a lens, of the rectified frame).
  PipelineResult<Scalar> finish(const std::vector<const float*>& depthMaps = {}) {
    if (!cameraDone_) finishCamera();
    if (finished_) throw Error("pipeline: finish() called twice");
    finished_ = true;
    const int T = static_cast<int>(frames_.size());
    PipelineResult<Scalar> res;
    res.frames = T;
    res.fps = opt_.fps;
    const bool stamped = static_cast<int>(times_.size()) == T;
    if (!times_.empty() && !stamped) warnings_.push_back("only the first " + std::to_string(times_.size()) + " of " + std::to_string(T) + " frames had a time: the times are frame / fps");
    for (int t = 0; t < T; ++t) res.times.push_back(stamped ? times_[static_cast<std::size_t>(t)] - times_.front() : Scalar(t) / opt_.fps);
    res.camera = opt_.camera;
    res.camera.fx = focal_.fx, res.camera.fy = focal_.fy;
    res.lens = lens_.lens.toString();
    res.focal = focal_;
    res.slamCamera = slamCam_;
    for (int s = 0; s < 2; ++s) collectCameraFrame(s, res.hands[s]);
    res.noHands = !res.hands[0].present && !res.hands[1].present;
    if (res.noHands) warnings_.push_back("no hands were found in the video");
    auto t0 = Clock::now();
    metricScale(res, depthMaps);
    addTime("scale", t0);
    const Scalar s = res.scale;
    for (const SE3<Scalar>& P : slam_result_.poses) res.cameraPoses.emplace_back(P.rotation(), Vec3<Scalar>(s * P.translation()));
    for (const Vec3<Scalar>& X : slam_result_.points) res.points.push_back(s * X);
    if (opt_.gravityAligned) {
      // the output's world: z up, the origin on the floor below the first camera (world_frame.hpp)
      res.world = gravityAlignedWorld(res.cameraPoses, res.scaleCues.groundRan ? &res.scaleCues.ground : nullptr, s);
      for (SE3<Scalar>& P : res.cameraPoses) P = res.world.fromFirstCamera * P;
      for (Vec3<Scalar>& X : res.points) X = res.world.fromFirstCamera * X;
    }
    for (int side = 0; side < 2; ++side) handToWorld(*models_[side], res.cameraPoses, opt_.infill, res.hands[side], timings_);
    res.slam = std::move(slam_result_);
    res.warnings = warnings_;
    res.timings = timings_;
    return res;
  }

 private:
  using Clock = std::chrono::steady_clock;
  static constexpr int kKeypoints = 21;

  /// One side's observation in one frame.
  struct Side {
    bool detected = false, fitted = false;
    bool byFlow = false;          ///< the keypoints came from the keypoint flow, not the network
    Pixels<Scalar> keypoints2d;   ///< (21, 2) image pixels (through the lens)
    Points3<Scalar> keypoints3d;  ///< (21, 3) the network's metric keypoints, or empty
    HandPose<Scalar> pose;        ///< camera frame (when fitted)
    Points3<Scalar> keypoints;    ///< (21, 3) fitted keypoints, camera frame
    Scalar reprojRmsPx = std::numeric_limits<Scalar>::quiet_NaN();
  };
  struct Observed {
    std::array<Side, 2> side;
  };

  void addTime(const char* stage, Clock::time_point t0) {
    timings_[stage] += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  }

  Scalar reach() const { return Scalar(0.15) * std::hypot(Scalar(opt_.camera.width), Scalar(opt_.camera.height)); }

  SlamOptions<Scalar> slamOptions(Scalar priorFx) const {
    SlamOptions<Scalar> o;
    o.useMasks = true;
    o.finish.refineFocal = opt_.refineFocal;
    o.rollingShutter = opt_.readout * opt_.fps;
    o.fps = opt_.fps;
    if (opt_.liveSource) o.frameStep = 1;  // the source's own dropping thins the frames
    o.focal.priorSigmaLog = opt_.priorSigma();
    if (priorFx > Scalar(0)) {
      o.finish.refineFocal = true;
      o.focal.priorFx = priorFx;
    }
    if (!opt_.slamSet.empty()) setSlamOptions(o, opt_.slamSet);
    return o;
  }

  /// Throws for a frame that is neither the video's nor the SLAM's grey one (nothing is kept).
  void checkFrame(const ImageU8& image, bool allowPending = false) const {
    if (cameraDone_) throw Error("pipeline: push() after finish");
    if (hasPending_ && !allowPending) throw Error("pipeline: trackPending() must follow pushDeferred() before the next frame");
    const int T = static_cast<int>(frames_.size());
    if (!image.consistent() || image.width <= 0 || image.height <= 0) throw Error("pipeline: frame " + std::to_string(T) + " is empty");
    const bool video = image.width == opt_.camera.width && image.height == opt_.camera.height &&
                       (image.channels == 1 || image.channels == 3 || image.channels == 4);
    const bool slamGrey = image.width == slamCam_.width && image.height == slamCam_.height && image.channels == 1;
    if (!video && !slamGrey) {
      throw Error("pipeline: frame " + std::to_string(T) + " is " + std::to_string(image.width) + "x" + std::to_string(image.height) + "x" +
                  std::to_string(image.channels) + ", expected the video's " + std::to_string(opt_.camera.width) + "x" +
                  std::to_string(opt_.camera.height) + " (1, 3 or 4 channels) or the SLAM's grey " + std::to_string(slamCam_.width) + "x" +
                  std::to_string(slamCam_.height));
    }
  }

  void checkDetection(const HandDetection<Scalar>& d, std::size_t i) const {
    const std::string what = "pipeline: frame " + std::to_string(frames_.size()) + ", detection " + std::to_string(i);
    if (d.keypoints2d.rows() != kKeypoints) throw Error(what + ": " + std::to_string(d.keypoints2d.rows()) + " keypoints, expected 21");
    if (!d.keypoints2d.allFinite()) throw Error(what + ": keypoints are not finite");
    if (d.keypoints3d.size() > 0 && (d.keypoints3d.rows() != kKeypoints || !d.keypoints3d.allFinite())) {
      throw Error(what + ": keypoints3d must be 21 finite points or empty");
    }
    if (!(d.pRight >= Scalar(0) && d.pRight <= Scalar(1))) throw Error(what + ": pRight must be in [0, 1]");
  }

  void checkPose(const HandPose<Scalar>& p, int s) const {
    const std::string what = "pipeline: frame " + std::to_string(frames_.size()) + ", the " + sideName(s) + " hand";
    if (p.handPose.rows() != models_[s]->numJoints() - 1 || p.handPose.cols() != 3) {
      throw Error(what + ": " + std::to_string(p.handPose.rows()) + " joint rotations, the model has " + std::to_string(models_[s]->numJoints() - 1));
    }
    if (p.betas.size() > models_[s]->numBetas()) throw Error(what + ": " + std::to_string(p.betas.size()) + " betas, the model has " + std::to_string(models_[s]->numBetas()));
    if (!p.rot.allFinite() || !p.handPose.allFinite() || !p.betas.allFinite() || !p.trans.allFinite()) throw Error(what + ": parameters are not finite");
  }

  bool believable(const Side& o) const {
    const Scalar z = o.pose.trans(2);
    return z > opt_.minHandDepth && z < opt_.maxHandDepth && std::isfinite(double(o.reprojRmsPx));
  }

  /// The fit of side s to its keypoints with intrinsics K (through the lens: undistorted first).
  /// firstPass: a failed fit counts, and an implausible one keeps the warm start (as it was
  /// found); in the refit an implausible one breaks the track.
  bool fitSide(int s, Side& o, const PinholeCamera<Scalar>& K, bool firstPass) {
    HandObservation<Scalar> obs;
    obs.keypoints2d = o.keypoints2d;
    if (withLens_) {
      CameraModel<Scalar> c{K, lens_.lens};
      obs.confidence2d = VecX<Scalar>::Zero(kKeypoints);
      for (int k = 0; k < kKeypoints; ++k) {
        Vec2<Scalar> u;
        if (c.undistortPixel(Vec2<Scalar>(o.keypoints2d(k, 0), o.keypoints2d(k, 1)), u) && u.allFinite()) {
          obs.keypoints2d.row(k) = u.transpose();
          obs.confidence2d(k) = Scalar(1);
        } else {
          obs.keypoints2d.row(k).setZero();
        }
      }
    }
    if (o.keypoints3d.size() > 0) obs.keypoints3d = o.keypoints3d;
    HandFitResult<Scalar> r;
    try {
      r = fitters_[s].fit(obs, K, fitOptions_, havePrevious_[s] ? &previous_[s] : nullptr);
    } catch (const std::exception&) {
      havePrevious_[s] = false;
      if (firstPass) ++fitFailures_;
      return false;
    }
    previous_[s] = r.pose;
    havePrevious_[s] = true;
    o.pose = r.pose;
    o.keypoints = r.keypoints;
    o.reprojRmsPx = r.reprojRmsPx;
    const bool ok = believable(o);
    if (!ok && !firstPass) havePrevious_[s] = false;
    return ok;
  }

  /// grey_: frame `index`'s image downscaled to the SLAM's size in grey.
  void makeGrey(const ImageU8& image, int index) {
    grey_.resize(slamCam_.width, slamCam_.height, 1);
    downscaleBox(image.data.data(), image.width, image.height, image.channels, slamCam_.width, slamCam_.height, true, grey_.data.data());
    greyFor_ = index;
  }

  /// push() up to the SLAM: the sides, the fits, the keypoint flow's observation.
  FrameInfo observe(const ImageU8& image, const std::vector<HandDetection<Scalar>>& detections) {
    checkFrame(image);
    for (std::size_t i = 0; i < detections.size(); ++i) checkDetection(detections[i], i);
    if (predictedFor_ == frames()) flow_.observe(detections);
    frames_.emplace_back();
    const auto t0 = Clock::now();
    const std::array<int, 2> sides = assignSides(detections, sideState_, reach());
    updateSideState(sideState_, detections, sides);
    FrameInfo info;
    info.detection = sides;
    Observed& f = frames_.back();
    for (int s = 0; s < 2; ++s) {
      if (sides[s] < 0) {
        havePrevious_[s] = false;
        continue;
      }
      const HandDetection<Scalar>& d = detections[static_cast<std::size_t>(sides[s])];
      Side& o = f.side[s];
      o.detected = true;
      o.keypoints2d = d.keypoints2d;
      o.byFlow = d.flow;
      o.keypoints3d = d.keypoints3d;
      o.fitted = fitSide(s, o, opt_.camera, true);
      info.valid[s] = o.fitted;
    }
    addTime("fit", t0);
    return info;
  }

  /// The hand mask the SLAM gets on the current frame (empty: no hand; docs/design.md §5). Each
  /// hand fitted on this frame: its silhouette grown by maskDilatePx. One the keypoint flow
  /// carried: grown further by the flow's error, flow.maskGrowth × its size (fingers that moved
  /// since the network's last run stay masked). A hand fitted within the last maskHoldSeconds but
  /// not on this frame, and slow enough to be still under it (stillCovered): held at its last
  /// pose and grown the same way. A hand that vanishes was more often missed (compressed,
  /// blurred, low-resolution video) than gone, and the features on it, moving with it, would
  /// steer the camera.
  Mask handMask() const {
    const int T = frames();
    const int hold = static_cast<int>(std::lround(opt_.maskHoldSeconds * opt_.fps));
    const Scalar toSlam = Scalar(slamCam_.width) / Scalar(opt_.camera.width);
    Mask mask;
    for (int s = 0; s < 2; ++s) {
      int age = 0;
      while (age <= hold && age < T && !frames_[static_cast<std::size_t>(T - 1 - age)].side[s].fitted) ++age;
      if (age > hold || age >= T) continue;
      const Side& o = frames_[static_cast<std::size_t>(T - 1 - age)].side[s];
      if (age > 0 && !stillCovered(s, T - 1 - age, age)) continue;
      int grow = 0;
      if (o.byFlow || age > 0) grow = static_cast<int>(std::lround(opt_.flow.maskGrowth * keypointExtent(o.keypoints2d) * toSlam));
      HandMaskHand<Scalar> h;
      h.model = models_[s];
      h.pose = o.pose;
      Mask one;
      renderHandMasks(std::vector<HandMaskHand<Scalar>>{h}, slamCam_, std::min(64, opt_.maskDilatePx + grow), one);
      if (mask.data.empty()) {
        mask = std::move(one);
      } else {
        for (std::size_t i = 0; i < mask.data.size(); ++i) mask.data[i] = std::max(mask.data[i], one.data[i]);
      }
    }
    return mask;
  }

  /// Whether side s, last fitted on frame f, would still lie under its held silhouette `age`
  /// frames later: at its image speed before f (its keypoints' centre, from the fit before within
  /// 3 frames) it has moved less than half its size. A still hand missed by the perception stays
  /// masked for the whole hold; a moving one (or one seen once) is not held where it no longer is.
  bool stillCovered(int s, int f, int age) const {
    const Side& last = frames_[static_cast<std::size_t>(f)].side[s];
    for (int g = f - 1; g >= std::max(0, f - 3); --g) {
      const Side& before = frames_[static_cast<std::size_t>(g)].side[s];
      if (!before.fitted) continue;
      const Scalar speed = (keypointCentre(last.keypoints2d) - keypointCentre(before.keypoints2d)).norm() / Scalar(f - g);
      return std::isfinite(double(speed)) && Scalar(age) * speed <= Scalar(0.5) * keypointExtent(last.keypoints2d);
    }
    return false;
  }

  /// Masks, the SLAM's frame and the SLAM on the current frame.
  SlamStatus trackFrame(const ImageU8& image) {
    auto t0 = Clock::now();
    Mask mask = handMask();
    if (opt_.depthMasks) depthMasks_.push_back(mask);
    addTime("masks", t0);
    t0 = Clock::now();
    const bool atSlamSize = image.width == slamCam_.width && image.height == slamCam_.height;
    // At the SLAM's own size the SLAM converts to grey itself.
    const ImageU8* slamFrame = &image;
    if (!atSlamSize || (withLens_ && image.channels != 1)) {
      if (greyFor_ != frames() - 1) makeGrey(image, frames() - 1);  // else predict() made it already
      slamFrame = &grey_;
    }
    const ImageU8* slamMask = mask.data.empty() ? nullptr : &mask;
    if (rectify_) {
      rectified_ = rectify_->remapBilinear(*slamFrame);
      slamFrame = &rectified_;
      slamMask = nullptr;
      if (rectify_->needsSlamMask(mask.data.empty() ? nullptr : mask.data.data())) {
        rectMask_.resize(slamCam_.width, slamCam_.height, 1);
        rectify_->slamMask(mask.data.empty() ? nullptr : mask.data.data(), rectMask_.data.data());
        slamMask = &rectMask_;
      }
    }
    if (keepSlam_) keepForRerun(*slamFrame, slamMask);
    addTime("slamPrep", t0);
    if (slamInputObserver_) slamInputObserver_(*slamFrame, slamMask);
    t0 = Clock::now();
    const SlamStatus st = slam_->process(*slamFrame, slamMask);
    addTime("slam", t0);
    return st;
  }

  void keepForRerun(const ImageU8& frame, const ImageU8* mask) {
    const std::size_t n = static_cast<std::size_t>(slamCam_.width) * static_cast<std::size_t>(slamCam_.height);
    if (keptBytes_ + 2 * n > opt_.focalRerunBytes) {
      // too long a video for a second SLAM pass: the focal is refined in the final BA only
      keepSlam_ = false;
      std::vector<ImageU8>().swap(keptFrames_);
      std::vector<ImageU8>().swap(keptMasks_);
      return;
    }
    ImageU8 g;
    if (frame.channels == 1) {
      g = frame;
    } else {
      g.resize(frame.width, frame.height, 1);
      downscaleBox(frame.data.data(), frame.width, frame.height, frame.channels, frame.width, frame.height, true, g.data.data());
    }
    keptBytes_ += g.data.size() + (mask ? mask->data.size() : 0);
    keptFrames_.push_back(std::move(g));
    keptMasks_.push_back(mask ? *mask : ImageU8());
  }

  // ---- passes over the recorded frames (pipeline/finish_passes.hpp) ---------------------------

  /// The hands fitted again at the refined focal, frame by frame as the first time.
  void refit();
  /// Side s's camera-frame arrays (NaN where not observed).
  void collectCameraFrame(int s, PipelineHand<Scalar>& h) const;
  /// Each seen hand's camera-frame wrist over the frames so far (the hand cues' input).
  std::vector<HandTrack<Scalar>> wristTracks() const;
  /// The metric scale from the cues at hand; res.scale is 1 with method "none" when none gave one.
  void metricScale(PipelineResult<Scalar>& res, const std::vector<const float*>& depthMaps);

  PipelineOptions<Scalar> opt_;
  std::array<const HandModel<Scalar>*, 2> models_;
  std::array<HandFitter<Scalar>, 2> fitters_;
  HandFitOptions<Scalar> fitOptions_;
  std::array<HandPose<Scalar>, 2> previous_;
  std::array<bool, 2> havePrevious_{false, false};
  CameraModel<Scalar> lens_;
  bool withLens_ = false;
  PinholeCamera<Scalar> slamCam_;
  std::unique_ptr<RectifyMap<Scalar>> rectify_;
  std::unique_ptr<MonoSlam<Scalar>> slam_;
  SlamInputObserver slamInputObserver_;
  SlamResult<Scalar> slam_result_;
  SideState<Scalar> sideState_;
  std::vector<Observed> frames_;
  std::vector<Mask> depthMasks_;
  bool keepSlam_ = false;
  std::size_t keptBytes_ = 0;
  std::vector<ImageU8> keptFrames_, keptMasks_;
  ImageU8 grey_, rectified_, rectMask_;
  ImageU8 pending_;  ///< pushDeferred()'s SLAM input
  bool hasPending_ = false;
  int greyFor_ = -1, predictedFor_ = -1;  ///< the frame grey_ holds and the one predict() saw
  LiveWorld<Scalar> live_;
  std::vector<Scalar> times_;  ///< stampFrame's, per frame
  KeypointFlow<Scalar> flow_;
  int fitFailures_ = 0;
  bool handsGiven_ = false, cameraDone_ = false, finished_ = false;
  PipelineFocal<Scalar> focal_;
  std::vector<std::string> warnings_;
  std::map<std::string, double> timings_;
};

}  // namespace hawor

// Member functions in their own headers.
#include "hawor/pipeline/finish_passes.hpp"
#include "hawor/pipeline/live.hpp"
