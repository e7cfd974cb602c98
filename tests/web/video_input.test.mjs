// Video files as phones and editors write them, through the CLI's reader (web/cli.mjs
// probeVideo / variableFrameTimes / decodeFrames): a display rotation (every portrait phone clip is
// stored landscape with a rotation) and a variable frame rate (phones lower it in dim light; cuts
// leave gaps). The references are independent of the reader: the unrotated clip's pixels turned by
// the display matrix's convention (counterclockwise degrees), and the frames kept by an ffmpeg
// select at their known times. Skipped without ffmpeg.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { root, modelsSkipReason } from './mediapipe_support.mjs';
import { probeVideo, variableFrameTimes, decodeFrames } from '../../web/cli.mjs';

const hasFfmpeg = spawnSync('ffmpeg', ['-version'], { stdio: 'ignore' }).status === 0;
const ffmpegSkip = hasFfmpeg ? false : 'ffmpeg is not installed';
const corePath = process.env.HAWOR_CORE ?? join(root, 'build/wasm/wasm/hawor_core.mjs');
function ffmpeg(args) { execFileSync('ffmpeg', ['-v', 'error', '-y', ...args]); }

/** Raw RGB frames of a clip as stored (no rotation applied, each coded frame once), by ffmpeg directly. */
function storedFrames(file, w, h) {
  const b = execFileSync('ffmpeg', ['-v', 'error', '-noautorotate', '-i', file, '-fps_mode', 'passthrough', '-f', 'rawvideo', '-pix_fmt', 'rgb24', '-'], { maxBuffer: 1 << 26 });
  const n = b.length / (w * h * 3);
  return Array.from({ length: n }, (_, i) => b.subarray(i * w * h * 3, (i + 1) * w * h * 3));
}

async function collect(gen) {
  const out = [];
  for await (const f of gen) out.push({ ...f, rgba: Uint8Array.from(f.rgba) });
  return out;
}

test('video input: a clip with a display rotation is probed and decoded as shown (90, 180, 270 degrees)', { skip: ffmpegSkip, timeout: 60000 }, async () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-rot-'));
  try {
    const W = 64; const H = 48;
    // lossless, so the rotated clip's pixels are the stored ones moved
    ffmpeg(['-f', 'lavfi', '-i', `testsrc2=s=${W}x${H}:r=30`, '-frames:v', '3', '-c:v', 'libx264', '-qp', '0', '-pix_fmt', 'yuv444p', join(dir, 'flat.mp4')]);
    const stored = storedFrames(join(dir, 'flat.mp4'), W, H);
    assert.equal(stored.length, 3);
    for (const deg of [0, 90, 180, 270]) {
      const file = join(dir, `r${deg}.mp4`);
      ffmpeg(['-i', join(dir, 'flat.mp4'), '-c', 'copy', '-metadata:s:v:0', `rotate=${deg}`, file]);
      const info = probeVideo(file);
      const quarter = deg % 180 === 90;
      assert.deepEqual([info.width, info.height, info.rotation], [quarter ? H : W, quarter ? W : H, deg], `rotate=${deg}`);
      const frames = await collect(decodeFrames(file, info.width, info.height, null, 0, { decode: 0 }));
      assert.equal(frames.length, 3);
      // shown pixel (x, y) of a counterclockwise turn by deg: the stored pixel it came from
      const src = (x, y) => (deg === 0 ? [x, y] : deg === 90 ? [W - 1 - y, x] : deg === 180 ? [W - 1 - x, H - 1 - y] : [y, H - 1 - x]);
      for (let f = 0; f < 3; ++f) {
        let bad = 0;
        for (let y = 0; y < info.height; ++y) {
          for (let x = 0; x < info.width; ++x) {
            const [sx, sy] = src(x, y);
            for (let c = 0; c < 3; ++c) if (frames[f].rgba[(y * info.width + x) * 3 + c] !== stored[f][(sy * W + sx) * 3 + c]) bad += 1;
          }
        }
        assert.equal(bad, 0, `rotate=${deg} frame ${f}: ${bad} values differ from the stored frame turned counterclockwise`);
      }
    }
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('video input: non-square pixels are probed at the shown size with square pixels (turned with a rotation)', { skip: ffmpegSkip, timeout: 60000 }, () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-sar-'));
  try {
    const cases = [['480x360', '4/3', 0, [640, 360]], ['640x480', '3/4', 0, [640, 640]], ['480x360', '4/3', 90, [360, 640]], ['320x240', '1/1', 0, [320, 240]]];
    for (const [size, sar, deg, want] of cases) {
      const file = join(dir, `s${deg}.mp4`);
      ffmpeg(['-f', 'lavfi', '-i', `testsrc2=s=${size}:r=30`, '-frames:v', '2', '-vf', `setsar=${sar}`, '-c:v', 'libx264', '-pix_fmt', 'yuv420p', join(dir, 'flat.mp4')]);
      ffmpeg(['-i', join(dir, 'flat.mp4'), '-c', 'copy', '-metadata:s:v:0', `rotate=${deg}`, file]);
      const info = probeVideo(file);
      assert.deepEqual([info.width, info.height, info.anamorphic], [...want, sar !== '1/1'], `${size} SAR ${sar} rotate ${deg}`);
    }
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('video input: a variable frame rate gives every frame once, at its own time; a constant one gives no times', { skip: ffmpegSkip, timeout: 60000 }, async () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-vfr-'));
  try {
    // 40 frames at 30 fps; frames 10-19 of the source dropped (a gap of 11 intervals), and from 30
    // on every other one: 25 frames left, their times n / 30 for the kept n
    const kept = [...Array(40).keys()].filter((n) => !(n >= 10 && n < 20) && !(n >= 30 && n % 2 === 1));
    ffmpeg(['-f', 'lavfi', '-i', 'testsrc2=s=96x64:r=30', '-vf', "trim=end_frame=40,select='not(between(n\\,10\\,19))*not(gte(n\\,30)*mod(n\\,2))'",
      '-fps_mode', 'vfr', '-c:v', 'libx264', '-qp', '0', '-pix_fmt', 'yuv444p', join(dir, 'vfr.mp4')]);
    ffmpeg(['-f', 'lavfi', '-i', 'testsrc2=s=96x64:r=30', '-frames:v', '40', '-c:v', 'libx264', '-qp', '0', '-pix_fmt', 'yuv444p', join(dir, 'cfr.mp4')]);
    assert.equal(variableFrameTimes(join(dir, 'cfr.mp4')), null);
    const vfr = variableFrameTimes(join(dir, 'vfr.mp4'));
    assert.ok(vfr, 'the gaps are found');
    assert.equal(vfr.times.length, kept.length);
    kept.forEach((n, i) => assert.ok(Math.abs(vfr.times[i] - (n - kept[0]) / 30) < 1e-3, `frame ${i}: ${vfr.times[i]} s against ${n / 30}`));
    assert.equal(vfr.fps, 30); // the median interval's rate
    // every stored frame once, in order, with its time (the stored frames: ffmpeg's own decoding)
    const stored = storedFrames(join(dir, 'vfr.mp4'), 96, 64);
    assert.equal(stored.length, kept.length);
    const frames = await collect(decodeFrames(join(dir, 'vfr.mp4'), 96, 64, null, 0, { decode: 0 }, vfr.times));
    assert.equal(frames.length, kept.length);
    frames.forEach((f, i) => {
      assert.equal(f.index, i);
      assert.equal(f.time, vfr.times[i]);
      assert.ok(Buffer.from(f.rgba).equals(Buffer.from(stored[i])), `frame ${i} is the stored frame ${i}`);
    });
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('video input: hawor run on a rotated, variable-rate clip reports the shown size and the frames\' own times', { skip: ffmpegSkip || modelsSkipReason() || (existsSync(corePath) ? false : `${corePath} missing`), timeout: 240000 }, () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-rotvfr-'));
  try {
    ffmpeg(['-f', 'lavfi', '-i', 'testsrc2=s=160x96:r=30', '-vf', "trim=end_frame=12,select='not(between(n\\,4\\,7))'", '-fps_mode', 'vfr',
      '-c:v', 'libx264', '-pix_fmt', 'yuv420p', join(dir, 'flat.mp4')]);
    ffmpeg(['-i', join(dir, 'flat.mp4'), '-c', 'copy', '-metadata:s:v:0', 'rotate=270', join(dir, 'clip.mp4')]);
    const r = spawnSync(process.execPath, [join(root, 'web/cli.mjs'), 'run', join(dir, 'clip.mp4'), '--out', join(dir, 'out')],
      { encoding: 'utf8', timeout: 200000, env: { ...process.env, HAWOR_CORE: corePath } });
    assert.equal(r.status, 0, r.stderr);
    const res = JSON.parse(readFileSync(join(dir, 'out', 'result.json'), 'utf8'));
    assert.deepEqual([res.width, res.height, res.frameCount], [96, 160, 8]);
    const ts = res.camera.timestamps;
    [0, 1, 2, 3, 8, 9, 10, 11].forEach((n, i) => assert.ok(Math.abs(ts[i] - n / 30) < 1e-3, `frame ${i}: ${ts[i]} s against ${n / 30}`));
    assert.match(r.stderr, /frame rate varies/);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
