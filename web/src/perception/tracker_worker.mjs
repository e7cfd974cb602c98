// tracker_worker.mjs: the worker thread of worker_tracker.mjs. Loads the networks' runtime and a
// HandTracker with the options it is given, says { ready } (or { error }), then answers each
// { image, predictions } with { hands, stats } (or { error }), one frame at a time.
import { parentPort, workerData } from 'node:worker_threads';

import { HandTracker } from './hand_tracker.mjs';
import { loadOrt } from '../ort_runtime.mjs';

async function start() {
  const { runtime, sessionOptions, threads, palm, landmark, trackerOptions, lens, corePath } = workerData;
  // the runtime the main thread chose (its session options come with it)
  const { ort } = await loadOrt(runtime, threads ?? 2);
  let lensCrops = null;
  if (lens) {
    // perspective landmark crops through the lens, as runPipeline makes them on its own thread
    const { loadCore } = await import('../core.mjs');
    const core = await loadCore(corePath ? { path: corePath } : {});
    const camera = new core.LensCamera(lens.intrinsics, lens.width, lens.height, lens.lens);
    lensCrops = { cropMap: (roi, n) => camera.cropMap(roi, n, n), cropToImage: (roi, uv) => camera.cropToImage(roi, uv) };
  }
  return HandTracker.create(ort, palm, landmark, { ...trackerOptions, lens: lensCrops, sessionOptions });
}

start().then((tracker) => {
  let queue = Promise.resolve();
  parentPort.on('message', (m) => {
    queue = queue.then(async () => {
      try {
        const hands = await tracker.track(m.image, m.predictions);
        parentPort.postMessage({ hands, stats: { ...tracker.stats } });
      } catch (e) {
        parentPort.postMessage({ error: e.message });
      }
    });
  });
  parentPort.postMessage({ ready: true });
}, (e) => parentPort.postMessage({ error: e.message }));
