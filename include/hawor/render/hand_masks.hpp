// hawor/render/hand_masks.hpp — the hand masks of one frame from fitted hands: each hand's
// forward pass (hand/forward.hpp) drawn into one mask at the camera's size (mask.hpp), optionally
// dilated. This is what the SLAM's dual masking and the scale step consume (docs/design.md §5, §6).
// Labels: every hand carries a value; equal values give the union of the silhouettes, different
// values a z-buffered labelled mask (nearest surface wins). Dilation (a disc of dilatePx pixels,
// dilateMask) needs one common value: a dilated ring has no nearest surface to take a label from.
// Thread-safety: a function; `ws` (optional) is the caller's scratch.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/render/mask.hpp"

namespace hawor {

/// One hand of the frame: a prepared model and its camera-frame pose (metres).
template <typename Scalar>
struct HandMaskHand {
  const HandModel<Scalar>* model = nullptr;
  HandPose<Scalar> pose;
  std::uint8_t value = 255;
};

/// Renders the hands' silhouettes into `out` (camera.width × camera.height, 0 = background), then
/// dilates by dilatePx (0 = none). Throws hawor::Error for a missing model, a bad pose (forward
/// pass), a bad camera, a negative dilation, or dilation with differing values (file comment).
template <typename Scalar>
void renderHandMasks(const std::vector<HandMaskHand<Scalar>>& hands, const PinholeCamera<Scalar>& camera,
                     int dilatePx, Mask& out) {
  camera.validate();
  if (dilatePx < 0) throw Error("renderHandMasks: dilation must be >= 0, got " + std::to_string(dilatePx));
  for (std::size_t i = 0; i < hands.size(); ++i) {
    if (!hands[i].model) throw Error("renderHandMasks: hand " + std::to_string(i) + " has no model");
    if (hands[i].value == 0) throw Error("renderHandMasks: hand " + std::to_string(i) + " has value 0 (background)");
    if (dilatePx > 0 && hands[i].value != hands.front().value) {
      throw Error("renderHandMasks: dilation needs one value for every hand (a dilated ring has no label)");
    }
  }
  std::vector<HandOutput<Scalar>> posed(hands.size());
  HandWorkspace<Scalar> ws;
  std::vector<MaskMesh<Scalar>> meshes(hands.size());
  for (std::size_t i = 0; i < hands.size(); ++i) {
    forward(*hands[i].model, hands[i].pose, ws, posed[i]);
    meshes[i].vertices = &posed[i].vertices;
    meshes[i].faces = &hands[i].model->faces;
    meshes[i].value = hands[i].value;
  }
  renderMask<Scalar>(meshes, camera, out);
  if (dilatePx > 0 && !hands.empty()) dilateMask(out, dilatePx, out, hands.front().value);
}

}  // namespace hawor
