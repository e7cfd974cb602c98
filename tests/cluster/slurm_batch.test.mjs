// hawor batch on a real Slurm: a single-node cluster on localhost (tests/cluster/slurm_local.sh:
// Debian's munge, slurmctld and slurmd, a slurm.conf of the test's own), the job-array script
// deploy/slurm/hawor_batch.sbatch over three clips (two `hawor synth` sequences, one truncated),
// an element cancelled with scancel while its clip runs, then the array resubmitted: the clips'
// outputs, the failure's message, the summary, and that finished clips are not run again.
// Skipped with the reason when Slurm is not installed (`bash tests/cluster/slurm_local.sh install`,
// which the suite's cluster stage runs), cannot start here (slurm_local.sh exits 77), or the
// builds it needs are missing.

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, readdirSync, rmSync, statSync, truncateSync, writeFileSync, copyFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const harness = join(root, 'tests/cluster/slurm_local.sh');
const sbatchScript = join(root, 'deploy/slurm/hawor_batch.sbatch');
const corePath = process.env.HAWOR_CORE ?? join(root, 'build/wasm/wasm/hawor_core.mjs');
const haworBin = process.env.HAWOR_BIN ?? join(root, 'build/native/examples/hawor');
const PATH = `${process.env.PATH}:/usr/sbin:/sbin`;
const has = (cmd) => spawnSync('bash', ['-c', `command -v ${cmd}`], { env: { ...process.env, PATH } }).status === 0;

let work = null;
let env = null;
let skip = false;

function skipReason() {
  if (!['sbatch', 'slurmctld', 'slurmd', 'munged'].every(has)) return 'Slurm is not installed (bash tests/cluster/slurm_local.sh install: slurmctld, slurmd, slurm-client and munge)';
  if (!existsSync(corePath)) return `${corePath} missing (cmake --build build/wasm --target hawor_core)`;
  if (!existsSync(haworBin)) return `${haworBin} missing (the native hawor CLI makes the clips)`;
  if (!['palm_detection_lite.onnx', 'hand_landmark_lite.onnx'].every((n) => existsSync(join(root, 'web/models', n)))) return 'web/models: the hand networks are missing (scripts/install.sh converts them)';
  return false;
}

before(() => {
  skip = skipReason();
  if (skip) return;
  work = mkdtempSync(join(tmpdir(), 'hawor-slurm-'));
  const r = spawnSync('bash', [harness, 'start', join(work, 'slurm')], { encoding: 'utf8', env: { ...process.env, PATH }, timeout: 90000 });
  if (r.status !== 0) {
    skip = r.status === 77 ? `Slurm cannot start here: ${r.stderr.trim().split('\n').filter((l) => l.includes('cannot start')).pop() ?? r.stderr.trim()}` : null;
    if (!skip) throw new Error(`slurm_local.sh start failed (${r.status}): ${r.stderr}`);
    return;
  }
  // `export NAME=value` lines: the client commands' environment
  env = { ...process.env, PATH, HAWOR_CORE: corePath, HAWOR_CLI: `${process.execPath} ${join(root, 'web/cli.mjs')}` };
  for (const m of r.stdout.matchAll(/^export (\w+)=(.*)$/gm)) env[m[1]] = m[2].replace(/^'(.*)'$/, '$1').replace(/^"(.*)"$/, '$1');
});

after(() => {
  if (work) {
    spawnSync('bash', [harness, 'stop', join(work, 'slurm')], { env: { ...process.env, PATH }, timeout: 60000 });
    rmSync(work, { recursive: true, force: true });
  }
});

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const slurm = (cmd, args) => execFileSync(cmd, args, { encoding: 'utf8', env, timeout: 30000 }).trim();

/** Waits until no element of the job is pending or running (bounded). */
async function waitJob(jobId, seconds = 240) {
  for (let i = 0; i < seconds * 5; ++i) {
    if (!slurm('squeue', ['-h', '-j', jobId, '-o', '%i %T'])) return;
    await sleep(200);
  }
  throw new Error(`job ${jobId} still in the queue after ${seconds} s: ${slurm('squeue', ['-j', jobId])}`);
}

/** The state of job array element JOB_I, as slurmctld remembers it (MinJobAge keeps it). */
const elementState = (id) => /JobState=(\w+)/.exec(slurm('scontrol', ['show', 'job', id]))?.[1];

test('hawor batch as a Slurm job array: outputs, a corrupt clip, scancel mid-clip, resubmission', { timeout: 600000 }, async (t) => {
  if (skip) { t.skip(skip); return; }
  const { makeSequence } = await import('../../examples/bench_pipeline.mjs');
  const clips = join(work, 'clips');
  mkdirSync(clips);
  const seqs = [1, 2].map((seed) => makeSequence(haworBin, 'table_work', seed, 40, '320x240', join(work, `seq${seed}`)));
  copyFileSync(join(seqs[0].dir, 'video.mp4'), join(clips, 'first.mp4'));
  copyFileSync(join(seqs[1].dir, 'video.mp4'), join(clips, 'second.mp4'));
  copyFileSync(join(seqs[0].dir, 'video.mp4'), join(clips, 'corrupt.mp4'));
  truncateSync(join(clips, 'corrupt.mp4'), Math.floor(statSync(join(clips, 'corrupt.mp4')).size / 3));
  // clip i to element i mod 2: first + corrupt to element 0, second to element 1
  writeFileSync(join(work, 'manifest.txt'), 'clips/first.mp4\nclips/second.mp4\nclips/corrupt.mp4\n');
  const out = join(work, 'out');
  const submit = () => slurm('sbatch', ['--parsable', '--array=0-1', '--cpus-per-task=1', '--mem=1500M', `--chdir=${work}`,
    '--output=slurm-%A_%a.log', sbatchScript, join(work, 'manifest.txt'), out, '--focal', String(seqs[0].fx)]).split(';')[0];

  // 1. submit; cancel element 1 while its clip runs (its .partial folder exists)
  const job = submit();
  let cancelled = false;
  for (let i = 0; i < 1200 && !cancelled; ++i) {
    const partial = join(out, '.partial');
    if (existsSync(partial) && readdirSync(partial).some((n) => n.startsWith('second-'))) {
      slurm('scancel', [`${job}_1`]);
      cancelled = true;
    } else await sleep(100);
  }
  assert.ok(cancelled, 'element 1 never started its clip');
  await waitJob(job);
  assert.equal(elementState(`${job}_1`), 'CANCELLED');
  assert.equal(elementState(`${job}_0`), 'FAILED', 'element 0 exits 1: one of its clips (the corrupt one) failed');
  const folders = () => Object.fromEntries(readdirSync(out).filter((n) => !n.startsWith('.') && n !== 'batch.json').map((n) => [n.split('-')[0], n]));
  let ids = folders();
  assert.deepEqual(Object.keys(ids).sort(), ['corrupt', 'first'], 'the cancelled clip has no folder');
  const first = JSON.parse(readFileSync(join(out, ids.first, 'status.json'), 'utf8'));
  assert.equal(first.status, 'ok');
  assert.deepEqual([first.task.slurm.arrayJobId, first.task.slurm.arrayTaskId, first.task.index, first.task.tasks], [job, '0', 0, 2]);
  const s1 = JSON.parse(slurm(process.execPath, [join(root, 'web/cli.mjs'), 'batch', '--summary', out, '--json']));
  assert.deepEqual([s1.clips, s1.ok, s1.failed, s1.pending], [3, 1, 1, 1]);

  // 2. resubmit the same array: element 1 runs its clip, element 0 skips the finished one and
  // retries the corrupt one
  const job2 = submit();
  await waitJob(job2);
  ids = folders();
  assert.deepEqual(Object.keys(ids).sort(), ['corrupt', 'first', 'second']);
  assert.equal(JSON.parse(readFileSync(join(out, ids.first, 'status.json'), 'utf8')).finishedAt, first.finishedAt, 'the finished clip was not run again');
  for (const k of ['first', 'second']) {
    const st = JSON.parse(readFileSync(join(out, ids[k], 'status.json'), 'utf8'));
    assert.equal(st.status, 'ok', `${k}: ${st.reason}`);
    assert.ok(st.result.frames === 40 && st.result.rightFrames + st.result.leftFrames > 0, JSON.stringify(st.result));
    for (const f of ['world.npz', 'hands_cam.npz', 'camera.tum', 'result.json']) assert.ok(existsSync(join(out, ids[k], f)), `${k}/${f}`);
  }
  const bad = JSON.parse(readFileSync(join(out, ids.corrupt, 'status.json'), 'utf8'));
  assert.equal(bad.status, 'failed');
  assert.match(bad.reason, /corrupt\.mp4: (cannot be decoded|not a readable video)/);
  const log0 = readFileSync(join(work, `slurm-${job2}_0.log`), 'utf8');
  assert.match(log0, /first-\w+: done already/);
  const text = slurm(process.execPath, [join(root, 'web/cli.mjs'), 'batch', '--summary', out]);
  assert.match(text, /3 clips .*: 2 ok, 1 failed, 0 skipped \(no hands\), 0 not done/);
  assert.match(text, /corrupt-\w+ \(.*corrupt\.mp4\): .*corrupt\.mp4/);
  assert.deepEqual(readdirSync(join(out, '.partial')), [], 'the cancelled element\'s .partial was cleared by the rerun');
});
