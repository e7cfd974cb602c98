// hawor/render/render.hpp — software rendering: images, the triangle rasteriser, hand masks.
#pragma once

#include "hawor/render/image.hpp"
#include "hawor/render/rasterizer.hpp"
#include "hawor/render/mask.hpp"
#include "hawor/render/hand_masks.hpp"
#include "hawor/render/resample.hpp"
