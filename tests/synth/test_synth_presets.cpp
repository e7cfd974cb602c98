// The presets do what their names promise: the camera motions (walking distance, fixed eye,
// fast turns, looking down), hands that come and go, and hands that cover 40 % of the image for
// seconds in hands_cover.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "synth_test_util.hpp"

namespace {

using namespace synth_test;
constexpr double kPi = 3.14159265358979323846;

/// Angle (rad) of the relative rotation Ra⁻¹·Rb.
double angleBetween(const hawor::Mat3<double>& Ra, const hawor::Mat3<double>& Rb) {
  return hawor::matrixToAxisAngle(hawor::Mat3<double>(Ra.transpose() * Rb)).norm();
}

}  // namespace

TEST_CASE("synth: the five presets exist, in order, with clear errors for others", "[synth]") {
  const std::vector<std::string> names = hs::synthPresetNames();
  const std::vector<std::string> expected = {"walk", "table_work", "fast_turns", "pure_rotation", "hands_cover"};
  REQUIRE(names.size() >= expected.size());
  for (const std::string& n : expected) CHECK(std::find(names.begin(), names.end(), n) != names.end());
  for (const hs::SynthPreset& p : hs::synthPresets()) {
    CHECK(!p.description.empty());
    CHECK(p.frames >= 150);
    CHECK(hs::findSynthPreset(p.name).name == p.name);
  }
  try {
    hs::findSynthPreset("no_such_preset");
    FAIL("no error");
  } catch (const hawor::Error& e) {
    const std::string m = e.what();
    CHECK(m.find("no_such_preset") != std::string::npos);
    CHECK(m.find("hands_cover") != std::string::npos);  // lists the known names
  }
}

TEST_CASE("synth: camera motions of the presets", "[synth]") {
  const Hands<double>& h = syntheticHands<double>();
  auto seqOf = [&](const std::string& name, std::uint64_t seed) {
    return hs::SynthSequence<double>(hs::findSynthPreset(name), seed, h.left, h.right, smallOptions(32),
                                     sharedScene<double>(seed));
  };
  for (std::uint64_t seed : {1u, 2u}) {
    {
      // Walking: metres of path at walking speed, eye height above the table, level-ish gaze.
      const hs::SynthSequence<double> s = seqOf("walk", seed);
      double path = 0;
      for (int i = 1; i < s.numFrames(); ++i) path += (s.worldFromCamera(i).t - s.worldFromCamera(i - 1).t).norm();
      const double speed = path / ((s.numFrames() - 1) / s.fps());
      CHECK(speed > 0.7);
      CHECK(speed < 1.4);
      for (int i = 0; i < s.numFrames(); i += 10) CHECK(s.worldFromCamera(i).t.z() > 1.4);
    }
    {
      // Pure rotation: the camera centre stays within a centimetre while the view turns a lot.
      const hs::SynthSequence<double> s = seqOf("pure_rotation", seed);
      double maxMove = 0, maxAngle = 0;
      for (int i = 0; i < s.numFrames(); ++i) {
        maxMove = std::max(maxMove, (s.worldFromCamera(i).t - s.worldFromCamera(0).t).norm());
        maxAngle = std::max(maxAngle, angleBetween(s.worldFromCamera(0).R, s.worldFromCamera(i).R));
      }
      CHECK(maxMove < 0.01);
      CHECK(maxAngle > 30.0 * kPi / 180.0);
    }
    {
      // Fast turns: peaks of several hundred degrees per second, but fixations in between.
      const hs::SynthSequence<double> s = seqOf("fast_turns", seed);
      double peak = 0;
      int slow = 0;
      for (int i = 1; i < s.numFrames(); ++i) {
        const double w = angleBetween(s.worldFromCamera(i - 1).R, s.worldFromCamera(i).R) * s.fps() * 180.0 / kPi;
        peak = std::max(peak, w);
        if (w < 30) ++slow;
      }
      CHECK(peak > 250);
      CHECK(slow > s.numFrames() / 4);
    }
    {
      // Table work: looking down at the table most of the time (optical axis vs. gravity).
      const hs::SynthSequence<double> s = seqOf("table_work", seed);
      int down = 0;
      for (int i = 0; i < s.numFrames(); ++i) {
        const hawor::Vec3<double> axis = s.worldFromCamera(i).R.col(2);
        if (axis.z() < -std::sin(30.0 * kPi / 180.0)) ++down;
      }
      CHECK(down > s.numFrames() * 2 / 3);
    }
  }
}

TEST_CASE("synth: hands move independently, enter and leave the view", "[synth]") {
  const Hands<double>& h = syntheticHands<double>();
  for (const hs::SynthPreset& p : hs::synthPresets()) {
    hs::SynthSequence<double> s(p, 4, h.left, h.right, smallOptions(48), sharedScene<double>(4));
    hs::SynthFrame<double> fr;
    int valid[2] = {0, 0}, differ = 0;
    for (int i = 0; i < s.numFrames(); ++i) {
      s.renderFrame(i, fr);
      for (int k = 0; k < 2; ++k) valid[k] += fr.hands[k].valid ? 1 : 0;
      if (fr.hands[0].valid != fr.hands[1].valid) ++differ;
    }
    INFO(p.name << ": valid left " << valid[0] << ", right " << valid[1] << " of " << s.numFrames());
    for (int k = 0; k < 2; ++k) {
      CHECK(valid[k] > s.numFrames() / 5);  // in view for a good part of the time
      if (p.name != "hands_cover") CHECK(valid[k] < s.numFrames());  // and leaving it
    }
    if (p.name != "hands_cover") CHECK(differ > 0);  // not in lockstep
  }
}

TEST_CASE("synth: hands_cover covers 40 % of the view, for seconds (default hand)", "[synth]") {
  const Hands<double>* h = defaultHands();
  if (!h) {
    WARN("the default WebXR hand files were not found (scripts/install.sh): coverage test skipped");
    return;
  }
  hs::SynthSequence<double> s(hs::findSynthPreset("hands_cover"), 3, h->left, h->right, smallOptions(64),
                              sharedScene<double>(3));
  hs::SynthFrame<double> fr;
  double best = 0;
  int run = 0, longest = 0;
  for (int i = 0; i < s.numFrames(); ++i) {
    s.renderFrame(i, fr);
    best = std::max(best, fr.coverage);
    run = fr.coverage >= 0.3 ? run + 1 : 0;
    longest = std::max(longest, run);
  }
  INFO("max coverage " << best << ", longest run at >= 30 %: " << longest << " frames");
  CHECK(best >= 0.4);
  CHECK(longest >= 2 * s.fps());
  // The other presets keep the hands smaller (they are about the camera, not the hands).
  hs::SynthSequence<double> w(hs::findSynthPreset("walk"), 3, h->left, h->right, smallOptions(64), sharedScene<double>(3));
  double bestWalk = 0;
  for (int i = 0; i < w.numFrames(); i += 2) {
    w.renderFrame(i, fr);
    bestWalk = std::max(bestWalk, fr.coverage);
  }
  CHECK(bestWalk < 0.35);
  CHECK(bestWalk > 0.02);
}

TEST_CASE("synth: hands hold still in the room while the head moves (table_work)", "[synth]") {
  const Hands<double>& h = syntheticHands<double>();
  for (std::uint64_t seed : {1u, 2u}) {
    const hs::SynthSequence<double> s(hs::findSynthPreset("table_work"), seed, h.left, h.right, smallOptions(32),
                                      sharedScene<double>(seed));
    // The longest run of frames over which the wrist moves < 0.1 mm per frame in the room, per
    // hand, while the camera moves on (the hold is in the room, not in the head frame).
    int longest = 0;
    double camDuring = 0;
    for (int side = 0; side < 2; ++side) {
      int run = 0;
      double cam = 0;
      for (int i = 1; i < s.numFrames(); ++i) {
        const double v = (s.handPoseWorld(side, i).trans - s.handPoseWorld(side, i - 1).trans).norm();
        const double c = (s.worldFromCamera(i).t - s.worldFromCamera(i - 1).t).norm();
        if (v < 1e-4) {
          ++run, cam += c;
        } else {
          run = 0, cam = 0;
        }
        if (run > longest) longest = run, camDuring = cam;
      }
    }
    INFO("seed " << seed << ": longest hold " << longest << " frames, camera path during it " << camDuring << " m");
    CHECK(longest >= static_cast<int>(0.5 * s.fps()));
    CHECK(camDuring > 0.005);
  }
}

TEST_CASE("synth: another frame rate samples the same motion over the preset's duration", "[synth]") {
  const Hands<double>& h = syntheticHands<double>();
  for (const std::string name : {"fast_turns", "table_work"}) {
    hs::SynthOptions o30 = smallOptions(32), o60 = smallOptions(32), o15 = smallOptions(32);
    o30.frames = o60.frames = o15.frames = 0;  // the preset's default length
    o60.fps = 60;
    o15.fps = 15;
    const hs::SynthSequence<double> a(hs::findSynthPreset(name), 3, h.left, h.right, o30, sharedScene<double>(3));
    const hs::SynthSequence<double> b(hs::findSynthPreset(name), 3, h.left, h.right, o60, sharedScene<double>(3));
    const hs::SynthSequence<double> c(hs::findSynthPreset(name), 3, h.left, h.right, o15, sharedScene<double>(3));
    const int n = hs::findSynthPreset(name).frames;
    CHECK(a.numFrames() == n);
    CHECK(b.numFrames() == 2 * n);
    CHECK(c.numFrames() == (n + 1) / 2);
    // frame i at 30 fps is frame 2i at 60 fps and frame i/2 at 15 fps: the same time, the same pose
    for (int i = 0; i < n; i += 7) {
      CHECK((a.worldFromCamera(i).t - b.worldFromCamera(2 * i).t).norm() < 1e-9);
      CHECK(angleBetween(a.worldFromCamera(i).R, b.worldFromCamera(2 * i).R) < 1e-9);
      if (i % 2 == 0) CHECK((a.worldFromCamera(i).t - c.worldFromCamera(i / 2).t).norm() < 1e-9);
    }
  }
}
