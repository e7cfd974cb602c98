// hawor/slam/slam_option_table.hpp — SlamOptions by name: `setSlamOption(options, "init.minTracks",
// "40")`, for tools that try a setting without a rebuild (`hawor slam --set NAME=VALUE,...`, the
// SLAM benchmarks' ablations). The numeric and boolean fields of SlamOptions and of its parts'
// option structs (PART.NAME: init, turn, reloc, revisit, link, place, finish, join, keyframe,
// corners, klt, twoView, pnp, bridge, sequence, headModel, focal); values are checked (an integer
// for an int, a finite number, true/false/1/0 for a bool) and an unknown name is an error that
// lists the known ones. Generated from slam_options.hpp and the parts' headers.
#pragma once

#include <cmath>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "../common.hpp"
#include "mono_slam.hpp"

namespace hawor {
namespace slam_option_detail {

template <typename O, typename T>
using Field = std::pair<const char*, T& (*)(O&)>;

/// The accessor of the field called `name` among `fields`, or null.
template <typename O, typename T>
auto find(const std::vector<Field<O, T>>& fields, const std::string& name) -> T& (*)(O&) {
  for (const auto& f : fields) {
    if (name == f.first) return f.second;
  }
  return nullptr;
}

template <typename Scalar>
const std::vector<Field<SlamOptions<Scalar>, int>>& intFields() {
  using O = SlamOptions<Scalar>;
  using T = int;
  static const std::vector<Field<O, T>> f = {
      {"frameStep", [](O& o) -> T& { return o.frameStep; }},
      {"pyramidLevels", [](O& o) -> T& { return o.pyramidLevels; }},
      {"maxFeatures", [](O& o) -> T& { return o.maxFeatures; }},
      {"maskDilatePx", [](O& o) -> T& { return o.maskDilatePx; }},
      {"maskBlock", [](O& o) -> T& { return o.maskBlock; }},
      {"minInliers", [](O& o) -> T& { return o.minInliers; }},
      {"lostFramesBeforeReset", [](O& o) -> T& { return o.lostFramesBeforeReset; }},
      {"backTrackFrames", [](O& o) -> T& { return o.backTrackFrames; }},
      {"backTrackBaselines", [](O& o) -> T& { return o.backTrackBaselines; }},
      {"windowKeyframes", [](O& o) -> T& { return o.windowKeyframes; }},
      {"localIterations", [](O& o) -> T& { return o.localIterations; }},
      {"globalIterations", [](O& o) -> T& { return o.globalIterations; }},
      {"finish.maxAdjustedKeyframes", [](O& o) -> T& { return o.finish.maxAdjustedKeyframes; }},
      {"init.everyFrames", [](O& o) -> T& { return o.init.everyFrames; }},
      {"init.minTracks", [](O& o) -> T& { return o.init.minTracks; }},
      {"init.reinitMinTracks", [](O& o) -> T& { return o.init.reinitMinTracks; }},
      {"init.maxGap", [](O& o) -> T& { return o.init.maxGap; }},
      {"turn.holdFrames", [](O& o) -> T& { return o.turn.holdFrames; }},
      {"turn.minInliers", [](O& o) -> T& { return o.turn.minInliers; }},
      {"turn.maxBridgeFrames", [](O& o) -> T& { return o.turn.maxBridgeFrames; }},
      {"turn.coastFrames", [](O& o) -> T& { return o.turn.coastFrames; }},
      {"reloc.keyframes", [](O& o) -> T& { return o.reloc.keyframes; }},
      {"reloc.spacing", [](O& o) -> T& { return o.reloc.spacing; }},
      {"reloc.anchors", [](O& o) -> T& { return o.reloc.anchors; }},
      {"reloc.maxPoints", [](O& o) -> T& { return o.reloc.maxPoints; }},
      {"reloc.minInliers", [](O& o) -> T& { return o.reloc.minInliers; }},
      {"revisit.minFrames", [](O& o) -> T& { return o.revisit.minFrames; }},
      {"revisit.maxPoints", [](O& o) -> T& { return o.revisit.maxPoints; }},
      {"revisit.minInliers", [](O& o) -> T& { return o.revisit.minInliers; }},
      {"link.maxPoints", [](O& o) -> T& { return o.link.maxPoints; }},
      {"link.minInliers", [](O& o) -> T& { return o.link.minInliers; }},
      {"link.yawSteps", [](O& o) -> T& { return o.link.yawSteps; }},
      {"link.everyFrames", [](O& o) -> T& { return o.link.everyFrames; }},
      {"link.enough", [](O& o) -> T& { return o.link.enough; }},
      {"place.minVotes", [](O& o) -> T& { return o.place.minVotes; }},
      {"place.candidates", [](O& o) -> T& { return o.place.candidates; }},
      {"place.minFramesApart", [](O& o) -> T& { return o.place.minFramesApart; }},
      {"place.maxDistance", [](O& o) -> T& { return o.place.maxDistance; }},
      {"place.minInliers", [](O& o) -> T& { return o.place.minInliers; }},
      {"finish.focalMaxFrames", [](O& o) -> T& { return o.finish.focalMaxFrames; }},
      {"finish.focalFrameSpacing", [](O& o) -> T& { return o.finish.focalFrameSpacing; }},
      {"keyframe.minInliers", [](O& o) -> T& { return o.keyframe.minInliers; }},
      {"keyframe.maxInterval", [](O& o) -> T& { return o.keyframe.maxInterval; }},
      {"keyframe.minInterval", [](O& o) -> T& { return o.keyframe.minInterval; }},
      {"keyframe.thinInterval", [](O& o) -> T& { return o.keyframe.thinInterval; }},
      {"corners.cellSize", [](O& o) -> T& { return o.corners.cellSize; }},
      {"corners.maxPerCell", [](O& o) -> T& { return o.corners.maxPerCell; }},
      {"corners.minDistance", [](O& o) -> T& { return o.corners.minDistance; }},
      {"corners.border", [](O& o) -> T& { return o.corners.border; }},
      {"corners.boxRadius", [](O& o) -> T& { return o.corners.boxRadius; }},
      {"klt.halfWindow", [](O& o) -> T& { return o.klt.halfWindow; }},
      {"klt.maxIterations", [](O& o) -> T& { return o.klt.maxIterations; }},
      {"twoView.maxIterations", [](O& o) -> T& { return o.twoView.maxIterations; }},
      {"twoView.minTriangulated", [](O& o) -> T& { return o.twoView.minTriangulated; }},
      {"twoView.minThirdView", [](O& o) -> T& { return o.twoView.minThirdView; }},
      {"twoView.refineIterations", [](O& o) -> T& { return o.twoView.refineIterations; }},
      {"pnp.maxIterations", [](O& o) -> T& { return o.pnp.maxIterations; }},
      {"pnp.minIterations", [](O& o) -> T& { return o.pnp.minIterations; }},
      {"pnp.minInliers", [](O& o) -> T& { return o.pnp.minInliers; }},
      {"bridge.minTracks", [](O& o) -> T& { return o.bridge.minTracks; }},
      {"bridge.minPoints", [](O& o) -> T& { return o.bridge.minPoints; }},
      {"sequence.minObservations", [](O& o) -> T& { return o.sequence.minObservations; }},
      {"sequence.minFrameObservations", [](O& o) -> T& { return o.sequence.minFrameObservations; }},
      {"sequence.maxAdjustedFrames", [](O& o) -> T& { return o.sequence.maxAdjustedFrames; }},
      {"sequence.denseMaxFrames", [](O& o) -> T& { return o.sequence.denseMaxFrames; }},
      {"sequence.rounds", [](O& o) -> T& { return o.sequence.rounds; }},
      {"sequence.iterations", [](O& o) -> T& { return o.sequence.iterations; }},
      {"headModel.window", [](O& o) -> T& { return o.headModel.window; }},
      {"headModel.minFrames", [](O& o) -> T& { return o.headModel.minFrames; }},
      {"headModel.lag", [](O& o) -> T& { return o.headModel.lag; }},
      {"focal.gridPerOctave", [](O& o) -> T& { return o.focal.gridPerOctave; }},
      {"focal.minPoses", [](O& o) -> T& { return o.focal.minPoses; }},
      {"focal.minObservations", [](O& o) -> T& { return o.focal.minObservations; }},
      {"focal.rounds", [](O& o) -> T& { return o.focal.rounds; }},
  };
  return f;
}

template <typename Scalar>
const std::vector<Field<SlamOptions<Scalar>, Scalar>>& scalarFields() {
  using O = SlamOptions<Scalar>;
  using T = Scalar;
  static const std::vector<Field<O, T>> f = {
      {"fps", [](O& o) -> T& { return o.fps; }},
      {"rollingShutter", [](O& o) -> T& { return o.rollingShutter; }},
      {"maxRayJumpDeg", [](O& o) -> T& { return o.maxRayJumpDeg; }},
      {"minTriangulationDeg", [](O& o) -> T& { return o.minTriangulationDeg; }},
      {"maxReprojPx", [](O& o) -> T& { return o.maxReprojPx; }},
      {"init.minFlowPx", [](O& o) -> T& { return o.init.minFlowPx; }},
      {"init.minRotationDeg", [](O& o) -> T& { return o.init.minRotationDeg; }},
      {"turn.rateDeg", [](O& o) -> T& { return o.turn.rateDeg; }},
      {"turn.rotationAgreementDeg", [](O& o) -> T& { return o.turn.rotationAgreementDeg; }},
      {"turn.bridgeMinParallaxDeg", [](O& o) -> T& { return o.turn.bridgeMinParallaxDeg; }},
      {"turn.coastMaxStepDeg", [](O& o) -> T& { return o.turn.coastMaxStepDeg; }},
      {"reloc.anchorDeg", [](O& o) -> T& { return o.reloc.anchorDeg; }},
      {"reloc.anchorDepths", [](O& o) -> T& { return o.reloc.anchorDepths; }},
      {"reloc.maxShiftPx", [](O& o) -> T& { return o.reloc.maxShiftPx; }},
      {"reloc.maxRotationDeg", [](O& o) -> T& { return o.reloc.maxRotationDeg; }},
      {"reloc.placeAgreeDeg", [](O& o) -> T& { return o.reloc.placeAgreeDeg; }},
      {"revisit.maxAngleDeg", [](O& o) -> T& { return o.revisit.maxAngleDeg; }},
      {"revisit.maxShiftPx", [](O& o) -> T& { return o.revisit.maxShiftPx; }},
      {"revisit.maxRotationDeg", [](O& o) -> T& { return o.revisit.maxRotationDeg; }},
      {"link.maxShiftPx", [](O& o) -> T& { return o.link.maxShiftPx; }},
      {"link.yawStepDeg", [](O& o) -> T& { return o.link.yawStepDeg; }},
      {"link.agreeDeg", [](O& o) -> T& { return o.link.agreeDeg; }},
      {"place.ratio", [](O& o) -> T& { return o.place.ratio; }},
      {"place.thresholdPx", [](O& o) -> T& { return o.place.thresholdPx; }},
      {"place.maxDepthError", [](O& o) -> T& { return o.place.maxDepthError; }},
      {"finish.focalMinStd", [](O& o) -> T& { return o.finish.focalMinStd; }},
      {"finish.redundantShare", [](O& o) -> T& { return o.finish.redundantShare; }},
      {"keyframe.inlierRatio", [](O& o) -> T& { return o.keyframe.inlierRatio; }},
      {"keyframe.maxRotationDeg", [](O& o) -> T& { return o.keyframe.maxRotationDeg; }},
      {"twoView.focalPx", [](O& o) -> T& { return o.twoView.focalPx; }},
      {"twoView.sigmaPx", [](O& o) -> T& { return o.twoView.sigmaPx; }},
      {"twoView.thresholdPx", [](O& o) -> T& { return o.twoView.thresholdPx; }},
      {"twoView.confidence", [](O& o) -> T& { return o.twoView.confidence; }},
      {"twoView.minParallaxDeg", [](O& o) -> T& { return o.twoView.minParallaxDeg; }},
      {"twoView.minPointParallaxDeg", [](O& o) -> T& { return o.twoView.minPointParallaxDeg; }},
      {"twoView.maxReprojPx", [](O& o) -> T& { return o.twoView.maxReprojPx; }},
      {"twoView.minInFrontRatio", [](O& o) -> T& { return o.twoView.minInFrontRatio; }},
      {"twoView.ambiguityRatio", [](O& o) -> T& { return o.twoView.ambiguityRatio; }},
      {"twoView.essentialOverPlaneInliers", [](O& o) -> T& { return o.twoView.essentialOverPlaneInliers; }},
      {"pnp.thresholdPx", [](O& o) -> T& { return o.pnp.thresholdPx; }},
      {"pnp.confidence", [](O& o) -> T& { return o.pnp.confidence; }},
      {"bridge.inlierPx", [](O& o) -> T& { return o.bridge.inlierPx; }},
      {"bridge.minInlierRatio", [](O& o) -> T& { return o.bridge.minInlierRatio; }},
      {"bridge.minStepDeg", [](O& o) -> T& { return o.bridge.minStepDeg; }},
      {"bridge.minPointRatio", [](O& o) -> T& { return o.bridge.minPointRatio; }},
      {"bridge.pointInlierPx", [](O& o) -> T& { return o.bridge.pointInlierPx; }},
      {"bridge.maxLengthRatio", [](O& o) -> T& { return o.bridge.maxLengthRatio; }},
      {"sequence.minParallaxDeg", [](O& o) -> T& { return o.sequence.minParallaxDeg; }},
      {"sequence.maxReprojPx", [](O& o) -> T& { return o.sequence.maxReprojPx; }},
      {"sequence.minGatePx", [](O& o) -> T& { return o.sequence.minGatePx; }},
      {"sequence.maxResectionRotationDeg", [](O& o) -> T& { return o.sequence.maxResectionRotationDeg; }},
      {"sequence.maxTranslationStdRatio", [](O& o) -> T& { return o.sequence.maxTranslationStdRatio; }},
      {"sequence.sigmaPx", [](O& o) -> T& { return o.sequence.sigmaPx; }},
      {"sequence.robustScale", [](O& o) -> T& { return o.sequence.robustScale; }},
      {"sequence.headPriorSigma", [](O& o) -> T& { return o.sequence.headPriorSigma; }},
      {"headModel.minSpreadDeg", [](O& o) -> T& { return o.headModel.minSpreadDeg; }},
      {"headModel.minR2", [](O& o) -> T& { return o.headModel.minR2; }},
      {"headModel.minMotionR2", [](O& o) -> T& { return o.headModel.minMotionR2; }},
      {"headModel.minFrontCos", [](O& o) -> T& { return o.headModel.minFrontCos; }},
      {"headModel.maxRadiusSpread", [](O& o) -> T& { return o.headModel.maxRadiusSpread; }},
      {"headModel.ridge", [](O& o) -> T& { return o.headModel.ridge; }},
      {"headModel.minGapTurnDeg", [](O& o) -> T& { return o.headModel.minGapTurnDeg; }},
      {"headModel.joinMinMotionR2", [](O& o) -> T& { return o.headModel.joinMinMotionR2; }},
      {"focal.priorSigmaLog", [](O& o) -> T& { return o.focal.priorSigmaLog; }},
      {"focal.priorFx", [](O& o) -> T& { return o.focal.priorFx; }},
      {"focal.searchMin", [](O& o) -> T& { return o.focal.searchMin; }},
      {"focal.maxStdLog", [](O& o) -> T& { return o.focal.maxStdLog; }},
      {"focal.minChange", [](O& o) -> T& { return o.focal.minChange; }},
      {"focal.minChangeStds", [](O& o) -> T& { return o.focal.minChangeStds; }},
      {"focal.minStdLog", [](O& o) -> T& { return o.focal.minStdLog; }},
  };
  return f;
}

template <typename Scalar>
const std::vector<Field<SlamOptions<Scalar>, float>>& floatFields() {
  using O = SlamOptions<Scalar>;
  using T = float;
  static const std::vector<Field<O, T>> f = {
      {"corners.minEigen", [](O& o) -> T& { return o.corners.minEigen; }},
      {"klt.epsilon", [](O& o) -> T& { return o.klt.epsilon; }},
      {"klt.minEigen", [](O& o) -> T& { return o.klt.minEigen; }},
      {"klt.maxResidual", [](O& o) -> T& { return o.klt.maxResidual; }},
      {"klt.maxFbError", [](O& o) -> T& { return o.klt.maxFbError; }},
  };
  return f;
}

template <typename Scalar>
const std::vector<Field<SlamOptions<Scalar>, bool>>& boolFields() {
  using O = SlamOptions<Scalar>;
  using T = bool;
  static const std::vector<Field<O, T>> f = {
      {"useMasks", [](O& o) -> T& { return o.useMasks; }},
      {"init.thirdView", [](O& o) -> T& { return o.init.thirdView; }},
      {"turn.bridge", [](O& o) -> T& { return o.turn.bridge; }},
      {"reloc.enabled", [](O& o) -> T& { return o.reloc.enabled; }},
      {"reloc.byPlace", [](O& o) -> T& { return o.reloc.byPlace; }},
      {"revisit.enabled", [](O& o) -> T& { return o.revisit.enabled; }},
      {"link.enabled", [](O& o) -> T& { return o.link.enabled; }},
      {"place.enabled", [](O& o) -> T& { return o.place.enabled; }},
      {"finish.globalBundleAdjustment", [](O& o) -> T& { return o.finish.globalBundleAdjustment; }},
      {"finish.refineFrames", [](O& o) -> T& { return o.finish.refineFrames; }},
      {"finish.sequenceRefine", [](O& o) -> T& { return o.finish.sequenceRefine; }},
      {"finish.headModelFill", [](O& o) -> T& { return o.finish.headModelFill; }},
      {"finish.refineFocal", [](O& o) -> T& { return o.finish.refineFocal; }},
      {"join.headModel", [](O& o) -> T& { return o.join.headModel; }},
      {"join.headModelAll", [](O& o) -> T& { return o.join.headModelAll; }},
      {"join.beforeRefine", [](O& o) -> T& { return o.join.beforeRefine; }},
      {"join.placeShort", [](O& o) -> T& { return o.join.placeShort; }},
      {"klt.forwardBackward", [](O& o) -> T& { return o.klt.forwardBackward; }},
      {"twoView.essentialOverPlane", [](O& o) -> T& { return o.twoView.essentialOverPlane; }},
      {"twoView.refine", [](O& o) -> T& { return o.twoView.refine; }},
      {"pnp.refine", [](O& o) -> T& { return o.pnp.refine; }},
      {"sequence.headPrior", [](O& o) -> T& { return o.sequence.headPrior; }},
      {"headModel.wholeSequenceFallback", [](O& o) -> T& { return o.headModel.wholeSequenceFallback; }},
  };
  return f;
}

}  // namespace slam_option_detail

/// Every settable name, in declaration order (ints, then numbers, then booleans).
template <typename Scalar>
std::vector<std::string> slamOptionNames() {
  std::vector<std::string> n;
  for (const auto& f : slam_option_detail::intFields<Scalar>()) n.emplace_back(f.first);
  for (const auto& f : slam_option_detail::scalarFields<Scalar>()) n.emplace_back(f.first);
  for (const auto& f : slam_option_detail::floatFields<Scalar>()) n.emplace_back(f.first);
  for (const auto& f : slam_option_detail::boolFields<Scalar>()) n.emplace_back(f.first);
  return n;
}

/// Sets one field from its text; throws hawor::Error naming the field and the problem.
template <typename Scalar>
void setSlamOption(SlamOptions<Scalar>& o, const std::string& name, const std::string& value) {
  namespace d = slam_option_detail;
  const std::string what = "SLAM option " + name + "=" + value + ": ";
  if (const auto field = d::find(d::boolFields<Scalar>(), name)) {
    if (value == "true" || value == "1") field(o) = true;
    else if (value == "false" || value == "0") field(o) = false;
    else throw Error(what + "expects true, false, 1 or 0");
    return;
  }
  char* end = nullptr;
  const double x = std::strtod(value.c_str(), &end);
  const bool number = !value.empty() && end && *end == '\0' && std::isfinite(x);
  if (const auto field = d::find(d::intFields<Scalar>(), name)) {
    if (!number || x != std::floor(x) || std::abs(x) > 1e9) throw Error(what + "expects an integer");
    field(o) = static_cast<int>(x);
    return;
  }
  if (const auto field = d::find(d::scalarFields<Scalar>(), name)) {
    if (!number) throw Error(what + "expects a finite number");
    field(o) = static_cast<Scalar>(x);
    return;
  }
  if (const auto field = d::find(d::floatFields<Scalar>(), name)) {
    if (!number) throw Error(what + "expects a finite number");
    field(o) = static_cast<float>(x);
    return;
  }
  std::string known;
  for (const std::string& n : slamOptionNames<Scalar>()) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown SLAM option '" + name + "' (known: " + known + ")");
}

/// "NAME=VALUE,NAME=VALUE": each set in turn (an empty list sets nothing).
template <typename Scalar>
void setSlamOptions(SlamOptions<Scalar>& o, const std::string& list) {
  std::size_t at = 0;
  while (at < list.size()) {
    std::size_t comma = list.find(',', at);
    if (comma == std::string::npos) comma = list.size();
    const std::string item = list.substr(at, comma - at);
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0) throw Error("SLAM option '" + item + "': expects NAME=VALUE");
    setSlamOption(o, item.substr(0, eq), item.substr(eq + 1));
    at = comma + 1;
  }
}

}  // namespace hawor
