// hawor/synth/synth.hpp — synthetic egocentric sequences with ground truth:
// procedural textures → indoor scene → head-like camera paths → hand rig and hand motion →
// renderer → capture effects → presets → sequence → PNG / npy / npz / TUM writer.
#pragma once

#include "random.hpp"
#include "texture.hpp"
#include "scene.hpp"
#include "trajectory.hpp"
#include "hand_rig.hpp"
#include "hand_motion.hpp"
#include "renderer.hpp"
#include "capture_options.hpp"
#include "capture.hpp"
#include "presets.hpp"
#include "sequence.hpp"
#include "png.hpp"
#include "writer.hpp"
