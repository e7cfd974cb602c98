// make_infiller_model.mjs and npz.mjs: the ONNX infiller fixture runs in onnxruntime with the
// documented inputs/outputs and masking, and its .npz is what numpy reads. (The comparison
// with the C++ network is tests/motion/ref_infiller_net.cpp.)

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { ort } from './support.mjs';
import { crc32, encodeStoredZip } from '../../web/tools/npz.mjs';
import { SMALL_CONFIG, buildInfillerOnnx, encodeInfillerNpz, infillerTensorSpecs, randomInfillerWeights } from '../../web/tools/make_infiller_model.mjs';

const python = '/usr/bin/python3';

test('crc32 and stored zip layout', () => {
  assert.equal(crc32(new TextEncoder().encode('123456789')), 0xcbf43926); // the CRC-32 check value
  assert.equal(crc32(new Uint8Array(0)), 0);
  const zip = encodeStoredZip([{ name: 'a.txt', bytes: new Uint8Array([1, 2, 3]) }]);
  const view = new DataView(zip.buffer);
  assert.equal(view.getUint32(0, true), 0x04034b50);
  assert.equal(view.getUint32(zip.length - 22, true), 0x06054b50);
  assert.equal(view.getUint32(zip.length - 6, true), 30 + 5 + 3); // central directory offset
  assert.throws(() => encodeStoredZip([{ name: '', bytes: new Uint8Array(1) }]), /needs a name/);
});

test('infiller .npz: numpy reads every tensor with its name, shape and values', { skip: !existsSync(python) && 'no /usr/bin/python3' }, () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-infiller-'));
  try {
    const weights = randomInfillerWeights(SMALL_CONFIG, 3);
    writeFileSync(join(dir, 'w.npz'), encodeInfillerNpz(weights));
    const specs = infillerTensorSpecs(SMALL_CONFIG);
    const script = [
      'import json, sys, numpy as np',
      `z = np.load(sys.argv[1])`,
      'print(json.dumps({k: [list(z[k].shape), str(z[k].dtype), float(z[k].ravel()[0]), float(z[k].sum())] for k in z.files}))',
    ].join('\n');
    const r = spawnSync(python, ['-c', script, join(dir, 'w.npz')], { encoding: 'utf8' });
    assert.equal(r.status, 0, r.stderr);
    const got = JSON.parse(r.stdout);
    assert.deepEqual(Object.keys(got), specs.map((s) => s.name));
    for (const { name, shape } of specs) {
      const [gShape, dtype, first, sum] = got[name];
      const { data } = weights.get(name);
      assert.deepEqual(gShape, shape, name);
      assert.equal(dtype, 'float32', name);
      assert.equal(first, data[0], name);
      const expect = data.reduce((a, b) => a + b, 0);
      assert.ok(Math.abs(sum - expect) <= 1e-4 * (1 + Math.abs(expect)), `${name}: sum ${sum} vs ${expect}`);
    }
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

async function run(session, config, x, valid) {
  const r = await session.run({ x: new ort.Tensor('float32', x, [config.window, config.features]), valid: new ort.Tensor('float32', valid, [config.window, 1]) });
  return r.y;
}

test('infiller ONNX: shapes, and masked frames are invisible to the masked blocks only', { timeout: 60000 }, async () => {
  for (const encoderLayers of [0, SMALL_CONFIG.encoderLayers]) {
    const config = { ...SMALL_CONFIG, encoderLayers };
    const session = await ort.InferenceSession.create(buildInfillerOnnx(config, randomInfillerWeights(config, 5)));
    assert.deepEqual(session.inputNames, ['x', 'valid']);
    assert.deepEqual(session.outputNames, ['y']);
    const { window: W, features: F } = config;
    const x = Float32Array.from({ length: W * F }, (_, i) => Math.sin(0.37 * i));
    const valid = new Float32Array(W).fill(1);
    for (let t = 3; t < 9; ++t) valid[t] = 0;
    const y = await run(session, config, x, valid);
    assert.deepEqual(y.dims, [W, F]);
    assert.ok(y.data.every(Number.isFinite));
    const x2 = x.slice();
    for (let c = 0; c < F; ++c) x2[5 * F + c] += 3; // frame 5 is masked
    const y2 = (await run(session, config, x2, valid)).data;
    let others = 0;
    let self = 0;
    for (let t = 0; t < W; ++t) {
      for (let c = 0; c < F; ++c) {
        const d = Math.abs(y2[t * F + c] - y.data[t * F + c]);
        if (t === 5) self = Math.max(self, d);
        else others = Math.max(others, d);
      }
    }
    assert.ok(self > 1e-3, `masked frame's own output moved by ${self}`);
    if (encoderLayers === 0) assert.ok(others <= 1e-6, `other frames moved by ${others} with the mask`);
    else assert.ok(others > 1e-4, `the unmasked encoder should see frame 5 (moved ${others})`);
    // the validity input matters
    const valid2 = valid.slice();
    valid2[20] = 0;
    const y3 = (await run(session, config, x, valid2)).data;
    assert.ok(y3.some((v, i) => Math.abs(v - y.data[i]) > 1e-4));
  }
});
