// hawor/motion/prefill.hpp — pre-fill of a hand's missing frames (docs/design.md §7, paper's baselines).
//
// Two fills of a HandMotion, both leaving valid frames bit for bit unchanged and the validity mask
// as it was (it keeps recording which frames were observed):
//   fillInterpolate  LERP of trans and betas, SLERP of rot and of each of the 15 joint rotations
//                    (the paper's "LERP" baseline and the infiller's input pre-fill)
//   fillLastPose     every missing frame repeats the last observed frame ("last pose" baseline)
// Before the first / after the last valid frame both hold the nearest valid frame.
#pragma once

#include "hawor/motion/hand_motion.hpp"
#include "hawor/motion/sequence.hpp"

namespace hawor {

/// LERP/SLERP pre-fill of every missing frame. Throws if no frame is valid.
template <typename Scalar>
HandMotion<Scalar> fillInterpolate(const HandMotion<Scalar>& m) {
  m.validate();
  HandMotion<Scalar> out;
  out.rot = fillRotations(m.rot, m.valid);
  out.trans = fillLinear(m.trans, m.valid);
  out.handPose = fillRotations(m.handPose, m.valid);
  out.betas = fillLinear(m.betas, m.valid);
  out.valid = m.valid;
  return out;
}

/// "Last pose" fill of every missing frame. Throws if no frame is valid.
template <typename Scalar>
HandMotion<Scalar> fillLastPose(const HandMotion<Scalar>& m) {
  m.validate();
  HandMotion<Scalar> out;
  out.rot = fillLastPose(m.rot, m.valid);
  out.trans = fillLastPose(m.trans, m.valid);
  out.handPose = fillLastPose(m.handPose, m.valid);
  out.betas = fillLastPose(m.betas, m.valid);
  out.valid = m.valid;
  return out;
}

}  // namespace hawor
