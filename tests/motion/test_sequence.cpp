// Unit/property tests of motion/sequence.hpp: gap segments and the three fill rules.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <limits>

#include "hawor/motion/sequence.hpp"

namespace {

template <typename S>
S seqTol() {
  return std::is_same<S, float>::value ? S(1e-5) : S(1e-13);
}

hawor::ValidMask testMask() {
  // frames: 0 1 2 | 3 4 | 5 | 6 7 8 9 | 10 11
  //         x x x   v v   x   v x x v    x  x
  return {0, 0, 0, 1, 1, 0, 1, 0, 0, 1, 0, 0};
}

template <typename S>
bool rowBitwiseEqual(const hawor::Sequence<S>& a, const hawor::Sequence<S>& b, Eigen::Index t) {
  return std::memcmp(a.row(t).data(), b.row(t).data(), sizeof(S) * size_t(a.cols())) == 0;
}

template <typename S>
hawor::Sequence<S> withNaNGaps(hawor::Sequence<S> seq, const hawor::ValidMask& valid) {
  for (Eigen::Index t = 0; t < seq.rows(); ++t)
    if (!valid[size_t(t)]) seq.row(t).setConstant(std::numeric_limits<S>::quiet_NaN());
  return seq;
}

}  // namespace

TEST_CASE("findGaps lists maximal missing runs with their neighbours", "[motion][sequence]") {
  const auto gaps = hawor::findGaps(testMask());
  REQUIRE(gaps.size() == 4);
  CHECK(gaps[0].start == 0);
  CHECK(gaps[0].end == 3);
  CHECK(gaps[0].before == -1);
  CHECK(gaps[0].after == 3);
  CHECK(!gaps[0].interior());
  CHECK(gaps[1].start == 5);
  CHECK(gaps[1].end == 6);
  CHECK(gaps[1].before == 4);
  CHECK(gaps[1].after == 6);
  CHECK(gaps[1].interior());
  CHECK(gaps[2].start == 7);
  CHECK(gaps[2].length() == 2);
  CHECK(gaps[2].before == 6);
  CHECK(gaps[2].after == 9);
  CHECK(gaps[3].start == 10);
  CHECK(gaps[3].end == 12);
  CHECK(gaps[3].before == 9);
  CHECK(gaps[3].after == -1);
  CHECK(hawor::findGaps({1, 1, 1}).empty());
  CHECK(hawor::findGaps({}).empty());
  const auto all = hawor::findGaps({0, 0});
  REQUIRE(all.size() == 1);
  CHECK((all[0].before == -1 && all[0].after == -1 && all[0].length() == 2));
  CHECK(hawor::countValid(testMask()) == 4);
}

TEMPLATE_TEST_CASE("fillLinear: valid frames untouched, interior linear, ends held",
                   "[motion][sequence]", float, double) {
  using S = TestType;
  const auto valid = testMask();
  std::srand(3);
  const hawor::Sequence<S> seq = withNaNGaps<S>(hawor::Sequence<S>::Random(12, 4), valid);
  const hawor::Sequence<S> out = hawor::fillLinear(seq, valid);
  REQUIRE(out.allFinite());
  for (Eigen::Index t = 0; t < 12; ++t)
    if (valid[size_t(t)]) CHECK(rowBitwiseEqual(out, seq, t));
  for (Eigen::Index t : {0, 1, 2}) CHECK(out.row(t) == seq.row(3));
  for (Eigen::Index t : {10, 11}) CHECK(out.row(t) == seq.row(9));
  CHECK((out.row(5) - S(0.5) * (seq.row(4) + seq.row(6))).norm() < seqTol<S>());
  CHECK((out.row(7) - (seq.row(6) + (seq.row(9) - seq.row(6)) / S(3))).norm() < seqTol<S>());
  CHECK((out.row(8) - (seq.row(6) + S(2) * (seq.row(9) - seq.row(6)) / S(3))).norm() < seqTol<S>());
  // a linear signal is reproduced exactly in the interior
  hawor::Sequence<S> ramp(12, 1);
  for (Eigen::Index t = 0; t < 12; ++t) ramp(t, 0) = S(2) * S(t) - S(3);
  const hawor::Sequence<S> r = hawor::fillLinear(withNaNGaps<S>(ramp, valid), valid);
  for (Eigen::Index t = 3; t <= 9; ++t) CHECK(std::abs(r(t, 0) - ramp(t, 0)) < seqTol<S>() * 20);
}

TEMPLATE_TEST_CASE("fillRotations: SLERP per triple in gaps, constant speed, ends held",
                   "[motion][sequence]", float, double) {
  using S = TestType;
  const auto valid = testMask();
  std::srand(5);
  hawor::Sequence<S> seq = hawor::Sequence<S>::Random(12, 6) * S(2);
  seq = withNaNGaps<S>(seq, valid);
  const hawor::Sequence<S> out = hawor::fillRotations(seq, valid);
  REQUIRE(out.allFinite());
  for (Eigen::Index t = 0; t < 12; ++t)
    if (valid[size_t(t)]) CHECK(rowBitwiseEqual(out, seq, t));
  for (Eigen::Index t : {0, 1, 2}) CHECK(out.row(t) == seq.row(3));
  for (Eigen::Index t : {10, 11}) CHECK(out.row(t) == seq.row(9));
  for (Eigen::Index k = 0; k < 6; k += 3) {
    const hawor::Vec3<S> a = seq.row(6).segment(k, 3).transpose();
    const hawor::Vec3<S> b = seq.row(9).segment(k, 3).transpose();
    const hawor::Vec3<S> r7 = out.row(7).segment(k, 3).transpose();
    const hawor::Vec3<S> e7 = hawor::slerpAxisAngle(a, b, S(1) / S(3));
    CHECK((r7 - e7).norm() < seqTol<S>() * 10);
    // equal angular steps 6 → 7 → 8 → 9
    const auto q = [&](Eigen::Index t) {
      const hawor::Vec3<S> v = out.row(t).segment(k, 3).transpose();
      return hawor::axisAngleToQuaternion(v);
    };
    const S d67 = q(6).angularDistance(q(7));
    const S d78 = q(7).angularDistance(q(8));
    const S d89 = q(8).angularDistance(q(9));
    CHECK(std::abs(d67 - d78) < S(100) * seqTol<S>());
    CHECK(std::abs(d78 - d89) < S(100) * seqTol<S>());
  }
  const hawor::Sequence<S> bad = hawor::Sequence<S>::Zero(12, 4);
  CHECK_THROWS_AS(hawor::fillRotations(bad, valid), hawor::Error);
}

TEMPLATE_TEST_CASE("fillLastPose holds the last valid frame", "[motion][sequence]", float, double) {
  using S = TestType;
  const auto valid = testMask();
  std::srand(9);
  const hawor::Sequence<S> seq = withNaNGaps<S>(hawor::Sequence<S>::Random(12, 3), valid);
  const hawor::Sequence<S> out = hawor::fillLastPose(seq, valid);
  for (Eigen::Index t = 0; t < 12; ++t)
    if (valid[size_t(t)]) CHECK(rowBitwiseEqual(out, seq, t));
  for (Eigen::Index t : {0, 1, 2}) CHECK(out.row(t) == seq.row(3));
  CHECK(out.row(5) == seq.row(4));
  CHECK(out.row(7) == seq.row(6));
  CHECK(out.row(8) == seq.row(6));
  CHECK(out.row(10) == seq.row(9));
  CHECK(out.row(11) == seq.row(9));
}

TEMPLATE_TEST_CASE("fills: no valid frame throws, one valid frame is held everywhere",
                   "[motion][sequence]", float, double) {
  using S = TestType;
  const hawor::Sequence<S> seq = hawor::Sequence<S>::Random(5, 3);
  const hawor::ValidMask none(5, 0);
  CHECK_THROWS_AS(hawor::fillLinear(seq, none), hawor::Error);
  CHECK_THROWS_AS(hawor::fillRotations(seq, none), hawor::Error);
  CHECK_THROWS_AS(hawor::fillLastPose(seq, none), hawor::Error);
  CHECK_THROWS_WITH(hawor::fillLinear(seq, none), Catch::Contains("no valid frame"));
  CHECK_THROWS_AS(hawor::fillLinear(seq, hawor::ValidMask(4, 1)), hawor::Error);
  const hawor::ValidMask one = {0, 0, 1, 0, 0};
  for (const auto& out :
       {hawor::fillLinear(seq, one), hawor::fillRotations(seq, one), hawor::fillLastPose(seq, one)})
    for (Eigen::Index t = 0; t < 5; ++t) CHECK(out.row(t) == seq.row(2));
  // empty sequence with an empty mask: nothing to fill, but no valid frame either
  CHECK_THROWS_AS(hawor::fillLinear(hawor::Sequence<S>(0, 3), hawor::ValidMask{}), hawor::Error);
}
