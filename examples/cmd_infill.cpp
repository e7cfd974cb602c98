// hawor infill — fills the frames where a hand was not observed (include/hawor/motion/infill.hpp).
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "cli_args.hpp"
#include "cli_hand.hpp"
#include "commands.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/load_model.hpp"
#include "hawor/hand/mirror.hpp"
#include "hawor/io/npz.hpp"
#include "hawor/motion/motion.hpp"
#include "hawor/motion/rest_root.hpp"
#include "hawor/motion/transformer_infill.hpp"
#include "hawor/parallel.hpp"

namespace hawor_cli {
namespace {

const char* kInfillHelp =
    "usage: hawor infill --in HANDS.npz --out FILLED.npz [--method last|lerp|spline|transformer]\n"
    "                    [--weights W.npz] [--threads N] [--smooth] [--model FILE|default] [--joints]\n"
    "\n"
    "Fills the frames where a hand was not observed, per hand, in the hand's canonical space\n"
    "(docs/design.md section 7). HANDS.npz holds, per hand (key prefix left_ and/or right_), the world-space\n"
    "keys of the original output:\n"
    "  trans      (T,3)    MANO translation, metres\n"
    "  rot        (T,3)    global orientation, axis-angle, radians\n"
    "  hand_pose  (T,3K) or (T,K,3)  joint axis-angles (MANO: K = 15; the default WebXR hand: 24)\n"
    "  betas      (T,B)    shape coefficients (MANO: B = 10; B may be 0)\n"
    "  valid      (T,)     1 = observed (bool, integer or float 0/1)\n"
    "Missing frames may hold anything (NaN included); observed frames must be finite. Both hands,\n"
    "when present, have the same T.\n"
    "\n"
    "  --method M     spline (default): the data-free cubic Hermite / SO(3) spline with boundary\n"
    "                 velocities from the visible frames; lerp: LERP/SLERP (the paper's baseline);\n"
    "                 last: repeat the last observed frame; transformer: the original infiller\n"
    "                 network (docs/design.md section 7) with --weights: both hands in 120-frame canonical\n"
    "                 windows, LERP/SLERP pre-fill, the network's output at the missing frames;\n"
    "                 MANO hands only (15 joint rotations, 10 betas); give --model for the exact\n"
    "                 canonical frame, as the network is not invariant to rigid motions\n"
    "  --weights W    the converted infiller weights (transformer only; README: tensor names)\n"
    "  --threads N    threads of the network's forward pass (transformer only; default 2)\n"
    "  --smooth       first smooth the observed frames lightly (each frame moves by at most\n"
    "                 3 noise sigmas, 1 cm, 0.05 rad); without it observed frames are copied bit\n"
    "                 for bit\n"
    "  --model M      a hand model (as for 'hawor hand'; FILE is mirrored for the other side,\n"
    "                 'default' = the shipped WebXR hands): joint 0 of the shaped rest hand (J0)\n"
    "                 then places the canonical frame exactly (docs/design.md section 3); without it J0 = 0,\n"
    "                 which changes nothing for last/lerp/spline (they commute with rigid motions)\n"
    "  --joints       also write <prefix>joints_world (T,K,3), the model's keypoints of the output\n"
    "                 parameters (needs --model; NaN where a frame stays unfilled)\n"
    "\n"
    "Writes FILLED.npz: per hand trans, rot, hand_pose (input layout), betas as float64 with the\n"
    "missing frames filled, valid as given, and <prefix>filled (T,) bool marking the filled\n"
    "frames; keys without a hand prefix are copied; other per-hand keys of the input (joints,\n"
    "camera-space copies, ...) describe the unfilled input and are not written. A hand with no\n"
    "observed frame is written unchanged with nothing filled (a note on stderr); one observed\n"
    "frame is held everywhere; a fully observed hand is unchanged. Prints one JSON object: method,\n"
    "smooth, per hand {frames, valid, filled}, out.\n";

const char* const kInfillSides[2] = {"left", "right"};

/// One hand's arrays as read from the file, and how to write them back.
struct InfillHandIn {
  bool present = false;
  hawor::HandMotion<double> motion;
  std::vector<size_t> poseShape;  ///< hand_pose as stored: (T,3K) or (T,K,3)
  hawor::NpyArray validArray;     ///< valid as stored (written back unchanged)
};

/// Rows of a (T,C) array (C = `cols`, or any when cols < 0) as a Sequence; names file and key.
hawor::Sequence<double> infillReadRows(const hawor::Npz& z, const std::string& key, size_t T, long cols,
                                       const std::string& expected) {
  const hawor::NpyArray& a = z.get(key);
  if (a.shape.size() != 2 || a.shape[0] != T || (cols >= 0 && a.shape[1] != static_cast<size_t>(cols)))
    throw hawor::Error(z.source() + ": '" + key + "' has shape " + hawor::shapeString(a.shape) + ", expected " +
                       expected);
  const std::vector<double> v = z.getAs<double>(key);
  hawor::Sequence<double> s(static_cast<Eigen::Index>(a.shape[0]), static_cast<Eigen::Index>(a.shape[1]));
  if (!v.empty()) std::copy(v.begin(), v.end(), s.data());
  return s;
}

/// The five keys of hand `side` ("left"/"right"); absent hand when none of them is present.
InfillHandIn infillReadHand(const hawor::Npz& z, const std::string& side) {
  const std::string p = side + "_";
  InfillHandIn h;
  const char* keys[5] = {"trans", "rot", "hand_pose", "betas", "valid"};
  std::string missing;
  for (const char* k : keys) {
    if (z.has(p + k))
      h.present = true;
    else
      missing += (missing.empty() ? "'" : ", '") + p + k + "'";
  }
  if (!h.present) return h;
  if (!missing.empty())
    throw hawor::Error(z.source() + ": the " + side + " hand lacks " + missing +
                       " (a hand needs trans, rot, hand_pose, betas and valid)");
  const hawor::NpyArray& va = z.get(p + "valid");
  if (va.shape.size() != 1)
    throw hawor::Error(z.source() + ": '" + p + "valid' must have shape (T,), got " + hawor::shapeString(va.shape));
  const size_t T = va.shape[0];
  h.validArray = va;
  const std::vector<double> v = z.getAs<double>(p + "valid");
  h.motion.valid.resize(T);
  for (size_t i = 0; i < T; ++i) {
    if (v[i] != 0 && v[i] != 1)
      throw hawor::Error(z.source() + ": '" + p + "valid' must hold 0/1, frame " + std::to_string(i) + " holds " +
                         std::to_string(v[i]));
    h.motion.valid[i] = v[i] != 0;
  }
  const std::string Ts = std::to_string(T);
  h.motion.trans = infillReadRows(z, p + "trans", T, 3, "(" + Ts + ",3)");
  h.motion.rot = infillReadRows(z, p + "rot", T, 3, "(" + Ts + ",3)");
  h.motion.betas = infillReadRows(z, p + "betas", T, -1, "(" + Ts + ",B)");
  const hawor::NpyArray& pa = z.get(p + "hand_pose");
  h.poseShape = pa.shape;
  if (pa.shape.size() == 3 && pa.shape[0] == T && pa.shape[2] == 3) {
    const std::vector<double> pv = z.getAs<double>(p + "hand_pose");
    h.motion.handPose.resize(static_cast<Eigen::Index>(T), static_cast<Eigen::Index>(3 * pa.shape[1]));
    if (!pv.empty()) std::copy(pv.begin(), pv.end(), h.motion.handPose.data());
  } else {
    if (pa.shape.size() != 2 || pa.shape[0] != T || pa.shape[1] % 3 != 0)
      throw hawor::Error(z.source() + ": '" + p + "hand_pose' has shape " + hawor::shapeString(pa.shape) +
                         ", expected (" + Ts + ",3K) or (" + Ts + ",K,3) (MANO: K = 15)");
    h.motion.handPose = infillReadRows(z, p + "hand_pose", T, -1, "");
  }
  try {
    h.motion.validate();
  } catch (const hawor::Error& e) {
    throw hawor::Error(z.source() + ": " + side + " hand: " + std::string(e.what()).substr(7));  // drop "hawor: "
  }
  return h;
}

/// Left and right models of --model (FILE: mirrored for the other side; default: both shipped).
void infillLoadModels(const Args& args, const char* argv0, std::array<hawor::HandModel<double>, 2>& models) {
  const std::string m = args.required("model");
  if (m == "default") {
    const std::vector<std::string> dirs = defaultModelDirs(argv0);
    models[1] = hawor::loadAnyHandModel<double>(hawor::findDefaultHandModel(hawor::HandSide::Right, dirs),
                                                hawor::HandSide::Right).model;
    try {
      models[0] = hawor::loadAnyHandModel<double>(hawor::findDefaultHandModel(hawor::HandSide::Left, dirs),
                                                  hawor::HandSide::Left).model;
    } catch (const hawor::Error&) {
      models[0] = hawor::mirrorHandModel(models[1]);
    }
    return;
  }
  hawor::LoadedHandModel<double> h = hawor::loadAnyHandModel<double>(m, hawor::HandSide::Auto);
  const int side = h.model.isLeft ? 0 : 1;
  models[static_cast<size_t>(1 - side)] = hawor::mirrorHandModel(h.model);
  models[static_cast<size_t>(side)] = std::move(h.model);
}

/// (T,K,3) keypoints of every frame whose parameters are finite (NaN elsewhere).
hawor::NpyArray infillJoints(const hawor::HandModel<double>& model, const hawor::HandMotion<double>& m,
                             const std::string& what) {
  const Eigen::Index J1 = model.numJoints() - 1, K = model.numKeypoints();
  if (m.handPose.cols() != 3 * J1)
    throw hawor::Error(what + ": hand_pose has " + std::to_string(m.handPose.cols() / 3) +
                       " joint rotations, the --model has " + std::to_string(J1) + " (--joints)");
  if (K == 0) throw hawor::Error("--joints: the --model has no keypoints");
  const Eigen::Index T = m.frames();
  std::vector<double> out(static_cast<size_t>(T * K * 3), std::numeric_limits<double>::quiet_NaN());
  hawor::HandWorkspace<double> ws;
  hawor::HandOutput<double> o;
  hawor::HandPose<double> pose = hawor::HandPose<double>::zero(model);
  for (Eigen::Index t = 0; t < T; ++t) {
    if (!m.rot.row(t).allFinite() || !m.trans.row(t).allFinite() || !m.handPose.row(t).allFinite() ||
        !m.betas.row(t).allFinite())
      continue;
    pose.rot = m.rot.row(t).transpose();
    pose.trans = m.trans.row(t).transpose();
    for (Eigen::Index j = 0; j < J1; ++j) pose.handPose.row(j) = m.handPose.row(t).segment(3 * j, 3);
    pose.betas = m.betas.row(t).transpose();
    hawor::forward(model, pose, ws, o);
    std::copy(o.keypoints.data(), o.keypoints.data() + 3 * K, out.begin() + t * K * 3);
  }
  return hawor::NpyArray::fromData(out.data(), {static_cast<size_t>(T), static_cast<size_t>(K), 3});
}

hawor::NpyArray infillRowsArray(const hawor::Sequence<double>& s, const std::vector<size_t>& shape) {
  return hawor::NpyArray::fromData(s.data(), shape);
}

}  // namespace

int cmdInfill(int argc, char** argv) {
  Args args(argc, argv, 2, {"in", "out", "method", "weights", "model", "threads"}, {"smooth", "joints"});
  if (args.help()) {
    std::fputs(kInfillHelp, stdout);
    return 0;
  }
  if (!args.positional().empty()) throw UsageError("unexpected argument '" + args.positional()[0] + "'");
  const std::string in = args.required("in"), out = args.required("out");
  const std::string method = args.get("method", "spline");
  if (method != "last" && method != "lerp" && method != "spline" && method != "transformer")
    throw UsageError("--method must be last, lerp, spline or transformer, got '" + method + "'");
  const bool transformer = method == "transformer";
  if (args.has("weights") && !transformer) throw UsageError("--weights is only used by --method transformer");
  if (args.has("threads") && !transformer) throw UsageError("--threads is only used by --method transformer");
  if (transformer && !args.has("weights")) throw UsageError("--method transformer needs --weights W.npz");
  if (args.flag("joints") && !args.has("model")) throw UsageError("--joints needs --model FILE|default");
  const double threadsArg = transformer ? args.number("threads", 2) : 1;
  if (threadsArg < 1 || threadsArg > 64 || threadsArg != std::floor(threadsArg))
    throw UsageError("--threads must be a whole number from 1 to 64");
  const long threads = static_cast<long>(threadsArg);
  hawor::InfillOptions<double> options;
  if (!transformer) options.method = hawor::parseInfillMethod(method);

  const hawor::Npz z = hawor::Npz::read(in);
  std::array<InfillHandIn, 2> hands = {infillReadHand(z, "left"), infillReadHand(z, "right")};
  if (!hands[0].present && !hands[1].present)
    throw hawor::Error(in + ": no hand found (expected left_* and/or right_* keys: trans, rot, hand_pose, betas, "
                       "valid)");
  if (hands[0].present && hands[1].present && hands[0].motion.frames() != hands[1].motion.frames())
    throw hawor::Error(in + ": the left hand has " + std::to_string(hands[0].motion.frames()) +
                       " frames, the right hand " + std::to_string(hands[1].motion.frames()));
  std::array<hawor::HandModel<double>, 2> models;
  const bool withModel = args.has("model");
  if (withModel) infillLoadModels(args, argv[0], models);
  // The network (read before any work, so a bad weights file fails fast).
  std::unique_ptr<hawor::InfillerNet<float>> net;
  if (transformer) net = std::make_unique<hawor::InfillerNet<float>>(hawor::InfillerNet<float>::read(args.required("weights")));

  // Per hand: the (optionally smoothed) motion and its rest joint 0.
  std::array<hawor::HandMotion<double>, 2> motion;
  std::array<hawor::Points3<double>, 2> J0;
  std::array<hawor::HandNoise<double>, 2> noise;
  std::array<bool, 2> smoothed = {false, false};
  for (size_t s = 0; s < 2; ++s) {
    J0[s] = hawor::Points3<double>::Zero(1, 3);
    if (!hands[s].present) continue;
    const std::string side = kInfillSides[s];
    motion[s] = hands[s].motion;
    const Eigen::Index nvalid = hawor::countValid(motion[s].valid);
    // --smooth: the gap filler keeps the noise levels of the raw observations (smoothing hides
    // the noise from its estimate, not from the boundary velocities).
    if (args.flag("smooth") && nvalid > 0) {
      noise[s] = hawor::estimateHandNoise(motion[s]);
      motion[s] = hawor::smoothObserved(motion[s]);
      smoothed[s] = true;
    }
    if (withModel && nvalid > 0) {
      // J0 of every frame from its (pre-filled, hence finite) betas.
      try {
        J0[s] = hawor::restRootJoints(models[s], motion[s]);
      } catch (const hawor::Error& e) {
        throw hawor::Error(in + ": " + side + " hand: " + std::string(e.what()).substr(7));  // drop "hawor: "
      }
    }
    if (nvalid == 0)
      std::fprintf(stderr, "hawor infill: %s hand: no observed frame, written unchanged (nothing filled)\n",
                   side.c_str());
  }

  std::array<hawor::InfillResult<double>, 2> result;
  if (transformer) {
    // Both hands in one window (docs/design.md §7); an absent hand enters as never observed.
    const size_t have = hands[0].present ? 0 : 1;
    for (size_t s = 0; s < 2; ++s) {
      if (hands[s].present) continue;
      const hawor::HandMotion<double>& o = motion[have];
      motion[s] = o;
      motion[s].valid.assign(o.valid.size(), 0);
    }
    hawor::ThreadPool pool(static_cast<int>(threads));
    hawor::TransformerWindowInfiller<double, float> pooled(*net, &pool);
    pooled.checkLayout(hawor::HandFeatureLayout::of(motion[0]));
    std::array<hawor::ValidMask, 2> filled;
    const std::array<hawor::HandMotion<double>, 2> r =
        hawor::infillWindowed(motion, J0, pooled, net->config().window, &filled);
    for (size_t s = 0; s < 2; ++s) result[s] = {r[s], filled[s]};
  } else {
    for (size_t s = 0; s < 2; ++s)
      if (hands[s].present)
        result[s] = hawor::infillHand(motion[s], J0[s], options, smoothed[s] ? &noise[s] : nullptr);
  }

  hawor::Npz outz;
  for (const std::string& name : z.names())
    if (name.rfind("left_", 0) != 0 && name.rfind("right_", 0) != 0) outz.set(name, z.get(name));
  JsonObject summary;
  summary.str("method", method).raw("smooth", args.flag("smooth") ? "true" : "false");
  if (transformer) summary.integer("threads", threads);
  for (size_t s = 0; s < 2; ++s) {
    if (!hands[s].present) continue;
    const std::string side = kInfillSides[s], p = side + "_";
    const hawor::InfillResult<double>& r = result[s];
    const Eigen::Index T = r.motion.frames();
    const size_t Tn = static_cast<size_t>(T);
    outz.set(p + "trans", infillRowsArray(r.motion.trans, {Tn, 3}));
    outz.set(p + "rot", infillRowsArray(r.motion.rot, {Tn, 3}));
    outz.set(p + "hand_pose", infillRowsArray(r.motion.handPose, hands[s].poseShape));
    outz.set(p + "betas", infillRowsArray(r.motion.betas, {Tn, static_cast<size_t>(r.motion.betas.cols())}));
    outz.set(p + "valid", hands[s].validArray);
    hawor::NpyArray filled = hawor::NpyArray::fromData(r.filled.data(), {Tn});
    filled.dtype = "|b1";
    outz.set(p + "filled", filled);
    if (args.flag("joints"))
      outz.set(p + "joints_world", infillJoints(models[s], r.motion, in + ": " + side + " hand"));
    summary.raw(side, JsonObject()
                          .integer("frames", static_cast<long long>(T))
                          .integer("valid", static_cast<long long>(hawor::countValid(hands[s].motion.valid)))
                          .integer("filled", static_cast<long long>(hawor::countValid(r.filled)))
                          .dump());
  }
  outz.write(out);
  summary.str("out", out);
  std::printf("%s\n", summary.dump().c_str());
  return 0;
}

}  // namespace hawor_cli
