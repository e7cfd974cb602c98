// hawor/scale/hand_track.hpp — the input and the result of the hand-anchored metric scale
// (hand_scale.hpp): a hand's camera-frame metric positions per frame, and what a scale cue found.
#pragma once

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"

namespace hawor {

/// One hand's camera-frame metric positions h_t (T) with validity (e.g. the fitted wrist).
template <typename Scalar>
struct HandTrack {
  std::vector<Vec3<Scalar>> positionCam;
  std::vector<char> valid;
};

template <typename Scalar>
struct HandScaleResult {
  Scalar scale = std::numeric_limits<Scalar>::quiet_NaN();
  Scalar relativeStdError = std::numeric_limits<Scalar>::quiet_NaN();
  Scalar confidence = Scalar(0);
  std::string method;    ///< "holds" or "smoothness": the cue that gave the scale
  int residuals = 0;     ///< smoothness: second-difference residuals; holds: windows examined
  int restFrames = 0;    ///< smoothness: velocity residuals of resting hands; holds: windows held
  int carriedWindows = 0;  ///< holds: windows left out, the hand still in the camera frame
  /// holds: the estimated noise of the hand positions along and across the viewing ray (metres)
  Scalar noiseAlongRay = std::numeric_limits<Scalar>::quiet_NaN();
  Scalar noiseAcrossRay = std::numeric_limits<Scalar>::quiet_NaN();
  bool ok() const { return std::isfinite(double(scale)) && scale > Scalar(0); }
};

/// Centred moving average of the positions (half-width k, symmetric: no lag) within each run of
/// valid frames.
template <typename Scalar>
void smoothHandTrack(HandTrack<Scalar>& h, int k) {
  const std::vector<Vec3<Scalar>> src = h.positionCam;
  const int T = static_cast<int>(src.size());
  for (int t = 0; t < T; ++t) {
    if (!h.valid[static_cast<std::size_t>(t)]) continue;
    int lo = t, hi = t;
    while (lo > t - k && lo > 0 && h.valid[static_cast<std::size_t>(lo - 1)]) --lo;
    while (hi < t + k && hi < T - 1 && h.valid[static_cast<std::size_t>(hi + 1)]) ++hi;
    const int w = std::min(t - lo, hi - t);
    Vec3<Scalar> sum = Vec3<Scalar>::Zero();
    for (int u = t - w; u <= t + w; ++u) sum += src[static_cast<std::size_t>(u)];
    h.positionCam[static_cast<std::size_t>(t)] = sum / Scalar(2 * w + 1);
  }
}

namespace scale_detail {

/// Throws unless every track has one position and one flag per camera pose.
template <typename Scalar>
void checkTracks(const char* who, const std::vector<SE3<Scalar>>& T_w_c, const std::vector<HandTrack<Scalar>>& hands) {
  for (std::size_t h = 0; h < hands.size(); ++h) {
    if (hands[h].positionCam.size() != T_w_c.size() || hands[h].valid.size() != T_w_c.size()) {
      throw Error(std::string(who) + ": hand " + std::to_string(h) + " has " + std::to_string(hands[h].positionCam.size()) +
                  " positions and " + std::to_string(hands[h].valid.size()) + " flags for " + std::to_string(T_w_c.size()) +
                  " camera poses");
    }
  }
}

/// Frame t of a track is usable: valid, finite position, finite camera pose.
template <typename Scalar>
bool usableFrame(const std::vector<SE3<Scalar>>& T_w_c, const HandTrack<Scalar>& h, std::size_t t) {
  return h.valid[t] && h.positionCam[t].allFinite() && T_w_c[t].translation().allFinite() &&
         T_w_c[t].rotation().matrix().allFinite();
}

}  // namespace scale_detail
}  // namespace hawor
