// hawor/synth/sequence.hpp — a synthetic egocentric sequence with ground truth: camera poses,
// RGB, depth, hand masks, hand parameters and keypoints, for a preset and a seed.
//
// Frames (docs/design.md §2). The world frame is the room's (scene.hpp): z up, gravity along −z,
// the floor at z = 0, metres, the pipeline's gravity-aligned output convention
// (pipeline/world_frame.hpp), so gravity, floor and metric scale can be checked against it.
// Camera poses are camera-to-world, T_w_c(i), at times t_i = i / fps.
// Hands (docs/design.md §3). Per hand and frame the MANO parameters in the world frame: rot (axis-angle
// of joint 0), handPose (the J−1 joint axis-angles), betas (fixed per sequence, shared by both
// hands: one person), trans, with vertices = forward(rot, handPose, betas, trans) in world
// coordinates (the rotation acts about J_0(β): the wrist is at J_0(β) + trans). The camera-frame
// parameters follow the same rule: rot_c = R_cw·rot, trans_c = R_cw·(trans + J_0) + t_cw − J_0.
// joints_world / joints_cam are the 21 keypoints (OpenPose order) of the forward pass, world and
// camera frame (joints_cam = T_c_w · joints_world).
// Placement: hand_motion.hpp plans each hand in a head frame that follows the camera's
// rotation with the preset's lag (exponential smoothing of the rotation, rate
// α = 1 − exp(−1/(lag·fps)) per frame), centred on the body: the camera centre smoothed by a
// Gaussian (bodySmoothSeconds), so the hands share the walk but not the head's bob, sway and
// neck lever arm; head-frame wrist p and orientation R_h map to the room as body + R_lag·p and
// R_lag·R_h. During a plan's holds the hand is frozen in the room (eased in and out): a hand
// holding or resting on something while the head moves.
// Visibility: `valid` = the hand has at least minVisiblePixels pixels of its own in the image
// (nearest surface there; a hand hidden by the scene or the other hand, or out of view, is
// invalid); per keypoint `inImage` = in front of the camera (z > 1 cm) and projecting inside the
// image (it may still be occluded).
// Capture (capture.hpp, SynthOptions::capture): exposure, rolling shutter, noise, exposure and
// white-balance drift, lens. The ground truth is that of the frame's reference time t_i = i/fps
// (the middle row's mid-exposure); sub-frames at t_i + τ take the camera from the continuous
// path (CameraPath::at) and the hands from their per-frame parameters, interpolated
// (interpolateHandPose: SLERP of the rotations, LERP of the translation). kp_in_image projects
// through the lens. Auto-exposure meters every frame up to the one rendered (a 64-pixel-wide
// render, cached), so frames may still be rendered in any order; the same small render gives
// the scene's image motion for the adaptive sub-frame count.
// Determinism: every random number comes from SynthRng streams of the seed (random.hpp), so a
// seed gives the same sequence on every run and platform.
// Thread-safety: renderFrame() uses the sequence's scratch buffers: one thread per sequence;
// the const members may be called concurrently. Movable, not copyable (the scene and models are
// shared, read-only, through sharedScene()).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/synth/capture.hpp"
#include "hawor/synth/hand_motion.hpp"
#include "hawor/synth/hand_rig.hpp"
#include "hawor/synth/presets.hpp"
#include "hawor/synth/random.hpp"
#include "hawor/synth/renderer.hpp"
#include "hawor/synth/scene.hpp"
#include "hawor/synth/trajectory.hpp"

namespace hawor {
namespace synth {

/// Size, length and camera of a generated sequence.
struct SynthOptions {
  int width = 640, height = 480;
  int frames = 0;          ///< 0: the preset's duration (its default frames at 30 fps)
  double fps = 30;
  double fovDeg = 90;      ///< diagonal field of view (PinholeCamera::fromFov)
  int textureDivisor = 1;  ///< 1 full-resolution textures, 2 or 4 coarser (faster setup)
  float noiseSigma = -1;   ///< pixel noise in grey levels; < 0: the preset's
  /// A hand is valid in a frame with at least max(1, round(fraction·W·H)) visible pixels.
  double minVisibleFraction = 2e-4;
  /// The camera's capture effects (capture.hpp); the default is the clean capture.
  CaptureOptions capture;
};

enum HandSideIndex { kLeftHand = 0, kRightHand = 1 };

/// Ground truth of one hand in one frame.
template <typename Scalar>
struct SynthHandFrame {
  HandPose<Scalar> world;         ///< MANO parameters, world frame
  HandPose<Scalar> camera;        ///< the same hand, camera frame
  Points3<Scalar> jointsWorld;    ///< (21,3)
  Points3<Scalar> jointsCam;      ///< (21,3)
  std::array<bool, 21> inImage{};  ///< keypoint in front of the camera and inside the image
  int visiblePixels = 0;          ///< pixels where this hand is the nearest surface
  bool valid = false;             ///< visiblePixels >= the sequence's threshold
};

/// One rendered frame with its ground truth.
template <typename Scalar>
struct SynthFrame {
  int index = 0;
  double time = 0;                 ///< seconds, index / fps
  RigidPose<Scalar> worldFromCamera;  ///< T_w_c
  RenderedImages images;           ///< rgb, depth, mask (left label 128, right 255)
  SynthHandFrame<Scalar> hands[2];  ///< kLeftHand, kRightHand
  double coverage = 0;             ///< fraction of the image covered by hands
  CaptureFrameInfo capture;        ///< sub-frames and gains of the capture model
};

template <typename Scalar>
class SynthSequence {
 public:
  static constexpr std::uint8_t kLeftLabel = 128, kRightLabel = 255;

  /// A sequence of `preset` for `seed` with the given left and right hand models (prepared,
  /// 21 keypoints; copied). The scene is built from the seed.
  SynthSequence(const SynthPreset& preset, std::uint64_t seed, const HandModel<Scalar>& left,
                const HandModel<Scalar>& right, const SynthOptions& options = SynthOptions())
      : SynthSequence(preset, seed, left, right, options, nullptr) {}

  /// The same with a prebuilt scene (shared, e.g. between tests); nullptr builds it.
  SynthSequence(const SynthPreset& preset, std::uint64_t seed, const HandModel<Scalar>& left,
                const HandModel<Scalar>& right, const SynthOptions& options,
                std::shared_ptr<const IndoorScene<Scalar>> scene)
      : preset_(preset), seed_(seed), opt_(options) {
    validateOptions();
    if (!left.isLeft) throw Error("synth: the left hand model is marked as a right hand");
    if (right.isLeft) throw Error("synth: the right hand model is marked as a left hand");
    models_[0] = std::make_shared<const HandModel<Scalar>>(left);
    models_[1] = std::make_shared<const HandModel<Scalar>>(right);
    rigs_[0] = std::make_shared<const HandRig<Scalar>>(*models_[0]);
    rigs_[1] = std::make_shared<const HandRig<Scalar>>(*models_[1]);
    if (!scene) {
      SceneOptions so;
      so.textureDivisor = opt_.textureDivisor;
      scene = std::make_shared<const IndoorScene<Scalar>>(makeIndoorScene<Scalar>(seed, so));
    }
    scene_ = std::move(scene);
    const CaptureOptions& co = opt_.capture;
    lensD_ = co.lens;
    lens_ = co.lens.template cast<Scalar>();
    fovDeg_ = co.fovDeg > 0 ? co.fovDeg : opt_.fovDeg;
    camera_ = lensIntrinsics<Scalar>(opt_.width, opt_.height, fovDeg_, lensD_);
    // the preset's duration (its frames are at 30 fps): another rate samples the same motion
    frames_ = opt_.frames > 0 ? opt_.frames : std::max(1, static_cast<int>(std::lround(preset_.frames * opt_.fps / 30)));
    const double readNoise = co.readNoise >= 0 ? co.readNoise : opt_.noiseSigma >= 0 ? opt_.noiseSigma : preset_.noiseSigma;
    noise_ = static_cast<float>(readNoise);
    plan();
    if (co.usesPipeline()) {
      const double duration = static_cast<double>(frames_ - 1) / opt_.fps + 1e-9;
      if (co.aeDrift > 0) {
        SynthRng rng(seed_, 20);
        aeDrift_ = SmoothSignal<Scalar>(rng, duration, 2.0, 1, VecX<Scalar>::Constant(1, Scalar(co.aeDrift)));
      }
      if (co.wbDrift > 0) {
        SynthRng rng(seed_, 21);
        wbDrift_ = SmoothSignal<Scalar>(rng, duration, 4.0, 2, VecX<Scalar>::Constant(2, Scalar(co.wbDrift)));
      }
    }
  }

  const SynthPreset& preset() const { return preset_; }
  std::uint64_t seed() const { return seed_; }
  const SynthOptions& options() const { return opt_; }
  int numFrames() const { return frames_; }
  double fps() const { return opt_.fps; }
  /// The intrinsics (with lens(): the camera; PinholeCamera::project alone is right only for a
  /// pinhole lens).
  const PinholeCamera<Scalar>& camera() const { return camera_; }
  /// The lens (capture.hpp; pinhole unless SynthOptions::capture sets one).
  const Lens<Scalar>& lens() const { return lens_; }
  /// The lens with the coefficients as given (double), e.g. for Lens::toString().
  const Lens<double>& lensDouble() const { return lensD_; }
  /// The read noise σ_r in grey levels (capture.hpp; the plain renderer's noise without capture
  /// effects).
  float readNoise() const { return noise_; }
  /// The diagonal field of view through the lens, degrees.
  double fovDeg() const { return fovDeg_; }
  /// The camera: intrinsics and lens.
  CameraModel<Scalar> cameraModel() const { return CameraModel<Scalar>{camera_, lens_}; }
  /// Pixel of a camera-frame point through the intrinsics and the lens.
  Vec2<Scalar> project(const Vec3<Scalar>& p) const {
    return lens_.kind == LensKind::Pinhole ? camera_.project(p) : cameraModel().project(p);
  }
  const IndoorScene<Scalar>& scene() const { return *scene_; }
  std::shared_ptr<const IndoorScene<Scalar>> sharedScene() const { return scene_; }
  const HandModel<Scalar>& model(int side) const { return *models_[checkSide(side)]; }
  /// Pixels a hand needs to be valid.
  int minVisiblePixels() const {
    const double n = opt_.minVisibleFraction * opt_.width * opt_.height;
    return std::max(1, static_cast<int>(n + 0.5));
  }

  /// T_w_c of frame i (camera-to-world, the room's frame).
  const RigidPose<Scalar>& worldFromCamera(int i) const { return worldFromCamera_[checkFrame(i)]; }
  /// Unit gravity direction in the world frame: −z.
  static Vec3<Scalar> gravityWorld() { return Vec3<Scalar>(0, 0, -1); }
  /// World-frame MANO parameters of a hand (kLeftHand / kRightHand) in frame i.
  const HandPose<Scalar>& handPoseWorld(int side, int i) const {
    return poses_[static_cast<std::size_t>(checkSide(side))][checkFrame(i)];
  }
  /// Camera-frame MANO parameters of a hand in frame i (see the file comment).
  HandPose<Scalar> handPoseCamera(int side, int i) const {
    const HandPose<Scalar>& w = handPoseWorld(side, i);
    const RigidPose<Scalar> cw = worldFromCamera(i).inverse();
    HandPose<Scalar> c = w;
    c.rot = matrixToAxisAngle(Mat3<Scalar>(cw.R * axisAngleToMatrix(w.rot)));
    const Vec3<Scalar>& j0 = root_[static_cast<std::size_t>(side)];  // J_0(β), β fixed per sequence
    c.trans = cw.R * (w.trans + j0) + cw.t - j0;
    return c;
  }

  /// Renders frame i and fills its ground truth.
  void renderFrame(int i, SynthFrame<Scalar>& out) {
    const std::size_t fi = checkFrame(i);
    out.index = i;
    out.time = static_cast<double>(i) / opt_.fps;
    out.worldFromCamera = worldFromCamera(i);
    const RigidPose<Scalar> cw = out.worldFromCamera.inverse();
    std::vector<HandMeshView<Scalar>> views;
    for (int s = 0; s < 2; ++s) {
      SynthHandFrame<Scalar>& h = out.hands[s];
      h.world = poses_[static_cast<std::size_t>(s)][fi];
      forward(*models_[static_cast<std::size_t>(s)], h.world, ws_, fwd_);
      h.jointsWorld = fwd_.keypoints;
      h.jointsCam.resize(h.jointsWorld.rows(), 3);
      for (Eigen::Index k = 0; k < h.jointsWorld.rows(); ++k) {
        h.jointsCam.row(k) = (cw.R * h.jointsWorld.row(k).transpose() + cw.t).transpose();
        const Vec3<Scalar> p = h.jointsCam.row(k).transpose();
        h.inImage[static_cast<std::size_t>(k)] = p.z() > Scalar(0.01) && camera_.inImage(project(p));
      }
      h.camera = handPoseCamera(s, i);
      toCamera(fwd_.vertices, cw, handVerts_[static_cast<std::size_t>(s)]);
      views.push_back(handView(s, handVerts_[static_cast<std::size_t>(s)]));
    }
    const std::uint32_t noiseSeed = hash3(static_cast<std::uint32_t>(seed_), static_cast<std::uint32_t>(seed_ >> 32),
                                          static_cast<std::uint32_t>(i));
    out.capture = CaptureFrameInfo();
    if (!opt_.capture.usesPipeline()) {
      if (!renderer_) renderer_ = std::make_unique<SceneRenderer<Scalar>>(*scene_, camera_);
      renderer_->render(worldFromCamera_[fi], views, noise_, noiseSeed, out.images);
    } else {
      const CaptureOptions& co = opt_.capture;
      if (!capture_) capture_ = std::make_unique<CaptureRenderer<Scalar>>(*scene_, camera_, lensD_, co.exposure, co.readout);
      CaptureFrameInfo& info = out.capture;
      CaptureExposure ex;
      if (co.hasShutter()) {
        if (co.subframes > 0) {
          info.subframes = co.subframes | 1;
        } else {
          info.motionPx = imageMotion(i, 0.5 * capture_->timing().span());
          info.subframes = adaptiveSubframes(info.motionPx, co);
        }
      }
      info.exposureGain = exposureGain(i);
      whiteBalance(i, info.whiteBalance);
      ex.subframes = info.subframes;
      ex.illumination = co.illumination;
      for (int c = 0; c < 3; ++c) ex.channelGain[c] = info.exposureGain * info.whiteBalance[c];
      ex.readNoise = noise_;
      ex.shotNoise = co.shotNoise;
      ex.noiseSeed = hashCombine(noiseSeed, 0x43415054u);
      capture_->render([&](double tau, RigidPose<Scalar>& roomFromCam, std::vector<HandMeshView<Scalar>>& hv) {
        stateAt(i, tau, roomFromCam, hv);
      }, ex, out.images);
    }
    const int need = minVisiblePixels();
    int covered = 0;
    for (int s = 0; s < 2; ++s) {
      out.hands[s].visiblePixels = out.images.handPixels[static_cast<std::size_t>(s)];
      out.hands[s].valid = out.hands[s].visiblePixels >= need;
      covered += out.hands[s].visiblePixels;
    }
    out.coverage = static_cast<double>(covered) / (static_cast<double>(opt_.width) * opt_.height);
  }

  /// The exposure gain g of frame i (capture.hpp: auto-exposure or the fixed gain, with drift).
  /// Auto-exposure meters frames 0 … i − 1 (cached).
  double exposureGain(int i) {
    checkFrame(i);
    const CaptureOptions& co = opt_.capture;
    double lg = std::log(co.gain);
    if (co.aeTime > 0) {
      while (static_cast<int>(aeLog_.size()) <= i) {
        const int k = static_cast<int>(aeLog_.size());
        const AutoExposure ae{co, opt_.fps};
        aeLog_.push_back(k == 0 ? ae.target(meter(0)) : ae.step(aeLog_.back(), meter(k - 1)));
      }
      lg = aeLog_[static_cast<std::size_t>(i)];
    }
    if (aeDrift_.dims() >= 1) lg += static_cast<double>(aeDrift_(static_cast<double>(i) / opt_.fps, 0));
    return std::min(co.aeMaxGain, std::max(co.aeMinGain, std::exp(lg)));
  }

  /// The white-balance gains (b_r, 1, b_b) of frame i (capture.hpp).
  void whiteBalance(int i, double b[3]) const {
    checkFrame(i);
    b[0] = b[1] = b[2] = 1;
    if (wbDrift_.dims() < 2) return;
    const double t = static_cast<double>(i) / opt_.fps;
    for (int c = 0; c < 2; ++c) {
      const double v = std::exp(static_cast<double>(wbDrift_(t, c)));
      b[2 * c] = std::min(std::exp(0.25), std::max(std::exp(-0.25), v));
    }
  }

  /// The auto-exposure's metered grey of frame i at unit gain (capture.hpp; cached).
  double meter(int i) {
    const std::size_t fi = checkFrame(i);
    if (meter_.size() <= fi) meter_.resize(fi + 1, -1.0);
    if (meter_[fi] < 0) {
      renderSmall(i);
      meter_[fi] = meteredGrey(meterRgb_);
    }
    return meter_[fi];
  }

 private:
  void validateOptions() const {
    if (opt_.width < 16 || opt_.height < 16 || opt_.width > 8192 || opt_.height > 8192) {
      throw Error("synth: image size " + std::to_string(opt_.width) + "x" + std::to_string(opt_.height) +
                  " outside 16..8192 pixels per side");
    }
    if (opt_.frames < 0 || opt_.frames > 1000000) throw Error("synth: frames must be in 1..1000000 (0 = preset default)");
    if (!(opt_.fps > 0 && opt_.fps <= 1000)) throw Error("synth: fps must be in (0, 1000]");
    if (!(opt_.fovDeg >= 20 && opt_.fovDeg <= 150)) throw Error("synth: diagonal field of view must be in [20, 150] degrees");
    if (!(opt_.minVisibleFraction >= 0 && opt_.minVisibleFraction < 1)) {
      throw Error("synth: minVisibleFraction must be in [0, 1)");
    }
    if (!std::isfinite(opt_.noiseSigma) || opt_.noiseSigma > 100) throw Error("synth: noiseSigma must be finite and <= 100");
    const CaptureOptions& co = opt_.capture;
    co.validate();
    const double interval = 1.0 / opt_.fps;
    if (co.exposure > interval || co.readout > interval) {
      throw Error("synth: capture " + std::string(co.exposure > interval ? "exposure " : "readout ") +
                  capture_detail::shortest(co.exposure > interval ? co.exposure : co.readout) +
                  " s exceeds the frame interval " + capture_detail::shortest(interval) + " s at " +
                  capture_detail::shortest(opt_.fps) + " fps");
    }
    if (preset_.frames < 1) throw Error("synth: preset '" + preset_.name + "' has no default length");
  }
  static int checkSide(int side) {
    if (side != kLeftHand && side != kRightHand) throw Error("synth: hand side must be 0 (left) or 1 (right)");
    return side;
  }
  std::size_t checkFrame(int i) const {
    if (i < 0 || i >= frames_) {
      throw Error("synth: frame " + std::to_string(i) + " outside [0, " + std::to_string(frames_) + ")");
    }
    return static_cast<std::size_t>(i);
  }

  // Camera path, head frame, hand plans and per-frame parameters (see the file comment).
  void plan() {
    const double duration = static_cast<double>(frames_ - 1) / opt_.fps + 1e-9;
    SynthRng camRng(seed_, 1);
    path_ = makeCameraPath<Scalar>(preset_.motion, scene_->layout, duration, camRng);
    worldFromCamera_.resize(static_cast<std::size_t>(frames_));
    for (int i = 0; i < frames_; ++i) worldFromCamera_[static_cast<std::size_t>(i)] = path_.at(static_cast<double>(i) / opt_.fps);
    // Head frame: exponentially smoothed camera rotation.
    const double lag = preset_.hands.lagSeconds;
    const Scalar alpha = lag > 0 ? Scalar(1 - std::exp(-1.0 / (lag * opt_.fps))) : Scalar(1);
    std::vector<Mat3<Scalar>> head(static_cast<std::size_t>(frames_));
    Eigen::Quaternion<Scalar> q = matrixToQuaternion(worldFromCamera_[0].R);
    for (int i = 0; i < frames_; ++i) {
      Eigen::Quaternion<Scalar> c = matrixToQuaternion(worldFromCamera_[static_cast<std::size_t>(i)].R);
      if (q.dot(c) < Scalar(0)) c.coeffs() = -c.coeffs();
      q.coeffs() = (Scalar(1) - alpha) * q.coeffs() + alpha * c.coeffs();
      q.normalize();
      head[static_cast<std::size_t>(i)] = q.toRotationMatrix();
    }
    // Body: the camera centre smoothed by a Gaussian of σ = bodySmoothSeconds, truncated at 3σ,
    // the path reflected oddly about its ends (c_{−k} = 2c_0 − c_k) so a straight walk is kept.
    std::vector<Vec3<Scalar>> body(static_cast<std::size_t>(frames_));
    const double sb = preset_.hands.bodySmoothSeconds * opt_.fps;
    const int rad = sb > 0 ? static_cast<int>(std::ceil(3 * sb)) : 0;
    auto centre = [&](int j) -> Vec3<Scalar> {
      const int n = frames_ - 1;
      if (j < 0) return Vec3<Scalar>(2 * worldFromCamera_[0].t - worldFromCamera_[static_cast<std::size_t>(std::min(-j, n))].t);
      if (j > n) {
        return Vec3<Scalar>(2 * worldFromCamera_[static_cast<std::size_t>(n)].t -
                            worldFromCamera_[static_cast<std::size_t>(std::max(2 * n - j, 0))].t);
      }
      return worldFromCamera_[static_cast<std::size_t>(j)].t;
    };
    for (int i = 0; i < frames_; ++i) {
      if (rad == 0) {
        body[static_cast<std::size_t>(i)] = worldFromCamera_[static_cast<std::size_t>(i)].t;
        continue;
      }
      Vec3<Scalar> acc = Vec3<Scalar>::Zero();
      double wsum = 0;
      for (int j = i - rad; j <= i + rad; ++j) {
        const double w = std::exp(-0.5 * double(j - i) * double(j - i) / (sb * sb));
        acc += Scalar(w) * centre(j);
        wsum += w;
      }
      body[static_cast<std::size_t>(i)] = acc / Scalar(wsum);
    }
    // Shape: one person, both hands (random when the model has shape coefficients).
    SynthRng shapeRng(seed_, 2);
    VecX<Scalar> betas[2];
    for (int s = 0; s < 2; ++s) betas[s] = VecX<Scalar>::Zero(models_[static_cast<std::size_t>(s)]->numBetas());
    for (Eigen::Index k = 0; k < 10; ++k) {
      const double v = std::max(-1.5, std::min(1.5, 0.7 * shapeRng.normal()));
      for (int s = 0; s < 2; ++s) {
        if (k < betas[s].size()) betas[s](k) = Scalar(v);
      }
    }
    for (int s = 0; s < 2; ++s) {
      SynthRng handRng(seed_, 10 + static_cast<std::uint64_t>(s));
      const double side = s == kLeftHand ? -1.0 : 1.0;
      const HandPlan<Scalar> hp = makeHandPlan(*rigs_[static_cast<std::size_t>(s)], preset_.hands, side, duration, handRng);
      std::vector<HandPose<Scalar>>& out = poses_[static_cast<std::size_t>(s)];
      out.resize(static_cast<std::size_t>(frames_));
      HandWorkspace<Scalar> ws;
      shapeHand(*models_[static_cast<std::size_t>(s)], betas[s], ws);
      root_[static_cast<std::size_t>(s)] = ws.jRest.row(0).transpose();
      // Room-frame wrist and orientation of the unfrozen path at frame i.
      auto roomAt = [&](int i, Vec3<Scalar>& wrist, Mat3<Scalar>& R, HandState<Scalar>& st) {
        const std::size_t fi = static_cast<std::size_t>(std::max(0, std::min(frames_ - 1, i)));
        st = hp.at(static_cast<double>(i) / opt_.fps);
        wrist = body[fi] + head[fi] * st.wrist;
        R = head[fi] * st.R;
      };
      // Holds: frozen wrist F and orientation at the hold's first frame; weight 1 inside, eased
      // (smoothstep) over holdEase before and after, so position and velocity stay continuous.
      struct Frozen {
        double t0, t1;
        Vec3<Scalar> wrist;
        Eigen::Quaternion<Scalar> q;
      };
      std::vector<Frozen> frozen;
      for (const HandHold& h : hp.holds) {
        Vec3<Scalar> w;
        Mat3<Scalar> R;
        HandState<Scalar> st;
        roomAt(static_cast<int>(std::lround(h.t0 * opt_.fps)), w, R, st);
        frozen.push_back({h.t0, h.t1, w, matrixToQuaternion(R)});
      }
      const double ease = std::max(1e-6, preset_.hands.holdEase);
      for (int i = 0; i < frames_; ++i) {
        const std::size_t fi = static_cast<std::size_t>(i);
        const double t = static_cast<double>(i) / opt_.fps;
        HandState<Scalar> st;
        Vec3<Scalar> wristRoom;
        Mat3<Scalar> Rroom;
        roomAt(i, wristRoom, Rroom, st);
        Scalar wBest = Scalar(0);
        const Frozen* fz = nullptr;
        for (const Frozen& f : frozen) {
          const double u = t < f.t0 ? 1 - (f.t0 - t) / ease : t > f.t1 ? 1 - (t - f.t1) / ease : 1.0;
          const Scalar w = u <= 0 ? Scalar(0) : smoothstep(Scalar(std::min(1.0, u)));
          if (w > wBest) wBest = w, fz = &f;
        }
        if (fz) {
          wristRoom = (Scalar(1) - wBest) * wristRoom + wBest * fz->wrist;
          Eigen::Quaternion<Scalar> q = matrixToQuaternion(Rroom);
          Rroom = q.slerp(wBest, fz->q).toRotationMatrix();
        }
        out[fi] = rigs_[static_cast<std::size_t>(s)]->pose(wristRoom, Rroom,
                                                            st.gesture, betas[s], ws);
      }
    }
  }

  // Camera-frame copy of world-frame points.
  static void toCamera(const Points3<Scalar>& world, const RigidPose<Scalar>& cw, Points3<Scalar>& cam) {
    cam.resize(world.rows(), 3);
    for (Eigen::Index k = 0; k < cam.rows(); ++k) cam.row(k) = (cw.R * world.row(k).transpose() + cw.t).transpose();
  }
  HandMeshView<Scalar> handView(int s, const Points3<Scalar>& verts) const {
    static const Rgb skin[2] = {Rgb(222.0f, 168.0f, 138.0f), Rgb(214.0f, 160.0f, 128.0f)};
    HandMeshView<Scalar> view;
    view.vertices = &verts;
    view.faces = &models_[static_cast<std::size_t>(s)]->faces;
    view.albedo = skin[s];
    view.label = s == kLeftHand ? kLeftLabel : kRightLabel;
    return view;
  }
  // World-frame hand parameters at frame position u = i + τ·fps (interpolated between frames,
  // held before the first and after the last).
  HandPose<Scalar> handPoseAt(int s, int i, double tau) const {
    const std::vector<HandPose<Scalar>>& P = poses_[static_cast<std::size_t>(s)];
    if (tau == 0) return P[static_cast<std::size_t>(i)];
    const double u = std::min(static_cast<double>(frames_ - 1), std::max(0.0, i + tau * opt_.fps));
    const int j = std::min(frames_ - 1, static_cast<int>(std::floor(u)));
    if (j + 1 >= frames_) return P[static_cast<std::size_t>(j)];
    return interpolateHandPose(P[static_cast<std::size_t>(j)], P[static_cast<std::size_t>(j) + 1], Scalar(u - j));
  }
  // The state of frame i at its reference time + τ (capture.hpp): the camera from the continuous
  // path (the frame's own pose at τ = 0), the hands interpolated; vertices in subVerts_.
  void stateAt(int i, double tau, RigidPose<Scalar>& roomFromCam, std::vector<HandMeshView<Scalar>>& views) {
    roomFromCam = tau == 0 ? worldFromCamera_[static_cast<std::size_t>(i)] : path_.at(static_cast<double>(i) / opt_.fps + tau);
    const RigidPose<Scalar> cw = roomFromCam.inverse();
    views.clear();
    for (int s = 0; s < 2; ++s) {
      forward(*models_[static_cast<std::size_t>(s)], handPoseAt(s, i, tau), ws_, fwd_);
      toCamera(fwd_.vertices, cw, subVerts_[static_cast<std::size_t>(s)]);
      views.push_back(handView(s, subVerts_[static_cast<std::size_t>(s)]));
    }
  }
  // The small render of frame i's reference state (64 pixels wide, pinhole, the field of view
  // up to 120°) into meterRgb_ / meterGeo_: the auto-exposure's metering and the scene's motion.
  void renderSmall(int i) {
    const std::size_t fi = static_cast<std::size_t>(i);
    if (!meterRenderer_) {
      const int mw = 64, mh = std::max(16, static_cast<int>(std::lround(64.0 * opt_.height / opt_.width)));
      meterRenderer_ = std::make_unique<SceneRenderer<Scalar>>(
          *scene_, PinholeCamera<Scalar>::fromFov(mw, mh, Scalar(std::min(fovDeg_, 120.0))));
    }
    const RigidPose<Scalar> cw = worldFromCamera(i).inverse();
    std::vector<HandMeshView<Scalar>> views;
    for (int s = 0; s < 2; ++s) {
      forward(*models_[static_cast<std::size_t>(s)], poses_[static_cast<std::size_t>(s)][fi], ws_, fwd_);
      toCamera(fwd_.vertices, cw, subVerts_[static_cast<std::size_t>(s)]);
      views.push_back(handView(s, subVerts_[static_cast<std::size_t>(s)]));
    }
    meterRenderer_->renderLinear(worldFromCamera_[fi], views, meterRgb_, meterGeo_);
  }

  // Image motion (pixels) of frame i between τ = −h and +h (capture.hpp: adaptive sub-frames):
  // the larger of the scene's and the hands'. Scene: the points of the small render's depth
  // map (hands left out), moved with the camera from its pose at −h to +h and projected with
  // the intrinsics: the 95th percentile of their displacement. Hands: their keypoints at least
  // 10 cm in front of the camera and in the image at one end or the other, the largest.
  double imageMotion(int i, double h) {
    RigidPose<Scalar> a, b;
    Points3<Scalar> ka[2], kb[2];
    for (int e = 0; e < 2; ++e) {
      const double tau = e == 0 ? -h : h;
      RigidPose<Scalar>& P = e == 0 ? a : b;
      P = path_.at(static_cast<double>(i) / opt_.fps + tau);
      const RigidPose<Scalar> cw = P.inverse();
      for (int s = 0; s < 2; ++s) {
        forward(*models_[static_cast<std::size_t>(s)], handPoseAt(s, i, tau), ws_, fwd_);
        toCamera(fwd_.keypoints, cw, e == 0 ? ka[s] : kb[s]);
      }
    }
    double motion = 0;
    for (int s = 0; s < 2; ++s) {
      for (Eigen::Index k = 0; k < ka[s].rows(); ++k) {
        const Vec3<Scalar> p = ka[s].row(k).transpose(), q = kb[s].row(k).transpose();
        if (!(p.z() > Scalar(0.1) && q.z() > Scalar(0.1))) continue;
        const Vec2<Scalar> u = camera_.project(p), v = camera_.project(q);
        if (!camera_.inImage(u) && !camera_.inImage(v)) continue;
        motion = std::max(motion, static_cast<double>((u - v).norm()));
      }
    }
    renderSmall(i);
    const PinholeCamera<Scalar>& m = meterRenderer_->camera();
    const RigidPose<Scalar>& c0 = worldFromCamera_[static_cast<std::size_t>(i)];
    const RigidPose<Scalar> ai = a.inverse(), bi = b.inverse();
    flow_.clear();
    for (int y = 0; y < m.height; ++y) {
      for (int x = 0; x < m.width; ++x) {
        const float z = meterGeo_.depth.at(x, y);
        if (!std::isfinite(z) || meterGeo_.mask.at(x, y) != 0) continue;
        const Vec3<Scalar> P = c0 * Vec3<Scalar>(m.ray(Vec2<Scalar>(Scalar(x), Scalar(y))) * Scalar(z));
        const Vec3<Scalar> p = ai * P, q = bi * P;
        if (!(p.z() > Scalar(0.05) && q.z() > Scalar(0.05))) continue;
        flow_.push_back(static_cast<double>((camera_.project(p) - camera_.project(q)).norm()));
      }
    }
    if (!flow_.empty()) {
      const std::size_t k = flow_.size() * 95 / 100;
      std::nth_element(flow_.begin(), flow_.begin() + static_cast<std::ptrdiff_t>(k), flow_.end());
      motion = std::max(motion, flow_[k]);
    }
    return motion;
  }

  SynthPreset preset_;
  std::uint64_t seed_ = 0;
  SynthOptions opt_;
  int frames_ = 0;
  float noise_ = 0;
  double fovDeg_ = 90;
  PinholeCamera<Scalar> camera_;
  Lens<Scalar> lens_;
  Lens<double> lensD_;
  CameraPath<Scalar> path_;
  std::shared_ptr<const IndoorScene<Scalar>> scene_;
  std::shared_ptr<const HandModel<Scalar>> models_[2];
  std::shared_ptr<const HandRig<Scalar>> rigs_[2];
  std::vector<RigidPose<Scalar>> worldFromCamera_;
  std::vector<HandPose<Scalar>> poses_[2];
  Vec3<Scalar> root_[2];  ///< J_0(β) per hand
  // Scratch of renderFrame().
  std::unique_ptr<SceneRenderer<Scalar>> renderer_;
  HandWorkspace<Scalar> ws_;
  HandOutput<Scalar> fwd_;
  Points3<Scalar> handVerts_[2];
  // Capture: renderer, sub-frame hand vertices, metering, drifts (capture.hpp).
  std::unique_ptr<CaptureRenderer<Scalar>> capture_;
  Points3<Scalar> subVerts_[2];
  std::unique_ptr<SceneRenderer<Scalar>> meterRenderer_;
  ImageF meterRgb_;
  RenderedImages meterGeo_;
  std::vector<double> meter_, aeLog_, flow_;
  SmoothSignal<Scalar> aeDrift_, wbDrift_;
};

}  // namespace synth
}  // namespace hawor
