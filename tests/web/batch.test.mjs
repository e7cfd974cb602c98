// The batch run (web/src/batch, `hawor batch`): the manifest and clip ids against independent
// references (python's hashlib for the sampled hash), the task slot from Slurm's and Kubernetes'
// variables, usage errors, and a corpus end to end: a `hawor synth` clip with hands, one without
// (ffmpeg's test pattern), a truncated one, a missing one and a duplicate line, over two tasks;
// the summary; a rerun that runs nothing; other options that rerun; a task killed mid-clip (no
// half-written clip folder, the rerun completes); an output folder on a read-only file system.
// Parts that need the WebAssembly core, the native CLI (it makes the clip), ffmpeg or python are
// skipped with a message when those are missing.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawn, spawnSync } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, readdirSync, rmSync, statSync, writeFileSync, copyFileSync, truncateSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { root, modelsSkipReason } from './mediapipe_support.mjs';
import { rng } from './support.mjs';
import { clipId, clipStem, clipsOfTask, contentHash, readManifest } from '../../web/src/batch/manifest.mjs';
import { taskSlot } from '../../web/src/batch/task.mjs';
import { parseArgs } from '../../web/cli.mjs';

const corePath = process.env.HAWOR_CORE ?? join(root, 'build/wasm/wasm/hawor_core.mjs');
const haworBin = process.env.HAWOR_BIN ?? join(root, 'build/native/examples/hawor');
const cli = join(root, 'web/cli.mjs');
const python = '/usr/bin/python3';
const hasFfmpeg = spawnSync('ffmpeg', ['-version'], { stdio: 'ignore' }).status === 0;
const skipOf = (...reasons) => reasons.map((r) => r()).find((r) => r) || false;
const coreSkip = () => (existsSync(corePath) ? false : `${corePath} missing (cmake --build build/wasm --target hawor_core)`);
const ffmpegSkip = () => (hasFfmpeg ? false : 'ffmpeg is not installed');
const synthSkip = () => (existsSync(haworBin) ? false : `${haworBin} missing (the native hawor CLI makes the clip)`);
const pythonSkip = () => (existsSync(python) ? false : `${python} missing (the hash reference)`);

function batch(args, timeout = 240000) {
  return spawnSync(process.execPath, [cli, 'batch', ...args], { encoding: 'utf8', timeout, env: { ...process.env, HAWOR_CORE: corePath } });
}
const status = (out, id) => JSON.parse(readFileSync(join(out, id, 'status.json'), 'utf8'));

test('readManifest: comments, blank lines, relative paths, duplicates; a folder; bad manifests', () => {
  const dir = mkdtempSync(join(tmpdir(), 'hawor-manifest-'));
  try {
    mkdirSync(join(dir, 'v', 'sub'), { recursive: true });
    for (const f of ['v/b.mp4', 'v/a.MOV', 'v/sub/c.webm', 'v/notes.txt', 'v/.hidden.mp4']) writeFileSync(join(dir, f), f);
    writeFileSync(join(dir, 'list.txt'), `# corpus\n\nv/b.mp4\r\n  v/a.MOV  \n${join(dir, 'v/b.mp4')}\n# v/x.mp4\nv/sub/../b.mp4\nmissing.mp4\n`);
    const m = readManifest(join(dir, 'list.txt'));
    assert.deepEqual(m.clips.map((c) => [c.line, c.path]), [[3, join(dir, 'v/b.mp4')], [4, join(dir, 'v/a.MOV')], [8, join(dir, 'missing.mp4')]]);
    assert.deepEqual(m.duplicates.map((d) => [d.line, d.firstLine]), [[5, 3], [7, 3]]);
    const f = readManifest(join(dir, 'v'));
    assert.deepEqual(f.clips.map((c) => c.path), ['v/a.MOV', 'v/b.mp4', 'v/sub/c.webm'].map((p) => join(dir, p)));
    assert.deepEqual(clipsOfTask([0, 1, 2, 3, 4, 5, 6], 1, 3), [1, 4]);
    writeFileSync(join(dir, 'empty.txt'), '# nothing\n\n');
    assert.throws(() => readManifest(join(dir, 'empty.txt')), /lists no clip/);
    writeFileSync(join(dir, 'video.mp4'), Buffer.from([0, 0, 0, 24, 102, 116, 121, 112]));
    assert.throws(() => readManifest(join(dir, 'video.mp4')), /not a text manifest/);
    assert.throws(() => readManifest(join(dir, 'nope.txt')), /no such manifest/);
    mkdirSync(join(dir, 'novideo'));
    assert.throws(() => readManifest(join(dir, 'novideo')), /no videos in this folder/);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('clip ids: the stem made safe, the sampled content hash against python hashlib', { skip: pythonSkip() }, () => {
  assert.equal(clipStem('/x/My clip (1).final.mp4'), 'My_clip__1_.final');
  assert.equal(clipStem('/x/.mp4'), '_mp4');
  assert.equal(clipStem(`/x/${'a'.repeat(100)}.mp4`).length, 60);
  const dir = mkdtempSync(join(tmpdir(), 'hawor-clipid-'));
  try {
    const r = rng(7);
    const sizes = [0, 1000, 3 << 20, (3 << 20) + 1, 5_000_000];
    for (const n of sizes) {
      const buf = Buffer.alloc(n);
      for (let i = 0; i < n; i += 4096) buf[i] = Math.floor(256 * r());
      writeFileSync(join(dir, `f${n}.bin`), buf);
    }
    // the reference: sha256 of "<size>\n" then the whole file (<= 3 MiB) or the 1 MiB windows at
    // 0, size/2 - 512 KiB and size - 1 MiB
    const ref = execFileSync(python, ['-c', `
import hashlib, os, sys
W = 1 << 20
for p in sys.argv[1:]:
    n = os.path.getsize(p); h = hashlib.sha256(f"{n}\\n".encode())
    with open(p, 'rb') as f:
        if n <= 3 * W: h.update(f.read())
        else:
            for s in (0, n // 2 - W // 2, n - W): f.seek(s); h.update(f.read(W))
    print(h.hexdigest()[:10])
`, ...sizes.map((n) => join(dir, `f${n}.bin`))], { encoding: 'utf8' }).trim().split('\n');
    assert.deepEqual(sizes.map((n) => contentHash(join(dir, `f${n}.bin`))), ref);
    // same name, other content: other ids; same content under another name: another id
    mkdirSync(join(dir, 'a')); mkdirSync(join(dir, 'b'));
    writeFileSync(join(dir, 'a', 'video.mp4'), 'one');
    writeFileSync(join(dir, 'b', 'video.mp4'), 'two');
    copyFileSync(join(dir, 'a', 'video.mp4'), join(dir, 'b', 'renamed.mp4'));
    const ids = ['a/video.mp4', 'b/video.mp4', 'b/renamed.mp4'].map((p) => clipId(join(dir, p)));
    assert.equal(new Set(ids).size, 3);
    assert.equal(ids[2].split('-').pop(), ids[0].split('-').pop());
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('taskSlot: given, Slurm job arrays (offset, count), Kubernetes indexed jobs, errors', () => {
  assert.deepEqual(taskSlot({}, {}), { index: 0, tasks: 1, from: 'default' });
  assert.deepEqual(taskSlot({ index: 2, tasks: 3 }, { SLURM_ARRAY_TASK_ID: '0' }), { index: 2, tasks: 3, from: 'given' });
  // --array=10-13: the span is the count
  assert.deepEqual(taskSlot({}, { SLURM_ARRAY_TASK_ID: '12', SLURM_ARRAY_TASK_MIN: '10', SLURM_ARRAY_TASK_MAX: '13', SLURM_ARRAY_TASK_COUNT: '4' }), { index: 2, tasks: 4, from: 'SLURM_ARRAY_TASK_ID' });
  // a resubmission of elements 1 and 3 of an array of 5 (Slurm then says COUNT=2, MIN=1, MAX=3):
  // with --tasks the element is the share; without, a warning names the shares not run
  const resub = { SLURM_ARRAY_TASK_ID: '3', SLURM_ARRAY_TASK_MIN: '1', SLURM_ARRAY_TASK_MAX: '3', SLURM_ARRAY_TASK_COUNT: '2' };
  assert.deepEqual(taskSlot({ tasks: 5 }, resub), { index: 3, tasks: 5, from: 'SLURM_ARRAY_TASK_ID' });
  assert.match(taskSlot({}, resub).warning, /2 elements over indices 1\.\.3/);
  assert.throws(() => taskSlot({ tasks: 4 }, { SLURM_ARRAY_TASK_ID: '4' }), /outside 0\.\.3/);
  assert.deepEqual(taskSlot({ tasks: 8 }, { JOB_COMPLETION_INDEX: '7' }), { index: 7, tasks: 8, from: 'JOB_COMPLETION_INDEX' });
  assert.throws(() => taskSlot({}, { JOB_COMPLETION_INDEX: '1' }), /give --tasks/);
  assert.throws(() => taskSlot({ tasks: 2 }, { JOB_COMPLETION_INDEX: '2' }), /outside 0\.\.1/);
});

test('hawor batch usage errors name the problem (exit code 2)', () => {
  const bad = (args, re) => {
    const e = (() => { try { parseArgs(['batch', ...args]); } catch (x) { return x; } return null; })();
    assert.ok(e, `${args.join(' ')}: no error`);
    assert.equal(e.exitCode, 2);
    assert.match(e.message, re);
  };
  bad([], /missing MANIFEST/);
  bad(['m.txt'], /--out DIR is required/);
  bad(['m.txt', '--out', 'o', '--focal', 'x'], /run option: --focal must be a number/);
  bad(['m.txt', '--out', 'o', '--sample'], /--sample is not a batch option/);
  bad(['m.txt', '--out', 'o', '--tasks', '0'], /--tasks must be an integer >= 1/);
  bad(['m.txt', '--out', 'o', '--task-index', '3', '--tasks', '3'], /must be below --tasks/);
  bad(['m.txt', '--out', 'o', 'extra.mp4'], /unexpected argument/);
  bad(['--summary'], /needs the batch's output folder/);
  const o = parseArgs(['batch', 'm.txt', '--out', 'o', '--fov', '90', '--threads', '1']);
  assert.deepEqual(o.options, { fovDeg: 90, infill: 'spline', model: 'lite', threads: 1 });
});

test('hawor batch end to end: two tasks, failures per clip, summary, rerun, kill mid-clip, read-only output', { skip: skipOf(coreSkip, ffmpegSkip, modelsSkipReason, synthSkip), timeout: 400000 }, async (t) => {
  const { makeSequence } = await import('../../examples/bench_pipeline.mjs');
  const dir = mkdtempSync(join(tmpdir(), 'hawor-batch-'));
  try {
    const seq = makeSequence(haworBin, 'table_work', 1, 12, '320x240', join(dir, 'seq'));
    const clips = join(dir, 'clips');
    mkdirSync(clips);
    copyFileSync(join(seq.dir, 'video.mp4'), join(clips, 'hands.mp4'));
    execFileSync('ffmpeg', ['-v', 'error', '-y', '-f', 'lavfi', '-i', 'testsrc=size=320x240:rate=30', '-frames:v', '8', '-pix_fmt', 'yuv420p', join(clips, 'pattern.mp4')]);
    copyFileSync(join(clips, 'hands.mp4'), join(clips, 'broken.mp4'));
    truncateSync(join(clips, 'broken.mp4'), Math.floor(statSync(join(clips, 'broken.mp4')).size / 3));
    writeFileSync(join(dir, 'clips.txt'), 'clips/hands.mp4\nclips/pattern.mp4\nclips/broken.mp4\nclips/gone.mp4\nclips/hands.mp4\n');
    const out = join(dir, 'out');
    const run = ['--focal', String(seq.fx), '--threads', '1'];
    // clip i goes to task i mod 2: hands + broken to task 0, pattern + gone to task 1
    const t0 = batch([join(dir, 'clips.txt'), '--out', out, '--task-index', '0', '--tasks', '2', ...run]);
    assert.equal(t0.status, 1, t0.stderr); // a clip failed (the others ran)
    assert.match(t0.stderr, /line 5: .*hands\.mp4 is a duplicate of line 1/);
    // without --task-index: the slot from Slurm's variables
    const t1s = spawnSync(process.execPath, [cli, 'batch', join(dir, 'clips.txt'), '--out', out, ...run], { encoding: 'utf8', timeout: 240000, env: { ...process.env, HAWOR_CORE: corePath, SLURM_ARRAY_TASK_ID: '1', SLURM_ARRAY_TASK_MIN: '0', SLURM_ARRAY_TASK_MAX: '1', SLURM_ARRAY_TASK_COUNT: '2' } });
    assert.equal(t1s.status, 1, t1s.stderr);
    assert.deepEqual(JSON.parse(t1s.stdout), { out, task: 1, tasks: 2, clips: 2, ok: 0, skipped: 1, failed: 1, done: 0, seconds: JSON.parse(t1s.stdout).seconds });
    const ids = Object.fromEntries(readdirSync(out).filter((n) => !n.startsWith('.') && n !== 'batch.json').map((n) => [n.split('-')[0], n]));
    assert.deepEqual(Object.keys(ids).sort(), ['broken', 'gone', 'hands', 'pattern']);
    const hands = status(out, ids.hands);
    assert.equal(hands.status, 'ok');
    assert.equal(hands.source, join(clips, 'hands.mp4'));
    assert.deepEqual(hands.options, { focalPx: seq.fx, infill: 'spline', model: 'lite', threads: 1 });
    for (const f of ['world.npz', 'hands_cam.npz', 'camera.tum', 'result.json', 'log.txt']) assert.ok(existsSync(join(out, ids.hands, f)), f);
    assert.ok(hands.result.frames === 12 && hands.result.rightFrames + hands.result.leftFrames > 0, JSON.stringify(hands.result));
    const pattern = status(out, ids.pattern);
    assert.equal(pattern.status, 'skipped');
    assert.equal(pattern.reason, 'no hands found');
    const broken = status(out, ids.broken);
    assert.equal(broken.status, 'failed');
    assert.match(broken.reason, /broken\.mp4/);
    assert.deepEqual(readdirSync(join(out, ids.broken)).sort(), ['log.txt', 'status.json']);
    assert.match(status(out, ids.gone).reason, /gone\.mp4: no such file/);
    // the summary, as text and JSON
    const s = batch(['--summary', out, '--json']);
    assert.equal(s.status, 0, s.stderr);
    const sj = JSON.parse(s.stdout);
    assert.deepEqual([sj.clips, sj.ok, sj.skipped, sj.failed, sj.pending, sj.duplicates.length, sj.partial], [4, 1, 1, 2, 0, 1, 0]);
    assert.deepEqual(sj.failures.map((x) => x.clip).sort(), [ids.broken, ids.gone].sort());
    const st = batch(['--summary', out]);
    assert.match(st.stdout, /4 clips .*: 1 ok, 2 failed, 1 skipped \(no hands\), 0 not done/);
    assert.match(st.stdout, /gone\.mp4: no such file/);

    // a rerun with the same options runs nothing that is done (the failed ones again)
    const before = status(out, ids.hands).finishedAt;
    const again = batch([join(dir, 'clips.txt'), '--out', out, ...run]);
    assert.equal(JSON.parse(again.stdout).done, 2, again.stderr);
    assert.equal(status(out, ids.hands).finishedAt, before);
    // other options: the summary counts the old results as not done; a rerun redoes them
    writeFileSync(join(dir, 'one.txt'), 'clips/hands.mp4\n');
    const other = batch([join(dir, 'one.txt'), '--out', out, ...run, '--max-frames', '6']);
    assert.equal(other.status, 0, other.stderr);
    assert.equal(status(out, ids.hands).result.frames, 6);

    // a task killed mid-clip (SIGKILL to its process group, as a node failure would): the clip's
    // folder keeps the earlier complete result, the .partial is cleared by the rerun
    const killed = spawn(process.execPath, [cli, 'batch', join(dir, 'one.txt'), '--out', out, ...run, '--force'], { detached: true, stdio: 'ignore', env: { ...process.env, HAWOR_CORE: corePath } });
    const partialDir = join(out, '.partial');
    for (let i = 0; i < 600 && !readdirSync(partialDir).some((n) => n.startsWith(ids.hands)); ++i) await new Promise((r) => setTimeout(r, 50));
    await new Promise((r) => setTimeout(r, 300));
    process.kill(-killed.pid, 'SIGKILL');
    await new Promise((r) => killed.on('close', r));
    assert.ok(readdirSync(partialDir).some((n) => n.startsWith(ids.hands)), 'a .partial folder is left by the killed task');
    assert.equal(status(out, ids.hands).result.frames, 6, 'the published folder is the earlier, complete one');
    assert.match(batch(['--summary', out]).stdout, /1 clip\(s\) in progress or left by a killed task/);
    const resumed = batch([join(dir, 'one.txt'), '--out', out, ...run]);
    assert.equal(resumed.status, 0, resumed.stderr);
    assert.equal(JSON.parse(resumed.stdout).ok, 1);
    assert.equal(status(out, ids.hands).result.frames, 12);
    assert.deepEqual(readdirSync(partialDir), []);

    // a read-only output folder: one clear error before any clip runs
    const ro = join(dir, 'ro');
    mkdirSync(ro);
    const mounted = spawnSync('mount', ['-t', 'tmpfs', '-o', 'ro,size=1m', 'tmpfs', ro]).status === 0;
    if (!mounted && process.getuid?.() === 0) {
      t.diagnostic('read-only check skipped: cannot mount a read-only tmpfs here, and root writes through permissions');
    } else {
      try {
        if (!mounted) spawnSync('chmod', ['0555', ro]);
        const r = batch([join(dir, 'clips.txt'), '--out', join(ro, 'out'), ...run]);
        assert.equal(r.status, 1);
        assert.match(r.stderr, /the output folder cannot be written \((EROFS|EACCES)\); none of this task's 4 clips was run/);
      } finally {
        if (mounted) spawnSync('umount', [ro]);
      }
    }
    // a full disk (a 32 KB tmpfs): each clip fails with the reason, the next still runs, nothing
    // half-written is left
    const full = join(dir, 'full');
    mkdirSync(full);
    if (spawnSync('mount', ['-t', 'tmpfs', '-o', 'size=32k', 'tmpfs', full]).status === 0) {
      try {
        const r = batch([join(dir, 'clips.txt'), '--out', full, ...run]);
        assert.equal(r.status, 1, r.stderr);
        const j = JSON.parse(r.stdout);
        assert.equal(j.failed + j.skipped + j.ok, 4, r.stdout);
        assert.ok(j.failed >= 3, r.stdout); // the clip with hands and the two unreadable ones at least
        assert.match(r.stderr, /ENOSPC|no space/i);
        assert.match(r.stderr, /4\/4 /, 'the last clip was reached');
        assert.deepEqual(readdirSync(join(full, '.partial')).filter((n) => !n.startsWith('.probe')), []);
      } finally {
        spawnSync('umount', [full]);
      }
    } else {
      t.diagnostic('full-disk check skipped: cannot mount a tmpfs here');
    }
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
