// worker.mjs — the app's Web Worker: loads the C++ core (hawor_core.mjs), onnxruntime-web, the
// hand networks and the hand models, receives decoded frames from the page (streamed, with
// back-pressure), runs the shared pipeline (web/src/pipeline/run.mjs) and answers exports.
// All files are read from this page's own origin or from what the user dropped; nothing leaves
// the browser.
//
// Every import is relative to this file; what the page's import map names (onnxruntime-web, the
// default hand of @webxr-input-profiles/assets) comes as URLs in the init message.
//
// page -> worker: {type:'init', urls: {ort, hands: {left, right}}} | {type:'start', meta, options} | {type:'frame', index, rgba}
//   | {type:'end'} | {type:'cancel'} | {type:'load-result', text, options} | {type:'export', format}
// worker -> page: {type:'ready', info} | {type:'credit'} | {type:'progress', stage, done, total}
//   | {type:'frame-info', info} | {type:'result', result, meshes} | {type:'error', kind, message}
//   | {type:'cancelled'} | {type:'exported', format, data, mime, filename}
//   live (meta.live: the camera): {type:'live-start', intrinsics} | {type:'live-frame', info}
//
// Frames: for a file the page keeps a few in flight ('credit': one was taken); live, a 'credit'
// says that the pipeline waits for a frame with none queued, and the page hands over exactly one
// (a camera frame that comes while none is asked for is dropped by the page, never queued).
import { loadCore } from '../src/core.mjs';
import { handMeshSequence } from '../src/export/hand_meshes.mjs';
import { buildGlb } from '../src/export/gltf.mjs';
import { chooseProvider } from '../src/perception/execution_provider.mjs';

let ort = null;          // onnxruntime-web's namespace, imported in init()
let ortUrls = null;      // { ort, ortWebgpu }: its WebAssembly and WebGPU builds
const state = {
  core: null,
  models: {},            // 'lite' | 'full' -> { palm, landmark } bytes
  backends: {},          // 'PREFERENCE/KIND/THREADS' -> chooseProvider's answer (probed once a page)
  defaultHands: null,    // { left, right } bytes
  run: null,             // the clip being processed
  result: null,          // the last result
  hands: null,           // { left: {bytes, name}, right: {bytes, name} } the result's hand models
};

const post = (m, transfer) => self.postMessage(m, transfer || []);
const fail = (kind, message) => post({ type: 'error', kind, message });

async function fetchBytes(url, what) {
  const r = await fetch(url);
  if (!r.ok) throw Object.assign(new Error(`${what} is missing from the server (${url}: HTTP ${r.status}); serve the app with web/server.mjs after scripts/build_web.sh (checkout) or from the installed package`), { kind: 'setup' });
  return new Uint8Array(await r.arrayBuffer());
}

async function init(urls) {
  const t0 = performance.now();
  const setup = (what, e) => Object.assign(new Error(`${what} could not be loaded: ${e.message}`), { kind: 'setup' });
  const [core, ortModule, left, right] = await Promise.all([
    loadCore().catch((e) => { throw setup('The C++ core', e); }),
    import(urls.ort).catch((e) => { throw setup(`onnxruntime-web (${urls.ort})`, e); }),
    fetchBytes(urls.hands.left, 'the default left hand'),
    fetchBytes(urls.hands.right, 'the default right hand'),
  ]);
  state.core = core;
  ort = ortModule;
  ortUrls = urls;
  configureOrt(ort, urls.ort);
  // The licence-free default hand: the WebXR glTF hands, read by the core as they are.
  state.defaultHands = { left: { bytes: left, name: 'left.glb' }, right: { bytes: right, name: 'right.glb' } };
  return { ms: performance.now() - t0, crossOriginIsolated: self.crossOriginIsolated, cores: navigator.hardwareConcurrency };
}

function configureOrt(ns, url) {
  ns.env.wasm.wasmPaths = new URL('./', url).href;
  ns.env.logLevel = 'error';
}

/// The backend of the hand networks (WebAssembly or WebGPU; execution_provider.mjs), measured once
/// per preference, network kind and thread count; the page is told which runs and why.
async function networkBackend(preference, kind, nets, threads) {
  const key = `${preference}/${kind}/${threads}`;
  if (!state.backends[key]) {
    ort.env.wasm.numThreads = threads;
    state.backends[key] = await chooseProvider({
      preference, ort, models: nets,
      loadWebgpu: async () => {
        if (!ortUrls.ortWebgpu) throw new Error('the page named no WebGPU build');
        const ns = await import(ortUrls.ortWebgpu);
        configureOrt(ns, ortUrls.ortWebgpu);
        ns.env.wasm.numThreads = threads;
        return ns;
      },
    });
  }
  const b = state.backends[key];
  post({ type: 'backend', info: { provider: b.provider, why: b.why, adapter: b.adapter ?? null, ms: b.ms ?? null, disagreement: b.disagreement ?? null } });
  return b;
}

async function networks(kind) {
  if (!state.models[kind]) {
    const [palm, landmark] = await Promise.all([
      fetchBytes(new URL(`../models/palm_detection_${kind}.onnx`, import.meta.url), `the palm detector (${kind})`),
      fetchBytes(new URL(`../models/hand_landmark_${kind}.onnx`, import.meta.url), `the hand landmarker (${kind})`),
    ]);
    state.models[kind] = { palm, landmark };
  }
  return state.models[kind];
}

/// The hand models of a run: the user's MANO files where given, the default hand otherwise.
/// Each is loaded once here so that a wrong file is reported before any frame is processed.
function handModels(options) {
  const out = {};
  for (const side of ['left', 'right']) {
    const given = options.mano && options.mano[side];
    const m = given ? { bytes: new Uint8Array(given.bytes), name: given.name } : state.defaultHands[side];
    let model = null;
    try {
      model = new state.core.HandModel(m.bytes, side, m.name);
      if (given && !model.kind().startsWith('mano')) {
        throw new Error(`it is a "${model.kind()}" hand model, not MANO`);
      }
    } catch (e) {
      throw Object.assign(new Error(given
        ? `The ${side} MANO file "${m.name}" cannot be used: ${e.message.replace(/^HandModel: /, '')}. Use MANO_${side.toUpperCase()}.pkl from the MANO website (or an .npz with its arrays).`
        : `The default ${side} hand failed to load: ${e.message}`), { kind: given ? 'mano' : 'setup' });
    } finally {
      if (model) model.delete();
    }
    out[side] = m;
  }
  return out;
}

function meshesOf(result, hands) {
  const T = result.frameCount;
  const meshes = {};
  for (const side of ['left', 'right']) {
    const model = new state.core.HandModel(hands[side].bytes, side, hands[side].name);
    try { meshes[side] = handMeshSequence(model, result.hands && result.hands[side], T); }
    finally { model.delete(); }
  }
  return meshes;
}

function postResult(result) {
  const meshes = meshesOf(result, state.hands);
  const transfer = [];
  for (const side of ['left', 'right']) transfer.push(meshes[side].vertices.buffer);
  post({ type: 'result', result, meshes }, transfer);
}

// --- frames from the page ------------------------------------------------------------------------

function frameQueue(signal, live = false) {
  const q = { items: [], ended: false, wake: null, asked: false };
  q.push = (f) => { q.items.push(f); q.asked = false; if (q.wake) { q.wake(); q.wake = null; } };
  q.end = () => { q.ended = true; if (q.wake) { q.wake(); q.wake = null; } };
  q.iterable = {
    [Symbol.asyncIterator]() {
      return {
        async next() {
          for (;;) {
            if (signal.aborted) throw new DOMException('cancelled', 'AbortError');
            if (q.items.length) { if (!live) post({ type: 'credit' }); return { value: q.items.shift(), done: false }; }
            if (q.ended) return { value: undefined, done: true };
            if (live && !q.asked) { q.asked = true; post({ type: 'credit' }); }
            await new Promise((r) => { q.wake = r; signal.addEventListener('abort', r, { once: true }); });
          }
        },
        async return() { q.items.length = 0; return { value: undefined, done: true }; },
      };
    },
  };
  return q;
}

async function start(meta, options) {
  if (state.run) return fail('busy', 'A clip is already being processed.');
  const controller = new AbortController();
  const live = !!meta.live;
  const frames = frameQueue(controller.signal, live);
  state.run = { controller, frames };
  try {
    let run, cameraIntrinsics;
    try {
      ({ runPipeline: run, cameraIntrinsics } = await import('../src/pipeline/run.mjs'));
    } catch (e) {
      throw Object.assign(new Error(`The processing pipeline (web/src/pipeline/run.mjs) could not be loaded: ${e.message}`), { kind: 'setup' });
    }
    const hands = handModels(options);
    const nets = await networks(options.modelKind || 'lite');
    const source = { width: meta.width, height: meta.height, fps: meta.fps, frameCount: meta.frameCount ?? null, frames: frames.iterable };
    // onnxruntime's threads: all cores but one (the page decodes the video meanwhile), at most 4;
    // threads need cross-origin isolation (SharedArrayBuffer).
    const threads = options.threads || (self.crossOriginIsolated ? Math.max(1, Math.min(4, (navigator.hardwareConcurrency || 2) - 1)) : 1);
    const backend = await networkBackend(options.backend || 'auto', options.modelKind || 'lite', nets, threads);
    const opts = {
      core: state.core, ort: backend.ort, sessionOptions: backend.sessionOptions,
      // the probe's sessions where it ran (kept for the page's later runs), else the bytes
      models: backend.sessions ? { ...backend.sessions } : { palm: nets.palm, landmark: nets.landmark },
      handModels: { left: hands.left.bytes, right: hands.right.bytes, leftName: hands.left.name, rightName: hands.right.name },
      modelKind: options.modelKind || 'lite',
      threads,
      // The SLAM's grey frames and masks kept for the focal re-runs: 64 MB in the page (≈ 100
      // frames at 640×480) instead of the pipeline's 256 MB, so that a long clip stays within the
      // page's memory budget; longer clips refine the focal in the final bundle adjustment only.
      focalRerunBytes: 64 * 1024 * 1024,
    };
    if (options.focalPx) opts.focalPx = options.focalPx;
    if (options.fovDeg) opts.fovDeg = options.fovDeg;
    if (options.eyeHeight) opts.eyeHeight = options.eyeHeight;
    if (options.camera) opts.camera = options.camera;
    if (options.readout) opts.readout = options.readout;
    if (options.depth) opts.depthModel = { bytes: new Uint8Array(options.depth.bytes), config: options.depth.config };
    if (live) {
      // the camera: causal estimates per frame
      opts.live = true;
      // the page draws the live frustum with the intrinsics the pipeline uses (throws as it would)
      post({ type: 'live-start', intrinsics: cameraIntrinsics(state.core, meta.width, meta.height, opts) });
    }
    const hooks = {
      signal: controller.signal,
      onProgress: (p) => post({ type: 'progress', stage: p.stage, done: p.done, total: p.total }),
      onFrame: live ? (info) => post({ type: 'live-frame', info: liveInfo(info) }) : (info) => post({ type: 'frame-info', info: plain(info) }),
    };
    const result = await run(source, opts, hooks);
    if (controller.signal.aborted) throw new DOMException('cancelled', 'AbortError');
    state.result = result;
    state.hands = hands;
    postResult(result);
  } catch (e) {
    if (controller.signal.aborted || (e && e.name === 'AbortError')) post({ type: 'cancelled' });
    else fail(e.kind || classify(e), e.message || String(e));
  } finally {
    state.run = null;
  }
}

/// Error kinds for the page's message (from the pipeline's own error text).
function classify(e) {
  const m = String(e && e.message || e);
  if (/too short|at least \d+ frames/i.test(m)) return 'short';
  if (/no hand/i.test(m)) return 'nohands';
  if (/^the camera model /.test(m)) return 'camera';
  return e && e.name === 'HaworError' ? 'core' : 'pipeline';
}

/// A live frame's info for the page: the hands seen (side, fitted, image keypoints), the frame's
/// camera and fitted joints in the live world, and the live world when it was updated.
function liveInfo(info) {
  return {
    index: info.index, ms: info.ms, slamStatus: info.slamStatus,
    hands: info.hands.map((h) => ({ side: h.side, valid: h.valid, keypoints2d: h.keypoints2d ?? null })),
    live: info.live ?? null, world: info.world ?? null,
  };
}

/// Only what structured cloning carries, small: frame infos may hold typed arrays.
function plain(info) {
  if (!info || typeof info !== 'object') return info;
  const o = {};
  for (const [k, v] of Object.entries(info)) if (v == null || typeof v !== 'object' || ArrayBuffer.isView(v) && v.length <= 512) o[k] = v;
  return o;
}

async function loadResult(text, options) {
  let result;
  try { result = JSON.parse(text); } catch (e) { throw Object.assign(new Error(`This file is not a hawor result.json: ${e.message}`), { kind: 'result' }); }
  if (!result || result.version !== 1 || !(result.frameCount > 0) || !result.camera || !result.hands) {
    throw Object.assign(new Error('This file is not a hawor result.json (version 1 with frameCount, camera and hands).'), { kind: 'result' });
  }
  state.hands = handModels(options);
  state.result = result;
  postResult(result);
}

async function exportResult(format) {
  const r = state.result;
  if (!r) throw Object.assign(new Error('Nothing to export yet.'), { kind: 'export' });
  if (format === 'glb') {
    const meshes = meshesOf(r, state.hands);
    const cam = r.camera || {};
    const glb = buildGlb({
      fps: r.fps, frameCount: r.frameCount, hands: meshes, points: r.points, world: r.world,
      camera: cam.positions && cam.quaternions ? { positions: cam.positions, quaternions: cam.quaternions, width: r.width, height: r.height, fx: r.intrinsics.fx, fy: r.intrinsics.fy } : null,
    });
    return { data: glb, mime: 'model/gltf-binary', filename: 'hawor.glb' };
  }
  const ex = await import('../src/pipeline/exports.mjs');
  if (format === 'json') return { data: ex.resultToJson(r), mime: 'application/json', filename: 'result.json' };
  if (format === 'npz') return { data: ex.resultToWorldNpz(r), mime: 'application/octet-stream', filename: 'hawor_world.npz' };
  if (format === 'tum') return { data: ex.resultToTum(r), mime: 'text/plain', filename: 'camera.tum' };
  throw Object.assign(new Error(`unknown export format ${format}`), { kind: 'export' });
}

self.onmessage = async (ev) => {
  const m = ev.data;
  try {
    switch (m.type) {
      case 'init': post({ type: 'ready', info: await init(m.urls) }); break;
      case 'start': start(m.meta, m.options); break;
      case 'frame': if (state.run) state.run.frames.push({ index: m.index, rgba: new Uint8ClampedArray(m.rgba), ...(m.time !== undefined ? { time: m.time } : {}) }); break;
      case 'end': if (state.run) state.run.frames.end(); break;
      case 'cancel': if (state.run) state.run.controller.abort(); break;
      case 'load-result': await loadResult(m.text, m.options || {}); break;
      case 'stats': post({ type: 'stats', stats: {
        coreHeapBytes: state.core && state.core.HEAPU8 ? state.core.HEAPU8.length : null,
        jsHeapBytes: self.performance && performance.memory ? performance.memory.usedJSHeapSize : null } }); break;
      case 'export': { const x = await exportResult(m.format); post({ type: 'exported', format: m.format, ...x }, x.data.buffer ? [x.data.buffer] : []); break; }
      default: fail('internal', `worker: unknown message ${m.type}`);
    }
  } catch (e) {
    fail(e.kind || classify(e), e.message || String(e));
  }
};
