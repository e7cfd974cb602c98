#!/usr/bin/env node
// make_infiller_model.mjs: the HaWoR infiller network (docs/design.md §7; the C++ forward pass is
// include/hawor/motion/infiller_net.hpp) as an ONNX model with RANDOM weights, and the same
// weights as the .npz the C++ loader reads, so the two runtimes can be compared. No trained
// weights exist here; this is a test fixture, not a model.
//
//   node web/tools/make_infiller_model.mjs --out DIR [--seed N] [--small]
// writes DIR/infiller.onnx (inputs x (W,F) and valid (W,1) float32, output y (W,F)) and
// DIR/infiller.npz, and prints one JSON line with the sizes. --small: a reduced configuration
// (SMALL_CONFIG) for quick experiments; default the official sizes (OFFICIAL_CONFIG).
//
// The graph follows the official model op by op, written from its description, not from the
// C++ code: separate q/k/v projections in stage 1 (Gemm transB=1 on the (out, in) weights),
// LayerNormalization (opset 17) with epsilon 1e-5, masking by Where(valid, scores, -inf) before
// Softmax, GELU built from Erf, Split of in_proj in stage 2, and the positional table as a
// float32 initializer from the formula PE(t,2i) = sin(t·ω_i), PE(t,2i+1) = cos(t·ω_i),
// ω_i = exp(−2i·ln(10000)/D). Tensor names are those of the official state_dict (see
// infiller_weights.hpp), which are also the ONNX initializer names.

import { OnnxGraph, attr } from './onnx_builder.mjs';
import { encodeNpzFloat32 } from './npz.mjs';

export const OFFICIAL_CONFIG = Object.freeze({ window: 120, features: 218, dModel: 384, heads: 8, ffDim: 2048, maskedLayers: 8, encoderLayers: 8 });
export const SMALL_CONFIG = Object.freeze({ window: 24, features: 14, dModel: 32, heads: 4, ffDim: 48, maskedLayers: 2, encoderLayers: 2 });

/** [{name, shape}] of every tensor, in state_dict order (mirrors infillerTensorSpecs in C++;
 *  pos_embedding.pe is left out: both sides compute it from the formula). */
export function infillerTensorSpecs(c) {
  const F = c.features, D = c.dModel, H = c.ffDim;
  const s = [['input_layer.weight', [D, F + 1]], ['input_layer.bias', [D]]];
  for (let i = 0; i < c.maskedLayers; ++i) {
    const a = `att_layers.${i}.`;
    s.push([`${a}q_linear.weight`, [D, D]], [`${a}k_linear.weight`, [D, D]], [`${a}v_linear.weight`, [D, D]],
      [`${a}out_linear.weight`, [D, D]], [`${a}layer_norm.weight`, [D]], [`${a}layer_norm.bias`, [D]]);
  }
  for (let i = 0; i < c.maskedLayers; ++i) {
    const p = `pff_layers.${i}.`;
    s.push([`${p}layer_norm.weight`, [D]], [`${p}layer_norm.bias`, [D]], [`${p}network.0.weight`, [H, D]],
      [`${p}network.0.bias`, [H]], [`${p}network.3.weight`, [D, H]], [`${p}network.3.bias`, [D]]);
  }
  s.push(['layer_norm.weight', [D]], ['layer_norm.bias', [D]]);
  for (let l = 0; l < c.encoderLayers; ++l) {
    const e = `transformer_encoder.layers.${l}.`;
    s.push([`${e}self_attn.in_proj_weight`, [3 * D, D]], [`${e}self_attn.in_proj_bias`, [3 * D]],
      [`${e}self_attn.out_proj.weight`, [D, D]], [`${e}self_attn.out_proj.bias`, [D]],
      [`${e}linear1.weight`, [H, D]], [`${e}linear1.bias`, [H]], [`${e}linear2.weight`, [D, H]], [`${e}linear2.bias`, [D]],
      [`${e}norm1.weight`, [D]], [`${e}norm1.bias`, [D]], [`${e}norm2.weight`, [D]], [`${e}norm2.bias`, [D]]);
  }
  s.push(['decoder.weight', [F, D]], ['decoder.bias', [F]]);
  return s.map(([name, shape]) => ({ name, shape }));
}

/** Deterministic uniform numbers in [0, 1) (mulberry32). */
export function mulberry32(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

/** Random weights: Map name -> {shape, data: Float32Array}. Matrices and biases uniform in
 *  ±1/√fan_in (PyTorch's nn.Linear default range); LayerNorm gains 1 ± 0.25 and offsets
 *  ±0.1 (not PyTorch's 1 and 0, so that a swapped gain/offset shows). */
export function randomInfillerWeights(c, seed = 1) {
  const u = mulberry32(seed);
  const w = new Map();
  for (const { name, shape } of infillerTensorSpecs(c)) {
    const n = shape.reduce((a, b) => a * b, 1);
    const data = new Float32Array(n);
    const isNorm = /norm/.test(name);
    const fanIn = shape.length === 2 ? shape[1] : c.dModel;
    const bound = isNorm ? (name.endsWith('weight') ? 0.25 : 0.1) : 1 / Math.sqrt(fanIn);
    const centre = isNorm && name.endsWith('weight') ? 1 : 0;
    for (let i = 0; i < n; ++i) data[i] = centre + bound * (2 * u() - 1);
    w.set(name, { shape, data });
  }
  return w;
}

/** The positional table (window × dModel, row-major, float64). */
export function positionalTable(c) {
  const pe = new Float64Array(c.window * c.dModel);
  for (let t = 0; t < c.window; ++t) {
    for (let i = 0; 2 * i < c.dModel; ++i) {
      const omega = Math.exp((-2 * i * Math.log(10000)) / c.dModel);
      pe[t * c.dModel + 2 * i] = Math.sin(t * omega);
      if (2 * i + 1 < c.dModel) pe[t * c.dModel + 2 * i + 1] = Math.cos(t * omega);
    }
  }
  return pe;
}

/** The network as .onnx bytes (opset 17), weights as initializers named as in the state_dict. */
export function buildInfillerOnnx(c, weights) {
  const W = c.window, F = c.features, D = c.dModel, H = c.heads, dh = D / H;
  if (!Number.isInteger(dh)) throw new Error('make_infiller_model: dModel must be divisible by heads');
  const g = new OnnxGraph('hawor_infiller');
  for (const [name, { shape, data }] of weights) g.addInitializer(name, shape, data);
  const int64 = (name, values) => g.addInitializer(name, [values.length], BigInt64Array.from(values, BigInt));
  const scalar = (name, v) => g.addInitializer(name, [], Float32Array.from([v]));
  // constants (only those the graph uses: onnxruntime warns about the others)
  if (c.maskedLayers + c.encoderLayers > 0) {
    int64('shape_heads', [W, H, dh]);
    int64('shape_model', [W, D]);
  }
  if (c.maskedLayers > 0) {
    scalar('minus_inf', -Infinity);
    scalar('masked_scale', 1 / Math.sqrt(D));
    scalar('threshold', 0.5);
  }
  if (c.encoderLayers > 0) {
    int64('split_qkv', [D, D, D]);
    scalar('encoder_scale', 1 / Math.sqrt(dh));
    scalar('one', 1);
    scalar('half', 0.5);
    scalar('sqrt2', Math.SQRT2);
  }
  g.addInitializer('pe', [W, D], Float32Array.from(positionalTable(c)));

  g.addInput('x', 'float32', [W, F]);
  g.addInput('valid', 'float32', [W, 1]);
  let k = 0;
  const v = (what) => `${what}_${k++}`;
  const node = (op, inputs, attrs = {}) => g.addNode(op, inputs, [v(op.toLowerCase())], attrs)[0];
  const gemm = (x, wName, bName) => node('Gemm', bName ? [x, wName, bName] : [x, wName], { transB: 1 });
  const layerNorm = (x, prefix) => node('LayerNormalization', [x, `${prefix}.weight`, `${prefix}.bias`], { axis: -1, epsilon: attr.float(1e-5) });
  // (W, D) -> (H, W, dh), or (H, dh, W) for keys
  const heads = (x, perm) => node('Transpose', [node('Reshape', [x, 'shape_heads'])], { perm });
  const attention = (q, kk, vv, scaleName, keyOk) => {
    let s = node('MatMul', [heads(q, [1, 0, 2]), heads(kk, [1, 2, 0])]); // (H, W, W)
    s = node('Mul', [s, scaleName]);
    if (keyOk) s = node('Where', [keyOk, s, 'minus_inf']); // keyOk (1, W) broadcasts over keys
    const p = node('Softmax', [s], { axis: -1 });
    const o = node('MatMul', [p, heads(vv, [1, 0, 2])]); // (H, W, dh)
    return node('Reshape', [node('Transpose', [o], { perm: [1, 0, 2] }), 'shape_model']);
  };

  // input layer: [x | valid] -> D, plus the positional table
  let h = node('Add', [gemm(node('Concat', ['x', 'valid'], { axis: 1 }), 'input_layer.weight', 'input_layer.bias'), 'pe']);
  const keyOk = c.maskedLayers > 0 ? node('Transpose', [node('Greater', ['valid', 'threshold'])], { perm: [1, 0] }) : null; // (1, W) bool
  // stage 1: pre-LN masked attention; the residual adds the normalised input (official)
  for (let i = 0; i < c.maskedLayers; ++i) {
    const a = `att_layers.${i}`;
    const n = layerNorm(h, `${a}.layer_norm`);
    const att = attention(gemm(n, `${a}.q_linear.weight`), gemm(n, `${a}.k_linear.weight`), gemm(n, `${a}.v_linear.weight`), 'masked_scale', keyOk);
    h = node('Add', [n, gemm(att, `${a}.out_linear.weight`)]);
    const p = `pff_layers.${i}`;
    const f = gemm(node('Relu', [gemm(layerNorm(h, `${p}.layer_norm`), `${p}.network.0.weight`, `${p}.network.0.bias`)]), `${p}.network.3.weight`, `${p}.network.3.bias`);
    h = node('Add', [h, f]);
  }
  h = layerNorm(h, 'layer_norm');
  // stage 2: nn.TransformerEncoderLayer, post-LN, GELU (erf), no mask
  for (let l = 0; l < c.encoderLayers; ++l) {
    const e = `transformer_encoder.layers.${l}`;
    const qkv = gemm(h, `${e}.self_attn.in_proj_weight`, `${e}.self_attn.in_proj_bias`);
    const [q, kk, vv] = g.addNode('Split', [qkv, 'split_qkv'], [v('q'), v('k'), v('v')], { axis: 1 });
    const att = gemm(attention(q, kk, vv, 'encoder_scale', null), `${e}.self_attn.out_proj.weight`, `${e}.self_attn.out_proj.bias`);
    h = layerNorm(node('Add', [h, att]), `${e}.norm1`);
    const z = gemm(h, `${e}.linear1.weight`, `${e}.linear1.bias`);
    const gelu = node('Mul', [node('Mul', [z, node('Add', [node('Erf', [node('Div', [z, 'sqrt2'])]), 'one'])]), 'half']);
    h = layerNorm(node('Add', [h, gemm(gelu, `${e}.linear2.weight`, `${e}.linear2.bias`)]), `${e}.norm2`);
  }
  g.addNode('Gemm', [h, 'decoder.weight', 'decoder.bias'], ['y'], { transB: 1 });
  g.addOutput('y', 'float32', [W, F]);
  return g.toBytes({ opsetVersion: 17, docString: 'hawor infiller network, random weights (test fixture)' });
}

/** The weights as an .npz (stored) of float32 tensors under their state_dict names. */
export function encodeInfillerNpz(weights) {
  return encodeNpzFloat32(weights);
}

async function main(argv) {
  const args = { out: null, seed: 1, small: false };
  for (let i = 0; i < argv.length; ++i) {
    if (argv[i] === '--out') args.out = argv[++i];
    else if (argv[i] === '--seed') args.seed = Number(argv[++i]);
    else if (argv[i] === '--small') args.small = true;
    else throw new Error(`make_infiller_model: unknown argument '${argv[i]}' (usage: --out DIR [--seed N] [--small])`);
  }
  if (!args.out) throw new Error('make_infiller_model: --out DIR is required');
  if (!Number.isSafeInteger(args.seed)) throw new Error('make_infiller_model: --seed must be an integer');
  const { mkdirSync, writeFileSync } = await import('node:fs');
  const { join } = await import('node:path');
  const config = args.small ? SMALL_CONFIG : OFFICIAL_CONFIG;
  const weights = randomInfillerWeights(config, args.seed);
  mkdirSync(args.out, { recursive: true });
  writeFileSync(join(args.out, 'infiller.onnx'), buildInfillerOnnx(config, weights));
  writeFileSync(join(args.out, 'infiller.npz'), encodeInfillerNpz(weights));
  console.log(JSON.stringify({ onnx: join(args.out, 'infiller.onnx'), npz: join(args.out, 'infiller.npz'), config, seed: args.seed }));
}

const isMain = typeof process !== 'undefined' && Array.isArray(process.argv) && process.argv[1] &&
  import.meta.url === (await import('node:url')).pathToFileURL(process.argv[1]).href;
if (isMain) {
  main(process.argv.slice(2)).catch((e) => {
    process.stderr.write(`${e.message}\n`);
    process.exit(1);
  });
}
