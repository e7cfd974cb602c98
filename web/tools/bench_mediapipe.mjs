// bench_mediapipe.mjs: median milliseconds per call of the converted MediaPipe networks under
// onnxruntime-web's wasm backend in node, at 1 and 2 threads (graph optimisation 'all').
//
//   node web/tools/bench_mediapipe.mjs [--models DIR] [--runs N] [--threads 1,2]
//
// Each thread count runs in its own child process (onnxruntime-web fixes the thread count when
// its wasm starts). Prints one JSON line per thread count and a table. The input is random in
// 0..1 (the cost of these networks does not depend on the pixels).

import { spawnSync } from 'node:child_process';
import { join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { defaultModelsDir, MODEL_NAMES } from './convert_mediapipe.mjs';

const self = fileURLToPath(import.meta.url);

function parse(argv) {
  const o = { models: defaultModelsDir, runs: 30, threads: [1, 2], child: false };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    if (a === '--models') o.models = resolve(argv[++i]);
    else if (a === '--runs') o.runs = Number(argv[++i]);
    else if (a === '--threads') o.threads = argv[++i].split(',').map(Number);
    else if (a === '--child') o.child = true;
    else throw new Error(`unknown argument '${a}'`);
  }
  if (!(o.runs >= 1) || o.threads.some((t) => !(t >= 1))) throw new Error('--runs and --threads must be positive');
  return o;
}

async function child(o) {
  const ort = await import('onnxruntime-web');
  ort.env.wasm.numThreads = o.threads[0];
  ort.env.logLevel = 'error';
  const res = { threads: o.threads[0], runs: o.runs, medianMs: {}, minMs: {} };
  for (const name of MODEL_NAMES) {
    const s = await ort.InferenceSession.create(join(o.models, `${name}.onnx`), { graphOptimizationLevel: 'all' });
    const N = name.startsWith('palm') ? 192 : 224;
    const x = new Float32Array(N * N * 3);
    for (let i = 0; i < x.length; ++i) x[i] = Math.random();
    const feeds = { [s.inputNames[0]]: new ort.Tensor('float32', x, [1, N, N, 3]) };
    for (let k = 0; k < 3; ++k) await s.run(feeds); // warm-up
    const times = [];
    for (let k = 0; k < o.runs; ++k) {
      const t0 = performance.now();
      await s.run(feeds);
      times.push(performance.now() - t0);
    }
    times.sort((a, b) => a - b);
    res.medianMs[name] = Number(times[Math.floor(times.length / 2)].toFixed(1));
    res.minMs[name] = Number(times[0].toFixed(1));
    await s.release();
  }
  process.stdout.write(`${JSON.stringify(res)}\n`);
}

async function main() {
  const o = parse(process.argv.slice(2));
  if (o.child) return child(o);
  const rows = [];
  for (const t of o.threads) {
    const r = spawnSync(process.execPath, [self, '--child', '--models', o.models, '--runs', String(o.runs), '--threads', String(t)], { encoding: 'utf8' });
    if (r.status !== 0) throw new Error(`child (${t} threads) failed: ${r.stderr}`);
    const line = r.stdout.trim().split('\n').pop();
    process.stdout.write(`${line}\n`);
    rows.push(JSON.parse(line));
  }
  process.stdout.write(`\nmedian ms per call (min), onnxruntime-web wasm, node ${process.version}\n`);
  process.stdout.write(`${'model'.padEnd(22)}${rows.map((r) => `${r.threads} thread${r.threads > 1 ? 's' : ''}`.padStart(16)).join('')}\n`);
  for (const n of MODEL_NAMES) {
    process.stdout.write(`${n.padEnd(22)}${rows.map((r) => `${r.medianMs[n]} (${r.minMs[n]})`.padStart(16)).join('')}\n`);
  }
}

main().catch((e) => { process.stderr.write(`bench_mediapipe: ${e.message}\n`); process.exitCode = 1; });
