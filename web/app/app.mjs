// app.mjs — the page: inputs, the Web Worker that processes a clip, the views, the timeline and
// the exports. The video is decoded here (the browser's <video>), frame by frame, and streamed to
// the worker; no frame is kept. Live mode streams a camera's frames the same way, each one only
// when the worker asks for one (the others are dropped, and counted). Nothing is uploaded: every
// file and frame stays in this browser.
import { InputError, LIMITS, openVideo, estimateFps, processingSize, videoFrames } from './video_source.mjs';
import { CameraFrames, closeCamera, listCameras, openCamera, playCamera } from './camera_source.mjs';
import { SceneView } from './view3d.mjs';
import { VideoOverlay } from './overlay.mjs';
import { parseDepthConfig } from '../src/depth_model.mjs';
import { EYE_HEIGHT_MIN, EYE_HEIGHT_MAX, eyeHeightError } from '../src/pipeline/eye_height.mjs';

const $ = (id) => document.getElementById(id);
/** The built-in sample's folder: the package's dist/ (web/server.mjs maps build/web there in a checkout). */
const SAMPLE_DIR = new URL('../../dist/', import.meta.url).href;
const t0 = performance.now();
const ui = {
  video: $('video'), progress: $('progress'), stage: $('stage'), stages: $('stages'), message: $('message'),
  cancel: $('btn-cancel'), play: $('btn-play'), scrub: $('scrub'), frameLabel: $('frame-label'), summary: $('summary'),
  engine: $('engine'), modelsNote: $('models-note'), focalNote: $('focal-note'),
  stop: $('btn-stop'), camera: $('btn-camera'), device: $('opt-device'), liveStatus: $('live-status'),
};
/** The bounds of a live recording: every processed frame stays in the worker until Stop (the
 *  pipeline's per-frame arrays, the SLAM's grey frames and masks up to the worker's 64 MB, then
 *  each hand's mesh per frame: 33 kB a frame for both default hands, 100 MB at 3000 frames) and
 *  Stop refines all of it; the recording stops by itself at the first bound reached, saying
 *  which (3000 frames: 5 minutes at 10 processed frames per second). */
const LIVE_LIMITS = { maxSeconds: 300, maxFrames: 3000 };

const app = {
  worker: null, ready: null, backend: null, busy: false, run: null, result: null, meshes: null,
  mano: { left: null, right: null }, depth: { onnx: null, config: null, configName: null },
  sample: null, frame: 0, playing: false, base: 0, hasVideo: false, lastRun: null, readyMs: null, errors: [],
  live: null, liveLimits: { ...LIVE_LIMITS },
};
window.haworApp = app;
// The camera-height field's range is the pipeline's (eye_height.mjs), not a copy in the HTML.
$('opt-eyeheight').min = String(EYE_HEIGHT_MIN);
$('opt-eyeheight').max = String(EYE_HEIGHT_MAX);

const scene = new SceneView($('scene'));
const overlay = new VideoOverlay(ui.video, $('overlay-gl'), $('overlay-2d'));

// --- messages ------------------------------------------------------------------------------------

function showMessage(text, kind = 'error') {
  ui.message.hidden = false;
  ui.message.className = `message ${kind === 'info' ? 'info' : ''}`;
  ui.message.textContent = text;
  if (kind !== 'info') app.errors.push(text);
  ui.message.dataset.kind = kind;
}
function clearMessage() { ui.message.hidden = true; ui.message.textContent = ''; delete ui.message.dataset.kind; }

const STAGE_NAMES = { decode: 'decoding frames' };
const stageText = (stage, st) => `${STAGE_NAMES[stage] || stage} ${st.total ? `${st.done}/${st.total}` : ''} · ${((st.last - st.first) / 1000).toFixed(1)} s`;

/** A stage that is over: its full count (a frame count keeps the frames it reached), class 'done'. */
function completeStage(stage, st) {
  if (st.total) { if (st.done > 0) st.total = st.done; else st.done = st.total; }
  st.li.className = 'done';
  st.li.textContent = stageText(stage, st);
}

function setStage(stage, done, total) {
  ui.stage.textContent = total ? `${STAGE_NAMES[stage] || stage}: ${done}/${total}` : `${STAGE_NAMES[stage] || stage}…`;
  if (total) ui.progress.value = Math.min(1, done / total);
  const run = app.run;
  if (!run) return;
  // The pipeline's end: every stage is over.
  if (stage === 'done') { for (const [k, st] of run.stages) completeStage(k, st); return; }
  let st = run.stages.get(stage);
  const now = performance.now();
  if (!st) {
    // A new stage of the pipeline: the ones before it are over, except the page's decoding, which
    // runs beside the worker's per-frame stage until its last frame (a cancel ends nothing).
    if (stage !== 'cancelling') for (const [k, prev] of run.stages) if (k !== 'decode' || run.decoded !== undefined) completeStage(k, prev);
    st = { first: now, last: now, li: document.createElement('li') };
    run.stages.set(stage, st);
    ui.stages.appendChild(st.li);
  }
  st.last = now;
  st.done = done; st.total = total;
  if (total && done >= total) st.li.className = 'done';
  st.li.textContent = stageText(stage, st);
}

// --- the worker ----------------------------------------------------------------------------------

function startWorker() {
  app.worker = new Worker(new URL('./worker.mjs', import.meta.url), { type: 'module' });
  app.ready = new Promise((resolve, reject) => {
    app.worker.onmessage = (ev) => onWorker(ev.data, resolve);
    app.worker.onerror = (ev) => { ev.preventDefault(); const m = `The processing worker failed to start: ${ev.message || 'load error'}`; showMessage(m); reject(new Error(m)); };
  });
  // A worker has no import map: it gets the mapped URLs of what it loads from here.
  const hand = (side) => import.meta.resolve(`@webxr-input-profiles/assets/dist/profiles/generic-hand/${side}.glb`);
  app.worker.postMessage({ type: 'init', urls: { ort: import.meta.resolve('onnxruntime-web'), ortWebgpu: import.meta.resolve('onnxruntime-web/webgpu'), hands: { left: hand('left'), right: hand('right') } } });
  return app.ready;
}

/// Which backend runs the hand networks, and why (execution_provider.mjs measured it).
function showBackend(info) {
  const name = info.provider === 'webgpu' ? 'WebGPU' : 'WebAssembly';
  const note = $('backend-note');
  note.textContent = `networks on ${name}: ${info.why}`;
  note.dataset.provider = info.provider;
  app.backend = info;
}

function onWorker(m, resolveReady) {
  const run = app.run;
  switch (m.type) {
    case 'ready':
      app.readyMs = performance.now() - t0;
      ui.engine.textContent = `ready in ${(app.readyMs / 1000).toFixed(1)} s · cross-origin isolated: ${m.info.crossOriginIsolated ? 'yes' : 'no'} · ${m.info.cores} cores`;
      document.body.dataset.ready = '1';
      resolveReady(m.info);
      break;
    case 'credit': if (run) { run.credits++; if (run.wake) { run.wake(); run.wake = null; } if (run.onCredit) run.onCredit(); } break;
    case 'progress': setStage(m.stage, m.done, m.total); break;
    case 'frame-info': break;
    case 'backend': showBackend(m.info); break;
    case 'live-start': if (run && run.live) scene.startLive(m.intrinsics, run.meta.width, run.meta.height); break;
    case 'live-frame': onLiveFrame(m.info); break;
    case 'result': onResult(m.result, m.meshes); break;
    case 'cancelled':
      if (run && run.cancelled) {
        finishRun();
        if (run.cancelMessage) showMessage(run.cancelMessage.text, run.cancelMessage.kind);
        else showMessage('Cancelled. Pick the next clip whenever you like.', 'info');
      }
      break;
    case 'error':
      if (run) finishRun();
      showMessage(errorText(m.kind, m.message));
      break;
    case 'exported': onExported(m); break;
    case 'stats': if (app.statsWaiter) { app.statsWaiter(m.stats); app.statsWaiter = null; } break;
    default: break;
  }
}

function errorText(kind, message) {
  const prefix = { mano: 'Wrong MANO file', short: 'Clip too short', nohands: 'No hands found', video: 'Unsupported or corrupt video',
    resolution: 'Resolution too large', setup: 'Setup problem', result: 'Not a result file', depth: 'Depth model problem',
    'eye-height': 'Wrong camera height', camera: 'Wrong camera model', readout: 'Wrong rolling-shutter readout',
    'webcam-denied': 'Camera permission denied', 'webcam-none': 'No camera', 'webcam-busy': 'Camera busy', webcam: 'Camera problem' }[kind];
  return prefix ? `${prefix}: ${message}` : message;
}

// --- processing a clip ---------------------------------------------------------------------------

function setBusy(b) {
  app.busy = b;
  ui.cancel.disabled = !b;
  for (const el of document.querySelectorAll('#input input, #input select, #btn-sample, #btn-camera')) el.disabled = b;
  if (!b) ui.stop.disabled = true;
  document.body.dataset.busy = b ? '1' : '0';
}

/** A run that failed while starting: when it is still the current run, the worker cancels it and
 *  the error is shown (an InputError's kind, else `kind`); false when another run replaced it. */
function failRun(run, e, kind) {
  if (app.run !== run) return false;
  if (run.started) app.worker.postMessage({ type: 'cancel' });
  finishRun();
  showMessage(errorText(e instanceof InputError ? e.kind : kind, e.message));
  return true;
}

function finishRun() {
  if (app.run) {
    app.run.finished = true; if (app.run.wake) app.run.wake(); clearTimeout(app.run.killTimer);
    if (app.run.live) endCapture(app.run.live);
    ui.stage.textContent = 'stopped'; ui.progress.value = 0;
  }
  app.run = null;
  setBusy(false);
}

function number(id) { const v = Number($(id).value); return $(id).value !== '' && Number.isFinite(v) && v > 0 ? v : null; }

/// The pipeline's options from the form, for frames of `size` (processingSize: the focal given in
/// pixels of the original is scaled with it) at `fps`: the focal or field of view (else the
/// sample's own focal, else the pipeline's default), the lens, the rolling-shutter readout, the
/// camera height, the user's MANO and depth files. Throws an InputError for a wrong value.
function formOptions(size, fps, sampleMeta = null) {
  const options = { modelKind: $('opt-model').value, backend: $('opt-backend').value };
  const focal = number('opt-focal'), fov = number('opt-fov');
  if (focal) options.focalPx = focal * size.scale;
  else if (fov) options.fovDeg = fov;
  else if (sampleMeta && sampleMeta.fx) options.focalPx = sampleMeta.fx * (size.width / sampleMeta.width);
  const camera = $('opt-camera').value.trim();
  if (camera) options.camera = camera;  // checked by the core in the worker (Lens::parse, CameraModel::validate)
  const readoutMs = number('opt-readout');
  if (readoutMs) {
    if (!(Math.abs(readoutMs) <= 1000 / fps)) throw new InputError('readout', `${readoutMs} ms is not within the frame interval (±${(1000 / fps).toFixed(1)} ms at ${fps} fps).`);
    options.readout = readoutMs / 1000;
  }
  const eye = number('opt-eyeheight');
  if (eye) {
    const bad = eyeHeightError(eye);
    if (bad) throw new InputError('eye-height', `${bad[0].toUpperCase()}${bad.slice(1)}.`);
    options.eyeHeight = eye;
  }
  for (const side of ['left', 'right']) if (app.mano[side]) (options.mano ||= {})[side] = { name: app.mano[side].name, bytes: app.mano[side].bytes.slice() };
  if (app.depth.onnx) {
    if (!app.depth.config) throw new InputError('depth', 'A depth ONNX was given without its JSON config (drop both files).');
    options.depth = { bytes: app.depth.onnx.bytes.slice(), config: app.depth.config };
  }
  return options;
}

/// The focal note's words on the options of a run.
function optionsNote(options) {
  return (options.focalPx ? `, focal ${options.focalPx.toFixed(1)} px at that size` : options.fovDeg ? `, field of view ${options.fovDeg}°` : ', focal: the pipeline\'s default')
    + (options.camera ? `, camera model ${options.camera}` : '')
    + (options.readout ? `, rolling shutter ${1000 * options.readout} ms` : '');
}

async function processVideo(url, name, sampleMeta = null) {
  if (app.busy) return;
  clearMessage();
  resetViews();
  setBusy(true);
  ui.stages.textContent = '';
  const run = { name, credits: 4, wake: null, finished: false, stages: new Map(), tStart: performance.now() };
  app.run = run;
  try {
    await app.ready;
    setStage('opening video');
    const meta = await openVideo(ui.video, url, name);
    const est = await estimateFps(ui.video);
    if (!est.fps) throw new InputError('short', `"${name}" is too short: ${est.presented} frame(s) decoded, at least ${LIMITS.minFrames} are needed.`);
    const fps = sampleMeta ? sampleMeta.fps : est.fps;
    let frameCount = Math.round(meta.duration * fps);
    const maxFrames = number('opt-maxframes');
    if (maxFrames) frameCount = Math.min(frameCount, Math.floor(maxFrames));
    if (frameCount < LIMITS.minFrames) throw new InputError('short', `"${name}" has ${frameCount} frame(s) at ${fps} fps; at least ${LIMITS.minFrames} are needed.`);
    const size = processingSize(meta.width, meta.height, number('opt-maxside') || 960);
    app.base = est.base;
    app.hasVideo = true;
    const options = formOptions(size, fps, sampleMeta);
    run.meta = { width: size.width, height: size.height, fps, frameCount, original: meta };
    ui.focalNote.textContent = `${meta.width}×${meta.height} at ${fps} fps, ${frameCount} frames; processed at ${size.width}×${size.height}${optionsNote(options)}`;
    app.worker.postMessage({ type: 'start', meta: { width: size.width, height: size.height, fps, frameCount }, options });
    run.started = true;
    const wait = () => new Promise((resolve) => {
      if (run.finished || run.credits > 0) return resolve();
      run.wake = resolve;
    });
    const tDecode = performance.now();
    let n = 0;
    for await (const f of videoFrames(ui.video, { fps, base: est.base, width: size.width, height: size.height, maxFrames: frameCount, wait })) {
      if (run.finished) break;
      run.credits--;
      app.worker.postMessage({ type: 'frame', index: f.index, rgba: f.rgba.buffer }, [f.rgba.buffer]);
      n++;
      setStage('decode', n, frameCount);
    }
    run.decodeMs = performance.now() - tDecode;
    run.decoded = n;
    if (!run.finished) {
      if (n < LIMITS.minFrames) {
        app.worker.postMessage({ type: 'cancel' });
        throw new InputError('short', `only ${n} frame(s) of "${name}" could be decoded; at least ${LIMITS.minFrames} are needed.`);
      }
      app.worker.postMessage({ type: 'end' });
    }
  } catch (e) {
    failRun(run, e, 'video');
  }
}

// --- live: the camera ----------------------------------------------------------------------------
// The camera's frames go to the worker one at a time, each when the pipeline asks for one (the
// worker's 'credit'; camera_source.mjs drops the others, counted). The worker runs the pipeline in
// live mode (run.mjs, options.live) and answers each frame with its causal estimates, drawn here;
// Stop ends the stream and the pipeline's refined result replaces them.

function newLive() {
  return {
    stream: null, frames: null, size: null, camera: null, timer: null, stopping: false, stopReason: null,
    processed: 0, capture: new Map(), latencies: [], pipelineMs: [], drawMs: [], tFirst: null, tLast: null, recent: [],
    scaleMethod: 'none', scale: null, scaleConfidence: null, up: 'none', cameraPoses: 0, handsSeen: 0, seen: { left: 0, right: 0 },
  };
}

async function startLive() {
  if (app.busy) return;
  clearMessage();
  resetViews();
  setBusy(true);
  ui.stages.textContent = '';
  const live = newLive();
  const run = { name: 'camera', live, credits: 0, wake: null, finished: false, stages: new Map(), tStart: performance.now() };
  app.run = run;
  app.live = live;
  try {
    await app.ready;
    setStage('opening the camera');
    const { stream, track } = await openCamera(ui.device.value);
    live.stream = stream;
    if (run.finished) { endCapture(live); return; }  // cancelled while the browser asked
    listCameras(ui.device);
    track.addEventListener('ended', () => stopLive('the camera stopped sending frames (unplugged, or taken by another application)'));
    app.hasVideo = false;
    const cam = await playCamera(ui.video, stream, track);
    if (live.stopping || run.finished) throw new InputError('webcam', live.stopReason || 'stopped before the first frame.');
    if (!(cam.width > 0 && cam.height > 0)) throw new InputError('webcam', 'the camera gave no picture size.');
    const fps = cam.fps || 30;
    const size = processingSize(cam.width, cam.height, number('opt-maxside') || 960);
    const options = formOptions(size, fps);
    live.size = size;
    live.camera = { ...cam, fps };
    run.meta = { width: size.width, height: size.height, fps, frameCount: null, original: { width: cam.width, height: cam.height }, live: true };
    ui.focalNote.textContent = `camera${cam.label ? ` "${cam.label}"` : ''} ${cam.width}×${cam.height} at ${fps} fps; processed at ${size.width}×${size.height}${optionsNote(options)}`;
    app.worker.postMessage({ type: 'start', meta: { width: size.width, height: size.height, fps, frameCount: null, live: true }, options });
    run.started = true;
    ui.stop.disabled = false;
    ui.liveStatus.hidden = false;
    ui.liveStatus.textContent = 'live: loading the networks…';
    ui.stage.textContent = 'loading the networks…';
    live.frames = new CameraFrames(ui.video, size.width, size.height, (f) => handOver(run, f));
    run.onCredit = () => live.frames.ask();
  } catch (e) {
    if (!failRun(run, e, 'webcam')) endCapture(live);
  }
}

/// A camera frame to the worker (the pipeline asked for it); the bounds of the recording.
function handOver(run, f) {
  const live = run.live, lim = app.liveLimits;
  if (f.index === 0) {
    const min = lim.maxSeconds / 60;
    live.timer = setTimeout(() => stopLive(`the recording reached its bound of ${Number.isInteger(min) ? `${min} minute${min === 1 ? '' : 's'}` : `${lim.maxSeconds} s`}`), 1000 * lim.maxSeconds);
  }
  live.capture.set(f.index, f.time);
  run.credits--;
  // the capture time in seconds (the pipeline's timeline: frames are dropped), strictly increasing
  const time = Math.max(f.time / 1000, (live.lastTime ?? -Infinity) + 1e-6);
  live.lastTime = time;
  app.worker.postMessage({ type: 'frame', index: f.index, rgba: f.rgba.buffer, time }, [f.rgba.buffer]);
  if (f.index + 1 >= lim.maxFrames) stopLive(`the recording reached its bound of ${lim.maxFrames} processed frames`);
}

/// Stops the camera (the frames already handed over are still processed).
function endCapture(live) {
  clearTimeout(live.timer);
  if (live.frames) live.frames.stop();
  closeCamera(ui.video, live.stream);
  live.stream = null;
}

/// Ends the recording (Stop, a bound, the camera gone): the worker refines what was processed.
function stopLive(reason = null) {
  const run = app.run, live = run && run.live;
  if (!live || live.stopping || run.finished) return;
  live.stopping = true;
  live.stopReason = reason;
  endCapture(live);
  ui.stop.disabled = true;
  if (!run.started) return;
  const sent = live.frames ? live.frames.sent : 0;
  if (sent < LIMITS.minFrames) {
    run.cancelled = true;
    run.cancelMessage = { kind: 'error', text: errorText('short', `${reason ? `${reason[0].toUpperCase()}${reason.slice(1)}; only` : 'Only'} ${sent} camera frame(s) were processed; at least ${LIMITS.minFrames} are needed.`) };
    app.worker.postMessage({ type: 'cancel' });
    return;
  }
  app.worker.postMessage({ type: 'end' });
  if (reason) showMessage(`Stopped: ${reason}. The refined result of the ${sent} processed frames follows.`, 'info');
  ui.liveStatus.textContent = liveStatusText(live);
}

/// One processed frame's live estimates (worker.mjs's liveInfo): drawn, and counted.
function onLiveFrame(info) {
  const run = app.run, live = run && run.live;
  if (!live || !live.size) return;
  live.processed++;
  const tDraw = performance.now();
  overlay.drawLive({ width: live.size.width, height: live.size.height, hands: info.hands });
  const w = info.world, l = info.live;
  if (w) {
    const prev = w.previous && l && w.previous.frame === l.frame ? w.previous : null;
    scene.liveWorld(w.up === 'none' ? 'first-camera' : 'z-up', w.origin, prev, l);
    Object.assign(live, { scaleMethod: w.scaleMethod, scale: w.scale, scaleConfidence: w.scaleConfidence, up: w.up });
  }
  scene.liveFrame(l);
  const t = performance.now();
  live.drawMs.push(t - tDraw);
  const tc = live.capture.get(info.index);
  live.capture.delete(info.index);
  if (tc !== undefined) live.latencies.push(t - tc);
  if (Number.isFinite(info.ms)) live.pipelineMs.push(info.ms);
  if (live.tFirst === null) live.tFirst = t;
  live.tLast = t;
  live.recent.push(t);
  while (live.recent.length && live.recent[0] < t - 2000) live.recent.shift();
  if (l && l.posed) live.cameraPoses++;
  if (info.hands.length) live.handsSeen++;
  for (const h of info.hands) live.seen[h.side]++;
  ui.liveStatus.textContent = liveStatusText(live);
}

function percentile(values, q) {
  if (!values.length) return null;
  const s = Float64Array.from(values).sort();
  return s[Math.max(0, Math.ceil(q * s.length) - 1)];
}

/// The live statistics (window.haworApp.liveStats()); null before the first live run.
function liveStats(l = app.live) {
  if (!l) return null;
  const fr = l.frames;
  const span = l.recent.length > 1 ? (l.recent[l.recent.length - 1] - l.recent[0]) / 1000 : 0;
  return {
    running: !!(app.run && app.run.live === l && !l.stopping), stopReason: l.stopReason,
    framesCaptured: fr ? fr.captured : 0, framesSent: fr ? fr.sent : 0, framesProcessed: l.processed, dropped: fr ? fr.dropped : 0,
    fps: l.processed > 1 ? (l.processed - 1) / ((l.tLast - l.tFirst) / 1000) : null,
    fpsRecent: span > 0 ? (l.recent.length - 1) / span : null,
    latencyMsP50: percentile(l.latencies, 0.5), latencyMsP95: percentile(l.latencies, 0.95), latencyClock: fr ? fr.clock : null,
    pipelineMsP50: percentile(l.pipelineMs, 0.5), pipelineMsP95: percentile(l.pipelineMs, 0.95),
    drawMsP50: percentile(l.drawMs, 0.5), drawMsP95: percentile(l.drawMs, 0.95),
    scaleMethod: l.scaleMethod, scale: l.scale, scaleConfidence: l.scaleConfidence, up: l.up,
    cameraPoses: l.cameraPoses, handsSeen: l.handsSeen, handsSeenBySide: { ...l.seen },
    size: l.size && { width: l.size.width, height: l.size.height }, camera: l.camera,
  };
}

function liveStatusText(l) {
  const s = liveStats(l);
  const ms = (x) => (x === null ? '–' : `${Math.round(x)} ms`);
  const fps = s.fpsRecent ?? s.fps;
  const scale = s.scaleMethod && s.scaleMethod !== 'none'
    ? `scale ${Number(s.scale).toFixed(3)} (${s.scaleMethod}, confidence ${Number(s.scaleConfidence).toFixed(2)})` : 'scale pending';
  return `${s.running ? 'live' : 'stopped'} · ${s.framesProcessed} frames processed · ${fps !== null ? fps.toFixed(1) : '–'} fps`
    + ` · ${s.dropped} dropped · latency ${ms(s.latencyMsP50)} (p95 ${ms(s.latencyMsP95)}) · ${scale}`
    + ` · camera posed on ${s.cameraPoses} · hands on ${s.handsSeen}${l.stopping && !app.result ? ' · refining…' : ''}`;
}

function cancelRun() {
  const run = app.run;
  if (!run) return;
  run.finished = true;
  run.cancelled = true;
  if (run.wake) run.wake();
  if (run.live) endCapture(run.live);
  setStage('cancelling');
  if (!run.started) { finishRun(); showMessage('Cancelled.', 'info'); return; }
  app.worker.postMessage({ type: 'cancel' });
  // A worker stuck inside a long call is replaced.
  run.killTimer = setTimeout(() => {
    if (app.run !== run) return;
    app.worker.terminate();
    finishRun();
    showMessage('Cancelled (the worker was restarted).', 'info');
    startWorker();
  }, 3000);
}

function onResult(result, meshes) {
  const run = app.run;
  app.result = result;
  app.meshes = meshes;
  if (run && run.live) run.decoded = run.live.frames ? run.live.frames.sent : 0;
  if (run) {
    app.lastRun = { name: run.name, totalMs: performance.now() - run.tStart, decodeMs: run.decodeMs, decoded: run.decoded, meta: run.meta,
      stages: Object.fromEntries([...run.stages].map(([k, s]) => [k, { ms: s.last - s.first, done: s.done, total: s.total }])),
      timings: result.timings || {}, ...(run.live ? { live: liveStats(run.live) } : {}) };
    finishRun();
    if (run.live) ui.liveStatus.textContent = `${liveStatusText(run.live)} · the refined result below replaced the live estimates`;
  }
  ui.progress.value = 1;
  ui.stage.textContent = 'done';
  scene.setResult(result, meshes);
  overlay.setResult(result, meshes, scene);
  ui.scrub.max = String(result.frameCount - 1);
  ui.scrub.disabled = false;
  ui.play.disabled = false;
  for (const b of document.querySelectorAll('[data-export]')) b.disabled = false;
  setFrame(0);
  const sum = scene.summary();
  const h = (s) => (sum.hands[s] ? `${sum.hands[s].frames} frames (${countFlags(result, s, 'infilled')} infilled)` : 'none');
  ui.summary.textContent = [
    `${result.frameCount} frames, ${result.width}×${result.height}, ${result.fps} fps; focal ${result.intrinsics.fx.toFixed(1)} px (${result.intrinsics.focalSource || '?'})${result.intrinsics.lens && result.intrinsics.lens !== 'pinhole' ? `, camera model ${result.intrinsics.lens}` : ''}`,
    `left hand: ${h('left')} · right hand: ${h('right')} · camera path: ${sum.cameraPath} poses · SLAM points: ${sum.points}`,
    `metric scale: ${result.scale ? `${Number(result.scale.scale).toFixed(3)} (${result.scale.method}, confidence ${Number(result.scale.confidence).toFixed(2)})` : '–'}${groundText(result.scale && result.scale.ground)}`,
    result.timings ? `timings: ${Object.entries(result.timings).map(([k, v]) => `${k} ${(v / 1000).toFixed(1)} s`).join(' · ')}` : '',
    ...(result.warnings || []).map((w) => `warning: ${w}`),
  ].filter(Boolean).join('\n');
  if (result.noHands) showMessage(errorText('nohands', 'no hand was detected in any frame of this clip; the camera path is shown, the hands are empty.'));
}

/** The ground cue in words (result.scale.ground, see web/src/pipeline/run.mjs). */
function groundText(g) {
  if (!g) return '';
  if (!g.ok) return ` · floor: ${g.reason}`;
  return ` · floor cue ${g.ambiguous ? '(one level: floor or table top)' : g.surfaceHeight ? `(a surface ${g.surfaceHeight.toFixed(2)} m above it)` : ''}, camera ${g.eyeHeight} m above the floor`;
}

function countFlags(result, side, key) {
  const a = result.hands && result.hands[side] && result.hands[side][key];
  if (!a) return 0;
  let n = 0; for (let i = 0; i < a.length; i++) n += Number(a[i]) ? 1 : 0;
  return n;
}

// --- views and timeline --------------------------------------------------------------------------

function resetViews() {
  pause();
  app.result = null; app.meshes = null;
  scene.clear(); overlay.clear();
  ui.scrub.disabled = true; ui.play.disabled = true; ui.scrub.value = '0'; ui.frameLabel.textContent = '–';
  for (const b of document.querySelectorAll('[data-export]')) b.disabled = true;
  ui.summary.textContent = '';
  ui.progress.value = 0;
  ui.liveStatus.hidden = true;
  ui.liveStatus.textContent = '';
}

function show() { return { kp: $('show-kp').checked, mesh: $('show-mesh').checked, mask: $('show-mask').checked }; }

function setFrame(t, seekVideo = true) {
  if (!app.result) return;
  t = Math.max(0, Math.min(app.result.frameCount - 1, t | 0));
  app.frame = t;
  ui.scrub.value = String(t);
  const inf = ['left', 'right'].filter((s) => app.meshes[s] && app.meshes[s].infilled[t]);
  ui.frameLabel.textContent = `frame ${t + 1}/${app.result.frameCount}${inf.length ? ` · infilled: ${inf.join(', ')}` : ''}`;
  scene.setFrame(t);
  overlay.draw(t, show());
  if (seekVideo && app.hasVideo && ui.video.readyState >= 1) ui.video.currentTime = app.base + (t + 0.25) / app.result.fps;
}

function play() {
  if (!app.result || app.playing) return;
  app.playing = true;
  ui.play.textContent = 'Pause';
  if (app.frame >= app.result.frameCount - 1) setFrame(0);
  const fps = app.result.fps;
  if (app.hasVideo) {
    const step = (now, md) => {
      if (!app.playing) return;
      setFrame(Math.round((md.mediaTime - app.base) * fps), false);
      ui.video.requestVideoFrameCallback(step);
    };
    ui.video.requestVideoFrameCallback(step);
    ui.video.onended = () => pause();
    ui.video.play().catch(() => pause());
  } else {
    let last = performance.now(), acc = 0;
    const tick = (now) => {
      if (!app.playing) return;
      acc += (now - last) * fps / 1000; last = now;
      if (acc >= 1) { const n = Math.floor(acc); acc -= n; if (app.frame + n >= app.result.frameCount) return pause(); setFrame(app.frame + n, false); }
      requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  }
}
function pause() {
  if (!app.playing) return;
  app.playing = false;
  ui.play.textContent = 'Play';
  if (app.hasVideo) ui.video.pause();
}

ui.play.onclick = () => (app.playing ? pause() : play());
ui.scrub.oninput = () => { pause(); setFrame(Number(ui.scrub.value)); };
for (const id of ['show-kp', 'show-mesh', 'show-mask']) $(id).onchange = () => overlay.draw(app.frame, show());

// --- exports -------------------------------------------------------------------------------------

const exportWaiters = new Map();
function onExported(m) {
  const blob = new Blob([m.data], { type: m.mime });
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = m.filename;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 60000);
  const w = exportWaiters.get(m.format);
  if (w) { exportWaiters.delete(m.format); w(m.filename); }
}
for (const b of document.querySelectorAll('[data-export]')) {
  b.onclick = () => { clearMessage(); app.worker.postMessage({ type: 'export', format: b.dataset.export }); };
}

// --- inputs --------------------------------------------------------------------------------------

function modelsNote() {
  const hands = app.mano.left || app.mano.right
    ? `MANO ${['left', 'right'].map((s) => `${s}: ${app.mano[s] ? app.mano[s].name : 'default hand'}`).join(', ')}`
    : 'the default (licence-free) hand';
  const depth = app.depth.onnx ? `${app.depth.onnx.name}${app.depth.config ? ` + ${app.depth.configName}` : ' (config missing)'}` : 'none (scale from the hands)';
  ui.modelsNote.textContent = `hands: ${hands} · depth: ${depth}`;
}

async function readFile(file) { return new Uint8Array(await file.arrayBuffer()); }

async function addManoFile(file, side) {
  const n = file.name.toLowerCase();
  const named = /left/.test(n) ? 'left' : /right/.test(n) ? 'right' : null;
  side = side || named;
  if (!side) throw new InputError('mano', `"${file.name}": cannot tell the side; name it MANO_LEFT / MANO_RIGHT or use the "MANO left/right" buttons.`);
  if (named && named !== side) throw new InputError('mano', `"${file.name}" looks like the ${named} hand but was given as the ${side} one.`);
  if (!/\.(pkl|npz)$/.test(n)) throw new InputError('mano', `"${file.name}" is not a .pkl or .npz file.`);
  app.mano[side] = { name: file.name, bytes: await readFile(file) };
  modelsNote();
}

async function addDepthFile(file) {
  if (/\.json$/i.test(file.name)) {
    const text = await file.text();
    try { parseDepthConfig(text); } catch (e) { throw new InputError('depth', `"${file.name}": ${e.message}`); }
    app.depth.config = text; app.depth.configName = file.name;
  } else {
    app.depth.onnx = { name: file.name, bytes: await readFile(file) };
  }
  modelsNote();
}

async function handleFiles(files, hint = null) {
  clearMessage();
  let video = null;
  try {
    for (const f of files) {
      const n = f.name.toLowerCase();
      if (hint === 'mano-left' || hint === 'mano-right') await addManoFile(f, hint.slice(5));
      else if (/\.(pkl|npz)$/.test(n)) await addManoFile(f, null);
      else if (/\.onnx$/.test(n) || (/\.json$/.test(n) && hint === 'depth')) await addDepthFile(f);
      else if (/\.json$/.test(n)) await loadResultFile(f);
      else video = f;
    }
  } catch (e) {
    showMessage(errorText(e.kind, e.message));
    return;
  }
  if (video) {
    if (app.videoUrl) URL.revokeObjectURL(app.videoUrl);
    app.videoUrl = URL.createObjectURL(video);
    await processVideo(app.videoUrl, video.name);
  }
}

async function loadResultFile(file) {
  resetViews();
  app.hasVideo = false;
  ui.video.removeAttribute('src'); ui.video.load();
  const options = {};
  for (const side of ['left', 'right']) if (app.mano[side]) (options.mano ||= {})[side] = { name: app.mano[side].name, bytes: app.mano[side].bytes.slice() };
  app.worker.postMessage({ type: 'load-result', text: await file.text(), options });
}

$('file-video').onchange = (e) => { const f = [...e.target.files]; e.target.value = ''; handleFiles(f); };
$('file-result').onchange = (e) => { const f = [...e.target.files]; e.target.value = ''; handleFiles(f); };
$('file-mano-left').onchange = (e) => { const f = [...e.target.files]; e.target.value = ''; handleFiles(f, 'mano-left'); };
$('file-mano-right').onchange = (e) => { const f = [...e.target.files]; e.target.value = ''; handleFiles(f, 'mano-right'); };
$('file-depth').onchange = (e) => { const f = [...e.target.files]; e.target.value = ''; handleFiles(f, 'depth'); };
$('btn-clear-models').onclick = () => { app.mano = { left: null, right: null }; app.depth = { onnx: null, config: null, configName: null }; modelsNote(); };
$('btn-sample').onclick = async () => {
  try {
    if (!app.sample) {
      const r = await fetch(SAMPLE_DIR + 'sample.json');
      if (!r.ok) throw new InputError('setup', 'the synthetic sample is not built (run scripts/build_web.sh).');
      app.sample = await r.json();
    }
    await processVideo(SAMPLE_DIR + app.sample.video, 'synthetic sample', app.sample);
  } catch (e) { showMessage(errorText(e.kind || 'setup', e.message)); }
};
ui.cancel.onclick = cancelRun;
ui.camera.onclick = startLive;
ui.stop.onclick = () => stopLive();
listCameras(ui.device);
if (navigator.mediaDevices && navigator.mediaDevices.addEventListener) navigator.mediaDevices.addEventListener('devicechange', () => listCameras(ui.device));
const drop = $('drop');
for (const ev of ['dragenter', 'dragover']) drop.addEventListener(ev, (e) => { e.preventDefault(); drop.classList.add('over'); });
for (const ev of ['dragleave', 'drop']) drop.addEventListener(ev, (e) => { e.preventDefault(); drop.classList.remove('over'); });
drop.addEventListener('drop', (e) => handleFiles([...e.dataTransfer.files]));
window.addEventListener('dragover', (e) => e.preventDefault());
window.addEventListener('drop', (e) => e.preventDefault());

app.view = { scene, overlay, setFrame, play, pause };
app.sceneSummary = () => scene.summary();
/// Live mode's statistics: { running, framesCaptured (camera frames since the first one handed
/// over), framesSent, framesProcessed, dropped, fps, fpsRecent (last 2 s), latencyMsP50,
/// latencyMsP95 (capture to the overlay drawn), pipelineMsP50 / P95 (the worker's time on a
/// frame), drawMsP50 / P95 (the page's, drawing it: overlay and 3D view), latencyClock, scaleMethod, scale, scaleConfidence,
/// up, cameraPoses (frames the SLAM posed), handsSeen (frames with a hand), handsSeenBySide, size,
/// camera, stopReason }; null before the first live run.
app.liveStats = () => liveStats();
app.stopLive = () => stopLive();
/// Memory of the worker's WebAssembly core and JavaScript heap, and of the page's heap.
app.stats = () => new Promise((resolve) => {
  app.statsWaiter = (w) => resolve({ ...w, pageJsHeapBytes: performance.memory ? performance.memory.usedJSHeapSize : null });
  app.worker.postMessage({ type: 'stats' });
});
app.exportFile = (format) => new Promise((resolve) => { exportWaiters.set(format, resolve); app.worker.postMessage({ type: 'export', format }); });
startWorker().catch(() => {});
