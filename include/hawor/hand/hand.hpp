// hawor/hand/hand.hpp — the hand-model module (docs/design.md §3): model data and forward pass, the
// left/right mirror convention, model files (MANO .pkl/.npz through a non-executing pickle
// reader, the WebXR glTF default hand, the library's own .npz), and the keypoint fit.
#pragma once

#include "hand_model.hpp"
#include "portable_random.hpp"
#include "forward.hpp"
#include "mirror.hpp"
#include "pickle_value.hpp"
#include "pickle.hpp"
#include "mano_loader.hpp"
#include "default_hand.hpp"
#include "model_io.hpp"
#include "load_model.hpp"
#include "joint_limits.hpp"
#include "keypoint_jacobian.hpp"
#include "fit.hpp"
#include "synthetic_hand.hpp"
