// The hawor subcommands; each is a thin main over include/hawor.
#pragma once

namespace hawor_cli {
int cmdMetrics(int argc, char** argv);  // hawor metrics camera|hands ...
int cmdDemo(int argc, char** argv);     // hawor demo --out DIR
int cmdConvertHand(int argc, char** argv);  // hawor convert-hand --glb F --side S --out M
int cmdHand(int argc, char** argv);  // hawor hand --model M [--pose P] --out mesh.obj
int cmdFit(int argc, char** argv);   // hawor fit --model M --obs K.npz --intrinsics ... --out F
int cmdSynth(int argc, char** argv);  // hawor synth --preset P --seed N --out DIR | --list
int cmdSlam(int argc, char** argv);   // hawor slam --images DIR --intrinsics ... --out TRAJ.tum
int cmdScale(int argc, char** argv);  // hawor scale --traj T.tum --keyframe-depths KD.npz ... --out M.tum
int cmdInfill(int argc, char** argv);
int cmdWorld(int argc, char** argv);  // hawor world --images DIR --hands H.npz --out DIR ...  // hawor infill --in HANDS.npz --out FILLED.npz [--method ...]
}  // namespace hawor_cli
