// hawor demo — the built-in example: writes a ground-truth and an estimated sequence (camera
// trajectory as TUM, hand joints as npz) to a folder, then evaluates them with the same code as
// `hawor metrics`. A stand-in for the full video pipeline until it lands (README).
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "cli_args.hpp"
#include "commands.hpp"
#include "hawor/eval/eval.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/io/npz.hpp"
#include "hawor/io/tum.hpp"

namespace hawor_cli {
namespace {

const char* kDemoHelp =
    "usage: hawor demo [--out DIR] [--frames N] [--seed N]\n"
    "\n"
    "Writes a built-in example to DIR (default hawor-demo): camera_gt.tum, camera_est.tum,\n"
    "hands_gt.npz and hands_est.npz (joints_world, joints_cam, valid), where the estimate is\n"
    "the ground truth seen through an unknown scale, drift and noise. Then prints the camera\n"
    "and hand metrics as `hawor metrics camera|hands` would, as one JSON object.\n";

using Vec3 = hawor::Vec3<double>;
using Mat3 = hawor::Mat3<double>;

/// 21 keypoints (MediaPipe order) of an open right hand in its own frame, metres:
/// wrist at the origin, fingers along +y, palm facing +z.
hawor::Points3<double> restHand() {
  hawor::Points3<double> p(21, 3);
  p.row(0) << 0, 0, 0;
  const double base_x[5] = {-0.035, -0.022, 0.0, 0.02, 0.037};  // thumb .. pinky
  const double base_y[5] = {0.03, 0.09, 0.095, 0.09, 0.08};
  const double seg[5] = {0.03, 0.028, 0.03, 0.028, 0.022};
  for (int f = 0; f < 5; ++f)
    for (int k = 0; k < 4; ++k)
      p.row(1 + 4 * f + k) << base_x[f] * (f == 0 ? 1.0 + 0.3 * k : 1.0),
          base_y[f] + seg[f] * k - (f == 0 ? 0.04 : 0.0), 0.0;
  return p;
}

void makeDir(const std::string& d) {
  if (::mkdir(d.c_str(), 0755) != 0 && errno != EEXIST)
    throw hawor::Error("cannot create folder " + d);
}

}  // namespace

int cmdDemo(int argc, char** argv) {
  Args args(argc, argv, 2, {"out", "frames", "seed"}, {});
  if (args.help()) {
    std::fputs(kDemoHelp, stdout);
    return 0;
  }
  const std::string out = args.get("out", "hawor-demo");
  const int T = static_cast<int>(args.number("frames", 300));
  if (T < 10 || T > 100000) throw UsageError("--frames must be in [10, 100000]");
  std::mt19937 rng(static_cast<unsigned>(args.number("seed", 7)));
  std::normal_distribution<double> n01(0.0, 1.0);
  const double fps = 30.0;
  makeDir(out);

  // Ground truth: a head walking forward with sway and bob; one hand moving in front of it.
  // Estimate: camera seen at an unknown scale (0.8) with slow drift and 3 mm jitter; hand joints
  // with 6 mm camera-space noise, mapped to the world with the drifting camera.
  const hawor::Points3<double> hand = restHand();
  std::vector<hawor::TumPose<double>> cam_gt, cam_est;
  hawor::JointSequence<double> jw_gt(T, 63), jc_gt(T, 63), jw_est(T, 63), jc_est(T, 63);
  std::vector<double> valid(static_cast<size_t>(T), 1.0);
  for (int t = 0; t < T; ++t) {
    const double s = t / fps;
    const Vec3 yaw_pitch(0.12 * std::sin(0.9 * s), 0.25 * std::sin(0.5 * s) + 0.05, 0.02);
    const Mat3 R = hawor::axisAngleToMatrix(Vec3(yaw_pitch.y(), yaw_pitch.x(), yaw_pitch.z()));
    const Vec3 p(0.3 * std::sin(0.4 * s), 0.02 * std::sin(2 * M_PI * 1.8 * s), 0.45 * s);
    const Vec3 drift(0.004 * s, -0.002 * s * s, 0.003 * s);
    const Vec3 p_est = 0.8 * (p + drift + 0.003 * Vec3(n01(rng), n01(rng), n01(rng)));
    const Mat3 R_est = R * hawor::axisAngleToMatrix(Vec3(0.002 * s, 0.0, -0.001 * s));
    hawor::TumPose<double> g, e;
    g.t = e.t = s;
    g.q = hawor::matrixToQuaternion(R);
    g.p = p;
    e.q = hawor::matrixToQuaternion(R_est);
    e.p = p_est;
    cam_gt.push_back(g);
    cam_est.push_back(e);
    // The hand in the camera: in front, lower right, waving and turning.
    const Mat3 Rh = hawor::axisAngleToMatrix(Vec3(-1.2 + 0.3 * std::sin(1.3 * s), 0.4 * std::sin(0.7 * s), 0.2));
    const Vec3 th(0.08 + 0.06 * std::sin(1.1 * s), 0.12 + 0.03 * std::cos(1.7 * s), 0.42 + 0.05 * std::sin(0.6 * s));
    // Frames 140-169: the hand leaves the view (not valid in the ground truth's sense).
    if (t >= 140 && t < 170) valid[static_cast<size_t>(t)] = 0.0;
    for (int j = 0; j < 21; ++j) {
      const Vec3 xc = Rh * hand.row(j).transpose() + th;
      const Vec3 xc_est = xc + 0.006 * Vec3(n01(rng), n01(rng), n01(rng));
      const Vec3 xw = R * xc + p;
      const Vec3 xw_est = R_est * xc_est + p_est / 0.8;  // metric scale recovered, drift kept
      jc_gt.block<1, 3>(t, 3 * j) = xc.transpose();
      jw_gt.block<1, 3>(t, 3 * j) = xw.transpose();
      jc_est.block<1, 3>(t, 3 * j) = xc_est.transpose();
      jw_est.block<1, 3>(t, 3 * j) = xw_est.transpose();
    }
  }
  hawor::writeTum(out + "/camera_gt.tum", cam_gt);
  hawor::writeTum(out + "/camera_est.tum", cam_est);
  const std::vector<size_t> shape = {static_cast<size_t>(T), 21, 3};
  auto save = [&](const std::string& path, const hawor::JointSequence<double>& w,
                  const hawor::JointSequence<double>& c) {
    hawor::Npz z;
    z.set("joints_world", hawor::NpyArray::fromData(w.data(), shape));
    z.set("joints_cam", hawor::NpyArray::fromData(c.data(), shape));
    z.set("valid", hawor::NpyArray::fromData(valid.data(), {static_cast<size_t>(T)}));
    z.write(path, true);
  };
  save(out + "/hands_gt.npz", jw_gt, jc_gt);
  save(out + "/hands_est.npz", jw_est, jc_est);

  // Evaluate exactly as `hawor metrics camera` / `hawor metrics hands` do.
  hawor::Points3<double> g(T, 3), e(T, 3);
  for (int t = 0; t < T; ++t) {
    g.row(t) = cam_gt[static_cast<size_t>(t)].p.transpose();
    e.row(t) = cam_est[static_cast<size_t>(t)].p.transpose();
  }
  const auto mc = hawor::evaluateCameras(g, e);
  std::vector<uint8_t> mask(valid.begin(), valid.end());
  const auto mh = hawor::evaluateHands(jw_gt, jw_est, jc_gt, jc_est, mask, fps);
  std::fprintf(stderr,
               "hawor demo: wrote %s/{camera_gt,camera_est}.tum and {hands_gt,hands_est}.npz\n"
               "  evaluate them again with:\n"
               "    hawor metrics camera --gt %s/camera_gt.tum --est %s/camera_est.tum\n"
               "    hawor metrics hands --gt %s/hands_gt.npz --est %s/hands_est.npz\n",
               out.c_str(), out.c_str(), out.c_str(), out.c_str(), out.c_str());
  const std::string cam_json = JsonObject()
                                   .num("ate", mc.ate / hawor::kMetresToMm)
                                   .num("ate_s", mc.ate_s / hawor::kMetresToMm)
                                   .num("scale", mc.scale)
                                   .integer("n", static_cast<long long>(mc.n))
                                   .dump();
  const std::string hand_json = JsonObject()
                                    .num("pa_mpjpe", mh.pa_mpjpe)
                                    .num("auc", mh.auc)
                                    .num("w_mpjpe", mh.w_mpjpe)
                                    .num("wa_mpjpe", mh.wa_mpjpe)
                                    .num("rte", mh.rte)
                                    .num("accel", mh.accel)
                                    .integer("n", static_cast<long long>(mh.n))
                                    .dump();
  std::printf("%s\n", JsonObject().str("out", out).raw("camera", cam_json).raw("hands", hand_json).dump().c_str());
  return 0;
}

}  // namespace hawor_cli
