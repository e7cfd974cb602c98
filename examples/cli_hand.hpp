// Command-line plumbing shared by the hand commands (hand, fit, metrics hands --model): the
// --model / --side options and the reading of hand parameters from .npz files. Parsing and
// checking only; the model formats and the forward pass live in include/hawor/hand.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#if defined(__linux__) && !defined(__EMSCRIPTEN__)
#include <unistd.h>
#endif

#include "cli_args.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/load_model.hpp"
#include "hawor/io/npz.hpp"

namespace hawor_cli {

/// Help text of the --model / --side options (shared by the hand commands).
inline const char* kModelOptionHelp =
    "  --model FILE|default  the hand model: a MANO .pkl (MANO_RIGHT.pkl / MANO_LEFT.pkl), a\n"
    "                        MANO-key .npz, a hawor hand-model .npz (hawor convert-hand) or a\n"
    "                        skinned binary glTF .glb; the format is read from the content.\n"
    "                        'default' = the shipped WebXR generic hand, searched in\n"
    "                        $HAWOR_HAND_DIR, <hawor dir>/../models (hand_<side>.npz, made by\n"
    "                        the build) and ./node_modules/@webxr-input-profiles/assets/dist/\n"
    "                        profiles/generic-hand (<side>.glb)\n"
    "  --side left|right     which hand; default: from the file (hawor .npz) or its name\n"
    "                        (MANO_LEFT.pkl, left.glb); 'default' models: right\n";

/// --side as a HandSide (Auto when absent).
inline hawor::HandSide sideOption(const Args& args) {
  if (!args.has("side")) return hawor::HandSide::Auto;
  const std::string s = args.required("side");
  if (s == "left") return hawor::HandSide::Left;
  if (s == "right") return hawor::HandSide::Right;
  throw UsageError("--side must be 'left' or 'right', got '" + s + "'");
}

/// Folder of the running executable ("" when unknown).
inline std::string executableDir(const char* argv0) {
  std::string path;
#if defined(__linux__) && !defined(__EMSCRIPTEN__)
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n > 0) path.assign(buf, static_cast<size_t>(n));
#endif
  if (path.empty() && argv0) path = argv0;
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string(".") : path.substr(0, slash);
}

/// Where `--model default` looks after $HAWOR_HAND_DIR.
inline std::vector<std::string> defaultModelDirs(const char* argv0) {
  return {executableDir(argv0) + "/../models",
          "node_modules/@webxr-input-profiles/assets/dist/profiles/generic-hand"};
}

/// Loads --model FILE|default with --side (see kModelOptionHelp).
inline hawor::LoadedHandModel<double> loadModelOption(const Args& args, const char* argv0) {
  const std::string m = args.required("model");
  const hawor::HandSide side = sideOption(args);
  if (m == "default") {
    const hawor::HandSide s = side == hawor::HandSide::Auto ? hawor::HandSide::Right : side;
    return hawor::loadAnyHandModel<double>(hawor::findDefaultHandModel(s, defaultModelDirs(argv0)), s);
  }
  return hawor::loadAnyHandModel<double>(m, side);
}

inline const char* sideName(const hawor::HandModel<double>& m) { return m.isLeft ? "left" : "right"; }

/// One hand-parameter array of an npz: either one frame (the per-frame shape) or T frames
/// (a leading T axis). Absent arrays read as zeros.
struct ParamArray {
  std::string key;            ///< the key found ("" when absent)
  std::vector<double> values;
  size_t perFrame = 0;        ///< values per frame
  size_t frames = 0;          ///< T for a per-frame array, 0 for a single frame or absent

  bool present() const { return !key.empty(); }
  /// Values of frame t (a single-frame array serves every frame).
  const double* at(size_t t) const { return values.data() + (frames ? t * perFrame : 0); }
};

/// Reads the first of `keys` present in `z`, whose shape must be one of `single` (one frame) or
/// T followed by one of them (T frames); `expected` describes the shapes for the message.
inline ParamArray readParamArray(const hawor::Npz& z, const std::vector<std::string>& keys,
                                 const std::vector<std::vector<size_t>>& single, const std::string& expected) {
  ParamArray p;
  for (const std::string& k : keys) {
    if (!z.has(k)) continue;
    if (p.present()) {
      throw hawor::Error(z.source() + ": both '" + p.key + "' and '" + k + "' are present; give only one");
    }
    p.key = k;
  }
  if (!p.present()) return p;
  const std::vector<size_t>& s = z.get(p.key).shape;
  bool ok = false;
  for (const std::vector<size_t>& one : single) {
    if (s == one) {
      ok = true;
      p.frames = 0;
    } else if (s.size() == one.size() + 1 && s[0] > 0 && std::vector<size_t>(s.begin() + 1, s.end()) == one) {
      ok = true;
      p.frames = s[0];
    }
    if (ok) {
      p.perFrame = 1;
      for (size_t d : one) p.perFrame *= d;
      break;
    }
  }
  if (!ok) {
    throw hawor::Error(z.source() + ": '" + p.key + "' has shape " + hawor::shapeString(s) + ", expected " + expected);
  }
  p.values = z.getAs<double>(p.key);
  return p;
}

/// The hand parameters of an npz for a model with J joints and B shape coefficients:
///   rot       `global_orient` or `rot`    (3) or (T,3) axis-angle, radians
///   handPose  `hand_pose`                 ((J-1)*3), (J-1,3), (T,(J-1)*3) or (T,J-1,3)
///   betas     `betas`                     (b) or (T,b), b <= B
///   trans     `transl` or `trans`         (3) or (T,3) metres
/// Missing arrays are zeros; single-frame arrays serve every frame.
struct HandParams {
  ParamArray rot, handPose, betas, trans;  ///< HandPose's fields
  std::string source;

  /// T of the per-frame arrays (all equal, checked), 0 when every array is single-frame.
  size_t frames() const {
    size_t t = 0;
    for (const ParamArray* a : {&rot, &handPose, &betas, &trans}) t = a->frames > t ? a->frames : t;
    return t;
  }

  /// Whether every value of frame t is finite.
  bool finiteAt(size_t t) const {
    for (const ParamArray* a : {&rot, &handPose, &betas, &trans}) {
      if (!a->present()) continue;
      const double* v = a->at(t);
      for (size_t i = 0; i < a->perFrame; ++i) {
        if (!std::isfinite(v[i])) return false;
      }
    }
    return true;
  }

  /// The parameters of frame t; throws naming the file, key and frame for non-finite values.
  hawor::HandPose<double> at(size_t t, const hawor::HandModel<double>& m) const {
    hawor::HandPose<double> p = hawor::HandPose<double>::zero(m);
    const auto check = [&](const ParamArray& a) {
      const double* v = a.at(t);
      for (size_t i = 0; i < a.perFrame; ++i) {
        if (!std::isfinite(v[i])) {
          throw hawor::Error(source + ": '" + a.key + "' holds a non-finite value" +
                             (a.frames ? " at frame " + std::to_string(t) : std::string()) + " (element " +
                             std::to_string(i) + ")");
        }
      }
      return v;
    };
    if (rot.present()) {
      const double* v = check(rot);
      p.rot = hawor::Vec3<double>(v[0], v[1], v[2]);
    }
    if (handPose.present()) {
      const double* v = check(handPose);
      for (Eigen::Index i = 0; i < p.handPose.size(); ++i) p.handPose.data()[i] = v[i];  // row-major
    }
    if (betas.present()) {
      const double* v = check(betas);
      p.betas = hawor::VecX<double>::Zero(m.numBetas());
      for (size_t i = 0; i < betas.perFrame; ++i) p.betas(static_cast<Eigen::Index>(i)) = v[i];
    }
    if (trans.present()) {
      const double* v = check(trans);
      p.trans = hawor::Vec3<double>(v[0], v[1], v[2]);
    }
    return p;
  }
};

/// Reads the hand parameters of `z` (see HandParams) with the given key names for the global
/// orientation and the translation, and `prefix` before hand_pose and betas (a two-hand file's
/// "left_" / "right_"); checks shapes against the model and the frame counts.
inline HandParams readHandParams(const hawor::Npz& z, const hawor::HandModel<double>& m,
                                 const std::vector<std::string>& orientKeys,
                                 const std::vector<std::string>& translKeys, const std::string& prefix = "") {
  const std::string poseKey = prefix + "hand_pose", betasKey = prefix + "betas";
  const size_t J1 = static_cast<size_t>(m.numJoints() - 1), B = static_cast<size_t>(m.numBetas());
  HandParams h;
  h.source = z.source();
  h.rot = readParamArray(z, orientKeys, {{3}}, "(3) or (T,3)");
  h.handPose = readParamArray(z, {poseKey}, {{J1 * 3}, {J1, 3}},
                          "(" + std::to_string(J1 * 3) + "), (" + std::to_string(J1) + ",3) or with a leading T axis "
                          "(the model has " + std::to_string(J1 + 1) + " joints)");
  h.trans = readParamArray(z, translKeys, {{3}}, "(3) or (T,3)");
  if (z.has(betasKey)) {
    const std::vector<size_t>& s = z.get(betasKey).shape;
    const size_t b = s.empty() ? 0 : s.back();
    if (b > B) {
      throw hawor::Error(z.source() + ": '" + betasKey + "' has shape " + hawor::shapeString(s) + ": " + std::to_string(b) +
                         " shape coefficients, the model has " + std::to_string(B));
    }
    h.betas = readParamArray(z, {betasKey}, {{b}}, "(B) or (T,B) with B <= " + std::to_string(B));
  }
  size_t T = 0;
  std::string first;
  for (const ParamArray* a : {&h.rot, &h.handPose, &h.betas, &h.trans}) {
    if (!a->frames) continue;
    if (T && a->frames != T) {
      throw hawor::Error(z.source() + ": '" + first + "' has " + std::to_string(T) + " frames but '" + a->key +
                         "' has " + std::to_string(a->frames));
    }
    T = a->frames;
    first = a->key;
  }
  return h;
}

/// Optional (T,) validity `key` of an npz, 0/1 (bool, integer or float); all valid when absent.
inline std::vector<uint8_t> readValidFlags(const hawor::Npz& z, size_t frames, const std::string& key = "valid") {
  if (!z.has(key)) return std::vector<uint8_t>(frames, 1);
  const hawor::NpyArray& a = z.get(key);
  if (a.shape.size() != 1 || a.shape[0] != frames) {
    throw hawor::Error(z.source() + ": '" + key + "' must have shape (" + std::to_string(frames) + ",), got " +
                       hawor::shapeString(a.shape));
  }
  const std::vector<double> v = z.getAs<double>(key);
  std::vector<uint8_t> out(frames);
  for (size_t i = 0; i < frames; ++i) {
    if (v[i] != 0 && v[i] != 1) {
      throw hawor::Error(z.source() + ": '" + key + "' must hold 0/1, frame " + std::to_string(i) + " holds " +
                         std::to_string(v[i]));
    }
    out[i] = v[i] != 0;
  }
  return out;
}

/// "[[x, y, z], ...]" of an (N,3) array, 17 significant digits (JSON).
inline std::string jsonPoints(const hawor::Points3<double>& p) {
  std::string s = "[";
  char buf[96];
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    std::snprintf(buf, sizeof buf, "%s[%.17g, %.17g, %.17g]", i ? ", " : "", p(i, 0), p(i, 1), p(i, 2));
    s += buf;
  }
  return s + "]";
}

}  // namespace hawor_cli
