#!/usr/bin/env node
// bench_app.mjs — the browser app on one video in headless Chromium: time from the file input to
// the full result, per stage, and the peak memory of the whole browser (the sum of the
// proportional set sizes of every chromium process: browser, renderer with the page and its
// worker, GPU, utility), sampled every 0.5 s. One JSON object on stdout.
//
//   node web/tools/bench_app.mjs VIDEO [--max-side 960] [--max-frames N] [--model lite|full]
//        [--port 0] [--screenshot FILE]
// Needs scripts/build_web.sh's outputs, npm playwright-core and /usr/bin/chromium.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, rmSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { createServer } from '../server.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const args = process.argv.slice(2);
const opt = (name, def) => { const i = args.indexOf(name); return i >= 0 ? args[i + 1] : def; };
const video = args[0];
if (!video || video.startsWith('--')) { console.error('usage: node web/tools/bench_app.mjs VIDEO [--max-side N] [--max-frames N] [--model lite|full] [--screenshot FILE]'); process.exit(2); }

/// Proportional set size (bytes: each shared page divided among the processes that map it, so
/// the sum over processes counts it once) of the descendants of a process.
function treePss(pid) {
  const out = execFileSync('ps', ['-e', '-o', 'pid=,ppid='], { encoding: 'utf8' });
  const kids = new Map();
  for (const l of out.trim().split('\n')) {
    const [p, pp] = l.trim().split(/\s+/).map(Number);
    if (!kids.has(pp)) kids.set(pp, []);
    kids.get(pp).push(p);
  }
  let sum = 0;
  const byType = {};
  const stack = [...(kids.get(pid) || [])];
  while (stack.length) {
    const p = stack.pop();
    try {
      const m = /^Pss:\s+(\d+) kB/m.exec(readFileSync(`/proc/${p}/smaps_rollup`, 'utf8'));
      const cmd = readFileSync(`/proc/${p}/cmdline`, 'utf8');
      const type = (/--type=([a-z-]+)/.exec(cmd) || [, 'browser'])[1] + ((/--utility-sub-type=([\w.]+)/.exec(cmd) || [, ''])[1] ? `:${/--utility-sub-type=([\w.]+)/.exec(cmd)[1]}` : '');
      if (m) { sum += Number(m[1]) * 1024; byType[type] = (byType[type] || 0) + Number(m[1]) * 1024; }
    } catch { /* exited */ }
    for (const k of kids.get(p) || []) stack.push(k);
  }
  lastByType = byType;
  return sum;
}
let lastByType = {};

const server = createServer(root);
await new Promise((r) => server.listen(Number(opt('--port', 0)), '127.0.0.1', r));
const url = `http://127.0.0.1:${server.address().port}/`;
const { chromium } = await import('playwright-core');
const dataDir = mkdtempSync(join(tmpdir(), 'hawor-bench-'));
const context = await chromium.launchPersistentContext(dataDir, {
  executablePath: process.env.HAWOR_CHROMIUM || '/usr/bin/chromium', headless: true, viewport: { width: 1400, height: 900 },
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync'],
});
// The browser's processes are this node process's descendants.
const pid = process.pid;
const page = context.pages()[0] || await context.newPage();
const errors = [];
page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
page.on('pageerror', (e) => errors.push(e.message));
let peak = 0;
const samples = [];
const tBench = Date.now();
const mb = (o) => Object.fromEntries(Object.entries(o).map(([k, v]) => [k, Math.round(v / 2 ** 20)]));
let peakByType = {};
const timer = setInterval(() => { try { const r = treePss(pid); samples.push([Date.now() - tBench, r]); if (r > peak) { peak = r; peakByType = lastByType; } } catch { /* ps raced */ } }, 500);
try {
  const t0 = Date.now();
  await page.goto(url);
  await page.waitForSelector('body[data-ready="1"]', { timeout: 60000 });
  const readyMs = Date.now() - t0;
  await page.fill('#opt-maxside', String(opt('--max-side', 960)));
  if (opt('--max-frames')) await page.fill('#opt-maxframes', String(opt('--max-frames')));
  await page.selectOption('#opt-model', opt('--model', 'lite'));
  const idle = treePss(pid);
  const idleByType = lastByType;
  const t1 = Date.now();
  await page.setInputFiles('#file-video', resolve(video));
  // The page's own breakdown (JavaScript realms: page, worker; ArrayBuffers and WebAssembly
  // memories included) 30 s into processing.
  let uaMemory = null;
  const uaTimer = setTimeout(() => page.evaluate(async () => {
    const m = await performance.measureUserAgentSpecificMemory();
    return { bytes: m.bytes, breakdown: m.breakdown.filter((b) => b.bytes > 1e6).map((b) => ({ MB: Math.round(b.bytes / 2 ** 20), types: b.types, scope: b.attribution.map((a) => a.scope) })) };
  }).then((m) => { uaMemory = m; }, (e) => { uaMemory = String(e.message || e); }), 30000);
  const progress = setInterval(() => page.textContent('#stage').then((t) => process.stderr.write(`bench_app: ${t}   \r`), () => {}), 5000);
  await page.waitForFunction(() => document.body.dataset.busy === '0' && (window.haworApp.result || !document.getElementById('message').hidden),
    null, { timeout: 3600 * 1000, polling: 1000 });
  const wallMs = Date.now() - t1;
  clearInterval(progress);
  clearTimeout(uaTimer);
  const msg = await page.evaluate(() => { const m = document.getElementById('message'); return m.hidden ? null : m.textContent; });
  const run = await page.evaluate(() => window.haworApp.lastRun);
  const scene = await page.evaluate(() => window.haworApp.sceneSummary());
  if (opt('--screenshot')) await page.screenshot({ path: opt('--screenshot') });
  const heaps = await page.evaluate(() => window.haworApp.stats());
  // The memory over time, one point every ~10 s (ms since the start, MB).
  const timeline = samples.filter((_, i) => i % 20 === 0).map(([t, b]) => [t, Math.round(b / 2 ** 20)]);
  console.log(JSON.stringify({ video, readyMs, wallMs, message: msg, run, scene, memory: { idleMB: idle / 2 ** 20, idleByTypeMB: mb(idleByType), peakMB: peak / 2 ** 20, peakByTypeMB: mb(peakByType), samples: samples.length, heaps, uaMemory, timeline },
    consoleErrors: errors }, null, 1));
} finally {
  clearInterval(timer);
  await context.close();
  server.close();
  rmSync(dataDir, { recursive: true, force: true });
}
