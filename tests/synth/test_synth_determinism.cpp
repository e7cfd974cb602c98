// Determinism (same seed: the same bytes; another seed: another sequence) and the written layout.
#include <catch2/catch.hpp>

#include <cstdio>
#include <string>
#include <vector>

#include "hawor/io/file.hpp"
#include "hawor/io/npy.hpp"
#include "hawor/io/npz.hpp"
#include "hawor/io/tum.hpp"
#include "synth_test_util.hpp"

namespace {

using namespace synth_test;

template <typename S>
bool sameFrame(const hs::SynthFrame<S>& a, const hs::SynthFrame<S>& b) {
  if (a.images.rgb.data != b.images.rgb.data || a.images.mask.data != b.images.mask.data) return false;
  if (a.images.depth.data.size() != b.images.depth.data.size()) return false;
  for (std::size_t i = 0; i < a.images.depth.data.size(); ++i) {
    if (a.images.depth.data[i] != b.images.depth.data[i]) return false;
  }
  if (a.worldFromCamera.R != b.worldFromCamera.R || a.worldFromCamera.t != b.worldFromCamera.t) return false;
  for (int s = 0; s < 2; ++s) {
    if (a.hands[s].jointsWorld != b.hands[s].jointsWorld || a.hands[s].world.handPose != b.hands[s].world.handPose) return false;
  }
  return true;
}

}  // namespace

TEMPLATE_TEST_CASE("synth: a seed gives identical sequences, another seed a different one", "[synth]", float, double) {
  using S = TestType;
  const Hands<S>& h = syntheticHands<S>();
  for (const hs::SynthPreset& p : hs::synthPresets()) {
    // Separately built scenes: the scene itself must be deterministic too.
    hs::SynthSequence<S> a(p, 42, h.left, h.right, smallOptions(48, 12));
    hs::SynthSequence<S> b(p, 42, h.left, h.right, smallOptions(48, 12));
    hs::SynthSequence<S> c(p, 43, h.left, h.right, smallOptions(48, 12));
    hs::SynthFrame<S> fa, fb, fc;
    int differ = 0;
    for (int i : {0, 5, 11}) {
      a.renderFrame(i, fa);
      b.renderFrame(i, fb);
      c.renderFrame(i, fc);
      INFO(p.name << " frame " << i);
      CHECK(sameFrame(fa, fb));
      if (fa.images.rgb.data != fc.images.rgb.data) ++differ;
    }
    CHECK(differ == 3);
    // Rendering out of order gives the same frame (no hidden state between frames).
    a.renderFrame(5, fa);
    b.renderFrame(11, fb);
    b.renderFrame(5, fb);
    CHECK(sameFrame(fa, fb));
  }
}

TEST_CASE("synth: the writer's layout, and identical bytes for identical input", "[synth]") {
  const Hands<double>& h = syntheticHands<double>();
  const int T = 4, W = 40, H = 30;
  hs::SynthOptions o = smallOptions(W, T);
  auto write = [&](const std::string& dir, std::uint64_t seed) {
    hs::SynthSequence<double> s(hs::findSynthPreset("fast_turns"), seed, h.left, h.right, o);
    hs::SynthWriteOptions wo;
    wo.meta = {{"note", "test \"quoted\""}};
    return hs::writeSynthSequence(s, dir, wo);
  };
  const std::string d1 = tempDir("w1"), d2 = tempDir("w2/nested"), d3 = tempDir("w3");
  const hs::SynthWriteSummary s1 = write(d1, 9);
  write(d2, 9);
  write(d3, 10);
  CHECK(s1.frames == T);
  CHECK(s1.renderMs.size() == std::size_t(T));
  std::vector<std::string> files = {"camera_gt.tum", "hands_gt.npz", "intrinsics.txt", "meta.json"};
  for (int i = 0; i < T; ++i) {
    char b[32];
    std::snprintf(b, sizeof b, "%06d", i);
    files.push_back(std::string("rgb/") + b + ".png");
    files.push_back(std::string("mask/") + b + ".png");
    files.push_back(std::string("depth/") + b + ".npy");
  }
  int differ = 0;
  for (const std::string& f : files) {
    INFO(f);
    const std::vector<std::uint8_t> a = hawor::readFileBytes(d1 + "/" + f);
    CHECK(a == hawor::readFileBytes(d2 + "/" + f));
    if (a != hawor::readFileBytes(d3 + "/" + f)) ++differ;
  }
  CHECK(differ >= 3 * T);
  // Contents.
  const std::vector<std::uint8_t> png = hawor::readFileBytes(d1 + "/rgb/000000.png");
  REQUIRE(png.size() > 8);
  CHECK(png[1] == 'P');
  CHECK(png[2] == 'N');
  CHECK(png[3] == 'G');
  const hawor::NpyArray depth = hawor::readNpyFile(d1 + "/depth/000002.npy");
  CHECK(depth.dtype == "<f4");
  CHECK(depth.shape == std::vector<std::size_t>{std::size_t(H), std::size_t(W)});
  for (float z : depth.as<float>()) {
    CHECK(std::isfinite(z));
    CHECK(z > 0);
  }
  const auto traj = hawor::readTum<double>(d1 + "/camera_gt.tum");
  REQUIRE(traj.size() == std::size_t(T));
  for (int i = 0; i < T; ++i) CHECK(traj[std::size_t(i)].t == Approx(i / 30.0));
  {  // the poses of the room's frame (z up, floor at z = 0): the sequence's own, to the file's digits
    const hs::SynthSequence<double> seq(hs::findSynthPreset("fast_turns"), 9, h.left, h.right, o);
    for (int i = 0; i < T; ++i) CHECK((traj[std::size_t(i)].p - seq.worldFromCamera(i).t).norm() < 1e-12);
    CHECK(traj[0].p.z() > 1.0);
  }
  const hawor::Npz z = hawor::Npz::read(d1 + "/hands_gt.npz");
  for (const char* side : {"left_", "right_"}) {
    const std::string p = side;
    CHECK(z.get(p + "trans").shape == std::vector<std::size_t>{std::size_t(T), 3});
    CHECK(z.get(p + "rot").shape == std::vector<std::size_t>{std::size_t(T), 3});
    CHECK(z.get(p + "hand_pose").shape == std::vector<std::size_t>{std::size_t(T), 45});
    CHECK(z.get(p + "betas").shape == std::vector<std::size_t>{std::size_t(T), 10});
    CHECK(z.get(p + "valid").shape == std::vector<std::size_t>{std::size_t(T)});
    CHECK(z.get(p + "valid").dtype == "|b1");
    CHECK(z.get(p + "joints_world").shape == std::vector<std::size_t>{std::size_t(T), 21, 3});
    CHECK(z.get(p + "joints_cam").shape == std::vector<std::size_t>{std::size_t(T), 21, 3});
    CHECK(z.get(p + "joints_cam").dtype == "<f8");
    CHECK(z.get(p + "visible_pixels").dtype == "<i4");
    CHECK(z.get(p + "kp_in_image").shape == std::vector<std::size_t>{std::size_t(T), 21});
  }
  const std::string intr = hawor::readFileText(d1 + "/intrinsics.txt");
  double fx, fy, cx, cy, fps;
  int w, hh;
  REQUIRE(std::sscanf(intr.c_str(), "%lf %lf %lf %lf %d %d %lf", &fx, &fy, &cx, &cy, &w, &hh, &fps) == 7);
  CHECK(w == W);
  CHECK(hh == H);
  CHECK(fps == 30);
  CHECK(cx == Approx((W - 1) / 2.0));
  CHECK(fx == fy);
  const std::string meta = hawor::readFileText(d1 + "/meta.json");
  CHECK(meta.find("\"preset\": \"fast_turns\"") != std::string::npos);
  CHECK(meta.find("\"note\": \"test \\\"quoted\\\"\"") != std::string::npos);
}

TEST_CASE("synth: textures and scenes are deterministic functions of the seed", "[synth]") {
  const hs::Texture a = hs::clutterTexture(64, 20, 5), b = hs::clutterTexture(64, 20, 5), c = hs::clutterTexture(64, 20, 6);
  int same = 0, total = 0;
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      const hs::Rgb p = a.texel(0, x, y), q = b.texel(0, x, y), r = c.texel(0, x, y);
      CHECK((p.r == q.r && p.g == q.g && p.b == q.b));
      same += (p.r == r.r && p.g == r.g && p.b == r.b) ? 1 : 0;
      ++total;
    }
  }
  CHECK(same < total * 9 / 10);
  hs::SceneOptions so;
  so.textureDivisor = 4;
  const hs::IndoorScene<double> s1 = hs::makeIndoorScene<double>(8, so), s2 = hs::makeIndoorScene<double>(8, so);
  const hs::IndoorScene<double> s3 = hs::makeIndoorScene<double>(9, so);
  CHECK(s1.vertices == s2.vertices);
  CHECK(s1.faces == s2.faces);
  CHECK(s1.uv == s2.uv);
  CHECK((s1.vertices.rows() != s3.vertices.rows() || s1.vertices != s3.vertices));
}

// Hidden (run with `test_synth "[.hash]"`): prints FNV-1a hashes of a few frames of every preset,
// to compare the native build with the WebAssembly one (the same seed must give the same bytes).
TEST_CASE("synth: frame hashes for cross-platform comparison", "[.hash]") {
  const Hands<double>& h = syntheticHands<double>();
  for (const hs::SynthPreset& p : hs::synthPresets()) {
    hs::SynthSequence<double> s(p, 77, h.left, h.right, smallOptions(80, 60));
    hs::SynthFrame<double> fr;
    std::uint64_t img = 1469598103934665603ULL, geo = 1469598103934665603ULL;
    auto mix = [](std::uint64_t& hsh, const void* data, std::size_t n) {
      const auto* b = static_cast<const std::uint8_t*>(data);
      for (std::size_t i = 0; i < n; ++i) hsh = (hsh ^ b[i]) * 1099511628211ULL;
    };
    for (int i = 0; i < s.numFrames(); i += 6) {
      s.renderFrame(i, fr);
      mix(img, fr.images.rgb.data.data(), fr.images.rgb.data.size());
      mix(img, fr.images.mask.data.data(), fr.images.mask.data.size());
      mix(img, fr.images.depth.data.data(), fr.images.depth.data.size() * sizeof(float));
      mix(geo, fr.worldFromCamera.R.data(), 9 * sizeof(double));
      mix(geo, fr.worldFromCamera.t.data(), 3 * sizeof(double));
      for (int k = 0; k < 2; ++k) mix(geo, fr.hands[k].jointsWorld.data(), 63 * sizeof(double));
    }
    std::printf("hash %-14s images %016llx geometry %016llx\n", p.name.c_str(), static_cast<unsigned long long>(img),
                static_cast<unsigned long long>(geo));
  }
}

// Hidden (run with `test_synth "[.dump]"`): writes short sequences of every preset into
// <build>/ref/synth_dump_{native,wasm}/ for a file-by-file comparison of the two platforms.
TEST_CASE("synth: dump sequences for cross-platform comparison", "[.dump]") {
#if defined(__EMSCRIPTEN__)
  const std::string platform = "wasm";
#else
  const std::string platform = "native";
#endif
  const Hands<double>& h = syntheticHands<double>();
  for (const hs::SynthPreset& p : hs::synthPresets()) {
    hs::SynthSequence<double> s(p, 77, h.left, h.right, smallOptions(80, 60));
    hs::writeSynthSequence(s, tempDir("dump_" + platform + "/" + p.name));
  }
}
