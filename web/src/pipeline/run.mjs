// run.mjs: the whole hawor pipeline on a stream of video frames, shared by the node CLI
// (web/cli.mjs) and the browser app (a Web Worker). No node-only import: the caller passes the
// C++ core (hawor_core.mjs, instantiated), the onnxruntime-web namespace and the bytes of every
// model, and feeds frames as RGBA (or RGB) byte arrays.
//
//   import { runPipeline } from './pipeline/run.mjs';
//   const result = await runPipeline(source, options, hooks);
//
// source  { width, height, fps, frameCount: number | null,
//           frames: async iterable of { index, rgba: Uint8Array | Uint8ClampedArray } }
//         rgba holds width*height*4 bytes (canvas ImageData) or width*height*3 (RGB from a
//         decoder); frames are consumed one at a time and not kept (except, with a depth model,
//         a copy at the SLAM resolution, see below).
// options { core, ort,
//           models: { palm: Uint8Array, landmark: Uint8Array }     ONNX bytes (or
//                   { palmSession, landmarkSession }: onnxruntime sessions already made),
//           handModels: { left: Uint8Array, right: Uint8Array,     any file the core reads
//                         leftName?, rightName? },                 (default hand .npz/.glb, MANO
//                                                                  .pkl/.npz); names help the
//                                                                  format check only
//           focalPx?, fovDeg?            focal length in pixels, or a diagonal field of view
//                                        (through the lens); default: DEFAULT_DIAGONAL_FOV_DEG
//           camera? ('pinhole')          the lens: 'pinhole', 'opencv:k1,k2,p1,p2[,k3]' or
//                                        'fisheye:k1,k2,k3,k4' (geometry/lens.hpp), with the
//                                        focal's intrinsics. Then: the landmark crops are
//                                        perspective views through the lens, the keypoints are
//                                        undistorted before the fit, and the SLAM runs in the
//                                        virtual pinhole camera with the same intrinsics at the
//                                        SLAM resolution (frames rectified after downscaling,
//                                        render/rectify.hpp; a fisheye's periphery beyond that
//                                        camera's field is cut), where the hand masks are
//                                        rendered too; its poses are the real camera's. The
//                                        focal refinement refines that virtual camera's focal,
//                                        and the lens' fx, fy scale with it (the output
//                                        intrinsics hold both). A string that does not parse,
//                                        or a lens that folds inside the image, throws
//           refineFocal? (true)          let the SLAM's final bundle adjustment refine the focal
//                                        (a profile over log f with a prior toward the given or
//                                        default focal; declined when the motion does not
//                                        determine it); when refined, the hands are re-fitted
//           focalPriorSigma? (0.3)       the prior's std of log f (user focal: 0.1 by default)
//           readout? (0)                 rolling shutter: seconds from the first row's exposure
//                                        to the last's (0: global shutter; at most 1 / fps;
//                                        negative: rows read bottom to top, as in a clip played
//                                        backwards); the
//                                        SLAM brings its points to the middle row's time under
//                                        the head's rotation (SlamOptions::rollingShutter)
//           focalMaxPasses? (4)          SLAM passes at most (see focalRerunBytes)
//           focalRerunBytes? (256 MB)    the SLAM's grey frames and masks are kept up to this
//                                        size; when the focal was refined and they were kept, the
//                                        SLAM runs a second pass with the refined focal (its
//                                        tracking and map then use it, not only its final BA)
//           handScaleSmooth? (0)         experiment: centred moving average (half-width, frames)
//                                        of the camera-frame wrists before the hand-anchored scale
//           modelKind: 'lite' | 'full'   recorded in the result (the caller picks the bytes)
//           depthModel?: { bytes, config }   a metric-depth ONNX + its JSON config (the slot of
//                                        web/src/depth_model.mjs), run on the SLAM keyframes,
//                        | { predict: async (frameIndex, rgb, width, height) => Float32Array }
//                                        any other source of metric depth (metres, NaN unknown)
//                                        at the SLAM resolution (benchmarks: ground truth); with
//                                        a lens, of the rectified frame it is given
//           threads?                     onnxruntime's threads (ort.env.wasm.numThreads, set here
//                                        if given; only effective before its first session)
//           slamMaxSide? (640)           the SLAM and hand masks run on frames downscaled to
//                                        this long side (intrinsics scaled alike)
//           maxPixels? (MAX_PIXELS)      larger frames are refused with a clear error (the
//                                        caller downscales first; the CLI does, with ffmpeg)
//           observations?: (index) => [{ handedness: 'left'|'right', handednessScore?,
//                                        landmarks: (2 or 3 per keypoint, 21) image px,
//                                        world: (63) metres | null }]
//                                        replaces the perception networks (benchmarks with
//                                        simulated keypoints); ort and models are then unused
//           infill? ('spline' | 'lerp' | 'last'), maskDilatePx? (2, at the SLAM resolution),
//           detectGap? (1)               while one hand is tracked, the palm detector looks for
//                                        the other only every detectGap+1 frames
//           minPresence? (0.3)           the landmark network's hand presence to keep a hand
//                                        (MediaPipe's 0.5 drops the wearer's hand gripping a
//                                        plate on the kitchen clip; tests/web/kitchen_hands)
//           tracker? ({})                further HandTracker options over
//                                        PIPELINE_TRACKER_OPTIONS (experiments)
//           groundScale? (true)          the ground cue of the metric scale: the cameras' height
//                                        above the map's floor plane (scale/ground_scale.hpp)
//           eyeHeight? (1.6)             that height in metres (a standing adult's head camera;
//                                        about 1.2 sitting) }
// hooks   { onProgress?({ stage, done, total }), onFrame?(frameInfo), signal?: AbortSignal }
//         onFrame gets { index, hands: [{ side, valid, keypoints2d: Float64Array(42) }],
//         slamStatus, ms } after each frame; an aborted signal throws an AbortError (checked
//         before every frame and between the stages after the last one).
//
// The result (what result.json holds; flat numeric arrays are typed arrays here, plain arrays
// in the JSON; NaN becomes null in the JSON):
// { version: 1, width, height, fps, frameCount,
//   modelKind, threads,
//   intrinsics: { fx, fy, cx, cy (the ones used for the output: refined when refined is true),
//                 lens (the camera model's lens, canonical: 'pinhole', 'opencv:...', 'fisheye:...'),
//                 focalSource: 'user-focal' | 'user-fov' | 'default-fov' | 'slam' (refined),
//                 guessSource (the source of the starting focal), guessFx, fovDeg (diagonal, of
//                 fx, through the lens), refined: bool, focalStd (relative posterior std, null when not
//                 estimated), focalEstimateFx (the SLAM's estimate even when not applied, null
//                 when none), focalReason (why refined / kept / declined), focalPasses (2: the
//                 SLAM ran again with the refined focal) },
//   slam: { width, height, numKeyframes, numLosses, numResets, numRelocalisations, numPlaceRelocalisations, numRevisitPoints,
//           numPlaceLinks, numPlacedSegments, numRefinedFrames, numHeadModelFrames, initialised },
//   camera: { positions (T*3, metres, camera centre in the world), quaternions (T*4, x y z w,
//             camera-to-world rotation), status (T: 0 tracked, 1 interpolated, 2 lost,
//             3 relocalised), timestamps (T, seconds) },
//   points: (N*3) the SLAM's final map points, world frame, metres; may be empty,
//   scale: { scale, method: 'depth'|'hands'|'ground'|'fused'|'none', confidence, ... (metricScale's
//            fields; ground: { ok, scale, confidence, cameraHeight, surfaceHeight, ... } or { ok, reason }) },
//   hands: { left: Hand, right: Hand },  Hand = {
//     valid (T: observed and fitted), infilled (T: filled by the infiller), present (any frame),
//     trans (T*3), rot (T*3 axis-angle), handPose (T*P), betas (T*B)   world frame, metres;
//                                      P = 3*(J-1) of the model (45 for MANO), B its betas (10
//                                      for MANO, 0 for the default hand); NaN where not present
//     camTrans, camRot (T*3)            camera frame (observed frames; NaN elsewhere)
//     jointsWorld (T*21*3)              the model's 21 keypoints of the world motion
//     jointsCam (T*21*3)                the fitted keypoints in the camera frame (NaN elsewhere)
//     keypoints2d (T*21*2)              the detected image keypoints (NaN where not detected;
//                                      image pixels of the video, distorted by its lens)
//     reprojRmsPx (T), handPoseCols P, betaCols B, model: kind },
//   faces: { left: Int32Array, right: Int32Array } (the hand meshes' triangles; the vertices
//          of frame t: core.HandModel(bytes).forward({rot, handPose, betas, trans} of frame t)),
//   timings: { stage: total ms, load: model loading }, warnings: [strings], noHands: bool,
//   stats: { palmRuns, landmarkRuns } (the tracker's; {} with observations) }
//
// Stages (timings keys): perception (networks + crops), fit (hand fit per hand), masks (hand
// silhouettes at the SLAM resolution), slamPrep (downscale + grey, and the rectification with a
// lens), slam (tracking + mapping),
// slamFinish (final bundle adjustment), depth (optional), scale, world (camera -> world),
// infill, joints (forward pass of the world motion).

import { HandTracker } from '../perception/hand_tracker.mjs';
import { DepthModel } from '../depth_model.mjs';
import { eyeHeightError } from './eye_height.mjs';

export const RESULT_VERSION = 1;
/** The default diagonal field of view when the caller gives none (see README: between a phone's
 *  main camera, ~75-80 degrees, and a head camera's wide lens, ~100-120). */
export const DEFAULT_DIAGONAL_FOV_DEG = 90;
/** Frames above this many pixels are refused (8K is 33 Mpx; the CLI downscales such videos). */
export const MAX_PIXELS = 4096 * 2304;
export const NUM_KP = 21;
/** The hand tracker's defaults in the pipeline (measured with web/tools/eval_kitchen_hands.mjs). */
export const PIPELINE_DETECT_GAP = 1;
export const PIPELINE_MIN_PRESENCE = 0.3;
/** The rest of the pipeline's tracking policy (hand_tracker.mjs; measured on the kitchen clip's
 *  variants, examples/bench_real.mjs, docs/benchmarks.md): palm candidates down to 0.1, the best
 *  two verified by the landmark network (below the detector's 0.5 a candidate needs MediaPipe's
 *  own presence threshold, 0.5), the detector's input box-prefiltered, re-detection on the
 *  frame a track is lost, constant-velocity search ROIs, and a lost track looked for once more. */
export const PIPELINE_TRACKER_OPTIONS = Object.freeze({
  candidateScore: 0.1, candidatePresence: 0.5, maxCandidates: 2, palmPrefilter: 0.5, redetectOnLoss: true, motion: true, coast: 1,
});

function abortError() {
  const e = new Error('the pipeline was aborted');
  e.name = 'AbortError';
  return e;
}
function checkAbort(signal) {
  if (signal && signal.aborted) throw abortError();
}
const now = () => (typeof performance !== 'undefined' ? performance.now() : Date.now());

/** Pinhole intrinsics for a frame: a given focal, or one from a diagonal field of view. The
 *  principal point is the image centre (pixel centres at integer coordinates, docs/design.md §2). */
export function defaultIntrinsics(width, height, { focalPx, fovDeg } = {}) {
  if (!(width > 0 && height > 0)) throw new Error(`intrinsics: bad image size ${width}x${height}`);
  const halfDiag = 0.5 * Math.hypot(width, height);
  let f;
  let focalSource;
  if (focalPx !== undefined && focalPx !== null) {
    if (!(Number.isFinite(focalPx) && focalPx > 0)) throw new Error(`focal length must be a positive number of pixels, not ${focalPx}`);
    f = focalPx;
    focalSource = 'user-focal';
  } else {
    const fov = fovDeg ?? DEFAULT_DIAGONAL_FOV_DEG;
    if (!(Number.isFinite(fov) && fov > 1 && fov < 179)) throw new Error(`field of view must be in (1, 179) degrees, not ${fovDeg}`);
    f = halfDiag / Math.tan((fov * Math.PI) / 360);
    focalSource = fovDeg === undefined || fovDeg === null ? 'default-fov' : 'user-fov';
  }
  const fovOut = (360 / Math.PI) * Math.atan(halfDiag / f);
  return { fx: f, fy: f, cx: (width - 1) / 2, cy: (height - 1) / 2, focalSource, fovDeg: fovOut, refined: false };
}

/**
 * The camera model of a width x height video: defaultIntrinsics plus `lens`, the canonical lens
 * string (options.camera, default 'pinhole'; a lens without distortion becomes 'pinhole'). With a
 * lens and no focalPx the field of view (fovDeg or the default) is measured through the lens
 * (CameraModel::fromFov), and fovDeg reports the diagonal field through it. Throws an Error
 * naming the string and the core's reason for a lens that does not parse, a coefficient that is
 * not finite, or a lens that folds inside the image.
 */
export function cameraIntrinsics(core, width, height, { focalPx, fovDeg, camera } = {}) {
  const intr = defaultIntrinsics(width, height, { focalPx, fovDeg });
  const spec = camera ?? 'pinhole';
  if (typeof spec !== 'string') throw new Error('the camera model must be a lens string (pinhole, opencv:k1,k2,p1,p2[,k3] or fisheye:k1,k2,k3,k4)');
  let lens;
  try {
    lens = core.parseLens(spec);
    if (lens !== 'pinhole' && intr.focalSource !== 'user-focal') {
      const c = core.cameraFromFov(width, height, lens, fovDeg ?? DEFAULT_DIAGONAL_FOV_DEG);
      Object.assign(intr, { fx: c.fx, fy: c.fy });
    }
    const d = core.describeCamera([intr.fx, intr.fy, intr.cx, intr.cy], width, height, lens);
    if (d.pinhole) lens = 'pinhole';
    else intr.fovDeg = 2 * d.maxFieldAngleDeg;
  } catch (e) {
    throw new Error(`the camera model '${spec}': ${e.message}`);
  }
  intr.lens = lens;
  return intr;
}

/** The SLAM's frame size: the long side at most maxSide, aspect kept, integer pixels. */
export function slamSize(width, height, maxSide = 640) {
  const s = Math.min(1, maxSide / Math.max(width, height));
  return { width: Math.max(16, Math.round(width * s)), height: Math.max(16, Math.round(height * s)), s };
}

/** P(right) of a detection: its track's (the tracker's handedness evidence summed over the
 *  frames of the track), else from its label and score. */
function pRight(h) {
  if (h.track && Number.isFinite(h.track.pRight)) return h.track.pRight;
  const s = h.handednessScore ?? 1;
  return h.handedness === 'right' ? s : 1 - s;
}

/**
 * Left/right slots for this frame's detections (at most one per side): the assignment of least
 * cost, where a detection's cost on a side is
 *   -log P(side) from the landmark network's handedness (of the detection's track when the
 *     tracker gives one), clamped to [0.05, 0.95] (one frame's label, which flips now and then
 *     with full confidence, can be outvoted), minus
 *   CONTINUITY when it continues the track that side last held (prev.tracks, tracker ids kept
 *     over frames without that side), else CONTINUITY * (1 - d / reach) / age when it lies
 *     within `reach` px of that side's last wrist, seen `age` frames ago (1: the previous
 *     frame; tracks keep their side, and a hand lost for a few frames mostly comes back where
 *     it was),
 * plus, for two hands, CROSSED when the left slot's wrist lies right of the right slot's (hands
 * rarely cross in an egocentric view: CROSSED exceeds both tracks' continuity, so two hands in
 * view are ordered left to right unless both hands' handedness evidence holds the crossing; a
 * track whose first frames' labels were wrong, as the network's often are on a hand entering
 * at the bottom edge, changes side as soon as the other hand is in view).
 * prev: { left: [x, y] | null, right: [x, y] | null, age?: { left, right } (default 1),
 *         tracks?: { left: id | null, right: id | null } } (sideState / updateSideState);
 * reach: pixels.
 */
export function assignSides(dets, prev, reach) {
  const CONTINUITY = 3.5;
  const CROSSED = 2 * CONTINUITY + 2;
  const cost = (d, side) => {
    const p = Math.min(Math.max(side === 'right' ? pRight(d) : 1 - pRight(d), 0.05), 0.95);
    let c = -Math.log(p);
    const w = prev[side];
    if (d.track && prev.tracks && prev.tracks[side] === d.track.id) c -= CONTINUITY;
    else if (w) {
      const dist = Math.hypot(d.landmarks[0] - w[0], d.landmarks[1] - w[1]);
      const age = prev.age ? Math.max(1, prev.age[side]) : 1;
      if (dist < reach) c -= (CONTINUITY * (1 - dist / reach)) / age;
    }
    return c;
  };
  if (dets.length === 0) return { left: null, right: null };
  if (dets.length === 1) {
    const d = dets[0];
    return cost(d, 'left') < cost(d, 'right') ? { left: d, right: null } : { left: null, right: d };
  }
  // the best two (the tracker returns at most maxHands)
  const [a, b] = dets;
  const crossed = (l, r) => (l.landmarks[0] > r.landmarks[0] ? CROSSED : 0);
  const ab = cost(a, 'left') + cost(b, 'right') + crossed(a, b);
  const ba = cost(b, 'left') + cost(a, 'right') + crossed(b, a);
  return ab <= ba ? { left: a, right: b } : { left: b, right: a };
}

/** The state assignSides reads: no side seen yet. */
export function sideState() {
  return { left: null, right: null, age: { left: 0, right: 0 }, tracks: { left: null, right: null } };
}

/** After a frame's assignment: each filled side's wrist, age 1 and track (a track holds one side
 *  at a time); an empty side keeps its last wrist and track, one frame older. */
export function updateSideState(prev, sides) {
  for (const side of ['left', 'right']) {
    const d = sides[side];
    if (!d) {
      if (prev[side]) prev.age[side] += 1;
      continue;
    }
    const other = side === 'left' ? 'right' : 'left';
    prev[side] = [d.landmarks[0], d.landmarks[1]];
    prev.age[side] = 1;
    prev.tracks[side] = d.track ? d.track.id : null;
    if (d.track && prev.tracks[other] === d.track.id) prev.tracks[other] = null;
  }
}

function nanArray(n) {
  const a = new Float64Array(n);
  a.fill(NaN);
  return a;
}

/** A growable per-frame store of one hand's camera-frame observations. */
class HandTrackStore {
  constructor(P, B) {
    Object.assign(this, { P, B });
    this.frames = [];
  }
  push(f) { this.frames.push(f); }
  column(get, width) {
    const T = this.frames.length;
    const a = nanArray(T * width);
    for (let t = 0; t < T; ++t) {
      const v = this.frames[t] && get(this.frames[t]);
      if (v) a.set(v.length > width ? v.subarray(0, width) : v, t * width);
    }
    return a;
  }
}

/** Centred moving average (half-width k) of a (T,3) track within each run of valid frames. */
function smoothTrack(positions, valid, T, k) {
  const src = Float64Array.from(positions);
  for (let t = 0; t < T; ++t) {
    if (!valid[t]) continue;
    let lo = t; while (lo > t - k && lo > 0 && valid[lo - 1]) lo -= 1;
    let hi = t; while (hi < t + k && hi < T - 1 && valid[hi + 1]) hi += 1;
    const h = Math.min(t - lo, hi - t); // symmetric window (no lag)
    for (let a = 0; a < 3; ++a) {
      let sum = 0;
      for (let u = t - h; u <= t + h; ++u) sum += src[3 * u + a];
      positions[3 * t + a] = sum / (2 * h + 1);
    }
  }
}

function modelName(bytes, given, side) {
  if (given) return given;
  // the core recognises the format from the content; a name helps MANO/glTF side detection only
  return `hand_${side}`;
}

/**
 * Runs the pipeline. See the header for source, options, hooks and the result.
 */
export async function runPipeline(source, options, hooks = {}) {
  const { core } = options ?? {};
  const { signal, onProgress, onFrame } = hooks ?? {};
  if (!core || !core.HandModel || !core.MonoSlam) throw new Error('runPipeline: options.core must be the instantiated hawor_core module');
  if (!source || typeof source !== 'object') throw new Error('runPipeline: source missing');
  const { width, height } = source;
  const fps = source.fps ?? 30;
  if (!(Number.isInteger(width) && Number.isInteger(height) && width > 0 && height > 0)) {
    throw new Error(`runPipeline: bad frame size ${width}x${height}`);
  }
  const maxPixels = options.maxPixels ?? MAX_PIXELS;
  if (width * height > maxPixels) {
    throw new Error(`runPipeline: frames of ${width}x${height} (${(width * height / 1e6).toFixed(1)} Mpx) exceed the limit of ${(maxPixels / 1e6).toFixed(1)} Mpx; downscale the video first (e.g. to 1920 px wide)`);
  }
  if (!(Number.isFinite(fps) && fps > 0)) throw new Error(`runPipeline: bad fps ${source.fps}`);
  const readout = options.readout ?? 0;
  if (!(Number.isFinite(readout) && Math.abs(readout) <= 1 / fps)) {
    throw new Error(`runPipeline: the rolling-shutter readout ${options.readout} s must lie within one frame interval (±${(1 / fps).toFixed(4)} s)`);
  }
  if (options.eyeHeight !== undefined && eyeHeightError(options.eyeHeight)) throw new Error(`runPipeline: ${eyeHeightError(options.eyeHeight)}`);
  if (!source.frames || typeof source.frames[Symbol.asyncIterator] !== 'function' && typeof source.frames[Symbol.iterator] !== 'function') {
    throw new Error('runPipeline: source.frames must be an (async) iterable of { index, rgba }');
  }
  if (!options.handModels || !options.handModels.left || !options.handModels.right) {
    throw new Error('runPipeline: options.handModels.left and .right (hand model file bytes) are required');
  }
  checkAbort(signal);

  const warnings = [];
  const timings = {};
  const addTime = (k, ms) => { timings[k] = (timings[k] ?? 0) + ms; };
  // The camera model (the core parses and checks the lens; a pinhole lens changes nothing below).
  const intr = cameraIntrinsics(core, width, height, options);
  const lens = intr.lens;
  const withLens = lens !== 'pinhole';
  const K = [intr.fx, intr.fy, intr.cx, intr.cy];
  const ss = slamSize(width, height, options.slamMaxSide ?? 640);
  const sx = ss.width / width;
  const sy = ss.height / height;
  // The SLAM image's pixel (u', v') covers source pixels u = (u' + 0.5) / s - 0.5.
  const Ks = [intr.fx * sx, intr.fy * sy, (intr.cx + 0.5) * sx - 0.5, (intr.cy + 0.5) * sy - 0.5];
  const dilate = options.maskDilatePx ?? 2; // pixels at the SLAM resolution (see README: 8 px was no better)
  const infillMethod = options.infill ?? 'spline';

  const owned = []; // embind objects to delete
  let tracker = null;
  let depthModel = null;
  try {
    // --- models ---
    const t0 = now();
    const models = {};
    for (const side of ['left', 'right']) {
      const bytes = options.handModels[side];
      if (!(bytes instanceof Uint8Array)) throw new Error(`runPipeline: handModels.${side} must be a Uint8Array`);
      try {
        models[side] = new core.HandModel(bytes, side, modelName(bytes, options.handModels[`${side}Name`], side));
      } catch (e) {
        throw new Error(`the ${side} hand model: ${e.message}`);
      }
      owned.push(models[side]);
      if (models[side].numKeypoints() !== NUM_KP) throw new Error(`the ${side} hand model gives ${models[side].numKeypoints()} keypoints, not 21`);
    }
    const fitters = { left: new core.HandFitter(models.left), right: new core.HandFitter(models.right) };
    owned.push(fitters.left, fitters.right);
    // With a lens: perspective landmark crops through it (full resolution), and the SLAM frames
    // rectified to the virtual pinhole camera (SLAM resolution).
    let lensCamera = null;
    let rectifier = null;
    if (withLens) {
      lensCamera = new core.LensCamera(K, width, height, lens);
      owned.push(lensCamera);
      rectifier = new core.Rectifier(Ks, ss.width, ss.height, lens);
      owned.push(rectifier);
      if (intr.focalSource !== 'user-focal') {
        warnings.push(`a lens model (${lens}) without a focal length: the focal comes from a ${options.fovDeg ?? DEFAULT_DIAGONAL_FOV_DEG} degree field of view through the lens; calibrated coefficients belong with their calibration's focal (give it)`);
      }
    }
    /** Keypoints for the fit: through the lens, undistorted to the virtual pinhole camera of K
     *  (those beyond the lens' reach get confidence 0). */
    const fitInput = (kp2, Kfit) => {
      if (!withLens) return { kp: kp2, conf: null };
      const u = core.undistortPoints(Kfit, lens, kp2);
      const conf = new Float64Array(NUM_KP);
      for (let k = 0; k < NUM_KP; ++k) {
        if (Number.isFinite(u[2 * k]) && Number.isFinite(u[2 * k + 1])) conf[k] = 1;
        else { u[2 * k] = 0; u[2 * k + 1] = 0; }
      }
      return { kp: u, conf };
    };
    const lensCrops = lensCamera ? { cropMap: (roi, n) => lensCamera.cropMap(roi, n, n), cropToImage: (roi, uv) => lensCamera.cropToImage(roi, uv) } : null;
    const P = { left: 3 * (models.left.numJoints() - 1), right: 3 * (models.right.numJoints() - 1) };
    const B = { left: models.left.numBetas(), right: models.right.numBetas() };
    if (options.threads && options.ort && options.ort.env && options.ort.env.wasm && !options.models?.palmSession) {
      options.ort.env.wasm.numThreads = options.threads; // effective before onnxruntime's first session only
    }
    if (!options.observations) {
      const ort = options.ort;
      if (!ort || !ort.InferenceSession) throw new Error('runPipeline: options.ort (the onnxruntime-web namespace) is required');
      const m = options.models ?? {};
      const detectGap = options.detectGap ?? PIPELINE_DETECT_GAP;
      const minPresence = options.minPresence ?? PIPELINE_MIN_PRESENCE;
      const policy = { ...PIPELINE_TRACKER_OPTIONS, ...(options.tracker ?? {}) };
      if (m.palmSession && m.landmarkSession) {
        tracker = new HandTracker(ort, m.palmSession, m.landmarkSession, { maxHands: 2, detectGap, minPresence, ...policy, lens: lensCrops });
      } else {
        if (!(m.palm instanceof Uint8Array) || !(m.landmark instanceof Uint8Array)) {
          throw new Error('runPipeline: options.models.palm and .landmark (ONNX bytes) are required');
        }
        tracker = await HandTracker.create(ort, m.palm, m.landmark, { maxHands: 2, detectGap, minPresence, ...policy, lens: lensCrops });
      }
    }
    if (options.depthModel && typeof options.depthModel.predict === 'function') {
      const custom = options.depthModel;
      depthModel = { predict: (rgb, w, h, c, frame) => custom.predict(frame, rgb, w, h) };
    } else if (options.depthModel) {
      if (!options.ort) throw new Error('runPipeline: a depth model needs options.ort');
      depthModel = await DepthModel.create(options.ort, options.depthModel.bytes, options.depthModel.config);
    }
    addTime('load', now() - t0);

    const refineFocal = options.refineFocal ?? true;
    const focalPriorSigma = options.focalPriorSigma ?? (intr.focalSource === 'user-focal' ? 0.1 : 0.3);
    const slam = new core.MonoSlam(Ks, ss.width, ss.height, { useMasks: true, refineFocal, focalPriorSigma, rollingShutter: readout * fps });
    const rerunBytes = options.focalRerunBytes ?? 256 * 1024 * 1024;
    let keptSlam = refineFocal && rerunBytes > 0 ? { frames: [], masks: [], bytes: 0 } : null;
    owned.push(slam);
    const stores = { left: new HandTrackStore(P.left, B.left), right: new HandTrackStore(P.right, B.right) };
    const keptRgb = depthModel ? [] : null; // frames (and hand masks) for the depth of the keyframes
    const keptMasks = depthModel ? [] : null;
    const prevWrist = sideState();
    const reach = 0.15 * Math.hypot(width, height);
    let T = 0;
    let channels = 0;
    let fitFailures = 0;

    for await (const frame of source.frames) {
      checkAbort(signal);
      const tf = now();
      const rgba = frame && frame.rgba;
      if (!(rgba instanceof Uint8Array || rgba instanceof Uint8ClampedArray)) throw new Error(`frame ${T}: rgba must be a Uint8Array`);
      const c = rgba.length / (width * height);
      if (c !== 3 && c !== 4) throw new Error(`frame ${T}: ${rgba.length} bytes, expected ${width}x${height}x4 (RGBA) or x3 (RGB)`);
      channels = c;
      // --- perception ---
      let t1 = now();
      let dets;
      if (options.observations) {
        dets = (await options.observations(T)) ?? [];
      } else {
        dets = await tracker.track({ width, height, data: rgba, channels: c });
      }
      addTime('perception', now() - t1);
      const sides = assignSides(dets, prevWrist, reach);
      updateSideState(prevWrist, sides);
      // --- fit ---
      t1 = now();
      const maskHands = [];
      const info = { index: frame.index ?? T, hands: [] };
      for (const side of ['left', 'right']) {
        const d = sides[side];
        if (!d) {
          fitters[side].reset();
          stores[side].push(null);
          continue;
        }
        const stride = d.landmarks.length === 63 ? 3 : 2;
        const kp2 = new Float64Array(2 * NUM_KP);
        for (let k = 0; k < NUM_KP; ++k) { kp2[2 * k] = d.landmarks[stride * k]; kp2[2 * k + 1] = d.landmarks[stride * k + 1]; }
        const kp3 = d.world ? Float64Array.from(d.world) : null;
        let fit = null;
        try {
          const fi = fitInput(kp2, K);
          fit = fitters[side].fit(fi.kp, fi.conf, kp3, null, K, width, height);
        } catch (e) {
          fitFailures += 1;
          fitters[side].reset();
        }
        // a fit behind the camera or absurdly far is not a hand
        const ok = fit && fit.trans[2] > 0.03 && fit.trans[2] < 5 && Number.isFinite(fit.reprojRmsPx);
        if (!ok) {
          stores[side].push({ kp2, kp3 });
          info.hands.push({ side, valid: false, keypoints2d: kp2 });
          continue;
        }
        stores[side].push({ kp2, kp3, fit });
        maskHands.push({ model: models[side], rot: fit.rot, handPose: fit.handPose, betas: fit.betas, trans: fit.trans, value: 255 });
        info.hands.push({ side, valid: true, keypoints2d: kp2 });
      }
      addTime('fit', now() - t1);
      // --- masks at the SLAM resolution ---
      t1 = now();
      const mask = maskHands.length ? core.renderHandMasks(ss.width, ss.height, Ks, maskHands, dilate) : null;
      if (keptMasks) keptMasks.push(mask);
      addTime('masks', now() - t1);
      // --- SLAM ---
      t1 = now();
      // at the frame's own size the core converts to grey itself; with a lens the grey frame is
      // rectified to the virtual pinhole camera, and the part of it the lens does not see joins
      // the mask
      let slamFrame = ss.width === width && ss.height === height && !rectifier ? rgba : core.downscaleImage(rgba, width, height, c, ss.width, ss.height, true);
      let slamMask = mask;
      if (rectifier) {
        slamFrame = rectifier.grey(slamFrame);
        slamMask = rectifier.slamMask(mask);
      }
      if (keptRgb) {
        const rgb = ss.width === width && ss.height === height && c === 3 ? rgba.slice() : core.downscaleImage(rgba, width, height, c, ss.width, ss.height, false);
        keptRgb.push(rectifier ? rectifier.image(rgb, 3) : rgb);
      }
      if (keptSlam) {
        if (keptSlam.bytes + 2 * ss.width * ss.height > rerunBytes) {
          keptSlam = null; // too long a video for a second SLAM pass: the focal is refined in the final BA only
        } else {
          const g = slamFrame === rgba ? core.downscaleImage(rgba, width, height, c, ss.width, ss.height, true) : slamFrame;
          keptSlam.frames.push(g);
          keptSlam.masks.push(slamMask);
          keptSlam.bytes += g.length + (slamMask ? slamMask.length : 0);
        }
      }
      addTime('slamPrep', now() - t1);
      t1 = now();
      info.slamStatus = slam.process(slamFrame, slamMask);
      addTime('slam', now() - t1);
      T += 1;
      info.ms = now() - tf;
      if (onFrame) onFrame(info);
      if (onProgress) onProgress({ stage: 'frames', done: T, total: source.frameCount ?? null });
    }
    if (T === 0) throw new Error('the video has no frames');
    if (fitFailures) warnings.push(`the hand fit failed on ${fitFailures} detections (those frames count as unobserved)`);
    checkAbort(signal);

    // --- SLAM finish ---
    let t1 = now();
    if (onProgress) onProgress({ stage: 'slam-finish', done: 0, total: 1 });
    let traj = slam.finish();
    addTime('slamFinish', now() - t1);
    const fr1 = traj.focal;
    let focalPasses = 1;
    const maxPasses = options.focalMaxPasses ?? 4;
    // Further passes with the refined focal while it still moves: a map built with a wrong focal
    // (its triangulations and culled observations) biases each pass's estimate toward its start.
    let last = fr1;
    t1 = now();
    while (last && last.changed && keptSlam && keptSlam.frames.length === T && focalPasses < maxPasses) {
      checkAbort(signal);
      const slam2 = new core.MonoSlam([last.fx, last.fy, Ks[2], Ks[3]], ss.width, ss.height, { useMasks: true, refineFocal: true, focalPriorSigma, focalPriorFx: Ks[0], rollingShutter: readout * fps });
      owned.push(slam2);
      for (let t = 0; t < T; ++t) slam2.process(keptSlam.frames[t], keptSlam.masks[t]);
      const traj2 = slam2.finish();
      if (!traj2.initialised && traj.initialised) break; // keep the previous pass
      traj = traj2;
      focalPasses += 1;
      last = traj2.focal;
    }
    if (focalPasses > 1) {
      addTime('slamRerun', now() - t1);
      const f = traj.focal;
      // the output's focal is the last pass's; refined relative to the user's guess
      traj.focal = { ...f, changed: true, accepted: true, stdLog: f.accepted ? f.stdLog : fr1.stdLog,
        estimateFx: f.estimateFx > 0 ? f.estimateFx : f.fx, reason: `${fr1.reason} (${focalPasses} SLAM passes)` };
    }
    keptSlam = null;
    if (!traj.initialised) {
      warnings.push(T < 2 ? 'a single frame: no camera motion can be estimated (identity pose)'
        : 'the SLAM did not initialise (too little camera translation or texture): the camera is held at the first pose');
    }
    // --- focal: the SLAM's refinement (the hands are re-fitted with it) ---
    const fr = traj.focal;
    const intrOut = { ...intr, guessSource: intr.focalSource, guessFx: intr.fx, refined: false, focalPasses,
      focalStd: fr && fr.accepted && Number.isFinite(fr.stdLog) ? fr.stdLog : null,
      focalEstimateFx: fr && fr.estimateFx > 0 ? fr.estimateFx / sx : null,
      focalReason: !refineFocal ? 'off' : (fr ? fr.reason : 'not run'), readout };
    if (fr && fr.changed) {
      intrOut.fx = fr.fx / sx;
      intrOut.fy = fr.fy / sy;
      intrOut.refined = true;
      intrOut.focalSource = 'slam';
      intrOut.fovDeg = withLens ? 2 * core.describeCamera([intrOut.fx, intrOut.fy, intr.cx, intr.cy], width, height, lens).maxFieldAngleDeg
        : (2 * Math.atan(0.5 * Math.hypot(width, height) / intrOut.fx) * 180) / Math.PI;
      t1 = now();
      const K2 = [intrOut.fx, intrOut.fy, intr.cx, intr.cy];
      for (const side of ['left', 'right']) {
        fitters[side].reset();
        let prevOk = false;
        for (const f of stores[side].frames) {
          if (!f) { if (prevOk) fitters[side].reset(); prevOk = false; continue; }
          let fit = null;
          try {
            // through a lens: the lens' fx, fy scale with the refined virtual focal
            const fi = fitInput(f.kp2, K2);
            fit = fitters[side].fit(fi.kp, fi.conf, f.kp3, null, K2, width, height);
          } catch (e) {
            fitters[side].reset();
          }
          const ok = fit && fit.trans[2] > 0.03 && fit.trans[2] < 5 && Number.isFinite(fit.reprojRmsPx);
          if (ok) f.fit = fit; else { delete f.fit; fitters[side].reset(); }
          prevOk = !!ok;
        }
      }
      addTime('refit', now() - t1);
    }
    const nLost = Array.from(traj.status).filter((s) => s === 2).length;
    if (nLost > 0) warnings.push(`the camera was lost on ${nLost} of ${T} frames (their poses are interpolated or held)`);
    checkAbort(signal);

    // --- hands: camera-frame motion per side ---
    const hands = {};
    const present = {};
    for (const side of ['left', 'right']) {
      const st = stores[side];
      const valid = new Uint8Array(T);
      for (let t = 0; t < T; ++t) valid[t] = st.frames[t] && st.frames[t].fit ? 1 : 0;
      present[side] = valid.some((v) => v);
      hands[side] = {
        valid,
        camRot: st.column((f) => f.fit && f.fit.rot, 3),
        camTrans: st.column((f) => f.fit && f.fit.trans, 3),
        handPose: st.column((f) => f.fit && f.fit.handPose, P[side]),
        betas: st.column((f) => f.fit && f.fit.betas, B[side]),
        jointsCam: st.column((f) => f.fit && f.fit.keypoints, 3 * NUM_KP),
        keypoints2d: st.column((f) => f.kp2, 2 * NUM_KP),
        reprojRmsPx: st.column((f) => f.fit && Float64Array.of(f.fit.reprojRmsPx), 1),
      };
    }
    const noHands = !present.left && !present.right;
    if (noHands) warnings.push('no hands were found in the video');

    // --- depth on keyframes (optional) ---
    let depthMaps = null;
    if (depthModel) {
      t1 = now();
      const frames = Array.from(traj.keyframeDepths.frames);
      depthMaps = [];
      for (let k = 0; k < frames.length; ++k) {
        checkAbort(signal);
        const map = await depthModel.predict(keptRgb[frames[k]], ss.width, ss.height, 3, frames[k]);
        if (!(map instanceof Float32Array) || map.length !== ss.width * ss.height) {
          throw new Error(`depth of keyframe ${frames[k]}: expected a Float32Array of ${ss.width}x${ss.height}`);
        }
        depthMaps.push(map);
        if (onProgress) onProgress({ stage: 'depth', done: k + 1, total: frames.length });
      }
      keptRgb.length = 0; // the masks are still needed by the scale
      addTime('depth', now() - t1);
    }

    // --- metric scale ---
    t1 = now();
    if (onProgress) onProgress({ stage: 'scale', done: 0, total: 1 });
    const handScaleSmooth = options.handScaleSmooth ?? 0;
    const wristTracks = [];
    for (const side of ['left', 'right']) {
      if (!present[side]) continue;
      const positions = new Float64Array(3 * T);
      const jc = hands[side].jointsCam;
      for (let t = 0; t < T; ++t) positions.set(hands[side].valid[t] ? jc.subarray(63 * t, 63 * t + 3) : [0, 0, 1], 3 * t);
      if (handScaleSmooth > 0) smoothTrack(positions, hands[side].valid, T, handScaleSmooth);
      wristTracks.push({ positions, valid: hands[side].valid });
    }
    let scale = { scale: NaN, method: 'none', confidence: 0 };
    const groundCue = options.groundScale ?? true;
    const havePoints = groundCue && traj.points.length >= 3;
    if (traj.initialised && (wristTracks.length || depthMaps || havePoints)) {
      try {
        const masksKf = depthMaps ? Array.from(traj.keyframeDepths.frames, (f) => keptMasks[f] ?? null) : undefined;
        scale = core.metricScale({
          rotations: traj.rotations, translations: traj.translations, fps,
          ...(depthMaps ? { keyframeDepths: traj.keyframeDepths, depthMaps, depthWidth: ss.width, depthHeight: ss.height, masks: masksKf } : {}),
          ...(wristTracks.length ? { hands: wristTracks } : {}),
          ...(havePoints ? { points: traj.points, ...(options.eyeHeight ? { eyeHeight: options.eyeHeight } : {}) } : {}),
        });
      } catch (e) {
        warnings.push(`metric scale: ${e.message}`);
      }
    }
    let s = scale.scale;
    if (!(Number.isFinite(s) && s > 0)) {
      // No metric cue: keep the SLAM's own units, flagged (the trajectory's shape is still right).
      s = 1;
      if (traj.initialised) warnings.push('no metric scale could be estimated (no depth model, no usable hand cue, no floor in the map): the camera trajectory is in the SLAM\'s arbitrary units');
      scale = { ...scale, scale: 1, method: 'none', confidence: 0 };
    } else if (scale.confidence < 0.4) {
      warnings.push(`the metric scale is uncertain (method ${scale.method}, confidence ${scale.confidence.toFixed(2)})`);
    }
    addTime('scale', now() - t1);
    checkAbort(signal);

    // --- camera in metres ---
    const positions = new Float64Array(3 * T);
    const quaternions = core.rotationsToQuaternions(traj.rotations);
    const timestamps = new Float64Array(T);
    for (let t = 0; t < T; ++t) {
      for (let a = 0; a < 3; ++a) positions[3 * t + a] = s * traj.translations[3 * t + a];
      timestamps[t] = t / fps;
    }
    // SLAM points: the final map, in metres
    const points = traj.points.map((v) => s * v);

    // --- world motion, infilling, joints ---
    const outHands = {};
    for (const side of ['left', 'right']) {
      const h = hands[side];
      const base = {
        valid: h.valid, present: present[side], camRot: h.camRot, camTrans: h.camTrans, jointsCam: h.jointsCam,
        keypoints2d: h.keypoints2d, reprojRmsPx: h.reprojRmsPx, handPoseCols: P[side], betaCols: B[side],
        model: models[side].kind(),
      };
      if (!present[side]) {
        outHands[side] = { ...base, infilled: new Uint8Array(T), trans: nanArray(3 * T), rot: nanArray(3 * T),
          handPose: nanArray(P[side] * T), betas: nanArray(B[side] * T), jointsWorld: nanArray(63 * T) };
        continue;
      }
      t1 = now();
      const camMotion = { rot: h.camRot, trans: h.camTrans, handPose: h.handPose, betas: h.betas, valid: h.valid };
      // cameraToWorld wants finite numbers everywhere: unobserved frames get zeros (they are
      // overwritten by the infiller)
      const finite = (a) => a.map((v) => (Number.isFinite(v) ? v : 0));
      const world = core.cameraToWorld({ rot: finite(camMotion.rot), trans: finite(camMotion.trans), handPose: finite(camMotion.handPose),
        betas: finite(camMotion.betas), valid: camMotion.valid }, T, traj.rotations, traj.translations, s, models[side]);
      addTime('world', now() - t1);
      t1 = now();
      for (const k of ['rot', 'trans', 'handPose', 'betas']) {
        const cols = world[k].length / T;
        for (let t = 0; t < T; ++t) if (!h.valid[t]) world[k].fill(NaN, t * cols, (t + 1) * cols);
      }
      const filled = core.infillHand(world, T, infillMethod, models[side]);
      addTime('infill', now() - t1);
      t1 = now();
      const jointsWorld = new Float64Array(63 * T);
      for (let t = 0; t < T; ++t) {
        const pose = {
          rot: filled.rot.subarray(3 * t, 3 * t + 3), trans: filled.trans.subarray(3 * t, 3 * t + 3),
          handPose: filled.handPose.subarray(P[side] * t, P[side] * (t + 1)), betas: filled.betas.subarray(B[side] * t, B[side] * (t + 1)),
        };
        jointsWorld.set(models[side].forward(pose).keypoints, 63 * t);
      }
      addTime('joints', now() - t1);
      outHands[side] = { ...base, infilled: filled.filled, trans: filled.trans, rot: filled.rot, handPose: filled.handPose,
        betas: filled.betas, jointsWorld };
    }
    if (onProgress) onProgress({ stage: 'done', done: 1, total: 1 });

    return {
      version: RESULT_VERSION,
      width, height, fps, frameCount: T, modelKind: options.observations ? 'observations' : (options.modelKind ?? 'lite'),
      threads: options.threads ?? 1,
      intrinsics: intrOut,
      slam: { width: ss.width, height: ss.height, numKeyframes: traj.numKeyframes, numLosses: traj.numLosses,
        numResets: traj.numResets, numRelocalisations: traj.numRelocalisations, numPlaceRelocalisations: traj.numPlaceRelocalisations, numRevisitPoints: traj.numRevisitPoints,
        numPlaceLinks: traj.numPlaceLinks, numPlacedSegments: traj.numPlacedSegments, numRefinedFrames: traj.numRefinedFrames, numHeadModelFrames: traj.numHeadModelFrames, initialised: traj.initialised },
      camera: { positions, quaternions, status: traj.status, timestamps },
      points,
      scale,
      hands: outHands,
      faces: { left: models.left.faces(), right: models.right.faces() },
      timings,
      warnings,
      noHands,
      stats: tracker ? { ...tracker.stats } : {},
    };
  } finally {
    for (const o of owned.reverse()) { try { o.delete(); } catch { /* already freed */ } }
  }
}
