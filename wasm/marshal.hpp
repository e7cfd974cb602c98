// hawor_core's marshalling between JavaScript values and the library's types, shared by the
// binding files (bindings.cpp: the library's parts; pipeline_bindings.hpp: the pipeline). No
// algorithm lives here.
#pragma once

#include <emscripten/bind.h>
#include <emscripten/val.h>

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hawor/geometry/camera.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/load_model.hpp"
#include "hawor/scale/metric_scale.hpp"

namespace hawor_wasm {

using emscripten::val;

// --- marshalling ---------------------------------------------------------------------------------

template <typename T>
inline std::vector<T> fromTyped(const val& a) {
  return emscripten::convertJSArrayToNumberVector<T>(a);
}

template <typename T>
inline val toTyped(const T* data, size_t n, const char* ctor) {
  // typed_memory_view aliases the heap; constructing a new typed array copies it out.
  return val::global(ctor).new_(emscripten::typed_memory_view(n, data));
}
inline val f64(const double* d, size_t n) { return toTyped(d, n, "Float64Array"); }

inline bool absent(const val& v) { return v.isNull() || v.isUndefined(); }

/// A typed array (or array) of exactly n numbers; `what` names it in the error.
template <typename T = double>
inline std::vector<T> exactly(const val& a, size_t n, const std::string& what) {
  if (absent(a)) throw hawor::Error(what + ": missing (expected " + std::to_string(n) + " numbers)");
  std::vector<T> v = fromTyped<T>(a);
  if (v.size() != n) {
    throw hawor::Error(what + ": length " + std::to_string(v.size()) + ", expected " + std::to_string(n));
  }
  return v;
}

/// Runs f; a C++ exception becomes a JavaScript Error thrown once f's frames are gone (a JS
/// exception crossing C++ frames would skip their destructors).
template <typename F>
inline auto guard(const char* fn, F&& f) -> decltype(f()) {
  std::optional<val> err;
  try {
    return f();
  } catch (const std::exception& e) {
    err = val::global("Error").new_(std::string(fn) + ": " + e.what());
  }
  err->set("name", "HaworError");
  err->throw_();
}

inline hawor::PinholeCamera<double> camera(const val& intrinsics, int width, int height) {
  const std::vector<double> k = exactly(intrinsics, 4, "intrinsics [fx, fy, cx, cy]");
  hawor::PinholeCamera<double> c;
  c.fx = k[0], c.fy = k[1], c.cx = k[2], c.cy = k[3];
  c.width = width, c.height = height;
  c.validate();
  return c;
}

// --- hand model ----------------------------------------------------------------------------------

struct HandModel {
  hawor::LoadedHandModel<double> loaded;
  const hawor::HandModel<double>& m() const { return loaded.model; }
};


/// A pose object {rot, handPose, betas, trans} for `model`.
inline hawor::HandPose<double> poseFrom(const val& p, const hawor::HandModel<double>& model, const std::string& what) {
  if (absent(p)) throw hawor::Error(what + ": missing pose");
  const size_t J1 = static_cast<size_t>(model.numJoints() - 1);
  hawor::HandPose<double> pose = hawor::HandPose<double>::zero(model);
  const std::vector<double> rot = exactly(p["rot"], 3, what + ".rot");
  const std::vector<double> trans = exactly(p["trans"], 3, what + ".trans");
  const std::vector<double> hp = exactly(p["handPose"], 3 * J1, what + ".handPose");
  pose.rot = hawor::Vec3<double>(rot[0], rot[1], rot[2]);
  pose.trans = hawor::Vec3<double>(trans[0], trans[1], trans[2]);
  std::copy(hp.begin(), hp.end(), pose.handPose.data());  // row-major (J-1,3)
  if (!absent(p["betas"])) {
    const std::vector<double> b = fromTyped<double>(p["betas"]);
    if (b.size() > static_cast<size_t>(model.numBetas())) {
      throw hawor::Error(what + ".betas: " + std::to_string(b.size()) + " values, the model has " +
                         std::to_string(model.numBetas()));
    }
    pose.betas = Eigen::Map<const hawor::VecX<double>>(b.data(), static_cast<Eigen::Index>(b.size()));
  }
  return pose;
}

inline void setPose(val& o, const hawor::HandPose<double>& p) {
  o.set("rot", f64(p.rot.data(), 3));
  o.set("handPose", f64(p.handPose.data(), static_cast<size_t>(p.handPose.size())));
  o.set("betas", f64(p.betas.data(), static_cast<size_t>(p.betas.size())));
  o.set("trans", f64(p.trans.data(), 3));
}


/// The metric scale's answer and every cue that ran, as the JavaScript object metricScale()
/// returns (eyeHeight: the ground cue's, reported with it).
inline val scaleToJs(const hawor::MetricScaleResult<double>& r, double eyeHeight) {
    val o = val::object();
    o.set("scale", r.fused.ok() ? r.fused.scale : std::nan(""));
    o.set("method", r.fused.ok() ? r.fused.method : std::string("none"));
    o.set("confidence", r.fused.confidence);
    if (r.depthRan) {
      o.set("keyframes", r.depth.keyframes);
      o.set("keyframesFitted", r.depth.fitted);
      o.set("depthScale", r.depth.scale);
      o.set("depthConfidence", r.depthConfidence);
    }
    if (r.handsRan) {
      o.set("handCue", r.hands.method);
      o.set("handScale", r.hands.scale);
      o.set("handConfidence", r.hands.confidence);
    }
    if (r.groundRan) {
      val g = val::object();
      g.set("ok", r.ground.ok());
      if (r.ground.ok()) {
        g.set("scale", r.groundUsed);  // the reading fused (floor, or the table top when ambiguous)
        g.set("floorScale", r.ground.scale);
        g.set("confidence", r.ground.confidence);
        g.set("cameraHeight", r.ground.height);  // map units
        g.set("heightSpread", r.ground.heightSpread);
        g.set("floorPoints", r.ground.floorPoints);
        if (std::isfinite(r.ground.floorWidth)) g.set("floorWidth", r.ground.floorWidth);  // camera heights
        g.set("levels", r.ground.levels);
        g.set("ambiguous", r.ground.ambiguous);
        g.set("eyeHeight", eyeHeight);
        if (std::isfinite(r.ground.surfaceHeight)) g.set("surfaceHeight", r.ground.surfaceHeight);
        g.set("up", f64(r.ground.up.data(), 3));
      } else {
        g.set("reason", r.ground.reason);
      }
      o.set("ground", g);
    }
    val left = val::array();  // cues inconsistent with the most confident (fuse_scale.hpp)
    for (const auto* f : {&r.noDepth, &r.fused}) {
      for (const std::string& c : f->leftOut) left.call<void>("push", c);
    }
    o.set("leftOut", left);
    return o;
}

}  // namespace hawor_wasm
