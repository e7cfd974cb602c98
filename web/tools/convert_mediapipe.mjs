// convert_mediapipe.mjs: the install step that turns MediaPipe's hand networks (npm
// @mediapipe/hands, Apache-2.0) into ONNX files for onnxruntime-web. Nothing it writes is
// committed (web/models/ is ignored); scripts/install.sh runs it on every fresh machine, and the
// npm package's postinstall (--postinstall: a failure only warns, the CLI converts at run time).
//
//   node web/tools/convert_mediapipe.mjs [--package DIR] [--out DIR] [--fp32] [--postinstall]
//
// @mediapipe/hands is found by node's module resolution from this file (in an installed package
// npm hoists it into the consumer's node_modules, beside this package).
//
// The hand landmark models ship as files; the palm detectors are packed into
// hands_solution_packed_assets.data, whose loader script lists each file's byte range. The
// ranges are read from the loader and each slice must start like a TFLite FlatBuffer ("TFL3"
// at byte 4); for the pinned version they are (docs/design.md §4): handedness.txt 0..11,
// palm_detection_full 11..2,341,291, palm_detection_lite 2,341,291..4,326,731.
// Writes <out>/{palm_detection_full,palm_detection_lite,hand_landmark_full,hand_landmark_lite}.onnx
// and <out>/mediapipe_models.json (source version, SHA-256 of each .tflite, inputs, outputs).

import { readFileSync, writeFileSync, mkdirSync, existsSync } from 'node:fs';
import { createHash } from 'node:crypto';
import { dirname, join, resolve } from 'node:path';
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';
import { readTflite } from './tflite_reader.mjs';
import { tfliteToOnnx } from './tflite_to_onnx.mjs';

export const MEDIAPIPE_HANDS_VERSION = '0.4.1675469240';
export const MODEL_NAMES = ['palm_detection_full', 'palm_detection_lite', 'hand_landmark_full', 'hand_landmark_lite'];

const here = dirname(fileURLToPath(import.meta.url));

/** The folder of the installed @mediapipe/hands as module resolution finds it, or null. */
export function findMediapipeHands() {
  try {
    return dirname(createRequire(import.meta.url).resolve('@mediapipe/hands/package.json'));
  } catch {
    return null;
  }
}

export const defaultPackageDir = findMediapipeHands() ?? resolve(here, '../../node_modules/@mediapipe/hands');
export const defaultModelsDir = resolve(here, '../models');

const PACKED = 'hands_solution_packed_assets.data';
const LOADER = 'hands_solution_packed_assets_loader.js';

/** The byte ranges the loader script declares: [{filename, start, end}]. */
export function packedRanges(loaderText) {
  const re = /"filename"\s*:\s*"([^"]+)"\s*,\s*"start"\s*:\s*(\d+)\s*,\s*"end"\s*:\s*(\d+)/g;
  const out = [];
  for (const m of loaderText.matchAll(re)) out.push({ filename: m[1], start: Number(m[2]), end: Number(m[3]) });
  return out;
}

function checkTflite(bytes, what) {
  const magic = bytes.length >= 8 ? String.fromCharCode(...bytes.subarray(4, 8)) : '';
  if (magic !== 'TFL3') throw new Error(`${what}: not a TFLite FlatBuffer (bytes 4..8 are ${JSON.stringify(magic)}, expected "TFL3")`);
  return bytes;
}

/** The four .tflite files of the package as Uint8Arrays, keyed by MODEL_NAMES. */
export function extractMediapipeModels(pkgDir = defaultPackageDir) {
  const pj = join(pkgDir, 'package.json');
  if (!existsSync(pj)) throw new Error(`${pkgDir}: @mediapipe/hands is not installed (npm install @mediapipe/hands@${MEDIAPIPE_HANDS_VERSION}, or scripts/install.sh in a checkout)`);
  const version = JSON.parse(readFileSync(pj, 'utf8')).version;
  if (version !== MEDIAPIPE_HANDS_VERSION) {
    throw new Error(`${pkgDir}: @mediapipe/hands ${version}, but the converter is checked against ${MEDIAPIPE_HANDS_VERSION}`);
  }
  const models = {};
  for (const name of ['hand_landmark_full', 'hand_landmark_lite']) {
    models[name] = checkTflite(new Uint8Array(readFileSync(join(pkgDir, `${name}.tflite`))), `${name}.tflite`);
  }
  const packed = new Uint8Array(readFileSync(join(pkgDir, PACKED)));
  const ranges = packedRanges(readFileSync(join(pkgDir, LOADER), 'utf8'));
  for (const name of ['palm_detection_full', 'palm_detection_lite']) {
    const r = ranges.find((x) => x.filename.endsWith(`/${name}.tflite`));
    if (!r) throw new Error(`${LOADER}: no byte range for ${name}.tflite`);
    if (!(r.start < r.end && r.end <= packed.length)) throw new Error(`${LOADER}: range ${r.start}..${r.end} of ${name}.tflite lies outside the ${packed.length}-byte ${PACKED}`);
    models[name] = checkTflite(packed.subarray(r.start, r.end), `${PACKED} bytes ${r.start}..${r.end} (${name})`);
  }
  return { version, models };
}

const sha256 = (u8) => createHash('sha256').update(u8).digest('hex');

/** Converts all four; returns the manifest written next to them. */
export function convertMediapipe({ pkgDir = defaultPackageDir, outDir = defaultModelsDir, weights = 'float16' } = {}) {
  const { version, models } = extractMediapipeModels(pkgDir);
  mkdirSync(outDir, { recursive: true });
  const manifest = { format: 'hawor-mediapipe-models', source: `@mediapipe/hands@${version}`, license: 'Apache-2.0', weights, models: {} };
  for (const name of MODEL_NAMES) {
    const conv = tfliteToOnnx(readTflite(models[name]), { weights, name });
    const file = `${name}.onnx`;
    writeFileSync(join(outDir, file), conv.bytes);
    manifest.models[name] = { file, tfliteSha256: sha256(models[name]), bytes: conv.bytes.length, inputs: conv.inputs, outputs: conv.outputs, opCounts: conv.opCounts };
  }
  writeFileSync(join(outDir, 'mediapipe_models.json'), `${JSON.stringify(manifest, null, 2)}\n`);
  return manifest;
}

/** The four .onnx files in outDir, converted first when any is missing: {converted, ms}. */
export function ensureMediapipeModels(outDir = defaultModelsDir, pkgDir = defaultPackageDir) {
  if (MODEL_NAMES.every((n) => existsSync(join(outDir, `${n}.onnx`)))) return { converted: false, ms: 0 };
  const t0 = Date.now();
  convertMediapipe({ pkgDir, outDir });
  return { converted: true, ms: Date.now() - t0 };
}

function main(argv) {
  const opts = {};
  let postinstall = false;
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    if (a === '--package') opts.pkgDir = resolve(argv[++i] ?? '');
    else if (a === '--out') opts.outDir = resolve(argv[++i] ?? '');
    else if (a === '--fp32') opts.weights = 'float32';
    else if (a === '--postinstall') postinstall = true;
    else {
      process.stderr.write(`convert_mediapipe: unknown argument '${a}'\nusage: node web/tools/convert_mediapipe.mjs [--package DIR] [--out DIR] [--fp32] [--postinstall]\n`);
      return 2;
    }
  }
  try {
    const t0 = Date.now();
    const m = convertMediapipe(opts);
    const sizes = Object.entries(m.models).map(([k, v]) => `${k} ${(v.bytes / 1e6).toFixed(2)} MB`).join(', ');
    process.stderr.write(`[convert_mediapipe] ${m.source} -> ${opts.outDir ?? defaultModelsDir} (${sizes}; ${Date.now() - t0} ms)\n`);
    return 0;
  } catch (e) {
    // A failed postinstall would abort the user's whole npm install; the CLI retries at run time.
    if (postinstall) {
      process.stderr.write(`hawor postinstall: the hand networks were not converted (hawor converts them on its first run): ${e.message}\n`);
      return 0;
    }
    process.stderr.write(`convert_mediapipe: ${e.message}\n`);
    return 1;
  }
}

if (process.argv[1] && resolve(process.argv[1]) === fileURLToPath(import.meta.url)) process.exitCode = main(process.argv.slice(2));
