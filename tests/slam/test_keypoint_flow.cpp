// The keypoint flow (pipeline/keypoint_flow.hpp): a textured hand moved by a known similarity over
// a background that stays put is carried to where the similarity puts it; the schedule lengthens
// the gap while the network agrees with the prediction and shortens it when it does not; bad
// options and broken continuity.
#include <catch2/catch.hpp>

#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "hawor/pipeline/keypoint_flow.hpp"

using namespace hawor;

namespace {

using C = std::complex<double>;

/// Smooth random texture: white noise box-blurred twice (radius 2).
std::vector<float> texture(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 255.0f);
  std::vector<float> a(std::size_t(w) * h), b(a.size());
  for (float& v : a) v = u(rng);
  for (int pass = 0; pass < 2; ++pass) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        float s = 0;
        int n = 0;
        for (int dy = -2; dy <= 2; ++dy) {
          for (int dx = -2; dx <= 2; ++dx) {
            const int xx = std::clamp(x + dx, 0, w - 1), yy = std::clamp(y + dy, 0, h - 1);
            s += a[std::size_t(yy) * w + xx];
            ++n;
          }
        }
        b[std::size_t(y) * w + x] = s / float(n);
      }
    }
    std::swap(a, b);
  }
  return a;
}

float bilinear(const std::vector<float>& t, int w, int h, double x, double y) {
  x = std::clamp(x, 0.0, w - 1.001);
  y = std::clamp(y, 0.0, h - 1.001);
  const int x0 = int(x), y0 = int(y);
  const double ax = x - x0, ay = y - y0;
  auto at = [&](int xx, int yy) { return double(t[std::size_t(yy) * w + xx]); };
  return float((1 - ax) * (1 - ay) * at(x0, y0) + ax * (1 - ay) * at(x0 + 1, y0) + (1 - ax) * ay * at(x0, y0 + 1) + ax * ay * at(x0 + 1, y0 + 1));
}

/// The hand: a disc of radius r about c textured by `hand`, over the background `bg`; the disc
/// and its texture moved by z -> a z + b.
ImageU8 render(const std::vector<float>& bg, const std::vector<float>& hand, int w, int h, C c, double r, C a, C b) {
  ImageU8 im(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const C z0 = (C(x, y) - b) / a;  // the hand's point seen here
      const double v = std::abs(z0 - c) < r ? bilinear(hand, w, h, z0.real(), z0.imag()) : bg[std::size_t(y) * w + x];
      im.data[std::size_t(y) * w + x] = static_cast<unsigned char>(std::clamp(std::lround(v), 0L, 255L));
    }
  }
  return im;
}

/// An open hand of about `size` pixels about c (MediaPipe's 21 keypoints).
Pixels<double> handKeypoints(C c, double size) {
  Pixels<double> k(21, 2);
  const double s = size / 2;
  const C wrist = c + C(0, 0.9 * s);
  k.row(0) << wrist.real(), wrist.imag();
  for (int f = 0; f < 5; ++f) {
    const double ang = -2.4 + 0.45 * f;  // fan of fingers, upward
    const C dir = std::polar(1.0, ang);
    for (int j = 0; j < 4; ++j) {
      const C p = wrist + dir * (0.45 * s + 0.35 * s * j) * (f == 0 ? 0.8 : 1.0);
      k.row(1 + 4 * f + j) << p.real(), p.imag();
    }
  }
  return k;
}

Pixels<double> moved(const Pixels<double>& k, C a, C b) {
  Pixels<double> out(k.rows(), 2);
  for (int i = 0; i < k.rows(); ++i) {
    const C z = a * C(k(i, 0), k(i, 1)) + b;
    out.row(i) << z.real(), z.imag();
  }
  return out;
}

}  // namespace

TEMPLATE_TEST_CASE("the keypoint flow carries a hand moved by a similarity over a still background", "[pipeline][flow]", float, double) {
  using S = TestType;
  const int w = 320, h = 240;
  const std::vector<float> bg = texture(w, h, 1), hand = texture(w, h, 2);
  const C c(160, 120);
  const double r = 70;
  const Pixels<double> k0 = handKeypoints(c, 110);
  // about the hand's centre: 6 degrees, 4 % larger, 5 px right and 3 px up
  const C a = std::polar(1.04, 6 * M_PI / 180), b = c - a * c + C(5, -3);
  KeypointFlowOptions<S> o;
  o.maxSkip = 3;
  KeypointFlow<S> flow(o);
  flow.setFrame(render(bg, hand, w, h, c, r, C(1, 0), C(0, 0)), 0, S(1));
  REQUIRE(flow.predict().empty());  // nothing seen yet
  HandDetection<S> d;
  d.keypoints2d = k0.cast<S>();
  d.keypoints3d = Points3<S>::Zero(21, 3);
  d.keypoints3d(8, 0) = S(0.05);  // the index tip 5 cm right of the hand's centre
  d.pRight = S(0.8);
  d.track = 7;
  flow.observe({d});
  flow.setFrame(render(bg, hand, w, h, c, r, a, b), 1, S(1));
  const auto& p = flow.predict();
  REQUIRE(p.size() == 1);
  CHECK(p[0].track == 7);
  CHECK(p[0].trusted);
  CHECK(p[0].inliers >= o.minInliers);
  CHECK(double(p[0].pRight) == Approx(0.8));
  CHECK(double(p[0].scale) == Approx(1.04).margin(0.01));
  CHECK(double(p[0].angle) == Approx(6 * M_PI / 180).margin(0.01));
  const Pixels<double> truth = moved(k0, a, b);
  double worst = 0;
  for (int i = 0; i < 21; ++i) worst = std::max(worst, (p[0].keypoints2d.row(i).template cast<double>() - truth.row(i)).norm());
  CHECK(worst < 0.6);
  // the 3D keypoints turn with the image: +x rotated by +6 degrees (y down)
  CHECK(double(p[0].keypoints3d(8, 0)) == Approx(0.05 * std::cos(6 * M_PI / 180)).margin(1e-3));
  CHECK(double(p[0].keypoints3d(8, 1)) == Approx(0.05 * std::sin(6 * M_PI / 180)).margin(1e-3));
}

TEST_CASE("the keypoint flow works between the video's pixels and a smaller grey frame", "[pipeline][flow]") {
  // the video is twice the frame: a pixel u is at 0.5 u - 0.25 in the frame
  const int w = 320, h = 240;
  const std::vector<float> bg = texture(w, h, 3), hand = texture(w, h, 4);
  const C c(150, 130);
  const C a(1, 0), b(6, 4);  // a translation in the frame's pixels
  KeypointFlowOptions<double> o;
  o.maxSkip = 2;
  KeypointFlow<double> flow(o);
  const Pixels<double> kFrame = handKeypoints(c, 100);
  Pixels<double> kVideo = (kFrame.array() + 0.25) * 2.0;
  flow.setFrame(render(bg, hand, w, h, c, 65, C(1, 0), C(0, 0)), 10, 0.5);
  HandDetection<double> d;
  d.keypoints2d = kVideo;
  d.track = 1;
  flow.observe({d});
  flow.setFrame(render(bg, hand, w, h, c, 65, a, b), 11, 0.5);
  const auto& p = flow.predict();
  REQUIRE(p.size() == 1);
  CHECK(p[0].keypoints3d.rows() == 0);
  for (int i = 0; i < 21; ++i) {
    CHECK(p[0].keypoints2d(i, 0) == Approx(kVideo(i, 0) + 12).margin(0.6));
    CHECK(p[0].keypoints2d(i, 1) == Approx(kVideo(i, 1) + 8).margin(0.6));
  }
  // a frame that does not follow: no hand is carried over it
  flow.observe({d});
  flow.setFrame(render(bg, hand, w, h, c, 65, a, b), 13, 0.5);
  CHECK(flow.predict().empty());
}

TEST_CASE("the keypoint flow's schedule follows the network's agreement with it", "[pipeline][flow]") {
  const int w = 320, h = 240;
  const std::vector<float> bg = texture(w, h, 5), hand = texture(w, h, 6);
  const C c(160, 120);
  KeypointFlowOptions<double> o;
  o.maxSkip = 3;
  KeypointFlow<double> flow(o);
  const Pixels<double> k0 = handKeypoints(c, 110);
  // the hand drifts 2 px a frame to the right; `offset` spoils the network's keypoints
  auto run = [&](int frames, double offset, std::vector<int>& trusted) {
    for (int t = 0; t < frames; ++t) {
      const C b(2.0 * t, 0);
      flow.setFrame(render(bg, hand, w, h, c, 70, C(1, 0), b), t, 1.0);
      const auto& p = flow.predict();
      const bool use = p.size() == 1 && p[0].trusted;
      trusted.push_back(use ? 1 : 0);
      HandDetection<double> d;
      d.track = 3;
      if (use) {
        d.keypoints2d = p[0].keypoints2d;
      } else {
        d.keypoints2d = moved(k0, C(1, 0), b);
        if (t > 0) d.keypoints2d.col(0).array() += offset * (t % 2 ? 1 : -1);
      }
      d.flow = use;
      flow.observe({d});
    }
  };
  std::vector<int> good;
  run(14, 0.0, good);
  // network on frame 0; one flow frame, then the gap grows by one per agreeing check up to 3
  CHECK(good == std::vector<int>{0, 1, 0, 1, 1, 0, 1, 1, 1, 0, 1, 1, 1, 0});
  CHECK(flow.skipOf(3) == 3);
  // the network now disagrees by 25 px (a hand of 110 px): each check halves the gap
  KeypointFlow<double> flow2(o);
  std::swap(flow, flow2);
  std::vector<int> bad;
  run(8, 25.0, bad);
  CHECK(bad == std::vector<int>{0, 1, 0, 0, 0, 0, 0, 0});
  CHECK(flow.skipOf(3) == 0);
}

TEST_CASE("keypoint flow options are checked", "[pipeline][flow]") {
  KeypointFlowOptions<double> o;
  o.maxSkip = -1;
  CHECK_THROWS_WITH(KeypointFlow<double>(o), Catch::Contains("maxSkip"));
  o = {};
  o.goodError = 0.2;
  CHECK_THROWS_WITH(KeypointFlow<double>(o), Catch::Contains("goodError"));
  o = {};
  o.minInliers = 1;
  CHECK_THROWS_WITH(KeypointFlow<double>(o), Catch::Contains("minInliers"));
  o = {};
  o.maxSkip = 0;
  KeypointFlow<double> f(o);
  CHECK_FALSE(f.enabled());
  CHECK_THROWS_WITH(f.setFrame(ImageU8(8, 8, 1), 0, 1.0), Catch::Contains("grey frame"));
}
