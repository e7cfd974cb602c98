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

import { cropImage, letterboxRoi, iou } from './geometry.mjs';
import { PALM_INPUT_SIZE, decodePalms, weightedNms, palmToImage, roiFromPalm } from './palm.mjs';
import { LANDMARK_INPUT_SIZE, decodeLandmarks, roiFromLandmarks } from './landmarks.mjs';

export class HandTracker {
  /**
   * @param ort          the onnxruntime namespace
   * @param palmModel    palm_detection_{full,lite}.onnx (path, URL or Uint8Array)
   * @param landmarkModel hand_landmark_{full,lite}.onnx
   * @param options      { maxHands = 2, minPalmScore = 0.5, minPresence = 0.5, mirrored = false,
   *                       detectGap = 0, sessionOptions (default graphOptimizationLevel 'all') }
   *                      detectGap: while at least one hand is tracked, the detector (looking for
   *                      the others) runs only after this many frames without it (0: every frame,
   *                      MediaPipe's behaviour); with no hand tracked it runs on every frame
   */
  static async create(ort, palmModel, landmarkModel, options = {}) {
    const so = { graphOptimizationLevel: 'all', ...(options.sessionOptions ?? {}) };
    const palm = await ort.InferenceSession.create(palmModel, so);
    const landmark = await ort.InferenceSession.create(landmarkModel, so);
    return new HandTracker(ort, palm, landmark, options);
  }

  constructor(ort, palmSession, landmarkSession, { maxHands = 2, minPalmScore = 0.5, minPresence = 0.5, mirrored = false, detectGap = 0 } = {}) {
    Object.assign(this, { ort, palmSession, landmarkSession, maxHands, minPalmScore, minPresence, mirrored, detectGap });
    this.framesWithoutDetect = 0;
    for (const [s, what, n] of [[palmSession, 'palm', 2], [landmarkSession, 'landmark', 4]]) {
      if (s.inputNames.length !== 1 || s.outputNames.length !== n) {
        throw new Error(`HandTracker: the ${what} model has ${s.inputNames.length} inputs / ${s.outputNames.length} outputs, expected 1 / ${n}`);
      }
    }
    this.palmInput = new Float32Array(PALM_INPUT_SIZE * PALM_INPUT_SIZE * 3);
    this.landmarkInput = new Float32Array(LANDMARK_INPUT_SIZE * LANDMARK_INPUT_SIZE * 3);
    this.tracked = []; // ROIs for the next frame
    this.stats = { palmRuns: 0, landmarkRuns: 0 };
  }

  /** Palm detections in image pixels, best first (weighted NMS, at most maxHands). */
  async detectPalms(image) {
    const S = PALM_INPUT_SIZE;
    const roi = letterboxRoi(image.width, image.height);
    cropImage(image, roi, S, S, this.palmInput, 'zero'); // letterbox bars are black
    const feeds = { [this.palmSession.inputNames[0]]: new this.ort.Tensor('float32', this.palmInput, [1, S, S, 3]) };
    const out = await this.palmSession.run(feeds);
    this.stats.palmRuns += 1;
    const dets = weightedNms(decodePalms(out.Identity.data, out.Identity_1.data, { minScore: this.minPalmScore }), { iouThreshold: 0.3, maxDetections: this.maxHands });
    return dets.map((d) => palmToImage(d, roi));
  }

  /** The landmark network on one ROI (see landmarks.mjs for the result). */
  async landmarks(image, roi) {
    const S = LANDMARK_INPUT_SIZE;
    cropImage(image, roi, S, S, this.landmarkInput, 'replicate'); // MediaPipe's default border
    const feeds = { [this.landmarkSession.inputNames[0]]: new this.ort.Tensor('float32', this.landmarkInput, [1, S, S, 3]) };
    const out = await this.landmarkSession.run(feeds);
    this.stats.landmarkRuns += 1;
    const plain = Object.fromEntries(Object.entries(out).map(([k, v]) => [k, v.data]));
    return decodeLandmarks(plain, roi, { mirrored: this.mirrored });
  }

  /** Forget the tracked hands (e.g. after a cut): the next frame runs the detector. */
  reset() { this.tracked = []; }

  /**
   * One video frame: landmarks for each tracked hand (tracks that converged on one hand merged);
   * the detector only if fewer than maxHands remain, its palms added where they do not overlap a
   * tracked hand (IoU of the ROIs' bounding squares < 0.5). Hands below minPresence are dropped. Returns [{...decodeLandmarks, source:
   * 'track' | 'detect'}] and keeps their next ROIs.
   */
  async track(image) {
    const box = (r) => ({ cx: r.cx, cy: r.cy, w: Math.max(r.w, r.h), h: Math.max(r.w, r.h) });
    const hands = [];
    for (const roi of this.tracked) {
      const h = await this.landmarks(image, roi);
      if (h.presence < this.minPresence) continue;
      // two tracks that converged on one hand (MediaPipe associates them the same way, IoU > 0.5
      // of the next ROIs): keep the more confident one
      const next = box(roiFromLandmarks(h.landmarks));
      const dup = hands.findIndex((o) => iou(box(roiFromLandmarks(o.landmarks)), next) > 0.5);
      if (dup < 0) hands.push({ ...h, source: 'track' });
      else if (h.presence > hands[dup].presence) hands[dup] = { ...h, source: 'track' };
    }
    const detect = hands.length < this.maxHands && (hands.length === 0 || this.framesWithoutDetect >= this.detectGap);
    this.framesWithoutDetect = detect ? 0 : this.framesWithoutDetect + 1;
    if (detect) {
      for (const palm of await this.detectPalms(image)) {
        if (hands.length >= this.maxHands) break;
        const roi = roiFromPalm(palm);
        if (hands.some((h) => iou(box(roiFromLandmarks(h.landmarks)), box(roi)) >= 0.5)) continue;
        const h = await this.landmarks(image, roi);
        if (h.presence >= this.minPresence) hands.push({ ...h, palm, source: 'detect' });
      }
    }
    this.tracked = hands.map((h) => roiFromLandmarks(h.landmarks));
    return hands;
  }
}
