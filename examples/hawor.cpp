// hawor — command-line front end. Subcommands are thin wrappers over include/hawor:
// they parse options, read files, call the library and print JSON on stdout.
// Errors go to stderr with a non-zero exit code (2: usage, 1: bad input or failure).
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "cli_args.hpp"
#include "commands.hpp"

namespace {

const char* kUsage =
    "usage: hawor <command> [options]\n"
    "\n"
    "commands:\n"
    "  metrics camera --gt GT.tum --est EST.tum     ATE / ATE-S of a camera trajectory\n"
    "  metrics hands  --gt GT.npz --est EST.npz     PA-MPJPE, AUC, W-/WA-MPJPE, RTE, Accel\n"
    "                 [--model FILE|default]        (joints from hand parameters)\n"
    "  demo [--out DIR]                             built-in example: writes a ground-truth and\n"
    "                                               an estimated sequence, then evaluates them\n"
    "  convert-hand --glb HAND.glb --side left|right --out MODEL.npz\n"
    "                                               skinned glTF hand -> hawor hand model\n"
    "  hand --model FILE|default [--pose POSE.npz] --out MESH.obj\n"
    "                                               posed hand mesh (forward pass) as OBJ\n"
    "  fit --model FILE|default --obs KEYPOINTS.npz --intrinsics fx,fy,cx,cy --out FIT.npz\n"
    "                                               per-frame hand fit to 2D/3D keypoints\n"
    "  synth --preset NAME --seed N --out DIR       synthetic egocentric sequence with ground\n"
    "        [--frames N] [--size WxH] [--model ..] truth (RGB, depth, masks, poses, hands);\n"
    "  synth --list                                 --list prints the preset names\n"
    "  slam --images DIR --intrinsics fx,fy,cx,cy   monocular SLAM with the hands masked out\n"
    "       [--masks DIR] --out TRAJ.tum            (camera trajectory, keyframe depths)\n"
    "  scale --traj TRAJ.tum --keyframe-depths KD.npz  metric scale of a SLAM trajectory from\n"
    "        [--metric-depth DIR] [--hands H.npz] --out M.tum  depth maps and/or the hands\n"
    "  infill --in HANDS.npz --out FILLED.npz        fill the frames where a hand was unseen\n"
    "         [--method last|lerp|spline|transformer] [--weights W.npz] [--smooth]\n"
    "  world --images DIR --hands HANDS.npz --out DIR  camera-frame hands from any regressor to\n"
    "        [--intrinsics ..|--fov DEG] [--mano DIR]  a metric world: masks, SLAM, scale, infill\n"
    "\n"
    "Run 'hawor <command> --help' for a command's options.\n";

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    std::fputs(kUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const std::string cmd = argv[1];
  try {
    if (cmd == "metrics") return hawor_cli::cmdMetrics(argc, argv);
    if (cmd == "demo") return hawor_cli::cmdDemo(argc, argv);
    if (cmd == "convert-hand") return hawor_cli::cmdConvertHand(argc, argv);
    if (cmd == "hand") return hawor_cli::cmdHand(argc, argv);
    if (cmd == "fit") return hawor_cli::cmdFit(argc, argv);
    if (cmd == "synth") return hawor_cli::cmdSynth(argc, argv);
    if (cmd == "slam") return hawor_cli::cmdSlam(argc, argv);
    if (cmd == "scale") return hawor_cli::cmdScale(argc, argv);
    if (cmd == "infill") return hawor_cli::cmdInfill(argc, argv);
    if (cmd == "world") return hawor_cli::cmdWorld(argc, argv);
    std::fprintf(stderr, "hawor: unknown command '%s'\n\n%s", cmd.c_str(), kUsage);
    return 2;
  } catch (const hawor_cli::UsageError& e) {
    std::fprintf(stderr, "hawor %s: %s (see 'hawor %s --help')\n", cmd.c_str(), e.what(),
                 cmd.c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
