// renderHandMasks (render/hand_masks.hpp): two posed hands against brute-force ray casting of
// their forward-pass meshes (union and labels), the dilation against a brute-force disc, errors.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "hawor/hand/mirror.hpp"
#include "hawor/hand/synthetic_hand.hpp"
#include "hawor/render/hand_masks.hpp"
#include "render_test_util.hpp"

namespace {

struct TwoHands {
  hawor::HandModel<double> right = hawor::makeSyntheticHand<double>(6);
  hawor::HandModel<double> left = hawor::mirrorHandModel(right);
  hawor::PinholeCamera<double> cam;
  std::vector<hawor::HandMaskHand<double>> hands;
  TwoHands() {
    cam.fx = 90, cam.fy = 92, cam.cx = 47.2, cam.cy = 35.6, cam.width = 96, cam.height = 72;
    for (int s = 0; s < 2; ++s) {
      hawor::HandMaskHand<double> h;
      h.model = s ? &right : &left;
      h.pose = hawor::HandPose<double>::zero(*h.model);
      h.pose.rot = hawor::Vec3<double>(0.3, s ? 0.4 : -0.5, 0.2);
      h.pose.handPose(3, 0) = 0.6;  // bend a finger
      h.pose.trans = hawor::Vec3<double>(s ? 0.03 : -0.04, 0.01, s ? 0.30 : 0.34);
      hands.push_back(h);
    }
  }
  hawor::Points3<double> vertices(int s) const { return hawor::forward(*hands[s].model, hands[s].pose).vertices; }
};

}  // namespace

TEST_CASE("renderHandMasks: union and labels match ray casting of the posed meshes", "[render][hand_masks]") {
  TwoHands t;
  const hawor::Points3<double> V[2] = {t.vertices(0), t.vertices(1)};
  const hawor::TriangleList F[2] = {t.hands[0].model->faces, t.hands[1].model->faces};
  hawor::Mask uni, lab;
  hawor::renderHandMasks(t.hands, t.cam, 0, uni);
  t.hands[0].value = 1, t.hands[1].value = 2;
  hawor::renderHandMasks(t.hands, t.cam, 0, lab);
  REQUIRE(uni.width == 96);
  REQUIRE(uni.height == 72);
  int judged = 0, set = 0, badUnion = 0, badLabel = 0;
  for (int y = 0; y < t.cam.height; ++y) {
    for (int x = 0; x < t.cam.width; ++x) {
      const int c0 = render_test::classify(t.cam, V[0], F[0], x, y, 1e-3);
      const int c1 = render_test::classify(t.cam, V[1], F[1], x, y, 1e-3);
      if (c0 < 0 || c1 < 0) continue;
      ++judged;
      const bool hit = c0 || c1;
      set += hit;
      badUnion += (uni.at(x, y) == 255) != hit || (uni.at(x, y) != 0 && uni.at(x, y) != 255);
      int want = 0;
      if (hit) {
        const double z0 = render_test::nearestHit(t.cam, V[0], F[0], x, y, 1e-3);
        const double z1 = render_test::nearestHit(t.cam, V[1], F[1], x, y, 1e-3);
        if (std::abs(z0 - z1) < 1e-4) continue;  // depth tie: either label
        want = z0 < z1 ? 1 : 2;
      }
      badLabel += lab.at(x, y) != want;
    }
  }
  CHECK(judged > 0.9 * 96 * 72);
  CHECK(set > 200);  // both hands are well inside the view
  CHECK(badUnion == 0);
  CHECK(badLabel == 0);
}

TEST_CASE("renderHandMasks: dilation is the disc dilation of the silhouettes", "[render][hand_masks]") {
  TwoHands t;
  hawor::Mask base, dil;
  hawor::renderHandMasks(t.hands, t.cam, 0, base);
  const int r = 3;
  hawor::renderHandMasks(t.hands, t.cam, r, dil);
  int bad = 0, grown = 0;
  for (int y = 0; y < base.height; ++y) {
    for (int x = 0; x < base.width; ++x) {
      bool near = false;
      for (int dy = -r; dy <= r && !near; ++dy)
        for (int dx = -r; dx <= r && !near; ++dx)
          near = dx * dx + dy * dy <= r * r && base.contains(x + dx, y + dy) && base.at(x + dx, y + dy);
      bad += (dil.at(x, y) == 255) != near;
      grown += near && !base.at(x, y);
    }
  }
  CHECK(bad == 0);
  CHECK(grown > 50);
}

TEST_CASE("renderHandMasks: errors", "[render][hand_masks]") {
  TwoHands t;
  hawor::Mask m;
  std::vector<hawor::HandMaskHand<double>> none;
  hawor::renderHandMasks(none, t.cam, 2, m);  // no hand: an empty mask of the camera's size
  CHECK(m.data.size() == 96u * 72u);
  CHECK(hawor::maskCoverage(m) == 0.0);
  t.hands[1].value = 7;
  CHECK_THROWS_WITH(hawor::renderHandMasks(t.hands, t.cam, 2, m), Catch::Contains("one value"));
  t.hands[1].value = 255;
  CHECK_THROWS_WITH(hawor::renderHandMasks(t.hands, t.cam, -1, m), Catch::Contains(">= 0"));
  t.hands[0].pose.trans(0) = NAN;
  CHECK_THROWS_WITH(hawor::renderHandMasks(t.hands, t.cam, 0, m), Catch::Contains("non-finite"));
  t.hands[0].model = nullptr;
  CHECK_THROWS_WITH(hawor::renderHandMasks(t.hands, t.cam, 0, m), Catch::Contains("no model"));
}
