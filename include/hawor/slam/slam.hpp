// hawor/slam/slam.hpp — the SLAM module (docs/design.md §5): front end (pyramid, hand masks,
// Shi–Tomasi corners with bucketing, pyramidal KLT), minimal solvers and robust estimation
// (RANSAC, 5-point essential, homography, P3P, PnP-RANSAC, triangulation, two-view
// initialisation), sparse bundle adjustment, the full-sequence refinement, the head model of a
// standing wearer, place recognition (binary descriptors, a keyframe index, Sim(3) RANSAC), a
// Sim(3) pose graph, and the monocular SLAM system with dual hand masking.
#pragma once

#include "image_pyramid.hpp"
#include "hand_mask.hpp"
#include "corners.hpp"
#include "klt.hpp"
#include "keyframe_policy.hpp"
#include "ransac.hpp"
#include "essential.hpp"
#include "homography.hpp"
#include "p3p.hpp"
#include "triangulation.hpp"
#include "two_view.hpp"
#include "pnp_ransac.hpp"
#include "ba_problem.hpp"
#include "ba_reduced_solver.hpp"
#include "bundle_adjustment.hpp"
#include "similarity_join.hpp"
#include "turn_bridge.hpp"
#include "focal_refine.hpp"
#include "sequence_refine.hpp"
#include "head_motion.hpp"
#include "binary_descriptor.hpp"
#include "place_index.hpp"
#include "sim3_ransac.hpp"
#include "pose_graph.hpp"
#include "slam_result.hpp"
#include "frame_step.hpp"
#include "slam_options.hpp"
#include "mono_slam.hpp"
#include "slam_option_table.hpp"
