// tflite_ref_interp.mjs: a plain, slow, float64 interpreter of a parsed TFLite graph (NHWC, op by
// op), the tests' independent reference for the ONNX conversion. Written from TFLite's kernel
// definitions directly on TFLite's own layout, it shares no code with tflite_to_onnx.mjs (only
// the FlatBuffer reader, which the TFLite runtime reference checks separately): no layout
// changes, no weight permutations, no ONNX.
//
// Not a test file: node --test runs only *.test.mjs.

// fp16 bit pattern -> number, by its definition: (-1)^s * 2^(e-15) * (1 + f/1024), subnormals
// 2^-14 * f/1024, e = 31 Inf/NaN.
function half(bits) {
  const s = bits >>> 15 ? -1 : 1;
  const e = (bits >>> 10) & 31;
  const f = bits & 1023;
  if (e === 31) return f === 0 ? s * Infinity : NaN;
  return e === 0 ? s * Math.pow(2, -14) * (f / 1024) : s * Math.pow(2, e - 15) * (1 + f / 1024);
}

const size = (shape) => shape.reduce((a, b) => a * b, 1);

function constData(t) {
  const dv = new DataView(t.data.buffer, t.data.byteOffset, t.data.byteLength);
  const n = size(t.shape);
  const out = new Float64Array(n);
  for (let i = 0; i < n; ++i) {
    if (t.type === 'float32') out[i] = dv.getFloat32(4 * i, true);
    else if (t.type === 'float16') out[i] = half(dv.getUint16(2 * i, true));
    else if (t.type === 'int32') out[i] = dv.getInt32(4 * i, true);
    else throw new Error(`ref: constant of type ${t.type}`);
  }
  return out;
}

function act(v, a) {
  switch (a) {
    case 'NONE': return v;
    case 'RELU': return v.map((x) => Math.max(0, x));
    case 'RELU6': return v.map((x) => Math.min(6, Math.max(0, x)));
    case 'RELU_N1_TO_1': return v.map((x) => Math.min(1, Math.max(-1, x)));
    default: throw new Error(`ref: activation ${a}`);
  }
}

// TFLite's padding rule (kernels/padding.h): out = SAME ? ceil(in/s) : ceil((in - eff + 1)/s),
// total = (out-1)*s + eff - in clamped at 0; the smaller half goes before.
function padBefore(padding, inSize, k, s, d) {
  const eff = (k - 1) * d + 1;
  if (padding === 'VALID') return { out: Math.floor((inSize - eff) / s) + 1, before: 0 };
  const out = Math.floor((inSize + s - 1) / s);
  const total = Math.max(0, (out - 1) * s + eff - inSize);
  return { out, before: total >> 1 };
}

// Broadcast binary op on row-major arrays (numpy rules).
function broadcast(a, as, b, bs, f) {
  const r = Math.max(as.length, bs.length);
  const A = [...new Array(r - as.length).fill(1), ...as];
  const B = [...new Array(r - bs.length).fill(1), ...bs];
  const O = A.map((d, i) => Math.max(d, B[i]));
  const out = new Float64Array(size(O));
  const idx = new Array(r).fill(0);
  for (let o = 0; o < out.length; ++o) {
    let ia = 0;
    let ib = 0;
    for (let i = 0; i < r; ++i) {
      ia = ia * A[i] + (A[i] === 1 ? 0 : idx[i]);
      ib = ib * B[i] + (B[i] === 1 ? 0 : idx[i]);
    }
    out[o] = f(a[ia], b[ib]);
    for (let i = r - 1; i >= 0; --i) { if (++idx[i] < O[i]) break; idx[i] = 0; }
  }
  return { data: out, shape: O };
}

/** Runs the main subgraph on `inputs` (array of Float32/64 arrays, one per model input).
 *  Returns {name: Float64Array} for every model output. */
export function runReference(model, inputs) {
  const T = model.tensors;
  const val = new Map();
  const read = (i) => {
    if (val.has(i)) return val.get(i);
    const t = T[i];
    if (!t.data) throw new Error(`ref: tensor ${i} read before written`);
    const v = constData(t);
    val.set(i, v);
    return v;
  };
  model.inputs.forEach((i, k) => val.set(i, Float64Array.from(inputs[k])));

  for (const op of model.operators) {
    const o = op.options;
    const [i0, i1, i2] = op.inputs;
    const out = op.outputs[0];
    const os = T[out].shape;
    let y;
    switch (op.op) {
      case 'DEQUANTIZE': y = read(i0); break;
      case 'LOGISTIC': y = read(i0).map((x) => 1 / (1 + Math.exp(-x))); break;
      case 'RESHAPE': y = read(i0); break;
      case 'CONV_2D':
      case 'DEPTHWISE_CONV_2D': {
        const x = read(i0);
        const w = read(i1);
        const b = i2 !== undefined && i2 >= 0 ? read(i2) : null;
        const [N, H, W, C] = T[i0].shape;
        const KH = T[i1].shape[1]; // CONV_2D [O,KH,KW,I], DEPTHWISE [1,KH,KW,C*m]
        const KW = T[i1].shape[2];
        const [, Ho, Wo, Co] = os;
        const ph = padBefore(o.padding, H, KH, o.strideH, o.dilationH);
        const pw = padBefore(o.padding, W, KW, o.strideW, o.dilationW);
        if (ph.out !== Ho || pw.out !== Wo) throw new Error(`ref: op ${op.index} output size`);
        y = new Float64Array(N * Ho * Wo * Co);
        const dw = op.op === 'DEPTHWISE_CONV_2D';
        const mult = Co / C;
        for (let n = 0; n < N; ++n) for (let oy = 0; oy < Ho; ++oy) for (let ox = 0; ox < Wo; ++ox) {
          const ob = ((n * Ho + oy) * Wo + ox) * Co;
          for (let co = 0; co < Co; ++co) y[ob + co] = b ? b[co] : 0;
          for (let ky = 0; ky < KH; ++ky) {
            const iy = oy * o.strideH - ph.before + ky * o.dilationH;
            if (iy < 0 || iy >= H) continue;
            for (let kx = 0; kx < KW; ++kx) {
              const ix = ox * o.strideW - pw.before + kx * o.dilationW;
              if (ix < 0 || ix >= W) continue;
              const xb = ((n * H + iy) * W + ix) * C;
              if (dw) { // filter [1, KH, KW, C*m]: output channel c*m + j reads input channel c
                const wb = (ky * KW + kx) * Co;
                for (let co = 0; co < Co; ++co) y[ob + co] += x[xb + Math.floor(co / mult)] * w[wb + co];
              } else { // filter [O, KH, KW, I]
                for (let co = 0; co < Co; ++co) {
                  const wb = ((co * KH + ky) * KW + kx) * C;
                  let s = 0;
                  for (let c = 0; c < C; ++c) s += x[xb + c] * w[wb + c];
                  y[ob + co] += s;
                }
              }
            }
          }
        }
        y = act(y, o.activation);
        break;
      }
      case 'MAX_POOL_2D': {
        const x = read(i0);
        const [N, H, W, C] = T[i0].shape;
        const [, Ho, Wo] = os;
        const ph = padBefore(o.padding, H, o.filterH, o.strideH, 1);
        const pw = padBefore(o.padding, W, o.filterW, o.strideW, 1);
        y = new Float64Array(N * Ho * Wo * C).fill(-Infinity);
        for (let n = 0; n < N; ++n) for (let oy = 0; oy < Ho; ++oy) for (let ox = 0; ox < Wo; ++ox) {
          for (let ky = 0; ky < o.filterH; ++ky) for (let kx = 0; kx < o.filterW; ++kx) {
            const iy = oy * o.strideH - ph.before + ky;
            const ix = ox * o.strideW - pw.before + kx;
            if (iy < 0 || iy >= H || ix < 0 || ix >= W) continue; // padding never wins
            for (let c = 0; c < C; ++c) {
              const q = ((n * Ho + oy) * Wo + ox) * C + c;
              y[q] = Math.max(y[q], x[((n * H + iy) * W + ix) * C + c]);
            }
          }
        }
        y = act(y, o.activation);
        break;
      }
      case 'FULLY_CONNECTED': {
        const x = read(i0);
        const w = read(i1);
        const b = i2 !== undefined && i2 >= 0 ? read(i2) : null;
        const [No, Ni] = T[i1].shape;
        const rows = x.length / Ni;
        y = new Float64Array(rows * No);
        for (let r = 0; r < rows; ++r) for (let j = 0; j < No; ++j) {
          let s = b ? b[j] : 0;
          for (let k = 0; k < Ni; ++k) s += x[r * Ni + k] * w[j * Ni + k];
          y[r * No + j] = s;
        }
        y = act(y, o.activation);
        break;
      }
      case 'ADD':
        y = act(broadcast(read(i0), T[i0].shape, read(i1), T[i1].shape, (p, q) => p + q).data, o.activation);
        break;
      case 'PRELU':
        y = broadcast(read(i0), T[i0].shape, read(i1), T[i1].shape, (x, a) => (x >= 0 ? x : a * x)).data;
        break;
      case 'CONCATENATION': {
        const r = os.length;
        const axis = o.axis < 0 ? o.axis + r : o.axis;
        const outer = size(os.slice(0, axis));
        const inner = size(os.slice(axis + 1));
        y = new Float64Array(size(os));
        let off = 0;
        for (const i of op.inputs) {
          const x = read(i);
          const ax = T[i].shape[axis];
          for (let p = 0; p < outer; ++p) for (let a = 0; a < ax; ++a) for (let q = 0; q < inner; ++q) {
            y[(p * os[axis] + off + a) * inner + q] = x[(p * ax + a) * inner + q];
          }
          off += ax;
        }
        y = act(y, o.activation);
        break;
      }
      case 'PAD': {
        const x = read(i0);
        const p = read(i1);
        const xs = T[i0].shape;
        const r = xs.length;
        y = new Float64Array(size(os));
        const idx = new Array(r).fill(0);
        for (let q = 0; q < x.length; ++q) {
          let d = 0;
          for (let k = 0; k < r; ++k) d = d * os[k] + idx[k] + p[2 * k];
          y[d] = x[q];
          for (let k = r - 1; k >= 0; --k) { if (++idx[k] < xs[k]) break; idx[k] = 0; }
        }
        break;
      }
      case 'MEAN': {
        const x = read(i0);
        const xs = T[i0].shape;
        const axes = Array.from(read(i1), (a) => (a < 0 ? a + xs.length : a));
        const ks = xs.map((d, k) => (axes.includes(k) ? 1 : d));
        const cnt = size(xs) / size(ks);
        y = new Float64Array(size(ks));
        const idx = new Array(xs.length).fill(0);
        for (let q = 0; q < x.length; ++q) {
          let d = 0;
          for (let k = 0; k < xs.length; ++k) d = d * ks[k] + (axes.includes(k) ? 0 : idx[k]);
          y[d] += x[q] / cnt;
          for (let k = xs.length - 1; k >= 0; --k) { if (++idx[k] < xs[k]) break; idx[k] = 0; }
        }
        break;
      }
      case 'RESIZE_BILINEAR': {
        // TFLite reference kernel: in = half_pixel ? (out + 0.5) * scale - 0.5 : out * scale,
        // scale = align_corners ? (in-1)/(out-1) : in/out; y0 = max(floor(in), 0),
        // y1 = min(ceil(in), size-1), weight = in - floor(in).
        const x = read(i0);
        const [N, H, W, C] = T[i0].shape;
        const [, Ho, Wo] = os;
        const sc = (inS, outS) => (o.alignCorners && outS > 1 ? (inS - 1) / (outS - 1) : inS / outS);
        const sy = sc(H, Ho);
        const sx = sc(W, Wo);
        const src = (v, s) => (o.halfPixelCenters ? (v + 0.5) * s - 0.5 : v * s);
        y = new Float64Array(N * Ho * Wo * C);
        for (let n = 0; n < N; ++n) for (let oy = 0; oy < Ho; ++oy) for (let ox = 0; ox < Wo; ++ox) {
          const fy = src(oy, sy);
          const fx = src(ox, sx);
          const y0 = Math.max(Math.floor(fy), 0);
          const y1 = Math.min(Math.ceil(fy), H - 1);
          const x0 = Math.max(Math.floor(fx), 0);
          const x1 = Math.min(Math.ceil(fx), W - 1);
          const wy = fy - Math.floor(fy);
          const wx = fx - Math.floor(fx);
          for (let c = 0; c < C; ++c) {
            const at = (yy, xx) => x[((n * H + yy) * W + xx) * C + c];
            y[((n * Ho + oy) * Wo + ox) * C + c] = (1 - wy) * ((1 - wx) * at(y0, x0) + wx * at(y0, x1))
              + wy * ((1 - wx) * at(y1, x0) + wx * at(y1, x1));
          }
        }
        break;
      }
      default:
        throw new Error(`ref: op ${op.op} not interpreted`);
    }
    if (y.length !== size(os)) throw new Error(`ref: op ${op.index} (${op.op}) produced ${y.length} values for ${os}`);
    val.set(out, y);
  }
  const res = {};
  for (const i of model.outputs) res[T[i].name] = val.get(i);
  return res;
}
