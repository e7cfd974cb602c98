// hawor hand — one forward pass of a hand model (hand/forward.hpp) written as a Wavefront OBJ.
#include <cstdio>
#include <string>

#include "cli_args.hpp"
#include "cli_hand.hpp"
#include "commands.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/load_model.hpp"
#include "hawor/io/file.hpp"
#include "hawor/io/npz.hpp"

namespace hawor_cli {
namespace {

const char* kHandHelpHead =
    "usage: hawor hand --model FILE|default [--side left|right] [--pose POSE.npz] [--frame N]\n"
    "                  --out MESH.obj\n"
    "\n"
    "Poses a hand model and writes the mesh as a Wavefront OBJ ('v x y z' lines in metres, then\n"
    "'f a b c' lines, 1-based, counter-clockwise seen from outside; left MANO models use the\n"
    "[0,2,1] winding). Without --pose the model is in its rest pose.\n"
    "\n";

const char* kHandHelpTail =
    "  --pose POSE.npz       hand parameters (missing arrays are zeros):\n"
    "                          global_orient or rot  (3) axis-angle of the wrist, radians\n"
    "                          hand_pose             ((J-1)*3) or (J-1,3) axis-angles of joints\n"
    "                                                1..J-1 relative to their parents (MANO: 45)\n"
    "                          betas                 (B') shape coefficients, B' <= the model's B\n"
    "                          transl or trans       (3) translation, metres\n"
    "                        each may also be per-frame, with a leading T axis (e.g. a 'hawor fit'\n"
    "                        output): --frame picks the frame; single-frame arrays serve all frames\n"
    "  --frame N             frame of the per-frame arrays (default 0)\n"
    "  --out MESH.obj        the OBJ to write\n"
    "\n"
    "Prints one JSON object: model, kind (mano-pkl, mano-npz, hawor-npz or glb), side, frame,\n"
    "vertices, faces, joints (counts) and keypoints (K x 3 list, metres; MANO: 21 in OpenPose order).\n";

}  // namespace

int cmdHand(int argc, char** argv) {
  Args args(argc, argv, 2, {"model", "side", "pose", "frame", "out"}, {});
  if (args.help()) {
    std::printf("%s%s%s", kHandHelpHead, kModelOptionHelp, kHandHelpTail);
    return 0;
  }
  if (!args.positional().empty()) throw UsageError("unexpected argument '" + args.positional()[0] + "'");
  const std::string out = args.required("out");
  args.required("model");
  const double frameArg = args.number("frame", 0);
  if (frameArg < 0 || frameArg != static_cast<double>(static_cast<long long>(frameArg)) || frameArg > 1e12) {
    throw UsageError("--frame must be a non-negative integer");
  }
  const size_t frame = static_cast<size_t>(frameArg);

  const hawor::LoadedHandModel<double> loaded = loadModelOption(args, argv[0]);
  const hawor::HandModel<double>& m = loaded.model;
  hawor::HandPose<double> pose = hawor::HandPose<double>::zero(m);
  if (args.has("pose")) {
    const hawor::Npz z = hawor::Npz::read(args.required("pose"));
    const HandParams params = readHandParams(z, m, {"global_orient", "rot"}, {"transl", "trans"});
    if (!params.rot.present() && !params.handPose.present() && !params.betas.present() && !params.trans.present()) {
      std::string keys;
      for (const std::string& k : z.names()) keys += (keys.empty() ? "" : ", ") + k;
      throw hawor::Error(z.source() + ": holds none of global_orient / rot, hand_pose, betas, transl / trans (keys: " +
                         (keys.empty() ? std::string("none") : keys) + ")");
    }
    const size_t T = params.frames();
    if (T == 0 && frame > 0) {
      throw hawor::Error(z.source() + ": --frame " + std::to_string(frame) +
                         " given but every array holds a single frame (no leading T axis)");
    }
    if (T > 0 && frame >= T) {
      throw hawor::Error(z.source() + ": --frame " + std::to_string(frame) + " is out of range (" + std::to_string(T) +
                         " frames)");
    }
    pose = params.at(frame, m);
  } else if (frame > 0) {
    throw UsageError("--frame needs --pose");
  }
  const hawor::HandOutput<double> o = hawor::forward(m, pose);

  std::string obj = "# hawor hand: " + loaded.source + " (" + hawor::handModelKindName(loaded.kind) + ", " +
                    sideName(m) + "), " + std::to_string(m.numVertices()) + " vertices, " +
                    std::to_string(m.faces.rows()) + " faces, metres\n";
  char buf[128];
  for (Eigen::Index v = 0; v < o.vertices.rows(); ++v) {
    std::snprintf(buf, sizeof buf, "v %.17g %.17g %.17g\n", o.vertices(v, 0), o.vertices(v, 1), o.vertices(v, 2));
    obj += buf;
  }
  for (Eigen::Index f = 0; f < m.faces.rows(); ++f) {
    std::snprintf(buf, sizeof buf, "f %d %d %d\n", m.faces(f, 0) + 1, m.faces(f, 1) + 1, m.faces(f, 2) + 1);
    obj += buf;
  }
  hawor::writeFileText(out, obj);
  std::printf("%s\n", JsonObject()
                          .str("model", loaded.source)
                          .str("kind", hawor::handModelKindName(loaded.kind))
                          .str("side", sideName(m))
                          .integer("frame", static_cast<long long>(frame))
                          .integer("vertices", m.numVertices())
                          .integer("faces", static_cast<long long>(m.faces.rows()))
                          .integer("joints", m.numJoints())
                          .raw("keypoints", jsonPoints(o.keypoints))
                          .dump()
                          .c_str());
  return 0;
}

}  // namespace hawor_cli
