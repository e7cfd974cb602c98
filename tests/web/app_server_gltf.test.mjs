// The browser app's static server (headers, MIME types, routes, ranges, no path escapes) and the
// glTF/GLB exporter (Khronos validator, three's GLTFLoader, the flip-book animation's keys).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { mkdtempSync, mkdirSync, writeFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { createServer, resolvePath, packageRoot } from '../../web/server.mjs';
import { buildGlb } from '../../web/src/export/gltf.mjs';

function fakeRepo() {
  const root = mkdtempSync(join(tmpdir(), 'hawor-srv-'));
  for (const d of ['web/app', 'web/src', 'web/models', 'build/wasm/wasm', 'build/web', 'dist', 'node_modules/three/build', 'node_modules/secret']) mkdirSync(join(root, d), { recursive: true });
  writeFileSync(join(root, 'web/app/index.html'), '<!doctype html>');
  writeFileSync(join(root, 'web/app/app.mjs'), 'export {}');
  writeFileSync(join(root, 'web/cli.mjs'), 'no');
  writeFileSync(join(root, 'build/wasm/wasm/hawor_core.wasm'), Buffer.from([0, 97, 115, 109, 1, 0, 0, 0]));
  writeFileSync(join(root, 'build/web/sample.webm'), Buffer.from('0123456789'));
  writeFileSync(join(root, 'build/web/sample.json'), '{"from": "build"}');
  writeFileSync(join(root, 'dist/sample.json'), '{"from": "dist"}');
  writeFileSync(join(root, 'dist/packed.json'), '{"from": "dist"}');
  // three's exports hide its package.json: the server finds the folder from the entry point.
  writeFileSync(join(root, 'node_modules/three/package.json'), JSON.stringify({ name: 'three', exports: { '.': { import: './build/three.module.js', require: './build/three.cjs' } } }));
  writeFileSync(join(root, 'node_modules/three/build/three.module.js'), 'export {}');
  writeFileSync(join(root, 'node_modules/three/build/three.cjs'), '');
  writeFileSync(join(root, 'node_modules/secret/x.js'), 'no');
  writeFileSync(join(root, 'package.json'), '{}');
  return root;
}

test('server: isolation headers, MIME types, ranges, only the routed folders', async () => {
  const root = fakeRepo();
  const server = createServer(root);
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  const base = `http://127.0.0.1:${server.address().port}`;
  try {
    const moved = await fetch(`${base}/`, { redirect: 'manual' });
    assert.equal(moved.status, 302);
    assert.equal(moved.headers.get('location'), '/web/app/');
    await moved.text();
    const page = await fetch(`${base}/`);
    assert.equal(page.status, 200);
    assert.equal(page.url, `${base}/web/app/`);
    assert.equal(await page.text(), '<!doctype html>');
    assert.equal(page.headers.get('cross-origin-opener-policy'), 'same-origin');
    assert.equal(page.headers.get('cross-origin-embedder-policy'), 'require-corp');
    assert.match(page.headers.get('content-type'), /^text\/html/);
    const types = { '/web/app/app.mjs': /^text\/javascript/, '/dist/hawor_core.wasm': /^application\/wasm$/, '/dist/sample.webm': /^video\/webm$/,
      '/node_modules/three/build/three.module.js': /^text\/javascript/ };
    for (const [p, re] of Object.entries(types)) {
      const r = await fetch(base + p);
      assert.equal(r.status, 200, p);
      assert.match(r.headers.get('content-type'), re, p);
      assert.equal(r.headers.get('cross-origin-embedder-policy'), 'require-corp', p);
      await r.arrayBuffer();
    }
    // /dist/: a checkout's build folders first (a dist/ staged by an earlier npm pack may be
    // older), then the package's dist/.
    assert.deepEqual(await (await fetch(`${base}/dist/sample.json`)).json(), { from: 'build' });
    assert.deepEqual(await (await fetch(`${base}/dist/packed.json`)).json(), { from: 'dist' });
    const part = await fetch(`${base}/dist/sample.webm`, { headers: { Range: 'bytes=2-5' } });
    assert.equal(part.status, 206);
    assert.equal(await part.text(), '2345');
    assert.equal(part.headers.get('content-range'), 'bytes 2-5/10');
    for (const p of ['/package.json', '/node_modules/secret/x.js', '/web/cli.mjs', '/app/app.mjs', '/web/app/../../package.json', '/web/app/%2e%2e/%2e%2e/package.json',
      '/web/app/..%2f..%2fpackage.json', '/dist/..%2fpackage.json', '/dist/%2e%2e/build/web/sample.json', '/web/app/missing.js']) {
      const r = await fetch(base + p);
      assert.equal(r.status, 404, p);
      await r.text();
    }
    const post = await fetch(`${base}/`, { method: 'POST', body: 'x' });
    assert.equal(post.status, 405);
    await post.text();
  } finally {
    server.close();
    rmSync(root, { recursive: true, force: true });
  }
  assert.equal(resolvePath('/r', '/web/app/..%2f..%2f..%2fetc/passwd'), null);
  assert.equal(resolvePath('/r', '/dist/..%2f..%2fetc/passwd'), null);
  assert.equal(resolvePath('/r', '/etc/passwd'), null);
});

test('server: npm packages are found where npm put them (hoisted beside an installed package)', () => {
  const proj = mkdtempSync(join(tmpdir(), 'hawor-srv-hoist-'));
  try {
    const root = join(proj, 'node_modules/hawor');
    const three = join(proj, 'node_modules/three');
    mkdirSync(root, { recursive: true });
    mkdirSync(join(three, 'build'), { recursive: true });
    // three's exports hide its package.json: the folder is found from its entry point.
    writeFileSync(join(three, 'package.json'), JSON.stringify({ name: 'three', exports: { '.': { import: './build/three.module.js', require: './build/three.cjs' } } }));
    writeFileSync(join(three, 'build/three.cjs'), '');
    writeFileSync(join(three, 'build/three.module.js'), 'export {}');
    assert.equal(packageRoot(root, 'three'), three);
    assert.equal(resolvePath(root, '/node_modules/three/build/three.module.js'), join(three, 'build/three.module.js'));
    assert.equal(packageRoot(root, 'not-installed'), join(root, 'node_modules/not-installed'));
  } finally {
    rmSync(proj, { recursive: true, force: true });
  }
});

/// A tetrahedron moving along x, present in frames 0, 1 and 3 of 5 (frame 3 infilled).
function tinyHand(T, dx) {
  const base = [0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1];
  const V = 4;
  const vertices = new Float32Array(T * V * 3);
  for (let t = 0; t < T; t++) for (let v = 0; v < V; v++) for (let k = 0; k < 3; k++) vertices[(t * V + v) * 3 + k] = base[v * 3 + k] + (k === 0 ? dx * t : 0);
  return { numVertices: V, faces: Uint32Array.from([0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2]), vertices,
    present: Uint8Array.from([1, 1, 0, 1, 0]), infilled: Uint8Array.from([0, 0, 0, 1, 0]) };
}

test('gltf: valid GLB; three.js reads the hands, camera, path and points with the flip-book animation', async () => {
  const T = 5, fps = 10;
  const camera = { positions: [[0, 0, 0], [0.1, 0, 0], [0.2, 0, 0], [0.3, 0, 0], [0.4, 0, 0]],
    quaternions: Array.from({ length: T }, () => [0, 0, 0, 1]), width: 640, height: 480, fx: 500, fy: 500 };
  const glb = buildGlb({ fps, frameCount: T, hands: { left: tinyHand(T, 0.1), right: tinyHand(T, -0.1) }, camera,
    points: [[0, 0, 1], [1, NaN, 2], [0.5, 0.5, 2]] });
  assert.equal(new DataView(glb.buffer).getUint32(0, true), 0x46546c67);
  assert.equal(new DataView(glb.buffer).getUint32(8, true), glb.byteLength);
  const validator = (await import('gltf-validator')).default;
  const report = await validator.validateBytes(glb);
  assert.equal(report.issues.numErrors, 0, JSON.stringify(report.issues.messages));
  assert.equal(report.issues.numWarnings, 0, JSON.stringify(report.issues.messages));

  const THREE = await import('three');
  const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
  const gltf = await new Promise((res, rej) => new GLTFLoader().parse(glb.buffer.slice(glb.byteOffset, glb.byteOffset + glb.byteLength), '', res, rej));
  const right = gltf.scene.getObjectByName('right_hand');
  assert.deepEqual(right.children.map((c) => c.name), ['right_hand_f00000', 'right_hand_f00001', 'right_hand_f00003_infilled']);
  assert.equal(gltf.cameras.length, 1);
  assert.ok(Math.abs(gltf.cameras[0].fov - 2 * Math.atan(240 / 500) * 180 / Math.PI) < 1e-3, `fov ${gltf.cameras[0].fov}`);
  const pts = gltf.scene.getObjectByName('slam_points');
  assert.equal(pts.geometry.getAttribute('position').count, 2, 'the non-finite point is dropped');
  // Play the animation: at t = 1/fps only frame 1's mesh is shown, the camera is at x = 0.1.
  const mixer = new THREE.AnimationMixer(gltf.scene);
  mixer.clipAction(gltf.animations[0]).play();
  const shown = (time) => { mixer.setTime(time); return right.children.filter((c) => c.scale.x > 0.5).map((c) => c.name); };
  assert.deepEqual(shown(0.0), ['right_hand_f00000']);
  assert.deepEqual(shown(0.1 + 1e-4), ['right_hand_f00001']);
  assert.deepEqual(shown(0.2 + 1e-4), []);
  assert.deepEqual(shown(0.3 + 1e-4), ['right_hand_f00003_infilled']);
  mixer.setTime(0.1 + 1e-4);
  assert.ok(Math.abs(gltf.scene.getObjectByName('camera').position.x - 0.1) < 1e-3);
  // World vertices are kept exactly; the root turns hawor's y-down world to glTF's y-up.
  const f1 = right.children[1];
  const p = f1.geometry.getAttribute('position');
  assert.ok(Math.abs(p.getX(1) - (1 - 0.1)) < 1e-6);
  const world = new THREE.Vector3(0, 1, 0).applyQuaternion(gltf.scene.getObjectByName('hawor_world').quaternion);
  assert.ok(Math.abs(world.y + 1) < 1e-6, 'y down becomes y up');
  // A gravity-aligned result (z up): its z becomes glTF's y.
  const g2 = buildGlb({ fps, frameCount: T, camera, world: { convention: 'z-up' } });
  const zUp = await new Promise((res, rej) => new GLTFLoader().parse(g2.buffer.slice(g2.byteOffset, g2.byteOffset + g2.byteLength), '', res, rej));
  const upward = new THREE.Vector3(0, 0, 1).applyQuaternion(zUp.scene.getObjectByName('hawor_world').quaternion);
  assert.ok(Math.abs(upward.y - 1) < 1e-6, 'z up becomes y up');
  // Bad input is refused.
  assert.throws(() => buildGlb({ fps: 0, frameCount: T }), /fps/);
  assert.throws(() => buildGlb({ fps, frameCount: T, hands: { left: tinyHand(4, 0) } }), /vertex values/);
});
