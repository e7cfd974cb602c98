// hawor/pipeline/sides.hpp — which detection is the left hand and which the right, frame by frame.
//
// The landmark network labels each hand it sees, but one frame's label flips now and then with
// full confidence (a hand entering at the bottom edge, a fist). The side of a detection is the
// assignment of least cost over at most two detections, where a detection's cost on a side is
//   −log P(side), P from the detection's track (the tracker's handedness evidence summed over the
//     frames of the track) or its label, clamped to [0.05, 0.95] (one label can be outvoted),
//   − CONTINUITY when it continues the track that side last held, else
//   − CONTINUITY·(1 − d / reach) / age when it lies within `reach` px of that side's last wrist,
//     seen `age` frames ago (a hand lost for a few frames mostly comes back where it was),
// plus, for two hands, CROSSED when the left slot's wrist lies right of the right slot's (hands
// rarely cross in an egocentric view: CROSSED exceeds both tracks' continuity, so two hands in
// view are ordered left to right unless both hands' evidence holds the crossing).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/pnp.hpp"

namespace hawor {

/// One hand the perception found in a frame: 21 image keypoints (pixels of the video, through its
/// lens), optional metric 3D keypoints (camera-aligned, any origin), and its handedness evidence.
template <typename Scalar>
struct HandDetection {
  Pixels<Scalar> keypoints2d;        ///< (21, 2)
  Points3<Scalar> keypoints3d;       ///< (21, 3) metres, or empty
  Scalar pRight = Scalar(0.5);       ///< P(right hand): the track's evidence, else the label's
  int track = -1;                    ///< the tracker's id of this hand over frames (-1: none)
  bool flow = false;                 ///< carried from the last frame (Pipeline::predict), not the network's
};

/// What assignSides remembers between frames: each side's last wrist, how many frames ago it was
/// seen (0: never), and the track that held it (-1: none).
template <typename Scalar>
struct SideState {
  std::array<Vec2<Scalar>, 2> wrist{Vec2<Scalar>::Zero(), Vec2<Scalar>::Zero()};
  std::array<int, 2> age{0, 0};
  std::array<int, 2> track{-1, -1};
};

/// Side indices of the pipeline's per-side arrays: 0 left, 1 right.
constexpr int kLeftSide = 0, kRightSide = 1;

inline const char* sideName(int side) { return side == kLeftSide ? "left" : "right"; }

/// The detection in each slot (index into dets, -1: none) for this frame. reach: pixels.
template <typename Scalar>
std::array<int, 2> assignSides(const std::vector<HandDetection<Scalar>>& dets, const SideState<Scalar>& prev, Scalar reach) {
  const Scalar continuity(3.5);
  const Scalar crossedCost = Scalar(2) * continuity + Scalar(2);
  auto cost = [&](const HandDetection<Scalar>& d, int side) {
    const Scalar p = std::min(std::max(side == kRightSide ? d.pRight : Scalar(1) - d.pRight, Scalar(0.05)), Scalar(0.95));
    Scalar c = -std::log(p);
    if (d.track >= 0 && prev.track[side] == d.track) {
      c -= continuity;
    } else if (prev.age[side] > 0) {
      const Scalar dist = std::hypot(d.keypoints2d(0, 0) - prev.wrist[side](0), d.keypoints2d(0, 1) - prev.wrist[side](1));
      if (dist < reach) c -= continuity * (Scalar(1) - dist / reach) / Scalar(std::max(1, prev.age[side]));
    }
    return c;
  };
  if (dets.empty()) return {-1, -1};
  if (dets.size() == 1) return cost(dets[0], kLeftSide) < cost(dets[0], kRightSide) ? std::array<int, 2>{0, -1} : std::array<int, 2>{-1, 0};
  // the best two (the tracker returns at most two)
  const HandDetection<Scalar>& a = dets[0];
  const HandDetection<Scalar>& b = dets[1];
  auto crossed = [&](const HandDetection<Scalar>& l, const HandDetection<Scalar>& r) {
    return l.keypoints2d(0, 0) > r.keypoints2d(0, 0) ? crossedCost : Scalar(0);
  };
  const Scalar ab = cost(a, kLeftSide) + cost(b, kRightSide) + crossed(a, b);
  const Scalar ba = cost(b, kLeftSide) + cost(a, kRightSide) + crossed(b, a);
  return ab <= ba ? std::array<int, 2>{0, 1} : std::array<int, 2>{1, 0};
}

/// After a frame's assignment: each filled side's wrist, age 1 and track (a track holds one side
/// at a time); an empty side keeps its last wrist and track, one frame older.
template <typename Scalar>
void updateSideState(SideState<Scalar>& s, const std::vector<HandDetection<Scalar>>& dets, const std::array<int, 2>& sides) {
  for (int side = 0; side < 2; ++side) {
    if (sides[side] < 0) {
      if (s.age[side] > 0) s.age[side] += 1;
      continue;
    }
    const HandDetection<Scalar>& d = dets[static_cast<std::size_t>(sides[side])];
    s.wrist[side] = Vec2<Scalar>(d.keypoints2d(0, 0), d.keypoints2d(0, 1));
    s.age[side] = 1;
    s.track[side] = d.track;
    if (d.track >= 0 && s.track[1 - side] == d.track) s.track[1 - side] = -1;
  }
}

}  // namespace hawor
