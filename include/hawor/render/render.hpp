// hawor/render/render.hpp — software rendering: images, the triangle rasteriser, hand masks,
// resampling, rectification of lens images and perspective crops through a lens.
#pragma once

#include "hawor/render/image.hpp"
#include "hawor/render/rasterizer.hpp"
#include "hawor/render/mask.hpp"
#include "hawor/render/hand_masks.hpp"
#include "hawor/render/resample.hpp"
#include "hawor/render/rectify.hpp"
#include "hawor/render/lens_crop.hpp"
