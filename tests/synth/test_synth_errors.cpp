// Bad input to the synthetic-sequence generator: clear hawor::Error messages, never a crash.
#include <catch2/catch.hpp>

#include <functional>
#include <limits>
#include <string>

#include "hawor/io/file.hpp"
#include "synth_test_util.hpp"

namespace {

using namespace synth_test;

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const hawor::Error& e) {
    return e.what();
  }
  return "<no error>";
}

bool mentions(const std::string& msg, const std::string& what) { return msg.find(what) != std::string::npos; }

}  // namespace

TEST_CASE("synth: bad options, models and frame indices are reported", "[synth]") {
  const Hands<double>& h = syntheticHands<double>();
  const hs::SynthPreset p = hs::findSynthPreset("walk");
  auto make = [&](const hs::SynthOptions& o) { hs::SynthSequence<double> s(p, 1, h.left, h.right, o, sharedScene<double>(1)); };
  hs::SynthOptions o = smallOptions(32, 5);
  o.width = 8;
  CHECK(mentions(errorOf([&] { make(o); }), "image size 8x24"));
  o = smallOptions(32, 5);
  o.fps = 0;
  CHECK(mentions(errorOf([&] { make(o); }), "fps"));
  o = smallOptions(32, 5);
  o.frames = -3;
  CHECK(mentions(errorOf([&] { make(o); }), "frames"));
  o = smallOptions(32, 5);
  o.fovDeg = 170;
  CHECK(mentions(errorOf([&] { make(o); }), "field of view"));
  o = smallOptions(32, 5);
  o.noiseSigma = std::numeric_limits<float>::infinity();
  CHECK(mentions(errorOf([&] { make(o); }), "noiseSigma"));
  o = smallOptions(32, 5);
  o.minVisibleFraction = 1.5;
  CHECK(mentions(errorOf([&] { make(o); }), "minVisibleFraction"));

  // Hands: swapped sides, a model without the 21 keypoints, an unprepared model.
  CHECK(mentions(errorOf([&] { hs::SynthSequence<double> s(p, 1, h.right, h.right, smallOptions(32, 5)); }), "left hand model"));
  CHECK(mentions(errorOf([&] { hs::SynthSequence<double> s(p, 1, h.left, h.left, smallOptions(32, 5)); }), "right hand model"));
  HandModel<double> noKeypoints = h.right;
  noKeypoints.keypointMap.clear();
  noKeypoints.prepare();
  CHECK(mentions(errorOf([&] { hs::SynthSequence<double> s(p, 1, h.left, noKeypoints, smallOptions(32, 5)); }), "21 keypoints"));
  HandModel<double> unprepared;
  unprepared.isLeft = false;
  CHECK(mentions(errorOf([&] { hs::SynthSequence<double> s(p, 1, h.left, unprepared, smallOptions(32, 5)); }), "not prepared"));

  // Frame indices and sides.
  hs::SynthSequence<double> s(p, 1, h.left, h.right, smallOptions(32, 5), sharedScene<double>(1));
  hs::SynthFrame<double> fr;
  CHECK(mentions(errorOf([&] { s.renderFrame(5, fr); }), "frame 5 outside [0, 5)"));
  CHECK(mentions(errorOf([&] { s.renderFrame(-1, fr); }), "frame -1"));
  CHECK(mentions(errorOf([&] { s.handPoseWorld(2, 0); }), "hand side"));
  CHECK(mentions(errorOf([&] { s.worldFromCamera(99); }), "frame 99"));
  // Presets.
  CHECK(mentions(errorOf([] { hs::findSynthPreset(""); }), "unknown synthetic preset"));
  hs::SynthPreset broken = p;
  broken.frames = 0;
  CHECK(mentions(errorOf([&] { hs::SynthSequence<double> b(broken, 1, h.left, h.right, smallOptions(32)); }), "default length"));
}

TEST_CASE("synth: writer and encoder errors name the problem", "[synth]") {
  const Hands<double>& h = syntheticHands<double>();
  hs::SynthSequence<double> s(hs::findSynthPreset("walk"), 1, h.left, h.right, smallOptions(32, 2), sharedScene<double>(1));
  // A file where a folder is needed.
  const std::string file = tempDir("not_a_folder");
  hawor::writeFileText(file, "x");
  CHECK(mentions(errorOf([&] { hs::writeSynthSequence(s, file + "/out"); }), "not_a_folder"));
  CHECK(mentions(errorOf([&] { hs::writeSynthSequence(s, ""); }), "empty output folder"));
  hawor::ImageU8 empty;
  CHECK(mentions(errorOf([&] { hawor::encodePng(empty); }), "encodePng"));
  hawor::ImageU8 five(4, 4, 5);
  CHECK(mentions(errorOf([&] { hawor::encodePng(five); }), "1-4 channels"));
  // Scene construction and texture generation.
  hs::SceneOptions so;
  so.textureDivisor = 3;
  CHECK(mentions(errorOf([&] { hs::makeIndoorScene<double>(1, so); }), "textureDivisor"));
  hs::SynthRng rng(1, 1);
  CHECK(mentions(errorOf([&] { hs::SmoothSignal<double>(rng, 1, 0, 1, hawor::VecX<double>::Ones(1)); }), "spacing"));
  CHECK(mentions(errorOf([&] { hs::CameraPath<double>().at(0); }), "no keys"));
}
