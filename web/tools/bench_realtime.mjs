#!/usr/bin/env node
// bench_realtime.mjs — speed side by side on the same decoded frames: hawor's whole pipeline in
// headless Chromium, MediaPipe's own web runtime doing only its keypoints in the same browser,
// and the headless node CLI. One JSON object on stdout (and in --json FILE), a table on stderr.
//
//   node web/tools/bench_realtime.mjs VIDEO [--max-side 960] [--frames N] [--runs 3] [--threads 2]
//        [--model lite|full] [--warmup 5] [--no-cli] [--webgl-check N] [--timeout-s S] [--json FILE]
//
// The video is decoded once by ffmpeg (web/cli.mjs's probeVideo and decodeFrames, scaled with
// its 'area' filter to --max-side on the long side) into RGB frames, which are also written
// uncompressed (rawvideo rgb24 in NUT: the same bytes, nothing to decode) in a temporary folder
// for the CLI: the page's frames are decoded before its clock starts, and so, in effect, are the
// CLI's (a lossless codec's decoding, FFV1's 14 ms of CPU a frame at 960 px, would share the two
// cores with the pipeline: a cost of the benchmark's own intermediate file, not of users' clips). One Chromium (launched as web/tools/bench_app.mjs does) loads a blank page from
// web/server.mjs's createServer (cross-origin isolated: onnxruntime-web's threads) plus this
// tool's own routes (/bench/: the page, its worker, the frames, @mediapipe/hands); the page and
// its worker each fetch the raw frames once before any timing. Then, --runs rounds of:
//   hawor-browser      runPipeline (web/src/pipeline/run.mjs) in a Web Worker as the app runs it
//                      (web/app/worker.mjs: the core from /dist/, onnxruntime-web with
//                      numThreads = --threads (the app's default is cores - 1), the --model
//                      networks, the app's default hand (the WebXR glTF hands), its 64 MB for the
//                      focal re-runs); RGB frames handed over as views of the fetched buffer.
//                      Per frame: the time between two frame requests of the pipeline (the frame's
//                      whole processing); also onFrame's `ms`, the load before the first frame, the
//                      finishing stages after the last, wall, and result.timings per stage.
//   mediapipe-browser  @mediapipe/hands (the legacy solution API, hands.js) in the page's main
//                      thread, tracking mode (a fresh `Hands` per run, frames sent in order):
//                      maxNumHands 2, modelComplexity 0 (lite) / 1 (full), confidences 0.5,
//                      selfieMode false, useCpuInference true. Per frame: `await hands.send()` on
//                      a canvas already holding the frame (the RGB -> canvas copy is not timed).
//   hawor-node         unless --no-cli: `node web/cli.mjs run FRAMES.nut --out TMP --threads T
//                      --model M` (HAWOR_HAND_DIR = the same WebXR hands), its printed msPerFrame
//                      ((wall - load) / frames, decoding and writing included) and stage table.
// Per-frame statistics (median, nearest-rank p95, mean; hands found per frame) skip the first
// --warmup frames (default 5); the summary takes the median over the runs of each figure, and
// the ratio hawor-browser / mediapipe-browser of the medians (and of the means). Each run also
// records the load average and, from /proc (Linux), the share of all CPUs' time that other
// processes took meanwhile. --webgl-check N adds, after the rounds, two MediaPipe runs on N frames,
// useCpuInference false (its WebGL inference path; in headless Chromium a software renderer)
// then true, and whether the runtime logged TensorFlow Lite's XNNPACK (CPU) delegate in each.
// --timeout-s: the limit of one run (default 120 s + 5 s per frame).
// Exit codes: 2 missing input, unreadable video or missing build output/package/browser (one
// line naming it and how to get it), 1 a failure while measuring (a timeout names the wait).
import { spawn } from 'node:child_process';
import { existsSync, mkdtempSync, readdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import http from 'node:http';
import { loadavg, tmpdir } from 'node:os';
import { dirname, extname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { probeVideo, decodeFrames } from '../cli.mjs';
import { createServer, isolationHeaders, MIME, packageRoot } from '../server.mjs';
import { builtFile } from '../src/core.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const CLI = join(root, 'web/cli.mjs');
const USAGE = 'usage: node web/tools/bench_realtime.mjs VIDEO [--max-side 960] [--frames N] [--runs 3] [--threads 2] [--model lite|full] [--warmup 5] [--no-cli] [--webgl-check N] [--timeout-s S] [--json FILE]';
const FLAGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync'];
/// The CLI's stages that run once for the clip (run.mjs's header); the others run per frame.
const ONCE_STAGES = ['load', 'write', 'slamFinish', 'depth', 'scale', 'world', 'infill', 'joints'];

const setupError = (msg) => Object.assign(new Error(msg), { exitCode: 2 });

function parseArgs(argv) {
  const o = { maxSide: 960, frames: 0, runs: 3, threads: 2, model: 'lite', warmup: 5, cli: true, webglCheck: 0, timeoutS: 0, json: null };
  const int = (v, name, min) => {
    const n = Number(v);
    if (!Number.isInteger(n) || n < min) throw setupError(`${name} must be an integer >= ${min}, not '${v}'\n${USAGE}`);
    return n;
  };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    const next = () => { if (i + 1 >= argv.length) throw setupError(`${a} needs a value\n${USAGE}`); return argv[++i]; };
    if (a === '--max-side') o.maxSide = int(next(), a, 16);
    else if (a === '--frames') o.frames = int(next(), a, 1);
    else if (a === '--runs') o.runs = int(next(), a, 1);
    else if (a === '--threads') o.threads = int(next(), a, 1);
    else if (a === '--model') { o.model = next(); if (!['lite', 'full'].includes(o.model)) throw setupError(`--model must be lite or full, not '${o.model}'`); }
    else if (a === '--warmup') o.warmup = int(next(), a, 0);
    else if (a === '--no-cli') o.cli = false;
    else if (a === '--webgl-check') o.webglCheck = int(next(), a, 0);
    else if (a === '--timeout-s') o.timeoutS = int(next(), a, 1);
    else if (a === '--json') o.json = next();
    else if (a === '--help' || a === '-h') { process.stdout.write(`${USAGE}\n`); process.exit(0); }
    else if (a.startsWith('--')) throw setupError(`unknown option '${a}'\n${USAGE}`);
    else if (!o.video) o.video = a;
    else throw setupError(`unexpected argument '${a}'\n${USAGE}`);
  }
  if (!o.video) throw setupError(`missing VIDEO\n${USAGE}`);
  return o;
}

/// Everything the measurement needs, checked before any work: a one-line message naming the
/// first missing piece and how to get it (exit code 2).
async function checkSetup(o) {
  if (!existsSync(o.video)) throw setupError(`${o.video}: no such file`);
  const core = await builtFile('hawor_core.mjs');
  if (!core || !existsSync(join(dirname(core), 'hawor_core.wasm'))) {
    throw setupError('the WebAssembly core (build/wasm/wasm/hawor_core.mjs + .wasm) is missing: run scripts/build_web.sh');
  }
  for (const m of [`palm_detection_${o.model}`, `hand_landmark_${o.model}`]) {
    if (!existsSync(join(root, 'web/models', `${m}.onnx`))) throw setupError(`web/models/${m}.onnx is missing: run scripts/build_web.sh (or node web/tools/convert_mediapipe.mjs --out web/models)`);
  }
  const pkgs = {
    mediapipe: packageRoot(root, '@mediapipe/hands'),
    ort: packageRoot(root, 'onnxruntime-web'),
    hands: join(packageRoot(root, '@webxr-input-profiles/assets'), 'dist/profiles/generic-hand'),
  };
  const needed = [[pkgs.mediapipe, 'hands.js'], [pkgs.mediapipe, `hand_landmark_${o.model}.tflite`], [pkgs.ort, 'dist/ort.wasm.min.mjs'],
    [pkgs.hands, 'left.glb'], [pkgs.hands, 'right.glb']];
  for (const [d, f] of needed) if (!existsSync(join(d, f))) throw setupError(`${join(d, f)} is missing: run npm install (scripts/install.sh)`);
  try { await import('playwright-core'); } catch { throw setupError('npm playwright-core is missing: run npm install (scripts/install.sh)'); }
  const chromium = process.env.HAWOR_CHROMIUM || '/usr/bin/chromium';
  if (!existsSync(chromium)) throw setupError(`${chromium} not found: apt-get install chromium (scripts/install.sh), or set HAWOR_CHROMIUM`);
  return { ...pkgs, chromium };
}

// --- statistics ----------------------------------------------------------------------------------

const sorted = (a) => Float64Array.from(a).sort();
function median(a) {
  if (!a.length) return NaN;
  const s = sorted(a), m = s.length >> 1;
  return s.length % 2 ? s[m] : 0.5 * (s[m - 1] + s[m]);
}
/// Nearest-rank percentile.
function percentile(a, p) {
  if (!a.length) return NaN;
  const s = sorted(a);
  return s[Math.min(s.length - 1, Math.max(0, Math.ceil((p / 100) * s.length) - 1))];
}
const r1 = (x) => (Number.isFinite(x) ? Math.round(10 * x) / 10 : null);
const r2 = (x) => (Number.isFinite(x) ? Math.round(100 * x) / 100 : null);
const mean = (a) => (a.length ? a.reduce((s, v) => s + v, 0) / a.length : NaN);
const load = () => loadavg().map(r2);

function frameStats(ms, hands, warmup) {
  const kept = ms.slice(warmup);
  return { medianMs: r1(median(kept)), p95Ms: r1(percentile(kept, 95)), meanMs: r1(mean(kept)), handsPerFrame: r2(mean(hands)) };
}

/// CPU time (clock ticks) of the whole machine (/proc/stat: busy, steal, total over all CPUs) and
/// of this process's tree (itself, the browser's processes, the CLI; children it reaped
/// included), or null off Linux. Between two snapshots, `other` is the share of all CPUs' time
/// that other processes took: the competition a run had, which the load average only hints at.
function cpuSnapshot() {
  try {
    const f = readFileSync('/proc/stat', 'utf8').split('\n')[0].trim().split(/\s+/).slice(1).map(Number);
    const [user, nice, system, idle, iowait, irq, softirq, steal] = f;
    const kids = new Map(), ticks = new Map();
    for (const d of readdirSync('/proc')) {
      if (!/^\d+$/.test(d)) continue;
      try {
        const st = readFileSync(`/proc/${d}/stat`, 'utf8');
        const v = st.slice(st.lastIndexOf(')') + 2).split(' ');
        const ppid = Number(v[1]);
        if (!kids.has(ppid)) kids.set(ppid, []);
        kids.get(ppid).push(Number(d));
        ticks.set(Number(d), Number(v[11]) + Number(v[12]) + Number(v[13]) + Number(v[14]));
      } catch { /* exited */ }
    }
    let tree = 0;
    for (const stack = [process.pid]; stack.length;) {
      const p = stack.pop();
      tree += ticks.get(p) ?? 0;
      stack.push(...(kids.get(p) ?? []));
    }
    return { busy: user + nice + system + irq + softirq, steal, total: user + nice + system + idle + iowait + irq + softirq + steal, tree };
  } catch {
    return null;
  }
}
/// Percent of all CPUs' time between two snapshots: taken by other processes, and stolen by the
/// hypervisor.
function competition(a, b) {
  if (!a || !b || !(b.total > a.total)) return { otherCpuPct: null, stealPct: null };
  const t = b.total - a.total;
  return { otherCpuPct: r1(Math.max(0, (100 * (b.busy - a.busy - (b.tree - a.tree))) / t)), stealPct: r1((100 * (b.steal - a.steal)) / t) };
}

/// Whether MediaPipe's runtime logged creating TensorFlow Lite's XNNPACK (CPU) delegate among
/// the console lines from..to: its inference then runs on the CPU, not in WebGL.
const xnnpack = (lines, from, to = lines.length) => lines.slice(from, to).some((l) => /XNNPACK delegate for CPU/.test(l));

/// A promise that rejects after `s` seconds with a message naming what was awaited.
function within(promise, s, what) {
  let timer;
  return Promise.race([promise, new Promise((_, rej) => { timer = setTimeout(() => rej(new Error(`timed out after ${s} s: ${what}`)), s * 1000); })])
    .finally(() => clearTimeout(timer));
}

// --- frames --------------------------------------------------------------------------------------

/// The video's frames as RGB (long side at most maxSide, ffmpeg's area filter, even sizes as the
/// CLI scales), in one buffer, and the same frames as an uncompressed video for the CLI.
async function decode(o, tmp) {
  let info;
  try { info = probeVideo(o.video); } catch (e) { throw setupError(e.message); }
  const s = Math.min(1, o.maxSide / Math.max(info.width, info.height));
  const scaleTo = s < 1 ? { width: 2 * Math.round((info.width * s) / 2), height: 2 * Math.round((info.height * s) / 2) } : null;
  const width = scaleTo ? scaleTo.width : info.width, height = scaleTo ? scaleTo.height : info.height;
  const timing = { decode: 0 };
  const chunks = [];
  try {
    for await (const f of decodeFrames(o.video, width, height, scaleTo, o.frames || undefined, timing)) chunks.push(f.rgba);
  } catch (e) {
    throw setupError(`${o.video}: ffmpeg cannot decode it (${e.message})`);
  }
  if (!chunks.length) throw setupError(`${o.video}: ffmpeg decoded no frame`);
  const frames = Buffer.concat(chunks);
  const cliVideo = join(tmp, `frames_${width}x${height}.nut`);
  if (o.cli) {
    await new Promise((res, rej) => {
      const ff = spawn('ffmpeg', ['-v', 'error', '-y', '-f', 'rawvideo', '-pix_fmt', 'rgb24', '-s', `${width}x${height}`, '-r', String(info.fps), '-i', '-',
        '-c:v', 'rawvideo', '-pix_fmt', 'rgb24', cliVideo], { stdio: ['pipe', 'ignore', 'pipe'] });
      let err = '';
      ff.stderr.on('data', (d) => { err += d; });
      ff.on('error', rej);
      ff.on('close', (code) => (code === 0 ? res() : rej(new Error(`ffmpeg (writing ${cliVideo}): ${err.trim().split('\n').pop()}`))));
      ff.stdin.end(frames);
    });
  }
  return { info, width, height, count: chunks.length, frames, cliVideo, decodeMs: timing.decode };
}

// --- the page and its worker (served at /bench/) -------------------------------------------------

const PAGE = `<!doctype html><html><head><meta charset="utf-8"><link rel="icon" href="data:,"><title>hawor bench_realtime</title>
<script src="/bench/mediapipe/hands.js"></script></head><body>bench_realtime</body></html>`;

/// The worker: as web/app/worker.mjs loads the core, onnxruntime-web, the networks and the
/// hands, then runs runPipeline on the fetched frames (views, in order) and answers timings.
const WORKER = `import { loadCore } from '/web/src/core.mjs';
import { runPipeline } from '/web/src/pipeline/run.mjs';
let ort, core, models, hands, frames, meta;
const bytes = async (url) => { const r = await fetch(url); if (!r.ok) throw new Error(url + ': HTTP ' + r.status); return new Uint8Array(await r.arrayBuffer()); };
async function init(m) {
  const t0 = performance.now();
  meta = m.meta;
  [core, ort] = await Promise.all([loadCore(), import(m.ortUrl)]);
  ort.env.wasm.wasmPaths = new URL('./', m.ortUrl).href;
  ort.env.logLevel = 'error';
  ort.env.wasm.numThreads = m.threads;
  const [palm, landmark, left, right, buf] = await Promise.all([bytes(m.palmUrl), bytes(m.landmarkUrl), bytes(m.leftUrl), bytes(m.rightUrl),
    fetch('/bench/frames.bin').then((r) => r.arrayBuffer())]);
  models = { palm, landmark };
  hands = { left, right, leftName: 'left.glb', rightName: 'right.glb' };
  frames = buf;
  if (frames.byteLength !== meta.width * meta.height * 3 * meta.count) throw new Error('frames.bin: ' + frames.byteLength + ' bytes');
  return { ms: performance.now() - t0, crossOriginIsolated: self.crossOriginIsolated, cores: navigator.hardwareConcurrency };
}
async function run(m) {
  const { width, height, count, fps } = meta;
  const size = width * height * 3;
  const requests = [];
  const source = { width, height, fps, frameCount: count, frames: { [Symbol.asyncIterator]() {
    let i = 0;
    return { next() {
      requests.push(performance.now());
      if (i >= count) return Promise.resolve({ value: undefined, done: true });
      const f = { index: i, rgba: new Uint8Array(frames, i * size, size) };
      i += 1;
      return Promise.resolve({ value: f, done: false });
    } };
  } } };
  const onFrame = [];
  const t0 = performance.now();
  const result = await runPipeline(source, { core, ort, models, handModels: hands, modelKind: m.model, threads: m.threads, focalRerunBytes: 64 * 1024 * 1024 },
    { onFrame: (info) => onFrame.push({ ms: info.ms, hands: info.hands.length, valid: info.hands.filter((h) => h.valid).length, slamStatus: info.slamStatus }) });
  const t1 = performance.now();
  const valid = (h) => Array.from(h.valid).reduce((s, v) => s + (v ? 1 : 0), 0);
  return { wallMs: t1 - t0, loadMs: requests[0] - t0, finishMs: t1 - requests[requests.length - 1],
    frameMs: requests.slice(1).map((t, i) => t - requests[i]), onFrame, timings: result.timings, stats: result.stats,
    frameCount: result.frameCount, threads: result.threads, noHands: result.noHands, slamInitialised: result.slam.initialised,
    leftFrames: valid(result.hands.left), rightFrames: valid(result.hands.right), warnings: result.warnings };
}
self.onmessage = async (ev) => {
  const m = ev.data;
  try {
    if (m.type === 'init') self.postMessage({ type: 'ready', info: await init(m) });
    else if (m.type === 'run') self.postMessage({ type: 'result', result: await run(m) });
  } catch (e) { self.postMessage({ type: 'error', message: String(e && e.stack || e) }); }
};
`;

/// Page-side helpers, installed once (page.evaluate of this function's text).
function pageSetup() {
  const bench = (window.bench = {});
  bench.worker = null;
  bench.ask = (msg) => new Promise((res, rej) => {
    bench.worker.onmessage = (ev) => (ev.data.type === 'error' ? rej(new Error(ev.data.message)) : res(ev.data));
    bench.worker.onerror = (e) => rej(new Error(`worker: ${e.message}`));
    bench.worker.postMessage(msg);
  });
  bench.init = async (m) => {
    const t0 = performance.now();
    bench.worker = new Worker('/bench/worker.mjs', { type: 'module' });
    const [ready, buf] = await Promise.all([bench.ask({ type: 'init', ...m }), fetch('/bench/frames.bin').then((r) => r.arrayBuffer())]);
    bench.meta = m.meta;
    bench.rgb = new Uint8Array(buf);
    const { width, height } = m.meta;
    bench.canvas = document.createElement('canvas');
    bench.canvas.width = width;
    bench.canvas.height = height;
    bench.ctx = bench.canvas.getContext('2d');
    bench.image = bench.ctx.createImageData(width, height);
    return { ...ready.info, pageMs: performance.now() - t0, pageIsolated: self.crossOriginIsolated, typeofHands: typeof window.Hands };
  };
  bench.hawor = async (m) => (await bench.ask({ type: 'run', ...m })).result;
  // MediaPipe's legacy solution: a fresh Hands per run, the frames in order (its tracking mode).
  bench.mediapipe = async ({ count, complexity, cpu }) => {
    const { width, height } = bench.meta;
    const size = width * height * 3;
    const hands = new window.Hands({ locateFile: (f) => `/bench/mediapipe/${f}` });
    hands.setOptions({ maxNumHands: 2, modelComplexity: complexity, minDetectionConfidence: 0.5, minTrackingConfidence: 0.5, selfieMode: false, useCpuInference: cpu });
    let results = 0, found = 0;
    hands.onResults((r) => { results += 1; found = r.multiHandLandmarks ? r.multiHandLandmarks.length : 0; });
    const t0 = performance.now();
    await hands.initialize();
    const initMs = performance.now() - t0;
    const frameMs = [], handsPer = [];
    const px = bench.image.data;
    for (let i = 0; i < count; ++i) {
      const src = bench.rgb.subarray(i * size, (i + 1) * size);
      for (let p = 0, q = 0; p < size; p += 3, q += 4) { px[q] = src[p]; px[q + 1] = src[p + 1]; px[q + 2] = src[p + 2]; px[q + 3] = 255; }
      bench.ctx.putImageData(bench.image, 0, 0);
      const before = results;
      found = 0;
      const ts = performance.now();
      await hands.send({ image: bench.canvas });
      frameMs.push(performance.now() - ts);
      if (results !== before + 1) throw new Error(`frame ${i}: ${results - before} results for one send`);
      handsPer.push(found);
    }
    await hands.close();
    return { initMs, frameMs, hands: handsPer };
  };
}

function serve(o, decoded, pkgs) {
  const base = createServer(root).listeners('request')[0];
  const frameBytes = decoded.frames;
  const send = (res, status, type, body) => {
    res.writeHead(status, { 'Content-Type': type, 'Cache-Control': 'no-cache', 'Content-Length': Buffer.byteLength(body), ...isolationHeaders() });
    res.end(body);
  };
  return http.createServer((req, res) => {
    const p = new URL(req.url, 'http://x').pathname;
    if (!p.startsWith('/bench/')) return base(req, res);
    if (p === '/bench/' || p === '/bench/index.html') return send(res, 200, MIME['.html'], PAGE);
    if (p === '/bench/worker.mjs') return send(res, 200, MIME['.mjs'], WORKER);
    if (p === '/bench/frames.bin') return send(res, 200, 'application/octet-stream', frameBytes);
    const m = /^\/bench\/mediapipe\/([\w.-]+)$/.exec(p);
    if (m && existsSync(join(pkgs.mediapipe, m[1]))) {
      return send(res, 200, MIME[extname(m[1])] || 'application/octet-stream', readFileSync(join(pkgs.mediapipe, m[1])));
    }
    return send(res, 404, 'text/plain', `not found: ${p}\n`);
  });
}

// --- the node CLI --------------------------------------------------------------------------------

function runCli(o, decoded, tmp, k, timeoutS, handDir) {
  return new Promise((res, rej) => {
    const out = join(tmp, `cli${k}`);
    const args = [CLI, 'run', decoded.cliVideo, '--out', out, '--threads', String(o.threads), '--model', o.model];
    const child = spawn(process.execPath, args, { env: { ...process.env, HAWOR_HAND_DIR: handDir }, stdio: ['ignore', 'pipe', 'pipe'] });
    let stdout = '', stderr = '';
    child.stdout.on('data', (d) => { stdout += d; });
    child.stderr.on('data', (d) => { stderr += d; });
    const timer = setTimeout(() => { child.kill(); rej(new Error(`timed out after ${timeoutS} s: node web/cli.mjs run (run ${k + 1})`)); }, timeoutS * 1000);
    child.on('error', (e) => { clearTimeout(timer); rej(e); });
    child.on('close', (code) => {
      clearTimeout(timer);
      if (code !== 0) return rej(new Error(`node web/cli.mjs run failed (exit ${code}): ${stderr.trim().split('\n').pop()}`));
      let summary;
      try { summary = JSON.parse(stdout.trim().split('\n').pop()); } catch { return rej(new Error(`node web/cli.mjs run: no JSON line (${stdout.slice(-200)})`)); }
      // Its stage table: "stage   total ms   ms/frame   share".
      const stages = {};
      for (const l of stderr.split('\n')) {
        const mm = /^(\w+)\s+(\d+)\s+([\d.]+)\s/.exec(l);
        if (mm && !['total', 'wall', 'stage'].includes(mm[1])) stages[mm[1]] = Number(mm[3]);
      }
      rmSync(out, { recursive: true, force: true });
      res({ args: ['node', 'web/cli.mjs', ...args.slice(1)], summary, stagesMsPerFrame: stages });
    });
  });
}

// --- main ----------------------------------------------------------------------------------------

async function main() {
  const o = parseArgs(process.argv.slice(2));
  const pkgs = await checkSetup(o);
  const tmp = mkdtempSync(join(tmpdir(), 'hawor-bench-rt-'));
  let context = null, server = null;
  const log = (s) => process.stderr.write(`bench_realtime: ${s}\n`);
  try {
    const loadBefore = load();
    const decoded = await decode(o, tmp);
    const { width, height, count } = decoded;
    if (count <= o.warmup) throw setupError(`only ${count} frame(s) decoded: more than --warmup (${o.warmup}) are needed`);
    log(`${count} frames at ${width}x${height} (from ${decoded.info.width}x${decoded.info.height}); load ${loadBefore.join(' ')}`);
    const runTimeout = o.timeoutS || 120 + 5 * count;

    server = serve(o, decoded, pkgs);
    await new Promise((r) => server.listen(0, '127.0.0.1', r));
    const url = `http://127.0.0.1:${server.address().port}`;
    const { chromium } = await import('playwright-core');
    const dataDir = join(tmp, 'chromium');
    context = await within(chromium.launchPersistentContext(dataDir, {
      executablePath: pkgs.chromium, headless: true, viewport: { width: 1400, height: 900 }, args: FLAGS,
    }), 60, 'launching Chromium');
    const page = context.pages()[0] || await context.newPage();
    const consoleLines = [];
    page.on('console', (m) => { if (consoleLines.length < 20000) consoleLines.push(`${m.type()}: ${m.text()}`); });
    page.on('pageerror', (e) => consoleLines.push(`pageerror: ${e.message}`));
    page.on('response', (r) => { if (r.status() >= 400) consoleLines.push(`http ${r.status()}: ${new URL(r.url()).pathname}`); });
    const resp = await within(page.goto(`${url}/bench/`), 30, 'loading the bench page');
    const headers = resp.headers();
    await page.evaluate(`(${pageSetup.toString()})()`);
    const meta = { width, height, count, fps: decoded.info.fps };
    const ready = await within(page.evaluate((m) => window.bench.init(m), {
      meta, threads: o.threads, model: o.model,
      ortUrl: `${url}/node_modules/onnxruntime-web/dist/ort.wasm.min.mjs`,
      palmUrl: `/web/models/palm_detection_${o.model}.onnx`, landmarkUrl: `/web/models/hand_landmark_${o.model}.onnx`,
      leftUrl: '/node_modules/@webxr-input-profiles/assets/dist/profiles/generic-hand/left.glb',
      rightUrl: '/node_modules/@webxr-input-profiles/assets/dist/profiles/generic-hand/right.glb',
    }), 120, 'the page and its worker loading the core, onnxruntime-web, the networks and the frames');
    if (!ready.crossOriginIsolated || !ready.pageIsolated) throw new Error('the bench page is not cross-origin isolated (onnxruntime-web would run one thread)');
    if (ready.typeofHands !== 'function') throw new Error('@mediapipe/hands did not load (window.Hands missing)');
    log(`page ready in ${Math.round(ready.pageMs)} ms (worker ${Math.round(ready.ms)} ms), cross-origin isolated, ${ready.cores} cores`);

    const complexity = o.model === 'lite' ? 0 : 1;
    const runs = { hawor: [], mediapipe: [], cli: [] };
    for (let k = 0; k < o.runs; ++k) {
      let l0 = load(), c0 = cpuSnapshot();
      const h = await within(page.evaluate((m) => window.bench.hawor(m), { threads: o.threads, model: o.model }), runTimeout, `hawor-browser run ${k + 1} (runPipeline in the worker)`);
      const hs = frameStats(h.frameMs, h.onFrame.map((f) => f.hands), o.warmup);
      const perFrame = Object.fromEntries(Object.entries(h.timings).map(([s, v]) => [s, r1(s === 'load' ? v : v / h.frameCount)]));
      runs.hawor.push({ ...hs, onFrameMedianMs: r1(median(h.onFrame.slice(o.warmup).map((f) => f.ms))),
        fittedPerFrame: r2(mean(h.onFrame.map((f) => f.valid))), loadMs: Math.round(h.loadMs), finishMs: Math.round(h.finishMs),
        wallMs: Math.round(h.wallMs), wallPerFrameMs: r1(h.wallMs / h.frameCount), wallNoLoadPerFrameMs: r1((h.wallMs - h.loadMs) / h.frameCount),
        stagesMsPerFrame: perFrame, tracker: h.stats, leftFrames: h.leftFrames, rightFrames: h.rightFrames, slamInitialised: h.slamInitialised,
        loadavg: l0, ...competition(c0, cpuSnapshot()), frameMs: h.frameMs.map(r1) });
      log(`round ${k + 1}/${o.runs}: hawor-browser ${hs.medianMs} ms/frame (p95 ${hs.p95Ms}), ${hs.handsPerFrame} hands/frame, other processes ${runs.hawor[k].otherCpuPct} % CPU`);

      l0 = load();
      c0 = cpuSnapshot();
      const n0 = consoleLines.length;
      const mp = await within(page.evaluate((m) => window.bench.mediapipe(m), { count, complexity, cpu: true }), runTimeout, `mediapipe-browser run ${k + 1} (hands.send)`);
      const ms = frameStats(mp.frameMs, mp.hands, o.warmup);
      runs.mediapipe.push({ ...ms, initMs: Math.round(mp.initMs), xnnpack: xnnpack(consoleLines, n0), loadavg: l0, ...competition(c0, cpuSnapshot()), frameMs: mp.frameMs.map(r1) });
      log(`round ${k + 1}/${o.runs}: mediapipe-browser ${ms.medianMs} ms/frame (p95 ${ms.p95Ms}), ${ms.handsPerFrame} hands/frame, other processes ${runs.mediapipe[k].otherCpuPct} % CPU`);

      if (o.cli) {
        l0 = load();
        c0 = cpuSnapshot();
        const c = await runCli(o, decoded, tmp, k, runTimeout, pkgs.hands);
        runs.cli.push({ msPerFrame: c.summary.msPerFrame, cpuMsPerFrame: c.summary.cpuMsPerFrame,
          perFrameStagesMs: r1(Object.entries(c.stagesMsPerFrame).reduce((s, [st, v]) => s + (ONCE_STAGES.includes(st) ? 0 : v), 0)),
          stagesMsPerFrame: c.stagesMsPerFrame, leftFrames: c.summary.leftFrames, rightFrames: c.summary.rightFrames, loadavg: l0, ...competition(c0, cpuSnapshot()), command: c.args.join(' ') });
        log(`round ${k + 1}/${o.runs}: hawor-node ${c.summary.msPerFrame} ms/frame, other processes ${runs.cli[k].otherCpuPct} % CPU`);
      }
    }

    let webglCheck = null;
    if (o.webglCheck > 0) {
      const n = Math.min(count, o.webglCheck);
      const w = Math.min(o.warmup, n - 1);
      const c0 = consoleLines.length;
      const gl = await within(page.evaluate((m) => window.bench.mediapipe(m), { count: n, complexity, cpu: false }), 120 + 30 * n, 'mediapipe-browser with useCpuInference false');
      const c1 = consoleLines.length;
      const cpu = await within(page.evaluate((m) => window.bench.mediapipe(m), { count: n, complexity, cpu: true }), 120 + 30 * n, 'mediapipe-browser with useCpuInference true');
      webglCheck = { frames: n, warmup: w, useCpuInferenceFalse: { ...frameStats(gl.frameMs, gl.hands, w), xnnpack: xnnpack(consoleLines, c0, c1) },
        useCpuInferenceTrue: { ...frameStats(cpu.frameMs, cpu.hands, w), xnnpack: xnnpack(consoleLines, c1) } };
      log(`useCpuInference false: ${webglCheck.useCpuInferenceFalse.medianMs} ms/frame, true: ${webglCheck.useCpuInferenceTrue.medianMs} ms/frame (${n} frames)`);
    }

    const over = (rs, key, round = r1) => round(median(rs.map((r) => r[key])));
    const summary = {
      hawor: { medianMs: over(runs.hawor, 'medianMs'), p95Ms: over(runs.hawor, 'p95Ms'), meanMs: over(runs.hawor, 'meanMs'), handsPerFrame: over(runs.hawor, 'handsPerFrame', r2),
        wallNoLoadPerFrameMs: over(runs.hawor, 'wallNoLoadPerFrameMs'), finishMs: over(runs.hawor, 'finishMs'),
        perceptionMsPerFrame: r1(median(runs.hawor.map((r) => r.stagesMsPerFrame.perception))) },
      mediapipe: { medianMs: over(runs.mediapipe, 'medianMs'), p95Ms: over(runs.mediapipe, 'p95Ms'), meanMs: over(runs.mediapipe, 'meanMs'), handsPerFrame: over(runs.mediapipe, 'handsPerFrame', r2) },
      cli: o.cli ? { msPerFrame: over(runs.cli, 'msPerFrame'), perFrameStagesMs: over(runs.cli, 'perFrameStagesMs') } : null,
    };
    summary.ratio = r2(summary.hawor.medianMs / summary.mediapipe.medianMs);
    summary.meanRatio = r2(summary.hawor.meanMs / summary.mediapipe.meanMs);
    summary.perceptionRatio = r2(summary.hawor.perceptionMsPerFrame / summary.mediapipe.medianMs);
    const loadAfter = load();
    const notes = [...new Set(consoleLines.filter((l) => /xnnpack|gl version|error|^http /i.test(l)).map((l) => l.replace(/[IWE]\d{4} [\d:.]+\s+\d+ /, '')))].slice(0, 20);
    const report = {
      video: o.video, source: { width: decoded.info.width, height: decoded.info.height, fps: decoded.info.fps },
      size: `${width}x${height}`, frames: count, warmupFrames: o.warmup, runs: o.runs, threads: o.threads, model: o.model,
      loadavgBefore: loadBefore, loadavgAfter: loadAfter,
      browser: { userAgent: await page.evaluate(() => navigator.userAgent), isolationHeaders: { coop: headers['cross-origin-opener-policy'], coep: headers['cross-origin-embedder-policy'] },
        readyMs: Math.round(ready.pageMs), cores: ready.cores },
      summary, webglCheck, runs, consoleNotes: notes,
    };
    const text = JSON.stringify(report);
    process.stdout.write(`${text}\n`);
    if (o.json) writeFileSync(o.json, `${JSON.stringify(report, null, 1)}\n`);
    process.stderr.write(table(report));
    return 0;
  } finally {
    if (context) await context.close().catch(() => {});
    if (server) server.close();
    rmSync(tmp, { recursive: true, force: true });
  }
}

function table(r) {
  const s = r.summary;
  const rows = [
    ['hawor-browser', s.hawor.medianMs, s.hawor.p95Ms, s.hawor.meanMs, s.hawor.handsPerFrame, r.runs.hawor.map((x) => `${x.medianMs}/${x.p95Ms} (${x.otherCpuPct} %)`).join('  ')],
    ['mediapipe-browser', s.mediapipe.medianMs, s.mediapipe.p95Ms, s.mediapipe.meanMs, s.mediapipe.handsPerFrame, r.runs.mediapipe.map((x) => `${x.medianMs}/${x.p95Ms} (${x.otherCpuPct} %)`).join('  ')],
  ];
  if (s.cli) rows.push(['hawor-node', s.cli.msPerFrame, '', '', '', r.runs.cli.map((x) => `${x.msPerFrame} (${x.otherCpuPct} %)`).join('  ')]);
  const lines = [
    '',
    `${r.frames} frames at ${r.size}, ${r.model} networks, ${r.threads} onnxruntime threads, first ${r.warmupFrames} frames skipped; load ${r.loadavgBefore.join(' ')} -> ${r.loadavgAfter.join(' ')}`,
    `${'row'.padEnd(19)}${'median ms/frame'.padStart(16)}${'p95'.padStart(8)}${'mean'.padStart(8)}${'hands/frame'.padStart(13)}   per run: median/p95 (other processes' CPU share)`,
    ...rows.map(([n, m, p, a, h, per]) => `${n.padEnd(19)}${String(m).padStart(16)}${String(p).padStart(8)}${String(a).padStart(8)}${String(h).padStart(13)}   ${per}`),
    `ratio hawor-browser / mediapipe-browser: ${s.ratio} of the medians, ${s.meanRatio} of the means (hawor's perception stage alone: ${s.hawor.perceptionMsPerFrame} ms/frame, ${s.perceptionRatio}x)`,
    `hawor-browser: (wall - load) / frames ${s.hawor.wallNoLoadPerFrameMs} ms (the CLI's msPerFrame's measure), finishing stages ${s.hawor.finishMs} ms after the last frame`
      + (s.cli ? `; hawor-node msPerFrame is (wall - load) / frames, its per-frame stages ${s.cli.perFrameStagesMs} ms` : ''),
    '',
  ];
  return lines.join('\n');
}

main().then((c) => { process.exitCode = c; }, (e) => {
  process.stderr.write(`bench_realtime: ${e.message}\n`);
  process.exitCode = e.exitCode ?? 1;
});
