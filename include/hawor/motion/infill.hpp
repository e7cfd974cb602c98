// hawor/motion/infill.hpp — motion infilling of one hand: world → canonical (docs/design.md §7) → fill
// → world, only the missing frames replaced; the data-free methods, and the spline as a window
// infiller for the windowed pipeline (infill_window.hpp).
//
// Methods (all data-free):
//   LastPose  a gap repeats the last observed frame (the paper's "last pose" baseline)
//   Lerp      LERP of translation and betas, SLERP of every rotation (the paper's LERP baseline,
//             and the pre-fill of docs/design.md §7)
//   Spline    the cubic Hermite / SO(3) spline with boundary velocities (spline_infill.hpp)
// The data-free methods run on the whole sequence at once (they need no window; a gap that
// crosses a 120-frame window boundary keeps its context on both sides): the canonical frame is
// the hand's first valid frame. The three rules commute with a fixed rigid motion, so the
// canonical round trip changes their output only by rounding; it is kept so that every method
// sees the same space as the learned infiller (which runs through infillWindowed).
// Sequences: no valid frame → returned unchanged, nothing filled (the caller reports it); one
// valid frame → every frame holds it; all frames valid → unchanged.
// Thread-safety: pure functions.
#pragma once

#include <array>
#include <string>

#include "hawor/common.hpp"
#include "hawor/motion/canonical.hpp"
#include "hawor/motion/hand_motion.hpp"
#include "hawor/motion/infill_window.hpp"
#include "hawor/motion/motion_noise.hpp"
#include "hawor/motion/prefill.hpp"
#include "hawor/motion/spline_infill.hpp"

namespace hawor {

/// The data-free infilling methods (file comment).
enum class InfillMethod { LastPose, Lerp, Spline };

/// "last", "lerp" or "spline" → InfillMethod; throws hawor::Error naming the accepted names.
inline InfillMethod parseInfillMethod(const std::string& name) {
  if (name == "last") return InfillMethod::LastPose;
  if (name == "lerp") return InfillMethod::Lerp;
  if (name == "spline") return InfillMethod::Spline;
  throw Error("unknown infill method '" + name + "' (last, lerp or spline)");
}

inline const char* infillMethodName(InfillMethod m) {
  switch (m) {
    case InfillMethod::LastPose: return "last";
    case InfillMethod::Lerp: return "lerp";
    case InfillMethod::Spline: return "spline";
  }
  return "?";
}

template <typename Scalar>
struct InfillOptions {
  InfillMethod method = InfillMethod::Spline;
  SplineInfillOptions<Scalar> spline;
};

/// An infilled hand: the motion (observed frames bit for bit as given) and the frames filled.
template <typename Scalar>
struct InfillResult {
  HandMotion<Scalar> motion;
  ValidMask filled;  ///< nonzero = the frame was missing and now holds a fill
};

/// Fills the missing frames of one world-space hand (J0: rest joint 0, one row or one per frame;
/// canonical.hpp) with the chosen method in the hand's canonical space. `noise` (optional, spline
/// only): the channels' noise levels to use instead of estimating them from `world` — pass
/// estimateHandNoise(raw) when `world` is the smoothed (smoothObserved) raw motion. Throws
/// hawor::Error for a malformed motion (HandMotion::validate) or bad options.
template <typename Scalar>
InfillResult<Scalar> infillHand(const HandMotion<Scalar>& world, const Points3<Scalar>& J0,
                                const InfillOptions<Scalar>& o = {},
                                const HandNoise<Scalar>* noise = nullptr) {
  world.validate();
  o.spline.validate();
  const Eigen::Index T = world.frames();
  InfillResult<Scalar> r;
  r.motion = world;
  r.filled.assign(static_cast<size_t>(T), 0);
  const Eigen::Index nvalid = countValid(world.valid);
  if (nvalid == 0 || nvalid == T) return r;
  // Missing frames may hold anything (NaN): give them the held values before the rigid
  // transform; every method reads valid frames only.
  const HandMotion<Scalar> clean = fillLastPose(world);
  CanonicalFrame<Scalar> frame;
  const HandMotion<Scalar> can = worldToCanonical(clean, J0, &frame);
  HandMotion<Scalar> fill;
  switch (o.method) {
    case InfillMethod::LastPose: fill = fillLastPose(can); break;
    case InfillMethod::Lerp: fill = fillInterpolate(can); break;
    case InfillMethod::Spline: fill = fillSpline(can, o.spline, noise); break;
  }
  const HandMotion<Scalar> back = canonicalToWorld(fill, frame, J0);
  for (Eigen::Index t = 0; t < T; ++t) {
    if (world.valid[static_cast<size_t>(t)]) continue;
    r.motion.rot.row(t) = back.rot.row(t);
    r.motion.trans.row(t) = back.trans.row(t);
    r.motion.handPose.row(t) = back.handPose.row(t);
    r.motion.betas.row(t) = back.betas.row(t);
    r.filled[static_cast<size_t>(t)] = 1;
  }
  return r;
}

/// The spline as a window infiller (infill_window.hpp): each hand of the window is unpacked
/// (rot6d → axis-angle), filled by fillSpline from the window's own valid frames, and packed
/// again. A hand without valid frames in the window keeps its input features. Useful to run the
/// data-free filler through the windowed pipeline (and to test that pipeline).
template <typename Scalar>
class SplineWindowInfiller : public WindowInfiller<Scalar> {
 public:
  explicit SplineWindowInfiller(const SplineInfillOptions<Scalar>& o = {}) : options_(o) { o.validate(); }

  Sequence<Scalar> infillWindow(const InfillWindow<Scalar>& w) const override {
    const HandFeatureLayout& l = w.layout;
    const Eigen::Index W = w.features.rows();
    Sequence<Scalar> y = w.features;
    for (int h = 0; h < 2; ++h) {
      if (countValid(w.valid[h]) == 0) continue;
      HandMotion<Scalar> m;
      m.rot.resize(W, 3);
      m.trans.resize(W, 3);
      m.handPose.resize(W, 3 * l.joints);
      m.betas.resize(W, l.betas);
      m.valid = w.valid[h];
      for (Eigen::Index r = 0; r < W; ++r) unpackHandFeatures(w.features, r, h * l.size(), l, m, r);
      const HandMotion<Scalar> f = fillSpline(m, options_);
      for (Eigen::Index r = 0; r < W; ++r) packHandFeatures(f, r, l, y, r, h * l.size());
    }
    return y;
  }

 private:
  SplineInfillOptions<Scalar> options_;
};

}  // namespace hawor
