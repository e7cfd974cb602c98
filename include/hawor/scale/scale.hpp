// hawor/scale/scale.hpp — metric scale of the monocular trajectory (issue 5, DESIGN §6): the
// official adaptive-sampling Geman–McClure fit on metric depth (and its plain-median baseline),
// and the hand-anchored scale that needs no depth network.
#pragma once

#include "robust_scale.hpp"
#include "hand_scale.hpp"
