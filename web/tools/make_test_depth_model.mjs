#!/usr/bin/env node
// make_test_depth_model.mjs: tiny ONNX "depth networks" whose output is a known function of
// their input, with their depth configs, for testing the depth slot without real weights.
//
//   node web/tools/make_test_depth_model.mjs --out DIR [--size WxH]
// writes DIR/affine.onnx + affine.json (NCHW, metric depth), affine_nhwc.onnx + .json (NHWC,
// output (1,h,w)), affine_inverse.json (the affine model read as inverse depth) and
// oracle.onnx + oracle.json, and prints one JSON line listing them.
//
// affine: y = sum_c w[c] * x[c] + b over the normalised input x[c] = (pixel * scale - mean[c]) /
//   std[c]: a 1x1 convolution with bias (NCHW) or a MatMul + Add over the channel axis (NHWC).
// oracle: y = R / 255 + G / (255 * 256) with scale 1/255, mean 0, std 1, i.e. the 16-bit code
//   k = 256 R + G over 65280, and multiplier ORACLE_MAX_DEPTH * 255 / 256, so that
//   depth = k * ORACLE_MAX_DEPTH / 65536 metres: a test writes ground-truth depth into the red
//   (high byte) and green (low byte) channels of a PNG and gets it back, to 0.12 mm, in metres.
//   Bilinear resampling is linear, so the code survives the resizes exactly (to rounding).

// The builders import nothing from node, so a browser page can import this module too; only
// the command line (main) loads node:fs and node:path.
import { OnnxGraph } from './onnx_builder.mjs';

export const ORACLE_MAX_DEPTH = 8; // metres: k = 65536 would be this depth

export const AFFINE_DEFAULTS = Object.freeze({
  weights: Object.freeze([0.5, 0.25, 0.125]),
  bias: 0.75,
  normalize: Object.freeze({ scale: 1 / 255, mean: Object.freeze([0.5, 0.4, 0.3]), std: Object.freeze([0.25, 0.5, 0.2]) }),
});

/** Appends a Reshape of `value` (1,1,h,w) or (1,h,w,1) to `outputShape` ('1x1xhxw', '1xhxw',
 *  'hxw'), or returns `value` when no reshape is needed. */
function reshapeTo(g, value, outputShape, width, height, name) {
  const dims = { '1x1xhxw': [1, 1, height, width], '1xhxw': [1, height, width], hxw: [height, width] }[outputShape];
  if (!dims) throw new Error(`make_test_depth_model: unknown outputShape '${outputShape}'`);
  g.addInitializer(`${name}_shape`, [dims.length], BigInt64Array.from(dims, BigInt));
  g.addNode('Reshape', [value, `${name}_shape`], [name]);
  return dims;
}

/** The affine test network as .onnx bytes. Options: width, height (fixed input size, or
 *  symbolic dims when `symbolicSize`), layout 'NCHW' | 'NHWC', weights [3], bias, outputShape
 *  ('1x1xhxw' default for NCHW, '1xhxw' default for NHWC, 'hxw', or 'bad' = (1,2,h,w)),
 *  inputName, outputName. */
export function buildAffineDepthModel({
  width, height, layout = 'NCHW', weights = AFFINE_DEFAULTS.weights, bias = AFFINE_DEFAULTS.bias,
  outputShape, inputName = 'image', outputName = 'depth', symbolicSize = false,
} = {}) {
  const g = new OnnxGraph('hawor_test_affine_depth');
  const H = symbolicSize ? 'height' : height;
  const W = symbolicSize ? 'width' : width;
  if (layout === 'NCHW') {
    g.addInput(inputName, 'float32', [1, 3, H, W]);
    if (outputShape === 'bad') {
      g.addInitializer('w', [2, 3, 1, 1], Float32Array.from([...weights, ...weights]));
      g.addInitializer('b', [2], Float32Array.from([bias, bias]));
      g.addNode('Conv', [inputName, 'w', 'b'], [outputName], { kernel_shape: [1, 1] });
      g.addOutput(outputName, 'float32', [1, 2, H, W]);
    } else {
      g.addInitializer('w', [1, 3, 1, 1], Float32Array.from(weights));
      g.addInitializer('b', [1], Float32Array.from([bias]));
      const shape = outputShape ?? '1x1xhxw';
      if (shape === '1x1xhxw') {
        g.addNode('Conv', [inputName, 'w', 'b'], [outputName], { kernel_shape: [1, 1] });
        g.addOutput(outputName, 'float32', [1, 1, H, W]);
      } else {
        g.addNode('Conv', [inputName, 'w', 'b'], ['conv'], { kernel_shape: [1, 1] });
        reshapeTo(g, 'conv', shape, width, height, outputName);
        g.addOutput(outputName, 'float32', null);
      }
    }
  } else if (layout === 'NHWC') {
    g.addInput(inputName, 'float32', [1, H, W, 3]);
    g.addInitializer('w', [3, 1], Float32Array.from(weights));
    g.addInitializer('b', [1], Float32Array.from([bias]));
    g.addNode('MatMul', [inputName, 'w'], ['wx']);
    g.addNode('Add', ['wx', 'b'], ['y']); // (1,h,w,1)
    reshapeTo(g, 'y', outputShape ?? '1xhxw', width, height, outputName);
    g.addOutput(outputName, 'float32', null);
  } else {
    throw new Error(`make_test_depth_model: unknown layout '${layout}'`);
  }
  return g.toBytes({ docString: 'hawor test depth model: y = w . x + b over the normalised RGB' });
}

/** The depth config of the affine network (kind 'metric_depth' or 'metric_inverse_depth'). */
export function affineDepthConfig({ width, height, layout = 'NCHW', kind = 'metric_depth', multiplier = 1, offset = 0, inputName, outputName } = {}) {
  const n = AFFINE_DEFAULTS.normalize;
  const cfg = {
    format: 'hawor-depth-model',
    version: 1,
    description: 'hawor test network: y = w . x + b over the normalised RGB',
    input: { width, height, layout },
    normalize: { scale: n.scale, mean: [...n.mean], std: [...n.std] },
    output: { kind, multiplier, offset },
  };
  if (inputName) cfg.input.name = inputName;
  if (outputName) cfg.output.name = outputName;
  return cfg;
}

/** The oracle network (see the header) at a fixed input size, NCHW, output (1,1,h,w). */
export function buildOracleDepthModel({ width, height } = {}) {
  const g = new OnnxGraph('hawor_test_oracle_depth');
  g.addInput('image', 'float32', [1, 3, height, width]);
  g.addInitializer('w', [1, 3, 1, 1], Float32Array.from([1, 1 / 256, 0]));
  g.addInitializer('b', [1], Float32Array.from([0]));
  g.addNode('Conv', ['image', 'w', 'b'], ['depth'], { kernel_shape: [1, 1] });
  g.addOutput('depth', 'float32', [1, 1, height, width]);
  return g.toBytes({ docString: 'hawor test oracle: y = R + G / 256 (normalised), depth coded in R (high) and G (low)' });
}

export function oracleDepthConfig({ width, height } = {}) {
  return {
    format: 'hawor-depth-model',
    version: 1,
    description: `hawor test oracle: depth = (256 R + G) * ${ORACLE_MAX_DEPTH} / 65536 metres`,
    input: { width, height, layout: 'NCHW', name: 'image' },
    normalize: { scale: 1 / 255, mean: [0, 0, 0], std: [1, 1, 1] },
    output: { kind: 'metric_depth', multiplier: (ORACLE_MAX_DEPTH * 255) / 256, offset: 0, name: 'depth' },
  };
}

async function main(argv) {
  const { writeFileSync, mkdirSync } = await import('node:fs');
  const { join } = await import('node:path');
  let out = null;
  let width = 64;
  let height = 48;
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    if (a === '--out' && i + 1 < argv.length) out = argv[++i];
    else if (a === '--size' && i + 1 < argv.length) {
      const m = /^(\d+)x(\d+)$/.exec(argv[++i]);
      if (!m) throw new Error(`--size must be WxH, got '${argv[i]}'`);
      width = Number(m[1]);
      height = Number(m[2]);
    } else if (a === '--help' || a === '-h') {
      process.stdout.write('usage: node web/tools/make_test_depth_model.mjs --out DIR [--size WxH]\n');
      return;
    } else throw new Error(`unknown argument '${a}' (usage: --out DIR [--size WxH])`);
  }
  if (!out) throw new Error('--out DIR is required');
  if (width <= 0 || height <= 0) throw new Error('--size must be positive');
  mkdirSync(out, { recursive: true });
  const files = [];
  const put = (name, data) => {
    writeFileSync(join(out, name), data);
    files.push(name);
  };
  const json = (o) => JSON.stringify(o, null, 2) + '\n';
  put('affine.onnx', buildAffineDepthModel({ width, height }));
  put('affine.json', json(affineDepthConfig({ width, height })));
  put('affine_inverse.json', json(affineDepthConfig({ width, height, kind: 'metric_inverse_depth' })));
  put('affine_nhwc.onnx', buildAffineDepthModel({ width, height, layout: 'NHWC' }));
  put('affine_nhwc.json', json(affineDepthConfig({ width, height, layout: 'NHWC' })));
  put('oracle.onnx', buildOracleDepthModel({ width, height }));
  put('oracle.json', json(oracleDepthConfig({ width, height })));
  process.stdout.write(JSON.stringify({ out, width, height, files }) + '\n');
}

const isMain = typeof process !== 'undefined' && Array.isArray(process.argv) && process.argv[1] &&
  import.meta.url === (await import('node:url')).pathToFileURL(process.argv[1]).href;
if (isMain) {
  main(process.argv.slice(2)).catch((e) => {
    process.stderr.write(`make_test_depth_model: ${e.message}\n`);
    process.exit(1);
  });
}
