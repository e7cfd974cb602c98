// The pipeline object (pipeline/pipeline.hpp) on synthetic sequences with ground truth: the side
// policy, camera-frame hands from another regressor (pushHands) and detections fitted (push)
// taken to a metric world, and bad input. Native only (the WebAssembly core's Pipeline is run by
// tests/web/pipeline_native_wasm.test.mjs against `hawor world`).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "hawor/geometry/alignment.hpp"
#include "hawor/pipeline/pipeline.hpp"
#include "hawor/synth/synth.hpp"
#include "synth_support.hpp"

// double only: every driver runs the pipeline in double, and its parts are instantiated and
// tested in float and double in their own modules (MonoSlam<float> beside it in this unit); a
// Pipeline<float> costs about a minute of the suite's compile for no path anyone takes.
template class hawor::Pipeline<double>;

namespace {

namespace hs = hawor::synth;
using V3 = hawor::Vec3<double>;

using slam_test::leftHand;
using slam_test::rightHand;

hawor::HandDetection<double> det(double x, double pRight, int track = -1) {
  hawor::HandDetection<double> d;
  d.keypoints2d = hawor::Pixels<double>::Zero(21, 2);
  d.keypoints2d(0, 0) = x, d.keypoints2d(0, 1) = 500;
  d.pRight = pRight;
  d.track = track;
  return d;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}

struct Outcome {
  hawor::PipelineResult<double> result;
  std::vector<V3> gtCam;                   // camera centres (the room: z up, floor at z = 0)
  std::vector<hawor::Mat3<double>> gtR;    // camera-to-room rotations
  std::vector<std::array<V3, 2>> gtWrist;  // world wrists (room frame), NaN where the hand is unseen
  std::vector<std::array<V3, 2>> gtWristCam;
  std::vector<std::array<bool, 2>> seen;
};

enum class Input { Hands, Detections, Joints };

/// `frames` frames of a preset through the pipeline: the ground-truth camera-frame hands
/// (pushHands), their keypoints as detections (push: 2D projections, metric 3D keypoints) or their
/// camera-frame joints (pushJoints), the joints jittered per frame by N(0, noise) across the view
/// and N(0, 3·noise) in depth (metres), as a regressor's would be.
Outcome runPipeline(const std::string& preset, int frames, Input input, std::uint64_t seed = 1, bool groundCue = true, double noise = 0) {
  const hs::SynthOptions so = slam_test::sequenceOptions(frames);
  hs::SynthSequence<double> seq(hs::findSynthPreset(preset), seed, leftHand(), rightHand(), so);
  hawor::PipelineOptions<double> po;
  po.camera = seq.camera();
  po.userFocal = true;
  po.refineFocal = false;
  po.groundScale = groundCue;
  hawor::Pipeline<double> p(po, leftHand(), rightHand());
  Outcome o;
  hs::SynthFrame<double> fr;
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0, 1);
  hawor::Points3<double> joints[2];
  for (int i = 0; i < seq.numFrames(); ++i) {
    seq.renderFrame(i, fr);
    o.gtCam.push_back(fr.worldFromCamera.t);
    o.gtR.push_back(fr.worldFromCamera.R);
    std::array<V3, 2> w, wc;
    std::array<bool, 2> seen{};
    std::array<const hawor::HandPose<double>*, 2> given{nullptr, nullptr};
    std::array<const hawor::Points3<double>*, 2> givenJoints{nullptr, nullptr};
    std::vector<hawor::HandDetection<double>> dets;
    for (int s = 0; s < 2; ++s) {
      const auto& h = fr.hands[s];
      seen[s] = h.valid;
      w[s] = h.jointsWorld.row(0).transpose();
      wc[s] = h.jointsCam.row(0).transpose();
      if (!h.valid) continue;
      given[s] = &h.camera;
      const V3 move(noise * normal(rng), noise * normal(rng), 3 * noise * normal(rng));
      joints[s] = h.jointsCam.rowwise() + move.transpose();
      givenJoints[s] = &joints[s];
      hawor::HandDetection<double> d;
      d.keypoints2d.resize(21, 2);
      for (int k = 0; k < 21; ++k) d.keypoints2d.row(k) = seq.camera().project(V3(h.jointsCam.row(k).transpose())).transpose();
      d.keypoints3d = h.jointsCam;
      d.pRight = s == 1 ? 0.9 : 0.1;
      dets.push_back(d);
    }
    o.gtWrist.push_back(w);
    o.gtWristCam.push_back(wc);
    o.seen.push_back(seen);
    if (input == Input::Detections) {
      p.push(fr.images.rgb, dets);
    } else if (input == Input::Joints) {
      p.pushJoints(fr.images.rgb, givenJoints);
    } else {
      p.pushHands(fr.images.rgb, given);
    }
  }
  o.result = p.finish();
  return o;
}

/// The camera-frame wrist errors (m) of the believed hands, and how many hand-frames the truth saw.
std::vector<double> wristErrorsCam(const Outcome& o, int& seen) {
  std::vector<double> err;
  seen = 0;
  for (int s = 0; s < 2; ++s) {
    for (std::size_t t = 0; t < o.seen.size(); ++t) {
      if (!o.seen[t][s]) continue;
      ++seen;
      if (!o.result.hands[s].valid[t]) continue;
      const auto& j = o.result.hands[s].jointsCam;
      const Eigen::Index i = static_cast<Eigen::Index>(t);
      err.push_back((V3(j(i, 0), j(i, 1), j(i, 2)) - o.gtWristCam[t][s]).norm());
    }
  }
  return err;
}

/// The Sim(3) that maps the estimated camera centres onto the ground truth's.
hawor::SimilarityTransform<double> alignCameras(const Outcome& o) {
  hawor::Points3<double> est(static_cast<Eigen::Index>(o.gtCam.size()), 3), gt(est.rows(), 3);
  for (Eigen::Index t = 0; t < est.rows(); ++t) {
    est.row(t) = o.result.cameraPoses[static_cast<std::size_t>(t)].translation().transpose();
    gt.row(t) = o.gtCam[static_cast<std::size_t>(t)].transpose();
  }
  return hawor::umeyama(est, gt, true);
}

}  // namespace

TEST_CASE("pipeline sides: track continuity, side memory over a short gap, two hands ordered left to right", "[pipeline]") {
  const double reach = 300;
  hawor::SideState<double> prev;
  // a track keeps its side against its own evidence while it is alone
  std::vector<hawor::HandDetection<double>> d{det(400, 0.1, 7)};
  hawor::updateSideState(prev, d, {0, -1});
  d = {det(420, 0.95, 7)};
  CHECK(hawor::assignSides(d, prev, reach) == std::array<int, 2>{0, -1});
  // a side empty for a frame or two still pulls a hand that comes back where it was
  prev = {};
  d = {det(400, 0.2)};
  hawor::updateSideState(prev, d, {0, -1});
  hawor::updateSideState(prev, d, {-1, -1});
  CHECK(prev.age[0] == 2);
  d = {det(430, 0.7)};
  CHECK(hawor::assignSides(d, prev, reach)[0] == 0);
  for (int k = 0; k < 10; ++k) hawor::updateSideState(prev, d, {-1, -1});
  CHECK(hawor::assignSides(d, prev, reach)[1] == 0);  // long gone: the label decides
  // two hands whose tracks both say right: the one on the left is the left hand
  prev = {};
  d = {det(900, 0.99, 1), det(300, 0.99, 2)};
  CHECK(hawor::assignSides(d, prev, reach) == std::array<int, 2>{1, 0});
  // even against both tracks' continuity when their evidence is unsure
  d = {det(900, 0.5, 1), det(300, 0.5, 2)};
  hawor::updateSideState(prev, d, {0, 1});
  CHECK(prev.track[0] == 1);
  CHECK(hawor::assignSides(d, prev, reach) == std::array<int, 2>{1, 0});
  // a crossing that both tracks' confident evidence supports is kept
  d = {det(900, 0.02, 1), det(300, 0.98, 2)};
  CHECK(hawor::assignSides(d, prev, reach) == std::array<int, 2>{0, 1});
  // a track takes its side from the other one
  hawor::updateSideState(prev, d, {1, -1});
  CHECK(prev.track[0] == 2);
  CHECK(prev.track[1] == -1);
  CHECK(hawor::assignSides(std::vector<hawor::HandDetection<double>>{}, prev, reach) == std::array<int, 2>{-1, -1});
  // the SLAM's frame size: the long side at most 640, the aspect kept
  CHECK(hawor::pipelineSlamSize(1920, 1080, 640) == std::array<int, 2>{640, 360});
  CHECK(hawor::pipelineSlamSize(320, 240, 640) == std::array<int, 2>{320, 240});
}

TEST_CASE("pipeline: camera-frame hands from another regressor to a metric world (table_work, 60 frames)", "[pipeline]") {
  const Outcome o = runPipeline("table_work", 60, Input::Hands);
  const hawor::PipelineResult<double>& r = o.result;
  REQUIRE(r.frames == 60);
  REQUIRE(r.slam.initialised);
  const hawor::SimilarityTransform<double> S = alignCameras(o);
  double path = 0, se = 0;
  for (std::size_t t = 1; t < o.gtCam.size(); ++t) path += (o.gtCam[t] - o.gtCam[t - 1]).norm();
  for (std::size_t t = 0; t < o.gtCam.size(); ++t) se += (S.apply(V3(r.cameraPoses[t].translation())) - o.gtCam[t]).squaredNorm();
  const double atePct = 100 * std::sqrt(se / double(o.gtCam.size())) / path;
  INFO("camera ATE " << atePct << " % of " << path << " m; scale " << r.scale << " (" << r.scaleMethod << ", confidence " << r.scaleConfidence
                     << "), alignment scale " << S.s);
  CHECK(atePct < 2.0);
  // the metric scale from the hands: the aligned trajectory needs little rescaling
  CHECK(r.scaleMethod != "none");
  CHECK(std::abs(std::log(S.s)) < std::log(1.3));
  // camera-frame hands are passed through; world wrists land on the truth under the cameras' Sim(3)
  std::vector<double> err, errCam;
  for (int s = 0; s < 2; ++s) {
    const hawor::PipelineHand<double>& h = r.hands[s];
    for (std::size_t t = 0; t < o.seen.size(); ++t) {
      if (!o.seen[t][s]) {
        CHECK(!h.valid[t]);
        continue;
      }
      REQUIRE(h.valid[t]);
      errCam.push_back((V3(h.jointsCam(static_cast<Eigen::Index>(t), 0), h.jointsCam(static_cast<Eigen::Index>(t), 1), h.jointsCam(static_cast<Eigen::Index>(t), 2)) -
                        o.gtWristCam[t][s]).norm());
      const V3 w(h.jointsWorld(static_cast<Eigen::Index>(t), 0), h.jointsWorld(static_cast<Eigen::Index>(t), 1), h.jointsWorld(static_cast<Eigen::Index>(t), 2));
      err.push_back((S.apply(w) - o.gtWrist[t][s]).norm());
    }
  }
  REQUIRE(err.size() > 20);
  CHECK(median(errCam) < 1e-9);
  INFO("world wrist error, median " << median(err) << " m");
  CHECK(median(err) < 0.05);
  CHECK(r.timings.count("slam") == 1);
}

TEST_CASE("pipeline: camera-frame 3D joints, exact and with a regressor's jitter, to a metric world (table_work, 60 frames)", "[pipeline]") {
  for (const double noise : {0.0, 0.005}) {
    const Outcome o = runPipeline("table_work", 60, Input::Joints, 1, true, noise);
    const hawor::PipelineResult<double>& r = o.result;
    REQUIRE(r.slam.initialised);
    // no alignment of scale or tilt: the first cameras' up and height against the room's, and the
    // wrists against the truth in each camera's frame (the fit kept at the joints' depth)
    int seen = 0;
    const std::vector<double> errCam = wristErrorsCam(o, seen);
    const V3 up0 = r.cameraPoses[0].rotationMatrix().transpose() * V3::UnitZ(), gtUp0 = o.gtR[0].transpose() * V3::UnitZ();
    const double upErr = std::acos(std::min(1.0, up0.dot(gtUp0))) * 180 / M_PI;
    INFO("noise " << noise << ": " << errCam.size() << " of " << seen << " hand-frames; camera-frame wrist error median " << median(errCam)
                  << " m; up error " << upErr << " deg; first camera at " << r.cameraPoses[0].translation()(2) << " m (truth " << o.gtCam[0](2)
                  << "); scale " << r.scale << " (" << r.scaleMethod << ")");
    REQUIRE(seen > 20);
    CHECK(errCam.size() >= static_cast<std::size_t>(0.95 * seen));
    CHECK(median(errCam) < (noise > 0 ? 0.02 : 0.005));
    CHECK(r.world.up == "floor");
    CHECK(upErr < 2.0);
    CHECK(std::abs(r.cameraPoses[0].translation()(2) - o.gtCam[0](2)) < 0.1 * o.gtCam[0](2));
  }
  // bad joints are refused naming the side
  hawor::PipelineOptions<double> po;
  po.camera.fx = po.camera.fy = 500, po.camera.cx = 319.5, po.camera.cy = 239.5, po.camera.width = 640, po.camera.height = 480;
  hawor::Pipeline<double> p(po, leftHand(), rightHand());
  hawor::Points3<double> bad = hawor::Points3<double>::Constant(21, 3, 0.4);
  bad(4, 2) = NAN;
  CHECK_THROWS_WITH(p.pushJoints(hawor::ImageU8(640, 480, 3, 90), {nullptr, &bad}), Catch::Contains("the right hand: joints must be 21 finite 3D points"));
  CHECK(p.frames() == 0);
}

TEST_CASE("pipeline: the output's world is gravity-aligned, z up, the origin on the floor (walk and table_work)", "[pipeline]") {
  for (const char* preset : {"walk", "table_work", "walk (no ground cue)"}) {
    const bool ground = std::string(preset).find("no ground") == std::string::npos;
    const Outcome o = runPipeline(ground ? preset : "walk", 60, Input::Hands, 1, ground);
    const hawor::PipelineResult<double>& r = o.result;
    // up in each camera's frame, estimated against the room's (independent of yaw and origin)
    double worst = 0;
    for (std::size_t t = 0; t < o.gtR.size(); ++t) {
      const V3 est = r.cameraPoses[t].rotationMatrix().transpose() * V3::UnitZ();
      const V3 gt = o.gtR[t].transpose() * V3::UnitZ();
      worst = std::max(worst, std::acos(std::min(1.0, est.dot(gt))) * 180 / M_PI);
    }
    INFO(preset << ": up from " << r.world.up << " (confidence " << r.world.upConfidence << "), origin on the floor " << r.world.originOnFloor
                << ", worst up error " << worst << " deg; first camera at height " << r.cameraPoses[0].translation()(2) << " m (truth "
                << o.gtCam[0](2) << ")");
    CHECK(r.world.up == (ground ? "floor" : "camera"));
    CHECK(worst < (ground ? 2.0 : 5.0));
    // the first camera looks along +y, horizontally
    const V3 f0 = r.cameraPoses[0].rotationMatrix().col(2);
    CHECK(std::abs(f0(0)) < 1e-9);
    CHECK(f0(1) > 0);
    const V3 c0 = r.cameraPoses[0].translation();
    CHECK(std::abs(c0(0)) < 1e-9);
    CHECK(std::abs(c0(1)) < 1e-9);
    if (r.world.originOnFloor) {
      CHECK(std::abs(c0(2) - o.gtCam[0](2)) < 0.15 * o.gtCam[0](2));  // the metric scale's error, nothing more
    } else {
      CHECK(std::abs(c0(2)) < 1e-9);
    }
  }
  // off: the first camera's frame
  hawor::PipelineOptions<double> po;
  po.camera.fx = po.camera.fy = 500, po.camera.cx = 319.5, po.camera.cy = 239.5, po.camera.width = 640, po.camera.height = 480;
  po.gravityAligned = false;
  hawor::Pipeline<double> p(po, leftHand(), rightHand());
  p.push(hawor::ImageU8(640, 480, 1, 80), {});
  const hawor::PipelineResult<double> r = p.finish();
  CHECK(r.world.up == "none");
  CHECK(r.cameraPoses[0].translation().norm() < 1e-12);
}

TEST_CASE("pipeline: detections fitted, sides kept, masks for the SLAM (hands_cover, 40 frames)", "[pipeline]") {
  const Outcome o = runPipeline("hands_cover", 40, Input::Detections, 2);
  const hawor::PipelineResult<double>& r = o.result;
  int seen = 0;
  const std::vector<double> errCam = wristErrorsCam(o, seen);
  for (int s = 0; s < 2; ++s) {
    for (std::size_t t = 0; t < o.seen.size(); ++t) {
      if (r.hands[s].valid[t]) CHECK(r.hands[s].reprojRmsPx[t] < 2.0);
    }
  }
  INFO(errCam.size() << " of " << seen << " hand-frames fitted; wrist error median " << median(errCam) << " m");
  REQUIRE(seen > 10);
  CHECK(errCam.size() == static_cast<std::size_t>(seen));  // every seen hand believed, on its own side
  CHECK(median(errCam) < 0.01);
  for (int s = 0; s < 2; ++s) {
    if (!r.hands[s].present) continue;
    for (std::size_t t = 0; t < o.seen.size(); ++t) CHECK(std::isfinite(r.hands[s].jointsWorld(static_cast<Eigen::Index>(t), 0)));  // filled
  }
}

TEST_CASE("pipeline: a still hand no longer found stays masked from the SLAM at its last pose for maskHoldSeconds, a moving one not", "[pipeline]") {
  // the hands of frame 9 given on frames 0-9 (still, or moving 2 cm a frame sideways), none
  // after: the SLAM's masks (observeSlamInputs) against the renderer's own hand labels of frame 9
  const int given = 10, frames = 30;
  const hs::SynthOptions so = slam_test::sequenceOptions(frames);
  hs::SynthSequence<double> seq(hs::findSynthPreset("table_work"), 1, leftHand(), rightHand(), so);
  hs::SynthFrame<double> last;
  seq.renderFrame(given - 1, last);
  REQUIRE((last.hands[0].valid || last.hands[1].valid));
  struct Case { double holdSeconds, speed; int heldFrames; };
  // still: held 15 frames (0.5 s at 30 fps); off: none; 2 cm a frame (~20 px at this focal, the
  // hands ~100-200 px): a few frames at most
  for (const Case c : {Case{0.5, 0.0, 15}, Case{0.0, 0.0, 0}, Case{0.5, 0.02, -1}}) {
    hawor::PipelineOptions<double> po;
    po.camera = seq.camera();
    po.userFocal = true;
    po.refineFocal = false;
    po.maskHoldSeconds = c.holdSeconds;
    hawor::Pipeline<double> p(po, leftHand(), rightHand());
    REQUIRE(p.slamCamera().width == seq.camera().width);  // the renderer's labels at the SLAM's size
    std::vector<hawor::ImageU8> masks;
    p.observeSlamInputs([&](const hawor::ImageU8&, const hawor::ImageU8* m) { masks.push_back(m ? *m : hawor::ImageU8()); });
    hs::SynthFrame<double> fr;
    for (int i = 0; i < frames; ++i) {
      seq.renderFrame(i, fr);
      std::array<hawor::HandPose<double>, 2> pose{last.hands[0].camera, last.hands[1].camera};
      std::array<const hawor::HandPose<double>*, 2> hands{nullptr, nullptr};
      for (int s = 0; s < 2 && i < given; ++s) {
        if (!last.hands[s].valid) continue;
        pose[static_cast<std::size_t>(s)].trans(0) += c.speed * (i - (given - 1));  // at frame 9's pose on frame 9
        hands[static_cast<std::size_t>(s)] = &pose[static_cast<std::size_t>(s)];
      }
      p.pushHands(fr.images.rgb, hands);
    }
    REQUIRE(masks.size() == static_cast<std::size_t>(frames));
    INFO("hold " << c.holdSeconds << " s, hands moving " << c.speed << " m a frame");
    int held = 0;
    for (int i = given; i < frames && !masks[static_cast<std::size_t>(i)].data.empty(); ++i) ++held;
    for (int i = given + held; i < frames; ++i) CHECK(masks[static_cast<std::size_t>(i)].data.empty());  // not again
    for (int i = 0; i < given; ++i) CHECK(!masks[static_cast<std::size_t>(i)].data.empty());
    if (c.heldFrames >= 0) {
      CHECK(held == c.heldFrames);
    } else {
      CHECK(held <= 4);
    }
    // held: every pixel of the hands' true silhouette on their last frame stays masked
    for (int i = given; i < given + held && c.speed == 0; ++i) {
      const hawor::ImageU8& m = masks[static_cast<std::size_t>(i)];
      std::size_t labelled = 0, covered = 0;
      for (std::size_t k = 0; k < last.images.mask.data.size(); ++k) {
        if (!last.images.mask.data[k]) continue;
        ++labelled;
        covered += m.data[k] ? 1 : 0;
      }
      REQUIRE(labelled > 100);
      CHECK(covered >= labelled * 99 / 100);
    }
  }
}

TEST_CASE("pipeline: pushDeferred + trackPending, with the next frame's predict() between them, give push()'s result exactly", "[pipeline]") {
  const int frames = 30;
  const hs::SynthOptions so = slam_test::sequenceOptions(frames);
  hs::SynthSequence<double> seq(hs::findSynthPreset("hands_cover"), 2, leftHand(), rightHand(), so);
  hawor::PipelineOptions<double> po;
  po.camera = seq.camera();
  po.userFocal = true;
  hawor::Pipeline<double> a(po, leftHand(), rightHand()), b(po, leftHand(), rightHand());
  hs::SynthFrame<double> fr;
  std::vector<hawor::ImageU8> images;
  std::vector<std::vector<hawor::HandDetection<double>>> dets;
  for (int i = 0; i < frames; ++i) {
    seq.renderFrame(i, fr);
    images.push_back(fr.images.rgb);
    dets.emplace_back();
    for (int s = 0; s < 2; ++s) {
      const auto& h = fr.hands[s];
      if (!h.valid) continue;
      hawor::HandDetection<double> d;
      d.keypoints2d.resize(21, 2);
      for (int k = 0; k < 21; ++k) d.keypoints2d.row(k) = seq.camera().project(V3(h.jointsCam.row(k).transpose())).transpose();
      d.pRight = s == 1 ? 0.9 : 0.1;
      d.track = s + 1;  // the flow follows tracks
      dets.back().push_back(d);
    }
  }
  int flowTrusted = 0;
  for (int i = 0; i < frames; ++i) {
    a.predict(images[static_cast<std::size_t>(i)]);
    a.push(images[static_cast<std::size_t>(i)], dets[static_cast<std::size_t>(i)]);
  }
  b.predict(images[0]);
  for (int i = 0; i < frames; ++i) {
    b.pushDeferred(images[static_cast<std::size_t>(i)], dets[static_cast<std::size_t>(i)]);
    if (i == 0) {
      CHECK_THROWS_WITH(b.push(images[1], {}), Catch::Contains("trackPending() must follow"));
      CHECK_THROWS_WITH(b.finishCamera(), Catch::Contains("trackPending() must follow"));
    }
    // the next frame's prediction (its perception would run now) before this frame's SLAM
    if (i + 1 < frames) {
      for (const auto& p : b.predict(images[static_cast<std::size_t>(i + 1)])) flowTrusted += p.trusted ? 1 : 0;
    }
    b.trackPending();
  }
  CHECK_THROWS_WITH(b.trackPending(), Catch::Contains("without a frame"));
  CHECK(flowTrusted > 0);  // the flow ran and its grey frame was the next frame's
  const hawor::PipelineResult<double> ra = a.finish(), rb = b.finish();
  REQUIRE(ra.cameraPoses.size() == rb.cameraPoses.size());
  for (std::size_t t = 0; t < ra.cameraPoses.size(); ++t) {
    CHECK((ra.cameraPoses[t].matrix() - rb.cameraPoses[t].matrix()).cwiseAbs().maxCoeff() == 0.0);
  }
  for (int s = 0; s < 2; ++s) CHECK((ra.hands[s].jointsWorld.array() == rb.hands[s].jointsWorld.array() || (ra.hands[s].jointsWorld.array().isNaN() && rb.hands[s].jointsWorld.array().isNaN())).all());
  CHECK(ra.scale == rb.scale);
}

TEST_CASE("pipeline: bad input is refused with a message naming it", "[pipeline]") {
  hawor::PipelineOptions<double> po;
  po.camera.fx = po.camera.fy = 500, po.camera.cx = 319.5, po.camera.cy = 239.5, po.camera.width = 640, po.camera.height = 480;
  {
    hawor::PipelineOptions<double> bad = po;
    bad.fps = 0;
    CHECK_THROWS_WITH((hawor::Pipeline<double>(bad, leftHand(), rightHand())), Catch::Contains("fps"));
    bad = po;
    bad.lens = "fisheye:nan,0,0,0";
    CHECK_THROWS((hawor::Pipeline<double>(bad, leftHand(), rightHand())));
    bad = po;
    bad.eyeHeight = 12;
    CHECK_THROWS_WITH((hawor::Pipeline<double>(bad, leftHand(), rightHand())), Catch::Contains("height above the floor"));
    bad = po;
    bad.slamSet = "noSuchOption=1";
    CHECK_THROWS_WITH((hawor::Pipeline<double>(bad, leftHand(), rightHand())), Catch::Contains("noSuchOption"));
  }
  hawor::Pipeline<double> p(po, leftHand(), rightHand());
  CHECK_THROWS_WITH(p.finishCamera(), Catch::Contains("no frames"));
  hawor::ImageU8 wrong(320, 200, 3);
  CHECK_THROWS_WITH(p.push(wrong, {}), Catch::Contains("320x200x3"));
  hawor::ImageU8 im(640, 480, 3, 100);
  std::vector<hawor::HandDetection<double>> d{det(100, 0.5)};
  d[0].keypoints2d(3, 1) = NAN;
  CHECK_THROWS_WITH(p.push(im, d), Catch::Contains("detection 0: keypoints are not finite"));
  d[0].keypoints2d(3, 1) = 1;
  d[0].pRight = 2;
  CHECK_THROWS_WITH(p.push(im, d), Catch::Contains("pRight"));
  hawor::HandPose<double> nanPose = hawor::HandPose<double>::zero(leftHand());
  nanPose.trans(0) = NAN;
  CHECK_THROWS_WITH(p.pushHands(im, {&nanPose, nullptr}), Catch::Contains("the left hand: parameters are not finite"));
  // a grey frame at the SLAM's size is taken as it is, then one frame gives a held camera
  hawor::ImageU8 grey(640, 480, 1, 90);
  p.push(grey, {});
  const hawor::PipelineResult<double> r = p.finish();
  CHECK(r.frames >= 1);
  CHECK(r.noHands);
  CHECK(std::find_if(r.warnings.begin(), r.warnings.end(), [](const std::string& w) { return w.find("no hands") != std::string::npos; }) != r.warnings.end());
  CHECK_THROWS_WITH(p.finish(), Catch::Contains("twice"));
  CHECK_THROWS_WITH(p.push(im, {}), Catch::Contains("after finish"));
}

TEST_CASE("pipeline: frame times from a source that drops frames", "[pipeline]") {
  hawor::PipelineOptions<double> po;
  po.camera.fx = po.camera.fy = 500, po.camera.cx = 319.5, po.camera.cy = 239.5, po.camera.width = 640, po.camera.height = 480;
  const hawor::ImageU8 grey(640, 480, 1, 90);
  {
    hawor::Pipeline<double> p(po, leftHand(), rightHand());
    CHECK_THROWS_WITH(p.stampFrame(0.0), Catch::Contains("before the first frame"));
    p.push(grey, {});
    p.stampFrame(10.0);
    p.push(grey, {});
    CHECK_THROWS_WITH(p.stampFrame(10.0), Catch::Contains("is not after frame 0"));
    CHECK_THROWS_WITH(p.stampFrame(NAN), Catch::Contains("not finite"));
    p.stampFrame(10.1);
    p.push(grey, {});
    p.stampFrame(10.25);
    CHECK(p.timelineFps() == Approx(2 / 0.25));  // the stamps' mean rate, not the options' 30
    const hawor::PipelineResult<double> r = p.finish();
    REQUIRE(r.times.size() == 3);
    CHECK(r.times[0] == 0.0);
    CHECK(r.times[1] == Approx(0.1));
    CHECK(r.times[2] == Approx(0.25));
    CHECK(r.fps == 30);  // the camera's
  }
  {
    hawor::Pipeline<double> p(po, leftHand(), rightHand());
    p.push(grey, {});
    p.push(grey, {});
    CHECK_THROWS_WITH(p.stampFrame(1.0), Catch::Contains("frame 0 was not"));
    CHECK(p.timelineFps() == 30);
    const hawor::PipelineResult<double> r = p.finish();
    CHECK(r.times == std::vector<double>{0.0, 1.0 / 30});
  }
  // a 60-fps video: the SLAM tracks every other frame; a 60-fps camera that drops frames: every
  // frame it is given
  po.fps = 60;
  {
    const hawor::Pipeline<double> p(po, leftHand(), rightHand());
    CHECK(p.slamOptions().atFrameRate().frameStep == 2);
    po.liveSource = true;
    const hawor::Pipeline<double> live(po, leftHand(), rightHand());
    CHECK(live.slamOptions().atFrameRate().frameStep == 1);
    CHECK(live.slamOptions().atFrameRate().fps == 60);
  }
}
