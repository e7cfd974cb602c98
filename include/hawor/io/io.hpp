// hawor/io/io.hpp — file formats: .npy arrays, ZIP / .npz archives, TUM trajectories, JSON and
// binary glTF (GLB).
// Define HAWOR_NO_STB (stored .npz members only) or HAWOR_STB_EXTERNAL (you compile stb) before
// including; see io/detail/stb.hpp.
#pragma once

#include "file.hpp"
#include "npy.hpp"
#include "deflate.hpp"
#include "zip.hpp"
#include "npz.hpp"
#include "tum.hpp"
#include "json.hpp"
#include "gltf.hpp"
#include "image_file.hpp"
