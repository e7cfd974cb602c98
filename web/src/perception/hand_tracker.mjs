// hand_tracker.mjs: palm detection + hand landmarks on video frames, MediaPipe-style tracking:
// the landmark network runs on a ROI predicted from the previous frame's landmarks, and the palm
// detector runs only when fewer than `maxHands` hands are tracked. Shared by the browser app and
// node: the caller passes the onnxruntime namespace (`import * as ort from 'onnxruntime-web'`)
// and the converted models (paths in node, URLs in a page, or bytes), so this module imports
// nothing but the project's geometry.
//
// Frames: { width, height, data: Uint8Array | Uint8ClampedArray, channels: 3 | 4 } (RGB from a
// decoder, or a canvas ImageData with channels 4). Outputs are in image pixels (docs/design.md §2) and
// world landmarks in metres (see landmarks.mjs).
//
// Lenses: with the `lens` option the landmark crops are locally perspective views through the
// camera's lens (the hand network was trained on perspective images), computed by the core
// (LensCamera, render/lens_crop.hpp); ROIs stay in image pixels and landmarks map back through
// the same map. The palm detector keeps its letterbox of the whole image.

import { cropImage, cropImageMapped, letterboxRoi, iou } from './geometry.mjs';
import { cropBoxFiltered } from './prefilter.mjs';
import { PALM_INPUT_SIZE, decodePalms, weightedNms, palmToImage, roiFromPalm } from './palm.mjs';
import { LANDMARK_INPUT_SIZE, decodeLandmarks, roiFromLandmarks } from './landmarks.mjs';

/** A hand as decodeLandmarks gives it, from the keypoint flow's prediction p for track st (its
 *  presence and handedness the track's last network run's). */
function flowHand(p, st) {
  const landmarks = new Float64Array(63);
  for (let k = 0; k < 21; ++k) { landmarks[3 * k] = p.keypoints2d[2 * k]; landmarks[3 * k + 1] = p.keypoints2d[2 * k + 1]; }
  const pRight = 1 / (1 + Math.exp(-st.logOdds));
  return { landmarks, world: p.keypoints3d ?? null, presence: st.presence ?? 1, handedness: pRight >= 0.5 ? 'right' : 'left',
    handednessScore: Math.max(pRight, 1 - pRight) };
}

/** The session options of the hand networks: the caller's over these defaults. The intra-op
 *  pool's threads sleep between calls instead of spinning: the networks alternate with the
 *  geometry (and a decoder) on the same few cores, which a spinning thread takes. */
export function handSessionOptions(sessionOptions = {}) {
  return { graphOptimizationLevel: 'all', extra: { session: { intra_op: { allow_spinning: '0' } } }, ...(sessionOptions ?? {}) };
}

export class HandTracker {
  /**
   * @param ort          the onnxruntime namespace
   * @param palmModel    palm_detection_{full,lite}.onnx (path, URL or Uint8Array)
   * @param landmarkModel hand_landmark_{full,lite}.onnx
   * @param options      { maxHands = 2, minPalmScore = 0.5, minPresence = 0.5, mirrored = false,
   *                       detectGap = 0, sessionOptions (default graphOptimizationLevel 'all',
   *                       the thread pool not spinning) }
   *                      detectGap: while at least one hand is tracked, the detector (looking for
   *                      the others) runs only after this many frames without it (0: every frame,
   *                      MediaPipe's behaviour); with no hand tracked it runs on every frame
   *                      detectBackoff (0: off): while at least one hand is tracked, each detector
   *                      run that adds no hand doubles that gap, up to this many frames; a hand
   *                      found or a track lost restores detectGap (a time budget: the live mode's)
   *                      lens: a camera with a lens, { cropMap(roi, n) -> { map: Float32Array(2n²),
   *                      rotation: (9) }, cropToImage(roi, uv: Float64Array) -> Float64Array }
   *                      (the core's LensCamera); null or absent: affine crops (a pinhole camera)
   *                    The policy beyond MediaPipe's (defaults: off, MediaPipe's behaviour; the
   *                    pipeline's settings: run.mjs's PIPELINE_TRACKER_OPTIONS):
   *                      candidateScore (minPalmScore): a detector-verifier cascade: palm
   *                      candidates down to this score, the best maxCandidates (maxHands) that do
   *                      not overlap a hand each verified by the landmark network on its crop;
   *                      one below minPalmScore needs candidatePresence (minPresence) there
   *                      palmPrefilter (0): the detector's letterbox sampled with a box of this
   *                      many sample spacings (prefilter.mjs; 0: bilinear points)
   *                      redetectOnLoss (false): the detector also runs on a frame where a track
   *                      was not found (lost, or still coasting), whatever detectGap says
   *                      motion (false): a track is looked for at its last ROI moved on at its
   *                      velocity (constant velocity, ROI centre per frame)
   *                      coast (0): a lost track is looked for again on this many more frames
   *                      (at its predicted ROI; not reported while lost)
   *                    Every hand carries its track: { id, pRight (the track's handedness
   *                    evidence), frames }; a hand found again by the detector on the frame its
   *                    track was lost, or while that track coasts, keeps the track.
   */
  static async create(ort, palmModel, landmarkModel, options = {}) {
    const so = handSessionOptions(options.sessionOptions);
    const palm = await ort.InferenceSession.create(palmModel, so);
    const landmark = await ort.InferenceSession.create(landmarkModel, so);
    return new HandTracker(ort, palm, landmark, options);
  }

  constructor(ort, palmSession, landmarkSession, { maxHands = 2, minPalmScore = 0.5, minPresence = 0.5, mirrored = false, detectGap = 0, detectBackoff = 0, lens = null,
    candidateScore = minPalmScore, candidatePresence = minPresence, maxCandidates = maxHands, palmPrefilter = 0, redetectOnLoss = false,
    motion = false, coast = 0 } = {}) {
    Object.assign(this, { ort, palmSession, landmarkSession, maxHands, minPalmScore, minPresence, mirrored, detectGap, detectBackoff, lens });
    Object.assign(this, { candidateScore, candidatePresence, maxCandidates, palmPrefilter, redetectOnLoss, motion, coast });
    this.framesWithoutDetect = 0;
    this.gap = detectGap; // the current gap (detectGap, or backed off)
    for (const [s, what, n] of [[palmSession, 'palm', 2], [landmarkSession, 'landmark', 4]]) {
      if (s.inputNames.length !== 1 || s.outputNames.length !== n) {
        throw new Error(`HandTracker: the ${what} model has ${s.inputNames.length} inputs / ${s.outputNames.length} outputs, expected 1 / ${n}`);
      }
    }
    this.palmInput = new Float32Array(PALM_INPUT_SIZE * PALM_INPUT_SIZE * 3);
    this.landmarkInput = new Float32Array(LANDMARK_INPUT_SIZE * LANDMARK_INPUT_SIZE * 3);
    this.tracked = []; // ROIs for the next frame
    this.trackStates = []; // their tracks (identity, handedness evidence, motion), see newTrack
    this.frame = 0;
    this.nextId = 1;
    this.stats = { palmRuns: 0, landmarkRuns: 0, flowHands: 0, candidatesVerified: 0, candidatesKept: 0 };
  }

  /** Palm detections in image pixels, best first (weighted NMS, at most maxDetections). */
  async detectPalms(image, { minScore = this.minPalmScore, maxDetections = this.maxHands } = {}) {
    const S = PALM_INPUT_SIZE;
    const roi = letterboxRoi(image.width, image.height);
    // letterbox bars are black
    if (this.palmPrefilter > 0) cropBoxFiltered(image, roi, S, S, this.palmInput, this.palmPrefilter);
    else cropImage(image, roi, S, S, this.palmInput, 'zero');
    const feeds = { [this.palmSession.inputNames[0]]: new this.ort.Tensor('float32', this.palmInput, [1, S, S, 3]) };
    const out = await this.palmSession.run(feeds);
    this.stats.palmRuns += 1;
    const dets = weightedNms(decodePalms(out.Identity.data, out.Identity_1.data, { minScore }), { iouThreshold: 0.3, maxDetections });
    return dets.map((d) => palmToImage(d, roi));
  }

  /** The landmark network on one ROI (see landmarks.mjs for the result). */
  async landmarks(image, roi) {
    const S = LANDMARK_INPUT_SIZE;
    let lensCrop = null;
    if (this.lens) {
      let crop = null;
      try {
        crop = this.lens.cropMap(roi, S);
      } catch {
        crop = null; // a ROI centre beyond the lens' reach: the affine crop
      }
      if (crop) {
        cropImageMapped(image, crop.map, S, S, this.landmarkInput, 'replicate');
        lensCrop = { toImage: (uv) => this.lens.cropToImage(roi, uv), rotation: crop.rotation };
      }
    }
    if (!lensCrop) cropImage(image, roi, S, S, this.landmarkInput, 'replicate'); // MediaPipe's default border
    const feeds = { [this.landmarkSession.inputNames[0]]: new this.ort.Tensor('float32', this.landmarkInput, [1, S, S, 3]) };
    const out = await this.landmarkSession.run(feeds);
    this.stats.landmarkRuns += 1;
    const plain = Object.fromEntries(Object.entries(out).map(([k, v]) => [k, v.data]));
    return decodeLandmarks(plain, roi, { mirrored: this.mirrored, lensCrop });
  }

  /** Forget the tracked hands (e.g. after a cut): the next frame runs the detector. */
  reset() {
    this.tracked = [];
    this.trackStates = [];
  }

  /** A new track on `roi`: its id, handedness evidence (sum of the frames' clamped log-odds of
   *  a right hand), the frame it was last seen on, its velocity (ROI centre, pixels a frame)
   *  and the frames it has missed since. */
  newTrack(roi) {
    return { id: this.nextId++, roi, logOdds: 0, frames: 0, lastFrame: this.frame, vel: [0, 0], misses: 0 };
  }

  /** The ROI a track is looked for in on this frame: its last one, moved on at its velocity
   *  with `motion` (a hand moving 100 px a frame at 10 fps leaves the ROI of its last position). */
  searchRoi(st) {
    if (!this.motion) return st.roi;
    const gap = this.frame - st.lastFrame;
    return { ...st.roi, cx: st.roi.cx + st.vel[0] * gap, cy: st.roi.cy + st.vel[1] * gap };
  }

  /** Hand h was found on this frame by track st: its next ROI, velocity and handedness. */
  confirm(st, h) {
    const roi = roiFromLandmarks(h.landmarks);
    const gap = this.frame - st.lastFrame;
    if (st.frames > 0 && gap > 0) st.vel = [(roi.cx - st.roi.cx) / gap, (roi.cy - st.roi.cy) / gap];
    st.roi = roi;
    st.lastFrame = this.frame;
    st.frames += 1;
    st.misses = 0;
    if (h.source === 'flow') { // no new handedness evidence
      h.track = { id: st.id, pRight: 1 / (1 + Math.exp(-st.logOdds)), frames: st.frames };
      return;
    }
    const L = Math.log(0.95 / 0.05); // one frame's label flips now and then with full confidence
    const p = h.handedness === 'right' ? h.handednessScore : 1 - h.handednessScore;
    st.logOdds += Math.max(-L, Math.min(L, Math.log(p / (1 - p))));
    h.track = { id: st.id, pRight: 1 / (1 + Math.exp(-st.logOdds)), frames: st.frames };
  }

  /** The track among `lost` (lost on this frame, or coasting) a newly detected hand (next ROI
   *  `roi`) continues: the nearest whose predicted centre lies within half the larger ROI's
   *  width (about a hand's length) of the hand's; removed from `lost`. */
  revive(lost, roi) {
    let best = -1;
    let bestD = Infinity;
    lost.forEach((st, k) => {
      const gap = this.frame - st.lastFrame;
      const d = Math.hypot(roi.cx - (st.roi.cx + st.vel[0] * gap), roi.cy - (st.roi.cy + st.vel[1] * gap));
      if (d < 0.5 * Math.max(st.roi.w, roi.w) && d < bestD) { best = k; bestD = d; }
    });
    return best < 0 ? null : lost.splice(best, 1)[0];
  }

  /**
   * One video frame: landmarks for each tracked hand (tracks that converged on one hand merged);
   * the detector only if fewer than maxHands remain, its palms added where they do not overlap a
   * tracked hand (IoU of the ROIs' bounding squares < 0.5) and their landmarks are not a hand
   * already found. Hands below minPresence are dropped. Returns [{...decodeLandmarks, source:
   * 'track' | 'detect' | 'flow', track: {id, pRight, frames}}] and keeps their next ROIs.
   * predictions: the core's keypoint flow for this frame (Pipeline.predict: [{track, keypoints2d,
   * keypoints3d, trusted}]); a trusted one is taken for its track's hand instead of running the
   * landmark network ('flow').
   */
  async track(image, predictions = null) {
    this.frame += 1;
    const box = (r) => ({ cx: r.cx, cy: r.cy, w: Math.max(r.w, r.h), h: Math.max(r.w, r.h) });
    // tracks of this.tracked (a caller may set it: those start as new tracks)
    const states = this.tracked.map((roi, j) => (this.trackStates[j] && this.trackStates[j].roi === roi ? this.trackStates[j] : this.newTrack(roi)));
    const hands = [];
    const owners = []; // the track of each hand
    const lost = []; // tracks not found on this frame: coasting (looked for again) or ended
    // one hand seen twice: the bounding boxes of the two views' 21 landmarks overlap by more
    // than half the smaller one (a track that drifted, or a detection framing the hand at another
    // scale, can have an IoU below 0.5 with the same hand's other view; the next ROIs, twice the
    // hand, overlap for two large hands side by side)
    const extent = (lm) => {
      let x0 = Infinity; let y0 = Infinity; let x1 = -Infinity; let y1 = -Infinity;
      for (let k = 0; k < lm.length; k += 3) { x0 = Math.min(x0, lm[k]); x1 = Math.max(x1, lm[k]); y0 = Math.min(y0, lm[k + 1]); y1 = Math.max(y1, lm[k + 1]); }
      return { x0, y0, x1, y1, area: Math.max(1e-9, (x1 - x0) * (y1 - y0)) };
    };
    const sameHand = (h) => {
      const a = extent(h.landmarks);
      return hands.findIndex((o) => {
        const b = extent(o.landmarks);
        const inter = Math.max(0, Math.min(a.x1, b.x1) - Math.max(a.x0, b.x0)) * Math.max(0, Math.min(a.y1, b.y1) - Math.max(a.y0, b.y0));
        return inter > 0.5 * Math.min(a.area, b.area);
      });
    };
    for (const st of states) {
      // the keypoint flow's prediction stands in for the network where the core trusts it
      const flow = predictions ? predictions.find((p) => p.trusted && p.track === st.id) : null;
      const h = flow ? flowHand(flow, st) : await this.landmarks(image, this.searchRoi(st));
      if (flow) this.stats.flowHands += 1;
      else st.presence = h.presence;
      if (h.presence < this.minPresence) {
        st.misses += 1;
        lost.push(st);
        continue;
      }
      // two tracks that converged on one hand (MediaPipe associates them the same way, IoU > 0.5
      // of the next ROIs): keep the more confident landmarks, and the track that moved less
      const dup = sameHand(h);
      if (dup < 0) {
        hands.push({ ...h, source: flow ? 'flow' : 'track' });
        owners.push(st);
        continue;
      }
      const c = roiFromLandmarks(h.landmarks);
      const moved = (s) => Math.hypot(c.cx - s.roi.cx, c.cy - s.roi.cy);
      if (moved(st) < moved(owners[dup])) owners[dup] = st;
      if (h.presence > hands[dup].presence) hands[dup] = { ...h, source: flow ? 'flow' : 'track' };
    }
    if (lost.length > 0) this.gap = this.detectGap;
    const detect = hands.length < this.maxHands && (hands.length === 0 || this.framesWithoutDetect >= this.gap || (this.redetectOnLoss && lost.length > 0));
    this.framesWithoutDetect = detect ? 0 : this.framesWithoutDetect + 1;
    const before = hands.length;
    if (detect) {
      // palm candidates down to candidateScore, each confirmed by the landmark network's presence
      // on its crop (minPresence above minPalmScore, candidatePresence below)
      const palms = await this.detectPalms(image, { minScore: Math.min(this.minPalmScore, this.candidateScore), maxDetections: this.maxHands + this.maxCandidates });
      let verified = 0;
      for (const palm of palms) {
        if (hands.length >= this.maxHands || verified >= this.maxCandidates) break;
        const roi = roiFromPalm(palm);
        if (hands.some((h) => iou(box(roiFromLandmarks(h.landmarks)), box(roi)) >= 0.5)) continue;
        verified += 1;
        this.stats.candidatesVerified += 1;
        const h = await this.landmarks(image, roi);
        if (h.presence < (palm.score >= this.minPalmScore ? this.minPresence : this.candidatePresence)) continue;
        const dup = sameHand(h);
        if (dup >= 0) {
          // a hand already found: the more confident view, on its track (a detection re-anchors
          // a track that drifted)
          if (h.presence > hands[dup].presence) hands[dup] = { ...h, palm, source: 'detect' };
          continue;
        }
        this.stats.candidatesKept += 1;
        hands.push({ ...h, palm, source: 'detect' });
        owners.push(this.revive(lost, roiFromLandmarks(h.landmarks)) ?? this.newTrack(roi));
      }
    }
    if (detect && this.detectBackoff > this.detectGap) {
      // an empty run with a hand tracked backs off (1, 2, 4, ... frames); a new hand resets
      this.gap = hands.length > before || before === 0 ? this.detectGap : Math.min(this.detectBackoff, Math.max(1, 2 * this.gap));
    }
    hands.forEach((h, j) => this.confirm(owners[j], h));
    // lost tracks within `coast` misses are looked for again on the next frame, while there is room
    const coasting = lost.filter((st) => st.misses <= this.coast).slice(0, Math.max(0, this.maxHands - hands.length));
    this.trackStates = [...owners, ...coasting];
    this.tracked = this.trackStates.map((st) => st.roi);
    return hands;
  }
}
