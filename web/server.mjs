#!/usr/bin/env node
// web/server.mjs — the static server of the browser app (node, no dependencies).
//
//   node web/server.mjs [--port 8080] [--host 127.0.0.1] [--root DIR]
//
// Serves the page and exactly the files it needs. URLs follow the npm package's own layout, so
// the app's relative imports (and index.html's import map) also work from any static host of an
// installed package; only /dist/ and /node_modules/ are looked up:
//   /                 redirects to /web/app/ (index.html)
//   /web/app/...      web/app/            the page, its modules and the Web Worker
//   /web/src/...      web/src/            the shared JavaScript (core loader, perception, pipeline, exports)
//   /web/tools/...    web/tools/          shared helpers the exports import (npz.mjs)
//   /web/models/...   web/models/         the ONNX hand networks converted at install
//   /dist/...         build/wasm/wasm/ and build/web/ (checkout), else dist/ (installed package):
//                     hawor_core.mjs + .wasm, the synthetic sample
//   /node_modules/{three,onnxruntime-web,@webxr-input-profiles/assets}/...   the npm packages the
//                     page loads (three.js, onnxruntime-web, the default hand), found by node's
//                     module resolution from ROOT (hoisted beside an installed package)
// Every response carries Cross-Origin-Opener-Policy: same-origin and
// Cross-Origin-Embedder-Policy: require-corp (cross-origin isolation: SharedArrayBuffer, so
// onnxruntime-web can use threads) and Cross-Origin-Resource-Policy: same-origin. Nothing is
// ever written: the page has no upload endpoint, only GET and HEAD are answered.
// Prints one line `hawor app: http://HOST:PORT/` once listening.
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';
import { BUILT_DIRS } from './src/core.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));

export const MIME = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.mjs': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8',
  '.json': 'application/json; charset=utf-8',
  '.wasm': 'application/wasm',
  '.onnx': 'application/octet-stream',
  '.npz': 'application/octet-stream',
  '.bin': 'application/octet-stream',
  '.glb': 'model/gltf-binary',
  '.webm': 'video/webm',
  '.mp4': 'video/mp4',
  '.png': 'image/png',
  '.svg': 'image/svg+xml',
  '.txt': 'text/plain; charset=utf-8',
  '.map': 'application/json; charset=utf-8',
};

/// The npm packages the page loads (index.html's import map names the same URLs).
export const PACKAGES = ['three', 'onnxruntime-web', '@webxr-input-profiles/assets'];

/// An npm package's folder as node resolves it from `root` (a package whose exports hide
/// package.json is found from its entry point), or ROOT/node_modules/NAME when not resolvable.
export function packageRoot(root, name) {
  const req = createRequire(path.join(root, 'package.json'));
  try { return path.dirname(req.resolve(`${name}/package.json`)); } catch { /* not exported */ }
  try {
    for (let d = path.dirname(req.resolve(name)); d !== path.dirname(d); d = path.dirname(d)) {
      const pj = path.join(d, 'package.json');
      if (fs.existsSync(pj) && JSON.parse(fs.readFileSync(pj, 'utf8')).name === name) return d;
    }
  } catch { /* not installed */ }
  return path.join(root, 'node_modules', name);
}

const routeCache = new Map();
/// URL prefix -> folders tried in order (absolute).
export function routes(root) {
  if (!routeCache.has(root)) {
    routeCache.set(root, [
      ['/web/app/', [path.join(root, 'web/app')]],
      ['/web/src/', [path.join(root, 'web/src')]],
      ['/web/tools/', [path.join(root, 'web/tools')]],
      ['/web/models/', [path.join(root, 'web/models')]],
      ['/dist/', BUILT_DIRS.map((d) => path.join(root, d))],
      ...PACKAGES.map((name) => [`/node_modules/${name}/`, [packageRoot(root, name)]]),
    ]);
  }
  return routeCache.get(root);
}

/// The file a URL path names, or null (outside every route, `..`, or not a plain file). Of a
/// route with several folders, the first that holds the file.
export function resolvePath(root, urlPath) {
  let p;
  try { p = decodeURIComponent(urlPath); } catch { return null; }
  if (p.includes('\0')) return null;
  if (p === '/web/app/') p = '/web/app/index.html';
  for (const [prefix, dirs] of routes(root)) {
    if (!p.startsWith(prefix)) continue;
    let first = null;
    for (const dir of dirs) {
      const file = path.resolve(dir, '.' + p.slice(prefix.length - 1));
      if (file !== dir && !file.startsWith(dir + path.sep)) return null;
      if (fs.existsSync(file)) return file;
      first ??= file;
    }
    return first;
  }
  return null;
}

function send(res, status, body, type = 'text/plain; charset=utf-8') {
  res.writeHead(status, { 'Content-Type': type, ...isolationHeaders(), 'Content-Length': Buffer.byteLength(body) });
  res.end(body);
}

export function isolationHeaders() {
  return {
    'Cross-Origin-Opener-Policy': 'same-origin',
    'Cross-Origin-Embedder-Policy': 'require-corp',
    'Cross-Origin-Resource-Policy': 'same-origin',
    'X-Content-Type-Options': 'nosniff',
  };
}

export function createServer(root) {
  return http.createServer((req, res) => {
    if (req.method !== 'GET' && req.method !== 'HEAD') return send(res, 405, 'method not allowed\n');
    const urlPath = new URL(req.url, 'http://x').pathname;
    if (urlPath === '/' || urlPath === '/index.html' || urlPath === '/web/app') {
      res.writeHead(302, { Location: '/web/app/', 'Content-Length': 0, ...isolationHeaders() });
      return res.end();
    }
    const file = resolvePath(root, urlPath);
    if (!file) return send(res, 404, `not found: ${urlPath}\n`);
    fs.stat(file, (err, st) => {
      if (err || !st.isFile()) return send(res, 404, `not found: ${urlPath}\n`);
      const type = MIME[path.extname(file).toLowerCase()] || 'application/octet-stream';
      const headers = { 'Content-Type': type, 'Cache-Control': 'no-cache', ...isolationHeaders() };
      // Range requests: <video> seeks with them.
      const range = req.headers.range && /^bytes=(\d*)-(\d*)$/.exec(req.headers.range);
      let start = 0, end = st.size - 1, status = 200;
      if (range && st.size > 0) {
        if (range[1] === '' && range[2] !== '') { start = Math.max(0, st.size - Number(range[2])); }
        else { start = Number(range[1] || 0); if (range[2] !== '') end = Math.min(end, Number(range[2])); }
        if (start > end || start >= st.size) {
          res.writeHead(416, { ...headers, 'Content-Range': `bytes */${st.size}` });
          return res.end();
        }
        status = 206;
        headers['Content-Range'] = `bytes ${start}-${end}/${st.size}`;
      }
      headers['Accept-Ranges'] = 'bytes';
      headers['Content-Length'] = st.size === 0 ? 0 : end - start + 1;
      res.writeHead(status, headers);
      if (req.method === 'HEAD' || st.size === 0) return res.end();
      fs.createReadStream(file, { start, end }).on('error', () => res.destroy()).pipe(res);
    });
  });
}

function parseArgs(argv) {
  const o = { port: 8080, host: '127.0.0.1', root: path.resolve(here, '..') };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i], v = argv[i + 1];
    if (a === '--port') { o.port = Number(v); i++; }
    else if (a === '--host') { o.host = v; i++; }
    else if (a === '--root') { o.root = path.resolve(v); i++; }
    else if (a === '--help' || a === '-h') {
      console.log('usage: node web/server.mjs [--port N (0: any free)] [--host H] [--root DIR (the checkout or the installed package)]');
      process.exit(0);
    } else { console.error(`server: unknown argument ${a}`); process.exit(2); }
  }
  if (!Number.isInteger(o.port) || o.port < 0 || o.port > 65535) { console.error('server: --port wants 0..65535'); process.exit(2); }
  return o;
}

/// The hand networks the page fetches: converted first when missing (an install without scripts).
async function ensureModels(root) {
  const dir = path.join(root, 'web/models');
  try {
    const { ensureMediapipeModels } = await import('./tools/convert_mediapipe.mjs');
    if (ensureMediapipeModels(dir).converted) console.error(`server: converted MediaPipe's hand networks into ${dir}`);
  } catch (e) {
    console.error(`server: warning: the hand networks are missing in ${dir} and could not be converted (${e.message}); the page will say so`);
  }
}

const invoked = (() => { try { return process.argv[1] && fs.realpathSync(process.argv[1]); } catch { return null; } })();
if (invoked === fileURLToPath(import.meta.url)) {
  const o = parseArgs(process.argv.slice(2));
  await ensureModels(o.root);
  const server = createServer(o.root);
  server.on('error', (e) => { console.error(`server: ${e.message}`); process.exit(1); });
  server.listen(o.port, o.host, () => {
    const { port } = server.address();
    console.log(`hawor app: http://${o.host}:${port}/`);
  });
}
