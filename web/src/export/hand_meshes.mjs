// hand_meshes.mjs — the world-space hand mesh of every frame of a result, computed by the C++
// core's forward pass (`core.HandModel(bytes).forward(pose)`); nothing geometric happens here.
// Shared by the app's views (in the Web Worker) and the glTF exporter (browser and node).

/// Row t (n numbers) of a per-frame array given flat (T*n) or nested ([T][n]).
export function row(a, t, n) {
  if (a == null) return null;
  const r = a[t];
  if (r != null && typeof r === 'object') return Float64Array.from(r);
  return Float64Array.from(a.slice ? a.slice(t * n, (t + 1) * n) : Array.prototype.slice.call(a, t * n, (t + 1) * n));
}

/// Number of per-frame values of a flat or nested array with T rows.
export function width(a, T) {
  if (a == null || T === 0) return 0;
  if (a[0] != null && typeof a[0] === 'object') return a[0].length;
  return a.length / T;
}

function flag(a, t) { return a != null && !!Number(a[t]); }

/// { numVertices, faces: Uint32Array(3F), vertices: Float32Array(T*V*3) (0 where absent),
///   present: Uint8Array(T) (observed or infilled), infilled: Uint8Array(T) } for one hand of
/// a result. `model` is a core.HandModel; frames whose pose is missing or not finite are absent.
export function handMeshSequence(model, hand, T) {
  const V = model.numVertices();
  const J1 = model.numJoints() - 1;
  const out = {
    numVertices: V,
    faces: Uint32Array.from(model.faces()),
    vertices: new Float32Array(T * V * 3),
    present: new Uint8Array(T),
    infilled: new Uint8Array(T),
  };
  if (!hand) return out;
  const nb = width(hand.betas, T);
  const sharedBetas = hand.betas && !(hand.betas[0] != null && typeof hand.betas[0] === 'object') && hand.betas.length <= model.numBetas() && T > 1;
  for (let t = 0; t < T; t++) {
    const valid = flag(hand.valid, t), inf = flag(hand.infilled, t);
    if (!valid && !inf) continue;
    const pose = {
      rot: row(hand.rot, t, 3),
      trans: row(hand.trans, t, 3),
      handPose: row(hand.handPose, t, 3 * J1),
      betas: sharedBetas ? Float64Array.from(hand.betas) : (nb ? row(hand.betas, t, nb) : new Float64Array(0)),
    };
    if (!pose.rot || !pose.trans || !pose.handPose) continue;
    let finite = true;
    for (const k of ['rot', 'trans', 'handPose', 'betas']) for (const v of pose[k]) if (!Number.isFinite(v)) finite = false;
    if (!finite) continue;
    const { vertices } = model.forward(pose);
    out.vertices.set(vertices, t * V * 3);
    out.present[t] = 1;
    out.infilled[t] = inf && !valid ? 1 : 0;
  }
  return out;
}
