// run.mjs: the whole hawor pipeline on a stream of video frames, shared by the node CLI
// (web/cli.mjs) and the browser app (a Web Worker). No node-only import: the caller passes the
// C++ core (hawor_core.mjs, instantiated), the onnxruntime-web namespace and the bytes of every
// model, and feeds frames as RGBA (or RGB) byte arrays.
//
//   import { runPipeline } from './pipeline/run.mjs';
//   const result = await runPipeline(source, options, hooks);
//
// source  { width, height, fps, frameCount: number | null,
//           frames: async iterable of { index, rgba: Uint8Array | Uint8ClampedArray, time? } }
//         time (seconds, increasing; every frame or none): the frame's capture time, for a
//         source that drops frames (a live camera): the result's timestamps and the hand cues'
//         frame rate come from the times; fps stays the camera's (the rolling shutter's)
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
//           sessionOptions?              onnxruntime session options for the networks (merged
//                                        over the defaults; e.g. onnxruntime-node's
//                                        { executionProviders: ['cpu'], intraOpNumThreads })
//           slamMaxSide? (640)           the SLAM and hand masks run on frames downscaled to
//                                        this long side (intrinsics scaled alike)
//           maxPixels? (MAX_PIXELS)      larger frames are refused with a clear error (the
//                                        caller downscales first; the CLI does, with ffmpeg)
//           observations?: (index) => [{ handedness: 'left'|'right', handednessScore?,
//                                        landmarks: (2 or 3 per keypoint, 21) image px,
//                                        world: (63) metres | null }]
//                                        replaces the perception networks (benchmarks with
//                                        simulated keypoints); ort and models are then unused
//           handsCam?: (index) => { left: hand | null, right: hand | null }
//                                        camera-frame hands from another regressor (HaMeR, WiLoR,
//                                        HaWoR's network): pose objects as HandModel.forward takes
//                                        ({rot, handPose, betas, trans}, the models' parameters),
//                                        or {joints} (63: 21 joints, metres, MediaPipe order; the
//                                        model is fitted to them), one kind per frame; replaces
//                                        perception and fit (`hawor world` natively)
//           infill? ('spline' | 'lerp' | 'last'), maskDilatePx? (2, at the SLAM resolution),
//                                        maskHoldSeconds? (0.5: a hand no longer found stays masked
//                                        from the SLAM at its last pose this long),
//           detectGap? (1)               while one hand is tracked, the palm detector looks for
//                                        the other only every detectGap+1 frames
//           flow? ({})                   the keypoint flow's options over the core's defaults
//                                        (pipeline/keypoint_flow.hpp: a hand's keypoints carried
//                                        from the last frame by KLT stand in for the landmark
//                                        network on up to maxSkip = 5 frames in a row, as often as
//                                        the network's later runs agree with them; maxSkip 0:
//                                        the network on every frame)
//           minPresence? (0.3)           the landmark network's hand presence to keep a hand
//                                        (MediaPipe's 0.5 drops the wearer's hand gripping a
//                                        plate on the kitchen clip; tests/web/kitchen_hands)
//           trackerFactory?              async (trackerOptions, lens | null) => a hand tracker run
//                                        elsewhere: { track(image, predictions) -> hands, stats,
//                                        close() } as HandTracker's (node:
//                                        perception/worker_tracker.mjs, a worker thread, so that the
//                                        networks of frame t+1 overlap the SLAM of frame t); lens:
//                                        { intrinsics, width, height, lens } for its crops; ort and
//                                        models are then unused
//           tracker? ({})                further HandTracker options over
//                                        PIPELINE_TRACKER_OPTIONS (experiments)
//           groundScale? (true)          the ground cue of the metric scale: the cameras' height
//                                        above the map's floor plane (scale/ground_scale.hpp)
//           eyeHeight? (1.6)             that height in metres (a standing adult's head camera;
//                                        about 1.2 sitting)
//           gravityAligned? (true)       the output's world z up with the origin on the floor
//                                        below the first camera (false: the first camera's)
//           live? (false)                causal estimates per frame (live mode): frameInfo.live
//                                        and, every liveWorldEvery frames, frameInfo.world
//           liveWorldEvery? (fps)        frames between updates of the live world (its scale
//                                        and gravity from the cues so far) }
// hooks   { onProgress?({ stage, done, total }), onFrame?(frameInfo), signal?: AbortSignal }
//         onFrame gets { index, hands: [{ side, valid, keypoints2d: Float64Array(42) }],
//         slamStatus, ms } after each frame; an aborted signal throws an AbortError (checked
//         before every frame and between the stages after the last one). With options.live
//         also live: the core's Pipeline.live() (the frame's camera pose and fitted joints in the
//         live world: { frame, posed, scale, cameraRotation (9), cameraPosition (3), valid,
//         joints: { left, right } }) and, when it was updated on this frame, world:
//         Pipeline.updateLiveWorld() ({ frames, scale, scaleMethod, scaleConfidence, up,
//         upConfidence, origin, previous: { frame, scale, cameraRotation, cameraPosition } (this
//         frame's camera in the live world before the update) }). streamPipeline gives the same
//         as an async iterator.
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
//   world: { convention: 'z-up' (gravity-aligned: z up, the first camera looking along +y) or
//            'first-camera' (its OpenCV frame: x right, y down, z forward), up: 'floor' (the
//            map's floor plane) | 'camera' (the cameras' axes) | 'none', upConfidence (0..1),
//            origin: 'floor' (below the first camera) | 'first-camera', upFirstCamera (3) },
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
//   stats: { palmRuns, landmarkRuns, flowHands (hands the keypoint flow gave instead of the
//            landmark network), candidatesVerified, candidatesKept (palm candidates checked by
//            the landmark network, and found to be hands) } (the tracker's; {} with observations) }
//
// Stages (timings keys): flow (the keypoint flow's predictions), perception (networks + crops),
// fit (hand fit per hand), masks (hand
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

/** Live (options.live), a frame's time is bounded: while a hand is tracked, the detector looking
 *  for the other backs off after runs that find nothing (2, 4, 8 frames), so that a hand out of
 *  view does not cost the palm detector and its candidates' checks on every other frame. */
export const PIPELINE_LIVE_TRACKER_OPTIONS = Object.freeze({ detectBackoff: 4 });

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

/** P(right) of a detection: its track's (the tracker's handedness evidence summed over the
 *  frames of the track), else from its label and score. */
function pRight(h) {
  if (h.track && Number.isFinite(h.track.pRight)) return h.track.pRight;
  const s = h.handednessScore ?? 1;
  return h.handedness === 'right' ? s : 1 - s;
}

/** The perception's detections ({landmarks (2 or 3 per keypoint), world, handedness,
 *  handednessScore, track}) as the core's Pipeline and SideAssigner take them. */
export function toDetections(dets) {
  return dets.map((d) => {
    const stride = d.landmarks.length === 63 ? 3 : 2;
    const kp2 = new Float64Array(2 * NUM_KP);
    for (let k = 0; k < NUM_KP; ++k) { kp2[2 * k] = d.landmarks[stride * k]; kp2[2 * k + 1] = d.landmarks[stride * k + 1]; }
    return { keypoints2d: kp2, keypoints3d: d.world ? Float64Array.from(d.world) : null, pRight: pRight(d), track: d.track ? d.track.id : -1, flow: d.source === 'flow' };
  });
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
  const K = [intr.fx, intr.fy, intr.cx, intr.cy];

  const owned = []; // embind objects to delete (in reverse: the pipeline before its models)
  let frames = null; // the source's iterator (closed on the way out: an error stops the decoder)
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
    let lensCrops = null;
    if (lens !== 'pinhole') {
      // perspective landmark crops through the lens (full resolution)
      const lensCamera = new core.LensCamera(K, width, height, lens);
      owned.push(lensCamera);
      lensCrops = { cropMap: (roi, n) => lensCamera.cropMap(roi, n, n), cropToImage: (roi, uv) => lensCamera.cropToImage(roi, uv) };
      if (intr.focalSource !== 'user-focal') {
        warnings.push(`a lens model (${lens}) without a focal length: the focal comes from a ${options.fovDeg ?? DEFAULT_DIAGONAL_FOV_DEG} degree field of view through the lens; calibrated coefficients belong with their calibration's focal (give it)`);
      }
    }
    if (options.threads && options.ort && options.ort.env && options.ort.env.wasm && !options.models?.palmSession) {
      options.ort.env.wasm.numThreads = options.threads; // effective before onnxruntime's first session only
    }
    if (!options.observations && !options.handsCam) {
      const ort = options.ort;
      const m = options.models ?? {};
      const detectGap = options.detectGap ?? PIPELINE_DETECT_GAP;
      const minPresence = options.minPresence ?? PIPELINE_MIN_PRESENCE;
      const policy = { ...PIPELINE_TRACKER_OPTIONS, ...(options.live ? PIPELINE_LIVE_TRACKER_OPTIONS : {}), ...(options.tracker ?? {}) };
      if (options.trackerFactory) {
        // the tracker elsewhere (a worker thread), with this policy; through a lens it builds its
        // own crops from the camera
        tracker = await options.trackerFactory({ maxHands: 2, detectGap, minPresence, ...policy },
          lens !== 'pinhole' ? { intrinsics: Array.from(K), width, height, lens } : null);
        if (typeof tracker.close === 'function') owned.push({ delete: () => tracker.close() });
      } else if (!ort || !ort.InferenceSession) {
        throw new Error('runPipeline: options.ort (the onnxruntime-web namespace) is required');
      } else if (m.palmSession && m.landmarkSession) {
        tracker = new HandTracker(ort, m.palmSession, m.landmarkSession, { maxHands: 2, detectGap, minPresence, ...policy, lens: lensCrops });
      } else {
        if (!(m.palm instanceof Uint8Array) || !(m.landmark instanceof Uint8Array)) {
          throw new Error('runPipeline: options.models.palm and .landmark (ONNX bytes) are required');
        }
        tracker = await HandTracker.create(ort, m.palm, m.landmark, { maxHands: 2, detectGap, minPresence, ...policy, lens: lensCrops, sessionOptions: options.sessionOptions });
      }
    }
    if (options.depthModel && typeof options.depthModel.predict === 'function') {
      const custom = options.depthModel;
      depthModel = { predict: (rgb, w, h, c, frame) => custom.predict(frame, rgb, w, h) };
    } else if (options.depthModel) {
      if (!options.ort) throw new Error('runPipeline: a depth model needs options.ort');
      depthModel = await DepthModel.create(options.ort, options.depthModel.bytes, options.depthModel.config, options.sessionOptions);
    }
    addTime('load', now() - t0);

    // The method's policy lives in the core's Pipeline (include/hawor/pipeline/pipeline.hpp).
    const refineFocal = options.refineFocal ?? true;
    const pipeline = new core.Pipeline({
      intrinsics: K, width, height, lens, fps, liveSource: !!options.live, readout, refineFocal, userFocal: intr.focalSource === 'user-focal',
      ...(options.focalPriorSigma !== undefined ? { focalPriorSigma: options.focalPriorSigma } : {}),
      ...(options.slamMaxSide !== undefined ? { slamMaxSide: options.slamMaxSide } : {}),
      ...(options.maskDilatePx !== undefined ? { maskDilatePx: options.maskDilatePx } : {}),
      ...(options.maskHoldSeconds !== undefined ? { maskHoldSeconds: options.maskHoldSeconds } : {}),
      ...(options.focalMaxPasses !== undefined ? { focalMaxPasses: options.focalMaxPasses } : {}),
      ...(options.focalRerunBytes !== undefined ? { focalRerunBytes: options.focalRerunBytes } : {}),
      ...(options.handScaleSmooth !== undefined ? { handScaleSmooth: options.handScaleSmooth } : {}),
      ...(options.eyeHeight !== undefined ? { eyeHeight: options.eyeHeight } : {}),
      infill: options.infill ?? 'spline', groundScale: options.groundScale ?? true, depthMasks: !!depthModel,
      gravityAligned: options.gravityAligned ?? true, ...(options.flow ? { flow: options.flow } : {}),
    }, models.left, models.right);
    owned.push(pipeline);
    const ss = pipeline.slamSize();
    // frames for the depth of the keyframes, at the SLAM's size (rectified through a lens)
    const keptRgb = depthModel ? [] : null;
    const rectifier = depthModel && lens !== 'pinhole' ? new core.Rectifier(ss.intrinsics, ss.width, ss.height, lens) : null;
    if (rectifier) owned.push(rectifier);
    let T = 0;

    // With the tracker elsewhere (options.trackerFactory: a worker), a frame's SLAM step
    // (Pipeline.pushDeferred, then trackPending) runs while the next frame's perception does;
    // otherwise, and live (each frame reported at once), it follows its own frame's push.
    const overlap = !!options.trackerFactory && !options.live;
    let pending = null;
    // frame t done: its live estimates, its time (ms before `since`, plus since then) and the hooks
    const report = (info, t, since, ms = 0) => {
      if (options.live) liveInfo(info, t);
      info.ms = ms + (now() - since);
      if (onFrame) onFrame(info);
      if (onProgress) onProgress({ stage: 'frames', done: t + 1, total: source.frameCount ?? null });
    };
    // the pending frame's SLAM step and its report; returns the time it took
    const finishFrame = (p) => {
      const ts = now();
      p.info.slamStatus = pipeline.trackPending().slamStatus;
      report(p.info, p.T, ts, p.ms);
      return now() - ts;
    };
    const liveInfo = (info, t) => {
      const every = options.liveWorldEvery ?? Math.max(1, Math.round(fps));
      if ((t + 1) % every === 0) {
        // the frame in the world before the update too: a live display carries what it drew
        // into the updated world (the same frame's camera in both worlds gives the change)
        const before = pipeline.live();
        info.world = pipeline.updateLiveWorld();
        info.world.previous = { frame: before.frame, scale: before.scale, cameraRotation: before.cameraRotation, cameraPosition: before.cameraPosition };
      }
      info.live = pipeline.live();
    };

    // the frames pulled by hand: with the overlap the next frame is requested while this one's
    // perception runs elsewhere, so its decoding (ffmpeg's pipe) fills that wait too
    frames = source.frames[Symbol.asyncIterator] ? source.frames[Symbol.asyncIterator]() : source.frames[Symbol.iterator]();
    let next = frames.next();
    for (;;) {
      const got = await next;
      if (got.done) break;
      const frame = got.value;
      next = null;
      checkAbort(signal);
      const tf = now();
      const rgba = frame && frame.rgba;
      if (!(rgba instanceof Uint8Array || rgba instanceof Uint8ClampedArray)) throw new Error(`frame ${T}: rgba must be a Uint8Array`);
      const c = rgba.length / (width * height);
      if (c !== 3 && c !== 4) throw new Error(`frame ${T}: ${rgba.length} bytes, expected ${width}x${height}x4 (RGBA) or x3 (RGB)`);
      if (frame.time !== undefined && typeof frame.time !== 'number') throw new Error(`frame ${T}: time must be a number of seconds`);
      if (keptRgb) {
        const rgb = ss.width === width && ss.height === height && c === 3 ? rgba.slice() : core.downscaleImage(rgba, width, height, c, ss.width, ss.height, false);
        keptRgb.push(rectifier ? rectifier.image(rgb, 3) : rgb);
      }
      const info = { index: frame.index ?? T, hands: [] };
      if (options.handsCam) {
        // camera-frame hands from another regressor: masks, SLAM (no perception; joints are fitted)
        const given = (await options.handsCam(T)) ?? {};
        const left = given.left ?? null, right = given.right ?? null;
        const joints = (left ?? right)?.joints !== undefined;
        if (left && right && (right.joints !== undefined) !== joints) throw new Error(`handsCam(${T}): one hand as joints, the other as parameters; give one kind per frame`);
        const r = joints ? pipeline.pushJoints(rgba, { left: left?.joints ?? null, right: right?.joints ?? null })
          : pipeline.pushHands(rgba, { left, right });
        info.slamStatus = r.slamStatus;
        ['left', 'right'].forEach((side, s) => { if (r.detection[s] >= 0) info.hands.push({ side, valid: !!r.valid[s] }); });
        if (frame.time !== undefined) pipeline.stampFrame(frame.time);
        report(info, T, tf);
      } else {
        // --- perception of this frame, the last frame's SLAM step meanwhile ---
        const t1 = now();
        const predictions = options.observations ? null : pipeline.predict(rgba);
        const perceived = options.observations ? options.observations(T) : tracker.track({ width, height, data: rgba, channels: c }, predictions);
        if (overlap) next = frames.next();
        const slamMs = pending ? finishFrame(pending) : 0;
        const dets = (await perceived) ?? [];
        addTime('perception', now() - t1 - slamMs);
        // --- sides and fit now, masks and SLAM with the next frame's perception ---
        const input = toDetections(dets);
        const r = pipeline.pushDeferred(rgba, input);
        ['left', 'right'].forEach((side, s) => {
          if (r.detection[s] >= 0) info.hands.push({ side, valid: !!r.valid[s], keypoints2d: input[r.detection[s]].keypoints2d });
        });
        // a source that drops frames gives their capture times (the timeline, the hand cues' rate)
        if (frame.time !== undefined) pipeline.stampFrame(frame.time);
        pending = { info, T, ms: now() - tf - slamMs };
        // overlap only pays with the tracker elsewhere, and live each frame is shown at once
        if (!overlap) { finishFrame(pending); pending = null; }
      }
      T += 1;
      next ??= frames.next();
    }
    if (pending) finishFrame(pending);
    if (T === 0) throw new Error('the video has no frames');
    checkAbort(signal);

    // --- the SLAM's finish, its passes with a refined focal, the hands fitted again ---
    if (onProgress) onProgress({ stage: 'slam-finish', done: 0, total: 1 });
    const cam = pipeline.finishCamera();
    checkAbort(signal);

    // --- depth on keyframes (optional) ---
    let depthMaps = null;
    if (depthModel) {
      const t1 = now();
      const frames = Array.from(cam.keyframeFrames);
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
      keptRgb.length = 0;
      addTime('depth', now() - t1);
    }

    // --- metric scale, camera and hands in the world, infilling ---
    if (onProgress) onProgress({ stage: 'scale', done: 0, total: 1 });
    const r = pipeline.finish(depthMaps);
    for (const [k, ms] of Object.entries(r.timings)) addTime(k, ms);
    const fi = r.intrinsics;
    const intrOut = { ...intr, guessSource: intr.focalSource, guessFx: intr.fx, refined: false, focalPasses: fi.focalPasses,
      focalStd: fi.focalStd, focalEstimateFx: fi.focalEstimateFx, focalReason: fi.focalReason, readout };
    if (fi.refined) {
      intrOut.fx = fi.fx;
      intrOut.fy = fi.fy;
      intrOut.refined = true;
      intrOut.focalSource = 'slam';
      intrOut.fovDeg = lens !== 'pinhole' ? 2 * core.describeCamera([fi.fx, fi.fy, intr.cx, intr.cy], width, height, lens).maxFieldAngleDeg
        : (2 * Math.atan(0.5 * Math.hypot(width, height) / fi.fx) * 180) / Math.PI;
    }
    for (const side of ['left', 'right']) r.hands[side].model = models[side].kind();
    if (onProgress) onProgress({ stage: 'done', done: 1, total: 1 });

    return {
      version: RESULT_VERSION,
      width, height, fps, frameCount: T, modelKind: options.handsCam ? 'camera-frame hands' : options.observations ? 'observations' : (options.modelKind ?? 'lite'),
      threads: options.threads ?? 1,
      intrinsics: intrOut,
      slam: r.slam,
      world: r.world,
      camera: r.camera,
      points: r.points,
      scale: r.scale,
      hands: r.hands,
      faces: { left: models.left.faces(), right: models.right.faces() },
      timings,
      warnings: [...warnings, ...r.warnings],
      noHands: r.noHands,
      stats: tracker ? { ...tracker.stats } : {},
    };
  } finally {
    for (const o of owned.reverse()) { try { o.delete(); } catch { /* already freed */ } }
    if (frames && typeof frames.return === 'function') { try { await frames.return(); } catch { /* the source's own error */ } }
  }
}

/**
 * runPipeline in live mode as an async iterator: yields { type: 'frame', ...frameInfo } for each
 * frame as it is processed (options.live set: causal estimates, see the header), then
 * { type: 'result', result } with the refined result once the source ends. Frames are pulled
 * from the source only as fast as they are processed (a live source drops what it cannot hand
 * over). Breaking out of the loop aborts the run.
 */
export async function* streamPipeline(source, options, hooks = {}) {
  const queue = [];
  let wake = null;
  let finished = false;
  const controller = new AbortController();
  if (hooks.signal) hooks.signal.addEventListener('abort', () => controller.abort(), { once: true });
  const push = (item) => { queue.push(item); if (wake) { wake(); wake = null; } };
  const run = runPipeline(source, { ...options, live: true }, {
    ...hooks, signal: controller.signal,
    onFrame: (info) => { if (hooks.onFrame) hooks.onFrame(info); push({ type: 'frame', ...info }); },
  }).then((result) => push({ type: 'result', result }), (error) => push({ type: 'error', error }));
  try {
    while (!finished) {
      if (queue.length === 0) await new Promise((r) => { wake = r; });
      const item = queue.shift();
      if (item.type === 'error') throw item.error;
      if (item.type === 'result') finished = true;
      yield item;
    }
  } finally {
    if (!finished) {
      controller.abort();
      await run;
    }
  }
}
