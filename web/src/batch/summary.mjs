// summary.mjs: the state of a batch's output folder (`hawor batch --summary OUT`): each clip of the
// manifest (OUT/batch.json) with its latest status.json, the failures with their reasons, and the
// time spent (docs/batch.md).

import { existsSync, readFileSync, readdirSync } from 'node:fs';
import { join } from 'node:path';
import { BATCH_FILE, PARTIAL_DIR, STATUS_FILE, readStatus } from './task.mjs';

const median = (v) => {
  if (!v.length) return null;
  const s = [...v].sort((a, b) => a - b);
  const h = s.length >> 1;
  return s.length % 2 ? s[h] : (s[h - 1] + s[h]) / 2;
};

/**
 * { manifest, clips, ok, failed, skipped, pending, otherOptions, duplicates, partial, unlisted,
 *   failures: [{clip, source, reason}], seconds: {total, median, min, max}, wallSeconds }.
 * A clip counts with its latest status.json (by finishedAt); one done with other run options than
 * the batch's counts as pending. Throws (exitCode 1) when OUT holds no batch.
 */
export function summarize(out) {
  const fail = (msg) => Object.assign(new Error(msg), { exitCode: 1 });
  if (!existsSync(out)) throw fail(`${out}: no such folder`);
  let batch = null;
  try {
    batch = JSON.parse(readFileSync(join(out, BATCH_FILE), 'utf8'));
  } catch (e) {
    if (existsSync(join(out, BATCH_FILE))) throw fail(`${join(out, BATCH_FILE)}: unreadable (${e.message})`);
  }
  const statuses = [];
  for (const e of readdirSync(out, { withFileTypes: true })) {
    if (!e.isDirectory() || e.name.startsWith('.')) continue;
    const st = readStatus(join(out, e.name));
    if (st) statuses.push(st); // else not a clip folder
  }
  if (!batch && !statuses.length) throw fail(`${out}: not a batch output folder (no ${BATCH_FILE}, no clip folders with ${STATUS_FILE})`);
  const latest = new Map();
  for (const s of statuses) {
    const p = latest.get(s.source);
    if (!p || String(s.finishedAt) > String(p.finishedAt)) latest.set(s.source, s);
  }
  const clips = batch ? batch.clips : [...latest.keys()].map((path) => ({ path }));
  const sum = { manifest: batch?.manifest ?? null, clips: clips.length, ok: 0, failed: 0, skipped: 0, pending: 0, otherOptions: 0,
    duplicates: batch?.duplicates ?? [], failures: [], unlisted: 0, partial: 0 };
  const seconds = [];
  let first = null;
  let last = null;
  const listed = new Set(clips.map((c) => c.path));
  for (const c of clips) {
    const s = latest.get(c.path);
    if (!s) { sum.pending += 1; continue; }
    if (batch && JSON.stringify(s.options) !== JSON.stringify(batch.options)) { sum.pending += 1; sum.otherOptions += 1; continue; }
    if (s.status === 'ok' || s.status === 'skipped' || s.status === 'failed') sum[s.status] += 1;
    if (s.status === 'failed') sum.failures.push({ clip: s.clip, source: s.source, reason: s.reason ?? 'no reason recorded' });
    if (Number.isFinite(s.seconds)) seconds.push(s.seconds);
    if (!first || s.startedAt < first) first = s.startedAt;
    if (!last || s.finishedAt > last) last = s.finishedAt;
  }
  for (const src of latest.keys()) if (!listed.has(src)) sum.unlisted += 1;
  try {
    sum.partial = readdirSync(join(out, PARTIAL_DIR)).filter((n) => !n.startsWith('.')).length;
  } catch { /* none */ }
  sum.seconds = { total: seconds.reduce((a, b) => a + b, 0), median: median(seconds), min: seconds.length ? Math.min(...seconds) : null, max: seconds.length ? Math.max(...seconds) : null };
  sum.wallSeconds = first && last ? (Date.parse(last) - Date.parse(first)) / 1000 : null;
  return sum;
}

/** The summary as lines of text. */
export function formatSummary(out, s) {
  const f = (v) => (v === null ? '-' : `${v.toFixed(1)} s`);
  const lines = [`${out}: ${s.clips} clips${s.manifest ? ` (manifest ${s.manifest})` : ''}: ${s.ok} ok, ${s.failed} failed, ${s.skipped} skipped (no hands), ${s.pending} not done${s.otherOptions ? ` (${s.otherOptions} of them done with other run options)` : ''}`];
  if (s.duplicates.length) lines.push(`duplicates in the manifest (run once): ${s.duplicates.map((d) => `line ${d.line} = line ${d.firstLine}`).join(', ')}`);
  if (s.failures.length) {
    lines.push('failed:');
    for (const x of s.failures) lines.push(`  ${x.clip} (${x.source}): ${x.reason}`);
  }
  lines.push(`time: ${f(s.seconds.total)} in all, per clip median ${f(s.seconds.median)} (${f(s.seconds.min)} to ${f(s.seconds.max)})${s.wallSeconds !== null ? `, ${f(s.wallSeconds)} from the first start to the last finish` : ''}`);
  if (s.partial) lines.push(`${s.partial} clip(s) in progress or left by a killed task (${PARTIAL_DIR}/; a rerun redoes them)`);
  if (s.unlisted) lines.push(`${s.unlisted} clip folder(s) from clips not in this manifest`);
  return lines.join('\n');
}
