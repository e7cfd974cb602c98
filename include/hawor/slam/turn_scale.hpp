// hawor/slam/turn_scale.hpp — the scale of a monocular trajectory from head turns, to carry the
// scale across a map re-initialisation (mono_slam.hpp, finish()).
//
// A standing person turns the head about the neck, and the eye sits a few centimetres off that
// axis, so a turn by θ moves the eye along a chord of the circle it rides on: |c_{t+L} − c_t| =
// 2·r·sin(θ/2), r the eye's distance from the axis (≈ 8–10 cm for an adult, the same before and
// after a tracking loss). Per window (t, t + L) with a turn θ_t = ∠(R_tᵀ·R_{t+L}) ≥ minAngle,
// r_t = |c_{t+L} − c_t| / (2·sin(θ_t/2)); the segment's r is the median of r_t, in its map units.
// Two segments of one standing turn sequence then differ in r only by their scales, and
// r_before / r_after is the factor that puts the second into the first one's units.
// When the head also translates for other reasons (walking), r_t scatters: the relative spread
// 1.4826·MAD(r_t) / median(r_t) says whether the model holds (the caller's gate).
// Thread-safety: pure function.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"

namespace hawor {

template <typename Scalar>
struct TurnRadius {
  Scalar radius = std::numeric_limits<Scalar>::quiet_NaN();  ///< median r_t (map units)
  Scalar spread = std::numeric_limits<Scalar>::quiet_NaN();  ///< 1.4826·MAD / median
  int windows = 0;                                           ///< windows with a turn ≥ minAngle
  bool ok() const { return windows > 0 && std::isfinite(double(radius)) && radius > Scalar(0); }
};

/// The turn radius (file comment) over frames [begin, end) of camera-to-world poses, using the
/// windows (t, t + lag) whose two frames are both `usable` (may be empty: all usable).
template <typename Scalar>
TurnRadius<Scalar> turnRadius(const std::vector<SE3<Scalar>>& T_w_c, const std::vector<char>& usable, int begin,
                              int end, int lag = 3, Scalar minAngle = Scalar(0.05)) {
  if (lag < 1 || !(minAngle > Scalar(0))) throw Error("turnRadius: lag must be >= 1 and minAngle > 0");
  if (!usable.empty() && usable.size() != T_w_c.size()) throw Error("turnRadius: usable flags and poses differ in length");
  begin = std::max(begin, 0);
  end = std::min(end, static_cast<int>(T_w_c.size()));
  std::vector<Scalar> r;
  for (int t = begin; t + lag < end; ++t) {
    const std::size_t a = static_cast<std::size_t>(t), b = static_cast<std::size_t>(t + lag);
    if (!usable.empty() && (!usable[a] || !usable[b])) continue;
    const Scalar theta = (T_w_c[a].rotation().inverse() * T_w_c[b].rotation()).log().norm();
    if (!(theta >= minAngle) || !std::isfinite(double(theta))) continue;
    const Scalar chord = (T_w_c[b].translation() - T_w_c[a].translation()).norm();
    if (std::isfinite(double(chord))) r.push_back(chord / (Scalar(2) * std::sin(theta / Scalar(2))));
  }
  TurnRadius<Scalar> out;
  out.windows = static_cast<int>(r.size());
  if (r.empty()) return out;
  out.radius = median(r);
  out.spread = out.radius > Scalar(0) ? madSigma(r, out.radius) / out.radius : std::numeric_limits<Scalar>::infinity();
  return out;
}

}  // namespace hawor
