// worker_tracker.mjs (node only): the hand tracker (hand_tracker.mjs) in a worker thread, so that
// the networks of frame t+1 run while the main thread does the geometry of frame t (runPipeline's
// options.trackerFactory). onnxruntime-node runs a network on its calling thread, so on one
// thread perception (~15 ms a frame at 960 px) and the masks and SLAM (~12 ms) add up; on two
// they overlap. The worker holds the tracker's whole state; one frame is in flight at a time.
//
//   import { workerTrackerFactory } from './perception/worker_tracker.mjs';
//   runPipeline(source, { ..., trackerFactory: workerTrackerFactory({ runtime: 'native',
//     sessionOptions, palm: Uint8Array, landmark: Uint8Array, corePath? }) });
import { Worker } from 'node:worker_threads';

const SCRIPT = new URL('./tracker_worker.mjs', import.meta.url);

/** A HandTracker stand-in whose track() runs in the worker: { track, stats, close }. */
class WorkerTracker {
  constructor(worker) {
    this.worker = worker;
    this.stats = { palmRuns: 0, landmarkRuns: 0, flowHands: 0, candidatesVerified: 0, candidatesKept: 0 };
    this.waiting = null; // { resolve, reject } of the frame in flight
    this.failure = null;
    this.closed = false;
    const fail = (e) => {
      this.failure = e;
      if (this.waiting) this.waiting.reject(e);
      this.waiting = null;
    };
    worker.on('message', (m) => {
      const w = this.waiting;
      this.waiting = null;
      if (!w) return;
      if (m.error) { w.reject(new Error(m.error)); return; }
      this.stats = m.stats;
      w.resolve(m.hands);
    });
    worker.on('error', fail);
    worker.on('exit', (code) => { if (!this.closed) fail(new Error(`the perception worker exited (code ${code})`)); });
  }

  /** HandTracker.track(image, predictions), in the worker (the frame's pixels are copied). */
  track(image, predictions = null) {
    if (this.failure) return Promise.reject(this.failure);
    if (this.waiting) return Promise.reject(new Error('WorkerTracker: one frame at a time'));
    return new Promise((resolve, reject) => {
      this.waiting = { resolve, reject };
      this.worker.postMessage({ image: { width: image.width, height: image.height, channels: image.channels, data: image.data }, predictions });
    });
  }

  close() {
    this.closed = true;
    return this.worker.terminate();
  }
}

/**
 * runPipeline's trackerFactory: a HandTracker with the pipeline's options in a worker thread.
 * config { runtime: 'native' | 'wasm' (onnxruntime-node or -web), sessionOptions, threads,
 * palm, landmark (ONNX bytes), corePath? (hawor_core.mjs, for a lens's crops) }.
 */
export function workerTrackerFactory(config) {
  return (trackerOptions, lens) => new Promise((resolve, reject) => {
    const worker = new Worker(SCRIPT, { workerData: { ...config, trackerOptions, lens } });
    const early = (e) => reject(new Error(`the perception worker failed to start: ${e.message}`));
    worker.once('error', early);
    worker.once('message', (m) => {
      worker.off('error', early);
      if (m.error) { worker.terminate(); reject(new Error(`the perception worker failed to start: ${m.error}`)); return; }
      resolve(new WorkerTracker(worker));
    });
  });
}
