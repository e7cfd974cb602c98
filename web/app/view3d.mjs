// view3d.mjs — the 3D view (three.js): world-space hand meshes of the current frame, the wrist
// tracks of both hands, the camera path, the current camera frustum and the SLAM points; in live
// mode (the camera) the path so far, the current frustum and the current hands' keypoints.
// Display only: every position comes from the result, the core's hand meshes or the pipeline's
// live estimates.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

export const SIDE_COLORS = { left: 0x2f7df6, right: 0xf2762e };
/// MediaPipe's 21-keypoint hand skeleton (display only).
export const BONES = [[0, 1], [1, 2], [2, 3], [3, 4], [0, 5], [5, 6], [6, 7], [7, 8], [5, 9], [9, 10], [10, 11], [11, 12],
  [9, 13], [13, 14], [14, 15], [15, 16], [13, 17], [0, 17], [17, 18], [18, 19], [19, 20]];
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
    // live mode follows the scene until the user turns the view
    this.controls.addEventListener('start', () => { if (this.objects && this.objects.live) this.objects.userMoved = true; });
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
    this.grid.scale.setScalar(1);
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
    if (!o || o.live) return;
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

  // --- live mode ---------------------------------------------------------------------------------

  /// Live mode: an empty world that grows with each processed frame (run.mjs's frameInfo.live):
  /// the camera path so far (the posed frames), the current frustum and the current hands' 21
  /// fitted keypoints as skeletons. K, width, height: the intrinsics and size of the frames.
  startLive(K, width, height) {
    this.clear();
    this.world.rotation.x = Math.PI;  // the first camera's frame (y down) until the world is gravity-aligned
    const o = { live: true, T: 0, hands: {}, pathPoints: 0, userMoved: false, convention: 'first-camera', origin: 'first-camera', worldChanges: 0 };
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * 1024), 3));
    g.setDrawRange(0, 0);
    o.path = new THREE.Line(g, new THREE.LineBasicMaterial({ color: 0xdddddd }));
    o.path.name = 'camera_path';
    o.path.frustumCulled = false;
    this.world.add(o.path);
    const fg = new THREE.BufferGeometry();
    fg.setAttribute('position', new THREE.BufferAttribute(frustumSegments(K, width, height, 1), 3));
    o.frustum = new THREE.LineSegments(fg, new THREE.LineBasicMaterial({ color: 0xffe066 }));
    o.frustum.name = 'camera_frustum';
    o.frustum.visible = false;
    this.world.add(o.frustum);
    for (const side of ['left', 'right']) {
      const geom = new THREE.BufferGeometry();
      geom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(63), 3));
      geom.setIndex(BONES.flat());
      const bones = new THREE.LineSegments(geom, new THREE.LineBasicMaterial({ color: SIDE_COLORS[side] }));
      const dots = new THREE.Points(geom, new THREE.PointsMaterial({ color: SIDE_COLORS[side], size: 4, sizeAttenuation: false }));
      bones.frustumCulled = false; dots.frustumCulled = false;
      const group = new THREE.Group();
      group.name = `${side}_hand`;
      group.add(bones, dots);
      group.visible = false;
      this.world.add(group);
      o.hands[side] = { group, geom, frames: 0 };
    }
    this.objects = o;
    this.render();
  }

  /// The live world changed (a frame that brought frameInfo.world): its convention ('z-up' once
  /// gravity-aligned, else 'first-camera') and origin; `before` and `after` are the same frame's
  /// camera in the previous and in the new world ({ scale, cameraRotation (9, row-major),
  /// cameraPosition }), which carry the path drawn so far into the new world: X' = c' + k R' Rᵀ
  /// (X − c), k = scale' / scale. Without them the path starts again.
  liveWorld(convention, origin, before, after) {
    const o = this.objects;
    if (!o || !o.live) return;
    const attr = o.path.geometry.getAttribute('position');
    const a = attr.array;
    if (before && after) {
      const R0 = before.cameraRotation, R1 = after.cameraRotation, c0 = before.cameraPosition, c1 = after.cameraPosition;
      const k = after.scale / before.scale;
      const D = new Float64Array(9);  // R1 R0ᵀ
      for (let i = 0; i < 3; i++) for (let j = 0; j < 3; j++) D[3 * i + j] = R1[3 * i] * R0[3 * j] + R1[3 * i + 1] * R0[3 * j + 1] + R1[3 * i + 2] * R0[3 * j + 2];
      for (let n = 0; n < o.pathPoints; n++) {
        const x = a[3 * n] - c0[0], y = a[3 * n + 1] - c0[1], z = a[3 * n + 2] - c0[2];
        for (let i = 0; i < 3; i++) a[3 * n + i] = c1[i] + k * (D[3 * i] * x + D[3 * i + 1] * y + D[3 * i + 2] * z);
      }
    } else {
      o.pathPoints = 0;
      o.path.geometry.setDrawRange(0, 0);
    }
    attr.needsUpdate = true;
    o.path.geometry.computeBoundingSphere();
    o.convention = convention;
    o.origin = origin;
    o.worldChanges++;
    this.world.rotation.x = convention === 'z-up' ? -Math.PI / 2 : Math.PI;
    if (!o.userMoved) this.fitLive();
    this.render();
  }

  /// One processed frame of live mode: frameInfo.live ({ posed, cameraRotation, cameraPosition,
  /// joints: { left, right } }); hands without joints on this frame are hidden.
  liveFrame(l) {
    const o = this.objects;
    if (!o || !o.live || !l) return;
    o.T++;
    const p = l.cameraPosition, R = l.cameraRotation;
    const ok = !!(p && R) && Number.isFinite(p[0] + p[1] + p[2]) && R.every(Number.isFinite);
    if (ok && l.posed) {
      let attr = o.path.geometry.getAttribute('position');
      if (3 * (o.pathPoints + 1) > attr.array.length) {
        const grown = new Float32Array(2 * attr.array.length);
        grown.set(attr.array);
        attr = new THREE.BufferAttribute(grown, 3);
        o.path.geometry.setAttribute('position', attr);
      }
      attr.array.set([p[0], p[1], p[2]], 3 * o.pathPoints);
      o.pathPoints++;
      attr.needsUpdate = true;
      o.path.geometry.setDrawRange(0, o.pathPoints);
    }
    o.frustum.visible = ok;
    if (ok) {
      const m = new THREE.Matrix4().set(R[0], R[1], R[2], 0, R[3], R[4], R[5], 0, R[6], R[7], R[8], 0, 0, 0, 0, 1);
      o.frustum.position.set(p[0], p[1], p[2]);
      o.frustum.quaternion.setFromRotationMatrix(m);
    }
    for (const side of ['left', 'right']) {
      const h = o.hands[side], J = l.joints && l.joints[side];
      h.group.visible = !!J;
      if (!J) continue;
      const attr = h.geom.getAttribute('position');
      attr.array.set(J);
      attr.needsUpdate = true;
      h.frames++;
    }
    if (!o.userMoved && (o.T <= 5 || o.T % 15 === 0)) this.fitLive();
    this.render();
  }

  /// Frames the live scene: the path and the visible hands in view, the frustum sized to them.
  fitLive() {
    const o = this.objects;
    const box = new THREE.Box3();
    const a = o.path.geometry.getAttribute('position').array;
    const v = new THREE.Vector3();
    for (let n = 0; n < o.pathPoints; n++) box.expandByPoint(v.set(a[3 * n], a[3 * n + 1], a[3 * n + 2]));
    for (const side of ['left', 'right']) {
      const h = o.hands[side];
      if (!h.group.visible) continue;
      const J = h.geom.getAttribute('position').array;
      for (let k = 0; k < 21; k++) if (Number.isFinite(J[3 * k] + J[3 * k + 1] + J[3 * k + 2])) box.expandByPoint(v.set(J[3 * k], J[3 * k + 1], J[3 * k + 2]));
    }
    if (box.isEmpty()) return;
    const extent = box.getSize(new THREE.Vector3()).length();
    // metres once the live world is metric; before that the SLAM's units (any size)
    const size = o.convention === 'z-up' ? Math.max(0.3, extent) : (extent > 0 ? extent : 1);
    o.frustum.scale.setScalar(0.08 * size);
    this.world.updateMatrixWorld(true);
    const cen = box.getCenter(new THREE.Vector3()).applyMatrix4(this.world.matrixWorld);
    this.grid.position.set(cen.x, o.convention === 'z-up' && o.origin === 'floor' ? 0 : cen.y - size * 0.6, cen.z);
    this.grid.scale.setScalar(o.convention === 'z-up' ? 1 : size);
    this.controls.target.copy(cen);
    this.camera.position.copy(cen).add(new THREE.Vector3(0.9, 0.7, 1.3).multiplyScalar(size));
    this.camera.near = size / 200; this.camera.far = size * 200; this.camera.updateProjectionMatrix();
    this.controls.update();
  }

  render() { this.renderer.render(this.scene, this.camera); }

  /// What the scene holds (for the page's summary and the tests): read from the scene objects.
  summary() {
    const o = this.objects;
    if (!o) return null;
    if (o.live) {
      const hands = {};
      for (const side of ['left', 'right']) hands[side] = { frames: o.hands[side].frames, visibleNow: o.hands[side].group.visible };
      return { live: true, frame: o.T - 1, hands, cameraPath: o.pathPoints, points: 0, frustum: o.frustum.visible,
        convention: o.convention, objects: this.world.children.map((c) => c.name) };
    }
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
