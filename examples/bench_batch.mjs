#!/usr/bin/env node
// bench_batch.mjs: what the batch path costs over a single `hawor run`, the memory a task needs,
// and the throughput of an array on this machine (docs/batch.md).
//
//   node examples/bench_batch.mjs [--video V] [--seconds 10] [--repeats 3] [--long 60]
//                                 [--throughput] [--work DIR] [--threads 2]
//
// 1. Overhead: `hawor run V` and `hawor batch` over a manifest of V, alternated --repeats times on
//    the same clip (default: the shared kitchen clip looped to --seconds at 1080p), wall time each;
//    the overhead is median(batch) / median(run) - 1.
// 2. Memory: one `hawor batch` task on a --long second 1080p clip; the peak resident memory of the
//    task's whole process tree (node, the clip's child, ffmpeg), sampled from /proc every 100 ms,
//    and its wall time per clip.
// 3. --throughput: two tasks at once (an array of 2 on this 2-core machine, --threads 1 each)
//    over two copies of the long clip; clips per hour = clips / wall time.
// Prints a table on stderr and one JSON line on stdout.

import { execFileSync, spawn } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, readdirSync, rmSync, writeFileSync, copyFileSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const repo = resolve(dirname(fileURLToPath(import.meta.url)), '..');
const cli = join(repo, 'web', 'cli.mjs');

function parse(argv) {
  const o = { seconds: 10, repeats: 3, long: 60, throughput: false, work: '/tmp/hawor_bench_batch', threads: 2 };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    const v = () => argv[++i];
    if (a === '--video') o.video = v();
    else if (a === '--seconds') o.seconds = Number(v());
    else if (a === '--repeats') o.repeats = Number(v());
    else if (a === '--long') o.long = Number(v());
    else if (a === '--throughput') o.throughput = true;
    else if (a === '--work') o.work = v();
    else if (a === '--threads') o.threads = Number(v());
    else throw new Error(`unknown option ${a}`);
  }
  return o;
}

/** The kitchen clip looped to `seconds` at 1080p 30 fps (H.264, as a phone writes it). */
function loopedClip(work, seconds) {
  const out = join(work, `kitchen_${seconds}s.mp4`);
  if (!existsSync(out)) {
    const src = resolve(repo, '../shared/data/egocentric_kitchen.mp4');
    execFileSync('ffmpeg', ['-v', 'error', '-y', '-stream_loop', '-1', '-i', src, '-t', String(seconds), '-an', '-vf', 'scale=1920:1080,fps=30',
      '-c:v', 'libx264', '-preset', 'veryfast', '-crf', '20', '-pix_fmt', 'yuv420p', out]);
  }
  return out;
}

/** Sum of VmRSS (kB) over pid and its descendants, from /proc. */
function treeRssKb(pid) {
  const kids = new Map();
  for (const d of readdirSync('/proc')) {
    if (!/^\d+$/.test(d)) continue;
    try {
      const st = readFileSync(`/proc/${d}/stat`, 'utf8');
      const ppid = Number(st.slice(st.lastIndexOf(')') + 2).split(' ')[1]);
      if (!kids.has(ppid)) kids.set(ppid, []);
      kids.get(ppid).push(Number(d));
    } catch { /* gone */ }
  }
  let kb = 0;
  const stack = [pid];
  while (stack.length) {
    const p = stack.pop();
    try {
      const m = /VmRSS:\s+(\d+)/.exec(readFileSync(`/proc/${p}/status`, 'utf8'));
      if (m) kb += Number(m[1]);
    } catch { /* gone */ }
    for (const k of kids.get(p) ?? []) stack.push(k);
  }
  return kb;
}

/** Runs node cli.mjs ARGS; resolves { seconds, peakMb, code, stdout }. */
function timed(args) {
  return new Promise((res) => {
    const t0 = performance.now();
    const child = spawn(process.execPath, [cli, ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
    let stdout = '';
    let stderr = '';
    child.stdout.on('data', (d) => { stdout += d; });
    child.stderr.on('data', (d) => { stderr += d; });
    let peak = 0;
    const timer = setInterval(() => { peak = Math.max(peak, treeRssKb(child.pid)); }, 100);
    child.on('close', (code) => {
      clearInterval(timer);
      if (code !== 0) process.stderr.write(stderr.slice(-2000));
      res({ seconds: (performance.now() - t0) / 1000, peakMb: peak / 1024, code, stdout });
    });
  });
}

const median = (v) => { const s = [...v].sort((a, b) => a - b); const h = s.length >> 1; return s.length % 2 ? s[h] : (s[h - 1] + s[h]) / 2; };

async function main() {
  const o = parse(process.argv.slice(2));
  mkdirSync(o.work, { recursive: true });
  const video = o.video ?? loopedClip(o.work, o.seconds);
  const common = ['--threads', String(o.threads)];
  const report = { video, repeats: o.repeats, threads: o.threads };

  // 1. overhead, alternated on the same clip
  writeFileSync(join(o.work, 'one.txt'), `${video}\n`);
  const runs = [];
  const batches = [];
  const peaks = [];
  for (let r = 0; r < o.repeats; ++r) {
    rmSync(join(o.work, 'run_out'), { recursive: true, force: true });
    rmSync(join(o.work, 'batch_out'), { recursive: true, force: true });
    const r1 = await timed(['run', video, '--out', join(o.work, 'run_out'), ...common]);
    const r2 = await timed(['batch', join(o.work, 'one.txt'), '--out', join(o.work, 'batch_out'), ...common]);
    runs.push(r1.seconds);
    batches.push(r2.seconds);
    peaks.push(r2.peakMb);
    process.stderr.write(`repeat ${r + 1}: run ${runs[r].toFixed(2)} s, batch ${batches[r].toFixed(2)} s\n`);
  }
  report.runSeconds = runs;
  report.batchSeconds = batches;
  report.overhead = median(batches) / median(runs) - 1;
  report.peakMb = median(peaks);

  // 2. memory of one task on the long clip
  if (o.long > 0) {
    const long = loopedClip(o.work, o.long);
    writeFileSync(join(o.work, 'long.txt'), `${long}\n`);
    rmSync(join(o.work, 'long_out'), { recursive: true, force: true });
    const m = await timed(['batch', join(o.work, 'long.txt'), '--out', join(o.work, 'long_out'), ...common]);
    report.long = { seconds: o.long, wallSeconds: m.seconds, peakMb: m.peakMb, code: m.code };
    process.stderr.write(`long clip (${o.long} s, 1080p): ${m.seconds.toFixed(1)} s, peak RSS of the task ${m.peakMb.toFixed(0)} MB\n`);

    // 3. two tasks at once, one thread each
    if (o.throughput) {
      const dir = join(o.work, 'array');
      rmSync(dir, { recursive: true, force: true });
      mkdirSync(join(dir, 'clips'), { recursive: true });
      for (const n of ['a', 'b']) copyFileSync(long, join(dir, 'clips', `${n}.mp4`));
      const t0 = performance.now();
      const tasks = await Promise.all([0, 1].map((i) => timed(['batch', join(dir, 'clips'), '--out', join(dir, 'out'), '--task-index', String(i), '--tasks', '2', '--threads', '1'])));
      const wall = (performance.now() - t0) / 1000;
      report.array = { tasks: 2, clips: 2, wallSeconds: wall, clipsPerHour: (2 * 3600) / wall, peakMbPerTask: tasks.map((t) => t.peakMb), codes: tasks.map((t) => t.code) };
      report.single = { clipsPerHour: 3600 / m.seconds };
      process.stderr.write(`array of 2 (1 thread each): ${wall.toFixed(1)} s for 2 clips: ${report.array.clipsPerHour.toFixed(1)} clips/hour (one task with ${o.threads} threads: ${report.single.clipsPerHour.toFixed(1)})\n`);
    }
  }
  process.stderr.write(`run median ${median(runs).toFixed(2)} s, batch median ${median(batches).toFixed(2)} s: overhead ${(100 * report.overhead).toFixed(1)} %\n`);
  process.stdout.write(`${JSON.stringify(report)}\n`);
}

main().catch((e) => { process.stderr.write(`bench_batch: ${e.message}\n`); process.exitCode = 1; });
