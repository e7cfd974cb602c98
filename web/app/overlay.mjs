// overlay.mjs — the video view's overlays: the 2D keypoints (canvas 2D), and the hand meshes
// seen through the estimated camera (three.js, a camera whose projection is the video's
// intrinsics): filled silhouettes (the hand mask) and wireframes (the projected mesh). In live
// mode (the camera) the keypoints of the last processed frame only.
import * as THREE from 'three';
import { SIDE_COLORS, BONES, cameraPoses, flat } from './view3d.mjs';

const CSS = { left: '#2f7df6', right: '#f2762e' };

/// One hand's 21 keypoints (K[o + 2i], K[o + 2i + 1]: image pixels of frames of size w x h) as a
/// skeleton inside the rectangle r.
function drawHand(ctx, K, o, side, r, w, h) {
  const sx = r.w / w, sy = r.h / h;
  const u = (i) => r.x + (K[o + 2 * i] + 0.5) * sx, v = (i) => r.y + (K[o + 2 * i + 1] + 0.5) * sy;
  if (!Number.isFinite(K[o] + K[o + 1])) return;
  ctx.strokeStyle = CSS[side]; ctx.fillStyle = CSS[side]; ctx.lineWidth = 2;
  ctx.beginPath();
  for (const [a, b] of BONES) {
    if (!Number.isFinite(K[o + 2 * a] + K[o + 2 * b] + K[o + 2 * a + 1] + K[o + 2 * b + 1])) continue;
    ctx.moveTo(u(a), v(a)); ctx.lineTo(u(b), v(b));
  }
  ctx.stroke();
  ctx.strokeStyle = '#fff'; ctx.lineWidth = 1;
  for (let i = 0; i < 21; i++) {
    if (!Number.isFinite(K[o + 2 * i] + K[o + 2 * i + 1])) continue;
    ctx.beginPath(); ctx.arc(u(i), v(i), 3, 0, 2 * Math.PI); ctx.fill(); ctx.stroke();
  }
}

/// OpenGL projection of a pinhole camera (OpenCV intrinsics, pixel centres at integers) for a
/// three.js camera looking down −z with y up.
function projection(K, w, h, near, far) {
  const m = new THREE.Matrix4();
  m.set(
    2 * K.fx / w, 0, 1 - 2 * (K.cx + 0.5) / w, 0,
    0, 2 * K.fy / h, 2 * (K.cy + 0.5) / h - 1, 0,
    0, 0, -(far + near) / (far - near), -2 * far * near / (far - near),
    0, 0, -1, 0);
  return m;
}

export class VideoOverlay {
  constructor(video, glCanvas, canvas2d) {
    this.video = video;
    this.gl = new THREE.WebGLRenderer({ canvas: glCanvas, alpha: true, antialias: true });
    this.gl.setClearColor(0x000000, 0);
    this.ctx = canvas2d.getContext('2d');
    this.c2d = canvas2d;
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera();
    this.camera.matrixAutoUpdate = false;
    this.flip = new THREE.Quaternion(1, 0, 0, 0);  // OpenCV camera axes -> three's (180° about x)
    this.state = null;
    this.live = null;
    new ResizeObserver(() => this.draw()).observe(canvas2d.parentElement);
  }

  clear() {
    if (this.state) for (const h of Object.values(this.state.hands)) { h.fill.material.dispose(); h.wire.material.dispose(); this.scene.remove(h.fill, h.wire); }
    this.state = null;
    this.live = null;
    this.draw();
  }

  /// Live mode: the keypoints of one processed frame, { width, height, hands: [{ side,
  /// keypoints2d (42) }] } (the hands seen on it), over the camera's picture.
  drawLive(frame) {
    this.live = frame;
    this.draw();
  }

  /// result + meshes as for SceneView; `sceneView` shares its per-frame hand geometry.
  setResult(result, meshes, sceneView) {
    this.clear();
    const T = result.frameCount;
    const s = { result, meshes, T, hands: {}, cam: cameraPoses(result), kp: {} };
    for (const side of ['left', 'right']) {
      const sv = sceneView.objects && sceneView.objects.hands[side];
      if (!sv) continue;
      const geom = sv.mesh.geometry;   // updated by SceneView.setFrame
      const fill = new THREE.Mesh(geom, new THREE.MeshBasicMaterial({ color: SIDE_COLORS[side], transparent: true, opacity: 0.35, side: THREE.DoubleSide, depthWrite: false }));
      const wire = new THREE.Mesh(geom, new THREE.MeshBasicMaterial({ color: SIDE_COLORS[side], wireframe: true, transparent: true, opacity: 0.6 }));
      this.scene.add(fill, wire);
      s.hands[side] = { fill, wire };
      s.kp[side] = flat(result.hands && result.hands[side] && result.hands[side].keypoints2d, 42);
    }
    this.state = s;
  }

  /// The rectangle (CSS px) where the video picture is drawn inside the view (object-fit: contain).
  rect() {
    const el = this.c2d.parentElement;
    const W = el.clientWidth, H = el.clientHeight;
    const s = (this.state && this.state.result) || this.live;
    const vw = s ? s.width : (this.video.videoWidth || 16), vh = s ? s.height : (this.video.videoHeight || 9);
    const k = Math.min(W / vw, H / vh);
    return { x: (W - vw * k) / 2, y: (H - vh * k) / 2, w: vw * k, h: vh * k, W, H };
  }

  draw(t = this.frame ?? 0, show = this.show || { kp: true, mesh: true, mask: true }) {
    this.frame = t;
    this.show = show;
    const r = this.rect();
    const dpr = Math.min(2, window.devicePixelRatio || 1);
    this.c2d.width = Math.round(r.W * dpr); this.c2d.height = Math.round(r.H * dpr);
    const ctx = this.ctx;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, r.W, r.H);
    this.gl.setPixelRatio(dpr);
    this.gl.setSize(r.W, r.H, false);
    this.gl.clear();
    const s = this.state;
    if (!s) {
      if (this.live && show.kp) for (const h of this.live.hands) if (h.keypoints2d) drawHand(ctx, h.keypoints2d, 0, h.side, r, this.live.width, this.live.height);
      return;
    }
    const res = s.result;
    // Meshes through the estimated camera.
    const p = s.cam.positions.subarray(3 * t, 3 * t + 3), q = s.cam.quaternions.subarray(4 * t, 4 * t + 4);
    const poseOk = Number.isFinite(p[0] + p[1] + p[2] + q[0] + q[1] + q[2] + q[3]);
    for (const side of Object.keys(s.hands)) {
      const m = s.meshes[side], h = s.hands[side];
      const on = poseOk && !!m.present[t];
      const inf = !!m.infilled[t];
      h.fill.visible = on && show.mask && !inf;
      h.wire.visible = on && show.mesh;
      h.wire.material.opacity = inf ? 0.3 : 0.6;
    }
    if (poseOk && res.intrinsics) {
      const quat = new THREE.Quaternion(q[0], q[1], q[2], q[3]).multiply(this.flip);
      this.camera.matrixWorld.compose(new THREE.Vector3(p[0], p[1], p[2]), quat, new THREE.Vector3(1, 1, 1));
      this.camera.matrixWorldInverse.copy(this.camera.matrixWorld).invert();
      this.camera.projectionMatrix.copy(projection(res.intrinsics, res.width, res.height, 0.01, 100));
      this.camera.projectionMatrixInverse.copy(this.camera.projectionMatrix).invert();
      this.gl.setViewport(r.x, r.y, r.w, r.h);
      this.gl.render(this.scene, this.camera);
    }
    // 2D keypoints (image pixels of the processed frames).
    if (!show.kp) return;
    for (const side of Object.keys(s.kp)) if (s.kp[side]) drawHand(ctx, s.kp[side], 42 * t, side, r, res.width, res.height);
  }
}
