// hawor metrics camera|hands — the standard metrics (docs/design.md §8) of files on disk.
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "cli_args.hpp"
#include "cli_hand.hpp"
#include "commands.hpp"
#include "hawor/eval/eval.hpp"
#include "hawor/io/npz.hpp"
#include "hawor/io/tum.hpp"

namespace hawor_cli {
namespace {

const char* kCameraHelp =
    "usage: hawor metrics camera --gt GT.tum --est EST.tum [--max-dt SECONDS]\n"
    "\n"
    "Camera trajectory error. Both files are TUM trajectories ('t tx ty tz qx qy qz qw',\n"
    "camera-to-world). Frames are matched by timestamp (nearest, one-to-one, |dt| <= max-dt,\n"
    "default 0.01 s). Prints one JSON object, lengths in metres:\n"
    "  ate    mean position error after Sim(3) (Umeyama, with scale) alignment\n"
    "  ate_s  mean position error after SE(3) alignment (no scale: tests the metric scale)\n"
    "  scale  the Sim(3) scale mapping the estimate onto the ground truth\n"
    "  rot_mean_deg, rot_max_deg  camera rotation error (degrees) after the best global rotation\n"
    "         of the estimate's world (defined also when the positions carry no motion)\n"
    "  n      number of matched frames\n";

const char* kHandsHelp =
    "usage: hawor metrics hands --gt GT.npz --est EST.npz [--fps 30]\n"
    "                           [--model FILE|default [--side left|right]]\n"
    "\n"
    "Hand motion error. Each npz holds joints_world (T,21,3) and joints_cam (T,21,3) in metres\n"
    "and optionally valid (T,). A frame is evaluated when it is valid in both files (missing key:\n"
    "all frames valid).\n"
    "A file without joints_world or joints_cam may hold hand parameters instead, turned into the\n"
    "model's keypoints (MANO: 21, OpenPose order) by the forward pass of --model (a MANO .pkl /\n"
    ".npz, a hawor hand-model .npz, a skinned .glb or 'default'; --side as for 'hawor hand'):\n"
    "  rot or global_orient  (T,3) axis-angle of the wrist, world frame, radians\n"
    "  hand_pose             (T,(J-1)*3) or (T,J-1,3) joint axis-angles (MANO: 45)\n"
    "  betas                 (T,B') or (B') shape coefficients, B' <= the model's B; optional\n"
    "  trans or transl       (T,3) translation, world frame, metres\n"
    "  cam_rot, cam_trans    (T,3) each, optional: the same hand in the camera frame\n"
    "joints_world = forward(rot, hand_pose, betas, trans); joints_cam = forward(cam_rot, hand_pose,\n"
    "betas, cam_trans) when both cam_ keys are present, else joints_cam = joints_world (a static\n"
    "camera at the world origin, e.g. a 'hawor fit' output). Arrays present in a file are always\n"
    "used as they are; parameters are read only for the joints a file lacks, and only at the\n"
    "frames its own 'valid' marks valid (others may hold NaN). Prints one JSON object:\n"
    "  pa_mpjpe  per-frame similarity-Procrustes joint error, camera joints (mm)\n"
    "  auc       area under the PCK curve over 0-50 mm, 100 steps (camera joints, PA)\n"
    "  w_mpjpe   world joints, 100-frame chunks aligned (Sim3) on their first 2 frames (mm)\n"
    "  wa_mpjpe  world joints, 100-frame chunks aligned (Sim3) on the whole chunk (mm)\n"
    "  rte       root (joint 0) error after rigid alignment, % of the ground-truth path length\n"
    "  accel     acceleration error of the world joints (m/s^2) at --fps\n"
    "  n         number of evaluated frames\n";

int metricsCamera(int argc, char** argv) {
  Args args(argc, argv, 3, {"gt", "est", "max-dt"}, {});
  if (args.help()) {
    std::fputs(kCameraHelp, stdout);
    return 0;
  }
  if (!args.positional().empty()) throw UsageError("unexpected argument '" + args.positional()[0] + "'");
  const std::string gt_path = args.required("gt"), est_path = args.required("est");
  const double max_dt = args.number("max-dt", 0.01);
  if (max_dt <= 0) throw UsageError("--max-dt must be positive");
  const auto gt = hawor::readTum<double>(gt_path);
  const auto est = hawor::readTum<double>(est_path);
  const auto pairs = hawor::associateByTimestamp(gt, est, max_dt);
  if (pairs.size() < 3)
    throw hawor::Error("metrics camera: only " + std::to_string(pairs.size()) +
                       " frames of " + gt_path + " and " + est_path +
                       " match by timestamp (need at least 3; check --max-dt)");
  hawor::Points3<double> g(static_cast<Eigen::Index>(pairs.size()), 3), e(g.rows(), 3);
  std::vector<hawor::Mat3<double>> gR, eR;
  for (size_t k = 0; k < pairs.size(); ++k) {
    g.row(static_cast<Eigen::Index>(k)) = gt[pairs[k].first].p.transpose();
    e.row(static_cast<Eigen::Index>(k)) = est[pairs[k].second].p.transpose();
    gR.push_back(gt[pairs[k].first].q.toRotationMatrix());
    eR.push_back(est[pairs[k].second].q.toRotationMatrix());
  }
  const auto m = hawor::evaluateCameras(g, e);
  const auto r = hawor::rotationErrors(gR, eR);
  // The library reports millimetres (docs/design.md §8 tables); this command's contract is metres.
  std::printf("%s\n", JsonObject()
                          .num("ate", m.ate / hawor::kMetresToMm)
                          .num("ate_s", m.ate_s / hawor::kMetresToMm)
                          .num("scale", m.scale)
                          .num("rot_mean_deg", r.mean_deg)
                          .num("rot_max_deg", r.max_deg)
                          .integer("n", static_cast<long long>(m.n))
                          .dump()
                          .c_str());
  return 0;
}

/// (T,J,3) joints of an npz as a T×3J joint sequence; names the file and key in errors.
hawor::JointSequence<double> readJoints(const hawor::Npz& z, const std::string& key) {
  const hawor::NpyArray& a = z.get(key);
  if (a.shape.size() != 3 || a.shape[2] != 3)
    throw hawor::Error(z.source() + ": '" + key + "' must have shape (T,J,3), got " +
                       hawor::shapeString(a.shape));
  const std::vector<double> v = z.getAs<double>(key);
  hawor::JointSequence<double> s(static_cast<Eigen::Index>(a.shape[0]),
                                 static_cast<Eigen::Index>(a.shape[1] * 3));
  if (v.size()) std::copy(v.begin(), v.end(), s.data());
  return s;
}

/// Optional (T,) validity; all frames valid when the key is absent.
std::vector<uint8_t> readValid(const hawor::Npz& z, size_t frames) {
  if (!z.has("valid")) return std::vector<uint8_t>(frames, 1);
  const hawor::NpyArray& a = z.get("valid");
  if (a.shape.size() != 1 || a.shape[0] != frames)
    throw hawor::Error(z.source() + ": 'valid' must have shape (" + std::to_string(frames) +
                       ",), got " + hawor::shapeString(a.shape));
  const std::vector<double> v = z.getAs<double>("valid");
  std::vector<uint8_t> out(frames);
  for (size_t i = 0; i < frames; ++i) {
    if (v[i] != 0 && v[i] != 1)
      throw hawor::Error(z.source() + ": 'valid' must hold 0/1, frame " + std::to_string(i) +
                         " holds " + std::to_string(v[i]));
    out[i] = v[i] != 0;
  }
  return out;
}

/// The --model of `metrics hands`, for files that hold hand parameters instead of joints.
class ModelOnDemand {
 public:
  /// Loads --model when given (a bad path is an error even if no file needs the model).
  ModelOnDemand(const Args& args, const char* argv0) {
    if (args.has("model")) {
      model_ = loadModelOption(args, argv0).model;
      loaded_ = true;
    }
  }
  const hawor::HandModel<double>& get(const std::string& why) const {
    if (!loaded_) {
      throw hawor::Error(why + ": give joints_world/joints_cam, or hand parameters (rot, hand_pose, betas, trans) "
                         "with --model FILE|default (see 'hawor metrics hands --help')");
    }
    return model_;
  }

 private:
  hawor::HandModel<double> model_;
  bool loaded_ = false;
};

/// joints_world / joints_cam of an npz: the array when present, else the forward pass of its hand
/// parameters (see kHandsHelp) at the frames its own 'valid' marks valid, NaN elsewhere.
hawor::JointSequence<double> jointsOf(const hawor::Npz& z, const std::string& key, const ModelOnDemand& model) {
  if (z.has(key)) return readJoints(z, key);
  const hawor::HandModel<double>& m = model.get(z.source() + " has no '" + key + "'");
  const bool cam = key == "joints_cam" && (z.has("cam_rot") || z.has("cam_trans"));
  if (cam && !(z.has("cam_rot") && z.has("cam_trans"))) {
    throw hawor::Error(z.source() + ": 'cam_rot' and 'cam_trans' must be given together");
  }
  const std::vector<std::string> rotKeys = cam ? std::vector<std::string>{"cam_rot"}
                                               : std::vector<std::string>{"rot", "global_orient"};
  const std::vector<std::string> transKeys = cam ? std::vector<std::string>{"cam_trans"}
                                                 : std::vector<std::string>{"trans", "transl"};
  const HandParams p = readHandParams(z, m, rotKeys, transKeys);
  if (!p.rot.present() || !p.handPose.present() || !p.trans.present()) {
    throw hawor::Error(z.source() + " has no '" + key + "' and its hand parameters are incomplete: '" +
                       (cam ? "cam_rot" : "rot") + "', 'hand_pose' and '" + (cam ? "cam_trans" : "trans") +
                       "' are needed");
  }
  const size_t T = p.frames() ? p.frames() : 1;
  const std::vector<uint8_t> valid = readValidFlags(z, T);
  const Eigen::Index K = m.numKeypoints();
  if (K == 0) throw hawor::Error("metrics hands: the --model has no keypoints to compare");
  hawor::JointSequence<double> s(static_cast<Eigen::Index>(T), 3 * K);
  s.setConstant(std::numeric_limits<double>::quiet_NaN());
  hawor::HandWorkspace<double> ws;
  hawor::HandOutput<double> o;
  for (size_t t = 0; t < T; ++t) {
    if (!valid[t]) continue;
    hawor::forward(m, p.at(t, m), ws, o);
    s.row(static_cast<Eigen::Index>(t)) = Eigen::Map<const Eigen::RowVectorXd>(o.keypoints.data(), 3 * K);
  }
  return s;
}

int metricsHands(int argc, char** argv) {
  Args args(argc, argv, 3, {"gt", "est", "fps", "model", "side"}, {});
  if (args.help()) {
    std::fputs(kHandsHelp, stdout);
    return 0;
  }
  if (!args.positional().empty()) throw UsageError("unexpected argument '" + args.positional()[0] + "'");
  const double fps = args.number("fps", 30.0);
  if (fps <= 0) throw UsageError("--fps must be positive");
  const hawor::Npz gt = hawor::Npz::read(args.required("gt"));
  const hawor::Npz est = hawor::Npz::read(args.required("est"));
  sideOption(args);  // a bad --side is a usage error even without --model
  const ModelOnDemand model(args, argv[0]);
  const auto gt_world = jointsOf(gt, "joints_world", model), gt_cam = jointsOf(gt, "joints_cam", model);
  const auto est_world = jointsOf(est, "joints_world", model), est_cam = jointsOf(est, "joints_cam", model);
  for (const auto* s : {&gt_cam, &est_world, &est_cam}) {
    if (s->rows() != gt_world.rows() || s->cols() != gt_world.cols())
      throw hawor::Error("metrics hands: joints_world/joints_cam of " + gt.source() + " and " +
                         est.source() + " must all have the same shape (T,J,3)");
  }
  const size_t T = static_cast<size_t>(gt_world.rows());
  std::vector<uint8_t> valid = readValid(gt, T);
  const std::vector<uint8_t> valid_est = readValid(est, T);
  for (size_t i = 0; i < T; ++i) valid[i] = valid[i] && valid_est[i];
  const auto m = hawor::evaluateHands(gt_world, est_world, gt_cam, est_cam, valid, fps);
  std::printf("%s\n", JsonObject()
                          .num("pa_mpjpe", m.pa_mpjpe)
                          .num("auc", m.auc)
                          .num("w_mpjpe", m.w_mpjpe)
                          .num("wa_mpjpe", m.wa_mpjpe)
                          .num("rte", m.rte)
                          .num("accel", m.accel)
                          .integer("n", static_cast<long long>(m.n))
                          .dump()
                          .c_str());
  return 0;
}

}  // namespace

int cmdMetrics(int argc, char** argv) {
  const std::string sub = argc > 2 ? argv[2] : "";
  if (sub == "camera") return metricsCamera(argc, argv);
  if (sub == "hands") return metricsHands(argc, argv);
  if (sub == "--help" || sub == "-h") {
    std::printf("%s\n%s", kCameraHelp, kHandsHelp);
    return 0;
  }
  throw UsageError(sub.empty() ? "metrics needs 'camera' or 'hands'"
                               : "unknown metrics kind '" + sub + "' (camera or hands)");
}

}  // namespace hawor_cli
