// expandFrameStep (slam/frame_step.hpp): a result over every k-th frame expanded to all frames,
// against poses on a known constant twist, T(f) = exp(f·ξ), where the screw interpolation
// between two tracked frames is exact.
#include <catch2/catch.hpp>

#include <vector>

#include "hawor/slam/frame_step.hpp"

TEMPLATE_TEST_CASE("expandFrameStep poses the frames between tracked ones on their screw motion", "[slam][frame_step]", float, double) {
  using S = TestType;
  using SE3 = hawor::SE3<S>;
  typename SE3::Tangent xi;
  xi << S(0.03), S(-0.01), S(0.02), S(0.05), S(0.08), S(-0.04);  // per input frame: translation, rotation
  const auto truth = [&](int f) { return SE3::exp(typename SE3::Tangent(S(f) * xi)); };
  const int step = 3, numFrames = 3 * 5 + 2;  // tracked 0, 3, …, 15; 16 and 17 after the last
  hawor::SlamResult<S> r;
  for (int i = 0; i * step < numFrames; ++i) {
    r.poses.push_back(truth(i * step));
    r.status.push_back(i == 2 ? hawor::SlamStatus::Lost : hawor::SlamStatus::Tracked);
    r.keyframe.push_back(i % 2 == 0 ? 1 : 0);
    r.inliers.push_back(100 + i);
  }
  r.keyframeDepths.resize(2);
  r.keyframeDepths[0].frame = 2;
  r.keyframeDepths[1].frame = 4;
  r.placeLinks.push_back({4, 0, 30});
  r.numKeyframes = 3;
  const hawor::SlamResult<S> e = hawor::expandFrameStep(r, step, numFrames);
  REQUIRE(e.poses.size() == std::size_t(numFrames));
  REQUIRE(e.status.size() == std::size_t(numFrames));
  REQUIRE(e.keyframe.size() == std::size_t(numFrames));
  REQUIRE(e.inliers.size() == std::size_t(numFrames));
  const double tol = sizeof(S) == 4 ? 1e-5 : 1e-12;
  for (int f = 0; f < numFrames; ++f) {
    CAPTURE(f);
    const SE3 want = f <= 15 ? truth(f) : truth(15);  // after the last tracked frame: held
    CHECK((e.poses[std::size_t(f)].matrix() - want.matrix()).norm() < tol);
    const bool tracked = f % step == 0;
    const int i = f / step;
    CHECK(e.keyframe[std::size_t(f)] == (tracked && i % 2 == 0 ? 1 : 0));
    CHECK(e.inliers[std::size_t(f)] == (tracked ? 100 + i : 0));
    // between: Interpolated, or Lost next to a lost tracked frame (6 is lost: 4, 5, 7, 8)
    const hawor::SlamStatus want_status = f == 6 ? hawor::SlamStatus::Lost
                                          : tracked ? hawor::SlamStatus::Tracked
                                          : (f >= 4 && f <= 8) ? hawor::SlamStatus::Lost
                                                               : hawor::SlamStatus::Interpolated;
    CHECK(e.status[std::size_t(f)] == want_status);
  }
  CHECK(e.keyframeDepths[0].frame == 6);
  CHECK(e.keyframeDepths[1].frame == 12);
  CHECK(e.placeLinks[0].frame == 12);
  CHECK(e.placeLinks[0].oldFrame == 0);
  CHECK(e.numKeyframes == 3);

  // step 1 is the identity; inconsistent lengths and counts are refused
  const hawor::SlamResult<S> same = hawor::expandFrameStep(r, 1, int(r.poses.size()));
  CHECK(same.poses.size() == r.poses.size());
  CHECK_THROWS_WITH(hawor::expandFrameStep(r, step, 30), Catch::Contains("cannot hold"));
  CHECK_THROWS_WITH(hawor::expandFrameStep(r, step, 14), Catch::Contains("cannot hold"));
  CHECK_THROWS_WITH(hawor::expandFrameStep(r, 0, numFrames), Catch::Contains("step"));
  hawor::SlamResult<S> bad = r;
  bad.status.pop_back();
  CHECK_THROWS_WITH(hawor::expandFrameStep(bad, step, numFrames), Catch::Contains("differ"));
  CHECK(hawor::expandFrameStep(hawor::SlamResult<S>(), step, 0).poses.empty());
}
