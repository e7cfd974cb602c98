// hawor_core — the C++ core exposed to JavaScript (embind). One binding file, no algorithm:
// typed arrays are copied in with one bulk transfer each (convertJSArrayToNumberVector), the
// library runs, results are copied out the same way (typed_memory_view). Everything is double
// (one instantiation of every template keeps the WebAssembly build short).
//
// JavaScript API (lengths in elements; "T" frames, "K" keypoints, "J" joints, "B" betas):
//   new HandModel(bytes: Uint8Array, side: 'left'|'right'|'auto', name: string)   any format of
//       loadAnyHandModel (MANO .pkl/.npz, hawor .npz, skinned .glb). Methods: numJoints(),
//       numBetas(), numKeypoints(), numVertices(), isLeft(), kind(), source(), faces(): Int32Array,
//       mirrored(): HandModel, restRoot(betas): Float64Array(3),
//       forward(pose): {vertices, joints, keypoints: Float64Array (N,3)}.
//   pose objects: {rot: (3), handPose: (3(J-1)), betas: (<= B), trans: (3)} Float64Arrays.
//   new HandFitter(model) .fit(kp2d (2K), conf2d (K)|null, kp3d (3K)|null, conf3d (K)|null,
//       intrinsics [fx,fy,cx,cy], width, height) -> pose & {keypoints (3K), reprojRmsPx,
//       reprojMedianPx, rms3d, cost, iterations, converged, warmStarted}; the solution is kept as
//       the next frame's warm start; reset() forgets it (track lost); hasPrevious().
//   renderHandMasks(width, height, intrinsics, hands: [{model, rot, handPose, betas, trans,
//       value?}], dilatePx) -> Uint8Array(width*height)
//   new MonoSlam(intrinsics, width, height, {useMasks?, refineFocal?, focalPriorSigma?, focalPriorFx?, rollingShutter?, set?, log?}) .process(frame: Uint8Array(W*H*c),
//       c = 1 grey, 3 RGB or 4 RGBA; mask: Uint8Array(W*H), hand != 0, or null) -> status; .finish() -> {rotations (9T, row-major R_c2w),
//       translations (3T), status: Uint8Array(T) (0 tracked, 1 interpolated, 2 lost,
//       3 relocalised), keyframe: Uint8Array(T), inliers: Int32Array(T), keyframeDepths:
//       {frames: Int32Array, kf: Int32Array, uv: Float64Array, depth: Float64Array}, points
//       (3N: the final map points, world = first camera, SLAM units), numKeyframes, numAdjustedKeyframes, numLosses,
//       numResets, numRelocalisations, numPlaceRelocalisations, numRevisitPoints, numPlaceLinks, placeLinks (Int32Array:
//       frame, older frame, matched points per link), numPlacedSegments,
//       numRefinedFrames, numHeadModelFrames, initialised, focal: {attempted, accepted, changed, guessFx,
//       fx, fy (the output's), estimateFx, stdLog (posterior std of log f), dataStdLog, rmsGuessPx, rmsPx,
//       evaluations, reason}}
//   metricScale({rotations, translations, fps?, keyframeDepths?, depthMaps?: [Float32Array],
//       depthWidth?, depthHeight?, masks?: [Uint8Array|null], hands?: [{positions (3T), valid}],
//       points?: Float64Array (3N map points, world, SLAM units: the ground cue), eyeHeight?,
//       sampling?: 'slam-depth'|'official', combine?: 'huber'|'median'})
//       -> {scale, method ('depth'|'hands'|'ground'|'fused'|'none'), confidence, ...}
//   downscaleImage(src: Uint8Array (sw*sh*channels), sw, sh, channels 1|3|4, dw, dh, grey: bool)
//       -> Uint8Array (dw*dh grey or dw*dh*3 RGB): box filter (render/resample.hpp)
//   rotationsToQuaternions(rotations: Float64Array (9T, row-major)) -> Float64Array (4T: x, y, z, w; w >= 0)
//   Lenses: lens_bindings.hpp (parseLens, describeCamera, cameraFromFov, undistortPoints,
//       Rectifier, LensCamera).
//   infillHand(motion, T, method 'spline'|'lerp'|'last', model|null) -> motion & {filled}
//   cameraToWorld(motion, T, rotations, translations, scale, model|null) -> motion
//   motion objects: {rot (3T), trans (3T), handPose (3KT), betas (BT), valid: Uint8Array(T)}.
//   evaluateCameras, evaluateHands, readNpz, writeNpz (see below).
// Errors: every entry point turns a C++ exception into a JavaScript Error (name 'HaworError')
// carrying the message, thrown after the C++ frames are unwound; errorMessage(ptr) remains for
// exceptions that escape as pointers. Objects made with `new` must be freed with .delete().
#include <emscripten/bind.h>
#include <emscripten/val.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "hawor/eval/eval.hpp"
#include "hawor/hand/fit.hpp"
#include "hawor/hand/load_model.hpp"
#include "hawor/hand/mirror.hpp"
#include "hawor/io/npz.hpp"
#include "hawor/motion/canonical.hpp"
#include "hawor/motion/infill.hpp"
#include "hawor/motion/rest_root.hpp"
#include "hawor/render/hand_masks.hpp"
#include "hawor/scale/metric_scale.hpp"
#include "hawor/geometry/camera_model.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/render/resample.hpp"
#include "hawor/slam/mono_slam.hpp"
#include "hawor/slam/slam_option_table.hpp"
#include "marshal.hpp"

using emscripten::val;

namespace {

using namespace hawor_wasm;

HandModel* newHandModel(const val& bytes, const std::string& side, const std::string& name) {
  return guard("HandModel", [&] {
    const hawor::HandSide s = side == "left"    ? hawor::HandSide::Left
                              : side == "right" ? hawor::HandSide::Right
                              : side == "auto" || side.empty()
                                  ? hawor::HandSide::Auto
                                  : throw hawor::Error("side must be 'left', 'right' or 'auto', not '" + side + "'");
    const std::vector<uint8_t> b = fromTyped<uint8_t>(bytes);
    return new HandModel{hawor::loadAnyHandModel<double>(b.data(), b.size(), s, name)};
  });
}

int numJoints(const HandModel& h) { return h.m().numJoints(); }
int numBetas(const HandModel& h) { return h.m().numBetas(); }
int numKeypoints(const HandModel& h) { return h.m().numKeypoints(); }
int numVertices(const HandModel& h) { return h.m().numVertices(); }
bool isLeft(const HandModel& h) { return h.m().isLeft; }
std::string kind(const HandModel& h) { return hawor::handModelKindName(h.loaded.kind); }
std::string source(const HandModel& h) { return h.loaded.source; }
val faces(const HandModel& h) { return toTyped(h.m().faces.data(), static_cast<size_t>(h.m().faces.size()), "Int32Array"); }

HandModel* mirrored(const HandModel& h) {
  return guard("HandModel.mirrored", [&] {
    HandModel* o = new HandModel{h.loaded};
    o->loaded.model = hawor::mirrorHandModel(h.m());
    return o;
  });
}

val forwardHand(const HandModel& h, const val& pose) {
  return guard("HandModel.forward", [&] {
    const hawor::HandOutput<double> out = hawor::forward(h.m(), poseFrom(pose, h.m(), "pose"));
    val o = val::object();
    o.set("vertices", f64(out.vertices.data(), static_cast<size_t>(out.vertices.size())));
    o.set("joints", f64(out.joints.data(), static_cast<size_t>(out.joints.size())));
    o.set("keypoints", f64(out.keypoints.data(), static_cast<size_t>(out.keypoints.size())));
    return o;
  });
}

val restRoot(const HandModel& h, const val& betas) {
  return guard("HandModel.restRoot", [&] {
    const std::vector<double> b = absent(betas) ? std::vector<double>() : fromTyped<double>(betas);
    hawor::Sequence<double> s(1, static_cast<Eigen::Index>(b.size()));
    std::copy(b.begin(), b.end(), s.data());
    const hawor::Points3<double> J0 = hawor::restRootJoints(h.m(), s);
    return f64(J0.data(), 3);
  });
}

// --- per-frame hand fit --------------------------------------------------------------------------

/// One hand track's fitter; the previous frame's solution is the warm start of the next.
class HandFitter {
 public:
  explicit HandFitter(const hawor::HandModel<double>& m) : fitter_(m), K_(m.numKeypoints()) {}

  val fit(const val& kp2d, const val& conf2d, const val& kp3d, const val& conf3d, const val& intrinsics, int width,
          int height) {
    return guard("HandFitter.fit", [&] {
      if (K_ == 0) throw hawor::Error("the model has no keypoints to fit");
      const size_t K = static_cast<size_t>(K_);
      const hawor::PinholeCamera<double> cam = camera(intrinsics, width, height);
      hawor::HandObservation<double> obs;
      const std::vector<double> k2 = exactly(kp2d, 2 * K, "keypoints2d");
      obs.keypoints2d = Eigen::Map<const hawor::Pixels<double>>(k2.data(), K_, 2);
      if (!absent(conf2d)) obs.confidence2d = vecFrom(exactly(conf2d, K, "confidence2d"));
      if (!absent(kp3d)) {
        const std::vector<double> k3 = exactly(kp3d, 3 * K, "keypoints3d");
        obs.keypoints3d = Eigen::Map<const hawor::Points3<double>>(k3.data(), K_, 3);
      }
      if (!absent(conf3d)) {
        if (absent(kp3d)) throw hawor::Error("confidence3d given without keypoints3d");
        obs.confidence3d = vecFrom(exactly(conf3d, K, "confidence3d"));
      }
      hawor::HandFitResult<double> r;
      try {
        r = fitter_.fit(obs, cam, options_, havePrevious_ ? &previous_ : nullptr);
      } catch (...) {
        havePrevious_ = false;  // a failed frame breaks the track (as `hawor fit` does)
        throw;
      }
      previous_ = r.pose;
      havePrevious_ = true;
      val o = val::object();
      setPose(o, r.pose);
      o.set("keypoints", f64(r.keypoints.data(), static_cast<size_t>(r.keypoints.size())));
      o.set("reprojRmsPx", r.reprojRmsPx);
      o.set("reprojMedianPx", r.reprojMedianPx);
      o.set("rms3d", r.rms3d);
      o.set("cost", r.cost);
      o.set("iterations", r.iterations);
      o.set("converged", r.converged);
      o.set("warmStarted", r.warmStarted);
      return o;
    });
  }
  void reset() { havePrevious_ = false; }
  bool hasPrevious() const { return havePrevious_; }
  /// Starts the next frame cold every time (the fit's warmStart option).
  void setWarmStart(bool on) { options_.warmStart = on; }

 private:
  static hawor::VecX<double> vecFrom(const std::vector<double>& v) {
    return Eigen::Map<const hawor::VecX<double>>(v.data(), static_cast<Eigen::Index>(v.size()));
  }
  hawor::HandFitter<double> fitter_;
  hawor::HandFitOptions<double> options_;
  hawor::HandPose<double> previous_;
  bool havePrevious_ = false;
  int K_ = 0;
};

HandFitter* newHandFitter(const HandModel& h) {
  return guard("HandFitter", [&] { return new HandFitter(h.m()); });
}

// --- hand masks ----------------------------------------------------------------------------------

val renderHandMasks(int width, int height, const val& intrinsics, const val& hands, int dilatePx) {
  return guard("renderHandMasks", [&] {
    const hawor::PinholeCamera<double> cam = camera(intrinsics, width, height);
    std::vector<hawor::HandMaskHand<double>> hs;
    const int n = absent(hands) ? 0 : hands["length"].as<int>();
    for (int i = 0; i < n; ++i) {
      const val h = hands[i];
      const std::string what = "hands[" + std::to_string(i) + "]";
      if (absent(h["model"])) throw hawor::Error(what + ".model: missing");
      const HandModel* m = h["model"].as<HandModel*>(emscripten::allow_raw_pointers());
      hawor::HandMaskHand<double> mh;
      mh.model = &m->m();
      mh.pose = poseFrom(h, m->m(), what);
      if (!absent(h["value"])) {
        const double v = h["value"].as<double>();
        if (!(v >= 1 && v <= 255 && v == std::floor(v))) throw hawor::Error(what + ".value must be an integer in [1, 255]");
        mh.value = static_cast<uint8_t>(v);
      }
      hs.push_back(std::move(mh));
    }
    hawor::Mask out;
    hawor::renderHandMasks(hs, cam, dilatePx, out);
    return toTyped(out.data.data(), out.data.size(), "Uint8Array");
  });
}

// --- SLAM ----------------------------------------------------------------------------------------

class MonoSlam {
 public:
  MonoSlam(const hawor::PinholeCamera<double>& cam, const hawor::SlamOptions<double>& opt)
      : slam_(cam, opt), width_(cam.width), height_(cam.height) {}

  int process(const val& grey, const val& mask) {
    return guard("MonoSlam.process", [&] {
      const size_t n = static_cast<size_t>(width_) * static_cast<size_t>(height_);
      if (absent(grey)) throw hawor::Error("frame: missing");
      image_.data = fromTyped<uint8_t>(grey);
      // Grey, RGB or RGBA (e.g. a canvas's ImageData) by the length: the library converts.
      const size_t c = image_.data.size() / n;
      if (image_.data.size() != c * n || (c != 1 && c != 3 && c != 4)) {
        throw hawor::Error("frame: length " + std::to_string(image_.data.size()) + " is not width*height*(1, 3 or 4) = " +
                           std::to_string(n) + "*c");
      }
      image_.width = width_, image_.height = height_, image_.channels = static_cast<int>(c);
      const bool hasMask = !absent(mask);
      if (hasMask) {
        mask_.width = width_, mask_.height = height_, mask_.channels = 1;
        mask_.data = exactly<uint8_t>(mask, n, "mask (width*height)");
      }
      return static_cast<int>(slam_.process(image_, hasMask ? &mask_ : nullptr));
    });
  }

  val finish() {
    return guard("MonoSlam.finish", [&] {
      const hawor::SlamResult<double> r = slam_.finish();
      const size_t T = r.poses.size();
      std::vector<double> R(9 * T), t(3 * T);
      std::vector<uint8_t> status(T), kf(T);
      for (size_t i = 0; i < T; ++i) {
        const hawor::Mat3<double> Ri = r.poses[i].rotationMatrix();
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) R[9 * i + 3 * a + b] = Ri(a, b);
          t[3 * i + a] = r.poses[i].translation()(a);
        }
        status[i] = static_cast<uint8_t>(r.status[i]);
        kf[i] = r.keyframe[i] ? 1 : 0;
      }
      std::vector<int32_t> frames, kfRow;
      std::vector<double> uv, depth;
      for (size_t j = 0; j < r.keyframeDepths.size(); ++j) {
        const auto& d = r.keyframeDepths[j];
        frames.push_back(d.frame);
        for (size_t q = 0; q < d.depth.size(); ++q) {
          kfRow.push_back(static_cast<int32_t>(j));
          uv.push_back(d.uv[q](0));
          uv.push_back(d.uv[q](1));
          depth.push_back(d.depth[q]);
        }
      }
      val o = val::object();
      o.set("rotations", f64(R.data(), R.size()));
      o.set("translations", f64(t.data(), t.size()));
      o.set("status", toTyped(status.data(), T, "Uint8Array"));
      o.set("keyframe", toTyped(kf.data(), T, "Uint8Array"));
      o.set("inliers", toTyped(r.inliers.data(), r.inliers.size(), "Int32Array"));
      val kd = val::object();
      kd.set("frames", toTyped(frames.data(), frames.size(), "Int32Array"));
      kd.set("kf", toTyped(kfRow.data(), kfRow.size(), "Int32Array"));
      kd.set("uv", f64(uv.data(), uv.size()));
      kd.set("depth", f64(depth.data(), depth.size()));
      o.set("keyframeDepths", kd);
      std::vector<double> pts;
      pts.reserve(3 * r.points.size());
      for (const auto& X : r.points) pts.insert(pts.end(), {X(0), X(1), X(2)});
      o.set("points", f64(pts.data(), pts.size()));
      o.set("numKeyframes", r.numKeyframes);
      o.set("numAdjustedKeyframes", r.numAdjustedKeyframes);
      o.set("numLosses", r.numLosses);
      o.set("numResets", r.numResets);
      o.set("numRelocalisations", r.numRelocalisations);
      o.set("numPlaceRelocalisations", r.numPlaceRelocalisations);
      o.set("numRevisitPoints", r.numRevisitPoints);
      o.set("numPlaceLinks", r.numPlaceLinks);
      std::vector<int> links;  // frame, older frame, matched points per place link
      for (const auto& l : r.placeLinks) links.insert(links.end(), {l.frame, l.oldFrame, l.points});
      o.set("placeLinks", toTyped(links.data(), links.size(), "Int32Array"));
      o.set("numPlacedSegments", r.numPlacedSegments);
      o.set("numRefinedFrames", r.numRefinedFrames);
      o.set("numHeadModelFrames", r.numHeadModelFrames);
      o.set("initialised", r.initialised);
      val fo = val::object();
      fo.set("attempted", r.focalAttempted);
      fo.set("accepted", r.focal.accepted);
      fo.set("changed", r.focal.changed);
      fo.set("guessFx", r.focal.guessFx);
      fo.set("fx", r.camera.fx);
      fo.set("fy", r.camera.fy);
      fo.set("estimateFx", r.focal.estimateFx);
      fo.set("stdLog", r.focal.stdLog);
      fo.set("dataStdLog", r.focal.dataStdLog);
      fo.set("rmsGuessPx", r.focal.rmsGuessPx);
      fo.set("rmsPx", r.focal.rmsPx);
      fo.set("evaluations", r.focal.evaluations);
      fo.set("reason", r.focal.reason);
      o.set("focal", fo);
      return o;
    });
  }

 private:
  hawor::MonoSlam<double> slam_;
  hawor::ImageU8 image_, mask_;
  int width_, height_;
};

MonoSlam* newMonoSlam(const val& intrinsics, int width, int height, const val& options) {
  return guard("MonoSlam", [&] {
    hawor::SlamOptions<double> opt;
    if (!absent(options) && !absent(options["useMasks"])) opt.useMasks = options["useMasks"].as<bool>();
    if (!absent(options) && !absent(options["refineFocal"])) opt.finish.refineFocal = options["refineFocal"].as<bool>();
    if (!absent(options) && !absent(options["rollingShutter"])) {
      opt.rollingShutter = options["rollingShutter"].as<double>();
      if (!(std::abs(opt.rollingShutter) <= 1)) throw hawor::Error("rollingShutter must be in [-1, 1] (readout / frame interval; negative: rows read bottom to top)");
    }
    if (!absent(options) && !absent(options["fps"])) {
      opt.fps = options["fps"].as<double>();  // validated by MonoSlam: (0, 1000]
    }
    if (!absent(options) && !absent(options["focalPriorSigma"])) {
      opt.focal.priorSigmaLog = options["focalPriorSigma"].as<double>();
      if (!(opt.focal.priorSigmaLog > 0)) throw hawor::Error("focalPriorSigma must be > 0");
    }
    if (!absent(options) && !absent(options["focalPriorFx"])) {
      opt.focal.priorFx = options["focalPriorFx"].as<double>();
      if (!(opt.focal.priorFx > 0) || !std::isfinite(opt.focal.priorFx)) throw hawor::Error("focalPriorFx must be finite and > 0");
    }
    // set: "NAME=VALUE,..." over any SlamOptions field (as `hawor slam --set`), for ablations
    // of the product's build; log: the SLAM's decisions line by line on stderr (the console).
    if (!absent(options) && !absent(options["set"])) hawor::setSlamOptions(opt, options["set"].as<std::string>());
    if (!absent(options) && !absent(options["log"]) && options["log"].as<bool>()) {
      opt.log = [](const std::string& line) { std::fprintf(stderr, "slam: %s\n", line.c_str()); };
    }
    return new MonoSlam(camera(intrinsics, width, height), opt);
  });
}

// --- poses and hand motion -------------------------------------------------------------------------

/// T camera-to-world poses from rotations (9T, row-major) and translations (3T).
void posesFrom(const val& rotations, const val& translations, std::vector<hawor::Mat3<double>>& R,
               std::vector<hawor::Vec3<double>>& t) {
  const std::vector<double> r = fromTyped<double>(rotations), p = fromTyped<double>(translations);
  if (r.size() % 9 != 0 || r.size() / 9 * 3 != p.size()) {
    throw hawor::Error("poses: " + std::to_string(r.size()) + " rotation and " + std::to_string(p.size()) +
                       " translation values are not 9T and 3T");
  }
  const size_t T = p.size() / 3;
  R.resize(T), t.resize(T);
  for (size_t i = 0; i < T; ++i) {
    R[i] = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(r.data() + 9 * i);
    t[i] = Eigen::Map<const hawor::Vec3<double>>(p.data() + 3 * i);
    if (!R[i].allFinite() || !t[i].allFinite()) throw hawor::Error("poses: frame " + std::to_string(i) + " is not finite");
  }
}

hawor::Sequence<double> rows(const val& a, int T, size_t cols, bool anyCols, const std::string& what) {
  const std::vector<double> v = absent(a) ? std::vector<double>() : fromTyped<double>(a);
  if (anyCols) {
    if (v.size() % static_cast<size_t>(T) != 0) {
      throw hawor::Error(what + ": length " + std::to_string(v.size()) + " is not a multiple of T = " + std::to_string(T));
    }
    cols = v.size() / static_cast<size_t>(T);
  } else if (v.size() != cols * static_cast<size_t>(T)) {
    throw hawor::Error(what + ": length " + std::to_string(v.size()) + ", expected " +
                       std::to_string(cols * static_cast<size_t>(T)));
  }
  hawor::Sequence<double> s(T, static_cast<Eigen::Index>(cols));
  std::copy(v.begin(), v.end(), s.data());
  return s;
}

/// A motion object {rot, trans, handPose, betas, valid} of T frames.
hawor::HandMotion<double> motionFrom(const val& m, int T) {
  if (T <= 0) throw hawor::Error("T must be > 0");
  if (absent(m)) throw hawor::Error("missing hand motion");
  hawor::HandMotion<double> h;
  h.rot = rows(m["rot"], T, 3, false, "rot");
  h.trans = rows(m["trans"], T, 3, false, "trans");
  h.handPose = rows(m["handPose"], T, 0, true, "handPose");
  h.betas = rows(m["betas"], T, 0, true, "betas");
  h.valid = exactly<uint8_t>(m["valid"], static_cast<size_t>(T), "valid");
  h.validate();
  return h;
}

val motionTo(const hawor::HandMotion<double>& h) {
  val o = val::object();
  o.set("rot", f64(h.rot.data(), static_cast<size_t>(h.rot.size())));
  o.set("trans", f64(h.trans.data(), static_cast<size_t>(h.trans.size())));
  o.set("handPose", f64(h.handPose.data(), static_cast<size_t>(h.handPose.size())));
  o.set("betas", f64(h.betas.data(), static_cast<size_t>(h.betas.size())));
  o.set("valid", toTyped(h.valid.data(), h.valid.size(), "Uint8Array"));
  return o;
}

/// J0 of every frame from the model (rest_root.hpp), or the origin without a model.
hawor::Points3<double> restRoots(const val& model, const hawor::HandMotion<double>& m) {
  if (absent(model)) return hawor::Points3<double>::Zero(1, 3);
  return hawor::restRootJoints(model.as<HandModel*>(emscripten::allow_raw_pointers())->m(), m);
}

val infillHand(const val& motion, int T, const std::string& method, const val& model) {
  return guard("infillHand", [&] {
    const hawor::HandMotion<double> m = motionFrom(motion, T);
    hawor::InfillOptions<double> opt;
    opt.method = hawor::parseInfillMethod(method);
    const hawor::InfillResult<double> r = hawor::infillHand(m, restRoots(model, m), opt);
    val o = motionTo(r.motion);
    o.set("filled", toTyped(r.filled.data(), r.filled.size(), "Uint8Array"));
    return o;
  });
}

val cameraToWorld(const val& motion, int T, const val& rotations, const val& translations, double scale,
                  const val& model) {
  return guard("cameraToWorld", [&] {
    const hawor::HandMotion<double> m = motionFrom(motion, T);
    std::vector<hawor::Mat3<double>> R;
    std::vector<hawor::Vec3<double>> t;
    posesFrom(rotations, translations, R, t);
    if (!(scale > 0) || !std::isfinite(scale)) throw hawor::Error("scale must be finite and > 0");
    for (auto& p : t) p *= scale;  // the SLAM's map units to metres
    return motionTo(hawor::cameraToWorld(m, R, t, restRoots(model, m)));
  });
}

// --- frames and rotations ------------------------------------------------------------------------

val downscaleImage(const val& src, int sw, int sh, int channels, int dw, int dh, bool grey) {
  return guard("downscaleImage", [&] {
    if (sw <= 0 || sh <= 0 || channels <= 0) throw hawor::Error("downscaleImage: empty source image");
    const std::vector<uint8_t> in = exactly<uint8_t>(src, static_cast<size_t>(sw) * sh * channels, "downscaleImage: src");
    std::vector<uint8_t> out(static_cast<size_t>(std::max(dw, 0)) * std::max(dh, 0) * (grey ? 1 : 3));
    hawor::downscaleBox(in.data(), sw, sh, channels, dw, dh, grey, out.data());
    return toTyped(out.data(), out.size(), "Uint8Array");
  });
}

val rotationsToQuaternions(const val& rotations) {
  return guard("rotationsToQuaternions", [&] {
    const std::vector<double> R = fromTyped<double>(rotations);
    if (R.size() % 9 != 0) throw hawor::Error("rotationsToQuaternions: length " + std::to_string(R.size()) + " is not 9T");
    std::vector<double> q(R.size() / 9 * 4);
    for (size_t t = 0; t < R.size() / 9; ++t) {
      const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> M(R.data() + 9 * t);
      const Eigen::Quaterniond e = hawor::matrixToQuaternion(Eigen::Matrix3d(M));
      q[4 * t] = e.x(), q[4 * t + 1] = e.y(), q[4 * t + 2] = e.z(), q[4 * t + 3] = e.w();
    }
    return f64(q.data(), q.size());
  });
}

// --- metric scale --------------------------------------------------------------------------------

val metricScale(const val& in) {
  return guard("metricScale", [&] {
    std::vector<hawor::Mat3<double>> R;
    std::vector<hawor::Vec3<double>> t;
    posesFrom(in["rotations"], in["translations"], R, t);
    const size_t T = R.size();
    std::vector<hawor::SE3<double>> poses;
    for (size_t i = 0; i < T; ++i) poses.emplace_back(R[i], t[i]);
    hawor::MetricScaleOptions<double> opt;
    if (!absent(in["fps"])) opt.setFps(in["fps"].as<double>());
    const std::string sampling = absent(in["sampling"]) ? "slam-depth" : in["sampling"].as<std::string>();
    if (sampling == "official") {
      opt.depth.sampling = hawor::AdaSmSampling::Official;
      opt.depth.minPixels = 10;
    } else if (sampling != "slam-depth") {
      throw hawor::Error("sampling must be 'slam-depth' or 'official', not '" + sampling + "'");
    }
    const std::string combine = absent(in["combine"]) ? "huber" : in["combine"].as<std::string>();
    if (combine == "median") {
      opt.depth.combine = hawor::KeyframeCombine::Median;
    } else if (combine != "huber") {
      throw hawor::Error("combine must be 'huber' or 'median', not '" + combine + "'");
    }

    std::vector<hawor::KeyframeDepthPairs<double>> keyframes;
    if (!absent(in["depthMaps"])) {
      const val kd = in["keyframeDepths"];
      if (absent(kd)) throw hawor::Error("depthMaps given without keyframeDepths");
      const std::vector<int32_t> frames = fromTyped<int32_t>(kd["frames"]), kf = fromTyped<int32_t>(kd["kf"]);
      const std::vector<double> uv = fromTyped<double>(kd["uv"]), depth = fromTyped<double>(kd["depth"]);
      if (kf.size() != depth.size() || uv.size() != 2 * depth.size()) {
        throw hawor::Error("keyframeDepths: kf, uv and depth disagree in length");
      }
      const val maps = in["depthMaps"], masks = in["masks"];
      const size_t K = frames.size();
      if (maps["length"].as<size_t>() != K) {
        throw hawor::Error("depthMaps: " + std::to_string(maps["length"].as<size_t>()) + " maps for " +
                           std::to_string(K) + " keyframes");
      }
      if (!absent(masks) && masks["length"].as<size_t>() != K) throw hawor::Error("masks: one per keyframe expected");
      const int W = in["depthWidth"].as<int>(), H = in["depthHeight"].as<int>();
      const size_t n = static_cast<size_t>(W) * static_cast<size_t>(H);
      // Pixels of keyframe k are the run of rows with kf == k (finish() writes them in order).
      size_t begin = 0;
      for (size_t k = 0; k < K; ++k) {
        size_t end = begin;
        while (end < kf.size() && kf[end] == static_cast<int32_t>(k)) ++end;
        const std::vector<float> map = exactly<float>(maps[k], n, "depthMaps[" + std::to_string(k) + "]");
        std::vector<uint8_t> mask;
        if (!absent(masks) && !absent(masks[k])) mask = exactly<uint8_t>(masks[k], n, "masks[" + std::to_string(k) + "]");
        keyframes.push_back(hawor::pairKeyframeDepths(uv.data() + 2 * begin, depth.data() + begin, end - begin,
                                                      map.data(), W, H, mask.empty() ? nullptr : mask.data()));
        begin = end;
      }
      if (begin != kf.size()) throw hawor::Error("keyframeDepths.kf must list the keyframes' rows in order 0..K-1");
    }
    std::vector<hawor::HandTrack<double>> hands;
    if (!absent(in["hands"])) {
      const val hs = in["hands"];
      for (int h = 0; h < hs["length"].as<int>(); ++h) {
        const std::string what = "hands[" + std::to_string(h) + "]";
        const std::vector<double> p = exactly(hs[h]["positions"], 3 * T, what + ".positions");
        const std::vector<uint8_t> v = exactly<uint8_t>(hs[h]["valid"], T, what + ".valid");
        hawor::HandTrack<double> track;
        for (size_t f = 0; f < T; ++f) {
          track.positionCam.emplace_back(p[3 * f], p[3 * f + 1], p[3 * f + 2]);
          track.valid.push_back(v[f] ? 1 : 0);
        }
        hands.push_back(std::move(track));
      }
    }
    std::vector<hawor::Vec3<double>> mapPoints;
    if (!absent(in["points"])) {
      const std::vector<double> p = fromTyped<double>(in["points"]);
      if (p.size() % 3 != 0) throw hawor::Error("points: length is not a multiple of 3");
      for (size_t i = 0; i + 2 < p.size(); i += 3) mapPoints.emplace_back(p[i], p[i + 1], p[i + 2]);
    }
    if (!absent(in["eyeHeight"])) {
      opt.ground.eyeHeight = in["eyeHeight"].as<double>();
      if (!(opt.ground.eyeHeight > opt.ground.tableHeight) || !std::isfinite(opt.ground.eyeHeight)) {
        throw hawor::Error("eyeHeight must be a number above the table height (" + std::to_string(opt.ground.tableHeight) + " m)");
      }
    }
    if (keyframes.empty() && hands.empty() && absent(in["points"])) {
      throw hawor::Error("give depthMaps (with keyframeDepths), hands, points, or several");
    }
    return scaleToJs(hawor::estimateMetricScale(keyframes, poses, hands, opt, &mapPoints), opt.ground.eyeHeight);
  });
}

// --- metrics and npz (unchanged API) ---------------------------------------------------------------

hawor::JointSequence<double> joints(const val& a, int T, const char* what) {
  const std::vector<double> v = fromTyped<double>(a);
  if (T <= 0 || v.size() % static_cast<size_t>(T) != 0 || (v.size() / T) % 3 != 0)
    throw hawor::Error(std::string(what) + ": length " + std::to_string(v.size()) +
                       " is not T x J x 3 with T = " + std::to_string(T));
  hawor::JointSequence<double> s(T, static_cast<Eigen::Index>(v.size() / T));
  std::copy(v.begin(), v.end(), s.data());
  return s;
}

hawor::Points3<double> points(const val& a, const char* what) {
  const std::vector<double> v = fromTyped<double>(a);
  if (v.size() % 3 != 0) throw hawor::Error(std::string(what) + ": length is not a multiple of 3");
  hawor::Points3<double> p(static_cast<Eigen::Index>(v.size() / 3), 3);
  std::copy(v.begin(), v.end(), p.data());
  return p;
}

/// Camera metrics of two (T,3) position tracks (flattened): {ate, ate_s (mm), scale, n}.
val evaluateCameras(const val& gt, const val& est) {
  return guard("evaluateCameras", [&] {
    const auto m = hawor::evaluateCameras(points(gt, "gt"), points(est, "est"));
    val o = val::object();
    o.set("ate", m.ate);
    o.set("ate_s", m.ate_s);
    o.set("scale", m.scale);
    o.set("n", static_cast<double>(m.n));
    return o;
  });
}

/// Hand metrics of (T,J,3) joint tracks (flattened); valid: Uint8Array of T or null.
val evaluateHands(const val& gt_world, const val& est_world, const val& gt_cam, const val& est_cam,
                  int T, const val& valid, double fps) {
  return guard("evaluateHands", [&] {
    std::vector<uint8_t> mask;
    if (!absent(valid)) mask = fromTyped<uint8_t>(valid);
    const auto m = hawor::evaluateHands(joints(gt_world, T, "gt_world"), joints(est_world, T, "est_world"),
                                        joints(gt_cam, T, "gt_cam"), joints(est_cam, T, "est_cam"), mask, fps);
    val o = val::object();
    o.set("pa_mpjpe", m.pa_mpjpe);
    o.set("auc", m.auc);
    o.set("w_mpjpe", m.w_mpjpe);
    o.set("wa_mpjpe", m.wa_mpjpe);
    o.set("rte", m.rte);
    o.set("accel", m.accel);
    o.set("n", static_cast<double>(m.n));
    return o;
  });
}

/// Parses an .npz held in a Uint8Array: {name: {shape: [...], dtype, data: Float64Array}}.
val readNpz(const val& bytes, const std::string& what) {
  return guard("readNpz", [&] {
    const std::vector<uint8_t> b = fromTyped<uint8_t>(bytes);
    const hawor::Npz z = hawor::Npz::fromBuffer(b, what);
    val out = val::object();
    for (const std::string& name : z.names()) {
      const hawor::NpyArray& a = z.get(name);
      val entry = val::object();
      val shape = val::array();
      for (size_t d : a.shape) shape.call<void>("push", static_cast<double>(d));
      entry.set("shape", shape);
      entry.set("dtype", a.dtype);
      const std::vector<double> v = z.getAs<double>(name);
      entry.set("data", f64(v.data(), v.size()));
      out.set(name, entry);
    }
    return out;
  });
}

/// Writes {name: {shape: [...], data: Float64Array | Float32Array | Int32Array | Uint8Array}}
/// as an .npz (deflated when `compressed`); returns the file's bytes as a Uint8Array.
val writeNpz(const val& arrays, bool compressed) {
  return guard("writeNpz", [&] {
    hawor::Npz z;
    const val keys = val::global("Object").call<val>("keys", arrays);
    const int n = keys["length"].as<int>();
    for (int i = 0; i < n; ++i) {
      const std::string name = keys[i].as<std::string>();
      const val entry = arrays[name];
      std::vector<size_t> shape;
      const val js_shape = entry["shape"];
      for (int d = 0; d < js_shape["length"].as<int>(); ++d) shape.push_back(js_shape[d].as<size_t>());
      const val data = entry["data"];
      const std::string type = data["constructor"]["name"].as<std::string>();
      size_t expect = 1;
      for (size_t d : shape) expect *= d;
      if (static_cast<size_t>(data["length"].as<double>()) != expect)
        throw hawor::Error("writeNpz: array '" + name + "' length does not match its shape");
      if (type == "Float64Array") {
        z.set(name, hawor::NpyArray::fromData(fromTyped<double>(data).data(), shape));
      } else if (type == "Float32Array") {
        z.set(name, hawor::NpyArray::fromData(fromTyped<float>(data).data(), shape));
      } else if (type == "Int32Array") {
        z.set(name, hawor::NpyArray::fromData(fromTyped<int32_t>(data).data(), shape));
      } else if (type == "Uint8Array") {
        z.set(name, hawor::NpyArray::fromData(fromTyped<uint8_t>(data).data(), shape));
      } else {
        throw hawor::Error("writeNpz: array '" + name + "' has unsupported type " + type);
      }
    }
    const std::vector<uint8_t> bytes = z.toBuffer(compressed);
    return toTyped(bytes.data(), bytes.size(), "Uint8Array");
  });
}

/// For exceptions that still reach JavaScript as a pointer (thrown outside guard()).
std::string errorMessage(intptr_t ptr) { return reinterpret_cast<const std::exception*>(ptr)->what(); }

}  // namespace

EMSCRIPTEN_BINDINGS(hawor_core) {
  using emscripten::allow_raw_pointers;
  emscripten::class_<HandModel>("HandModel")
      .constructor(&newHandModel, allow_raw_pointers())
      .function("numJoints", &numJoints)
      .function("numBetas", &numBetas)
      .function("numKeypoints", &numKeypoints)
      .function("numVertices", &numVertices)
      .function("isLeft", &isLeft)
      .function("kind", &kind)
      .function("source", &source)
      .function("faces", &faces)
      .function("mirrored", &mirrored, allow_raw_pointers())
      .function("restRoot", &restRoot)
      .function("forward", &forwardHand);
  emscripten::class_<HandFitter>("HandFitter")
      .constructor(&newHandFitter, allow_raw_pointers())
      .function("fit", &HandFitter::fit)
      .function("reset", &HandFitter::reset)
      .function("hasPrevious", &HandFitter::hasPrevious)
      .function("setWarmStart", &HandFitter::setWarmStart);
  emscripten::class_<MonoSlam>("MonoSlam")
      .constructor(&newMonoSlam, allow_raw_pointers())
      .function("process", &MonoSlam::process)
      .function("finish", &MonoSlam::finish);
  emscripten::function("renderHandMasks", &renderHandMasks);
  emscripten::function("metricScale", &metricScale);
  emscripten::function("downscaleImage", &downscaleImage);
  emscripten::function("rotationsToQuaternions", &rotationsToQuaternions);
  emscripten::function("infillHand", &infillHand);
  emscripten::function("cameraToWorld", &cameraToWorld);
  emscripten::function("evaluateCameras", &evaluateCameras);
  emscripten::function("evaluateHands", &evaluateHands);
  emscripten::function("readNpz", &readNpz);
  emscripten::function("writeNpz", &writeNpz);
  emscripten::function("errorMessage", &errorMessage);
}

// The lenses and the pipeline object (their own files, the same translation unit).
#include "lens_bindings.hpp"
#include "pipeline_bindings.hpp"
