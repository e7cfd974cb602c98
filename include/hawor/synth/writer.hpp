// hawor/synth/writer.hpp — writes a SynthSequence to disk in this layout:
//
//   DIR/rgb/000000.png …     RGB, 8 bit
//   DIR/mask/000000.png …    grey, 8 bit: 0 background, 128 left hand, 255 right hand (non-zero =
//                            hand: the nearest surface there is a hand mesh)
//   DIR/depth/000000.npy …   float32 (H, W), metres along the optical axis (hands included)
//   DIR/camera_gt.tum        camera-to-world poses, timestamps frame / fps (io/tum.hpp)
//   DIR/hands_gt.npz         per hand, prefixes left_ / right_ (T frames, float64 unless noted):
//                              trans (T,3), rot (T,3)        world-frame MANO translation and
//                                                            wrist axis-angle (sequence.hpp)
//                              hand_pose (T,(J−1)·3)         joint axis-angles (MANO: 45)
//                              betas (T,B)                   shape (B = the model's count)
//                              valid (T,) bool               visible in the image
//                              joints_world, joints_cam (T,21,3)  keypoints, OpenPose order
//                              cam_rot, cam_trans (T,3)      the same hand in the camera frame
//                              visible_pixels (T,) int32     pixels where the hand is nearest
//                              kp_in_image (T,21) bool       keypoint in front and inside image
//                            and timestamps (T,) float64
//   DIR/intrinsics.txt       one line "fx fy cx cy width height fps"; with capture effects a
//                            second line "lens SPEC" (Lens::toString: pinhole, opencv:k1,k2,p1,p2,k3
//                            or fisheye:k1,k2,k3,k4; pixel = (fx·m.x + cx, fy·m.y + cy) of the
//                            lens's distorted normalised m)
//   DIR/capture.json         with capture effects only: the settings (capture.hpp), the encoding
//                            a benchmark should apply (ffmpeg arguments for this size), and per
//                            frame the sub-frames, the exposure gain and the white balance
//   DIR/meta.json            preset, seed, sizes, mask labels, the world frame and gravity in it,
//                            the capture profile (with capture effects), and the caller's extra
//                            string fields (e.g. the hand-model files)
// The clean capture (CaptureOptions::isClean) writes neither the lens line nor capture.json.
// The world frame is the room's: z up, the floor at z = 0 (sequence.hpp). Folders are created as needed;
// existing files of the same names are replaced. Deterministic: the same sequence writes the
// same bytes.
// Thread-safety: one call per sequence at a time (it renders with the sequence's buffers).
#pragma once

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <sys/stat.h>
#include <sys/types.h>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/io/json.hpp"
#include "hawor/io/npy.hpp"
#include "hawor/io/npz.hpp"
#include "hawor/io/tum.hpp"
#include "hawor/synth/png.hpp"
#include "hawor/synth/sequence.hpp"

namespace hawor {
namespace synth {
// Uses npz.hpp and png.hpp, whose functions depend on the stb configuration: tagged like them.
inline namespace HAWOR_IO_DEFLATE_NS {

struct SynthWriteOptions {
  /// Extra "key": "value" string fields for meta.json.
  std::vector<std::pair<std::string, std::string>> meta;
  /// Called after each frame with (frames done, total); may be empty.
  std::function<void(int, int)> progress;
};

/// What writeSynthSequence did.
struct SynthWriteSummary {
  int frames = 0;
  int validFrames[2] = {0, 0};   ///< left, right
  double coverageMax = 0, coverageMean = 0;
  int framesCovered20 = 0;       ///< frames with hand coverage >= 20 %
  std::vector<double> renderMs;  ///< per frame: generation and rendering
  std::vector<double> writeMs;   ///< per frame: PNG / npy encoding and writing
  std::vector<int> subframes;    ///< per frame: sub-frames rendered (capture.hpp)
};

namespace writer_detail {

/// mkdir -p (POSIX; also under Emscripten's file systems).
inline void makeDirs(const std::string& path) {
  if (path.empty()) throw Error("synth writer: empty output folder");
  std::string cur;
  std::size_t pos = 0;
  while (pos <= path.size()) {
    const std::size_t next = path.find('/', pos);
    cur = path.substr(0, next == std::string::npos ? path.size() : next);
    pos = next == std::string::npos ? path.size() + 1 : next + 1;
    if (cur.empty()) continue;
    if (::mkdir(cur.c_str(), 0755) != 0 && errno != EEXIST) {
      throw Error("synth writer: cannot create folder '" + cur + "': " + std::strerror(errno));
    }
  }
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    throw Error("synth writer: '" + path + "' is not a folder");
  }
}

inline std::string frameName(int i, const char* ext) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06d.%s", i, ext);
  return buf;
}

inline double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// capture.json (file comment): settings, encoding, per-frame gains.
template <typename Scalar>
std::string captureJson(const SynthSequence<Scalar>& seq, const std::vector<CaptureFrameInfo>& frames) {
  const CaptureOptions& c = seq.options().capture;
  auto num = [](double v) { return detail::formatShortest(v, false); };
  const int W = seq.camera().width, H = seq.camera().height;
  std::string j = "{\n";
  j += "  \"profile\": " + jsonQuote(c.profile) + ",\n";
  j += "  \"exposure_s\": " + num(c.exposure) + ",\n  \"readout_s\": " + num(c.readout) + ",\n";
  j += "  \"row_window\": \"row r is exposed over t + (r - (H-1)/2)/H * readout_s -/+ exposure_s/2; t = frame / fps is "
       "the ground truth's time (the middle row's mid-exposure)\",\n";
  j += "  \"subframes\": " + std::to_string(c.subframes) + ",\n  \"max_subframes\": " + std::to_string(c.maxSubframes) +
       ",\n  \"subframe_step_px\": " + num(c.subframeStepPx) + ",\n";
  j += "  \"illumination\": " + num(c.illumination) + ",\n  \"gain\": " + num(c.gain) + ",\n";
  j += "  \"read_noise\": " + num(c.readNoise >= 0 ? c.readNoise : -1) + ",\n  \"read_noise_used\": " +
       num(static_cast<double>(seq.readNoise())) + ",\n  \"shot_noise\": " + num(c.shotNoise) + ",\n";
  j += "  \"auto_exposure\": {\"time_constant_s\": " + num(c.aeTime) + ", \"target\": " + num(c.aeTarget) +
       ", \"min_gain\": " + num(c.aeMinGain) + ", \"max_gain\": " + num(c.aeMaxGain) + ", \"drift\": " + num(c.aeDrift) +
       "},\n";
  j += "  \"white_balance_drift\": " + num(c.wbDrift) + ",\n";
  j += "  \"lens\": " + jsonQuote(seq.lensDouble().toString()) + ",\n  \"fov_deg\": " + num(seq.fovDeg()) + ",\n";
  const EncodeSpec::Resolved e = c.encode.resolve(W, H, seq.fps());
  j += "  \"encode\": {\"spec\": " + jsonQuote(c.encode.toString());
  if (!c.encode.none()) {
    j += ", \"codec\": " + jsonQuote(c.encode.codec) + ", \"width\": " + std::to_string(e.width) +
         ", \"height\": " + std::to_string(e.height) + ", \"kbps\": " + num(std::round(e.kbps)) + ", \"crf\": " +
         std::to_string(c.encode.crf) + ", \"ffmpeg_args\": [";
    for (std::size_t k = 0; k < e.ffmpegArgs.size(); ++k) j += (k ? ", " : "") + jsonQuote(e.ffmpegArgs[k]);
    j += "]";
  }
  j += "},\n";
  auto list = [&](const char* key, auto get) {
    j += std::string("  \"") + key + "\": [";
    for (std::size_t k = 0; k < frames.size(); ++k) j += (k ? ", " : "") + get(frames[k]);
    j += "]";
  };
  list("frame_subframes", [](const CaptureFrameInfo& f) { return std::to_string(f.subframes); });
  j += ",\n";
  list("frame_gain", [&](const CaptureFrameInfo& f) { return num(f.exposureGain); });
  j += ",\n";
  list("frame_white_balance", [&](const CaptureFrameInfo& f) {
    return "[" + num(f.whiteBalance[0]) + ", " + num(f.whiteBalance[1]) + ", " + num(f.whiteBalance[2]) + "]";
  });
  j += "\n}\n";
  return j;
}

}  // namespace writer_detail

/// Renders every frame of `seq` and writes the layout of the file comment into `dir`.
template <typename Scalar>
SynthWriteSummary writeSynthSequence(SynthSequence<Scalar>& seq, const std::string& dir,
                                     const SynthWriteOptions& options = SynthWriteOptions()) {
  using namespace writer_detail;
  const std::string base = dir.empty() || dir.back() == '/' ? dir : dir + "/";
  makeDirs(dir);
  makeDirs(base + "rgb");
  makeDirs(base + "mask");
  makeDirs(base + "depth");
  const int T = seq.numFrames();
  const PinholeCamera<Scalar>& cam = seq.camera();
  const std::size_t K = 21;
  SynthWriteSummary sum;
  sum.frames = T;
  // Per-hand arrays, C order.
  struct HandArrays {
    std::vector<double> trans, rot, pose, betas, joints, jointsCam, camRot, camTrans;
    std::vector<std::uint8_t> valid, kpIn;
    std::vector<std::int32_t> pixels;
    std::size_t poseDim = 0, betaDim = 0;
  } arr[2];
  for (int s = 0; s < 2; ++s) {
    arr[s].poseDim = static_cast<std::size_t>(seq.model(s).numJoints() - 1) * 3;
    arr[s].betaDim = static_cast<std::size_t>(seq.model(s).numBetas());
  }
  std::vector<TumPose<Scalar>> traj(static_cast<std::size_t>(T));
  std::vector<CaptureFrameInfo> captured;
  std::vector<double> stamps(static_cast<std::size_t>(T));
  SynthFrame<Scalar> fr;
  double covSum = 0;
  for (int i = 0; i < T; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    seq.renderFrame(i, fr);
    sum.renderMs.push_back(msSince(t0));
    const auto t1 = std::chrono::steady_clock::now();
    writePng(base + "rgb/" + frameName(i, "png"), fr.images.rgb);
    writePng(base + "mask/" + frameName(i, "png"), fr.images.mask);
    writeNpyFile(base + "depth/" + frameName(i, "npy"),
                 NpyArray::fromData(fr.images.depth.data.data(),
                                    {static_cast<std::size_t>(fr.images.depth.height), static_cast<std::size_t>(fr.images.depth.width)}));
    sum.writeMs.push_back(msSince(t1));
    // Ground truth.
    TumPose<Scalar>& tp = traj[static_cast<std::size_t>(i)];
    tp.t = fr.time;
    tp.q = Eigen::Quaternion<Scalar, Eigen::DontAlign>(matrixToQuaternion(fr.worldFromCamera.R));
    tp.p = fr.worldFromCamera.t;
    stamps[static_cast<std::size_t>(i)] = fr.time;
    for (int s = 0; s < 2; ++s) {
      const SynthHandFrame<Scalar>& h = fr.hands[s];
      HandArrays& a = arr[s];
      for (int c = 0; c < 3; ++c) {
        a.trans.push_back(static_cast<double>(h.world.trans(c)));
        a.rot.push_back(static_cast<double>(h.world.rot(c)));
        a.camRot.push_back(static_cast<double>(h.camera.rot(c)));
        a.camTrans.push_back(static_cast<double>(h.camera.trans(c)));
      }
      for (Eigen::Index k = 0; k < h.world.handPose.size(); ++k) a.pose.push_back(static_cast<double>(h.world.handPose.data()[k]));
      for (std::size_t k = 0; k < a.betaDim; ++k) {
        a.betas.push_back(static_cast<Eigen::Index>(k) < h.world.betas.size() ? static_cast<double>(h.world.betas(static_cast<Eigen::Index>(k))) : 0.0);
      }
      if (static_cast<std::size_t>(h.jointsWorld.rows()) != K) throw Error("synth writer: the hand model does not give 21 keypoints");
      for (std::size_t k = 0; k < K; ++k) {
        for (int c = 0; c < 3; ++c) {
          a.joints.push_back(static_cast<double>(h.jointsWorld(static_cast<Eigen::Index>(k), c)));
          a.jointsCam.push_back(static_cast<double>(h.jointsCam(static_cast<Eigen::Index>(k), c)));
        }
        a.kpIn.push_back(h.inImage[k] ? 1 : 0);
      }
      a.valid.push_back(h.valid ? 1 : 0);
      a.pixels.push_back(h.visiblePixels);
      if (h.valid) ++sum.validFrames[s];
    }
    covSum += fr.coverage;
    sum.coverageMax = std::max(sum.coverageMax, fr.coverage);
    if (fr.coverage >= 0.2) ++sum.framesCovered20;
    captured.push_back(fr.capture);
    sum.subframes.push_back(fr.capture.subframes);
    if (options.progress) options.progress(i + 1, T);
  }
  sum.coverageMean = T > 0 ? covSum / T : 0;
  writeTum(base + "camera_gt.tum", traj);
  // hands_gt.npz
  Npz z;
  const std::size_t Tn = static_cast<std::size_t>(T);
  auto boolArray = [](const std::vector<std::uint8_t>& v, std::vector<std::size_t> shape) {
    NpyArray a = NpyArray::fromData(v.data(), std::move(shape));
    a.dtype = "|b1";
    return a;
  };
  for (int s = 0; s < 2; ++s) {
    const std::string p = s == kLeftHand ? "left_" : "right_";
    const HandArrays& a = arr[s];
    z.set(p + "trans", NpyArray::fromData(a.trans.data(), {Tn, 3}));
    z.set(p + "rot", NpyArray::fromData(a.rot.data(), {Tn, 3}));
    z.set(p + "hand_pose", NpyArray::fromData(a.pose.data(), {Tn, a.poseDim}));
    z.set(p + "betas", NpyArray::fromData(a.betas.data(), {Tn, a.betaDim}));
    z.set(p + "valid", boolArray(a.valid, {Tn}));
    z.set(p + "joints_world", NpyArray::fromData(a.joints.data(), {Tn, K, 3}));
    z.set(p + "joints_cam", NpyArray::fromData(a.jointsCam.data(), {Tn, K, 3}));
    z.set(p + "cam_rot", NpyArray::fromData(a.camRot.data(), {Tn, 3}));
    z.set(p + "cam_trans", NpyArray::fromData(a.camTrans.data(), {Tn, 3}));
    z.set(p + "visible_pixels", NpyArray::fromData(a.pixels.data(), {Tn}));
    z.set(p + "kp_in_image", boolArray(a.kpIn, {Tn, K}));
  }
  z.set("timestamps", NpyArray::fromData(stamps.data(), {Tn}));
  z.write(base + "hands_gt.npz");
  // intrinsics.txt
  const std::string intr = detail::formatShortest(static_cast<double>(cam.fx), false) + " " +
                           detail::formatShortest(static_cast<double>(cam.fy), false) + " " +
                           detail::formatShortest(static_cast<double>(cam.cx), false) + " " +
                           detail::formatShortest(static_cast<double>(cam.cy), false) + " " + std::to_string(cam.width) +
                           " " + std::to_string(cam.height) + " " + detail::formatShortest(seq.fps(), false) + "\n";
  const CaptureOptions& co = seq.options().capture;
  writeFileText(base + "intrinsics.txt", co.isClean() ? intr : intr + "lens " + seq.lensDouble().toString() + "\n");
  if (!co.isClean()) writeFileText(base + "capture.json", captureJson(seq, captured));
  // meta.json
  const Vec3<Scalar> g = seq.gravityWorld();
  std::string m = "{\n";
  m += "  \"preset\": " + jsonQuote(seq.preset().name) + ",\n";
  m += "  \"seed\": " + std::to_string(seq.seed()) + ",\n";
  m += "  \"frames\": " + std::to_string(T) + ",\n";
  m += "  \"fps\": " + detail::formatShortest(seq.fps(), false) + ",\n";
  m += "  \"width\": " + std::to_string(cam.width) + ",\n  \"height\": " + std::to_string(cam.height) + ",\n";
  m += "  \"world_frame\": \"the room: z up, floor at z = 0, metres\",\n";
  m += "  \"gravity_world\": [" + detail::formatShortest(static_cast<double>(g.x()), false) + ", " +
       detail::formatShortest(static_cast<double>(g.y()), false) + ", " +
       detail::formatShortest(static_cast<double>(g.z()), false) + "],\n";
  if (!co.isClean()) m += "  \"capture\": " + jsonQuote(co.profile) + ",\n";
  m += "  \"mask_labels\": {\"left\": " + std::to_string(int(SynthSequence<Scalar>::kLeftLabel)) +
       ", \"right\": " + std::to_string(int(SynthSequence<Scalar>::kRightLabel)) + "},\n";
  m += "  \"hand_joints\": {\"left\": " + std::to_string(seq.model(kLeftHand).numJoints()) +
       ", \"right\": " + std::to_string(seq.model(kRightHand).numJoints()) + "}";
  for (const auto& kv : options.meta) m += ",\n  " + jsonQuote(kv.first) + ": " + jsonQuote(kv.second);
  m += "\n}\n";
  writeFileText(base + "meta.json", m);
  return sum;
}

}  // namespace HAWOR_IO_DEFLATE_NS
}  // namespace synth
}  // namespace hawor
