#!/usr/bin/env node
// web/server.mjs — the static server of the browser app (node, no dependencies).
//
//   node web/server.mjs [--port 8080] [--host 127.0.0.1] [--root DIR]
//
// Serves the page and exactly the files it needs, each from where the build leaves it:
//   /                 web/app/index.html
//   /app/...          web/app/            the page, its modules and the Web Worker
//   /src/...          web/src/            the shared JavaScript (perception, pipeline, exports)
//   /tools/...        web/tools/          shared helpers the exports import (npz.mjs)
//   /models/...       web/models/         the ONNX hand networks converted at install
//   /core/...         build/wasm/wasm/    hawor_core.mjs + hawor_core.wasm
//   /assets/...       build/web/          the default hand models and the synthetic sample
//   /node_modules/three/..., /node_modules/onnxruntime-web/...   the two npm runtimes the page loads
// Every response carries Cross-Origin-Opener-Policy: same-origin and
// Cross-Origin-Embedder-Policy: require-corp (cross-origin isolation: SharedArrayBuffer, so
// onnxruntime-web can use threads) and Cross-Origin-Resource-Policy: same-origin. Nothing is
// ever written: the page has no upload endpoint, only GET and HEAD are answered.
// Prints one line `hawor app: http://HOST:PORT/` once listening.
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

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

/// URL prefix -> folder (relative to the repository root).
export function routes(root) {
  return [
    ['/app/', path.join(root, 'web/app')],
    ['/src/', path.join(root, 'web/src')],
    ['/tools/', path.join(root, 'web/tools')],
    ['/models/', path.join(root, 'web/models')],
    ['/core/', path.join(root, 'build/wasm/wasm')],
    ['/assets/', path.join(root, 'build/web')],
    ['/node_modules/three/', path.join(root, 'node_modules/three')],
    ['/node_modules/onnxruntime-web/', path.join(root, 'node_modules/onnxruntime-web')],
  ];
}

/// The file a URL path names, or null (outside every route, `..`, or not a plain file).
export function resolvePath(root, urlPath) {
  let p;
  try { p = decodeURIComponent(urlPath); } catch { return null; }
  if (p.includes('\0')) return null;
  if (p === '/' || p === '/index.html') return path.join(root, 'web/app/index.html');
  for (const [prefix, dir] of routes(root)) {
    if (!p.startsWith(prefix)) continue;
    const file = path.resolve(dir, '.' + p.slice(prefix.length - 1));
    if (file !== dir && !file.startsWith(dir + path.sep)) return null;
    return file;
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
      console.log('usage: node web/server.mjs [--port N (0: any free)] [--host H] [--root REPO]');
      process.exit(0);
    } else { console.error(`server: unknown argument ${a}`); process.exit(2); }
  }
  if (!Number.isInteger(o.port) || o.port < 0 || o.port > 65535) { console.error('server: --port wants 0..65535'); process.exit(2); }
  return o;
}

if (process.argv[1] && path.resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  const o = parseArgs(process.argv.slice(2));
  const server = createServer(o.root);
  server.on('error', (e) => { console.error(`server: ${e.message}`); process.exit(1); });
  server.listen(o.port, o.host, () => {
    const { port } = server.address();
    console.log(`hawor app: http://${o.host}:${port}/`);
  });
}
