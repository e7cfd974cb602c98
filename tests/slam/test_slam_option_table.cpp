// SlamOptions by name (slam_option_table.hpp): each kind of field set through its name lands in
// that field (read back directly), defaults elsewhere untouched, and malformed settings refused
// with the name in the message. Completeness against the headers' declarations is checked by
// tests/cli/test_slam_cli.py, which parses them independently.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "hawor/slam/slam_option_table.hpp"

TEMPLATE_TEST_CASE("setSlamOptions sets fields by name", "[slam][options]", float, double) {
  using O = hawor::SlamOptions<TestType>;
  O o;
  const O d;
  hawor::setSlamOptions(o, "init.minTracks=41,init.minFlowPx=2.5,reloc.enabled=false,klt.maxResidual=9,twoView.minTriangulated=12,"
                           "pnp.thresholdPx=1.5,corners.cellSize=16,useMasks=0,join.placeShort=false,finish.focalMinStd=0.05");
  CHECK(o.init.minTracks == 41);
  CHECK(o.init.minFlowPx == TestType(2.5));
  CHECK(o.reloc.enabled == false);
  CHECK(o.klt.maxResidual == 9.0f);
  CHECK(o.twoView.minTriangulated == 12);
  CHECK(o.pnp.thresholdPx == TestType(1.5));
  CHECK(o.corners.cellSize == 16);
  CHECK(o.useMasks == false);
  CHECK(o.join.placeShort == false);
  CHECK(o.finish.focalMinStd == TestType(0.05));
  CHECK(o.init.reinitMinTracks == d.init.reinitMinTracks);  // untouched
  CHECK(o.twoView.minParallaxDeg == d.twoView.minParallaxDeg);
  hawor::setSlamOptions(o, "");  // nothing
  CHECK(o.init.minTracks == 41);
  // every listed name accepts a value of its kind
  for (const std::string& n : hawor::slamOptionNames<TestType>()) {
    O p;
    bool ok = true;
    try {
      hawor::setSlamOption(p, n, "1");
    } catch (const hawor::Error&) {
      ok = false;
    }
    CHECK(ok);
  }
}

TEMPLATE_TEST_CASE("setSlamOptions refuses malformed settings", "[slam][options]", float, double) {
  hawor::SlamOptions<TestType> o;
  const auto refused = [&](const std::string& list, const std::string& word) {
    try {
      hawor::setSlamOptions(o, list);
    } catch (const hawor::Error& e) {
      return std::string(e.what()).find(word) != std::string::npos;
    }
    return false;
  };
  CHECK(refused("noSuch=1", "noSuch"));
  CHECK(refused("noSuch=1", "init.minTracks"));  // the known names listed
  CHECK(refused("init.minTracks=4.5", "integer"));
  CHECK(refused("init.minTracks=1e12", "integer"));
  CHECK(refused("init.minFlowPx=inf", "finite"));
  CHECK(refused("init.minFlowPx=3px", "finite"));
  CHECK(refused("reloc.enabled=yes", "true, false"));
  CHECK(refused("reloc.enabled", "NAME=VALUE"));
  CHECK(refused("=1", "NAME=VALUE"));
  CHECK(refused("init.minTracks=40,,", "NAME=VALUE"));
}

TEMPLATE_TEST_CASE("SlamOptions::validate names the bad field or combination", "[slam][options]", float, double) {
  using O = hawor::SlamOptions<TestType>;
  const auto message = [](const O& o) -> std::string {
    try {
      o.validate();
    } catch (const hawor::Error& e) {
      return e.what();
    }
    return "";
  };
  CHECK(message(O{}).empty());  // the defaults are valid
  const auto with = [](const std::string& list) {
    O o;
    hawor::setSlamOptions(o, list);
    return o;
  };
  CHECK(message(with("reloc.enabled=false")).find("revisit.enabled needs reloc.enabled") != std::string::npos);
  CHECK(message(with("reloc.enabled=false,revisit.enabled=false")).empty());
  CHECK(message(with("place.enabled=false")).find("reloc.byPlace needs place.enabled") != std::string::npos);
  CHECK(message(with("place.enabled=false,reloc.byPlace=false")).empty());
  CHECK(message(with("reloc.placeAgreeDeg=-1")).find("reloc.placeAgreeDeg") != std::string::npos);
  CHECK(message(with("join.headModelAll=false")).find("join.headModelAll") != std::string::npos);
  CHECK(message(with("join.headModelAll=false,join.beforeRefine=false,join.placeShort=false")).empty());
  CHECK(message(with("reloc.spacing=0")).find("reloc.spacing") != std::string::npos);
  CHECK(message(with("revisit.minInliers=3")).find("revisit.minInliers") != std::string::npos);
  CHECK(message(with("link.everyFrames=0")).find("link.everyFrames") != std::string::npos);
  CHECK(message(with("place.ratio=1.5")).find("place.ratio") != std::string::npos);
  CHECK(message(with("finish.focalFrameSpacing=0")).find("finish.focalFrameSpacing") != std::string::npos);
  CHECK(message(with("rollingShutter=1.5")).find("rollingShutter") != std::string::npos);
  CHECK(message(with("maxFeatures=5")).find("maxFeatures") != std::string::npos);
  CHECK(message(with("init.everyFrames=0")).find("init.everyFrames") != std::string::npos);
  // MonoSlam refuses them at construction, with the same message
  hawor::PinholeCamera<TestType> cam;
  cam.fx = cam.fy = TestType(500);
  cam.cx = TestType(320);
  cam.cy = TestType(240);
  CHECK_THROWS_WITH(hawor::MonoSlam<TestType>(cam, with("reloc.enabled=false")), Catch::Contains("revisit.enabled"));
}

TEMPLATE_TEST_CASE("SlamOptions::atFrameRate applies the 30-fps frame counts and head-speed bounds above 30 fps", "[slam][options]", float, double) {
  using O = hawor::SlamOptions<TestType>;
  const O d;  // 30 fps
  // every frame count, read by name (the table), and its value at 30 fps
  const std::vector<std::string> counts = {"init.everyFrames", "init.maxGap", "turn.holdFrames", "turn.maxBridgeFrames",
                                           "turn.coastFrames", "place.minFramesApart", "reloc.spacing", "revisit.minFrames",
                                           "link.everyFrames", "finish.focalFrameSpacing", "lostFramesBeforeReset",
                                           "keyframe.maxInterval", "keyframe.minInterval", "keyframe.thinInterval",
                                           "headModel.window", "headModel.minFrames", "headModel.lag", "backTrackFrames"};
  const auto count = [](const O& o, const std::string& name) {
    O copy = o;
    const auto field = hawor::slam_option_detail::find(hawor::slam_option_detail::intFields<TestType>(), name);
    REQUIRE(field != nullptr);
    return field(copy);
  };
  const O same = d.atFrameRate();
  for (const auto& n : counts) CHECK(count(same, n) == count(d, n));
  CHECK(same.turn.coastMaxStepDeg == d.turn.coastMaxStepDeg);

  O o = d;
  o.fps = TestType(60);
  o.frameStep = 1;  // every frame tracked
  const O at60 = o.atFrameRate();
  CHECK(at60.frameStep == 1);
  for (const auto& n : counts) CHECK(count(at60, n) == 2 * count(d, n));
  CHECK(at60.sequence.headModel.window == 2 * d.sequence.headModel.window);
  CHECK(at60.turn.coastMaxStepDeg == Approx(double(d.turn.coastMaxStepDeg) / 2));
  CHECK(at60.bridge.minStepDeg == Approx(double(d.bridge.minStepDeg) / 2));
  CHECK(at60.maxRayJumpDeg == Approx(double(d.maxRayJumpDeg) / 2));
  CHECK(at60.turn.rateDeg == d.turn.rateDeg);          // the image motion a frame: stays
  CHECK(at60.init.minFlowPx == d.init.minFlowPx);      // not a count
  CHECK(at60.keyframe.maxRotationDeg == d.keyframe.maxRotationDeg);
  CHECK_NOTHROW(at60.validate());

  // at 30 fps and below nothing changes (the counts also bound the frames of evidence)
  o.fps = TestType(10);
  const O at10 = o.atFrameRate();
  for (const auto& n : counts) CHECK(count(at10, n) == count(d, n));
  CHECK(at10.turn.coastMaxStepDeg == d.turn.coastMaxStepDeg);
  CHECK(at10.maxRayJumpDeg == d.maxRayJumpDeg);
  // 45 fps: × 1.5, rounded half away from zero; a 0 (off) stays 0
  o.fps = TestType(45);
  o.turn.coastFrames = 0;
  const O at45 = o.atFrameRate();
  CHECK(at45.lostFramesBeforeReset == 6);
  CHECK(at45.init.everyFrames == 5);  // 4.5
  CHECK(at45.keyframe.thinInterval == 2);  // 1.5
  CHECK(at45.turn.coastFrames == 0);
  CHECK(at45.turn.coastMaxStepDeg == Approx(double(d.turn.coastMaxStepDeg) / 1.5));
  CHECK_NOTHROW(at45.validate());
  o.fps = TestType(1000);
  CHECK(o.atFrameRate().backTrackFrames == 300);  // the memory bound
  CHECK_NOTHROW(o.atFrameRate().validate());

  for (double bad : {0.0, -30.0, 1e4}) {
    o.frameStep = 1;
    o.fps = TestType(bad);
    CHECK_THROWS_WITH(o.atFrameRate(), Catch::Contains("fps"));
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("fps"));
  }
  hawor::PinholeCamera<TestType> cam;
  cam.fx = cam.fy = TestType(500);
  cam.cx = TestType(320);
  cam.cy = TestType(240);
  CHECK_THROWS_WITH(hawor::MonoSlam<TestType>(cam, o), Catch::Contains("fps"));
}

TEMPLATE_TEST_CASE("SlamOptions::atFrameRate with a frame step: the options of the tracked rate", "[slam][options]", float, double) {
  using O = hawor::SlamOptions<TestType>;
  const O d;
  O o = d;
  o.fps = TestType(60);  // automatic step: 2, tracked at 30 fps
  o.rollingShutter = TestType(0.6);
  const O at60 = o.atFrameRate();
  CHECK(at60.frameStep == 2);
  CHECK(at60.fps == Approx(30));
  CHECK(at60.rollingShutter == Approx(0.3));  // the readout, a fraction of the tracked frames' interval
  CHECK(at60.lostFramesBeforeReset == d.lostFramesBeforeReset);
  CHECK(at60.keyframe.maxInterval == d.keyframe.maxInterval);
  CHECK(at60.maxRayJumpDeg == d.maxRayJumpDeg);
  // an explicit step at 120 fps: tracked at 40 fps, the counts × 4/3
  o.fps = TestType(120);
  o.frameStep = 3;
  const O at120 = o.atFrameRate();
  CHECK(at120.frameStep == 3);
  CHECK(at120.fps == Approx(40));
  CHECK(at120.lostFramesBeforeReset == 5);  // 4 · 4/3 = 5.3
  CHECK(at120.maxRayJumpDeg == Approx(double(d.maxRayJumpDeg) * 0.75));
  // the automatic step keeps the tracked rate at or above 25 fps
  for (auto [fps, step] : std::vector<std::pair<double, int>>{{10, 1}, {29.97, 1}, {30, 1}, {48, 1}, {50, 2}, {59.94, 2}, {60, 2}, {90, 3}, {120, 4}, {240, 9}}) {
    CAPTURE(fps);
    CHECK(hawor::autoFrameStep(fps) == step);
    if (fps >= 25) CHECK(fps / step >= 25.0);
  }
  o.frameStep = -1;
  CHECK_THROWS_WITH(o.atFrameRate(), Catch::Contains("frameStep"));
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("frameStep"));
}
