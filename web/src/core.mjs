// core.mjs: loads the WebAssembly core (hawor_core.mjs + hawor_core.wasm, the C++ library through
// wasm/bindings.cpp) in node and in a browser or Web Worker; the package's "hawor/core".
//
//   import { loadCore } from 'hawor/core';
//   const core = await loadCore();            // { HandModel, HandFitter, MonoSlam, metricScale, ... }
//
// Build outputs are found by one resolver, builtFile(name): build/wasm/wasm/ and build/web/ in a
// checkout, else dist/ in an installed package (web/tools/stage_package.mjs copies them there when
// packing). No node module is imported statically: this file also runs in a browser, where the
// core is loaded from dist/ relative to the package root (web/server.mjs maps it).

/** Folders that may hold a build output, relative to the package root, in the order they are
 *  searched: a checkout's build folders first (a dist/ staged by an earlier `npm pack` may be
 *  older than them), then an installed package's dist/. web/server.mjs serves them, in this
 *  order, at /dist/, the one URL a browser asks for. */
export const BUILT_DIRS = ['build/wasm/wasm', 'build/web', 'dist'];
const PACKAGE_ROOT = new URL('../../', import.meta.url);
const isNode = typeof process === 'object' && !!(process.versions && process.versions.node) && typeof window === 'undefined';
const BUILD_HINT = 'build it with `emcmake cmake -S . -B build/wasm && cmake --build build/wasm --target hawor_core` in a checkout, or reinstall the package';

/** node only: the path of `name` in the first of BUILT_DIRS that holds it, or null. */
export async function builtFile(name) {
  const { existsSync } = await import('node:fs');
  const { fileURLToPath } = await import('node:url');
  for (const d of BUILT_DIRS) {
    const p = fileURLToPath(new URL(`${d}/${name}`, PACKAGE_ROOT));
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
  const candidates = [url ? new URL(url, import.meta.url) : new URL('dist/hawor_core.mjs', PACKAGE_ROOT)];
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
