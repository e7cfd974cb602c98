// hawor/eval/eval.hpp — umbrella header of the evaluation module: the hand and camera metrics of
// the paper (docs/design.md §8) and the camera alignment used before the world metrics.
#pragma once

#include "hawor/eval/camera_metrics.hpp"
#include "hawor/eval/hand_metrics.hpp"
#include "hawor/eval/joint_sequence.hpp"
