// hawor synth — writes a synthetic egocentric sequence with ground truth (include/hawor/synth).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "cli_args.hpp"
#include "cli_hand.hpp"
#include "commands.hpp"
#include "hawor/hand/load_model.hpp"
#include "hawor/hand/mirror.hpp"
#include "hawor/hand/synthetic_hand.hpp"
#include "hawor/synth/synth.hpp"

namespace hawor_cli {
namespace {

const char* kSynthHelp =
    "usage: hawor synth --preset NAME --seed N [--frames N] [--size WxH] [--model FILE|default|synthetic]\n"
    "                   [--left-model FILE] [--fps F] [--noise SIGMA] [--capture PROFILE] [capture options]\n"
    "                   --out DIR\n"
    "       hawor synth --list\n"
    "\n"
    "Renders a synthetic egocentric sequence (a textured room, head-like camera motion, two\n"
    "articulated hands) with ground truth. The same preset, seed, options and hand models give\n"
    "the same bytes on every run.\n"
    "\n"
    "  --list                print the presets and the capture profiles, one a line ('preset NAME\n"
    "                        description' / 'capture NAME description'), and exit\n"
    "  --preset NAME         walk, table_work, fast_turns, pure_rotation, hands_cover\n"
    "  --seed N              integer in [0, 2^64)\n"
    "  --frames N            number of frames (default: the preset's, 300-360)\n"
    "  --size WxH            image size (default 640x480; 16..8192 per side)\n"
    "  --model FILE|default|synthetic\n"
    "                        the hands: 'default' (the default) = the shipped WebXR generic hands\n"
    "                        (hand_left/right.npz in $HAWOR_HAND_DIR or <hawor dir>/../models, or\n"
    "                        left/right.glb of the npm package); 'synthetic' = the built-in\n"
    "                        procedural MANO-like hand (no file needed); FILE = a MANO .pkl / .npz,\n"
    "                        a hawor hand-model .npz or a skinned .glb of one side, mirrored for\n"
    "                        the other side\n"
    "  --left-model FILE     a separate file for the left hand (e.g. MANO_LEFT.pkl)\n"
    "  --fps F               frame rate (default 30)\n"
    "  --noise SIGMA         pixel (read) noise in grey levels (default: the preset's, 1.5, or the\n"
    "                        capture profile's)\n"
    "  --out DIR             output folder (created)\n"
    "\n"
    "Capture (include/hawor/synth/capture.hpp): what a real camera does to the images; the ground\n"
    "truth stays exact (that of time frame/fps, the middle row's mid-exposure).\n"
    "  --capture PROFILE     clean (the default: the generator's own output), phone, action_cam, aria,\n"
    "                        low_light, webcam_360p ('hawor synth --list' describes them); the\n"
    "                        options below override the profile's settings\n"
    "\n"
    "Writes DIR/rgb/000000.png ..., DIR/mask/000000.png (0 background, 128 left hand, 255 right\n"
    "hand), DIR/depth/000000.npy (float32 metres along the optical axis), DIR/camera_gt.tum\n"
    "(camera-to-world, timestamps frame/fps; world = the room: z up, floor at z = 0), DIR/hands_gt.npz\n"
    "(left_/right_: trans, rot, hand_pose, betas, valid, joints_world, joints_cam, cam_rot,\n"
    "cam_trans, visible_pixels, kp_in_image (through the lens); timestamps), DIR/intrinsics.txt\n"
    "('fx fy cx cy width height fps'; with a capture profile other than clean a second line\n"
    "'lens SPEC'), DIR/capture.json (with capture effects: the settings, the encoding for\n"
    "benchmarks with its ffmpeg arguments, per-frame sub-frames and gains) and DIR/meta.json.\n"
    "Prints one JSON object: preset, capture, lens, seed, frames, width, height, fps,\n"
    "coverage_max / coverage_mean (hand pixels / image), frames_coverage_20 (frames with hands on\n"
    ">= 20 % of the image), valid_left / valid_right (frames), subframes_mean, render_ms_mean,\n"
    "render_ms_median, render_ms_p95, write_ms_median, out.\n";

/// The help lines of the capture options (from capture.hpp's field table).
std::string captureOptionsHelp() {
  std::string h;
  for (const hawor::synth::CaptureField& f : hawor::synth::captureFields()) {
    std::string head = std::string("  --") + f.name + " " + f.value;
    if (head.size() < 24) head.resize(24, ' ');
    else head += "\n" + std::string(24, ' ');
    h += head + f.help + "\n";
  }
  return h;
}

/// A non-negative decimal integer <= maxValue (no sign, no spaces).
std::uint64_t parseUnsigned(const std::string& s, const std::string& what, std::uint64_t maxValue) {
  if (s.empty() || s.size() > 20) throw UsageError(what + " expects a non-negative integer, got '" + s + "'");
  std::uint64_t v = 0;
  for (char c : s) {
    if (c < '0' || c > '9') throw UsageError(what + " expects a non-negative integer, got '" + s + "'");
    const std::uint64_t d = static_cast<std::uint64_t>(c - '0');
    if (v > (maxValue - d) / 10) throw UsageError(what + " is too large: '" + s + "' (at most " + std::to_string(maxValue) + ")");
    v = v * 10 + d;
  }
  return v;
}

/// The left and right hand models of --model / --left-model.
void loadHands(const Args& args, const char* argv0, hawor::HandModel<double>& left, hawor::HandModel<double>& right,
               std::string& leftSource, std::string& rightSource) {
  const std::string m = args.get("model", "default");
  auto other = [](const hawor::HandModel<double>& h) { return hawor::mirrorHandModel(h); };
  if (m == "synthetic") {
    right = hawor::makeSyntheticHand<double>();
    left = other(right);
    rightSource = "synthetic";
    leftSource = "synthetic (mirrored)";
  } else if (m == "default") {
    const std::vector<std::string> dirs = defaultModelDirs(argv0);
    rightSource = hawor::findDefaultHandModel(hawor::HandSide::Right, dirs);
    right = hawor::loadAnyHandModel<double>(rightSource, hawor::HandSide::Right).model;
    try {
      leftSource = hawor::findDefaultHandModel(hawor::HandSide::Left, dirs);
      left = hawor::loadAnyHandModel<double>(leftSource, hawor::HandSide::Left).model;
    } catch (const hawor::Error&) {
      left = other(right);
      leftSource = rightSource + " (mirrored)";
    }
  } else {
    hawor::LoadedHandModel<double> h = hawor::loadAnyHandModel<double>(m, hawor::HandSide::Auto);
    if (h.model.isLeft) {
      left = std::move(h.model);
      right = other(left);
      leftSource = m;
      rightSource = m + " (mirrored)";
    } else {
      right = std::move(h.model);
      left = other(right);
      rightSource = m;
      leftSource = m + " (mirrored)";
    }
  }
  if (args.has("left-model")) {
    const std::string f = args.required("left-model");
    left = hawor::loadAnyHandModel<double>(f, hawor::HandSide::Left).model;
    leftSource = f;
  }
}

}  // namespace

int cmdSynth(int argc, char** argv) {
  std::set<std::string> valued = {"preset", "seed", "frames", "size", "model", "left-model", "fps", "noise", "out", "capture"};
  for (const hawor::synth::CaptureField& f : hawor::synth::captureFields()) valued.insert(f.name);
  Args args(argc, argv, 2, valued, {"list"});
  if (args.help()) {
    const std::string help = kSynthHelp;
    const std::size_t at = help.find("\nWrites DIR/");
    std::fputs((help.substr(0, at) + captureOptionsHelp() + help.substr(at)).c_str(), stdout);
    return 0;
  }
  if (!args.positional().empty()) throw UsageError("unexpected argument '" + args.positional()[0] + "'");
  if (args.flag("list")) {
    if (args.has("preset") || args.has("out") || args.has("capture")) throw UsageError("--list takes no other options");
    for (const hawor::synth::SynthPreset& p : hawor::synth::synthPresets()) {
      std::printf("preset  %-14s %s\n", p.name.c_str(), p.description.c_str());
    }
    for (const hawor::synth::CaptureProfile& p : hawor::synth::captureProfiles()) {
      std::printf("capture %-14s %s\n", p.name.c_str(), p.description.c_str());
    }
    return 0;
  }
  const std::string presetName = args.required("preset");
  hawor::synth::SynthPreset preset;
  try {
    preset = hawor::synth::findSynthPreset(presetName);
  } catch (const hawor::Error& e) {
    throw UsageError(std::string(e.what()).substr(7) + "; 'hawor synth --list' prints them");  // drop "hawor: "
  }
  const std::uint64_t seed = parseUnsigned(args.required("seed"), "--seed", ~std::uint64_t(0));
  const std::string out = args.required("out");
  hawor::synth::SynthOptions opt;
  if (args.has("frames")) {
    opt.frames = static_cast<int>(parseUnsigned(args.required("frames"), "--frames", 1000000));
    if (opt.frames < 1) throw UsageError("--frames must be at least 1");
  }
  if (args.has("size")) {
    const std::string s = args.required("size");
    const std::size_t x = s.find('x');
    if (x == std::string::npos) throw UsageError("--size expects WxH (e.g. 640x480), got '" + s + "'");
    opt.width = static_cast<int>(parseUnsigned(s.substr(0, x), "--size width", 100000));
    opt.height = static_cast<int>(parseUnsigned(s.substr(x + 1), "--size height", 100000));
    if (opt.width < 16 || opt.height < 16 || opt.width > 8192 || opt.height > 8192) {
      throw UsageError("--size: each side must be in 16..8192 pixels, got '" + s + "'");
    }
  }
  opt.fps = args.number("fps", 30);
  if (!(opt.fps > 0 && opt.fps <= 1000)) throw UsageError("--fps must be in (0, 1000]");
  // The capture profile, then the options that override its fields.
  hawor::synth::CaptureOptions& cap = opt.capture;
  if (args.has("capture")) {
    try {
      cap = hawor::synth::findCaptureProfile(args.required("capture"));
    } catch (const hawor::Error& e) {
      throw UsageError(std::string(e.what()).substr(7) + "; 'hawor synth --list' prints them");  // drop "hawor: "
    }
  }
  std::string changed;
  for (const hawor::synth::CaptureField& f : hawor::synth::captureFields()) {
    if (!args.has(f.name)) continue;
    try {
      hawor::synth::setCaptureField(cap, f.name, args.required(f.name));
    } catch (const hawor::Error& e) {
      throw UsageError("--" + std::string(f.name) + ": " + std::string(e.what()).substr(7));
    }
    changed += (changed.empty() ? "+" : ",") + std::string(f.name);
  }
  if (args.has("noise")) {
    const double n = args.number("noise", 0);
    if (!(n >= 0 && n <= 100)) throw UsageError("--noise must be in [0, 100] grey levels");
    opt.noiseSigma = static_cast<float>(n);
    if (cap.readNoise >= 0 && !args.has("read-noise")) cap.readNoise = n;  // explicit beats the profile
  }
  cap.profile += changed;
  try {
    cap.validate();
    hawor::synth::lensIntrinsics<double>(opt.width, opt.height, cap.fovDeg > 0 ? cap.fovDeg : opt.fovDeg, cap.lens);
  } catch (const hawor::Error& e) {
    throw UsageError(std::string(e.what()).substr(7));
  }
  const double interval = 1.0 / opt.fps;
  if (cap.exposure > interval) throw UsageError("--exposure " + args.get("exposure", std::to_string(cap.exposure)) +
                                                " s exceeds the frame interval at --fps " + std::to_string(opt.fps));
  if (cap.readout > interval) throw UsageError("--readout " + args.get("readout", std::to_string(cap.readout)) +
                                               " s exceeds the frame interval at --fps " + std::to_string(opt.fps));
  const std::string model = args.get("model", "default");
  if (model.empty()) throw UsageError("--model needs a file, 'default' or 'synthetic'");

  hawor::HandModel<double> left, right;
  std::string leftSource, rightSource;
  loadHands(args, argv[0], left, right, leftSource, rightSource);
  hawor::synth::SynthSequence<double> seq(preset, seed, left, right, opt);
  hawor::synth::SynthWriteOptions wo;
  wo.meta = {{"hand_model_left", leftSource}, {"hand_model_right", rightSource}};
  const hawor::synth::SynthWriteSummary sum = hawor::synth::writeSynthSequence(seq, out, wo);

  auto mean = [](const std::vector<double>& v) {
    double t = 0;
    for (double x : v) t += x;
    return v.empty() ? 0.0 : t / static_cast<double>(v.size());
  };
  double subframes = 0;
  for (int i = 0; i < sum.frames; ++i) subframes += sum.subframes[static_cast<std::size_t>(i)];
  JsonObject j;
  j.str("preset", preset.name)
      .str("capture", cap.profile)
      .str("lens", seq.lensDouble().toString())
      .raw("seed", std::to_string(seed))
      .integer("frames", sum.frames)
      .integer("width", seq.camera().width)
      .integer("height", seq.camera().height)
      .num("fps", seq.fps())
      .num("coverage_max", sum.coverageMax)
      .num("coverage_mean", sum.coverageMean)
      .integer("frames_coverage_20", sum.framesCovered20)
      .integer("valid_left", sum.validFrames[0])
      .integer("valid_right", sum.validFrames[1])
      .num("subframes_mean", sum.frames > 0 ? subframes / sum.frames : 0)
      .num("render_ms_mean", mean(sum.renderMs))
      .num("render_ms_median", hawor::percentile(sum.renderMs, 0.5))
      .num("render_ms_p95", hawor::percentile(sum.renderMs, 0.95))
      .num("write_ms_median", hawor::percentile(sum.writeMs, 0.5))
      .str("out", out);
  std::printf("%s\n", j.dump().c_str());
  return 0;
}

}  // namespace hawor_cli
