// hawor convert-hand — a skinned glTF hand (.glb) to the library's hand-model .npz
// (hand/default_hand.hpp for the conversion, hand/model_io.hpp for the file format).
#include <cstdio>
#include <string>

#include "cli_args.hpp"
#include "commands.hpp"
#include "hawor/hand/default_hand.hpp"
#include "hawor/hand/model_io.hpp"

namespace hawor_cli {
namespace {

const char* kConvertHandHelp =
    "usage: hawor convert-hand --glb HAND.glb --side left|right --out MODEL.npz\n"
    "\n"
    "Converts a skinned glTF 2.0 hand (binary .glb with one skinned mesh, e.g. the WebXR\n"
    "generic hands of npm @webxr-input-profiles/assets, MIT) into a hawor hand model: bind-pose\n"
    "template, faces, linear-blend-skinning weights, kinematic tree, a joint regressor that\n"
    "reproduces the bind-pose joints, and the 21 MediaPipe keypoints when the joints carry the\n"
    "WebXR names. No shape space, no pose correctives. Prints one JSON object:\n"
    "  vertices, faces, joints, keypoints  sizes of the model\n"
    "  hand_length  wrist to middle fingertip at rest, metres (null without keypoints)\n"
    "  side         left or right, as given\n";

}  // namespace

int cmdConvertHand(int argc, char** argv) {
  Args args(argc, argv, 2, {"glb", "side", "out"}, {});
  if (args.help()) {
    std::fputs(kConvertHandHelp, stdout);
    return 0;
  }
  if (!args.positional().empty()) throw UsageError("unexpected argument '" + args.positional()[0] + "'");
  const std::string glb = args.required("glb"), side = args.required("side"), out = args.required("out");
  if (side != "left" && side != "right") throw UsageError("--side must be 'left' or 'right', got '" + side + "'");
  const hawor::DefaultHand<double> hand = hawor::loadDefaultHand<double>(glb, side == "left");
  hawor::saveHandModel(hand.model, out, hand.jointNames);
  const hawor::HandModel<double>& m = hand.model;
  std::printf("%s\n", JsonObject()
                          .integer("vertices", m.numVertices())
                          .integer("faces", static_cast<long long>(m.faces.rows()))
                          .integer("joints", m.numJoints())
                          .integer("keypoints", m.numKeypoints())
                          .num("hand_length", hawor::restHandLength(m))
                          .str("side", side)
                          .dump()
                          .c_str());
  return 0;
}

}  // namespace hawor_cli
