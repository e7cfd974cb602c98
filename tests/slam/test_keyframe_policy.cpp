// The keyframe policy (keyframe_policy.hpp) against the rule written out here as a plain
// disjunction over every combination of its inputs on a grid around each threshold, plus the
// reason's precedence and the options' validation.
#include <catch2/catch.hpp>

#include <string>

#include "hawor/slam/keyframe_policy.hpp"

TEMPLATE_TEST_CASE("keyframeReason: the rule over a grid of inputs", "[slam][keyframe]", float, double) {
  using S = TestType;
  hawor::KeyframePolicyOptions<S> o;  // defaults: 0.7, 60, 10, 3, 1, 12°
  int checked = 0;
  for (int mapped : {0, 20, 49, 50, 51, 59, 60, 61, 69, 70, 71, 200})
    for (int last : {0, 60, 86, 100, 120})
      for (int since : {0, 1, 2, 3, 4, 9, 10, 11})
        for (bool turning : {false, true})
          for (S rot : {S(0), S(11.9), S(12), S(12.1), S(40)}) {
            hawor::KeyframeQuery<S> q;
            q.mappedInliers = mapped;
            q.lastKeyframeInliers = last;
            q.framesSinceKeyframe = since;
            q.trackingMinInliers = 25;
            q.turning = turning;
            q.rotationSinceKeyframeDeg = rot;
            const bool thin = mapped < 60 || double(mapped) < 0.7 * double(last);
            const bool expected = since >= 10 || (thin && since >= 3) || (mapped < 50 && since >= 1) || (turning && double(rot) > 12.0);
            const hawor::KeyframeReason r = hawor::keyframeReason(q, o);
            CHECK((r != hawor::KeyframeReason::None) == expected);
            ++checked;
          }
  CHECK(checked == 12 * 5 * 8 * 2 * 5);
}

TEMPLATE_TEST_CASE("keyframeReason: the first reason that holds", "[slam][keyframe]", float, double) {
  using S = TestType;
  hawor::KeyframePolicyOptions<S> o;
  hawor::KeyframeQuery<S> q;
  q.mappedInliers = 10;  // thin and nearly lost
  q.lastKeyframeInliers = 100;
  q.turning = true;
  q.rotationSinceKeyframeDeg = S(30);
  q.framesSinceKeyframe = 10;
  CHECK(hawor::keyframeReason(q, o) == hawor::KeyframeReason::MaxInterval);
  q.framesSinceKeyframe = 3;
  CHECK(hawor::keyframeReason(q, o) == hawor::KeyframeReason::Thin);
  q.framesSinceKeyframe = 1;
  CHECK(hawor::keyframeReason(q, o) == hawor::KeyframeReason::NearlyLost);
  q.framesSinceKeyframe = 0;
  CHECK(hawor::keyframeReason(q, o) == hawor::KeyframeReason::Swept);
  q.turning = false;
  CHECK(hawor::keyframeReason(q, o) == hawor::KeyframeReason::None);
  CHECK(std::string(hawor::keyframeReasonName(hawor::KeyframeReason::Swept)) == "swept");
}

TEMPLATE_TEST_CASE("KeyframePolicyOptions::validate names the bad field", "[slam][keyframe]", float, double) {
  const auto message = [](hawor::KeyframePolicyOptions<TestType> o) {
    try {
      o.validate();
    } catch (const hawor::Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  hawor::KeyframePolicyOptions<TestType> o;
  CHECK(message(o).empty());
  o.maxInterval = 0;
  CHECK(message(o).find("maxInterval") != std::string::npos);
  o = {};
  o.inlierRatio = TestType(1.5);
  CHECK(message(o).find("inlierRatio") != std::string::npos);
  o = {};
  o.maxRotationDeg = TestType(0);
  CHECK(message(o).find("maxRotationDeg") != std::string::npos);
}
