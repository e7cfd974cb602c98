// track_hands.mjs: runs the perception module (palm detection + hand landmarks, MediaPipe-style
// tracking) over a video in node and writes one JSON line per frame.
//
//   node web/tools/track_hands.mjs --video IN.mp4 --out hands.jsonl
//        [--model lite|full] [--first N] [--count N] [--max-hands 2] [--threads 1] [--mirrored]
//
// Frames are decoded by ffmpeg (Debian's; web/cli.mjs's decodeFrames, RGB24 at full resolution,
// one process for the whole run, stopping after frame first + count). Each output line:
//   {"frame": i, "hands": [{"handedness": "left"|"right", "handednessScore", "presence",
//     "source": "track"|"detect", "landmarks": [[x, y, z] x 21] image pixels,
//     "world": [[x, y, z] x 21] metres, "roi": {cx, cy, w, h, rotation}}]}
// A summary JSON line goes to stderr (frames, hands per frame, detector runs, ms per frame).
// Exit code 2: usage error; 1: a missing or bad file (the message names it).

import { createWriteStream, existsSync } from 'node:fs';
import { join } from 'node:path';
import { defaultModelsDir } from './convert_mediapipe.mjs';
import { HandTracker } from '../src/perception/hand_tracker.mjs';
import { probeVideo, decodeFrames } from '../cli.mjs';

function usage(msg) {
  const e = new Error(`${msg}\nusage: node web/tools/track_hands.mjs --video IN.mp4 --out hands.jsonl [--model lite|full] [--first N] [--count N] [--max-hands N] [--threads N] [--mirrored]`);
  e.exitCode = 2;
  return e;
}

function parse(argv) {
  const o = { model: 'lite', first: 0, count: Infinity, maxHands: 2, threads: 1, mirrored: false, models: defaultModelsDir };
  const int = (v, name, min) => {
    const n = Number(v);
    if (!Number.isInteger(n) || n < min) throw usage(`${name} must be an integer >= ${min}, not '${v}'`);
    return n;
  };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    const next = () => { if (i + 1 >= argv.length) throw usage(`${a} needs a value`); return argv[++i]; };
    if (a === '--video') o.video = next();
    else if (a === '--out') o.out = next();
    else if (a === '--model') { o.model = next(); if (!['lite', 'full'].includes(o.model)) throw usage(`--model must be lite or full, not '${o.model}'`); }
    else if (a === '--models') o.models = next();
    else if (a === '--first') o.first = int(next(), '--first', 0);
    else if (a === '--count') o.count = int(next(), '--count', 1);
    else if (a === '--max-hands') o.maxHands = int(next(), '--max-hands', 1);
    else if (a === '--threads') o.threads = int(next(), '--threads', 1);
    else if (a === '--mirrored') o.mirrored = true;
    else throw usage(`unknown argument '${a}'`);
  }
  if (!o.video || !o.out) throw usage('--video and --out are required');
  return o;
}

const fail = (msg) => Object.assign(new Error(msg), { exitCode: 1 });

const round = (v, d) => Number(v.toFixed(d));
const triples = (a, d) => Array.from({ length: a.length / 3 }, (_, k) => [round(a[3 * k], d), round(a[3 * k + 1], d), round(a[3 * k + 2], d)]);

async function main(argv) {
  const o = parse(argv);
  if (!existsSync(o.video)) throw fail(`${o.video}: no such file`);
  const palm = join(o.models, `palm_detection_${o.model}.onnx`);
  const lm = join(o.models, `hand_landmark_${o.model}.onnx`);
  for (const f of [palm, lm]) if (!existsSync(f)) throw fail(`${f}: missing (scripts/install.sh converts the models)`);
  const { width, height } = probeVideo(o.video);
  const ort = await import('onnxruntime-web');
  ort.env.wasm.numThreads = o.threads;
  ort.env.logLevel = 'error';
  const tracker = await HandTracker.create(ort, palm, lm, { maxHands: o.maxHands, mirrored: o.mirrored });
  const out = createWriteStream(o.out);
  const perFrame = [];
  const hist = new Array(o.maxHands + 1).fill(0);
  // full resolution; ffmpeg stops after the last frame asked for (0: the whole clip)
  const maxFrames = Number.isFinite(o.count) ? o.first + o.count : 0;
  for await (const f of decodeFrames(o.video, width, height, null, maxFrames, { decode: 0 })) {
    if (f.index < o.first) continue;
    const t0 = performance.now();
    const hands = await tracker.track({ width, height, data: f.rgba, channels: 3 });
    perFrame.push(performance.now() - t0);
    hist[hands.length] += 1;
    const rec = {
      frame: f.index,
      hands: hands.map((h) => ({
        handedness: h.handedness, handednessScore: round(h.handednessScore, 4), presence: round(h.presence, 4), source: h.source,
        landmarks: triples(h.landmarks, 2), world: triples(h.world, 5),
        roi: { cx: round(h.roi.cx, 2), cy: round(h.roi.cy, 2), w: round(h.roi.w, 2), h: round(h.roi.h, 2), rotation: round(h.roi.rotation, 5) },
      })),
    };
    if (!out.write(`${JSON.stringify(rec)}\n`)) await new Promise((res) => out.once('drain', res));
  }
  await new Promise((res, rej) => out.end((e) => (e ? rej(e) : res())));
  if (perFrame.length === 0) throw fail(`${o.video}: no frame in [${o.first}, ${o.first + o.count})`);
  const sorted = perFrame.slice().sort((a, b) => a - b);
  const summary = {
    video: o.video, width, height, model: o.model, threads: o.threads, frames: perFrame.length,
    framesWithHands: Object.fromEntries(hist.map((n, k) => [k, n])),
    palmRuns: tracker.stats.palmRuns, landmarkRuns: tracker.stats.landmarkRuns,
    medianMsPerFrame: round(sorted[Math.floor(sorted.length / 2)], 1),
  };
  process.stderr.write(`${JSON.stringify(summary)}\n`);
  return 0;
}

main(process.argv.slice(2)).then((c) => { process.exitCode = c; }, (e) => {
  process.stderr.write(`track_hands: ${e.message}\n`);
  process.exitCode = e.exitCode ?? 1;
});
