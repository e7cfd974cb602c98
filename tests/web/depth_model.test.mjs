// DepthModel: the depth slot gives the known function of the test networks, at and away from
// the network's input size, for both output kinds and layouts, RGB and RGBA; and refuses
// mismatched or corrupt models with a clear error.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { DepthModel, resizeBilinear } from '../../web/src/depth_model.mjs';
import {
  buildAffineDepthModel, affineDepthConfig, AFFINE_DEFAULTS, buildOracleDepthModel, oracleDepthConfig, ORACLE_MAX_DEPTH,
} from '../../web/tools/make_test_depth_model.mjs';
import { ort, rng, assertClose } from './support.mjs';

/** The affine network's output for one pixel, from its definition (make_test_depth_model.mjs). */
function affineY(r, g, b) {
  const { weights: w, bias, normalize: n } = AFFINE_DEFAULTS;
  const px = [r, g, b];
  let y = bias;
  for (let c = 0; c < 3; ++c) y += w[c] * ((px[c] * n.scale - n.mean[c]) / n.std[c]);
  return y;
}

function randomImage(seed, w, h, channels = 3) {
  const r = rng(seed);
  return Uint8Array.from({ length: w * h * channels }, () => Math.floor(r() * 256));
}

/** Expected depth per pixel of an RGB(A) image for depth = f(y), NaN where not finite > 0. */
function expectedDepth(img, w, h, channels, f) {
  const out = new Float64Array(w * h);
  for (let i = 0; i < w * h; ++i) {
    const d = f(affineY(img[i * channels], img[i * channels + 1], img[i * channels + 2]));
    out[i] = Number.isFinite(d) && d > 0 ? d : NaN;
  }
  return out;
}

/** Compares depth maps: NaN exactly where expected is NaN, except pixels whose expected value
 *  sits within `margin` of the validity threshold; values to rel 1e-5. */
function assertDepth(actual, expected, { rel = 1e-5, abs = 1e-6, skip = () => false } = {}) {
  assert.equal(actual.length, expected.length);
  let compared = 0;
  for (let i = 0; i < expected.length; ++i) {
    if (skip(i)) continue;
    const e = expected[i];
    const a = actual[i];
    if (Number.isNaN(e)) {
      assert.ok(Number.isNaN(a), `pixel ${i}: ${a}, expected NaN`);
    } else {
      assert.ok(Math.abs(a - e) <= rel * Math.abs(e) + abs, `pixel ${i}: ${a}, expected ${e}`);
      compared += 1;
    }
  }
  return compared;
}

const nearZero = (img, channels, eps) => (i) => Math.abs(affineY(img[i * channels], img[i * channels + 1], img[i * channels + 2])) < eps;

test('at the network size the depth is the known affine function (NCHW, metric depth)', async () => {
  const w = 12;
  const h = 9;
  const model = await DepthModel.create(ort, buildAffineDepthModel({ width: w, height: h }),
    affineDepthConfig({ width: w, height: h, multiplier: 2, offset: 0.1 }));
  const img = randomImage(1, w, h);
  const depth = await model.predict(img, w, h);
  assert.ok(depth instanceof Float32Array);
  const expected = expectedDepth(img, w, h, 3, (y) => 2 * y + 0.1);
  const n = assertDepth(depth, expected, { skip: nearZero(img, 3, 1e-4) });
  assert.ok(n > w * h / 3, `only ${n} valid pixels compared`);
  assert.ok(expected.some(Number.isNaN), 'the test image must also produce invalid (<= 0) depth');
  await model.dispose();
  await assert.rejects(model.predict(img, w, h), /after dispose/);
});

test('metric inverse depth: depth = 1 / (m y + o)', async () => {
  const w = 10;
  const h = 7;
  const model = await DepthModel.create(ort, buildAffineDepthModel({ width: w, height: h }),
    affineDepthConfig({ width: w, height: h, kind: 'metric_inverse_depth', multiplier: 0.5, offset: 0.2 }));
  const img = randomImage(2, w, h);
  const depth = await model.predict(img, w, h);
  const expected = expectedDepth(img, w, h, 3, (y) => 1 / (0.5 * y + 0.2));
  const skip = (i) => Math.abs(0.5 * affineY(img[3 * i], img[3 * i + 1], img[3 * i + 2]) + 0.2) < 1e-3;
  assertDepth(depth, expected, { rel: 1e-4, skip });
  await model.dispose();
});

test('NHWC layout with a (1,h,w) output, and an (h,w) output, give the same function', async () => {
  const w = 8;
  const h = 6;
  const img = randomImage(3, w, h);
  const expected = expectedDepth(img, w, h, 3, (y) => y);
  const nhwc = await DepthModel.create(ort, buildAffineDepthModel({ width: w, height: h, layout: 'NHWC' }),
    affineDepthConfig({ width: w, height: h, layout: 'NHWC' }));
  assertDepth(await nhwc.predict(img, w, h), expected, { skip: nearZero(img, 3, 1e-4) });
  await nhwc.dispose();
  const hw = await DepthModel.create(ort, buildAffineDepthModel({ width: w, height: h, outputShape: 'hxw' }),
    affineDepthConfig({ width: w, height: h }));
  assertDepth(await hw.predict(img, w, h), expected, { skip: nearZero(img, 3, 1e-4) });
  await hw.dispose();
});

test('RGBA input gives exactly the RGB result (alpha ignored)', async () => {
  const w = 9;
  const h = 5;
  const model = await DepthModel.create(ort, buildAffineDepthModel({ width: 6, height: 4 }), affineDepthConfig({ width: 6, height: 4 }));
  const rgb = randomImage(4, w, h);
  const alpha = randomImage(5, w, h, 1);
  const rgba = new Uint8Array(w * h * 4);
  for (let i = 0; i < w * h; ++i) {
    rgba.set(rgb.subarray(3 * i, 3 * i + 3), 4 * i);
    rgba[4 * i + 3] = alpha[i];
  }
  const a = await model.predict(rgb, w, h, 3);
  const b = await model.predict(new Uint8ClampedArray(rgba.buffer), w, h, 4);
  assert.deepEqual(Array.from(b), Array.from(a));
  await model.dispose();
});

test('a resized linear gradient: the interior matches the known function of the gradient', async () => {
  // R = 4x + 10, G = 6y + 5, B = 100 (exact bytes). Bilinear resampling reproduces a linear
  // function exactly wherever it does not clamp at the border, so after the resize down to
  // the network (32x24), the affine network and the resize back to 50x37, every interior
  // pixel must hold f(R(x), G(y), B) itself (offset 1 keeps the depth positive).
  const w = 50;
  const h = 37;
  const mw = 32;
  const mh = 24;
  const img = new Uint8Array(w * h * 3);
  for (let y = 0; y < h; ++y) for (let x = 0; x < w; ++x) img.set([4 * x + 10, 6 * y + 5, 100], 3 * (y * w + x));
  const model = await DepthModel.create(ort, buildAffineDepthModel({ width: mw, height: mh }), affineDepthConfig({ width: mw, height: mh, offset: 1 }));
  const depth = await model.predict(img, w, h);
  assert.equal(depth.length, w * h);
  const mx = Math.ceil(w / mw) + 1;
  const my = Math.ceil(h / mh) + 1;
  let compared = 0;
  for (let y = my; y < h - my; ++y) for (let x = mx; x < w - mx; ++x) {
    const e = affineY(4 * x + 10, 6 * y + 5, 100) + 1;
    const a = depth[y * w + x];
    assert.ok(e > 0.05, 'the gradient is chosen to give positive depth');
    assert.ok(Math.abs(a - e) <= 1e-5 * e, `(${x},${y}): ${a}, expected ${e}`);
    compared += 1;
  }
  assert.ok(compared > 0.6 * w * h);
  // Upsampling from a smaller image is exact in the interior too.
  const small = new Uint8Array(20 * 15 * 3);
  for (let y = 0; y < 15; ++y) for (let x = 0; x < 20; ++x) small.set([4 * x + 10, 6 * y + 5, 100], 3 * (y * 20 + x));
  const up = await model.predict(small, 20, 15);
  for (let y = 1; y < 14; ++y) for (let x = 1; x < 19; ++x) {
    const e = affineY(4 * x + 10, 6 * y + 5, 100) + 1;
    assert.ok(Math.abs(up[y * 20 + x] - e) <= 1e-5 * e, `small (${x},${y}): ${up[y * 20 + x]}, expected ${e}`);
  }
  await model.dispose();
});

test('resampling uses half-pixel centres (align_corners=false), both ways', async () => {
  // 4 -> 2: destination pixel x samples (x + 0.5) * 2 - 0.5 = 0.5, 2.5: block means.
  assert.deepEqual(Array.from(resizeBilinear(Float32Array.from([0, 1, 2, 6]), 4, 1, 2, 1)), [0.5, 4]);
  // 2 -> 4: samples at -0.25 (clamped to 0), 0.25, 0.75, 1.25 (clamped to 1).
  assert.deepEqual(Array.from(resizeBilinear(Float32Array.from([0, 8]), 2, 1, 4, 1)), [0, 2, 6, 8]);
  // 2-D: 2x2 -> 1x1 is the mean; a NaN of weight 0 does not spread, one of weight > 0 does.
  assert.deepEqual(Array.from(resizeBilinear(Float32Array.from([1, 2, 3, 6]), 2, 2, 1, 1)), [3]);
  assert.deepEqual(Array.from(resizeBilinear(Float32Array.from([1, NaN, 3, 4]), 2, 2, 2, 2)), [1, NaN, 3, 4]);
  assert.ok(Number.isNaN(resizeBilinear(Float32Array.from([1, NaN, 3, 4]), 2, 2, 1, 1)[0]));
  // The network input: a 4x2 image to a 2x1 network averages 2x2 blocks, per channel, then
  // normalises: (mean * scale - mean_c) / std_c.
  const model = await DepthModel.create(ort, buildAffineDepthModel({ width: 2, height: 1 }), affineDepthConfig({ width: 2, height: 1 }));
  const img = new Uint8Array(4 * 2 * 3);
  for (let i = 0; i < 8; ++i) img.set([10 * i, 20 + 5 * i, 200 - 7 * i], 3 * i);
  const t = model.prepareInput(img, 4, 2, 3);
  assert.deepEqual(Array.from(t.dims), [1, 3, 1, 2]);
  const n = AFFINE_DEFAULTS.normalize;
  const expected = [];
  for (let c = 0; c < 3; ++c) for (const x0 of [0, 2]) {
    const px = [x0, x0 + 1, 4 + x0, 5 + x0].map((i) => img[3 * i + c]);
    expected.push(((px.reduce((a, b) => a + b, 0) / 4) * n.scale - n.mean[c]) / n.std[c]);
  }
  assertClose(t.data, expected, { rel: 1e-6, abs: 1e-6, what: 'network input' });
  await model.dispose();
});

test('the oracle network returns the depth coded in R (high byte) and G (low byte)', async () => {
  const w = 16;
  const h = 12;
  const r = rng(9);
  const step = ORACLE_MAX_DEPTH / 65536;
  const truth = Float64Array.from({ length: w * h }, () => 0.2 + 5 * r());
  const img = new Uint8Array(w * h * 3);
  truth.forEach((d, i) => {
    const k = Math.round(d / step);
    img.set([k >> 8, k & 255, 0], 3 * i);
  });
  img.set([0, 0, 0], 0); // code 0 = no depth
  const model = await DepthModel.create(ort, buildOracleDepthModel({ width: w, height: h }), oracleDepthConfig({ width: w, height: h }));
  const depth = await model.predict(img, w, h);
  assert.ok(Number.isNaN(depth[0]));
  for (let i = 1; i < w * h; ++i) assert.ok(Math.abs(depth[i] - truth[i]) <= step, `pixel ${i}: ${depth[i]} vs ${truth[i]}`);
  await model.dispose();
});

test('a model with symbolic input dims runs at the size the config gives', async () => {
  const model = await DepthModel.create(ort, buildAffineDepthModel({ symbolicSize: true }), affineDepthConfig({ width: 7, height: 5 }));
  const img = randomImage(6, 7, 5);
  assertDepth(await model.predict(img, 7, 5), expectedDepth(img, 7, 5, 3, (y) => y), { skip: nearZero(img, 3, 1e-4) });
  await model.dispose();
});

test('model/config mismatches are named', async () => {
  const bytes = buildAffineDepthModel({ width: 32, height: 24 });
  const cfg = (o) => affineDepthConfig({ width: 32, height: 24, ...o });
  await assert.rejects(DepthModel.create(ort, bytes, cfg({ inputName: 'pixels' })), /input.name is 'pixels' but the model's inputs are \[image\]/);
  await assert.rejects(DepthModel.create(ort, bytes, cfg({ outputName: 'disparity' })), /output.name is 'disparity' but the model's outputs are \[depth\]/);
  await assert.rejects(DepthModel.create(ort, bytes, affineDepthConfig({ width: 30, height: 24 })), /input 'image' has shape \[1, 3, 24, 32\] but the config \(NCHW, 30x24\)/);
  await assert.rejects(DepthModel.create(ort, bytes, cfg({ layout: 'NHWC' })), /has shape \[1, 3, 24, 32\] but the config \(NHWC/);
  const bad = await DepthModel.create(ort, buildAffineDepthModel({ width: 8, height: 6, outputShape: 'bad' }), affineDepthConfig({ width: 8, height: 6 }));
  await assert.rejects(bad.predict(randomImage(1, 8, 6), 8, 6), /output 'depth' has shape \[1, 2, 6, 8\]; a depth map must be/);
  await bad.dispose();
  const ok = await DepthModel.create(ort, bytes, cfg({ inputName: 'image', outputName: 'depth' }));
  await assert.rejects(ok.predict(new Uint8Array(10), 4, 4), /10 bytes, 4x4x3 = 48 expected/);
  await assert.rejects(ok.predict(new Uint8Array(32), 4, 4, 2), /channels must be 3 or 4/);
  await assert.rejects(ok.predict([1, 2, 3], 1, 1), /must be a Uint8Array/);
  await ok.dispose();
  await assert.rejects(DepthModel.create({}, bytes, cfg({})), /onnxruntime namespace/);
});

test('corrupt, truncated or empty ONNX bytes fail with a clear error, never a hang', { timeout: 30000 }, async () => {
  const cfg = affineDepthConfig({ width: 8, height: 6 });
  const good = buildAffineDepthModel({ width: 8, height: 6 });
  const r = rng(3);
  const noise = Uint8Array.from({ length: 4096 }, () => Math.floor(r() * 256));
  await assert.rejects(DepthModel.create(ort, noise, cfg), /cannot load the ONNX model/);
  await assert.rejects(DepthModel.create(ort, good.slice(0, good.length - 7), cfg), /cannot load the ONNX model/);
  await assert.rejects(DepthModel.create(ort, good.slice(0, 40), cfg), /cannot load the ONNX model/);
  await assert.rejects(DepthModel.create(ort, new Uint8Array(0), cfg), /model file is empty/);
  await assert.rejects(DepthModel.create(ort, 'model.onnx', cfg), /must be a Uint8Array or ArrayBuffer/);
  // a valid protobuf that is not a usable model (a graph with an unknown operator)
  const flipped = good.slice();
  const at = Buffer.from(flipped).indexOf(Buffer.from([0x22, 4, ...Buffer.from('Conv')])); // op_type = 4, 4 bytes
  assert.ok(at > 0);
  flipped.set([0x58, 0x58, 0x58, 0x58], at + 2); // op_type "XXXX"
  await assert.rejects(DepthModel.create(ort, flipped, cfg), /cannot load the ONNX model/);
});
