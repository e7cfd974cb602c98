// The capture model of the synthetic generator (synth/capture.hpp), float and double where it is
// templated: the clean profile gives the generator's own bytes; the shutter's timing and row
// weights; motion blur and the rolling shutter against the closed forms on a wall with one
// vertical edge turned about the vertical axis (blur length f·ω·E, shear f·ω·R·(H−1)/H);
// distortion against the lens model (a straight edge curved as the lens projects it, the
// hands' ground-truth joints re-projected through the lens onto their mask, depth along the
// lens's rays); noise statistics on flat patches; auto-exposure and white balance bounded,
// lagging as specified and deterministic per seed; profiles, fields and their errors.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "hawor/io/file.hpp"
#include "synth_test_util.hpp"

template class hawor::synth::CaptureRenderer<float>;
template class hawor::synth::CaptureRenderer<double>;
template struct hawor::synth::LensViews<float>;
template struct hawor::synth::LensViews<double>;

namespace capture_test {

using namespace synth_test;
using hawor::Lens;
using hawor::Mat3;
using hawor::PinholeCamera;

/// A wall z = 2 m (room frame), ±20 m, lit to exactly its texture (ambient 1), grey `left` for
/// x < 0 and `right` for x > 0: one vertical edge at x = 0.
template <typename S>
hs::IndoorScene<S> wallScene(float left, float right) {
  hs::IndoorScene<S> sc;
  const S hw = S(20), z = S(2);
  sc.textures.push_back(hs::Texture::generate(1024, [&](int x, int) {
    const float g = x < 512 ? left : right;
    return hs::Rgb(g, g, g);
  }));
  sc.materials.push_back({0, hs::Rgb(1, 1, 1), 1024.0f / (2 * 20.0f)});
  sc.vertices.resize(4, 3);
  sc.vertices << -hw, -hw, z, hw, -hw, z, hw, hw, z, -hw, hw, z;
  sc.faces.resize(2, 3);
  sc.faces << 0, 1, 2, 0, 2, 3;
  sc.uv = {0, 0, 40, 0, 40, 40, 0, 40};
  sc.faceMaterial = {0, 0};
  sc.ambient = 1, sc.light1 = 0, sc.light2 = 0;
  return sc;
}

/// Camera-to-room rotation turned by `a` about the (shared) y axis: R_y(a).
template <typename S>
Mat3<S> turnY(double a) {
  Mat3<S> R;
  R << S(std::cos(a)), S(0), S(std::sin(a)), S(0), S(1), S(0), S(-std::sin(a)), S(0), S(std::cos(a));
  return R;
}

/// Renders the wall through a CaptureRenderer with the camera turning at ω rad/s about y from
/// the yaw β at the reference time.
template <typename S>
hawor::synth::RenderedImages renderWall(const hs::IndoorScene<S>& scene, const PinholeCamera<S>& cam, const Lens<double>& lens,
                                        double exposure, double readout, int subframes, double beta, double omega,
                                        const hs::CaptureExposure* exposureIn = nullptr) {
  hs::CaptureRenderer<S> r(scene, cam, lens, exposure, readout);
  hs::CaptureExposure ex;
  if (exposureIn) ex = *exposureIn;
  ex.subframes = subframes;
  hawor::synth::RenderedImages out;
  r.render([&](double tau, hs::RigidPose<S>& P, std::vector<hs::HandMeshView<S>>& hands) {
    P.R = turnY<S>(beta + omega * tau);
    P.t.setZero();
    hands.clear();
  }, ex, out);
  return out;
}

/// Grey of pixel (x, y) of an RGB byte image.
inline double greyAt(const hawor::ImageU8& im, int x, int y) {
  const unsigned char* p = im.row(y) + 3 * x;
  return (p[0] + p[1] + p[2]) / 3.0;
}

/// Sub-pixel x where row y first crosses `level` going right (linear between pixels); NaN if
/// it never does.
inline double crossing(const hawor::ImageU8& im, int y, double level) {
  for (int x = 0; x + 1 < im.width; ++x) {
    const double a = greyAt(im, x, y), b = greyAt(im, x + 1, y);
    if (a < level && b >= level) return x + (level - a) / (b - a);
  }
  return NAN;
}

template <typename S>
bool sameImages(const hs::RenderedImages& a, const hs::RenderedImages& b) {
  if (a.rgb.data != b.rgb.data || a.mask.data != b.mask.data || a.handPixels != b.handPixels) return false;
  if (a.depth.data.size() != b.depth.data.size()) return false;
  for (std::size_t i = 0; i < a.depth.data.size(); ++i)
    if (a.depth.data[i] != b.depth.data[i]) return false;
  return true;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const hawor::Error& e) {
    return e.what();
  }
  return "<no error>";
}

}  // namespace capture_test

TEST_CASE("capture: profiles, fields, encoding specs and their errors", "[synth]") {
  using namespace capture_test;
  const std::vector<std::string> names = hs::captureProfileNames();
  for (const char* n : {"clean", "phone", "action_cam", "aria", "low_light", "webcam_360p"}) {
    CHECK(std::find(names.begin(), names.end(), n) != names.end());
  }
  for (const hs::CaptureProfile& p : hs::captureProfiles()) {
    INFO(p.name);
    CHECK(!p.description.empty());
    CHECK(p.options.profile == p.name);
    p.options.validate();
    CHECK(p.options.isClean() == (p.name == "clean"));
    CHECK(p.options.usesPipeline() == (p.name != "clean"));
    // Every profile's lens serves its field of view at 640 × 480 and 64 × 48.
    for (int w : {640, 64}) {
      const PinholeCamera<double> K = hs::lensIntrinsics<double>(w, w * 3 / 4, p.options.fovDeg > 0 ? p.options.fovDeg : 90, p.options.lens);
      CHECK(K.fx > 0);
      CHECK(K.cx == Approx((w - 1) / 2.0));
    }
    // The encoding spec reads back.
    CHECK(hs::EncodeSpec::parse(p.options.encode.toString()).toString() == p.options.encode.toString());
  }
  // Lenses: the intrinsics put the diagonal's end at fov/2 through the lens.
  const hs::CaptureOptions ac = hs::findCaptureProfile("action_cam");
  const PinholeCamera<double> K = hs::lensIntrinsics<double>(640, 480, ac.fovDeg, ac.lens);
  hawor::Vec3<double> b;
  REQUIRE(ac.lens.unproject(hawor::Vec2<double>((639.5 - K.cx) / K.fx, (479.5 - K.cy) / K.fy), b));
  CHECK(std::acos(b.z()) * 360 / 3.14159265358979323846 == Approx(125).epsilon(0.01));
  // A pinhole lens gives PinholeCamera::fromFov exactly.
  const PinholeCamera<double> P = hs::lensIntrinsics<double>(640, 480, 90, Lens<double>::pinhole());
  CHECK(P.fx == PinholeCamera<double>::fromFov(640, 480, 90).fx);
  // Encoding: the phone's 17 Mbit/s at 1080p30 is 0.27 bit per pixel at any size.
  const hs::EncodeSpec::Resolved e = hs::findCaptureProfile("phone").encode.resolve(640, 480, 30);
  CHECK(e.width == 640);
  CHECK(e.height == 480);
  CHECK(e.kbps == Approx(17000.0 * 640 * 480 / (1920 * 1080)));
  CHECK(std::find(e.ffmpegArgs.begin(), e.ffmpegArgs.end(), "libx264") != e.ffmpegArgs.end());
  const hs::EncodeSpec::Resolved w = hs::findCaptureProfile("webcam_360p").encode.resolve(640, 480, 30);
  CHECK(w.height == 360);
  CHECK(w.width == 480);
  CHECK(std::find(w.ffmpegArgs.begin(), w.ffmpegArgs.end(), "scale=480:360") != w.ffmpegArgs.end());
  const hs::EncodeSpec crf = hs::EncodeSpec::parse("vp9,crf=30");
  CHECK(crf.resolve(64, 48, 30).ffmpegArgs[3] == "30");
  // Fields override a profile; errors name the field and the value.
  hs::CaptureOptions o = hs::findCaptureProfile("phone");
  hs::setCaptureField(o, "exposure", "0.02");
  hs::setCaptureField(o, "lens", "fisheye:0.01,0,0,0");
  hs::setCaptureField(o, "fov", "140");
  CHECK(o.exposure == 0.02);
  CHECK(o.lens.kind == hawor::LensKind::Fisheye);
  CHECK(o.readout == 0.025);  // the profile's, untouched
  o.validate();
  CHECK(errorOf([&] { hs::setCaptureField(o, "exposure", "fast"); }).find("exposure expects a finite number, got 'fast'") !=
        std::string::npos);
  CHECK(errorOf([&] { hs::setCaptureField(o, "shutter", "1"); }).find("unknown field 'shutter'") != std::string::npos);
  CHECK(errorOf([&] { hs::setCaptureField(o, "lens", "kb:1"); }).find("kb") != std::string::npos);
  CHECK(errorOf([&] { hs::setCaptureField(o, "encode", "mpeg2"); }).find("unknown codec 'mpeg2'") != std::string::npos);
  CHECK(errorOf([&] { hs::setCaptureField(o, "subframes", "2.5"); }).find("whole number") != std::string::npos);
  hs::CaptureOptions bad = o;
  bad.exposure = 2;
  CHECK(errorOf([&] { bad.validate(); }).find("exposure 2 s outside [0, 1] s") != std::string::npos);
  bad = hs::findCaptureProfile("clean");
  bad.fovDeg = 160;  // a pinhole cannot
  CHECK(errorOf([&] { bad.validate(); }).find("fov 160") != std::string::npos);
  CHECK(errorOf([] { hs::findCaptureProfile("cinema"); }).find("known profiles: clean, phone") != std::string::npos);
  // A radial-tangential lens that folds before the corners is refused, naming the fold.
  CHECK(errorOf([&] { hs::lensIntrinsics<double>(640, 480, 160, ac.lens); }).find("folds") != std::string::npos);
}

TEST_CASE("capture: shutter timing, row weights and adaptive sub-frames", "[synth]") {
  using namespace capture_test;
  hs::ShutterTiming T;
  T.exposure = 0.01, T.readout = 0.03, T.rows = 48;
  // The middle row's mid-exposure is the reference time; the rows start R/H apart.
  CHECK(T.rowCentre(0) + T.rowCentre(47) == Approx(0).margin(1e-15));
  CHECK(T.rowBegin(1) - T.rowBegin(0) == Approx(0.03 / 48));
  CHECK(T.span() == Approx(0.03 * 47 / 48 + 0.01));
  for (int S : {1, 3, 9, 25}) {
    const std::vector<double> t = T.subframeTimes(S);
    REQUIRE(t.size() == std::size_t(S));
    CHECK(t[std::size_t((S - 1) / 2)] == 0.0);  // exactly the reference
    if (S > 1) {
      CHECK(t.front() == Approx(T.rowBegin(0)));
      CHECK(t.back() == Approx(T.rowEnd(47)));
    }
    std::vector<double> w(std::size_t(S), 0.0);
    for (int r = 0; r < 48; ++r) {
      T.rowWeights(t, r, w.data());
      double sum = 0, mean = 0;
      for (int s = 0; s < S; ++s) {
        CHECK(w[std::size_t(s)] >= -1e-15);
        sum += w[std::size_t(s)];
        mean += w[std::size_t(s)] * t[std::size_t(s)];
        // Only sub-frames within a step of the row's window take part.
        if (S > 1 && w[std::size_t(s)] > 0) {
          const double step = t[1] - t[0];
          CHECK(t[std::size_t(s)] > T.rowBegin(r) - step - 1e-12);
          CHECK(t[std::size_t(s)] < T.rowEnd(r) + step + 1e-12);
        }
      }
      CHECK(sum == Approx(1).epsilon(1e-12));
      // Hats reproduce linear functions: the weighted time is the window's centre.
      if (S > 1) CHECK(mean == Approx(T.rowCentre(r)).margin(1e-12));
    }
  }
  // An instant exposure interpolates linearly between the two nearest sub-frames.
  hs::ShutterTiming G;
  G.exposure = 0, G.readout = 0.02, G.rows = 10;
  const std::vector<double> t = G.subframeTimes(5);
  std::vector<double> w(5);
  G.rowWeights(t, 7, w.data());
  const double c = G.rowCentre(7);
  int nonzero = 0;
  for (double v : w) nonzero += v > 0 ? 1 : 0;
  CHECK(nonzero <= 2);
  CHECK(w[0] * t[0] + w[1] * t[1] + w[2] * t[2] + w[3] * t[3] + w[4] * t[4] == Approx(c).margin(1e-15));
  // Adaptive: one render when still, odd counts up to the cap.
  hs::CaptureOptions o;
  CHECK(hs::adaptiveSubframes(0, o) == 1);
  CHECK(hs::adaptiveSubframes(1.9, o) == 1);
  CHECK(hs::adaptiveSubframes(9, o) == 7);  // ceil(9/2) + 1 = 6 → 7
  CHECK(hs::adaptiveSubframes(1000, o) == 25);
  o.maxSubframes = 10;
  CHECK(hs::adaptiveSubframes(1000, o) == 11);
}

TEMPLATE_TEST_CASE("capture: exposure blurs a moving camera by f·ω·E and leaves a still one alone", "[synth]", float, double) {
  using namespace capture_test;
  using S = TestType;
  const hs::IndoorScene<S> scene = wallScene<S>(40, 200);
  const PinholeCamera<S> cam = PinholeCamera<S>::fromFov(64, 48, S(60));
  const double f = double(cam.fx);
  // Still camera: exposure and readout change nothing (any number of sub-frames).
  const hs::RenderedImages sharp = renderWall(scene, cam, Lens<double>::pinhole(), 0, 0, 1, 0.1, 0);
  const hs::RenderedImages still = renderWall(scene, cam, Lens<double>::pinhole(), 0.02, 0.03, 9, 0.1, 0);
  int differ = 0, maxDiff = 0;
  for (std::size_t i = 0; i < sharp.rgb.data.size(); ++i) {
    const int d = std::abs(int(sharp.rgb.data[i]) - int(still.rgb.data[i]));
    differ += d ? 1 : 0;
    maxDiff = std::max(maxDiff, d);
  }
  CHECK(maxDiff <= 1);
  CHECK(differ <= int(sharp.rgb.data.size() / 200));
  // The plain renderer gives the same bytes as the capture renderer with nothing to do.
  hs::SceneRenderer<S> plain(scene, cam);
  hs::RenderedImages direct;
  hs::RigidPose<S> P;
  P.R = turnY<S>(0.1);
  plain.render(P, {}, 0.0f, 0, direct);
  CHECK(sameImages<S>(direct, sharp));
  // Turning at ω with a global shutter: every row's edge becomes a ramp of length L = f·ω·E
  // (the mean of the edge positions over the exposure), centred where the edge is at the
  // reference time; the steepest gradient drops by about L.
  const double omega = 5, E = 0.02, L = f * omega * E;
  const hs::RenderedImages blur = renderWall(scene, cam, Lens<double>::pinhole(), E, 0, 31, 0.0, omega);
  double width = 0, centre = 0, gSharp = 0, gBlur = 0;
  for (int y = 4; y < 44; ++y) {
    const double x10 = crossing(blur.rgb, y, 40 + 0.1 * 160), x90 = crossing(blur.rgb, y, 40 + 0.9 * 160);
    width += (x90 - x10) / 40;
    centre += crossing(blur.rgb, y, 120) / 40;
    for (int x = 0; x + 1 < 64; ++x) {
      gSharp = std::max(gSharp, std::abs(greyAt(sharp.rgb, x + 1, y) - greyAt(sharp.rgb, x, y)));
      gBlur = std::max(gBlur, std::abs(greyAt(blur.rgb, x + 1, y) - greyAt(blur.rgb, x, y)));
    }
  }
  INFO("blur length " << L << " px: 10-90 % width " << width << ", centre " << centre);
  CHECK(width == Approx(0.8 * L).margin(0.6));
  CHECK(centre == Approx(double(cam.cx)).margin(0.25));
  CHECK(gBlur < 1.6 * 160 / L);
  CHECK(gSharp > 100);
  // The mask and depth are those of the reference time: the still frame's at yaw 0.
  const hs::RenderedImages ref = renderWall(scene, cam, Lens<double>::pinhole(), 0, 0, 1, 0.0, omega);
  CHECK(blur.depth.data == ref.depth.data);
}

TEMPLATE_TEST_CASE("capture: a rolling shutter shears a vertical edge by f·ω·R·(H−1)/H", "[synth]", float, double) {
  using namespace capture_test;
  using S = TestType;
  const hs::IndoorScene<S> scene = wallScene<S>(40, 200);
  const PinholeCamera<S> cam = PinholeCamera<S>::fromFov(64, 48, S(60));
  const double f = double(cam.fx), omega = 5, R = 0.03;
  // An instant exposure: row r sees the camera at δ_r = (r − (H−1)/2)/H·R, where the edge is at
  // x = cx − f·tan(ω·δ_r).
  const hs::RenderedImages im = renderWall(scene, cam, Lens<double>::pinhole(), 0, R, 21, 0.0, omega);
  hs::ShutterTiming T;
  T.readout = R, T.rows = 48;
  double worst = 0;
  for (int y = 0; y < 48; ++y) {
    const double expect = double(cam.cx) - f * std::tan(omega * T.rowCentre(y));
    worst = std::max(worst, std::abs(crossing(im.rgb, y, 120) - expect));
  }
  const double shear = crossing(im.rgb, 0, 120) - crossing(im.rgb, 47, 120);
  INFO("shear " << shear << " px, expected about " << f * omega * R * 47 / 48 << "; worst row off by " << worst);
  CHECK(worst < 0.3);
  CHECK(shear == Approx(f * omega * R * 47 / 48).epsilon(0.03));
  // Turning the other way shears the other way.
  const hs::RenderedImages back = renderWall(scene, cam, Lens<double>::pinhole(), 0, R, 21, 0.0, -omega);
  CHECK(crossing(back.rgb, 0, 120) - crossing(back.rgb, 47, 120) == Approx(-shear).margin(0.3));
}

TEMPLATE_TEST_CASE("capture: lens distortion curves a straight edge as the model projects it", "[synth]", float, double) {
  using namespace capture_test;
  using S = TestType;
  const hs::IndoorScene<S> scene = wallScene<S>(40, 200);
  for (const char* profile : {"action_cam", "aria"}) {
    const hs::CaptureOptions o = hs::findCaptureProfile(profile);
    const PinholeCamera<S> cam = hs::lensIntrinsics<S>(96, 72, o.fovDeg, o.lens);
    const double beta = 0.6;  // the edge off-centre (a line through the centre stays straight)
    const hs::RenderedImages im = renderWall(scene, cam, o.lens, 0, 0, 1, beta, 0);
    // The model's edge: the camera-frame line p(Y) = R_y(β)ᵀ(0, Y, 2), projected; for each row
    // the Y that lands on it (bisection: v(Y) increases), then its column.
    auto project = [&](double Y) {
      const hawor::Vec3<double> p(-2 * std::sin(beta), Y, 2 * std::cos(beta));
      const hawor::Vec2<double> m = o.lens.project(p);
      return hawor::Vec2<double>(double(cam.fx) * m.x() + double(cam.cx), double(cam.fy) * m.y() + double(cam.cy));
    };
    // Y within the lens's monotonic field (a radial-tangential polynomial folds beyond it).
    const double zc = 2 * std::cos(beta), xn = std::tan(beta);
    const double rmax = std::min(20.0, std::tan(std::min(1.5, 0.99 * o.lens.maxMonotonicAngle())));
    const double ymax = zc * std::sqrt(std::max(0.0, rmax * rmax - xn * xn));
    double worst = 0;
    std::vector<double> xs;
    for (int y = 2; y < 70; ++y) {
      double lo = -ymax, hi = ymax;
      if (!(project(lo).y() < y && project(hi).y() > y)) continue;
      for (int it = 0; it < 80; ++it) {
        const double mid = 0.5 * (lo + hi);
        (project(mid).y() < y ? lo : hi) = mid;
      }
      const double expect = project(0.5 * (lo + hi)).x();
      const double got = crossing(im.rgb, y, 120);
      worst = std::max(worst, std::abs(got - expect));
      xs.push_back(got);
    }
    CHECK(xs.size() > 60);
    // Curved: the middle of the edge is off the chord between its ends by pixels.
    const double chordMid = 0.5 * (xs.front() + xs.back());
    const double bow = std::abs(xs[xs.size() / 2] - chordMid);
    INFO(profile << ": worst row off the model by " << worst << " px, bow " << bow << " px");
    CHECK(worst < 0.35);
    CHECK(bow > 1.5);
    // Depth along every pixel's ray through the lens: the wall's plane n·p = 2 in the camera
    // frame (n = R_y(β)ᵀ·z), z = 2·b.z/(n·b); +inf where the ray passes the wall's end. Depth
    // comes from the nearest view pixel, whose ray is within 0.75 output pixel of the pixel's
    // own: it may differ by 0.75 of z's change to the neighbouring pixels.
    const hawor::Vec3<double> n(-std::sin(beta), 0, std::cos(beta));
    const Mat3<double> Rb = turnY<double>(beta);
    auto wallZ = [&](double x, double y, hawor::Vec3<double>* hit) -> double {
      hawor::Vec3<double> b;
      if (!o.lens.unproject(hawor::Vec2<double>((x - double(cam.cx)) / double(cam.fx), (y - double(cam.cy)) / double(cam.fy)), b)) return NAN;
      const double cosI = n.dot(b);
      if (hit) *hit = Rb * (b * (2 / cosI));
      return cosI > 0.05 ? 2 * b.z() / cosI : INFINITY;
    };
    int off = 0, wall = 0, past = 0;
    for (int y = 0; y < 72; ++y) {
      for (int x = 0; x < 96; ++x) {
        hawor::Vec3<double> hit;
        const double z = wallZ(x, y, &hit);
        REQUIRE(!std::isnan(z));
        if (std::isinf(z) || std::abs(hit.x()) > 19.5 || std::abs(hit.y()) > 19.5) {
          past += std::isinf(im.depth.at(x, y)) ? 1 : 0;
          continue;
        }
        ++wall;
        double change = 0;
        for (int k = 0; k < 4; ++k) change = std::max(change, std::abs(wallZ(x + (k == 0) - (k == 1), y + (k == 2) - (k == 3), nullptr) - z));
        if (!(std::abs(im.depth.at(x, y) - z) <= 0.002 * z + 0.75 * change)) ++off;
      }
    }
    INFO(profile << ": " << off << " of " << wall << " wall pixels off, " << past << " past the wall's end");
    CHECK(wall > 96 * 72 * 3 / 4);
    CHECK(off == 0);
  }
}

TEMPLATE_TEST_CASE("capture: the hands' ground-truth joints re-projected through the lens land on their mask", "[synth]", float,
                   double) {
  using namespace capture_test;
  using S = TestType;
  const Hands<S>& h = syntheticHands<S>();
  for (const char* profile : {"action_cam", "aria"}) {
    hs::SynthOptions opt = smallOptions(128, 60);
    opt.capture = hs::findCaptureProfile(profile);
    opt.capture.exposure = opt.capture.readout = 0;  // the lens alone (the shutter is tested above)
    hs::SynthSequence<S> seq(hs::findSynthPreset("table_work"), 5, h.left, h.right, opt, sharedScene<S>(5));
    const PinholeCamera<S>& cam = seq.camera();
    hs::SynthFrame<S> fr;
    int inImage = 0, onMask = 0, onMaskPinhole = 0;
    for (int i = 0; i < seq.numFrames(); i += 4) {
      seq.renderFrame(i, fr);
      for (int s = 0; s < 2; ++s) {
        const hs::SynthHandFrame<S>& hf = fr.hands[s];
        const int label = s == 0 ? hs::SynthSequence<S>::kLeftLabel : hs::SynthSequence<S>::kRightLabel;
        for (int k = 0; k < 21; ++k) {
          const hawor::Vec3<double> p = hf.jointsCam.row(k).transpose().template cast<double>();
          // The flag, recomputed through the lens in double.
          const hawor::Vec2<double> m = opt.capture.lens.project(p);
          const double u = double(cam.fx) * m.x() + double(cam.cx), v = double(cam.fy) * m.y() + double(cam.cy);
          const bool expect = p.z() > 0.01 && u >= -0.5 && v >= -0.5 && u <= cam.width - 0.5 && v <= cam.height - 0.5;
          CHECK(hf.inImage[std::size_t(k)] == expect);
          if (!expect || !hf.valid) continue;
          auto near = [&](double uu, double vv) {
            const int x0 = int(std::lround(uu)), y0 = int(std::lround(vv));
            for (int dy = -2; dy <= 2; ++dy)
              for (int dx = -2; dx <= 2; ++dx) {
                const int x = x0 + dx, y = y0 + dy;
                if (x >= 0 && y >= 0 && x < cam.width && y < cam.height && fr.images.mask.at(x, y) == label) return true;
              }
            return false;
          };
          const int x0 = std::min(cam.width - 1, std::max(0, int(std::lround(u))));
          const int y0 = std::min(cam.height - 1, std::max(0, int(std::lround(v))));
          if (fr.images.depth.at(x0, y0) < float(p.z()) - 0.03f && fr.images.mask.at(x0, y0) != label) continue;  // occluded
          ++inImage;
          onMask += near(u, v) ? 1 : 0;
          // The pinhole projection of the same intrinsics misses (the lens matters).
          onMaskPinhole += near(double(cam.fx) * p.x() / p.z() + double(cam.cx), double(cam.fy) * p.y() / p.z() + double(cam.cy)) ? 1 : 0;
        }
      }
    }
    INFO(profile << ": " << onMask << " of " << inImage << " keypoints on their mask through the lens, " << onMaskPinhole
                 << " with a pinhole projection");
    CHECK(inImage > 60);
    CHECK(onMask >= inImage * 9 / 10);
    CHECK(onMaskPinhole < onMask - inImage / 20);
  }
}

TEMPLATE_TEST_CASE("capture: noise has mean 0 and the variance G²σr² + G·k·v on flat patches", "[synth]", float, double) {
  using namespace capture_test;
  using S = TestType;
  const hs::IndoorScene<S> scene = wallScene<S>(60, 140);
  const PinholeCamera<S> cam = PinholeCamera<S>::fromFov(96, 72, S(60));
  hs::CaptureExposure ex;
  ex.readNoise = 2, ex.shotNoise = 0.1, ex.noiseSeed = 12345;
  ex.channelGain[0] = 1.5, ex.channelGain[1] = 1.2, ex.channelGain[2] = 0.9;
  const hs::RenderedImages im = renderWall(scene, cam, Lens<double>::pinhole(), 0, 0, 1, 0.0, 0, &ex);
  // Both halves (edge at the centre column, ±3 columns left out), per channel; no clipping
  // (the brightest mean is 1.5·140 = 210, σ < 7).
  for (int half = 0; half < 2; ++half) {
    for (int c = 0; c < 3; ++c) {
      const double G = ex.channelGain[c], v = G * (half ? 140 : 60);
      double sum = 0, sq = 0;
      int n = 0;
      for (int y = 0; y < 72; ++y) {
        for (int x = half ? 51 : 0; x < (half ? 96 : 45); ++x) {
          const double d = im.rgb.at(x, y, c) - v;
          sum += d, sq += d * d, ++n;
        }
      }
      const double mean = sum / n, var = sq / n - mean * mean;
      const double model = G * G * 4 + G * 0.1 * v + 1.0 / 12;  // + the rounding to bytes
      INFO("half " << half << " channel " << c << ": mean " << mean << ", variance " << var << " (model " << model << ")");
      CHECK(std::abs(mean) < 4 * std::sqrt(model / n));  // 4 standard errors
      CHECK(var == Approx(model).epsilon(4 * std::sqrt(2.0 / n)));
    }
  }
  // Deterministic per seed; another seed, another pattern.
  const hs::RenderedImages again = renderWall(scene, cam, Lens<double>::pinhole(), 0, 0, 1, 0.0, 0, &ex);
  CHECK(again.rgb.data == im.rgb.data);
  ex.noiseSeed = 54321;
  const hs::RenderedImages other = renderWall(scene, cam, Lens<double>::pinhole(), 0, 0, 1, 0.0, 0, &ex);
  CHECK(other.rgb.data != im.rgb.data);
}

TEST_CASE("capture: auto-exposure follows the metered brightness with its lag, bounded", "[synth]") {
  using namespace capture_test;
  hs::CaptureOptions o;
  o.aeTime = 0.5, o.aeTarget = 118;
  const double fps = 30, alpha = 1 - std::exp(-1 / (0.5 * 30));
  std::vector<double> m(60, 100.0);
  for (std::size_t i = 30; i < 60; ++i) m[i] = 200;  // the view turns to something brighter
  const std::vector<double> g = hs::autoExposureGains(m, fps, o);
  CHECK(g[0] == Approx(1.18));
  CHECK(g[30] == Approx(1.18));  // reacts to the previous frame
  for (int n = 1; n < 30; ++n) {
    // log g = log g*_new + (log g*_old − log g*_new)·(1 − α)^n
    const double expect = std::exp(std::log(0.59) + (std::log(1.18) - std::log(0.59)) * std::pow(1 - alpha, n));
    CHECK(g[std::size_t(30 + n)] == Approx(expect).epsilon(1e-12));
  }
  // Bounded: a black view, a blinding one.
  const std::vector<double> ext = hs::autoExposureGains({0.0, 0.0, 1e6, 1e6}, fps, o);
  CHECK(ext[0] == Approx(o.aeMaxGain));
  for (double v : ext) CHECK((v >= o.aeMinGain - 1e-12 && v <= o.aeMaxGain + 1e-12));
  // Off: the fixed gain.
  hs::CaptureOptions off;
  off.gain = 2;
  CHECK(hs::autoExposureGains(m, fps, off)[40] == 2);
}

TEST_CASE("capture: exposure and white-balance gains of a sequence are bounded and deterministic per seed", "[synth]") {
  using namespace capture_test;
  const Hands<double>& h = syntheticHands<double>();
  hs::SynthOptions opt = smallOptions(48, 90);
  opt.capture = hs::findCaptureProfile("low_light");
  opt.capture.exposure = opt.capture.readout = 0;  // fast: one render per frame
  opt.capture.wbDrift = 0.2;                       // large enough to see in 3 s
  auto run = [&](std::uint64_t seed) {
    hs::SynthSequence<double> s(hs::findSynthPreset("fast_turns"), seed, h.left, h.right, opt, sharedScene<double>(seed));
    std::vector<double> out;
    hs::SynthFrame<double> fr;
    for (int i = 0; i < s.numFrames(); i += 3) {
      s.renderFrame(i, fr);
      out.push_back(fr.capture.exposureGain);
      for (int c = 0; c < 3; ++c) out.push_back(fr.capture.whiteBalance[c]);
      CHECK(fr.capture.exposureGain >= opt.capture.aeMinGain);
      CHECK(fr.capture.exposureGain <= opt.capture.aeMaxGain);
      CHECK(fr.capture.whiteBalance[1] == 1);
      for (int c : {0, 2}) {
        CHECK(fr.capture.whiteBalance[c] >= std::exp(-0.25) - 1e-12);
        CHECK(fr.capture.whiteBalance[c] <= std::exp(0.25) + 1e-12);
      }
    }
    return out;
  };
  const std::vector<double> a = run(7), b = run(7), c = run(8);
  CHECK(a == b);
  CHECK(a != c);
  // Low light: the gain makes up most of the missing light (about 1/0.2) and changes as the
  // head turns towards brighter and darker walls.
  double lo = 1e9, hi = 0;
  for (std::size_t i = 0; i < a.size(); i += 4) lo = std::min(lo, a[i]), hi = std::max(hi, a[i]);
  INFO("exposure gain " << lo << " .. " << hi);
  CHECK(lo > 2.5);
  CHECK(hi / lo > 1.1);
  // Without drift the gains are exactly autoExposureGains of the metered greys.
  opt.capture.aeDrift = 0;
  hs::SynthSequence<double> s(hs::findSynthPreset("fast_turns"), 7, h.left, h.right, opt, sharedScene<double>(7));
  std::vector<double> m;
  for (int i = 0; i < 40; ++i) m.push_back(s.meter(i));
  const std::vector<double> g = hs::autoExposureGains(m, s.fps(), opt.capture);
  for (int i : {0, 1, 17, 39}) CHECK(s.exposureGain(i) == Approx(g[std::size_t(i)]).epsilon(1e-12));
}

TEMPLATE_TEST_CASE("capture: the clean profile gives the generator's own frames", "[synth]", float, double) {
  using namespace capture_test;
  using S = TestType;
  const Hands<S>& h = syntheticHands<S>();
  hs::SynthOptions plainOpt = smallOptions(64, 20), cleanOpt = plainOpt;
  cleanOpt.capture = hs::findCaptureProfile("clean");
  for (const char* preset : {"walk", "hands_cover"}) {
    hs::SynthSequence<S> a(hs::findSynthPreset(preset), 3, h.left, h.right, plainOpt, sharedScene<S>(3));
    hs::SynthSequence<S> b(hs::findSynthPreset(preset), 3, h.left, h.right, cleanOpt, sharedScene<S>(3));
    hs::SynthFrame<S> fa, fb;
    for (int i : {0, 9, 19}) {
      a.renderFrame(i, fa);
      b.renderFrame(i, fb);
      INFO(preset << " frame " << i);
      CHECK(sameImages<S>(fa.images, fb.images));
      CHECK(fb.capture.subframes == 1);
    }
  }
}

TEST_CASE("capture: the writer adds the lens line and capture.json, and nothing for clean", "[synth]") {
  using namespace capture_test;
  const Hands<double>& h = syntheticHands<double>();
  auto write = [&](const std::string& dir, const char* profile) {
    hs::SynthOptions o = smallOptions(40, 3);
    if (profile) o.capture = hs::findCaptureProfile(profile);
    hs::SynthSequence<double> s(hs::findSynthPreset("fast_turns"), 9, h.left, h.right, o, sharedScene<double>(9));
    return hs::writeSynthSequence(s, dir);
  };
  const std::string plain = tempDir("cap_plain"), clean = tempDir("cap_clean"), aria = tempDir("cap_aria");
  write(plain, nullptr);
  write(clean, "clean");
  const hs::SynthWriteSummary sum = write(aria, "aria");
  for (const char* f : {"intrinsics.txt", "meta.json", "camera_gt.tum", "hands_gt.npz", "rgb/000001.png", "mask/000002.png"}) {
    INFO(f);
    CHECK(hawor::readFileBytes(plain + "/" + f) == hawor::readFileBytes(clean + "/" + f));
  }
  std::FILE* none = std::fopen((clean + "/capture.json").c_str(), "rb");
  CHECK(none == nullptr);
  if (none) std::fclose(none);
  // A lens: the first line as before (read -r fx fy cx cy w h fps), then the lens.
  const std::string intr = hawor::readFileText(aria + "/intrinsics.txt");
  const std::size_t nl = intr.find('\n');
  REQUIRE(nl != std::string::npos);
  double fx, fy, cx, cy, fps;
  int w, hh;
  REQUIRE(std::sscanf(intr.substr(0, nl).c_str(), "%lf %lf %lf %lf %d %d %lf", &fx, &fy, &cx, &cy, &w, &hh, &fps) == 7);
  CHECK(w == 40);
  const std::string second = intr.substr(nl + 1);
  REQUIRE(second.rfind("lens fisheye:", 0) == 0);
  const Lens<double> back = Lens<double>::parse(second.substr(5, second.size() - 6));
  CHECK(back.k == hs::findCaptureProfile("aria").lens.k);
  const std::string json = hawor::readFileText(aria + "/capture.json");
  for (const char* key : {"\"profile\": \"aria\"", "\"exposure_s\": 0.008", "\"frame_gain\"", "\"frame_subframes\"", "\"lens\": \"fisheye:"}) {
    INFO(key);
    CHECK(json.find(key) != std::string::npos);
  }
  CHECK(hawor::readFileText(aria + "/meta.json").find("\"capture\": \"aria\"") != std::string::npos);
  CHECK(sum.subframes.size() == 3);
}

TEST_CASE("capture: sequence errors name the setting", "[synth]") {
  using namespace capture_test;
  const Hands<double>& h = syntheticHands<double>();
  const hs::SynthPreset p = hs::findSynthPreset("walk");
  auto make = [&](const hs::SynthOptions& o) { hs::SynthSequence<double> s(p, 1, h.left, h.right, o, sharedScene<double>(1)); };
  hs::SynthOptions o = smallOptions(32, 5);
  o.capture = hs::findCaptureProfile("phone");
  o.capture.exposure = 0.05;
  CHECK(errorOf([&] { make(o); }).find("exposure 0.05 s exceeds the frame interval") != std::string::npos);
  o.capture.exposure = 0.01;
  o.fps = 60;
  o.capture.readout = 0.02;
  CHECK(errorOf([&] { make(o); }).find("readout 0.02 s exceeds") != std::string::npos);
  o = smallOptions(32, 5);
  o.capture.lens = Lens<double>::radTan(-0.5, 0, 0, 0, 0);
  o.capture.fovDeg = 120;
  CHECK(errorOf([&] { make(o); }).find("folds") != std::string::npos);
}

// Hidden (run with `test_synth "[.hash]"`): FNV-1a hashes of a few frames of every capture
// profile, to compare the native build with the WebAssembly one.
TEST_CASE("capture: frame hashes for cross-platform comparison", "[.hash]") {
  using namespace capture_test;
  const Hands<double>& h = syntheticHands<double>();
  for (const hs::CaptureProfile& p : hs::captureProfiles()) {
    hs::SynthOptions o = smallOptions(80, 24);
    o.capture = p.options;
    hs::SynthSequence<double> s(hs::findSynthPreset("fast_turns"), 77, h.left, h.right, o);
    hs::SynthFrame<double> fr;
    std::uint64_t img = 1469598103934665603ULL;
    for (int i = 0; i < s.numFrames(); i += 6) {
      s.renderFrame(i, fr);
      for (const std::vector<unsigned char>* d : {&fr.images.rgb.data, &fr.images.mask.data}) {
        for (unsigned char b : *d) img = (img ^ b) * 1099511628211ULL;
      }
    }
    std::printf("hash capture %-12s images %016llx\n", p.name.c_str(), static_cast<unsigned long long>(img));
  }
}
