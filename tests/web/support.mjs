// Shared helpers of the node tests (not a test file: node --test runs only *.test.mjs here).

import * as ort from 'onnxruntime-web';

ort.env.wasm.numThreads = 1; // deterministic results, no worker threads
ort.env.logLevel = 'error';

export { ort };

/** Deterministic pseudo-random numbers in [0, 1) (mulberry32), so failures reproduce. */
export function rng(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

/** Asserts |actual - expected| <= rel * |expected| + abs elementwise; names the first miss. */
export function assertClose(actual, expected, { rel = 1e-5, abs = 1e-6, what = 'value' } = {}) {
  if (actual.length !== expected.length) throw new Error(`${what}: length ${actual.length}, expected ${expected.length}`);
  for (let i = 0; i < expected.length; ++i) {
    const a = actual[i];
    const e = expected[i];
    if (!(Math.abs(a - e) <= rel * Math.abs(e) + abs)) {
      throw new Error(`${what}[${i}] = ${a}, expected ${e} (tolerance rel ${rel}, abs ${abs})`);
    }
  }
}
