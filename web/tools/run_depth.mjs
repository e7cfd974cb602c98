#!/usr/bin/env node
// run_depth.mjs: runs a metric-depth network (ONNX + hawor depth config) over a folder of PNG
// frames with onnxruntime-web, writing the depth maps `hawor scale --metric-depth` reads.
//
//   node web/tools/run_depth.mjs --model M.onnx --config C.json --images DIR --out DIR
//                                [--frames 0,5,9]
//
// Every DIR/*.png (or, with --frames, DIR/%06d.png of the listed frames) becomes
// OUT/<stem>.npy: float32 (H,W) metres along the optical axis, little-endian, C order, at the
// image's resolution, NaN where the network gave no valid depth. Prints one JSON line:
// {"images", "width", "height", "model_width", "model_height", "kind", "valid_fraction",
//  "load_ms", "ms_per_image_median", "out"}. Errors go to stderr: exit 2 for a usage error,
// 1 for a missing or bad file.

import { readFileSync, readdirSync, writeFileSync, mkdirSync, statSync } from 'node:fs';
import { join, basename, extname } from 'node:path';
import * as ort from 'onnxruntime-web';
import pngjs from 'pngjs';
import { DepthModel, parseDepthConfig } from '../src/depth_model.mjs';
import { encodeNpyFloat32 } from './npy.mjs';

const USAGE = 'usage: node web/tools/run_depth.mjs --model M.onnx --config C.json --images DIR --out DIR [--frames 0,5,9]';

class UsageError extends Error {}

function parseArgs(argv) {
  const opts = {};
  const known = { '--model': 'model', '--config': 'config', '--images': 'images', '--out': 'out', '--frames': 'frames' };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    if (a === '--help' || a === '-h') return { help: true };
    const key = known[a];
    if (!key) throw new UsageError(`unknown argument '${a}'`);
    if (i + 1 >= argv.length) throw new UsageError(`${a} needs a value`);
    opts[key] = argv[++i];
  }
  for (const k of ['model', 'config', 'images', 'out']) if (!opts[k]) throw new UsageError(`--${k} is required`);
  if (opts.frames !== undefined) {
    const parts = opts.frames.split(',').map((s) => s.trim());
    opts.frames = parts.map((s) => {
      if (!/^\d+$/.test(s) || !Number.isSafeInteger(Number(s))) throw new UsageError(`--frames: '${s}' is not a frame number (expected e.g. 0,5,9)`);
      return Number(s);
    });
  }
  return opts;
}

function readFile(path, what) {
  try {
    return readFileSync(path);
  } catch (e) {
    throw new Error(e.code === 'ENOENT' ? `${what} '${path}' not found` : `cannot read ${what} '${path}' (${e.message})`);
  }
}

function listImages(dir, frames) {
  let st;
  try {
    st = statSync(dir);
  } catch {
    throw new Error(`--images folder '${dir}' not found`);
  }
  if (!st.isDirectory()) throw new Error(`--images '${dir}' is not a folder`);
  if (frames) {
    const paths = frames.map((f) => join(dir, `${String(f).padStart(6, '0')}.png`));
    for (const p of paths) {
      try {
        statSync(p);
      } catch {
        throw new Error(`image '${p}' not found`); // before any work, not after half the frames
      }
    }
    return paths;
  }
  const names = readdirSync(dir).filter((n) => extname(n).toLowerCase() === '.png').sort();
  if (names.length === 0) throw new Error(`no .png file in '${dir}'`);
  return names.map((n) => join(dir, n));
}

function decodePng(path) {
  const bytes = readFile(path, 'image');
  try {
    const png = pngjs.PNG.sync.read(bytes);
    return { width: png.width, height: png.height, rgba: new Uint8Array(png.data.buffer, png.data.byteOffset, png.data.length) };
  } catch (e) {
    throw new Error(`cannot decode PNG '${path}' (${e.message})`);
  }
}

async function main(argv) {
  const opts = parseArgs(argv);
  if (opts.help) {
    process.stdout.write(USAGE + '\n');
    return;
  }
  const configText = readFile(opts.config, 'config').toString('utf8');
  let config;
  try {
    config = parseDepthConfig(configText);
  } catch (e) {
    throw new Error(`${opts.config}: ${e.message}`);
  }
  const modelBytes = readFile(opts.model, 'model');
  const images = listImages(opts.images, opts.frames);

  ort.env.wasm.numThreads = 1; // deterministic, and the machines are small
  ort.env.logLevel = 'error';
  const t0 = performance.now();
  const model = await DepthModel.create(ort, new Uint8Array(modelBytes.buffer, modelBytes.byteOffset, modelBytes.length), config);
  const loadMs = performance.now() - t0;

  mkdirSync(opts.out, { recursive: true });
  const times = [];
  let valid = 0;
  let total = 0;
  const sizes = new Set();
  for (const path of images) {
    const img = decodePng(path);
    sizes.add(`${img.width}x${img.height}`);
    const t = performance.now();
    const depth = await model.predict(img.rgba, img.width, img.height, 4);
    times.push(performance.now() - t);
    for (const d of depth) if (d === d) valid += 1; // d === d: not NaN
    total += depth.length;
    const stem = basename(path, extname(path));
    writeFileSync(join(opts.out, `${stem}.npy`), encodeNpyFloat32(depth, [img.height, img.width]));
  }
  await model.dispose();
  times.sort((a, b) => a - b);
  const [w, h] = sizes.size === 1 ? [...sizes][0].split('x').map(Number) : [null, null];
  const round = (x) => Math.round(x * 1000) / 1000;
  process.stdout.write(JSON.stringify({
    images: images.length,
    width: w,
    height: h,
    model_width: config.input.width,
    model_height: config.input.height,
    kind: config.output.kind,
    valid_fraction: total ? round(valid / total) : 0,
    load_ms: round(loadMs),
    ms_per_image_median: round(times[Math.floor(times.length / 2)]),
    out: opts.out,
  }) + '\n');
}

main(process.argv.slice(2)).catch((e) => {
  if (e instanceof UsageError) {
    process.stderr.write(`run_depth: ${e.message}\n${USAGE}\n`);
    process.exit(2);
  }
  process.stderr.write(`run_depth: ${e.message}\n`);
  process.exit(1);
});
