// Reference outputs of the infiller network from onnxruntime-web (node, wasm, one thread), for
// tests/motion/ref_infiller_net.cpp:
//   node tests/ref/infiller_onnx.mjs OUT.txt [--seed N] [--windows K] [--small]
// builds the network with random weights (web/tools/make_infiller_model.mjs), writes the
// weights to OUT.txt.npz, runs K random windows with random validity masks through
// onnxruntime, and writes x<i> (W,F), valid<i> (W,) and y<i> (W,F) to OUT.txt in the plain-text
// format of tests/ref/refio.py (tests/support/ref_data.hpp reads it). Values are float32
// numbers printed exactly (JavaScript's shortest round-trip form of the double).

import { writeFileSync } from 'node:fs';
import * as ort from 'onnxruntime-web';
import {
  OFFICIAL_CONFIG, SMALL_CONFIG, buildInfillerOnnx, encodeInfillerNpz, mulberry32, randomInfillerWeights,
} from '../../web/tools/make_infiller_model.mjs';

ort.env.wasm.numThreads = 1;
ort.env.logLevel = 'error';

const argv = process.argv.slice(2);
const out = argv[0];
let seed = 7;
let windows = 3;
let small = false;
for (let i = 1; i < argv.length; ++i) {
  if (argv[i] === '--seed') seed = Number(argv[++i]);
  else if (argv[i] === '--windows') windows = Number(argv[++i]);
  else if (argv[i] === '--small') small = true;
  else throw new Error(`infiller_onnx: unknown argument ${argv[i]}`);
}
if (!out) throw new Error('usage: node tests/ref/infiller_onnx.mjs OUT.txt [--seed N] [--windows K] [--small]');

const config = small ? SMALL_CONFIG : OFFICIAL_CONFIG;
const W = config.window;
const F = config.features;
const weights = randomInfillerWeights(config, seed);
writeFileSync(`${out}.npz`, encodeInfillerNpz(weights));
const session = await ort.InferenceSession.create(buildInfillerOnnx(config, weights));

// Validity patterns, window i: kind (i + 1) % 4 of gaps of 10-60 frames (1), only a few frames
// observed (2), the first half missing (3), all observed (0).
const u = mulberry32(seed + 1000);
function mask(kind) {
  const v = new Float32Array(W).fill(1);
  if (kind === 0) return v;
  if (kind === 2) {
    v.fill(0);
    for (let n = 0; n < 5; ++n) v[Math.floor(u() * W)] = 1;
    return v;
  }
  if (kind === 3) {
    for (let t = 0; t < W / 2; ++t) v[t] = 0;
    return v;
  }
  let t = Math.floor(u() * 10);
  while (t < W) {
    const gap = 10 + Math.floor(u() * 51);
    for (let j = t; j < Math.min(W, t + gap); ++j) v[j] = 0;
    t += gap + 5 + Math.floor(u() * 30);
  }
  v[Math.floor(u() * W)] = 1; // never all masked
  return v;
}

const lines = [];
const put = (name, shape, data) => {
  lines.push(`${name} ${shape.length} ${shape.join(' ')}`);
  lines.push(Array.from(data, (x) => String(x)).join(' '));
};
for (let i = 0; i < windows; ++i) {
  const x = new Float32Array(W * F);
  for (let j = 0; j < x.length; ++j) x[j] = 2 * u() - 1;
  const valid = mask((i + 1) % 4);
  const r = await session.run({ x: new ort.Tensor('float32', x, [W, F]), valid: new ort.Tensor('float32', valid, [W, 1]) });
  put(`x${i}`, [W, F], x);
  put(`valid${i}`, [W], valid);
  put(`y${i}`, [W, F], r.y.data);
}
writeFileSync(out, lines.join('\n') + '\n');
