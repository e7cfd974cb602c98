// End-to-end tests of the browser app in headless Chromium (npm playwright-core driving Debian's
// /usr/bin/chromium, docs/design.md §9): page load and cross-origin isolation, the error messages (corrupt
// file, huge resolution, clip too short, wrong MANO file), cancel, the synthetic sample and the
// real clip (../shared/data/egocentric_kitchen.mp4, its first HAWOR_KITCHEN_FRAMES frames, default
// 40, at 640 px; skipped with a message when absent) through the file input, the stage list (every
// stage done after a run), the 3D scene, every
// export (npz read by numpy, GLB by three's GLTFLoader and the Khronos validator, JSON, TUM), the
// page's runPipeline against the native `hawor world` on the same frames and hands, and a
// console free of errors. Screenshots, exports and timings go to build/browser-test/.
//
//   bash scripts/build_web.sh && node --test tests/browser/
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve, dirname } from 'node:path';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { createServer } from '../../web/server.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const out = join(root, 'build/browser-test');
const CHROMIUM = process.env.HAWOR_CHROMIUM || '/usr/bin/chromium';
const KITCHEN = resolve(root, '../shared/data/egocentric_kitchen.mp4');
const KITCHEN_FRAMES = Number(process.env.HAWOR_KITCHEN_FRAMES || 40);
const PY = '/usr/bin/python3';
const FLAGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync'];

const needed = ['build/wasm/wasm/hawor_core.mjs', 'build/wasm/wasm/hawor_core.wasm', 'build/web/sample.webm',
  'build/web/sample.json', 'node_modules/@webxr-input-profiles/assets/dist/profiles/generic-hand/left.glb', 'web/models/palm_detection_lite.onnx',
  'web/models/hand_landmark_lite.onnx'];
const missing = needed.filter((f) => !existsSync(join(root, f)));
const noChromium = !existsSync(CHROMIUM);
if (noChromium) console.log(`# SKIP browser tests: ${CHROMIUM} not found (apt-get install chromium; scripts/install.sh does)`);

let server, url, context, page, dataDir;
const consoleErrors = [];
const timings = {};

before(async () => {
  if (noChromium) return;
  assert.deepEqual(missing, [], `missing build outputs (run scripts/build_web.sh): ${missing.join(', ')}`);
  mkdirSync(out, { recursive: true });
  server = createServer(root);
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  url = `http://127.0.0.1:${server.address().port}/`;
  const { chromium } = await import('playwright-core');
  dataDir = mkdtempSync(join(tmpdir(), 'hawor-chromium-'));
  context = await chromium.launchPersistentContext(dataDir, {
    executablePath: CHROMIUM, headless: true, args: FLAGS, viewport: { width: 1400, height: 900 }, acceptDownloads: true,
  });
  page = context.pages()[0] || await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => consoleErrors.push(`pageerror: ${e.message}`));
});

after(async () => {
  if (context) await context.close();
  if (server) server.close();
  if (dataDir) rmSync(dataDir, { recursive: true, force: true });
  if (Object.keys(timings).length) writeFileSync(join(out, 'timings.json'), JSON.stringify(timings, null, 2));
});

const skip = noChromium ? 'chromium not installed' : false;

async function message() {
  return page.evaluate(() => { const m = document.getElementById('message'); return m.hidden ? null : { kind: m.dataset.kind, text: m.textContent }; });
}
async function waitDone(timeout) {
  await page.waitForFunction(() => document.body.dataset.busy === '0' && (window.haworApp.result || !document.getElementById('message').hidden), null, { timeout });
}
// The models note is updated once the page has read the dropped file (asynchronously): wait for
// it to match, then assert it (a read right after setInputFiles raced with that update).
async function modelsNote(re, timeout = 10000) {
  await page.waitForFunction(([src, flags]) => new RegExp(src, flags).test(document.getElementById('models-note').textContent),
    [re.source, re.flags], { timeout }).catch(() => {});
  assert.match(await page.textContent('#models-note'), re);
}

async function expectError(kindText, timeout = 30000) {
  await page.waitForFunction(() => !document.getElementById('message').hidden && document.body.dataset.busy !== '1', null, { timeout });
  const m = await message();
  assert.ok(m && m.text.startsWith(kindText), `expected a message starting "${kindText}", got ${JSON.stringify(m)}`);
  return m.text;
}
function ffmpeg(args) {
  const r = spawnSync('ffmpeg', ['-v', 'error', '-y', ...args], { encoding: 'utf8' });
  assert.equal(r.status, 0, `ffmpeg ${args.join(' ')}: ${r.stderr}`);
}
async function download(format) {
  const d = page.waitForEvent('download', { timeout: 60000 });
  await page.click(`[data-export="${format}"]`);
  const failed = page.waitForFunction(() => !document.getElementById('message').hidden, null, { timeout: 60000 }).then(() => null, () => null);
  const dl = await Promise.race([d, failed]);
  if (!dl) throw new Error(`export ${format}: ${JSON.stringify(await message())}`);
  const file = join(out, dl.suggestedFilename());
  await dl.saveAs(file);
  return file;
}

test('the page loads cross-origin isolated, ready within 3 s', { skip }, async () => {
  const t0 = Date.now();
  const resp = await page.goto(url);
  assert.equal(resp.headers()['cross-origin-opener-policy'], 'same-origin');
  assert.equal(resp.headers()['cross-origin-embedder-policy'], 'require-corp');
  await page.waitForSelector('body[data-ready="1"]', { timeout: 30000 });
  timings.pageReadyMs = Date.now() - t0;
  timings.pageReadyInPageMs = await page.evaluate(() => window.haworApp.readyMs);
  assert.equal(await page.evaluate(() => self.crossOriginIsolated), true);
  assert.ok(timings.pageReadyMs <= 3000, `page ready after ${timings.pageReadyMs} ms`);
});

test('bad inputs give clear messages and the app stays usable', { skip }, async () => {
  const dir = join(out, 'inputs');
  mkdirSync(dir, { recursive: true });
  // A corrupt video: random bytes behind an MP4 name.
  const junk = Buffer.alloc(200000);
  for (let i = 0; i < junk.length; i++) junk[i] = (i * 2654435761) >>> 24;
  writeFileSync(join(dir, 'corrupt.mp4'), junk);
  await page.setInputFiles('#file-video', join(dir, 'corrupt.mp4'));
  const corrupt = await expectError('Unsupported or corrupt video');
  assert.match(corrupt, /corrupt\.mp4/);
  // A huge resolution (5000 px wide) and a clip too short (4 frames).
  ffmpeg(['-f', 'lavfi', '-i', 'testsrc=size=5000x64:rate=10', '-frames:v', '3', '-c:v', 'libvpx-vp9', '-deadline', 'realtime', join(dir, 'huge.webm')]);
  await page.setInputFiles('#file-video', join(dir, 'huge.webm'));
  assert.match(await expectError('Resolution too large'), /5000×64/);
  ffmpeg(['-f', 'lavfi', '-i', 'testsrc=size=320x240:rate=30', '-frames:v', '4', '-c:v', 'libvpx-vp9', '-deadline', 'realtime', join(dir, 'short.webm')]);
  await page.setInputFiles('#file-video', join(dir, 'short.webm'));
  await expectError('Clip too short');
  // A clip without hands (flat grey): processed, then said so.
  ffmpeg(['-f', 'lavfi', '-i', 'color=c=gray:size=320x240:rate=30', '-frames:v', '12', '-c:v', 'libvpx-vp9', '-deadline', 'realtime', join(dir, 'grey.webm')]);
  await page.setInputFiles('#file-video', join(dir, 'grey.webm'));
  assert.match(await expectError('No hands found', 60000), /no hand was detected/);
  assert.equal((await page.evaluate(() => window.haworApp.result.frameCount)), 12);
  // A wrong MANO file: refused before any frame is processed.
  writeFileSync(join(dir, 'MANO_RIGHT.pkl'), Buffer.from('this is not a pickle'));
  await page.setInputFiles('#file-mano-right', join(dir, 'MANO_RIGHT.pkl'));
  await modelsNote(/MANO_RIGHT\.pkl/);
  await page.click('#btn-sample');
  assert.match(await expectError('Wrong MANO file', 60000), /right MANO file "MANO_RIGHT\.pkl"/);
  // A MANO file given for the wrong side.
  await page.setInputFiles('#file-mano-left', join(dir, 'MANO_RIGHT.pkl'));
  await expectError('Wrong MANO file');
  await page.click('#btn-clear-models');
  await modelsNote(/default/);
  // An impossible camera height above the floor: refused before any frame is processed.
  await page.fill('#opt-eyeheight', '5');
  await page.click('#btn-sample');
  assert.match(await expectError('Wrong camera height'), /between 0\.8 and 3 m/);
  await page.fill('#opt-eyeheight', '');
  // A rolling-shutter readout longer than a frame interval: refused before any frame.
  await page.fill('#opt-readout', '50');
  await page.click('#btn-sample');
  assert.match(await expectError('Wrong rolling-shutter readout'), /50 ms is not within the frame interval \(±33\.\d ms at [\d.]+ fps\)/);
  await page.fill('#opt-readout', '');
  await page.screenshot({ path: join(out, 'error-message.png') });
});

test('cancel stops a run; the next run starts cleanly', { skip }, async () => {
  await page.click('#btn-sample');
  await page.waitForFunction(() => /frames: [3-9]|frames: \d\d/.test(document.getElementById('stage').textContent), null, { timeout: 60000 });
  await page.click('#btn-cancel');
  await page.waitForFunction(() => document.body.dataset.busy === '0', null, { timeout: 15000 });
  const m = await message();
  assert.ok(m && m.kind === 'info' && /Cancelled/.test(m.text), JSON.stringify(m));
  assert.equal(await page.evaluate(() => window.haworApp.result), null);
});

/// After a finished run every listed stage is done: class 'done' and, where it counts, its full count.
async function checkStagesDone(label) {
  const stages = await page.$$eval('#stages li', (lis) => lis.map((li) => ({ cls: li.className, text: li.textContent })));
  assert.ok(stages.length >= 4, `${label}: stages ${JSON.stringify(stages)}`);
  for (const st of stages) {
    assert.equal(st.cls, 'done', `${label}: ${JSON.stringify(st)}`);
    const count = /(\d+)\/(\d+)/.exec(st.text);
    if (count) assert.equal(count[1], count[2], `${label}: ${JSON.stringify(st)}`);
  }
  for (const name of ['decoding frames 60/60', 'frames 60/60', 'slam-finish 1/1', 'scale 1/1']) {
    assert.ok(stages.some((st) => st.text.startsWith(name)), `${label}: no stage "${name}" in ${JSON.stringify(stages.map((st) => st.text))}`);
  }
}

async function checkScene(T, label) {
  const s = await page.evaluate(() => window.haworApp.sceneSummary());
  assert.ok(s, `${label}: no scene`);
  assert.equal(s.cameraPath, T, `${label}: camera path of ${s.cameraPath} poses for ${T} frames`);
  const hands = Object.values(s.hands).filter((h) => h.frames > 0);
  assert.ok(hands.length >= 1, `${label}: no hand track in the scene ${JSON.stringify(s)}`);
  for (const h of hands) assert.ok(h.trackPoints >= 2 && h.vertices > 700, `${label}: ${JSON.stringify(h)}`);
  assert.ok(s.frustum, `${label}: no camera frustum`);
  return s;
}

test('the synthetic sample: views, timeline and every export', { skip }, async () => {
  const t0 = Date.now();
  await page.click('#btn-sample');
  await waitDone(120000);
  assert.equal(await message(), null, 'no message after the sample');
  const run = await page.evaluate(() => window.haworApp.lastRun);
  timings.sample = { wallMs: Date.now() - t0, ...run };
  const result = await page.evaluate(() => ({ T: window.haworApp.result.frameCount, w: window.haworApp.result.width, fps: window.haworApp.result.fps }));
  assert.equal(result.T, 60, 'all 60 frames of the sample');
  const s = await checkScene(60, 'sample');
  assert.ok(s.hands.left.frames > 0 && s.hands.right.frames > 0, `both hands of the sample: ${JSON.stringify(s.hands)}`);
  await checkStagesDone('sample');
  assert.ok(s.points > 50, `SLAM points: ${s.points}`);
  // The timeline drives the views.
  await page.fill('#scrub', '30');
  await page.dispatchEvent('#scrub', 'input');
  assert.equal(await page.evaluate(() => window.haworApp.sceneSummary().frame), 30);
  assert.match(await page.textContent('#frame-label'), /frame 31\/60/);
  await page.click('#btn-play');
  await page.waitForTimeout(500);
  await page.click('#btn-play');
  await page.waitForTimeout(100);
  await page.screenshot({ path: join(out, 'sample.png') });

  // Exports.
  const json = JSON.parse(readFileSync(await download('json'), 'utf8'));
  assert.equal(json.version, 1);
  assert.equal(json.frameCount, 60);
  assert.equal(json.camera.positions.length, 60 * 3);
  const tum = readFileSync(await download('tum'), 'utf8').split('\n').filter((l) => l && !l.startsWith('#'));
  assert.equal(tum.length, 60);
  for (const l of tum) { const v = l.trim().split(/\s+/).map(Number); assert.equal(v.length, 8); assert.ok(v.every(Number.isFinite), l); }
  const npz = await download('npz');
  const py = spawnSync(PY, ['-c', `
import json, sys, numpy as np
d = np.load(sys.argv[1])
print(json.dumps({k: list(d[k].shape) for k in d.files}))`, npz], { encoding: 'utf8' });
  assert.equal(py.status, 0, py.stderr);
  const shapes = JSON.parse(py.stdout);
  for (const side of ['left', 'right']) {
    for (const k of ['trans', 'rot', 'hand_pose', 'betas', 'valid']) {
      const key = Object.keys(shapes).find((x) => x === `${side}_${k}`);
      assert.ok(key, `npz key ${side}_${k} missing: ${Object.keys(shapes)}`);
      assert.equal(shapes[key][0], 60, `${key}: ${shapes[key]}`);
    }
  }
  const glb = await download('glb');
  await checkGlb(glb, 60, result.fps);
});

async function checkGlb(file, T, fps) {
  const bytes = readFileSync(file);
  const validator = (await import('gltf-validator')).default;
  const report = await validator.validateBytes(new Uint8Array(bytes));
  assert.equal(report.issues.numErrors, 0, JSON.stringify(report.issues.messages.slice(0, 5)));
  assert.equal(report.issues.numWarnings, 0, JSON.stringify(report.issues.messages.slice(0, 5)));
  const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
  const gltf = await new Promise((res, rej) => new GLTFLoader().parse(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength), '', res, rej));
  const names = new Set();
  gltf.scene.traverse((o) => names.add(o.name));
  for (const n of ['hawor_world', 'left_hand', 'right_hand', 'camera', 'camera_path']) assert.ok(names.has(n), `GLB node ${n} missing`);
  assert.equal(gltf.cameras.length, 1);
  assert.equal(gltf.animations.length, 1);
  assert.ok(Math.abs(gltf.animations[0].duration - (T - 1) / fps) < 1.5 / fps, `animation of ${gltf.animations[0].duration} s`);
  const frames = gltf.scene.getObjectByName('right_hand').children.length + gltf.scene.getObjectByName('left_hand').children.length;
  assert.ok(frames > 0, 'no hand frames in the GLB');
}

test('MANO files dropped on the page drive the meshes (stand-in MANO files, 30 frames of the sample)', { skip }, async () => {
  const dir = join(out, 'mano');
  mkdirSync(dir, { recursive: true });
  const py = spawnSync(PY, [join(root, 'tests/ref/hand_make_mano.py'), join(dir, 'ref.txt'), dir], { encoding: 'utf8' });
  assert.equal(py.status, 0, py.stderr);
  // Dropped together on the drop zone: the sides come from the names.
  const files = ['MANO_LEFT.pkl', 'MANO_RIGHT.pkl'].map((n) => ({ name: n, mimeType: 'application/octet-stream', buffer: readFileSync(join(dir, n)) }));
  const handle = await page.evaluateHandle(() => new DataTransfer());
  for (const f of files) {
    await page.evaluate(({ dt, name, b64 }) => dt.items.add(new File([Uint8Array.from(atob(b64), (c) => c.charCodeAt(0))], name)),
      { dt: handle, name: f.name, b64: f.buffer.toString('base64') });
  }
  await page.dispatchEvent('#drop', 'drop', { dataTransfer: handle });
  await page.waitForFunction(() => /MANO left: MANO_LEFT\.pkl, right: MANO_RIGHT\.pkl/.test(document.getElementById('models-note').textContent), null, { timeout: 20000 });
  await page.fill('#opt-maxframes', '30');
  await page.click('#btn-sample');
  await waitDone(120000);
  assert.equal(await message(), null, JSON.stringify(await page.evaluate(() => window.haworApp.result && window.haworApp.result.warnings)));
  const s = await page.evaluate(() => window.haworApp.sceneSummary());
  for (const side of ['left', 'right']) assert.equal(s.hands[side].vertices, 778, `${side}: ${JSON.stringify(s.hands[side])}`);
  await page.click('#btn-clear-models');
  await page.fill('#opt-maxframes', '');
});

test('the real clip through the file input', { skip: skip || (!existsSync(KITCHEN) && 'the clip is absent') }, async () => {
  if (!existsSync(KITCHEN)) console.log(`# SKIP: ${KITCHEN} not found`);
  await page.fill('#opt-maxside', '640');
  await page.fill('#opt-maxframes', String(KITCHEN_FRAMES));
  await page.fill('#opt-eyeheight', '1.7'); // reaches the ground cue (reported back when it found a level)
  const t0 = Date.now();
  await page.setInputFiles('#file-video', KITCHEN);
  await waitDone(240000);
  assert.equal(await message(), null, 'no message after the clip');
  const run = await page.evaluate(() => window.haworApp.lastRun);
  timings.kitchen = { wallMs: Date.now() - t0, ...run };
  const r = await page.evaluate(() => { const x = window.haworApp.result; return { T: x.frameCount, w: x.width, h: x.height, fx: x.intrinsics.fx }; });
  assert.equal(r.T, KITCHEN_FRAMES);
  assert.deepEqual([r.w, r.h], [640, 360]);
  const { ground, slamOk } = await page.evaluate(() => ({ ground: window.haworApp.result.scale.ground ?? null, slamOk: window.haworApp.result.slam.initialised }));
  if (slamOk) {
    assert.ok(ground, 'the ground cue ran on the SLAM map');
    if (ground.ok) assert.equal(ground.eyeHeight, 1.7);
    else assert.ok(ground.reason, JSON.stringify(ground));
    assert.match(await page.textContent('#summary'), /floor/);
  }
  await page.fill('#opt-eyeheight', '');
  await checkScene(KITCHEN_FRAMES, 'kitchen');
  const kitchenStages = await page.$$eval('#stages li', (lis) => lis.map((li) => li.className));
  assert.ok(kitchenStages.length > 0 && kitchenStages.every((c) => c === 'done'), `kitchen stages: ${kitchenStages}`);
  await page.evaluate(() => window.haworApp.view.setFrame(20));
  await page.waitForTimeout(300);
  await page.screenshot({ path: join(out, 'kitchen.png') });
  await checkGlb(await download('glb'), KITCHEN_FRAMES, 30);
});

const HAWOR = join(root, 'build/native/examples/hawor');
const HANDS_DIR = join(root, 'build/native/models');
const noWorld = !existsSync(HAWOR) ? `${HAWOR} missing` : !existsSync(join(HANDS_DIR, 'hand_left.npz')) ? `${HANDS_DIR}/hand_left.npz missing` : false;

test('the browser and the native `hawor world` give the same world on the same frames and camera-frame hands', { skip: skip || noWorld, timeout: 240000 }, async () => {
  // A hawor synth sequence and its ground-truth camera-frame hands: the native run, then the
  // page's runPipeline (the WebAssembly core in Chromium) on the same RGB frames.
  const W = 480, H = 360, T = 40;  // the smallest at which the SLAM initialises on these 40 frames
  const dir = mkdtempSync(join(tmpdir(), 'hawor-browser-world-'));
  try {
    let r = spawnSync(HAWOR, ['synth', '--preset', 'table_work', '--seed', '2', '--frames', String(T), '--size', `${W}x${H}`, '--out', join(dir, 'seq')], { encoding: 'utf8' });
    assert.equal(r.status, 0, r.stderr);
    const [fx, fy, cx, cy] = readFileSync(join(dir, 'seq/intrinsics.txt'), 'utf8').split('\n')[0].trim().split(/\s+/).map(Number);
    r = spawnSync(HAWOR, ['world', '--images', join(dir, 'seq/rgb'), '--hands', join(dir, 'seq/hands_gt.npz'), '--intrinsics', `${fx},${fy},${cx},${cy}`,
      '--out', join(dir, 'native')], { encoding: 'utf8', env: { ...process.env, HAWOR_HAND_DIR: HANDS_DIR } });
    assert.equal(r.status, 0, r.stderr);
    const rgb = spawnSync('ffmpeg', ['-v', 'error', '-i', join(dir, 'seq/rgb/%06d.png'), '-f', 'rawvideo', '-pix_fmt', 'rgb24', '-'], { maxBuffer: 1 << 28 }).stdout;
    assert.equal(rgb.length, T * W * H * 3);
    const { loadCore } = await import('../../web/cli.mjs');
    const core = await loadCore(join(root, 'build/wasm/wasm/hawor_core.mjs'));
    const gt = core.readNpz(readFileSync(join(dir, 'seq/hands_gt.npz')), 'hands_gt.npz');
    const rows = (key) => Array.from(gt[key].data).map(Number);
    const hands = {};
    for (const side of ['left', 'right']) {
      hands[side] = { valid: Array.from(gt[`${side}_valid`].data).map(Number), rot: rows(`${side}_cam_rot`), trans: rows(`${side}_cam_trans`),
        handPose: rows(`${side}_hand_pose`), betas: rows(`${side}_betas`) };
    }
    const models = { left: readFileSync(join(HANDS_DIR, 'hand_left.npz')).toString('base64'), right: readFileSync(join(HANDS_DIR, 'hand_right.npz')).toString('base64') };
    const res = await page.evaluate(async ({ frames, hands, models, W, H, T, fx }) => {
      const bytes = (b64) => Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
      const all = bytes(frames);
      const { loadCore } = await import('/web/src/core.mjs');
      const { runPipeline } = await import('/web/src/pipeline/run.mjs');
      const core = await loadCore();
      const n = (side, key) => hands[side][key].length / T;
      const handsCam = (f) => {
        const out = {};
        for (const side of ['left', 'right']) {
          const h = hands[side], row = (key) => Float64Array.from(h[key].slice(n(side, key) * f, n(side, key) * (f + 1)));
          out[side] = h.valid[f] ? { rot: row('rot'), trans: row('trans'), handPose: row('handPose'), betas: row('betas') } : null;
        }
        return out;
      };
      const source = { width: W, height: H, fps: 30, frameCount: T,
        frames: (async function* () { for (let f = 0; f < T; ++f) yield { index: f, rgba: all.subarray(f * W * H * 3, (f + 1) * W * H * 3) }; })() };
      const r = await runPipeline(source, { core, handModels: { left: bytes(models.left), right: bytes(models.right) }, handsCam, focalPx: fx });
      return { positions: Array.from(r.camera.positions), scale: r.scale.scale, method: r.scale.method, initialised: r.slam.initialised,
        left: Array.from(r.hands.left.jointsWorld), right: Array.from(r.hands.right.jointsWorld) };
    }, { frames: rgb.toString('base64'), hands, models, W, H, T, fx });
    assert.ok(res.initialised, 'the SLAM initialised in the browser');
    const summary = JSON.parse(r.stdout);
    assert.equal(res.method, summary.method);
    const tum = readFileSync(join(dir, 'native/camera.tum'), 'utf8').trim().split('\n').filter((l) => !l.startsWith('#')).map((l) => l.trim().split(/\s+/).map(Number));
    let dCam = 0;
    for (let f = 0; f < T; ++f) for (let a = 0; a < 3; ++a) dCam = Math.max(dCam, Math.abs(tum[f][1 + a] - res.positions[3 * f + a]));
    const world = core.readNpz(readFileSync(join(dir, 'native/world.npz')), 'world.npz');
    let dHand = 0, compared = 0;
    for (const side of ['left', 'right']) {
      const a = world[`${side}_joints_world`].data, b = res[side];  // NaN crosses page.evaluate as null
      assert.equal(a.length, b.length);
      for (let i = 0; i < a.length; ++i) {
        if (Number.isNaN(a[i]) || b[i] === null || Number.isNaN(b[i])) { assert.ok(Number.isNaN(a[i]) && (b[i] === null || Number.isNaN(b[i])), `${side} joint ${i}: NaN in one run only`); continue; }
        dHand = Math.max(dHand, Math.abs(a[i] - b[i]));
        compared += 1;
      }
    }
    timings.worldBrowserVsNative = { camera: dCam, joints: dHand, compared };
    assert.ok(compared > 500, `${compared} joint coordinates compared`);
    assert.ok(dCam <= 1e-6, `camera positions differ by ${dCam} m`);
    assert.ok(dHand <= 1e-6, `world joints differ by ${dHand} m`);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('the console stayed free of errors', { skip }, () => {
  assert.deepEqual(consoleErrors, []);
});
