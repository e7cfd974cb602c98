// web/tools/bench_realtime.mjs, small: its usage errors (exit code 2, one line naming what is
// missing) and one round on 8 frames of the built-in sample without the CLI (hawor's pipeline in
// a worker and MediaPipe's runtime in headless Chromium): the JSON's structure, both timings
// positive and finite, MediaPipe on its CPU (XNNPACK) path. About 10 s.
//
//   bash scripts/build_web.sh && node --test tests/browser/bench_realtime.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const TOOL = join(root, 'web/tools/bench_realtime.mjs');
const SAMPLE = join(root, 'build/web/sample.webm');
const CHROMIUM = process.env.HAWOR_CHROMIUM || '/usr/bin/chromium';
const noChromium = !existsSync(CHROMIUM);
if (noChromium) console.log(`# SKIP bench_realtime's browser run: ${CHROMIUM} not found (apt-get install chromium; scripts/install.sh does)`);

const tool = (args, timeout = 120000) => spawnSync(process.execPath, [TOOL, ...args], { cwd: root, encoding: 'utf8', timeout });
const finitePositive = (x, what) => assert.ok(Number.isFinite(x) && x > 0, `${what}: ${x}`);

test('bench_realtime: a missing or unreadable video is a one-line error with exit code 2', () => {
  const none = tool([]);
  assert.equal(none.status, 2);
  assert.match(none.stderr, /missing VIDEO/);
  const absent = tool(['/nonexistent/clip.mp4']);
  assert.equal(absent.status, 2);
  assert.equal(absent.stderr.trim(), 'bench_realtime: /nonexistent/clip.mp4: no such file');
  const dir = mkdtempSync(join(tmpdir(), 'hawor-bench-rt-test-'));
  try {
    writeFileSync(join(dir, 'junk.mp4'), Buffer.alloc(4096, 7));
    const junk = tool([join(dir, 'junk.mp4'), '--no-cli']);
    assert.equal(junk.status, 2);
    assert.match(junk.stderr, /junk\.mp4: not a readable video/);
    assert.equal(junk.stderr.trim().split('\n').length, 1);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('bench_realtime: one round on 8 frames of the sample', { skip: noChromium ? 'chromium not installed' : false }, () => {
  assert.ok(existsSync(SAMPLE), `${SAMPLE} missing: run scripts/build_web.sh`);
  const dir = mkdtempSync(join(tmpdir(), 'hawor-bench-rt-test-'));
  try {
    const json = join(dir, 'bench.json');
    const r = tool([SAMPLE, '--frames', '8', '--runs', '1', '--no-cli', '--json', json], 90000);
    assert.equal(r.status, 0, `exit ${r.status} (${r.signal ?? ''}): ${r.stderr}`);
    const out = JSON.parse(r.stdout.trim().split('\n').pop());
    assert.deepEqual(JSON.parse(readFileSync(json, 'utf8')), out);
    assert.equal(out.frames, 8);
    assert.equal(out.size, '640x480');
    assert.equal(out.warmupFrames, 5);
    assert.equal(out.loadavgBefore.length, 3);
    assert.equal(out.loadavgAfter.length, 3);
    assert.equal(out.browser.isolationHeaders.coep, 'require-corp');
    assert.equal(out.runs.hawor.length, 1);
    assert.equal(out.runs.mediapipe.length, 1);
    assert.deepEqual(out.runs.cli, []);
    assert.equal(out.summary.cli, null);
    const h = out.runs.hawor[0], m = out.runs.mediapipe[0];
    assert.equal(h.frameMs.length, 8);
    assert.equal(m.frameMs.length, 8);
    for (const x of [...h.frameMs, ...m.frameMs]) finitePositive(x, 'a frame time');
    finitePositive(out.summary.hawor.medianMs, 'hawor-browser median');
    finitePositive(out.summary.hawor.p95Ms, 'hawor-browser p95');
    finitePositive(out.summary.mediapipe.medianMs, 'mediapipe-browser median');
    finitePositive(out.summary.mediapipe.p95Ms, 'mediapipe-browser p95');
    finitePositive(out.summary.ratio, 'ratio');
    finitePositive(h.stagesMsPerFrame.perception, 'hawor perception');
    assert.ok(h.finishMs >= 0 && h.wallMs > 0);
    assert.ok(h.handsPerFrame >= 0 && m.handsPerFrame >= 0);
    // useCpuInference honoured: MediaPipe's runtime created TensorFlow Lite's CPU delegate.
    assert.equal(m.xnnpack, true);
    assert.match(r.stderr, /hawor-browser .*\n.*mediapipe-browser/);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
