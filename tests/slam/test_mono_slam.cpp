// MonoSlam end to end on short sequences of the synthetic generator (native and WASM): accuracy
// against the ground-truth trajectory (Sim(3)-aligned), the keyframe depths against the rendered
// depth maps, the hand masking, and bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "hawor/eval/camera_metrics.hpp"
#include "hawor/slam/mono_slam.hpp"
#include "hawor/synth/synth.hpp"
#include "synth_support.hpp"

template class hawor::MonoSlam<float>;
template class hawor::MonoSlam<double>;

namespace {

namespace hs = hawor::synth;

struct Run {
  hawor::SlamResult<double> result;
  std::vector<hawor::Vec3<double>> gt;
  std::vector<hawor::Mat3<double>> gtR;  // camera-to-world rotations
  std::vector<hs::SynthFrame<double>> keep;  // frames kept for the checks (keyframes only)
  double path = 0;
};

using slam_test::leftHand;
using slam_test::rightHand;

/// `coverFrom`..`coverTo` (inclusive): frames whose mask covers the whole image (a hand over the
/// lens), `opt` the SLAM options (useMasks is set from `masks`), `textureDivisor` the scene's
/// (2: coarser textures, quicker to set up; 1: those of `hawor synth` and bench_slam).
Run runPreset(const std::string& preset, int frames, bool masks, std::uint64_t seed, int coverFrom = -1, int coverTo = -2,
              hawor::SlamOptions<double> opt = {}, int textureDivisor = 2) {
  const hs::SynthOptions so = slam_test::sequenceOptions(frames, textureDivisor);
  hs::SynthSequence<double> seq(hs::findSynthPreset(preset), seed, leftHand(), rightHand(), so);
  opt.useMasks = masks;
  hawor::MonoSlam<double> slam(seq.camera(), opt);
  Run run;
  std::vector<hs::SynthFrame<double>> all;
  hs::SynthFrame<double> fr;
  for (int i = 0; i < seq.numFrames(); ++i) {
    seq.renderFrame(i, fr);
    run.gt.push_back(fr.worldFromCamera.t);
    run.gtR.push_back(fr.worldFromCamera.R);
    if (i >= coverFrom && i <= coverTo) std::fill(fr.images.mask.data.begin(), fr.images.mask.data.end(), 255);
    slam.process(fr.images.rgb, &fr.images.mask);
    all.push_back(fr);
    all.back().images.rgb = hawor::ImageU8();  // keep depth and mask only
  }
  run.result = slam.finish();
  for (std::size_t i = 1; i < run.gt.size(); ++i) run.path += (run.gt[i] - run.gt[i - 1]).norm();
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (run.result.keyframe[i]) run.keep.push_back(std::move(all[i]));
  }
  return run;
}

/// The preset's first `frames` frames played `passes` times, forward and backward in turn (the
/// frame at a turning point not repeated): a wearer going back and forth over the same places.
Run runPasses(const std::string& preset, int frames, int passes, std::uint64_t seed, hawor::SlamOptions<double> opt = {}) {
  const hs::SynthOptions so = slam_test::sequenceOptions(frames);
  hs::SynthSequence<double> seq(hs::findSynthPreset(preset), seed, leftHand(), rightHand(), so);
  opt.useMasks = true;
  hawor::MonoSlam<double> slam(seq.camera(), opt);
  Run run;
  hs::SynthFrame<double> fr;
  for (int p = 0; p < passes; ++p) {
    for (int j = p == 0 ? 0 : 1; j < frames; ++j) {
      const int i = p % 2 == 0 ? j : frames - 1 - j;
      seq.renderFrame(i, fr);
      run.gt.push_back(fr.worldFromCamera.t);
      run.gtR.push_back(fr.worldFromCamera.R);
      slam.process(fr.images.rgb, &fr.images.mask);
    }
  }
  run.result = slam.finish();
  for (std::size_t i = 1; i < run.gt.size(); ++i) run.path += (run.gt[i] - run.gt[i - 1]).norm();
  return run;
}

/// Angle of a rotation matrix (degrees): acos((tr R − 1) / 2).
double angleDeg(const hawor::Mat3<double>& R) {
  return std::acos(std::min(1.0, std::max(-1.0, (R.trace() - 1.0) / 2.0))) * 180.0 / M_PI;
}

/// Rotation error (degrees) of frame i relative to frame 0, against the truth.
double rotationErrorDeg(const Run& r, int i) {
  const hawor::Mat3<double> truth = r.gtR[0].transpose() * r.gtR[static_cast<std::size_t>(i)];
  const hawor::Mat3<double> est = r.result.poses[0].rotationMatrix().transpose() * r.result.poses[static_cast<std::size_t>(i)].rotationMatrix();
  return angleDeg(truth.transpose() * est);
}

double ateMetres(const Run& r, double* scale = nullptr) {
  std::vector<hawor::Vec3<double>> est;
  for (const auto& T : r.result.poses) est.push_back(T.translation());
  return hawor::ateSim3(hawor::cameraPositions(r.gt), hawor::cameraPositions(est), scale) / 1000.0;
}

}  // namespace

TEST_CASE("MonoSlam: walking sequence with hands, accurate up to a similarity", "[slam][system]") {
  const Run r = runPreset("walk", 60, true, 3);
  const int n = static_cast<int>(r.result.poses.size());
  REQUIRE(n == 60);
  CHECK(r.result.initialised);
  CHECK(r.result.numKeyframes >= 3);
  CHECK(r.result.poses[0].translation().norm() < 1e-9);
  CHECK(r.result.count(hawor::SlamStatus::Tracked) >= n * 3 / 4);
  CHECK(r.result.count(hawor::SlamStatus::Lost) == 0);
  double scale = 0;
  const double ate = ateMetres(r, &scale);
  INFO("ATE " << ate << " m over a path of " << r.path << " m");
  CHECK(ate < 0.02 * r.path);

  // Keyframe depths: the SLAM's depths times the Sim(3) scale match the rendered depth maps, and
  // none lies on a hand (back-end masking keeps masked points out of the scale step).
  std::size_t k = 0, checked = 0, onHand = 0;
  std::vector<double> rel;
  for (const auto& kd : r.result.keyframeDepths) {
    while (k < r.keep.size() && r.keep[k].index != kd.frame) ++k;
    REQUIRE(k < r.keep.size());
    const hs::SynthFrame<double>& f = r.keep[k];
    for (std::size_t q = 0; q < kd.depth.size(); ++q) {
      const int x = int(std::lround(kd.uv[q](0))), y = int(std::lround(kd.uv[q](1)));
      REQUIRE(f.images.depth.contains(x, y));
      if (f.images.mask.at(x, y)) ++onHand;
      const double g = f.images.depth.at(x, y);
      if (std::isfinite(g)) rel.push_back(scale * kd.depth[q] / g);
      ++checked;
    }
  }
  REQUIRE(checked > 100);
  CHECK(onHand == 0);
  std::sort(rel.begin(), rel.end());
  const double med = rel[rel.size() / 2];
  CHECK(med == Approx(1.0).margin(0.05));
  // Most points lie on the surface they were seen on (depth discontinuities excepted).
  std::size_t close = 0;
  for (double v : rel) close += std::abs(v - 1.0) < 0.05 ? 1 : 0;
  CHECK(close > rel.size() * 8 / 10);
}

TEST_CASE("MonoSlam: at 60 fps every other frame is tracked and the frames between interpolated (frameStep)", "[slam][system]") {
  // the walk's first two seconds at 60 fps: the same motion as the 60 frames above
  hs::SynthOptions so = slam_test::sequenceOptions(120);
  so.fps = 60;
  hs::SynthSequence<double> seq(hs::findSynthPreset("walk"), 3, leftHand(), rightHand(), so);
  hawor::SlamOptions<double> opt;
  opt.fps = 60;  // frameStep automatic: 2
  hawor::MonoSlam<double> slam(seq.camera(), opt);
  CHECK(slam.frameStep() == 2);
  Run r;
  hs::SynthFrame<double> fr;
  for (int i = 0; i < seq.numFrames(); ++i) {
    seq.renderFrame(i, fr);
    r.gt.push_back(fr.worldFromCamera.t);
    r.gtR.push_back(fr.worldFromCamera.R);
    const hawor::SlamStatus st = slam.process(fr.images.rgb, &fr.images.mask);
    if (i % 2 == 1) CHECK(st != hawor::SlamStatus::Tracked);  // not tracked: provisional
    CHECK(slam.numFrames() == i + 1);
    CHECK(slam.livePose(i).translation().allFinite());
  }
  r.result = slam.finish();
  for (std::size_t i = 1; i < r.gt.size(); ++i) r.path += (r.gt[i] - r.gt[i - 1]).norm();
  const int n = static_cast<int>(r.result.poses.size());
  REQUIRE(n == 120);
  CHECK(r.result.initialised);
  int oddKeyframes = 0, oddTracked = 0;
  for (int i = 1; i < n; i += 2) {
    oddKeyframes += r.result.keyframe[std::size_t(i)];
    oddTracked += r.result.status[std::size_t(i)] == hawor::SlamStatus::Tracked ? 1 : 0;
  }
  CHECK(oddKeyframes == 0);
  CHECK(oddTracked == 0);
  for (const auto& d : r.result.keyframeDepths) CHECK(d.frame % 2 == 0);
  CHECK(r.result.count(hawor::SlamStatus::Tracked) >= n * 3 / 8);
  CHECK(r.result.count(hawor::SlamStatus::Lost) == 0);
  const double ate = ateMetres(r);
  INFO("ATE " << ate << " m over a path of " << r.path << " m");
  CHECK(ate < 0.02 * r.path);
  // the interpolated frames' rotations as good as the tracked ones' (the walk turns slowly)
  double worst = 0;
  for (int i = 1; i < n; i += 2) worst = std::max(worst, rotationErrorDeg(r, i));
  CHECK(worst < 1.0);
}

TEST_CASE("MonoSlam: fast head turns, the map is built within the first turn (turn mode)", "[slam][system]") {
  // fast_turns, seed 1: a fixation (eye still to 2 mm: no parallax), then head turns at frames
  // ~38-50 and ~70-81 of 60-150 degrees in half a second whose only translation is the 9 cm
  // neck pivot. Tracks live a few frames in a turn; without the rotation-predicted KLT and the
  // rolling two-view reference the map waited for a slower turn (frame 123 of the benchmark's
  // sequence) and every frame before it kept the first position.
  const Run r = runPreset("fast_turns", 100, true, 1);
  const int n = static_cast<int>(r.result.poses.size());
  REQUIRE(n == 100);
  CHECK(r.result.initialised);
  int first = n;
  for (int i = 0; i < n; ++i) {
    if (r.result.status[static_cast<std::size_t>(i)] == hawor::SlamStatus::Tracked && r.result.keyframe[static_cast<std::size_t>(i)]) {
      first = i;
      break;
    }
  }
  INFO("first keyframe at frame " << first);
  CHECK(first <= 55);
  // 49 frames tracked (the first map at frame 47, the second turn re-initialising at 77); 100
  // before tracks that jump off the rays' rotation were dropped (SlamOptions::maxRayJumpDeg),
  // which made these 100 frames 1.4 -> 6.3 % of the path and fast_turns seeds 1-8 better on
  // the whole (README, "SLAM benchmark").
  CHECK(r.result.count(hawor::SlamStatus::Tracked) >= n * 45 / 100);
  for (const auto& T : r.result.poses) CHECK(T.translation().allFinite());
  // Lost frames keep the rotation of the tracked rays (not a SLERP between the posed frames
  // around them, which cut a fast turn short: fast_turns seed 4 lost frames 33 deg off on
  // average, 1.0 deg with the rays): each frame's rotation relative to frame 0 against the truth.
  double worstLost = 0;
  int lost = 0;
  for (int i = 0; i < n; ++i) {
    if (r.result.status[static_cast<std::size_t>(i)] != hawor::SlamStatus::Lost) continue;
    worstLost = std::max(worstLost, rotationErrorDeg(r, i));
    ++lost;
  }
  INFO(lost << " lost frames, worst rotation error " << worstLost << " deg");
  CHECK(worstLost < 5.0);
  // Loose: the second turn still re-initialises here (see the README's SLAM benchmark).
  const double ate = ateMetres(r);
  INFO("ATE " << ate << " m over a path of " << r.path << " m");
  CHECK(ate < 0.25 * r.path);
}

TEST_CASE("MonoSlam: a turn under a hand that covers the view keeps turning (coastRotation)", "[slam][system]") {
  // fast_turns, seed 1: a head turn over frames 38-51. Frames 42-44 are fully masked (a hand
  // over the lens: no track, no rotation from the rays; frame 45 has no track from 44 either).
  // Carried on at the last step's angular velocity (6.5 deg a frame while the head sped up to
  // 9 deg) the turn loses 8.5 deg; held, it loses everything turned under the hand, and every
  // later frame keeps that offset.
  hawor::SlamOptions<double> on, off;
  off.turn.coastFrames = 0;
  const Run r = runPreset("fast_turns", 60, true, 1, 42, 44, on);
  const Run q = runPreset("fast_turns", 60, true, 1, 42, 44, off);
  double turned = 0;  // the truth's turn under the hand
  for (int i = 42; i <= 44; ++i) {
    turned += angleDeg(r.gtR[static_cast<std::size_t>(i - 1)].transpose() * r.gtR[static_cast<std::size_t>(i)]);
  }
  double withCoast = 0, held = 0;  // worst rotation errors over frames 42-59
  for (int i = 42; i <= 59; ++i) {
    withCoast = std::max(withCoast, rotationErrorDeg(r, i));
    held = std::max(held, rotationErrorDeg(q, i));
  }
  INFO("turned " << turned << " deg under the hand; worst rotation error over frames 42-59: carried on "
       << withCoast << " deg, held " << held << " deg");
  REQUIRE(turned > 15.0);
  CHECK(withCoast < 0.4 * turned);
  CHECK(held > 0.9 * turned);
}

TEST_CASE("MonoSlam: after a hand covers the whole view, relocalisation puts the frames back in the map; without it, place recognition places the new segment", "[slam][system]") {
  // table_work, seed 1: frames 40-49 fully masked (no track survives: tracking is lost and the
  // map is reset after lostFramesBeforeReset frames). When the view comes back the old map's
  // points are found again from the kept keyframe images: the same map goes on (no new segment,
  // so no new scale), the first pose back is Relocalised; without relocalisation a second map
  // segment starts.
  hawor::SlamOptions<double> on, off;
  off.reloc.enabled = false;
  off.revisit.enabled = false;  // (it searches relocalisation's kept keyframes)
  const Run r = runPreset("table_work", 90, true, 1, 40, 49, on);
  const Run q = runPreset("table_work", 90, true, 1, 40, 49, off);
  const auto& a = r.result;
  CHECK(a.numLosses == 1);
  CHECK(a.numRelocalisations >= 1);
  CHECK(a.numResets == 0);
  int back = -1;
  for (int i = 50; i < 60 && back < 0; ++i) {
    if (a.status[static_cast<std::size_t>(i)] == hawor::SlamStatus::Relocalised) back = i;
  }
  INFO("relocalised at frame " << back);
  CHECK(back >= 50);
  CHECK(back <= 53);
  for (int i = 40; i < 50; ++i) CHECK(a.status[static_cast<std::size_t>(i)] == hawor::SlamStatus::Lost);
  CHECK(a.count(hawor::SlamStatus::Tracked) >= 70);
  CHECK(q.result.numResets >= 1);
  CHECK(q.result.numRelocalisations == 0);
  const double ate = ateMetres(r);
  INFO("ATE " << ate << " m over a path of " << r.path << " m (without relocalisation " << ateMetres(q) << " m)");
  CHECK(ate < 0.03 * r.path);

  // Without relocalisation the second segment is in a scale of its own. Its keyframes see the
  // table the first segment mapped: place recognition links them (every link a true revisit: by
  // the ground truth the two cameras stand within 0.3 m and look within 30° of each other), and
  // finish() moves the segment into the first one's world by the linked points. Without place
  // recognition the segments are joined by the head model and the median-depth join only.
  hawor::SlamOptions<double> noPlace = off;
  noPlace.place.enabled = false;
  noPlace.reloc.byPlace = false;
  const Run p = runPreset("table_work", 90, true, 1, 40, 49, noPlace);
  REQUIRE(!q.result.placeLinks.empty());
  CHECK(q.result.numPlaceLinks == static_cast<int>(q.result.placeLinks.size()));
  CHECK(q.result.numPlacedSegments >= 1);
  for (const auto& l : q.result.placeLinks) {
    const std::size_t f = static_cast<std::size_t>(l.frame), g = static_cast<std::size_t>(l.oldFrame);
    const double apart = (q.gt[f] - q.gt[g]).norm();
    const double turned = angleDeg(q.gtR[g].transpose() * q.gtR[f]);
    INFO("link " << l.frame << " -> " << l.oldFrame << " (" << l.points << " points): " << apart << " m, " << turned << " deg");
    CHECK(l.frame > l.oldFrame);
    CHECK(l.points >= off.place.minInliers);
    CHECK(apart < 0.3);
    CHECK(turned < 30.0);
  }
  CHECK(p.result.placeLinks.empty());
  CHECK(p.result.numPlacedSegments == 0);
  const double placed = ateMetres(q), unplaced = ateMetres(p);
  INFO("ATE " << placed << " m placed by the links, " << unplaced << " m without, path " << q.path << " m");
  CHECK(placed < 0.03 * q.path);
  CHECK(placed < unplaced);
}

TEST_CASE("MonoSlam: relocalisation by place recognition re-enters the old map without kept images", "[slam][system]") {
  // The same loss with no keyframe image kept (reloc.keyframes = reloc.anchors = 0: the KLT
  // search has nothing to search from, as when the view comes back to a place mapped long
  // before): the frames' tracks described and looked up in the place index find the old
  // keyframes, two agreeing PnP poses put the frame back, and the reset is undone.
  hawor::SlamOptions<double> opt;
  opt.reloc.keyframes = 0;
  opt.reloc.anchors = 0;
  const Run r = runPreset("table_work", 70, true, 1, 40, 49, opt);
  const auto& a = r.result;
  CHECK(a.numLosses == 1);
  CHECK(a.numRelocalisations == 0);
  CHECK(a.numPlaceRelocalisations == 1);
  CHECK(a.numResets == 0);
  int back = -1;
  for (int i = 50; i < 70 && back < 0; ++i) {
    if (a.status[static_cast<std::size_t>(i)] == hawor::SlamStatus::Relocalised) back = i;
  }
  INFO("relocalised at frame " << back);
  CHECK(back >= 50);
  CHECK(back <= 56);
  // Without it the same loss starts a new map segment.
  opt.reloc.byPlace = false;
  const Run q = runPreset("table_work", 70, true, 1, 40, 49, opt);
  CHECK(q.result.numPlaceRelocalisations == 0);
  CHECK(q.result.numResets == 1);
  const double ate = ateMetres(r);
  INFO("ATE " << ate << " m over a path of " << r.path << " m (" << ateMetres(q) << " m with a new segment)");
  CHECK(ate < 0.03 * r.path);
}


TEST_CASE("MonoSlam: a view seen before a broken rotation chain puts the later frames' rotation right (link.enabled)", "[slam][system]") {
  // fast_turns, seed 8 (full-resolution textures, as `hawor synth` writes it): the map is lost
  // in a turn at frame 88; at frame 186 the head turns from rest onto a bare wall and no frame
  // gives the rotation of the next 86 degrees, so the segment built after it (frame ~200) lives
  // in a world rotated by them. From frame ~243 the head looks where the lost segment's last
  // keyframe (frame 87) looked: PnP against that keyframe's points gives the frames' rotation in
  // the old world, and finish() rotates the chain after the break by it. Without the links the
  // offset stays to the end.
  hawor::SlamOptions<double> on, off;
  off.link.enabled = false;
  const int n = 262;
  const Run r = runPreset("fast_turns", n, true, 8, -1, -2, on, 1);
  const Run q = runPreset("fast_turns", n, true, 8, -1, -2, off, 1);
  // Worst rotation errors over the frames of the links (the last 20) and over the segment after
  // the break (200-230). The second is looser: between it and the links the head turns again
  // (frames 226-240, the rays' rotation carried through a few frames), and that turn's own
  // error of ~8 degrees is not the links' to correct.
  double lastWith = 0, lastWithout = 0, segWith = 0, segWithout = 0;
  for (int i = n - 20; i < n; ++i) {
    lastWith = std::max(lastWith, rotationErrorDeg(r, i));
    lastWithout = std::max(lastWithout, rotationErrorDeg(q, i));
  }
  for (int i = 200; i <= 230; ++i) {
    segWith = std::max(segWith, rotationErrorDeg(r, i));
    segWithout = std::max(segWithout, rotationErrorDeg(q, i));
  }
  INFO("worst rotation error, last 20 frames: with links " << lastWith << " deg, without " << lastWithout
       << " deg; frames 200-230: " << segWith << " / " << segWithout << " deg; ATE " << ateMetres(r) << " / " << ateMetres(q)
       << " m over " << r.path << " m; resets " << r.result.numResets);
  CHECK(r.result.numResets >= 1);
  CHECK(lastWithout > 30.0);
  CHECK(lastWith < 3.0);
  CHECK(segWithout > 30.0);
  CHECK(segWith < 15.0);
  // Frames 0-87 are untouched: the links only rotate what follows the break.
  for (int i = 0; i < 88; i += 8) CHECK(rotationErrorDeg(r, i) == Approx(rotationErrorDeg(q, i)).margin(1e-9));
}

TEST_CASE("MonoSlam: bad input gives errors or statuses, never a crash", "[slam][system]") {
  hawor::PinholeCamera<double> cam;
  cam.fx = cam.fy = 200, cam.cx = 159.5, cam.cy = 119.5;
  SECTION("empty, mismatched sizes, wrong mask, calls out of order") {
    hawor::MonoSlam<double> slam(cam);
    CHECK_THROWS_AS(slam.process(hawor::ImageU8()), hawor::Error);
    slam.process(hawor::ImageU8(320, 240, 3, 40));
    CHECK_THROWS_WITH(slam.process(hawor::ImageU8(321, 240, 3, 40)), Catch::Contains("321x240"));
    const hawor::ImageU8 badMask(100, 100, 1, 0);
    CHECK_THROWS_WITH(slam.process(hawor::ImageU8(320, 240, 3, 40), &badMask), Catch::Contains("mask"));
    slam.finish();
    CHECK_THROWS_AS(slam.process(hawor::ImageU8(320, 240, 3, 40)), hawor::Error);
    CHECK_THROWS_AS(slam.finish(), hawor::Error);
  }
  SECTION("invalid intrinsics") {
    hawor::PinholeCamera<double> bad = cam;
    bad.fx = 0;
    CHECK_THROWS_AS(hawor::MonoSlam<double>(bad), hawor::Error);
    bad = cam;
    bad.cx = std::nan("");
    CHECK_THROWS_AS(hawor::MonoSlam<double>(bad), hawor::Error);
  }
  SECTION("invalid options") {
    hawor::SlamOptions<double> o;
    o.turn.coastFrames = -1;
    CHECK_THROWS_WITH(hawor::MonoSlam<double>(cam, o), Catch::Contains("turn.coastFrames"));
    o = hawor::SlamOptions<double>();
    o.turn.coastMaxStepDeg = std::nan("");
    CHECK_THROWS_WITH(hawor::MonoSlam<double>(cam, o), Catch::Contains("turn.coastMaxStepDeg"));
    o = hawor::SlamOptions<double>();
    o.init.maxGap = 0;
    CHECK_THROWS_WITH(hawor::MonoSlam<double>(cam, o), Catch::Contains("init.maxGap"));
    o = hawor::SlamOptions<double>();
    o.keyframe.maxInterval = 0;
    CHECK_THROWS_WITH(hawor::MonoSlam<double>(cam, o), Catch::Contains("keyframe.maxInterval"));
    o = hawor::SlamOptions<double>();
    CHECK_NOTHROW(hawor::MonoSlam<double>(cam, o));
  }
  SECTION("all-black frames and a mask over everything: statuses, identity poses") {
    for (int variant = 0; variant < 2; ++variant) {
      hawor::MonoSlam<double> slam(cam);
      const hawor::ImageU8 black(320, 240, 1, 0), full(320, 240, 1, 255);
      hs::SynthOptions so;
      so.width = 320, so.height = 240, so.frames = 12, so.textureDivisor = 4;
      hs::SynthSequence<double> seq(hs::findSynthPreset("walk"), 1, leftHand(), rightHand(), so);
      hs::SynthFrame<double> fr;
      for (int i = 0; i < 12; ++i) {
        if (variant == 0) {
          CHECK(slam.process(black) == hawor::SlamStatus::Interpolated);
        } else {
          seq.renderFrame(i, fr);
          CHECK(slam.process(fr.images.rgb, &full) == hawor::SlamStatus::Interpolated);
          CHECK(slam.numLiveTracks() == 0);
        }
      }
      const hawor::SlamResult<double> r = slam.finish();
      REQUIRE(r.poses.size() == 12);
      CHECK_FALSE(r.initialised);
      for (const auto& T : r.poses) {
        CHECK(T.translation().norm() == 0.0);
        CHECK(T.rotationMatrix().isApprox(Eigen::Matrix3d::Identity(), 1e-9));
      }
    }
  }
}

TEST_CASE("MonoSlam<float> runs the same pipeline", "[slam][system]") {
  hs::SynthOptions so;
  so.width = 320, so.height = 240, so.frames = 30, so.textureDivisor = 4;
  hs::SynthSequence<double> seq(hs::findSynthPreset("walk"), 2, leftHand(), rightHand(), so);
  hawor::PinholeCamera<float> cam = seq.camera().cast<float>();
  hawor::MonoSlam<float> slam(cam);
  hs::SynthFrame<double> fr;
  for (int i = 0; i < seq.numFrames(); ++i) {
    seq.renderFrame(i, fr);
    slam.process(fr.images.rgb, &fr.images.mask);
  }
  const hawor::SlamResult<float> r = slam.finish();
  REQUIRE(r.poses.size() == 30);
  for (const auto& T : r.poses) CHECK(T.translation().allFinite());
}

TEST_CASE("MonoSlam: the revisit search and the sequence refinement tighten a table-work trajectory", "[slam][system]") {
  // table_work, seed 3 (150 frames of the suite's coarser textures): the head looks back at the
  // same part of the table again and again. With both off the trajectory is the keyframes' map
  // (measured: 8.5 % of the path with both off, 3.5 % on; the first frames, before a map, carry
  // most of what is left).
  hawor::SlamOptions<double> off;
  off.revisit.enabled = false;
  off.finish.sequenceRefine = false;
  const Run on = runPreset("table_work", 150, true, 3);
  const Run plain = runPreset("table_work", 150, true, 3, -1, -2, off);
  const int n = static_cast<int>(on.result.poses.size());
  CHECK(on.result.numRevisitPoints > 0);
  CHECK(on.result.numRefinedFrames >= n * 9 / 10);
  CHECK(plain.result.numRevisitPoints == 0);
  CHECK(plain.result.numRefinedFrames == 0);
  const double a = ateMetres(on), b = ateMetres(plain);
  INFO("ATE " << a << " m with, " << b << " m without, path " << on.path << " m");
  CHECK(a < 0.6 * b);
  CHECK(a < 0.05 * on.path);

}

TEST_CASE("MonoSlam: back and forth over one place, the global bundle adjustment leaves out redundant keyframes above its budget", "[slam][system]") {
  // Keyframe culling (finish.maxAdjustedKeyframes, finish.redundantShare): the passes after the
  // first see the same points, so their keyframes are left out of the final adjustment once the
  // keyframes exceed the budget (here 10); the trajectory stays as accurate as with every
  // keyframe adjusted (the default budget, 500, keeps all of this clip's).
  hawor::SlamOptions<double> budget;
  budget.finish.maxAdjustedKeyframes = 10;
  const Run culled = runPasses("walk", 30, 5, 3, budget);
  const Run every = runPasses("walk", 30, 5, 3);
  REQUIRE(culled.result.poses.size() == 146);
  const double ateCulled = ateMetres(culled), ateEvery = ateMetres(every);
  INFO("keyframes " << culled.result.numKeyframes << ", adjusted " << culled.result.numAdjustedKeyframes
                    << "; ATE " << ateCulled << " m (every keyframe: " << ateEvery << " m) over " << culled.path << " m");
  CHECK(every.result.numAdjustedKeyframes == every.result.numKeyframes);
  CHECK(culled.result.numAdjustedKeyframes < culled.result.numKeyframes * 3 / 4);
  CHECK(culled.result.numAdjustedKeyframes >= 10);
  CHECK(ateCulled < 0.01 * culled.path);
  CHECK(ateCulled < 1.5 * ateEvery + 1e-3 * culled.path);
  hawor::SlamOptions<double> bad;
  bad.finish.redundantShare = 0.0;
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("finish.redundantShare"));
  bad.finish.redundantShare = 0.9;
  bad.finish.maxAdjustedKeyframes = 1;
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("finish.maxAdjustedKeyframes"));
}
