// The networks' two runtimes (web/cli.mjs loadOrt): onnxruntime-node (native, the CLI's default
// when installed) against onnxruntime-web (WebAssembly, what the browser runs) on the same
// inputs, each network's every output; the CLI's --runtime choice and usage error. Skipped with
// a message when the optional onnxruntime-node is not installed or the networks are missing.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { root, modelsDir, modelsSkipReason } from './mediapipe_support.mjs';
import { ort as web, rng, assertClose } from './support.mjs';
import { loadOrt, parseArgs } from '../../web/cli.mjs';

let native = null;
try {
  native = (await import('onnxruntime-node')).default;
} catch {
  native = null;
}
const nativeSkip = () => (native ? false : 'onnxruntime-node is not installed (an optional dependency: ONNXRUNTIME_NODE_INSTALL=skip npm install)');

test('onnxruntime-node and onnxruntime-web agree on every output of the four hand networks', { skip: nativeSkip() || modelsSkipReason() }, async () => {
  const r = rng(11);
  for (const [name, S] of [['palm_detection_lite', 192], ['palm_detection_full', 192], ['hand_landmark_lite', 224], ['hand_landmark_full', 224]]) {
    const bytes = readFileSync(join(modelsDir, `${name}.onnx`));
    const a = await web.InferenceSession.create(bytes);
    const b = await native.InferenceSession.create(bytes, { executionProviders: ['cpu'], intraOpNumThreads: 1 });
    assert.deepEqual(b.outputNames, a.outputNames, name);
    // an image-like input: smooth gradients plus noise in [0, 1]
    const x = new Float32Array(S * S * 3);
    for (let i = 0; i < x.length; ++i) x[i] = Math.min(1, Math.max(0, 0.5 + 0.4 * Math.sin(i / 97) + 0.1 * (r() - 0.5)));
    const oa = await a.run({ [a.inputNames[0]]: new web.Tensor('float32', x, [1, S, S, 3]) });
    const ob = await b.run({ [b.inputNames[0]]: new native.Tensor('float32', x, [1, S, S, 3]) });
    // float32 kernels that differ in summation order: absolute 1e-3 on outputs up to ~200 px
    for (const k of a.outputNames) assertClose(ob[k].data, oa[k].data, { rel: 1e-5, abs: 1e-3, what: `${name} ${k}` });
    await a.release?.();
    await b.release?.();
  }
});

test('loadOrt: native by default when installed, wasm on request; --runtime is checked', { skip: nativeSkip() }, async () => {
  const n = await loadOrt('auto', 1);
  assert.equal(n.runtime, 'native');
  assert.deepEqual(n.sessionOptions, { executionProviders: ['cpu'], intraOpNumThreads: 1, interOpNumThreads: 1 });
  const w = await loadOrt('wasm', 1);
  assert.equal(w.runtime, 'wasm');
  assert.equal(w.sessionOptions, undefined);
  assert.equal(parseArgs(['run', 'v.mp4', '--out', 'o', '--runtime', 'wasm']).runtime, 'wasm');
  assert.throws(() => parseArgs(['run', 'v.mp4', '--out', 'o', '--runtime', 'gpu']), /--runtime must be auto, native or wasm, not 'gpu'/);
  assert.ok(existsSync(join(root, 'web/cli.mjs')));
});
