// hawor/hawor.hpp — umbrella header: every module, in the order data flows. Each module also has
// its own umbrella header, hawor/<module>/<module>.hpp, for programs that need only part of it:
//   geometry/  rotations, SO3 / SE3 / Sim3, interpolation, alignment, pinhole camera, PnP
//   hand/      the MANO hand model: loaders (pickle, npz, glTF), forward pass, keypoint fit
//   render/    software rasteriser, hand masks, resampling
//   slam/      monocular SLAM with hand masking, bundle adjustment
//   scale/     metric scale: depth (AdaSM), hands, ground plane, fusion
//   motion/    SLERP/LERP, camera → canonical → world, infilling
//   eval/      the hand and camera metrics (PA-MPJPE, W-MPJPE, RTE, ATE, ...)
//   io/        .npy / .npz, TUM, JSON, glTF, image files (stb unless HAWOR_NO_STB)
//   synth/     synthetic egocentric sequences with ground truth (benchmarks and tests)
#pragma once

#include "version.hpp"
#include "common.hpp"
#include "parallel.hpp"
#include "matmul.hpp"
#include "geometry/geometry.hpp"
#include "hand/hand.hpp"
#include "render/render.hpp"
#include "slam/slam.hpp"
#include "scale/scale.hpp"
#include "motion/motion.hpp"
#include "pipeline/pipeline.hpp"
#include "eval/eval.hpp"
#include "io/io.hpp"
#include "synth/synth.hpp"
