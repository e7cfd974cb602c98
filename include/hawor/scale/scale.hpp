// hawor/scale/scale.hpp — metric scale of the monocular trajectory (docs/design.md §6): the
// official adaptive-sampling Geman–McClure fit on metric depth (and its plain-median baseline),
// the two scales that need no depth network — hand-anchored (holds, then smoothness) and ground-plane
// (the cameras' height above the floor) — and their fusion.
#pragma once

#include "robust_scale.hpp"
#include "hand_track.hpp"
#include "hand_hold_scale.hpp"
#include "hand_smoothness_scale.hpp"
#include "hand_scale.hpp"
#include "ground_scale.hpp"
#include "confidence.hpp"
#include "fuse_scale.hpp"
#include "metric_scale.hpp"
