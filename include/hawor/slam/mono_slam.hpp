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
//      TURN MODE: while the rotation exceeds turn.rateDeg a frame (a fast head turn: up to
//      20° ≈ 140 px a frame; looking around and walking stay below 3.5°), every track is also
//      started at its ray rotated by a constant-angular-velocity prediction (the infinite
//      homography), the rotation coming from the map or, without a map pose, from the rays.
//      ROLLING SHUTTER (rollingShutter ≠ 0): the tracked pixels stay raw for KLT; the geometry
//      sees them moved to the middle row's time under the last frame's raw-pixel rotation.
//   3. Before a map exists: two-view initialisation (two_view.hpp: E or H by GRIC, RANSAC)
//      between a reference frame and the current one once the median flow is large enough; the
//      reference is the oldest of the last init.maxGap frames sharing init.minTracks tracks (their
//      observations are kept per frame; new corners join whenever the tracks thin out, so that a
//      recent reference exists while hands sweep the old tracks away); in turn mode the pair is
//      also tried after
//      init.minRotationDeg of rotation (the rays' rotation absorbs most of the parallax of the
//      neck's sideways translation, so the compensated flow understates it). The rotation of
//      not-yet-initialised frames comes from the tracked rays (Kabsch, pure-rotation
//      hypothesis) with the position held; a track more than maxRayJumpDeg off that rotation
//      jumped (KLT locked onto a weak texture off the true match at a turn's onset) and is
//      dropped, and a two-view whose best motion puts fewer than minInFrontRatio of its inliers
//      in front of both cameras is refused (two_view.hpp).
//      With a map: Then the pose by P3P-RANSAC + robust LM on the
//      tracks' map points (pnp_ransac.hpp);
//      in turn mode a pose from as few as turn.minInliers points is accepted when its rotation
//      agrees with the rays' (the map leaves the view faster than new points are made); when
//      even that fails right after two posed frames, the TURN BRIDGE (turn_bridge.hpp, turn.bridge)
//      poses the frame from the last one: the step's direction from a head sphere (Δc ∝ Δz),
//      the rotation from the tracks' epipolar geometry, the length from the map points still
//      tracked and the tracks triangulated from the two posed frames; the frame becomes a
//      keyframe, so the tracks born in the turn are triangulated and the map goes on.
//   4. Keyframes when the tracked map points fall below a fraction of the last keyframe's, below
//      an absolute count, after a maximum interval, or in turn mode after keyframe.maxRotationDeg
//      of rotation (new corners only come at keyframes). REVISITS first (revisit.enabled, on): the
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
//      PLACE RECOGNITION (place, on; mono_slam/place_links.hpp): the keyframe's map points are
//      described by binary descriptors in its image and the older keyframes indexed by theirs are
//      asked for the same place (another segment's, or this one's a while ago); a candidate
//      verified by a Sim(3) over matched map points is a place link.
//   5. Tracking loss (too few PnP inliers): RELOCALISATION first (reloc.enabled, on by default):
//      the map points of a few kept keyframes (reloc.keyframes, reloc.spacing frames apart) are
//      projected under the frame's guess (rotation from the tracked rays, position held) and
//      searched by KLT from those keyframes' images; PnP-RANSAC on them, its rotation checked
//      against the rays' (or, where the ray chain disagrees, two consecutive relocalisations
//      against the rays' rotation between them), puts the frame back into the map it lost (a hand that covered the view
//      moves away, a turn comes back), with no new scale. This is tried on every lost frame and,
//      after the reset below, until a new map is built.
//      TRACKS FOLLOWED BACK (backTrackFrames; mono_slam/front_end.hpp followTracksBack): the
//      images of the lost frames are kept, and the first frame posed again (new map or old)
//      follows its map's tracks back through them by KLT while PnP still poses each one (a new
//      map at most backTrackBaselines pair gaps before its reference), so that finish() resects
//      them instead of interpolating across the loss.
//      Otherwise the frame is Lost, its rotation still follows the
//      tracked rays; after lostFramesBeforeReset lost frames the system re-initialises a new map
//      segment from the current frame and joins it to the old world at the frame where
//      tracking was lost: rotation from the ray chain, position from the last estimate, scale so that the median scene depth is
//      continuous across the join. Until that new map is built, RELOCALISATION BY PLACE
//      (reloc.byPlace, on; mono_slam/place_links.hpp) describes the frame's tracks and asks the
//      place index for keyframes of any segment: two consecutive frames' PnP poses on the
//      matched map points, agreeing with the rays' rotation between them, put the frame into
//      that segment (the lost one, or an older one: the head came back to a place it mapped),
//      its map points around the view found by projection, and the segment goes on there (a
//      segment's frames and keyframes need not be contiguous; segmentParent_ keeps which
//      segment each one was started from, and the joins move a segment with the ones started
//      from it). A segment that later sees the old map again is not merged
//      with it; but when the rotation chain to the old segment is broken (frames with no
//      rotation, or one only carried on), the old segment's kept images are searched for the
//      current view (PLACE RECOGNITION, link.enabled) and the poses found in the old world fix
//      the rotation of everything after the break in finish().
// finish(): the rotation chains after a break turned by their agreeing segment links, segments
// joined by the head model (head_motion.hpp), a global bundle
// adjustment over all keyframes and points (per segment: first keyframe fixed, a scale prior on
// its first baseline), every frame's pose re-estimated against the final map from its stored 2D
// observations (RANSAC for frames without a tracked pose, robust LM otherwise); each segment with
// place links to earlier ones moved into their world by the linked points; then the
// SEQUENCE REFINEMENT (sequence_refine.hpp, finish.sequenceRefine, on): every frame's observations of
// every track (a track renamed at a reset, tracks that follow one map point, and the two points
// of a place link, joined) in one
// bundle adjustment, frames with a guessed position resected, ill-conditioned frames left out;
// frames that still have no pose get their position from the HEAD MODEL fitted to the posed
// frames around them where it explains them (head_motion.hpp: c = n + M·z, the eye in front of
// the neck), else interpolated between their neighbours.
// Output frame: camera-to-world poses (docs/design.md §2) with the world = the first frame's camera,
// monocular scale (the first baseline is 1 in the map's units); per-keyframe sparse depths
// (pixel, depth along the optical axis, unmasked points only) for the metric-scale step (docs/design.md §6).
// Memory per frame: the pyramid of two frames, plus the frame's track observations (≈ 12 bytes
// a track) and, per keyframe, a 1/4-resolution mask bitmap (also for the two-view reference and
// the last init.maxGap frames while no map exists); for relocalisation, the pyramids of
// reloc.keyframes recent and up to
// reloc.anchors anchor keyframes (about 1.6 MB each at 640×480), and of the last keyframe; while
// lost, of up to backTrackFrames lost frames; after
// a broken rotation chain, until its links are found, the lost segment's too (link.enabled); no
// other images. finish() first
// lets every image go, then holds every frame's observations twice more (≈ 24 bytes an
// observation as the sequence refinement's input, 12 grouped by track inside it) and the
// adjustment of at most sequence.maxAdjustedFrames frames.
// Not thread-safe; one instance per video.
// A video at 50 fps or more is tracked on every frameStep-th frame, the frames between posed by
// interpolation in finish() (frame_step.hpp).
// This header holds the class with its state and process() (the options in slam_options.hpp,
// the result in slam_result.hpp); the member
// functions are in mono_slam/, one part a header, in the order a frame meets them: front_end,
// initialisation, tracking, relocalisation (with the revisit and segment-link searches),
// place_links (place recognition, segments placed by it), mapping (keyframes, bundle adjustment),
// finish (the passes over the whole sequence), segment_joins.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
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
#include "hawor/slam/binary_descriptor.hpp"
#include "hawor/slam/bundle_adjustment.hpp"
#include "hawor/slam/corners.hpp"
#include "hawor/slam/focal_refine.hpp"
#include "hawor/slam/hand_mask.hpp"
#include "hawor/slam/head_motion.hpp"
#include "hawor/slam/image_pyramid.hpp"
#include "hawor/slam/keyframe_policy.hpp"
#include "hawor/slam/klt.hpp"
#include "hawor/slam/place_index.hpp"
#include "hawor/slam/pnp_ransac.hpp"
#include "hawor/slam/sequence_refine.hpp"
#include "hawor/slam/sim3_ransac.hpp"
#include "hawor/slam/slam_options.hpp"
#include "hawor/slam/slam_result.hpp"
#include "hawor/slam/frame_step.hpp"
#include "hawor/slam/triangulation.hpp"
#include "hawor/slam/turn_bridge.hpp"
#include "hawor/slam/two_view.hpp"

namespace hawor {

template <typename Scalar>
class MonoSlam {
 public:
  using V2 = Vec2<Scalar>;
  using V3 = Vec3<Scalar>;
  using SE3T = SE3<Scalar>;

  MonoSlam(const PinholeCamera<Scalar>& camera, const SlamOptions<Scalar>& options = {})
      : cam_(camera), opt_(options.atFrameRate()) {
    if (!(cam_.fx > Scalar(0)) || !(cam_.fy > Scalar(0)) || !std::isfinite(double(cam_.fx)) ||
        !std::isfinite(double(cam_.fy)) || !std::isfinite(double(cam_.cx)) || !std::isfinite(double(cam_.cy))) {
      throw Error("MonoSlam: the intrinsics must be finite with fx, fy > 0");
    }
    opt_.validate();
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
    const int input = inputFrames_;
    if (!image.consistent() || image.width <= 0 || image.height <= 0) {
      throw Error("MonoSlam: frame " + std::to_string(input) + " is empty");
    }
    if (input == 0) {
      width_ = image.width, height_ = image.height;
    } else if (image.width != width_ || image.height != height_) {
      throw Error("MonoSlam: frame " + std::to_string(input) + " is " + std::to_string(image.width) +
                  "x" + std::to_string(image.height) + " but the first frame was " + std::to_string(width_) +
                  "x" + std::to_string(height_));
    }
    if (mask && (mask->width != width_ || mask->height != height_)) {
      binaryHandMask(*mask, width_, height_, curMask_);  // throws its size error
    }
    ++inputFrames_;
    // between tracked frames (frameStep): posed by interpolation in finish()
    if (input % opt_.frameStep != 0) {
      return frames_.back().status == SlamStatus::Lost ? SlamStatus::Lost : SlamStatus::Interpolated;
    }
    std::swap(prevPyr_, curPyr_);
    curPyr_.build(image, opt_.pyramidLevels);
    hasMask_ = false;
    if (mask && opt_.useMasks) {
      binaryHandMask(*mask, width_, height_, curMask_);
      dilateSquare(curMask_, opt_.maskDilatePx, maskTmp_);
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
    if (opt_.link.enabled && !linkPyr_.empty() && !frames_.back().posed && f % std::max(1, opt_.link.everyFrames) == 0) {
      searchSegmentLinks(f);
    }
    recordObservations(frames_.back());
    frames_.back().segment = segment_;
    keepForTracksBack(f);
    return frames_.back().status;
  }

  /// Global bundle adjustment, per-frame refinement, interpolation of the remaining frames, and
  /// the result in the first frame's world. Call once, after the last frame.
  SlamResult<Scalar> finish();

  /// The tracker's causal estimates, before finish() refines them: frame f's camera-to-world
  /// pose in the first frame's camera (after a reset, in the new map's world: it jumps), whether
  /// a map posed it (else held or guessed), and the map's points in the same world.
  /// A frame between tracked ones (frameStep) holds the last tracked frame's estimate.
  SE3T livePose(int f) const { return frames_[0].T.inverse() * frames_.at(trackedIndex(f)).T; }
  bool livePosed(int f) const { return frames_.at(trackedIndex(f)).posed; }
  std::vector<V3> liveMapPoints() const {
    std::vector<V3> X;
    if (frames_.empty()) return X;
    const SE3T T0inv = frames_[0].T.inverse();
    for (const MapPoint& p : points_) {
      if (p.valid) X.push_back(T0inv * p.X);
    }
    return X;
  }

  int numFrames() const { return inputFrames_; }          ///< frames given to process()
  int frameStep() const { return opt_.frameStep; }         ///< every frameStep-th of them is tracked
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
  std::size_t trackedIndex(int f) const {
    if (f < 0 || f >= inputFrames_) throw Error("MonoSlam: frame " + std::to_string(f) + " was not processed");
    return static_cast<std::size_t>(f / opt_.frameStep);
  }
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
  };
  struct Keyframe {
    int frame;
    SE3T T;
    CoarseMask mask;
    std::vector<int> points;  ///< map points it observes
    int segment;
    std::vector<BinaryDescriptor> desc;  ///< SlamOptions::place: of its map points seen in its image
    std::vector<int> descPoint;          ///< their map points
    std::vector<V2> descUv;              ///< and pixels
  };
  struct PlaceLink {
    int kf;      ///< keyframe linked
    int oldKf;   ///< to this older one
    std::vector<std::pair<int, int>> pairs;  ///< (point seen by kf, point seen by oldKf): one physical point
  };
  struct KeyframePyramid {
    int kf = -1;
    ImagePyramid pyr;
    bool anchor = false;  ///< relocPyr_: an anchor (SlamOptions::reloc.anchors), not a recent one
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
    int segment = 0;           ///< the map segment (world) its pose is in
    CoarseMask mask;           ///< hand mask, kept for the recent frames while initialising
    std::vector<int> obsTrack;
    std::vector<Vec2f> obsUv;
  };

  // front end (mono_slam/front_end.hpp)
  V2 normalised(const Vec2f& uv) const;
  bool masked(const Vec2f& uv) const;
  bool insideImage(const Vec2f& uv, float margin) const;
  Vec2f rollingShutterShift(const Vec2f& p, Scalar sign) const;
  V3 rsRate();
  void trackFeatures(int f);
  void replenish();
  void setReference(int f);
  void recordObservations(Frame& fr);
  bool rayRotation(Mat3<Scalar>& Rprev_cur);
  SE3T rotationCarriedOn(int f) const;
  bool coastRotation(int f);
  void dropJumpedTracks(const Mat3<Scalar>& dR);
  void keepForTracksBack(int f);
  void followTracksBack(int f);

  // initialisation (mono_slam/initialisation.hpp)
  void initialise(int f);
  void buildMap(int f, const TwoViewResult<Scalar>& tv, const std::vector<int>& idx);

  // tracking (mono_slam/tracking.hpp)
  static Scalar rotationAngleDeg(const SE3T& a, const SE3T& b);
  void mappedTracks(std::vector<V3>& X, std::vector<V2>& uv, std::vector<int>& ti) const;
  void mappedObservations(const Frame& fr, std::vector<V3>& X, std::vector<V2>& uv, std::vector<int>& pids) const;
  void dropOutlierTracks(const std::vector<int>& ti, const std::vector<char>& inliers);
  int countMapped() const;
  void trackPose(int f);
  bool bridgeTurn(int f);
  int addPoint(MapPoint&& p, int trackId);

  // relocalisation and place search (mono_slam/relocalisation.hpp)
  bool relocalise(int f);
  int undoReset(int f);
  void searchMapPoints(int f, const std::vector<KeyframePyramid>& store, const SE3T& pose,
      Scalar maxShiftPx, int maxPoints, const char* what, const std::vector<char>* use = nullptr);
  void searchRevisits(int f);
  bool chainBreak(int f) const;
  int chainStart(int f) const;
  void searchSegmentLinks(int f);
  int linkChainStart(const SegmentLink& l) const;
  void applySegmentLinks();

  // place recognition (mono_slam/place_links.hpp)
  void describeAndLinkKeyframe(int k);
  bool verifyPlaceLink(int k, int c, int votes);
  bool relocaliseByPlace(int f);
  void searchPlaceByProjection(int f, int centre);
  int placeSegmentsByLinks();

  // mapping (mono_slam/mapping.hpp)
  void keepPyramid(std::vector<KeyframePyramid>& store, int capacity, int k, bool anchor = false);
  void keepRelocPyramid(int k);
  void closeKeyframe(Frame& fr);
  void insertKeyframe(int f);
  void updateMedianDepth();
  std::vector<int> lastWindow() const;
  static BAOptions<Scalar> mapBAOptions(int iterations);
  BAReport<Scalar> adjust(const std::vector<int>& window, int iterations, bool global, bool withFocal = false,
                          const std::vector<char>* leftOut = nullptr);
  void cullObservations(const std::vector<int>& pts, const std::vector<char>* leftOut = nullptr);
  void foundCorrespondences(std::size_t before, std::vector<V3>& X, std::vector<V2>& uv) const;
  void removeTracksFrom(std::size_t before);
  void removeTracks(const std::vector<char>& drop);

  // finish() (mono_slam/finish.hpp)
  std::vector<char> redundantKeyframes() const;
  void carryFramesWithKeyframes(const std::vector<SE3T>& before, const std::vector<int>& kept);
  void refineAllFrames();
  bool refineWholeSequence();
  bool refineFocalOnSequence();
  void fillUnposed(int from = 0, int to = -1);

  // joining map segments after resets (mono_slam/segment_joins.hpp)
  template <typename G> void transformFrom(int f1, int seg, const G& g, const SO3<Scalar>* R = nullptr);
  std::vector<int> segmentFirstKeyframes() const;
  void joinSegmentPairsByHead();
  bool joinAllSegmentsByHead(bool placeShort = true);

  PinholeCamera<Scalar> cam_;
  SlamOptions<Scalar> opt_;
  int width_ = 0, height_ = 0;
  bool finished_ = false;
  int inputFrames_ = 0;  // frames given to process(), tracked or not (frameStep)
  State state_ = State::Initialising;
  ImagePyramid prevPyr_, curPyr_;
  struct BackFrame {
    int frame = -1;
    ImagePyramid pyr;
    CoarseMask mask;  ///< its hand mask
  };
  std::deque<BackFrame> backPyr_;  ///< the last unposed frames' images (backTrackFrames)
  ImageU8 curMask_;
  std::vector<unsigned char> maskTmp_;
  bool hasMask_ = false;
  CoarseMask refMask_;
  std::vector<Track> tracks_;
  std::vector<MapPoint> points_;
  std::vector<Keyframe> keyframes_;
  std::vector<Frame> frames_;
  std::vector<KeyframePyramid> relocPyr_;  ///< reloc.keyframes keyframes' pyramids, reloc.spacing apart
  std::vector<KeyframePyramid> linkPyr_;   ///< the last segment's, after a broken rotation chain (link.enabled)
  KeyframePyramid lastKfPyr_;              ///< the last keyframe's (link.enabled; kf −1: none)
  std::vector<int> trackPoint_;  ///< track id → map point (−1: none), for finish()
  std::vector<Vec3<Scalar>> seqPoints_;  ///< finish(): the sequence refinement's points (world)
  std::vector<std::vector<std::pair<int, Vec2<Scalar>>>> seqPointObs_;  ///< and their (frame, pixel) observations
  std::vector<int> trackAlias_;  ///< track id → the id the same track had before a reset (−1: none; may be short)
  int refFrame_ = 0, lastInitAttempt_ = -1000;
  int segment_ = 0, segmentStart_ = 0;  ///< current map segment, its first frame (reset)
  /// Per segment id: the segment it was started from at a reset (its world was joined to that
  /// one's), −1 for the first. A segment re-entered later (relocalisation by place recognition)
  /// keeps its id, so a segment's frames and keyframes need not be contiguous: "a segment and
  /// the ones started from it" is the subtree, not the ids from it on.
  std::vector<int> segmentParent_{-1};
  bool inSegment(int label, int root) const {
    while (label > root) label = segmentParent_[static_cast<std::size_t>(label)];
    return label == root;
  }
  std::vector<SegmentLink> links_;  ///< SlamOptions::link.enabled
  BinaryDescriptorExtractor describer_;  ///< SlamOptions::place
  PlaceIndex placeIndex_;
  std::vector<PlaceLink> placeLinks_;
  int placedSegments_ = 0;
  int lost_ = 0, losses_ = 0, resets_ = 0, relocalisations_ = 0, revisitPoints_ = 0, refinedFrames_ = 0, headModelFrames_ = 0;
  /// The segments placed by the head model (join.placeShort), with their frame ranges [from, to):
  /// their keyframe depths and points are in a scale of their own and are left out of the result.
  struct PlacedRange {
    int from, to, segment;
  };
  std::vector<PlacedRange> placedRanges_;
  bool placedFrame(int f) const {
    for (const PlacedRange& r : placedRanges_) {
      if (f >= r.from && f < r.to && frames_[static_cast<std::size_t>(f)].segment == r.segment) return true;
    }
    return false;
  }
  int relocCandidateFrame_ = -1;  ///< last frame whose relocalisation waits for the next one's agreement
  SE3T relocCandidate_;
  int placeCandFrame_ = -1, placeCandSegment_ = -1, placeCandInliers_ = 0;  ///< the same for the relocalisation by place
  bool placeWaiting_ = false;  ///< this frame's place pose waits for the next frame's
  SE3T placeCand_;
  int placeRelocalisations_ = 0;
  bool afterLoss_ = false, everInitialised_ = false;
  int lastKfInliers_ = 0, framesSinceKf_ = 0;
  int adjustedKeyframes_ = 0;  ///< keyframes in finish()'s global bundle adjustment
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

// The member functions, by part (each header is one part of MonoSlam).
#include "mono_slam/front_end.hpp"
#include "mono_slam/initialisation.hpp"
#include "mono_slam/tracking.hpp"
#include "mono_slam/relocalisation.hpp"
#include "mono_slam/place_links.hpp"
#include "mono_slam/mapping.hpp"
#include "mono_slam/finish.hpp"
#include "mono_slam/segment_joins.hpp"
