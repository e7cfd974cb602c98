// stage_package.mjs: npm's prepack step (`npm pack`, `npm publish`). Copies the build outputs the
// package ships but git does not hold into dist/ (ignored): the WebAssembly core
// (build/wasm/wasm/hawor_core.{mjs,wasm}) and the built-in synthetic sample
// (build/web/sample.{webm,json}). Fails, naming the build command, when one is missing, and when
// package.json's version is not CMakeLists.txt's project VERSION.
//
//   node web/tools/stage_package.mjs [--root DIR]

import { copyFileSync, existsSync, mkdirSync, readFileSync, rmSync, statSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

export const STAGED = [
  ['build/wasm/wasm/hawor_core.mjs', 'emcmake cmake -S . -B build/wasm -DCMAKE_BUILD_TYPE=Release && cmake --build build/wasm --target hawor_core'],
  ['build/wasm/wasm/hawor_core.wasm', 'emcmake cmake -S . -B build/wasm -DCMAKE_BUILD_TYPE=Release && cmake --build build/wasm --target hawor_core'],
  ['build/web/sample.webm', 'bash scripts/build_web.sh'],
  ['build/web/sample.json', 'bash scripts/build_web.sh'],
];

/** CMakeLists.txt's `project(hawor VERSION x.y.z ...)`, or null. */
export function cmakeVersion(text) {
  const m = /^\s*project\s*\(\s*hawor\s+VERSION\s+([0-9][0-9.]*)/im.exec(text);
  return m ? m[1] : null;
}

/** Copies STAGED into ROOT/dist (emptied first); returns [{file, bytes}]. */
export function stagePackage(root) {
  const pkg = JSON.parse(readFileSync(join(root, 'package.json'), 'utf8'));
  const cmake = cmakeVersion(readFileSync(join(root, 'CMakeLists.txt'), 'utf8'));
  if (pkg.version !== cmake) throw new Error(`package.json's version ${pkg.version} is not CMakeLists.txt's project VERSION ${cmake}`);
  const missing = STAGED.filter(([f]) => !existsSync(join(root, f)));
  if (missing.length) {
    const commands = [...new Set(missing.map(([, c]) => c))].join('; then ');
    throw new Error(`cannot pack: ${missing.map(([f]) => f).join(', ')} missing (build outputs, not in git); build them first: ${commands}`);
  }
  const dist = join(root, 'dist');
  rmSync(dist, { recursive: true, force: true });
  mkdirSync(dist);
  return STAGED.map(([f]) => {
    const to = join(dist, f.split('/').pop());
    copyFileSync(join(root, f), to);
    return { file: to, bytes: statSync(to).size };
  });
}

function main(argv) {
  let root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
  for (let i = 0; i < argv.length; ++i) {
    if (argv[i] === '--root' && i + 1 < argv.length) root = resolve(argv[++i]);
    else {
      process.stderr.write(`stage_package: unknown argument '${argv[i]}'\nusage: node web/tools/stage_package.mjs [--root DIR]\n`);
      return 2;
    }
  }
  try {
    const staged = stagePackage(root);
    process.stderr.write(`[stage_package] dist/: ${staged.map((s) => `${s.file.split('/').pop()} (${(s.bytes / 1e6).toFixed(2)} MB)`).join(', ')}\n`);
    return 0;
  } catch (e) {
    process.stderr.write(`stage_package: ${e.message}\n`);
    return 1;
  }
}

if (process.argv[1] && resolve(process.argv[1]) === fileURLToPath(import.meta.url)) process.exitCode = main(process.argv.slice(2));
