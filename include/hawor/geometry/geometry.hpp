// hawor/geometry/geometry.hpp — everything in the geometry module: rotation conversions,
// the groups SO(3)/SE(3)/Sim(3), interpolation, Umeyama alignment, the pinhole camera and the
// lens models (pinhole, radial-tangential, fisheye) with the camera that combines them.
#pragma once

#include "hawor/geometry/rotation.hpp"
#include "hawor/geometry/so3.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/geometry/sim3.hpp"
#include "hawor/geometry/interpolate.hpp"
#include "hawor/geometry/alignment.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/lens.hpp"
#include "hawor/geometry/camera_model.hpp"
#include "hawor/geometry/robust_loss.hpp"
#include "hawor/geometry/pnp.hpp"
