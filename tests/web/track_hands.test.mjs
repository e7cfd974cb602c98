// web/tools/track_hands.mjs: the perception module over a video from the command line.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { root, clipPath, clipSkipReason, modelsSkipReason } from './mediapipe_support.mjs';

const tool = join(root, 'web/tools/track_hands.mjs');
const run = (args) => spawnSync(process.execPath, [tool, ...args], { encoding: 'utf8' });

test('track_hands: usage errors exit 2, a missing or unreadable video exits 1, each with a message', () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-track-'));
  try {
    let r = run(['--video', 'x.mp4']);
    assert.equal(r.status, 2); assert.match(r.stderr, /--video and --out are required/);
    r = run(['--video', 'x.mp4', '--out', join(dir, 'o'), '--model', 'huge']);
    assert.equal(r.status, 2); assert.match(r.stderr, /--model must be lite or full/);
    r = run(['--video', 'x.mp4', '--out', join(dir, 'o'), '--count', '0']);
    assert.equal(r.status, 2); assert.match(r.stderr, /--count must be an integer >= 1/);
    r = run(['--video', join(dir, 'none.mp4'), '--out', join(dir, 'o')]);
    assert.equal(r.status, 1); assert.match(r.stderr, /none\.mp4: no such file/);
    if (!modelsSkipReason() && spawnSync('ffprobe', ['-version']).status === 0) {
      r = run(['--video', tool, '--out', join(dir, 'o')]); // a JavaScript file is no video
      assert.equal(r.status, 1); assert.match(r.stderr, /not a readable video/);
    }
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('track_hands: frames 18..22 of the clip, one JSON line each, hands tracked after the first detection', { skip: clipSkipReason() || modelsSkipReason(), timeout: 120000 }, () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-track-'));
  try {
    const out = join(dir, 'hands.jsonl');
    const r = run(['--video', clipPath, '--out', out, '--first', '18', '--count', '5']);
    assert.equal(r.status, 0, r.stderr);
    const summary = JSON.parse(r.stderr.trim().split('\n').pop());
    assert.equal(summary.frames, 5);
    assert.equal(summary.model, 'lite');
    const lines = readFileSync(out, 'utf8').trim().split('\n').map((l) => JSON.parse(l));
    assert.deepEqual(lines.map((l) => l.frame), [18, 19, 20, 21, 22]);
    for (const l of lines) {
      assert.ok(l.hands.length >= 1 && l.hands.length <= 2, `frame ${l.frame}: ${l.hands.length} hands`);
      for (const h of l.hands) {
        assert.ok(['left', 'right'].includes(h.handedness));
        assert.equal(h.landmarks.length, 21); assert.equal(h.world.length, 21);
        assert.ok(h.landmarks.every((p) => p.length === 3 && p.every(Number.isFinite)));
        assert.ok(h.presence >= 0.5 && h.presence <= 1);
      }
    }
    // detection on the first frame, then tracking: fewer detector runs than frames
    assert.equal(lines[0].hands[0].source, 'detect');
    assert.ok(summary.palmRuns < 5, `detector ran ${summary.palmRuns} times on 5 frames`);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
