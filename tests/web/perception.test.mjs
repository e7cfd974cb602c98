// The perception module (web/src/perception): anchors, palm decoding, weighted NMS, ROIs from
// palms and landmarks, the rotated crop and its inverse, on synthetic data with known answers;
// then the whole tracker on frames of the sample clip.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import {
  palmAnchors, decodePalms, weightedNms, palmToImage, roiFromPalm, PALM_NUM_ANCHORS,
  cropToImage, imageToCrop, cropImage, transformRoi, letterboxRoi, normalizeRadians, iou,
  decodeLandmarks, roiFromLandmarks, HandTracker,
} from '../../web/src/perception/index.mjs';
import { ort, rng } from './support.mjs';
import { clipSkipReason, modelsSkipReason, decodeFrame, modelsDir } from './mediapipe_support.mjs';

const near = (a, b, tol, what) => assert.ok(Math.abs(a - b) <= tol, `${what}: ${a} vs ${b} (tol ${tol})`);

test('palm anchors: 2016 = 24x24x2 (stride 8) + 12x12x6 (stride 16), cell centres, row-major', () => {
  const a = palmAnchors();
  assert.equal(a.length, 2 * PALM_NUM_ANCHORS);
  assert.equal(24 * 24 * 2 + 12 * 12 * 6, 2016);
  // first cell of the fine grid, twice
  assert.deepEqual([a[0], a[1], a[2], a[3]], [0.5 / 24, 0.5 / 24, 0.5 / 24, 0.5 / 24].map(Math.fround));
  // anchor 2 is the next cell to the right (x fastest)
  near(a[4], 1.5 / 24, 1e-7, 'x of anchor 2'); near(a[5], 0.5 / 24, 1e-7, 'y of anchor 2');
  // the last fine cell, then the coarse grid (6 per cell)
  near(a[2 * 1151], 23.5 / 24, 1e-7, 'x of anchor 1151'); near(a[2 * 1151 + 1], 23.5 / 24, 1e-7, 'y of anchor 1151');
  for (let k = 0; k < 6; ++k) { near(a[2 * (1152 + k)], 0.5 / 12, 1e-7, 'coarse x'); near(a[2 * (1152 + k) + 1], 0.5 / 12, 1e-7, 'coarse y'); }
  near(a[2 * 1158], 1.5 / 12, 1e-7, 'second coarse cell');
  near(a[2 * 2015], 11.5 / 12, 1e-7, 'last x'); near(a[2 * 2015 + 1], 11.5 / 12, 1e-7, 'last y');
  // every anchor centre lies on its grid: (x + 0.5) / g
  for (let i = 0; i < PALM_NUM_ANCHORS; ++i) {
    const g = i < 1152 ? 24 : 12;
    for (const v of [a[2 * i], a[2 * i + 1]]) near(v * g - 0.5, Math.round(v * g - 0.5), 1e-5, `anchor ${i}`);
  }
});

function syntheticPalmOutputs(entries) {
  // entries: [{anchor, logit, box: [dx, dy, w, h] px, kps: [[dx, dy] x 7] px}]
  const reg = new Float32Array(2016 * 18);
  const sc = new Float32Array(2016).fill(-20);
  for (const e of entries) {
    sc[e.anchor] = e.logit;
    reg.set(e.box, e.anchor * 18);
    e.kps.forEach(([x, y], k) => { reg[e.anchor * 18 + 4 + 2 * k] = x; reg[e.anchor * 18 + 5 + 2 * k] = y; });
  }
  return { reg, sc };
}

test('palm decoding: box and keypoints relative to the anchor in 192 px units, sigmoid scores, threshold', () => {
  const kps = Array.from({ length: 7 }, (_, k) => [k, -k]);
  const { reg, sc } = syntheticPalmOutputs([
    { anchor: 100, logit: 2, box: [9.6, -19.2, 48, 24], kps }, // anchor 100: cell 50 = (x 2, y 2) of the 24 grid
    { anchor: 1500, logit: 0.1, box: [0, 0, 10, 10], kps }, // sigmoid(0.1) = 0.525
    { anchor: 7, logit: -0.1, box: [0, 0, 10, 10], kps }, // below 0.5: dropped
  ]);
  const dets = decodePalms(reg, sc);
  assert.equal(dets.length, 2);
  const d = dets.find((x) => x.anchor === 100);
  near(d.score, 1 / (1 + Math.exp(-2)), 1e-7, 'score');
  near(d.box.cx, 2.5 / 24 + 9.6 / 192, 1e-6, 'cx'); near(d.box.cy, 2.5 / 24 - 19.2 / 192, 1e-6, 'cy');
  near(d.box.w, 0.25, 1e-7, 'w'); near(d.box.h, 0.125, 1e-7, 'h');
  near(d.keypoints[3][0], 2.5 / 24 + 3 / 192, 1e-6, 'kp3 x'); near(d.keypoints[3][1], 2.5 / 24 - 3 / 192, 1e-6, 'kp3 y');
  // logits are clipped at +-100 before the sigmoid (no NaN from huge values)
  const big = syntheticPalmOutputs([{ anchor: 0, logit: 1e30, box: [0, 0, 1, 1], kps }]);
  assert.equal(decodePalms(big.reg, big.sc)[0].score, 1);
  assert.equal(decodePalms(reg, sc, { minScore: 0.9 }).length, 0);
  assert.throws(() => decodePalms(new Float32Array(10), sc), /10 regressor values/);
});

test('weighted NMS: overlapping detections merge into their score-weighted mean, others stay', () => {
  const kp = (x) => Array.from({ length: 7 }, () => [x, x]);
  const dets = [
    { score: 0.6, box: { cx: 0.52, cy: 0.5, w: 0.2, h: 0.2 }, keypoints: kp(0.4) },
    { score: 0.9, box: { cx: 0.5, cy: 0.5, w: 0.2, h: 0.2 }, keypoints: kp(0.1) },
    { score: 0.7, box: { cx: 0.1, cy: 0.1, w: 0.1, h: 0.1 }, keypoints: kp(0.9) },
    { score: 0.55, box: { cx: 0.7, cy: 0.5, w: 0.2, h: 0.2 }, keypoints: kp(0.5) }, // IoU with the first 0 -> own group
  ];
  const out = weightedNms(dets, { iouThreshold: 0.3 });
  assert.equal(out.length, 3);
  assert.equal(out[0].score, 0.9);
  assert.equal(out[0].merged, 2);
  near(out[0].box.cx, (0.9 * 0.5 + 0.6 * 0.52) / 1.5, 1e-12, 'merged cx');
  near(out[0].keypoints[0][0], (0.9 * 0.1 + 0.6 * 0.4) / 1.5, 1e-12, 'merged keypoint');
  assert.deepEqual(out.map((d) => d.score), [0.9, 0.7, 0.55]);
  assert.equal(weightedNms(dets, { maxDetections: 1 }).length, 1);
  near(iou({ cx: 0, cy: 0, w: 2, h: 2 }, { cx: 1, cy: 0, w: 2, h: 2 }), 2 / 6, 1e-12, 'iou');
});

test('ROI from a palm: wrist -> middle MCP points up in the crop, x2.6, shifted 0.5 towards the fingers', () => {
  // hand pointing up: no rotation, the centre moves up (-y) by 0.5 x box height
  const up = { box: { cx: 100, cy: 200, w: 40, h: 30 }, keypoints: [[100, 220], [0, 0], [100, 180], [0, 0], [0, 0], [0, 0], [0, 0]] };
  const r = roiFromPalm(up);
  near(r.rotation, 0, 1e-12, 'rotation'); near(r.cx, 100, 1e-9, 'cx'); near(r.cy, 200 - 0.5 * 30, 1e-9, 'cy');
  near(r.w, 2.6 * 40, 1e-9, 'w (square on the long side)'); near(r.h, 2.6 * 40, 1e-9, 'h');
  // pointing right (+x): rotation +90 degrees, the shift goes right
  const right = { box: { cx: 100, cy: 200, w: 40, h: 40 }, keypoints: [[80, 200], [0, 0], [120, 200], [0, 0], [0, 0], [0, 0], [0, 0]] };
  const q = roiFromPalm(right);
  near(q.rotation, Math.PI / 2, 1e-12, 'rotation'); near(q.cx, 120, 1e-9, 'cx'); near(q.cy, 200, 1e-9, 'cy');
  // the crop's up direction (v < 0) is the finger direction
  const [x, y] = cropToImage(q, 0, -0.5);
  near(x, 120 + 52, 1e-9, 'top of the crop x'); near(y, 200, 1e-9, 'top of the crop y');
  near(normalizeRadians(3 * Math.PI / 2), -Math.PI / 2, 1e-12, 'wrap');
});

test('letterbox: palm detections map back to the frame', () => {
  const roi = letterboxRoi(1920, 1080);
  const det = { score: 0.9, box: { cx: 0.5, cy: 0.5, w: 0.1, h: 0.1 }, keypoints: [[0, 0], [1, 1], [0.5, 0.5 - 420 / 1920], [0, 0], [0, 0], [0, 0], [0, 0]] };
  const p = palmToImage(det, roi);
  near(p.box.cx, 959.5, 1e-9, 'centre x'); near(p.box.cy, 539.5, 1e-9, 'centre y'); near(p.box.w, 192, 1e-9, 'w');
  // (0, 0) of the square is above the frame: the frame's top edge (-0.5) is 420 px below it
  near(p.keypoints[0][0], -0.5, 1e-9, 'corner x'); near(p.keypoints[0][1], -420.5, 1e-9, 'corner y');
  near(p.keypoints[2][1], 539.5 - 420, 1e-9, 'keypoint y');
});

test('rotated crop: imageToCrop inverts cropToImage, and the crop samples a linear image exactly', () => {
  const r = rng(5);
  const W = 64;
  const H = 48;
  // a linear image: R = 2x + 1, G = 3y + 2, B = x + y (all within 0..255 on the frame)
  const data = new Uint8Array(W * H * 4);
  for (let y = 0; y < H; ++y) for (let x = 0; x < W; ++x) data.set([2 * x + 1, 3 * y + 2, x + y, 255], (y * W + x) * 4);
  const image = { width: W, height: H, data, channels: 4 };
  for (let k = 0; k < 20; ++k) {
    const roi = { cx: 20 + 24 * r(), cy: 16 + 16 * r(), w: 8 + 10 * r(), h: 8 + 10 * r(), rotation: (r() - 0.5) * 6 };
    const [u, v] = [r() - 0.5, r() - 0.5];
    const [x, y] = cropToImage(roi, u, v);
    const [u2, v2] = imageToCrop(roi, x, y);
    near(u2, u, 1e-12, 'u'); near(v2, v, 1e-12, 'v');
    const N = 16;
    const crop = cropImage(image, roi, N);
    for (const [i, j] of [[0, 0], [N - 1, 0], [7, 9], [N - 1, N - 1]]) {
      const [px, py] = cropToImage(roi, (i + 0.5) / N - 0.5, (j + 0.5) / N - 0.5);
      const o = (j * N + i) * 3;
      near(crop[o] * 255, 2 * px + 1, 1e-3, `R at crop (${i},${j})`);
      near(crop[o + 1] * 255, 3 * py + 2, 1e-3, `G at crop (${i},${j})`);
      near(crop[o + 2] * 255, px + py, 1e-3, `B at crop (${i},${j})`);
    }
  }
  // RGB input equals RGBA input; outside the image is black
  const rgb = new Uint8Array(W * H * 3);
  for (let p = 0; p < W * H; ++p) rgb.set(data.subarray(4 * p, 4 * p + 3), 3 * p);
  const roi = { cx: 30, cy: 20, w: 30, h: 20, rotation: 0.3 };
  assert.deepEqual(cropImage({ width: W, height: H, data: rgb, channels: 3 }, roi, 8), cropImage(image, roi, 8));
  const far = cropImage(image, { cx: -100, cy: -100, w: 10, h: 10, rotation: 0 }, 4);
  assert.ok(far.every((v) => v === 0));
  // replicate: far above-left reads the corner pixel (1, 2, 0)
  const rep = cropImage(image, { cx: -100, cy: -100, w: 10, h: 10, rotation: 0 }, 4, 4, undefined, 'replicate');
  for (let p = 0; p < 16; ++p) assert.deepEqual(Array.from(rep.subarray(3 * p, 3 * p + 3), (v) => Math.round(v * 255)), [1, 2, 0]);
  // replicate on the right edge column: x clamps to W - 1, y still interpolates
  const edge = cropImage(image, { cx: W + 20, cy: 20.25, w: 1, h: 1, rotation: 0 }, 1, 1, undefined, 'replicate');
  near(edge[0] * 255, 2 * (W - 1) + 1, 1e-4, 'R at the edge'); near(edge[1] * 255, 3 * 20.25 + 2, 1e-4, 'G at the edge');
  assert.throws(() => cropImage(image, roi, 8, 8, undefined, 'mirror'), /border 'mirror'/);
  assert.throws(() => cropImage({ width: W, height: H, data: rgb, channels: 4 }, roi, 8), /bytes for a 64x48x4 image/);
});

test('landmarks: crop pixels -> image pixels, world landmarks rotated with the ROI, handedness swapped', () => {
  const roi = { cx: 500, cy: 300, w: 200, h: 200, rotation: Math.PI / 2 };
  const Identity = new Float32Array(63);
  const Identity_3 = new Float32Array(63);
  Identity.set([112, 0, 8.96], 0); // top centre of the crop, z = 8.96 / 224 / 0.4 = 0.1 crop widths
  Identity.set([224, 112, 0], 3); // right edge centre
  Identity_3.set([0.05, 0, 0.01], 0); // 5 cm along the crop's x
  const out = decodeLandmarks({ Identity, Identity_1: new Float32Array([0.97]), Identity_2: new Float32Array([0.8]), Identity_3 }, roi);
  // rotation 90 deg: crop up (-v) is image +x, crop right (+u) is image +y
  near(out.landmarks[0], 600, 1e-4, 'x of the top centre'); near(out.landmarks[1], 300, 1e-4, 'y of the top centre');
  near(out.landmarks[2], 20, 1e-4, 'z in pixels');
  near(out.landmarks[3], 500, 1e-4, 'x of the right edge'); near(out.landmarks[4], 400, 1e-4, 'y of the right edge');
  near(out.world[0], 0, 1e-7, 'world x'); near(out.world[1], 0.05, 1e-7, 'world y'); near(out.world[2], 0.01, 1e-7, 'world z');
  assert.equal(out.presence, Math.fround(0.97));
  assert.equal(out.handedness, 'right'); // class 0 "Left" of a mirrored image = a right hand here
  near(out.handednessScore, 0.8, 1e-7, 'handedness score');
  const mirrored = decodeLandmarks({ Identity, Identity_1: new Float32Array([0.97]), Identity_2: new Float32Array([0.8]), Identity_3 }, roi, { mirrored: true });
  assert.equal(mirrored.handedness, 'left');
  assert.throws(() => decodeLandmarks({ Identity: new Float32Array(42) }, roi), /expected outputs/);
});

test('ROI from landmarks recovers the rotation and the box of a known hand, x2.0 and shift -0.1', () => {
  // a hand in its own frame (x right, y down, fingers up = -y), 12 bounding landmarks spanning
  // x in [-30, 30], y in [-40, 40], wrist at (0, 40), the three MCPs on the axis above it
  const local = new Array(21).fill(null).map(() => [0, 0]);
  local[0] = [0, 40]; local[1] = [-30, 20]; local[2] = [-25, 0]; local[3] = [-20, -10];
  local[5] = [-10, -20]; local[6] = [-10, -40]; local[9] = [0, -20]; local[10] = [0, -40];
  local[13] = [10, -20]; local[14] = [10, -40]; local[17] = [30, -10]; local[18] = [25, -30];
  const truth = { cx: 400, cy: 250, rotation: 0.7 };
  const lm = new Float32Array(63);
  local.forEach(([x, y], k) => {
    lm[3 * k] = truth.cx + x * Math.cos(truth.rotation) - y * Math.sin(truth.rotation);
    lm[3 * k + 1] = truth.cy + x * Math.sin(truth.rotation) + y * Math.cos(truth.rotation);
  });
  const roi = roiFromLandmarks(lm);
  near(roi.rotation, truth.rotation, 1e-6, 'rotation');
  near(roi.w, 2 * 80, 1e-3, 'w = 2 x long side'); near(roi.h, 160, 1e-3, 'h');
  // shift -0.1 x height (80) along the crop's up axis
  const [ex, ey] = cropToImage({ ...truth, w: 60, h: 80 }, 0, -0.1);
  near(roi.cx, ex, 1e-3, 'cx'); near(roi.cy, ey, 1e-3, 'cy');
  const t = transformRoi({ cx: 0, cy: 0, w: 10, h: 20, rotation: 0 }, { scale: 2, shiftX: 0.5, shiftY: 0 });
  assert.deepEqual([t.cx, t.w, t.h], [5, 40, 40]);
});

// ---- the tracker on the clip ------------------------------------------------------------------

test('tracker on the clip: finds both hands, tracks them without the detector, metric hand size', { skip: clipSkipReason() || modelsSkipReason(), timeout: 300000 }, async (t) => {
  const tracker = await HandTracker.create(ort, join(modelsDir, 'palm_detection_full.onnx'), join(modelsDir, 'hand_landmark_full.onnx'));
  const frame = (i) => { const f = decodeFrame(i); return { width: f.width, height: f.height, data: f.rgb, channels: 3 }; };
  const f20 = frame(20);
  // both hands hold the plate (frame 20): the right one near (1350-1400, 600-700), the left near (960-990, 780-850)
  const palms = await tracker.detectPalms(f20);
  assert.equal(palms.length, 2, 'two palms');
  const hands = await tracker.track(f20);
  assert.equal(hands.length, 2);
  assert.deepEqual(hands.map((h) => h.source), ['detect', 'detect']);
  const byX = hands.slice().sort((a, b) => a.landmarks[0] - b.landmarks[0]);
  assert.deepEqual(byX.map((h) => h.handedness), ['left', 'right'], 'egocentric: the left hand on the left');
  for (const h of hands) {
    assert.ok(h.presence > 0.8, `presence ${h.presence}`);
    // the wrist inside the frame and inside its own ROI
    const [u, v] = imageToCrop(h.roi, h.landmarks[0], h.landmarks[1]);
    assert.ok(Math.abs(u) < 0.5 && Math.abs(v) < 0.5, 'wrist inside the ROI');
    // metric geometry (loose: a hand seen edge-on, as the one gripping the plate, comes out
    // narrow): wrist -> middle MCP 6..12 cm, index MCP -> pinky MCP 2.5..10 cm
    const d = (a, b) => Math.hypot(h.world[3 * a] - h.world[3 * b], h.world[3 * a + 1] - h.world[3 * b + 1], h.world[3 * a + 2] - h.world[3 * b + 2]);
    assert.ok(d(0, 9) > 0.06 && d(0, 9) < 0.12, `wrist-middle MCP ${d(0, 9)} m`);
    assert.ok(d(5, 17) > 0.025 && d(5, 17) < 0.10, `index-pinky MCP ${d(5, 17)} m`);
    // image-space and world-space hand agree in direction (both in image axes): wrist -> middle MCP
    const img = [h.landmarks[27] - h.landmarks[0], h.landmarks[28] - h.landmarks[1]];
    const wld = [h.world[27] - h.world[0], h.world[28] - h.world[1]];
    assert.ok((img[0] * wld[0] + img[1] * wld[1]) / Math.hypot(...img) / Math.hypot(...wld) > 0.8, 'directions agree');
  }
  near(byX[1].landmarks[0], 1390, 80, 'right wrist x'); near(byX[1].landmarks[1], 660, 80, 'right wrist y');
  near(byX[0].landmarks[0], 966, 80, 'left wrist x'); near(byX[0].landmarks[1], 847, 80, 'left wrist y');
  // the next frames are tracked from the landmarks, the detector does not run
  const palmRuns = tracker.stats.palmRuns;
  for (const i of [21, 22]) {
    const next = await tracker.track(frame(i));
    assert.equal(next.length, 2, `frame ${i}`);
    assert.deepEqual(next.map((h) => h.source), ['track', 'track']);
  }
  assert.equal(tracker.stats.palmRuns, palmRuns);
  // two tracks on the same hand merge into one (the other hand is found again by the detector)
  const right = byX[1];
  tracker.tracked = [right.roi, { ...right.roi, cx: right.roi.cx + 10 }];
  const merged = await tracker.track(f20);
  assert.equal(merged.length, 2, 'one track per hand');
  assert.deepEqual(merged.map((h) => h.source).sort(), ['detect', 'track']);
  // a crop without a hand (the floor, top left of frame 20) has a low presence
  const empty = await tracker.landmarks(f20, { cx: 150, cy: 150, w: 250, h: 250, rotation: 0 });
  assert.ok(empty.presence < 0.2, `presence on the floor ${empty.presence}`);
  t.diagnostic(hands.map((h) => `${h.handedness} p=${h.presence.toFixed(3)} wrist (${h.landmarks[0].toFixed(0)}, ${h.landmarks[1].toFixed(0)})`).join('; '));
});
