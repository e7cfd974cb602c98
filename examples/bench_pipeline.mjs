// bench_pipeline.mjs: the whole pipeline (web/src/pipeline/run.mjs) end to end on synthetic
// sequences with ground truth (`hawor synth`), one table on stdout.
//
//   node examples/bench_pipeline.mjs [--hawor build/native/examples/hawor] [--presets table_work,hands_cover,walk]
//        [--seeds 3] [--frames 90] [--size 640x480] [--mode network,simulated] [--model lite|full]
//        [--threads 2] [--noise-px 2] [--noise-mm 5] [--fov DEG] [--work DIR] [--json FILE]
//        [--focal-factor 1[,0.7,1.3]] [--refine-focal on[,off]] [--hand-smooth 0[,3,7]] [--mask-dilate PX]
//        [--mask-hold S[,S2]]
//        [--tracker JSON] [--capture clean,phone,...] [--readout] [--flow-max-skip 0[,3]]
//
// Per sequence: `hawor synth` (the licence-free default hand; frames encoded to H.264 at CRF 12
// by ffmpeg, decoded back exactly as `web/cli.mjs run` does), then runPipeline with the true
// focal length (or --fov DEG for the default guess) in two modes:
//   network    the MediaPipe networks find the rendered hands (the real product path);
//   simulated  the ground-truth keypoints projected into the image + Gaussian noise (--noise-px)
//              and the camera-frame keypoints + noise (--noise-mm) as "world landmarks", fed to
//              the same pipeline after perception (options.observations);
//   MODE+depth either, with the rendered depth corrupted as in the scale benchmark (per-keyframe
//              ±5 % bias, 5 % noise, 10 % outliers) as the metric-depth network.
// --mode takes a list, e.g. network,simulated,network+depth,simulated+depth.
// Metrics (docs/design.md §8, the core's evaluateHands / evaluateCameras), per hand on the frames where
// the hand is in view and was observed, then the mean of the two hands: PA-MPJPE, W-MPJPE,
// WA-MPJPE (mm), RTE (%), Accel (m/s²); camera: ATE and ATE-S (mm, Sim(3) / SE(3) alignment);
// found = observed / in-view frames; swaps = observed frames whose wrist is nearer the other
// hand's true wrist. --focal-factor F: the focal guess is F × the true one (given as the diagonal
// FOV it implies, so the pipeline treats it as a FOV guess); --refine-focal on,off: with and
// without the SLAM's focal refinement (a second table: refined focal, its error and ATE).
// --hand-smooth K: runPipeline's handScaleSmooth (moving average of the camera-frame wrists before
// the hand-anchored scale). --tracker '{"motion":false}': HandTracker options over the pipeline's
// (runPipeline's options.tracker; '{"candidateScore":0.5,...}' for MediaPipe's policy).
// --capture P1,P2: each sequence rendered through these `hawor synth --capture` profiles (motion
// blur, rolling shutter, noise, exposure drift, the lens) and encoded as the profile's
// capture.json says, one row per profile; the pipeline gets the lens (options.camera) and the
// true focal at the video's size; 'none' is the default CRF 12 video. Simulated observations
// are pinhole projections (use them without a lens). --readout: the pipeline also gets the
// profile's rolling-shutter readout (capture.json's readout_s; runPipeline's options.readout). Each row also has handDepth per hand: the median ratio of the fitted
// camera-frame wrist depth to the true one, its spread and the frame-to-frame jitter (mm) of the
// fitted and the true depth (what the hand-anchored scale has to work with).
// --mask-hold S,S2: runPipeline's maskHoldSeconds (a hand no longer found stays masked from the
// SLAM at its last pose this long; 0: off), one row per value, labelled 'hold S s'.
// --flow-max-skip N: runPipeline's flow.maxSkip (the keypoint flow stands in for the landmark
// network on up to N frames in a row); the table's flow column: N (landmark runs / flow hands);
// --flow '{"minInliers":6}': the flow's other options.
// Timing: median over sequences of each stage's ms per frame.

import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, readdirSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { decodeFrames, handModelFiles, loadCore, probeVideo } from '../web/cli.mjs';
import { runPipeline } from '../web/src/pipeline/run.mjs';
import { decodeNpy } from '../web/tools/npy.mjs';

const repo = resolve(dirname(fileURLToPath(import.meta.url)), '..');

function parse(argv) {
  const o = {
    hawor: process.env.HAWOR_BIN ?? join(repo, 'build', 'native', 'examples', 'hawor'), presets: ['table_work', 'hands_cover', 'walk'],
    seeds: [3], frames: 90, size: '640x480', modes: ['network', 'simulated'], model: 'lite', threads: 2, noisePx: 2, noiseMm: 5,
    work: join(tmpdir(), 'hawor_bench_pipeline'), core: process.env.HAWOR_CORE ?? join(repo, 'build', 'wasm', 'wasm', 'hawor_core.mjs'),
  };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    const v = () => argv[++i];
    if (a === '--hawor') o.hawor = v();
    else if (a === '--presets') o.presets = v().split(',');
    else if (a === '--seeds') o.seeds = v().split(',').map(Number);
    else if (a === '--frames') o.frames = Number(v());
    else if (a === '--size') o.size = v();
    else if (a === '--mode') o.modes = v().split(',');
    else if (a === '--model') o.model = v();
    else if (a === '--threads') o.threads = Number(v());
    else if (a === '--noise-px') o.noisePx = Number(v());
    else if (a === '--noise-mm') o.noiseMm = Number(v());
    else if (a === '--fov') o.fov = Number(v());
    else if (a === '--work') o.work = v();
    else if (a === '--core') o.core = v();
    else if (a === '--json') o.json = v();
    else if (a === '--mask-dilate') o.maskDilate = Number(v());
    else if (a === '--tracker') o.tracker = JSON.parse(v());
    else if (a === '--capture') o.captures = v().split(',');
    else if (a === '--readout') o.readout = true;
    else if (a === '--hand-smooth') o.handSmooth = v().split(',').map(Number);
    else if (a === '--mask-hold') o.maskHold = v().split(',').map(Number);
    else if (a === '--flow-max-skip') o.flowMaxSkip = v().split(',').map(Number);
    else if (a === '--flow') o.flow = JSON.parse(v());
    else if (a === '--focal-factor') o.focalFactors = v().split(',').map(Number);
    else if (a === '--refine-focal') o.refineFocal = v().split(',').map((x) => x === 'on');
    else throw new Error(`unknown argument ${a}`);
  }
  return o;
}

// Deterministic noise (mulberry32 + Box-Muller).
function rng(seed) {
  let s = seed | 0;
  const u = () => {
    s = (s + 0x6d2b79f5) | 0;
    let t = Math.imul(s ^ (s >>> 15), 1 | s);
    t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
  return () => Math.sqrt(-2 * Math.log(u() + 1e-300)) * Math.cos(2 * Math.PI * u());
}

export function readTumPositions(file) {
  const rows = readFileSync(file, 'utf8').split('\n').filter((l) => l.trim() && !l.startsWith('#')).map((l) => l.trim().split(/\s+/).map(Number));
  return Float64Array.from(rows.flatMap((r) => [r[1], r[2], r[3]]));
}

/**
 * Makes (or reuses) a synthetic sequence and its H.264 video. options.capture: a `hawor synth
 * --capture` profile (with options.captureArgs, more `--exposure`-style overrides); the video is
 * then encoded as the profile's capture.json says (its ffmpeg_args), else losslessly enough (CRF 12).
 * Returns the intrinsics of intrinsics.txt's first line (of the rendered W × H), its lens ('pinhole'
 * without a lens line) and the video's size (smaller when the profile's encoding downscales:
 * scale the intrinsics by videoWidth / W).
 */
export function makeSequence(hawor, preset, seed, frames, size, dir, options = {}) {
  if (!existsSync(join(dir, 'video.mp4'))) {
    const glb = join(repo, 'node_modules', '@webxr-input-profiles', 'assets', 'dist', 'profiles', 'generic-hand');
    const env = { ...process.env };
    if (!env.HAWOR_HAND_DIR && !existsSync(join(dirname(hawor), '..', 'models', 'hand_right.npz'))) env.HAWOR_HAND_DIR = glb;
    const capture = options.capture ? ['--capture', options.capture, ...(options.captureArgs ?? [])] : [];
    execFileSync(hawor, ['synth', '--preset', preset, '--seed', String(seed), '--frames', String(frames), '--size', size, ...capture, '--out', dir], { env, stdio: ['ignore', 'ignore', 'inherit'] });
    const cj = join(dir, 'capture.json');
    const enc = existsSync(cj) ? JSON.parse(readFileSync(cj, 'utf8')).encode : null;
    const codec = enc && enc.ffmpeg_args ? enc.ffmpeg_args : ['-c:v', 'libx264', '-crf', '12', '-pix_fmt', 'yuv420p'];
    execFileSync('ffmpeg', ['-v', 'error', '-y', '-framerate', '30', '-i', join(dir, 'rgb', '%06d.png'), ...codec, join(dir, 'video.mp4')]);
  }
  const lines = readFileSync(join(dir, 'intrinsics.txt'), 'utf8').trim().split('\n');
  const [fx, fy, cx, cy, W, H, fps] = lines[0].trim().split(/\s+/).map(Number);
  const lensLine = lines.slice(1).find((l) => l.startsWith('lens '));
  const cj = join(dir, 'capture.json');
  const cap = existsSync(cj) ? JSON.parse(readFileSync(cj, 'utf8')) : null;
  const enc = cap ? cap.encode : null;
  const videoWidth = enc && enc.width ? enc.width : W, videoHeight = enc && enc.height ? enc.height : H;
  const readout = cap ? cap.readout_s ?? 0 : 0;
  return { dir, fx, fy, cx, cy, W, H, fps, lens: lensLine ? lensLine.slice(5).trim() : 'pinhole', videoWidth, videoHeight, readout };
}

/** fx, fy, cx, cy of a sequence at its video's size (pixel centres at integers). */
export function videoIntrinsics(seq) {
  const s = seq.videoWidth / seq.W;
  return [seq.fx * s, seq.fy * s, s * (seq.cx + 0.5) - 0.5, s * (seq.cy + 0.5) - 0.5];
}

/** Simulated perception: GT keypoints projected + noise (options.observations). */
export function simulatedObservations(gt, seq, T, noisePx, noiseMm, seed) {
  const n = rng(seed);
  return (t) => {
    const out = [];
    for (const side of ['left', 'right']) {
      if (!gt[`${side}_valid`].data[t]) continue;
      const inImg = gt[`${side}_kp_in_image`].data.subarray(21 * t, 21 * t + 21);
      if (inImg.reduce((a, v) => a + (v ? 1 : 0), 0) < 15) continue; // mostly out of view: a detector would miss it
      const jc = gt[`${side}_joints_cam`].data.subarray(63 * t, 63 * t + 63);
      const landmarks = new Float32Array(42);
      const world = new Float32Array(63);
      for (let k = 0; k < 21; ++k) {
        const [x, y, z] = [jc[3 * k], jc[3 * k + 1], jc[3 * k + 2]];
        landmarks[2 * k] = seq.fx * (x / z) + seq.cx + noisePx * n();
        landmarks[2 * k + 1] = seq.fy * (y / z) + seq.cy + noisePx * n();
        for (let a = 0; a < 3; ++a) world[3 * k + a] = jc[3 * k + a] - jc[a] + 1e-3 * noiseMm * n();
      }
      out.push({ handedness: side, handednessScore: 0.95, landmarks, world });
    }
    return out;
  };
}

/** A metric-depth source from the rendered depth (options.depthModel.predict): per keyframe a
 *  ±5 % bias, 5 % noise per pixel and 10 % outliers in [0.1, 5] m, hands left in (the pipeline's
 *  masks drop them), as the scale benchmark corrupts it. */
export function noisyTrueDepth(seq, seed) {
  const n = rng(seed);
  return {
    predict: async (frame, rgb, width, height) => {
      const { data } = decodeNpy(new Uint8Array(readFileSync(join(seq.dir, 'depth', `${String(frame).padStart(6, '0')}.npy`))));
      if (data.length !== width * height) throw new Error('noisyTrueDepth: the SLAM runs at another size than the rendered depth');
      const bias = 1 + 0.05 * Math.max(-1, Math.min(1, n()));
      const out = new Float32Array(data.length);
      for (let i = 0; i < data.length; ++i) {
        // |N| > 1.645 on 10 % of the pixels: an outlier, uniform-ish in [0.1, 5] m
        const z = n();
        out[i] = Math.abs(z) > 1.645 ? 0.1 + 4.9 * ((Math.abs(z) * 7.31) % 1) : data[i] * bias * (1 + 0.05 * n());
      }
      return out;
    },
  };
}

/** Accuracy of a result against a sequence's ground truth. */
export function evaluate(core, result, gt, seq, gtCam) {
  // the ground truth in the video's pixels (a profile's encoding may downscale; pixel centres at
  // integers), the result's keypoints undistorted to that pinhole camera
  const k = videoIntrinsics(seq);
  const undistort = (kp) => (seq.lens && seq.lens !== 'pinhole' ? core.undistortPoints(k, seq.lens, Float64Array.from(kp)) : kp);
  const T = result.frameCount;
  let cam = { ate: NaN, ate_s: NaN, scale: NaN };
  try {
    cam = core.evaluateCameras(gtCam, result.camera.positions);
  } catch (e) {
    if (!/coincide/.test(e.message)) throw e; // the SLAM did not initialise: no trajectory
  }
  const perHand = {};
  for (const side of ['left', 'right']) {
    const h = result.hands[side];
    const gv = gt[`${side}_valid`].data;
    const valid = new Uint8Array(T);
    let inView = 0; let observed = 0; let swaps = 0;
    const other = side === 'left' ? 'right' : 'left';
    for (let t = 0; t < T; ++t) {
      if (gv[t]) inView += 1;
      if (gv[t] && h.valid[t]) {
        valid[t] = 1; observed += 1;
        // wrist in the image vs both true wrists
        const proj = (jc) => [k[0] * (jc[0] / jc[2]) + k[2], k[1] * (jc[1] / jc[2]) + k[3]];
        const me = proj(gt[`${side}_joints_cam`].data.subarray(63 * t, 63 * t + 3));
        const kp = undistort(h.keypoints2d.subarray(42 * t, 42 * t + 2));
        const dMe = Math.hypot(kp[0] - me[0], kp[1] - me[1]);
        if (gt[`${other}_valid`].data[t]) {
          const ot = proj(gt[`${other}_joints_cam`].data.subarray(63 * t, 63 * t + 3));
          if (Math.hypot(kp[0] - ot[0], kp[1] - ot[1]) < dMe) swaps += 1;
        }
      }
    }
    const clean = (a) => a.map((v) => (Number.isFinite(v) ? v : 0));
    let m = null;
    if (observed >= 3) {
      m = core.evaluateHands(gt[`${side}_joints_world`].data, clean(h.jointsWorld), gt[`${side}_joints_cam`].data, clean(h.jointsCam), T, valid, seq.fps);
    }
    // the camera-frame wrist depth against the truth (what the hand-anchored scale rests on):
    // median ratio, its spread (median |ratio/median - 1|) and the frame-to-frame jitter of both
    // (1.4826 MAD of second differences / sqrt(6), mm) on runs of 3 observed frames
    const ratios = []; const d2e = []; const d2g = [];
    const ze = (t) => h.jointsCam[63 * t + 2]; const zg = (t) => gt[`${side}_joints_cam`].data[63 * t + 2];
    for (let t = 0; t < T; ++t) {
      if (!valid[t]) continue;
      ratios.push(ze(t) / zg(t));
      if (t >= 2 && valid[t - 1] && valid[t - 2]) {
        d2e.push(Math.abs(ze(t) - 2 * ze(t - 1) + ze(t - 2)));
        d2g.push(Math.abs(zg(t) - 2 * zg(t - 1) + zg(t - 2)));
      }
    }
    const rMed = ratios.length ? median(ratios) : NaN;
    const depth = { ratio: rMed, spread: ratios.length ? median(ratios.map((r) => Math.abs(r / rMed - 1))) : NaN,
      jitterMm: d2e.length ? (1e3 * 1.4826 * median(d2e)) / Math.sqrt(6) : NaN, jitterGtMm: d2g.length ? (1e3 * 1.4826 * median(d2g)) / Math.sqrt(6) : NaN };
    perHand[side] = { inView, observed, swaps, metrics: m, depth };
  }
  return { ate: cam.ate, ate_s: cam.ate_s, simScale: cam.scale, perHand };
}

const median = (a) => { const s = a.filter(Number.isFinite).sort((x, y) => x - y); return s.length ? s[Math.floor((s.length - 1) / 2)] * 0.5 + s[Math.ceil((s.length - 1) / 2)] * 0.5 : NaN; };
const mean = (a) => { const s = a.filter(Number.isFinite); return s.length ? s.reduce((x, y) => x + y, 0) / s.length : NaN; };

async function main() {
  const o = parse(process.argv.slice(2));
  if (!existsSync(o.hawor)) throw new Error(`${o.hawor}: the native hawor CLI is missing (it generates the sequences)`);
  const core = await loadCore(o.core);
  const ort = await import('onnxruntime-web');
  ort.env.wasm.numThreads = o.threads;
  ort.env.logLevel = 'error';
  const models = {
    palm: new Uint8Array(readFileSync(join(repo, 'web', 'models', `palm_detection_${o.model}.onnx`))),
    landmark: new Uint8Array(readFileSync(join(repo, 'web', 'models', `hand_landmark_${o.model}.onnx`))),
  };
  const hm = handModelFiles({});
  const handModels = { left: new Uint8Array(readFileSync(hm.left)), right: new Uint8Array(readFileSync(hm.right)), leftName: hm.left, rightName: hm.right };
  mkdirSync(o.work, { recursive: true });
  const rows = [];
  for (const preset of o.presets) {
    for (const seed of o.seeds) for (const capture of o.captures ?? ['none']) {
      const tag = capture === 'none' ? '' : `_${capture}`;
      const seq = makeSequence(o.hawor, preset, seed, o.frames, o.size, join(o.work, `${preset}_${seed}_${o.frames}_${o.size}${tag}`),
        capture === 'none' ? {} : { capture });
      const fxVideo = videoIntrinsics(seq)[0];
      const gt = core.readNpz(new Uint8Array(readFileSync(join(seq.dir, 'hands_gt.npz'))), 'hands_gt.npz');
      const gtCam = readTumPositions(join(seq.dir, 'camera_gt.tum'));
      const info = probeVideo(join(seq.dir, 'video.mp4'));
      for (const mode of o.modes) for (const factor of o.focalFactors ?? [null]) for (const refine of o.refineFocal ?? [true]) for (const smooth of o.handSmooth ?? [0]) for (const flow of o.flowMaxSkip ?? [null]) for (const hold of o.maskHold ?? [null]) {
        const timing = { decode: 0 };
        const source = { width: info.width, height: info.height, fps: seq.fps, frameCount: info.frameCount,
          frames: decodeFrames(join(seq.dir, 'video.mp4'), info.width, info.height, null, 0, timing) };
        // the generator's world is the first camera's: the output in that frame too
        const options = { core, ort, models, handModels, modelKind: o.model, threads: o.threads, gravityAligned: false,
          refineFocal: refine, handScaleSmooth: smooth, ...(o.maskDilate !== undefined ? { maskDilatePx: o.maskDilate } : {}),
          ...(hold !== null ? { maskHoldSeconds: hold } : {}),
          ...(o.tracker ? { tracker: o.tracker } : {}), ...(flow !== null || o.flow ? { flow: { ...(o.flow ?? {}), ...(flow !== null ? { maxSkip: flow } : {}) } } : {}),
          ...(seq.lens !== 'pinhole' ? { camera: seq.lens } : {}),
          ...(o.readout ? { readout: seq.readout } : {}),
          ...(o.fov ? { fovDeg: o.fov } : factor ? { fovDeg: (2 * Math.atan(0.5 * Math.hypot(info.width, info.height) / (factor * fxVideo)) * 180) / Math.PI } : { focalPx: fxVideo }) };
        if (mode.startsWith('simulated')) options.observations = simulatedObservations(gt, seq, info.frameCount, o.noisePx, o.noiseMm, 1000 + seed);
        if (mode.endsWith('+depth')) options.depthModel = noisyTrueDepth(seq, 2000 + seed);
        const t0 = performance.now();
        const result = await runPipeline(source, options, {});
        const wall = performance.now() - t0;
        const ev = evaluate(core, result, gt, seq, gtCam);
        const T = result.frameCount;
        const hands = ['left', 'right'].map((s) => ev.perHand[s]).filter((h) => h.metrics);
        const row = {
          sequence: `${preset}/${seed}${capture === 'none' ? '' : ` ${capture}`}${o.readout && seq.readout > 0 ? ` (readout ${1000 * seq.readout} ms)` : ''}${hold !== null ? ` hold ${hold} s` : ''}`, mode, frames: T, focalFactor: factor, refine, handSmooth: smooth, flowMaxSkip: flow,
          landmarkRuns: result.stats.landmarkRuns, flowHands: result.stats.flowHands,
          focalGuess: result.intrinsics.guessFx, focalOut: result.intrinsics.fx, focalTrue: fxVideo, focalRefined: result.intrinsics.refined,
          focalStd: result.intrinsics.focalStd, focalEstimate: result.intrinsics.focalEstimateFx, focalReason: result.intrinsics.focalReason,
          found: `${ev.perHand.left.observed + ev.perHand.right.observed}/${ev.perHand.left.inView + ev.perHand.right.inView}`,
          swaps: ev.perHand.left.swaps + ev.perHand.right.swaps,
          pa_mpjpe: mean(hands.map((h) => h.metrics.pa_mpjpe)), w_mpjpe: mean(hands.map((h) => h.metrics.w_mpjpe)),
          wa_mpjpe: mean(hands.map((h) => h.metrics.wa_mpjpe)), rte: mean(hands.map((h) => h.metrics.rte)), accel: mean(hands.map((h) => h.metrics.accel)),
          ate: ev.ate, ate_s: ev.ate_s, scale: 1 / ev.simScale, scaleMethod: result.scale.method,
          scaleConfidence: result.scale.confidence, handDepth: { left: ev.perHand.left.depth, right: ev.perHand.right.depth },
          msPerFrame: Object.fromEntries(Object.entries({ decode: timing.decode, ...result.timings }).filter(([k]) => k !== 'load').map(([k, v]) => [k, v / T])),
          wallMsPerFrame: (wall + timing.decode * 0) / T,
          warnings: result.warnings,
        };
        rows.push(row);
        process.stderr.write(`${JSON.stringify(row)}\n`);
      }
    }
  }
  const f = (v, d = 1) => (Number.isFinite(v) ? v.toFixed(d) : '–');
  console.log(`\n${o.size}, ${o.frames} frames, ${o.model} networks, ${o.threads} threads, focal ${o.fov ? `from a ${o.fov}° diagonal FOV` : 'true'}; simulated noise ${o.noisePx} px / ${o.noiseMm} mm`);
  console.log('| sequence | mode | flow | found | swaps | PA-MPJPE | W-MPJPE | WA-MPJPE | RTE % | Accel | ATE | ATE-S | α/α_true | ms/frame |');
  console.log('| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |');
  for (const r of rows) {
    console.log(`| ${r.sequence} | ${r.mode} | ${r.flowMaxSkip ?? '–'} (${r.landmarkRuns ?? '–'} / ${r.flowHands ?? '–'}) | ${r.found} | ${r.swaps} | ${f(r.pa_mpjpe)} | ${f(r.w_mpjpe)} | ${f(r.wa_mpjpe)} | ${f(r.rte, 2)} | ${f(r.accel, 2)} | ${f(r.ate)} | ${f(r.ate_s)} | ${f(r.scale, 3)} (${r.scaleMethod}) | ${f(r.wallMsPerFrame, 0)} |`);
  }
  if (o.focalFactors || o.refineFocal) {
    console.log('\n| sequence | mode | guess/true | refine | focal out/true | error % | std % | ATE | ATE-S | α/α_true | reason |');
    console.log('| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |');
    for (const r of rows) {
      console.log(`| ${r.sequence} | ${r.mode} | ${f(r.focalGuess / r.focalTrue, 3)} | ${r.refine ? 'on' : 'off'} | ${f(r.focalOut / r.focalTrue, 3)} | ${f(100 * (r.focalOut / r.focalTrue - 1), 1)} | ${r.focalStd == null ? '–' : f(100 * r.focalStd, 1)} | ${f(r.ate)} | ${f(r.ate_s)} | ${f(r.scale, 3)} | ${r.focalReason} |`);
    }
  }
  for (const mode of o.modes) {
    const rs = rows.filter((r) => r.mode === mode);
    if (!rs.length) continue;
    const stages = [...new Set(rs.flatMap((r) => Object.keys(r.msPerFrame)))];
    console.log(`\nms per frame, median over sequences (${mode}): ${stages.map((s) => `${s} ${f(median(rs.map((r) => r.msPerFrame[s] ?? 0)))}`).join(', ')}; total ${f(median(rs.map((r) => Object.values(r.msPerFrame).reduce((a, b) => a + b, 0))))}`);
  }
  if (o.json) writeFileSync(o.json, JSON.stringify(rows, null, 1));
}

if (process.argv[1] && resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  main().catch((e) => { process.stderr.write(`bench_pipeline: ${e.stack}\n`); process.exitCode = 1; });
}
