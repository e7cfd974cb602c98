// Lenses in the JavaScript pipeline: the core's lens calls (parseLens, describeCamera,
// cameraFromFov, undistortPoints, Rectifier, LensCamera) against reference formulas written here
// (the Kannala-Brandt fisheye and OpenCV's radial-tangential projection, bilinear and nearest
// sampling); the perception's mapped crop against the affine one; runPipeline with keypoints
// simulated through a fisheye (the fit on undistorted keypoints, the SLAM on rectified frames);
// the pipeline CLI with --camera on a short `hawor synth --capture aria` clip, through the true
// model and the wrong (pinhole) one; bad --camera strings (exit code 2, the problem named).
// Parts that need the WebAssembly core ($HAWOR_CORE), the native CLI ($HAWOR_BIN), ffmpeg or the
// hand networks are skipped with a message when those are missing.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { root, modelsSkipReason } from './mediapipe_support.mjs';
import { rng } from './support.mjs';
import { runPipeline, cameraIntrinsics } from '../../web/src/pipeline/run.mjs';
import { cropImage, cropImageMapped } from '../../web/src/perception/geometry.mjs';

const corePath = process.env.HAWOR_CORE ?? join(root, 'build/wasm/wasm/hawor_core.mjs');
const haworBin = process.env.HAWOR_BIN ?? join(root, 'build/native/examples/hawor');
const cli = join(root, 'web/cli.mjs');
const hasFfmpeg = spawnSync('ffmpeg', ['-version'], { stdio: 'ignore' }).status === 0;
const coreSkip = () => (existsSync(corePath) ? false : `${corePath} missing (cmake --build build/wasm --target hawor_core)`);
const ffmpegSkip = () => (hasFfmpeg ? false : 'ffmpeg is not installed');
const synthSkip = () => (existsSync(haworBin) ? false : `${haworBin} missing (the native hawor CLI generates the sequence)`);
const skipOf = (...reasons) => reasons.map((r) => r()).find((r) => r) || false;

const FISHEYE = 'fisheye:-0.0036,0.0368,-0.0343,0.0052';
const FISH_K = [-0.0036, 0.0368, -0.0343, 0.0052];
const RADTAN = 'opencv:-0.16,0.02,0.0004,-0.0003,-0.001';
const RADTAN_K = [-0.16, 0.02, 0.0004, -0.0003, -0.001];
const PINCUSHION = 'opencv:0.12,0.03,0.002,-0.001,0.01';

let corePromise = null;
async function loadCore() {
  const { loadCore: load } = await import('../../web/cli.mjs');
  corePromise ??= load(corePath);
  return corePromise;
}
function runCli(args, timeout = 240000) {
  return spawnSync(process.execPath, [cli, ...args], { encoding: 'utf8', timeout, env: { ...process.env, HAWOR_CORE: corePath } });
}

// --- reference projections (docs/design.md §11) ---------------------------------------------------

/** Distorted normalised coordinates of the camera-frame point p. */
function distort(kind, k, p) {
  const [x, y, z] = p;
  if (kind === 'fisheye') {
    const r = Math.hypot(x, y);
    if (r === 0) return [0, 0];
    const th = Math.atan2(r, z);
    const t2 = th * th;
    const td = th * (1 + k[0] * t2 + k[1] * t2 * t2 + k[2] * t2 ** 3 + k[3] * t2 ** 4);
    return [(td / r) * x, (td / r) * y];
  }
  const a = x / z;
  const b = y / z;
  const r2 = a * a + b * b;
  const rad = 1 + k[0] * r2 + k[1] * r2 * r2 + k[4] * r2 ** 3;
  return [a * rad + 2 * k[2] * a * b + k[3] * (r2 + 2 * a * a), b * rad + k[2] * (r2 + 2 * b * b) + 2 * k[3] * a * b];
}
const pix = (K, m) => [K[0] * m[0] + K[2], K[1] * m[1] + K[3]];

function bilinear(img, W, H, x, y) {
  const xf = Math.floor(x);
  const yf = Math.floor(y);
  const a = x - xf;
  const b = y - yf;
  const px = (u, v) => img[Math.min(Math.max(v, 0), H - 1) * W + Math.min(Math.max(u, 0), W - 1)];
  return (1 - b) * ((1 - a) * px(xf, yf) + a * px(xf + 1, yf)) + b * ((1 - a) * px(xf, yf + 1) + a * px(xf + 1, yf + 1));
}

// --- the core's lens calls --------------------------------------------------------------------------

test('core lenses: parseLens, describeCamera, cameraFromFov and their messages', { skip: coreSkip() }, async () => {
  const core = await loadCore();
  assert.equal(core.parseLens(' FISHEYE: -0.0036, 0.0368,-0.0343,0.0052 '), FISHEYE);
  assert.equal(core.parseLens('pinhole'), 'pinhole');
  for (const [s, re] of [['bogus', /unknown lens model/], ['fisheye:1,2', /takes 4 coefficients/], ['fisheye:nan,0,0,0', /not finite/],
    ['opencv:1,x,0,0', /is not a number/], ['pinhole:0', /no coefficients/]]) {
    assert.throws(() => core.parseLens(s), (e) => e.name === 'HaworError' && re.test(e.message), s);
  }
  const d = core.describeCamera([313.6876484765642, 313.6876484765642, 319.5, 239.5], 640, 480, FISHEYE);
  assert.equal(d.lens, FISHEYE);
  assert.equal(d.pinhole, false);
  assert.ok(Math.abs(d.maxFieldAngleDeg - 75) < 1e-6 && d.foldAngleDeg > 90, JSON.stringify(d));
  assert.equal(core.describeCamera([400, 400, 319.5, 239.5], 640, 480, 'opencv:0,0,0,0').pinhole, true);
  assert.throws(() => core.describeCamera([300, 300, 319.5, 239.5], 640, 480, 'opencv:-0.6,0.05,0,0'), /folds at 37\.9 degrees/);
  const c = core.cameraFromFov(640, 480, FISHEYE, 150);
  assert.ok(Math.abs(c.fx - 313.6876484765642) < 1e-6 && c.fx === c.fy && c.cx === 319.5, JSON.stringify(c));
  // the pipeline's camera: the field of view through the lens, the canonical lens, errors named
  const intr = cameraIntrinsics(core, 640, 480, { fovDeg: 150, camera: 'fisheye:-0.0036,0.0368,-0.0343,0.0052' });
  assert.ok(Math.abs(intr.fx - c.fx) < 1e-9 && Math.abs(intr.fovDeg - 150) < 1e-6 && intr.lens === FISHEYE, JSON.stringify(intr));
  assert.equal(cameraIntrinsics(core, 640, 480, { camera: 'opencv:0,0,0,0' }).lens, 'pinhole');
  assert.ok(Math.abs(cameraIntrinsics(core, 640, 480, {}).fx - 400) < 1e-9);
  assert.equal(cameraIntrinsics(core, 640, 480, {}).lens, 'pinhole');
  assert.throws(() => cameraIntrinsics(core, 640, 480, { focalPx: 300, camera: 'opencv:-0.6,0.05,0,0' }), /the camera model 'opencv:-0\.6,0\.05,0,0': .*folds/);
});

test('core.undistortPoints: pixels through a lens back to the pinhole camera with the same intrinsics', { skip: coreSkip() }, async () => {
  const core = await loadCore();
  const K = [300, 303, 321.2, 238.9];
  const r = rng(3);
  for (const [spec, kind, k, maxDeg] of [[FISHEYE, 'fisheye', FISH_K, 80], [RADTAN, 'opencv', RADTAN_K, 55]]) {
    const n = 200;
    const pts = new Float64Array(2 * n);
    const ref = new Float64Array(2 * n);
    for (let i = 0; i < n; ++i) {
      const th = (Math.PI / 180) * maxDeg * Math.sqrt(0.5 * (r() + 1));
      const ph = Math.PI * r();
      const p = [Math.sin(th) * Math.cos(ph), Math.sin(th) * Math.sin(ph), Math.cos(th)];
      [pts[2 * i], pts[2 * i + 1]] = pix(K, distort(kind, k, p));
      [ref[2 * i], ref[2 * i + 1]] = pix(K, [p[0] / p[2], p[1] / p[2]]);
    }
    const u = core.undistortPoints(K, spec, pts);
    for (let i = 0; i < 2 * n; ++i) assert.ok(Math.abs(u[i] - ref[i]) < 1e-6 * Math.max(1, Math.abs(ref[i])), `${spec} ${i}: ${u[i]} vs ${ref[i]}`);
  }
  // a fisheye ray at 90 degrees or more has no pinhole pixel; beyond the fold nothing is defined
  const side = pix(K, distort('fisheye', FISH_K, [1, 0, -0.05]));
  const u = core.undistortPoints(K, FISHEYE, Float64Array.of(...side, 1e7, 1e7, 321.2, 238.9));
  assert.ok(Number.isNaN(u[0]) && Number.isNaN(u[1]) && Number.isNaN(u[2]) && Number.isNaN(u[3]));
  assert.ok(Math.abs(u[4] - 321.2) < 1e-12 && Math.abs(u[5] - 238.9) < 1e-12);
  assert.deepEqual(Array.from(core.undistortPoints(K, 'pinhole', Float64Array.of(1.5, -2))), [1.5, -2]);
  assert.throws(() => core.undistortPoints(K, FISHEYE, Float64Array.of(1, 2, 3)), /2N/);
});

test('core.Rectifier: grey (bilinear), mask (nearest) and the SLAM mask against brute force; a pinhole is a copy', { skip: coreSkip() }, async () => {
  const core = await loadCore();
  const W = 160;
  const H = 120;
  const img = new Uint8Array(W * H);
  const r = rng(5);
  for (let i = 0; i < img.length; ++i) img[i] = Math.floor(128 + 127 * r());
  // pinhole: the same bytes, no mask of its own
  const pin = new core.Rectifier([100, 100, 79.5, 59.5], W, H, 'pinhole');
  try {
    assert.equal(pin.identity(), true);
    assert.deepEqual(pin.grey(img), img);
    assert.equal(pin.slamMask(null), null);
    assert.deepEqual(pin.slamMask(img), img);
  } finally { pin.delete(); }
  for (const [spec, kind, k, K] of [[FISHEYE, 'fisheye', FISH_K, [78.4, 79.2, 80.8, 58.8]], [PINCUSHION, 'opencv', [0.12, 0.03, 0.002, -0.001, 0.01], [110, 111, 80, 60]]]) {
    const rect = new core.Rectifier(K, W, H, spec);
    try {
      assert.equal(rect.identity(), false);
      const grey = rect.grey(img);
      const mask = rect.mask(img);
      const rgba = new Uint8Array(W * H * 4).map((_, i) => img[i >> 2]);
      const rgbaOut = rect.image(rgba, 4);
      let outside = 0; let exact = 0; let inside = 0;
      for (let y = 0; y < H; ++y) {
        for (let x = 0; x < W; ++x) {
          const m = distort(kind, k, [(x - K[2]) / K[0], (y - K[3]) / K[1], 1]);
          const [u, v] = pix(K, m);
          const i = y * W + x;
          if (!(u >= -0.5 && v >= -0.5 && u <= W - 0.5 && v <= H - 0.5)) {
            outside += 1;
            assert.equal(grey[i], 0); assert.equal(mask[i], 0);
            continue;
          }
          inside += 1;
          const ref = bilinear(img, W, H, u, v);
          assert.ok(Math.abs(grey[i] - ref) <= 1.01, `${spec} (${x}, ${y}): ${grey[i]} vs ${ref}`);
          if (grey[i] === Math.round(ref)) exact += 1;
          const nx = Math.min(Math.floor(u + 0.5), W - 1);
          const ny = Math.min(Math.floor(v + 0.5), H - 1);
          assert.equal(mask[i], img[Math.max(ny, 0) * W + Math.max(nx, 0)]);
          assert.equal(rgbaOut[4 * i], grey[i]);
        }
      }
      assert.ok(exact >= 0.98 * inside, `${exact} of ${inside} exact`);
      assert.equal(rect.numOutside(), outside);
      const sm = rect.slamMask(null);
      if (outside === 0) {
        assert.equal(sm, null); // a fisheye onto its own intrinsics sees the whole pinhole view
      } else {
        // the border grown by 6 px; a hand pixel joins it
        assert.ok(sm instanceof Uint8Array && sm.length === W * H);
        const hand = new Uint8Array(W * H); hand[60 * W + 80] = 200;
        const both = rect.slamMask(hand);
        assert.equal(both[60 * W + 80], 255);
        assert.equal(sm[60 * W + 80], 0);
        assert.ok(sm.filter((v) => v).length > outside);
      }
    } finally { rect.delete(); }
  }
  assert.throws(() => new core.Rectifier([100, 100, 79.5, 59.5], W, H, 'opencv:-0.9,0,0,0'), /folds|beyond what lens/);
});

test('core.LensCamera and the perception crop: perspective views through the lens, landmarks back through the same map, the rectified frame\'s letterbox', { skip: coreSkip() }, async () => {
  const core = await loadCore();
  const K = [313.6876484765642, 313.6876484765642, 319.5, 239.5];
  const lc = new core.LensCamera(K, 640, 480, FISHEYE);
  try {
    const roi = { cx: 560, cy: 90, w: 140, h: 140, rotation: 0.6 };
    const { map, rotation: R, focal } = lc.cropMap(roi, 8, 8);
    assert.equal(map.length, 128);
    // orthonormal, its axis through the ROI centre
    for (let a = 0; a < 3; ++a) {
      for (let b = 0; b < 3; ++b) {
        let d = 0;
        for (let c = 0; c < 3; ++c) d += R[3 * c + a] * R[3 * c + b];
        assert.ok(Math.abs(d - (a === b ? 1 : 0)) < 1e-12);
      }
    }
    const axis = pix(K, distort('fisheye', FISH_K, [R[2], R[5], R[8]]));
    assert.ok(Math.hypot(axis[0] - roi.cx, axis[1] - roi.cy) < 1e-6, `${axis}`);
    assert.ok(focal > 200 && focal < 400, `${focal}`);
    // the map at the crop pixels' centres = cropToImage there = the reference projection of the ray
    const uv = new Float64Array(128);
    for (let j = 0; j < 8; ++j) for (let i = 0; i < 8; ++i) { uv[2 * (8 * j + i)] = (i + 0.5) / 8 - 0.5; uv[2 * (8 * j + i) + 1] = (j + 0.5) / 8 - 0.5; }
    const back = lc.cropToImage(roi, uv);
    const c = Math.cos(roi.rotation);
    const s = Math.sin(roi.rotation);
    for (let p = 0; p < 64; ++p) {
      const a = uv[2 * p] * roi.w;
      const b = uv[2 * p + 1] * roi.h;
      const t = [(a * c - b * s) / focal, (a * s + b * c) / focal, 1];
      const ray = [0, 1, 2].map((row) => R[3 * row] * t[0] + R[3 * row + 1] * t[1] + R[3 * row + 2] * t[2]);
      const ref = pix(K, distort('fisheye', FISH_K, ray));
      assert.ok(Math.abs(back[2 * p] - ref[0]) < 1e-6 && Math.abs(back[2 * p + 1] - ref[1]) < 1e-6);
      assert.ok(Math.abs(map[2 * p] - ref[0]) < 1e-3 && Math.abs(map[2 * p + 1] - ref[1]) < 1e-3);
    }
    // a whole-frame detector's view: the rectified frame's letterbox through the lens, and back
    const L = 16;
    const lb = lc.letterboxMap(L, L);
    const virt = new Float64Array(2 * L * L);
    for (let j = 0; j < L; ++j) {
      for (let i = 0; i < L; ++i) {
        const x = 319.5 + 640 * ((i + 0.5) / L - 0.5);
        const y = 239.5 + 640 * ((j + 0.5) / L - 0.5);
        virt[2 * (j * L + i)] = x;
        virt[2 * (j * L + i) + 1] = y;
        const ref = pix(K, distort('fisheye', FISH_K, [(x - K[2]) / K[0], (y - K[3]) / K[1], 1]));
        assert.ok(Math.abs(lb[2 * (j * L + i)] - ref[0]) < 1e-3 && Math.abs(lb[2 * (j * L + i) + 1] - ref[1]) < 1e-3, `(${i}, ${j})`);
      }
    }
    const back2 = lc.virtualToImage(virt);
    for (let p = 0; p < 2 * L * L; ++p) assert.ok(Math.abs(back2[p] - lb[p]) < 1e-3);
    assert.throws(() => lc.cropMap({ cx: 1e8, cy: 0, w: 10, h: 10, rotation: 0 }, 4, 4), /beyond what lens/);
    assert.throws(() => lc.cropMap({ cx: 1, cy: 0, w: 10, rotation: 0 }, 4, 4), /roi\.h/);
  } finally { lc.delete(); }
  // cropImageMapped with the affine crop's own sampling points is the affine crop; NaN reads black
  const W = 64;
  const H = 48;
  const data = new Uint8Array(W * H * 4).map((_, i) => (i * 37) % 251);
  const image = { width: W, height: H, data, channels: 4 };
  const roi = { cx: 30.3, cy: 20.7, w: 40, h: 36, rotation: 0.4 };
  const N = 12;
  const map = new Float64Array(2 * N * N);
  for (let j = 0; j < N; ++j) {
    for (let i = 0; i < N; ++i) {
      const u = (i + 0.5) / N - 0.5;
      const v = (j + 0.5) / N - 0.5;
      map[2 * (j * N + i)] = roi.cx + u * roi.w * Math.cos(roi.rotation) - v * roi.h * Math.sin(roi.rotation);
      map[2 * (j * N + i) + 1] = roi.cy + u * roi.w * Math.sin(roi.rotation) + v * roi.h * Math.cos(roi.rotation);
    }
  }
  for (const border of ['zero', 'replicate']) {
    const a = cropImage(image, roi, N, N, undefined, border);
    const b = cropImageMapped(image, map, N, N, undefined, border);
    for (let i = 0; i < a.length; ++i) assert.ok(Math.abs(a[i] - b[i]) < 1e-5, `${border} ${i}`);
  }
  map[0] = NaN;
  const z = cropImageMapped(image, map, N, N);
  assert.deepEqual(Array.from(z.subarray(0, 3)), [0, 0, 0]);
});

// --- the pipeline through a fisheye -----------------------------------------------------------------

let seqPromise = null;
/** walk, seed 2, 60 frames at 640 x 480 through the Aria-like fisheye (one sub-frame per frame,
 *  to render quickly), and its H.264 video. */
async function ariaSequence(dir) {
  const { makeSequence } = await import('../../examples/bench_pipeline.mjs');
  seqPromise ??= Promise.resolve(makeSequence(haworBin, 'walk', 2, 60, '640x480', join(dir, 'aria'), { capture: 'aria', captureArgs: ['--subframes', '1'] }));
  return seqPromise;
}
const work = mkdtempSync(join(tmpdir(), 'hawor-pipe-lens-'));
process.on('exit', () => rmSync(work, { recursive: true, force: true }));

/** Keypoints as a perfect detector through the lens would see them, plus noise. */
function lensObservations(gt, seq, noisePx, noiseMm, seed) {
  const n = rng(seed);
  const K = [seq.fx, seq.fy, seq.cx, seq.cy];
  return (t) => {
    const out = [];
    for (const side of ['left', 'right']) {
      if (!gt[`${side}_valid`].data[t]) continue;
      const inImg = gt[`${side}_kp_in_image`].data.subarray(21 * t, 21 * t + 21);
      if (inImg.reduce((a, v) => a + (v ? 1 : 0), 0) < 15) continue;
      const jc = gt[`${side}_joints_cam`].data.subarray(63 * t, 63 * t + 63);
      const landmarks = new Float32Array(42);
      const world = new Float32Array(63);
      for (let k = 0; k < 21; ++k) {
        const [x, y] = pix(K, distort('fisheye', FISH_K, [jc[3 * k], jc[3 * k + 1], jc[3 * k + 2]]));
        landmarks[2 * k] = x + noisePx * n();
        landmarks[2 * k + 1] = y + noisePx * n();
        for (let a = 0; a < 3; ++a) world[3 * k + a] = jc[3 * k + a] - jc[a] + 1e-3 * noiseMm * n();
      }
      out.push({ handedness: side, handednessScore: 0.95, landmarks, world });
    }
    return out;
  };
}

test('runPipeline through a fisheye (keypoints simulated through it): the fit and the SLAM in the virtual pinhole camera, the wrong model worse', { skip: skipOf(coreSkip, ffmpegSkip, synthSkip), timeout: 400000 }, async () => {
  const core = await loadCore();
  const seq = await ariaSequence(work);
  assert.equal(seq.lens, FISHEYE);
  const { evaluate, readTumPositions } = await import('../../examples/bench_pipeline.mjs');
  const { decodeFrames, probeVideo, handModelFiles } = await import('../../web/cli.mjs');
  const gt = core.readNpz(new Uint8Array(readFileSync(join(seq.dir, 'hands_gt.npz'))), 'hands_gt.npz');
  const gtCam = readTumPositions(join(seq.dir, 'camera_gt.tum'));
  const info = probeVideo(join(seq.dir, 'video.mp4'));
  const hm = handModelFiles({});
  const run = (camera) => runPipeline({ width: info.width, height: info.height, fps: 30, frameCount: 60,
    frames: decodeFrames(join(seq.dir, 'video.mp4'), info.width, info.height, null, 0, { decode: 0 }) },
  { core, focalPx: seq.fx, camera, refineFocal: false,
    handModels: { left: new Uint8Array(readFileSync(hm.left)), right: new Uint8Array(readFileSync(hm.right)) },
    observations: lensObservations(gt, seq, 1, 5, 9) });
  const right = await run(FISHEYE);
  const wrong = await run('pinhole');
  assert.equal(right.intrinsics.lens, FISHEYE);
  assert.equal(wrong.intrinsics.lens, 'pinhole');
  assert.ok(Math.abs(right.intrinsics.fovDeg - 150) < 1e-6, `${right.intrinsics.fovDeg}`);
  assert.ok(right.slam.initialised && wrong.slam.initialised);
  const er = evaluate(core, right, gt, seq, gtCam);
  const ew = evaluate(core, wrong, gt, seq, gtCam);
  let path = 0;
  for (let t = 1; t < 60; ++t) path += Math.hypot(gtCam[3 * t] - gtCam[3 * t - 3], gtCam[3 * t + 1] - gtCam[3 * t - 2], gtCam[3 * t + 2] - gtCam[3 * t - 1]);
  const h = er.perHand.left;
  const hw = ew.perHand.left;
  console.log(`simulated keypoints through the fisheye: ATE ${er.ate.toFixed(2)} mm (wrong model ${ew.ate.toFixed(2)}), left PA-MPJPE ${h.metrics.pa_mpjpe.toFixed(1)} / WA-MPJPE ${h.metrics.wa_mpjpe.toFixed(1)} mm (wrong model ${hw.metrics.pa_mpjpe.toFixed(1)} / ${hw.metrics.wa_mpjpe.toFixed(1)}), path ${path.toFixed(2)} m`);
  assert.ok(er.ate < 0.01 * path * 1000, `ATE ${er.ate} mm on a ${path} m path`);
  assert.ok(ew.ate > 3 * er.ate, `wrong model ATE ${ew.ate} vs ${er.ate}`);
  assert.ok(h.observed >= 0.8 * h.inView && h.metrics.pa_mpjpe < 8 && h.metrics.wa_mpjpe < 40, JSON.stringify(h));
  assert.ok(hw.metrics.wa_mpjpe > 1.5 * h.metrics.wa_mpjpe, `wrong model WA-MPJPE ${hw.metrics.wa_mpjpe} vs ${h.metrics.wa_mpjpe}`);
  // the detected keypoints stay in the video's (distorted) pixels
  const t0 = Array.from(right.hands.left.valid).indexOf(1);
  const jc = gt.left_joints_cam.data.subarray(63 * t0, 63 * t0 + 3);
  const w = pix([seq.fx, seq.fy, seq.cx, seq.cy], distort('fisheye', FISH_K, jc));
  assert.ok(Math.hypot(right.hands.left.keypoints2d[42 * t0] - w[0], right.hands.left.keypoints2d[42 * t0 + 1] - w[1]) < 6);
});

test('pipeline CLI --camera on a synthetic fisheye clip: the true model tracks, the wrong one drifts; bad strings exit 2', { skip: skipOf(coreSkip, ffmpegSkip, synthSkip, modelsSkipReason), timeout: 400000 }, async () => {
  const core = await loadCore();
  const seq = await ariaSequence(work);
  const { evaluate, readTumPositions } = await import('../../examples/bench_pipeline.mjs');
  const gt = core.readNpz(new Uint8Array(readFileSync(join(seq.dir, 'hands_gt.npz'))), 'hands_gt.npz');
  const gtCam = readTumPositions(join(seq.dir, 'camera_gt.tum'));
  const video = join(seq.dir, 'video.mp4');
  const results = {};
  for (const [name, camera] of [['right', FISHEYE], ['wrong', 'pinhole']]) {
    const out = join(work, `cli_${name}`);
    const r = runCli(['run', video, '--out', out, '--focal', String(seq.fx), '--camera', camera, '--threads', '1']);
    assert.equal(r.status, 0, r.stderr);
    const summary = JSON.parse(r.stdout.trim().split('\n').pop());
    assert.equal(summary.camera, camera);
    const result = JSON.parse(readFileSync(join(out, 'result.json'), 'utf8'));
    assert.equal(result.intrinsics.lens, camera);
    const arr = (a) => Float64Array.from(a, (v) => (v === null ? NaN : v));
    for (const s of ['left', 'right']) for (const k of ['jointsWorld', 'jointsCam', 'keypoints2d']) result.hands[s][k] = arr(result.hands[s][k]);
    result.camera.positions = arr(result.camera.positions);
    results[name] = { result, ev: evaluate(core, result, gt, seq, gtCam) };
  }
  const { right, wrong } = results;
  let path = 0;
  for (let t = 1; t < 60; ++t) path += Math.hypot(gtCam[3 * t] - gtCam[3 * t - 3], gtCam[3 * t + 1] - gtCam[3 * t - 2], gtCam[3 * t + 2] - gtCam[3 * t - 1]);
  console.log(`CLI through the fisheye: ATE ${right.ev.ate.toFixed(2)} mm, left hand on ${right.ev.perHand.left.observed}/${right.ev.perHand.left.inView} frames; wrong model ATE ${wrong.ev.ate.toFixed(2)} mm`);
  assert.ok(right.result.slam.initialised, 'the SLAM initialised');
  assert.ok(right.ev.ate < 0.02 * path * 1000, `ATE ${right.ev.ate} mm on a ${path} m path`);
  assert.ok(!wrong.result.slam.initialised || wrong.ev.ate > 3 * right.ev.ate, `wrong model ATE ${wrong.ev.ate} vs ${right.ev.ate}`);
  const lh = right.ev.perHand.left;
  assert.ok(lh.observed >= 0.4 * lh.inView, `left hand found on ${lh.observed} of ${lh.inView} frames`);

  // bad --camera strings: exit 2 naming the problem (parse, NaN, folding inside the frame)
  for (const [camera, re] of [['bogus', /unknown lens model "bogus"/], ['fisheye:1,2', /takes 4 coefficients/],
    ['fisheye:NaN,0,0,0', /not finite/], ['opencv:-0.6,0.05,0,0', /folds at/], ['', /--camera needs a lens/]]) {
    const r = runCli(['run', video, '--out', join(work, 'bad'), '--focal', String(seq.fx), '--camera', camera, '--max-frames', '8']);
    assert.equal(r.status, 2, `${camera}: ${r.status} ${r.stderr}`);
    assert.match(r.stderr, /--camera/);
    assert.match(r.stderr, re, r.stderr);
    assert.ok(!existsSync(join(work, 'bad', 'result.json')));
  }
});
