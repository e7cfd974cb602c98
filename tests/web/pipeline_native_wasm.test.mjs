// One pipeline in C++ (include/hawor/pipeline/pipeline.hpp), two drivers: the JavaScript entry
// (runPipeline with camera-frame hands, through the WebAssembly core) and the native `hawor
// world` on the same `hawor synth` sequence and its ground-truth camera-frame hands, given as MANO
// parameters and as 3D joints. They give
// the same camera and world hands up to floating-point reassociation; bad hands files are refused
// naming the file and the key. Skipped with a message without the core, the native CLI, ffmpeg
// or the default hand models.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { root } from './mediapipe_support.mjs';
import { runPipeline } from '../../web/src/pipeline/run.mjs';

const corePath = process.env.HAWOR_CORE ?? join(root, 'build/wasm/wasm/hawor_core.mjs');
const haworBin = process.env.HAWOR_BIN ?? join(root, 'build/native/examples/hawor');
const modelsDir = join(root, 'build/native/models');
const hasFfmpeg = spawnSync('ffmpeg', ['-version'], { stdio: 'ignore' }).status === 0;
const skip = !existsSync(corePath) ? `${corePath} missing` : !existsSync(haworBin) ? `${haworBin} missing`
  : !hasFfmpeg ? 'ffmpeg is not installed' : !existsSync(join(modelsDir, 'hand_left.npz')) ? `${modelsDir}/hand_left.npz missing (cmake --build build/native --target default_hands)` : false;

const hasNumpy = spawnSync('/usr/bin/python3', ['-c', 'import numpy'], { stdio: 'ignore' }).status === 0;
const W = 640, H = 480, T = 40;

test('pipeline: camera-frame hands through node (WebAssembly core) and native `hawor world` give the same world', { skip, timeout: 300000 }, async (t) => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-world-'));
  try {
    execFileSync(haworBin, ['synth', '--preset', 'table_work', '--seed', '2', '--frames', String(T), '--size', `${W}x${H}`, '--out', join(dir, 'seq')], { stdio: 'ignore' });
    const [fx, fy, cx, cy] = readFileSync(join(dir, 'seq/intrinsics.txt'), 'utf8').split('\n')[0].trim().split(/\s+/).map(Number);
    // runPipeline centres the principal point; the native run is given the same intrinsics
    assert.ok(Math.abs(cx - (W - 1) / 2) < 1e-9 && Math.abs(cy - (H - 1) / 2) < 1e-9 && fx === fy);
    const { loadCore } = await import('../../web/cli.mjs');
    const core = await loadCore(corePath);
    const gt = core.readNpz(readFileSync(join(dir, 'seq/hands_gt.npz')), 'hands_gt.npz');
    const rgb = execFileSync('ffmpeg', ['-v', 'error', '-i', join(dir, 'seq/rgb/%06d.png'), '-f', 'rawvideo', '-pix_fmt', 'rgb24', '-'], { maxBuffer: 1 << 28 });
    assert.equal(rgb.length, T * W * H * 3);
    const row = (key, f, n) => gt[key].data.subarray(n * f, n * (f + 1));
    const handModels = { left: readFileSync(join(modelsDir, 'hand_left.npz')), right: readFileSync(join(modelsDir, 'hand_right.npz')) };
    // the hands as MANO parameters, then as 3D joints (the model fitted to them)
    for (const input of ['params', 'joints']) {
      const native = spawnSync(haworBin, ['world', '--images', join(dir, 'seq/rgb'), '--hands', join(dir, 'seq/hands_gt.npz'), '--hands-input', input,
        '--intrinsics', `${fx},${fy},${cx},${cy}`, '--out', join(dir, input)], { encoding: 'utf8', env: { ...process.env, HAWOR_HAND_DIR: modelsDir } });
      assert.equal(native.status, 0, native.stderr);
      const summary = JSON.parse(native.stdout);
      assert.equal(summary.frames, T);
      const frames = (async function* () { for (let f = 0; f < T; ++f) yield { index: f, rgba: new Uint8Array(rgb.buffer, rgb.byteOffset + f * W * H * 3, W * H * 3) }; })();
      const handsCam = (f) => {
        const out = {};
        for (const side of ['left', 'right']) {
          out[side] = !gt[`${side}_valid`].data[f] ? null : input === 'joints' ? { joints: row(`${side}_joints_cam`, f, 63) }
            : { rot: row(`${side}_cam_rot`, f, 3), trans: row(`${side}_cam_trans`, f, 3),
              handPose: row(`${side}_hand_pose`, f, gt[`${side}_hand_pose`].data.length / T), betas: row(`${side}_betas`, f, gt[`${side}_betas`].data.length / T) };
        }
        return out;
      };
      const r = await runPipeline({ width: W, height: H, fps: 30, frameCount: T, frames },
        { core, handModels: { left: new Uint8Array(handModels.left), right: new Uint8Array(handModels.right) }, handsCam, focalPx: fx });

      assert.equal(r.scale.method, summary.method);
      assert.ok(Math.abs(r.scale.scale - summary.scale) <= 1e-9 * summary.scale, `${input}: scale ${r.scale.scale} / ${summary.scale}`);
      assert.equal(r.modelKind, 'camera-frame hands');
      // the camera (TUM: t x y z qx qy qz qw)
      const tum = readFileSync(join(dir, input, 'camera.tum'), 'utf8').trim().split('\n').filter((l) => !l.startsWith('#')).map((l) => l.trim().split(/\s+/).map(Number));
      assert.equal(tum.length, T);
      let dCam = 0;
      for (let f = 0; f < T; ++f) for (let a = 0; a < 3; ++a) dCam = Math.max(dCam, Math.abs(tum[f][1 + a] - r.camera.positions[3 * f + a]));
      // the world hands
      const world = core.readNpz(readFileSync(join(dir, input, 'world.npz')), 'world.npz');
      let dHand = 0, compared = 0;
      for (const side of ['left', 'right']) {
        const a = world[`${side}_joints_world`].data, b = r.hands[side].jointsWorld;
        assert.equal(a.length, b.length);
        for (let i = 0; i < a.length; ++i) {
          if (Number.isNaN(a[i]) || Number.isNaN(b[i])) { assert.ok(Number.isNaN(a[i]) && Number.isNaN(b[i]), `${input}, ${side} joint ${i}: NaN in one run only`); continue; }
          dHand = Math.max(dHand, Math.abs(a[i] - b[i]));
          compared += 1;
        }
        assert.deepEqual(Array.from(world[`${side}_valid`].data), Array.from(r.hands[side].valid));
      }
      assert.ok(compared > 1000, `${compared} joint coordinates compared`);
      t.diagnostic(`${input}, native vs node: camera ${dCam} m, world joints ${dHand} m over ${compared} coordinates; scale ${summary.scale} (${summary.method})`);
      assert.ok(dCam <= 1e-6, `${input}: camera positions differ by ${dCam} m`);
      assert.ok(dHand <= 1e-6, `${input}: world joints differ by ${dHand} m`);
    }
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('hawor world: bad hands files are refused naming the file and the key', { skip: skip || (hasNumpy ? false : 'no /usr/bin/python3 with numpy (it writes the bad files)'), timeout: 120000 }, () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-world-bad-'));
  try {
    execFileSync(haworBin, ['synth', '--preset', 'walk', '--seed', '1', '--frames', '4', '--size', '160x120', '--out', join(dir, 'seq')], { stdio: 'ignore' });
    const py = (code) => spawnSync('/usr/bin/python3', ['-c', code], { encoding: 'utf8' });
    const make = (name, edit) => {
      const r = py(`import numpy as np\nz = dict(np.load('${dir}/seq/hands_gt.npz'))\n${edit}\nnp.savez('${dir}/${name}', **z)`);
      assert.equal(r.status, 0, r.stderr);
      return join(dir, name);
    };
    const world = (hands, extra = []) => spawnSync(haworBin, ['world', '--images', join(dir, 'seq/rgb'), '--hands', hands, '--out', join(dir, 'out'), ...extra],
      { encoding: 'utf8', env: { ...process.env, HAWOR_HAND_DIR: modelsDir } });
    let r = world(make('short.npz', "z = {k: (v[:3] if v.ndim and v.shape[0] == 4 else v) for k, v in z.items()}"));
    assert.equal(r.status, 1);
    assert.match(r.stderr, /short\.npz: 'left_\w+' has 3 frames, .* has 4 images/);
    r = world(make('nokey.npz', "del z['right_cam_trans']"));
    assert.equal(r.status, 1);
    assert.match(r.stderr, /nokey\.npz: the right hand lacks 'right_cam_trans'/);
    r = world(make('nan.npz', "z['left_valid'][:] = True\nz['left_cam_rot'][2, 1] = np.nan"));
    assert.equal(r.status, 1);
    assert.match(r.stderr, /nan\.npz: 'left_cam_rot' holds a non-finite value at frame 2/);
    r = world(make('size.npz', "z['image_size'] = np.array([640, 480])"));
    assert.equal(r.status, 1);
    assert.match(r.stderr, /size\.npz: 'image_size' says the hands were estimated on other frames than the 160x120 ones/);
    writeFileSync(join(dir, 'junk.npz'), 'not a zip');
    r = world(join(dir, 'junk.npz'));
    assert.equal(r.status, 1);
    assert.match(r.stderr, /junk\.npz/);
    r = world(join(dir, 'seq/hands_gt.npz'), ['--fov', '400']);
    assert.equal(r.status, 2);
    assert.match(r.stderr, /--fov/);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
