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
  hawor::setSlamOptions(o, "init.minTracks=41,init.minFlowPx=2.5,relocalise=false,klt.maxResidual=9,twoView.minTriangulated=12,"
                           "pnp.thresholdPx=1.5,corners.cellSize=16,useMasks=0");
  CHECK(o.init.minTracks == 41);
  CHECK(o.init.minFlowPx == TestType(2.5));
  CHECK(o.relocalise == false);
  CHECK(o.klt.maxResidual == 9.0f);
  CHECK(o.twoView.minTriangulated == 12);
  CHECK(o.pnp.thresholdPx == TestType(1.5));
  CHECK(o.corners.cellSize == 16);
  CHECK(o.useMasks == false);
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
  CHECK(refused("relocalise=yes", "true, false"));
  CHECK(refused("relocalise", "NAME=VALUE"));
  CHECK(refused("=1", "NAME=VALUE"));
  CHECK(refused("init.minTracks=40,,", "NAME=VALUE"));
}
