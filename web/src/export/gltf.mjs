// gltf.mjs — a result as one binary glTF 2.0 file (GLB): both hands' world-space meshes over
// time, the camera (an animated glTF camera with the video's field of view), the camera path
// and the SLAM points. Pure serialisation: the meshes come from the core's forward pass
// (hand_meshes.mjs), the poses from the pipeline's result.
//
// The hands are "flip-book" animated: one mesh node per frame in which the hand exists, shown
// by a STEP scale animation (scale 1 during its frame, 0 otherwise). Skinning would be smaller
// but loses MANO's pose correctives and needs the model's skeleton; morph targets need T
// weights per key (quadratic in the clip's length). Node scale animation is read the same way by
// Blender's importer and three.js's GLTFLoader. Frames filled by the infiller use a paler
// material of the hand's colour (names end in `_infilled`).
//
// Coordinates: the hawor world is gravity-aligned with z up (`world.convention` 'z-up', the
// pipeline's default) or the first camera's OpenCV frame (x right, y down, z forward), metres.
// glTF is y up: the root node `hawor_world` turns the world by −90° about x (z up) or 180° about
// x (y down), so the numbers inside stay exactly the result's. The camera node carries the camera-to-world pose;
// its child `camera_optical` turns OpenCV's camera axes into glTF's (looking down −z, y up).

const FLOAT = 5126, UINT16 = 5123, UINT32 = 5125;
const ARRAY_BUFFER = 34962, ELEMENT_ARRAY_BUFFER = 34963;
const RX_PI = [1, 0, 0, 0];  // quaternion (x, y, z, w) of 180° about x
const RX_MINUS_HALF_PI = [-Math.SQRT1_2, 0, 0, Math.SQRT1_2];  // −90° about x: z up becomes y up

const COLORS = {
  left: [0.184, 0.490, 0.965],
  right: [0.949, 0.463, 0.180],
};

function rows(a, n) {
  if (a == null) return null;
  if (a.length && a[0] != null && typeof a[0] === 'object') {
    const out = new Float32Array(a.length * n);
    a.forEach((r, i) => { for (let k = 0; k < n; k++) out[i * n + k] = r[k]; });
    return out;
  }
  return Float32Array.from(a);
}

class Builder {
  constructor() {
    this.chunks = [];
    this.length = 0;
    this.json = { asset: { version: '2.0', generator: 'hawor web app' }, buffers: [], bufferViews: [], accessors: [],
      meshes: [], materials: [], nodes: [], scenes: [], animations: [] };
  }
  view(bytes, target) {
    const pad = (4 - (this.length % 4)) % 4;
    if (pad) { this.chunks.push(new Uint8Array(pad)); this.length += pad; }
    const u8 = new Uint8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    this.chunks.push(u8);
    const v = { buffer: 0, byteOffset: this.length, byteLength: u8.byteLength };
    if (target) v.target = target;
    this.length += u8.byteLength;
    this.json.bufferViews.push(v);
    return this.json.bufferViews.length - 1;
  }
  accessor(typed, type, componentType, { target, minmax = false, count } = {}) {
    const n = { SCALAR: 1, VEC3: 3, VEC4: 4 }[type];
    const acc = { bufferView: this.view(typed, target), componentType, count: count ?? typed.length / n, type };
    if (minmax) {
      const min = new Array(n).fill(Infinity), max = new Array(n).fill(-Infinity);
      for (let i = 0; i < typed.length; i++) { const k = i % n; if (typed[i] < min[k]) min[k] = typed[i]; if (typed[i] > max[k]) max[k] = typed[i]; }
      acc.min = min.map(Math.fround); acc.max = max.map(Math.fround);
    }
    this.json.accessors.push(acc);
    return this.json.accessors.length - 1;
  }
  material(name, rgb, alpha, unlit = false) {
    const m = { name, pbrMetallicRoughness: { baseColorFactor: [...rgb, alpha], metallicFactor: 0, roughnessFactor: 0.8 }, doubleSided: true };
    if (alpha < 1) m.alphaMode = 'BLEND';
    if (unlit) { m.extensions = { KHR_materials_unlit: {} }; this.unlit = true; }
    this.json.materials.push(m);
    return this.json.materials.length - 1;
  }
  node(n) { this.json.nodes.push(n); return this.json.nodes.length - 1; }
  glb() {
    const j = this.json;
    if (this.unlit) j.extensionsUsed = ['KHR_materials_unlit'];
    for (const k of ['meshes', 'materials', 'animations', 'accessors', 'bufferViews']) if (!j[k].length) delete j[k];
    const pad = (4 - (this.length % 4)) % 4;
    if (pad) { this.chunks.push(new Uint8Array(pad)); this.length += pad; }
    j.buffers = [{ byteLength: this.length }];
    const raw = new TextEncoder().encode(JSON.stringify(j));
    const jsonBytes = new Uint8Array(Math.ceil(raw.length / 4) * 4).fill(0x20);
    jsonBytes.set(raw);
    const total = 12 + 8 + jsonBytes.length + 8 + this.length;
    const out = new Uint8Array(total);
    const dv = new DataView(out.buffer);
    dv.setUint32(0, 0x46546c67, true); dv.setUint32(4, 2, true); dv.setUint32(8, total, true);
    dv.setUint32(12, jsonBytes.length, true); dv.setUint32(16, 0x4e4f534a, true);
    out.set(jsonBytes, 20);
    let o = 20 + jsonBytes.length;
    dv.setUint32(o, this.length, true); dv.setUint32(o + 4, 0x004e4942, true);
    o += 8;
    for (const c of this.chunks) { out.set(c, o); o += c.byteLength; }
    return out;
  }
}

/// GLB bytes of a result.
///   fps, frameCount
///   hands: { left, right }: each null or { numVertices, faces: Uint32Array, vertices:
///          Float32Array(T*V*3), present: Uint8Array(T), infilled: Uint8Array(T) }
///   camera: null or { positions (T,3), quaternions (T,4) x,y,z,w camera-to-world, width,
///          height, fx, fy } (flat or nested)
///   points: null or (N,3) world points
export function buildGlb({ fps, frameCount, hands = {}, camera = null, points = null, world = null, name = 'hawor' }) {
  if (!(fps > 0)) throw new Error('gltf: fps must be > 0');
  const T = frameCount;
  if (!Number.isInteger(T) || T < 1) throw new Error('gltf: frameCount must be a positive integer');
  const b = new Builder();
  const rootChildren = [];
  const anim = { name: `${name}_motion`, samplers: [], channels: [] };
  const dt = 1 / fps;

  // Shared scale keys of the flip-book: [0 -> 1 -> 0], [1 -> 0] (first frame), [0 -> 1] (last).
  const keys = { mid: [0, 0, 0, 1, 1, 1, 0, 0, 0], first: [1, 1, 1, 0, 0, 0], last: [0, 0, 0, 1, 1, 1], only: [1, 1, 1] };
  const made = {};
  const scales = (k) => (made[k] ??= b.accessor(new Float32Array(keys[k]), 'VEC3', FLOAT));

  for (const side of ['left', 'right']) {
    const h = hands[side];
    if (!h) continue;
    const V = h.numVertices;
    if (h.vertices.length !== T * V * 3) throw new Error(`gltf: ${side} hand: ${h.vertices.length} vertex values, expected ${T}×${V}×3`);
    const idx = V < 65536 ? Uint16Array.from(h.faces) : Uint32Array.from(h.faces);
    const indices = b.accessor(idx, 'SCALAR', V < 65536 ? UINT16 : UINT32, { target: ELEMENT_ARRAY_BUFFER });
    const mObs = b.material(`${side}_hand`, COLORS[side], 1);
    const mInf = b.material(`${side}_hand_infilled`, COLORS[side].map((c) => 0.55 + 0.45 * c), 0.6);
    const children = [];
    for (let t = 0; t < T; t++) {
      if (!h.present[t]) continue;
      const pos = b.accessor(h.vertices.subarray(t * V * 3, (t + 1) * V * 3), 'VEC3', FLOAT, { target: ARRAY_BUFFER, minmax: true });
      b.json.meshes.push({ name: `${side}_hand_${t}`, primitives: [{ attributes: { POSITION: pos }, indices, material: h.infilled[t] ? mInf : mObs }] });
      const node = b.node({ name: `${side}_hand_f${String(t).padStart(5, '0')}${h.infilled[t] ? '_infilled' : ''}`, mesh: b.json.meshes.length - 1,
        scale: t === 0 ? [1, 1, 1] : [0, 0, 0] });
      children.push(node);
      let times, values;
      if (T === 1) { times = [0]; values = scales('only'); }
      else if (t === 0) { times = [0, dt]; values = scales('first'); }
      else if (t === T - 1) { times = [0, t * dt]; values = scales('last'); }
      else { times = [0, t * dt, (t + 1) * dt]; values = scales('mid'); }
      const input = b.accessor(new Float32Array(times), 'SCALAR', FLOAT, { minmax: true });
      anim.samplers.push({ input, output: values, interpolation: 'STEP' });
      anim.channels.push({ sampler: anim.samplers.length - 1, target: { node, path: 'scale' } });
    }
    rootChildren.push(b.node({ name: `${side}_hand`, children }));
  }

  if (camera && camera.positions && camera.quaternions) {
    const P = rows(camera.positions, 3), Q = rows(camera.quaternions, 4);
    if (P.length !== T * 3 || Q.length !== T * 4) throw new Error(`gltf: camera: ${P.length / 3} positions / ${Q.length / 4} rotations for ${T} frames`);
    const times = new Float32Array(T);
    for (let t = 0; t < T; t++) times[t] = t * dt;
    const input = b.accessor(times, 'SCALAR', FLOAT, { minmax: true });
    const aspect = camera.width / camera.height;
    const yfov = 2 * Math.atan(camera.height / (2 * camera.fy));
    b.json.cameras = [{ name: 'video_camera', type: 'perspective', perspective: { aspectRatio: aspect, yfov, znear: 0.01, zfar: 100 } }];
    const optical = b.node({ name: 'camera_optical', camera: 0, rotation: RX_PI });
    const cam = b.node({ name: 'camera', children: [optical], translation: [P[0], P[1], P[2]], rotation: [Q[0], Q[1], Q[2], Q[3]] });
    rootChildren.push(cam);
    anim.samplers.push({ input, output: b.accessor(P, 'VEC3', FLOAT), interpolation: 'LINEAR' });
    anim.channels.push({ sampler: anim.samplers.length - 1, target: { node: cam, path: 'translation' } });
    anim.samplers.push({ input, output: b.accessor(Q, 'VEC4', FLOAT), interpolation: 'LINEAR' });
    anim.channels.push({ sampler: anim.samplers.length - 1, target: { node: cam, path: 'rotation' } });
    // The path as a line strip.
    const mPath = b.material('camera_path', [0.85, 0.85, 0.85], 1, true);
    const pathPos = b.accessor(P, 'VEC3', FLOAT, { target: ARRAY_BUFFER, minmax: true });
    b.json.meshes.push({ name: 'camera_path', primitives: [{ attributes: { POSITION: pathPos }, mode: 3, material: mPath }] });
    rootChildren.push(b.node({ name: 'camera_path', mesh: b.json.meshes.length - 1 }));
  }

  if (points) {
    const X = rows(points, 3);
    let n = 0;
    const keep = new Float32Array(X.length);
    for (let i = 0; i + 2 < X.length; i += 3) {
      if (Number.isFinite(X[i]) && Number.isFinite(X[i + 1]) && Number.isFinite(X[i + 2])) { keep.set(X.subarray(i, i + 3), n); n += 3; }
    }
    if (n > 0) {
      const mPts = b.material('slam_points', [0.6, 0.9, 0.6], 1, true);
      const acc = b.accessor(keep.slice(0, n), 'VEC3', FLOAT, { target: ARRAY_BUFFER, minmax: true });
      b.json.meshes.push({ name: 'slam_points', primitives: [{ attributes: { POSITION: acc }, mode: 0, material: mPts }] });
      rootChildren.push(b.node({ name: 'slam_points', mesh: b.json.meshes.length - 1 }));
    }
  }

  const root = b.node({ name: 'hawor_world', rotation: world && world.convention === 'z-up' ? RX_MINUS_HALF_PI : RX_PI, children: rootChildren });
  b.json.scenes.push({ name, nodes: [root] });
  b.json.scene = 0;
  if (anim.channels.length) b.json.animations.push(anim);
  return b.glb();
}
