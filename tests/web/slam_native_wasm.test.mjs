// The product's build against the native one: the WebAssembly core's MonoSlam (hawor_core.mjs,
// built with the product's flags, as the app and the node CLI load it) and the native `hawor
// slam` track the same frames and masks of a `hawor synth` sequence, and must give the same
// trajectory. The two builds differ only in the last bits of their arithmetic (libm, Eigen's SSE
// path natively), so the poses agree to far better than the tracking's own error; a miscompiled
// core does not (Emscripten 3.1.6 with -msimd128 computed essential matrices off the epipolar
// constraints, and every run initialised differently). Skipped with a message without the core,
// the native CLI or ffmpeg.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, readdirSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { root, clipPath, clipSkipReason } from './mediapipe_support.mjs';

const corePath = process.env.HAWOR_CORE ?? join(root, 'build/wasm/wasm/hawor_core.mjs');
const haworBin = process.env.HAWOR_BIN ?? join(root, 'build/native/examples/hawor');
const hasFfmpeg = spawnSync('ffmpeg', ['-version'], { stdio: 'ignore' }).status === 0;
const skip = !existsSync(corePath) ? `${corePath} missing (cmake --build build/wasm --target hawor_core)`
  : !existsSync(haworBin) ? `${haworBin} missing (cmake --build build/native --target hawor_cli)`
    : !hasFfmpeg ? 'ffmpeg is not installed' : false;

/** The PNG frames of DIR, numbered without gaps (%06d.png), as raw bytes in one ffmpeg run
 *  (lossless): n Uint8Arrays of w*h*channels. */
function decodePngs(dir, n, w, h, pixFmt, channels) {
  const raw = execFileSync('ffmpeg', ['-v', 'error', '-i', join(dir, '%06d.png'), '-f', 'rawvideo', '-pix_fmt', pixFmt, '-'], { maxBuffer: 1 << 28 });
  const size = w * h * channels;
  assert.equal(raw.length, n * size, `${dir}: ${raw.length} bytes, expected ${n} frames of ${size}`);
  return Array.from({ length: n }, (_, i) => new Uint8Array(raw.buffer, raw.byteOffset + i * size, size));
}

/** Native `hawor slam` and the core's MonoSlam on the PNG frames (and masks) of DIR; returns
 *  the per-frame status of both, the largest position difference and the native path length. */
async function nativeAndCore(frames, masksDir, K, W, H, work) {
  const args = ['slam', '--images', frames, '--intrinsics', K.join(','), '--out', join(work, 'native.tum'), '--stats', join(work, 'native.json')];
  if (masksDir) args.push('--masks', masksDir);
  const r = spawnSync(haworBin, args, { encoding: 'utf8' });
  assert.equal(r.status, 0, r.stderr);
  const native = readFileSync(join(work, 'native.tum'), 'utf8').trim().split('\n').filter((l) => !l.startsWith('#')).map((l) => l.trim().split(/\s+/).map(Number));
  const nativeStatus = JSON.parse(readFileSync(join(work, 'native.json'), 'utf8')).status;
  const names = readdirSync(frames).filter((n) => n.endsWith('.png')).sort();
  const rgb = decodePngs(frames, names.length, W, H, 'rgb24', 3);
  const masks = masksDir ? decodePngs(masksDir, names.length, W, H, 'gray', 1) : null;  // one per frame
  const { loadCore } = await import('../../web/src/core.mjs');
  const core = await loadCore({ path: corePath });
  const slam = new core.MonoSlam(K, W, H, { useMasks: !!masksDir });
  rgb.forEach((frame, i) => slam.process(frame, masks ? masks[i] : null));
  const res = slam.finish();
  slam.delete();
  assert.equal(native.length, names.length);
  const statusNames = ['tracked', 'interpolated', 'lost', 'relocalised'];
  let path = 0;
  let worst = 0;
  for (let i = 0; i < native.length; ++i) {
    const a = native[i].slice(1, 4);
    const b = [res.translations[3 * i], res.translations[3 * i + 1], res.translations[3 * i + 2]];
    worst = Math.max(worst, Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]));
    if (i > 0) path += Math.hypot(...a.map((v, k) => v - native[i - 1][1 + k]));
  }
  return { nativeStatus, coreStatus: Array.from(res.status, (s) => statusNames[s]), worst, path, keyframes: res.numKeyframes, initialised: res.initialised };
}

// Last-bit differences grown through RANSAC, bundle adjustment and the finishing passes stay orders
// of magnitude under the tracking error (1e-8 of the path on both sequences, the error ~1e-3).
function assertSame(c, what) {
  assert.ok(c.initialised && c.keyframes >= 3, `${what}: the core initialised (${c.keyframes} keyframes)`);
  assert.deepEqual(c.coreStatus, c.nativeStatus, `${what}: per-frame status`);
  assert.ok(c.path > 0, `${what}: the camera moved`);
  assert.ok(c.worst <= 1e-6 * c.path, `${what}: positions differ by up to ${c.worst} on a ${c.path} path (${c.worst / c.path} of it)`);
}

test('MonoSlam: the WebAssembly core and the native hawor slam give the same trajectory on a hawor synth sequence', { skip, timeout: 240000 }, async () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-slam-nw-'));
  try {
    // walk seed 1, 75 frames at 320x240, hands masked: initialisation, tracking, 22 keyframes, the finishing passes
    const env = { ...process.env };
    env.HAWOR_HAND_DIR ??= join(root, 'node_modules', '@webxr-input-profiles', 'assets', 'dist', 'profiles', 'generic-hand');
    execFileSync(haworBin, ['synth', '--preset', 'walk', '--seed', '1', '--frames', '75', '--size', '320x240', '--out', join(dir, 'seq')], { env, stdio: ['ignore', 'ignore', 'inherit'] });
    const [fx, fy, cx, cy, W, H] = readFileSync(join(dir, 'seq', 'intrinsics.txt'), 'utf8').trim().split('\n')[0].trim().split(/\s+/).map(Number);
    assertSame(await nativeAndCore(join(dir, 'seq', 'rgb'), join(dir, 'seq', 'mask'), [fx, fy, cx, cy], W, H, dir), 'synthetic walk');
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('MonoSlam: the WebAssembly core and the native hawor slam give the same trajectory on the kitchen clip', { skip: skip || clipSkipReason(), timeout: 240000 }, async () => {
  // The clip's first 60 frames at the pipeline's SLAM size (640x360, focal of a 90° diagonal):
  // the first map comes from a two-frame pair at 5 px of flow, where the miscompiled core's
  // essential matrices chose a homography and every later frame differed.
  const dir = mkdtempSync(join(tmpdir(), 'hawor-slam-nwk-'));
  try {
    execFileSync('ffmpeg', ['-v', 'error', '-i', clipPath, '-frames:v', '60', '-vf', 'scale=640:360:flags=area', join(dir, '%06d.png')]);
    const f = 0.5 * Math.hypot(640, 360);  // a 90° diagonal field of view
    assertSame(await nativeAndCore(dir, null, [f, f, 319.5, 179.5], 640, 360, dir), 'kitchen clip');
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
