// hawor/slam/slam_options.hpp — the options of MonoSlam (mono_slam.hpp), one struct per part, in
// the order a frame meets them: initialisation, turns, relocalisation, revisits, segment links,
// place recognition, then finish()'s passes and joins. Each part validates itself; SlamOptions::
// validate() checks them all and the combinations, naming the field. The names are the ones
// `hawor slam --set part.NAME=VALUE` takes (slam_option_table.hpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "hawor/common.hpp"
#include "hawor/slam/corners.hpp"
#include "hawor/slam/focal_refine.hpp"
#include "hawor/slam/frame_step.hpp"
#include "hawor/slam/head_motion.hpp"
#include "hawor/slam/keyframe_policy.hpp"
#include "hawor/slam/klt.hpp"
#include "hawor/slam/pnp_ransac.hpp"
#include "hawor/slam/sequence_refine.hpp"
#include "hawor/slam/turn_bridge.hpp"
#include "hawor/slam/two_view.hpp"

namespace hawor {

/// Initialisation of a map segment (mono_slam/initialisation.hpp): the two-view pair's reference
/// and when the pair is tried.
template <typename Scalar>
struct SlamInitOptions {
  Scalar minFlowPx = Scalar(4);       ///< median rotation-compensated flow before trying
  int everyFrames = 3;                ///< frames between two-view attempts
  int minTracks = 60;
  int reinitMinTracks = 60;           ///< minTracks after a tracking loss (40 measured: no gain)
  int maxGap = 60;                    ///< the two-view reference is one of the last this many frames
  Scalar minRotationDeg = Scalar(8);  ///< in turn mode: try after this much rotation (every other frame)
  /// Every second frame between the reference and the current one as further views that settle
  /// a two-fold ambiguity (a planar scene's homography; two_view.hpp).
  bool thirdView = true;

  /// Throws hawor::Error naming the first bad field.
  void validate() const {
    if (!(minFlowPx >= Scalar(0))) throw Error("init.minFlowPx must be >= 0");
    if (everyFrames < 1) throw Error("init.everyFrames must be >= 1");
    if (minTracks < 8 || reinitMinTracks < 8) throw Error("init.minTracks and init.reinitMinTracks must be >= 8");
    if (maxGap < 1) throw Error("init.maxGap must be >= 1");
    if (!(minRotationDeg > Scalar(0))) throw Error("init.minRotationDeg must be > 0");
  }
};

/// Fast head turns (turn mode; mono_slam/front_end.hpp, tracking.hpp).
template <typename Scalar>
struct SlamTurnOptions {
  Scalar rateDeg = Scalar(5);         ///< rotation a frame that starts turn mode (walking: < 3.5)
  int holdFrames = 5;                 ///< frames it lasts after the last such increment
  int minInliers = 10;                ///< PnP inliers enough when the rays agree
  Scalar rotationAgreementDeg = Scalar(1);  ///< PnP vs tracked-ray rotation, for that
  /// Turn bridge (turn_bridge.hpp): in turn mode, a frame whose PnP fails right after two posed
  /// frames is posed from the last one and the tracks between them (the step's direction from a
  /// head sphere, the rotation from the tracks' epipolar geometry, the length from the map points
  /// still tracked and the tracks triangulated from the two posed frames), at most
  /// maxBridgeFrames in a row; it becomes a keyframe, so the tracks born in the turn are
  /// triangulated and the map goes on instead of being reset.
  bool bridge = true;
  int maxBridgeFrames = 12;
  Scalar bridgeMinParallaxDeg = Scalar(0.2);  ///< of a track triangulated from the two posed frames
  /// A frame whose tracked rays give no rotation turns on at the last step's angular velocity
  /// (coastRotation), for at most coastFrames frames in a row, from a step of at most
  /// coastMaxStepDeg (a head peaks near 600°/s, 20° a frame at 30 fps); 0: held instead.
  int coastFrames = 6;
  Scalar coastMaxStepDeg = Scalar(20);

  /// Throws hawor::Error naming the first bad field.
  void validate() const {
    if (!(rateDeg > Scalar(0))) throw Error("turn.rateDeg must be > 0");
    if (holdFrames < 0 || maxBridgeFrames < 0 || coastFrames < 0) throw Error("turn.holdFrames, turn.maxBridgeFrames and turn.coastFrames must be >= 0");
    if (minInliers < 6) throw Error("turn.minInliers must be >= 6");
    if (!(rotationAgreementDeg >= Scalar(0)) || !(bridgeMinParallaxDeg >= Scalar(0)) || !(coastMaxStepDeg >= Scalar(0))) {
      throw Error("turn.rotationAgreementDeg, turn.bridgeMinParallaxDeg and turn.coastMaxStepDeg must be >= 0");
    }
  }
};

/// Place recognition between keyframes and the joins it makes (mono_slam/place_links.hpp).
template <typename Scalar>
struct SlamPlaceOptions {
  bool enabled = true;
  int minVotes = 12;                ///< index votes of a candidate (place_index.hpp)
  int candidates = 3;               ///< best candidates verified per keyframe
  int minFramesApart = 30;          ///< a candidate in the keyframe's own segment is this much older
  int maxDistance = 64;             ///< Hamming distance of a descriptor match, at most (of 256)
  Scalar ratio = Scalar(0.8);       ///< nearest / second-nearest distance, below
  int minInliers = 20;              ///< Sim(3) inliers of a link
  Scalar thresholdPx = Scalar(4);   ///< reprojection error of a Sim(3) inlier, in both keyframes
  Scalar maxDepthError = Scalar(0.1);  ///< and its 3D error, relative to its depth (sim3_ransac.hpp)

  /// Throws hawor::Error naming the first bad field.
  void validate() const {
    if (minVotes < 1 || candidates < 1 || minFramesApart < 0) throw Error("place.minVotes and place.candidates must be >= 1, place.minFramesApart >= 0");
    if (maxDistance < 0 || maxDistance > 256) throw Error("place.maxDistance must be in [0, 256]");
    if (!(ratio > Scalar(0) && ratio <= Scalar(1))) throw Error("place.ratio must be in (0, 1]");
    if (minInliers < 3) throw Error("place.minInliers must be >= 3");
    if (!(thresholdPx > Scalar(0))) throw Error("place.thresholdPx must be > 0");
    if (!(maxDepthError >= Scalar(0))) throw Error("place.maxDepthError must be >= 0");
  }
};

/// Relocalisation after a tracking loss, against the lost segment's map (mono_slam/
/// relocalisation.hpp): the pyramids of up to `keyframes` keyframes at least `spacing` frames
/// apart are kept (about 1.6 MB each at 640×480); while tracking is lost, and after the reset
/// until a new map is built, their points are projected under the frame's guess (rotation from
/// the tracked rays, position held) and searched by KLT from the keyframe images (within
/// maxShiftPx: the held position is off by the motion since the loss); PnP-RANSAC with
/// minInliers inliers puts the frame back in the old map, and the old segment goes on (no new
/// scale).
template <typename Scalar>
struct SlamRelocOptions {
  bool enabled = true;
  int keyframes = 10;
  int spacing = 15;
  /// Besides those (the most recent), up to `anchors` ANCHOR keyframes of the segment are kept:
  /// a keyframe becomes one when no anchor looks within anchorDeg of its direction from within
  /// anchorDepths median scene depths of its position. A head that stays in place (looking
  /// around, fast turns, working at a table) keeps a view of every direction it mapped, however
  /// long ago, for relocalisation and for the revisit search; walking, the oldest anchor goes.
  int anchors = 8;
  Scalar anchorDeg = Scalar(20);
  Scalar anchorDepths = Scalar(0.3);
  int maxPoints = 300;
  Scalar maxShiftPx = Scalar(40);
  int minInliers = 30;
  Scalar maxRotationDeg = Scalar(0.6);  ///< relocalised vs the rays' rotation, at most
  /// After the reset, also by place recognition into any segment's map (needs place.enabled;
  /// mono_slam/place_links.hpp relocaliseByPlace): a lost place re-entered joins its old map.
  bool byPlace = true;
  /// Its two consecutive poses vs the rays' rotation between them, at most (the rays' pure-rotation
  /// fit absorbs the step's translation: up to 1° a frame walking; the matches are descriptors',
  /// not searched around a guess, so a wrong pair is not pulled towards agreement).
  Scalar placeAgreeDeg = Scalar(2);

  /// Throws hawor::Error naming the first bad field.
  void validate() const {
    if (keyframes < 0 || spacing < 1 || anchors < 0) throw Error("reloc.keyframes and reloc.anchors must be >= 0, reloc.spacing >= 1");
    if (maxPoints < 1 || minInliers < 6) throw Error("reloc.maxPoints must be >= 1, reloc.minInliers >= 6");
    if (!(anchorDeg > Scalar(0)) || !(anchorDepths >= Scalar(0)) || !(maxShiftPx > Scalar(0)) || !(maxRotationDeg >= Scalar(0)) ||
        !(placeAgreeDeg >= Scalar(0))) {
      throw Error("reloc.anchorDeg and reloc.maxShiftPx must be > 0, reloc.anchorDepths, reloc.maxRotationDeg and reloc.placeAgreeDeg >= 0");
    }
  }
};

/// At each keyframe, the kept keyframes (relocalisation's) that saw the current view a while ago
/// searched under the current pose (mono_slam/relocalisation.hpp searchRevisits): their points
/// become tracks of those old points when a PnP on them alone agrees with the tracked pose.
template <typename Scalar>
struct SlamRevisitOptions {
  bool enabled = true;              ///< needs reloc.enabled (its kept keyframes)
  int minFrames = 30;               ///< a kept keyframe this many frames old, at least
  Scalar maxAngleDeg = Scalar(30);  ///< between its viewing direction and the current one
  Scalar maxShiftPx = Scalar(20);   ///< found this close to the projection
  int maxPoints = 200;
  int minInliers = 20;
  Scalar maxRotationDeg = Scalar(2);  ///< PnP on the found points vs the tracked pose

  /// Throws hawor::Error naming the first bad field.
  void validate() const {
    if (minFrames < 0 || maxPoints < 1 || minInliers < 6) throw Error("revisit.minFrames must be >= 0, revisit.maxPoints >= 1, revisit.minInliers >= 6");
    if (!(maxAngleDeg > Scalar(0)) || !(maxShiftPx > Scalar(0)) || !(maxRotationDeg >= Scalar(0))) {
      throw Error("revisit.maxAngleDeg and revisit.maxShiftPx must be > 0, revisit.maxRotationDeg >= 0");
    }
  }
};

/// Segment links across a break of the rotation chain (a turn onto a bare wall: no frame gives
/// its rotation, so the next segment's world is rotated by the unseen turn;
/// mono_slam/relocalisation.hpp). The lost segment's kept images (relocalisation's, and its last
/// keyframe's) stay; at each keyframe after the break, and on every everyFrames-th frame without
/// a map pose, each is tried as the place: its points are searched by KLT around where it saw
/// them (guesses: its own view, and turned about its vertical axis), and PnP-RANSAC gives the
/// frame's pose in the old world (a link). finish() rotates the frames after the break (and
/// everything after them) by C = R_old·Rᵀ when two links agree; the joins then place and scale
/// them.
template <typename Scalar>
struct SlamLinkOptions {
  bool enabled = true;
  Scalar maxShiftPx = Scalar(80);  ///< found this close to where the kept keyframe saw it
  int maxPoints = 200;             ///< KLT attempts per kept keyframe
  int minInliers = 20;
  int yawSteps = 2;                ///< guesses turned by ±1..yawSteps steps besides the view itself
  Scalar yawStepDeg = Scalar(12);
  int everyFrames = 3;             ///< frames without a map pose searched (keyframes: each)
  int enough = 6;                  ///< links of a chain after which the search stops
  Scalar agreeDeg = Scalar(2);     ///< two links' rotations agree within this

  /// Throws hawor::Error naming the first bad field.
  void validate() const {
    if (maxPoints < 1 || minInliers < 6 || yawSteps < 0 || everyFrames < 1 || enough < 2) {
      throw Error("link.maxPoints must be >= 1, link.minInliers >= 6, link.yawSteps >= 0, link.everyFrames >= 1, link.enough >= 2");
    }
    if (!(maxShiftPx > Scalar(0)) || !(yawStepDeg > Scalar(0)) || !(agreeDeg >= Scalar(0))) {
      throw Error("link.maxShiftPx and link.yawStepDeg must be > 0, link.agreeDeg >= 0");
    }
  }
};

/// Segments joined by the head model in finish() (mono_slam/segment_joins.hpp, head_motion.hpp).
struct SlamJoinOptions {
  /// A segment joined to the one before it by one head model fitted to both (fitHeadJoin: scale
  /// and offset), where it explains them.
  bool headModel = true;
  /// After the sequence refinement: every segment with headModel.minFrames posed frames and its
  /// views spread over headModel.minSpreadDeg re-joined at once by one head model fitted to all
  /// of them (fitHeadJoinAll), where it passes the head tests. The pairwise joins above run
  /// before the bundle adjustments, on positions too noisy for the motion test; a segment left
  /// out (too short) keeps its join to the one before.
  bool headModelAll = true;
  /// With headModelAll: the same join also before the sequence refinement, on the global bundle
  /// adjustment's poses (short segments keep their frames: the refinement may pose more of
  /// them). Segments joined in one scale let the refinement's head prior pass its tests and its
  /// tracks across a reset start consistent (fast_turns seed 6 masked: 1.42 → 0.45 %).
  bool beforeRefine = true;
  /// With headModelAll's model accepted: the posed frames of a segment it left out (too few
  /// frames or views to fix its scale) are placed by the head model like lost frames (status
  /// Interpolated); their keyframe depths (empty) and points are left out of the result.
  bool placeShort = true;

  /// Throws hawor::Error naming the first bad combination.
  void validate() const {
    if ((beforeRefine || placeShort) && !headModelAll) throw Error("join.beforeRefine and join.placeShort need join.headModelAll");
  }
};

/// The passes over the whole sequence in finish() (mono_slam/finish.hpp).
template <typename Scalar>
struct SlamFinishOptions {
  bool globalBundleAdjustment = true;  ///< every keyframe and point, per segment
  /// Above maxAdjustedKeyframes keyframes, the global bundle adjustment leaves out redundant
  /// ones, newest first, until that many are left: a keyframe at least redundantShare of whose
  /// map points are seen by 3 other keyframes it keeps (keyframe culling, Mur-Artal et al. 2015
  /// §VI-E). A clip that revisits one place for minutes adds keyframes that see only old points
  /// (10 minutes of a kitchen: 3,388 keyframes, the adjustment 94 s; 48 s with 2,309 of them).
  /// Below the budget every keyframe is adjusted: the redundant ones still add constraints (left
  /// out on the clean synthetic seeds, the geometric mean ATE rose 0.261 -> 0.287 %). The
  /// left-out keyframes move with the kept ones like any frame. redundantShare > 1: every
  /// keyframe.
  int maxAdjustedKeyframes = 500;
  Scalar redundantShare = Scalar(0.9);
  bool refineFrames = true;            ///< every frame re-estimated against the final map
  /// Full-sequence bundle adjustment of every frame over every track (sequence_refine.hpp),
  /// tracks joined across resets, relocalisations and place links.
  bool sequenceRefine = true;
  /// Frames without a map pose placed by the head model fitted to the posed frames around them
  /// (head_motion.hpp), where it explains them; otherwise held / interpolated.
  bool headModelFill = true;
  /// Self-calibrate the shared focal (fx, fy by one factor, principal point fixed) in the global
  /// bundle adjustment (focal_refine.hpp: profile of the BA cost over log f, a prior toward the
  /// given focal, declined when the motion does not determine it); the per-frame refinement then
  /// uses the refined focal. With sequenceRefine, on the sequence refinement's problem instead
  /// (refineFocalOnSequence), which is refined again with a changed focal. Off by default (the
  /// tracking used the given focal).
  bool refineFocal = false;
  int focalMaxFrames = 60;  ///< frames of the sequence refinement's problem in the focal profile
  /// ...taken at least this many posed frames apart: a track's errors in consecutive frames are
  /// correlated (KLT drift), which the profile's std (independent residuals) does not know; on
  /// every frame the std comes out ~5x too small and a right guess is moved by 2-3 %.
  int focalFrameSpacing = 5;
  /// ...and the std of its estimate is taken as this at least (FocalRefineOptions::minStdLog): a
  /// guess within ~2 × this of the estimate is kept.
  Scalar focalMinStd = Scalar(0.02);

  /// Throws hawor::Error naming the first bad field.
  void validate() const {
    if (focalMaxFrames < 3 || focalFrameSpacing < 1) throw Error("finish.focalMaxFrames must be >= 3, finish.focalFrameSpacing >= 1");
    if (!(focalMinStd >= Scalar(0))) throw Error("finish.focalMinStd must be >= 0");
    if (!(redundantShare > Scalar(0)) || maxAdjustedKeyframes < 2) {
      throw Error("finish.redundantShare must be > 0 and finish.maxAdjustedKeyframes >= 2");
    }
  }
};

template <typename Scalar>
struct SlamOptions {
  /// The video's frame rate. The frame counts and the per-frame angles among these options are
  /// stated for 30 fps, where they were measured; MonoSlam applies them at this rate
  /// (atFrameRate), so that at 60 fps a loss, a keyframe gap or a search window spans the same
  /// time and head motion as at 30 (synthetic presets rendered at 60 fps, seeds 1-8: geometric
  /// mean ATE 0.43 → 0.38 % of the path, hands_cover 0.74 → 0.49, fast_turns 1.86 → 1.50).
  Scalar fps = Scalar(30);
  /// Track every frameStep-th frame and interpolate the frames between (frame_step.hpp); 0: the
  /// largest step that keeps the tracked rate at or above 25 fps (autoFrameStep; 60 fps → 2).
  /// The counts, angles and the rolling shutter's fraction below are then those of the tracked
  /// rate, fps / frameStep. Measured on the synthetic presets rendered at 60 fps (seeds 1-8,
  /// docs/benchmarks.md "Frame rate").
  int frameStep = 0;
  int pyramidLevels = 4;
  KltOptions klt;
  CornerOptions corners;
  int maxFeatures = 350;            ///< live tracks after replenishing at a keyframe
  /// Rolling shutter: the readout time from the first row to the last as a fraction of the frame
  /// interval (readout seconds × fps; a phone's CMOS at 30 fps: 0.45–0.9; 0: a global shutter;
  /// negative: the rows were read bottom to top, as in a clip played backwards).
  /// Row v is exposed (v − (H−1)/2)/H · readout frames after the middle row; each tracked point
  /// is brought to the middle row's time, b ← exp(δω)·b, with ω the last frame's rotation fitted
  /// to the raw pixels (rsRate), before any geometry uses it; KLT keeps the raw pixels. The
  /// translation during the readout is neglected (docs/design.md §11).
  Scalar rollingShutter = Scalar(0);
  bool useMasks = true;             ///< dual hand masking (false: masks are ignored, the ablation)
  int maskDilatePx = 6;             ///< front-end dilation of the hand mask
  int maskBlock = 4;                ///< keyframe mask resolution (pixels per bit)
  // Initialisation.
  TwoViewOptions<Scalar> twoView;
  SlamInitOptions<Scalar> init;     ///< when and from which pair a map segment starts
  // Tracking.
  PnPRansacOptions<Scalar> pnp;
  int minInliers = 25;
  SlamTurnOptions<Scalar> turn;     ///< fast head turns: turn mode, its tracking, the bridge, coasting
  TurnBridgeOptions<Scalar> bridge;
  int lostFramesBeforeReset = 4;
  /// When a frame is posed after a loss (a new map, or the old map found again), the mapped tracks are followed back by KLT through the images of
  /// up to this many of those frames (followTracksBack), so that finish() resects them against
  /// the map instead of interpolating them; 0: off. A global shutter only (rollingShutter 0):
  /// the frames keep the geometry's positions, which are the pixels only then. Memory: this many
  /// image pyramids while the camera is lost (about 1.2 MB each at 640 × 360). Not before the
  /// first map (posing those frames from it measured worse: docs/experiments.md).
  int backTrackFrames = 20;
  /// A map just built from a pair of frames poses frames before the pair's reference by
  /// extrapolating its baseline: the walk back stops this many times the pair's frame gap before
  /// the reference (unbounded, a fast_turns run went 0.36 → 0.51 %).
  int backTrackBaselines = 2;
  /// Before a map, tracks more than this far off the frame's rotation from the rays are dropped
  /// (dropJumpedTracks); 0: off. Measured on fast_turns seeds 1-8 (bench_slam, masked /
  /// unmasked ATE sums, 300 frames and the first 100): 5° 21.3 / 19.0 and 39.9 / 29.2, 6° 22.7 /
  /// 19.9 and 29.1 / 17.9, 8° 30.1 / 18.6 and 38.4 / 41.6, off 29.6 / 22.4 and 38.4 / 38.9. Near
  /// points in a 15°-a-frame turn (the eye 2 cm a frame about the neck) move 4-5° off the rays'
  /// rotation, and a lower bound drops them.
  Scalar maxRayJumpDeg = Scalar(6);
  // Relocalisation, revisits and place recognition.
  SlamRelocOptions<Scalar> reloc;     ///< back into the lost map after a tracking loss
  SlamRevisitOptions<Scalar> revisit; ///< old points of this segment found again at keyframes
  SlamLinkOptions<Scalar> link;       ///< segment links across a broken rotation chain
  SlamPlaceOptions<Scalar> place;   ///< place recognition between keyframes, segments joined by it
  // Keyframes and mapping.
  KeyframePolicyOptions<Scalar> keyframe;  ///< when a tracked frame becomes one (keyframe_policy.hpp)
  Scalar minTriangulationDeg = Scalar(0.6);
  Scalar maxReprojPx = Scalar(3);
  int windowKeyframes = 7;
  int localIterations = 8;
  int globalIterations = 25;
  // finish().
  SlamFinishOptions<Scalar> finish;  ///< the passes over the whole sequence
  SlamJoinOptions join;              ///< segments joined by the head model
  SequenceRefineOptions<Scalar> sequence;
  HeadModelOptions<Scalar> headModel;
  FocalRefineOptions<Scalar> focal;
  /// Optional diagnostics sink (one line per event: initialisation attempts, losses, resets).
  std::function<void(const std::string&)> log;

  /// Throws hawor::Error naming the first bad field or combination.
  void validate() const {
    if (!(fps > Scalar(0)) || !(fps <= Scalar(1000))) throw Error("fps must be in (0, 1000]");
    if (frameStep < 0 || frameStep > 100) throw Error("frameStep must be in [0, 100] (0: automatic)");
    if (pyramidLevels < 1 || maxFeatures < 20 || windowKeyframes < 2 || minInliers < 6 || lostFramesBeforeReset < 1) {
      throw Error("pyramidLevels must be >= 1, maxFeatures >= 20, windowKeyframes >= 2, minInliers >= 6, lostFramesBeforeReset >= 1");
    }
    if (maskDilatePx < 0 || maskBlock < 1) throw Error("maskDilatePx must be >= 0, maskBlock >= 1");
    if (backTrackFrames < 0 || backTrackFrames > 300) throw Error("backTrackFrames must be in 0..300");
    if (backTrackBaselines < 0) throw Error("backTrackBaselines must be >= 0");
    if (!(std::abs(rollingShutter) <= Scalar(1))) throw Error("rollingShutter must be in [-1, 1]");
    init.validate();
    turn.validate();
    keyframe.validate();
    reloc.validate();
    revisit.validate();
    link.validate();
    place.validate();
    finish.validate();
    join.validate();
    if (revisit.enabled && !reloc.enabled) throw Error("revisit.enabled needs reloc.enabled (the revisit search uses its kept keyframes)");
    if (reloc.byPlace && !place.enabled) throw Error("reloc.byPlace needs place.enabled (it asks the place index)");
  }

  /// These options at `fps`: above 30 fps every frame count × fps/30 (rounded) and the per-frame
  /// angles that bound the head's motion × 30/fps; at 30 fps and below unchanged. A count bounds
  /// both a time and the frames of evidence (views for a fit, frames lost before a reset):
  /// above 30 fps the time binds, below it the evidence does (scaled down at 15 fps, the synthetic
  /// presets' runs within 1 % went 20 → 18 of 32 and the kitchen clip's 15-fps copy 0.46 → 2.01 %).
  /// With a frame step k (frameStep, or automatic) they are first those of the tracked frames:
  /// fps / k, and the rolling shutter's readout a k-th of their interval. MonoSlam applies this
  /// once; the result's frameStep is resolved.
  SlamOptions atFrameRate() const {
    if (!(fps > Scalar(0)) || !(fps <= Scalar(1000))) throw Error("fps must be in (0, 1000]");
    if (frameStep < 0 || frameStep > 100) throw Error("frameStep must be in [0, 100] (0: automatic)");
    SlamOptions o = *this;
    o.frameStep = frameStep > 0 ? frameStep : autoFrameStep(double(fps));
    o.fps = fps / Scalar(o.frameStep);
    o.rollingShutter = rollingShutter / Scalar(o.frameStep);
    const double k = std::max(1.0, double(o.fps) / 30.0);
    if (k == 1.0) return o;
    auto frames = [k](int& n) { n = n <= 0 ? n : std::max(1, static_cast<int>(std::lround(n * k))); };
    auto perFrame = [k](Scalar& deg) { deg = Scalar(double(deg) / k); };
    for (int* n : {&o.init.everyFrames, &o.init.maxGap, &o.turn.holdFrames, &o.turn.maxBridgeFrames, &o.turn.coastFrames,
                   &o.place.minFramesApart, &o.reloc.spacing, &o.revisit.minFrames, &o.link.everyFrames,
                   &o.finish.focalFrameSpacing, &o.lostFramesBeforeReset, &o.keyframe.maxInterval, &o.keyframe.minInterval,
                   &o.keyframe.thinInterval, &o.headModel.window, &o.headModel.minFrames, &o.headModel.lag,
                   &o.sequence.headModel.window, &o.sequence.headModel.minFrames, &o.sequence.headModel.lag,
                   &o.backTrackFrames}) {
      frames(*n);
    }
    o.backTrackFrames = std::min(300, o.backTrackFrames);  // the memory bound validate() keeps
    // turn.rateDeg stays a frame's: turn mode is about the image motion between two frames,
    // which KLT and the map's tracking must bridge (60 fps, fast_turns seeds 1-4: median 5.0 %
    // scaled, 2.5 % not)
    for (Scalar* deg : {&o.turn.coastMaxStepDeg, &o.bridge.minStepDeg, &o.maxRayJumpDeg}) perFrame(*deg);
    return o;
  }

  SlamOptions() {
    pnp.thresholdPx = Scalar(3);
    pnp.maxIterations = 200;
    pnp.refinement.maxIterations = 6;
    twoView.maxIterations = 300;
  }
};

}  // namespace hawor
