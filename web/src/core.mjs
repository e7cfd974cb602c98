// core.mjs: loads the WebAssembly core (hawor_core.mjs + hawor_core.wasm, the C++ library through
// wasm/bindings.cpp) in node and in a browser or Web Worker; the package's "hawor/core".
//
//   import { loadCore } from 'hawor/core';
//   const core = await loadCore();            // { HandModel, HandFitter, MonoSlam, metricScale, ... }
//
// Build outputs are found by one resolver, builtFile(name): dist/ in an installed package
// (web/tools/stage_package.mjs copies them there when packing), else build/wasm/wasm/ and
// build/web/ in a checkout. No node module is imported statically: this file also runs in a
// browser, where the candidates are tried as URLs relative to this file.

/** Folders that may hold a build output, relative to the package root, in order. */
export const BUILT_DIRS = ['dist', 'build/wasm/wasm', 'build/web'];
const PACKAGE_ROOT = new URL('../../', import.meta.url);
const isNode = typeof process === 'object' && !!(process.versions && process.versions.node) && typeof window === 'undefined';
const BUILD_HINT = 'build it with `emcmake cmake -S . -B build/wasm && cmake --build build/wasm --target hawor_core` in a checkout, or reinstall the package';

/** The candidate URLs of a build output (dist/, build/wasm/wasm/, build/web/). */
export function builtUrls(name) {
  return BUILT_DIRS.map((d) => new URL(`${d}/${name}`, PACKAGE_ROOT));
}

/** node only: the path of the first existing candidate of builtUrls(name), or null. */
export async function builtFile(name) {
  const { existsSync } = await import('node:fs');
  const { fileURLToPath } = await import('node:url');
  for (const u of builtUrls(name)) {
    const p = fileURLToPath(u);
    if (existsSync(p)) return p;
  }
  return null;
}

/**
 * The core's module instance. options.path (node) or options.url (browser) names hawor_core.mjs;
 * by default the resolver finds it. Other options go to the emscripten module factory.
 * Throws an Error naming the missing file and the build command.
 */
export async function loadCore(options = {}) {
  const { path, url, ...moduleOptions } = options;
  return isNode ? loadInNode(path, moduleOptions) : loadInBrowser(url, moduleOptions);
}

async function loadInNode(path, moduleOptions) {
  const { existsSync, readFileSync } = await import('node:fs');
  const { createRequire } = await import('node:module');
  const { dirname, join, resolve } = await import('node:path');
  const { pathToFileURL } = await import('node:url');
  const file = path ? resolve(path) : await builtFile('hawor_core.mjs');
  if (!file || !existsSync(file)) {
    const where = path ? file : `not in ${BUILT_DIRS.join('/, ')}/ of ${new URL(PACKAGE_ROOT).pathname}`;
    throw new Error(`the WebAssembly core hawor_core.mjs is missing (${where}): ${BUILD_HINT}`);
  }
  const dir = dirname(file);
  const wasm = join(dir, 'hawor_core.wasm');
  if (!existsSync(wasm)) throw new Error(`${wasm}: missing next to the core (${BUILD_HINT})`);
  // emscripten's ES6 output reads require and __dirname in node (docs/design.md §9).
  globalThis.require ??= createRequire(import.meta.url);
  globalThis.__dirname = dir;
  const { default: create } = await import(pathToFileURL(file).href);
  // The .wasm bytes are handed over directly: node 20's fetch cannot read file paths.
  return create({ locateFile: (f) => join(dir, f), wasmBinary: readFileSync(wasm), ...moduleOptions });
}

async function loadInBrowser(url, moduleOptions) {
  const candidates = url ? [new URL(url, import.meta.url)] : builtUrls('hawor_core.mjs');
  const errors = [];
  for (const u of candidates) {
    let create;
    try {
      ({ default: create } = await import(u.href));
    } catch (e) {
      errors.push(`${u.href}: ${e.message}`);
      continue;
    }
    return create({ locateFile: (f) => new URL(f, u).href, ...moduleOptions });
  }
  throw new Error(`the WebAssembly core hawor_core.mjs could not be loaded (${errors.join('; ')}): ${BUILD_HINT}`);
}
