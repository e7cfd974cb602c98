// hawor world — the world-space half of the method for camera-frame hands from any regressor
// (HaMeR, WiLoR, HaWoR's own network, hawor's fit): a folder of frames and a hands file in, the
// metric camera and both hands in the world out. A thin driver of pipeline/pipeline.hpp (the
// browser app and `node web/cli.mjs run` drive the same object through the WebAssembly core).
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cli_args.hpp"
#include "cli_hand.hpp"
#include "commands.hpp"
#include "hawor/geometry/camera_model.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/io/file.hpp"
#include "hawor/io/image_file.hpp"
#include "hawor/io/npz.hpp"
#include "hawor/io/tum.hpp"
#include "hawor/pipeline/pipeline.hpp"

namespace hawor_cli {
namespace {

const char* kWorldHelp =
    "usage: hawor world --images DIR --hands HANDS.npz [--hands-input auto|params|joints] --out DIR\n"
    "                   [--intrinsics fx,fy,cx,cy | --fov DEG]\n"
    "                   [--camera LENS] [--fps F] [--readout S] [--mano DIR] [--no-refine-focal]\n"
    "                   [--eye-height M] [--no-ground] [--infill spline|lerp|last] [--set NAME=VALUE,...]\n"
    "\n"
    "Camera-frame hands to a metric world: hand masks, masked SLAM, metric scale, camera -> world,\n"
    "infilling (docs/pipeline.md). The hands come from any regressor, in HANDS.npz per side\n"
    "(prefix left_ / right_; a side without keys was never seen; docs/pipeline.md#hands-file):\n"
    "MANO parameters:\n"
    "  <side>cam_rot (T,3)     axis-angle of the wrist, camera frame (x right, y down, z forward);\n"
    "                          or <side>global_orient\n"
    "  <side>cam_trans (T,3)   the model's translation, camera frame, metres; or <side>transl\n"
    "  <side>hand_pose (T,3K) or (T,K,3)   joint axis-angles (MANO: K = 15)\n"
    "  <side>betas (T,B) or (B,)           shape (optional: zeros)\n"
    "or 3D joints (the model is fitted to them and kept at their depth):\n"
    "  <side>joints_cam (T,21,3)  camera frame, metres, MediaPipe / OpenPose order\n"
    "and for both:\n"
    "  <side>valid (T,)        frames where the hand was seen (optional: frames with finite values)\n"
    "  image_size (2,)         width, height the hands were estimated on (optional, checked)\n"
    "--hands-input auto (default) takes the parameters when the file has them, else the joints.\n"
    "`hawor synth`'s hands_gt.npz has both.\n"
    "\n"
    "  --images DIR          the video's frames (.png/.jpg/.bmp) in file-name order, one per hand row\n"
    "  --intrinsics fx,fy,cx,cy  the camera's; else --fov DEG (diagonal, default 90) through the lens\n"
    "  --camera LENS         pinhole (default), opencv:k1,k2,p1,p2[,k3] or fisheye:k1,k2,k3,k4\n"
    "  --fps F               frame rate (default 30); --readout S: rolling-shutter readout time\n"
    "  --mano DIR            MANO_LEFT.pkl and MANO_RIGHT.pkl (default: the default hand, as\n"
    "                        `hawor hand --model default`); the hands' parameters are that model's\n"
    "  --no-refine-focal     keep the focal (default: the SLAM refines it; the given hands stay)\n"
    "  --eye-height M        the camera's height above the floor for the ground cue (default 1.6)\n"
    "  --no-ground           no ground cue (the scale from the hands alone)\n"
    "  --infill M            how unseen frames are filled (default spline)\n"
    "  --set NAME=VALUE,...  SLAM options (`hawor slam --set`)\n"
    "  --first-camera-world  the output in the first camera's frame (default: gravity-aligned,\n"
    "                        z up, the origin on the floor below the first camera when found)\n"
    "\n"
    "Writes DIR/world.npz (per side trans, rot, hand_pose, betas, joints_world, valid, infilled;\n"
    "timestamps, fps, z_up, origin_on_floor: the layout of the app's export), DIR/camera.tum\n"
    "(camera-to-world, metres, in that world) and prints one JSON object (frames, scale, method, confidence,\n"
    "intrinsics, SLAM counts, warnings).\n";

const char* const kSides[2] = {"left", "right"};

/// One side's camera-frame hands from the file: MANO parameters or 3D joints (none: never seen).
struct GivenHand {
  std::vector<hawor::HandPose<double>> poses;  ///< per frame, with parameters
  hawor::Points3<double> joints;               ///< (21·T, 3), with joints
  std::vector<char> valid;
  bool present() const { return !valid.empty(); }
};

enum class HandsInput { Auto, Params, Joints };

/// Side s's parameters (`<side>cam_rot` or `<side>global_orient`, `<side>cam_trans` or
/// `<side>transl`, `<side>hand_pose`, `<side>betas`) or joints (`<side>joints_cam`, (T,21,3)),
/// `<side>valid` when given, else the frames whose values are finite.
GivenHand readGivenHand(const hawor::Npz& z, const std::string& side, size_t T, const hawor::HandModel<double>& model, bool joints) {
  const std::string p = side + "_";
  GivenHand h;
  const bool given = z.has(p + "valid");
  if (joints) {
    const std::string key = p + "joints_cam";
    if (!z.has(key)) return h;
    const hawor::NpyArray& a = z.get(key);
    if (a.shape != std::vector<size_t>{T, 21, 3}) {
      throw hawor::Error(z.source() + ": '" + key + "' has shape " + hawor::shapeString(a.shape) + ", expected (" + std::to_string(T) + ", 21, 3)");
    }
    const std::vector<double> v = z.getAs<double>(key);
    h.joints = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(v.data(), static_cast<Eigen::Index>(21 * T), 3);
    h.valid.assign(T, 1);
    const std::vector<uint8_t> flags = readValidFlags(z, T, p + "valid");
    for (size_t t = 0; t < T; ++t) {
      const bool finite = h.joints.middleRows(static_cast<Eigen::Index>(21 * t), 21).allFinite();
      if (given && flags[t] && !finite) throw hawor::Error(z.source() + ": '" + key + "' holds a non-finite value at frame " + std::to_string(t) + ", marked valid");
      h.valid[t] = given ? flags[t] : finite;
    }
    return h;
  }
  const HandParams hp = readHandParams(z, model, {p + "cam_rot", p + "global_orient"}, {p + "cam_trans", p + "transl"}, p);
  if (!hp.rot.present() && !hp.trans.present() && !hp.handPose.present()) return h;
  for (const ParamArray* a : {&hp.rot, &hp.trans, &hp.handPose}) {
    if (!a->present()) {
      const std::string k = a == &hp.rot ? "cam_rot" : a == &hp.trans ? "cam_trans" : "hand_pose";
      throw hawor::Error(z.source() + ": the " + side + " hand lacks '" + p + k + "' (a hand needs cam_rot, cam_trans and hand_pose)");
    }
  }
  const std::vector<uint8_t> flags = readValidFlags(z, T, p + "valid");
  h.poses.resize(T);
  h.valid.assign(T, 0);
  for (size_t t = 0; t < T; ++t) {
    h.valid[t] = given ? flags[t] : hp.finiteAt(t);
    if (h.valid[t]) h.poses[t] = hp.at(t, model);  // throws naming the key and frame when not finite
  }
  return h;
}

void writeWorldNpz(const std::string& path, const hawor::PipelineResult<double>& r) {
  hawor::Npz z;
  const size_t T = static_cast<size_t>(r.frames);
  for (int s = 0; s < 2; ++s) {
    const std::string p = std::string(kSides[s]) + "_";
    const hawor::PipelineHand<double>& h = r.hands[s];
    z.set(p + "trans", hawor::NpyArray::fromData(h.world.trans.data(), {T, 3}));
    z.set(p + "rot", hawor::NpyArray::fromData(h.world.rot.data(), {T, 3}));
    z.set(p + "hand_pose", hawor::NpyArray::fromData(h.world.handPose.data(), {T, static_cast<size_t>(h.world.handPose.cols())}));
    z.set(p + "betas", hawor::NpyArray::fromData(h.world.betas.data(), {T, static_cast<size_t>(h.world.betas.cols())}));
    z.set(p + "joints_world", hawor::NpyArray::fromData(h.jointsWorld.data(), {T, 21, 3}));
    std::vector<uint8_t> v(h.valid.begin(), h.valid.end()), f(h.infilled.begin(), h.infilled.end());
    z.set(p + "valid", hawor::NpyArray::fromRaw("|b1", {T}, v));
    z.set(p + "infilled", hawor::NpyArray::fromRaw("|b1", {T}, f));
  }
  std::vector<double> stamps(T);
  for (size_t t = 0; t < T; ++t) stamps[t] = r.times[t];
  z.set("timestamps", hawor::NpyArray::fromVector(stamps));
  z.set("fps", hawor::NpyArray::fromData(&r.fps, {}));
  z.set("z_up", hawor::NpyArray::fromRaw("|b1", {}, {uint8_t(r.world.up != "none" ? 1 : 0)}));
  z.set("origin_on_floor", hawor::NpyArray::fromRaw("|b1", {}, {uint8_t(r.world.originOnFloor ? 1 : 0)}));
  z.write(path);
}

}  // namespace

int cmdWorld(int argc, char** argv) {
  const Args args(argc, argv, 2,
                  {"images", "hands", "hands-input", "out", "intrinsics", "fov", "camera", "fps", "readout", "mano", "eye-height", "infill", "set"},
                  {"no-refine-focal", "no-ground", "first-camera-world"});
  if (args.help()) {
    std::fputs(kWorldHelp, stdout);
    return 0;
  }
  const std::string dir = args.required("images"), handsPath = args.required("hands"), out = args.required("out");
  if (args.has("intrinsics") && args.has("fov")) throw UsageError("give --intrinsics or --fov, not both");
  const std::string inputName = args.get("hands-input", "auto");
  if (inputName != "auto" && inputName != "params" && inputName != "joints") throw UsageError("--hands-input must be auto, params or joints");
  const HandsInput input = inputName == "params" ? HandsInput::Params : inputName == "joints" ? HandsInput::Joints : HandsInput::Auto;
  const std::vector<std::string> names = hawor::listImageFiles(dir);
  if (names.empty()) throw hawor::Error("--images " + dir + ": no images (.png/.jpg/.bmp)");
  hawor::ImageU8 first = hawor::readImage(dir + "/" + names[0]);
  hawor::PipelineOptions<double> po;
  po.lens = args.get("camera", "pinhole");
  hawor::Lens<double> lens;
  try {
    lens = hawor::Lens<double>::parse(po.lens);
  } catch (const hawor::Error& e) {
    throw UsageError(std::string("--camera: ") + (e.what() + 7));
  }
  if (args.has("intrinsics")) {
    const std::vector<double> k = args.numbers("intrinsics", 4);
    po.camera.fx = k[0], po.camera.fy = k[1], po.camera.cx = k[2], po.camera.cy = k[3];
    po.userFocal = true;
  } else {
    const double fov = args.number("fov", 90.0);
    if (!(fov > 1 && fov < 179)) throw UsageError("--fov must be in (1, 179) degrees");
    po.camera = hawor::CameraModel<double>::fromFov(first.width, first.height, lens, fov).intrinsics;
  }
  po.camera.width = first.width, po.camera.height = first.height;
  po.fps = args.number("fps", 30.0);
  po.readout = args.number("readout", 0.0);
  po.refineFocal = !args.flag("no-refine-focal");
  po.eyeHeight = args.number("eye-height", 1.6);
  po.groundScale = !args.flag("no-ground");
  po.gravityAligned = !args.flag("first-camera-world");
  if (args.has("infill")) po.infill = hawor::parseInfillMethod(args.get("infill", "spline"));
  for (const std::string& s : args.all("set")) po.slamSet += (po.slamSet.empty() ? "" : ",") + s;
  try {
    po.validate();
  } catch (const hawor::Error& e) {
    throw UsageError(e.what() + 7);
  }
  hawor::LoadedHandModel<double> models[2];
  for (int s = 0; s < 2; ++s) {
    const hawor::HandSide side = s == 0 ? hawor::HandSide::Left : hawor::HandSide::Right;
    const std::string file = args.has("mano") ? args.get("mano", "") + (s == 0 ? "/MANO_LEFT.pkl" : "/MANO_RIGHT.pkl")
                                              : hawor::findDefaultHandModel(side, defaultModelDirs(argv[0]));
    models[s] = hawor::loadAnyHandModel<double>(file, side);
  }
  const hawor::Npz z = hawor::Npz::read(handsPath);
  const size_t T = names.size();
  if (z.has("image_size")) {
    const std::vector<double> sz = z.getAs<double>("image_size");
    if (sz.size() != 2 || sz[0] != first.width || sz[1] != first.height) {
      throw hawor::Error(handsPath + ": 'image_size' says the hands were estimated on other frames than the " + std::to_string(first.width) + "x" +
                         std::to_string(first.height) + " ones in " + dir);
    }
  }
  for (int s = 0; s < 2; ++s) {
    for (const std::string& k : z.names()) {
      const std::string p = std::string(kSides[s]) + "_";
      if (k.compare(0, p.size(), p) == 0 && z.get(k).ndim() >= 1 && z.get(k).shape[0] != T && k != p + "betas") {
        throw hawor::Error(handsPath + ": '" + k + "' has " + std::to_string(z.get(k).shape[0]) + " frames, " + dir + " has " + std::to_string(T) + " images");
      }
    }
  }
  GivenHand hands[2];
  bool joints = input == HandsInput::Joints;
  for (int s = 0; s < 2; ++s) hands[s] = readGivenHand(z, kSides[s], T, models[s].model, joints);
  if (input == HandsInput::Auto && !hands[0].present() && !hands[1].present()) {
    joints = true;  // auto: parameters when the file has them, else joints
    for (int s = 0; s < 2; ++s) hands[s] = readGivenHand(z, kSides[s], T, models[s].model, joints);
  }
  if (!hands[0].present() && !hands[1].present()) {
    throw hawor::Error(handsPath + (joints ? ": no hand joints (no left_joints_cam / right_joints_cam; see hawor world --help)"
                                           : ": no hand (no left_cam_rot / right_cam_rot ...; see hawor world --help)"));
  }
  hawor::Pipeline<double> p(po, models[0].model, models[1].model);
  for (size_t t = 0; t < T; ++t) {
    const hawor::ImageU8 img = t == 0 ? std::move(first) : hawor::readImage(dir + "/" + names[t]);
    if (joints) {
      hawor::Points3<double> X[2];
      std::array<const hawor::Points3<double>*, 2> given{nullptr, nullptr};
      for (int s = 0; s < 2; ++s) {
        if (!hands[s].present() || !hands[s].valid[t]) continue;
        X[s] = hands[s].joints.middleRows(static_cast<Eigen::Index>(21 * t), 21);
        given[static_cast<std::size_t>(s)] = &X[s];
      }
      p.pushJoints(img, given);
    } else {
      std::array<const hawor::HandPose<double>*, 2> given{nullptr, nullptr};
      for (int s = 0; s < 2; ++s) {
        if (hands[s].present() && hands[s].valid[t]) given[static_cast<std::size_t>(s)] = &hands[s].poses[t];
      }
      p.pushHands(img, given);
    }
  }
  const hawor::PipelineResult<double> r = p.finish();
  if (::mkdir(out.c_str(), 0755) != 0 && errno != EEXIST) throw hawor::Error("--out " + out + ": " + std::strerror(errno));
  writeWorldNpz(out + "/world.npz", r);
  std::vector<hawor::TumPose<double>> tum(static_cast<std::size_t>(r.frames));
  for (std::size_t t = 0; t < tum.size(); ++t) {
    tum[t].t = r.times[t];
    tum[t].q = hawor::matrixToQuaternion(Eigen::Matrix3d(r.cameraPoses[t].rotationMatrix()));
    tum[t].p = r.cameraPoses[t].translation();
  }
  hawor::writeTum(out + "/camera.tum", tum);
  JsonObject j;
  j.integer("frames", r.frames)
      .num("scale", r.scale)
      .str("method", r.scaleMethod)
      .num("confidence", r.scaleConfidence)
      .str("hand_cue", r.scaleCues.handsRan ? r.scaleCues.hands.method : std::string("none"))
      .num("hand_scale", r.scaleCues.handsRan ? r.scaleCues.hands.scale : NAN)
      .num("hand_confidence", r.scaleCues.handsRan ? r.scaleCues.hands.confidence : 0.0)
      .num("ground_scale", r.scaleCues.groundRan && r.scaleCues.ground.ok() ? r.scaleCues.groundUsed : NAN)
      .num("ground_confidence", r.scaleCues.groundRan && r.scaleCues.ground.ok() ? r.scaleCues.ground.confidence : 0.0)
      .str("world", r.world.up == "none" ? "first-camera" : "z-up")
      .str("up", r.world.up)
      .num("up_confidence", r.world.upConfidence)
      .str("origin", r.world.originOnFloor ? "floor" : "first-camera")
      .num("fx", r.camera.fx)
      .num("fy", r.camera.fy)
      .raw("focal_refined", r.focal.refined ? "true" : "false")
      .str("focal_reason", r.focal.reason)
      .raw("slam_initialised", r.slam.initialised ? "true" : "false")
      .integer("keyframes", r.slam.numKeyframes)
      .integer("lost_frames", r.slam.count(hawor::SlamStatus::Lost))
      .integer("left_valid", std::count(r.hands[0].valid.begin(), r.hands[0].valid.end(), 1))
      .integer("right_valid", std::count(r.hands[1].valid.begin(), r.hands[1].valid.end(), 1))
      .strings("warnings", r.warnings)
      .str("out", out);
  std::printf("%s\n", j.dump().c_str());
  return 0;
}

}  // namespace hawor_cli
