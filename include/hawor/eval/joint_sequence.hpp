// hawor/eval/joint_sequence.hpp — joint tracks as the metrics take them.
//
// A joint sequence is a T×3J row-major matrix: frame t's row is (x0, y0, z0, x1, ...), the exact
// memory of a numpy (T, J, 3) C-order array (J = 21 hand keypoints, docs/design.md §3). Consecutive
// frames are contiguous, so a block of frames is viewed as an (n·J)×3 point set without copying.
// Units: metres.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/motion/sequence.hpp"

namespace hawor {

/// T×3J joints per frame (numpy (T, J, 3) layout).
template <typename Scalar>
using JointSequence = Sequence<Scalar>;

/// Packs per-frame J×3 point sets into a T×3J joint sequence. Throws if frames differ in J.
template <typename Scalar>
JointSequence<Scalar> toJointSequence(const std::vector<Points3<Scalar>>& frames) {
  const Eigen::Index T = static_cast<Eigen::Index>(frames.size());
  const Eigen::Index J = T ? frames[0].rows() : 0;
  JointSequence<Scalar> out(T, 3 * J);
  for (Eigen::Index t = 0; t < T; ++t) {
    const Points3<Scalar>& f = frames[static_cast<size_t>(t)];
    if (f.rows() != J)
      throw Error("toJointSequence: frame " + std::to_string(t) + " has " +
                  std::to_string(f.rows()) + " joints, frame 0 has " + std::to_string(J));
    out.row(t) = Eigen::Map<const Eigen::Matrix<Scalar, 1, Eigen::Dynamic>>(f.data(), 3 * J);
  }
  return out;
}

/// Number of joints J of a T×3J sequence; throws if the column count is not a multiple of 3.
template <typename Scalar>
Eigen::Index jointCount(const JointSequence<Scalar>& seq) {
  if (seq.cols() % 3 != 0)
    throw Error("joint sequence has " + std::to_string(seq.cols()) +
                " columns, not a multiple of 3 (expected T x 3J)");
  return seq.cols() / 3;
}

/// Frames [begin, end) of a joint sequence as one ((end−begin)·J)×3 point set (a view).
template <typename Scalar>
Eigen::Map<const Points3<Scalar>> framePoints(const JointSequence<Scalar>& seq, Eigen::Index begin,
                                              Eigen::Index end) {
  const Eigen::Index J = jointCount(seq);
  return Eigen::Map<const Points3<Scalar>>(seq.data() + begin * seq.cols(), (end - begin) * J, 3);
}

/// Frame t of a joint sequence as a J×3 point set (a copy).
template <typename Scalar>
Points3<Scalar> frameJoints(const JointSequence<Scalar>& seq, Eigen::Index t) {
  return framePoints(seq, t, t + 1);
}

/// The frames whose mask entry is nonzero, in order (a T'×3J copy).
template <typename Scalar>
JointSequence<Scalar> selectFrames(const JointSequence<Scalar>& seq, const ValidMask& valid) {
  checkMask(valid, seq.rows(), "selectFrames");
  JointSequence<Scalar> out(countValid(valid), seq.cols());
  Eigen::Index k = 0;
  for (Eigen::Index t = 0; t < seq.rows(); ++t)
    if (valid[static_cast<size_t>(t)]) out.row(k++) = seq.row(t);
  return out;
}

}  // namespace hawor
