// One real-clip variant through the whole pipeline (the cheap end of examples/bench_real.mjs): the
// first 60 frames of the shared kitchen clip, downscaled to 640x360 and compressed to 0.8 Mbit/s
// (the benchmark's 640_1M variant; x264 preset veryfast, one thread, so the bytes do not depend
// on the machine). `node web/cli.mjs run` with default options must succeed, find the hands on
// the by-eye labelled frames (tests/data/kitchen_hands_visible.json) on the right sides without
// reporting hands that are labelled absent, and give a finite camera path that moves.
// Measured when written: recall 0.92 left / 0.82 right, one false positive (frame 55: the left
// hand, alone in view, put in the right slot), a 0.41 m path, 18 frames lost in the turn from the
// table (frames 42-59). The strongly compressed 640x360 variant (CRF 36) is no test case today:
// on these 60 frames its SLAM does not initialise and the left hand is found on 2 of 12 frames
// (docs/benchmarks.md, real-video robustness).
// Skipped with a message when the shared clip, ffmpeg, the networks or the core are missing.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { root, clipPath, clipSkipReason, modelsSkipReason } from './mediapipe_support.mjs';
import { VARIANTS, scoreHands } from '../../examples/bench_real.mjs';

const corePath = process.env.HAWOR_CORE ?? join(root, 'build/wasm/wasm/hawor_core.mjs');
const coreSkip = existsSync(corePath) ? false : `${corePath} missing (cmake --build build/wasm --target hawor_core)`;
const skip = clipSkipReason() || modelsSkipReason() || coreSkip;
const FRAMES = 60;

test('kitchen clip at 640x360, 0.8 Mbit/s, first 60 frames: hands found on the labelled frames, a finite moving camera', { skip, timeout: 120_000 }, () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-real-variant-'));
  try {
    const v = VARIANTS['640_1M'];
    const video = join(dir, 'v.mp4');
    const ff = spawnSync('ffmpeg', ['-v', 'error', '-nostdin', '-y', '-i', clipPath, '-an', '-frames:v', String(FRAMES), '-vf', v.vf,
      '-c:v', 'libx264', '-preset', 'veryfast', '-threads', '1', '-pix_fmt', 'yuv420p', ...v.enc, video], { encoding: 'utf8' });
    assert.equal(ff.status, 0, ff.stderr);
    const out = join(dir, 'out');
    const p = spawnSync(process.execPath, [join(root, 'web/cli.mjs'), 'run', video, '--out', out, '--core', corePath],
      { encoding: 'utf8', timeout: 110_000 });
    assert.equal(p.status, 0, p.stderr.slice(-2000));
    const r = JSON.parse(readFileSync(join(out, 'result.json'), 'utf8'));
    assert.equal(r.frameCount, FRAMES);
    assert.deepEqual([r.width, r.height], [640, 360]);

    // Hands: frames 0-55 are labelled (every 5th): 12 with the left hand, 11 with the right, 1
    // with the right labelled absent.
    const labels = JSON.parse(readFileSync(join(root, 'tests/data/kitchen_hands_visible.json'), 'utf8'));
    const h = scoreHands(r, v, labels, labels.frameCount, null);
    const msg = JSON.stringify({ recall: h.recall, missed: { left: h.left.missed, right: h.right.missed }, fp: h.fpFrames, crossed: h.crossed });
    assert.equal(h.labelledFrames, 12);
    assert.ok(h.left.visible + h.right.visible >= 20, msg);
    assert.ok(h.recall.both >= 0.7, `hands found on too few labelled frames: ${msg}`);
    assert.ok(h.recall.left >= 0.6 && h.recall.right >= 0.6, msg);
    assert.ok(h.fp <= 2, `hands reported where the labels say none: ${msg}`);
    assert.equal(h.crossed, 0, `left and right crossed: ${msg}`);

    // Camera: initialised, finite, moving (the wearer leans over the table and turns away).
    const pos = r.camera.positions;
    assert.ok(r.slam.initialised, `the SLAM did not initialise: ${JSON.stringify(r.slam)}`);
    assert.equal(pos.length, 3 * FRAMES);
    assert.ok(pos.every(Number.isFinite), 'camera positions must be finite');
    assert.ok(r.camera.quaternions.every(Number.isFinite), 'camera rotations must be finite');
    let path = 0;
    for (let t = 1; t < FRAMES; ++t) path += Math.hypot(pos[3 * t] - pos[3 * t - 3], pos[3 * t + 1] - pos[3 * t - 2], pos[3 * t + 2] - pos[3 * t - 1]);
    assert.ok(path > 0.05 && path < 10, `camera path ${path} (scale ${r.scale.scale}, ${r.scale.method})`);
    const lost = r.camera.status.filter((s) => s === 2).length;
    assert.ok(lost <= FRAMES / 2, `the camera was lost on ${lost} of ${FRAMES} frames`);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
