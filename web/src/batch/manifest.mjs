// manifest.mjs: a corpus as a list of clips (a manifest file or a folder) and each clip's id, the
// name of its output folder (docs/batch.md).
//
// A manifest is a text file with one video path per line; blank lines and lines starting with
// '#' are skipped, relative paths are relative to the manifest's folder. A folder stands for the
// videos under it (recursively, by extension), in sorted order. The same path listed twice is
// kept once: the later lines are reported as duplicates of the first.
//
// A clip's id is its file name's stem (characters outside [A-Za-z0-9._-] become '_', at most 60)
// and a short hash of its content: two clips called video.mp4 in different folders get different
// ids, and a renamed clip is a new clip. The hash reads a fixed sample of the file (its size and
// three 1 MiB windows: start, middle, end; all of it when smaller) so that a rerun over thousands
// of clips costs milliseconds per clip, not a full read: two encodes of real video that agree on
// size, container header, middle and tail are not expected.

import { createHash } from 'node:crypto';
import { closeSync, openSync, readFileSync, readSync, readdirSync, statSync } from 'node:fs';
import { basename, dirname, extname, isAbsolute, join, relative, resolve } from 'node:path';

export const VIDEO_EXTENSIONS = ['.mp4', '.mov', '.m4v', '.mkv', '.webm', '.avi', '.mts', '.m2ts', '.ts', '.mpg', '.mpeg', '.y4m', '.wmv', '.flv', '.3gp'];
const WINDOW = 1 << 20;

const fail = (msg) => Object.assign(new Error(msg), { exitCode: 1 });

function listVideos(dir) {
  const out = [];
  const walk = (d) => {
    let entries;
    try {
      entries = readdirSync(d, { withFileTypes: true });
    } catch (e) {
      throw fail(`${d}: cannot list the folder (${e.code ?? e.message})`);
    }
    for (const e of entries) {
      if (e.name.startsWith('.')) continue; // hidden files and folders (.partial of a batch output among them)
      const p = join(d, e.name);
      if (e.isDirectory()) walk(p);
      else if (VIDEO_EXTENSIONS.includes(extname(e.name).toLowerCase())) out.push(p);
    }
  };
  walk(dir);
  return out.sort((a, b) => (relative(dir, a) < relative(dir, b) ? -1 : 1));
}

/**
 * The clips of a manifest file or folder: { source, clips: [{line, path}], duplicates: [{line,
 * path, firstLine}] }, paths absolute, clips in manifest order. Throws (exitCode 1) when the
 * manifest is missing, unreadable, binary, or lists no clip.
 */
export function readManifest(manifest) {
  const source = resolve(manifest);
  let st;
  try {
    st = statSync(source);
  } catch {
    throw fail(`${manifest}: no such manifest file or folder`);
  }
  let entries;
  if (st.isDirectory()) {
    entries = listVideos(source).map((p, i) => ({ line: i + 1, path: p }));
    if (!entries.length) throw fail(`${manifest}: no videos in this folder (extensions ${VIDEO_EXTENSIONS.join(' ')})`);
  } else {
    let text;
    try {
      text = readFileSync(source);
    } catch (e) {
      throw fail(`${manifest}: cannot read the manifest (${e.code ?? e.message})`);
    }
    if (text.includes(0)) throw fail(`${manifest}: not a text manifest (it holds NUL bytes: a video given where the list of videos belongs?)`);
    const base = dirname(source);
    entries = [];
    text.toString('utf8').split(/\r?\n/).forEach((raw, i) => {
      const l = raw.trim();
      if (!l || l.startsWith('#')) return;
      entries.push({ line: i + 1, path: isAbsolute(l) ? resolve(l) : resolve(base, l) });
    });
    if (!entries.length) throw fail(`${manifest}: lists no clip (one video path per line)`);
  }
  const first = new Map();
  const clips = [];
  const duplicates = [];
  for (const e of entries) {
    if (first.has(e.path)) duplicates.push({ ...e, firstLine: first.get(e.path) });
    else { first.set(e.path, e.line); clips.push(e); }
  }
  return { source, clips, duplicates };
}

/** Clip i of the deduplicated list goes to task i mod tasks. */
export function clipsOfTask(clips, index, tasks) {
  return clips.filter((_, i) => i % tasks === index);
}

/** The file-name part of a clip id. */
export function clipStem(path) {
  const stem = basename(path, extname(path)).replace(/[^A-Za-z0-9._-]/g, '_').replace(/^\.+/, '_');
  return (stem || 'clip').slice(0, 60);
}

/** 10 hex digits of SHA-256 over the file's size and its sampled windows (see the top). */
export function contentHash(path) {
  const h = createHash('sha256');
  const fd = openSync(path, 'r');
  try {
    const { size } = statSync(path);
    h.update(`${size}\n`);
    const starts = size <= 3 * WINDOW ? [0] : [0, Math.floor(size / 2) - WINDOW / 2, size - WINDOW];
    const buf = Buffer.allocUnsafe(size <= 3 * WINDOW ? size : WINDOW);
    for (const s of starts) {
      let n = 0;
      while (n < buf.length) {
        const r = readSync(fd, buf, n, buf.length - n, s + n);
        if (r === 0) break;
        n += r;
      }
      h.update(buf.subarray(0, n));
    }
  } finally {
    closeSync(fd);
  }
  return h.digest('hex').slice(0, 10);
}

/** The id of a clip that can be read: stem-hash. */
export function clipId(path) {
  return `${clipStem(path)}-${contentHash(path)}`;
}

/** The id of a clip that cannot be read (missing, a folder, no permission): stem-x and a hash of
 *  its path, so that its failure has a folder of its own. */
export function unreadableClipId(path) {
  return `${clipStem(path)}-x${createHash('sha256').update(path).digest('hex').slice(0, 9)}`;
}
