// ort_runtime.mjs (node only): the hand networks' onnxruntime for the CLI and its perception
// worker (web/cli.mjs, perception/tracker_worker.mjs).

/**
 * The networks' runtime: onnxruntime-node (onnxruntime's native CPU build, an optional dependency;
 * the networks run 5-10x faster than in WebAssembly) unless `which` is 'wasm' or it is not
 * installed, else onnxruntime-web's WebAssembly build, the one the browser runs. Both take the
 * same ONNX files and API; their outputs agree to float rounding (tests/web/runtime.test.mjs).
 */
export async function loadOrt(which = 'auto', threads = 2) {
  if (which !== 'wasm') {
    try {
      const m = await import('onnxruntime-node');
      const ort = m.default?.InferenceSession ? m.default : m;
      ort.env.logLevel = 'error';
      return { ort, runtime: 'native', sessionOptions: { executionProviders: ['cpu'], intraOpNumThreads: threads, interOpNumThreads: 1 } };
    } catch (e) {
      if (which === 'native') throw Object.assign(new Error(`--runtime native: onnxruntime-node cannot be loaded (${e.message.split('\n')[0]}); npm install onnxruntime-node, or --runtime wasm`), { exitCode: 1 });
    }
  }
  const ort = await import('onnxruntime-web');
  ort.env.wasm.numThreads = threads;
  ort.env.logLevel = 'error';
  return { ort, runtime: 'wasm', sessionOptions: undefined };
}
