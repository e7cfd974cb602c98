// hawor/motion/infill_window.hpp — the windowed two-hand infilling pipeline of the original
// method (docs/design.md §7) and the interface a window infiller (the transformer) plugs into.
//
// For a sequence of T frames with both hands in world space (each with its validity):
//   1. split into windows of W = 120 frames: [0, W), [W, 2W), …; the last, shorter window is
//      padded to W frames by repeating its last frame (features and validity; official);
//   2. per window and hand: the canonical frame (canonical.hpp) of the hand's first valid frame
//      in the window; world → canonical; pre-fill of the window's missing frames (LERP for trans
//      and betas, SLERP for rotations, the window's ends holding its nearest valid frame:
//      prefill.hpp), in canonical space;
//   3. features per frame: [left hand | right hand], per hand
//        [trans (3) | betas (B) | rot6d of the global orientation (6) | rot6d of each joint (6K)]
//      (MANO: 3 + 10 + 6 + 90 = 109, two hands 218; the official order, rot6d of docs/design.md §2);
//   4. the infiller maps the window's features and validity to features of the same shape;
//   5. per hand, only the window's frames that were missing for that hand (padding excluded)
//      take the output: rot6d → rotation (Gram–Schmidt), canonical → world.
// A hand without any valid frame in a window (but valid elsewhere) enters it with the whole
// sequence's pre-fill (held / interpolated from outside the window), all frames marked missing,
// canonical frame = the window's first frame. A hand without any valid frame in the whole
// sequence is left unchanged (its features are the identity pose, all missing).
// Observed frames are never changed. Both hands must have the same frame count, joint count and
// number of betas.
// Thread-safety: the pipeline is a pure function; the infiller is only called through const.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/motion/canonical.hpp"
#include "hawor/motion/hand_motion.hpp"
#include "hawor/motion/prefill.hpp"
#include "hawor/motion/sequence.hpp"

namespace hawor {

/// Window length of the original infiller (frames).
constexpr Eigen::Index kInfillWindow = 120;

/// Column layout of one hand's per-frame features (step 3 of the file comment).
struct HandFeatureLayout {
  Eigen::Index betas = 10;   ///< B
  Eigen::Index joints = 15;  ///< K joint rotations (handPose has 3K columns)

  Eigen::Index size() const { return 3 + betas + 6 + 6 * joints; }
  Eigen::Index transOffset() const { return 0; }
  Eigen::Index betasOffset() const { return 3; }
  Eigen::Index rootOffset() const { return 3 + betas; }
  Eigen::Index jointOffset(Eigen::Index j) const { return 3 + betas + 6 + 6 * j; }

  /// The layout of a hand motion's sizes.
  template <typename Scalar>
  static HandFeatureLayout of(const HandMotion<Scalar>& m) {
    HandFeatureLayout l;
    l.betas = m.betas.cols();
    l.joints = m.handPose.cols() / 3;
    return l;
  }
};

/// One window as the infiller sees it.
template <typename Scalar>
struct InfillWindow {
  Sequence<Scalar> features;       ///< W × 2F: left hand's F columns, then the right hand's
  std::array<ValidMask, 2> valid;  ///< per hand (0 left, 1 right), W flags (padding repeats)
  HandFeatureLayout layout;        ///< F = layout.size()
  Eigen::Index start = 0;          ///< sequence index of the window's first frame
  Eigen::Index frames = 0;         ///< real frames (≤ W); the rest is padding
};

/// The interface of a window infiller: features of a canonical, pre-filled window in, features
/// of the same shape out (only the rows of missing frames are used, per hand). Implementations:
/// the spline adapter (infill.hpp) and the transformer.
template <typename Scalar>
class WindowInfiller {
 public:
  virtual ~WindowInfiller() = default;
  virtual Sequence<Scalar> infillWindow(const InfillWindow<Scalar>& window) const = 0;
};

/// Writes frame t of a hand (axis-angle rotations) into row `row` of `f` at column `col0`.
template <typename Scalar>
void packHandFeatures(const HandMotion<Scalar>& m, Eigen::Index t, const HandFeatureLayout& l,
                      Sequence<Scalar>& f, Eigen::Index row, Eigen::Index col0) {
  f.row(row).template segment<3>(col0 + l.transOffset()) = m.trans.row(t).template head<3>();
  f.row(row).segment(col0 + l.betasOffset(), l.betas) = m.betas.row(t);
  const Vec3<Scalar> root = m.rot.row(t).transpose();
  f.row(row).template segment<6>(col0 + l.rootOffset()) = matrixToRot6d(axisAngleToMatrix(root)).transpose();
  for (Eigen::Index j = 0; j < l.joints; ++j) {
    const Vec3<Scalar> a = m.handPose.row(t).template segment<3>(3 * j).transpose();
    f.row(row).template segment<6>(col0 + l.jointOffset(j)) = matrixToRot6d(axisAngleToMatrix(a)).transpose();
  }
}

/// Reads row `row` of `f` at column `col0` into frame t of a hand: rot6d → rotation matrix
/// (Gram–Schmidt, so any non-degenerate 6-vector gives a rotation) → axis-angle. Throws
/// hawor::Error naming the frame for a non-finite or degenerate feature.
template <typename Scalar>
void unpackHandFeatures(const Sequence<Scalar>& f, Eigen::Index row, Eigen::Index col0,
                        const HandFeatureLayout& l, HandMotion<Scalar>& m, Eigen::Index t) {
  if (!f.row(row).segment(col0, l.size()).allFinite())
    throw Error("infill window: non-finite infiller output at window frame " + std::to_string(row));
  m.trans.row(t).template head<3>() = f.row(row).template segment<3>(col0 + l.transOffset());
  m.betas.row(t) = f.row(row).segment(col0 + l.betasOffset(), l.betas);
  const Vec6<Scalar> r = f.row(row).template segment<6>(col0 + l.rootOffset()).transpose();
  m.rot.row(t).template head<3>() = matrixToAxisAngle(rot6dToMatrix(r)).transpose();
  for (Eigen::Index j = 0; j < l.joints; ++j) {
    const Vec6<Scalar> q = f.row(row).template segment<6>(col0 + l.jointOffset(j)).transpose();
    m.handPose.row(t).template segment<3>(3 * j) = matrixToAxisAngle(rot6dToMatrix(q)).transpose();
  }
}

namespace window_detail {

/// Frames [begin, begin + n) of a hand motion (and of its J0 when per frame).
template <typename Scalar>
HandMotion<Scalar> sliceFrames(const HandMotion<Scalar>& m, Eigen::Index begin, Eigen::Index n) {
  HandMotion<Scalar> s;
  s.rot = m.rot.middleRows(begin, n);
  s.trans = m.trans.middleRows(begin, n);
  s.handPose = m.handPose.middleRows(begin, n);
  s.betas = m.betas.middleRows(begin, n);
  s.valid.assign(m.valid.begin() + begin, m.valid.begin() + begin + n);
  return s;
}

template <typename Scalar>
Points3<Scalar> sliceJ0(const Points3<Scalar>& J0, Eigen::Index T, Eigen::Index begin, Eigen::Index n) {
  if (J0.rows() == 1) return J0;
  if (J0.rows() != T)
    throw Error("infill window: rest joint 0 (J0) has " + std::to_string(J0.rows()) +
                " rows; expected 1 or " + std::to_string(T));
  return J0.middleRows(begin, n);
}

/// Identity pose (zeros; rot6d of I) features for a hand that has no valid frame at all.
template <typename Scalar>
void packIdentity(const HandFeatureLayout& l, Sequence<Scalar>& f, Eigen::Index row, Eigen::Index col0) {
  f.row(row).segment(col0, l.size()).setZero();
  const Vec6<Scalar> I = matrixToRot6d(Mat3<Scalar>::Identity());
  f.row(row).template segment<6>(col0 + l.rootOffset()) = I.transpose();
  for (Eigen::Index j = 0; j < l.joints; ++j) f.row(row).template segment<6>(col0 + l.jointOffset(j)) = I.transpose();
}

}  // namespace window_detail

/// The windowed pipeline of the file comment: hands[0] = left, hands[1] = right (world space),
/// J0[h] their rest joint 0 (one row, or one per frame; canonical.hpp). Returns both hands with
/// the missing frames filled by `infiller`; `filled` (optional) receives, per hand, the frames
/// that took the infiller's output. Throws hawor::Error for mismatched hands or bad output.
template <typename Scalar>
std::array<HandMotion<Scalar>, 2> infillWindowed(const std::array<HandMotion<Scalar>, 2>& hands,
                                                 const std::array<Points3<Scalar>, 2>& J0,
                                                 const WindowInfiller<Scalar>& infiller,
                                                 Eigen::Index window = kInfillWindow,
                                                 std::array<ValidMask, 2>* filled = nullptr) {
  for (const auto& h : hands) h.validate();
  const Eigen::Index T = hands[0].frames();
  if (hands[1].frames() != T)
    throw Error("infillWindowed: the hands have " + std::to_string(T) + " and " +
                std::to_string(hands[1].frames()) + " frames");
  const HandFeatureLayout layout = HandFeatureLayout::of(hands[0]);
  const HandFeatureLayout other = HandFeatureLayout::of(hands[1]);
  if (layout.betas != other.betas || layout.joints != other.joints)
    throw Error("infillWindowed: the hands differ in joint or shape-coefficient count");
  if (window < 1) throw Error("infillWindowed: window must be at least 1 frame");
  const Eigen::Index F = layout.size();

  std::array<HandMotion<Scalar>, 2> out = hands;
  std::array<HandMotion<Scalar>, 2> prefilled;  // whole-sequence pre-fill (world)
  std::array<bool, 2> any;
  for (int h = 0; h < 2; ++h) {
    any[h] = countValid(hands[h].valid) > 0;
    if (any[h]) prefilled[h] = fillInterpolate(hands[h]);
    if (filled) (*filled)[h].assign(static_cast<size_t>(T), 0);
  }

  InfillWindow<Scalar> w;
  w.layout = layout;
  w.features.resize(window, 2 * F);
  for (Eigen::Index start = 0; start < T; start += window) {
    const Eigen::Index n = std::min(window, T - start);
    w.start = start;
    w.frames = n;
    std::array<HandMotion<Scalar>, 2> can;
    std::array<CanonicalFrame<Scalar>, 2> frame;
    std::array<Points3<Scalar>, 2> j0;
    for (int h = 0; h < 2; ++h) {
      const Eigen::Index col0 = h * F;
      w.valid[h].assign(static_cast<size_t>(window), 0);
      if (!any[h]) {
        for (Eigen::Index r = 0; r < window; ++r) window_detail::packIdentity(layout, w.features, r, col0);
        continue;
      }
      j0[h] = window_detail::sliceJ0(J0[h], T, start, n);
      HandMotion<Scalar> world = window_detail::sliceFrames(prefilled[h], start, n);
      // Canonical frame: the first valid frame of the window, else its first (pre-filled) frame.
      Eigen::Index origin = 0;
      while (origin < n && !world.valid[static_cast<size_t>(origin)]) ++origin;
      if (origin == n) origin = 0;
      frame[h] = canonicalFrameAt(world, j0[h], origin);
      can[h] = worldToCanonical(world, frame[h], j0[h]);
      // In-window pre-fill in canonical space (the whole-sequence values stay where the window
      // has no valid frame).
      if (countValid(can[h].valid) > 0) can[h] = fillInterpolate(can[h]);
      for (Eigen::Index r = 0; r < window; ++r) {
        const Eigen::Index t = std::min(r, n - 1);  // padding repeats the last frame
        packHandFeatures(can[h], t, layout, w.features, r, col0);
        w.valid[h][static_cast<size_t>(r)] = can[h].valid[static_cast<size_t>(t)] ? 1 : 0;
      }
    }
    const Sequence<Scalar> y = infiller.infillWindow(w);
    if (y.rows() != window || y.cols() != 2 * F)
      throw Error("infillWindowed: the infiller returned " + std::to_string(y.rows()) + "x" +
                  std::to_string(y.cols()) + " features, expected " + std::to_string(window) + "x" +
                  std::to_string(2 * F));
    for (int h = 0; h < 2; ++h) {
      if (!any[h]) continue;
      HandMotion<Scalar> res = can[h];
      bool some = false;
      for (Eigen::Index r = 0; r < n; ++r) {
        if (can[h].valid[static_cast<size_t>(r)]) continue;
        unpackHandFeatures(y, r, h * F, layout, res, r);
        some = true;
      }
      if (!some) continue;
      const HandMotion<Scalar> back = canonicalToWorld(res, frame[h], j0[h]);
      for (Eigen::Index r = 0; r < n; ++r) {
        if (can[h].valid[static_cast<size_t>(r)]) continue;
        const Eigen::Index t = start + r;
        out[h].rot.row(t) = back.rot.row(r);
        out[h].trans.row(t) = back.trans.row(r);
        out[h].handPose.row(t) = back.handPose.row(r);
        out[h].betas.row(t) = back.betas.row(r);
        if (filled) (*filled)[h][static_cast<size_t>(t)] = 1;
      }
    }
  }
  return out;
}

}  // namespace hawor
