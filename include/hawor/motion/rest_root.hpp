// hawor/motion/rest_root.hpp — J0, the rest position of joint 0 of the shaped hand, that the
// camera → world → canonical rules (canonical.hpp, docs/design.md §3) need: MANO rotates about joint 0.
// Per frame from that frame's betas; missing frames (any content, NaN included) take the betas
// linearly interpolated between observed ones (sequence.hpp), so J0 is finite everywhere.
// Thread-safety: pure functions.
#pragma once

#include <string>

#include "hawor/common.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/motion/hand_motion.hpp"
#include "hawor/motion/sequence.hpp"

namespace hawor {

/// J0(β_t) for every row of `betas` (T × B', B' ≤ the model's B; finite). Throws otherwise.
template <typename Scalar>
Points3<Scalar> restRootJoints(const HandModel<Scalar>& model, const Sequence<Scalar>& betas) {
  if (betas.cols() > model.numBetas()) {
    throw Error("rest joint 0: " + std::to_string(betas.cols()) + " betas, the model has " +
                std::to_string(model.numBetas()));
  }
  Points3<Scalar> J0(betas.rows(), 3);
  HandWorkspace<Scalar> ws;
  for (Eigen::Index t = 0; t < betas.rows(); ++t) {
    const VecX<Scalar> b = betas.row(t).transpose();
    shapeHand(model, b, ws);
    J0.row(t) = ws.jRest.row(0);
  }
  return J0;
}

/// J0 per frame of a hand motion (file comment). A motion without observed frames has no shape
/// to take: the model's mean shape (one row).
template <typename Scalar>
Points3<Scalar> restRootJoints(const HandModel<Scalar>& model, const HandMotion<Scalar>& m) {
  if (countValid(m.valid) == 0) return restRootJoints(model, Sequence<Scalar>(Sequence<Scalar>::Zero(1, 0)));
  return restRootJoints(model, fillLinear(m.betas, m.valid));
}

}  // namespace hawor
