// End to end through the depth slot: hawor synth -> hawor slam -> ground-truth depth coded into
// PNGs -> run_depth.mjs with the oracle network -> hawor scale --metric-depth. The scale must
// agree (3 %) with the Sim(3) (Umeyama) scale of the SLAM trajectory onto the ground truth.
// Needs the native hawor binary: $HAWOR_BIN, default build/native/examples/hawor; skipped
// with a message when it is not there.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, mkdirSync, readFileSync, writeFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { inflateRawSync } from 'node:zlib';
import pngjs from 'pngjs';
import { decodeNpy } from '../../web/tools/npy.mjs';
import { buildOracleDepthModel, oracleDepthConfig, ORACLE_MAX_DEPTH } from '../../web/tools/make_test_depth_model.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const bin = resolve(root, process.env.HAWOR_BIN || 'build/native/examples/hawor');
const runDepth = join(root, 'web/tools/run_depth.mjs');

function run(cmd, args, what) {
  const r = spawnSync(cmd, args, { encoding: 'utf8', timeout: 120000, maxBuffer: 1 << 24 });
  if (r.error) throw new Error(`${what}: ${r.error.message}`);
  assert.equal(r.status, 0, `${what} exited ${r.status}: ${r.stderr}`);
  const last = r.stdout.trim().split('\n').at(-1);
  return JSON.parse(last);
}

/** The members of a .npz (zip) file, stored or deflated: {name: Uint8Array}. */
function readZip(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  let eocd = -1;
  for (let i = bytes.length - 22; i >= Math.max(0, bytes.length - 65557); --i) {
    if (view.getUint32(i, true) === 0x06054b50) { eocd = i; break; }
  }
  assert.ok(eocd >= 0, 'npz: no end of central directory');
  const count = view.getUint16(eocd + 10, true);
  let p = view.getUint32(eocd + 16, true);
  const out = {};
  for (let k = 0; k < count; ++k) {
    assert.equal(view.getUint32(p, true), 0x02014b50, 'npz: bad central directory entry');
    const method = view.getUint16(p + 10, true);
    const csize = view.getUint32(p + 20, true);
    const nameLen = view.getUint16(p + 28, true);
    const extraLen = view.getUint16(p + 30, true);
    const commentLen = view.getUint16(p + 32, true);
    const local = view.getUint32(p + 42, true);
    const name = Buffer.from(bytes.subarray(p + 46, p + 46 + nameLen)).toString('utf8');
    const start = local + 30 + view.getUint16(local + 26, true) + view.getUint16(local + 28, true);
    const raw = bytes.subarray(start, start + csize);
    assert.ok(method === 0 || method === 8, `npz: ${name} uses compression method ${method}`);
    out[name] = method === 0 ? raw : new Uint8Array(inflateRawSync(raw));
    p += 46 + nameLen + extraLen + commentLen;
  }
  return out;
}

function readTum(path) {
  return readFileSync(path, 'utf8').split('\n').filter((l) => l.trim() && !l.startsWith('#'))
    .map((l) => l.trim().split(/\s+/).map(Number));
}

/** Eigenvalues of a symmetric 3x3 matrix by cyclic Jacobi rotations. */
function symEigenvalues3(m) {
  const a = m.map((r) => r.slice());
  for (let sweep = 0; sweep < 50; ++sweep) {
    const off = a[0][1] ** 2 + a[0][2] ** 2 + a[1][2] ** 2;
    if (off < 1e-30) break;
    for (const [p, q] of [[0, 1], [0, 2], [1, 2]]) {
      if (Math.abs(a[p][q]) < 1e-300) continue;
      const theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
      const t = Math.sign(theta || 1) / (Math.abs(theta) + Math.sqrt(theta * theta + 1));
      const c = 1 / Math.sqrt(t * t + 1);
      const s = t * c;
      for (let k = 0; k < 3; ++k) { // A <- A J (columns p, q)
        const akp = a[k][p];
        const akq = a[k][q];
        a[k][p] = c * akp - s * akq;
        a[k][q] = s * akp + c * akq;
      }
      for (let k = 0; k < 3; ++k) { // A <- J^T A (rows p, q)
        const apk = a[p][k];
        const aqk = a[q][k];
        a[p][k] = c * apk - s * aqk;
        a[q][k] = s * apk + c * aqk;
      }
    }
  }
  return [a[0][0], a[1][1], a[2][2]];
}

const det3 = (m) => m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
  m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);

/** Umeyama's scale of the similarity that maps points x onto points y:
 *  s = (d1 + d2 + sign(det Sigma) d3) / sigma_x^2, with Sigma = cov(y, x), d_i its singular values
 *  (descending) and sigma_x^2 the mean squared distance of x to its centroid. */
function umeyamaScale(x, y) {
  const n = x.length;
  const mx = [0, 1, 2].map((k) => x.reduce((s, p) => s + p[k], 0) / n);
  const my = [0, 1, 2].map((k) => y.reduce((s, p) => s + p[k], 0) / n);
  const S = [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
  let varx = 0;
  for (let i = 0; i < n; ++i) {
    for (let r = 0; r < 3; ++r) {
      for (let c = 0; c < 3; ++c) S[r][c] += ((y[i][r] - my[r]) * (x[i][c] - mx[c])) / n;
      varx += (x[i][r] - mx[r]) ** 2 / n;
    }
  }
  const StS = [0, 1, 2].map((r) => [0, 1, 2].map((c) => S[0][r] * S[0][c] + S[1][r] * S[1][c] + S[2][r] * S[2][c]));
  const d = symEigenvalues3(StS).map((e) => Math.sqrt(Math.max(0, e))).sort((a, b) => b - a);
  const sign = det3(S) < 0 ? -1 : 1;
  return (d[0] + d[1] + sign * d[2]) / varx;
}

test('umeyamaScale recovers a known similarity (self-check of the test helper)', () => {
  const x = [[0, 0, 0], [1, 0.2, 0], [0.3, 1, 0.1], [0.5, 0.4, 1], [2, 1, -1]];
  const c = Math.cos(0.7);
  const s = Math.sin(0.7);
  const y = x.map(([a, b, z]) => [2.5 * (c * a - s * b) + 1, 2.5 * (s * a + c * b) - 2, 2.5 * z + 0.5]);
  assert.ok(Math.abs(umeyamaScale(x, y) - 2.5) < 1e-9);
  const mirrored = y.map(([a, b, z]) => [a, b, -z]); // a reflection is not a rotation: scale < 2.5
  assert.ok(umeyamaScale(x, mirrored) < 2.4);
});

test('synth -> slam -> oracle depth network -> hawor scale recovers the metric scale', { timeout: 120000 }, (t) => {
  if (!existsSync(bin)) {
    t.skip(`hawor binary not found at ${bin} (build it, or set HAWOR_BIN)`);
    return;
  }
  const dir = mkdtempSync(join(tmpdir(), 'hawor-depth-e2e-'));
  try {
    const syn = join(dir, 'syn');
    run(bin, ['synth', '--preset', 'table_work', '--seed', '1', '--frames', '50', '--size', '320x240', '--out', syn], 'hawor synth');
    const [fx, fy, cx, cy, width, height] = readFileSync(join(syn, 'intrinsics.txt'), 'utf8').trim().split(/\s+/).map(Number);
    assert.equal(width, 320);
    assert.equal(height, 240);
    const traj = join(dir, 'T.tum');
    const kd = join(dir, 'KD.npz');
    run(bin, ['slam', '--images', join(syn, 'rgb'), '--intrinsics', `${fx},${fy},${cx},${cy}`, '--masks', join(syn, 'mask'),
      '--out', traj, '--keyframe-depths', kd], 'hawor slam');
    const frames = Array.from(decodeNpy(readZip(readFileSync(kd))['frames.npy']).data, Number);
    assert.ok(frames.length >= 2, `only ${frames.length} keyframes`);

    // Ground-truth depth of each keyframe -> 16-bit code k = depth * 65536 / ORACLE_MAX_DEPTH
    // in R (high byte) and G (low byte); 0 (no depth) where the truth is not finite.
    const enc = join(dir, 'enc');
    mkdirSync(enc);
    const step = ORACLE_MAX_DEPTH / 65536;
    const truth = {};
    for (const f of frames) {
      const name = String(f).padStart(6, '0');
      const gt = decodeNpy(readFileSync(join(syn, 'depth', `${name}.npy`)));
      assert.deepEqual(gt.shape, [height, width]);
      truth[f] = gt.data;
      const png = new pngjs.PNG({ width, height });
      for (let i = 0; i < width * height; ++i) {
        const d = gt.data[i];
        const k = Number.isFinite(d) && d > 0 ? Math.min(65535, Math.max(1, Math.round(d / step))) : 0;
        png.data.set([k >> 8, k & 255, 0, 255], 4 * i);
      }
      writeFileSync(join(enc, `${name}.png`), pngjs.PNG.sync.write(png, { colorType: 2 }));
    }

    // The oracle network at half the image size: run_depth resizes down and back up.
    const models = join(dir, 'models');
    mkdirSync(models);
    writeFileSync(join(models, 'oracle.onnx'), buildOracleDepthModel({ width: 160, height: 120 }));
    writeFileSync(join(models, 'oracle.json'), JSON.stringify(oracleDepthConfig({ width: 160, height: 120 })));
    const md = join(dir, 'metric_depth');
    const summary = run(process.execPath, [runDepth, '--model', join(models, 'oracle.onnx'), '--config', join(models, 'oracle.json'),
      '--images', enc, '--out', md, '--frames', frames.join(',')], 'run_depth');
    assert.equal(summary.images, frames.length);
    assert.equal(summary.width, width);
    assert.equal(summary.height, height);

    // The depth maps come back in metres: smooth surfaces exactly (to the code step), depth
    // edges blurred by the resampling, so the median error is tiny.
    for (const f of frames) {
      const got = decodeNpy(readFileSync(join(md, `${String(f).padStart(6, '0')}.npy`)));
      assert.deepEqual(got.shape, [height, width]);
      const rel = [];
      for (let i = 0; i < width * height; ++i) {
        const e = Math.abs(got.data[i] - truth[f][i]) / truth[f][i];
        rel.push(Number.isNaN(e) ? Infinity : e);
      }
      rel.sort((a, b) => a - b);
      assert.ok(rel[Math.floor(rel.length / 2)] < 1e-3, `frame ${f}: median relative depth error ${rel[Math.floor(rel.length / 2)]}`);
    }

    const scaled = run(bin, ['scale', '--traj', traj, '--keyframe-depths', kd, '--metric-depth', md, '--masks', join(syn, 'mask'),
      '--out', join(dir, 'M.tum')], 'hawor scale');
    assert.equal(scaled.method, 'depth');

    const est = readTum(traj);
    const gt = readTum(join(syn, 'camera_gt.tum'));
    assert.equal(est.length, gt.length);
    for (let i = 0; i < est.length; ++i) assert.ok(Math.abs(est[i][0] - gt[i][0]) < 1e-6, `timestamps differ at line ${i}`);
    const sim3 = umeyamaScale(est.map((r) => r.slice(1, 4)), gt.map((r) => r.slice(1, 4)));
    const err = Math.abs(scaled.scale / sim3 - 1);
    t.diagnostic(`hawor scale ${scaled.scale}, Sim(3) scale ${sim3}, error ${(100 * err).toFixed(2)} %, keyframes ${frames.join(',')}`);
    assert.ok(err < 0.03, `scale ${scaled.scale} vs Sim(3) ${sim3}: ${(100 * err).toFixed(2)} % off`);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
