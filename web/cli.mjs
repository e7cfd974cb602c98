#!/usr/bin/env node
// cli.mjs: the headless hawor pipeline on a video file (node glue only: arguments, ffmpeg
// decoding, progress, files; every algorithm is in web/src/pipeline/run.mjs and the C++ core).
//
//   hawor run VIDEO|--sample --out DIR [--focal PX | --fov DEG] [--camera LENS] [--readout S] [--no-refine-focal] [--mano DIR]
//        [--depth-model M.onnx [--depth-config M.json]] [--model full|lite] [--threads N]
//        [--core hawor_core.mjs] [--models DIR] [--max-frames N] [--infill spline|lerp|last]
//        [--eye-height M | --no-ground-scale] [--first-camera-world] [--flow-max-skip N]
//        [--runtime auto|native|wasm] [--perception thread|main]
//   hawor batch MANIFEST|FOLDER --out DIR [--task-index N --tasks M] [--force] [--clip-timeout S] [run options]
//   hawor batch --summary DIR [--json]
//   (`hawor` is the npm package's bin; in a checkout: node web/cli.mjs ...)
//
// batch runs `hawor run` on its task's share of a corpus, one clip per child process, into
// DIR/<clip id>/ with a status.json each (src/batch/task.mjs, docs/batch.md); exit code 1 when a
// clip of the task failed (the others still ran).
//
// --sample runs the built-in synthetic sample (sample.webm, 60 frames of a table scene) with its
// true focal from sample.json (unless --focal or --fov is given).
//
// --camera LENS: the lens, 'pinhole' (default), 'opencv:k1,k2,p1,p2[,k3]' or
// 'fisheye:k1,k2,k3,k4' (run.mjs: perspective hand crops, keypoints undistorted, the SLAM on
// rectified frames); a string that does not parse, a coefficient that is not finite, or a lens
// that folds inside the video's frame is a usage error naming the problem.
//
// Writes DIR/world.npz, DIR/hands_cam.npz, DIR/camera.tum and DIR/result.json (exports.mjs
// describes them), prints a progress bar and a per-stage timing table on stderr and one JSON
// summary line on stdout. Frames are decoded by ffmpeg (Debian's) as a stream of RGB frames;
// videos above 8.3 Mpx (4096x2304) are downscaled by ffmpeg to 1920 px on the long side (said on
// stderr). Exit codes: 2 usage error, 1 bad input (the message names it), 0 success (also when
// no hand was found: result.json says "noHands": true).
//
// --runtime: the networks' runtime (loadOrt): native = onnxruntime-node, wasm = onnxruntime-web
// (the browser's), auto (default) = native when installed. The summary line names it.
// --perception: where the hand networks run: main (default) = on the pipeline's own thread;
// thread = a worker thread (src/perception/worker_tracker.mjs), the next frame's networks
// overlapping this frame's SLAM and the decoding. The same result either way. On two cores the
// process is CPU-bound and both take the same time (docs/experiments.md); the overlap needs cores
// to spare.
//
// Defaults: the core from $HAWOR_CORE, else build/wasm/wasm (checkout) or dist/ (installed
// package), found by src/core.mjs's builtFile, which also finds the sample (build/web or dist/);
// hand models from --mano DIR (MANO_LEFT/RIGHT .pkl or .npz), else $HAWOR_HAND_DIR or
// build/native/models (hand_{left,right}.npz or {left,right}.glb, as the native tool's
// findDefaultHandModel looks), else the WebXR glTF hands of the installed
// @webxr-input-profiles/assets; perception networks from web/models (converted at install; when
// missing there, e.g. after npm install --ignore-scripts, they are converted on the spot).

import { spawn, spawnSync } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, realpathSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { builtFile, loadCore as loadCoreModule } from './src/core.mjs';
import { runPipeline, cameraIntrinsics, MAX_PIXELS } from './src/pipeline/run.mjs';
import { eyeHeightError } from './src/pipeline/eye_height.mjs';
import { canonicalOptions, runTask, taskSlot } from './src/batch/task.mjs';
import { formatSummary, summarize } from './src/batch/summary.mjs';
import { workerTrackerFactory } from './src/perception/worker_tracker.mjs';
import { loadOrt } from './src/ort_runtime.mjs';

export { loadOrt };
import { resultToWorldNpz, resultToHandsCamNpz, resultToTum, resultToJson } from './src/pipeline/exports.mjs';

const here = dirname(fileURLToPath(import.meta.url));
const repo = resolve(here, '..');
const defaultModels = join(here, 'models');
const USAGE = 'usage: hawor run VIDEO|--sample --out DIR [--focal PX | --fov DEG] [--camera pinhole|opencv:k1,k2,p1,p2[,k3]|fisheye:k1,k2,k3,k4] [--readout S] [--no-refine-focal] [--mano DIR] [--depth-model M.onnx [--depth-config M.json]] [--model full|lite] [--threads N] [--core hawor_core.mjs] [--models DIR] [--max-frames N] [--infill spline|lerp|last] [--eye-height M | --no-ground-scale] [--first-camera-world] [--flow-max-skip N] [--runtime auto|native|wasm] [--perception thread|main]';

const BATCH_USAGE = 'usage: hawor batch MANIFEST|FOLDER --out DIR [--task-index N --tasks M] [--force] [--clip-timeout S] [hawor run options]\n       hawor batch --summary DIR [--json]\n(the task index defaults to SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX; clip i goes to task i mod M)';
const usage = (msg) => Object.assign(new Error(`${msg}\n${USAGE}`), { exitCode: 2 });
const fail = (msg) => Object.assign(new Error(msg), { exitCode: 1 });

export function parseArgs(argv) {
  if (argv[0] === '--help' || argv[0] === '-h') return { help: true };
  if (argv[0] === 'batch') return parseBatchArgs(argv);
  if (argv[0] !== 'run') throw usage(argv.length ? `unknown command '${argv[0]}'` : 'missing command');
  const o = { model: 'lite', threads: 2, infill: 'spline' };
  const num = (v, name, min) => {
    const n = Number(v);
    if (!Number.isFinite(n) || n <= min) throw usage(`${name} must be a number > ${min}, not '${v}'`);
    return n;
  };
  for (let i = 1; i < argv.length; ++i) {
    const a = argv[i];
    const next = () => { if (i + 1 >= argv.length) throw usage(`${a} needs a value`); return argv[++i]; };
    if (a === '--out') o.out = next();
    else if (a === '--sample') o.sample = true;
    else if (a === '--focal') o.focalPx = num(next(), '--focal', 0);
    else if (a === '--fov') { o.fovDeg = num(next(), '--fov', 1); if (o.fovDeg >= 179) throw usage('--fov must be below 179 degrees'); }
    else if (a === '--camera') { o.camera = next(); if (!o.camera.trim()) throw usage('--camera needs a lens (pinhole, opencv:k1,k2,p1,p2[,k3] or fisheye:k1,k2,k3,k4)'); }
    else if (a === '--no-refine-focal') o.refineFocal = false;
    else if (a === '--readout') {
      const v = next();
      o.readout = v.trim() === '' ? NaN : Number(v);
      if (!Number.isFinite(o.readout) || Math.abs(o.readout) > 0.1) throw usage(`--readout is the rolling shutter's readout in seconds (a phone: 0.015-0.03; negative for a clip played backwards), at most one frame interval, not '${v}'`);
    }
    else if (a === '--mano') o.mano = next();
    else if (a === '--depth-model') o.depthModel = next();
    else if (a === '--depth-config') o.depthConfig = next();
    else if (a === '--model') { o.model = next(); if (!['lite', 'full'].includes(o.model)) throw usage(`--model must be lite or full, not '${o.model}'`); }
    else if (a === '--threads') { o.threads = num(next(), '--threads', 0); if (!Number.isInteger(o.threads)) throw usage('--threads must be an integer'); }
    else if (a === '--core') o.core = next();
    else if (a === '--models') o.models = next();
    else if (a === '--max-frames') { o.maxFrames = num(next(), '--max-frames', 0); if (!Number.isInteger(o.maxFrames)) throw usage('--max-frames must be an integer'); }
    else if (a === '--infill') { o.infill = next(); if (!['spline', 'lerp', 'last'].includes(o.infill)) throw usage(`--infill must be spline, lerp or last, not '${o.infill}'`); }
    else if (a === '--eye-height') { o.eyeHeight = num(next(), '--eye-height', 0); const bad = eyeHeightError(o.eyeHeight); if (bad) throw usage(`--eye-height: ${bad}`); }
    else if (a === '--no-ground-scale') o.groundScale = false;
    else if (a === '--first-camera-world') o.gravityAligned = false;
    else if (a === '--perception') { o.perception = next(); if (!['thread', 'main'].includes(o.perception)) throw usage(`--perception must be thread or main, not '${o.perception}'`); }
    else if (a === '--runtime') { o.runtime = next(); if (!['auto', 'native', 'wasm'].includes(o.runtime)) throw usage(`--runtime must be auto, native or wasm, not '${o.runtime}'`); }
    else if (a === '--flow-max-skip') { o.flowMaxSkip = num(next(), '--flow-max-skip', -1); if (!Number.isInteger(o.flowMaxSkip) || o.flowMaxSkip > 30) throw usage('--flow-max-skip must be an integer from 0 to 30'); }
    else if (a === '--help' || a === '-h') return { help: true };
    else if (a.startsWith('--')) throw usage(`unknown option '${a}'`);
    else if (!o.video) o.video = a;
    else throw usage(`unexpected argument '${a}'`);
  }
  if (o.sample && o.video) throw usage('give VIDEO or --sample, not both');
  if (!o.video && !o.sample) throw usage('missing VIDEO (or --sample)');
  if (!o.out) throw usage('--out DIR is required');
  if (o.focalPx !== undefined && o.fovDeg !== undefined) throw usage('give --focal or --fov, not both');
  if (o.depthConfig && !o.depthModel) throw usage('--depth-config needs --depth-model');
  if (o.eyeHeight !== undefined && o.groundScale === false) throw usage('give --eye-height or --no-ground-scale, not both');
  return o;
}

/** `hawor batch MANIFEST --out DIR [--task-index N] [--tasks M] [--force] [--clip-timeout S]
 *  [run options]` or `hawor batch --summary DIR [--json]`. MANIFEST comes first; every option
 *  that is not the batch's own is a `hawor run` option, checked here by run's parser. */
export function parseBatchArgs(argv) {
  const bad = (msg) => Object.assign(new Error(`${msg}\n${BATCH_USAGE}`), { exitCode: 2 });
  const a = argv.slice(1);
  if (a[0] === '--help' || a[0] === '-h') return { help: true, batch: true };
  if (a[0] === '--summary') {
    if (!a[1] || a[1].startsWith('--')) throw bad('--summary needs the batch\'s output folder');
    const rest = a.slice(2);
    if (rest.some((x) => x !== '--json')) throw bad(`unexpected argument '${rest.find((x) => x !== '--json')}' after --summary DIR`);
    return { command: 'summary', out: a[1], json: rest.includes('--json') };
  }
  if (!a.length || a[0].startsWith('--')) throw bad('missing MANIFEST (a text file of video paths, or a folder of videos)');
  const o = { command: 'batch', manifest: a[0], runArgs: [], force: false, clipTimeoutS: 3600 };
  const int = (v, name, min) => {
    if (v === undefined || !/^\d+$/.test(v) || Number(v) < min) throw bad(`${name} must be an integer >= ${min}, not '${v ?? ''}'`);
    return Number(v);
  };
  for (let i = 1; i < a.length; ++i) {
    const x = a[i];
    if (x === '--out') { o.out = a[++i]; if (!o.out) throw bad('--out needs a folder'); }
    else if (x === '--task-index') o.index = int(a[++i], '--task-index', 0);
    else if (x === '--tasks') o.tasks = int(a[++i], '--tasks', 1);
    else if (x === '--force') o.force = true;
    else if (x === '--clip-timeout') o.clipTimeoutS = int(a[++i], '--clip-timeout', 0);
    else if (x === '--sample') throw bad('--sample is not a batch option: list the clips in MANIFEST');
    else o.runArgs.push(x);
  }
  if (!o.out) throw bad('--out DIR is required');
  if (o.index !== undefined && o.tasks !== undefined && o.index >= o.tasks) throw bad(`--task-index ${o.index} must be below --tasks ${o.tasks}`);
  // the run options, as `hawor run` would take them for each clip
  try {
    o.options = canonicalOptions(parseArgs(['run', 'CLIP', '--out', 'OUT', ...o.runArgs]));
  } catch (e) {
    throw bad(`run option: ${e.message.split('\n')[0]}`);
  }
  return o;
}

/** `hawor batch`: one task of the batch, or the summary of its output folder. */
async function batchMain(o) {
  if (o.help) { process.stdout.write(`${BATCH_USAGE}\n`); return 0; }
  if (o.command === 'summary') {
    const s = summarize(o.out);
    process.stdout.write(`${o.json ? JSON.stringify(s) : formatSummary(o.out, s)}\n`);
    return 0;
  }
  const slot = taskSlot({ index: o.index, tasks: o.tasks });
  if (slot.warning) process.stderr.write(`hawor: warning: ${slot.warning}\n`);
  const r = await runTask({ ...o, ...slot, log: (l) => process.stderr.write(`hawor: ${l}\n`) });
  process.stdout.write(`${JSON.stringify({ out: o.out, task: slot.index, tasks: slot.tasks, ...r, seconds: Number(r.seconds.toFixed(1)) })}\n`);
  return r.failed ? 1 : 0;
}

/** ffprobe: the frame size as shown (a phone clip's display rotation applied, as ffmpeg's decoder
 *  applies it: a portrait clip stored as 1920 x 1080 with a 90° rotation is 1080 x 1920; non-square
 *  pixels made square: `anamorphic`, decode with scaleTo that size), fps, frame count (null when
 *  the container does not say) and the rotation in degrees. */
export function probeVideo(video) {
  const r = spawnSync('ffprobe', ['-v', 'error', '-select_streams', 'v:0', '-show_entries',
    'stream=width,height,sample_aspect_ratio,r_frame_rate,avg_frame_rate,nb_frames:stream_side_data=rotation:stream_tags=rotate', '-of', 'json', video], { encoding: 'utf8' });
  if (r.error) throw fail('ffprobe is not installed (apt-get install ffmpeg)');
  let s = null;
  try { s = JSON.parse(r.stdout).streams?.[0] ?? null; } catch { s = null; }
  if (r.status !== 0 || !s || !(s.width > 0 && s.height > 0)) {
    const why = (r.stderr || '').trim().split('\n').pop() || 'no video stream';
    throw fail(`${video}: not a readable video (${why})`);
  }
  const rate = (txt) => { const [a, b] = String(txt ?? '').split('/').map(Number); return a > 0 && b > 0 ? a / b : NaN; };
  let fps = rate(s.avg_frame_rate);
  if (!(fps > 0 && fps < 1000)) fps = rate(s.r_frame_rate);
  if (!(fps > 0 && fps < 1000)) fps = 30;
  const n = Number(s.nb_frames);
  const turn = Number((s.side_data_list ?? []).find((d) => d.rotation !== undefined)?.rotation ?? s.tags?.rotate ?? 0);
  const rotation = Number.isFinite(turn) ? ((Math.round(turn / 90) * 90) % 360 + 360) % 360 : 0;
  const quarter = rotation === 90 || rotation === 270;
  // non-square pixels (anamorphic video): the picture as shown, widened (or heightened) to
  // square pixels, which the camera model assumes (fx = fy); the caller decodes at that size
  let sar = rate(String(s.sample_aspect_ratio ?? '').replace(':', '/'));
  if (!(sar > 0.1 && sar < 10) || Math.abs(sar - 1) < 0.01) sar = 1;
  const even = (x) => Math.max(2, 2 * Math.round(x / 2));
  const w = sar > 1 ? even(s.width * sar) : s.width;
  const h = sar < 1 ? even(s.height / sar) : s.height;
  return { width: quarter ? h : w, height: quarter ? w : h, fps, frameCount: Number.isInteger(n) && n > 0 ? n : null,
    rotation, anamorphic: sar !== 1 };
}

/** The frames' presentation times (seconds from the first frame) when the clip's frame rate varies
 *  (phones lower it in dim light, screen recorders and edits leave gaps), from the packets' time
 *  stamps (no decoding); null for a constant rate (every interval within 10 % of the median: the
 *  times are frame / fps) or when the stamps are missing or repeat. fps: the median interval's
 *  rate, the camera's frame rate while it kept pace. */
export function variableFrameTimes(video) {
  const r = spawnSync('ffprobe', ['-v', 'error', '-select_streams', 'v:0', '-show_entries', 'packet=pts_time,flags',
    '-of', 'csv=p=0', video], { encoding: 'utf8', maxBuffer: 1 << 28 });
  if (r.error || r.status !== 0) return null;
  const t = [];
  for (const line of r.stdout.split('\n')) {
    const [pts, flags = ''] = line.trim().split(',');
    if (!pts || flags.includes('D')) continue; // a packet the demuxer discards (an edit list's)
    const x = Number(pts);
    if (!Number.isFinite(x)) return null; // 'N/A': an elementary stream without time stamps
    t.push(x);
  }
  if (t.length < 3) return null;
  t.sort((a, b) => a - b);
  const d = t.slice(1).map((x, i) => x - t[i]);
  if (!d.every((x) => x > 0)) return null;
  const med = [...d].sort((a, b) => a - b)[d.length >> 1];
  if (d.every((x) => Math.abs(x - med) <= 0.1 * med)) return null;
  return { times: t.map((x) => x - t[0]), fps: Math.round(1e3 / med) / 1e3 }; // stamps are in µs or coarser
}

/** Frames from one ffmpeg process as RGB24, one preallocated buffer per frame (backpressure:
 *  the pipe is read only as fast as the pipeline consumes frames). scaleTo: {width, height,
 *  flags?} resizes with ffmpeg's scale filter (flags default 'area'). Every decoded frame once
 *  (no frames repeated or dropped to a constant rate); times (variableFrameTimes'): each frame
 *  carries its `time`, a frame past the list the last interval on. */
export async function* decodeFrames(video, width, height, scaleTo, maxFrames, timing, times = null) {
  const args = ['-v', 'error', '-nostdin', '-i', video, '-an', '-sn'];
  if (scaleTo) args.push('-vf', `scale=${scaleTo.width}:${scaleTo.height}:flags=${scaleTo.flags ?? 'area'}`);
  if (maxFrames) args.push('-frames:v', String(maxFrames));
  args.push('-fps_mode', 'passthrough', '-f', 'rawvideo', '-pix_fmt', 'rgb24', '-');
  const timeOf = (i) => (i < times.length ? times[i] : times[times.length - 1] + (i - times.length + 1) * (times[times.length - 1] - times[times.length - 2]));
  const ff = spawn('ffmpeg', args, { stdio: ['ignore', 'pipe', 'pipe'] });
  let err = '';
  ff.stderr.on('data', (d) => { if (err.length < 1e4) err += d; });
  const closed = new Promise((res) => ff.on('close', (code) => res(code)));
  const size = width * height * 3;
  let frame = new Uint8Array(size);
  let fill = 0;
  let index = 0;
  let t = performance.now();
  try {
    for await (const chunk of ff.stdout) {
      let off = 0;
      while (off < chunk.length) {
        const n = Math.min(size - fill, chunk.length - off);
        frame.set(chunk.subarray(off, off + n), fill);
        fill += n; off += n;
        if (fill === size) {
          timing.decode += performance.now() - t;
          yield times ? { index, rgba: frame, time: timeOf(index++) } : { index: index++, rgba: frame };
          t = performance.now();
          frame = new Uint8Array(size);
          fill = 0;
        }
      }
    }
  } finally {
    if (ff.exitCode === null) ff.kill();
  }
  const code = await closed;
  if (code !== 0 && err.trim()) {
    // ffmpeg's lines without their '[demuxer @ 0x...]' prefixes, the first (the cause) first
    const lines = [...new Set(err.trim().split('\n').map((l) => l.replace(/^\[[^\]]*@ 0x[0-9a-f]+\]\s*/, '').trim()).filter(Boolean))];
    throw fail(`${video}: cannot be decoded (ffmpeg: ${lines.join('; ').slice(0, 400)})`);
  }
}

/** The core's module (src/core.mjs; a missing file is a bad-input error, exit code 1). */
export async function loadCore(path) {
  try {
    return await loadCoreModule(path ? { path } : {});
  } catch (e) {
    throw fail(`${e.message}${path ? '' : ' (or give --core)'}`);
  }
}

/** The folder of an installed npm package as module resolution finds it from here, or null. */
function packageDir(name) {
  try {
    return dirname(createRequire(import.meta.url).resolve(`${name}/package.json`));
  } catch {
    return null;
  }
}

export function handModelFiles(o) {
  if (o.mano) {
    const pick = (side) => {
      for (const n of [`MANO_${side.toUpperCase()}.pkl`, `MANO_${side.toUpperCase()}.npz`, `mano_${side}.pkl`, `mano_${side}.npz`]) {
        if (existsSync(join(o.mano, n))) return join(o.mano, n);
      }
      throw fail(`${o.mano}: no MANO_${side.toUpperCase()}.pkl or .npz there`);
    };
    return { left: pick('left'), right: pick('right') };
  }
  const dirs = [process.env.HAWOR_HAND_DIR, join(repo, 'build', 'native', 'models')].filter(Boolean);
  for (const d of dirs) {
    for (const [l, r] of [['hand_left.npz', 'hand_right.npz'], ['left.glb', 'right.glb']]) {
      if (existsSync(join(d, l)) && existsSync(join(d, r))) return { left: join(d, l), right: join(d, r) };
    }
  }
  const assets = packageDir('@webxr-input-profiles/assets');
  const glb = assets && join(assets, 'dist', 'profiles', 'generic-hand');
  if (glb && existsSync(join(glb, 'left.glb')) && existsSync(join(glb, 'right.glb'))) return { left: join(glb, 'left.glb'), right: join(glb, 'right.glb') };
  throw fail('no hand model: give --mano DIR, set HAWOR_HAND_DIR, or install the default hand (npm install @webxr-input-profiles/assets)');
}

/** The perception networks' folder: --models DIR as given, else web/models, converted from
 *  @mediapipe/hands first when missing (< 1 s; into the temporary folder if web/models is not
 *  writable). */
async function modelsDir(o) {
  const names = [`palm_detection_${o.model}.onnx`, `hand_landmark_${o.model}.onnx`];
  const has = (d) => names.every((n) => existsSync(join(d, n)));
  if (o.models) {
    for (const n of names) if (!existsSync(join(o.models, n))) throw fail(`${join(o.models, n)}: missing (node web/tools/convert_mediapipe.mjs --out DIR converts the models)`);
    return o.models;
  }
  if (has(defaultModels)) return defaultModels;
  const { ensureMediapipeModels, MEDIAPIPE_HANDS_VERSION } = await import('./tools/convert_mediapipe.mjs');
  const fallback = join(tmpdir(), `hawor-models-${MEDIAPIPE_HANDS_VERSION}`);
  if (has(fallback)) return fallback;
  let lastError = null;
  for (const dir of [defaultModels, fallback]) {
    try {
      const r = ensureMediapipeModels(dir);
      process.stderr.write(`hawor: converted MediaPipe's hand networks to ONNX in ${dir} (${r.ms} ms; once)\n`);
      return dir;
    } catch (e) {
      lastError = e;
      if (!['EACCES', 'EPERM', 'EROFS'].includes(e.code)) break;
    }
  }
  throw fail(`the hand networks are missing (${defaultModels}) and could not be converted: ${lastError.message}`);
}

function progressBar(total) {
  const tty = process.stderr.isTTY;
  let lastPct = -1;
  const t0 = performance.now();
  return ({ stage, done, total: tot }) => {
    const n = tot ?? total;
    if (stage !== 'frames') {
      if (tty) process.stderr.write('\n');
      if (stage !== 'done') process.stderr.write(`hawor: ${stage}...\n`);
      return;
    }
    const ms = (performance.now() - t0) / done;
    if (tty) {
      const frac = n ? Math.min(1, done / n) : 0;
      const w = 30;
      const bar = n ? `[${'#'.repeat(Math.round(frac * w)).padEnd(w, '.')}] ` : '';
      process.stderr.write(`\r${bar}${done}${n ? `/${n}` : ''} frames, ${ms.toFixed(0)} ms/frame   `);
    } else {
      const pct = n ? Math.floor((10 * done) / n) * 10 : Math.floor(done / 50) * 50;
      if (pct !== lastPct) { lastPct = pct; process.stderr.write(`hawor: ${done}${n ? `/${n}` : ''} frames (${ms.toFixed(0)} ms/frame)\n`); }
    }
  };
}

function timingTable(timings, frames) {
  const rows = Object.entries(timings).filter(([, v]) => v > 0);
  const total = rows.filter(([k]) => k !== 'load').reduce((a, [, v]) => a + v, 0);
  const lines = ['stage          total ms   ms/frame   share'];
  for (const [k, v] of rows) {
    lines.push(`${k.padEnd(14)} ${v.toFixed(0).padStart(8)}   ${(v / frames).toFixed(1).padStart(8)}   ${k === 'load' ? '  (once)' : `${((100 * v) / total).toFixed(1).padStart(5)} %`}`);
  }
  lines.push(`${'total'.padEnd(14)} ${total.toFixed(0).padStart(8)}   ${(total / frames).toFixed(1).padStart(8)}   (without load)`);
  return lines.join('\n');
}

/** --sample: the built-in synthetic clip and, unless given, its true focal (sample.json). */
async function useSample(o) {
  const video = await builtFile('sample.webm');
  const meta = await builtFile('sample.json');
  if (!video || !meta) throw fail('the built-in sample is missing (dist/ or build/web/sample.webm + sample.json): run scripts/build_web.sh in a checkout');
  let info;
  try { info = JSON.parse(readFileSync(meta, 'utf8')); } catch (e) { throw fail(`${meta}: ${e.message}`); }
  o.video = video;
  if (o.focalPx === undefined && o.fovDeg === undefined) {
    if (!(info.fx > 0)) throw fail(`${meta}: no focal length (fx)`);
    o.focalPx = info.fx;
  }
  process.stderr.write(`hawor: the built-in sample ${video} (${info.preset ?? 'synthetic'}, focal ${o.focalPx} px)\n`);
}

export async function main(argv) {
  const o = parseArgs(argv);
  if (o.batch || o.command) return batchMain(o);
  if (o.help) { process.stdout.write(`${USAGE}\n${BATCH_USAGE}\n`); return 0; }
  if (o.sample) await useSample(o);
  if (!existsSync(o.video)) throw fail(`${o.video}: no such file`);
  const models = await modelsDir(o);
  const palm = join(models, `palm_detection_${o.model}.onnx`);
  const lm = join(models, `hand_landmark_${o.model}.onnx`);
  const depthConfig = o.depthModel ? o.depthConfig ?? o.depthModel.replace(/\.onnx$/i, '.json') : null;
  if (o.depthModel && !existsSync(o.depthModel)) throw fail(`${o.depthModel}: no such file`);
  if (o.depthModel && !existsSync(depthConfig)) throw fail(`${depthConfig}: the depth model's config is missing (give --depth-config)`);
  const info = probeVideo(o.video);
  let { width, height } = info;
  let scaleTo = info.anamorphic ? { width, height, flags: 'bicubic' } : null;
  if (width * height > MAX_PIXELS) {
    const s = 1920 / Math.max(width, height);
    scaleTo = { width: 2 * Math.round((width * s) / 2), height: 2 * Math.round((height * s) / 2) };
    process.stderr.write(`hawor: ${width}x${height} is above ${(MAX_PIXELS / 1e6).toFixed(1)} Mpx: decoding at ${scaleTo.width}x${scaleTo.height} (intrinsics refer to that size)\n`);
    ({ width, height } = scaleTo);
  }
  const hm = handModelFiles(o);
  const handModels = { left: new Uint8Array(readFileSync(hm.left)), right: new Uint8Array(readFileSync(hm.right)), leftName: hm.left, rightName: hm.right };
  let depthModel;
  if (o.depthModel) depthModel = { bytes: new Uint8Array(readFileSync(o.depthModel)), config: readFileSync(depthConfig, 'utf8') };
  const tLoad = performance.now();
  const core = await loadCore(o.core ?? process.env.HAWOR_CORE);
  const { ort, runtime, sessionOptions } = await loadOrt(o.runtime, o.threads);
  const coreLoadMs = performance.now() - tLoad;
  if (o.camera !== undefined) {
    // the lens against the frame it must cover (the core's parse and validate messages)
    try {
      cameraIntrinsics(core, width, height, { focalPx: o.focalPx, fovDeg: o.fovDeg, camera: o.camera });
    } catch (e) {
      throw usage(`--camera: ${e.message}`);
    }
  }
  const decodeTiming = { decode: 0 };
  const vfr = variableFrameTimes(o.video);
  const total = o.maxFrames ? Math.min(o.maxFrames, vfr?.times.length ?? info.frameCount ?? Infinity) : vfr?.times.length ?? info.frameCount;
  const source = { width, height, fps: vfr?.fps ?? info.fps, frameCount: Number.isFinite(total) ? total : null,
    frames: decodeFrames(o.video, width, height, scaleTo, o.maxFrames, decodeTiming, vfr?.times) };
  const cpu0 = process.cpuUsage();
  const networks = { palm: new Uint8Array(readFileSync(palm)), landmark: new Uint8Array(readFileSync(lm)) };
  const trackerFactory = o.perception === 'thread'
    ? workerTrackerFactory({ runtime, sessionOptions, threads: o.threads, ...networks, corePath: o.core ?? process.env.HAWOR_CORE }) : undefined;
  const tRun = performance.now();
  const result = await runPipeline(source, {
    core, ort, sessionOptions, models: networks, trackerFactory,
    handModels, focalPx: o.focalPx, fovDeg: o.fovDeg, camera: o.camera, readout: o.readout, refineFocal: o.refineFocal ?? true, modelKind: o.model, depthModel, threads: o.threads, infill: o.infill,
    groundScale: o.groundScale ?? true, eyeHeight: o.eyeHeight, gravityAligned: o.gravityAligned ?? true, ...(o.flowMaxSkip !== undefined ? { flow: { maxSkip: o.flowMaxSkip } } : {}),
  }, { onProgress: progressBar(source.frameCount) });
  const cpu = process.cpuUsage(cpu0);
  const pipelineLoadMs = result.timings.load;
  result.timings = { decode: decodeTiming.decode, ...result.timings, load: result.timings.load + coreLoadMs };
  if (width !== info.width) result.warnings.push(`the video (${info.width}x${info.height}) was downscaled to ${width}x${height}`);
  if (info.anamorphic) result.warnings.push(`the video's pixels are not square: it was processed as shown, at ${width}x${height}`);
  if (vfr) result.warnings.push(`the video's frame rate varies (${vfr.times.length} frames in ${vfr.times[vfr.times.length - 1].toFixed(2)} s, mostly ${vfr.fps.toFixed(2)} fps): each frame is timed by its time stamp`);
  if (vfr && result.frameCount !== Math.min(vfr.times.length, o.maxFrames || Infinity)) {
    result.warnings.push(`the video's time stamps list ${vfr.times.length} frames but ${result.frameCount} were decoded (a damaged file?): frames after a missing one may be timed a frame off`);
  }
  const tw = performance.now();
  mkdirSync(o.out, { recursive: true });
  writeFileSync(join(o.out, 'world.npz'), resultToWorldNpz(result));
  writeFileSync(join(o.out, 'hands_cam.npz'), resultToHandsCamNpz(result));
  writeFileSync(join(o.out, 'camera.tum'), resultToTum(result));
  result.timings.write = performance.now() - tw;
  writeFileSync(join(o.out, 'result.json'), resultToJson(result));
  const T = result.frameCount;
  // the wall time of decoding, processing and writing (the stages overlap with --perception thread:
  // their sum is more)
  const wallMs = performance.now() - tRun - pipelineLoadMs;
  const cpuMsPerFrame = (cpu.user + cpu.system) / 1000 / T;
  process.stderr.write(`${timingTable(result.timings, T)}\n${'wall'.padEnd(14)} ${wallMs.toFixed(0).padStart(8)}   ${(wallMs / T).toFixed(1).padStart(8)}   (without load; the stages overlap)\nCPU time of this process (all its threads, model loading included): ${cpuMsPerFrame.toFixed(1)} ms per frame\n`);
  for (const w of result.warnings) process.stderr.write(`hawor: warning: ${w}\n`);
  const count = (a) => Array.from(a).reduce((s, v) => s + (v ? 1 : 0), 0);
  const summary = {
    out: o.out, frames: T, width, height, fps: result.fps, focal: result.intrinsics.fx, focalSource: result.intrinsics.focalSource,
    camera: result.intrinsics.lens,
    focalRefined: result.intrinsics.refined, focalGuess: result.intrinsics.guessFx,
    noHands: result.noHands, leftFrames: count(result.hands.left.valid), rightFrames: count(result.hands.right.valid),
    scale: result.scale.scale, scaleMethod: result.scale.method, slamInitialised: result.slam.initialised,
    runtime, perception: o.perception ?? 'main', msPerFrame: Number((wallMs / T).toFixed(1)),
    cpuMsPerFrame: Number(cpuMsPerFrame.toFixed(1)),
  };
  process.stdout.write(`${JSON.stringify(summary)}\n`);
  return 0;
}

// Run as a program: also through npm's bin link (node_modules/.bin/hawor), hence realpath.
const invoked = (() => { try { return process.argv[1] && realpathSync(process.argv[1]); } catch { return null; } })();
if (invoked === fileURLToPath(import.meta.url)) {
  main(process.argv.slice(2)).then((c) => { process.exitCode = c; }, (e) => {
    process.stderr.write(`hawor: ${e.message}\n`);
    process.exitCode = e.exitCode ?? 1;
  });
}
