// The hand networks in a worker thread (web/src/perception/worker_tracker.mjs, the CLI's
// `--perception thread`): the same result as on the pipeline's own thread (`--perception main`,
// the default), every value of result.json but the timings; a worker that cannot start
// (networks that do not load) is an error naming it; the option is checked, and batch's rerun
// check ignores it.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { root, clipPath, clipSkipReason, modelsSkipReason } from './mediapipe_support.mjs';
import { parseArgs } from '../../web/cli.mjs';
import { workerTrackerFactory } from '../../web/src/perception/worker_tracker.mjs';
import { canonicalOptions } from '../../web/src/batch/task.mjs';

const corePath = process.env.HAWOR_CORE ?? join(root, 'build/wasm/wasm/hawor_core.mjs');
const coreSkip = () => (existsSync(corePath) ? false : `${corePath} missing (cmake --build build/wasm --target hawor_core)`);
const skipOf = (...reasons) => reasons.map((r) => r()).find((r) => r) || false;

test('--perception thread and main give the same result.json (kitchen clip, 40 frames)', { skip: skipOf(coreSkip, clipSkipReason, modelsSkipReason), timeout: 300000 }, () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-perception-thread-'));
  try {
    const results = {};
    for (const where of ['main', 'thread']) {
      const out = join(dir, where);
      const r = spawnSync(process.execPath, [join(root, 'web/cli.mjs'), 'run', clipPath, '--out', out, '--max-frames', '40', '--perception', where],
        { encoding: 'utf8', timeout: 240000, env: { ...process.env, HAWOR_CORE: corePath } });
      assert.equal(r.status, 0, r.stderr);
      const res = JSON.parse(readFileSync(join(out, 'result.json'), 'utf8'));
      delete res.timings;
      results[where] = res;
    }
    assert.ok(results.main.stats.landmarkRuns > 0 && !results.main.noHands, JSON.stringify(results.main.stats));
    assert.deepEqual(results.thread, results.main);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('a perception worker that cannot load its networks fails with a message, not a hang', { timeout: 60000 }, async () => {
  const factory = workerTrackerFactory({ runtime: 'wasm', threads: 1, palm: new Uint8Array([1, 2, 3]), landmark: new Uint8Array([4, 5, 6]) });
  await assert.rejects(factory({ maxHands: 2 }, null), /the perception worker failed to start/);
});

test('--perception takes thread or main, and a batch rerun does not count it as another option', () => {
  assert.equal(parseArgs(['run', 'v.mp4', '--out', 'o', '--perception', 'main']).perception, 'main');
  const opts = (where) => canonicalOptions(parseArgs(['run', 'v.mp4', '--out', 'o', '--threads', '1', '--perception', where]));
  assert.deepEqual(opts('thread'), opts('main'));
  assert.equal(opts('main').threads, 1);
  assert.throws(() => parseArgs(['run', 'v.mp4', '--out', 'o', '--perception', 'gpu']), /--perception must be thread or main, not 'gpu'/);
});
