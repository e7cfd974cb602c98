// hawor_core's Pipeline (pipeline/pipeline.hpp): the method's policy, fed frame by frame from
// JavaScript (web/src/pipeline/run.mjs), as `hawor world` feeds it natively.
//
//   new Pipeline(options, leftModel: HandModel, rightModel: HandModel), options {
//       intrinsics [fx, fy, cx, cy] (the video's), width, height, lens?, fps?, liveSource?, readout?,
//       slamMaxSide?, maskDilatePx?, maskHoldSeconds?, refineFocal?, focalPriorSigma?, userFocal?, focalMaxPasses?,
//       focalRerunBytes?, set? (SlamOptions "NAME=VALUE,..."), infill? ('spline'|'lerp'|'last'),
//       handScaleSmooth?, groundScale?, eyeHeight?, depthMasks?, gravityAligned?,
//       flow?: {maxSkip, maxCorners, minInliers, minInlierRatio, inlierShare, reach, goodError,
//       badError, pyramidLevels, maskGrowth} (any subset) }   (pipeline/options.hpp, keypoint_flow.hpp)
//     .slamSize() -> {width, height, intrinsics: [fx, fy, cx, cy]} (the SLAM's virtual camera)
//     .slamOptions() -> {useMasks, refineFocal, focalPriorSigma, rollingShutter, set?} the SLAM's,
//           as new MonoSlam takes them
//     .observeSlamInputs(fn | null) fn(frame: Uint8Array, width, height, channels, mask:
//           Uint8Array | null) with what the SLAM is given on each frame (copies; must not throw)
//     .predict(frame) -> [{track, keypoints2d (42), keypoints3d (63) | null, pRight, inliers,
//           trusted}] the last frame's hands carried to this one (pipeline/keypoint_flow.hpp;
//           [] with the flow off); call before push() with the same frame
//     .push(frame: Uint8Array (width*height*c, c = 1, 3, 4; or the SLAM's grey frame),
//           detections: [{keypoints2d (42), keypoints3d (63) | null, pRight, track (-1: none),
//           flow (a prediction standing in for the network)}])
//       -> {slamStatus, detection: Int32Array(2) (index per side, -1 none), valid: Uint8Array(2)}
//     .pushDeferred(frame, detections) -> push()'s, slamStatus null: the SLAM step waits for
//       .trackPending() -> {slamStatus}, which must come before the next frame (between them
//       predict() may run on the next frame: its perception can overlap this frame's SLAM)
//     .pushHands(frame, {left: pose | null, right: pose | null}) -> the same (camera-frame hands
//       from another regressor; pose objects as HandModel.forward takes)
//     .pushJoints(frame, {left: joints (63) | null, right: ...}) -> the same (camera-frame 3D
//       joints from another regressor, metres, 21 in MediaPipe order; the model fitted to them)
//     .stampFrame(seconds) the capture time of the frame just pushed (a source that drops
//       frames: the result's timestamps and the hand cues' rate come from the stamps)
//     .updateLiveWorld() -> {frames, scale, scaleMethod, scaleConfidence, up, upConfidence, origin}
//       the causal world from the frames so far (live mode; every second or so)
//     .live() -> {frame, posed, scale, cameraRotation (9, row-major), cameraPosition (3),
//       valid: Uint8Array(2), joints: {left: Float64Array(63) | null, right}} the last frame in
//       that world (camera to world; the fitted keypoints)
//     .finishCamera() -> {keyframeFrames: Int32Array, initialised}
//     .finish(depthMaps: [Float32Array (SLAM width*height)] | null) -> the result (run.mjs's
//       header: intrinsics' focal fields, slam, world, camera, points, scale, hands, noHands, warnings,
//       timings).
//   new SideAssigner(reach px).assign(detections) -> Int32Array(2) (detection per side, -1 none):
//       the side policy alone, frame by frame (web/tools/eval_kitchen_hands.mjs).
// The models must outlive the pipeline (delete the pipeline first).
// Included at the end of bindings.cpp: one translation unit, so that the SLAM, the fit and the
// scale are compiled once (a second unit doubled the core's compile time).
#pragma once

#include <emscripten/bind.h>
#include <emscripten/val.h>

#include <memory>
#include <string>
#include <vector>

#include "hawor/pipeline/pipeline.hpp"
#include "marshal.hpp"

using emscripten::val;
using namespace hawor_wasm;

namespace {

using Result = hawor::PipelineResult<double>;

hawor::ImageU8 frameFrom(const val& frame, const hawor::Pipeline<double>& p) {
  if (absent(frame)) throw hawor::Error("frame: missing");
  hawor::ImageU8 im;
  im.data = fromTyped<uint8_t>(frame);
  const hawor::PinholeCamera<double>& v = p.options().camera;
  const hawor::PinholeCamera<double>& s = p.slamCamera();
  const size_t nv = static_cast<size_t>(v.width) * static_cast<size_t>(v.height);
  const size_t c = im.data.size() / nv;
  if (im.data.size() == c * nv && (c == 1 || c == 3 || c == 4)) {
    im.width = v.width, im.height = v.height, im.channels = static_cast<int>(c);
  } else if (im.data.size() == static_cast<size_t>(s.width) * static_cast<size_t>(s.height)) {
    im.width = s.width, im.height = s.height, im.channels = 1;
  } else {
    throw hawor::Error("frame: " + std::to_string(im.data.size()) + " bytes, expected " + std::to_string(v.width) + "x" +
                       std::to_string(v.height) + "x(1, 3 or 4) or the SLAM's grey " + std::to_string(s.width) + "x" + std::to_string(s.height));
  }
  return im;
}

/// Detections [{keypoints2d (42), keypoints3d (63) | null, pRight, track}] from JavaScript.
std::vector<hawor::HandDetection<double>> detectionsFrom(const val& detections) {
  std::vector<hawor::HandDetection<double>> dets;
  const int n = absent(detections) ? 0 : detections["length"].as<int>();
  for (int i = 0; i < n; ++i) {
    const val d = detections[i];
    const std::string what = "detections[" + std::to_string(i) + "]";
    hawor::HandDetection<double> h;
    const std::vector<double> k2 = exactly(d["keypoints2d"], 42, what + ".keypoints2d");
    h.keypoints2d = Eigen::Map<const hawor::Pixels<double>>(k2.data(), 21, 2);
    if (!absent(d["keypoints3d"])) {
      const std::vector<double> k3 = exactly(d["keypoints3d"], 63, what + ".keypoints3d");
      h.keypoints3d = Eigen::Map<const hawor::Points3<double>>(k3.data(), 21, 3);
    }
    if (!absent(d["pRight"])) h.pRight = d["pRight"].as<double>();
    if (!absent(d["track"])) h.track = d["track"].as<int>();
    if (!absent(d["flow"])) h.flow = d["flow"].as<bool>();
    dets.push_back(std::move(h));
  }
  return dets;
}

val seqToJs(const hawor::Sequence<double>& s) { return f64(s.data(), static_cast<size_t>(s.size())); }

val handToJs(const hawor::PipelineHand<double>& h, const hawor::HandModel<double>& model) {
  val o = val::object();
  o.set("valid", toTyped(h.valid.data(), h.valid.size(), "Uint8Array"));
  o.set("present", h.present);
  o.set("camRot", seqToJs(h.camera.rot));
  o.set("camTrans", seqToJs(h.camera.trans));
  o.set("jointsCam", seqToJs(h.jointsCam));
  o.set("keypoints2d", seqToJs(h.keypoints2d));
  o.set("reprojRmsPx", f64(h.reprojRmsPx.data(), h.reprojRmsPx.size()));
  o.set("handPoseCols", 3 * (model.numJoints() - 1));
  o.set("betaCols", model.numBetas());
  o.set("infilled", toTyped(h.infilled.data(), h.infilled.size(), "Uint8Array"));
  o.set("trans", seqToJs(h.world.trans));
  o.set("rot", seqToJs(h.world.rot));
  o.set("handPose", seqToJs(h.world.handPose));
  o.set("betas", seqToJs(h.world.betas));
  o.set("jointsWorld", seqToJs(h.jointsWorld));
  return o;
}

val resultToJs(const Result& r, const hawor::PipelineOptions<double>& opt, const HandModel& left, const HandModel& right) {
  const size_t T = static_cast<size_t>(r.frames);
  val o = val::object();
  val in = val::object();  // the focal's part of the result's intrinsics (run.mjs adds the rest)
  in.set("fx", r.camera.fx);
  in.set("fy", r.camera.fy);
  in.set("refined", r.focal.refined);
  in.set("focalPasses", r.focal.passes);
  in.set("focalStd", std::isfinite(r.focal.stdLog) ? val(r.focal.stdLog) : val::null());
  in.set("focalEstimateFx", std::isfinite(r.focal.estimateFx) ? val(r.focal.estimateFx) : val::null());
  in.set("focalReason", r.focal.reason);
  o.set("intrinsics", in);
  const hawor::SlamResult<double>& s = r.slam;
  val sl = val::object();
  sl.set("width", r.slamCamera.width);
  sl.set("height", r.slamCamera.height);
  sl.set("numKeyframes", s.numKeyframes);
  sl.set("numLosses", s.numLosses);
  sl.set("numResets", s.numResets);
  sl.set("numRelocalisations", s.numRelocalisations);
  sl.set("numPlaceRelocalisations", s.numPlaceRelocalisations);
  sl.set("numRevisitPoints", s.numRevisitPoints);
  sl.set("numPlaceLinks", s.numPlaceLinks);
  sl.set("numPlacedSegments", s.numPlacedSegments);
  sl.set("numRefinedFrames", s.numRefinedFrames);
  sl.set("numHeadModelFrames", s.numHeadModelFrames);
  sl.set("initialised", s.initialised);
  o.set("slam", sl);
  val wo = val::object();  // the output's world (pipeline/world_frame.hpp)
  wo.set("convention", opt.gravityAligned ? std::string("z-up") : std::string("first-camera"));
  wo.set("up", r.world.up);
  wo.set("upConfidence", r.world.upConfidence);
  wo.set("origin", r.world.originOnFloor ? std::string("floor") : std::string("first-camera"));
  wo.set("upFirstCamera", f64(r.world.upFirstCamera.data(), 3));
  o.set("world", wo);
  std::vector<double> pos(3 * T), quat(4 * T), stamps(T);
  std::vector<uint8_t> status(T);
  for (size_t t = 0; t < T; ++t) {
    const hawor::SE3<double>& P = r.cameraPoses[t];
    for (int a = 0; a < 3; ++a) pos[3 * t + a] = P.translation()(a);
    const Eigen::Quaterniond q = hawor::matrixToQuaternion(Eigen::Matrix3d(P.rotationMatrix()));
    quat[4 * t] = q.x(), quat[4 * t + 1] = q.y(), quat[4 * t + 2] = q.z(), quat[4 * t + 3] = q.w();
    stamps[t] = r.times[t];
    status[t] = static_cast<uint8_t>(s.status[t]);
  }
  val cam = val::object();
  cam.set("positions", f64(pos.data(), pos.size()));
  cam.set("quaternions", f64(quat.data(), quat.size()));
  cam.set("status", toTyped(status.data(), T, "Uint8Array"));
  cam.set("timestamps", f64(stamps.data(), T));
  o.set("camera", cam);
  std::vector<double> pts;
  for (const auto& X : r.points) pts.insert(pts.end(), {X(0), X(1), X(2)});
  o.set("points", f64(pts.data(), pts.size()));
  val sc = scaleToJs(r.scaleCues, opt.eyeHeight);
  sc.set("scale", r.scale);
  sc.set("method", r.scaleMethod);
  sc.set("confidence", r.scaleConfidence);
  o.set("scale", sc);
  val hands = val::object();
  hands.set("left", handToJs(r.hands[0], left.m()));
  hands.set("right", handToJs(r.hands[1], right.m()));
  o.set("hands", hands);
  o.set("noHands", r.noHands);
  val w = val::array();
  for (const std::string& m : r.warnings) w.call<void>("push", m);
  o.set("warnings", w);
  val tm = val::object();
  for (const auto& kv : r.timings) tm.set(kv.first, kv.second);
  o.set("timings", tm);
  return o;
}

hawor::PipelineOptions<double> optionsFrom(const val& o) {
  if (absent(o)) throw hawor::Error("options: missing");
  hawor::PipelineOptions<double> p;
  p.camera = camera(o["intrinsics"], absent(o["width"]) ? 0 : o["width"].as<int>(), absent(o["height"]) ? 0 : o["height"].as<int>());
  auto num = [&](const char* k, double& v) {
    if (!absent(o[k])) v = o[k].as<double>();
  };
  auto integer = [&](const char* k, int& v) {
    if (!absent(o[k])) v = o[k].as<int>();
  };
  auto flag = [&](const char* k, bool& v) {
    if (!absent(o[k])) v = o[k].as<bool>();
  };
  if (!absent(o["lens"])) p.lens = o["lens"].as<std::string>();
  num("fps", p.fps);
  flag("liveSource", p.liveSource);
  num("readout", p.readout);
  integer("slamMaxSide", p.slamMaxSide);
  integer("maskDilatePx", p.maskDilatePx);
  num("maskHoldSeconds", p.maskHoldSeconds);
  flag("refineFocal", p.refineFocal);
  num("focalPriorSigma", p.focalPriorSigma);
  flag("userFocal", p.userFocal);
  integer("focalMaxPasses", p.focalMaxPasses);
  if (!absent(o["focalRerunBytes"])) {
    const double b = o["focalRerunBytes"].as<double>();
    if (!(b >= 0)) throw hawor::Error("focalRerunBytes must be >= 0");
    p.focalRerunBytes = static_cast<size_t>(b);
  }
  if (!absent(o["set"])) p.slamSet = o["set"].as<std::string>();
  if (!absent(o["infill"])) p.infill = hawor::parseInfillMethod(o["infill"].as<std::string>());
  integer("handScaleSmooth", p.handScaleSmooth);
  flag("groundScale", p.groundScale);
  num("eyeHeight", p.eyeHeight);
  flag("depthMasks", p.depthMasks);
  flag("gravityAligned", p.gravityAligned);
  if (!absent(o["flow"])) {  // KeypointFlowOptions, any subset
    const val f = o["flow"];
    auto fi = [&](const char* k, int& v) { if (!absent(f[k])) v = f[k].as<int>(); };
    auto fd = [&](const char* k, double& v) { if (!absent(f[k])) v = f[k].as<double>(); };
    fi("maxSkip", p.flow.maxSkip);
    fi("maxCorners", p.flow.maxCorners);
    fi("minInliers", p.flow.minInliers);
    fd("minInlierRatio", p.flow.minInlierRatio);
    fd("inlierShare", p.flow.inlierShare);
    fd("reach", p.flow.reach);
    fd("goodError", p.flow.goodError);
    fd("badError", p.flow.badError);
    fi("pyramidLevels", p.flow.pyramidLevels);
    fd("maskGrowth", p.flow.maskGrowth);
  }
  return p;
}

class Pipeline {
 public:
  Pipeline(const hawor::PipelineOptions<double>& o, const HandModel* left, const HandModel* right)
      : left_(left), right_(right), p_(o, left->m(), right->m()) {}

  val slamSize() const {
    const hawor::PinholeCamera<double>& s = p_.slamCamera();
    val o = val::object();
    o.set("width", s.width);
    o.set("height", s.height);
    const double k[4] = {s.fx, s.fy, s.cx, s.cy};
    o.set("intrinsics", f64(k, 4));
    return o;
  }

  val predict(const val& frame) {
    return guard("Pipeline.predict", [&] {
      const hawor::ImageU8 im = frameFrom(frame, p_);
      val out = val::array();
      for (const hawor::KeypointPrediction<double>& q : p_.predict(im)) {
        val o = val::object();
        o.set("track", q.track);
        o.set("keypoints2d", f64(q.keypoints2d.data(), 42));
        o.set("keypoints3d", q.keypoints3d.rows() == 21 ? f64(q.keypoints3d.data(), 63) : val::null());
        o.set("pRight", q.pRight);
        o.set("inliers", q.inliers);
        o.set("trusted", q.trusted);
        out.call<void>("push", o);
      }
      return out;
    });
  }

  // the SLAM's options as MonoSlam's constructor takes them (its first pass)
  val slamOptions() const {
    const hawor::SlamOptions<double> s = p_.slamOptions();
    val o = val::object();
    o.set("useMasks", s.useMasks);
    o.set("refineFocal", s.finish.refineFocal);
    o.set("focalPriorSigma", s.focal.priorSigmaLog);
    o.set("rollingShutter", s.rollingShutter);
    if (!p_.options().slamSet.empty()) o.set("set", p_.options().slamSet);
    return o;
  }

  // observer(frame: Uint8Array, width, height, channels, mask: Uint8Array | null) with what the
  // SLAM is given on each frame (copies); null stops it.
  void observeSlamInputs(const val& observer) {
    if (absent(observer)) {
      p_.observeSlamInputs(nullptr);
      return;
    }
    if (observer.typeOf().as<std::string>() != "function") throw hawor::Error("Pipeline.observeSlamInputs: a function or null");
    p_.observeSlamInputs([observer](const hawor::ImageU8& f, const hawor::ImageU8* m) {
      observer(toTyped(f.data.data(), f.data.size(), "Uint8Array"), f.width, f.height, f.channels,
               m ? toTyped(m->data.data(), m->data.size(), "Uint8Array") : val::null());
    });
  }

  val push(const val& frame, const val& detections) {
    return guard("Pipeline.push", [&] {
      const hawor::ImageU8 im = frameFrom(frame, p_);
      const std::vector<hawor::HandDetection<double>> dets = detectionsFrom(detections);
      return info(p_.push(im, dets));
    });
  }

  val pushDeferred(const val& frame, const val& detections) {
    return guard("Pipeline.pushDeferred", [&] {
      const hawor::ImageU8 im = frameFrom(frame, p_);
      val o = info(p_.pushDeferred(im, detectionsFrom(detections)));
      o.set("slamStatus", val::null());  // trackPending()'s
      return o;
    });
  }

  val trackPending() {
    return guard("Pipeline.trackPending", [&] {
      val o = val::object();
      o.set("slamStatus", static_cast<int>(p_.trackPending()));
      return o;
    });
  }

  val pushHands(const val& frame, const val& hands) {
    return guard("Pipeline.pushHands", [&] {
      const hawor::ImageU8 im = frameFrom(frame, p_);
      hawor::HandPose<double> pose[2];
      std::array<const hawor::HandPose<double>*, 2> given{nullptr, nullptr};
      const char* names[2] = {"left", "right"};
      for (int s = 0; s < 2; ++s) {
        if (absent(hands) || absent(hands[names[s]])) continue;
        pose[s] = poseFrom(hands[names[s]], (s == 0 ? left_ : right_)->m(), std::string("hands.") + names[s]);
        given[s] = &pose[s];
      }
      return info(p_.pushHands(im, given));
    });
  }

  val pushJoints(const val& frame, const val& joints) {
    return guard("Pipeline.pushJoints", [&] {
      const hawor::ImageU8 im = frameFrom(frame, p_);
      hawor::Points3<double> X[2];
      std::array<const hawor::Points3<double>*, 2> given{nullptr, nullptr};
      const char* names[2] = {"left", "right"};
      for (int s = 0; s < 2; ++s) {
        if (absent(joints) || absent(joints[names[s]])) continue;
        const std::vector<double> v = exactly(joints[names[s]], 63, std::string("joints.") + names[s]);
        X[s] = Eigen::Map<const hawor::Points3<double>>(v.data(), 21, 3);
        given[s] = &X[s];
      }
      return info(p_.pushJoints(im, given));
    });
  }

  void stampFrame(double seconds) {
    guard("Pipeline.stampFrame", [&] { p_.stampFrame(seconds); return 0; });
  }

  val updateLiveWorld() {
    return guard("Pipeline.updateLiveWorld", [&] {
      const hawor::LiveWorld<double>& w = p_.updateLiveWorld();
      val o = val::object();
      o.set("frames", w.frames);
      o.set("scale", w.scale);
      o.set("scaleMethod", w.scaleMethod);
      o.set("scaleConfidence", w.scaleConfidence);
      o.set("up", w.world.up);
      o.set("upConfidence", w.world.upConfidence);
      o.set("origin", w.world.originOnFloor ? std::string("floor") : std::string("first-camera"));
      return o;
    });
  }

  val live() const {
    return guard("Pipeline.live", [&] {
      const hawor::LiveFrame<double> l = p_.live();
      val o = val::object();
      o.set("frame", l.frame);
      o.set("posed", l.posed);
      o.set("scale", l.scale);
      const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> R = l.cameraPose.rotation().matrix();
      const Eigen::Vector3d t = l.cameraPose.translation();
      o.set("cameraRotation", f64(R.data(), 9));
      o.set("cameraPosition", f64(t.data(), 3));
      const uint8_t v[2] = {uint8_t(l.valid[0]), uint8_t(l.valid[1])};
      o.set("valid", toTyped(v, 2, "Uint8Array"));
      val j = val::object();
      j.set("left", l.valid[0] ? f64(l.joints[0].data(), 63) : val::null());
      j.set("right", l.valid[1] ? f64(l.joints[1].data(), 63) : val::null());
      o.set("joints", j);
      return o;
    });
  }

  val finishCamera() {
    return guard("Pipeline.finishCamera", [&] {
      const hawor::SlamResult<double>& r = p_.finishCamera();
      const std::vector<int> f = p_.keyframeFrames();
      val o = val::object();
      o.set("keyframeFrames", toTyped(f.data(), f.size(), "Int32Array"));
      o.set("initialised", r.initialised);
      return o;
    });
  }

  val finish(const val& depthMaps) {
    return guard("Pipeline.finish", [&] {
      std::vector<std::vector<float>> maps;
      std::vector<const float*> ptrs;
      if (!absent(depthMaps)) {
        const hawor::PinholeCamera<double>& s = p_.slamCamera();
        const size_t n = static_cast<size_t>(s.width) * static_cast<size_t>(s.height);
        for (int k = 0; k < depthMaps["length"].as<int>(); ++k) maps.push_back(exactly<float>(depthMaps[k], n, "depthMaps[" + std::to_string(k) + "]"));
        for (const auto& m : maps) ptrs.push_back(m.data());
      }
      return resultToJs(p_.finish(ptrs), p_.options(), *left_, *right_);
    });
  }

 private:
  static val info(const hawor::Pipeline<double>::FrameInfo& f) {
    val o = val::object();
    o.set("slamStatus", static_cast<int>(f.slamStatus));
    const int32_t d[2] = {f.detection[0], f.detection[1]};
    const uint8_t v[2] = {uint8_t(f.valid[0]), uint8_t(f.valid[1])};
    o.set("detection", toTyped(d, 2, "Int32Array"));
    o.set("valid", toTyped(v, 2, "Uint8Array"));
    return o;
  }
  const HandModel* left_;
  const HandModel* right_;
  hawor::Pipeline<double> p_;
};

/// assignSides (pipeline/sides.hpp) frame by frame, for tools that score the side policy alone.
class SideAssigner {
 public:
  explicit SideAssigner(double reach) : reach_(reach) {}
  val assign(const val& detections) {
    return guard("SideAssigner.assign", [&] {
      const std::vector<hawor::HandDetection<double>> dets = detectionsFrom(detections);
      const std::array<int, 2> s = hawor::assignSides(dets, state_, reach_);
      hawor::updateSideState(state_, dets, s);
      const int32_t d[2] = {s[0], s[1]};
      return toTyped(d, 2, "Int32Array");
    });
  }

 private:
  double reach_;
  hawor::SideState<double> state_;
};

Pipeline* newPipeline(const val& options, const val& left, const val& right) {
  return guard("Pipeline", [&] {
    if (absent(left) || absent(right)) throw hawor::Error("the left and right HandModel are required");
    return new Pipeline(optionsFrom(options), left.as<HandModel*>(emscripten::allow_raw_pointers()),
                        right.as<HandModel*>(emscripten::allow_raw_pointers()));
  });
}

}  // namespace

EMSCRIPTEN_BINDINGS(hawor_pipeline) {
  using emscripten::allow_raw_pointers;
  emscripten::class_<Pipeline>("Pipeline")
      .constructor(&newPipeline, allow_raw_pointers())
      .function("slamSize", &Pipeline::slamSize)
      .function("predict", &Pipeline::predict)
      .function("slamOptions", &Pipeline::slamOptions)
      .function("observeSlamInputs", &Pipeline::observeSlamInputs)
      .function("push", &Pipeline::push)
      .function("pushDeferred", &Pipeline::pushDeferred)
      .function("trackPending", &Pipeline::trackPending)
      .function("pushHands", &Pipeline::pushHands)
      .function("pushJoints", &Pipeline::pushJoints)
      .function("stampFrame", &Pipeline::stampFrame)
      .function("updateLiveWorld", &Pipeline::updateLiveWorld)
      .function("live", &Pipeline::live)
      .function("finishCamera", &Pipeline::finishCamera)
      .function("finish", &Pipeline::finish);
  emscripten::class_<SideAssigner>("SideAssigner").constructor<double>().function("assign", &SideAssigner::assign);
}
