// The README's commands run as written. Every fenced `sh` block of README.md runs in order
// (bash -euo pipefail, from the repository root, HOME = a fresh folder so that ~/... lands there),
// except those SKIP lists with the reason. Before that, the files the README's other code blocks
// describe are written from those blocks (~/my_app/CMakeLists.txt and main.cpp,
// ~/my_js_app/example.mjs), and ~/clips/ gets two short clips cut from the built-in sample. A
// block that starts the app's server runs until the server answers over HTTP, then is stopped.
// EXPECT checks what some blocks must have produced beyond their exit status.
//
//   bash scripts/build_web.sh && node --test tests/docs/
//
// Needs the suite's builds (build/native, the WebAssembly core, the sample) and npm's cache or
// registry (the JavaScript quick start installs the packed tarball).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, readdirSync, rmSync, writeFileSync } from 'node:fs';
import { homedir, tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { spawn, spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { builtFile } from '../../web/src/core.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const readme = readFileSync(join(root, 'README.md'), 'utf8');

/** The fenced code blocks of a Markdown text: [{lang, code, line}]. */
export function codeBlocks(md) {
  const out = [];
  const re = /^```([\w+-]*)[^\n]*\n([\s\S]*?)^```[ \t]*$/gm;
  for (const m of md.matchAll(re)) out.push({ lang: m[1], code: m[2], line: md.slice(0, m.index).split('\n').length });
  return out;
}

// Blocks not run, each named by a string only it contains.
const SKIP = [
  ['scripts/test.sh', 'the whole suite: it is what runs this test'],
  ['--mano ~/mano', "needs the user's own MANO files (licence-restricted, never in the repository)"],
];
// Blocks that end in a server (it never exits on its own).
const SERVERS = ['scripts/serve.sh', 'scripts/demo.sh'];
// Files written from the README's code blocks before the sh blocks run: [file under HOME, lang, marker].
const FILES = [
  ['my_app/CMakeLists.txt', 'cmake', 'find_package(hawor'],
  ['my_app/main.cpp', 'cpp', 'int main'],
  ['my_js_app/example.mjs', 'js', "from 'hawor/core'"],
];
// What some blocks must leave behind (the block is named by a string it contains).
const EXPECT = [
  ['run ~/clips/kitchen.mp4 --out ~/hawor-out/kitchen --fov', (h) => resultFrames(join(h, 'hawor-out/kitchen'))],
  ['batch --summary ~/hawor-batch', (h, out) => {
    assert.match(out, /: 2 clips .*: 2 ok, 0 failed/);
    const desk = readdirSync(join(h, 'hawor-batch')).find((n) => n.startsWith('desk-'));
    assert.ok(desk, 'a desk-<hash> clip folder');
    resultFrames(join(h, 'hawor-batch', desk));
  }],
  ['hawor world --images ~/frames/kitchen', (h, out) => {
    assert.ok(existsSync(join(h, 'hawor-out/kitchen-world/world.npz')) && existsSync(join(h, 'hawor-out/kitchen-world/camera.tum')));
    assert.equal(JSON.parse(out.trim().split('\n').pop()).frames, JSON.parse(readFileSync(join(h, 'hawor-out/kitchen/result.json'), 'utf8')).frameCount);
  }],
  ['~/my_app/build/my_app', (h, out) => assert.match(out, /1360 vertices, 21 keypoints, PA-MPJPE 0\.0000\d\d mm/)],
  ['npx hawor run --sample', (h) => resultFrames(join(h, 'my_js_app/sample-out'))],
  ['node example.mjs', (h, out) => assert.match(out, /^function function \[ ?0, ?0, ?0, ?1 ?\]$/m)],
];

function resultFrames(dir) {
  const r = JSON.parse(readFileSync(join(dir, 'result.json'), 'utf8'));
  assert.ok(r.frameCount > 0 && existsSync(join(dir, 'world.npz')) && existsSync(join(dir, 'camera.tum')), dir);
}

const blocks = codeBlocks(readme);
let home;
// The children's environment: HOME is the sandbox; npm keeps its real cache (warm after
// scripts/install.sh); the suite's HAWOR_* variables are dropped (the README's commands find
// their own files); a C++ compiler as the suite's (clang when installed) for the CMake example.
const env = () => {
  const e = Object.fromEntries(Object.entries(process.env).filter(([k]) => !k.startsWith('HAWOR_')));
  e.npm_config_cache ??= join(homedir(), '.npm');
  e.HOME = home;
  if (!e.CXX && spawnSync('clang++', ['--version']).status === 0) e.CXX = 'clang++';
  return e;
};

before(async () => {
  home = mkdtempSync(join(tmpdir(), 'hawor-readme-'));
  for (const [file, lang, marker] of FILES) {
    const hits = blocks.filter((b) => b.lang === lang && b.code.includes(marker));
    assert.equal(hits.length, 1, `README: one \`\`\`${lang} block with ${marker} (found ${hits.length})`);
    mkdirSync(dirname(join(home, file)), { recursive: true });
    writeFileSync(join(home, file), hits[0].code);
  }
  const sample = await builtFile('sample.webm');
  assert.ok(sample, 'the built-in sample is missing: bash scripts/build_web.sh');
  mkdirSync(join(home, 'clips'));
  for (const [name, start] of [['kitchen', 0], ['desk', 1]]) {
    const r = spawnSync('ffmpeg', ['-v', 'error', '-y', '-ss', String(start), '-i', sample, '-frames:v', '20',
      '-c:v', 'libx264', '-pix_fmt', 'yuv420p', join(home, 'clips', `${name}.mp4`)], { encoding: 'utf8' });
    assert.equal(r.status, 0, r.stderr);
  }
});
after(() => {
  if (home) rmSync(home, { recursive: true, force: true });
});

test('README: the skip, server, file and expectation lists each name one block', () => {
  const sh = blocks.filter((b) => b.lang === 'sh');
  assert.ok(sh.length >= 6, `README has ${sh.length} sh blocks`);
  for (const [marker] of [...SKIP, ...EXPECT, ...SERVERS.map((s) => [s])]) {
    assert.equal(sh.filter((b) => b.code.includes(marker)).length, 1, `one sh block contains ${marker}`);
  }
  assert.ok(readme.split('\n').length <= 300, 'README.md is at most 300 lines');
});

/** Runs a server block until its first `hawor app: URL` line, fetches the URL, stops it. */
async function runServer(code) {
  const child = spawn('bash', ['-euo', 'pipefail', '-c', code], {
    cwd: root, env: { ...env(), PORT: '0', HOST: '127.0.0.1' }, detached: true, stdio: ['ignore', 'pipe', 'pipe'] });
  let log = '';
  try {
    const url = await new Promise((res, rej) => {
      const timer = setTimeout(() => rej(new Error(`no 'hawor app:' line within 300 s:\n${log.slice(-3000)}`)), 300000);
      const onData = (d) => {
        log += d;
        const m = /hawor app: (http:\/\/\S+)/.exec(log);
        if (m) { clearTimeout(timer); res(m[1]); }
      };
      child.stdout.on('data', onData);
      child.stderr.on('data', onData);
      child.on('exit', (c) => { clearTimeout(timer); rej(new Error(`exited ${c} before serving:\n${log.slice(-3000)}`)); });
    });
    const r = await fetch(url);
    assert.equal(r.status, 200, url);
    assert.match(await r.text(), /<title>hawor/i);
    return log;
  } finally {
    try { process.kill(-child.pid, 'SIGTERM'); } catch { /* already gone */ }
  }
}

for (const b of blocks.filter((x) => x.lang === 'sh')) {
  const skip = SKIP.find(([m]) => b.code.includes(m));
  const title = `README line ${b.line}: ${b.code.trim().split('\n')[0].slice(0, 70)}`;
  test(title, { skip: skip ? skip[1] : false, timeout: 600000 }, async () => {
    let out;
    if (SERVERS.some((s) => b.code.includes(s))) {
      out = await runServer(b.code);
    } else {
      const r = spawnSync('bash', ['-euo', 'pipefail', '-c', b.code], { cwd: root, env: env(), encoding: 'utf8', timeout: 600000, maxBuffer: 64 << 20 });
      assert.equal(r.status, 0, `exit ${r.status} ${r.error ?? ''}\n--- stdout\n${(r.stdout || '').slice(-2000)}\n--- stderr\n${(r.stderr || '').slice(-4000)}`);
      out = r.stdout;
    }
    for (const [marker, check] of EXPECT) if (b.code.includes(marker)) check(home, out);
  });
}
