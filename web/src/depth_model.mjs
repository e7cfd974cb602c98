// depth_model.mjs: the depth-network slot. Runs a user's metric-depth network (ONNX) on an RGB
// image and returns metres per pixel at the image resolution, for `hawor scale --metric-depth`.
//
// Shared by the browser app and the node CLI (web/tools/run_depth.mjs): the caller passes the
// onnxruntime namespace (`import * as ort from 'onnxruntime-web'`), so this module imports
// nothing and runs wherever onnxruntime-web does.
//
// The network comes with a small JSON config (schema below, validated by parseDepthConfig):
//
//   {
//     "format": "hawor-depth-model",        required, exactly this
//     "version": 1,                         required, exactly 1
//     "description": "...",                 optional free text
//     "input": {
//       "width": 518, "height": 392,        required: the network's input size (integers > 0)
//       "layout": "NCHW",                   required: "NCHW" (1,3,H,W) or "NHWC" (1,H,W,3)
//       "name": "pixel_values"              optional: the input's name (default: the only one)
//     },
//     "normalize": {                        required: x = (pixel * scale - mean[c]) / std[c],
//       "scale": 0.00392156862745098,         pixel in 0..255, c = R, G, B
//       "mean": [0.485, 0.456, 0.406],
//       "std": [0.229, 0.224, 0.225]
//     },
//     "output": {
//       "kind": "metric_depth",             required: "metric_depth" -> depth = m * y + o
//                                           or "metric_inverse_depth" -> depth = 1 / (m * y + o)
//       "multiplier": 1, "offset": 0,       optional (defaults 1 and 0): m and o above
//       "name": "predicted_depth"           optional: the output's name (default: the only one)
//     }
//   }
//
// y is the network's output, shaped (1,1,h,w), (1,h,w) or (h,w); h, w need not equal the input
// size. Depth is along the optical axis (z), in metres. Relative / affine-invariant outputs
// are refused: their unknown per-image scale (and shift) is exactly what `hawor scale` must
// recover, so they cannot anchor it.
//
// Resampling (both ways) is bilinear with align_corners=false (half-pixel centres, the
// convention of OpenCV's INTER_LINEAR and PyTorch's interpolate(align_corners=False) without
// antialiasing): destination pixel x samples the source at (x + 0.5) * (W_src / W_dst) - 0.5,
// clamped to [0, W_src - 1]. Downscaling by much more than 2 therefore aliases; feed images no
// more than about twice the network's size. Depth is resampled in metres (after the output
// conversion); an output pixel with an invalid (non-finite or <= 0) neighbour of non-zero weight
// is NaN. At equal sizes both resizes are the identity.

const FORMAT = 'hawor-depth-model';
const KINDS = ['metric_depth', 'metric_inverse_depth'];
const REFUSED_KINDS = ['relative_depth', 'relative_inverse_depth', 'affine_invariant_depth',
  'affine_invariant_inverse_depth', 'relative', 'disparity', 'inverse_relative_depth'];

function fail(field, what) {
  return new Error(`depth config: '${field}' ${what}`);
}

function describe(v) {
  if (v === null) return 'null';
  if (Array.isArray(v)) return 'an array';
  return typeof v === 'string' ? `"${v}"` : `${typeof v} ${JSON.stringify(v)}`;
}

function checkObject(obj, field, allowed) {
  if (obj === undefined) throw fail(field, 'is missing');
  if (obj === null || typeof obj !== 'object' || Array.isArray(obj)) throw fail(field, `must be an object, got ${describe(obj)}`);
  for (const k of Object.keys(obj)) {
    if (!allowed.includes(k)) throw fail(field ? `${field}.${k}` : k, `is not a known field (known: ${allowed.join(', ')})`);
  }
}

function finiteNumber(v, field, { optional = false, fallback } = {}) {
  if (v === undefined) {
    if (optional) return fallback;
    throw fail(field, 'is missing');
  }
  if (typeof v !== 'number' || !Number.isFinite(v)) throw fail(field, `must be a finite number, got ${describe(v)}`);
  return v;
}

function positiveInt(v, field) {
  if (v === undefined) throw fail(field, 'is missing');
  if (typeof v !== 'number' || !Number.isInteger(v)) throw fail(field, `must be an integer, got ${describe(v)}`);
  if (v <= 0) throw fail(field, `must be positive, got ${v}`);
  if (v > 16384) throw fail(field, `is ${v}, more than 16384`);
  return v;
}

function optionalName(v, field) {
  if (v === undefined || v === null) return null; // null: "not given", as parseDepthConfig returns it
  if (typeof v !== 'string' || v.length === 0) throw fail(field, `must be a non-empty string, got ${describe(v)}`);
  return v;
}

function triple(v, field, nonZero) {
  if (v === undefined) throw fail(field, 'is missing');
  if (!Array.isArray(v) || v.length !== 3) throw fail(field, `must be an array of 3 numbers (R, G, B), got ${describe(v)}`);
  return v.map((x, i) => {
    const n = finiteNumber(x, `${field}[${i}]`);
    if (nonZero && n === 0) throw fail(`${field}[${i}]`, 'must not be 0 (it divides)');
    return n;
  });
}

/** Validates a depth-model config (JSON text or an already parsed object) against the schema
 *  in this file's header; returns a normalised frozen copy with every default filled in.
 *  Throws an Error naming the first bad field and what is wrong with it. */
export function parseDepthConfig(input) {
  let c = input;
  if (typeof input === 'string') {
    try {
      c = JSON.parse(input);
    } catch (e) {
      throw new Error(`depth config: not valid JSON (${e.message})`);
    }
  }
  if (c === null || typeof c !== 'object' || Array.isArray(c)) throw new Error(`depth config: must be a JSON object, got ${describe(c)}`);
  checkObject(c, '', ['format', 'version', 'input', 'normalize', 'output', 'description']);
  if (c.format === undefined) throw fail('format', `is missing (must be "${FORMAT}")`);
  if (c.format !== FORMAT) throw fail('format', `must be "${FORMAT}", got ${describe(c.format)}`);
  if (c.version === undefined) throw fail('version', 'is missing (must be 1)');
  if (c.version !== 1) throw fail('version', `must be 1, got ${describe(c.version)}`);
  if (c.description !== undefined && typeof c.description !== 'string') throw fail('description', `must be a string, got ${describe(c.description)}`);

  checkObject(c.input, 'input', ['width', 'height', 'layout', 'name']);
  const width = positiveInt(c.input.width, 'input.width');
  const height = positiveInt(c.input.height, 'input.height');
  if (c.input.layout === undefined) throw fail('input.layout', 'is missing (must be "NCHW" or "NHWC")');
  if (c.input.layout !== 'NCHW' && c.input.layout !== 'NHWC') throw fail('input.layout', `must be "NCHW" or "NHWC", got ${describe(c.input.layout)}`);
  const inputName = optionalName(c.input.name, 'input.name');

  checkObject(c.normalize, 'normalize', ['scale', 'mean', 'std']);
  const scale = finiteNumber(c.normalize.scale, 'normalize.scale');
  if (scale <= 0) throw fail('normalize.scale', `must be positive, got ${scale}`);
  const mean = triple(c.normalize.mean, 'normalize.mean', false);
  const std = triple(c.normalize.std, 'normalize.std', true);

  checkObject(c.output, 'output', ['kind', 'multiplier', 'offset', 'name']);
  const kind = c.output.kind;
  if (kind === undefined) throw fail('output.kind', `is missing (must be one of ${KINDS.join(', ')})`);
  if (typeof kind !== 'string') throw fail('output.kind', `must be a string, got ${describe(kind)}`);
  if (!KINDS.includes(kind)) {
    if (REFUSED_KINDS.includes(kind) || /relative|affine|invariant|disparity/.test(kind)) {
      throw fail('output.kind', `"${kind}" is refused: a relative or affine-invariant depth has an unknown scale ` +
        '(and shift) in every image, which is exactly what the metric scale step has to find, so it cannot give ' +
        'metres; use a network trained for metric depth and set kind to metric_depth or metric_inverse_depth');
    }
    throw fail('output.kind', `must be one of ${KINDS.join(', ')}, got "${kind}"`);
  }
  const multiplier = finiteNumber(c.output.multiplier, 'output.multiplier', { optional: true, fallback: 1 });
  if (multiplier === 0) throw fail('output.multiplier', 'must not be 0');
  const offset = finiteNumber(c.output.offset, 'output.offset', { optional: true, fallback: 0 });
  const outputName = optionalName(c.output.name, 'output.name');

  return Object.freeze({
    format: FORMAT,
    version: 1,
    input: Object.freeze({ width, height, layout: c.input.layout, name: inputName }),
    normalize: Object.freeze({ scale, mean: Object.freeze(mean), std: Object.freeze(std) }),
    output: Object.freeze({ kind, multiplier, offset, name: outputName }),
  });
}

/** Sampling table of a 1-D bilinear resize (align_corners=false) from `src` to `dst` samples:
 *  for each destination index its two source indices and the weight of the second. */
function resizeTable(src, dst) {
  const i0 = new Int32Array(dst);
  const i1 = new Int32Array(dst);
  const w1 = new Float32Array(dst);
  const ratio = src / dst;
  for (let d = 0; d < dst; ++d) {
    let s = (d + 0.5) * ratio - 0.5;
    if (s < 0) s = 0;
    if (s > src - 1) s = src - 1;
    const f = Math.floor(s);
    i0[d] = f;
    i1[d] = Math.min(f + 1, src - 1);
    w1[d] = s - f;
  }
  return { i0, i1, w1 };
}

/** Bilinear resize of a single-channel float image (sw x sh, row-major) to dw x dh. NaN in any
 *  of the (up to four) neighbours with a non-zero weight gives NaN. */
export function resizeBilinear(src, sw, sh, dw, dh) {
  if (src.length !== sw * sh) throw new Error(`resizeBilinear: ${src.length} values for ${sw}x${sh}`);
  const out = new Float32Array(dw * dh);
  const xs = resizeTable(sw, dw);
  const ys = resizeTable(sh, dh);
  for (let y = 0; y < dh; ++y) {
    const r0 = ys.i0[y] * sw;
    const r1 = ys.i1[y] * sw;
    const wy = ys.w1[y];
    for (let x = 0; x < dw; ++x) {
      const a = xs.i0[x];
      const b = xs.i1[x];
      const wx = xs.w1[x];
      // a neighbour of weight 0 is skipped, so that its NaN does not spread (NaN * 0 = NaN)
      const top = wx === 0 ? src[r0 + a] : src[r0 + a] + (src[r0 + b] - src[r0 + a]) * wx;
      if (wy === 0) {
        out[y * dw + x] = top;
        continue;
      }
      const bottom = wx === 0 ? src[r1 + a] : src[r1 + a] + (src[r1 + b] - src[r1 + a]) * wx;
      out[y * dw + x] = top + (bottom - top) * wy;
    }
  }
  return out;
}

/** A metric-depth network loaded into onnxruntime. Not safe for concurrent predict() calls on
 *  one instance (onnxruntime-web runs one inference per session at a time); await each. */
export class DepthModel {
  constructor(ort, session, config, inputName, outputName) {
    this.ort = ort;
    this.session = session;
    this.config = config;
    this.inputName = inputName;
    this.outputName = outputName;
  }

  /** Loads `modelBytes` (Uint8Array / ArrayBuffer of an .onnx file) with the onnxruntime
   *  namespace `ort` and checks it against `config` (JSON text, object, or parseDepthConfig's
   *  result): input/output names, element type float32, input rank 4 and its fixed dims. */
  static async create(ort, modelBytes, config, sessionOptions = {}) {
    if (!ort || !ort.InferenceSession || !ort.Tensor) throw new Error('depth model: the first argument must be the onnxruntime namespace');
    const cfg = parseDepthConfig(config);
    let bytes = modelBytes;
    if (bytes instanceof ArrayBuffer) bytes = new Uint8Array(bytes);
    if (!(bytes instanceof Uint8Array)) throw new Error('depth model: the model must be a Uint8Array or ArrayBuffer of an .onnx file');
    if (bytes.length === 0) throw new Error('depth model: the model file is empty');
    let session;
    try {
      session = await ort.InferenceSession.create(bytes, { executionProviders: ['wasm'], ...sessionOptions });
    } catch (e) {
      throw new Error(`depth model: cannot load the ONNX model (${e && e.message ? e.message : e})`);
    }
    try {
      const inputName = pickName(session.inputNames, cfg.input.name, 'input');
      const outputName = pickName(session.outputNames, cfg.output.name, 'output');
      checkInputMetadata(session, inputName, cfg);
      checkOutputMetadata(session, outputName);
      return new DepthModel(ort, session, cfg, inputName, outputName);
    } catch (e) {
      await session.release?.();
      throw e;
    }
  }

  /** Depth in metres for an 8-bit image: `rgb` holds width * height * channels bytes, row-major,
   *  channels 3 (RGB) or 4 (RGBA, alpha ignored). Returns a Float32Array(width * height);
   *  invalid pixels (non-finite or <= 0 depth) are NaN. */
  async predict(rgb, width, height, channels = 3) {
    if (!(rgb instanceof Uint8Array || rgb instanceof Uint8ClampedArray)) throw new Error('depth model: the image must be a Uint8Array or Uint8ClampedArray');
    if (!Number.isInteger(width) || !Number.isInteger(height) || width <= 0 || height <= 0) throw new Error(`depth model: bad image size ${width}x${height}`);
    if (channels !== 3 && channels !== 4) throw new Error(`depth model: channels must be 3 or 4, got ${channels}`);
    if (rgb.length !== width * height * channels) {
      throw new Error(`depth model: the image has ${rgb.length} bytes, ${width}x${height}x${channels} = ${width * height * channels} expected`);
    }
    if (!this.session) throw new Error('depth model: predict() after dispose()');
    const input = this.prepareInput(rgb, width, height, channels);
    let result;
    try {
      result = await this.session.run({ [this.inputName]: input });
    } catch (e) {
      throw new Error(`depth model: inference failed (${e && e.message ? e.message : e})`);
    }
    const out = result[this.outputName];
    for (const [name, t] of Object.entries(result)) if (name !== this.outputName) t.dispose?.();
    const { data, w, h } = checkOutput(out, this.outputName);
    const metres = toMetres(data, this.config.output);
    out.dispose?.();
    return resizeBilinear(metres, w, h, width, height);
  }

  /** The normalised, resized input tensor (1,3,H,W) or (1,H,W,3). */
  prepareInput(rgb, width, height, channels) {
    const { width: mw, height: mh, layout } = this.config.input;
    const { scale, mean, std } = this.config.normalize;
    const data = new Float32Array(3 * mw * mh);
    const xs = resizeTable(width, mw);
    const ys = resizeTable(height, mh);
    const plane = mw * mh;
    for (let y = 0; y < mh; ++y) {
      const r0 = ys.i0[y] * width;
      const r1 = ys.i1[y] * width;
      const wy = ys.w1[y];
      for (let x = 0; x < mw; ++x) {
        const a = xs.i0[x];
        const b = xs.i1[x];
        const wx = xs.w1[x];
        for (let c = 0; c < 3; ++c) {
          const p00 = rgb[(r0 + a) * channels + c];
          const p01 = rgb[(r0 + b) * channels + c];
          const p10 = rgb[(r1 + a) * channels + c];
          const p11 = rgb[(r1 + b) * channels + c];
          const top = p00 + (p01 - p00) * wx;
          const bottom = p10 + (p11 - p10) * wx;
          const v = ((top + (bottom - top) * wy) * scale - mean[c]) / std[c];
          if (layout === 'NCHW') data[c * plane + y * mw + x] = v;
          else data[(y * mw + x) * 3 + c] = v;
        }
      }
    }
    const dims = layout === 'NCHW' ? [1, 3, mh, mw] : [1, mh, mw, 3];
    return new this.ort.Tensor('float32', data, dims);
  }

  /** Frees the onnxruntime session. */
  async dispose() {
    if (this.session) await this.session.release?.();
    this.session = null;
  }
}

function pickName(names, wanted, what) {
  const list = Array.from(names ?? []);
  if (wanted !== null) {
    if (!list.includes(wanted)) throw new Error(`depth model: the config's ${what}.name is '${wanted}' but the model's ${what}s are [${list.join(', ')}]`);
    return wanted;
  }
  if (list.length !== 1) throw new Error(`depth model: the model has ${list.length} ${what}s [${list.join(', ')}]; set ${what}.name in the config`);
  return list[0];
}

function metadataOf(list, name) {
  if (!Array.isArray(list)) return null;
  return list.find((m) => m && m.name === name) ?? null;
}

function checkInputMetadata(session, name, cfg) {
  const m = metadataOf(session.inputMetadata, name);
  if (!m || !m.isTensor) return; // older runtimes: no metadata; run() will complain instead
  if (m.type !== 'float32') throw new Error(`depth model: input '${name}' has element type ${m.type}, float32 expected`);
  if (!m.shape || m.shape.length === 0) return;
  const { width, height, layout } = cfg.input;
  const want = layout === 'NCHW' ? [1, 3, height, width] : [1, height, width, 3];
  const label = layout === 'NCHW' ? '(1, 3, height, width)' : '(1, height, width, 3)';
  const shape = `[${m.shape.join(', ')}]`;
  if (m.shape.length !== 4) throw new Error(`depth model: input '${name}' has shape ${shape}; the config's layout ${layout} needs rank 4 ${label}`);
  for (let i = 0; i < 4; ++i) {
    const d = m.shape[i];
    if (typeof d === 'number' && d > 0 && d !== want[i]) {
      throw new Error(`depth model: input '${name}' has shape ${shape} but the config (${layout}, ${width}x${height}) gives [${want.join(', ')}]`);
    }
  }
}

function checkOutputMetadata(session, name) {
  const m = metadataOf(session.outputMetadata, name);
  if (!m || !m.isTensor) return;
  if (m.type !== 'float32') throw new Error(`depth model: output '${name}' has element type ${m.type}, float32 expected`);
}

/** The output's data and size; accepts (1,1,h,w), (1,h,w) and (h,w). */
function checkOutput(t, name) {
  if (!t) throw new Error(`depth model: the model returned no output '${name}'`);
  if (t.type !== 'float32') throw new Error(`depth model: output '${name}' is ${t.type}, float32 expected`);
  const d = Array.from(t.dims);
  const ok = (d.length === 4 && d[0] === 1 && d[1] === 1) || (d.length === 3 && d[0] === 1) || d.length === 2;
  if (!ok || d.some((x) => !(x > 0))) {
    throw new Error(`depth model: output '${name}' has shape [${d.join(', ')}]; a depth map must be (1, 1, h, w), (1, h, w) or (h, w)`);
  }
  return { data: t.data, h: d[d.length - 2], w: d[d.length - 1] };
}

/** Network output -> metres: m * y + o, or 1 / (m * y + o) for inverse depth; NaN where the
 *  result is not a finite positive number. */
function toMetres(y, output) {
  const { kind, multiplier, offset } = output;
  const out = new Float32Array(y.length);
  const inverse = kind === 'metric_inverse_depth';
  for (let i = 0; i < y.length; ++i) {
    const v = multiplier * y[i] + offset;
    const d = Math.fround(inverse ? 1 / v : v); // as stored: a huge value overflows to Infinity
    out[i] = Number.isFinite(d) && d > 0 ? d : NaN;
  }
  return out;
}
