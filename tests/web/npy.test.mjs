// npy.mjs: the .npy files run_depth writes are what numpy (and hawor) read.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, writeFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { encodeNpyFloat32, decodeNpy } from '../../web/tools/npy.mjs';

test('float32 .npy: format 1.0 header, 64-byte aligned data, round trip', () => {
  const data = Float32Array.from([1.5, -2, NaN, Infinity, 0, 3.25]);
  const bytes = encodeNpyFloat32(data, [2, 3]);
  assert.deepEqual(Array.from(bytes.subarray(0, 8)), [0x93, 78, 85, 77, 80, 89, 1, 0]);
  const headerLen = bytes[8] | (bytes[9] << 8);
  assert.equal((10 + headerLen) % 64, 0);
  assert.equal(bytes.length, 10 + headerLen + 24);
  const header = Buffer.from(bytes.subarray(10, 10 + headerLen)).toString('latin1');
  assert.match(header, /^\{'descr': '<f4', 'fortran_order': False, 'shape': \(2, 3\), \} *\n$/);
  const back = decodeNpy(bytes);
  assert.deepEqual(back.shape, [2, 3]);
  assert.deepEqual(Array.from(back.data), Array.from(data));
  assert.deepEqual(decodeNpy(encodeNpyFloat32(new Float32Array(4), [4])).shape, [4]);
  // inside a larger buffer at an odd offset (node Buffers share a pool like this)
  const pool = Buffer.alloc(bytes.length + 13, 0x55);
  pool.set(bytes, 5);
  assert.deepEqual(Array.from(decodeNpy(pool.subarray(5, 5 + bytes.length)).data), Array.from(data));
  assert.throws(() => encodeNpyFloat32(new Float32Array(5), [2, 3]), /5 values for shape \(2, 3\)/);
  assert.throws(() => decodeNpy(new Uint8Array(20)), /bad magic/);
  assert.throws(() => decodeNpy(bytes.subarray(0, bytes.length - 1)), /truncated data/);
});

test('numpy reads what encodeNpyFloat32 writes', (t) => {
  const python = '/usr/bin/python3';
  if (!existsSync(python) || spawnSync(python, ['-c', 'import numpy'], { timeout: 20000 }).status !== 0) {
    t.skip('no /usr/bin/python3 with numpy');
    return;
  }
  const dir = mkdtempSync(join(tmpdir(), 'hawor-npy-'));
  try {
    const h = 3;
    const w = 5;
    const data = Float32Array.from({ length: h * w }, (_, i) => (i === 7 ? NaN : i * 0.5 - 2));
    writeFileSync(join(dir, 'a.npy'), encodeNpyFloat32(data, [h, w]));
    const script = 'import sys, numpy as np\n' +
      'a = np.load(sys.argv[1])\n' +
      'print(a.dtype.str, a.shape, a.flags["C_CONTIGUOUS"], int(np.isnan(a).sum()), float(np.nansum(a)), float(a[2, 4]))\n';
    const r = spawnSync(python, ['-c', script, join(dir, 'a.npy')], { encoding: 'utf8', timeout: 20000 });
    assert.equal(r.status, 0, r.stderr);
    const nansum = Array.from(data).filter((v) => !Number.isNaN(v)).reduce((a, b) => a + b, 0);
    assert.equal(r.stdout.trim(), `<f4 (3, 5) True 1 ${nansum.toFixed(1)} ${data[14].toFixed(1)}`);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
