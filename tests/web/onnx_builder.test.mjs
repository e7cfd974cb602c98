// onnx_builder: the bytes it writes load in onnxruntime-web and compute what the graph says,
// checked against plain-JS re-computations of each operator written here from the ONNX
// operator definitions (not from the builder).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { OnnxGraph, ProtoWriter, attr } from '../../web/tools/onnx_builder.mjs';
import { ort, rng, assertClose } from './support.mjs';

// ---- plain-JS reference operators on row-major arrays ----------------------------------------

function matmul(a, b, n, k, m) { // (n,k) x (k,m)
  const out = new Float64Array(n * m);
  for (let i = 0; i < n; ++i) for (let j = 0; j < m; ++j) {
    let s = 0;
    for (let t = 0; t < k; ++t) s += a[i * k + t] * b[t * m + j];
    out[i * m + j] = s;
  }
  return out;
}

function transpose2(a, n, m) {
  const out = new Float64Array(n * m);
  for (let i = 0; i < n; ++i) for (let j = 0; j < m; ++j) out[j * n + i] = a[i * m + j];
  return out;
}

// erf by its Maclaurin series (|x| <= 3) and continued fraction (|x| > 3): exact to ~1e-12.
function erf(x) {
  const ax = Math.abs(x);
  let r;
  if (ax <= 3) {
    let term = ax;
    let sum = ax;
    for (let n = 1; n < 200; ++n) {
      term *= -(ax * ax) / n;
      const add = term / (2 * n + 1);
      sum += add;
      if (Math.abs(add) < 1e-17) break;
    }
    r = (2 / Math.sqrt(Math.PI)) * sum;
  } else {
    let f = 0;
    for (let n = 60; n >= 1; --n) f = (n / 2) / (ax + f);
    r = 1 - Math.exp(-ax * ax) / Math.sqrt(Math.PI) / (ax + f);
  }
  return x < 0 ? -r : r;
}

function rows(a, n, m, fn) { // applies fn(rowArray) -> rowArray to each row
  const out = new Float64Array(n * m);
  for (let i = 0; i < n; ++i) out.set(fn(Array.from(a.subarray(i * m, (i + 1) * m))), i * m);
  return out;
}

function softmaxRow(r) {
  const mx = Math.max(...r);
  const e = r.map((v) => Math.exp(v - mx));
  const s = e.reduce((p, q) => p + q, 0);
  return e.map((v) => v / s);
}

function layerNormRow(r, gamma, beta, eps) {
  const mu = r.reduce((p, q) => p + q, 0) / r.length;
  const v = r.reduce((p, q) => p + (q - mu) * (q - mu), 0) / r.length;
  return r.map((x, i) => ((x - mu) / Math.sqrt(v + eps)) * gamma[i] + beta[i]);
}

// 2-D convolution, NCHW, one image: pads [top, left, bottom, right], square stride.
function conv2d(x, C, H, W, w, K, kh, kw, bias, pads, stride) {
  const [pt, pl, pb, pr] = pads;
  const Ho = Math.floor((H + pt + pb - kh) / stride) + 1;
  const Wo = Math.floor((W + pl + pr - kw) / stride) + 1;
  const out = new Float64Array(K * Ho * Wo);
  for (let k = 0; k < K; ++k) for (let oy = 0; oy < Ho; ++oy) for (let ox = 0; ox < Wo; ++ox) {
    let s = bias[k];
    for (let c = 0; c < C; ++c) for (let dy = 0; dy < kh; ++dy) for (let dx = 0; dx < kw; ++dx) {
      const iy = oy * stride + dy - pt;
      const ix = ox * stride + dx - pl;
      if (iy < 0 || iy >= H || ix < 0 || ix >= W) continue;
      s += x[(c * H + iy) * W + ix] * w[((k * C + c) * kh + dy) * kw + dx];
    }
    out[(k * Ho + oy) * Wo + ox] = s;
  }
  return { out, Ho, Wo };
}

const randArray = (r, n, lo = -1, hi = 1) => Float32Array.from({ length: n }, () => lo + (hi - lo) * r());

// ---- wire format ---------------------------------------------------------------------------------

test('protobuf varints and keys follow the wire format', () => {
  const bytesOf = (fn) => { const w = new ProtoWriter(); fn(w); return Array.from(w.finish()); };
  assert.deepEqual(bytesOf((w) => w.varint(0)), [0]);
  assert.deepEqual(bytesOf((w) => w.varint(1)), [1]);
  assert.deepEqual(bytesOf((w) => w.varint(300)), [0xac, 0x02]); // the protobuf docs' example
  assert.deepEqual(bytesOf((w) => w.varint(2 ** 53 - 1)), [255, 255, 255, 255, 255, 255, 255, 15]);
  assert.deepEqual(bytesOf((w) => w.varint(-1)), [255, 255, 255, 255, 255, 255, 255, 255, 255, 1]);
  assert.deepEqual(bytesOf((w) => w.varint(-2n)), [254, 255, 255, 255, 255, 255, 255, 255, 255, 1]);
  assert.deepEqual(bytesOf((w) => w.int(1, 150)), [0x08, 0x96, 0x01]); // field 1, varint 150
  assert.deepEqual(bytesOf((w) => w.string(2, 'testing')), [0x12, 7, 116, 101, 115, 116, 105, 110, 103]);
  assert.deepEqual(bytesOf((w) => w.float(2, 1)), [0x15, 0, 0, 0x80, 0x3f]); // 1.0f little-endian
  assert.throws(() => new ProtoWriter().varint(2 ** 60), /safe integer/);
  assert.throws(() => new ProtoWriter().varint(1n << 64n), /64 bits/);
});

test('the builder refuses wiring mistakes with the value named', () => {
  const g = new OnnxGraph();
  g.addInput('x', 'float32', [2]);
  assert.throws(() => g.addNode('Relu', ['nope'], ['y']), /input 'nope' is not defined/);
  g.addNode('Relu', ['x'], ['y']);
  assert.throws(() => g.addNode('Relu', ['x'], ['y']), /'y' is already defined/);
  assert.throws(() => g.addInitializer('w', [2, 2], new Float32Array(3)), /3 values for dims \[2, 2\]/);
  assert.throws(() => g.addOutput('z'), /output 'z' is not produced/);
  assert.throws(() => g.addInput('q', 'complex', [1]), /unknown element type 'complex'/);
  assert.throws(() => g.addNode('Foo', ['x'], ['f'], { a: [] }), /empty list needs attr.ints/);
  assert.throws(() => new OnnxGraph().toBytes(), /has no output/);
});

// ---- a transformer-like graph: every attribute kind, negative ints, symbolic dims -------------

test('a MatMul/Gemm/LayerNorm/Gelu/Softmax/Transpose/Reshape/Concat graph computes what it says', async () => {
  const r = rng(7);
  const B = 2;
  const D = 4;
  const Hd = 3;
  const x = randArray(r, B * D, -2, 2);
  const Wg = randArray(r, Hd * D);
  const bg = randArray(r, Hd);
  const Wm = randArray(r, Hd * D);
  const gamma = randArray(r, D, 0.5, 1.5);
  const beta = randArray(r, D, -0.5, 0.5);
  const K = randArray(r, 2 * D, 0.5, 2);

  const g = new OnnxGraph('transformer_bits');
  g.addInput('x', 'float32', ['batch', D]);
  g.addInitializer('Wg', [Hd, D], Wg);
  g.addInitializer('bg', [Hd], bg);
  g.addInitializer('Wm', [Hd, D], Wm);
  g.addInitializer('gamma', [D], gamma);
  g.addInitializer('beta', [D], beta);
  g.addInitializer('sqrt2', [], Float32Array.from([Math.SQRT2]));
  g.addInitializer('one', [], Float32Array.from([1]));
  g.addInitializer('half', [], Float32Array.from([0.5]));
  g.addInitializer('shape', [2], BigInt64Array.from([2n, -1n]));
  // Gemm: 0.5 * x Wg^T + 2 * bg; beta = 2 must be a FLOAT attribute, hence attr.float
  g.addNode('Gemm', ['x', 'Wg', 'bg'], ['gm'], { alpha: 0.5, beta: attr.float(2), transB: 1 });
  g.addNode('Relu', ['gm'], ['rl']);
  g.addNode('MatMul', ['rl', 'Wm'], ['mm']);
  g.addNode('Add', ['mm', 'x'], ['res']);
  g.addNode('LayerNormalization', ['res', 'gamma', 'beta'], ['ln'], { axis: -1, epsilon: 1e-5 });
  g.addNode('Div', ['ln', 'sqrt2'], ['gd']); // Gelu = x * 0.5 * (1 + erf(x / sqrt 2)) from ops
  g.addNode('Erf', ['gd'], ['ge']);
  g.addNode('Add', ['ge', 'one'], ['g1']);
  g.addNode('Mul', ['ln', 'g1'], ['g2']);
  g.addNode('Mul', ['g2', 'half'], ['gelu']);
  g.addNode('Transpose', ['gelu'], ['tr'], { perm: [1, 0] });
  g.addNode('Reshape', ['tr', 'shape'], ['rs']);
  g.addNode('Concat', ['rs', 'x'], ['cat'], { axis: -1 });
  g.addNode('Softmax', ['cat'], ['sm'], { axis: -1 });
  g.addNode('Constant', [], ['k'], { value: attr.tensor([1, 2 * D], K) });
  g.addNode('Mul', ['sm', 'k'], ['y']);
  g.addOutput('y', 'float32', ['batch', 2 * D]);
  g.addOutput('ln', 'float32', ['batch', D]);

  const session = await ort.InferenceSession.create(g.toBytes());
  assert.deepEqual(session.inputNames, ['x']);
  assert.deepEqual(session.outputNames, ['y', 'ln']);
  const res = await session.run({ x: new ort.Tensor('float32', x, [B, D]) });

  // the same maths in plain JS
  const gm = matmul(x, transpose2(Wg, Hd, D), B, D, Hd).map((v, i) => 0.5 * v + 2 * bg[i % Hd]);
  const rl = gm.map((v) => Math.max(0, v));
  const res0 = matmul(rl, Wm, B, Hd, D).map((v, i) => v + x[i]);
  const ln = rows(res0, B, D, (row) => layerNormRow(row, gamma, beta, 1e-5));
  const gelu = ln.map((v) => 0.5 * v * (1 + erf(v / Math.SQRT2)));
  const rs = transpose2(gelu, B, D); // (D,B) data read as (2, D*B/2) = (2, 4)
  const cat = new Float64Array(B * 2 * D);
  for (let i = 0; i < B; ++i) for (let j = 0; j < 2 * D; ++j) cat[i * 2 * D + j] = j < D ? rs[i * D + j] : x[i * D + j - D];
  const y = rows(cat, B, 2 * D, softmaxRow).map((v, i) => v * K[i % (2 * D)]);

  assert.deepEqual(Array.from(res.y.dims), [B, 2 * D]);
  assertClose(res.ln.data, ln, { rel: 1e-4, abs: 1e-5, what: 'ln' });
  assertClose(res.y.data, y, { rel: 1e-4, abs: 1e-6, what: 'y' });
  await session.release();
});

test('Conv with ints, strings (auto_pad) and strides matches a direct convolution', async () => {
  const r = rng(11);
  const C = 2;
  const H = 5;
  const W = 6;
  const K = 3;
  const x = randArray(r, C * H * W);
  const w = randArray(r, K * C * 3 * 3);
  const b = randArray(r, K);

  const g = new OnnxGraph('convs');
  g.addInput('x', 'float32', [1, C, H, W]);
  g.addInitializer('w', [K, C, 3, 3], w);
  g.addInitializer('b', [K], b);
  g.addNode('Conv', ['x', 'w', 'b'], ['same'], { kernel_shape: [3, 3], auto_pad: 'SAME_UPPER' });
  g.addNode('Conv', ['x', 'w', 'b'], ['strided'], { kernel_shape: [3, 3], pads: [1, 0, 1, 0], strides: [2, 2] });
  g.addOutput('same', 'float32', [1, K, H, W]);
  g.addOutput('strided', 'float32', null);

  const session = await ort.InferenceSession.create(g.toBytes({ opsetVersion: 13, irVersion: 7 }));
  const res = await session.run({ x: new ort.Tensor('float32', x, [1, C, H, W]) });
  const same = conv2d(x, C, H, W, w, K, 3, 3, b, [1, 1, 1, 1], 1);
  const strided = conv2d(x, C, H, W, w, K, 3, 3, b, [1, 0, 1, 0], 2);
  assert.deepEqual(Array.from(res.same.dims), [1, K, same.Ho, same.Wo]);
  assert.deepEqual(Array.from(res.strided.dims), [1, K, strided.Ho, strided.Wo]);
  assertClose(res.same.data, same.out, { rel: 1e-5, abs: 1e-6, what: 'same' });
  assertClose(res.strided.data, strided.out, { rel: 1e-5, abs: 1e-6, what: 'strided' });
  await session.release();
});

test('int64 initializers and integer outputs round-trip', async () => {
  const g = new OnnxGraph('ints');
  g.addInput('x', 'int64', [3]);
  g.addInitializer('big', [3], BigInt64Array.from([-5n, 1n << 40n, 7n]));
  g.addNode('Add', ['x', 'big'], ['y']);
  g.addOutput('y', 'int64', [3]);
  const session = await ort.InferenceSession.create(g.toBytes());
  const res = await session.run({ x: new ort.Tensor('int64', BigInt64Array.from([1n, 2n, -3n]), [3]) });
  assert.deepEqual(Array.from(res.y.data), [-4n, (1n << 40n) + 2n, 4n]);
  await session.release();
});

test('float16 initializers (Uint16Array bit patterns) load and Cast to the exact float values', async () => {
  // 1, -2, 65504 (largest half), 2^-24 (smallest subnormal), 1/3 rounded to half
  const bits = new Uint16Array([0x3c00, 0xc000, 0x7bff, 0x0001, 0x3555]);
  const g = new OnnxGraph('half');
  g.addInitializer('h', [5], bits, 'float16');
  g.addNode('Cast', ['h'], ['y'], { to: 1 });
  g.addOutput('y', 'float32', [5]);
  const s = await ort.InferenceSession.create(g.toBytes());
  const { y } = await s.run({});
  assert.deepEqual(Array.from(y.data), [1, -2, 65504, 2 ** -24, 0.333251953125]);
  assert.throws(() => new OnnxGraph().addInitializer('u', [1], new Uint16Array(1)), /Uint16Array needs type float16 or uint16/);
});
