// hawor/motion/motion.hpp — umbrella header of the motion module: interpolation, gap filling,
// hand sequences, camera → world → canonical transforms, pre-fill (DESIGN §7).
#pragma once

#include "hawor/motion/canonical.hpp"
#include "hawor/motion/hand_motion.hpp"
#include "hawor/motion/prefill.hpp"
#include "hawor/motion/sequence.hpp"
#include "hawor/motion/slerp.hpp"
