// task.mjs: one task of a batch: its share of a manifest's clips, each run by `hawor run` in a
// child process and published atomically into OUT/<clip id>/ with a status.json (docs/batch.md).
//
// A clip is run in a process of its own so that whatever one clip does (a decoder error, the
// WebAssembly core aborting, running out of memory) is that clip's failure, not the task's. Its
// outputs are written into OUT/.partial/<clip id>.<host>.<pid>/ and renamed to OUT/<clip id>/ once
// status.json is in it: a task killed mid-clip leaves only a .partial folder, which the next task
// that runs the clip removes. A clip whose status.json says ok or skipped (no hands) with the same
// run options is not run again; a failed one is (its cause may have been transient).

import { spawn } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, readdirSync, renameSync, rmSync, statSync, writeFileSync } from 'node:fs';
import { hostname } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { clipId, clipsOfTask, readManifest, unreadableClipId } from './manifest.mjs';

export const STATUS_FILE = 'status.json';
export const BATCH_FILE = 'batch.json';
export const PARTIAL_DIR = '.partial';
const CLI = fileURLToPath(new URL('../../cli.mjs', import.meta.url));
const VERSION = JSON.parse(readFileSync(new URL('../../../package.json', import.meta.url), 'utf8')).version;

/** The task's index and the number of tasks: given, else from Slurm's job array, else from a
 *  Kubernetes Indexed Job (JOB_COMPLETION_INDEX; the count must be given), else task 0 of 1.
 *  Slurm: with --tasks M the index is SLURM_ARRAY_TASK_ID itself (0-based elements; this is what
 *  lets a resubmission of some elements, `--array=3,7`, take the same shares); without it the
 *  array's span is the count (SLURM_ARRAY_TASK_MIN..MAX, so --array=1-8 works too). Slurm's own
 *  SLURM_ARRAY_TASK_COUNT counts the elements of the submission, not the shares. */
export function taskSlot(given, env = process.env) {
  const int = (v) => (v !== undefined && /^\d+$/.test(String(v).trim()) ? Number(v) : undefined);
  let index = given.index;
  let tasks = given.tasks;
  let from = 'given';
  let warning = null;
  if (index === undefined && int(env.SLURM_ARRAY_TASK_ID) !== undefined) {
    from = 'SLURM_ARRAY_TASK_ID';
    const id = int(env.SLURM_ARRAY_TASK_ID);
    if (tasks !== undefined) index = id;
    else {
      const min = int(env.SLURM_ARRAY_TASK_MIN) ?? 0;
      const max = int(env.SLURM_ARRAY_TASK_MAX) ?? id;
      index = id - min;
      tasks = max - min + 1;
      const count = int(env.SLURM_ARRAY_TASK_COUNT);
      if (count !== undefined && count < tasks) warning = `the job array has ${count} elements over indices ${min}..${max}: the shares of the missing indices are not run (give --tasks M and 0-based elements to run some shares again)`;
    }
  } else if (index === undefined && int(env.JOB_COMPLETION_INDEX) !== undefined) {
    index = int(env.JOB_COMPLETION_INDEX);
    from = 'JOB_COMPLETION_INDEX';
  }
  if (index === undefined) return { index: 0, tasks: tasks ?? 1, from: 'default' };
  if (tasks === undefined) throw Object.assign(new Error(`the task index comes from ${from} but the number of tasks is unknown: give --tasks M`), { exitCode: 2 });
  if (!(index >= 0 && index < tasks)) throw Object.assign(new Error(`task index ${index} (${from}) is outside 0..${tasks - 1} (--tasks ${tasks})`), { exitCode: 2 });
  return warning ? { index, tasks, from, warning } : { index, tasks, from };
}

/** The run options as compared between runs: the parsed `hawor run` options without the video,
 *  the output folder and where the networks run (--perception: the same result), keys sorted. */
export function canonicalOptions(parsed) {
  const { video, out, perception, ...rest } = parsed;
  return Object.fromEntries(Object.entries(rest).sort(([a], [b]) => (a < b ? -1 : 1)));
}

/** A clip folder's status.json, or null (none, or unreadable). */
export function readStatus(dir) {
  try {
    return JSON.parse(readFileSync(join(dir, STATUS_FILE), 'utf8'));
  } catch {
    return null;
  }
}

/** Writes a file through a temporary name and a rename (readers see the old or the new one). */
function writeAtomic(path, text) {
  const tmp = `${path}.${hostname()}.${process.pid}.tmp`;
  writeFileSync(tmp, text);
  renameSync(tmp, path);
}

/** Moves a finished clip folder into place: the old one (another run's) aside, then the rename. */
function publish(out, id, partial) {
  const dest = join(out, id);
  let old = null;
  if (existsSync(dest)) {
    old = join(out, PARTIAL_DIR, `${id}.old.${hostname()}.${process.pid}`);
    renameSync(dest, old);
  }
  renameSync(partial, dest);
  if (old) rmSync(old, { recursive: true, force: true });
}

/** Removes the .partial folders a killed run of this clip left behind. */
function clearPartials(out, id) {
  const dir = join(out, PARTIAL_DIR);
  for (const n of readdirSync(dir)) if (n.startsWith(`${id}.`)) rmSync(join(dir, n), { recursive: true, force: true });
}

/** The message of a failed `hawor run`: its last 'hawor: ...' line (warnings aside). */
function failureReason(stderr, code, signal) {
  const lines = stderr.split('\n').map((l) => l.trim()).filter((l) => l.startsWith('hawor: ') && !l.startsWith('hawor: warning'));
  const last = lines.length ? lines[lines.length - 1].slice('hawor: '.length) : null;
  if (signal) return `killed by ${signal}${signal === 'SIGKILL' ? ' (out of memory, or the clip timeout)' : ''}${last ? `: ${last}` : ''}`;
  return last ?? `hawor run exited with status ${code}: ${stderr.trim().split('\n').pop() || 'no message'}`;
}

/** Runs `hawor run SRC --out DIR RUNARGS` in a child process; resolves {code, signal, stdout,
 *  stderr, timedOut}. The child is killed when the task is (see runTask) or after timeoutS. */
function runClip(src, dir, runArgs, timeoutS, live) {
  return new Promise((resolvePromise) => {
    const child = spawn(process.execPath, [CLI, 'run', src, '--out', dir, ...runArgs], { stdio: ['ignore', 'pipe', 'pipe'] });
    live.child = child;
    let stdout = '';
    let stderr = '';
    child.stdout.on('data', (d) => { stdout += d; });
    child.stderr.on('data', (d) => { stderr += d; if (stderr.length > 1e6) stderr = stderr.slice(-5e5); });
    let timedOut = false;
    const timer = timeoutS > 0 ? setTimeout(() => { timedOut = true; child.kill('SIGKILL'); }, timeoutS * 1000) : null;
    child.on('error', (e) => { stderr += `\nhawor: cannot start ${process.execPath}: ${e.message}`; });
    child.on('close', (code, signal) => {
      if (timer) clearTimeout(timer);
      live.child = null;
      resolvePromise({ code, signal, stdout, stderr, timedOut });
    });
  });
}

/** Fails before any clip when OUT cannot be written (a read-only path, no permission): every
 *  clip would fail the same way, and their status.json could not be written there either. */
function prepareOut(out, clipCount) {
  try {
    mkdirSync(join(out, PARTIAL_DIR), { recursive: true });
    const probe = join(out, PARTIAL_DIR, `.probe.${hostname()}.${process.pid}`);
    writeFileSync(probe, '');
    rmSync(probe);
  } catch (e) {
    throw Object.assign(new Error(`${out}: the output folder cannot be written (${realCause(out, e)}); none of this task's ${clipCount} clips was run`), { exitCode: 1 });
  }
}

/** The error code of creating `path` itself: node's recursive mkdir says ENOENT for a parent on a
 *  read-only file system; creating the first missing folder by itself gives EROFS or EACCES. */
function realCause(path, e) {
  if (e.code !== 'ENOENT') return e.code ?? e.message;
  let p = resolve(path);
  while (!existsSync(dirname(p)) && dirname(p) !== p) p = dirname(p);
  try {
    mkdirSync(p);
    rmSync(p, { recursive: true });
    return e.code;
  } catch (e2) {
    return e2.code ?? e2.message;
  }
}

/**
 * Runs one task. o: { manifest, out, runArgs: [strings], options: canonical run options, index,
 * tasks, force, clipTimeoutS, log(line) }. Returns { clips, ok, skipped, failed, done, seconds }.
 */
export async function runTask(o) {
  const t0 = performance.now();
  const m = readManifest(o.manifest);
  const mine = clipsOfTask(m.clips, o.index, o.tasks);
  prepareOut(o.out, mine.length);
  // the batch as a whole, for `hawor batch --summary` (every task writes the same content)
  writeAtomic(join(o.out, BATCH_FILE), `${JSON.stringify({
    manifest: m.source, clips: m.clips.map((c) => ({ line: c.line, path: c.path })), duplicates: m.duplicates,
    options: o.options, runArgs: o.runArgs, tasks: o.tasks, hawor: VERSION,
  }, null, 1)}\n`);
  if (o.index === 0) for (const d of m.duplicates) o.log(`line ${d.line}: ${d.path} is a duplicate of line ${d.firstLine} (run once)`);

  // SIGTERM/SIGINT (scancel, a pod's termination): the running clip is killed, its .partial
  // folder removed, and the task exits with 128 + the signal's number.
  const live = { child: null, partial: null };
  const onSignal = (sig) => {
    if (live.child) live.child.kill('SIGKILL');
    if (live.partial) rmSync(live.partial, { recursive: true, force: true });
    o.log(`stopped by ${sig}`);
    process.exit(sig === 'SIGINT' ? 130 : 143);
  };
  process.on('SIGTERM', onSignal);
  process.on('SIGINT', onSignal);

  const tally = { clips: mine.length, ok: 0, skipped: 0, failed: 0, done: 0 };
  try {
    for (let k = 0; k < mine.length; ++k) {
      const c = mine[k];
      const tag = `[task ${o.index}/${o.tasks}] ${k + 1}/${mine.length}`;
      let r;
      try {
        r = await processClip(c, o, live);
      } catch (e) {
        // the task's own failure on this clip (a full disk, a folder renamed under it): the clip
        // counts as failed, its partial output goes, the next clip runs
        if (live.partial) rmSync(live.partial, { recursive: true, force: true });
        live.partial = null;
        r = { id: c.path, status: 'failed', reason: `could not be written: ${e.message}`, counted: 'failed' };
      }
      tally[r.counted] += 1;
      o.log(`${tag} ${r.id}: ${r.counted === 'done' ? 'done already' : r.status}${r.reason ? ` (${r.reason})` : ''}${r.seconds !== undefined ? `, ${r.seconds.toFixed(1)} s` : ''}`);
    }
  } finally {
    process.off('SIGTERM', onSignal);
    process.off('SIGINT', onSignal);
  }
  return { ...tally, seconds: (performance.now() - t0) / 1000 };
}

/** The engine's ids of this task, when it runs under one (for finding its log). */
function engineIds(env = process.env) {
  if (env.SLURM_JOB_ID) return { slurm: { jobId: env.SLURM_JOB_ID, arrayJobId: env.SLURM_ARRAY_JOB_ID ?? null, arrayTaskId: env.SLURM_ARRAY_TASK_ID ?? null } };
  if (env.JOB_COMPLETION_INDEX !== undefined) return { kubernetes: { pod: env.HOSTNAME ?? null, completionIndex: env.JOB_COMPLETION_INDEX } };
  return {};
}

/** One clip: its id, the check against an earlier status, the run, status.json, the publish. */
async function processClip(c, o, live) {
  const started = new Date();
  const base = { source: c.path, manifestLine: c.line, options: o.options, runArgs: o.runArgs, hawor: VERSION,
    task: { index: o.index, tasks: o.tasks, host: hostname(), ...engineIds() } };
  let id;
  let unreadable = null;
  try {
    const st = statSync(c.path);
    if (!st.isFile()) unreadable = `${c.path}: not a file`;
    else id = clipId(c.path);
  } catch (e) {
    unreadable = e.code === 'ENOENT' ? `${c.path}: no such file` : `${c.path}: cannot be read (${e.code ?? e.message})`;
  }
  if (unreadable) id = unreadableClipId(c.path);
  const dest = join(o.out, id);
  const prev = readStatus(dest);
  if (!unreadable && !o.force && prev && (prev.status === 'ok' || prev.status === 'skipped') && JSON.stringify(prev.options) === JSON.stringify(o.options)) {
    return { id, status: prev.status, counted: 'done' };
  }
  clearPartials(o.out, id);
  const partial = join(o.out, PARTIAL_DIR, `${id}.${hostname()}.${process.pid}`);
  mkdirSync(partial, { recursive: true });
  live.partial = partial;
  const t0 = performance.now();
  let status;
  let reason = null;
  let result = null;
  let log = '';
  if (unreadable) {
    status = 'failed';
    reason = unreadable;
  } else {
    const r = await runClip(c.path, partial, o.runArgs, o.clipTimeoutS, live);
    log = r.stderr;
    try { result = JSON.parse(r.stdout.trim().split('\n').pop()); } catch { result = null; }
    if (r.code === 0 && result) {
      status = result.noHands ? 'skipped' : 'ok';
      if (result.noHands) reason = 'no hands found';
      if (result.out) delete result.out;
    } else {
      status = 'failed';
      reason = r.timedOut ? `no result within the clip timeout (${o.clipTimeoutS} s)` : failureReason(r.stderr, r.code, r.signal);
      // a failed clip keeps only its log and status: no partial outputs beside them
      for (const n of readdirSync(partial)) rmSync(join(partial, n), { recursive: true, force: true });
    }
  }
  const seconds = (performance.now() - t0) / 1000;
  writeFileSync(join(partial, 'log.txt'), log);
  writeFileSync(join(partial, STATUS_FILE), `${JSON.stringify({
    clip: id, status, ...(reason ? { reason } : {}), ...base, startedAt: started.toISOString(), finishedAt: new Date().toISOString(),
    seconds: Number(seconds.toFixed(3)), result,
  }, null, 1)}\n`);
  publish(o.out, id, partial);
  live.partial = null;
  return { id, status, reason, seconds, counted: status };
}
