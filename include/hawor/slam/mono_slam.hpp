// hawor/slam/mono_slam.hpp — sparse monocular SLAM with dual hand masking (docs/design.md §5): the
// camera trajectory of the method, CPU- and WASM-friendly in place of DROID-SLAM.
//
// Per frame (process):
//   1. Gaussian pyramid of the grey image (image_pyramid.hpp); the hand mask, dilated
//      (hand_mask.hpp).
//   2. Pyramidal KLT of every live track from the previous frame (klt.hpp), started at the
//      projection of its map point under a constant-velocity pose prediction, the other tracks
//      at the mean shift of those guesses. FRONT-END MASKING: a track that lands on the dilated
//      hand mask is dropped, and no corner is ever detected there (corners.hpp).
//      TURN MODE: while the rotation exceeds turnRateDeg a frame (a fast head turn: up to
//      20° ≈ 140 px a frame; looking around and walking stay below 3.5°), every track is also
//      started at its ray rotated by a constant-angular-velocity prediction (the infinite
//      homography), the rotation coming from the map or, without a map pose, from the rays.
//      ROLLING SHUTTER (rollingShutter ≠ 0): the tracked pixels stay raw for KLT; the geometry
//      sees them moved to the middle row's time under the last frame's raw-pixel rotation.
//   3. Before a map exists: two-view initialisation (two_view.hpp: E or H by GRIC, RANSAC)
//      between a reference frame and the current one once the median flow is large enough; the
//      reference is the oldest of the last initMaxGap frames sharing initMinTracks tracks (their
//      observations are kept per frame; new corners join whenever the tracks thin out, so that a
//      recent reference exists while hands sweep the old tracks away); in turn mode the pair is
//      also tried after
//      initMinRotationDeg of rotation (the rays' rotation absorbs most of the parallax of the
//      neck's sideways translation, so the compensated flow understates it). The rotation of
//      not-yet-initialised frames comes from the tracked rays (Kabsch, pure-rotation
//      hypothesis) with the position held; a track more than maxRayJumpDeg off that rotation
//      jumped (KLT locked onto a weak texture off the true match at a turn's onset) and is
//      dropped, and a two-view whose best motion puts fewer than minInFrontRatio of its inliers
//      in front of both cameras is refused (two_view.hpp).
//      With a map: RE-FINDING first (optional, off by default) while fewer than refindBelow map
//      points are tracked: the points of the last refindKeyframes keyframes (their pyramids are
//      kept) that no track follows are projected under the predicted pose and searched by KLT
//      from the keyframe's image (a point covered by a hand, or out of view in a turn, comes
//      back as the same map point instead of a new unmapped corner). Then the pose by P3P-RANSAC + robust LM on the
//      tracks' map points (pnp_ransac.hpp);
//      in turn mode a pose from as few as minTurnInliers points is accepted when its rotation
//      agrees with the rays' (the map leaves the view faster than new points are made); when
//      even that fails right after two posed frames, the TURN BRIDGE (turn_bridge.hpp, turnBridge)
//      poses the frame from the last one: the step's direction from a head sphere (Δc ∝ Δz),
//      the rotation from the tracks' epipolar geometry, the length from the map points still
//      tracked and the tracks triangulated from the two posed frames; the frame becomes a
//      keyframe, so the tracks born in the turn are triangulated and the map goes on.
//   4. Keyframes when the tracked map points fall below a fraction of the last keyframe's, below
//      an absolute count, after a maximum interval, or in turn mode after keyframeMaxRotationDeg
//      of rotation (new corners only come at keyframes). REVISITS first (revisitSearch, on): the
//      points of kept keyframes (relocalisation's) of this segment that looked at the current view
//      a while ago are searched under the current pose, and kept as tracks of those old points when
//      a PnP on them alone agrees with the tracked pose (the head looks back at a place: the
//      bundle adjustments tie the map to its older part instead of letting the scale drift).
//      At a keyframe: new points are triangulated
//      from tracks seen in two keyframes with enough parallax (triangulation.hpp), a
//      sliding-window bundle adjustment runs (bundle_adjustment.hpp: LM, Schur complement,
//      Huber loss) and new corners fill the empty cells of the bucketing grid.
//      BACK-END MASKING: a bundle-adjustment residual whose measured pixel or current projection
//      lands on the keyframe's hand mask gets weight 0.
//   5. Tracking loss (too few PnP inliers): RELOCALISATION first (relocalise, on by default):
//      the map points of a few kept keyframes (relocKeyframes, relocSpacing frames apart) are
//      projected under the frame's guess (rotation from the tracked rays, position held) and
//      searched by KLT from those keyframes' images; PnP-RANSAC on them, its rotation checked
//      against the rays' (or, where the ray chain disagrees, two consecutive relocalisations
//      against the rays' rotation between them), puts the frame back into the map it lost (a hand that covered the view
//      moves away, a turn comes back), with no new scale. This is tried on every lost frame and,
//      after the reset below, until a new map is built.
//      Otherwise the frame is Lost, its rotation still follows the
//      tracked rays; after lostFramesBeforeReset lost frames the system re-initialises a new map
//      segment from the current frame and joins it to the old world: with joinOldMap (off by
//      default) and when enough of the new two-view points were tracks seen by the old
//      segment's keyframes, by the similarity that puts them on their old rays
//      (similarity_join.hpp; its scale must be observable), and the new keyframes continue the
//      old segment (those points keep their old observations, so the
//      bundle adjustments tie both); otherwise at the frame where tracking was lost: rotation from
//      the ray chain, position from the last estimate, scale so that the median scene depth is
//      continuous across the join. A segment that later sees the old map again is not merged
//      with it; but when the rotation chain to the old segment is broken (frames with no
//      rotation, or one only carried on), the old segment's kept images are searched for the
//      current view (PLACE RECOGNITION, segmentLinks) and the poses found in the old world fix
//      the rotation of everything after the break in finish().
// finish(): the rotation chains after a break turned by their agreeing segment links, segments
// re-scaled by the head's turn radius (turn_scale.hpp), a global bundle
// adjustment over all keyframes and points (per segment: first keyframe fixed, a scale prior on
// its first baseline), every frame's pose re-estimated against the final map from its stored 2D
// observations (RANSAC for frames without a tracked pose, robust LM otherwise); then the
// SEQUENCE REFINEMENT (sequence_refine.hpp, sequenceRefine, on): every frame's observations of
// every track (a track renamed at a reset, and tracks that follow one map point, joined) in one
// bundle adjustment, frames with a guessed position resected, ill-conditioned frames left out;
// frames that still have no pose get their position from the HEAD MODEL fitted to the posed
// frames around them where it explains them (head_motion.hpp: c = n + M·z, the eye in front of
// the neck), else interpolated between their neighbours.
// Output frame: camera-to-world poses (docs/design.md §2) with the world = the first frame's camera,
// monocular scale (the first baseline is 1 in the map's units); per-keyframe sparse depths
// (pixel, depth along the optical axis, unmasked points only) for the metric-scale step (docs/design.md §6).
// Memory per frame: the pyramid of two frames, plus the frame's track observations (≈ 12 bytes
// a track) and, per keyframe, a 1/4-resolution mask bitmap (also for the two-view reference and
// the last initMaxGap frames while no map exists); with re-finding on, the pyramids of the last
// refindKeyframes keyframes and, for relocalisation, of relocKeyframes recent and up to
// relocAnchors anchor keyframes (about 1.6 MB each at 640×480), and of the last keyframe; after
// a broken rotation chain, until its links are found, the lost segment's too (segmentLinks); no
// other images. finish() first
// lets every image go, then holds every frame's observations twice more (≈ 24 bytes an
// observation as the sequence refinement's input, 12 grouped by track inside it) and the
// adjustment of at most sequence.maxAdjustedFrames frames.
// Not thread-safe; one instance per video.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/interpolate.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/render/image.hpp"
#include "hawor/slam/bundle_adjustment.hpp"
#include "hawor/slam/corners.hpp"
#include "hawor/slam/focal_refine.hpp"
#include "hawor/slam/hand_mask.hpp"
#include "hawor/slam/head_motion.hpp"
#include "hawor/slam/image_pyramid.hpp"
#include "hawor/slam/klt.hpp"
#include "hawor/slam/pnp_ransac.hpp"
#include "hawor/slam/sequence_refine.hpp"
#include "hawor/slam/similarity_join.hpp"
#include "hawor/slam/triangulation.hpp"
#include "hawor/slam/turn_bridge.hpp"
#include "hawor/slam/turn_scale.hpp"
#include "hawor/slam/two_view.hpp"

namespace hawor {

/// Per-frame status of the SLAM output.
enum class SlamStatus : int {
  Tracked = 0,       ///< pose from the frame's features against the map
  Interpolated = 1,  ///< no map pose: rotation from the tracked rays or interpolation, position held/interpolated
  Lost = 2,          ///< tracking was lost here; the pose is interpolated between good frames
  Relocalised = 3,   ///< put back into the lost map (relocalisation), or the first frame of a re-initialised segment
};

inline const char* slamStatusName(SlamStatus s) {
  switch (s) {
    case SlamStatus::Tracked: return "tracked";
    case SlamStatus::Interpolated: return "interpolated";
    case SlamStatus::Lost: return "lost";
    case SlamStatus::Relocalised: return "relocalised";
  }
  return "unknown";
}

template <typename Scalar>
struct SlamOptions {
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
  Scalar initMinFlowPx = Scalar(4);   ///< median rotation-compensated flow before trying
  int initEveryFrames = 3;            ///< frames between two-view attempts
  int initMinTracks = 60;
  int reinitMinTracks = 60;           ///< initMinTracks after a tracking loss (40 measured: no gain)
  int initMaxGap = 60;                ///< the two-view reference is one of the last this many frames
  Scalar initMinRotationDeg = Scalar(8);  ///< in turn mode: try after this much rotation (every other frame)
  // Tracking.
  PnPRansacOptions<Scalar> pnp;
  int minInliers = 25;
  // Turn mode (fast head turns).
  Scalar turnRateDeg = Scalar(5);     ///< rotation a frame that starts turn mode (walking: < 3.5)
  int turnHoldFrames = 5;             ///< frames it lasts after the last such increment
  int minTurnInliers = 10;                       ///< PnP inliers enough when the rays agree (turns)
  Scalar turnRotationAgreementDeg = Scalar(1);   ///< PnP vs tracked-ray rotation, for that
  bool fewPointsRayCheck = false;  ///< the same outside turn mode (measured: no gain on hands_cover)
  /// Turn bridge (turn_bridge.hpp): in turn mode, a frame whose PnP fails right after two posed
  /// frames is posed from the last one and the tracks between them (the step's direction from a
  /// head sphere, the rotation from the tracks' epipolar geometry, the length from the map points
  /// still tracked and the tracks triangulated from the two posed frames), at most
  /// maxBridgeFrames in a row; it becomes a keyframe, so the tracks born in the turn are
  /// triangulated and the map goes on instead of being reset.
  bool turnBridge = true;
  int maxBridgeFrames = 12;
  Scalar bridgeMinParallaxDeg = Scalar(0.2);  ///< of a track triangulated from the two posed frames
  TurnBridgeOptions<Scalar> bridge;
  int lostFramesBeforeReset = 4;
  /// In turn mode, a frame whose tracked rays give no rotation turns on at the last step's
  /// angular velocity (coastRotation), for at most coastFrames frames in a row, from a step of at
  /// most coastMaxStepDeg (a head peaks near 600°/s, 20° a frame at 30 fps); 0: held instead.
  int coastFrames = 6;
  Scalar coastMaxStepDeg = Scalar(20);
  /// Before a map, tracks more than this far off the frame's rotation from the rays are dropped
  /// (dropJumpedTracks); 0: off. Measured on fast_turns seeds 1-8 (bench_slam, masked /
  /// unmasked ATE sums, 300 frames and the first 100): 5° 21.3 / 19.0 and 39.9 / 29.2, 6° 22.7 /
  /// 19.9 and 29.1 / 17.9, 8° 30.1 / 18.6 and 38.4 / 41.6, off 29.6 / 22.4 and 38.4 / 38.9. Near
  /// points in a 15°-a-frame turn (the eye 2 cm a frame about the neck) move 4-5° off the rays'
  /// rotation, and a lower bound drops them.
  Scalar maxRayJumpDeg = Scalar(6);
  // Re-finding map points that left the tracks (covered by a hand, out of view and back).
  /// Recent keyframes whose pyramids are kept for it; 0 (default): off. Measured with 5
  /// (bench_slam, seeds 1-2, masked, an earlier joinOldMap on): no preset consistently better
  /// (table_work seed 1 0.15 -> 0.13 %, seed 2 1.06 -> 1.42 %; hands_cover unchanged;
  /// fast_turns seed 1 2.7 -> 4.6 %, seed 2 5.8 -> 4.6 %).
  int refindKeyframes = 0;
  int refindBelow = 150;             ///< tried while fewer map points than this are tracked
  int refindMaxPoints = 200;         ///< KLT attempts a frame, at most
  Scalar refindMaxShiftPx = Scalar(6);  ///< found this close to the point's predicted projection
  // Re-joining a re-initialised map to the old one (see joinToOldMap). Off by default: measured
  // (bench_slam, seeds 1-2, masked/unmasked) it joins table_work seed 2 (masked 1.76 -> 1.33 %)
  // but makes the unmasked runs worse (table_work seed 2 1.70 -> 2.89 %, hands_cover seed 1
  // 2.90 -> 5.79 %), and in fast_turns the old keyframes at the start of a turn agree with no
  // similarity (their poses are already off), so it never joins there.
  bool joinOldMap = false;
  /// finish(): re-scale each re-initialised segment so that the eye's turn radius about the neck
  /// (turn_scale.hpp) matches the segment before it, when both segments have turns that follow
  /// the neck model (≥ turnScaleMinWindows windows, relative spread ≤ turnScaleMaxSpread). The
  /// reset's scale from the median scene depth is off when the head turns to a nearer or farther
  /// view (fast_turns seed 1: by 1.45×).
  bool turnScaleJoin = true;
  /// finish(), before the turn-radius join: a segment joined to the one before it by one head
  /// model fitted to both (head_motion.hpp fitHeadJoin: scale and offset), where it explains them.
  bool headModelJoin = true;
  /// finish(), after the sequence refinement: every segment with headModel.minFrames posed
  /// frames and its views spread over headModel.minSpreadDeg re-joined at once by one head model
  /// fitted to all of them (fitHeadJoinAll), where it passes the head tests. The pairwise joins
  /// above run before the bundle adjustments, on positions too noisy for the motion test; a
  /// segment left out (too short) keeps its join to the one before.
  bool headModelJoinAll = true;
  /// With headModelJoinAll: the same join also before the sequence refinement, on the global
  /// bundle adjustment's poses (short segments keep their frames: the refinement may pose more
  /// of them). Segments joined in one scale let the refinement's head prior pass its tests and
  /// its tracks across a reset start consistent (fast_turns seed 6 masked: 1.42 → 0.45 %).
  bool headModelJoinBeforeRefine = true;
  /// With headModelJoinAll's model accepted: the posed frames of a segment it left out (too few
  /// frames or views to fix its scale) are placed by the head model like lost frames (status
  /// Interpolated); their keyframe depths (empty) and points are left out of the result.
  bool headModelPlaceShort = true;
  int turnScaleLag = 3;                       ///< frames per window
  Scalar turnScaleMinAngleDeg = Scalar(3);    ///< a window's turn, at least
  int turnScaleMinWindows = 8;
  Scalar turnScaleMaxSpread = Scalar(0.35);
  // Relocalisation after a tracking loss, against the lost segment's map (on by default): the
  // pyramids of up to relocKeyframes keyframes at least relocSpacing frames apart are kept
  // (about 1.6 MB each at 640×480); while tracking is lost, and after the reset until a new map
  // is built, their points are projected under the frame's guess (rotation from the tracked rays,
  // position held) and searched by KLT from the keyframe images (within relocMaxShiftPx: the
  // held position is off by the motion since the loss); PnP-RANSAC with relocMinInliers inliers
  // puts the frame back in the old map, and the old segment goes on (no new scale).
  bool relocalise = true;
  /// Two-view initialisation: every second frame between the reference and the current one as
  /// further views that settle a two-fold ambiguity (a planar scene's homography; two_view.hpp).
  bool twoViewThirdView = true;
  /// At each keyframe, search the kept keyframes (relocalise's) that saw the current view a while
  /// ago (searchRevisits); needs relocalise.
  bool revisitSearch = true;
  int revisitMinFrames = 30;                ///< a kept keyframe this many frames old, at least
  Scalar revisitMaxAngleDeg = Scalar(30);   ///< between its viewing direction and the current one
  Scalar revisitMaxShiftPx = Scalar(20);    ///< found this close to the projection
  int revisitMaxPoints = 200;
  int revisitMinInliers = 20;
  Scalar revisitMaxRotationDeg = Scalar(2); ///< PnP on the found points vs the tracked pose
  int relocKeyframes = 10;
  int relocSpacing = 15;
  // Place recognition across a break of the rotation chain (a turn onto a bare wall: no frame
  // gives its rotation, so the next segment's world is rotated by the unseen turn). The lost
  // segment's kept images (relocalise's, and its last keyframe's) stay; at each keyframe after
  // the break, and on every linkEveryFrames-th frame without a map pose, each is tried as the
  // place: its points are searched by KLT around where it saw them (guesses: its own view, and
  // turned about its vertical axis), and PnP-RANSAC gives the frame's pose in the old world (a
  // link). finish() rotates the frames after the break (and everything after them) by
  // C = R_old·Rᵀ when two links agree; the joins then place and scale them.
  bool segmentLinks = true;
  Scalar linkMaxShiftPx = Scalar(80);   ///< found this close to where the kept keyframe saw it
  int linkMaxPoints = 200;              ///< KLT attempts per kept keyframe
  int linkMinInliers = 20;
  int linkYawSteps = 2;                 ///< guesses turned by ±1..linkYawSteps steps besides the view itself
  Scalar linkYawStepDeg = Scalar(12);
  int linkEveryFrames = 3;              ///< frames without a map pose searched (keyframes: each)
  int linkEnough = 6;                   ///< links of a chain after which the search stops
  Scalar linkAgreeDeg = Scalar(2);      ///< two links' rotations agree within this
  // Besides those (the most recent), up to relocAnchors ANCHOR keyframes of the segment are kept:
  // a keyframe becomes one when no anchor looks within relocAnchorDeg of its direction from within
  // relocAnchorDepths median scene depths of its position. A head that stays in place (looking
  // around, fast turns, working at a table) keeps a view of every direction it mapped, however
  // long ago, for relocalisation and for the revisit search; walking, the oldest anchor goes.
  int relocAnchors = 8;
  Scalar relocAnchorDeg = Scalar(20);
  Scalar relocAnchorDepths = Scalar(0.3);
  int relocMaxPoints = 300;
  Scalar relocMaxShiftPx = Scalar(40);
  int relocMinInliers = 30;
  Scalar relocMaxRotationDeg = Scalar(0.6);  ///< relocalised vs the rays' rotation, at most
  int joinMinTracks = 12;                 ///< tracks with old observations agreeing with the join
  Scalar joinMaxScaleStd = Scalar(0.05);  ///< relative standard deviation of its scale, at most
  // Keyframes and mapping.
  Scalar keyframeInlierRatio = Scalar(0.7);
  int keyframeMinInliers = 60;
  int keyframeMaxInterval = 10;
  int keyframeMinInterval = 3;
  int keyframeThinInterval = 1;   ///< frames between keyframes while fewer than 2·minInliers are mapped (2: mixed)
  Scalar keyframeMaxRotationDeg = Scalar(12);  ///< a keyframe after this much rotation (head turns)
  Scalar minTriangulationDeg = Scalar(0.6);
  Scalar maxReprojPx = Scalar(3);
  int windowKeyframes = 7;
  int localIterations = 8;
  int globalIterations = 25;
  bool globalBundleAdjustment = true;
  bool refineFrames = true;         ///< finish(): re-estimate every frame against the final map
  /// finish(): full-sequence bundle adjustment of every frame over every track
  /// (sequence_refine.hpp), tracks joined across resets and relocalisations.
  bool sequenceRefine = true;
  SequenceRefineOptions<Scalar> sequence;
  /// finish(): frames without a map pose placed by the head model fitted to the posed frames
  /// around them (head_motion.hpp), where it explains them; otherwise held / interpolated.
  bool headModelFill = true;
  HeadModelOptions<Scalar> headModel;
  /// finish(): self-calibrate the shared focal (fx, fy by one factor, principal point fixed) in
  /// the global bundle adjustment (focal_refine.hpp: profile of the BA cost over log f, a prior
  /// toward the given focal, declined when the motion does not determine it); the per-frame
  /// refinement then uses the refined focal. With sequenceRefine, on the sequence refinement's
  /// problem instead (refineFocalOnSequence), which is refined again with a changed focal. Off by
  /// default (the tracking used the given focal).
  bool refineFocal = false;
  FocalRefineOptions<Scalar> focal;
  int focalMaxFrames = 60;          ///< frames of the sequence refinement's problem in the focal profile
  /// ...taken at least this many posed frames apart: a track's errors in consecutive frames are
  /// correlated (KLT drift), which the profile's std (independent residuals) does not know; on
  /// every frame the std comes out ~5x too small and a right guess is moved by 2-3 %.
  int focalFrameSpacing = 5;
  /// ...and the std of its estimate is taken as this at least (FocalRefineOptions::minStdLog): a
  /// guess within ~2 × this of the estimate is kept.
  Scalar focalMinStd = Scalar(0.02);
  /// Optional diagnostics sink (one line per event: initialisation attempts, losses, resets).
  std::function<void(const std::string&)> log;

  SlamOptions() {
    pnp.thresholdPx = Scalar(3);
    pnp.maxIterations = 200;
    pnp.refinement.maxIterations = 6;
    twoView.maxIterations = 300;
  }
};

/// Sparse depths of one keyframe for the scale step: pixels and depths along the optical axis
/// (map units), of the map points it observes outside the hand masks.
template <typename Scalar>
struct SlamKeyframeDepths {
  int frame = 0;
  std::vector<Vec2<Scalar>> uv;
  std::vector<Scalar> depth;
};

template <typename Scalar>
struct SlamResult {
  std::vector<SE3<Scalar>> poses;     ///< T_w_c per frame, world = first frame's camera
  std::vector<SlamStatus> status;     ///< per frame
  std::vector<char> keyframe;         ///< per frame
  std::vector<int> inliers;           ///< per frame: PnP inliers (0 without a map pose)
  std::vector<SlamKeyframeDepths<Scalar>> keyframeDepths;
  std::vector<Vec3<Scalar>> points;   ///< final map points (world)
  int numKeyframes = 0;
  int numLosses = 0;                  ///< tracking-loss events (runs of Lost frames)
  int numResets = 0;                  ///< map re-initialisations (a reset undone by relocalisation is not one)
  int numRelocalisations = 0;         ///< lost frames put back into the map they had lost
  int numRevisitPoints = 0;           ///< old map points found again by the revisit search
  int numRefinedFrames = 0;           ///< frames adjusted by the sequence refinement (0: not run)
  int numHeadModelFrames = 0;         ///< unposed frames placed by the head model
  bool initialised = false;           ///< a map was ever built (false: rotation-only output)
  PinholeCamera<Scalar> camera;       ///< the intrinsics of the output (refined when focal.changed)
  bool focalAttempted = false;        ///< SlamOptions::refineFocal ran (false: off, or no map)
  FocalRefineResult<Scalar> focal;    ///< its outcome (reason says why declined / not applied)
  int count(SlamStatus s) const {
    int n = 0;
    for (SlamStatus t : status) n += t == s ? 1 : 0;
    return n;
  }
};

template <typename Scalar>
class MonoSlam {
 public:
  using V2 = Vec2<Scalar>;
  using V3 = Vec3<Scalar>;
  using SE3T = SE3<Scalar>;

  MonoSlam(const PinholeCamera<Scalar>& camera, const SlamOptions<Scalar>& options = {})
      : cam_(camera), opt_(options) {
    if (!(cam_.fx > Scalar(0)) || !(cam_.fy > Scalar(0)) || !std::isfinite(double(cam_.fx)) ||
        !std::isfinite(double(cam_.fy)) || !std::isfinite(double(cam_.cx)) || !std::isfinite(double(cam_.cy))) {
      throw Error("MonoSlam: the intrinsics must be finite with fx, fy > 0");
    }
    if (opt_.pyramidLevels < 1 || opt_.maxFeatures < 20 || opt_.windowKeyframes < 2 || opt_.minInliers < 6 ||
        opt_.keyframeMaxInterval < 1 || opt_.lostFramesBeforeReset < 1 || opt_.maskDilatePx < 0 ||
        opt_.maskBlock < 1 || opt_.coastFrames < 0 || !(opt_.coastMaxStepDeg >= Scalar(0)) ||
        !(std::abs(opt_.rollingShutter) <= Scalar(1))) {
      throw Error("MonoSlam: invalid options");
    }
    opt_.twoView.focalPx = Scalar(0.5) * (cam_.fx + cam_.fy);
    // every focal refinement's prior stays on the focal given here (or focal.priorFx)
    if (!(opt_.focal.priorFx > Scalar(0))) opt_.focal.priorFx = cam_.fx;
  }

  /// Processes the next frame (8-bit grey or RGB(A)); `mask` may be null (no hands) or an 8-bit
  /// image of the same size, hand pixels non-zero. Returns the frame's provisional status.
  /// Throws hawor::Error for an empty image, a size different from the first frame's, or a mask
  /// of the wrong size; a textureless or fully masked frame is simply not tracked.
  SlamStatus process(const ImageU8& image, const ImageU8* mask = nullptr) {
    if (finished_) throw Error("MonoSlam: process() after finish()");
    if (!image.consistent() || image.width <= 0 || image.height <= 0) {
      throw Error("MonoSlam: frame " + std::to_string(frames_.size()) + " is empty");
    }
    if (frames_.empty()) {
      width_ = image.width, height_ = image.height;
    } else if (image.width != width_ || image.height != height_) {
      throw Error("MonoSlam: frame " + std::to_string(frames_.size()) + " is " + std::to_string(image.width) +
                  "x" + std::to_string(image.height) + " but the first frame was " + std::to_string(width_) +
                  "x" + std::to_string(height_));
    }
    std::swap(prevPyr_, curPyr_);
    curPyr_.build(image, opt_.pyramidLevels);
    hasMask_ = false;
    if (mask && opt_.useMasks) {
      binaryHandMask(*mask, width_, height_, curMask_);
      dilateMask(curMask_, opt_.maskDilatePx, maskTmp_);
      hasMask_ = true;
    } else if (mask) {
      binaryHandMask(*mask, width_, height_, curMask_);  // size check only
    }
    const int f = static_cast<int>(frames_.size());
    frames_.emplace_back();
    Frame& fr = frames_.back();
    fr.T = frames_.size() > 1 ? frames_[frames_.size() - 2].T : SE3T();

    if (f == 0) {
      setReference(0);
      recordObservations(fr);
      return fr.status;
    }
    trackFeatures(f);
    if (state_ != State::Tracking) {
      initialise(f);
    } else {
      trackPose(f);
    }
    if (opt_.segmentLinks && !linkPyr_.empty() && !frames_.back().posed && f % std::max(1, opt_.linkEveryFrames) == 0) {
      searchSegmentLinks(f);
    }
    recordObservations(frames_.back());
    return frames_.back().status;
  }

  /// Global bundle adjustment, per-frame refinement, interpolation of the remaining frames, and
  /// the result in the first frame's world. Call once, after the last frame.
  SlamResult<Scalar> finish() {
    if (finished_) throw Error("MonoSlam: finish() called twice");
    finished_ = true;
    // No frame comes after finish(): the images kept for tracking, re-finding and relocalisation
    // (up to 20 pyramids, about 30 MB at 640×480) go before the sequence refinement needs its
    // memory.
    prevPyr_ = ImagePyramid();
    curPyr_ = ImagePyramid();
    std::vector<KeyframePyramid>().swap(kfPyr_);
    std::vector<KeyframePyramid>().swap(relocPyr_);
    std::vector<KeyframePyramid>().swap(linkPyr_);
    lastKfPyr_ = KeyframePyramid();
    curMask_ = ImageU8();
    std::vector<unsigned char>().swap(maskTmp_);
    SlamResult<Scalar> res;
    const int n = static_cast<int>(frames_.size());
    if (n == 0) return res;
    if (opt_.segmentLinks && resets_ > 0) applySegmentLinks();
    if ((opt_.turnScaleJoin || opt_.headModelJoin) && resets_ > 0) joinSegmentsByTurns();
    if (opt_.globalBundleAdjustment && keyframes_.size() >= 2) {
      std::vector<int> all(keyframes_.size());
      for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<int>(k);
      // With the sequence refinement on, the focal is refined on its problem instead (every
      // frame's tracks, far more of the motion that determines the focal than the keyframes').
      adjust(all, opt_.globalIterations, true, opt_.refineFocal && !opt_.sequenceRefine);
      for (std::size_t k = 0; k < keyframes_.size(); ++k) frames_[static_cast<std::size_t>(keyframes_[k].frame)].T = keyframes_[k].T;
    }
    if (opt_.refineFrames && !points_.empty()) refineAllFrames();
    fillUnposed();
    if (opt_.sequenceRefine && opt_.headModelJoin && opt_.headModelJoinAll && opt_.headModelJoinBeforeRefine && resets_ > 0) {
      joinAllSegmentsByHead(false);
    }
    bool sequenceDone = opt_.sequenceRefine && everInitialised_ && refineWholeSequence();
    // The refinement's points and inliers were chosen at the old focal: repeat while it moves
    // (at most 3 times); the result reports the first guess and the last estimate.
    if (sequenceDone && opt_.refineFocal) {
      const Scalar guess = cam_.fx;
      bool changed = false;
      for (int round = 0; sequenceDone && round < 3 && refineFocalOnSequence(); ++round) {
        changed = true;
        sequenceDone = refineWholeSequence();
      }
      if (changed) {
        // the last round's own reason (it may have kept its guess, the previous round's estimate)
        focal_.reason = "refined by the bundle adjustment of the sequence" +
                        (focal_.changed ? std::string() : " (last round: " + focal_.reason + ")");
        focal_.guessFx = guess;
        focal_.changed = true;
        focal_.accepted = true;
        focal_.fx = cam_.fx;
        focal_.fy = cam_.fy;
      }
    }
    if (opt_.headModelJoin && opt_.headModelJoinAll && resets_ > 0) joinAllSegmentsByHead();
    if (opt_.headModelFill && everInitialised_) {
      std::vector<SE3T> T(static_cast<std::size_t>(n));
      std::vector<char> posed(static_cast<std::size_t>(n)), rot(static_cast<std::size_t>(n));
      std::string headLog;
      for (int f = 0; f < n; ++f) {
        T[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].T;
        posed[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].posed;
        rot[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].rotationKnown;
      }
      const int changed = fillGapsByHeadModel(T, posed, rot, opt_.headModel, opt_.log ? &headLog : nullptr);
      headModelFrames_ = changed;
      for (int f = 0; f < n; ++f) frames_[static_cast<std::size_t>(f)].T = T[static_cast<std::size_t>(f)];
      if (opt_.log) opt_.log("head model: " + std::to_string(changed) + " unposed frames placed;" + headLog);
    }
    // Express everything in the first frame's camera.
    const SE3T T0inv = frames_[0].T.inverse();
    res.poses.resize(static_cast<std::size_t>(n));
    res.status.resize(static_cast<std::size_t>(n));
    res.keyframe.resize(static_cast<std::size_t>(n), 0);
    res.inliers.resize(static_cast<std::size_t>(n), 0);
    for (int i = 0; i < n; ++i) {
      const Frame& fr = frames_[static_cast<std::size_t>(i)];
      res.poses[static_cast<std::size_t>(i)] = T0inv * fr.T;
      res.status[static_cast<std::size_t>(i)] = fr.status;
      res.inliers[static_cast<std::size_t>(i)] = fr.inliers;
    }
    for (const Keyframe& kf : keyframes_) res.keyframe[static_cast<std::size_t>(kf.frame)] = 1;
    if (sequenceDone) {
      for (std::size_t j = 0; j < seqPoints_.size(); ++j) {
        if (seqPointObs_[j].empty() || !placedFrame(seqPointObs_[j].front().first)) res.points.push_back(T0inv * seqPoints_[j]);
      }
    } else {
      for (const MapPoint& p : points_) {
        if (p.valid && (p.obs.empty() || !placedFrame(keyframes_[static_cast<std::size_t>(p.obs.front().kf)].frame))) res.points.push_back(T0inv * p.X);
      }
    }
    // Keyframe depths (camera z does not depend on the world frame).
    if (sequenceDone) {
      // From the refined points: each keyframe's observations of them, off its hand mask.
      std::vector<int> kfOfFrame(static_cast<std::size_t>(n), -1);
      for (std::size_t k = 0; k < keyframes_.size(); ++k) kfOfFrame[static_cast<std::size_t>(keyframes_[k].frame)] = static_cast<int>(k);
      res.keyframeDepths.resize(keyframes_.size());
      for (std::size_t k = 0; k < keyframes_.size(); ++k) res.keyframeDepths[k].frame = keyframes_[k].frame;
      for (std::size_t j = 0; j < seqPoints_.size(); ++j) {
        for (const auto& o : seqPointObs_[j]) {
          const int k = kfOfFrame[static_cast<std::size_t>(o.first)];
          if (k < 0 || placedFrame(o.first) || keyframes_[static_cast<std::size_t>(k)].mask.test(o.second(0), o.second(1))) continue;
          const V3 Xc = frames_[static_cast<std::size_t>(o.first)].T.inverse() * seqPoints_[j];
          if (!(Xc(2) > Scalar(0))) continue;
          res.keyframeDepths[static_cast<std::size_t>(k)].uv.push_back(o.second);
          res.keyframeDepths[static_cast<std::size_t>(k)].depth.push_back(Xc(2));
        }
      }
    }
    for (std::size_t k = 0; k < keyframes_.size() && !sequenceDone; ++k) {
      SlamKeyframeDepths<Scalar> d;
      d.frame = keyframes_[k].frame;
      const SE3T Tcw = keyframes_[k].T.inverse();
      for (int pid : placedFrame(d.frame) ? std::vector<int>() : keyframes_[k].points) {
        const MapPoint& p = points_[static_cast<std::size_t>(pid)];
        if (!p.valid) continue;
        for (const Obs& o : p.obs) {
          if (o.kf != static_cast<int>(k)) continue;
          if (keyframes_[k].mask.test(o.uv(0), o.uv(1))) break;
          const V3 Xc = Tcw * p.X;
          if (Xc(2) > Scalar(0)) {
            d.uv.push_back(o.uv);
            d.depth.push_back(Xc(2));
          }
          break;
        }
      }
      res.keyframeDepths.push_back(std::move(d));
    }
    res.numKeyframes = static_cast<int>(keyframes_.size());
    res.numLosses = losses_;
    res.numResets = resets_;
    res.numRelocalisations = relocalisations_;
    res.numRevisitPoints = revisitPoints_;
    res.numRefinedFrames = refinedFrames_;
    res.numHeadModelFrames = headModelFrames_;
    res.initialised = everInitialised_;
    res.camera = cam_;
    res.focalAttempted = focalAttempted_;
    res.focal = focal_;
    if (!focalAttempted_) {
      res.focal.guessFx = res.focal.fx = cam_.fx;
      res.focal.fy = cam_.fy;
      res.focal.reason = opt_.refineFocal ? "no map for the global bundle adjustment" : "off";
    }
    return res;
  }

  int numFrames() const { return static_cast<int>(frames_.size()); }
  int numKeyframes() const { return static_cast<int>(keyframes_.size()); }
  int numLiveTracks() const { return static_cast<int>(tracks_.size()); }
  /// Bytes held for the whole sequence (observations, map, keyframe masks), excluding the two
  /// pyramids and scratch buffers.
  std::size_t sequenceBytes() const {
    std::size_t b = frames_.size() * sizeof(Frame);
    for (const Frame& f : frames_) b += f.obsTrack.capacity() * sizeof(int) + f.obsUv.capacity() * sizeof(Vec2f) + f.mask.bytes();
    for (const Keyframe& k : keyframes_) b += sizeof(Keyframe) + k.mask.bytes() + k.points.capacity() * sizeof(int);
    for (const MapPoint& p : points_) b += sizeof(MapPoint) + p.obs.capacity() * sizeof(Obs);
    b += trackPoint_.capacity() * sizeof(int);
    return b;
  }

 private:
  enum class State { Initialising, Tracking };
  using Vec2f = Eigen::Matrix<float, 2, 1, Eigen::DontAlign>;

  struct Obs {
    int kf;
    V2 uv;
  };
  struct MapPoint {
    V3 X;
    std::vector<Obs> obs;
    bool valid = true;
  };
  struct Track {
    int id;
    Vec2f uv = Vec2f::Zero();     ///< position for the geometry (rolling shutter compensated)
    Vec2f px = Vec2f::Zero();     ///< position in the image (KLT's; = uv for a global shutter)
    int point = -1;
    std::vector<Obs> kfObs;  ///< keyframe observations while unmapped
    Vec2f refUv = Vec2f::Zero();  ///< position in the initialisation reference frame
    bool fromRef = false;
    std::vector<Obs> oldObs;  ///< keyframe observations in the map segment before a reset (joinToOldMap)
    int oldPoint = -1;        ///< its map point in that segment (−1: none)
  };
  struct Keyframe {
    int frame;
    SE3T T;
    CoarseMask mask;
    std::vector<int> points;  ///< map points it observes
    int segment;
  };
  struct KeyframePyramid {
    int kf = -1;
    ImagePyramid pyr;
    bool anchor = false;  ///< relocPyr_: an anchor (SlamOptions::relocAnchors), not a recent one
  };
  struct SegmentLink {
    int frame;     ///< placed in the world of the segment before its chain's break
    int oldFrame;  ///< by the kept image of this keyframe frame (in that segment)
    SE3T T_old;    ///< its pose in that world
    int inliers;
  };
  struct Frame {
    SE3T T;
    SlamStatus status = SlamStatus::Interpolated;
    bool posed = false;        ///< T comes from a map (tracked) rather than a guess
    bool rotationKnown = true; ///< rotation from rays/tracking (false: only interpolate)
    bool coasted = false;      ///< rotation carried on from the last steps (coastRotation)
    int inliers = 0;
    CoarseMask mask;           ///< hand mask, kept for the recent frames while initialising
    std::vector<int> obsTrack;
    std::vector<Vec2f> obsUv;
  };

  // ---------------------------------------------------------------- front end
  V2 normalised(const Vec2f& uv) const {
    return V2((Scalar(uv(0)) - cam_.cx) / cam_.fx, (Scalar(uv(1)) - cam_.cy) / cam_.fy);
  }
  bool masked(const Vec2f& uv) const {
    if (!hasMask_) return false;
    const int x = int(std::floor(uv(0) + 0.5f)), y = int(std::floor(uv(1) + 0.5f));
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return false;
    return curMask_.at(x, y) != 0;
  }
  bool insideImage(const Vec2f& uv, float margin) const {
    return uv(0) >= margin && uv(1) >= margin && uv(0) <= float(width_ - 1) - margin &&
           uv(1) <= float(height_ - 1) - margin;
  }

  /// SlamOptions::rollingShutter: image pixel → the middle row's time (sign +1), or back (−1,
  /// the inverse to first order). The identity for a global shutter or without a rotation rate.
  Vec2f rollingShutterShift(const Vec2f& p, Scalar sign) const {
    if (opt_.rollingShutter == Scalar(0) || rsOmega_.isZero(Scalar(0))) return p;
    const Scalar d = sign * opt_.rollingShutter * ((Scalar(p(1)) - Scalar(0.5) * Scalar(height_ - 1)) / Scalar(height_));
    const V3 b((Scalar(p(0)) - cam_.cx) / cam_.fx, (Scalar(p(1)) - cam_.cy) / cam_.fy, Scalar(1));
    const V3 r = SO3<Scalar>::exp(V3(rsOmega_ * d)) * b;
    if (!(r(2) > Scalar(0))) return p;
    return Vec2f(float(cam_.fx * r(0) / r(2) + cam_.cx), float(cam_.fy * r(1) / r(2) + cam_.cy));
  }

  /// The camera's rotation over the last frame from the raw pixels KLT just tracked (from_ → to_,
  /// ok_), as a rotation vector in camera axes (R(t+1) = R(t)·exp(ω)); zero for a global shutter
  /// or with fewer than 8 rays. The rolling shutter's shear is the same in both frames under a
  /// steady turn, so the raw rays' best rotation is the middle rows' one.
  V3 rsRate() {
    if (opt_.rollingShutter == Scalar(0)) return V3::Zero();
    std::vector<V2> a, b;
    for (std::size_t i = 0; i < from_.size(); ++i) {
      if (!ok_[i]) continue;
      a.push_back(normalised(from_[i]));
      b.push_back(normalised(to_[i]));
    }
    Mat3<Scalar> R21;
    if (a.size() < 8 || two_view_detail::rotationFromRaysReweighted(a, b, Scalar(3), R21) < 8) return V3::Zero();
    return SO3<Scalar>::fromMatrix(Mat3<Scalar>(R21.transpose())).log();
  }

  void trackFeatures(int f) {
    // Prediction (c2w). Rotation: constant angular velocity, R_pred = R1·(R2ᵀ·R1), from the last
    // two frames' rotations, known from the map or from the tracked rays (a fast head turn moves
    // the image by up to 20° ≈ 140 px a frame, far beyond the pyramid's range without a guess).
    // Translation: constant velocity when both frames have a map pose, else held.
    const Frame& p1 = frames_[static_cast<std::size_t>(f - 1)];
    const bool rot2 = f >= 2 && frames_[static_cast<std::size_t>(f - 2)].rotationKnown && p1.rotationKnown;
    // Turn mode: the last rotation increment is at least turnRateDeg a frame (a fast head
    // turn; slow looking around stays far below), held for turnHoldFrames after (deceleration).
    if (rot2 && rotationAngleDeg(frames_[static_cast<std::size_t>(f - 2)].T, p1.T) >= opt_.turnRateDeg) {
      turnUntil_ = f + opt_.turnHoldFrames;
    }
    turning_ = f <= turnUntil_;
    havePrediction_ = state_ == State::Tracking && f >= 2 && frames_[static_cast<std::size_t>(f - 2)].posed && p1.posed;
    if (havePrediction_) {
      const Frame& p2 = frames_[static_cast<std::size_t>(f - 2)];
      predicted_ = p1.T * (p2.T.inverse() * p1.T);
    } else if (rot2 && turning_) {
      predicted_ = rotationCarriedOn(f);
    } else {
      predicted_ = p1.T;
    }
    // Camera-1 → predicted-camera rotation for directions (the infinite homography K·Rpc·K⁻¹:
    // exact for distant points, a few pixels off for near ones under the small head translation).
    const Mat3<Scalar> Rpc = predicted_.rotationMatrix().transpose() * p1.T.rotationMatrix();
    // The rolling shutter's angular velocity for this frame: the last step's, measured on the raw
    // pixels (rsRate, below), so that the compensation never feeds back into its own rate.
    rsOmega_ = rsOmegaNext_;
    from_.resize(tracks_.size());
    to_.resize(tracks_.size());
    const SE3T Tcw = predicted_.inverse();
    std::vector<char> guessed(tracks_.size(), 0);
    float sdx = 0, sdy = 0;
    int npred = 0;
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
      const Track& t = tracks_[i];
      from_[i] = t.px;
      to_[i] = t.uv;
      if (turning_) {
        const V2 x = normalised(t.uv);
        const V3 d = Rpc * V3(x(0), x(1), Scalar(1));
        const Vec2f h(float(cam_.fx * d(0) / d(2) + cam_.cx), float(cam_.fy * d(1) / d(2) + cam_.cy));
        if (d(2) > Scalar(0) && std::isfinite(h(0)) && std::isfinite(h(1))) to_[i] = h;
      }
      if (t.point >= 0 && (havePrediction_ || (turning_ && state_ == State::Tracking))) {
        // A mapped track: its point projected under the predicted pose.
        const V3 Xc = Tcw * points_[static_cast<std::size_t>(t.point)].X;
        if (Xc(2) > Scalar(0)) {
          const V2 q = cam_.project(Xc);
          const Vec2f g(float(q(0)), float(q(1)));
          if (std::isfinite(g(0)) && std::isfinite(g(1)) && insideImage(g, -50.0f)) {
            sdx += g(0) - to_[i](0), sdy += g(1) - to_[i](1);
            ++npred;
            to_[i] = g;
            guessed[i] = 1;
          }
        }
      }
    }
    // Unmapped tracks: the mean shift of the mapped ones' guesses (in a turn: on top of the
    // rotation guess, i.e. the mean translation-induced shift).
    if (npred > 0) {
      const float mx = sdx / float(npred), my = sdy / float(npred);
      for (std::size_t i = 0; i < tracks_.size(); ++i) {
        if (!guessed[i]) to_[i] = Vec2f(to_[i](0) + mx, to_[i](1) + my);
      }
    }
    // The guesses are geometric positions; KLT looks in the image.
    for (std::size_t i = 0; i < tracks_.size(); ++i) to_[i] = rollingShutterShift(to_[i], Scalar(-1));
    trackKlt(prevPyr_, curPyr_, from_, to_, ok_, opt_.klt);
    std::size_t w = 0;
    const float margin = float(opt_.klt.halfWindow + 1);
    prevUv_.clear();
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
      if (!ok_[i] || !insideImage(to_[i], margin) || masked(to_[i])) continue;
      prevUv_.push_back(tracks_[i].uv);
      if (w != i) tracks_[w] = std::move(tracks_[i]);  // (a self-move would empty kfObs)
      tracks_[w].px = to_[i];
      tracks_[w].uv = rollingShutterShift(to_[i], Scalar(1));
      ++w;
    }
    tracks_.resize(w);
    rsOmegaNext_ = rsRate();
  }

  /// New tracks in the empty cells of the bucketing grid (never on the dilated hand mask).
  void replenish() {
    const int want = opt_.maxFeatures - static_cast<int>(tracks_.size());
    if (want <= 0) return;
    existing_.clear();
    for (const Track& t : tracks_) existing_.push_back(t.px);
    fresh_.clear();
    detectCorners(curPyr_.level(0), hasMask_ ? &curMask_ : nullptr, existing_, want, opt_.corners, fresh_, cornerScratch_);
    for (const Vec2f& p : fresh_) {
      Track t;
      t.id = static_cast<int>(trackPoint_.size());
      trackPoint_.push_back(-1);
      t.px = p;
      t.uv = rollingShutterShift(p, Scalar(1));
      tracks_.push_back(std::move(t));
    }
  }

  /// Frame f becomes the reference of the two-view initialisation (tracks replenished first).
  void setReference(int f) {
    replenish();
    refFrame_ = f;
    refMask_ = hasMask_ ? CoarseMask(curMask_, opt_.maskBlock) : CoarseMask();
    frames_[static_cast<std::size_t>(f)].mask = refMask_;
    for (Track& t : tracks_) {
      t.refUv = t.uv;
      t.fromRef = true;
    }
  }

  void recordObservations(Frame& fr) {
    fr.obsTrack.resize(tracks_.size());
    fr.obsUv.resize(tracks_.size());
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
      fr.obsTrack[i] = tracks_[i].id;
      fr.obsUv[i] = tracks_[i].uv;
    }
    fr.obsTrack.shrink_to_fit();
    fr.obsUv.shrink_to_fit();
  }

  /// Rotation of the current frame relative to the previous one from the tracked rays (Kabsch
  /// with one re-weighting pass that drops rays more than 3° off), as a c2w increment.
  bool rayRotation(Mat3<Scalar>& Rprev_cur) {
    std::vector<V2> a, b;
    a.reserve(tracks_.size());
    b.reserve(tracks_.size());
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
      a.push_back(normalised(prevUv_[i]));
      b.push_back(normalised(tracks_[i].uv));
    }
    if (a.size() < 8) return false;
    Mat3<Scalar> R;
    if (two_view_detail::rotationFromRaysReweighted(a, b, Scalar(3), R) < 8) return false;
    // rotationFromRays gives R21 (f2 ≈ R21·f1): camera 1 → camera 2 for directions, so
    // R_c1_c2 (c2w increment) = R21ᵀ.
    Rprev_cur = R.transpose();
    return true;
  }

  /// Frame f's pose at the last step's angular velocity, position held: R_f = R_{f−1}·(R_{f−2}ᵀ·R_{f−1})
  /// (KLT's guess in a turn, and coastRotation).
  SE3T rotationCarriedOn(int f) const {
    const SE3T& T1 = frames_[static_cast<std::size_t>(f - 1)].T;
    const Mat3<Scalar> R1 = T1.rotationMatrix(), R2 = frames_[static_cast<std::size_t>(f - 2)].T.rotationMatrix();
    return SE3T(SO3<Scalar>::fromMatrix(Mat3<Scalar>(R1 * (R2.transpose() * R1))), T1.translation());
  }

  /// SlamOptions::coastFrames: frame f's rotation when the tracked rays give none, in turn mode:
  /// the last step carried on, R_f = R_{f−1}·(R_{f−2}ᵀ·R_{f−1}) (constant angular velocity),
  /// position held; at most coastFrames frames in a row and only from a step of at most
  /// coastMaxStepDeg. A head turning onto a bare wall keeps turning while no track survives;
  /// holding the rotation instead loses the whole turn (fast_turns seed 8: 66° over frames 88–91)
  /// and every later frame, posed or not, keeps that offset.
  bool coastRotation(int f) {
    Frame& fr = frames_.back();
    if (opt_.coastFrames <= 0 || !turning_ || f < 2) return false;
    const Frame& p1 = frames_[static_cast<std::size_t>(f - 1)];
    const Frame& p2 = frames_[static_cast<std::size_t>(f - 2)];
    if (!p1.rotationKnown || !p2.rotationKnown) return false;
    int run = 0;
    while (run < f && frames_[static_cast<std::size_t>(f - 1 - run)].coasted) ++run;
    if (run >= opt_.coastFrames) return false;
    if (rotationAngleDeg(p2.T, p1.T) > opt_.coastMaxStepDeg) return false;
    fr.T = rotationCarriedOn(f);
    fr.rotationKnown = true;
    fr.coasted = true;
    if (opt_.log) opt_.log("frame " + std::to_string(f) + ": no rotation from the rays, the last step's carried on");
    return true;
  }

  /// Before a map: a track whose ray is more than maxRayJumpDeg off the frame's rotation from
  /// the rays (f2 ≈ dRᵀ·f1) jumped — KLT locked onto a repeated or weak texture one period off
  /// at the onset of a turn, where the prediction lags — and is dropped: such tracks move
  /// together and give the two-view a coherent wrong motion (fast_turns seed 6 frame 25: 37 of 85
  /// tracks 40–160 px off). A frame's parallax from the head's translation is a few pixels.
  void dropJumpedTracks(const Mat3<Scalar>& dR) {
    if (!(opt_.maxRayJumpDeg > Scalar(0)) || prevUv_.size() != tracks_.size()) return;
    const Scalar cosMax = std::cos(opt_.maxRayJumpDeg * Constants<Scalar>::pi() / Scalar(180));
    const Mat3<Scalar> R21 = dR.transpose();
    std::vector<char> drop(tracks_.size(), 0);
    int n = 0;
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
      if (two_view_detail::rotatedRayCos(R21, normalised(prevUv_[i]), normalised(tracks_[i].uv)) < cosMax) drop[i] = 1, ++n;
    }
    if (n == 0) return;
    if (opt_.log) opt_.log("frame " + std::to_string(frames_.size() - 1) + ": " + std::to_string(n) + " tracks jumped off the rays' rotation, dropped");
    removeTracks(drop);
  }

  // ---------------------------------------------------------------- initialisation
  void initialise(int f) {
    Frame& fr = frames_.back();
    // Rotation-only pose from the ray chain (position held).
    Mat3<Scalar> dR;
    if (rayRotation(dR)) {
      fr.T = SE3T(SO3<Scalar>::fromMatrix(Mat3<Scalar>(frames_[static_cast<std::size_t>(f - 1)].T.rotationMatrix() * dR)),
                  frames_[static_cast<std::size_t>(f - 1)].T.translation());
      dropJumpedTracks(dR);
    } else if (!coastRotation(f)) {
      fr.rotationKnown = false;
    }
    fr.status = afterLoss_ ? SlamStatus::Lost : SlamStatus::Interpolated;
    if (afterLoss_ && relocalise(f)) return;
    // Reference: the fixed reference frame (refFrame_, replaced when it has lost most of its
    // tracks), or any of the last initMaxGap frames (their tracks are in the per-frame
    // observations, their rotations from the rays): the oldest of them sharing initMinTracks
    // tracks. During a head turn the tracks live only a few frames, and while hands sweep over a
    // slowly moving view they die one by one: a fixed reference would lose them all before the
    // motion gives parallax (hands_cover seed 7 never initialised in 300 frames).
    fr.mask = hasMask_ ? CoarseMask(curMask_, opt_.maskBlock) : CoarseMask();
    const int window = f - opt_.initMaxGap;
    if (window - 1 >= 0 && window - 1 != refFrame_) frames_[static_cast<std::size_t>(window - 1)].mask = CoarseMask();
    const int oldest = std::max(segmentStart_, std::min(refFrame_, window));
    const int minTracks = afterLoss_ ? opt_.reinitMinTracks : opt_.initMinTracks;
    int bestG = -1, refAlive = 0;
    float bestFlow = -1;
    std::vector<int> bestIdx, bestOther;
    std::vector<int> idx, other;
    std::vector<float> flow;
    for (int g = f - 1; g >= oldest; --g) {
      const Frame& rf = frames_[static_cast<std::size_t>(g)];
      if (g != refFrame_ && (g < window || !rf.rotationKnown)) continue;
      // Common tracks: both observation lists are sorted by track id (ids only grow).
      idx.clear(), other.clear(), flow.clear();
      std::size_t a = 0;
      for (std::size_t i = 0; i < tracks_.size(); ++i) {
        while (a < rf.obsTrack.size() && rf.obsTrack[a] < tracks_[i].id) ++a;
        if (a < rf.obsTrack.size() && rf.obsTrack[a] == tracks_[i].id) idx.push_back(static_cast<int>(i)), other.push_back(static_cast<int>(a));
      }
      if (g == refFrame_) refAlive = static_cast<int>(idx.size());
      if (static_cast<int>(idx.size()) < minTracks) continue;
      // Rotation-compensated flow: where the reference ray lands under the rotation alone.
      const Mat3<Scalar> Rcr = fr.T.rotationMatrix().transpose() * rf.T.rotationMatrix();
      for (std::size_t j = 0; j < idx.size(); ++j) {
        const V2 x1 = normalised(rf.obsUv[static_cast<std::size_t>(other[j])]);
        const V2 x2 = normalised(tracks_[static_cast<std::size_t>(idx[j])].uv);
        const V3 r = Rcr * V3(x1(0), x1(1), Scalar(1));
        if (!(r(2) > Scalar(0))) continue;
        const float du = float(cam_.fx * (r(0) / r(2) - x2(0))), dv = float(cam_.fy * (r(1) / r(2) - x2(1)));
        flow.push_back(std::sqrt(du * du + dv * dv));
      }
      if (flow.size() < 8) continue;
      std::nth_element(flow.begin(), flow.begin() + static_cast<std::ptrdiff_t>(flow.size() / 2), flow.end());
      // The oldest frame with enough common tracks: the longest baseline available.
      bestFlow = flow[flow.size() / 2], bestG = g, bestIdx = idx, bestOther = other;
    }
    // Try when the rotation-compensated flow is large enough, or after a large rotation: the
    // flow is compensated with the rays' rotation, which under a sideways head translation
    // absorbs most of the parallax (the rotation–translation ambiguity); the two-view decides.
    const Scalar turnedDeg = bestG >= 0 ? rotationAngleDeg(frames_[static_cast<std::size_t>(bestG)].T, fr.T) : Scalar(0);
    const bool fastTurn = bestG >= 0 && turning_ && turnedDeg >= opt_.initMinRotationDeg;
    const bool tryNow = bestG >= 0 && ((bestFlow >= float(opt_.initMinFlowPx) && f - lastInitAttempt_ >= opt_.initEveryFrames) ||
                                       (fastTurn && f - lastInitAttempt_ >= 2));
    if (tryNow) {
      lastInitAttempt_ = f;
      const Frame& rf = frames_[static_cast<std::size_t>(bestG)];
      std::vector<V2> x1, x2;
      for (std::size_t j = 0; j < bestIdx.size(); ++j) {
        x1.push_back(normalised(rf.obsUv[static_cast<std::size_t>(bestOther[j])]));
        x2.push_back(normalised(tracks_[static_cast<std::size_t>(bestIdx[j])].uv));
      }
      // Further views (the frames between, every second) settle a two-fold ambiguity
      // (two_view.hpp): the head's sway curves, and a view off the pair's line of motion fits
      // only the true plane.
      std::vector<std::vector<V2>> x3;
      if (opt_.twoViewThirdView) {
        const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
        for (int mid = bestG + 2; mid < f; mid += 2) {
          const Frame& mf = frames_[static_cast<std::size_t>(mid)];
          std::vector<V2> v;
          std::size_t a = 0;
          for (std::size_t j = 0; j < bestIdx.size(); ++j) {
            const int id = tracks_[static_cast<std::size_t>(bestIdx[j])].id;
            while (a < mf.obsTrack.size() && mf.obsTrack[a] < id) ++a;
            v.push_back(a < mf.obsTrack.size() && mf.obsTrack[a] == id ? normalised(mf.obsUv[a]) : V2(nan, nan));
          }
          x3.push_back(std::move(v));
        }
      }
      TwoViewOptions<Scalar> tvo = opt_.twoView;
      tvo.seed = opt_.twoView.seed + static_cast<std::uint32_t>(f);
      // In a fast turn the rotation dwarfs the translation: H (the rotation) is the model, and
      // E's extra inliers are noise read as parallax (fast_turns seed 8, frame 204).
      tvo.essentialOverPlane = opt_.twoView.essentialOverPlane && !turning_;
      const TwoViewResult<Scalar> tv = initializeTwoView(x1, x2, tvo, x3.empty() ? nullptr : &x3);
      if (opt_.log) {
        opt_.log("frame " + std::to_string(f) + ": two-view with reference " + std::to_string(bestG) + ", " +
                 std::to_string(x1.size()) + " tracks, flow " + std::to_string(bestFlow) + " px: status " +
                 std::to_string(int(tv.status)) + " model " + std::to_string(int(tv.model)) + " inliers " +
                 std::to_string(tv.numInliers) + " triangulated " + std::to_string(tv.numTriangulated) +
                 " parallax " + std::to_string(double(tv.medianParallaxDeg)) +
                 (tv.essentialOverPlane ? " (E over GRIC's H)" : "") +
                 (tv.thirdViewCandidates > 0 ? ", further views: " +
                                                   std::to_string(tv.thirdViewCandidates) + " candidates, costs " +
                                                   std::to_string(double(tv.thirdViewCost)) + " / " +
                                                   std::to_string(double(tv.thirdViewRunnerUp)) + " px2"
                                             : std::string()));
      }
      if (tv.ok()) {
        if (bestG != refFrame_ && refFrame_ < window) frames_[static_cast<std::size_t>(refFrame_)].mask = CoarseMask();
        refFrame_ = bestG;
        refMask_ = rf.mask;
        for (Track& t : tracks_) t.fromRef = false;
        for (std::size_t j = 0; j < bestIdx.size(); ++j) {
          Track& t = tracks_[static_cast<std::size_t>(bestIdx[j])];
          t.refUv = rf.obsUv[static_cast<std::size_t>(bestOther[j])];
          t.fromRef = true;
        }
        buildMap(f, tv, bestIdx);
        for (int g = oldest; g <= f; ++g) frames_[static_cast<std::size_t>(g)].mask = CoarseMask();
        return;
      }
    }
    // Too few reference tracks left: this frame becomes the reference (new corners first). New
    // corners also whenever the tracks thin out (they give the later frames a reference among
    // the recent ones).
    const int refTracks = static_cast<int>(frames_[static_cast<std::size_t>(refFrame_)].obsTrack.size());
    if (refAlive < std::max(minTracks, refTracks / 4)) {
      if (opt_.log) {
        opt_.log("frame " + std::to_string(f) + ": new initialisation reference (" + std::to_string(refAlive) + " tracks left)");
      }
      if (refFrame_ < window) frames_[static_cast<std::size_t>(refFrame_)].mask = CoarseMask();
      setReference(f);
    } else if (static_cast<int>(tracks_.size()) < opt_.maxFeatures * 7 / 10) {
      replenish();
    }
  }

  void buildMap(int f, const TwoViewResult<Scalar>& tv, const std::vector<int>& idx) {
    SE3T Tref = frames_[static_cast<std::size_t>(refFrame_)].T;  // provisional world of the ref frame
    // The two-view map lives in the reference camera's frame with a unit baseline. Join it to
    // the existing world (first map: the reference frame's provisional pose, scale 1; after a
    // loss: by the tracks' observations in the old map's keyframes when they determine a
    // similarity (joinToOldMap; the new keyframes then continue the old segment), else the
    // rotation from the rays, the position held and the scale from the median scene depth of
    // the last map, docs/design.md §5).
    Scalar s = Scalar(1);
    std::vector<char> linked;
    const bool joined = everInitialised_ && opt_.joinOldMap && joinToOldMap(f, tv, idx, Tref, s, linked);
    if (joined) --segment_;
    if (!joined) {
      // A new segment: the old map is no longer the one tracked. Its kept images stay for the
      // place recognition when the rotation chain to it is broken (segmentLinks; else the images
      // kept from an earlier break stay, for the same chain).
      if (opt_.segmentLinks && !keyframes_.empty() && chainStart(f) > keyframes_.back().frame) {
        linkPyr_.swap(relocPyr_);
        // The segment's last keyframe too: a break comes in a turn, and the head often turns back.
        if (lastKfPyr_.kf >= 0 && std::none_of(linkPyr_.begin(), linkPyr_.end(), [&](const KeyframePyramid& e) { return e.kf == lastKfPyr_.kf; })) {
          linkPyr_.push_back(std::move(lastKfPyr_));
        }
      }
      relocPyr_.clear();
      lastKfPyr_ = KeyframePyramid();
    }
    const int seg = segment_;
    if (!joined && everInitialised_ && lastMedianDepth_ > Scalar(0)) {
      std::vector<Scalar> d;
      for (std::size_t j = 0; j < idx.size(); ++j) {
        if (tv.triangulated[j] && tv.points[j](2) > Scalar(0)) d.push_back(tv.points[j](2));
      }
      if (!d.empty()) {
        std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
        s = lastMedianDepth_ / d[d.size() / 2];
        if (opt_.log) {
          opt_.log("frame " + std::to_string(f) + ": new segment scaled by the median depth: " + std::to_string(double(lastMedianDepth_)) +
                   " (last map) / " + std::to_string(double(d[d.size() / 2])) + " (two-view, " + std::to_string(d.size()) +
                   " points) = " + std::to_string(double(s)));
        }
      }
    }
    auto toWorld = [&](const V3& x) { return V3(Tref * V3(s * x)); };
    SE3T T1 = Tref * SE3T(tv.T_c1_c2.rotation(), V3(s * tv.T_c1_c2.translation()));
    const int k0 = static_cast<int>(keyframes_.size());
    keyframes_.push_back(Keyframe{refFrame_, Tref, refMask_, {}, seg});
    keyframes_.push_back(Keyframe{f, T1, hasMask_ ? CoarseMask(curMask_, opt_.maskBlock) : CoarseMask(), {}, seg});
    for (std::size_t j = 0; j < idx.size(); ++j) {
      Track& t = tracks_[static_cast<std::size_t>(idx[j])];
      const V2 u0(Scalar(t.refUv(0)), Scalar(t.refUv(1))), u1(Scalar(t.uv(0)), Scalar(t.uv(1)));
      if (tv.triangulated[j] && joined && linked[j] && t.oldPoint >= 0) {
        // The same physical point as an old map point: one point, observed by both segments.
        MapPoint& p = points_[static_cast<std::size_t>(t.oldPoint)];
        p.obs.push_back(Obs{k0, u0});
        p.obs.push_back(Obs{k0 + 1, u1});
        keyframes_[static_cast<std::size_t>(k0)].points.push_back(t.oldPoint);
        keyframes_[static_cast<std::size_t>(k0 + 1)].points.push_back(t.oldPoint);
        t.point = t.oldPoint;
        trackPoint_[static_cast<std::size_t>(t.id)] = t.oldPoint;
      } else if (tv.triangulated[j]) {
        MapPoint p;
        p.X = toWorld(tv.points[j]);
        p.obs = {Obs{k0, u0}, Obs{k0 + 1, u1}};
        if (joined && linked[j]) p.obs.insert(p.obs.begin(), t.oldObs.begin(), t.oldObs.end());
        t.point = addPoint(std::move(p), t.id);
      } else {
        t.kfObs = {Obs{k0, u0}, Obs{k0 + 1, u1}};
      }
    }
    for (Track& t : tracks_) {
      t.fromRef = false;
      t.oldObs.clear();
      t.oldPoint = -1;
    }
    Frame& fr = frames_.back();
    fr.T = T1;
    fr.posed = true;
    fr.status = everInitialised_ ? SlamStatus::Relocalised : SlamStatus::Tracked;
    frames_[static_cast<std::size_t>(refFrame_)].T = Tref;
    frames_[static_cast<std::size_t>(refFrame_)].posed = true;
    // Frames between: interpolated for now (refined against the map in finish()).
    for (int g = refFrame_ + 1; g < f; ++g) {
      const Scalar a = Scalar(g - refFrame_) / Scalar(f - refFrame_);
      Frame& m = frames_[static_cast<std::size_t>(g)];
      m.T = SE3T(m.rotationKnown ? m.T.rotation() : interpolate(Tref.rotation(), T1.rotation(), a),
                 V3((Scalar(1) - a) * Tref.translation() + a * T1.translation()));
    }
    state_ = State::Tracking;
    everInitialised_ = true;
    afterLoss_ = false;
    lost_ = 0;
    closeKeyframe(fr);
  }

  /// After a reset, the similarity taking the new two-view map (reference camera frame, unit
  /// baseline) into the old world (similarity_join.hpp), from the tracks the old segment saw:
  /// their rays in the old keyframes, or their old map points; started at the reference frame's
  /// rotation from the ray chain and its held position. Accepted with joinMinTracks inliers (half
  /// of the candidates at least) and the scale known to joinMaxScaleStd: old keyframes too close
  /// to the new cameras leave it unobservable, and the median-depth join is kept. `linked`: per
  /// idx entry, the tracks that agree.
  bool joinToOldMap(int f, const TwoViewResult<Scalar>& tv, const std::vector<int>& idx, SE3T& Tref, Scalar& sOut,
                    std::vector<char>& linked) {
    linked.assign(idx.size(), 0);
    std::vector<SimJoinCandidate<Scalar>> cands;
    std::vector<int> candJ;
    std::vector<Scalar> depths;
    for (std::size_t j = 0; j < idx.size(); ++j) {
      if (!tv.triangulated[j]) continue;
      const Track& t = tracks_[static_cast<std::size_t>(idx[j])];
      if (t.oldPoint < 0 && t.oldObs.empty()) continue;
      SimJoinCandidate<Scalar> cd;
      cd.x = tv.points[j];
      if (t.oldPoint >= 0) cd.rows.push_back({points_[static_cast<std::size_t>(t.oldPoint)].X, V3::Zero(), true});
      for (const Obs& o : t.oldObs) {
        const Keyframe& kf = keyframes_[static_cast<std::size_t>(o.kf)];
        const V3 x((o.uv(0) - cam_.cx) / cam_.fx, (o.uv(1) - cam_.cy) / cam_.fy, Scalar(1));
        cd.rows.push_back({kf.T.translation(), V3(kf.T.rotationMatrix() * x).normalized(), false});
      }
      if (tv.points[j](2) > Scalar(0)) depths.push_back(tv.points[j](2));
      cands.push_back(std::move(cd));
      candJ.push_back(static_cast<int>(j));
    }
    const int nc = static_cast<int>(cands.size());
    if (nc < opt_.joinMinTracks || depths.empty()) {
      if (opt_.log) opt_.log("frame " + std::to_string(f) + ": join to the old map: " + std::to_string(nc) + " candidate tracks, too few");
      return false;
    }
    std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2), depths.end());
    const Scalar focal = Scalar(0.5) * (cam_.fx + cam_.fy);
    SimJoinOptions<Scalar> jo;
    jo.thresholdRad = opt_.maxReprojPx / focal;
    jo.noiseRad = Scalar(1) / focal;
    jo.distanceGuess = lastMedianDepth_ > Scalar(0) ? lastMedianDepth_ : Scalar(1);
    jo.scaleGuess = jo.distanceGuess / depths[depths.size() / 2];  // the median-depth join
    jo.seed = 0x9e3779b9u + static_cast<std::uint32_t>(f);
    const SimJoinResult<Scalar> r = estimateSimilarityJoin(cands, Mat3<Scalar>(Tref.rotationMatrix()), V3(Tref.translation()), jo);
    const bool ok = r.solved && r.numInliers >= opt_.joinMinTracks && 2 * r.numInliers >= nc && r.scaleRelStd <= opt_.joinMaxScaleStd;
    if (opt_.log) {
      opt_.log("frame " + std::to_string(f) + ": join to the old map: " + std::to_string(nc) + " candidate tracks, " +
               std::to_string(r.numInliers) + " agree, scale " + std::to_string(double(r.s)) + " (median-depth guess " +
               std::to_string(double(jo.scaleGuess)) + ", relative std " + std::to_string(double(r.scaleRelStd)) +
               "), rotation changed " +
               std::to_string(double(r.solved ? rotationAngleDeg(Tref, SE3T(SO3<Scalar>::fromMatrix(r.R), r.c)) : Scalar(0))) +
               " deg, centre moved " + std::to_string(double((r.c - Tref.translation()).norm())) + (ok ? ": joined" : ": not joined"));
    }
    if (!ok) return false;
    Tref = SE3T(SO3<Scalar>::fromMatrix(r.R), r.c);
    sOut = r.s;
    for (std::size_t c = 0; c < cands.size(); ++c) {
      if (r.inliers[c]) linked[static_cast<std::size_t>(candJ[c])] = 1;
    }
    return true;
  }

  /// Appends the current pyramid as keyframe k's to `store`, at most `capacity` entries of its
  /// kind (`anchor`) there (the oldest entry of that kind goes, its buffers reused); the store
  /// stays sorted by keyframe.
  void keepPyramid(std::vector<KeyframePyramid>& store, int capacity, int k, bool anchor = false) {
    auto ofKind = [anchor](const KeyframePyramid& e) { return e.anchor == anchor; };
    const auto oldest = std::find_if(store.begin(), store.end(), ofKind);
    if (oldest != store.end() && std::count_if(store.begin(), store.end(), ofKind) >= capacity) {
      std::rotate(oldest, oldest + 1, store.end());  // to the back, its buffers reused
    } else {
      store.emplace_back();
    }
    store.back().kf = k;
    store.back().pyr = curPyr_;
    store.back().anchor = anchor;
  }

  /// relocPyr_: keyframe k joins as an anchor when no anchor of the segment looks within
  /// relocAnchorDeg of its direction from within relocAnchorDepths median scene depths, else as
  /// a recent one; each kind drops its oldest beyond its capacity (keepPyramid).
  void keepRelocPyramid(int k) {
    const Keyframe& kk = keyframes_[static_cast<std::size_t>(k)];
    const V3 z = kk.T.rotationMatrix().col(2);
    const Scalar cosMax = std::cos(opt_.relocAnchorDeg * Constants<Scalar>::pi() / Scalar(180));
    const Scalar maxDist = opt_.relocAnchorDepths * lastMedianDepth_;
    const bool anchor = opt_.relocAnchors > 0 && lastMedianDepth_ > Scalar(0) &&
                        std::none_of(relocPyr_.begin(), relocPyr_.end(), [&](const KeyframePyramid& e) {
                          const Keyframe& ka = keyframes_[static_cast<std::size_t>(e.kf)];
                          return e.anchor && ka.segment == kk.segment && V3(ka.T.rotationMatrix().col(2)).dot(z) >= cosMax &&
                                 (ka.T.translation() - kk.T.translation()).norm() <= maxDist;
                        });
    keepPyramid(relocPyr_, anchor ? opt_.relocAnchors : opt_.relocKeyframes, k, anchor);
  }

  /// After a keyframe's points are in: sliding-window bundle adjustment, the frame takes the
  /// adjusted pose, new corners fill the grid (their first keyframe observation is this one).
  void closeKeyframe(Frame& fr) {
    const int k = static_cast<int>(keyframes_.size()) - 1;
    adjust(lastWindow(), opt_.localIterations, false);
    fr.T = keyframes_.back().T;
    const bool current = keyframes_.back().frame == static_cast<int>(frames_.size()) - 1;
    // The current frame's pyramid, for re-finding this keyframe's points later.
    if (opt_.refindKeyframes > 0 && current) keepPyramid(kfPyr_, opt_.refindKeyframes, k);
    if (opt_.segmentLinks && current) {
      lastKfPyr_.kf = k;
      lastKfPyr_.pyr.levels = curPyr_.levels;  // (buffers reused)
    }
    if (opt_.relocalise && opt_.relocKeyframes > 0 && current &&
        (relocPyr_.empty() ||
         keyframes_.back().frame - keyframes_[static_cast<std::size_t>(relocPyr_.back().kf)].frame >= opt_.relocSpacing)) {
      keepRelocPyramid(k);
    }
    lastKfInliers_ = countMapped();
    framesSinceKf_ = 0;
    replenish();
    for (Track& t : tracks_) {
      if (t.point < 0 && t.kfObs.empty()) t.kfObs = {Obs{k, V2(Scalar(t.uv(0)), Scalar(t.uv(1)))}};
    }
    updateMedianDepth();
  }

  // ---------------------------------------------------------------- tracking
  /// Angle of the relative rotation between two poses (degrees): acos((tr(R_aᵀR_b) − 1)/2).
  static Scalar rotationAngleDeg(const SE3T& a, const SE3T& b) {
    const Scalar c = (Mat3<Scalar>(a.rotationMatrix().transpose() * b.rotationMatrix()).trace() - Scalar(1)) / Scalar(2);
    return std::acos(std::max(Scalar(-1), std::min(Scalar(1), c))) * Scalar(180) / Constants<Scalar>::pi();
  }

  /// The tracks that follow a map point: its position, the track's pixel, the track's index.
  /// (A track never refers to an invalid point: cullObservations removes those tracks.)
  void mappedTracks(std::vector<V3>& X, std::vector<V2>& uv, std::vector<int>& ti) const {
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
      if (tracks_[i].point < 0) continue;
      X.push_back(points_[static_cast<std::size_t>(tracks_[i].point)].X);
      uv.push_back(V2(Scalar(tracks_[i].uv(0)), Scalar(tracks_[i].uv(1))));
      ti.push_back(static_cast<int>(i));
    }
  }

  /// After PnP-RANSAC on mappedTracks: an outlier track has drifted off its point, so it is
  /// dropped (a new corner replaces it).
  void dropOutlierTracks(const std::vector<int>& ti, const std::vector<char>& inliers) {
    std::vector<char> drop(tracks_.size(), 0);
    for (std::size_t j = 0; j < ti.size(); ++j) {
      if (!inliers[j]) drop[static_cast<std::size_t>(ti[j])] = 1;
    }
    removeTracks(drop);
  }

  int countMapped() const {
    int n = 0;
    for (const Track& t : tracks_) n += t.point >= 0 ? 1 : 0;
    return n;
  }

  void trackPose(int f) {
    Frame& fr = frames_.back();
    if (opt_.refindKeyframes > 0 && countMapped() < opt_.refindBelow) refindPoints(f);
    std::vector<V3> X;
    std::vector<V2> uv;
    std::vector<int> ti;
    mappedTracks(X, uv, ti);
    bool ok = false;
    // Rotation-checked tracking: while a head turn sweeps the map out of view, fewer than
    // minInliers map points may remain. A pose from as few as minTurnInliers is accepted when
    // its rotation agrees with the one of all tracked rays (hundreds of tracks, mapped or not;
    // near-exact for a rotation-dominant motion) and most of the points are inliers.
    const int needed = std::min(opt_.minInliers, opt_.minTurnInliers);
    Mat3<Scalar> dRays;
    const bool haveRays = (turning_ || opt_.fewPointsRayCheck) && static_cast<int>(X.size()) < 2 * opt_.minInliers && rayRotation(dRays);
    if (static_cast<int>(X.size()) >= (haveRays ? needed : opt_.minInliers)) {
      PnPRansacOptions<Scalar> po = opt_.pnp;
      po.seed = opt_.pnp.seed + static_cast<std::uint32_t>(f);
      po.minInliers = haveRays ? needed : opt_.minInliers;
      const PnPRansacResult<Scalar> r = solvePnPRansac(X, uv, cam_, po);
      bool accept = r.ok();
      if (accept && r.numInliers < opt_.minInliers) {
        const SE3T& prev = frames_[static_cast<std::size_t>(f - 1)].T;
        const SE3T byRays(SO3<Scalar>::fromMatrix(Mat3<Scalar>(prev.rotationMatrix() * dRays)), prev.translation());
        accept = rotationAngleDeg(byRays, r.T_w_c) < opt_.turnRotationAgreementDeg &&
                 Scalar(r.numInliers) >= Scalar(0.8) * Scalar(X.size());
      }
      if (accept) {
        ok = true;
        fr.T = r.T_w_c;
        fr.inliers = r.numInliers;
        dropOutlierTracks(ti, r.inliers);
      }
    }
    if (opt_.log) {
      opt_.log("frame " + std::to_string(f) + ": pnp " + std::to_string(X.size()) + " mapped tracks, " +
               std::to_string(ok ? fr.inliers : 0) + " inliers, " + std::to_string(tracks_.size()) + " tracks");
    }
    if (ok) {
      bridged_ = 0;
    } else if (opt_.turnBridge && turning_ && f >= 2 && frames_[static_cast<std::size_t>(f - 1)].posed &&
               frames_[static_cast<std::size_t>(f - 2)].posed && bridged_ < opt_.maxBridgeFrames) {
      ok = bridgeTurn(f);
      bridged_ = ok ? bridged_ + 1 : 0;
    }
    if (ok) {
      fr.posed = true;
      fr.status = SlamStatus::Tracked;
      lost_ = 0;
      ++framesSinceKf_;
      const int mapped = fr.inliers;
      // A keyframe when the map thins out (but not more often than keyframeMinInterval unless
      // tracking is about to fail) or after keyframeMaxInterval frames.
      const bool thin = mapped < opt_.keyframeMinInliers || Scalar(mapped) < opt_.keyframeInlierRatio * Scalar(lastKfInliers_);
      // Rotation-aware (turn mode): a head turn sweeps the map out of view within a few frames,
      // and new corners are only detected at keyframes, so a keyframe every
      // keyframeMaxRotationDeg of rotation keeps the leading edge of the view seeded (its tracks
      // are triangulated once the neck's translation gives them parallax).
      const bool swept = turning_ && rotationAngleDeg(keyframes_.back().T, fr.T) > opt_.keyframeMaxRotationDeg;
      if (framesSinceKf_ >= opt_.keyframeMaxInterval || (thin && framesSinceKf_ >= opt_.keyframeMinInterval) ||
          (mapped < 2 * opt_.minInliers && framesSinceKf_ >= opt_.keyframeThinInterval) || swept) {
        insertKeyframe(f);
      }
      return;
    }
    // Lost: rotation from the rays, position held; relocalisation against the map; after a few
    // frames, a new map segment.
    fr.posed = false;
    Mat3<Scalar> dR;
    const Frame& prev = frames_[static_cast<std::size_t>(f - 1)];
    if (rayRotation(dR)) {
      fr.T = SE3T(SO3<Scalar>::fromMatrix(Mat3<Scalar>(prev.T.rotationMatrix() * dR)), prev.T.translation());
    } else if (!coastRotation(f)) {
      fr.T = prev.T;
      fr.rotationKnown = false;
    }
    if (relocalise(f)) return;
    if (lost_ == 0) ++losses_;
    ++lost_;
    fr.status = SlamStatus::Lost;
    if (lost_ >= opt_.lostFramesBeforeReset) {
      state_ = State::Initialising;
      afterLoss_ = true;
      ++resets_;
      ++segment_;
      segmentStart_ = f;
      // The tracks go on, under new ids: their old observations keep mapping to the old points.
      // Their observations in the old segment's keyframes (or their old points) are kept to join
      // the new map to the old one (joinToOldMap).
      for (Track& t : tracks_) {
        t.oldPoint = t.point >= 0 && points_[static_cast<std::size_t>(t.point)].valid ? t.point : -1;
        t.oldObs.clear();
        if (t.oldPoint < 0) std::swap(t.oldObs, t.kfObs);
        t.point = -1;
        t.kfObs.clear();
        const int oldId = t.id;
        t.id = static_cast<int>(trackPoint_.size());
        trackPoint_.push_back(-1);
        trackAlias_.resize(trackPoint_.size(), -1);
        trackAlias_.back() = oldId;
      }
      kfPyr_.clear();
      setReference(f);
    }
  }

  /// SlamOptions::turnBridge (turn_bridge.hpp): the pose of frame f from frame f − 1 and the
  /// tracks between them. The length's points: the map points still tracked and every other
  /// track seen in frames f − 2 and f − 1 (both posed), triangulated from those two.
  bool bridgeTurn(int f) {
    Frame& fr = frames_.back();
    const Frame& p1 = frames_[static_cast<std::size_t>(f - 1)];
    const Frame& p2 = frames_[static_cast<std::size_t>(f - 2)];
    const SE3T T1cw = p1.T.inverse(), T2cw = p2.T.inverse();
    const Scalar cosMin = std::cos(opt_.bridgeMinParallaxDeg * Constants<Scalar>::pi() / Scalar(180));
    std::vector<V2> x1, x2, y;
    std::vector<V3> X;
    x1.reserve(tracks_.size()), x2.reserve(tracks_.size());
    int fresh = 0;
    // (Tracks added after the KLT step, by re-finding, have no previous position: the first
    // prevUv_.size() are the tracked ones.)
    for (std::size_t i = 0; i < std::min(tracks_.size(), prevUv_.size()); ++i) {
      const Track& t = tracks_[i];
      x1.push_back(normalised(prevUv_[i]));
      x2.push_back(normalised(t.uv));
      if (t.point >= 0 && points_[static_cast<std::size_t>(t.point)].valid) {
        X.push_back(points_[static_cast<std::size_t>(t.point)].X);
        y.push_back(x2.back());
        continue;
      }
      // Its observation in frame f − 2 (observation lists are sorted by track id).
      const auto it = std::lower_bound(p2.obsTrack.begin(), p2.obsTrack.end(), t.id);
      if (it == p2.obsTrack.end() || *it != t.id) continue;
      const Vec2f& u2 = p2.obsUv[static_cast<std::size_t>(it - p2.obsTrack.begin())];
      const V2 x0 = normalised(u2);
      const V3 r0 = p2.T.rotationMatrix() * V3(x0(0), x0(1), Scalar(1));
      const V3 r1 = p1.T.rotationMatrix() * V3(x1.back()(0), x1.back()(1), Scalar(1));
      if (r0.normalized().dot(r1.normalized()) > cosMin) continue;
      V3 P;
      if (!triangulateDLT(T2cw, T1cw, x0, x1.back(), P)) continue;
      if (!((T2cw * P)(2) > Scalar(0)) || !((T1cw * P)(2) > Scalar(0))) continue;
      X.push_back(P);
      y.push_back(x2.back());
      ++fresh;
    }
    // Predicted length: the last step's radius, |c₁ − c₂| / (2·sin(θ₁₂/2)), times 2·sin(θ/2)
    // with θ the rays' rotation (none when the last step hardly turned).
    Scalar step = Scalar(-1);
    Mat3<Scalar> dR;
    const Scalar th12 = rotationAngleDeg(p2.T, p1.T) * Constants<Scalar>::pi() / Scalar(180);
    if (th12 > Scalar(2) * Constants<Scalar>::pi() / Scalar(180) && rayRotation(dR)) {
      const Scalar th = SO3<Scalar>::fromMatrix(dR).log().norm();
      step = (p1.T.translation() - p2.T.translation()).norm() / (Scalar(2) * std::sin(th12 / Scalar(2))) * Scalar(2) * std::sin(th / Scalar(2));
    }
    const TurnBridgeResult<Scalar> r = bridgeTurnPose(p1.T, x1, x2, X, y, cam_.fx, step, opt_.bridge);
    if (opt_.log) {
      opt_.log("frame " + std::to_string(f) + ": turn bridge, " + std::to_string(x1.size()) + " tracks, " +
               std::to_string(r.inliers) + " epipolar inliers, rotation moved " + std::to_string(double(r.rotationChangeDeg)) +
               " deg from the rays', length " + std::to_string(double(r.length)) + " (predicted " + std::to_string(double(step)) + ") from " + std::to_string(r.pointInliers) + " of " +
               std::to_string(X.size()) + " points (" + std::to_string(fresh) + " triangulated): " + (r.ok ? std::string("posed") : r.why));
    }
    if (!r.ok) return false;
    fr.T = r.T_w_c;
    fr.inliers = r.pointInliers;
    return true;
  }

  /// SlamOptions::relocalise: the points of the kept keyframes searched under the frame's guess
  /// (frames_.back().T: rotation from the rays, position held), then PnP-RANSAC on every mapped
  /// track. Success: the frame is Relocalised in the old segment (a reset without a new map is
  /// undone) and becomes a keyframe. Failure: the tracks the search added are dropped again.
  bool relocalise(int f) {
    Frame& fr = frames_.back();
    if (!opt_.relocalise || relocPyr_.empty()) return false;
    // The guess's rotation is the rays' when the ray chain is unbroken since the last posed frame;
    // otherwise (every track died: a hand over the lens, a black frame) it is only held.
    bool chain = true;
    for (int g = f; g > 0 && chain && !frames_[static_cast<std::size_t>(g)].posed; --g) {
      chain = frames_[static_cast<std::size_t>(g)].rotationKnown;
    }
    const std::size_t before = tracks_.size();
    searchMapPoints(f, relocPyr_, fr.T, opt_.relocMaxShiftPx, opt_.relocMaxPoints, "relocalisation");
    std::vector<V3> X;
    std::vector<V2> uv;
    std::vector<int> ti;
    mappedTracks(X, uv, ti);
    bool ok = false;
    PnPRansacResult<Scalar> r;
    if (static_cast<int>(X.size()) >= opt_.relocMinInliers) {
      PnPRansacOptions<Scalar> po = opt_.pnp;
      po.seed = opt_.pnp.seed + 0x5bd1e995u + static_cast<std::uint32_t>(f);
      po.minInliers = opt_.relocMinInliers;
      r = solvePnPRansac(X, uv, cam_, po);
      // The rays' rotation is near-exact over a short loss: a pose that disagrees with it is a
      // wrong match set (measured: right ones agree within 0.42°, wrong ones are 1-10° off).
      // Without the chain, or when the chain disagrees (its rotation drifts in a fast turn: the
      // rays' pure-rotation fit absorbs the neck's translation, up to 1° a frame), two consecutive
      // relocalisations must agree with the rays' rotation between them instead.
      ok = r.ok() && r.numInliers >= opt_.relocMinInliers;
      if (ok && chain && rotationAngleDeg(fr.T, r.T_w_c) <= opt_.relocMaxRotationDeg) {
        ok = true;
      } else if (ok) {
        const SE3T& prevGuess = frames_[static_cast<std::size_t>(f - 1)].T;
        const bool agree = relocCandidateFrame_ == f - 1 && fr.rotationKnown &&
                           rotationAngleDeg(SE3T(relocCandidate_.inverse() * r.T_w_c), SE3T(prevGuess.inverse() * fr.T)) <=
                               opt_.relocMaxRotationDeg;
        relocCandidateFrame_ = f;
        relocCandidate_ = r.T_w_c;
        ok = agree;
      }
    }
    if (opt_.log) {
      opt_.log("frame " + std::to_string(f) + ": relocalisation: " + std::to_string(X.size()) + " mapped tracks, " +
               std::to_string(r.ok() ? r.numInliers : 0) + " inliers" +
               (r.ok() ? ": rotation " + std::to_string(double(rotationAngleDeg(fr.T, r.T_w_c))) + " deg from the " +
                             (chain ? "rays'" : "held one") + ", moved " +
                         std::to_string(double((r.T_w_c.translation() - fr.T.translation()).norm() / std::max(lastMedianDepth_, Scalar(1e-9)))) +
                         " scene depths" + (ok ? ": relocalised" : ": rejected")
                   : std::string()));
    }
    if (!ok) {
      removeTracksFrom(before);
      return false;
    }
    fr.T = r.T_w_c;
    fr.posed = true;
    fr.inliers = r.numInliers;
    fr.status = SlamStatus::Relocalised;
    dropOutlierTracks(ti, r.inliers);
    if (state_ == State::Initialising) {
      // The reset built no map: the old segment goes on.
      --resets_;
      segment_ = keyframes_.back().segment;
      for (int g = std::max(0, std::min(segmentStart_, refFrame_)); g <= f; ++g) frames_[static_cast<std::size_t>(g)].mask = CoarseMask();
      for (Track& t : tracks_) {
        t.fromRef = false;
        t.oldObs.clear();
        t.oldPoint = -1;
      }
      state_ = State::Tracking;
    }
    afterLoss_ = false;
    lost_ = 0;
    ++relocalisations_;
    insertKeyframe(f);
    return true;
  }

  /// Map points of the recent keyframes (kfPyr_) that no live track follows and that project
  /// into the frame under the predicted pose, off the hand mask: KLT from the keyframe's image at
  /// the point's observation (forward-backward checked) started at the prediction; a result
  /// within refindMaxShiftPx of it becomes a mapped track again (PnP-RANSAC then judges it). A
  /// point covered by a hand, or out of view in a turn, and seen again keeps its place in the map
  /// instead of being replaced by a new, unmapped corner.
  void refindPoints(int f) { searchMapPoints(f, kfPyr_, predicted_, opt_.refindMaxShiftPx, opt_.refindMaxPoints, "re-finding"); }

  /// The search of refindPoints over the keyframe pyramids `store` (newest first), the points
  /// projected under `pose`, accepted within maxShiftPx of their projection; the found points
  /// become mapped tracks.
  void searchMapPoints(int f, const std::vector<KeyframePyramid>& store, const SE3T& pose, Scalar maxShiftPx, int maxPoints,
                      const char* what, const std::vector<char>* use = nullptr) {
    if (store.empty()) return;
    std::vector<char> tried(points_.size(), 0);
    for (const Track& t : tracks_) {
      if (t.point >= 0) tried[static_cast<std::size_t>(t.point)] = 1;
    }
    const SE3T Tcw = pose.inverse();
    const SE3T Tpw = frames_[static_cast<std::size_t>(f - 1)].T.inverse();
    const float margin = float(opt_.klt.halfWindow + 2);
    const bool withPrev = prevUv_.size() == tracks_.size();
    int attempts = 0, found = 0;
    std::vector<Vec2f> from, to, guess;
    std::vector<int> pids;
    std::vector<char> ok;
    for (auto it = store.rbegin(); it != store.rend() && attempts < maxPoints; ++it) {
      if (use && !(*use)[static_cast<std::size_t>(store.rend() - it - 1)]) continue;
      const int k = it->kf;
      from.clear(), to.clear(), pids.clear();
      for (int pid : keyframes_[static_cast<std::size_t>(k)].points) {
        if (attempts >= maxPoints) break;
        if (tried[static_cast<std::size_t>(pid)]) continue;
        const MapPoint& p = points_[static_cast<std::size_t>(pid)];
        if (!p.valid) continue;
        const Obs* o = nullptr;
        for (const Obs& ob : p.obs) {
          if (ob.kf == k) {
            o = &ob;
            break;
          }
        }
        if (!o) continue;
        const V3 Xc = Tcw * p.X;
        if (!(Xc(2) > Scalar(0))) continue;
        const V2 q = cam_.project(Xc);
        const Vec2f g(float(q(0)), float(q(1)));
        const Vec2f u0(float(o->uv(0)), float(o->uv(1)));
        if (!std::isfinite(g(0)) || !std::isfinite(g(1)) || !insideImage(g, margin) || masked(g) || !insideImage(u0, margin)) continue;
        tried[static_cast<std::size_t>(pid)] = 1;
        from.push_back(u0);
        to.push_back(g);
        pids.push_back(pid);
        ++attempts;
      }
      if (from.empty()) continue;
      guess = to;
      trackKlt(it->pyr, curPyr_, from, to, ok, opt_.klt);
      const float maxShift2 = float(maxShiftPx * maxShiftPx);
      for (std::size_t i = 0; i < from.size(); ++i) {
        const float dx = to[i](0) - guess[i](0), dy = to[i](1) - guess[i](1);
        if (!ok[i] || dx * dx + dy * dy > maxShift2 || !insideImage(to[i], margin) || masked(to[i])) continue;
        Track t;
        t.id = static_cast<int>(trackPoint_.size());
        trackPoint_.push_back(pids[i]);
        t.px = to[i];
        t.uv = rollingShutterShift(to[i], Scalar(1));
        t.point = pids[i];
        if (withPrev) {
          // Its position in the previous frame (for the ray rotation): the projection there.
          const V3 Xp = Tpw * points_[static_cast<std::size_t>(pids[i])].X;
          const V2 qp = Xp(2) > Scalar(0) ? V2(cam_.project(Xp)) : V2(Scalar(to[i](0)), Scalar(to[i](1)));
          prevUv_.push_back(Vec2f(float(qp(0)), float(qp(1))));
        }
        tracks_.push_back(std::move(t));
        ++found;
      }
    }
    if (opt_.log && attempts > 0) {
      opt_.log("frame " + std::to_string(f) + ": " + what + ": " + std::to_string(attempts) + " map points tried, " +
               std::to_string(found) + " found");
    }
  }

  int addPoint(MapPoint&& p, int trackId) {
    const int id = static_cast<int>(points_.size());
    for (const Obs& o : p.obs) keyframes_[static_cast<std::size_t>(o.kf)].points.push_back(id);
    points_.push_back(std::move(p));
    trackPoint_[static_cast<std::size_t>(trackId)] = id;
    return id;
  }

  /// SlamOptions::revisitSearch: the head looks back at a place it mapped a while ago (a standing
  /// person looking around, a table worked at for minutes). The points of the kept keyframes of
  /// this segment at least revisitMinFrames old whose view is within revisitMaxAngleDeg of the
  /// current one are searched under the current pose (searchMapPoints); when PnP-RANSAC on the
  /// found points alone has revisitMinInliers inliers and a rotation within revisitMaxRotationDeg
  /// of the tracked pose, its inliers become tracks of those old points. The keyframe then
  /// observes them: the bundle adjustments tie the current map to the old one (with the old
  /// keyframes fixed in the local window) instead of letting the scale drift turn after turn.
  void searchRevisits(int f) {
    const Frame& fr = frames_.back();
    std::vector<char> use(relocPyr_.size(), 0);
    const V3 z = fr.T.rotationMatrix().col(2);
    const Scalar cosMax = std::cos(opt_.revisitMaxAngleDeg * Constants<Scalar>::pi() / Scalar(180));
    int any = 0;
    for (std::size_t i = 0; i < relocPyr_.size(); ++i) {
      const Keyframe& kf = keyframes_[static_cast<std::size_t>(relocPyr_[i].kf)];
      if (kf.segment != segment_ || f - kf.frame < opt_.revisitMinFrames) continue;
      if (V3(kf.T.rotationMatrix().col(2)).dot(z) < cosMax) continue;
      use[i] = 1;
      ++any;
    }
    if (!any) return;
    const std::size_t before = tracks_.size();
    searchMapPoints(f, relocPyr_, fr.T, opt_.revisitMaxShiftPx, opt_.revisitMaxPoints, "revisit", &use);
    std::vector<V3> X;
    std::vector<V2> uv;
    foundCorrespondences(before, X, uv);
    bool ok = false;
    PnPRansacResult<Scalar> r;
    if (static_cast<int>(X.size()) >= opt_.revisitMinInliers) {
      PnPRansacOptions<Scalar> po = opt_.pnp;
      po.seed = opt_.pnp.seed + 0x2545f491u + static_cast<std::uint32_t>(f);
      po.minInliers = opt_.revisitMinInliers;
      r = solvePnPRansac(X, uv, cam_, po);
      ok = r.ok() && r.numInliers >= opt_.revisitMinInliers && rotationAngleDeg(fr.T, r.T_w_c) <= opt_.revisitMaxRotationDeg;
    }
    std::vector<char> drop(tracks_.size(), 0);
    int kept = 0;
    for (std::size_t i = before; i < tracks_.size(); ++i) {
      drop[i] = !ok || !r.inliers[i - before];
      kept += drop[i] ? 0 : 1;
    }
    removeTracks(drop);
    revisitPoints_ += kept;
    if (opt_.log) {
      opt_.log("frame " + std::to_string(f) + ": revisit: " + std::to_string(X.size()) + " old points found, " +
               std::to_string(ok ? r.numInliers : 0) + " PnP inliers" +
               (r.ok() ? ", rotation " + std::to_string(double(rotationAngleDeg(fr.T, r.T_w_c))) + " deg from the tracked pose, moved " +
                             std::to_string(double((r.T_w_c.translation() - fr.T.translation()).norm() / std::max(lastMedianDepth_, Scalar(1e-9)))) +
                             " scene depths"
                       : std::string()) +
               (ok ? ": kept " + std::to_string(kept) : ": none kept"));
    }
  }

  /// A frame that breaks the rotation chain: no rotation, or one only carried on (coastRotation;
  /// right within a few degrees in a steady turn, far off when the turn changes under it).
  bool chainBreak(int f) const {
    const Frame& fr = frames_[static_cast<std::size_t>(f)];
    return !fr.rotationKnown || fr.coasted;
  }
  /// The first frame of frame f's rotation chain: the frame after the last break before it
  /// (0: unbroken since the start).
  int chainStart(int f) const {
    for (int g = f; g > 0; --g) {
      if (chainBreak(g)) return g + 1;
    }
    return 0;
  }

  /// SlamOptions::segmentLinks: frame f (a keyframe, or every linkEveryFrames-th frame without a
  /// map pose) whose rotation chain starts after the kept images of the segment before the break
  /// (linkPyr_): each image is tried as the current view (its points searched by KLT around where
  /// it saw them), and a PnP pose in that segment's world with linkMinInliers inliers is kept as
  /// a link. Its tracks are not kept: the worlds differ.
  void searchSegmentLinks(int f) {
    if (linkPyr_.empty() || chainBreak(f)) return;
    const int start = chainStart(f);
    int linked = 0;
    for (const SegmentLink& l : links_) linked += l.frame >= start ? 1 : 0;
    if (linked >= opt_.linkEnough) {  // enough to agree on: the images go
      std::vector<KeyframePyramid>().swap(linkPyr_);
      return;
    }
    for (std::size_t i = 0; i < linkPyr_.size(); ++i) {
      const Keyframe& kk = keyframes_[static_cast<std::size_t>(linkPyr_[i].kf)];
      std::vector<char> use(linkPyr_.size(), 0);
      use[i] = 1;
      // The guesses: the kept keyframe's own view, then turned by ±linkYawStepDeg, ±2·… about
      // its camera's vertical axis (a head turns mostly about it; KLT reaches about 8° from a
      // guess at 640×480).
      PnPRansacResult<Scalar> r;
      std::size_t found = 0;
      bool ok = false;
      for (int h = 0; h <= 2 * opt_.linkYawSteps && !ok; ++h) {
        const Scalar yaw = Scalar((h + 1) / 2 * (h % 2 == 1 ? 1 : -1)) * opt_.linkYawStepDeg * Constants<Scalar>::pi() / Scalar(180);
        const SE3T guess = kk.T * SE3T(SO3<Scalar>::exp(V3(Scalar(0), yaw, Scalar(0))), V3::Zero());
        const std::size_t before = tracks_.size();
        searchMapPoints(f, linkPyr_, guess, opt_.linkMaxShiftPx, opt_.linkMaxPoints, "segment link", &use);
        std::vector<V3> X;
        std::vector<V2> uv;
        foundCorrespondences(before, X, uv);
        removeTracksFrom(before);
        found = std::max(found, X.size());
        if (static_cast<int>(X.size()) < opt_.linkMinInliers) continue;
        PnPRansacOptions<Scalar> po = opt_.pnp;
        po.seed = opt_.pnp.seed + 0x68e31da4u + static_cast<std::uint32_t>(f);
        po.minInliers = opt_.linkMinInliers;
        r = solvePnPRansac(X, uv, cam_, po);
        ok = r.ok() && r.numInliers >= opt_.linkMinInliers;
      }
      if (opt_.log) {
        opt_.log("frame " + std::to_string(f) + ": segment link to keyframe " + std::to_string(linkPyr_[i].kf) + " (frame " +
                 std::to_string(kk.frame) + "): at most " + std::to_string(found) + " points found" +
                 (ok ? ", " + std::to_string(r.numInliers) + " PnP inliers, rotation " +
                           std::to_string(double(rotationAngleDeg(frames_[static_cast<std::size_t>(f)].T, r.T_w_c))) + " deg from the frame's: kept"
                     : std::string(": none")));
      }
      if (ok) links_.push_back(SegmentLink{f, kk.frame, r.T_w_c, r.numInliers});
    }
  }

  /// SlamOptions::segmentLinks: the first frame that link l's correction applies to. After the
  /// last frame without a rotation between its kept image and it; when there is none (only
  /// rotations carried on: coastRotation), after the first run of carried-on frames.
  int linkChainStart(const SegmentLink& l) const {
    for (int g = l.frame; g > l.oldFrame; --g) {
      if (!frames_[static_cast<std::size_t>(g)].rotationKnown) return g + 1;
    }
    int g = l.oldFrame + 1;
    while (g <= l.frame && !chainBreak(g)) ++g;
    while (g <= l.frame && chainBreak(g)) ++g;
    return g;
  }

  /// SlamOptions::segmentLinks, in finish() before the joins. The links are grouped by the frame
  /// their correction starts at (linkChainStart); for each group, in order, the corrections
  /// C = R_old(f)·R(f)ᵀ (R_old with the corrections already made to the older frames) must
  /// agree, two at different frames within linkAgreeDeg; the best-supported one (then the most
  /// inliers) rotates the frames from the start on (keyframes and points with them) about the
  /// start frame's position. The joins then place and scale the segments.
  void applySegmentLinks() {
    if (links_.empty()) return;
    const int n = static_cast<int>(frames_.size());
    const Scalar agreeRad = opt_.linkAgreeDeg * Constants<Scalar>::pi() / Scalar(180);
    std::vector<int> starts(links_.size());
    for (std::size_t i = 0; i < links_.size(); ++i) starts[i] = linkChainStart(links_[i]);
    std::vector<int> order = starts;
    std::sort(order.begin(), order.end());
    order.erase(std::unique(order.begin(), order.end()), order.end());
    std::vector<std::pair<int, Mat3<Scalar>>> made;  // (first frame, rotation) of each correction
    for (int S : order) {
      if (S >= n) continue;
      std::vector<Mat3<Scalar>> C;
      std::vector<const SegmentLink*> L;
      for (std::size_t i = 0; i < links_.size(); ++i) {
        const SegmentLink& l = links_[i];
        if (starts[i] != S || l.frame < S) continue;
        Mat3<Scalar> Rold = l.T_old.rotationMatrix();
        for (const auto& m : made) {
          if (m.first <= l.oldFrame) Rold = m.second * Rold;
        }
        C.push_back(Mat3<Scalar>(Rold * frames_[static_cast<std::size_t>(l.frame)].T.rotationMatrix().transpose()));
        L.push_back(&l);
      }
      int best = -1, bestSupport = 0;
      for (std::size_t i = 0; i < C.size(); ++i) {
        int support = 0;
        for (std::size_t j = 0; j < C.size(); ++j) {
          if (L[j]->frame != L[i]->frame && SO3<Scalar>::fromMatrix(Mat3<Scalar>(C[i].transpose() * C[j])).log().norm() <= agreeRad) ++support;
        }
        if (support > bestSupport || (support > 0 && support == bestSupport && L[i]->inliers > L[static_cast<std::size_t>(best)]->inliers)) {
          best = static_cast<int>(i), bestSupport = support;
        }
      }
      if (opt_.log && !C.empty()) {
        opt_.log("rotation chain from frame " + std::to_string(S) + ": " + std::to_string(C.size()) + " links" +
                 (best >= 0 ? ", the best agreed by " + std::to_string(bestSupport) + ": rotated by " +
                                  std::to_string(double(SO3<Scalar>::fromMatrix(C[static_cast<std::size_t>(best)]).log().norm() * Scalar(180) /
                                                        Constants<Scalar>::pi())) + " deg"
                            : std::string(", none agree")));
      }
      if (best < 0) continue;
      const Mat3<Scalar> R = C[static_cast<std::size_t>(best)];
      const V3 c = frames_[static_cast<std::size_t>(S)].T.translation();
      auto move = [&](const SE3T& T) {
        return SE3T(SO3<Scalar>::fromMatrix(Mat3<Scalar>(R * T.rotationMatrix())), V3(R * (T.translation() - c) + c));
      };
      for (int g = S; g < n; ++g) frames_[static_cast<std::size_t>(g)].T = move(frames_[static_cast<std::size_t>(g)].T);
      for (Keyframe& kf : keyframes_) {
        if (kf.frame >= S) kf.T = move(kf.T);
      }
      for (MapPoint& p : points_) {
        if (!p.obs.empty() && keyframes_[static_cast<std::size_t>(p.obs.front().kf)].frame >= S) p.X = V3(R * (p.X - c) + c);
      }
      made.emplace_back(S, R);
    }
  }

  void insertKeyframe(int f) {
    if (opt_.revisitSearch && opt_.relocalise) searchRevisits(f);
    if (opt_.segmentLinks) searchSegmentLinks(f);
    Frame& fr = frames_.back();
    const int k = static_cast<int>(keyframes_.size());
    keyframes_.push_back(Keyframe{f, fr.T, hasMask_ ? CoarseMask(curMask_, opt_.maskBlock) : CoarseMask(), {}, segment_});
    const SE3T Tcw = fr.T.inverse();
    const Scalar cosMin = std::cos(opt_.minTriangulationDeg * Constants<Scalar>::pi() / Scalar(180));
    const Scalar maxErr2 = opt_.maxReprojPx * opt_.maxReprojPx;
    int triCand = 0, triParallax = 0, triNew = 0, triBehind = 0, triReproj = 0;
    for (Track& t : tracks_) {
      const V2 u(Scalar(t.uv(0)), Scalar(t.uv(1)));
      if (t.point >= 0) {
        points_[static_cast<std::size_t>(t.point)].obs.push_back(Obs{k, u});
        keyframes_.back().points.push_back(t.point);
        continue;
      }
      t.kfObs.push_back(Obs{k, u});
      if (t.kfObs.size() < 2) continue;
      // Triangulate from the first keyframe observation and this one.
      const Obs& o0 = t.kfObs.front();
      const SE3T T0cw = keyframes_[static_cast<std::size_t>(o0.kf)].T.inverse();
      const V2 x0 = normalised(Vec2f(float(o0.uv(0)), float(o0.uv(1))));
      const V2 x1 = normalised(t.uv);
      const V3 r0 = keyframes_[static_cast<std::size_t>(o0.kf)].T.rotationMatrix() * V3(x0(0), x0(1), Scalar(1));
      const V3 r1 = fr.T.rotationMatrix() * V3(x1(0), x1(1), Scalar(1));
      ++triCand;
      if (r0.normalized().dot(r1.normalized()) > cosMin) continue;  // not enough parallax yet
      ++triParallax;
      V3 X;
      if (!triangulateDLT(T0cw, Tcw, x0, x1, X)) continue;
      bool good = true;
      for (const Obs& o : t.kfObs) {
        const V3 Xc = keyframes_[static_cast<std::size_t>(o.kf)].T.inverse() * X;
        if (!(Xc(2) > Scalar(0))) {
          good = false;
          ++triBehind;
          break;
        }
        if ((cam_.project(Xc) - o.uv).squaredNorm() > maxErr2) {
          good = false;
          ++triReproj;
          break;
        }
      }
      if (!good) continue;
      ++triNew;
      MapPoint p;
      p.X = X;
      p.obs = t.kfObs;
      t.point = addPoint(std::move(p), t.id);
      t.kfObs.clear();
    }
    const int before = countMapped();
    closeKeyframe(fr);
    if (opt_.log) {
      opt_.log("frame " + std::to_string(f) + ": keyframe " + std::to_string(k) + ", mapped tracks " +
               std::to_string(before) + " -> " + std::to_string(lastKfInliers_) + " after bundle adjustment; " +
               "triangulation: " + std::to_string(triCand) + " candidates, " + std::to_string(triParallax) +
               " with parallax, " + std::to_string(triNew) + " new points (" + std::to_string(triBehind) +
               " behind a camera, " + std::to_string(triReproj) + " off in a keyframe)");
    }
  }

  void updateMedianDepth() {
    const Keyframe& kf = keyframes_.back();
    const SE3T Tcw = kf.T.inverse();
    std::vector<Scalar> d;
    for (int pid : kf.points) {
      const MapPoint& p = points_[static_cast<std::size_t>(pid)];
      if (!p.valid) continue;
      const V3 Xc = Tcw * p.X;
      if (Xc(2) > Scalar(0)) d.push_back(Xc(2));
    }
    if (d.size() >= 10) {
      std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
      lastMedianDepth_ = d[d.size() / 2];
    }
  }

  std::vector<int> lastWindow() const {
    std::vector<int> w;
    for (int k = static_cast<int>(keyframes_.size()) - 1; k >= 0 && static_cast<int>(w.size()) < opt_.windowKeyframes; --k) {
      if (keyframes_[static_cast<std::size_t>(k)].segment != segment_) break;
      w.push_back(k);
    }
    std::reverse(w.begin(), w.end());
    return w;
  }

  // ---------------------------------------------------------------- bundle adjustment
  /// The map's bundle-adjustment settings (keyframe windows, the global BA, the focal profile):
  /// Huber at 2σ with σ = 1 px.
  static BAOptions<Scalar> mapBAOptions(int iterations) {
    BAOptions<Scalar> bo;
    bo.maxIterations = iterations;
    bo.loss = RobustLoss::Huber;
    bo.sigmaPx = Scalar(1);
    bo.robustScale = Scalar(2);
    bo.functionTolerance = Scalar(1e-5);
    return bo;
  }

  /// Bundle adjustment of the keyframes `window` (free) and their points; keyframes outside the
  /// window that see those points are fixed. Gauge: the first keyframe of each segment is fixed
  /// and its first baseline held by a scale prior when no other fixed keyframe anchors the scale.
  void adjust(const std::vector<int>& window, int iterations, bool global, bool withFocal = false) {
    if (window.empty()) return;
    std::vector<int> kfVar(keyframes_.size(), -1), ptVar(points_.size(), -1);
    BAProblem<Scalar> P;
    P.camera = cam_;
    std::vector<int> kfOf, ptOf;
    auto addKf = [&](int k, bool fixed) {
      if (kfVar[static_cast<std::size_t>(k)] >= 0) return;
      kfVar[static_cast<std::size_t>(k)] = static_cast<int>(P.poses.size());
      P.poses.push_back(keyframes_[static_cast<std::size_t>(k)].T);
      P.poseFixed.push_back(fixed ? 1 : 0);
      kfOf.push_back(k);
    };
    for (int k : window) addKf(k, false);
    for (int k : window) {
      for (int pid : keyframes_[static_cast<std::size_t>(k)].points) {
        if (!points_[static_cast<std::size_t>(pid)].valid || ptVar[static_cast<std::size_t>(pid)] >= 0) continue;
        ptVar[static_cast<std::size_t>(pid)] = static_cast<int>(P.points.size());
        P.points.push_back(points_[static_cast<std::size_t>(pid)].X);
        ptOf.push_back(pid);
      }
    }
    if (P.points.empty()) return;
    for (int pid : ptOf) {
      for (const Obs& o : points_[static_cast<std::size_t>(pid)].obs) {
        if (kfVar[static_cast<std::size_t>(o.kf)] < 0) addKf(o.kf, true);
      }
    }
    // Gauge, per segment (docs/design.md §5: monocular, 7 freedoms). Local: the keyframes outside the
    // window that see its points are fixed; when fewer than two of a segment's are, its oldest
    // free keyframe is fixed too, and with none at all its first baseline is held by a scale
    // prior. Global: each segment's first keyframe fixed, a scale prior on its first baseline.
    std::vector<int> segs;
    for (int k : kfOf) {
      const int seg = keyframes_[static_cast<std::size_t>(k)].segment;
      if (std::find(segs.begin(), segs.end(), seg) == segs.end()) segs.push_back(seg);
    }
    for (int seg : segs) {
      std::vector<int> freeV;  // problem indices of the segment's free keyframes, oldest first
      int fixedInSeg = 0;
      for (std::size_t v = 0; v < kfOf.size(); ++v) {
        if (keyframes_[static_cast<std::size_t>(kfOf[v])].segment != seg) continue;
        if (P.poseFixed[v]) {
          ++fixedInSeg;
        } else {
          freeV.push_back(static_cast<int>(v));
        }
      }
      std::sort(freeV.begin(), freeV.end(), [&](int a, int b) { return kfOf[static_cast<std::size_t>(a)] < kfOf[static_cast<std::size_t>(b)]; });
      if (freeV.empty()) continue;
      if (global || fixedInSeg == 0) {
        P.poseFixed[static_cast<std::size_t>(freeV[0])] = 1;
        if (freeV.size() >= 2) {
          BAScalePrior<Scalar> sp;
          sp.poseA = freeV[0];
          sp.poseB = freeV[1];
          sp.distance = (P.poses[static_cast<std::size_t>(sp.poseA)].translation() -
                         P.poses[static_cast<std::size_t>(sp.poseB)].translation()).norm();
          sp.weight = Scalar(1e4) / std::max(sp.distance * sp.distance, Scalar(1e-12));
          if (sp.distance > Scalar(0)) P.scalePriors.push_back(sp);
        }
      } else if (fixedInSeg == 1) {
        P.poseFixed[static_cast<std::size_t>(freeV[0])] = 1;
      }
    }
    // Observations, masked residuals at weight 0 (back-end masking).
    for (std::size_t j = 0; j < ptOf.size(); ++j) {
      const MapPoint& p = points_[static_cast<std::size_t>(ptOf[j])];
      for (const Obs& o : p.obs) {
        BAObservation<Scalar> ob;
        ob.pose = kfVar[static_cast<std::size_t>(o.kf)];
        ob.point = static_cast<int>(j);
        ob.uv = o.uv;
        const Keyframe& kf = keyframes_[static_cast<std::size_t>(o.kf)];
        if (opt_.useMasks && !kf.mask.bits.empty()) {
          const V3 Xc = kf.T.inverse() * p.X;
          const V2 q = Xc(2) > Scalar(0) ? cam_.project(Xc) : o.uv;
          if (kf.mask.test(o.uv(0), o.uv(1)) || kf.mask.test(q(0), q(1))) ob.weight = Scalar(0);
        }
        P.observations.push_back(ob);
      }
    }
    const BAOptions<Scalar> bo = mapBAOptions(iterations);
    if (withFocal) {
      FocalRefineOptions<Scalar> fo = opt_.focal;
      fo.ba = bo;
      focal_ = refineFocal(P, fo);
      focalAttempted_ = true;
      if (focal_.changed) {
        cam_ = P.camera;
        opt_.twoView.focalPx = Scalar(0.5) * (cam_.fx + cam_.fy);
      }
      if (opt_.log) {
        opt_.log("focal: " + std::string(focal_.changed ? "refined " : "kept ") + std::to_string(double(cam_.fx)) +
                 " px (guess " + std::to_string(double(focal_.guessFx)) + ", std " +
                 std::to_string(double(100 * focal_.stdLog)) + " %, " + std::to_string(focal_.evaluations) +
                 " BAs): " + focal_.reason);
      }
    } else {
      bundleAdjust(P, bo);
    }
    for (std::size_t v = 0; v < kfOf.size(); ++v) {
      if (!P.poseFixed[v]) keyframes_[static_cast<std::size_t>(kfOf[v])].T = P.poses[v];
    }
    for (std::size_t j = 0; j < ptOf.size(); ++j) points_[static_cast<std::size_t>(ptOf[j])].X = P.points[j];
    cullObservations(ptOf);
  }

  /// Drops observations whose reprojection error exceeds maxReprojPx (or that are behind the
  /// camera); a point left with fewer than two observations is invalid, and its track unmapped.
  void cullObservations(const std::vector<int>& pts) {
    const Scalar maxErr2 = Scalar(4) * opt_.maxReprojPx * opt_.maxReprojPx;
    for (int pid : pts) {
      MapPoint& p = points_[static_cast<std::size_t>(pid)];
      std::size_t w = 0;
      for (std::size_t i = 0; i < p.obs.size(); ++i) {
        const Keyframe& kf = keyframes_[static_cast<std::size_t>(p.obs[i].kf)];
        const V3 Xc = kf.T.inverse() * p.X;
        if (Xc(2) > Scalar(0) && (cam_.project(Xc) - p.obs[i].uv).squaredNorm() <= maxErr2) p.obs[w++] = p.obs[i];
      }
      p.obs.resize(w);
      if (w < 2) p.valid = false;
    }
    std::vector<char> drop(tracks_.size(), 0);
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
      const Track& t = tracks_[i];
      if (t.point >= 0 && !points_[static_cast<std::size_t>(t.point)].valid) drop[i] = 1;
    }
    removeTracks(drop);
  }

  /// The map points and pixels of the tracks from index `before` on (those a searchMapPoints just
  /// added), for PnP.
  void foundCorrespondences(std::size_t before, std::vector<V3>& X, std::vector<V2>& uv) const {
    for (std::size_t i = before; i < tracks_.size(); ++i) {
      X.push_back(points_[static_cast<std::size_t>(tracks_[i].point)].X);
      uv.push_back(V2(Scalar(tracks_[i].uv(0)), Scalar(tracks_[i].uv(1))));
    }
  }
  /// Drops the tracks from index `before` on (a search's finds that were not kept).
  void removeTracksFrom(std::size_t before) {
    std::vector<char> drop(tracks_.size(), 0);
    for (std::size_t i = before; i < tracks_.size(); ++i) drop[i] = 1;
    removeTracks(drop);
  }

  /// Removes the flagged tracks (keeping prevUv_ aligned with tracks_).
  void removeTracks(const std::vector<char>& drop) {
    std::size_t w = 0;
    const bool withPrev = prevUv_.size() == tracks_.size();
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
      if (drop[i]) continue;
      if (withPrev) prevUv_[w] = prevUv_[i];
      if (w != i) tracks_[w] = std::move(tracks_[i]);
      ++w;
    }
    tracks_.resize(w);
    if (withPrev) prevUv_.resize(w);
  }

  // ---------------------------------------------------------------- finish
  void refineAllFrames() {
    for (Frame& fr : frames_) {
      std::vector<V3> X;
      std::vector<V2> uv;
      for (std::size_t i = 0; i < fr.obsTrack.size(); ++i) {
        const int pid = trackPoint_[static_cast<std::size_t>(fr.obsTrack[i])];
        if (pid < 0 || !points_[static_cast<std::size_t>(pid)].valid) continue;
        X.push_back(points_[static_cast<std::size_t>(pid)].X);
        uv.push_back(V2(Scalar(fr.obsUv[i](0)), Scalar(fr.obsUv[i](1))));
      }
      if (static_cast<int>(X.size()) < opt_.minInliers) continue;
      PnPRansacOptions<Scalar> po = opt_.pnp;
      po.minInliers = opt_.minInliers;
      if (fr.posed) {
        SE3T T = fr.T;
        std::vector<Scalar> w(X.size(), Scalar(1));
        const SE3T Tcw = T.inverse();
        int used = 0;
        for (std::size_t i = 0; i < X.size(); ++i) {
          const V3 Xc = Tcw * X[i];
          const bool in = Xc(2) > Scalar(0) && (cam_.project(Xc) - uv[i]).norm() < Scalar(3) * po.thresholdPx;
          w[i] = in ? Scalar(1) : Scalar(0);
          used += in ? 1 : 0;
        }
        if (used >= opt_.minInliers) {
          PoseRefineOptions<Scalar> ro = po.refinement;
          ro.maxIterations = 10;
          refinePose(X, uv, &w, cam_, T, ro);
          if (T.translation().allFinite()) fr.T = T;
        }
      } else {
        const PnPRansacResult<Scalar> r = solvePnPRansac(X, uv, cam_, po);
        if (r.ok()) {
          fr.T = r.T_w_c;
          fr.posed = true;
          fr.inliers = r.numInliers;
          if (fr.status == SlamStatus::Interpolated) fr.status = SlamStatus::Tracked;
        }
      }
    }
  }

  /// SlamOptions::sequenceRefine: every frame's observations, with the tracks that are one
  /// physical point joined (a track renamed at a reset, tracks that follow the same map point),
  /// adjusted together (sequence_refine.hpp). Frames it adjusts are posed from it; the others are
  /// left to fillUnposed. False when it found nothing to adjust.
  bool refineWholeSequence() {
    const int n = static_cast<int>(frames_.size());
    const int nt = static_cast<int>(trackPoint_.size());
    std::vector<int> parent(static_cast<std::size_t>(nt));
    for (int i = 0; i < nt; ++i) parent[static_cast<std::size_t>(i)] = i;
    auto find = [&](int i) {
      while (parent[static_cast<std::size_t>(i)] != i) {
        parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
        i = parent[static_cast<std::size_t>(i)];
      }
      return i;
    };
    auto unite = [&](int a, int b) {
      a = find(a), b = find(b);
      if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
    };
    for (std::size_t i = 0; i < trackAlias_.size(); ++i) {
      if (trackAlias_[i] >= 0) unite(static_cast<int>(i), trackAlias_[i]);
    }
    std::vector<int> firstTrack(points_.size(), -1);
    for (int i = 0; i < nt; ++i) {
      const int pid = trackPoint_[static_cast<std::size_t>(i)];
      if (pid < 0 || !points_[static_cast<std::size_t>(pid)].valid) continue;
      if (firstTrack[static_cast<std::size_t>(pid)] < 0) {
        firstTrack[static_cast<std::size_t>(pid)] = i;
      } else {
        unite(i, firstTrack[static_cast<std::size_t>(pid)]);
      }
    }
    std::vector<SE3T> poses(static_cast<std::size_t>(n));
    std::vector<char> usable(static_cast<std::size_t>(n));
    std::vector<std::vector<TrackObservation<Scalar>>> obs(static_cast<std::size_t>(n));
    for (int f = 0; f < n; ++f) {
      const Frame& fr = frames_[static_cast<std::size_t>(f)];
      poses[static_cast<std::size_t>(f)] = fr.T;
      usable[static_cast<std::size_t>(f)] = fr.posed ? 2 : (fr.rotationKnown ? 1 : 0);
      auto& o = obs[static_cast<std::size_t>(f)];
      o.resize(fr.obsTrack.size());
      for (std::size_t i = 0; i < fr.obsTrack.size(); ++i) {
        o[i].track = find(fr.obsTrack[i]);
        o[i].uv = V2(Scalar(fr.obsUv[i](0)), Scalar(fr.obsUv[i](1)));
      }
    }
    SequenceRefineResult<Scalar> r = refineSequence(cam_, poses, usable, obs, opt_.sequence);
    if (opt_.log) {
      int adj = 0;
      for (char a : r.adjusted) adj += a;
      opt_.log("sequence refinement: " + std::to_string(adj) + " of " + std::to_string(n) + " frames, " +
               std::to_string(r.points.size()) + " points, " + std::to_string(r.observations) + " observations, rms " +
               std::to_string(double(r.finalRmsPx)) + " px, " + std::to_string(r.iterations) + " iterations, " +
               std::to_string(r.illConditioned) + " frames ill-conditioned" +
               (r.headPriorRounds > 0 ? ", head prior in " + std::to_string(r.headPriorRounds) + " rounds (fit rms " +
                                            std::to_string(double(r.headPriorRms)) + ")"
                                      : std::string()));
    }
    if (r.points.empty()) return false;
    refinedFrames_ = 0;  // the last refinement's count (it runs again after a focal change)
    for (char a : r.adjusted) refinedFrames_ += a;
    for (int f = 0; f < n; ++f) {
      Frame& fr = frames_[static_cast<std::size_t>(f)];
      if (r.adjusted[static_cast<std::size_t>(f)]) {
        fr.T = r.poses[static_cast<std::size_t>(f)];
        fr.posed = true;
        fr.rotationKnown = true;
        if (fr.status == SlamStatus::Interpolated) fr.status = SlamStatus::Tracked;
      } else if (r.carried[static_cast<std::size_t>(f)] && fr.inliers >= 2 * opt_.minInliers) {
        // Tracked on plenty of points but not adjusted (a long sequence is subsampled): its pose
        // moves with its neighbours'. A weakly tracked one (a head turn running out of map) is
        // left to the gap filling below.
        fr.T = r.poses[static_cast<std::size_t>(f)];
      } else {
        fr.posed = false;
        if (fr.status == SlamStatus::Tracked) fr.status = SlamStatus::Interpolated;
      }
    }
    fillUnposed();
    seqPoints_ = std::move(r.points);
    seqPointObs_ = std::move(r.pointObs);
    return true;
  }

  /// Applies the position map `g` (a similarity without rotation) to the frames from f1 on, the
  /// keyframes of segment `seg` and later ones, and their points (later segments continue its
  /// scale).
  template <typename G>
  void transformFrom(int f1, int seg, const G& g) {
    for (std::size_t f = static_cast<std::size_t>(f1); f < frames_.size(); ++f) {
      Frame& fr = frames_[f];
      fr.T = SE3T(fr.T.rotation(), g(V3(fr.T.translation())));
    }
    for (Keyframe& kf : keyframes_) {
      if (kf.segment >= seg) kf.T = SE3T(kf.T.rotation(), g(V3(kf.T.translation())));
    }
    for (MapPoint& p : points_) {
      if (!p.obs.empty() && keyframes_[static_cast<std::size_t>(p.obs.front().kf)].segment >= seg) p.X = g(V3(p.X));
    }
    // The sequence refinement's points (after it ran) by their first observation.
    for (std::size_t j = 0; j < seqPoints_.size(); ++j) {
      if (!seqPointObs_[j].empty() && seqPointObs_[j].front().first >= f1) seqPoints_[j] = g(V3(seqPoints_[j]));
    }
  }

  /// SlamOptions::refineFocal with the sequence refinement: the focal profile (focal_refine.hpp)
  /// on a bundle-adjustment problem of the refined points and at most focalMaxFrames of the
  /// adjusted frames (evenly spaced, focalFrameSpacing apart at least; each profile step is one
  /// adjustment). True when the focal
  /// changed (the caller refines the sequence again with it).
  bool refineFocalOnSequence() {
    std::vector<int> posedFrames;
    for (int f = 0; f < static_cast<int>(frames_.size()); ++f) {
      if (frames_[static_cast<std::size_t>(f)].posed) posedFrames.push_back(f);
    }
    focalAttempted_ = true;
    if (posedFrames.size() < 3) {
      focal_ = FocalRefineResult<Scalar>();
      focal_.guessFx = focal_.fx = cam_.fx;
      focal_.fy = cam_.fy;
      focal_.reason = "too few posed frames for the focal";
      return false;
    }
    const std::size_t step = std::max<std::size_t>(static_cast<std::size_t>(std::max(1, opt_.focalFrameSpacing)),
                                                   (posedFrames.size() + opt_.focalMaxFrames - 1) / static_cast<std::size_t>(std::max(1, opt_.focalMaxFrames)));
    BAProblem<Scalar> P;
    P.camera = cam_;
    std::vector<int> poseOf(frames_.size(), -1);
    for (std::size_t i = 0; i < posedFrames.size(); i += std::max<std::size_t>(1, step)) {
      poseOf[static_cast<std::size_t>(posedFrames[i])] = static_cast<int>(P.poses.size());
      P.poses.push_back(frames_[static_cast<std::size_t>(posedFrames[i])].T);
    }
    for (std::size_t j = 0; j < seqPoints_.size(); ++j) {
      if (addTrackObservations(P, static_cast<int>(P.points.size()), seqPointObs_[j], poseOf, 2)) P.points.push_back(seqPoints_[j]);
    }
    P.poseFixed.assign(P.poses.size(), 0);
    P.poseFixed[0] = 1;
    addFarthestScalePrior(P, 0);
    FocalRefineOptions<Scalar> fo = opt_.focal;
    fo.minStdLog = std::max(fo.minStdLog, opt_.focalMinStd);
    fo.ba = mapBAOptions(opt_.globalIterations);
    focal_ = refineFocal(P, fo);
    if (opt_.log) {
      opt_.log("focal (sequence, " + std::to_string(P.poses.size()) + " frames, " + std::to_string(P.points.size()) + " points): " +
               std::string(focal_.changed ? "refined " : "kept ") + std::to_string(double(P.camera.fx)) + " px (guess " +
               std::to_string(double(focal_.guessFx)) + ", std " + std::to_string(double(100 * focal_.stdLog)) + " %, " +
               std::to_string(focal_.evaluations) + " BAs): " + focal_.reason);
    }
    if (!focal_.changed) return false;
    cam_ = P.camera;
    opt_.twoView.focalPx = Scalar(0.5) * (cam_.fx + cam_.fy);
    // The problem holds the adjustment at the new focal: its frames take those poses, the other
    // posed frames move with the nearest of them (T' = T'_a·T_a⁻¹·T), so that the next refinement
    // starts from poses that fit the new focal.
    std::vector<SE3T> before(frames_.size());
    for (std::size_t f = 0; f < frames_.size(); ++f) before[f] = frames_[f].T;
    for (std::size_t f = 0; f < frames_.size(); ++f) {
      if (poseOf[f] >= 0) frames_[f].T = P.poses[static_cast<std::size_t>(poseOf[f])];
    }
    for (std::size_t f = 0, last = frames_.size(); f < frames_.size(); ++f) {
      if (poseOf[f] >= 0) {
        last = f;
        continue;
      }
      std::size_t ref = last;
      for (std::size_t g = f + 1; ref == frames_.size() && g < frames_.size(); ++g) ref = poseOf[g] >= 0 ? g : ref;
      if (ref < frames_.size()) frames_[f].T = frames_[ref].T * before[ref].inverse() * before[f];
    }
    return true;
  }

  /// The first keyframe of each map segment, in order.
  std::vector<int> segmentFirstKeyframes() const {
    std::vector<int> first;
    for (std::size_t k = 0; k < keyframes_.size(); ++k) {
      if (k == 0 || keyframes_[k].segment != keyframes_[k - 1].segment) first.push_back(static_cast<int>(k));
    }
    return first;
  }

  /// SlamOptions::turnScaleJoin: each later segment scaled about its first keyframe's position
  /// by r_before / r_after (turn_scale.hpp), with everything after it (later segments continue
  /// its scale); frames before its first keyframe (lost, not posed) are filled in later.
  void joinSegmentsByTurns() {
    const std::vector<int> segFirstKf = segmentFirstKeyframes();
    if (segFirstKf.size() < 2) return;
    const int n = static_cast<int>(frames_.size());
    std::vector<SE3T> T(static_cast<std::size_t>(n));
    std::vector<char> usable(static_cast<std::size_t>(n));
    auto gather = [&] {
      for (int f = 0; f < n; ++f) {
        T[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].T;
        usable[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].posed;
      }
    };
    const Scalar minAngle = opt_.turnScaleMinAngleDeg * Scalar(M_PI / 180);
    for (std::size_t i = 1; i < segFirstKf.size(); ++i) {
      gather();
      const int f0 = keyframes_[static_cast<std::size_t>(segFirstKf[i - 1])].frame;
      const int f1 = keyframes_[static_cast<std::size_t>(segFirstKf[i])].frame;
      const int f2 = i + 1 < segFirstKf.size() ? keyframes_[static_cast<std::size_t>(segFirstKf[i + 1])].frame : n;
      if (opt_.headModelJoin) {
        // One head model for both segments (head_motion.hpp): B's positions into A's units.
        std::vector<int> idxA, idxB;
        for (int f = std::max(f0, f1 - opt_.headModel.window); f < f1; ++f) {
          if (usable[static_cast<std::size_t>(f)]) idxA.push_back(f);
        }
        for (int f = f1; f < std::min(f2, f1 + opt_.headModel.window); ++f) {
          if (usable[static_cast<std::size_t>(f)]) idxB.push_back(f);
        }
        const HeadJoin<Scalar> hj = fitHeadJoin(T, idxA, idxB, opt_.headModel);
        if (opt_.log) {
          opt_.log("segment starting at frame " + std::to_string(f1) + ": head model over " + std::to_string(idxA.size()) + " + " +
                   std::to_string(idxB.size()) + " frames: scale " + std::to_string(double(hj.s)) + ", R2 " +
                   std::to_string(double(hj.fit.r2)) + ", motion R2 " + std::to_string(double(hj.fit.motionR2)) + ", front " +
                   std::to_string(double(hj.fit.frontCos)) + ", radius spread " + std::to_string(double(hj.fit.radiusSpread)) +
                   ", view spreads " + std::to_string(double(hj.spreadA)) + "/" + std::to_string(double(hj.spreadB)) + " deg" +
                   (hj.ok ? ": joined" : ": not used"));
        }
        if (hj.ok) {
          transformFrom(f1, keyframes_[static_cast<std::size_t>(segFirstKf[i])].segment, [&](const V3& x) { return V3(hj.s * x + hj.t); });
          continue;
        }
      }
      if (!opt_.turnScaleJoin) continue;
      const TurnRadius<Scalar> before = turnRadius(T, usable, f0, f1, opt_.turnScaleLag, minAngle);
      const TurnRadius<Scalar> after = turnRadius(T, usable, f1, f2, opt_.turnScaleLag, minAngle);
      const bool model = before.windows >= opt_.turnScaleMinWindows && after.windows >= opt_.turnScaleMinWindows &&
                         before.spread <= opt_.turnScaleMaxSpread && after.spread <= opt_.turnScaleMaxSpread &&
                         before.ok() && after.ok();
      const Scalar k = model ? before.radius / after.radius : Scalar(1);
      if (opt_.log) {
        opt_.log("segment starting at frame " + std::to_string(f1) + ": turn radius " + std::to_string(double(before.radius)) +
                 " (" + std::to_string(before.windows) + " windows, spread " + std::to_string(double(before.spread)) +
                 ") before, " + std::to_string(double(after.radius)) + " (" + std::to_string(after.windows) +
                 " windows, spread " + std::to_string(double(after.spread)) + ") after: " +
                 (model && k > Scalar(1) / 3 && k < Scalar(3) ? "scaled by " + std::to_string(double(k)) : std::string("kept")));
      }
      if (!model || !(k > Scalar(1) / 3 && k < Scalar(3))) continue;
      const V3 J = keyframes_[static_cast<std::size_t>(segFirstKf[i])].T.translation();
      transformFrom(f1, keyframes_[static_cast<std::size_t>(segFirstKf[i])].segment, [&](const V3& x) { return V3(J + k * (x - J)); });
    }
  }

  /// SlamOptions::headModelJoinAll: the segments (first keyframes segFirstKf; segment i spans
  /// the frames from its first keyframe to the next one's) with enough posed frames and turn
  /// joined by one head model (fitHeadJoinAll, the longest segment the reference). True when it
  /// passed the tests and was applied; a segment left out moves with the one before it, and with
  /// placeShort (SlamOptions::headModelPlaceShort also on) its frames are placed by the model.
  bool joinAllSegmentsByHead(bool placeShort = true) {
    const std::vector<int> segFirstKf = segmentFirstKeyframes();
    const int n = static_cast<int>(frames_.size());
    const std::size_t S = segFirstKf.size();
    if (S < 2) return false;
    std::vector<SE3T> T(static_cast<std::size_t>(n));
    std::vector<char> usable(static_cast<std::size_t>(n));
    for (int f = 0; f < n; ++f) {
      T[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].T;
      usable[static_cast<std::size_t>(f)] = frames_[static_cast<std::size_t>(f)].posed;
    }
    std::vector<int> first(S + 1, n);
    for (std::size_t i = 0; i < S; ++i) first[i] = i == 0 ? 0 : keyframes_[static_cast<std::size_t>(segFirstKf[i])].frame;
    const SegmentsHeadJoin<Scalar> R = joinSegmentsByHeadModel(T, usable, first, opt_.headModel);
    const HeadJoinAll<Scalar>& J = R.join;
    if (opt_.log) {
      std::string sc;
      for (std::size_t k = 0; k < J.s.size(); ++k) sc += (k ? "/" : "") + std::to_string(double(J.s[k]));
      opt_.log("segments joined by one head model:" + R.report + " scales " + sc + ", R2 " + std::to_string(double(J.fit.r2)) +
               ", motion R2 " + std::to_string(double(J.fit.motionR2)) + ", front " + std::to_string(double(J.fit.frontCos)) +
               ", radius spread " + std::to_string(double(J.fit.radiusSpread)) + (R.ok ? ": joined" : ": not used"));
    }
    if (!R.ok) return false;
    const std::vector<int>& groupOf = R.group;
    // Segment by segment, in order: transformFrom moves everything from a segment on, so each
    // joined segment gets its own similarity composed with the inverse of the one applied so far.
    Scalar a = Scalar(1);
    V3 b = V3::Zero();
    for (std::size_t i = 0; i < S; ++i) {
      if (groupOf[i] < 0) continue;
      const Scalar s = J.s[static_cast<std::size_t>(groupOf[i])];
      const V3 t = J.t[static_cast<std::size_t>(groupOf[i])];
      transformFrom(first[i], keyframes_[static_cast<std::size_t>(segFirstKf[i])].segment,
                    [&](const V3& x) { return V3(s * (x - b) / a + t); });
      a = s;
      b = t;
    }
    // A segment too short to fix its own scale: its frames are placed by the head model instead
    // (fillGapsByHeadModel), like lost ones.
    if (opt_.headModelPlaceShort && placeShort) {
      for (std::size_t i = 0; i < S; ++i) {
        if (groupOf[i] >= 0) continue;
        placedRanges_.emplace_back(first[i], first[i + 1]);
        for (int f = first[i]; f < first[i + 1]; ++f) {
          Frame& fr = frames_[static_cast<std::size_t>(f)];
          if (!fr.posed) continue;
          fr.posed = false;
          fr.rotationKnown = true;
          fr.status = SlamStatus::Interpolated;
        }
        // Interpolated from the joined frames around it (its own positions are in its own
        // scale); the head model's gap filling replaces them where its tests pass.
        fillUnposed(first[i], first[i + 1]);
      }
    }
    return true;
  }

  /// Frames without a map pose: translation (and rotation where the rays gave none) interpolated
  /// between the nearest posed frames; held at the ends. A lost frame keeps the rays' rotation:
  /// a SLERP between the posed frames around a loss cuts a fast turn inside it short (fast_turns
  /// seed 4: lost frames 33° off on average, 1.0° with the rays).
  /// Only the frames in [from, to) (all by default) are changed.
  void fillUnposed(int from = 0, int to = -1) {
    const int n = static_cast<int>(frames_.size());
    if (to < 0) to = n;
    int prev = -1;
    for (int i = 0; i < to; ++i) {
      if (frames_[static_cast<std::size_t>(i)].posed) {
        prev = i;
        continue;
      }
      if (i < from) continue;
      int next = i + 1;
      while (next < n && !frames_[static_cast<std::size_t>(next)].posed) ++next;
      Frame& fr = frames_[static_cast<std::size_t>(i)];
      if (prev < 0 && next >= n) continue;  // nothing posed at all: rotation-only output
      if (prev < 0) {
        fr.T = SE3T(fr.rotationKnown ? fr.T.rotation() : frames_[static_cast<std::size_t>(next)].T.rotation(),
                    frames_[static_cast<std::size_t>(next)].T.translation());
      } else if (next >= n) {
        fr.T = SE3T(fr.rotationKnown ? fr.T.rotation() : frames_[static_cast<std::size_t>(prev)].T.rotation(),
                    frames_[static_cast<std::size_t>(prev)].T.translation());
      } else {
        const Scalar a = Scalar(i - prev) / Scalar(next - prev);
        const SE3T& A = frames_[static_cast<std::size_t>(prev)].T;
        const SE3T& B = frames_[static_cast<std::size_t>(next)].T;
        fr.T = SE3T(fr.rotationKnown ? fr.T.rotation() : interpolate(A.rotation(), B.rotation(), a),
                    V3((Scalar(1) - a) * A.translation() + a * B.translation()));
      }
    }
  }

  PinholeCamera<Scalar> cam_;
  SlamOptions<Scalar> opt_;
  int width_ = 0, height_ = 0;
  bool finished_ = false;
  State state_ = State::Initialising;
  ImagePyramid prevPyr_, curPyr_;
  ImageU8 curMask_;
  std::vector<unsigned char> maskTmp_;
  bool hasMask_ = false;
  CoarseMask refMask_;
  std::vector<Track> tracks_;
  std::vector<MapPoint> points_;
  std::vector<Keyframe> keyframes_;
  std::vector<Frame> frames_;
  std::vector<KeyframePyramid> kfPyr_;  ///< the last refindKeyframes keyframes' pyramids
  std::vector<KeyframePyramid> relocPyr_;  ///< relocKeyframes keyframes' pyramids, relocSpacing apart
  std::vector<KeyframePyramid> linkPyr_;   ///< the last segment's, after a broken rotation chain (segmentLinks)
  KeyframePyramid lastKfPyr_;              ///< the last keyframe's (segmentLinks; kf −1: none)
  std::vector<int> trackPoint_;  ///< track id → map point (−1: none), for finish()
  std::vector<Vec3<Scalar>> seqPoints_;  ///< finish(): the sequence refinement's points (world)
  std::vector<std::vector<std::pair<int, Vec2<Scalar>>>> seqPointObs_;  ///< and their (frame, pixel) observations
  std::vector<int> trackAlias_;  ///< track id → the id the same track had before a reset (−1: none; may be short)
  int refFrame_ = 0, lastInitAttempt_ = -1000;
  int segment_ = 0, segmentStart_ = 0;  ///< current map segment, its first frame (reset)
  std::vector<SegmentLink> links_;  ///< SlamOptions::segmentLinks
  int lost_ = 0, losses_ = 0, resets_ = 0, relocalisations_ = 0, revisitPoints_ = 0, refinedFrames_ = 0, headModelFrames_ = 0;
  /// Frame ranges [a, b) of the segments placed by the head model (headModelPlaceShort): their
  /// keyframe depths and points are in a scale of their own and are left out of the result.
  std::vector<std::pair<int, int>> placedRanges_;
  bool placedFrame(int f) const {
    for (const auto& r : placedRanges_) {
      if (f >= r.first && f < r.second) return true;
    }
    return false;
  }
  int relocCandidateFrame_ = -1;  ///< last frame whose relocalisation waits for the next one's agreement
  SE3T relocCandidate_;
  bool afterLoss_ = false, everInitialised_ = false;
  int lastKfInliers_ = 0, framesSinceKf_ = 0;
  Scalar lastMedianDepth_ = Scalar(0);
  bool focalAttempted_ = false;
  FocalRefineResult<Scalar> focal_;
  SE3T predicted_;
  V3 rsOmega_ = V3::Zero();      ///< this frame's rotation per frame for the rolling shutter (camera axes)
  V3 rsOmegaNext_ = V3::Zero();  ///< the last step's, from the raw pixels (rsRate)
  bool havePrediction_ = false;
  bool turning_ = false;
  int turnUntil_ = -1;
  int bridged_ = 0;  ///< frames posed by the turn bridge in a row
  // Scratch.
  std::vector<Vec2f> from_, to_, prevUv_, existing_, fresh_;
  std::vector<char> ok_;
  CornerScratch cornerScratch_;
};

}  // namespace hawor
