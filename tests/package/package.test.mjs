// The npm package end to end: package.json against the repository (version = CMakeLists.txt's,
// every exports / bin / files entry exists), `npm pack` (its prepack stages the WebAssembly core
// and the synthetic sample into dist/), an install of the tarball into an empty folder (its
// postinstall converts MediaPipe's networks), then from that folder `npx hawor --help`,
// `npx hawor run --sample` on 30 frames and its files, the networks converted at run time when
// missing, clear errors when the core is missing, and imports of hawor/core, hawor/pipeline,
// hawor/perception and hawor/export.
//
//   bash scripts/build_web.sh && node --test tests/package/
//
// npm install needs the registry or npm's cache (warm after scripts/install.sh; --prefer-offline).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync, mkdtempSync, readdirSync, readFileSync, renameSync, rmSync, statSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { cmakeVersion, STAGED } from '../../web/tools/stage_package.mjs';
import { MODEL_NAMES } from '../../web/tools/convert_mediapipe.mjs';
import { BUILT_DIRS } from '../../web/src/core.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const pkg = JSON.parse(readFileSync(join(root, 'package.json'), 'utf8'));
const missing = STAGED.map(([f]) => f).filter((f) => !existsSync(join(root, f)));
const timings = {};
let work, tarball, project, installed;

// Children run without the suite's HAWOR_* variables: the installed package finds its own files.
const env = Object.fromEntries(Object.entries(process.env).filter(([k]) => !k.startsWith('HAWOR_')));
function run(cmd, args, cwd, timeout = 120000, extraEnv = {}) {
  const t0 = Date.now();
  const r = spawnSync(cmd, args, { cwd, env: { ...env, ...extraEnv }, encoding: 'utf8', timeout, maxBuffer: 64 << 20 });
  r.ms = Date.now() - t0;
  if (r.error) throw new Error(`${cmd} ${args.join(' ')}: ${r.error.message}`);
  return r;
}
const ok = (r, what) => assert.equal(r.status, 0, `${what} exited ${r.status}:\n${(r.stderr || '').slice(-3000)}`);
// --no: never fetch a registry package of that name; --: the rest (--help too) is hawor's.
const hawor = (args, timeout) => run('npx', ['--no', '--', 'hawor', ...args], project, timeout);

before(() => {
  work = mkdtempSync(join(tmpdir(), 'hawor-package-'));
});
after(() => {
  if (work) rmSync(work, { recursive: true, force: true });
  if (Object.keys(timings).length) console.log(`# package timings (ms): ${JSON.stringify(timings)}`);
});

test('package.json: the version is CMakeLists.txt\'s, Apache-2.0 with its LICENSE, every entry exists', () => {
  assert.equal(pkg.name, 'hawor');
  assert.equal(pkg.version, cmakeVersion(readFileSync(join(root, 'CMakeLists.txt'), 'utf8')));
  assert.equal(pkg.private, undefined);
  assert.equal(pkg.type, 'module');
  assert.equal(pkg.license, 'Apache-2.0');
  assert.match(readFileSync(join(root, 'LICENSE'), 'utf8'), /Apache License\s+Version 2\.0, January 2004/);
  for (const k of ['./core', './pipeline', './perception', './export', './package.json']) {
    assert.ok(pkg.exports[k] && existsSync(join(root, pkg.exports[k])), `exports ${k}: ${pkg.exports[k]}`);
  }
  assert.equal(pkg.bin.hawor, 'web/cli.mjs');
  assert.match(readFileSync(join(root, pkg.bin.hawor), 'utf8'), /^#!\/usr\/bin\/env node\n/);
  for (const f of pkg.files) if (!f.startsWith('dist/')) assert.ok(existsSync(join(root, f)), `files: ${f}`);
  // dist/ holds exactly what the prepack step stages.
  assert.deepEqual(pkg.files.filter((f) => f.startsWith('dist/')).sort(), STAGED.map(([f]) => `dist/${f.split('/').pop()}`).sort());
  // Run time needs only the dependencies; test and build tools are devDependencies.
  assert.deepEqual(Object.keys(pkg.dependencies).sort(), ['@mediapipe/hands', '@webxr-input-profiles/assets', 'onnxruntime-web', 'three']);
  for (const d of ['playwright-core', 'gltf-validator', 'pngjs', '@tensorflow/tfjs-core']) assert.ok(pkg.devDependencies[d], d);
});

test('npm pack: the core, the sample, the app and the CLI; no weights, builds or node_modules', { timeout: 120000 }, () => {
  assert.deepEqual(missing, [], `build outputs missing (run scripts/build_web.sh): ${missing.join(', ')}`);
  const r = run('npm', ['pack', '--json', '--pack-destination', work], root);
  ok(r, 'npm pack');
  timings.pack = r.ms;
  const info = JSON.parse(r.stdout.slice(r.stdout.indexOf('[')))[0];
  tarball = join(work, info.filename);
  assert.ok(existsSync(tarball), tarball);
  const files = info.files.map((f) => f.path);
  for (const f of ['package.json', 'LICENSE', 'README.md', 'web/cli.mjs', 'web/server.mjs', 'web/app/index.html', 'web/app/worker.mjs',
    'web/src/core.mjs', 'web/src/pipeline/run.mjs', 'web/src/export/index.mjs', 'web/tools/convert_mediapipe.mjs', 'web/tools/npz.mjs',
    'dist/hawor_core.mjs', 'dist/hawor_core.wasm', 'dist/sample.webm', 'dist/sample.json']) {
    assert.ok(files.includes(f), `${f} not in the tarball`);
  }
  for (const f of files) {
    assert.doesNotMatch(f, /\.(onnx|tflite|pkl|npz)$|^node_modules\/|^build\/|^tests\/|^include\/|^web\/models\//, `${f} must not be shipped`);
  }
  // The staged files are the build's.
  for (const [f] of STAGED) assert.deepEqual(readFileSync(join(root, 'dist', f.split('/').pop())), readFileSync(join(root, f)), f);
  timings.tarballBytes = statSync(tarball).size;
  timings.unpackedBytes = info.unpackedSize;
  timings.files = files.length;
});

test('the installed package: npx hawor --help, run --sample, networks converted when missing, clear errors, imports', { timeout: 300000 }, () => {
  assert.ok(tarball, 'no tarball (the npm pack test failed)');
  project = join(work, 'project');
  rmSync(project, { recursive: true, force: true });
  spawnSync('mkdir', ['-p', project]);
  writeFileSync(join(project, 'package.json'), '{ "name": "hawor-package-test", "private": true }\n');
  // onnxruntime-node (optional) without its CUDA download, as the README says
  let r = run('npm', ['install', '--no-audit', '--no-fund', '--prefer-offline', '--loglevel=error', tarball], project, 240000, { ONNXRUNTIME_NODE_INSTALL: 'skip' });
  ok(r, 'npm install of the tarball');
  timings.install = r.ms;
  installed = join(project, 'node_modules/hawor');
  // postinstall converted the networks into the package; none came in the tarball.
  for (const n of MODEL_NAMES) assert.ok(existsSync(join(installed, 'web/models', `${n}.onnx`)), `postinstall: ${n}.onnx`);

  r = hawor(['--help']);
  ok(r, 'npx hawor --help');
  assert.match(r.stdout, /usage: hawor run VIDEO\|--sample --out DIR/);

  const out = join(project, 'out');
  r = hawor(['run', '--sample', '--out', out, '--max-frames', '30']);
  ok(r, 'npx hawor run --sample');
  timings.run = r.ms;
  const sample = JSON.parse(readFileSync(join(installed, 'dist/sample.json'), 'utf8'));
  assert.match(r.stderr, new RegExp(`the built-in sample ${join(installed, 'dist/sample.webm').replace(/[.*+?^${}()|[\]\\]/g, '\\$&')}`));
  const summary = JSON.parse(r.stdout.trim().split('\n').pop());
  assert.equal(summary.frames, 30);
  assert.equal(summary.runtime, 'native', 'the optional onnxruntime-node was installed and runs the networks');
  assert.equal(summary.focalGuess ?? summary.focal, sample.fx, 'the sample\'s true focal is the starting focal');
  assert.ok(summary.leftFrames + summary.rightFrames > 0, JSON.stringify(summary));
  const result = JSON.parse(readFileSync(join(out, 'result.json'), 'utf8'));
  assert.equal(result.frameCount, 30);
  assert.equal(result.width, sample.width);
  for (const f of ['world.npz', 'hands_cam.npz']) assert.equal(readFileSync(join(out, f)).subarray(0, 2).toString(), 'PK', f);
  const tum = readFileSync(join(out, 'camera.tum'), 'utf8').split('\n').filter((l) => l && !l.startsWith('#'));
  assert.equal(tum.length, 30);
  for (const l of tum) assert.ok(l.trim().split(/\s+/).map(Number).every(Number.isFinite) && l.trim().split(/\s+/).length === 8, l);

  // An install without scripts has no networks: the CLI converts them on its first run.
  rmSync(join(installed, 'web/models'), { recursive: true, force: true });
  r = hawor(['run', '--sample', '--out', join(project, 'out2'), '--max-frames', '6']);
  ok(r, 'npx hawor run without converted networks');
  timings.runConverting = r.ms;
  assert.match(r.stderr, /converted MediaPipe's hand networks to ONNX in .*node_modules\/hawor\/web\/models/);
  assert.ok(existsSync(join(project, 'out2/result.json')));

  // Bad setups: clear messages, exit code 1.
  r = hawor(['run', '--sample', '--out', join(project, 'out3'), '--core', join(project, 'none/hawor_core.mjs')]);
  assert.equal(r.status, 1, r.stderr);
  assert.match(r.stderr, /^hawor: the WebAssembly core hawor_core\.mjs is missing \(.*none\/hawor_core\.mjs\): build it with/m);
  renameSync(join(installed, 'dist/hawor_core.mjs'), join(installed, 'dist/moved.mjs'));
  try {
    r = hawor(['run', '--sample', '--out', join(project, 'out3')]);
    assert.equal(r.status, 1, r.stderr);
    // The message lists every folder the resolver looked in (core.mjs's BUILT_DIRS, in order).
    const looked = BUILT_DIRS.map((d) => `${d}/`).join(', ').replace(/[/.]/g, '\\$&');
    assert.match(r.stderr, new RegExp(`the WebAssembly core hawor_core\\.mjs is missing \\(not in ${looked} of .*node_modules/hawor/\\)`));
  } finally {
    renameSync(join(installed, 'dist/moved.mjs'), join(installed, 'dist/hawor_core.mjs'));
  }
  r = hawor(['run', join(installed, 'dist/sample.json'), '--out', join(project, 'out3')]);
  assert.equal(r.status, 1, r.stderr);
  assert.match(r.stderr, /sample\.json: not a readable video/);

  // The modules, imported by their package names from the consumer's folder.
  r = run(process.execPath, ['--input-type=module', '-e', `
    import { loadCore, builtFile } from 'hawor/core';
    import { runPipeline, defaultIntrinsics } from 'hawor/pipeline';
    import { HandTracker } from 'hawor/perception';
    import { resultToTum, buildGlb } from 'hawor/export';
    import { createRequire } from 'node:module';
    const core = await loadCore();
    const k = defaultIntrinsics(640, 480);
    console.log(JSON.stringify({ core: typeof core.MonoSlam, hand: typeof core.HandModel, run: typeof runPipeline, tracker: typeof HandTracker,
      tum: typeof resultToTum, glb: typeof buildGlb, fx: Math.round(k.fx * 1e6) / 1e6, wasm: await builtFile('hawor_core.wasm'),
      version: createRequire(import.meta.url)('hawor/package.json').version }));`], project);
  ok(r, 'imports of hawor/core, hawor/pipeline, hawor/perception, hawor/export');
  const got = JSON.parse(r.stdout.trim().split('\n').pop());
  assert.deepEqual(got, { core: 'function', hand: 'function', run: 'function', tracker: 'function', tum: 'function', glb: 'function', fx: 400,
    wasm: join(installed, 'dist/hawor_core.wasm'), version: pkg.version });
  assert.deepEqual(readdirSync(join(installed, 'dist')).sort(), ['hawor_core.mjs', 'hawor_core.wasm', 'sample.json', 'sample.webm']);
});
