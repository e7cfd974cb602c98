// hawor/motion/sequence.hpp — per-frame sequences with a validity mask, and gap filling.
//
// A sequence is a T×D row-major matrix, one frame per row: the memory layout of a numpy (T, D)
// C-order array. A validity mask is a std::vector<uint8_t> of length T, nonzero = the frame was
// observed (valid), zero = missing. Gap filling never modifies a valid frame: its row is copied
// bit for bit; only missing rows are written.
//
// Fill rules (docs/design.md §7 pre-fill, and the paper's "last pose" baseline):
//   fillLinear     interior gap between valid frames a < b: x_t = x_a + (t−a)/(b−a)·(x_b − x_a)
//   fillRotations  the same fraction, SLERP per axis-angle triple (short path)
//   fillLastPose   a gap holds the last valid frame before it
// Before the first valid frame every rule holds the first valid frame; after the last valid
// frame linear/SLERP hold the last valid frame (fillLastPose does so by definition).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/motion/slerp.hpp"

namespace hawor {

/// T×D frames-by-rows sequence (numpy (T, D) layout).
template <typename Scalar>
using Sequence = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Per-frame validity, nonzero = observed.
using ValidMask = std::vector<std::uint8_t>;

/// A maximal run [start, end) of missing frames. `before` is the last valid frame before it and
/// `after` the first valid frame after it; -1 when the gap touches the start / end of the sequence.
struct GapSegment {
  Eigen::Index start = 0;
  Eigen::Index end = 0;
  Eigen::Index before = -1;
  Eigen::Index after = -1;
  Eigen::Index length() const { return end - start; }
  bool interior() const { return before >= 0 && after >= 0; }
};

/// Number of valid frames.
inline Eigen::Index countValid(const ValidMask& valid) {
  Eigen::Index n = 0;
  for (std::uint8_t v : valid) n += v ? 1 : 0;
  return n;
}

/// Throws unless `valid` has `frames` entries. `what` names the caller in the message.
inline void checkMask(const ValidMask& valid, Eigen::Index frames, const char* what) {
  if (static_cast<Eigen::Index>(valid.size()) != frames)
    throw Error(std::string(what) + ": validity mask has " + std::to_string(valid.size()) +
                " entries for " + std::to_string(frames) + " frames");
}

/// Maximal runs of missing frames, in order (used by the pre-fill and by the infiller).
inline std::vector<GapSegment> findGaps(const ValidMask& valid) {
  std::vector<GapSegment> gaps;
  const Eigen::Index n = static_cast<Eigen::Index>(valid.size());
  Eigen::Index last_valid = -1;
  Eigen::Index t = 0;
  while (t < n) {
    if (valid[static_cast<size_t>(t)]) {
      last_valid = t++;
      continue;
    }
    GapSegment g;
    g.start = t;
    while (t < n && !valid[static_cast<size_t>(t)]) ++t;
    g.end = t;
    g.before = last_valid;
    g.after = t < n ? t : -1;
    gaps.push_back(g);
  }
  return gaps;
}

namespace detail {

/// Shared driver: copies `seq`, then for every missing frame either holds a valid row (ends, or
/// `hold_last`) or calls interp(out, row, a, b, fraction) for interior gaps.
template <typename Scalar, typename Interp>
Sequence<Scalar> fillGaps(const Sequence<Scalar>& seq, const ValidMask& valid, bool hold_last,
                          const char* what, Interp interp) {
  checkMask(valid, seq.rows(), what);
  if (countValid(valid) == 0)
    throw Error(std::string(what) + ": no valid frame to fill from (all " +
                std::to_string(seq.rows()) + " frames missing)");
  Sequence<Scalar> out = seq;
  for (const GapSegment& g : findGaps(valid)) {
    for (Eigen::Index t = g.start; t < g.end; ++t) {
      if (g.before < 0) {
        out.row(t) = seq.row(g.after);
      } else if (g.after < 0 || hold_last) {
        out.row(t) = seq.row(g.before);
      } else {
        const Scalar f = Scalar(t - g.before) / Scalar(g.after - g.before);
        interp(out, t, g.before, g.after, f);
      }
    }
  }
  return out;
}

}  // namespace detail

/// Fills missing frames by per-column linear interpolation between the surrounding valid frames;
/// leading/trailing gaps hold the nearest valid frame. Throws if no frame is valid.
template <typename Scalar>
Sequence<Scalar> fillLinear(const Sequence<Scalar>& seq, const ValidMask& valid) {
  return detail::fillGaps(
      seq, valid, false, "fillLinear",
      [&seq](Sequence<Scalar>& out, Eigen::Index t, Eigen::Index a, Eigen::Index b, Scalar f) {
        out.row(t) = seq.row(a) + f * (seq.row(b) - seq.row(a));
      });
}

/// Fills missing frames of a T×3K sequence of K axis-angle rotations by SLERP (per triple,
/// shortest path) between the surrounding valid frames; ends hold the nearest valid frame.
/// Throws if the column count is not a multiple of 3 or no frame is valid.
template <typename Scalar>
Sequence<Scalar> fillRotations(const Sequence<Scalar>& seq, const ValidMask& valid) {
  if (seq.cols() % 3 != 0)
    throw Error("fillRotations: " + std::to_string(seq.cols()) +
                " columns is not a multiple of 3 (axis-angle triples)");
  return detail::fillGaps(
      seq, valid, false, "fillRotations",
      [&seq](Sequence<Scalar>& out, Eigen::Index t, Eigen::Index a, Eigen::Index b, Scalar f) {
        for (Eigen::Index k = 0; k < seq.cols(); k += 3) {
          const Vec3<Scalar> r0 = seq.row(a).template segment<3>(k).transpose();
          const Vec3<Scalar> r1 = seq.row(b).template segment<3>(k).transpose();
          out.row(t).template segment<3>(k) = slerpAxisAngle(r0, r1, f).transpose();
        }
      });
}

/// "Last pose" baseline: a gap holds the last valid frame before it; a leading gap holds the first
/// valid frame. Throws if no frame is valid.
template <typename Scalar>
Sequence<Scalar> fillLastPose(const Sequence<Scalar>& seq, const ValidMask& valid) {
  return detail::fillGaps(
      seq, valid, true, "fillLastPose",
      [](Sequence<Scalar>&, Eigen::Index, Eigen::Index, Eigen::Index, Scalar) {});
}

}  // namespace hawor
