// hawor/motion/motion.hpp — umbrella header of the motion module: interpolation, gap filling,
// hand sequences, camera → world → canonical transforms, pre-fill, the spline infiller, the
// observed-frame smoother, the windowed infilling pipeline and the original infiller network's
// forward pass for a user's converted weights (docs/design.md §7).
#pragma once

#include "hawor/motion/canonical.hpp"
#include "hawor/motion/hand_motion.hpp"
#include "hawor/motion/infill.hpp"
#include "hawor/motion/infill_window.hpp"
#include "hawor/motion/local_poly.hpp"
#include "hawor/motion/motion_noise.hpp"
#include "hawor/motion/prefill.hpp"
#include "hawor/motion/rest_root.hpp"
#include "hawor/motion/sequence.hpp"
#include "hawor/motion/slerp.hpp"
#include "hawor/motion/smooth.hpp"
#include "hawor/motion/spline_infill.hpp"
#include "hawor/motion/infiller_weights.hpp"
#include "hawor/motion/infiller_net.hpp"
#include "hawor/motion/transformer_infill.hpp"
