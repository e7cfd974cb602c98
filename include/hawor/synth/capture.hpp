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
// The settings and the named profiles that bundle them are in capture_options.hpp.
// Thread-safety: a CaptureRenderer holds scratch buffers (one per thread).
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
#include "hawor/synth/capture_options.hpp"
#include "hawor/synth/random.hpp"
#include "hawor/synth/renderer.hpp"
#include "hawor/synth/scene.hpp"
#include "hawor/synth/trajectory.hpp"

namespace hawor {
namespace synth {

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
