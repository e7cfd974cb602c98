// hawor/synth/capture.hpp — what a real camera does to the synthetic images: motion blur over
// the exposure, a rolling shutter, sensor noise, auto-exposure and white-balance drift, lens
// distortion, and the video encoding a benchmark applies afterwards (docs/design.md §11). The
// ground truth (poses, keypoints, masks, depth) stays exact.
//
// Timing (one mechanism for blur and rolling shutter). Frame i's reference time is t_i = i/fps,
// the time of its ground truth. Row r of an H-row sensor is exposed over
//   [t_i + δ_r − E/2, t_i + δ_r + E/2],   δ_r = (r − (H−1)/2)/H · R
// (exposure time E, readout time R: row r starts R/H after row r − 1, as "row r starts its
// exposure at t0 + r/H·R" with t0 chosen so that the middle row's mid-exposure is t_i). The
// frame renders S sub-frames (S odd) at times t_i + τ_s evenly spread over the union of the
// rows' windows, τ_s = (s − (S−1)/2)·(R(H−1)/H + E)/(S−1); the middle one, τ = 0, is the
// reference render and gives the mask, the depth and the hand pixel counts (exact ground truth
// of t_i). Between sub-frames the image is taken as linear in time (hat functions h_s), and row r
// gets the mean over its window:
//   I_r = Σ_s w_s(r) I_s,r,   w_s(r) = (1/E) ∫ h_s(t) dt over row r's window   (E = 0: h_s(t_i + δ_r))
// so the weights change smoothly from row to row (no bands) and E = R = 0 gives the reference
// image. S is adaptive by default: the image motion over the frame's window (the larger of the
// scene's, the 95th percentile over the points of a small depth render moved with the camera,
// and the hands', their keypoints in the image; sequence.hpp) divided by subframeStepPx, plus 1,
// rounded up to odd, at most maxSubframes; a frame moving less than a step renders once.
// Sub-frames render only the rows (bands) whose weights need them.
//
// Light and sensor. With L the rendered colour (grey levels, render()'s values before noise),
// channel c of the output is v_c = G_c·λ·L_c: λ the scene illumination (low light: λ < 1), and
// the per-channel gain G_c = g·b_c, g the exposure gain (fixed, or auto-exposure) and b_c the
// white balance (b_g = 1). Noise acts on the sensor signal λL before the gain: read noise σ_r and
// shot noise of variance k per grey level of signal, so
//   σ_c² = G_c²·σ_r² + G_c·k·v_c        (grey levels²; deterministic hash of seed and pixel,
//                                         an Irwin–Hall sum of four bytes ≈ Gaussian)
// then rounding to bytes. Auto-exposure: the metered brightness m_j of frame j is the
// centre-weighted (Gaussian, σ = 0.35 of the half-size) mean grey of a small pinhole render at
// unit gain; the camera aims at g*_j = target/(λ·m_j) (clamped to [aeMinGain, aeMaxGain]) and
// follows it with a lag, reacting to the previous frame:
//   log g_i = log g_{i−1} + α·(log g*_{i−1} − log g_{i−1}),  α = 1 − exp(−1/(τ·fps)),  g_0 = g*_0
// times exp(drift(t)) (a smooth random signal of standard deviation aeDrift, knots every 2 s),
// clamped again. White balance: log b_r, log b_b are smooth random signals of standard deviation
// wbDrift (knots every 4 s), each gain clamped to [e^−0.25, e^0.25]. Both signals come from
// SynthRng streams of the seed (20: exposure drift, 21: white balance).
//
// Lens. The output camera is the PinholeCamera intrinsics (fx, fy, cx, cy, the same convention:
// pixel = (fx·m.x + cx, fy·m.y + cy)) with a Lens of geometry/lens.hpp mapping camera points to
// the distorted normalised m; the focal follows from the diagonal field of view through the lens:
// f = (√(W²+H²)/2)/|m(θ = fov/2)| along the diagonal. Rendering: up to five pinhole views share
// the camera centre (the +z view and the four turned by 90° about x and y, the faces of a cube),
// each output pixel's bearing goes to the view it is most central in, views are cropped to the
// bearings they serve, and their focal f_v = ρ·f with ρ ≥ 1 the smallest factor that gives every
// output pixel at least one view pixel (at most 2). Colour is resampled bilinearly; mask and
// depth take the nearest view pixel (depth converted to z of the output camera: the same
// surface point, z along the output's optical axis). One view (the output camera itself, no
// resampling) when the lens is a pinhole.
//
// Named profiles (captureProfiles()) bundle these settings; `clean` is the generator's own
// output (global shutter, no blur, pinhole, the preset's noise: the same bytes as without
// capture options).
// Thread-safety: options and profiles are values; a CaptureRenderer holds scratch buffers (one
// per thread).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/camera_model.hpp"
#include "hawor/geometry/lens.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/render/image.hpp"
#include "hawor/synth/random.hpp"
#include "hawor/synth/renderer.hpp"
#include "hawor/synth/scene.hpp"
#include "hawor/synth/trajectory.hpp"

namespace hawor {
namespace synth {

namespace capture_detail {

/// The shortest decimal that reads back to v (whole numbers below 10^15 without an exponent).
inline std::string shortest(double v) {
  char buf[40];
  if (v == std::floor(v) && std::abs(v) < 1e15) {
    std::snprintf(buf, sizeof buf, "%.0f", v);
    return buf;
  }
  for (int prec = 1; prec <= 17; ++prec) {
    std::snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

/// A whole string as a finite number; throws hawor::Error naming `what` otherwise.
inline double number(const std::string& what, const std::string& s) {
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(v)) {
    throw Error("capture: " + what + " expects a finite number, got '" + s + "'");
  }
  return v;
}

inline void checkRange(const std::string& what, double v, double lo, double hi, const char* unit = "") {
  if (!(v >= lo && v <= hi)) {
    throw Error("capture: " + what + " " + shortest(v) + unit + " outside [" + shortest(lo) + ", " + shortest(hi) + "]" +
                unit);
  }
}

}  // namespace capture_detail

/// How a benchmark encodes the frames after generation (the generator itself writes lossless
/// PNGs; the benchmark scripts run ffmpeg): a codec at a device's bit rate. The rate is given for
/// the device's own video size and frame rate (width × height at fps) and applies as bits per
/// pixel: a smaller rendering gets the same compression, rate × (w·h·fps')/(width·height·fps).
struct EncodeSpec {
  std::string codec;          ///< "" (none), "h264", "h265" or "vp9"
  double kbps = 0;            ///< average rate at width × height, fps (kbit/s); 0: constant quality
  int crf = -1;               ///< constant-quality factor when kbps = 0 (ffmpeg's -crf)
  int width = 0, height = 0;  ///< the device's video size the rate is quoted for
  double fps = 30;
  int maxHeight = 0;          ///< encode at most this many rows (downscaled, aspect kept); 0: as rendered

  bool none() const { return codec.empty(); }

  /// "none" or "CODEC[,kbps=K,size=WxH,fps=F][,crf=N][,max-height=H]".
  std::string toString() const {
    using capture_detail::shortest;
    if (none()) return "none";
    std::string s = codec;
    if (kbps > 0) s += ",kbps=" + shortest(kbps) + ",size=" + std::to_string(width) + "x" + std::to_string(height) + ",fps=" + shortest(fps);
    if (crf >= 0) s += ",crf=" + std::to_string(crf);
    if (maxHeight > 0) s += ",max-height=" + std::to_string(maxHeight);
    return s;
  }

  /// Reads toString()'s form; size defaults to the rendering's (0x0) and fps to 30. Throws
  /// hawor::Error quoting the text.
  static EncodeSpec parse(const std::string& text) {
    EncodeSpec e;
    if (text == "none" || text.empty()) return e;
    auto fail = [&](const std::string& why) -> void {
      throw Error("capture: encode '" + text + "': " + why +
                  " (expected none or CODEC[,kbps=K,size=WxH,fps=F][,crf=N][,max-height=H], CODEC h264, h265 or vp9)");
    };
    std::vector<std::string> parts;
    std::size_t start = 0;
    while (true) {
      const std::size_t c = text.find(',', start);
      parts.push_back(text.substr(start, c == std::string::npos ? std::string::npos : c - start));
      if (c == std::string::npos) break;
      start = c + 1;
    }
    e.codec = parts[0];
    if (e.codec != "h264" && e.codec != "h265" && e.codec != "vp9") fail("unknown codec '" + e.codec + "'");
    for (std::size_t i = 1; i < parts.size(); ++i) {
      const std::size_t eq = parts[i].find('=');
      if (eq == std::string::npos) fail("'" + parts[i] + "' is not key=value");
      const std::string k = parts[i].substr(0, eq), v = parts[i].substr(eq + 1);
      if (k == "kbps") {
        e.kbps = capture_detail::number("encode kbps", v);
        if (!(e.kbps > 0 && e.kbps <= 1e6)) fail("kbps must be in (0, 1e6]");
      } else if (k == "crf") {
        const double c = capture_detail::number("encode crf", v);
        if (!(c >= 0 && c <= 63) || c != std::floor(c)) fail("crf must be an integer in [0, 63]");
        e.crf = static_cast<int>(c);
      } else if (k == "size") {
        const std::size_t x = v.find('x');
        if (x == std::string::npos) fail("size expects WxH");
        const double w = capture_detail::number("encode width", v.substr(0, x));
        const double h = capture_detail::number("encode height", v.substr(x + 1));
        if (!(w >= 16 && h >= 16 && w <= 16384 && h <= 16384) || w != std::floor(w) || h != std::floor(h)) {
          fail("size must be whole numbers in 16..16384");
        }
        e.width = static_cast<int>(w);
        e.height = static_cast<int>(h);
      } else if (k == "fps") {
        e.fps = capture_detail::number("encode fps", v);
        if (!(e.fps > 0 && e.fps <= 1000)) fail("fps must be in (0, 1000]");
      } else if (k == "max-height") {
        const double h = capture_detail::number("encode max-height", v);
        if (!(h >= 16 && h <= 16384) || h != std::floor(h)) fail("max-height must be a whole number in 16..16384");
        e.maxHeight = static_cast<int>(h);
      } else {
        fail("unknown key '" + k + "'");
      }
    }
    if ((e.kbps > 0) == (e.crf >= 0)) fail("give either kbps (with size) or crf");
    if (e.kbps > 0 && e.width == 0) fail("kbps needs the size it is quoted for");
    return e;
  }

  /// The encoding of a W × H rendering at `fpsOut`: the output size (maxHeight applied, even
  /// sides for 4:2:0), the rate at that size, and ffmpeg's output arguments.
  struct Resolved {
    int width = 0, height = 0;
    double kbps = 0;
    std::vector<std::string> ffmpegArgs;
  };
  Resolved resolve(int W, int H, double fpsOut) const {
    Resolved r;
    if (none()) return r;
    int h = H, w = W;
    if (maxHeight > 0 && H > maxHeight) {
      h = maxHeight;
      w = static_cast<int>(std::lround(static_cast<double>(W) * maxHeight / H));
    }
    r.width = w & ~1;
    r.height = h & ~1;
    const char* lib = codec == "h264" ? "libx264" : codec == "h265" ? "libx265" : "libvpx-vp9";
    r.ffmpegArgs = {"-c:v", lib};
    if (kbps > 0) {
      r.kbps = kbps * (static_cast<double>(r.width) * r.height * fpsOut) / (static_cast<double>(width) * height * fps);
      const long k = std::lround(r.kbps);
      r.ffmpegArgs.insert(r.ffmpegArgs.end(), {"-b:v", std::to_string(k) + "k", "-maxrate", std::to_string(k * 3 / 2) + "k",
                                               "-bufsize", std::to_string(k * 2) + "k"});
    } else {
      r.ffmpegArgs.insert(r.ffmpegArgs.end(), {"-crf", std::to_string(crf)});
      if (codec == "vp9") r.ffmpegArgs.insert(r.ffmpegArgs.end(), {"-b:v", "0"});
    }
    if (r.width != W || r.height != H) {
      r.ffmpegArgs.insert(r.ffmpegArgs.end(), {"-vf", "scale=" + std::to_string(r.width) + ":" + std::to_string(r.height)});
    }
    r.ffmpegArgs.insert(r.ffmpegArgs.end(), {"-pix_fmt", "yuv420p"});
    return r;
  }
};

/// The capture settings (units in the comments; the defaults are the clean capture: everything
/// off). Composable: start from a profile and override fields (setCaptureField).
struct CaptureOptions {
  std::string profile = "clean";  ///< the profile these started from (for the record)
  // Shutter (file comment: Timing).
  double exposure = 0;        ///< E, seconds each row integrates light (0: an instant)
  double readout = 0;         ///< R, seconds from the first row's start to the last's (0: global shutter)
  int subframes = 0;          ///< 0: adaptive; ≥ 1: that many sub-frames (rounded up to odd)
  int maxSubframes = 25;      ///< adaptive: at most this many
  double subframeStepPx = 2;  ///< adaptive: image motion between sub-frames, pixels
  // Light and sensor (file comment).
  double illumination = 1;    ///< λ, scene light relative to the modelled room
  double gain = 1;            ///< exposure gain without auto-exposure
  double readNoise = -1;      ///< σ_r, grey levels; < 0: SynthOptions::noiseSigma, else the preset's
  double shotNoise = 0;       ///< k, grey levels² per grey level of signal
  double aeTime = 0;          ///< auto-exposure time constant τ, seconds; 0: off (gain fixed)
  double aeTarget = 118;      ///< metered grey the auto-exposure aims at (18 % grey in sRGB)
  double aeMinGain = 0.25, aeMaxGain = 8;
  double aeDrift = 0;         ///< standard deviation of the slow log-gain drift
  double wbDrift = 0;         ///< standard deviation of the slow log white-balance drift (red, blue)
  // Lens.
  Lens<double> lens;          ///< pinhole by default
  double fovDeg = 0;          ///< diagonal field of view through the lens; 0: SynthOptions::fovDeg
  // After generation.
  EncodeSpec encode;

  /// Timing: exposure or readout; then the sub-frame machinery runs.
  bool hasShutter() const { return exposure > 0 || readout > 0; }
  /// Anything that needs the capture pipeline (read noise and the field of view alone do not:
  /// the plain renderer draws them).
  bool usesPipeline() const {
    return hasShutter() || illumination != 1 || gain != 1 || shotNoise > 0 || aeTime > 0 || aeDrift > 0 ||
           wbDrift > 0 || !lens.isPinhole();
  }
  /// The clean capture: the generator's own output, nothing to record.
  bool isClean() const {
    return !usesPipeline() && readNoise < 0 && fovDeg == 0 && lens.kind == LensKind::Pinhole && encode.none();
  }
  /// Throws hawor::Error naming the first field out of range (fps-dependent limits are checked
  /// by the sequence).
  void validate() const {
    using capture_detail::checkRange;
    checkRange("exposure", exposure, 0, 1, " s");
    checkRange("readout", readout, 0, 1, " s");
    checkRange("subframes", subframes, 0, 255);
    checkRange("max-subframes", maxSubframes, 1, 255);
    checkRange("subframe-step", subframeStepPx, 0.25, 1000, " px");
    checkRange("illumination", illumination, 1e-3, 100);
    checkRange("gain", gain, 1e-3, 100);
    if (readNoise >= 0 || !std::isfinite(readNoise)) checkRange("read-noise", readNoise, 0, 100);
    checkRange("shot-noise", shotNoise, 0, 100);
    checkRange("ae", aeTime, 0, 60, " s");
    checkRange("ae-target", aeTarget, 1, 254);
    checkRange("ae min gain", aeMinGain, 1e-3, 1000);
    checkRange("ae max gain", aeMaxGain, aeMinGain, 1000);
    checkRange("ae-drift", aeDrift, 0, 1);
    checkRange("wb-drift", wbDrift, 0, 1);
    if (fovDeg != 0) checkRange("fov", fovDeg, 20, lens.isPinhole() ? 150 : 170, " degrees");
    lens.validate(0);
  }
};

/// A named capture profile.
struct CaptureProfile {
  std::string name, description;
  CaptureOptions options;
};

/// Every profile, in a fixed order. The values and why:
///   clean        the generator's own output (global shutter, instant exposure, pinhole, the
///                preset's read noise of 1.5 grey levels)
///   phone        a phone's main camera indoors at 30 fps: 1/60 s exposure, a 25 ms rolling
///                readout (typical of phone CMOS sensors at 1080p), mild noise (σ_r = 1, k = 0.025:
///                σ ≈ 2 at mid-grey after the phone's denoising), auto-exposure with τ = 0.5 s and
///                5 % drift, 3 % white-balance drift; pinhole at the sequence's field of view (the
///                same view as clean, so the two compare frame by frame); H.264 1080p30 at
///                17 Mbit/s (a phone's default rate, 0.27 bit per pixel), at most 1080 rows
///   action_cam   a GoPro-like wide lens: radial-tangential k1 = −0.16, k2 = 0.02, k3 = −0.001
///                and a little decentring (p1 = 4e-4, p2 = −3e-4), 125° diagonal (101° × 78° on
///                4:3): strong barrel distortion (the corners 37 % nearer the centre than a
///                pinhole's), monotonic to 70°, and nowhere more than 1.23 times the centre's
///                angular resolution (a wide lens does not magnify its periphery; five-coefficient
///                fits that reach GoPro's 150° fold inside the image); 1/50 s exposure (indoor
///                auto shutter: strong blur in head turns), 15 ms readout, σ_r = 1.5, k = 0.04 (a
///                small sensor), auto-exposure τ = 0.3 s; H.264 at 40 Mbit/s for 1440p30 (an
///                action camera's standard rate)
///   aria         an Aria-like glasses camera: equidistant fisheye k = (−0.0036, 0.0368, −0.0343,
///                0.0052) (a Kannala–Brandt calibration of a 160° class lens; monotonic to 180°),
///                150° diagonal; short 8 ms exposure and 12 ms readout with more gain (σ_r = 1.5,
///                k = 0.05), auto-exposure τ = 0.4 s; no encoding (frames kept as recorded)
///   low_light    the phone in a dim room: 1/30 s exposure, 25 ms readout, illumination 0.2 (2.3
///                stops darker) brought back by auto-exposure (up to 8×), so the gain amplifies
///                σ_r = 1.2, k = 0.04 to σ ≈ 7 grey levels; 6 % white-balance drift (auto white
///                balance struggles); H.264 as the phone
///   webcam_360p  a cheap USB webcam: 1/30 s exposure, 30 ms readout, σ_r = 2, k = 0.05, slow
///                auto-exposure (τ = 0.8 s, 6 % drift), 5 % white-balance drift; H.264 at a video
///                call's 500 kbit/s for 640×360 (0.07 bit per pixel: heavy compression), at most
///                360 rows
inline std::vector<CaptureProfile> captureProfiles() {
  std::vector<CaptureProfile> out;
  {
    CaptureProfile p;
    p.name = "clean";
    p.description = "the generator's own output: global shutter, no blur, pinhole, the preset's noise";
    out.push_back(p);
  }
  {
    CaptureProfile p;
    p.name = "phone";
    p.description = "phone at 30 fps indoors: 1/60 s, 25 ms rolling shutter, mild noise, AE/WB drift; H.264 1080p 17 Mbit/s";
    CaptureOptions& o = p.options;
    o.exposure = 1.0 / 60, o.readout = 0.025;
    o.readNoise = 1.0, o.shotNoise = 0.025;
    o.aeTime = 0.5, o.aeDrift = 0.05, o.wbDrift = 0.03;
    o.encode = EncodeSpec::parse("h264,kbps=17000,size=1920x1080,fps=30,max-height=1080");
    out.push_back(p);
  }
  {
    CaptureProfile p;
    p.name = "action_cam";
    p.description = "GoPro-like: 125 deg wide radial-tangential lens, 1/50 s (blur in head turns), 15 ms rolling shutter";
    CaptureOptions& o = p.options;
    o.exposure = 0.02, o.readout = 0.015;
    o.readNoise = 1.5, o.shotNoise = 0.04;
    o.aeTime = 0.3, o.aeDrift = 0.04, o.wbDrift = 0.03;
    o.lens = Lens<double>::radTan(-0.16, 0.02, 4e-4, -3e-4, -0.001);
    o.fovDeg = 125;
    o.encode = EncodeSpec::parse("h264,kbps=40000,size=1920x1440,fps=30");
    out.push_back(p);
  }
  {
    CaptureProfile p;
    p.name = "aria";
    p.description = "Aria-like glasses: 150 deg equidistant fisheye, 8 ms exposure, 12 ms rolling shutter, no encoding";
    CaptureOptions& o = p.options;
    o.exposure = 0.008, o.readout = 0.012;
    o.readNoise = 1.5, o.shotNoise = 0.05;
    o.aeTime = 0.4, o.aeDrift = 0.04, o.wbDrift = 0.02;
    o.lens = Lens<double>::fisheye(-0.0036, 0.0368, -0.0343, 0.0052);
    o.fovDeg = 150;
    out.push_back(p);
  }
  {
    CaptureProfile p;
    p.name = "low_light";
    p.description = "phone in a dim room: 1/30 s, 25 ms rolling shutter, 5x less light, high gain and strong noise";
    CaptureOptions& o = p.options;
    o.exposure = 1.0 / 30, o.readout = 0.025;
    o.illumination = 0.2;
    o.readNoise = 1.2, o.shotNoise = 0.04;
    o.aeTime = 0.6, o.aeDrift = 0.05, o.wbDrift = 0.06;
    o.encode = EncodeSpec::parse("h264,kbps=17000,size=1920x1080,fps=30,max-height=1080");
    out.push_back(p);
  }
  {
    CaptureProfile p;
    p.name = "webcam_360p";
    p.description = "cheap webcam: 1/30 s, 30 ms rolling shutter, noisy, slow AE; H.264 360p at 500 kbit/s";
    CaptureOptions& o = p.options;
    o.exposure = 1.0 / 30, o.readout = 0.03;
    o.readNoise = 2.0, o.shotNoise = 0.05;
    o.aeTime = 0.8, o.aeDrift = 0.06, o.wbDrift = 0.05;
    o.encode = EncodeSpec::parse("h264,kbps=500,size=640x360,fps=30,max-height=360");
    out.push_back(p);
  }
  for (CaptureProfile& p : out) p.options.profile = p.name;
  return out;
}

/// The names of captureProfiles(), in order.
inline std::vector<std::string> captureProfileNames() {
  std::vector<std::string> n;
  for (const CaptureProfile& p : captureProfiles()) n.push_back(p.name);
  return n;
}

/// The options of the profile called `name`; throws hawor::Error listing the known names.
inline CaptureOptions findCaptureProfile(const std::string& name) {
  std::string known;
  for (const CaptureProfile& p : captureProfiles()) {
    if (p.name == name) return p.options;
    known += (known.empty() ? "" : ", ") + p.name;
  }
  throw Error("unknown capture profile '" + name + "' (known profiles: " + known + ")");
}

/// One field setCaptureField() takes (the CLI's option --name VALUE).
struct CaptureField {
  const char* name;
  const char* value;  ///< what the value is, e.g. "S"
  const char* help;
};

/// The fields, in the order the help lists them.
inline const std::vector<CaptureField>& captureFields() {
  static const std::vector<CaptureField> f = {
      {"exposure", "S", "exposure time of each row, seconds (0: instant)"},
      {"readout", "S", "rolling-shutter readout, first row to last, seconds (0: global shutter)"},
      {"subframes", "N", "sub-frames per frame (0: adaptive, from the image motion)"},
      {"max-subframes", "N", "adaptive sub-frames at most (25)"},
      {"subframe-step", "PX", "adaptive: image motion between sub-frames, pixels (2; larger renders faster)"},
      {"illumination", "X", "scene light relative to the modelled room (low light < 1)"},
      {"gain", "G", "exposure gain when auto-exposure is off"},
      {"read-noise", "SIGMA", "read noise, grey levels (default: --noise, else the preset's)"},
      {"shot-noise", "K", "shot-noise variance per grey level of signal"},
      {"ae", "TAU", "auto-exposure time constant, seconds (0: off)"},
      {"ae-target", "GREY", "the metered grey auto-exposure aims at"},
      {"ae-drift", "SIGMA", "slow exposure drift (standard deviation of the log gain)"},
      {"wb-drift", "SIGMA", "slow white-balance drift (standard deviation of the log gains)"},
      {"lens", "SPEC", "pinhole | opencv:k1,k2,p1,p2[,k3] | fisheye:k1,k2,k3,k4"},
      {"fov", "DEG", "diagonal field of view through the lens"},
      {"encode", "SPEC", "none | CODEC[,kbps=K,size=WxH,fps=F][,crf=N][,max-height=H], for the benchmark"},
  };
  return f;
}

/// Sets one field by name (captureFields()) from text; throws hawor::Error naming the field and
/// the value (unknown names list the known ones). Ranges are checked by validate(), once all
/// fields are set (the field of view's range depends on the lens).
inline void setCaptureField(CaptureOptions& o, const std::string& name, const std::string& value) {
  using capture_detail::number;
  auto whole = [&](double v) {
    if (v != std::floor(v) || std::abs(v) > 1e6) throw Error("capture: " + name + " expects a whole number, got '" + value + "'");
    return static_cast<int>(v);
  };
  if (name == "exposure") {
    o.exposure = number(name, value);
  } else if (name == "readout") {
    o.readout = number(name, value);
  } else if (name == "subframes") {
    o.subframes = whole(number(name, value));
  } else if (name == "max-subframes") {
    o.maxSubframes = whole(number(name, value));
  } else if (name == "subframe-step") {
    o.subframeStepPx = number(name, value);
  } else if (name == "illumination") {
    o.illumination = number(name, value);
  } else if (name == "gain") {
    o.gain = number(name, value);
  } else if (name == "read-noise") {
    o.readNoise = number(name, value);
  } else if (name == "shot-noise") {
    o.shotNoise = number(name, value);
  } else if (name == "ae") {
    o.aeTime = number(name, value);
  } else if (name == "ae-target") {
    o.aeTarget = number(name, value);
  } else if (name == "ae-drift") {
    o.aeDrift = number(name, value);
  } else if (name == "wb-drift") {
    o.wbDrift = number(name, value);
  } else if (name == "lens") {
    o.lens = Lens<double>::parse(value);
  } else if (name == "fov") {
    o.fovDeg = number(name, value);
  } else if (name == "encode") {
    o.encode = EncodeSpec::parse(value);
  } else {
    std::string known;
    for (const CaptureField& f : captureFields()) known += std::string(known.empty() ? "" : ", ") + f.name;
    throw Error("capture: unknown field '" + name + "' (known: " + known + ")");
  }
}

// ---------------------------------------------------------------------------------------------
// Timing.

/// Row exposure windows and sub-frame times of one frame (file comment: Timing), as offsets
/// from the frame's reference time, seconds.
struct ShutterTiming {
  double exposure = 0, readout = 0;
  int rows = 1;

  /// δ_r, the offset of row r's mid-exposure.
  double rowCentre(int r) const { return (static_cast<double>(r) - 0.5 * (rows - 1)) / rows * readout; }
  double rowBegin(int r) const { return rowCentre(r) - 0.5 * exposure; }
  double rowEnd(int r) const { return rowCentre(r) + 0.5 * exposure; }
  /// The union of the rows' windows: [−span/2, span/2], span = R(H−1)/H + E.
  double span() const { return readout * (rows - 1) / rows + exposure; }

  /// τ_0 … τ_{S−1} for S sub-frames (S odd; S = 1 gives {0}); the middle one is exactly 0.
  std::vector<double> subframeTimes(int S) const {
    std::vector<double> t(static_cast<std::size_t>(S), 0.0);
    if (S < 2) return t;
    const double step = span() / (S - 1);
    const int m = (S - 1) / 2;
    for (int s = 0; s < S; ++s) t[static_cast<std::size_t>(s)] = (s - m) * step;
    return t;
  }

  /// w_s(r) of the file comment for sub-frame times `t` (increasing): the mean of each hat
  /// function over row r's window (its value at the window's centre when E = 0). Σ_s w_s = 1.
  void rowWeights(const std::vector<double>& t, int r, double* w) const {
    const std::size_t S = t.size();
    std::fill(w, w + S, 0.0);
    if (S == 1) {
      w[0] = 1;
      return;
    }
    const double a = std::max(t.front(), rowBegin(r)), b = std::min(t.back(), rowEnd(r));
    if (!(b - a > 1e-12 * (t.back() - t.front()))) {
      // An instant (or a window squeezed to the ends by rounding): linear interpolation.
      const double c = std::min(t.back(), std::max(t.front(), 0.5 * (a + b)));
      std::size_t k = 0;
      while (k + 2 < S && c > t[k + 1]) ++k;
      const double u = (c - t[k]) / (t[k + 1] - t[k]);
      w[k] = 1 - u;
      w[k + 1] = u;
      return;
    }
    // ∫ over each segment [t_k, t_k+1] ∩ [a, b] of (1 − u) and u, u = (t − t_k)/(t_k+1 − t_k).
    for (std::size_t k = 0; k + 1 < S; ++k) {
      const double lo = std::max(a, t[k]), hi = std::min(b, t[k + 1]);
      if (!(hi > lo)) continue;
      const double d = t[k + 1] - t[k];
      const double u0 = (lo - t[k]) / d, u1 = (hi - t[k]) / d;
      const double iu = 0.5 * (u1 * u1 - u0 * u0) * d;  // ∫ u dt
      w[k + 1] += iu;
      w[k] += (hi - lo) - iu;
    }
    const double inv = 1.0 / (b - a);
    for (std::size_t k = 0; k < S; ++k) w[k] *= inv;
  }
};

/// Adaptive sub-frame count for an image motion of `motionPx` over the frame's window: 1 when
/// below one step, else ceil(motion/step) + 1 rounded up to odd, at most maxSubframes (odd).
inline int adaptiveSubframes(double motionPx, const CaptureOptions& o) {
  if (!(motionPx > o.subframeStepPx)) return 1;
  const int cap = std::max(1, o.maxSubframes | 1);
  const double n = std::ceil(motionPx / o.subframeStepPx) + 1;
  if (!(n < cap)) return cap;
  return static_cast<int>(n) | 1;
}

// ---------------------------------------------------------------------------------------------
// Exposure and white balance.

/// The auto-exposure of the file comment, one step at a time (log gains).
struct AutoExposure {
  const CaptureOptions& o;
  double fps;

  /// log g* for a metered grey m (unit gain, illumination 1), clamped to the gain range.
  double target(double m) const {
    const double v = m > 0 ? o.aeTarget / (o.illumination * m) : o.aeMaxGain;
    return std::log(std::min(o.aeMaxGain, std::max(o.aeMinGain, v)));
  }
  /// log g_i from log g_{i−1} and the previous frame's metered grey.
  double step(double logPrev, double meteredPrev) const {
    const double alpha = 1 - std::exp(-1.0 / (o.aeTime * fps));
    return logPrev + alpha * (target(meteredPrev) - logPrev);
  }
};

/// The auto-exposure recursion over metered greys m_0 … m_{T−1} (unit gain, illumination 1),
/// without the drift: g_i for every frame (the fixed gain when auto-exposure is off).
inline std::vector<double> autoExposureGains(const std::vector<double>& metered, double fps, const CaptureOptions& o) {
  std::vector<double> g(metered.size(), o.gain);
  if (!(o.aeTime > 0) || metered.empty()) return g;
  const AutoExposure ae{o, fps};
  double lg = ae.target(metered[0]);
  g[0] = std::exp(lg);
  for (std::size_t i = 1; i < metered.size(); ++i) {
    lg = ae.step(lg, metered[i - 1]);
    g[i] = std::exp(lg);
  }
  return g;
}

/// Centre-weighted mean grey (0.299 R + 0.587 G + 0.114 B) of a float W × H × 3 image, weights
/// exp(−(dx² + dy²)/(2·0.35²)) with dx, dy the offsets from the centre in half-sizes.
inline double meteredGrey(const ImageF& rgb) {
  double sum = 0, wsum = 0;
  const double hx = 0.5 * rgb.width, hy = 0.5 * rgb.height;
  for (int y = 0; y < rgb.height; ++y) {
    const double dy = (y + 0.5 - hy) / hy;
    const float* row = rgb.row(y);
    for (int x = 0; x < rgb.width; ++x) {
      const double dx = (x + 0.5 - hx) / hx;
      const double w = std::exp(-(dx * dx + dy * dy) / (2 * 0.35 * 0.35));
      sum += w * (0.299 * row[3 * x] + 0.587 * row[3 * x + 1] + 0.114 * row[3 * x + 2]);
      wsum += w;
    }
  }
  return wsum > 0 ? sum / wsum : 0;
}

/// What one frame's capture was (and what the writer records).
struct CaptureFrameInfo {
  int subframes = 1;
  double motionPx = 0;           ///< image motion over the frame's window (adaptive sub-frames)
  double exposureGain = 1;       ///< g (auto-exposure or fixed, with drift)
  double whiteBalance[3] = {1, 1, 1};  ///< b_r, b_g = 1, b_b
};

// ---------------------------------------------------------------------------------------------
// Lens.

/// Intrinsics of a W × H camera whose lens spans `fovDeg` across the image diagonal (file
/// comment); PinholeCamera::fromFov itself for a pinhole lens. Throws hawor::Error when the lens
/// folds before the image corners (Lens::validate, CameraModel::validate).
template <typename Scalar>
PinholeCamera<Scalar> lensIntrinsics(int W, int H, double fovDeg, const Lens<double>& lens) {
  if (lens.kind == LensKind::Pinhole) return PinholeCamera<Scalar>::fromFov(W, H, Scalar(fovDeg));
  const double half = fovDeg * 3.14159265358979323846 / 360.0;
  lens.validate(half);
  const double diag = std::sqrt(double(W) * W + double(H) * H);
  const Vec3<double> p(std::sin(half) * W / diag, std::sin(half) * H / diag, std::cos(half));
  const double m = lens.project(p).norm();
  PinholeCamera<double> c;
  c.fx = c.fy = 0.5 * diag / m;
  c.cx = (W - 1) / 2.0;
  c.cy = (H - 1) / 2.0;
  c.width = W;
  c.height = H;
  CameraModel<double>{c, lens}.validate();  // every corner within the lens's monotonic field
  return c.template cast<Scalar>();
}

/// The pinhole views that render a lens camera and the map from each output pixel to them
/// (file comment: Lens). Built once per camera.
template <typename Scalar>
struct LensViews {
  struct View {
    Mat3<double> R = Mat3<double>::Identity();  ///< view ← camera rotation
    PinholeCamera<Scalar> cam;                   ///< the cropped view
    std::vector<int> rowMin, rowMax;             ///< per output row: view rows it reads (rowMin > rowMax: none)
  };
  std::vector<View> views;
  int width = 0, height = 0;      ///< output size
  double focalFactor = 1;         ///< ρ
  std::vector<std::uint8_t> view;  ///< per output pixel: view index, 255 = outside the lens's field
  std::vector<float> sx, sy;       ///< per output pixel: view pixel coordinates
  std::vector<float> depthFactor;  ///< z_out = z_view · factor at the nearest view pixel

  /// The view rows that output rows [r0, r1] read in view v: [lo, hi] (lo > hi: none).
  void viewRows(std::size_t v, int r0, int r1, int& lo, int& hi) const {
    lo = std::numeric_limits<int>::max(), hi = -1;
    for (int r = r0; r <= r1; ++r) {
      lo = std::min(lo, views[v].rowMin[static_cast<std::size_t>(r)]);
      hi = std::max(hi, views[v].rowMax[static_cast<std::size_t>(r)]);
    }
  }

  static LensViews build(const PinholeCamera<Scalar>& K, const Lens<double>& lens) {
    LensViews L;
    const int W = K.width, H = K.height;
    L.width = W, L.height = H;
    const std::size_t N = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
    // Cube faces: +z, +x, −x, +y, −y (rows of R = the view's axes in the camera frame).
    Mat3<double> faces[5];
    faces[0].setIdentity();
    faces[1] << 0, 0, -1, 0, 1, 0, 1, 0, 0;
    faces[2] << 0, 0, 1, 0, 1, 0, -1, 0, 0;
    faces[3] << 1, 0, 0, 0, 0, -1, 0, 1, 0;
    faces[4] << 1, 0, 0, 0, 0, 1, 0, -1, 0;
    const double fx = static_cast<double>(K.fx), fy = static_cast<double>(K.fy);
    const double cx = static_cast<double>(K.cx), cy = static_cast<double>(K.cy);
    std::vector<Vec3<double>> bearing(N);
    L.view.assign(N, 255);
    for (int y = 0; y < H; ++y) {
      for (int x = 0; x < W; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * W + x;
        Vec3<double> b;
        if (!lens.unproject(Vec2<double>((x - cx) / fx, (y - cy) / fy), b)) continue;
        bearing[p] = b;
        int best = 0;
        for (int f = 1; f < 5; ++f)
          if (faces[f].row(2).dot(b) > faces[best].row(2).dot(b)) best = f;
        L.view[p] = static_cast<std::uint8_t>(best);
      }
    }
    // ρ: every output step must map to at least one view pixel at f_v = ρ·f (the smallest
    // singular value of d(view pixel)/d(output pixel) at ρ = 1, from forward differences).
    auto raw = [&](int f, const Vec3<double>& b) {
      const Vec3<double> q = faces[f] * b;
      return Vec2<double>(fx * q.x() / q.z(), fy * q.y() / q.z());
    };
    double rho = 1;
    for (int y = 0; y + 1 < H; ++y) {
      for (int x = 0; x + 1 < W; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * W + x;
        if (L.view[p] == 255 || L.view[p + 1] == 255 || L.view[p + W] == 255) continue;
        const int f = L.view[p];
        const Vec2<double> a = raw(f, bearing[p]);
        Eigen::Matrix2d J;
        J.col(0) = raw(f, bearing[p + 1]) - a;
        J.col(1) = raw(f, bearing[p + W]) - a;
        // σ_min² = (‖J‖² − √(‖J‖⁴ − 4 det²))/2.
        const double n2 = J.squaredNorm(), det = J.determinant();
        const double smin = std::sqrt(std::max(0.0, 0.5 * (n2 - std::sqrt(std::max(0.0, n2 * n2 - 4 * det * det)))));
        if (smin > 1e-9) rho = std::max(rho, 1 / smin);
      }
    }
    L.focalFactor = rho = std::min(rho, 2.0);
    // Each used view: the bounding box of the view pixels it serves (bilinear neighbours and a
    // pixel of margin), as a cropped pinhole camera.
    L.sx.assign(N, 0.0f);
    L.sy.assign(N, 0.0f);
    L.depthFactor.assign(N, 1.0f);
    int index[5] = {-1, -1, -1, -1, -1};
    std::vector<Vec2<double>> src(N);
    double lo[5][2], hi[5][2];
    for (int f = 0; f < 5; ++f) lo[f][0] = lo[f][1] = 1e300, hi[f][0] = hi[f][1] = -1e300;
    for (std::size_t p = 0; p < N; ++p) {
      if (L.view[p] == 255) continue;
      const int f = L.view[p];
      src[p] = rho * raw(f, bearing[p]);
      for (int c = 0; c < 2; ++c) {
        lo[f][c] = std::min(lo[f][c], src[p](c));
        hi[f][c] = std::max(hi[f][c], src[p](c));
      }
    }
    for (int f = 0; f < 5; ++f) {
      if (hi[f][0] < lo[f][0]) continue;
      View v;
      v.R = faces[f];
      const double x0 = std::floor(lo[f][0]) - 1, y0 = std::floor(lo[f][1]) - 1;
      const double x1 = std::floor(hi[f][0]) + 2, y1 = std::floor(hi[f][1]) + 2;
      const double fv = rho * fx, fvy = rho * fy;
      v.cam.fx = Scalar(fv);
      v.cam.fy = Scalar(fvy);
      v.cam.cx = Scalar(-x0);
      v.cam.cy = Scalar(-y0);
      v.cam.width = static_cast<int>(x1 - x0 + 1);
      v.cam.height = static_cast<int>(y1 - y0 + 1);
      if (v.cam.width > 16 * (W + H) || v.cam.height > 16 * (W + H)) {
        throw Error("capture: lens " + lens.toString() + " needs a view of " + std::to_string(v.cam.width) + "x" +
                    std::to_string(v.cam.height) + " pixels (too wide a field for the cube views)");
      }
      v.rowMin.assign(static_cast<std::size_t>(H), std::numeric_limits<int>::max());
      v.rowMax.assign(static_cast<std::size_t>(H), -1);
      index[f] = static_cast<int>(L.views.size());
      L.views.push_back(v);
    }
    for (int y = 0; y < H; ++y) {
      for (int x = 0; x < W; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * W + x;
        if (L.view[p] == 255) continue;
        const int f = L.view[p];
        View& v = L.views[static_cast<std::size_t>(index[f])];
        L.view[p] = static_cast<std::uint8_t>(index[f]);
        const double X = src[p].x() + static_cast<double>(v.cam.cx), Y = src[p].y() + static_cast<double>(v.cam.cy);
        L.sx[p] = static_cast<float>(X);
        L.sy[p] = static_cast<float>(Y);
        const int ry = static_cast<int>(std::floor(Y));
        v.rowMin[static_cast<std::size_t>(y)] = std::min(v.rowMin[static_cast<std::size_t>(y)], ry);
        v.rowMax[static_cast<std::size_t>(y)] = std::max(v.rowMax[static_cast<std::size_t>(y)], ry + 1);
        // The nearest view pixel's ray, in the camera frame: z_out = z_view·(Rᵀ·ray).z.
        const double nx = std::floor(X + 0.5), ny = std::floor(Y + 0.5);
        const Vec3<double> ray((nx - static_cast<double>(v.cam.cx)) / static_cast<double>(v.cam.fx),
                               (ny - static_cast<double>(v.cam.cy)) / static_cast<double>(v.cam.fy), 1.0);
        L.depthFactor[p] = static_cast<float>(v.R.col(2).dot(ray));
      }
    }
    return L;
  }
};

// ---------------------------------------------------------------------------------------------
// The renderer.

/// Per-frame inputs of CaptureRenderer::render.
struct CaptureExposure {
  int subframes = 1;                 ///< S (made odd)
  double illumination = 1;           ///< λ
  double channelGain[3] = {1, 1, 1};  ///< G_c = g·b_c
  double readNoise = 0, shotNoise = 0;  ///< σ_r (grey levels), k
  std::uint32_t noiseSeed = 0;
};

/// Renders frames through the capture model of the file comment: sub-frames over the shutter's
/// window, the lens views, gains, noise, quantisation.
template <typename Scalar>
class CaptureRenderer {
 public:
  /// `camera` (intrinsics) with `lens` sees `scene`; `exposure` and `readout` in seconds.
  CaptureRenderer(const IndoorScene<Scalar>& scene, const PinholeCamera<Scalar>& camera, const Lens<double>& lens,
                  double exposure, double readout)
      : camera_(camera), renderer_(scene, camera) {
    timing_.exposure = exposure;
    timing_.readout = readout;
    timing_.rows = camera.height;
    if (!lens.isPinhole()) views_ = std::make_unique<LensViews<Scalar>>(LensViews<Scalar>::build(camera, lens));
  }

  const PinholeCamera<Scalar>& camera() const { return camera_; }
  const ShutterTiming& timing() const { return timing_; }
  /// The lens views (nullptr for a pinhole lens: the output camera renders directly).
  const LensViews<Scalar>* views() const { return views_.get(); }

  /// Renders one frame. at(τ, roomFromCamera, hands) fills the state at the reference time + τ
  /// seconds (τ = 0: the frame's own; hands in the camera frame, their vertices kept alive by the
  /// caller until the next call). Fills out.rgb, out.depth, out.mask, out.handPixels.
  template <typename StateFn>
  void render(StateFn&& at, const CaptureExposure& ex, RenderedImages& out) {
    const int W = camera_.width, H = camera_.height;
    const std::size_t N = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
    const int S = std::max(1, ex.subframes | 1);
    const int mid = (S - 1) / 2;
    const std::vector<double> times = timing_.subframeTimes(S);
    weights_.assign(static_cast<std::size_t>(H) * S, 0.0f);
    std::vector<double> w(static_cast<std::size_t>(S));
    for (int r = 0; r < H; ++r) {
      timing_.rowWeights(times, r, w.data());
      for (int s = 0; s < S; ++s) weights_[static_cast<std::size_t>(r) * S + s] = static_cast<float>(w[static_cast<std::size_t>(s)]);
    }
    acc_.assign(3 * N, 0.0f);
    RigidPose<Scalar> pose;
    for (int s = 0; s < S; ++s) {
      // Rows this sub-frame contributes to.
      int r0 = H, r1 = -1;
      for (int r = 0; r < H; ++r) {
        if (weights_[static_cast<std::size_t>(r) * S + s] > 0.0f) r0 = std::min(r0, r), r1 = r;
      }
      const bool reference = s == mid;
      if (r1 < r0 && !reference) continue;
      hands_.clear();
      at(times[static_cast<std::size_t>(s)], pose, hands_);
      if (!views_) {
        // The output camera itself: the whole image for the reference (mask and depth), else
        // the band of rows [r0, r1].
        const int b0 = reference ? 0 : r0, b1 = reference ? H - 1 : r1;
        renderBand(pose, hands_, camera_, b0, b1, lin_, reference ? out : scratch_);
        for (int r = std::max(r0, b0); r <= r1; ++r) {
          const float wr = weights_[static_cast<std::size_t>(r) * S + s];
          if (!(wr > 0.0f)) continue;
          const float* src = lin_.row(r - b0);
          float* dst = acc_.data() + static_cast<std::size_t>(r) * W * 3;
          for (int k = 0; k < 3 * W; ++k) dst[k] += wr * src[k];
        }
        continue;
      }
      // Lens: render every view's band, then resample the output rows.
      const LensViews<Scalar>& L = *views_;
      const int o0 = reference ? 0 : r0, o1 = reference ? H - 1 : r1;
      viewLin_.resize(L.views.size());
      viewGeo_.resize(L.views.size());
      viewBand_.assign(L.views.size(), 0);
      for (std::size_t v = 0; v < L.views.size(); ++v) {
        int lo, hi;
        L.viewRows(v, o0, o1, lo, hi);
        lo = std::max(lo, 0);
        hi = std::min(hi, L.views[v].cam.height - 1);
        if (hi < lo) {
          viewBand_[v] = -1;
          continue;
        }
        viewBand_[v] = lo;
        const RigidPose<Scalar> roomFromView = pose * RigidPose<Scalar>{L.views[v].R.transpose().template cast<Scalar>(), Vec3<Scalar>::Zero()};
        turnHands(L.views[v].R, hands_, viewHands_, viewVerts_);
        renderBand(roomFromView, viewHands_, L.views[v].cam, lo, hi, viewLin_[v], viewGeo_[v]);
      }
      for (int r = o0; r <= o1; ++r) {
        const float wr = weights_[static_cast<std::size_t>(r) * S + s];
        float* dst = acc_.data() + static_cast<std::size_t>(r) * W * 3;
        for (int x = 0; x < W; ++x) {
          const std::size_t p = static_cast<std::size_t>(r) * W + x;
          const int v = L.view[p];
          if (v == 255) continue;
          if (wr > 0.0f) {
            const ImageF& img = viewLin_[static_cast<std::size_t>(v)];
            const float X = L.sx[p], Y = L.sy[p] - static_cast<float>(viewBand_[static_cast<std::size_t>(v)]);
            const int x0 = std::min(std::max(static_cast<int>(std::floor(X)), 0), img.width - 2);
            const int y0 = std::min(std::max(static_cast<int>(std::floor(Y)), 0), img.height - 2);
            const float ax = std::min(1.0f, std::max(0.0f, X - x0)), ay = std::min(1.0f, std::max(0.0f, Y - y0));
            const float* a = img.row(y0) + 3 * x0;
            const float* b = img.row(y0 + 1) + 3 * x0;
            for (int c = 0; c < 3; ++c) {
              const float top = a[c] + ax * (a[3 + c] - a[c]);
              const float bot = b[c] + ax * (b[3 + c] - b[c]);
              dst[3 * x + c] += wr * (top + ay * (bot - top));
            }
          }
        }
      }
      if (reference) resampleGeometry(out);
    }
    finish(ex, out);
  }

 private:
  // Renders rows [y0, y1] of `cam` (a band camera: cy − y0, height y1 − y0 + 1) into `rgb`.
  void renderBand(const RigidPose<Scalar>& roomFromCamera, const std::vector<HandMeshView<Scalar>>& hands,
                  const PinholeCamera<Scalar>& cam, int y0, int y1, ImageF& rgb, RenderedImages& geo) {
    PinholeCamera<Scalar> band = cam;
    band.cy = cam.cy - Scalar(y0);
    band.height = y1 - y0 + 1;
    renderer_.setCamera(band);
    renderer_.renderLinear(roomFromCamera, hands, rgb, geo);
  }

  // Hand meshes turned into a view frame (p_v = R·p_c); the +z view keeps the caller's.
  static void turnHands(const Mat3<double>& R, const std::vector<HandMeshView<Scalar>>& in, std::vector<HandMeshView<Scalar>>& out,
                        std::vector<Points3<Scalar>>& verts) {
    out = in;
    if (R.isIdentity(0)) return;
    verts.resize(in.size());
    const Mat3<Scalar> Rs = R.template cast<Scalar>();
    for (std::size_t h = 0; h < in.size(); ++h) {
      const Points3<Scalar>& v = *in[h].vertices;
      verts[h].resize(v.rows(), 3);
      for (Eigen::Index k = 0; k < v.rows(); ++k) verts[h].row(k) = (Rs * v.row(k).transpose()).transpose();
      out[h].vertices = &verts[h];
    }
  }

  // Mask and depth of the reference sub-frame through the lens: the nearest view pixel (hands_
  // holds the reference's meshes: their labels count the hand pixels). Outside the lens's
  // field: mask 0, depth +inf.
  void resampleGeometry(RenderedImages& out) {
    const LensViews<Scalar>& L = *views_;
    const int W = camera_.width, H = camera_.height;
    out.depth.resize(W, H, 1, std::numeric_limits<float>::infinity());
    out.mask.resize(W, H, 1, 0);
    out.handPixels.assign(hands_.size(), 0);
    for (std::size_t p = 0; p < out.mask.data.size(); ++p) {
      const int v = L.view[p];
      if (v == 255 || viewBand_[static_cast<std::size_t>(v)] < 0) continue;
      const RenderedImages& g = viewGeo_[static_cast<std::size_t>(v)];
      const int nx = static_cast<int>(std::floor(L.sx[p] + 0.5f));
      const int ny = static_cast<int>(std::floor(L.sy[p] + 0.5f)) - viewBand_[static_cast<std::size_t>(v)];
      if (nx < 0 || ny < 0 || nx >= g.depth.width || ny >= g.depth.height) continue;
      out.depth.data[p] = g.depth.at(nx, ny) * L.depthFactor[p];
      const std::uint8_t m = g.mask.at(nx, ny);
      out.mask.data[p] = m;
      if (m == 0) continue;
      for (std::size_t h = 0; h < hands_.size(); ++h) {
        if (hands_[h].label == m) ++out.handPixels[h];
      }
    }
  }

  // Gains, noise and bytes (file comment: Light and sensor).
  void finish(const CaptureExposure& ex, RenderedImages& out) {
    const int W = camera_.width, H = camera_.height;
    out.rgb.resize(W, H, 3);
    float G[3], G2r[3], Gk[3];
    for (int c = 0; c < 3; ++c) {
      G[c] = static_cast<float>(ex.channelGain[c] * ex.illumination);
      G2r[c] = static_cast<float>(ex.channelGain[c] * ex.channelGain[c] * ex.readNoise * ex.readNoise);
      Gk[c] = static_cast<float>(ex.channelGain[c] * ex.shotNoise);
    }
    const bool noisy = ex.readNoise > 0 || ex.shotNoise > 0;
    const float invSd = 1.0f / 147.801f;  // √(4·(256² − 1)/12): the Irwin–Hall sum's deviation
    const std::size_t N = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
    for (std::size_t q = 0; q < N; ++q) {
      for (int c = 0; c < 3; ++c) {
        const std::size_t p = 3 * q + static_cast<std::size_t>(c);
        float v = acc_[p] * G[c];
        if (noisy) {
          const float var = G2r[c] + Gk[c] * (v > 0.0f ? v : 0.0f);
          const std::uint32_t h = hash32(ex.noiseSeed ^ (static_cast<std::uint32_t>(p) * 0x9E3779B1u));
          const float z = (static_cast<float>(h & 0xFFu) + static_cast<float>((h >> 8) & 0xFFu) +
                           static_cast<float>((h >> 16) & 0xFFu) + static_cast<float>(h >> 24) - 510.0f) *
                          invSd;
          v += std::sqrt(var) * z;
        }
        const float cl = v < 0.0f ? 0.0f : (v > 255.0f ? 255.0f : v);
        out.rgb.data[p] = static_cast<std::uint8_t>(cl + 0.5f);
      }
    }
  }

  PinholeCamera<Scalar> camera_;
  SceneRenderer<Scalar> renderer_;
  ShutterTiming timing_;
  std::unique_ptr<LensViews<Scalar>> views_;
  // Scratch.
  std::vector<float> weights_, acc_;
  ImageF lin_;
  RenderedImages scratch_;
  std::vector<HandMeshView<Scalar>> hands_, viewHands_;
  std::vector<Points3<Scalar>> viewVerts_;
  std::vector<ImageF> viewLin_;
  std::vector<RenderedImages> viewGeo_;
  std::vector<int> viewBand_;
};

/// SLERP of the rotations (wrist and every joint, as axis-angles) and LERP of translation and
/// shape between two hand poses, u ∈ [0, 1]; u = 0 and 1 return a and b exactly.
template <typename Scalar>
HandPose<Scalar> interpolateHandPose(const HandPose<Scalar>& a, const HandPose<Scalar>& b, Scalar u) {
  if (u <= Scalar(0)) return a;
  if (u >= Scalar(1)) return b;
  auto slerp = [u](const Vec3<Scalar>& x, const Vec3<Scalar>& y) {
    const Eigen::Quaternion<Scalar> qx = axisAngleToQuaternion(x), qy = axisAngleToQuaternion(y);
    return Vec3<Scalar>(quaternionToAxisAngle(qx.slerp(u, qy)));
  };
  HandPose<Scalar> p = a;
  p.rot = slerp(a.rot, b.rot);
  for (Eigen::Index j = 0; j < a.handPose.rows(); ++j) {
    p.handPose.row(j) = slerp(a.handPose.row(j).transpose(), b.handPose.row(j).transpose()).transpose();
  }
  p.trans = a.trans + u * (b.trans - a.trans);
  if (a.betas.size() == b.betas.size()) p.betas = a.betas + u * (b.betas - a.betas);
  return p;
}

}  // namespace synth
}  // namespace hawor
