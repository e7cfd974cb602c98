// hawor scale — metric scale of a SLAM trajectory (include/hawor/scale): AdaSM on metric depth
// maps at the keyframes' sparse SLAM depths, the hand-anchored scale from camera-frame hands, the
// cameras' height above the map's floor plane, fused by confidence.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cli_args.hpp"
#include "commands.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/io/image_file.hpp"
#include "hawor/io/npy.hpp"
#include "hawor/io/npz.hpp"
#include "hawor/io/tum.hpp"
#include "hawor/scale/scale.hpp"
#include "hawor/scale/metric_scale.hpp"

namespace hawor_cli {
namespace {

const char* kScaleHelp =
    "usage: hawor scale --traj TRAJ.tum --keyframe-depths KD.npz [--metric-depth DIR_OF_NPY]\n"
    "                   [--masks DIR] [--hands HANDS_CAM.npz] [--intrinsics fx,fy,cx,cy]\n"
    "                   [--eye-height M] --out TRAJ_METRIC.tum\n"
    "                   [--near M] [--far M] [--sigma M] [--sampling official|slam-depth]\n"
    "                   [--combine huber|median] [--baseline]\n"
    "\n"
    "Scales a monocular trajectory to metres.\n"
    "  --traj TRAJ.tum        camera-to-world poses from 'hawor slam' (one per frame, in order)\n"
    "  --keyframe-depths KD.npz  'hawor slam --keyframe-depths': frames (K,), kf (N,), uv (N,2),\n"
    "                         depth (N,) SLAM depths at keyframe pixels\n"
    "  --metric-depth DIR     metric depth maps, DIR/<frame:06d>.npy float (H,W) metres (a depth\n"
    "                         network's output, or ground truth): AdaSM (near/far window,\n"
    "                         Geman-McClure sigma) on the keyframes' pixels, then over keyframes\n"
    "  --masks DIR            hand masks DIR/<frame:06d>.png (non-zero = hand): pixels dropped\n"
    "  --hands HANDS_CAM.npz  camera-frame hands: [left_|right_]joints_cam (T,21,3) metres and\n"
    "                         [left_|right_]valid (T,): the hand-anchored scale from the wrists\n"
    "                         (hands holding still while the head moves; else their smoothness)\n"
    "  --intrinsics fx,fy,cx,cy  the ground cue: the keyframe depths back-projected to map points;\n"
    "                         the cameras' median height above the lowest horizontal level (the\n"
    "                         floor) is --eye-height metres (scale/ground_scale.hpp)\n"
    "  --eye-height M         camera height above the floor (default 1.6: a standing adult's\n"
    "                         head-worn camera; about 1.2 sitting)\n"
    "  --sampling S           AdaSM's re-selection window on the metric depth and the scaled SLAM\n"
    "                         depth ('official', docs/design.md section 6) or on the scaled SLAM depth only\n"
    "                         plus a +-25 % gate about it ('slam-depth', default: no truncation\n"
    "                         bias with sparse depths; windows widened to 30 points, not 10)\n"
    "  --combine C            the keyframes' scales into one: 'huber' (default: Huber estimate of\n"
    "                         their log, ~1.3-1.7x less error than the median under per-frame\n"
    "                         depth bias) or 'median' (official)\n"
    "  --baseline             with --metric-depth: also report the plain median scale, the other\n"
    "                         sampling's scale (with the official median over keyframes when that\n"
    "                         is the official sampling) and this sampling's with the other --combine\n"
    "  --out TRAJ_METRIC.tum  the trajectory with positions multiplied by the scale\n"
    "\n"
    "Prints {\"scale\", \"method\" (depth|hands|ground|fused), \"confidence\", ...}. The cues that\n"
    "need no depth network (hands, ground) are combined first, a floor reading that could be a\n"
    "table top taking the reading the hands agree with; then that and the depth cue: in log space,\n"
    "weighted by their confidences. A cue that disagrees with the most confident one beyond both\n"
    "their errors is left out (\"left_out\").\n";

std::string frameName(int f, const char* ext) {
  char b[32];
  std::snprintf(b, sizeof b, "%06d%s", f, ext);
  return b;
}

bool exists(const std::string& p) {
  std::FILE* f = std::fopen(p.c_str(), "rb");
  if (!f) return false;
  std::fclose(f);
  return true;
}

}  // namespace

int cmdScale(int argc, char** argv) {
  const Args args(argc, argv, 2,
                  {"traj", "keyframe-depths", "metric-depth", "masks", "hands", "intrinsics", "eye-height", "out", "near", "far",
                   "sigma", "sampling", "combine"},
                  {"baseline"});
  if (args.help()) {
    std::fputs(kScaleHelp, stdout);
    return 0;
  }
  const std::vector<hawor::TumPose<double>> traj = hawor::readTum<double>(args.required("traj"));
  const std::string out = args.required("out");
  if (!args.has("metric-depth") && !args.has("hands") && !args.has("intrinsics")) {
    throw UsageError("give --metric-depth DIR, --hands HANDS_CAM.npz, --intrinsics fx,fy,cx,cy (the ground cue), or several");
  }
  if (traj.size() < 3) throw hawor::Error(args.required("traj") + ": need at least 3 poses");
  // Defaults of the library's one-call metric scale (scale/metric_scale.hpp): SLAM-depth
  // sampling with 30 points per window, Huber over keyframes, hold windows of half a second.
  hawor::MetricScaleOptions<double> opt;
  hawor::AdaptiveScaleOptions<double>& aopt = opt.depth;
  aopt.nearM = args.number("near", aopt.nearM);
  aopt.farM = args.number("far", aopt.farM);
  aopt.sigma = args.number("sigma", aopt.sigma);
  const std::string sampling = args.get("sampling", "slam-depth");
  if (sampling == "official") {
    aopt.sampling = hawor::AdaSmSampling::Official;
    aopt.minPixels = hawor::AdaptiveScaleOptions<double>().minPixels;
  } else if (sampling != "slam-depth") {
    throw UsageError("--sampling must be 'official' or 'slam-depth', not '" + sampling + "'");
  }
  const std::string combine = args.get("combine", "huber");
  if (combine == "median") {
    aopt.combine = hawor::KeyframeCombine::Median;
  } else if (combine != "huber") {
    throw UsageError("--combine must be 'huber' or 'median', not '" + combine + "'");
  }
  if (traj.size() >= 2 && traj[1].t > traj[0].t) opt.setFps(1.0 / (traj[1].t - traj[0].t));
  opt.ground.eyeHeight = args.number("eye-height", opt.ground.eyeHeight);
  if (!(opt.ground.eyeHeight > opt.ground.tableHeight)) {
    throw UsageError("--eye-height must exceed the table height (" + std::to_string(opt.ground.tableHeight) + " m)");
  }

  // Depth cue: each keyframe's sparse SLAM depths paired with its metric depth map (and mask).
  std::vector<hawor::KeyframeDepthPairs<double>> keyframes;
  std::vector<int> frames, kf;
  std::vector<double> uv, depth;
  if (args.has("metric-depth") || args.has("intrinsics")) {
    const std::string kdPath = args.required("keyframe-depths");
    const hawor::Npz kd = hawor::Npz::read(kdPath);
    for (const char* key : {"frames", "kf", "uv", "depth"}) {
      if (!kd.has(key)) throw hawor::Error(kdPath + ": missing array '" + key + "'");
    }
    frames = kd.get("frames").as<int>(kdPath + ": frames");
    kf = kd.get("kf").as<int>(kdPath + ": kf");
    uv = kd.get("uv").as<double>(kdPath + ": uv");
    depth = kd.get("depth").as<double>(kdPath + ": depth");
    if (kf.size() != depth.size() || uv.size() != 2 * depth.size()) {
      throw hawor::Error(kdPath + ": kf, uv and depth disagree in length");
    }
    for (std::size_t i = 0; i < kf.size(); ++i) {
      if (kf[i] < 0 || static_cast<std::size_t>(kf[i]) >= frames.size()) throw hawor::Error(kdPath + ": kf out of range");
    }
    for (int f : frames) {
      if (f < 0 || static_cast<std::size_t>(f) >= traj.size()) {
        throw hawor::Error(kdPath + ": keyframe " + std::to_string(f) + " is not a frame of the trajectory");
      }
    }
  }
  if (args.has("metric-depth")) {
    const std::string dir = args.required("metric-depth");
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const std::string p = dir + "/" + frameName(frames[k], ".npy");
      const hawor::NpyArray a = hawor::readNpyFile(p);
      if (a.ndim() != 2) throw hawor::Error(p + ": expected a (H,W) depth map");
      const int H = static_cast<int>(a.shape[0]), W = static_cast<int>(a.shape[1]);
      const std::vector<double> m = a.as<double>(p);
      hawor::ImageU8 mask;
      const std::string mp = args.get("masks", "") + "/" + frameName(frames[k], ".png");
      const bool haveMask = args.has("masks") && exists(mp);
      if (haveMask) {
        mask = hawor::readImage(mp, 1);
        if (mask.width != W || mask.height != H) throw hawor::Error(mp + ": mask size differs from the depth map " + p);
      }
      std::vector<double> kuv, kdepth;
      for (std::size_t i = 0; i < depth.size(); ++i) {
        if (kf[i] != static_cast<int>(k)) continue;
        kuv.push_back(uv[2 * i]), kuv.push_back(uv[2 * i + 1]), kdepth.push_back(depth[i]);
      }
      keyframes.push_back(hawor::pairKeyframeDepths(kuv.data(), kdepth.data(), kdepth.size(), m.data(), W, H,
                                                    haveMask ? mask.data.data() : nullptr));
    }
  }
  // Hand cue: the wrists (joint 0) of the camera-frame hands.
  std::vector<hawor::HandTrack<double>> tracks;
  if (args.has("hands")) {
    const std::string hp = args.required("hands");
    const hawor::Npz z = hawor::Npz::read(hp);
    for (const std::string prefix : {"left_", "right_", ""}) {
      if (!z.has(prefix + "joints_cam")) continue;
      const hawor::NpyArray& a = z.get(prefix + "joints_cam");
      if (a.ndim() != 3 || a.shape[2] != 3 || a.shape[0] != traj.size()) {
        throw hawor::Error(hp + ": " + prefix + "joints_cam must be (T,K,3) with T = " + std::to_string(traj.size()) +
                           " poses of the trajectory");
      }
      const std::vector<double> v = a.as<double>(hp + ": " + prefix + "joints_cam");
      std::vector<int> valid(traj.size(), 1);
      if (z.has(prefix + "valid")) valid = z.get(prefix + "valid").as<int>(hp + ": " + prefix + "valid");
      if (valid.size() != traj.size()) throw hawor::Error(hp + ": " + prefix + "valid has the wrong length");
      hawor::HandTrack<double> t;
      const std::size_t K = a.shape[1];
      for (std::size_t f = 0; f < traj.size(); ++f) {
        const double* p = v.data() + f * K * 3;  // joint 0: the wrist
        t.positionCam.emplace_back(p[0], p[1], p[2]);
        t.valid.push_back(valid[f] ? 1 : 0);
      }
      tracks.push_back(std::move(t));
      if (prefix.empty()) break;
    }
    if (tracks.empty()) throw hawor::Error(hp + ": no [left_|right_]joints_cam array");
  }
  std::vector<hawor::SE3<double>> poses;
  for (const auto& p : traj) poses.emplace_back(hawor::SO3<double>::fromQuaternion(Eigen::Quaterniond(p.q)), hawor::Vec3<double>(p.p));

  // Ground cue: the keyframes' depths back-projected into the world, p = T_w_c · (z·K⁻¹[u v 1]).
  std::vector<hawor::Vec3<double>> mapPoints;
  if (args.has("intrinsics")) {
    const std::vector<double> k = args.numbers("intrinsics", 4);
    if (!(k[0] > 0) || !(k[1] > 0)) throw UsageError("--intrinsics expects fx,fy,cx,cy with fx, fy > 0");
    hawor::PinholeCamera<double> cam;
    cam.fx = k[0], cam.fy = k[1], cam.cx = k[2], cam.cy = k[3];
    for (std::size_t i = 0; i < depth.size(); ++i) {
      const hawor::Vec3<double> xc = cam.unproject(hawor::Vec2<double>(uv[2 * i], uv[2 * i + 1]), depth[i]);
      mapPoints.push_back(poses[static_cast<std::size_t>(frames[static_cast<std::size_t>(kf[i])])] * xc);
    }
  }

  const hawor::MetricScaleResult<double> r = hawor::estimateMetricScale(keyframes, poses, tracks, opt, &mapPoints);
  JsonObject j;
  if (r.depthRan) {
    j.integer("keyframes", r.depth.keyframes).integer("keyframes_fitted", r.depth.fitted);
    if (r.depth.ok())
      j.num("depth_scale", r.depth.scale).num("depth_confidence", r.depthConfidence).num("depth_spread", r.depth.relativeSpread);
  }
  if (r.depthRan && args.flag("baseline")) {
    std::vector<std::vector<double>> d, D;
    std::vector<std::vector<char>> hand;
    for (const auto& k : keyframes) d.push_back(k.slam), D.push_back(k.metric), hand.push_back(k.masked);
    const hawor::SequenceScale<double> b = hawor::medianScale(d, D, &hand);
    if (b.ok()) j.num("median_scale", b.scale);
    hawor::AdaptiveScaleOptions<double> other = aopt;
    other.sampling = aopt.sampling == hawor::AdaSmSampling::Official ? hawor::AdaSmSampling::SlamDepth
                                                                     : hawor::AdaSmSampling::Official;
    other.minPixels = other.sampling == hawor::AdaSmSampling::Official ? 10 : 30;
    if (other.sampling == hawor::AdaSmSampling::Official) other.combine = hawor::KeyframeCombine::Median;
    const hawor::SequenceScale<double> o = hawor::adaptiveScale(d, D, &hand, other);
    if (o.ok()) j.num(other.sampling == hawor::AdaSmSampling::Official ? "official_scale" : "slam_depth_scale", o.scale);
    hawor::AdaptiveScaleOptions<double> swap = aopt;
    swap.combine = aopt.combine == hawor::KeyframeCombine::Huber ? hawor::KeyframeCombine::Median
                                                                 : hawor::KeyframeCombine::Huber;
    const hawor::SequenceScale<double> c = hawor::adaptiveScale(d, D, &hand, swap);
    if (c.ok()) j.num(swap.combine == hawor::KeyframeCombine::Huber ? "huber_combine_scale" : "median_combine_scale", c.scale);
  }
  if (r.handsRan) {
    j.str("hand_cue", r.hands.method).integer("hand_residuals", r.hands.residuals).integer("hand_rest", r.hands.restFrames);
    if (r.hands.ok()) j.num("hand_scale", r.hands.scale).num("hand_confidence", r.hands.confidence);
  }
  if (r.groundRan) {
    if (r.ground.ok()) {
      j.num("ground_scale", r.groundUsed).num("ground_confidence", r.ground.confidence).num("ground_floor_scale", r.ground.scale);
      j.integer("ground_floor_points", r.ground.floorPoints).integer("ground_levels", r.ground.levels);
      j.num("ground_floor_width", r.ground.floorWidth);
      j.raw("ground_ambiguous", r.ground.ambiguous ? "true" : "false");
      if (std::isfinite(r.ground.surfaceHeight)) j.num("ground_surface_m", r.ground.surfaceHeight);
    } else {
      j.str("ground_reason", r.ground.reason);
    }
  }
  const hawor::FusedScale<double>& fused = r.fused;
  if (!fused.ok()) {
    throw hawor::Error(
        "no metric scale could be estimated: no keyframe had usable metric depth, no hand held still while the "
        "camera moved nor gave a positive smoothness scale, and no floor was found in the map" +
        (r.groundRan ? " (" + r.ground.reason + ")" : std::string()));
  }
  const double scale = fused.scale;
  std::vector<hawor::TumPose<double>> scaled = traj;
  for (auto& p : scaled) p.p *= scale;
  hawor::writeTum(out, scaled);
  JsonObject head;
  head.num("scale", scale).str("method", fused.method).num("confidence", fused.confidence);
  std::vector<std::string> leftOut = r.noDepth.leftOut;
  leftOut.insert(leftOut.end(), fused.leftOut.begin(), fused.leftOut.end());
  if (!leftOut.empty()) head.strings("left_out", leftOut);  // cues inconsistent with the most confident
  std::string s = head.dump();
  const std::string rest = j.dump();
  if (rest.size() > 2) s = s.substr(0, s.size() - 1) + ", " + rest.substr(1);
  std::printf("%s\n", s.c_str());
  return 0;
}

}  // namespace hawor_cli
