// view3d.mjs — the 3D view (three.js): world-space hand meshes of the current frame, the wrist
// tracks of both hands, the camera path, the current camera frustum and the SLAM points.
// Display only: every position comes from the result or the core's hand meshes.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

export const SIDE_COLORS = { left: 0x2f7df6, right: 0xf2762e };
const PALE = { left: 0x9cc0fb, right: 0xf9bd98 };

/// Flat Float32Array of a (T,n) array given flat or nested (nulls become NaN).
export function flat(a, n) {
  if (a == null) return null;
  if (a.length && a[0] != null && typeof a[0] === 'object') {
    const out = new Float32Array(a.length * n);
    a.forEach((r, i) => { for (let k = 0; k < n; k++) out[i * n + k] = r[k] == null ? NaN : r[k]; });
    return out;
  }
  return Float32Array.from(a, (v) => (v == null ? NaN : v));
}

/// Camera poses of a result: { positions Float32Array(3T), quaternions Float32Array(4T) x,y,z,w }.
export function cameraPoses(result) {
  const c = result.camera || {};
  const T = result.frameCount;
  if (c.positions && c.quaternions) return { positions: flat(c.positions, 3), quaternions: flat(c.quaternions, 4) };
  const rows = c.tum || c.rows || (Array.isArray(c) ? c : null);
  if (rows) {
    const R = flat(rows, 8), positions = new Float32Array(3 * T), quaternions = new Float32Array(4 * T);
    for (let t = 0; t < T; t++) { positions.set(R.subarray(8 * t + 1, 8 * t + 4), 3 * t); quaternions.set(R.subarray(8 * t + 4, 8 * t + 8), 4 * t); }
    return { positions, quaternions };
  }
  return { positions: new Float32Array(3 * T).fill(NaN), quaternions: new Float32Array(4 * T).fill(NaN) };
}

/// The image corners at depth d in the camera frame (OpenCV), as line segments of a frustum.
function frustumSegments(K, w, h, d) {
  const c = [[-0.5, -0.5], [w - 0.5, -0.5], [w - 0.5, h - 0.5], [-0.5, h - 0.5]]
    .map(([u, v]) => [(u - K.cx) / K.fx * d, (v - K.cy) / K.fy * d, d]);
  const s = [];
  for (let i = 0; i < 4; i++) { s.push(0, 0, 0, ...c[i]); s.push(...c[i], ...c[(i + 1) % 4]); }
  return new Float32Array(s);
}

export class SceneView {
  constructor(canvas) {
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true });
    this.renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x111318);
    this.camera = new THREE.PerspectiveCamera(50, 16 / 9, 0.01, 200);
    this.camera.position.set(0.8, 0.6, 1.2);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.addEventListener('change', () => this.render());
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x333344, 2.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.2);
    sun.position.set(1, 2, 1.5);
    this.scene.add(sun);
    // hawor's world (z up, or the first camera's OpenCV frame, y down) turned to three's y up in
    // setResult.
    this.world = new THREE.Group();
    this.world.rotation.x = Math.PI;
    this.scene.add(this.world);
    this.grid = new THREE.GridHelper(4, 40, 0x3a3e47, 0x262a31);
    this.scene.add(this.grid);
    this.objects = null;
    new ResizeObserver(() => this.resize()).observe(canvas.parentElement);
    this.resize();
  }

  resize() {
    const el = this.canvas.parentElement;
    const w = Math.max(1, el.clientWidth), h = Math.max(1, el.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  clear() {
    if (!this.objects) return;
    this.world.traverse((o) => { if (o.geometry) o.geometry.dispose(); if (o.material) o.material.dispose(); });
    this.world.clear();
    this.objects = null;
    this.render();
  }

  /// result: the pipeline's result; meshes: { left, right } from hand_meshes.mjs.
  setResult(result, meshes) {
    this.clear();
    const T = result.frameCount;
    const o = { T, hands: {}, meshes };
    const zUp = result.world && result.world.convention === 'z-up';
    this.world.rotation.x = zUp ? -Math.PI / 2 : Math.PI;
    const box = new THREE.Box3();
    // Hands: one mesh per side, its vertices replaced every frame.
    for (const side of ['left', 'right']) {
      const m = meshes[side];
      if (!m) continue;
      const geom = new THREE.BufferGeometry();
      geom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(m.numVertices * 3), 3));
      geom.setIndex(new THREE.BufferAttribute(m.faces, 1));
      const observed = new THREE.MeshStandardMaterial({ color: SIDE_COLORS[side], roughness: 0.7, side: THREE.DoubleSide });
      const infilled = new THREE.MeshStandardMaterial({ color: PALE[side], roughness: 0.9, wireframe: true, transparent: true, opacity: 0.7 });
      const mesh = new THREE.Mesh(geom, observed);
      mesh.name = `${side}_hand`;
      mesh.visible = false;
      this.world.add(mesh);
      // The wrist track (joint 0 of the 21 world keypoints) over the frames the hand exists.
      const J = flat(result.hands && result.hands[side] && result.hands[side].jointsWorld, 63);
      const pts = [], cols = [];
      const c = new THREE.Color(SIDE_COLORS[side]), cp = new THREE.Color(PALE[side]);
      for (let t = 0; J && t < T; t++) {
        if (!m.present[t]) continue;
        const x = J[63 * t], y = J[63 * t + 1], z = J[63 * t + 2];
        if (!Number.isFinite(x + y + z)) continue;
        pts.push(x, y, z);
        const k = m.infilled[t] ? cp : c;
        cols.push(k.r, k.g, k.b);
        box.expandByPoint(new THREE.Vector3(x, y, z));
      }
      let track = null;
      if (pts.length >= 6) {
        const g = new THREE.BufferGeometry();
        g.setAttribute('position', new THREE.Float32BufferAttribute(pts, 3));
        g.setAttribute('color', new THREE.Float32BufferAttribute(cols, 3));
        track = new THREE.Line(g, new THREE.LineBasicMaterial({ vertexColors: true }));
        track.name = `${side}_track`;
        this.world.add(track);
      }
      o.hands[side] = { mesh, observed, infilled, track, frames: m.present.reduce((a, b) => a + b, 0), trackPoints: pts.length / 3 };
    }
    // Camera path and frustum.
    const cam = cameraPoses(result);
    o.cam = cam;
    const path = [];
    for (let t = 0; t < T; t++) {
      const p = cam.positions.subarray(3 * t, 3 * t + 3);
      if (Number.isFinite(p[0] + p[1] + p[2])) { path.push(p[0], p[1], p[2]); box.expandByPoint(new THREE.Vector3(p[0], p[1], p[2])); }
    }
    if (path.length >= 6) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.Float32BufferAttribute(path, 3));
      o.path = new THREE.Line(g, new THREE.LineBasicMaterial({ color: 0xdddddd }));
      o.path.name = 'camera_path';
      this.world.add(o.path);
    }
    o.pathPoints = path.length / 3;
    const K = result.intrinsics;
    const size = box.isEmpty() ? 1 : Math.max(0.3, box.getSize(new THREE.Vector3()).length());
    if (K && K.fx) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(frustumSegments(K, result.width, result.height, 0.08 * size), 3));
      o.frustum = new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: 0xffe066 }));
      o.frustum.name = 'camera_frustum';
      this.world.add(o.frustum);
    }
    // SLAM points.
    const P = flat(result.points, 3);
    o.numPoints = 0;
    if (P && P.length) {
      const keep = [];
      for (let i = 0; i + 2 < P.length; i += 3) if (Number.isFinite(P[i] + P[i + 1] + P[i + 2])) keep.push(P[i], P[i + 1], P[i + 2]);
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.Float32BufferAttribute(keep, 3));
      o.points = new THREE.Points(g, new THREE.PointsMaterial({ color: 0x88d888, size: 0.006 * size + 0.002, sizeAttenuation: true }));
      o.points.name = 'slam_points';
      this.world.add(o.points);
      o.numPoints = keep.length / 3;
    }
    this.objects = o;
    // Look at the hands and the path (the points may spread far).
    if (!box.isEmpty()) {
      this.world.updateMatrixWorld(true);
      const cen = box.getCenter(new THREE.Vector3()).applyMatrix4(this.world.matrixWorld);
      // the floor where it was found (the world's z = 0), else below the scene
      this.grid.position.set(cen.x, zUp && result.world.origin === 'floor' ? 0 : cen.y - size * 0.6, cen.z);
      this.controls.target.copy(cen);
      this.camera.position.copy(cen).add(new THREE.Vector3(0.9, 0.7, 1.3).multiplyScalar(size));
      this.camera.near = size / 200; this.camera.far = size * 200; this.camera.updateProjectionMatrix();
      this.controls.update();
    }
    this.setFrame(0);
  }

  setFrame(t) {
    const o = this.objects;
    if (!o) return;
    this.frame = t;
    for (const side of ['left', 'right']) {
      const h = o.hands[side], m = o.meshes[side];
      if (!h) continue;
      const on = !!m.present[t];
      h.mesh.visible = on;
      if (on) {
        const attr = h.mesh.geometry.getAttribute('position');
        attr.array.set(m.vertices.subarray(t * m.numVertices * 3, (t + 1) * m.numVertices * 3));
        attr.needsUpdate = true;
        h.mesh.geometry.computeVertexNormals();
        h.mesh.geometry.computeBoundingSphere();
        h.mesh.material = m.infilled[t] ? h.infilled : h.observed;
      }
    }
    if (o.frustum) {
      const p = o.cam.positions.subarray(3 * t, 3 * t + 3), q = o.cam.quaternions.subarray(4 * t, 4 * t + 4);
      const ok = Number.isFinite(p[0] + p[1] + p[2] + q[0] + q[1] + q[2] + q[3]);
      o.frustum.visible = ok;
      if (ok) { o.frustum.position.set(p[0], p[1], p[2]); o.frustum.quaternion.set(q[0], q[1], q[2], q[3]); }
    }
    this.render();
  }

  render() { this.renderer.render(this.scene, this.camera); }

  /// What the scene holds (for the page's summary and the tests): read from the scene objects.
  summary() {
    const o = this.objects;
    if (!o) return null;
    const s = { frame: this.frame, hands: {}, cameraPath: 0, points: 0, frustum: false };
    for (const side of ['left', 'right']) {
      const h = o.hands[side];
      if (!h) continue;
      s.hands[side] = { frames: h.frames, trackPoints: h.track ? h.track.geometry.getAttribute('position').count : 0,
        visibleNow: h.mesh.visible, vertices: h.mesh.geometry.getAttribute('position').count };
    }
    s.cameraPath = o.path ? o.path.geometry.getAttribute('position').count : 0;
    s.points = o.points ? o.points.geometry.getAttribute('position').count : 0;
    s.frustum = !!(o.frustum && o.frustum.visible);
    s.objects = this.world.children.map((c) => c.name);
    return s;
  }
}
