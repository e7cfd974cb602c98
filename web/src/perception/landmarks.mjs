// landmarks.mjs: MediaPipe hand landmark (full / lite, 224 x 224) outputs -> image and world
// coordinates, and the next frame's ROI from the landmarks.
//
// Network outputs (names as in the .tflite, kept by the converter):
//   Identity   [1, 63]  21 x (x, y, z): x, y in crop pixels (0..224 edge to edge), z relative
//                       depth (smaller = nearer the camera) about the wrist, in crop pixels x 0.4;
//   Identity_1 [1, 1]   hand presence, a probability (the graph ends in a LOGISTIC);
//   Identity_2 [1, 1]   handedness s: MediaPipe labels it with handedness.txt ("Left", "Right")
//                       as a binary classifier, class 0 ("Left") scoring s, class 1 ("Right")
//                       1 - s, for a MIRRORED (selfie) image; in an unmirrored (egocentric)
//                       view the labels swap: s is the probability of a right hand;
//   Identity_3 [1, 63]  21 x (x, y, z) world landmarks in metres about the hand's centre, axes
//                       of the crop (x right, y down, z away), rotated here into the image axes.
// Keypoints in MediaPipe order: 0 wrist, 1-4 thumb, 5-8 index, 9-12 middle, 13-16 ring, 17-20 pinky.

import { cropToImage, transformRoi, normalizeRadians } from './geometry.mjs';

export const LANDMARK_INPUT_SIZE = 224;
export const NUM_LANDMARKS = 21;
const Z_NORMALIZE = 0.4;

/**
 * Decodes one landmark-network run on the crop of `roi`.
 * @param outputs {Identity, Identity_1, Identity_2, Identity_3} as typed arrays
 * @param opts.mirrored  true when the image is a selfie view (MediaPipe's own assumption);
 *                       egocentric video is not mirrored (default), so the label is swapped
 * @param opts.lensCrop  the crop was a perspective view through a lens (render/lens_crop.hpp):
 *                       { toImage(uv: Float64Array(2N) crop-normalised) -> Float64Array(2N) image
 *                       pixels (NaN outside the lens), rotation: (9) row-major, the virtual
 *                       camera's axes in the camera frame }: landmarks map back through it and
 *                       world landmarks turn into the camera's axes; without it the affine crop
 * @returns {presence, handedness: 'left'|'right', handednessScore, landmarks: Float32Array(63)
 *          image pixels (x, y) and z in pixels at the crop's scale, world: Float32Array(63) metres}
 */
export function decodeLandmarks(outputs, roi, { mirrored = false, lensCrop = null } = {}) {
  const lm = outputs.Identity;
  const world = outputs.Identity_3;
  if (!lm || lm.length !== 63 || !world || world.length !== 63 || !outputs.Identity_1 || !outputs.Identity_2) {
    throw new Error('decodeLandmarks: expected outputs Identity [63], Identity_1 [1], Identity_2 [1], Identity_3 [63]');
  }
  const S = LANDMARK_INPUT_SIZE;
  const landmarks = new Float32Array(63);
  let mapped = null;
  if (lensCrop) {
    const uv = new Float64Array(2 * NUM_LANDMARKS);
    for (let k = 0; k < NUM_LANDMARKS; ++k) { uv[2 * k] = lm[3 * k] / S - 0.5; uv[2 * k + 1] = lm[3 * k + 1] / S - 0.5; }
    mapped = lensCrop.toImage(uv);
  }
  for (let k = 0; k < NUM_LANDMARKS; ++k) {
    const [x, y] = mapped ? [mapped[2 * k], mapped[2 * k + 1]] : cropToImage(roi, lm[3 * k] / S - 0.5, lm[3 * k + 1] / S - 0.5);
    landmarks[3 * k] = x;
    landmarks[3 * k + 1] = y;
    // MediaPipe: z / 224 / 0.4 (normalize_z, "the Z distribution of the training data"), then
    // times the ROI width
    landmarks[3 * k + 2] = (lm[3 * k + 2] / S / Z_NORMALIZE) * roi.w;
  }
  // world landmarks: the crop's axes are the image axes rotated by r (through a lens: the
  // virtual camera's image axes, then that camera's rotation into the camera frame)
  const c = Math.cos(roi.rotation);
  const s = Math.sin(roi.rotation);
  const w = new Float32Array(63);
  const R = lensCrop ? lensCrop.rotation : null;
  for (let k = 0; k < NUM_LANDMARKS; ++k) {
    const x = world[3 * k];
    const y = world[3 * k + 1];
    const a = x * c - y * s;
    const b = x * s + y * c;
    const z = world[3 * k + 2];
    if (R) {
      w[3 * k] = R[0] * a + R[1] * b + R[2] * z;
      w[3 * k + 1] = R[3] * a + R[4] * b + R[5] * z;
      w[3 * k + 2] = R[6] * a + R[7] * b + R[8] * z;
    } else {
      w[3 * k] = a;
      w[3 * k + 1] = b;
      w[3 * k + 2] = z;
    }
  }
  const s0 = outputs.Identity_2[0]; // P(class 0 = "Left") under MediaPipe's mirrored assumption
  const right = mirrored ? s0 <= 0.5 : s0 > 0.5;
  return {
    // a landmark beyond the lens' reach (only in a degenerate crop): not a usable hand
    presence: mapped && !mapped.every(Number.isFinite) ? 0 : outputs.Identity_1[0],
    handedness: right ? 'right' : 'left',
    handednessScore: Math.max(s0, 1 - s0),
    landmarks,
    world: w,
    roi,
  };
}

// The 12 landmarks MediaPipe bounds the next ROI with (wrist, thumb CMC/MCP/IP and the MCP and
// PIP of each finger); within them 4, 6, 8 are the index, middle and ring MCPs.
const PARTIAL = [0, 1, 2, 3, 5, 6, 9, 10, 13, 14, 17, 18];

/**
 * The next frame's ROI from image-pixel landmarks (MediaPipe's HandLandmarksToRect + rect
 * transformation): rotation from the wrist to ((index MCP + ring MCP)/2 + middle MCP)/2, the
 * bounding box of the 12 landmarks in that rotated frame, then shift_y -0.1, square long, x2.0.
 */
export function roiFromLandmarks(landmarks, { scale = 2.0, shiftY = -0.1 } = {}) {
  const P = (i, d) => landmarks[3 * PARTIAL[i] + d];
  const x0 = P(0, 0);
  const y0 = P(0, 1);
  const x1 = ((P(4, 0) + P(8, 0)) / 2 + P(6, 0)) / 2;
  const y1 = ((P(4, 1) + P(8, 1)) / 2 + P(6, 1)) / 2;
  const rotation = normalizeRadians(Math.PI / 2 - Math.atan2(-(y1 - y0), x1 - x0));
  // bounding box in the frame rotated by -rotation, about the axis-aligned centre
  let minX = Infinity;
  let minY = Infinity;
  let maxX = -Infinity;
  let maxY = -Infinity;
  for (let i = 0; i < PARTIAL.length; ++i) { minX = Math.min(minX, P(i, 0)); maxX = Math.max(maxX, P(i, 0)); minY = Math.min(minY, P(i, 1)); maxY = Math.max(maxY, P(i, 1)); }
  const ax = (minX + maxX) / 2;
  const ay = (minY + maxY) / 2;
  const c = Math.cos(rotation);
  const s = Math.sin(rotation);
  minX = minY = Infinity;
  maxX = maxY = -Infinity;
  for (let i = 0; i < PARTIAL.length; ++i) {
    const dx = P(i, 0) - ax;
    const dy = P(i, 1) - ay;
    const px = dx * c + dy * s; // rotate by -rotation
    const py = -dx * s + dy * c;
    minX = Math.min(minX, px); maxX = Math.max(maxX, px); minY = Math.min(minY, py); maxY = Math.max(maxY, py);
  }
  const pcx = (minX + maxX) / 2;
  const pcy = (minY + maxY) / 2;
  const roi = { cx: ax + pcx * c - pcy * s, cy: ay + pcx * s + pcy * c, w: maxX - minX, h: maxY - minY, rotation };
  return transformRoi(roi, { scale, shiftY, squareLong: true });
}
