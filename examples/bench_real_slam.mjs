#!/usr/bin/env node
// bench_real_slam.mjs: the camera part of bench_real.mjs, fast enough to judge every SLAM change.
// bench_real runs each variant of the kitchen clip through the whole pipeline (perception ~200
// ms a frame); the SLAM sees only the grey frames at its resolution and the rendered hand masks.
// This benchmark records exactly those inputs once per variant (the pipeline of web/cli.mjs with
// a core whose MonoSlam writes what it is given: frames and masks as PNG, the intrinsics and
// options), then runs the native `hawor slam` on them and judges the camera as bench_real does
// (COLMAP's two segments, Sim(3) ATE in % of the segment's path, through `hawor metrics camera`).
//
//   node examples/bench_real_slam.mjs [--work DIR] [--inputs DIR] [--variants a,b] [--hawor BIN]
//        [--core hawor_core.mjs] [--jobs N] [--json OUT] [--record-only] [--rerecord]
//        [--runtime auto|native|wasm] (the networks' while recording, as `hawor run` takes it)
//        [--playback forward|reverse|both] [--passes N] [-- extra hawor slam flags]
//
// --playback    reverse: each variant's recorded inputs in reverse order (the clip played
//               backwards; a `--readout S` among the extra flags is negated, the rows being read
//               bottom to top in that clip's time), the trajectory scored back in forward order;
//               both: forward and reverse rows. The SLAM should not care which way the clip runs
//               (a different sequence of the same frames: twice the evidence for a change).
//
// --passes N    each variant played as one clip of N passes, forward and backward in turn (the
//               frame at a turning point not repeated): the wearer going back and forth over the
//               same places, N x 4 s. Every showing of a frame is scored against the same COLMAP
//               pose with one Sim(3) per segment over all passes (ATE in % of one pass's path), and
//               'scale x' is the largest over the smallest of the passes' path lengths in a
//               segment (1: every pass at one scale). No --readout (the rows' order flips at
//               each turning point). N up to 150 (10 minutes of video): the native runs' 'finish
//               s' (the SLAM's finishing passes) and 'peak MB' (the process' peak resident
//               memory) show what a long clip costs.
//
// --work DIR    bench_real's work folder (default $TMPDIR/hawor_bench_real): its variants/ and
//               colmap/reference.json are used (run bench_real.mjs --make-only once, and COLMAP
//               through a first bench_real run); nothing there is written.
// --inputs DIR  the recorded SLAM inputs (default $TMPDIR/hawor_bench_real_slam): NAME/frames/
//               NNNNNN.png (grey, the SLAM's resolution), NAME/masks/NNNNNN.png (only frames with
//               hands), NAME/slam.json (intrinsics, options, frame count). Recorded when missing
//               (or with --rerecord) with the checkout's core and networks; the runs' outputs go
//               to NAME/out/.
// The SLAM runs as the pipeline's first pass does (masks, --refine-focal, the focal prior the
// pipeline gave); the pipeline's further passes with a refined focal are not repeated (the focal
// was refined on none of the variants). --core FILE runs the WebAssembly core's MonoSlam on the
// same inputs in this process instead (the product's build; $HAWOR_CORE is used for recording
// only); the two builds differ only in the last bits of their arithmetic and give the same table
// (tests/web/slam_native_wasm.test.mjs holds them to it). `hawor metrics camera` (--hawor) scores
// both.
import { spawn, spawnSync } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, readdirSync, rmSync, symlinkSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { deflateSync, inflateSync } from 'node:zlib';

import { VARIANTS, origFrame, segmentsOf, scoreCamera, pool, passOrder, passScaleSpread } from './bench_real.mjs';
import { crc32 } from '../web/tools/npz.mjs';

const repo = resolve(dirname(fileURLToPath(import.meta.url)), '..');

// ------------------------------------------------------------------------------------ PNG (grey)
function chunk(type, data) {
  const b = Buffer.alloc(12 + data.length);
  b.writeUInt32BE(data.length, 0);
  b.write(type, 4, 'latin1');
  data.copy(b, 8);
  b.writeUInt32BE(crc32(b.subarray(4, 8 + data.length)), 8 + data.length);
  return b;
}
/** An 8-bit PNG of w x h pixels of c channels (1: grey; 3: RGB; 4: RGBA written as RGB, the
 *  SLAM's grey ignores alpha). */
export function greyPng(bytes, w, h, c = 1) {
  const oc = c === 1 ? 1 : 3;
  const raw = Buffer.alloc((w * oc + 1) * h);
  for (let y = 0; y < h; ++y) {
    const row = y * (w * oc + 1) + 1;
    if (c === oc) Buffer.from(bytes.buffer, bytes.byteOffset + y * w * c, w * c).copy(raw, row);
    else for (let x = 0; x < w; ++x) for (let k = 0; k < 3; ++k) raw[row + 3 * x + k] = bytes[(y * w + x) * c + k];
  }
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(w, 0);
  ihdr.writeUInt32BE(h, 4);
  ihdr[8] = 8; ihdr[9] = oc === 1 ? 0 : 2; ihdr[10] = 0; ihdr[11] = 0; ihdr[12] = 0;
  return Buffer.concat([Buffer.from([137, 80, 78, 71, 13, 10, 26, 10]), chunk('IHDR', ihdr), chunk('IDAT', deflateSync(raw, { level: 3 })), chunk('IEND', Buffer.alloc(0))]);
}

/** Decodes the PNGs greyPng writes (8-bit grey or RGB, filter 0 on every row): { w, h, c, data }. */
export function readOwnPng(buf) {
  const w = buf.readUInt32BE(16), h = buf.readUInt32BE(20);
  const c = buf[25] === 0 ? 1 : 3;
  const idat = [];
  for (let p = 8; p < buf.length;) {
    const n = buf.readUInt32BE(p);
    const type = buf.toString('latin1', p + 4, p + 8);
    if (type === 'IDAT') idat.push(buf.subarray(p + 8, p + 8 + n));
    p += 12 + n;
  }
  const raw = inflateSync(Buffer.concat(idat));
  const data = new Uint8Array(w * h * c);
  for (let y = 0; y < h; ++y) {
    if (raw[y * (w * c + 1)] !== 0) throw new Error('readOwnPng: a filtered row (not a PNG this benchmark wrote)');
    data.set(raw.subarray(y * (w * c + 1) + 1, (y + 1) * (w * c + 1)), y * w * c);
  }
  return { w, h, c, data };
}

// ------------------------------------------------------------------------------------ recording
/** Runs the pipeline on `file` with a core whose Pipeline records what its SLAM is given
 *  (Pipeline.observeSlamInputs) into dir: the first pass only (the focal's further passes replay
 *  the same frames inside finishCamera). */
async function record(file, dir, runtimeName) {
  const cli = await import('../web/cli.mjs');
  const { runPipeline } = await import('../web/src/pipeline/run.mjs');
  rmSync(dir, { recursive: true, force: true });
  mkdirSync(join(dir, 'frames'), { recursive: true });
  mkdirSync(join(dir, 'masks'), { recursive: true });
  const core = await cli.loadCore(process.env.HAWOR_CORE);
  const meta = { intrinsics: null, options: null, frames: 0, masks: 0 };
  const Base = core.Pipeline;
  // (embind classes cannot be extended: a constructor function that returns the observed instance)
  function Recording(opts, left, right) {
    const pipeline = new Base(opts, left, right);
    const ss = pipeline.slamSize();
    Object.assign(meta, { intrinsics: [...ss.intrinsics], width: ss.width, height: ss.height, options: pipeline.slamOptions() });
    pipeline.observeSlamInputs((frame, w, h, c, mask) => {
      const name = `${String(meta.frames).padStart(6, '0')}.png`;
      // grey at the SLAM's size; RGB(A) when the video already has it (the SLAM makes it grey)
      if (w !== meta.width || h !== meta.height || ![1, 3, 4].includes(c)) throw new Error(`bench_real_slam: a ${w}x${h}x${c} SLAM frame, expected ${meta.width}x${meta.height}`);
      writeFileSync(join(dir, 'frames', name), greyPng(frame, w, h, c));
      if (mask) { writeFileSync(join(dir, 'masks', name), greyPng(mask, w, h)); meta.masks += 1; }
      meta.frames += 1;
    });
    return pipeline;
  }
  const wrapped = new Proxy(core, { get: (t, k) => (k === 'Pipeline' ? Recording : t[k]) });
  const info = cli.probeVideo(file);
  const models = join(repo, 'web', 'models');
  const hm = cli.handModelFiles({});
  // the networks on the runtime `hawor run --runtime` would pick (their decisions downstream can
  // differ between runtimes: docs/benchmarks.md)
  const { ort, runtime, sessionOptions } = await cli.loadOrt(runtimeName, 2);
  const source = { width: info.width, height: info.height, fps: info.fps, frameCount: info.frameCount,
    frames: cli.decodeFrames(file, info.width, info.height, null, 0, { decode: 0 }) };
  const result = await runPipeline(source, {
    core: wrapped, ort, sessionOptions, models: { palm: new Uint8Array(readFileSync(join(models, 'palm_detection_lite.onnx'))), landmark: new Uint8Array(readFileSync(join(models, 'hand_landmark_lite.onnx'))) },
    handModels: { left: new Uint8Array(readFileSync(hm.left)), right: new Uint8Array(readFileSync(hm.right)), leftName: hm.left, rightName: hm.right },
    refineFocal: true, modelKind: 'lite', threads: 2, groundScale: true,
  });
  if (meta.frames === 0 || meta.frames !== result.frameCount) throw new Error(`bench_real_slam: ${file}: the SLAM was given ${meta.frames} of ${result.frameCount} frames (is the core's Pipeline the one observed?)`);
  meta.fps = info.fps;
  meta.runtime = runtime;
  meta.pipelineCamera = { status: Array.from(result.camera.status) };
  writeFileSync(join(dir, 'slam.json'), JSON.stringify(meta));
  return meta;
}

// ------------------------------------------------------------------------------------ runs
function readTum(text) {
  return text.trim().split('\n').filter((l) => l && !l.startsWith('#')).map((l) => l.trim().split(/\s+/).map(Number));
}

/** The recorded inputs in reverse order, as links in DIR/reversed/{frames,masks}: frame i is
 *  frame n-1-i (made once). */
function reversedInputs(dir, meta) {
  const rdir = join(dir, 'reversed');
  if (existsSync(join(rdir, 'done'))) return rdir;
  rmSync(rdir, { recursive: true, force: true });
  for (const sub of ['frames', 'masks']) {
    mkdirSync(join(rdir, sub), { recursive: true });
    for (let i = 0; i < meta.frames; ++i) {
      const src = join(dir, sub, `${String(meta.frames - 1 - i).padStart(6, '0')}.png`);
      if (existsSync(src)) symlinkSync(resolve(src), join(rdir, sub, `${String(i).padStart(6, '0')}.png`));
    }
  }
  writeFileSync(join(rdir, 'done'), '');
  return rdir;
}

/** The recorded inputs as a clip of `passes` passes (passOrder), as links in DIR/passes_N/. */
function passesInputs(dir, meta, passes) {
  const pdir = join(dir, `passes_${passes}`);
  if (existsSync(join(pdir, 'done'))) return pdir;
  rmSync(pdir, { recursive: true, force: true });
  const { order } = passOrder(meta.frames, passes);
  for (const sub of ['frames', 'masks']) {
    mkdirSync(join(pdir, sub), { recursive: true });
    order.forEach((r, i) => {
      const src = join(dir, sub, `${String(r).padStart(6, '0')}.png`);
      if (existsSync(src)) symlinkSync(resolve(src), join(pdir, sub, `${String(i).padStart(6, '0')}.png`));
    });
  }
  writeFileSync(join(pdir, 'done'), '');
  return pdir;
}

/** The extra flags for a reversed run: --readout negated. */
function reversedFlags(extra) {
  return extra.map((a, i) => (i > 0 && extra[i - 1] === '--readout' ? String(-Number(a)) : a.startsWith('--readout=') ? `--readout=${-Number(a.slice(10))}` : a));
}

/** A reversed run's out/ files (camera.tum, stats.json) put back in forward frame order. */
function unreverseOutputs(out, fps) {
  const rows = readTum(readFileSync(join(out, 'camera.tum'), 'utf8')).reverse();
  writeFileSync(join(out, 'camera.tum'), rows.map((r, i) => [i / fps, ...r.slice(1)].join(' ')).join('\n') + '\n');
  const stats = JSON.parse(readFileSync(join(out, 'stats.json'), 'utf8'));
  if (stats.status) stats.status.reverse();
  if (stats.per_frame) stats.per_frame.reverse();
  writeFileSync(join(out, 'stats.json'), JSON.stringify(stats));
}

function runSlam(o, dir, meta, extra, reversed = false, passes = 0) {
  return new Promise((res) => {
    const out = join(dir, passes ? `out_passes_${passes}` : reversed ? 'out_reversed' : 'out');
    const src = passes ? passesInputs(dir, meta, passes) : reversed ? reversedInputs(dir, meta) : dir;
    rmSync(out, { recursive: true, force: true });
    mkdirSync(out, { recursive: true });
    const args = ['slam', '--images', join(src, 'frames'), '--masks', join(src, 'masks'), '--intrinsics', meta.intrinsics.join(','),
      '--out', join(out, 'camera.tum'), '--stats', join(out, 'stats.json'), '--fps', String(meta.fps ?? 30)];
    if (meta.options?.refineFocal) args.push('--refine-focal', '--focal-prior', String(meta.options.focalPriorSigma ?? 0.3));
    args.push(...(reversed ? reversedFlags(extra) : extra));
    const p = spawn('nice', ['-n', '10', o.hawor, ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
    let stdout = '';
    let stderr = '';
    p.stdout.on('data', (d) => { stdout += d; });
    p.stderr.on('data', (d) => { stderr += d; });
    p.on('close', (code) => {
      writeFileSync(join(out, 'slam.log'), stderr);
      let summary = null;
      try { summary = JSON.parse(stdout.trim().split('\n').pop()); } catch { summary = null; }
      if (code === 0 && reversed) unreverseOutputs(out, meta.fps ?? 30);
      res({ code, summary, stderrTail: stderr.trim().split('\n').slice(-3).join('\n') });
    });
  });
}

/** The same run through the WebAssembly core's MonoSlam (the product's build) in this process:
 *  { code, summary, tum rows, status }. */
async function runSlamWasm(o, dir, meta, reversed = false, passes = 0) {
  const { loadCore } = await import('../web/src/core.mjs');
  const core = await loadCore({ path: o.core });
  const out = join(dir, passes ? `out_passes_${passes}` : reversed ? 'out_reversed' : 'out');
  rmSync(out, { recursive: true, force: true });
  mkdirSync(out, { recursive: true });
  const order = passes ? passOrder(meta.frames, passes).order : Array.from({ length: meta.frames }, (_, j) => (reversed ? meta.frames - 1 - j : j));
  const options = { ...meta.options };
  // the extra flags `--set NAME=VALUE,...` (repeatable) and `--verbose` (the log on stderr), as hawor slam takes them
  const sets = o.extra.flatMap((a, i) => (o.extra[i - 1] === '--set' ? [a] : a.startsWith('--set=') ? [a.slice(6)] : []));
  if (sets.length) options.set = sets.join(',');
  if (o.extra.includes('--verbose')) options.log = true;
  if (reversed && options.rollingShutter) options.rollingShutter = -options.rollingShutter;
  const slam = new core.MonoSlam(meta.intrinsics, meta.width, meta.height, options);
  const ms = [];
  for (const i of order) {
    const name = `${String(i).padStart(6, '0')}.png`;
    const f = readOwnPng(readFileSync(join(dir, 'frames', name)));
    const mp = join(dir, 'masks', name);
    const m = existsSync(mp) ? readOwnPng(readFileSync(mp)).data : null;
    const t0 = performance.now();
    slam.process(f.data, m);
    ms.push(performance.now() - t0);
  }
  const r = slam.finish();
  slam.delete();
  const q = core.rotationsToQuaternions(r.rotations);
  const fps = meta.fps ?? 30;
  const rows = [];
  for (let i = 0; i < order.length; ++i) rows.push([i / fps, r.translations[3 * i], r.translations[3 * i + 1], r.translations[3 * i + 2], q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]]);
  writeFileSync(join(out, 'camera.tum'), rows.map((x) => x.join(' ')).join('\n') + '\n');
  const names = ['tracked', 'interpolated', 'lost', 'relocalised'];
  writeFileSync(join(out, 'stats.json'), JSON.stringify({ status: Array.from(r.status, (s) => names[s]) }));
  if (reversed) unreverseOutputs(out, fps);
  ms.sort((a, b) => a - b);
  return { code: 0, summary: { resets: r.numResets, place_links: r.numPlaceLinks, placed_segments: r.numPlacedSegments, median_ms_per_frame: ms[Math.floor(ms.length / 2)] } };
}

const STATUS = { tracked: 0, interpolated: 1, lost: 2, relocalised: 3 };

function parse(argv) {
  const o = { work: join(tmpdir(), 'hawor_bench_real'), inputs: join(tmpdir(), 'hawor_bench_real_slam'), variants: Object.keys(VARIANTS),
    hawor: process.env.HAWOR_BIN ?? join(repo, 'build', 'native', 'examples', 'hawor'), jobs: 1, extra: [], playback: 'forward', runtime: 'auto' };
  const k = argv.indexOf('--');
  if (k >= 0) { o.extra = argv.slice(k + 1); argv = argv.slice(0, k); }
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    const v = () => { if (i + 1 >= argv.length) throw new Error(`${a} needs a value`); return argv[++i]; };
    if (a === '--work') o.work = v();
    else if (a === '--inputs') o.inputs = v();
    else if (a === '--variants') o.variants = v().split(',').filter(Boolean);
    else if (a === '--hawor') o.hawor = v();
    else if (a === '--core') o.core = resolve(v());
    else if (a === '--jobs') o.jobs = Number(v());
    else if (a === '--json') o.json = v();
    else if (a === '--record-only') o.recordOnly = true;
    else if (a === '--rerecord') o.rerecord = true;
    else if (a === '--runtime') { o.runtime = v(); if (!['auto', 'native', 'wasm'].includes(o.runtime)) throw new Error(`--runtime must be auto, native or wasm, not '${o.runtime}'`); }
    else if (a === '--passes') { o.passes = Number(v()); if (!Number.isInteger(o.passes) || o.passes < 2 || o.passes > 150) throw new Error(`--passes must be an integer from 2 to 150, not '${argv[i]}'`); }
    else if (a === '--playback') { o.playback = v(); if (!['forward', 'reverse', 'both'].includes(o.playback)) throw new Error(`--playback must be forward, reverse or both, not '${o.playback}'`); }
    else throw new Error(`unknown argument '${a}'`);
  }
  if (o.passes && o.extra.some((a) => a.startsWith('--readout'))) throw new Error('--passes cannot take --readout: the rows\' order flips at every turning point');
  for (const n of o.variants) if (!VARIANTS[n]) throw new Error(`unknown variant '${n}' (known: ${Object.keys(VARIANTS).join(', ')})`);
  return o;
}

const f2 = (x, d = 2) => (x === null || x === undefined || !Number.isFinite(x) ? '-' : x.toFixed(d));

async function main(argv) {
  const o = parse(argv);
  const video = process.env.HAWOR_CLIP ?? resolve(repo, '..', 'shared', 'data', 'egocentric_kitchen.mp4');
  const refFile = join(o.work, 'colmap', 'reference.json');
  if (!existsSync(refFile)) throw new Error(`${refFile}: missing (run examples/bench_real.mjs once: it makes COLMAP's reference)`);
  const segs = segmentsOf(JSON.parse(readFileSync(refFile, 'utf8')));
  const n0 = 121;
  for (const n of o.variants) {
    const dir = join(o.inputs, n);
    // (a slam.json without intrinsics is an incomplete recording: recorded again)
    if (existsSync(join(dir, 'slam.json')) && JSON.parse(readFileSync(join(dir, 'slam.json'), 'utf8')).intrinsics && !o.rerecord) continue;
    const file = VARIANTS[n].vf ? join(o.work, 'variants', `${n}.mp4`) : video;
    if (!existsSync(file)) throw new Error(`${file}: missing (node examples/bench_real.mjs --make-only)`);
    process.stderr.write(`bench_real_slam: recording the SLAM inputs of ${n}...\n`);
    const t0 = performance.now();
    const m = await record(file, dir, o.runtime);
    process.stderr.write(`bench_real_slam: ${n}: ${m.frames} frames ${m.width}x${m.height}, ${m.masks} masks, networks on ${m.runtime} (${((performance.now() - t0) / 1000).toFixed(0)} s)\n`);
  }
  if (o.recordOnly) return 0;
  if (!existsSync(o.hawor)) throw new Error(`${o.hawor}: missing (cmake --build DIR --target hawor_cli)`);
  const dirs = o.passes ? [false] : { forward: [false], reverse: [true], both: [false, true] }[o.playback];
  const jobs = o.variants.flatMap((n) => dirs.map((reversed) => ({ n, reversed })));
  const rows = await pool(jobs, o.jobs, async ({ n, reversed }) => {
    const v = VARIANTS[n];
    const dir = join(o.inputs, n);
    const out = join(dir, o.passes ? `out_passes_${o.passes}` : reversed ? 'out_reversed' : 'out');
    const name = o.passes ? `${n} (x${o.passes})` : reversed ? `${n} (rev)` : n;
    const meta = JSON.parse(readFileSync(join(dir, 'slam.json'), 'utf8'));
    const run = o.core ? await runSlamWasm(o, dir, meta, reversed, o.passes ?? 0) : await runSlam(o, dir, meta, o.extra, reversed, o.passes ?? 0);
    if (run.code !== 0) return { name, reversed, error: `exit ${run.code}: ${run.stderrTail}` };
    const stats = JSON.parse(readFileSync(join(out, 'stats.json'), 'utf8'));
    const tum = readTum(readFileSync(join(out, 'camera.tum'), 'utf8'));
    const T = tum.length;
    const positions = new Float64Array(3 * T);
    const quaternions = new Float64Array(4 * T);
    tum.forEach((r, i) => { positions.set(r.slice(1, 4), 3 * i); quaternions.set(r.slice(4, 8), 4 * i); });
    const st = stats.per_frame ? stats.per_frame.map((f) => STATUS[f.status] ?? 1) : (stats.status ?? []).map((s) => STATUS[s] ?? 1);
    const res = { frameCount: T, camera: { positions, quaternions, status: st } };
    const passes = o.passes ? passOrder(meta.frames, o.passes) : null;
    const camera = scoreCamera(res, v, segs, n0, out, o.hawor, passes?.order);
    if (passes) {
      const spread = passScaleSpread(positions, passes.order, passes.pass, v, segs, n0);
      for (const s of segs) if (camera[s.name]) camera[s.name].scaleSpread = spread[s.name];
    }
    // the run's first tracked frame (for a reversed run: the last in forward order)
    const tracked = st.map((s, i) => (s === 0 || s === 3 ? i : -1)).filter((i) => i >= 0);
    const firstTracked = tracked.length ? (reversed ? tracked[tracked.length - 1] : tracked[0]) : -1;
    return { name, reversed, frames: T, camera, init: firstTracked >= 0 ? origFrame(v, passes ? passes.order[firstTracked] : firstTracked, n0) : null, lost: st.filter((s) => s === 2).length,
      interpolated: st.filter((s) => s === 1).length, resets: run.summary?.resets, links: run.summary?.place_links, placed: run.summary?.placed_segments, msMedian: run.summary?.median_ms_per_frame,
      finishS: run.summary?.finish_ms / 1000, peakMb: run.summary?.peak_rss_mb, status: st.join('') };
  });
  const names = segs.map((s) => s.name);
  const head = ['variant', 'frames', ...names.map((s) => `ATE % ${s}`), ...names.map((s) => `rot ° ${s}`), ...(o.passes ? names.map((s) => `scale x ${s}`) : []), 'init', 'lost', 'interp', 'resets', 'links', 'placed', 'ms/frame', 'finish s', 'peak MB'];
  const lines = [head];
  for (const r of rows) {
    if (r.error) { lines.push([r.name, `error: ${r.error}`]); continue; }
    lines.push([r.name, String(r.frames), ...names.map((s) => (r.camera[s]?.held ? `held ${f2(r.camera[s].atePct, 0)}` : f2(r.camera[s]?.atePct))),
      ...names.map((s) => f2(r.camera[s]?.rot_mean_deg, 1)), ...(o.passes ? names.map((s) => f2(r.camera[s]?.scaleSpread)) : []), String(r.init ?? '-'), String(r.lost), String(r.interpolated), String(r.resets ?? '-'), String(r.links ?? '-'), String(r.placed ?? '-'), f2(r.msMedian, 1), f2(r.finishS, 1), f2(r.peakMb, 0)]);
  }
  const w = head.map((_, c) => Math.max(...lines.map((l) => (l[c] ?? '').length)));
  process.stdout.write(`${lines.map((l) => l.map((x, c) => (c === 0 ? (x ?? '').padEnd(w[c]) : (x ?? '').padStart(w[c]))).join('  ')).join('\n')}\n`);
  for (const reversed of dirs) {
    const these = rows.filter((r) => r.reversed === reversed);
    const within = these.filter((r) => !r.error && names.every((s) => r.camera[s]?.atePct <= 2)).length;
    process.stdout.write(`variants with ATE <= 2 % on every segment${dirs.length > 1 ? (reversed ? ', played backwards' : ', forwards') : ''}: ${within}/${these.length}\n`);
  }
  if (o.json) writeFileSync(o.json, `${JSON.stringify({ segments: segs.map((s) => ({ ...s, poses: undefined })), variants: rows }, null, 1)}\n`);
  return 0;
}

if (process.argv[1] && fileURLToPath(import.meta.url) === resolve(process.argv[1])) {
  main(process.argv.slice(2)).then((c) => { process.exitCode = c; }, (e) => {
    process.stderr.write(`bench_real_slam: ${e.stack ?? e.message}\n`);
    process.exitCode = 1;
  });
}
