// The synthetic hands and sequence size the SLAM system tests and the pipeline tests run on
// (test_mono_slam.cpp, test_pipeline.cpp: one unity build, one copy of each model).
#pragma once

#include "hawor/hand/mirror.hpp"
#include "hawor/hand/synthetic_hand.hpp"
#include "hawor/synth/synth.hpp"

namespace slam_test {

inline const hawor::HandModel<double>& rightHand() {
  static const hawor::HandModel<double> r = hawor::makeSyntheticHand<double>();
  return r;
}
inline const hawor::HandModel<double>& leftHand() {
  static const hawor::HandModel<double> l = hawor::mirrorHandModel(rightHand());
  return l;
}

/// `frames` frames at 640 x 480 with textures at 1 / textureDivisor of `hawor synth`'s (2:
/// coarser, quicker to set up; 1: those of `hawor synth` and bench_slam).
inline hawor::synth::SynthOptions sequenceOptions(int frames, int textureDivisor = 2) {
  hawor::synth::SynthOptions so;
  so.width = 640;
  so.height = 480;
  so.frames = frames;
  so.textureDivisor = textureDivisor;
  return so;
}

}  // namespace slam_test
