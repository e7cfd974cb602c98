// hawor fit — per-frame fit of a hand model to keypoint observations (hand/fit.hpp), over a
// sequence, each frame warm-started from the previous one. With a lens (--camera) the 2D
// keypoints are undistorted first (CameraModel::undistortPixel) and the pinhole fit runs in the
// pinhole camera with the same intrinsics: the same rays, so the fitted hand is exact.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "cli_args.hpp"
#include "cli_hand.hpp"
#include "commands.hpp"
#include "hawor/geometry/camera_model.hpp"
#include "hawor/hand/fit.hpp"
#include "hawor/hand/load_model.hpp"
#include "hawor/io/npz.hpp"

namespace hawor_cli {
namespace {

const char* kFitHelpHead =
    "usage: hawor fit --model FILE|default [--side left|right] --obs KEYPOINTS.npz\n"
    "                 --intrinsics fx,fy,cx,cy [--camera LENS] --out FIT.npz [--cold]\n"
    "\n"
    "Fits the hand model's pose, shape, global rotation and metric camera-frame translation to\n"
    "each frame's keypoints (Levenberg-Marquardt, robust 2D term, centred 3D term, joint limits;\n"
    "include/hawor/hand/fit.hpp). Each frame starts from the previous frame's solution; a frame\n"
    "after a skipped or failed one starts cold.\n"
    "\n";

const char* kFitHelpTail =
    "  --obs KEYPOINTS.npz   observations, K = the model's keypoints (21, MediaPipe order):\n"
    "                          keypoints2d   (T,K,2) pixels (OpenCV: origin top-left, pixel\n"
    "                                        centres at integers)\n"
    "                          confidence2d  (T,K) in [0,1], optional (default 1; 0 = unused,\n"
    "                                        and its keypoint may then be NaN)\n"
    "                          keypoints3d   (T,K,3) metres, camera-aligned axes, any origin,\n"
    "                                        optional (e.g. MediaPipe's world landmarks)\n"
    "                          confidence3d  (T,K) in [0,1], optional\n"
    "                          valid         (T,) 0/1, optional: frames with 0 are skipped\n"
    "  --intrinsics fx,fy,cx,cy  intrinsics in pixels\n"
    "  --camera LENS         the lens: pinhole (default), opencv:k1,k2,p1,p2[,k3] or\n"
    "                        fisheye:k1,k2,k3,k4; the keypoints (raw image pixels) are\n"
    "                        undistorted to the pinhole camera with the same intrinsics, where\n"
    "                        the fit runs (reproj_rms_px is in its pixels); a keypoint the lens\n"
    "                        cannot undistort (beyond its fold, or 90 degrees or more off the\n"
    "                        axis) is left out, as with confidence 0\n"
    "  --cold                start every frame cold (no warm start)\n"
    "  --out FIT.npz         the result, float64 unless noted, NaN at frames not fitted:\n"
    "                          rot (T,3) axis-angle, hand_pose (T,(J-1)*3), betas (T,B),\n"
    "                          trans (T,3) metres (camera frame; MANO rotates about joint 0, so\n"
    "                          trans is not the wrist position), joints_cam (T,K,3) fitted\n"
    "                          keypoints in metres, valid (T,) uint8, reproj_rms_px (T,),\n"
    "                          iterations (T,) int32\n"
    "\n"
    "Prints one JSON object: model, kind, side, camera, frames, fitted, skipped (valid = 0),\n"
    "failed (the fit threw: see stderr), keypoints_outside_lens, median_reproj_rms_px and\n"
    "median_ms_per_frame over fitted frames.\n";

/// An optional (T,K,...) float array of the observations, checked against its shape.
std::vector<double> readObsArray(const hawor::Npz& z, const std::string& key, const std::vector<size_t>& shape) {
  if (!z.has(key)) return {};
  const std::vector<size_t>& s = z.get(key).shape;
  if (s != shape) {
    throw hawor::Error(z.source() + ": '" + key + "' has shape " + hawor::shapeString(s) + ", expected " +
                       hawor::shapeString(shape));
  }
  return z.getAs<double>(key);
}

/// Confidences must lie in [0,1].
void checkConfidence(const hawor::Npz& z, const std::string& key, const std::vector<double>& c,
                     const std::vector<uint8_t>& valid, size_t K) {
  for (size_t i = 0; i < c.size(); ++i) {
    if (!valid[i / K]) continue;
    if (!(c[i] >= 0 && c[i] <= 1)) {
      throw hawor::Error(z.source() + ": '" + key + "' frame " + std::to_string(i / K) + " keypoint " +
                         std::to_string(i % K) + " is " + std::to_string(c[i]) + ", expected a value in [0,1]");
    }
  }
}

}  // namespace

int cmdFit(int argc, char** argv) {
  Args args(argc, argv, 2, {"model", "side", "obs", "intrinsics", "camera", "out"}, {"cold"});
  if (args.help()) {
    std::printf("%s%s%s", kFitHelpHead, kModelOptionHelp, kFitHelpTail);
    return 0;
  }
  if (!args.positional().empty()) throw UsageError("unexpected argument '" + args.positional()[0] + "'");
  args.required("model");
  const std::string obsPath = args.required("obs"), out = args.required("out");
  const std::vector<double> K4 = args.numbers("intrinsics", 4);
  if (!(K4[0] > 0) || !(K4[1] > 0)) throw UsageError("--intrinsics: fx and fy must be > 0");
  hawor::Lens<double> lens;
  try {
    lens = hawor::Lens<double>::parse(args.get("camera", "pinhole"));
    lens.validate(0.0);  // the coefficients alone: the keypoints are checked one by one
  } catch (const hawor::Error& e) {
    throw UsageError(std::string("--camera: ") + (e.what() + 7));  // without "hawor: "
  }
  hawor::PinholeCamera<double> cam;
  cam.fx = K4[0];
  cam.fy = K4[1];
  cam.cx = K4[2];
  cam.cy = K4[3];
  // The fit never uses the image size; an image centred on the principal point satisfies validate().
  cam.width = static_cast<int>(std::max(1.0, std::min(1e9, std::round(2 * cam.cx + 1))));
  cam.height = static_cast<int>(std::max(1.0, std::min(1e9, std::round(2 * cam.cy + 1))));

  const hawor::LoadedHandModel<double> loaded = loadModelOption(args, argv[0]);
  const hawor::HandModel<double>& m = loaded.model;
  const size_t K = static_cast<size_t>(m.numKeypoints());
  if (K == 0) {
    throw hawor::Error(loaded.source + ": the model has no keypoints to fit (a MANO model, or a glTF hand whose "
                       "joints carry the WebXR names, has the 21 MediaPipe keypoints)");
  }

  // --- observations ---------------------------------------------------------------------------
  const hawor::Npz z = hawor::Npz::read(obsPath);
  const std::vector<size_t>& s2 = z.get("keypoints2d").shape;
  if (s2.size() != 3 || s2[1] != K || s2[2] != 2) {
    throw hawor::Error(z.source() + ": 'keypoints2d' has shape " + hawor::shapeString(s2) + ", expected (T," +
                       std::to_string(K) + ",2) (the model has " + std::to_string(K) + " keypoints)");
  }
  const size_t T = s2[0];
  std::vector<double> kp2 = z.getAs<double>("keypoints2d");
  std::vector<double> c2 = readObsArray(z, "confidence2d", {T, K});
  std::vector<double> kp3 = readObsArray(z, "keypoints3d", {T, K, 3});
  const std::vector<double> c3 = readObsArray(z, "confidence3d", {T, K});
  if (!c3.empty() && kp3.empty()) throw hawor::Error(z.source() + ": 'confidence3d' is given without 'keypoints3d'");
  const std::vector<uint8_t> valid = readValidFlags(z, T);
  checkConfidence(z, "confidence2d", c2, valid, K);
  checkConfidence(z, "confidence3d", c3, valid, K);
  // Non-finite keypoints are allowed only where their confidence is 0 (then they are unused).
  const auto checkFinite = [&](std::vector<double>& kp, const std::vector<double>& conf, const char* key, size_t dim) {
    for (size_t i = 0; i < kp.size(); ++i) {
      const size_t t = i / (K * dim), k = (i / dim) % K;
      if (!valid[t] || std::isfinite(kp[i])) continue;
      if (!conf.empty() && conf[t * K + k] == 0) {
        kp[i] = 0;
        continue;
      }
      throw hawor::Error(z.source() + ": '" + key + "' frame " + std::to_string(t) + " keypoint " + std::to_string(k) +
                         " is not finite (give it confidence 0 to mark it missing, or valid = 0 for the frame)");
    }
  };
  checkFinite(kp2, c2, "keypoints2d", 2);
  checkFinite(kp3, c3, "keypoints3d", 3);
  // Through the lens: raw pixels -> the pinhole camera with the same intrinsics (the same ray).
  size_t outsideLens = 0;
  if (!lens.isPinhole()) {
    const hawor::CameraModel<double> model{cam, lens};
    if (c2.empty()) c2.assign(T * K, 1.0);
    for (size_t t = 0; t < T; ++t) {
      if (!valid[t]) continue;
      for (size_t k = 0; k < K; ++k) {
        if (c2[t * K + k] == 0) continue;
        double* p = &kp2[(t * K + k) * 2];
        hawor::Vec2<double> u;
        if (model.undistortPixel(hawor::Vec2<double>(p[0], p[1]), u)) {
          p[0] = u(0), p[1] = u(1);
        } else {
          p[0] = p[1] = 0;
          c2[t * K + k] = 0;
          ++outsideLens;
        }
      }
    }
  }

  // --- fit, frame by frame ------------------------------------------------------------------------
  const size_t J1 = static_cast<size_t>(m.numJoints() - 1), B = static_cast<size_t>(m.numBetas());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> rot(T * 3, nan), handPose(T * J1 * 3, nan), betas(T * B, nan), trans(T * 3, nan);
  std::vector<double> joints(T * K * 3, nan), rms(T, nan);
  std::vector<int32_t> iterations(T, 0);
  std::vector<uint8_t> fitted(T, 0);
  std::vector<double> msPerFrame, rmsFitted;
  size_t skipped = 0, failed = 0;
  std::string firstFailure;

  hawor::HandFitter<double> fitter(m);
  hawor::HandFitOptions<double> opt;
  hawor::HandObservation<double> obs;
  obs.keypoints2d.resize(static_cast<Eigen::Index>(K), 2);
  hawor::HandPose<double> previous;
  bool havePrevious = false;
  const bool warm = !args.flag("cold");
  for (size_t t = 0; t < T; ++t) {
    if (!valid[t]) {
      ++skipped;
      havePrevious = false;
      continue;
    }
    for (size_t k = 0; k < K; ++k) {
      const Eigen::Index r = static_cast<Eigen::Index>(k);
      for (size_t c = 0; c < 2; ++c) obs.keypoints2d(r, static_cast<Eigen::Index>(c)) = kp2[(t * K + k) * 2 + c];
    }
    obs.confidence2d.resize(c2.empty() ? 0 : static_cast<Eigen::Index>(K));
    for (size_t k = 0; k < K && !c2.empty(); ++k) obs.confidence2d(static_cast<Eigen::Index>(k)) = c2[t * K + k];
    obs.keypoints3d.resize(kp3.empty() ? 0 : static_cast<Eigen::Index>(K), 3);
    for (size_t i = 0; i < K * 3 && !kp3.empty(); ++i) obs.keypoints3d.data()[i] = kp3[t * K * 3 + i];  // row-major
    obs.confidence3d.resize(c3.empty() ? 0 : static_cast<Eigen::Index>(K));
    for (size_t k = 0; k < K && !c3.empty(); ++k) obs.confidence3d(static_cast<Eigen::Index>(k)) = c3[t * K + k];

    hawor::HandFitResult<double> res;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      res = fitter.fit(obs, cam, opt, warm && havePrevious ? &previous : nullptr);
    } catch (const hawor::Error& e) {
      // A frame the fit cannot handle (e.g. all confidences 0) is marked not fitted.
      const std::string why = std::string(e.what()).substr(7);  // without "hawor: "
      std::fprintf(stderr, "hawor fit: frame %zu not fitted: %s\n", t, why.c_str());
      if (firstFailure.empty()) firstFailure = why;
      ++failed;
      havePrevious = false;
      continue;
    }
    const auto t1 = std::chrono::steady_clock::now();
    msPerFrame.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    const hawor::HandPose<double>& p = res.pose;
    for (int c = 0; c < 3; ++c) {
      rot[t * 3 + static_cast<size_t>(c)] = p.rot(c);
      trans[t * 3 + static_cast<size_t>(c)] = p.trans(c);
    }
    for (size_t i = 0; i < J1 * 3; ++i) handPose[t * J1 * 3 + i] = p.handPose.data()[i];  // row-major
    for (size_t b = 0; b < B; ++b) betas[t * B + b] = p.betas(static_cast<Eigen::Index>(b));
    for (size_t i = 0; i < K * 3; ++i) joints[t * K * 3 + i] = res.keypoints.data()[i];
    rms[t] = res.reprojRmsPx;
    rmsFitted.push_back(res.reprojRmsPx);
    iterations[t] = res.iterations;
    fitted[t] = 1;
    previous = p;
    havePrevious = true;
  }
  const size_t nFitted = msPerFrame.size();
  if (nFitted == 0 && failed > 0) {
    throw hawor::Error(z.source() + ": no frame could be fitted; the first failure: " +
                       firstFailure);
  }

  hawor::Npz res;
  res.set("rot", hawor::NpyArray::fromData(rot.data(), {T, 3}));
  res.set("hand_pose", hawor::NpyArray::fromData(handPose.data(), {T, J1 * 3}));
  res.set("betas", hawor::NpyArray::fromData(betas.data(), {T, B}));
  res.set("trans", hawor::NpyArray::fromData(trans.data(), {T, 3}));
  res.set("joints_cam", hawor::NpyArray::fromData(joints.data(), {T, K, 3}));
  res.set("valid", hawor::NpyArray::fromData(fitted.data(), {T}));
  res.set("reproj_rms_px", hawor::NpyArray::fromData(rms.data(), {T}));
  res.set("iterations", hawor::NpyArray::fromData(iterations.data(), {T}));
  res.write(out);

  std::printf("%s\n", JsonObject()
                          .str("model", loaded.source)
                          .str("kind", hawor::handModelKindName(loaded.kind))
                          .str("side", sideName(m))
                          .str("camera", lens.toString())
                          .integer("frames", static_cast<long long>(T))
                          .integer("fitted", static_cast<long long>(nFitted))
                          .integer("skipped", static_cast<long long>(skipped))
                          .integer("failed", static_cast<long long>(failed))
                          .integer("keypoints_outside_lens", static_cast<long long>(outsideLens))
                          .num("median_reproj_rms_px", hawor::median(rmsFitted))
                          .num("median_ms_per_frame", hawor::median(msPerFrame))
                          .dump()
                          .c_str());
  return 0;
}

}  // namespace hawor_cli
