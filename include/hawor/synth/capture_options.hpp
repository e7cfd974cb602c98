// hawor/synth/capture_options.hpp — the capture settings of the synthetic generator (capture.hpp
// renders them): exposure and rolling-shutter readout, sensor noise, auto-exposure and white-
// balance drift, illumination, the lens, and the encoding a benchmark applies afterwards; the
// named profiles that bundle them (captureProfiles(): clean, phone, action_cam, aria, low_light,
// webcam_360p) and the fields the CLI sets by name (setCaptureField). `clean` is the generator's
// own output (global shutter, no blur, pinhole, the preset's noise: the same bytes as without
// capture options).
// Thread-safety: options and profiles are values.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/lens.hpp"

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

}  // namespace synth
}  // namespace hawor
