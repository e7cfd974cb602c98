// SlamOptions by name (slam_option_table.hpp): each kind of field set through its name lands in
// that field (read back directly), defaults elsewhere untouched, and malformed settings refused
// with the name in the message. Completeness against the headers' declarations is checked by
// tests/cli/test_slam_cli.py, which parses them independently.
#include <catch2/catch.hpp>

#include <string>

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
