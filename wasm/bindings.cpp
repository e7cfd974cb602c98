// hawor_core — the C++ core exposed to JavaScript (embind). One binding file, no algorithm:
// typed arrays are copied in with one bulk transfer, the library runs, results are copied out.
#include <emscripten/bind.h>
#include <emscripten/val.h>

#include <cstdint>
#include <string>
#include <vector>

#include "hawor/eval/eval.hpp"
#include "hawor/io/npz.hpp"

using emscripten::val;

namespace {

template <typename T>
std::vector<T> fromTyped(const val& a) {
  return emscripten::convertJSArrayToNumberVector<T>(a);
}

template <typename T>
val toTyped(const T* data, size_t n, const char* ctor) {
  // typed_memory_view aliases the heap; constructing a new typed array copies it out.
  return val::global(ctor).new_(emscripten::typed_memory_view(n, data));
}

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
  const auto m = hawor::evaluateCameras(points(gt, "gt"), points(est, "est"));
  val o = val::object();
  o.set("ate", m.ate);
  o.set("ate_s", m.ate_s);
  o.set("scale", m.scale);
  o.set("n", static_cast<double>(m.n));
  return o;
}

/// Hand metrics of (T,J,3) joint tracks (flattened); valid: Uint8Array of T or null.
val evaluateHands(const val& gt_world, const val& est_world, const val& gt_cam, const val& est_cam,
                  int T, const val& valid, double fps) {
  std::vector<uint8_t> mask;
  if (!valid.isNull() && !valid.isUndefined()) mask = fromTyped<uint8_t>(valid);
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
}

/// Parses an .npz held in a Uint8Array: {name: {shape: [...], dtype, data: Float64Array}}.
val readNpz(const val& bytes, const std::string& what) {
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
    entry.set("data", toTyped(v.data(), v.size(), "Float64Array"));
    out.set(name, entry);
  }
  return out;
}

/// Writes {name: {shape: [...], data: Float64Array | Float32Array | Int32Array | Uint8Array}}
/// as an .npz (deflated when `compressed`); returns the file's bytes as a Uint8Array.
val writeNpz(const val& arrays, bool compressed) {
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
    const size_t expect = z.get(name).size();
    if (static_cast<size_t>(data["length"].as<double>()) != expect)
      throw hawor::Error("writeNpz: array '" + name + "' length does not match its shape");
  }
  const std::vector<uint8_t> bytes = z.toBuffer(compressed);
  return toTyped(bytes.data(), bytes.size(), "Uint8Array");
}

/// Library errors reach JavaScript as exceptions; this turns the pointer into the message.
std::string errorMessage(intptr_t ptr) { return reinterpret_cast<const std::exception*>(ptr)->what(); }

}  // namespace

EMSCRIPTEN_BINDINGS(hawor_core) {
  emscripten::function("evaluateCameras", &evaluateCameras);
  emscripten::function("evaluateHands", &evaluateHands);
  emscripten::function("readNpz", &readNpz);
  emscripten::function("writeNpz", &writeNpz);
  emscripten::function("errorMessage", &errorMessage);
}
