// run_depth.mjs (the node CLI): PNG frames in, .npy depth maps out; clear errors otherwise.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, mkdirSync, writeFileSync, readFileSync, existsSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import pngjs from 'pngjs';
import { decodeNpy } from '../../web/tools/npy.mjs';
import { buildAffineDepthModel, affineDepthConfig, AFFINE_DEFAULTS } from '../../web/tools/make_test_depth_model.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const cli = join(root, 'web/tools/run_depth.mjs');

function runDepth(args) {
  return spawnSync(process.execPath, [cli, ...args], { encoding: 'utf8', timeout: 60000 });
}

function writePng(path, w, h, pixel) {
  const png = new pngjs.PNG({ width: w, height: h });
  for (let y = 0; y < h; ++y) for (let x = 0; x < w; ++x) png.data.set([...pixel(x, y), 255], 4 * (y * w + x));
  writeFileSync(path, pngjs.PNG.sync.write(png, { colorType: 2 }));
}

function affineY(r, g, b) {
  const { weights: wt, bias, normalize: n } = AFFINE_DEFAULTS;
  return bias + [r, g, b].reduce((s, p, c) => s + wt[c] * ((p * n.scale - n.mean[c]) / n.std[c]), 0);
}

test('run_depth: PNG frames -> float32 (H,W) .npy metres, listed frames only, JSON summary', { timeout: 60000 }, () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-run-depth-'));
  try {
    const w = 10;
    const h = 8;
    writeFileSync(join(dir, 'm.onnx'), buildAffineDepthModel({ width: w, height: h }));
    writeFileSync(join(dir, 'c.json'), JSON.stringify(affineDepthConfig({ width: w, height: h, offset: 1 })));
    mkdirSync(join(dir, 'img'));
    const pixel = (f) => (x, y) => [(20 * x + 7 * f) % 256, (30 * y + 3 * f) % 256, (x * y + f) % 256];
    for (const f of [0, 3, 7]) writePng(join(dir, 'img', `${String(f).padStart(6, '0')}.png`), w, h, pixel(f));
    const r = runDepth(['--model', join(dir, 'm.onnx'), '--config', join(dir, 'c.json'), '--images', join(dir, 'img'),
      '--out', join(dir, 'out'), '--frames', '0,7']);
    assert.equal(r.status, 0, r.stderr);
    const summary = JSON.parse(r.stdout);
    assert.equal(summary.images, 2);
    assert.equal(summary.width, w);
    assert.equal(summary.height, h);
    assert.equal(summary.kind, 'metric_depth');
    assert.ok(!existsSync(join(dir, 'out', '000003.npy')), 'an unlisted frame was processed');
    for (const f of [0, 7]) {
      const { shape, data } = decodeNpy(readFileSync(join(dir, 'out', `${String(f).padStart(6, '0')}.npy`)));
      assert.deepEqual(shape, [h, w]);
      assert.ok(data instanceof Float32Array);
      for (let y = 0; y < h; ++y) for (let x = 0; x < w; ++x) {
        const e = affineY(...pixel(f)(x, y)) + 1;
        const a = data[y * w + x];
        if (e > 1e-4) assert.ok(Math.abs(a - e) <= 1e-5 * e, `frame ${f} (${x},${y}): ${a}, expected ${e}`);
        else if (e < -1e-4) assert.ok(Number.isNaN(a), `frame ${f} (${x},${y}): ${a}, expected NaN`);
      }
    }
    // without --frames: every PNG of the folder
    const all = runDepth(['--model', join(dir, 'm.onnx'), '--config', join(dir, 'c.json'), '--images', join(dir, 'img'), '--out', join(dir, 'all')]);
    assert.equal(all.status, 0, all.stderr);
    assert.equal(JSON.parse(all.stdout).images, 3);
    assert.ok(existsSync(join(dir, 'all', '000003.npy')));
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('run_depth: missing or corrupt inputs give one clear line and a non-zero exit', { timeout: 60000 }, () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-run-depth-'));
  try {
    writeFileSync(join(dir, 'm.onnx'), buildAffineDepthModel({ width: 4, height: 4 }));
    writeFileSync(join(dir, 'c.json'), JSON.stringify(affineDepthConfig({ width: 4, height: 4 })));
    writeFileSync(join(dir, 'bad.json'), JSON.stringify({ ...affineDepthConfig({ width: 4, height: 4 }), version: 3 }));
    writeFileSync(join(dir, 'garbage.onnx'), Buffer.from('this is not an onnx file'));
    mkdirSync(join(dir, 'img'));
    writePng(join(dir, 'img', '000000.png'), 4, 4, () => [1, 2, 3]);
    writeFileSync(join(dir, 'img', '000001.png'), readFileSync(join(dir, 'img', '000000.png')).subarray(0, 30));
    mkdirSync(join(dir, 'empty'));
    const base = (o = {}) => {
      const a = { '--model': join(dir, 'm.onnx'), '--config': join(dir, 'c.json'), '--images': join(dir, 'img'), '--out': join(dir, 'out'), ...o };
      return Object.entries(a).filter(([, v]) => v !== null).flat();
    };
    const cases = [
      [base({ '--model': join(dir, 'nope.onnx') }), 1, /run_depth: model '.*nope.onnx' not found/],
      [base({ '--model': join(dir, 'garbage.onnx') }), 1, /run_depth: depth model: cannot load the ONNX model/],
      [base({ '--config': join(dir, 'nope.json') }), 1, /run_depth: config '.*nope.json' not found/],
      [base({ '--config': join(dir, 'bad.json') }), 1, /bad.json: depth config: 'version' must be 1/],
      [base({ '--images': join(dir, 'nope') }), 1, /--images folder '.*nope' not found/],
      [base({ '--images': join(dir, 'empty') }), 1, /no .png file in/],
      [base({ '--frames': '0,5' }), 1, /image '.*000005.png' not found/],
      [base({ '--frames': '1' }), 1, /cannot decode PNG '.*000001.png'/],
      [base({ '--frames': '0,x' }), 2, /--frames: 'x' is not a frame number/],
      [base({ '--out': null }), 2, /--out is required/],
      [[...base(), '--bogus', '1'], 2, /unknown argument '--bogus'/],
    ];
    for (const [args, code, pattern] of cases) {
      const r = runDepth(args);
      assert.equal(r.status, code, `${args.join(' ')}: exit ${r.status}, stderr ${r.stderr}`);
      assert.match(r.stderr, pattern);
      assert.doesNotMatch(r.stderr, /\n\s+at /, 'a stack trace leaked');
    }
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
