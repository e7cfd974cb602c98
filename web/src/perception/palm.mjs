// palm.mjs: MediaPipe palm detection (full / lite, 192 x 192) post-processing: anchors, box and
// keypoint decoding, weighted non-maximum suppression, and the hand ROI a palm implies.
//
// Network outputs (docs/design.md §4): regressors [1, 2016, 18] and score logits [1, 2016, 1]. Per
// anchor the regressors are the box centre x, y, width, height and 7 keypoints (x, y), in input
// pixels (0..192) relative to the anchor centre; keypoint 0 is the wrist, 2 the middle-finger MCP.
// Anchors (SSD, fixed unit size): a 24 x 24 grid with 2 anchors per cell (stride 8), then a
// 12 x 12 grid with 6 per cell (stride 16, three layers merged), row-major, centres
// ((x + 0.5) / g, (y + 0.5) / g) in the input's normalised coordinates.

import { cropToImage, transformRoi, normalizeRadians, iou } from './geometry.mjs';

export const PALM_INPUT_SIZE = 192;
export const PALM_NUM_ANCHORS = 2016;
export const PALM_NUM_KEYPOINTS = 7;
export const PALM_WRIST = 0;
export const PALM_MIDDLE_MCP = 2;

/** Anchor centres, Float32Array [x0, y0, x1, y1, ...] (2016 anchors). */
export function palmAnchors() {
  const out = new Float32Array(PALM_NUM_ANCHORS * 2);
  let k = 0;
  for (const [grid, perCell] of [[24, 2], [12, 6]]) {
    for (let y = 0; y < grid; ++y) {
      for (let x = 0; x < grid; ++x) {
        for (let a = 0; a < perCell; ++a) {
          out[k++] = (x + 0.5) / grid;
          out[k++] = (y + 0.5) / grid;
        }
      }
    }
  }
  return out;
}

const ANCHORS = palmAnchors();

/**
 * Decodes the raw outputs into detections above `minScore`, in the network input's normalised
 * coordinates (0..1 across the 192 px square): { score, box: {cx, cy, w, h}, keypoints: [[x, y] x 7] }.
 * score = sigmoid(clamp(logit, -100, 100)) (MediaPipe's score_clipping_thresh).
 */
export function decodePalms(regressors, scores, { minScore = 0.5 } = {}) {
  if (regressors.length !== PALM_NUM_ANCHORS * 18) throw new Error(`decodePalms: ${regressors.length} regressor values, expected ${PALM_NUM_ANCHORS} x 18`);
  if (scores.length !== PALM_NUM_ANCHORS) throw new Error(`decodePalms: ${scores.length} scores, expected ${PALM_NUM_ANCHORS}`);
  const S = PALM_INPUT_SIZE;
  const dets = [];
  for (let i = 0; i < PALM_NUM_ANCHORS; ++i) {
    const logit = Math.max(-100, Math.min(100, scores[i]));
    const score = 1 / (1 + Math.exp(-logit));
    if (!(score >= minScore)) continue;
    const ax = ANCHORS[2 * i];
    const ay = ANCHORS[2 * i + 1];
    const r = i * 18;
    const box = { cx: regressors[r] / S + ax, cy: regressors[r + 1] / S + ay, w: regressors[r + 2] / S, h: regressors[r + 3] / S };
    const keypoints = [];
    for (let k = 0; k < PALM_NUM_KEYPOINTS; ++k) keypoints.push([regressors[r + 4 + 2 * k] / S + ax, regressors[r + 5 + 2 * k] / S + ay]);
    dets.push({ score, box, keypoints, anchor: i });
  }
  return dets;
}

/**
 * Weighted non-maximum suppression (MediaPipe's WEIGHTED algorithm): repeatedly take the
 * highest-scoring detection, gather every remaining one whose IoU with it exceeds `iouThreshold`
 * (itself included), and replace the group by its score-weighted mean box and keypoints, keeping
 * the top score. Returns at most `maxDetections`, best first.
 */
export function weightedNms(dets, { iouThreshold = 0.3, maxDetections = Infinity } = {}) {
  let remaining = dets.slice().sort((a, b) => b.score - a.score);
  const out = [];
  while (remaining.length && out.length < maxDetections) {
    const top = remaining[0];
    const group = [];
    const rest = [];
    for (const d of remaining) (iou(top.box, d.box) > iouThreshold || d === top ? group : rest).push(d);
    remaining = rest;
    let wsum = 0;
    const box = { cx: 0, cy: 0, w: 0, h: 0 };
    const keypoints = top.keypoints.map(() => [0, 0]);
    for (const d of group) {
      wsum += d.score;
      for (const k of ['cx', 'cy', 'w', 'h']) box[k] += d.score * d.box[k];
      d.keypoints.forEach((p, k) => { keypoints[k][0] += d.score * p[0]; keypoints[k][1] += d.score * p[1]; });
    }
    for (const k of ['cx', 'cy', 'w', 'h']) box[k] /= wsum;
    for (const p of keypoints) { p[0] /= wsum; p[1] /= wsum; }
    out.push({ score: top.score, box, keypoints, merged: group.length });
  }
  return out;
}

/** A detection in the network input's normalised coordinates -> image pixels, given the ROI
 *  the input was cropped from (the letterbox ROI for a whole frame). */
export function palmToImage(det, roi) {
  const p = (x, y) => cropToImage(roi, x - 0.5, y - 0.5);
  const [cx, cy] = p(det.box.cx, det.box.cy);
  const keypoints = det.keypoints.map(([x, y]) => p(x, y));
  // sizes scale with the ROI (boxes are axis-aligned in the crop; the palm ROI has no rotation)
  return { score: det.score, box: { cx, cy, w: det.box.w * roi.w, h: det.box.h * roi.h }, keypoints };
}

/**
 * The hand ROI of a palm detection in image pixels (MediaPipe's palm -> hand rect): rotation such
 * that wrist -> middle-finger MCP points up in the crop, r = normalize(pi/2 - atan2(-(y2 - y0),
 * x2 - x0)); then shifted by -0.5 of its height along the crop's up axis, squared on the long side
 * and scaled by 2.6, so that the whole hand (fingers beyond the palm) is inside.
 */
export function roiFromPalm(det, { scale = 2.6, shiftY = -0.5 } = {}) {
  const [x0, y0] = det.keypoints[PALM_WRIST];
  const [x1, y1] = det.keypoints[PALM_MIDDLE_MCP];
  const rotation = normalizeRadians(Math.PI / 2 - Math.atan2(-(y1 - y0), x1 - x0));
  return transformRoi({ cx: det.box.cx, cy: det.box.cy, w: det.box.w, h: det.box.h, rotation }, { scale, shiftY, squareLong: true });
}
