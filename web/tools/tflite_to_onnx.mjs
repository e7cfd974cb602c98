// tflite_to_onnx.mjs: converts a float TFLite model (as read by tflite_reader.mjs) to ONNX, for
// exactly the 13 builtin ops MediaPipe's palm detector and hand landmarker use:
//   ADD, CONCATENATION, CONV_2D, DEPTHWISE_CONV_2D, DEQUANTIZE (fp16 weights), FULLY_CONNECTED,
//   LOGISTIC, MAX_POOL_2D, RESHAPE, RESIZE_BILINEAR, PAD, MEAN, PRELU.
// Anything else (another op, an option value we do not map, a shape that disagrees with what
// the op computes) is an Error naming the operator, its tensors and what is wrong.
//
// Layout. TFLite is NHWC, ONNX's Conv/MaxPool/Resize are NCHW. The graph keeps the model's NHWC
// input [1,H,W,3] (values 0..1, as MediaPipe feeds them) and transposes once; every rank-4
// value then lives in NCHW ('nchw'), everything else in TFLite's own order ('tfl'). A value is
// transposed back only where TFLite's memory order matters (RESHAPE, FULLY_CONNECTED, the
// outputs); constants are permuted here, at conversion time.
//
// Weights. MediaPipe stores weights as fp16 constants followed by DEQUANTIZE (fp16 -> fp32).
// By default they stay fp16 in the file, each followed by a Cast to float: half the file size,
// and onnxruntime folds the Cast at session creation, so inference is fp32 on exactly the values
// TFLite computes with. `weights: 'float32'` writes fp32 initializers instead.
//
// Semantics mapped (TFLite kernel definitions):
//   padding SAME: out = ceil(in / s); total = max((out - 1) s + (k - 1) d + 1 - in, 0);
//     before = floor(total / 2), after = total - before (the extra pixel goes after).
//   padding VALID: out = ceil((in - (k - 1) d) / s), no padding.
//   CONV_2D filter [O, KH, KW, I] -> ONNX [O, I, KH, KW]; DEPTHWISE_CONV_2D filter
//     [1, KH, KW, C*m] -> [C*m, 1, KH, KW] with group = C (output channel c*m + j reads input c
//     in both); FULLY_CONNECTED weights [out, in]: y = x W^T + b on x flattened to [-1, in].
//     An omitted bias (input -1) is zero.
//   fused activations: RELU -> Relu, RELU6 -> Clip(0, 6), RELU_N1_TO_1 -> Clip(-1, 1).
//   RESIZE_BILINEAR: align_corners -> 'align_corners', half_pixel_centers -> 'half_pixel'
//     (x_in = (x + 0.5) / scale - 0.5, clamped to the edge, as TFLite clamps), else
//     'asymmetric' (x_in = x / scale).
//   PAD: constant zeros; MEAN: ReduceMean over the given axes; PRELU: y = x < 0 ? a x : x.

import { readFileSync, writeFileSync } from 'node:fs';
import { resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { OnnxGraph } from './onnx_builder.mjs';
import { readTflite } from './tflite_reader.mjs';

export const SUPPORTED_OPS = Object.freeze(['ADD', 'CONCATENATION', 'CONV_2D', 'DEPTHWISE_CONV_2D', 'DEQUANTIZE',
  'FULLY_CONNECTED', 'LOGISTIC', 'MAX_POOL_2D', 'RESHAPE', 'RESIZE_BILINEAR', 'PAD', 'MEAN', 'PRELU']);

const NHWC_TO_NCHW_AXIS = [0, 2, 3, 1]; // NHWC axis a is NCHW axis NHWC_TO_NCHW_AXIS[a]
const PERM_TO_NCHW = [0, 3, 1, 2];
const PERM_TO_NHWC = [0, 2, 3, 1];

/** IEEE 754 half (bit pattern) -> number: sign, 5-bit exponent (bias 15), 10-bit fraction. */
export function halfToFloat(h) {
  const e = (h >> 10) & 0x1f;
  const f = h & 0x3ff;
  let v;
  if (e === 0) v = f * 2 ** -24; // subnormal: f / 1024 * 2^-14
  else if (e === 31) v = f ? NaN : Infinity;
  else v = (1 + f / 1024) * 2 ** (e - 15);
  return h & 0x8000 ? -v : v;
}

const count = (shape) => shape.reduce((a, b) => a * b, 1);
const fmt = (shape) => `[${shape.join(',')}]`;

/** Row-major permutation of a typed array: out dims = shape[perm[i]]. */
function permute(data, shape, perm) {
  const r = shape.length;
  const outShape = perm.map((p) => shape[p]);
  const inStrides = new Array(r);
  let s = 1;
  for (let i = r - 1; i >= 0; --i) { inStrides[i] = s; s *= shape[i]; }
  const out = new data.constructor(data.length);
  const idx = new Array(r).fill(0);
  for (let o = 0; o < data.length; ++o) {
    let src = 0;
    for (let i = 0; i < r; ++i) src += idx[i] * inStrides[perm[i]];
    out[o] = data[src];
    for (let i = r - 1; i >= 0; --i) { // odometer over the output index
      if (++idx[i] < outShape[i]) break;
      idx[i] = 0;
    }
  }
  return { data: out, shape: outShape };
}

/** Copies a (possibly unaligned) byte view into a fresh typed array. */
function typedCopy(bytes, Ctor) {
  if (bytes.length % Ctor.BYTES_PER_ELEMENT !== 0) return null;
  return new Ctor(bytes.slice().buffer);
}

/** Pads per spatial dim, or an Error message when TFLite's output size disagrees. */
function spatialPads(padding, inSize, k, s, d, outSize) {
  const eff = (k - 1) * d + 1;
  let out;
  let before = 0;
  let after = 0;
  if (padding === 'SAME') {
    out = Math.ceil(inSize / s);
    const total = Math.max((out - 1) * s + eff - inSize, 0);
    before = Math.floor(total / 2);
    after = total - before;
  } else if (padding === 'VALID') {
    out = Math.ceil((inSize - eff + 1) / s);
  } else {
    return { error: `padding ${padding} is not SAME or VALID` };
  }
  if (out !== outSize) return { error: `${padding} padding of ${inSize} with kernel ${k}, stride ${s}, dilation ${d} gives ${out}, but the output tensor says ${outSize}` };
  return { before, after };
}

/**
 * Converts a parsed TFLite model to ONNX bytes.
 * @param model  readTflite(bytes)
 * @param opts   { weights: 'float16' (default, fp16 + Cast) | 'float32', name, opsetVersion (17) }
 * @returns {{ bytes: Uint8Array, inputs: [{name, shape}], outputs: [{name, shape}], opCounts }}
 */
export function tfliteToOnnx(model, { weights = 'float16', name = 'tflite', opsetVersion = 17 } = {}) {
  if (weights !== 'float16' && weights !== 'float32') throw new Error(`tflite->onnx: weights must be 'float16' or 'float32', not ${weights}`);
  const T = model.tensors;
  const g = new OnnxGraph(name);
  const opCounts = {};

  // Constants: float ones as {shape, f32} or {shape, f16 (bit patterns)}; int32 as {shape, i32}.
  const consts = new Map();
  for (const t of T) {
    if (!t.data) continue;
    if (t.quantized) continue; // refused where an op reads it (DEQUANTIZE of int8 etc.)
    const n = count(t.shape);
    const Ctor = { float32: Float32Array, float16: Uint16Array, int32: Int32Array }[t.type];
    if (!Ctor) continue; // an unusual constant type: refused if an op reads it
    const data = typedCopy(t.data, Ctor);
    if (!data || data.length !== n) {
      throw new Error(`tflite->onnx: constant tensor ${t.index} '${t.name}' has ${t.data.length} bytes, but its shape ${fmt(t.shape)} of ${t.type} needs ${n * Ctor.BYTES_PER_ELEMENT}`);
    }
    if (t.type === 'float32') consts.set(t.index, { shape: t.shape, f32: data });
    else if (t.type === 'float16') consts.set(t.index, { shape: t.shape, f16: data, raw16: true });
    else consts.set(t.index, { shape: t.shape, i32: data });
  }

  const values = new Map(); // tensor index -> { name, layout }
  const cache = new Map(); // `${index}:${layout}` -> ONNX value name
  let uid = 0;
  const fresh = (base) => `${base}_${uid++}`;

  // A float initializer (weights) in the chosen storage; returns the float32 value's name.
  function floatInit(base, shape, c) {
    const nm = fresh(base);
    if (c.f16 && weights === 'float16') {
      g.addInitializer(`${nm}_f16`, shape, c.f16, 'float16');
      g.addNode('Cast', [`${nm}_f16`], [nm], { to: 1 }); // to FLOAT
      return nm;
    }
    const f32 = c.f32 ?? Float32Array.from(c.f16, halfToFloat);
    g.addInitializer(nm, shape, f32);
    return nm;
  }
  const floatConst = (i, what) => {
    const c = consts.get(i);
    if (!c || c.i32 || c.raw16) throw new Error(`${what}: tensor ${i} '${T[i]?.name}' must be a float32 constant (or a DEQUANTIZE of an fp16 one)`);
    return c;
  };
  const intConst = (i, what) => {
    const c = consts.get(i);
    if (!c || !c.i32) throw new Error(`${what}: tensor ${i} '${T[i]?.name}' must be an int32 constant`);
    return c;
  };
  const permuteConst = (c, perm) => {
    const src = c.f32 ?? c.f16;
    const p = permute(src, c.shape, perm);
    return c.f32 ? { shape: p.shape, f32: p.data } : { shape: p.shape, f16: p.data };
  };
  const int64Init = (base, arr) => {
    const nm = fresh(base);
    g.addInitializer(nm, [arr.length], BigInt64Array.from(arr, (v) => BigInt(v)));
    return nm;
  };

  /** ONNX value of tensor i in `layout`. Runtime rank-4 values are transposed (once, cached);
   *  float constants become initializers, a rank < 4 one in 'nchw' is first padded to rank 4
   *  with leading ones (numpy broadcasting, which both formats use) and then permuted. */
  function get(i, layout, what) {
    const key = `${i}:${layout}`;
    if (cache.has(key)) return cache.get(key);
    let nm;
    if (values.has(i)) {
      const v = values.get(i);
      if (v.layout === layout) return v.name;
      if (T[i].shape.length !== 4) throw new Error(`${what}: internal: rank-${T[i].shape.length} tensor ${i} has no '${layout}' layout`);
      nm = fresh(`t${i}_${layout}`);
      g.addNode('Transpose', [v.name], [nm], { perm: layout === 'nchw' ? PERM_TO_NCHW : PERM_TO_NHWC });
    } else if (consts.has(i)) {
      let c = floatConst(i, what);
      if (layout === 'nchw') {
        if (c.shape.length > 4) throw new Error(`${what}: constant ${i} of rank ${c.shape.length} next to a rank-4 tensor`);
        c = { ...c, shape: [...new Array(4 - c.shape.length).fill(1), ...c.shape] };
        c = permuteConst(c, PERM_TO_NCHW);
      }
      nm = floatInit(`c${i}`, c.shape, c);
    } else {
      throw new Error(`${what}: tensor ${i} '${T[i]?.name}' is read before any operator writes it`);
    }
    cache.set(key, nm);
    return nm;
  }

  function setValue(i, name, layout) {
    if (values.has(i) || consts.has(i)) throw new Error(`tflite->onnx: tensor ${i} '${T[i].name}' is written twice`);
    values.set(i, { name, layout });
  }

  function activation(a, x, what) {
    if (a === 'NONE') return x;
    const y = fresh('act');
    if (a === 'RELU') g.addNode('Relu', [x], [y]);
    else if (a === 'RELU6' || a === 'RELU_N1_TO_1') {
      const [lo, hi] = a === 'RELU6' ? [0, 6] : [-1, 1];
      const lon = fresh('clip_lo');
      const hin = fresh('clip_hi');
      g.addInitializer(lon, [], new Float32Array([lo]));
      g.addInitializer(hin, [], new Float32Array([hi]));
      g.addNode('Clip', [x, lon, hin], [y]);
    } else {
      // TANH / SIGN_BIT exist in the enum, but TFLite's kernels refuse (FULLY_CONNECTED) or
      // ignore (CONV_2D, ADD) them: no meaning to convert
      throw new Error(`${what}: fused activation ${a} is not supported (TFLite's kernels apply only RELU, RELU6, RELU_N1_TO_1)`);
    }
    return y;
  }

  // Graph inputs: NHWC float32, transposed once to NCHW.
  for (const i of model.inputs) {
    const t = T[i];
    if (t.type !== 'float32') throw new Error(`tflite->onnx: input '${t.name}' is ${t.type}, only float32 inputs are supported`);
    g.addInput(t.name, 'float32', t.shape);
    if (t.shape.length === 4) {
      const nm = fresh(`t${i}_nchw`);
      g.addNode('Transpose', [t.name], [nm], { perm: PERM_TO_NCHW });
      values.set(i, { name: nm, layout: 'nchw' });
      cache.set(`${i}:tfl`, t.name);
    } else {
      values.set(i, { name: t.name, layout: 'tfl' });
    }
  }

  for (const op of model.operators) {
    const what = `tflite->onnx: operator ${op.index} (${op.op})`;
    if (!SUPPORTED_OPS.includes(op.op)) {
      throw new Error(`${what} is not supported (the converter maps ${SUPPORTED_OPS.join(', ')})`);
    }
    opCounts[op.op] = (opCounts[op.op] ?? 0) + 1;
    const o = op.options;
    const ins = op.inputs;
    const nIn = (n, m = n) => {
      if (ins.length < n || ins.length > m) throw new Error(`${what}: ${ins.length} inputs, expected ${n === m ? n : `${n}..${m}`}`);
      if (op.outputs.length !== 1) throw new Error(`${what}: ${op.outputs.length} outputs, expected 1`);
    };
    const out = op.outputs[0];
    const outT = T[out];
    const shapeOf = (i) => T[i].shape;
    const rank4 = (i, role) => {
      if (shapeOf(i).length !== 4) throw new Error(`${what}: ${role} '${T[i].name}' has shape ${fmt(shapeOf(i))}, expected rank 4 (NHWC)`);
      return shapeOf(i);
    };
    for (const i of op.outputs) {
      if (T[i].type !== 'float32') throw new Error(`${what}: output '${T[i].name}' is ${T[i].type}; only float32 values are supported`);
    }

    switch (op.op) {
      case 'DEQUANTIZE': {
        nIn(1);
        const src = T[ins[0]];
        const c = consts.get(ins[0]);
        if (src.type === 'float16' && c) {
          // fp16 weights: a float constant from here on, kept as fp16 bits until written.
          if (count(src.shape) !== count(outT.shape)) throw new Error(`${what}: ${fmt(src.shape)} -> ${fmt(outT.shape)} changes the element count`);
          consts.set(out, { shape: outT.shape, f16: c.f16 });
        } else {
          // (a runtime fp16 value cannot occur: inputs and every op output are float32)
          throw new Error(`${what}: input '${src.name}' is ${src.type}${src.quantized ? ' (quantized)' : ''}${c ? '' : ', not a constant'}; only DEQUANTIZE of fp16 constants is supported`);
        }
        break;
      }
      case 'CONV_2D':
      case 'DEPTHWISE_CONV_2D': {
        nIn(2, 3);
        const dw = op.op === 'DEPTHWISE_CONV_2D';
        const [, H, W, C] = rank4(ins[0], 'input');
        const wc = floatConst(ins[1], `${what} filter`);
        if (wc.shape.length !== 4) throw new Error(`${what}: filter '${T[ins[1]].name}' has shape ${fmt(wc.shape)}, expected rank 4`);
        const [, Ho, Wo, Co] = rank4(out, 'output');
        let wOnnx;
        let group = 1;
        let KH;
        let KW;
        if (dw) {
          const [one, kh, kw, cm] = wc.shape;
          if (one !== 1 || cm !== Co || cm % C !== 0) {
            throw new Error(`${what}: depthwise filter ${fmt(wc.shape)} does not fit input channels ${C} and output channels ${Co} ([1,KH,KW,C*multiplier] expected)`);
          }
          [KH, KW] = [kh, kw];
          group = C;
          wOnnx = permuteConst(wc, [3, 0, 1, 2]); // [1,KH,KW,C*m] -> [C*m,1,KH,KW]
        } else {
          const [oc, kh, kw, ic] = wc.shape;
          if (oc !== Co || ic !== C) throw new Error(`${what}: filter ${fmt(wc.shape)} does not fit input channels ${C} and output channels ${Co} ([O,KH,KW,I] expected)`);
          [KH, KW] = [kh, kw];
          wOnnx = permuteConst(wc, [0, 3, 1, 2]); // [O,KH,KW,I] -> [O,I,KH,KW]
        }
        if (!(o.strideH >= 1 && o.strideW >= 1 && o.dilationH >= 1 && o.dilationW >= 1)) {
          throw new Error(`${what}: strides ${o.strideH},${o.strideW} / dilations ${o.dilationH},${o.dilationW} must be >= 1`);
        }
        const ph = spatialPads(o.padding, H, KH, o.strideH, o.dilationH, Ho);
        const pw = spatialPads(o.padding, W, KW, o.strideW, o.dilationW, Wo);
        for (const p of [ph, pw]) if (p.error) throw new Error(`${what}: ${p.error}`);
        const inputs = [get(ins[0], 'nchw', what), floatInit(`w${op.index}`, wOnnx.shape, wOnnx)];
        if (ins.length === 3 && ins[2] !== -1) {
          const b = floatConst(ins[2], `${what} bias`);
          if (count(b.shape) !== Co) throw new Error(`${what}: bias ${fmt(b.shape)} for ${Co} output channels`);
          inputs.push(floatInit(`b${op.index}`, [Co], b));
        }
        const y = fresh(`conv${op.index}`);
        g.addNode('Conv', inputs, [y], {
          kernel_shape: [KH, KW], strides: [o.strideH, o.strideW], dilations: [o.dilationH, o.dilationW],
          pads: [ph.before, pw.before, ph.after, pw.after], group,
        });
        setValue(out, activation(o.activation, y, what), 'nchw');
        break;
      }
      case 'MAX_POOL_2D': {
        nIn(1);
        const [, H, W, C] = rank4(ins[0], 'input');
        const [, Ho, Wo, Co] = rank4(out, 'output');
        if (C !== Co) throw new Error(`${what}: ${C} channels in, ${Co} out`);
        const ph = spatialPads(o.padding, H, o.filterH, o.strideH, 1, Ho);
        const pw = spatialPads(o.padding, W, o.filterW, o.strideW, 1, Wo);
        for (const p of [ph, pw]) if (p.error) throw new Error(`${what}: ${p.error}`);
        const y = fresh(`pool${op.index}`);
        // ONNX MaxPool ignores padded cells (like -inf), as TFLite's SAME pooling does.
        g.addNode('MaxPool', [get(ins[0], 'nchw', what)], [y], {
          kernel_shape: [o.filterH, o.filterW], strides: [o.strideH, o.strideW],
          pads: [ph.before, pw.before, ph.after, pw.after],
        });
        setValue(out, activation(o.activation, y, what), 'nchw');
        break;
      }
      case 'FULLY_CONNECTED': {
        nIn(2, 3);
        const wc = floatConst(ins[1], `${what} weights`);
        if (wc.shape.length !== 2) throw new Error(`${what}: weights ${fmt(wc.shape)}, expected [out, in]`);
        if (o.weightsFormat !== 0) throw new Error(`${what}: weights_format ${o.weightsFormat} (shuffled int8) is not supported`);
        const [No, Ni] = wc.shape;
        const xs = shapeOf(ins[0]);
        if (count(xs) % Ni !== 0) throw new Error(`${what}: input ${fmt(xs)} does not flatten to rows of ${Ni} (weights ${fmt(wc.shape)})`);
        const rows = count(xs) / Ni;
        if (count(outT.shape) !== rows * No) throw new Error(`${what}: output ${fmt(outT.shape)} is not ${rows} x ${No}`);
        let x = get(ins[0], 'tfl', what);
        if (xs.length !== 2 || xs[1] !== Ni) {
          const r = fresh(`fc_in${op.index}`);
          g.addNode('Reshape', [x, int64Init('shape', [rows, Ni])], [r]);
          x = r;
        }
        const inputs = [x, floatInit(`w${op.index}`, wc.shape, wc)];
        if (ins.length === 3 && ins[2] !== -1) {
          const b = floatConst(ins[2], `${what} bias`);
          if (count(b.shape) !== No) throw new Error(`${what}: bias ${fmt(b.shape)} for ${No} outputs`);
          inputs.push(floatInit(`b${op.index}`, [No], b));
        }
        let y = fresh(`fc${op.index}`);
        g.addNode('Gemm', inputs, [y], { transB: 1 });
        y = activation(o.activation, y, what);
        if (outT.shape.length !== 2 || outT.shape[0] !== rows) {
          const r = fresh(`fc_out${op.index}`);
          g.addNode('Reshape', [y, int64Init('shape', outT.shape)], [r]);
          y = r;
        }
        setValue(out, y, 'tfl');
        break;
      }
      case 'ADD': {
        nIn(2);
        const r = outT.shape.length;
        const layout = r === 4 ? 'nchw' : 'tfl';
        for (const i of ins) {
          if (shapeOf(i).length > r) throw new Error(`${what}: input ${fmt(shapeOf(i))} has a higher rank than the output ${fmt(outT.shape)}`);
          if (values.has(i) && r === 4 && shapeOf(i).length !== 4) throw new Error(`${what}: a rank-${shapeOf(i).length} runtime input next to a rank-4 output is not supported`);
        }
        const y = fresh(`add${op.index}`);
        g.addNode('Add', [get(ins[0], layout, what), get(ins[1], layout, what)], [y]);
        setValue(out, activation(o.activation, y, what), layout);
        break;
      }
      case 'CONCATENATION': {
        if (ins.length < 1 || op.outputs.length !== 1) throw new Error(`${what}: ${ins.length} inputs / ${op.outputs.length} outputs`);
        const r = outT.shape.length;
        let axis = o.axis < 0 ? o.axis + r : o.axis;
        if (!(axis >= 0 && axis < r)) throw new Error(`${what}: axis ${o.axis} for rank ${r}`);
        let total = 0;
        for (const i of ins) {
          const s = shapeOf(i);
          if (s.length !== r || s.some((d, k) => k !== axis && d !== outT.shape[k])) {
            throw new Error(`${what}: input '${T[i].name}' ${fmt(s)} does not concatenate into ${fmt(outT.shape)} along axis ${axis}`);
          }
          total += s[axis];
        }
        if (total !== outT.shape[axis]) throw new Error(`${what}: inputs add up to ${total} along axis ${axis}, output has ${outT.shape[axis]}`);
        const layout = r === 4 ? 'nchw' : 'tfl';
        if (r === 4) axis = NHWC_TO_NCHW_AXIS[axis];
        const y = fresh(`concat${op.index}`);
        g.addNode('Concat', ins.map((i) => get(i, layout, what)), [y], { axis });
        setValue(out, activation(o.activation, y, what), layout);
        break;
      }
      case 'LOGISTIC': {
        nIn(1);
        const v = values.get(ins[0]);
        if (!v) throw new Error(`${what}: input '${T[ins[0]].name}' is not a runtime value`);
        const y = fresh(`sigmoid${op.index}`);
        g.addNode('Sigmoid', [v.name], [y]);
        setValue(out, y, v.layout);
        break;
      }
      case 'RESHAPE': {
        nIn(1, 2);
        const xs = shapeOf(ins[0]);
        if (count(xs) !== count(outT.shape)) throw new Error(`${what}: ${fmt(xs)} (${count(xs)} values) cannot be reshaped to ${fmt(outT.shape)}`);
        if (ins.length === 2 && ins[1] !== -1 && consts.has(ins[1])) {
          const ns = Array.from(intConst(ins[1], `${what} shape`).i32);
          const ok = ns.length === outT.shape.length && ns.every((d, k) => d === -1 || d === outT.shape[k]);
          if (!ok) throw new Error(`${what}: new shape ${fmt(ns)} disagrees with the output tensor ${fmt(outT.shape)}`);
        }
        const y = fresh(`reshape${op.index}`);
        g.addNode('Reshape', [get(ins[0], 'tfl', what), int64Init('shape', outT.shape)], [y]);
        setValue(out, y, 'tfl');
        break;
      }
      case 'RESIZE_BILINEAR': {
        nIn(2);
        const [N, , , C] = rank4(ins[0], 'input');
        const [, Ho, Wo] = rank4(out, 'output');
        const size = Array.from(intConst(ins[1], `${what} size`).i32);
        if (size.length !== 2 || size[0] !== Ho || size[1] !== Wo) throw new Error(`${what}: size ${fmt(size)} disagrees with the output ${fmt(outT.shape)}`);
        if (o.alignCorners && o.halfPixelCenters) throw new Error(`${what}: align_corners and half_pixel_centers are both set`);
        const mode = o.alignCorners ? 'align_corners' : o.halfPixelCenters ? 'half_pixel' : 'asymmetric';
        const y = fresh(`resize${op.index}`);
        g.addNode('Resize', [get(ins[0], 'nchw', what), '', '', int64Init('sizes', [N, C, Ho, Wo])], [y],
          { mode: 'linear', coordinate_transformation_mode: mode });
        setValue(out, y, 'nchw');
        break;
      }
      case 'PAD': {
        nIn(2);
        const xs = shapeOf(ins[0]);
        const r = xs.length;
        const p = intConst(ins[1], `${what} paddings`);
        if (p.shape.length !== 2 || p.shape[0] !== r || p.shape[1] !== 2) throw new Error(`${what}: paddings ${fmt(p.shape)} for a rank-${r} input, expected [${r},2]`);
        for (let k = 0; k < r; ++k) {
          const [b, a] = [p.i32[2 * k], p.i32[2 * k + 1]];
          if (b < 0 || a < 0 || xs[k] + b + a !== outT.shape[k]) throw new Error(`${what}: padding ${b},${a} of axis ${k} takes ${xs[k]} to ${xs[k] + b + a}, output says ${outT.shape[k]}`);
        }
        const layout = r === 4 ? 'nchw' : 'tfl';
        const tflAxis = (j) => (r === 4 ? PERM_TO_NCHW[j] : j); // ONNX axis j reads TFLite axis
        const pads = [];
        for (let j = 0; j < r; ++j) pads.push(p.i32[2 * tflAxis(j)]);
        for (let j = 0; j < r; ++j) pads.push(p.i32[2 * tflAxis(j) + 1]);
        const y = fresh(`pad${op.index}`);
        g.addNode('Pad', [get(ins[0], layout, what), int64Init('pads', pads)], [y], { mode: 'constant' });
        setValue(out, y, layout);
        break;
      }
      case 'MEAN': {
        nIn(2);
        const xs = shapeOf(ins[0]);
        const r = xs.length;
        const axes = [...new Set(Array.from(intConst(ins[1], `${what} axes`).i32, (a) => (a < 0 ? a + r : a)))].sort();
        if (axes.some((a) => a < 0 || a >= r)) throw new Error(`${what}: axes ${fmt(axes)} for a rank-${r} input`);
        const kept = xs.map((d, k) => (axes.includes(k) ? 1 : d));
        const expect = o.keepDims ? kept : kept.filter((_, k) => !axes.includes(k));
        if (fmt(expect) !== fmt(outT.shape)) throw new Error(`${what}: mean of ${fmt(xs)} over ${fmt(axes)} is ${fmt(expect)}, output says ${fmt(outT.shape)}`);
        const layout = r === 4 ? 'nchw' : 'tfl';
        const onnxAxes = r === 4 ? axes.map((a) => NHWC_TO_NCHW_AXIS[a]).sort() : axes;
        let y = fresh(`mean${op.index}`);
        g.addNode('ReduceMean', [get(ins[0], layout, what)], [y], { axes: onnxAxes, keepdims: 1 });
        if (r === 4 && o.keepDims) {
          setValue(out, y, 'nchw');
        } else {
          if (r === 4) { // back to TFLite order before dropping the reduced axes
            const tr = fresh(`mean_nhwc${op.index}`);
            g.addNode('Transpose', [y], [tr], { perm: PERM_TO_NHWC });
            y = tr;
          }
          const rs = fresh(`mean_out${op.index}`);
          g.addNode('Reshape', [y, int64Init('shape', outT.shape)], [rs]);
          setValue(out, rs, 'tfl');
        }
        break;
      }
      case 'PRELU': {
        nIn(2);
        const r = shapeOf(ins[0]).length;
        const layout = r === 4 ? 'nchw' : 'tfl';
        if (!consts.has(ins[1])) throw new Error(`${what}: alpha '${T[ins[1]].name}' must be a constant`);
        const y = fresh(`prelu${op.index}`);
        g.addNode('PRelu', [get(ins[0], layout, what), get(ins[1], layout, `${what} alpha`)], [y]);
        setValue(out, y, layout);
        break;
      }
      default:
        throw new Error(`${what}: internal: no mapping`);
    }
  }

  // Outputs in TFLite order under the TFLite names.
  const outputs = [];
  for (const i of model.outputs) {
    const t = T[i];
    const src = get(i, 'tfl', `tflite->onnx: output '${t.name}'`);
    g.addNode('Identity', [src], [t.name]);
    g.addOutput(t.name, 'float32', t.shape);
    outputs.push({ name: t.name, shape: t.shape.slice() });
  }
  const inputs = model.inputs.map((i) => ({ name: T[i].name, shape: T[i].shape.slice() }));
  const bytes = g.toBytes({ opsetVersion, docString: `converted from TFLite by hawor tflite_to_onnx.mjs (weights ${weights})` });
  return { bytes, inputs, outputs, opCounts };
}

// CLI: node web/tools/tflite_to_onnx.mjs IN.tflite OUT.onnx [--fp32]
function main(argv) {
  const files = argv.filter((a) => !a.startsWith('--'));
  const flags = argv.filter((a) => a.startsWith('--'));
  if (files.length !== 2 || flags.some((f) => f !== '--fp32')) {
    process.stderr.write('usage: node web/tools/tflite_to_onnx.mjs IN.tflite OUT.onnx [--fp32]\n');
    return 2;
  }
  try {
    const conv = tfliteToOnnx(readTflite(new Uint8Array(readFileSync(files[0]))), { weights: flags.includes('--fp32') ? 'float32' : 'float16' });
    writeFileSync(files[1], conv.bytes);
    process.stdout.write(`${JSON.stringify({ out: files[1], bytes: conv.bytes.length, inputs: conv.inputs, outputs: conv.outputs, opCounts: conv.opCounts })}\n`);
    return 0;
  } catch (e) {
    process.stderr.write(`tflite_to_onnx: ${files[0]}: ${e.message}\n`);
    return 1;
  }
}

if (process.argv[1] && resolve(process.argv[1]) === fileURLToPath(import.meta.url)) process.exitCode = main(process.argv.slice(2));
