// Each mapped op in the settings the MediaPipe networks do NOT exercise (VALID and odd sizes,
// dilation, depth multipliers, align-corners and asymmetric resizing, rank-4 channel concat,
// broadcasting constants, padding every axis, MEAN with and without keep_dims, FULLY_CONNECTED
// on rank-4 input and keep_num_dims, RESHAPE between rank-4 shapes, the fused activations):
// tiny models written by tests/web/tflite_writer.mjs, run three ways — converted to ONNX under
// onnxruntime-web, by TFLite's own runtime, and by the float64 interpreter. TFLite agreeing with
// the interpreter also checks the writer's and the reader's schema field ids against TFLite.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { writeTflite } from './tflite_writer.mjs';
import { readTflite } from '../../web/tools/tflite_reader.mjs';
import { tfliteToOnnx } from '../../web/tools/tflite_to_onnx.mjs';
import { runReference } from './tflite_ref_interp.mjs';
import { tfliteRuntime, maxAbsDiff } from './mediapipe_support.mjs';
import { ort, rng } from './support.mjs';

const r = rng(2024);
const rand = (n, lo = -1, hi = 1) => Float32Array.from({ length: n }, () => lo + (hi - lo) * r());
const size = (s) => s.reduce((a, b) => a * b, 1);

// float -> fp16 bits (round to nearest even), for DEQUANTIZE weights
function toHalf(v) {
  const f = new Float32Array([v]);
  const b = new Uint32Array(f.buffer)[0];
  const sign = (b >>> 16) & 0x8000;
  const exp = ((b >>> 23) & 0xff) - 127 + 15;
  let mant = b & 0x7fffff;
  if (exp <= 0) return sign; // tiny values: zero is fine for test weights
  let h = sign | (exp << 10) | (mant >>> 13);
  mant &= 0x1fff;
  if (mant > 0x1000 || (mant === 0x1000 && (h & 1))) h += 1;
  return h;
}

/** A model builder: t(shape, {data, type, name}) adds a tensor and returns its index. */
function graph() {
  const tensors = [];
  const ops = [];
  return {
    tensors, ops,
    t(shape, { data, type = 'float32' } = {}) { tensors.push({ name: `t${tensors.length}`, shape, type, data }); return tensors.length - 1; },
    c(shape, lo = -1, hi = 1) { return this.t(shape, { data: rand(size(shape), lo, hi) }); },
    i32(values, shape = [values.length]) { return this.t(shape, { type: 'int32', data: Int32Array.from(values) }); },
    op(op, inputs, outShape, options = {}) { const o = this.t(outShape); ops.push({ op, inputs, outputs: [o], options }); return o; },
  };
}

async function check(name, g, inputs, outputs, { tflite = true } = {}) {
  const bytes = writeTflite({ tensors: g.tensors, inputs, outputs, ops: g.ops });
  const model = readTflite(bytes);
  const x = inputs.map((i) => rand(size(g.tensors[i].shape), -2, 2));
  const exact = runReference(model, x);
  const tfl = tflite ? (await tfliteRuntime()).run(bytes, x[0]) : null;
  const conv = tfliteToOnnx(model);
  const sess = await ort.InferenceSession.create(conv.bytes, { graphOptimizationLevel: 'all' });
  const feeds = Object.fromEntries(inputs.map((i, k) => [g.tensors[i].name, new ort.Tensor('float32', x[k], g.tensors[i].shape)]));
  const got = await sess.run(feeds);
  for (const o of outputs) {
    const n = g.tensors[o].name;
    assert.deepEqual(got[n].dims, g.tensors[o].shape, `${name}: ${n} shape`);
    const dO = maxAbsDiff(got[n].data, exact[n]);
    if (tfl) {
      const dT = maxAbsDiff(tfl[n], exact[n]);
      assert.ok(dT <= 1e-5, `${name}: TFLite runtime vs float64 interpreter ${dT} (writer, reader or interpreter disagree with TFLite)`);
    }
    assert.ok(dO <= 1e-5, `${name}: ONNX vs float64 ${dO}`);
  }
  return conv;
}

test('CONV_2D: VALID, stride 2, odd sizes, RELU; SAME with dilation 2, RELU_N1_TO_1', async () => {
  const g = graph();
  const x = g.t([1, 9, 11, 3]);
  const a = g.op('CONV_2D', [x, g.c([4, 3, 3, 3]), g.c([4])], [1, 4, 5, 4], { padding: 'VALID', strideW: 2, strideH: 2, activation: 'RELU' });
  const b = g.op('CONV_2D', [x, g.c([2, 3, 3, 3]), g.c([2])], [1, 9, 11, 2], { padding: 'SAME', dilationW: 2, dilationH: 2, activation: 'RELU_N1_TO_1' });
  await check('conv', g, [x], [a, b]);
});

test('DEPTHWISE_CONV_2D with multiplier 2, SAME stride 2 on odd sizes, RELU6; fp16 weights via DEQUANTIZE', async () => {
  const g = graph();
  const x = g.t([1, 7, 9, 3]);
  const w16 = g.t([1, 3, 3, 6], { type: 'float16', data: Uint16Array.from(rand(54), toHalf) });
  const w = g.op('DEQUANTIZE', [w16], [1, 3, 3, 6]);
  const y = g.op('DEPTHWISE_CONV_2D', [x, w, g.c([6])], [1, 4, 5, 6], { padding: 'SAME', strideW: 2, strideH: 2, depthMultiplier: 2, activation: 'RELU6' });
  await check('depthwise', g, [x], [y]);
});

test('MAX_POOL_2D 3x3 stride 2 SAME on odd sizes; RESIZE_BILINEAR align_corners, asymmetric, half-pixel', async () => {
  const g = graph();
  const x = g.t([1, 7, 9, 4]);
  const p = g.op('MAX_POOL_2D', [x], [1, 4, 5, 4], { padding: 'SAME', strideW: 2, strideH: 2, filterW: 3, filterH: 3 });
  const ac = g.op('RESIZE_BILINEAR', [p, g.i32([9, 13])], [1, 9, 13, 4], { alignCorners: true });
  const as = g.op('RESIZE_BILINEAR', [p, g.i32([10, 14])], [1, 10, 14, 4], {});
  const hp = g.op('RESIZE_BILINEAR', [p, g.i32([7, 9])], [1, 7, 9, 4], { halfPixelCenters: true });
  await check('pool+resize', g, [x], [p, ac, as, hp]);
});

test('CONCATENATION on channels (rank 4, axis -1), ADD with a broadcast constant, PRELU', async () => {
  const g = graph();
  const x = g.t([1, 4, 5, 2]);
  const y = g.op('CONV_2D', [x, g.c([3, 1, 1, 2]), g.c([3])], [1, 4, 5, 3], { padding: 'SAME', activation: 'RELU6' });
  const c = g.op('CONCATENATION', [x, y], [1, 4, 5, 5], { axis: -1 });
  const a = g.op('ADD', [c, g.c([5])], [1, 4, 5, 5], { activation: 'NONE' });
  const s = g.op('ADD', [a, c], [1, 4, 5, 5], { activation: 'RELU' });
  const pr = g.op('PRELU', [a, g.c([1, 1, 5], 0, 0.5)], [1, 4, 5, 5]);
  const h = g.op('CONCATENATION', [pr, s], [1, 8, 5, 5], { axis: 1 }); // along H
  await check('concat+add+prelu', g, [x], [h]);
});

test('PAD on every axis, MEAN with keep_dims over H,W and without over W (rank 4 -> 3)', async () => {
  const g = graph();
  const x = g.t([1, 4, 5, 3]);
  const p = g.op('PAD', [x, g.i32([0, 0, 1, 2, 2, 1, 1, 0], [4, 2])], [1, 7, 8, 4]);
  const m1 = g.op('MEAN', [p, g.i32([1, 2])], [1, 1, 1, 4], { keepDims: true });
  const m2 = g.op('MEAN', [p, g.i32([2])], [1, 7, 4], { keepDims: false });
  const q = g.op('PAD', [m2, g.i32([0, 0, 1, 1, 0, 2], [3, 2])], [1, 9, 6]); // a rank-3 pad
  await check('pad+mean', g, [x], [m1, q]);
});

test('FULLY_CONNECTED on rank-4 input with bias, keep_num_dims on rank 3 without bias; RESHAPE rank 4 -> 4; LOGISTIC', async () => {
  const g = graph();
  const x = g.t([1, 2, 3, 4]);
  const conv = g.op('CONV_2D', [x, g.c([4, 1, 1, 4]), g.c([4])], [1, 2, 3, 4], { padding: 'VALID' });
  const fc = g.op('FULLY_CONNECTED', [conv, g.c([5, 24]), g.c([5])], [1, 5], { activation: 'RELU' });
  const rs = g.op('RESHAPE', [conv, g.i32([1, 3, 2, 4])], [1, 3, 2, 4]); // memory order matters here
  const after = g.op('CONV_2D', [rs, g.c([2, 2, 1, 4]), g.c([2])], [1, 2, 2, 2], { padding: 'VALID' });
  const r3 = g.op('RESHAPE', [conv, g.i32([1, 6, 4])], [1, 6, 4], { newShape: [1, 6, 4] });
  const k = g.op('FULLY_CONNECTED', [r3, g.c([3, 4]), -1], [1, 6, 3], { keepNumDims: true });
  const s = g.op('LOGISTIC', [k], [1, 6, 3]);
  await check('fc+reshape', g, [x], [fc, after, s]);
});

test('CONV_2D without a bias (-1): converted as zero bias (this TFLite runtime refuses such models)', async () => {
  const g = graph();
  const x = g.t([1, 4, 5, 2]);
  const y = g.op('CONV_2D', [x, g.c([3, 1, 1, 2]), -1], [1, 4, 5, 3], { padding: 'SAME' });
  await check('conv without bias', g, [x], [y], { tflite: false });
});

test('fused TANH is refused with the operator named (TFLite itself ignores or refuses it)', () => {
  const g = graph();
  const x = g.t([1, 4, 5, 2]);
  const y = g.op('ADD', [x, x], [1, 4, 5, 2], { activation: 'TANH' });
  const m = readTflite(writeTflite({ tensors: g.tensors, inputs: [x], outputs: [y], ops: g.ops }));
  assert.throws(() => tfliteToOnnx(m), /operator 0 \(ADD\): fused activation TANH is not supported/);
});

test('the writer round-trips through the reader: options, shapes, constants', () => {
  const g = graph();
  const x = g.t([1, 5, 5, 2]);
  const y = g.op('DEPTHWISE_CONV_2D', [x, g.c([1, 3, 3, 4]), g.c([4])], [1, 3, 3, 4], { padding: 'VALID', depthMultiplier: 2, activation: 'RELU6', dilationW: 1, dilationH: 1 });
  const m = readTflite(writeTflite({ tensors: g.tensors, inputs: [x], outputs: [y], ops: g.ops }));
  assert.equal(m.version, 3);
  assert.equal(m.description, 'hawor test model');
  assert.deepEqual(m.operators[0].options, { padding: 'VALID', strideW: 1, strideH: 1, depthMultiplier: 2, activation: 'RELU6', dilationW: 1, dilationH: 1 });
  assert.deepEqual(m.tensors[1].shape, [1, 3, 3, 4]);
  assert.deepEqual(new Float32Array(m.tensors[1].data.slice().buffer), g.tensors[1].data);
  assert.deepEqual(m.inputs, [0]);
  assert.deepEqual(m.outputs, [y]);
});

test('DEQUANTIZE of anything but an fp16 constant is refused with the operator named', () => {
  const g = graph();
  const x = g.t([1, 2, 2, 1]);
  const q = g.t([1, 1, 1, 1], { type: 'int32', data: Int32Array.from([3]) });
  const w = g.op('DEQUANTIZE', [q], [1, 1, 1, 1]);
  const y = g.op('ADD', [x, w], [1, 2, 2, 1]);
  const m = readTflite(writeTflite({ tensors: g.tensors, inputs: [x], outputs: [y], ops: g.ops }));
  assert.throws(() => tfliteToOnnx(m), /operator 0 \(DEQUANTIZE\): input 't1' is int32; only DEQUANTIZE of fp16 constants/);
});
