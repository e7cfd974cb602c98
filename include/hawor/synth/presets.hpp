// hawor/synth/presets.hpp — the named synthetic sequences (`hawor synth --preset NAME`): a camera
// motion of trajectory.hpp, a hand behaviour of hand_motion.hpp, a default length and the pixel
// noise. The five presets of the SLAM benchmark:
//   walk           walking through the room, hands now and then in view
//   table_work     standing at the table looking down while the hands work
//   fast_turns     standing, turning the head fast (hands trail and leave the view)
//   pure_rotation  the eye fixed, looking around (the degenerate case for two-view geometry)
//   hands_cover    at the table with both hands close to the camera: 40–60 % of the image
//                  covered for seconds at a time
// Every preset has holds (a hand still in the room for about a second, holding or resting on
// something): most at the table, few while walking.
// Thread-safety: functions return values; no shared state.
#pragma once

#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/synth/hand_motion.hpp"
#include "hawor/synth/trajectory.hpp"

namespace hawor {
namespace synth {

struct SynthPreset {
  std::string name;
  std::string description;
  CameraMotion motion = CameraMotion::Walk;
  int frames = 300;          ///< default length at 30 fps
  HandBehaviour hands;
  float noiseSigma = 1.5f;   ///< pixel noise, grey levels (standard deviation)
};

/// Every preset, in a fixed order.
inline std::vector<SynthPreset> synthPresets() {
  std::vector<SynthPreset> out;
  {
    SynthPreset p;
    p.name = "walk";
    p.description = "walking around the table; hands now and then in view";
    p.motion = CameraMotion::Walk;
    p.frames = 360;
    p.hands.inViewChance = 0.55;
    p.hands.inViewMin = 1.0, p.hands.inViewMax = 3.0;
    p.hands.outMin = 1.0, p.hands.outMax = 2.5;
    p.hands.depthMin = 0.25, p.hands.depthMax = 0.45;
    p.hands.lateralMin = 0.05, p.hands.lateralMax = 0.22;
    p.hands.heightMin = 0.06, p.hands.heightMax = 0.2;
    p.hands.lagSeconds = 0.2;
    p.hands.holdChance = 0.1;
    out.push_back(p);
  }
  {
    SynthPreset p;
    p.name = "table_work";
    p.description = "standing at the table, looking down while both hands work";
    p.motion = CameraMotion::TableWork;
    p.frames = 300;
    p.hands.inViewChance = 0.85;
    p.hands.inViewMin = 2.0, p.hands.inViewMax = 4.0;
    p.hands.outMin = 0.5, p.hands.outMax = 1.5;
    p.hands.depthMin = 0.16, p.hands.depthMax = 0.34;
    p.hands.lateralMin = 0.03, p.hands.lateralMax = 0.17;
    p.hands.heightMin = 0.0, p.hands.heightMax = 0.15;
    p.hands.lagSeconds = 0.3;
    p.hands.startInView = 0.85;
    p.hands.holdChance = 0.4;
    out.push_back(p);
  }
  {
    SynthPreset p;
    p.name = "fast_turns";
    p.description = "standing, fast head turns of 60-150 degrees in 0.4-0.7 s between fixations";
    p.motion = CameraMotion::FastTurns;
    p.frames = 300;
    p.hands.inViewChance = 0.7;
    p.hands.lagSeconds = 0.35;
    p.hands.holdChance = 0.2;
    out.push_back(p);
  }
  {
    SynthPreset p;
    p.name = "pure_rotation";
    p.description = "the eye fixed (millimetre jitter), looking around the room";
    p.motion = CameraMotion::PureRotation;
    p.frames = 300;
    p.hands.inViewChance = 0.7;
    p.hands.lagSeconds = 0.3;
    p.hands.holdChance = 0.2;
    out.push_back(p);
  }
  {
    SynthPreset p;
    p.name = "hands_cover";
    p.description = "at the table with both hands close to the camera, covering 40-60% of the view for seconds at a time";
    p.motion = CameraMotion::TableWork;
    p.frames = 300;
    p.hands.inViewChance = 0.9;
    p.hands.inViewMin = 2.5, p.hands.inViewMax = 5.0;
    p.hands.outMin = 0.4, p.hands.outMax = 1.0;
    p.hands.depthMin = 0.12, p.hands.depthMax = 0.16;
    p.hands.lateralMin = 0.05, p.hands.lateralMax = 0.11;
    p.hands.heightMin = 0.04, p.hands.heightMax = 0.12;
    p.hands.fingerUpMin = 0.8, p.hands.fingerUpMax = 1.8;
    p.hands.palmToCamera = 0.35;
    p.hands.backToCamera = 0.35;
    p.hands.lagSeconds = 0.1;
    p.hands.startInView = 1.0;
    p.hands.maxInView = 8.0;
    p.hands.holdChance = 0.3;
    out.push_back(p);
  }
  return out;
}

/// The names of synthPresets(), in order.
inline std::vector<std::string> synthPresetNames() {
  std::vector<std::string> n;
  for (const SynthPreset& p : synthPresets()) n.push_back(p.name);
  return n;
}

/// The preset called `name`; throws hawor::Error listing the known names otherwise.
inline SynthPreset findSynthPreset(const std::string& name) {
  std::string known;
  for (const SynthPreset& p : synthPresets()) {
    if (p.name == name) return p;
    known += (known.empty() ? "" : ", ") + p.name;
  }
  throw Error("unknown synthetic preset '" + name + "' (known presets: " + known + ")");
}

}  // namespace synth
}  // namespace hawor
