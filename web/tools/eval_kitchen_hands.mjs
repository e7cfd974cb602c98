// eval_kitchen_hands.mjs: recall of each hand and left/right correctness of the perception +
// side assignment (HandTracker + the core's SideAssigner, the pipeline's defaults) on the kitchen
// clip, against the by-eye labels in tests/data/kitchen_hands_visible.json.
//
//   node web/tools/eval_kitchen_hands.mjs [--video /work/shared/data/egocentric_kitchen.mp4]
//        [--labels tests/data/kitchen_hands_visible.json] [--max-side N] [--model lite|full]
//        [--detect-gap N] [--min-presence P] [--min-palm-score S]
//
// Every frame is tracked (tracking needs them all); the labelled ones (every 5th) are scored:
//   recall[side]  labelled-visible (true) frames where that side got a detection
//   sideErrors    labelled frames where a side got a detection although that hand is labelled
//                 not visible (a wrong side or a false hand), plus frames where both were found
//                 with the left wrist right of the right one (the hands do not cross in this clip)
// 'partial' labels count neither way. Prints one JSON summary (with ms per frame).

import { readFileSync } from 'node:fs';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { defaultModelsDir } from './convert_mediapipe.mjs';
import { HandTracker } from '../src/perception/hand_tracker.mjs';
import { probeVideo, decodeFrames, loadCore } from '../cli.mjs';
import { toDetections, PIPELINE_DETECT_GAP, PIPELINE_MIN_PRESENCE, PIPELINE_TRACKER_OPTIONS } from '../src/pipeline/run.mjs';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
export const defaultVideo = '/work/shared/data/egocentric_kitchen.mp4';
export const defaultLabels = join(root, 'tests', 'data', 'kitchen_hands_visible.json');

/**
 * Runs the tracker + side assignment over the clip; returns { perFrame: [{left, right}] (wrist
 * [x, y] in full-resolution pixels or null), msPerFrame, stats, width, height }.
 */
export async function trackSides({ video = defaultVideo, maxSide = 0, model = 'lite', trackerOptions = {} } = {}) {
  const { width: W, height: H } = probeVideo(video);
  const s = maxSide > 0 ? Math.min(1, maxSide / Math.max(W, H)) : 1;
  const width = Math.round(W * s / 2) * 2;
  const height = Math.round(H * s / 2) * 2;
  const ort = await import('onnxruntime-web');
  ort.env.wasm.numThreads = 1;
  ort.env.logLevel = 'error';
  const tracker = await HandTracker.create(ort, join(defaultModelsDir, `palm_detection_${model}.onnx`), join(defaultModelsDir, `hand_landmark_${model}.onnx`),
    { maxHands: 2, detectGap: PIPELINE_DETECT_GAP, minPresence: PIPELINE_MIN_PRESENCE, ...PIPELINE_TRACKER_OPTIONS, ...trackerOptions }); // runPipeline's defaults
  const core = await loadCore(process.env.HAWOR_CORE ?? join(root, 'build', 'wasm', 'wasm', 'hawor_core.mjs'));
  const assigner = new core.SideAssigner(0.15 * Math.hypot(width, height)); // the pipeline's reach
  const perFrame = [];
  let ms = 0;
  // ffmpeg's default scaling (bicubic), as the labelled figures were measured
  const scaleTo = s !== 1 ? { width, height, flags: 'bicubic' } : null;
  for await (const { rgba: data } of decodeFrames(video, width, height, scaleTo, 0, { decode: 0 })) {
    const t0 = performance.now();
    const dets = await tracker.track({ width, height, data, channels: 3 });
    ms += performance.now() - t0;
    const sides = assigner.assign(toDetections(dets));
    const rec = {};
    ['left', 'right'].forEach((side, k) => {
      const d = sides[k] >= 0 ? dets[sides[k]] : null;
      rec[side] = d ? [d.landmarks[0] * W / width, d.landmarks[1] * H / height] : null;
    });
    perFrame.push(rec);
  }
  assigner.delete();
  return { perFrame, msPerFrame: ms / Math.max(1, perFrame.length), stats: tracker.stats, width, height };
}

/** Scores a trackSides result against the labels file. */
export function score(perFrame, labels) {
  const r = { left: { visible: 0, found: 0 }, right: { visible: 0, found: 0 }, partialFound: { left: 0, right: 0 }, sideErrors: [], missed: { left: [], right: [] } };
  for (const [k, lab] of Object.entries(labels.frames)) {
    const f = perFrame[Number(k)];
    if (!f) continue;
    for (const side of ['left', 'right']) {
      if (lab[side] === true) {
        r[side].visible += 1;
        if (f[side]) r[side].found += 1; else r.missed[side].push(Number(k));
      } else if (lab[side] === 'partial') {
        if (f[side]) r.partialFound[side] += 1;
      } else if (f[side]) r.sideErrors.push({ frame: Number(k), why: `${side} found, not visible` });
    }
    if (f.left && f.right && f.left[0] > f.right[0]) r.sideErrors.push({ frame: Number(k), why: 'left wrist right of the right one' });
  }
  r.recall = { left: r.left.found / r.left.visible, right: r.right.found / r.right.visible };
  return r;
}

async function main(argv) {
  const o = { video: defaultVideo, labels: defaultLabels, maxSide: 0, model: 'lite', trackerOptions: {} };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    const v = argv[++i];
    if (a === '--video') o.video = v;
    else if (a === '--labels') o.labels = v;
    else if (a === '--max-side') o.maxSide = Number(v);
    else if (a === '--model') o.model = v;
    else if (a === '--detect-gap') o.trackerOptions.detectGap = Number(v);
    else if (a === '--min-presence') o.trackerOptions.minPresence = Number(v);
    else if (a === '--min-palm-score') o.trackerOptions.minPalmScore = Number(v);
    else throw new Error(`unknown argument '${a}'`);
  }
  const labels = JSON.parse(readFileSync(o.labels, 'utf8'));
  const t = await trackSides(o);
  const found = { left: t.perFrame.filter((f) => f.left).length, right: t.perFrame.filter((f) => f.right).length };
  const r = score(t.perFrame, labels);
  process.stdout.write(`${JSON.stringify({ frames: t.perFrame.length, size: [t.width, t.height], foundAll: found, recall: r.recall, left: r.left, right: r.right, partialFound: r.partialFound, missed: r.missed, sideErrors: r.sideErrors, msPerFrame: Number(t.msPerFrame.toFixed(1)), ...t.stats })}\n`);
}

if (process.argv[1] && fileURLToPath(import.meta.url) === process.argv[1]) {
  main(process.argv.slice(2)).catch((e) => { process.stderr.write(`eval_kitchen_hands: ${e.message}\n`); process.exitCode = 1; });
}
