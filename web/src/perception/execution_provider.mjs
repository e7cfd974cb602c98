// execution_provider.mjs — which onnxruntime-web backend runs the hand networks in a browser:
// WebAssembly (the default, on the CPU) or WebGPU (a GPU the browser exposes). WebGPU is used only
// where it is measured to be both right and faster on this machine:
//   1. the browser has a WebGPU adapter, and (for 'auto') not a software one (SwiftShader and the
//      like run on the same CPU cores as WebAssembly, through a GPU emulation: never faster);
//   2. both networks give the WebAssembly outputs on the same input, each output within
//      AGREE_REL of its largest magnitude (float32 everywhere; reassociation differs only);
//   3. the palm + landmark pair takes, median over `runs` timed runs after a warm-up, less than
//      FASTER × the WebAssembly median ('auto' only; 'webgpu' asks for it whenever it agrees,
//      and times one run of each for the page to show).
// Otherwise WebAssembly runs, and `why` says why, for the page to show.
//
// The probe's sessions of the chosen backend are handed on (HandTracker takes them as they are,
// so WebGPU's shaders are not compiled twice); the other backend's are released. Nothing here is
// method policy: the same networks run either way, on the same inputs.

import { handSessionOptions } from './hand_tracker.mjs';
import { PALM_INPUT_SIZE } from './palm.mjs';
import { LANDMARK_INPUT_SIZE } from './landmarks.mjs';

export const PROVIDER_CHOICES = ['auto', 'wasm', 'webgpu'];
export const AGREE_REL = 1e-3;
export const FASTER = 0.9;

/// The browser's WebGPU adapter, or why there is none. `gpu`: navigator.gpu (a parameter for tests).
export async function webgpuAdapter(gpu = globalThis.navigator?.gpu) {
  if (!gpu) return { adapter: null, why: 'this browser has no WebGPU' };
  let adapter = null;
  try { adapter = await gpu.requestAdapter({ powerPreference: 'high-performance' }); } catch (e) { return { adapter: null, why: `WebGPU refused an adapter (${e.message})` }; }
  if (!adapter) return { adapter: null, why: 'WebGPU has no adapter on this machine' };
  const info = adapter.info || {};
  const name = [info.vendor, info.architecture, info.description].filter(Boolean).join(' ') || 'unnamed';
  const software = !!(info.isFallbackAdapter || adapter.isFallbackAdapter) || /swiftshader|llvmpipe|software/i.test(name);
  return { adapter, name, software };
}

/// A deterministic smooth test image in [0, 1], S × S × 3 (NHWC), the networks' input layout.
export function probeInput(S) {
  const x = new Float32Array(S * S * 3);
  for (let i = 0; i < x.length; ++i) x[i] = 0.5 + 0.4 * Math.sin(i * 0.013) * Math.cos(i * 0.0007);
  return x;
}

const median = (v) => { const s = [...v].sort((a, b) => a - b); const n = s.length; return n % 2 ? s[(n - 1) / 2] : (s[n / 2 - 1] + s[n / 2]) / 2; };

/// Largest |a − b| over an output relative to its largest |a| (at least 1e-6); Infinity when
/// the sizes differ or a value is not finite.
export function outputDisagreement(a, b) {
  if (a.length !== b.length) return Infinity;
  let d = 0, m = 0;
  for (let i = 0; i < a.length; ++i) {
    const e = Math.abs(a[i] - b[i]);
    if (!Number.isFinite(e)) return Infinity;
    if (e > d) d = e;
    if (Math.abs(a[i]) > m) m = Math.abs(a[i]);
  }
  return d / Math.max(m, 1e-6);
}

/// Runs both networks `1 + runs` times on the probe inputs with one backend: the warm-up's outputs
/// (name -> Float32Array), the timed runs' ms of the pair and the sessions ({ palmSession,
/// landmarkSession }; release() them when not used). `stopAfterMs`: stop timing once one run took
/// longer (a backend already known to be slower).
async function probeBackend(ort, models, sessionOptions, runs, stopAfterMs = Infinity) {
  const sessions = [];
  try {
    for (const [bytes, S] of [[models.palm, PALM_INPUT_SIZE], [models.landmark, LANDMARK_INPUT_SIZE]]) {
      const s = await ort.InferenceSession.create(bytes, handSessionOptions(sessionOptions));
      sessions.push({ s, feeds: { [s.inputNames[0]]: new ort.Tensor('float32', probeInput(S), [1, S, S, 3]) } });
    }
    const outputs = {};
    const ms = [];
    for (let k = 0; k <= runs; ++k) {
      const t0 = performance.now();
      for (const [j, { s, feeds }] of sessions.entries()) {
        const o = await s.run(feeds);
        if (k === 0) for (const n of s.outputNames) outputs[`${j ? 'landmark' : 'palm'}/${n}`] = Float32Array.from(o[n].data);
      }
      if (k > 0) ms.push(performance.now() - t0);
      if (k > 0 && ms[ms.length - 1] > stopAfterMs) break;
    }
    return { outputs, ms, sessions: { palmSession: sessions[0].s, landmarkSession: sessions[1].s } };
  } catch (e) {
    await release(sessions.map((x) => x.s));
    throw e;
  }
}

async function release(list) {
  for (const s of list) { try { await s?.release?.(); } catch { /* already gone */ } }
}
const releaseBoth = (p) => (p ? release([p.sessions.palmSession, p.sessions.landmarkSession]) : undefined);

/**
 * Picks the backend of the hand networks.
 *   preference: 'auto' | 'wasm' | 'webgpu'
 *   ort: onnxruntime-web's WebAssembly namespace; loadWebgpu(): the namespace of its WebGPU build
 *   (loaded only when an adapter exists); models: { palm, landmark } ONNX bytes;
 *   sessionOptions: the WebAssembly session options the pipeline uses; runs: timed runs (3).
 * Returns { provider: 'wasm' | 'webgpu', ort, sessionOptions, why, adapter?, ms?: { wasm, webgpu },
 * disagreement?, sessions?: { palmSession, landmarkSession } } (sessions: where the probe ran, the
 * chosen backend's, for the caller to use and release).
 */
export async function chooseProvider({ preference = 'auto', ort, loadWebgpu, models, sessionOptions = {}, runs = 3, gpu } = {}) {
  if (!PROVIDER_CHOICES.includes(preference)) throw new Error(`chooseProvider: unknown network backend "${preference}" (expected ${PROVIDER_CHOICES.join(', ')})`);
  const onWasm = (why, extra = {}) => ({ provider: 'wasm', ort, sessionOptions, why, ...extra });
  if (preference === 'wasm') return onWasm('WebAssembly was asked for');
  const found = await webgpuAdapter(gpu);
  const { adapter, name, software } = found;
  if (!adapter) return onWasm(found.why);
  if (software && preference === 'auto') return onWasm(`the only WebGPU adapter is a software renderer (${name}), which runs on the same CPU cores`, { adapter: name });
  let gpuOrt;
  try { gpuOrt = await loadWebgpu(); } catch (e) { return onWasm(`onnxruntime-web's WebGPU build could not be loaded (${e.message})`, { adapter: name }); }
  const gpuOptions = { ...sessionOptions, executionProviders: ['webgpu'] };
  // asked for WebGPU, the timing is only reported: one timed run each
  if (preference === 'webgpu') runs = 1;
  const cpu = await probeBackend(ort, models, sessionOptions, runs);
  const cpuMs = median(cpu.ms);
  let gpuRun;
  try {
    gpuRun = await probeBackend(gpuOrt, models, gpuOptions, runs, preference === 'auto' ? 2 * cpuMs : Infinity);
  } catch (e) {
    return onWasm(`the networks failed on WebGPU (${e.message})`, { adapter: name, sessions: cpu.sessions });
  }
  let disagreement = 0;
  for (const [k, a] of Object.entries(cpu.outputs)) disagreement = Math.max(disagreement, gpuRun.outputs[k] ? outputDisagreement(a, gpuRun.outputs[k]) : Infinity);
  const ms = { wasm: cpuMs, webgpu: median(gpuRun.ms) };
  const extra = { adapter: name, ms, disagreement };
  let why = null;
  if (!(disagreement <= AGREE_REL)) why = `WebGPU's outputs differ from WebAssembly's (${disagreement.toExponential(1)} of their range)`;
  else if (preference === 'auto' && !(ms.webgpu < FASTER * ms.wasm)) why = `WebGPU (${name}) is not faster here: ${ms.webgpu.toFixed(1)} against ${ms.wasm.toFixed(1)} ms per frame's networks`;
  if (why) {
    await releaseBoth(gpuRun);
    return onWasm(why, { ...extra, sessions: cpu.sessions });
  }
  await releaseBoth(cpu);
  return {
    provider: 'webgpu', ort: gpuOrt, sessionOptions: gpuOptions, sessions: gpuRun.sessions, ...extra,
    why: preference === 'webgpu' ? `WebGPU (${name}) was asked for; its outputs agree with WebAssembly's` : `WebGPU (${name}) is faster here: ${ms.webgpu.toFixed(1)} against ${ms.wasm.toFixed(1)} ms per frame's networks`,
  };
}
