// hawor/hawor.hpp — umbrella header: one include per module, in the order data flows
// (geometry → hand model → rendering/masks → SLAM → scale → motion → eval → io).
#pragma once

#include "common.hpp"
#include "geometry/geometry.hpp"
#include "hand/hand.hpp"
#include "render/render.hpp"
#include "slam/slam.hpp"
#include "motion/motion.hpp"
#include "eval/eval.hpp"
#include "io/io.hpp"
