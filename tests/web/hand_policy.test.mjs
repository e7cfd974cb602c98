// The tracking policy beyond MediaPipe's (web/src/perception/hand_tracker.mjs, prefilter.mjs),
// with stub networks whose outputs the tests choose: the detector-verifier cascade (a low-score
// palm confirmed by the landmark network is accepted, an unconfirmed one rejected, the
// verifications bounded), re-detection on a lost track, constant-velocity search ROIs, coasting,
// track identity and handedness evidence, one hand seen twice and the box-prefiltered detector
// input (the side assignment is the core's: tests/slam/test_pipeline.cpp). No model files, no
// clip.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { HandTracker } from '../../web/src/perception/hand_tracker.mjs';
import { cropBoxFiltered } from '../../web/src/perception/prefilter.mjs';
import { cropImage, letterboxRoi } from '../../web/src/perception/geometry.mjs';
import { PIPELINE_TRACKER_OPTIONS } from '../../web/src/pipeline/run.mjs';
import { rng } from './support.mjs';

const ort = { Tensor: class { constructor(type, data, dims) { Object.assign(this, { type, data, dims }); } } };
const T = (data) => ({ data });
const logit = (p) => Math.log(p / (1 - p));

/** A palm session returning candidates [{ cell: [x, y] of the 24 x 24 grid, score }]: a 40 px box
 *  on that anchor (192 px input), wrist 10 px below and middle MCP 10 px above its centre. */
function palmSession(candidates) {
  // candidates: a list, or a function giving the list of the run
  const outputs = (list) => {
    const reg = new Float32Array(2016 * 18);
    const sc = new Float32Array(2016).fill(-20);
    for (const { cell: [x, y], score } of list) {
      const a = 2 * (y * 24 + x);
      sc[a] = logit(score);
      reg.set([0, 0, 40, 40], a * 18);
      reg.set([0, 10], a * 18 + 4); // wrist
      reg.set([0, -10], a * 18 + 8); // keypoint 2, the middle-finger MCP
    }
    return { Identity: T(reg), Identity_1: T(sc) };
  };
  return { inputNames: ['input_1'], outputNames: ['Identity', 'Identity_1'], run: async () => outputs(typeof candidates === 'function' ? candidates() : candidates) };
}

/** A landmark session whose presence (and P(class 0), handedness) each call takes from
 *  `next(callIndex)`; the 21 keypoints spread over the middle of the crop. */
function landmarkSession(next) {
  const lm = new Float32Array(63);
  for (let k = 0; k < 21; ++k) { lm[3 * k] = 80 + 3 * k; lm[3 * k + 1] = 150 - 4 * k; }
  let calls = 0;
  return {
    inputNames: ['input_1'], outputNames: ['Identity', 'Identity_1', 'Identity_2', 'Identity_3'],
    run: async () => {
      const { presence, s0 = 0.9 } = next(calls++);
      return { Identity: T(lm), Identity_1: T(Float32Array.of(presence)), Identity_2: T(Float32Array.of(s0)), Identity_3: T(new Float32Array(63)) };
    },
  };
}

const image = { width: 192, height: 192, data: new Uint8Array(192 * 192 * 3), channels: 3 };
const CASCADE = { candidateScore: 0.1, candidatePresence: 0.5, maxCandidates: 2 };

test('cascade: a palm below the detector threshold is accepted when the landmark network confirms it, rejected when it does not', async () => {
  for (const [presence, accepted] of [[0.8, true], [0.4, false]]) {
    const tr = new HandTracker(ort, palmSession([{ cell: [12, 12], score: 0.3 }]), landmarkSession(() => ({ presence })), { minPresence: 0.3, ...CASCADE });
    const hands = await tr.track(image);
    assert.equal(tr.stats.landmarkRuns, 1, 'the candidate is verified once');
    assert.equal(hands.length, accepted ? 1 : 0, `presence ${presence}`);
    if (accepted) {
      assert.equal(hands[0].source, 'detect');
      assert.ok(Math.abs(hands[0].palm.score - 0.3) < 1e-6);
      assert.ok(hands[0].track && hands[0].track.id >= 1 && hands[0].track.frames === 1);
    }
  }
  // above the detector's threshold the tracking presence (minPresence) suffices
  const strong = new HandTracker(ort, palmSession([{ cell: [12, 12], score: 0.7 }]), landmarkSession(() => ({ presence: 0.4 })), { minPresence: 0.3, ...CASCADE });
  assert.equal((await strong.track(image)).length, 1);
  // MediaPipe's policy (no cascade): the weak palm is not even verified
  const plain = new HandTracker(ort, palmSession([{ cell: [12, 12], score: 0.3 }]), landmarkSession(() => ({ presence: 0.8 })), { minPresence: 0.3 });
  assert.equal((await plain.track(image)).length, 0);
  assert.equal(plain.stats.landmarkRuns, 0);
});

test('cascade: at most maxCandidates verifications per detector run, best palm first', async () => {
  const cands = [[3, 3, 0.2], [20, 3, 0.35], [3, 20, 0.25], [20, 20, 0.3]].map(([x, y, score]) => ({ cell: [x, y], score }));
  const seen = [];
  const tr = new HandTracker(ort, palmSession(cands), landmarkSession(() => ({ presence: 0.1 })), { minPresence: 0.3, ...CASCADE });
  const detect = tr.detectPalms.bind(tr);
  tr.detectPalms = async (img, o) => { const p = await detect(img, o); seen.push(...p.map((d) => d.score)); return p; };
  assert.equal((await tr.track(image)).length, 0);
  assert.equal(tr.stats.landmarkRuns, 2);
  assert.ok(Math.abs(seen[0] - 0.35) < 1e-6 && Math.abs(seen[1] - 0.3) < 1e-6, `best first: ${seen}`);
});

test('tracking: re-detection on the frame a track is lost, a lost track coasts one frame', async () => {
  // two tracked hands; on frame 2 the second is lost (presence 0.05): with redetectOnLoss the
  // detector runs on that frame although detectGap is large
  const presences = [0.9, 0.9, 0.9, 0.05, 0.9, 0.05, 0.9];
  const make = (opts) => {
    const tr = new HandTracker(ort, palmSession([]), landmarkSession((k) => ({ presence: presences[k] ?? 0.9 })), { minPresence: 0.3, detectGap: 10, ...opts });
    tr.tracked = [{ cx: 50, cy: 96, w: 60, h: 60, rotation: 0 }, { cx: 150, cy: 96, w: 60, h: 60, rotation: 0 }];
    return tr;
  };
  const tr = make({ redetectOnLoss: true, coast: 1 });
  assert.equal((await tr.track(image)).length, 2);
  assert.equal(tr.stats.palmRuns, 0, 'both hands tracked: no detector');
  assert.equal((await tr.track(image)).length, 1);
  assert.equal(tr.stats.palmRuns, 1, 'the detector ran on the frame the track was lost');
  assert.equal(tr.tracked.length, 2, 'the lost track coasts');
  assert.equal(tr.trackStates[1].misses, 1);
  assert.equal((await tr.track(image)).length, 1);
  assert.equal(tr.stats.landmarkRuns, 6, 'the coasting track was looked for');
  assert.equal(tr.tracked.length, 1, 'after `coast` frames the track ends');
  // MediaPipe's policy: the detector waits for detectGap, the lost track ends at once
  const plain = make({});
  for (let f = 0; f < 3; ++f) await plain.track(image);
  assert.equal(plain.stats.palmRuns, 0);
  assert.equal(plain.stats.landmarkRuns, 5);
});

test('tracking: constant-velocity search ROIs, handedness evidence summed over the track', () => {
  const tr = new HandTracker(ort, palmSession([]), landmarkSession(() => ({ presence: 1 })), { motion: true });
  const hand = (cx, right) => {
    // landmarks whose next ROI is centred near cx (a vertical hand 40 px tall)
    const lm = new Float32Array(63);
    for (let k = 0; k < 21; ++k) { lm[3 * k] = cx + (k % 5) - 2; lm[3 * k + 1] = 100 + 20 - 2 * k; }
    return { landmarks: lm, handedness: right ? 'right' : 'left', handednessScore: 0.9 };
  };
  const st = tr.newTrack({ cx: 100, cy: 90, w: 80, h: 80, rotation: 0 });
  tr.frame = 1; const h1 = hand(100, true); tr.confirm(st, h1);
  tr.frame = 2; const h2 = hand(130, true); tr.confirm(st, h2);
  assert.ok(Math.abs(st.vel[0] - 30) < 1e-3 && Math.abs(st.vel[1]) < 1e-3, `velocity ${st.vel}`);
  tr.frame = 3;
  const roi = tr.searchRoi(st);
  assert.ok(Math.abs(roi.cx - (st.roi.cx + 30)) < 1e-9, 'moved on by one frame of motion');
  tr.frame = 4;
  assert.ok(Math.abs(tr.searchRoi(st).cx - (st.roi.cx + 60)) < 1e-9, 'two frames after the last sighting');
  assert.equal(new HandTracker(ort, palmSession([]), landmarkSession(() => ({ presence: 1 }))).searchRoi(st), st.roi, 'without motion: the last ROI');
  // evidence: two right frames (each log 9), then one left: still right, and every hand carries it
  assert.ok(h2.track.pRight > 0.98 && h2.track.frames === 2 && h2.track.id === h1.track.id);
  tr.frame = 5; const h3 = hand(190, false); tr.confirm(st, h3);
  assert.ok(Math.abs(h3.track.pRight - 0.9) < 1e-9, `pRight ${h3.track.pRight}`);
  // one frame's label counts at most log(0.95 / 0.05)
  const st2 = tr.newTrack({ cx: 100, cy: 90, w: 80, h: 80, rotation: 0 });
  const sure = { ...hand(100, true), handednessScore: 1 };
  tr.confirm(st2, sure);
  assert.ok(Math.abs(sure.track.pRight - 0.95) < 1e-9);
});

test('one hand seen twice: a detection of a tracked hand is no second hand; it keeps the track', async () => {
  // a weak track (presence 0.35) on a large ROI, and the detector's palm at its centre (its ROI
  // 104 px: IoU 0.22 with the track's, so it is verified); the stub's landmarks fall on the same
  // place in both crops: one hand, the more confident view (0.9), the track's id
  const presences = [0.35, 0.9];
  const tr = new HandTracker(ort, palmSession([{ cell: [12, 12], score: 0.9 }]), landmarkSession((k) => ({ presence: presences[k] ?? 0 })), { minPresence: 0.3, detectGap: 0 });
  tr.tracked = [{ cx: 100, cy: 80, w: 220, h: 220, rotation: 0 }];
  const first = await tr.track(image);
  assert.equal(tr.stats.landmarkRuns, 2, 'the palm was verified');
  assert.equal(first.length, 1, JSON.stringify(first.map((h) => [h.source, h.presence])));
  assert.equal(first[0].source, 'detect');
  assert.ok(first[0].presence > 0.8, 'the more confident view');
  assert.equal(first[0].track.id, tr.trackStates[0].id);
  assert.equal(first[0].track.frames, 1);
  assert.equal(tr.trackStates.length, 1);
});

test('prefilter: footprint 0 is bilinear sampling, a box averages noise away, outside reads black', () => {
  const r = rng(3);
  const W = 200;
  const H = 120;
  const data = new Uint8Array(W * H * 3);
  for (let i = 0; i < data.length; ++i) data[i] = Math.floor(256 * r());
  const img = { width: W, height: H, data, channels: 3 };
  // upsampling and downsampling ROIs: bilinear exactly at footprint 0 (a one-pixel box)
  for (const roi of [{ cx: 60.3, cy: 50.7, w: 40, h: 30, rotation: 0 }, letterboxRoi(W, H)]) {
    const a = cropImage(img, roi, 48, 48);
    const b = cropBoxFiltered(img, roi, 48, 48, undefined, 0);
    for (let i = 0; i < a.length; ++i) assert.ok(Math.abs(a[i] - b[i]) < 1e-5, `sample ${i}: ${a[i]} vs ${b[i]}`);
  }
  // a 10x downsample of uniform noise (std 0.29): bilinear points average at most 4 pixels
  // (about 0.15 left), a half-spacing box 5 x 5 (about 0.06), a full box 10 x 10 (about 0.03)
  const roi = { cx: 99.5, cy: 59.5, w: 200, h: 120, rotation: 0 };
  const std = (a) => { const m = a.reduce((s, v) => s + v, 0) / a.length; return Math.sqrt(a.reduce((s, v) => s + (v - m) ** 2, 0) / a.length); };
  const s0 = std(cropImage(img, roi, 20, 12));
  const s5 = std(cropBoxFiltered(img, roi, 20, 12, undefined, 0.5));
  const s10 = std(cropBoxFiltered(img, roi, 20, 12, undefined, 1));
  assert.ok(s0 > 0.12 && s5 < 0.07 && s10 < 0.04, `spread ${s0} ${s5} ${s10}`);
  // a constant image stays constant inside; the letterbox bars read black
  const flat = { width: W, height: H, data: new Uint8Array(W * H * 3).fill(200), channels: 3 };
  const lb = cropBoxFiltered(flat, letterboxRoi(W, H), 20, 20, undefined, 0.5);
  assert.ok(Math.abs(lb[(10 * 20 + 10) * 3] - 200 / 255) < 1e-6, 'inside');
  assert.equal(lb[0], 0, 'the bar above the frame');
  assert.throws(() => cropBoxFiltered(flat, { ...roi, rotation: 0.1 }, 4, 4), /axis-aligned/);
});

test('the pipeline\'s tracker policy names only options the tracker has', () => {
  assert.deepEqual(Object.keys(PIPELINE_TRACKER_OPTIONS).sort(), ['candidatePresence', 'candidateScore', 'coast', 'maxCandidates', 'motion', 'palmPrefilter', 'redetectOnLoss']);
});

test('detectBackoff: empty detector runs with a hand tracked double the gap up to the cap; a found hand resets it', async () => {
  // one hand tracked throughout (presence 0.9); the detector finds nothing on frames 0-11, then
  // a palm whose crop is a second hand from frame 12 on
  let frame = 0;
  let palms = [];
  const palm = palmSession(() => palms);
  const runs = [];
  const tr = new HandTracker(ort, palm, landmarkSession(() => ({ presence: 0.9 })), { minPresence: 0.3, detectGap: 1, detectBackoff: 4 });
  const detect = tr.detectPalms.bind(tr);
  tr.detectPalms = async (img, o) => { runs.push(frame); return detect(img, o); };
  tr.tracked = [{ cx: 50, cy: 96, w: 60, h: 60, rotation: 0 }];
  for (; frame < 12; ++frame) await tr.track(image);
  // gaps 1, 2, 4, 4: runs on frames 1, 4, 9 (and none in between)
  assert.deepEqual(runs, [1, 4, 9]);
  palms = [{ cell: [20, 20], score: 0.9 }];
  for (; frame < 20; ++frame) await tr.track(image);
  assert.ok(runs.includes(14), `the next run after the cap (frame 14): ${runs}`);
  assert.equal(tr.gap, 1, 'a hand found restores detectGap');
  // off (the offline default): every detectGap + 1 frames
  const plain = new HandTracker(ort, palmSession([]), landmarkSession(() => ({ presence: 0.9 })), { minPresence: 0.3, detectGap: 1 });
  plain.tracked = [{ cx: 50, cy: 96, w: 60, h: 60, rotation: 0 }];
  for (let f = 0; f < 12; ++f) await plain.track(image);
  assert.equal(plain.stats.palmRuns, 6);
});
