// Live mode of the browser app (the Camera button) in headless Chromium with its fake camera
// (--use-fake-device-for-media-stream, fed with the synthetic sample converted to y4m by ffmpeg;
// the fake device loops it): the camera errors (permission denied, device busy, a camera that is
// not there) as messages with the page usable after them; frames flowing to the worker with the
// drop policy, hands and camera poses appearing live (window.haworApp.liveStats()), Stop giving
// the refined result in the result view with the exports enabled; a recording that stops by itself
// at its frame bound, saying why; Stop before 8 frames, Cancel, a camera unplugged while
// recording, a file processed after the camera; and a console free of errors. Prints the processed fps, the
// dropped frames and the capture-to-overlay latency (not asserted: a shared machine). About 40 s.
//
//   bash scripts/build_web.sh && node --test tests/browser/live.test.mjs
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync, mkdirSync, mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve, dirname } from 'node:path';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { createServer } from '../../web/server.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const out = join(root, 'build/browser-test/live');
const CHROMIUM = process.env.HAWOR_CHROMIUM || '/usr/bin/chromium';
const SAMPLE = join(root, 'build/web/sample.webm');
const FLAGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync'];
/** Camera frames to process before Stop (the sample is 60 frames: the fake camera loops it). */
const LIVE_FRAMES = Number(process.env.HAWOR_LIVE_FRAMES || 45);

const needed = ['build/wasm/wasm/hawor_core.mjs', 'build/wasm/wasm/hawor_core.wasm', 'build/web/sample.webm',
  'node_modules/@webxr-input-profiles/assets/dist/profiles/generic-hand/left.glb', 'web/models/palm_detection_lite.onnx',
  'web/models/hand_landmark_lite.onnx'];
const missing = needed.filter((f) => !existsSync(join(root, f)));
const noChromium = !existsSync(CHROMIUM);
const noFfmpeg = spawnSync('ffmpeg', ['-version']).status !== 0;
const skip = noChromium ? `${CHROMIUM} not found` : noFfmpeg ? 'ffmpeg not found' : missing.length ? `missing build outputs (run scripts/build_web.sh): ${missing.join(', ')}` : false;
if (skip) console.log(`# SKIP live-camera browser tests: ${skip}`);

let server, url, context, page, dataDir;
const consoleErrors = [];
const report = {};

before(async () => {
  if (skip) return;
  mkdirSync(out, { recursive: true });
  const y4m = join(out, 'sample.y4m');
  const r = spawnSync('ffmpeg', ['-v', 'error', '-y', '-i', SAMPLE, '-pix_fmt', 'yuv420p', '-r', '30', y4m], { encoding: 'utf8' });
  assert.equal(r.status, 0, `ffmpeg: ${r.stderr}`);
  server = createServer(root);
  await new Promise((res) => server.listen(0, '127.0.0.1', res));
  url = `http://127.0.0.1:${server.address().port}/`;
  const { chromium } = await import('playwright-core');
  dataDir = mkdtempSync(join(tmpdir(), 'hawor-chromium-live-'));
  context = await chromium.launchPersistentContext(dataDir, {
    executablePath: CHROMIUM, headless: true, viewport: { width: 1400, height: 900 },
    args: [...FLAGS, '--use-fake-device-for-media-stream', '--use-fake-ui-for-media-stream', `--use-file-for-fake-video-capture=${y4m}`],
  });
  page = context.pages()[0] || await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => consoleErrors.push(`pageerror: ${e.message}`));
  await page.goto(url);
  await page.waitForSelector('body[data-ready="1"]', { timeout: 30000 });
});

after(async () => {
  if (context) await context.close();
  if (server) server.close();
  if (dataDir) rmSync(dataDir, { recursive: true, force: true });
  if (Object.keys(report).length) {
    writeFileSync(join(out, 'live.json'), JSON.stringify(report, null, 2));
    console.log(`# live: ${JSON.stringify(report)}`);
  }
});

async function message() {
  return page.evaluate(() => { const m = document.getElementById('message'); return m.hidden ? null : { kind: m.dataset.kind, text: m.textContent }; });
}
async function expectError(prefix, timeout = 20000) {
  await page.waitForFunction(() => !document.getElementById('message').hidden && document.body.dataset.busy === '0', null, { timeout });
  const m = await message();
  assert.ok(m && m.text.startsWith(prefix), `expected a message starting "${prefix}", got ${JSON.stringify(m)}`);
  assert.equal(await page.isDisabled('#btn-camera'), false, 'the Camera button is usable again');
  assert.equal(await page.isDisabled('#btn-stop'), true);
  return m.text;
}
const stats = () => page.evaluate(() => window.haworApp.liveStats());

test('camera errors: permission denied, device busy, a camera that is not there', { skip }, async () => {
  for (const [name, prefix] of [['NotAllowedError', 'Camera permission denied'], ['NotReadableError', 'Camera busy']]) {
    await page.evaluate((n) => {
      const md = navigator.mediaDevices;
      md.realGetUserMedia ||= md.getUserMedia.bind(md);
      md.getUserMedia = () => Promise.reject(new DOMException(`simulated ${n}`, n));
    }, name);
    await page.click('#btn-camera');
    assert.match(await expectError(prefix), new RegExp(`simulated ${name}`));
  }
  await page.evaluate(() => { navigator.mediaDevices.getUserMedia = navigator.mediaDevices.realGetUserMedia; });
  // A device that is not (or no longer) there: the real getUserMedia with its id.
  await page.evaluate(() => { const s = document.getElementById('opt-device'); s.append(new Option('gone', 'no-such-camera')); s.value = 'no-such-camera'; });
  await page.click('#btn-camera');
  assert.match(await expectError('No camera'), /chosen camera is not available/);
  await page.selectOption('#opt-device', '');
  assert.equal(await page.evaluate(() => window.haworApp.result), null);
});

test('live: frames flow with drops, hands and camera poses appear, Stop gives the refined result', { skip, timeout: 120000 }, async () => {
  const t0 = Date.now();
  await page.click('#btn-camera');
  await page.waitForFunction((n) => { const s = window.haworApp.liveStats(); return s && s.framesProcessed >= n; }, LIVE_FRAMES, { timeout: 60000, polling: 200 });
  const live = await stats();
  report.liveWallMs = Date.now() - t0;
  // the device picker names the fake camera once it was allowed
  const devices = await page.$$eval('#opt-device option', (os) => os.map((o) => o.textContent));
  assert.ok(devices.length >= 2, `device picker: ${JSON.stringify(devices)}`);
  assert.ok(live.running, JSON.stringify(live));
  assert.ok(live.framesCaptured >= live.framesSent && live.dropped === live.framesCaptured - live.framesSent, JSON.stringify(live));
  assert.ok(live.framesSent - live.framesProcessed <= 1, `at most one frame in flight: ${JSON.stringify(live)}`);
  assert.ok(live.cameraPoses > 0, `no camera pose live: ${JSON.stringify(live)}`);
  assert.ok(live.handsSeen > 0, `no hand live: ${JSON.stringify(live)}`);
  assert.ok(Number.isFinite(live.fps) && live.fps > 0 && Number.isFinite(live.latencyMsP50) && live.latencyMsP50 > 0, JSON.stringify(live));
  assert.deepEqual(live.size, { width: 640, height: 480 });
  const scene = await page.evaluate(() => window.haworApp.sceneSummary());
  assert.ok(scene && scene.live && scene.cameraPath > 0 && scene.frustum, `live scene: ${JSON.stringify(scene)}`);
  assert.ok(scene.hands.left.frames > 0 || scene.hands.right.frames > 0, `live hands in 3D: ${JSON.stringify(scene)}`);
  assert.match(await page.textContent('#live-status'), /^live · \d+ frames processed · [\d.]+ fps · \d+ dropped · latency \d+ ms \(p95 \d+ ms\) · scale /);
  await page.screenshot({ path: join(out, 'live.png') });

  const tStop = Date.now();
  await page.click('#btn-stop');
  await page.waitForFunction(() => document.body.dataset.busy === '0' && (window.haworApp.result || !document.getElementById('message').hidden), null, { timeout: 90000 });
  report.refineMs = Date.now() - tStop;
  assert.equal(await message(), null, 'no message after Stop');
  const end = await stats();
  const r = await page.evaluate(() => {
    const x = window.haworApp.result;
    const p = Array.from(x.camera.positions);
    let finite = 0;
    for (let t = 0; t < x.frameCount; t++) if ([0, 1, 2].every((a) => Number.isFinite(p[3 * t + a]))) finite++;
    const ts = Array.from(x.camera.timestamps);
    const stages = Object.fromEntries(Object.entries(x.timings).map(([k, v]) => [k, +(v / x.frameCount).toFixed(1)]));
    return { T: x.frameCount, w: x.width, h: x.height, positions: p.length, finite, scale: x.scale && x.scale.method, ts, stages, tracker: x.stats,
      left: x.hands.left.valid.reduce((a, b) => a + Number(b), 0), right: x.hands.right.valid.reduce((a, b) => a + Number(b), 0) };
  });
  assert.equal(end.running, false);
  assert.equal(r.T, end.framesProcessed, `the refined result holds every processed frame: ${JSON.stringify({ r, end })}`);
  assert.equal(r.T, end.framesSent);
  assert.deepEqual([r.w, r.h], [640, 480]);
  assert.equal(r.positions, 3 * r.T);
  // the timeline is the frames' capture times: increasing, and with frames dropped longer than
  // the processed frames at the camera's 30 fps would span
  assert.ok(r.ts[0] === 0 && r.ts.every((t, i) => i === 0 || t > r.ts[i - 1]), `timestamps ${r.ts.slice(0, 5)}`);
  if (end.dropped > r.T) assert.ok(r.ts[r.T - 1] > 1.2 * (r.T - 1) / 30, `last timestamp ${r.ts[r.T - 1]} s for ${r.T} frames with ${end.dropped} dropped`);
  delete r.ts;
  report.stagesMsPerFrame = r.stages;
  report.tracker = r.tracker;
  delete r.stages;
  delete r.tracker;
  assert.ok(r.finite >= Math.min(r.T, end.cameraPoses), `camera poses in the result: ${JSON.stringify(r)}`);
  assert.ok(r.left + r.right > 0, `hands in the refined result: ${JSON.stringify(r)}`);
  const sum = await page.evaluate(() => window.haworApp.sceneSummary());
  assert.ok(!sum.live && sum.cameraPath === r.T, `the result view: ${JSON.stringify(sum)}`);
  for (const f of ['json', 'npz', 'glb', 'tum']) assert.equal(await page.isDisabled(`[data-export="${f}"]`), false, `export ${f}`);
  assert.match(await page.textContent('#live-status'), /^stopped · .* the refined result below replaced the live estimates$/);
  await page.screenshot({ path: join(out, 'refined.png') });
  Object.assign(report, {
    framesCaptured: end.framesCaptured, framesProcessed: end.framesProcessed, dropped: end.dropped,
    fps: +end.fps.toFixed(2), latencyMsP50: Math.round(end.latencyMsP50), latencyMsP95: Math.round(end.latencyMsP95), latencyClock: end.latencyClock,
    pipelineMsP50: Math.round(end.pipelineMsP50), pipelineMsP95: Math.round(end.pipelineMsP95),
    drawMsP50: Math.round(end.drawMsP50), drawMsP95: Math.round(end.drawMsP95),
    liveScale: end.scaleMethod === 'none' ? 'pending' : `${end.scaleMethod} ${Number(end.scale).toFixed(3)} (confidence ${Number(end.scaleConfidence).toFixed(2)})`,
    cameraPoses: end.cameraPoses, handsSeen: end.handsSeen, handsSeenBySide: end.handsSeenBySide, refinedScale: r.scale,
  });
});

test('a recording stops by itself at its bound, saying why, and is refined', { skip, timeout: 90000 }, async () => {
  await page.evaluate(() => { window.haworApp.liveLimits.maxFrames = 12; });
  await page.click('#btn-camera');
  await page.waitForFunction(() => document.body.dataset.busy === '0' && window.haworApp.result, null, { timeout: 80000 });
  const m = await message();
  assert.ok(m && m.kind === 'info' && /bound of 12 processed frames/.test(m.text), JSON.stringify(m));
  assert.equal(await page.evaluate(() => window.haworApp.result.frameCount), 12);
  const s = await stats();
  assert.equal(s.framesProcessed, 12);
  assert.match(s.stopReason, /bound of 12 processed frames/);
  await page.evaluate(() => { window.haworApp.liveLimits.maxFrames = 3000; });
});

test('Stop before 8 frames, Cancel, a camera unplugged while recording, then a file', { skip, timeout: 90000 }, async () => {
  // Stop right after the first frame: too short, said so; the page stays usable.
  await page.click('#btn-camera');
  await page.waitForFunction(() => window.haworApp.liveStats()?.framesSent >= 1, null, { timeout: 30000, polling: 20 });
  await page.click('#btn-stop');
  assert.match(await expectError('Clip too short'), /camera frame\(s\) were processed; at least 8 are needed/);
  assert.equal(await page.evaluate(() => window.haworApp.result), null);
  // Cancel: no result, the camera released.
  await page.click('#btn-camera');
  await page.waitForFunction(() => window.haworApp.liveStats()?.framesProcessed >= 3, null, { timeout: 30000 });
  await page.click('#btn-cancel');
  await page.waitForFunction(() => document.body.dataset.busy === '0', null, { timeout: 15000 });
  const m = await message();
  assert.ok(m && m.kind === 'info' && /Cancelled/.test(m.text), JSON.stringify(m));
  assert.equal(await page.evaluate(() => document.getElementById('video').srcObject), null, 'the camera released');
  // The camera's track ends (unplugged): the recording stops, saying why, and is refined.
  await page.click('#btn-camera');
  await page.waitForFunction(() => window.haworApp.liveStats()?.framesProcessed >= 10, null, { timeout: 30000 });
  await page.evaluate(() => document.getElementById('video').srcObject.getVideoTracks()[0].dispatchEvent(new Event('ended')));
  await page.waitForFunction(() => document.body.dataset.busy === '0' && window.haworApp.result, null, { timeout: 60000 });
  const u = await message();
  assert.ok(u && u.kind === 'info' && /camera stopped sending frames/.test(u.text), JSON.stringify(u));
  assert.equal(await page.evaluate(() => window.haworApp.result.frameCount), (await stats()).framesProcessed);
  // A file after the camera: the <video> plays files again.
  await page.fill('#opt-maxframes', '12');
  await page.click('#btn-sample');
  await page.waitForFunction(() => document.body.dataset.busy === '1', null, { timeout: 10000 });
  await page.waitForFunction(() => document.body.dataset.busy === '0', null, { timeout: 60000 });
  assert.equal(await message(), null);
  assert.equal(await page.evaluate(() => window.haworApp.result.frameCount), 12);
  assert.equal(await page.isHidden('#live-status'), true);
  await page.fill('#opt-maxframes', '');
});

test('the console stayed free of errors', { skip }, () => {
  assert.deepEqual(consoleErrors, []);
});
