// The hand networks' backend in the browser app (web/src/perception/execution_provider.mjs), in
// headless Chromium with WebGPU enabled: this machine has no GPU, so its only adapter is Chromium's
// software one (SwiftShader). 'auto' must keep WebAssembly and say why; asked for WebGPU, the page
// runs the networks there after checking them against WebAssembly, and the run's hands agree with
// the WebAssembly run's on the same frames of the synthetic sample. Skipped with a message when
// Chromium offers no WebGPU adapter at all.
//
//   bash scripts/build_web.sh && node --test tests/browser/webgpu.test.mjs
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { createServer } from '../../web/server.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const CHROMIUM = process.env.HAWOR_CHROMIUM || '/usr/bin/chromium';
const FRAMES = 8; // SwiftShader takes seconds per inference: the fewest frames a clip may have
const FLAGS = ['--headless', '--no-sandbox', '--enable-unsafe-webgpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync'];
const needed = ['build/wasm/wasm/hawor_core.mjs', 'build/web/sample.webm', 'web/models/palm_detection_lite.onnx',
  'node_modules/onnxruntime-web/dist/ort.webgpu.min.mjs'];
const missing = needed.filter((f) => !existsSync(join(root, f)));
const noChromium = !existsSync(CHROMIUM);
if (noChromium) console.log(`# SKIP WebGPU tests: ${CHROMIUM} not found (apt-get install chromium; scripts/install.sh does)`);

let server, context, page, dataDir, adapter = null;
const consoleErrors = [];

before(async () => {
  if (noChromium) return;
  assert.deepEqual(missing, [], `missing build outputs (run scripts/build_web.sh): ${missing.join(', ')}`);
  server = createServer(root);
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  const { chromium } = await import('playwright-core');
  dataDir = mkdtempSync(join(tmpdir(), 'hawor-chromium-'));
  context = await chromium.launchPersistentContext(dataDir, { executablePath: CHROMIUM, headless: true, args: FLAGS, viewport: { width: 1400, height: 900 } });
  page = context.pages()[0] || await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => consoleErrors.push(`pageerror: ${e.message}`));
  await page.goto(`http://127.0.0.1:${server.address().port}/`);
  await page.waitForFunction(() => document.body.dataset.ready === '1', null, { timeout: 60000 });
  adapter = await page.evaluate(async () => {
    const a = navigator.gpu && await navigator.gpu.requestAdapter();
    return a ? [a.info?.vendor, a.info?.architecture].filter(Boolean).join(' ') || 'unnamed' : null;
  });
  if (!adapter) console.log('# SKIP WebGPU runs: Chromium offers no WebGPU adapter here');
});

after(async () => {
  if (context) await context.close();
  if (server) server.close();
  if (dataDir) rmSync(dataDir, { recursive: true, force: true });
});

/// Runs FRAMES frames of the synthetic sample with the given backend choice; the page's backend
/// note and the result's 2D keypoints.
async function runSample(backend) {
  await page.selectOption('#opt-backend', backend);
  await page.fill('#opt-maxframes', String(FRAMES));
  await page.click('#btn-sample');
  await page.waitForFunction(() => document.body.dataset.busy === '0' && (window.haworApp.result || !document.getElementById('message').hidden), null, { timeout: 600000 });
  return page.evaluate(() => {
    const m = document.getElementById('message');
    const r = window.haworApp.result;
    return {
      error: m.hidden || m.dataset.kind === 'info' ? null : m.textContent,
      backend: window.haworApp.backend,
      note: document.getElementById('backend-note').textContent,
      frames: r ? r.frameCount : 0,
      keypoints: r ? { left: Array.from(r.hands.left.keypoints2d), right: Array.from(r.hands.right.keypoints2d) } : null,
    };
  });
}

const skip = noChromium ? 'chromium not installed' : false;
let onWasm = null;

test("'auto' keeps WebAssembly on a software WebGPU adapter and says why", { skip, timeout: 600000 }, async (t) => {
  if (!adapter) return t.skip('no WebGPU adapter');
  onWasm = await runSample('auto');
  assert.equal(onWasm.error, null);
  assert.equal(onWasm.frames, FRAMES);
  assert.equal(onWasm.backend.provider, 'wasm');
  assert.match(onWasm.note, /networks on WebAssembly: the only WebGPU adapter is a software renderer/);
});

test('asked for WebGPU, the networks run there and give the WebAssembly run\'s hands', { skip, timeout: 600000 }, async (t) => {
  if (!adapter) return t.skip('no WebGPU adapter');
  if (!onWasm) onWasm = await runSample('wasm');
  const onGpu = await runSample('webgpu');
  assert.equal(onGpu.error, null);
  assert.equal(onGpu.backend.provider, 'webgpu', onGpu.note);
  assert.match(onGpu.note, /networks on WebGPU: WebGPU \(.+\) was asked for; its outputs agree/);
  assert.ok(onGpu.backend.disagreement <= 1e-3, `probe outputs differ by ${onGpu.backend.disagreement} of their range`);
  assert.ok(onGpu.backend.ms.wasm > 0 && onGpu.backend.ms.webgpu > 0, JSON.stringify(onGpu.backend.ms));
  let compared = 0, dmax = 0;
  for (const side of ['left', 'right']) {
    const a = onWasm.keypoints[side], b = onGpu.keypoints[side];
    assert.equal(a.length, b.length);
    for (let i = 0; i < a.length; ++i) {
      assert.equal(Number.isFinite(a[i]), Number.isFinite(b[i]), `${side} keypoint ${i}: found on one backend only`);
      if (Number.isFinite(a[i])) { dmax = Math.max(dmax, Math.abs(a[i] - b[i])); ++compared; }
    }
  }
  t.diagnostic(`${onGpu.note}; probe: WebAssembly ${onGpu.backend.ms.wasm.toFixed(1)} ms, WebGPU ${onGpu.backend.ms.webgpu.toFixed(1)} ms, outputs ${onGpu.backend.disagreement.toExponential(1)} apart; 2D keypoints up to ${dmax.toExponential(1)} px apart over ${compared} coordinates`);
  assert.ok(compared >= 42 * FRAMES, `${compared} keypoint coordinates compared`);
  assert.ok(dmax <= 0.05, `2D keypoints differ by up to ${dmax} px between WebAssembly and WebGPU`);
});

test('the console stayed free of errors', { skip }, () => {
  assert.deepEqual(consoleErrors, []);
});
