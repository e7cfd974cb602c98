"""Synthetic skinned .glb files and what a reader and the glTF -> hand-model conversion must
return for them (tests/hand/ref_gltf.cpp). Written from the glTF 2.0 specification with struct +
json only (no glTF library).

usage: gltf_make.py OUT.txt
Writes OUT.txt.<k>.glb for k = 0, 1, 2 and the arrays (refio.save) named v<k>_*:
  acc<i>      decoded values of accessor i, shape (count, components); normalised integers as
              c/255 or c/65535 (glTF "Accessors")
  node_world  (N,4,4) world transform of every node (parents' local transforms applied)
  v_template  (V,3) POSITION of both primitives, unchanged (skinned mesh node transform ignored)
  faces       (F,3) their triangles, indices offset by the vertices of earlier primitives
  order       (J,) skin joint index of each model joint: nearest-joint-ancestor tree, made
              parent-first by repeatedly taking the smallest skin index whose parent is placed
  order_finger (J,) the generator's joint id (node name "j<id>") of each model joint
  parents     (J,) model parents; rest (J,3) translation of inv(IBM); weights (V,J) rows summing to 1
  pose        (J,3) axis-angles (model order; row 0 the global orientation)
  posed       (V,3) glTF skinning sum_k w_k W_k IBM_k p of the raw data, with W_j = [Rg_j Q_j | g_j]:
              Rg_j = Rg_p R_j, g_j = g_p + Rg_p (J_j - J_p), (Q_j, J_j) from inv(IBM_j)
Variants: 0 plain skin order; 1 shuffled skin order and JOINTS_1/WEIGHTS_1 on primitive 0;
2 node transforms moved away from the bind pose after the IBMs were computed.
"""
import json
import struct
import sys

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, __import__("os").path.dirname(__file__))
import refio  # noqa: E402


def quat_matrix(q):
    x, y, z, w = np.asarray(q, dtype=np.float64) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def trs(t, q, s):
    m = np.eye(4)
    m[:3, :3] = quat_matrix(q) @ np.diag(s)
    m[:3, 3] = t
    return m


class Bin:
    def __init__(self):
        self.data = bytearray()
        self.views = []
        self.accessors = []
        self.decoded = []

    def view(self, raw, stride=None):
        while len(self.data) % 4:
            self.data += b"\0"
        v = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(raw)}
        if stride:
            v["byteStride"] = stride
        self.data += raw
        self.views.append(v)
        return len(self.views) - 1

    def accessor(self, view, offset, ctype, count, typ, decoded, normalized=False):
        a = {"bufferView": view, "componentType": ctype, "count": count, "type": typ}
        if offset:
            a["byteOffset"] = offset
        if normalized:
            a["normalized"] = True
        self.accessors.append(a)
        self.decoded.append(np.asarray(decoded, dtype=np.float64).reshape(count, -1))
        return len(self.accessors) - 1


def strided(rows, stride, fill=b"\xAB"):
    """Rows of bytes laid out every `stride` bytes, the gaps filled with junk."""
    out = bytearray()
    for r in rows:
        out += r + fill * (stride - len(r))
    return bytes(out)


def make(variant, path, rng):
    # --- skeleton: nodes 0 armature (matrix), 1 mesh, 2.. joints and one non-joint node ---------
    # joint tree (finger ids): 0 root; 1 <- 0; 2 <- 1; 3 <- 0; 4 <- 3; 5 <- (helper) <- 0; 6 <- 5
    jparent = [-1, 0, 1, 0, 3, 0, 5]
    J = len(jparent)
    names = ["j%d" % j for j in range(J)]
    # node ids: joint j -> node 2 + j; helper node = 2 + J
    helper = 2 + J
    node_parent = {1: 0, 2: 0}
    for j in range(1, J):
        node_parent[2 + j] = 2 + jparent[j]
    node_parent[2 + 5] = helper
    node_parent[helper] = 2
    N = helper + 1

    def rand_trs(scale=True):
        t = rng.normal(0, 0.03, 3)
        q = Rotation.random(random_state=rng).as_quat()  # x, y, z, w
        s = rng.uniform(0.8, 1.25, 3) if scale else np.ones(3)
        return t, q, s

    local = {}
    node_json = [dict() for _ in range(N)]
    for n in range(N):
        if n == 1:
            t, q, s = np.array([3.0, -2.0, 1.0]), np.array([0, 0, 0, 1.0]), np.ones(3)  # ignored
        else:
            t, q, s = rand_trs(scale=(n != 2))
        local[n] = trs(t, q, s)
        if n in (0, 4):  # written as a matrix (column-major)
            node_json[n]["matrix"] = [float(v) for v in local[n].T.ravel()]
        else:
            node_json[n]["translation"] = [float(v) for v in t]
            node_json[n]["rotation"] = [float(v) for v in q]
            if n != 2:
                node_json[n]["scale"] = [float(v) for v in s]

    def world_of(loc):
        w = {}
        def get(n):
            if n not in w:
                p = node_parent.get(n)
                w[n] = loc[n] if p is None else get(p) @ loc[n]
            return w[n]
        return np.array([get(n) for n in range(N)])

    bind_world = world_of(local)
    skin_order = list(range(J)) if variant != 1 else [4, 0, 6, 2, 5, 1, 3]  # skin k -> finger joint
    skin_of = {f: k for k, f in enumerate(skin_order)}
    ibm = np.array([np.linalg.inv(bind_world[2 + skin_order[k]]) for k in range(J)]).astype(np.float32)

    if variant == 2:  # move the nodes after binding: the IBMs still define the rest pose
        for n in range(2, N):
            t, q, s = rand_trs()
            local[n] = trs(t, q, s)
            node_json[n] = {"translation": [float(v) for v in t], "rotation": [float(v) for v in q],
                            "scale": [float(v) for v in s]}
    world = world_of(local)

    for n in range(N):
        kids = sorted(c for c, p in node_parent.items() if p == n)
        if kids:
            node_json[n]["children"] = kids
    node_json[0]["name"] = "Armature"
    node_json[1].update({"name": "mesh", "mesh": 0, "skin": 0})
    for j in range(J):
        node_json[2 + j]["name"] = names[j]
    node_json[helper]["name"] = "helper"

    # --- mesh: vertices around the bind-pose joints ----------------------------------------------
    bind_pos = np.array([bind_world[2 + j][:3, 3] for j in range(J)])
    b = Bin()
    prims = []
    all_pos, all_faces, weight_rows = [], [], []
    offset = 0
    for p, V in enumerate([40, 30]):
        home = rng.integers(0, J, V)
        pos = (bind_pos[home] + rng.normal(0, 0.01, (V, 3))).astype(np.float32)
        # Two to four influences per vertex (skin indices), raw integer weights.
        nsets = 2 if (variant == 1 and p == 0) else 1
        jidx = np.zeros((V, 4 * nsets), dtype=np.int64)
        wdec = np.zeros((V, 4 * nsets))
        for v in range(V):
            fj = home[v]
            cands = [fj, jparent[fj] if jparent[fj] >= 0 else fj, int(rng.integers(0, J))]
            k = 3 if nsets == 1 else 5
            for q in range(k):
                jidx[v, q] = skin_of[cands[q % 3]]
        faces = rng.integers(0, V, (2 * V, 3))
        attrs = {}
        if p == 0:
            # POSITION tightly packed float; JOINTS_0 ushort; WEIGHTS_0 normalised ubyte summing to 255.
            attrs["POSITION"] = b.accessor(b.view(pos.tobytes()), 0, 5126, V, "VEC3", pos)
            raw = np.zeros((V, 4), dtype=np.uint8)
            for v in range(V):
                cut = np.sort(rng.integers(0, 256, 2))
                raw[v, :3] = [cut[0], cut[1] - cut[0], 255 - cut[1]]
                raw[v, 0] = max(raw[v, 0], 1)  # at least one non-zero weight
            wdec[:, :4] = raw / 255.0
            attrs["JOINTS_0"] = b.accessor(b.view(jidx[:, :4].astype(np.uint16).tobytes()), 0, 5123, V, "VEC4",
                                           jidx[:, :4])
            attrs["WEIGHTS_0"] = b.accessor(b.view(raw.tobytes()), 0, 5121, V, "VEC4", wdec[:, :4], normalized=True)
            if nsets == 2:
                w1 = np.zeros((V, 4), dtype=np.float32)
                w1[:, :2] = rng.uniform(0, 0.5, (V, 2)).astype(np.float32)
                wdec[:, 4:] = w1
                attrs["JOINTS_1"] = b.accessor(b.view(jidx[:, 4:].astype(np.uint8).tobytes()), 0, 5121, V, "VEC4",
                                               jidx[:, 4:])
                attrs["WEIGHTS_1"] = b.accessor(b.view(w1.tobytes()), 0, 5126, V, "VEC4", w1)
            ind = b.accessor(b.view(faces.astype(np.uint8).tobytes()), 0, 5121, faces.size, "SCALAR", faces.ravel())
        else:
            # POSITION + NORMAL interleaved with stride 28; WEIGHTS_0 normalised ushort, stride 16;
            # JOINTS_0 ubyte at byteOffset 4 inside a view; indices uint32.
            nrm = rng.normal(0, 1, (V, 3)).astype(np.float32)
            inter = strided([pos[v].tobytes() + nrm[v].tobytes() for v in range(V)], 28)
            view = b.view(inter, stride=28)
            attrs["POSITION"] = b.accessor(view, 0, 5126, V, "VEC3", pos)
            attrs["NORMAL"] = b.accessor(view, 12, 5126, V, "VEC3", nrm)
            raw = rng.integers(0, 65536, (V, 4)).astype(np.uint16)
            raw[:, 3] = 0
            raw[:, 0] = np.maximum(raw[:, 0], 1)
            wdec[:, :4] = raw / 65535.0
            attrs["WEIGHTS_0"] = b.accessor(b.view(strided([raw[v].tobytes() for v in range(V)], 16), stride=16), 0,
                                            5123, V, "VEC4", wdec[:, :4], normalized=True)
            attrs["JOINTS_0"] = b.accessor(b.view(b"\x07" * 4 + jidx[:, :4].astype(np.uint8).tobytes()), 4, 5121, V,
                                           "VEC4", jidx[:, :4])
            ind = b.accessor(b.view(faces.astype(np.uint32).tobytes()), 0, 5125, faces.size, "SCALAR", faces.ravel())
        prims.append({"attributes": attrs, "indices": ind, "mode": 4})
        all_pos.append(pos.astype(np.float64))
        all_faces.append(faces + offset)
        offset += V
        # Weights per vertex over skin joints.
        W = np.zeros((V, J))
        for v in range(V):
            for q in range(jidx.shape[1]):
                W[v, jidx[v, q]] += wdec[v, q]
        weight_rows.append(W)
    mat = b.accessor(b.view(ibm.transpose(0, 2, 1).tobytes()), 0, 5126, J, "MAT4", ibm.transpose(0, 2, 1).reshape(J, 16))

    doc = {"asset": {"version": "2.0", "generator": "hawor tests/ref/gltf_make.py"},
           "scene": 0, "scenes": [{"nodes": [0]}], "nodes": node_json,
           "meshes": [{"name": "thing", "primitives": prims}],
           "skins": [{"joints": [2 + skin_order[k] for k in range(J)], "inverseBindMatrices": mat}],
           "accessors": b.accessors, "bufferViews": b.views,
           "buffers": [{"byteLength": len(b.data)}]}
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    data = bytes(b.data) + b"\0" * (-len(b.data) % 4)
    glb = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(data))
    glb += struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(data), 0x004E4942) + data
    with open(path, "wb") as f:
        f.write(glb)

    # --- expected conversion -----------------------------------------------------------------------
    # Nearest joint ancestor (skin indices), then parent-first order by smallest skin index.
    skin_nodes = {2 + skin_order[k]: k for k in range(J)}
    par_skin = []
    for k in range(J):
        n = node_parent.get(2 + skin_order[k])
        while n is not None and n not in skin_nodes:
            n = node_parent.get(n)
        par_skin.append(skin_nodes[n] if n is not None else -1)
    order = []
    while len(order) < J:
        k = min(k for k in range(J) if k not in order and (par_skin[k] < 0 or par_skin[k] in order))
        order.append(k)
    model_of = {k: i for i, k in enumerate(order)}
    parents = [model_of[par_skin[k]] if par_skin[k] >= 0 else -1 for k in order]
    bind = np.linalg.inv(ibm.astype(np.float64))  # (J,4,4) in skin order
    rest = bind[order][:, :3, 3]
    Wall = np.vstack(weight_rows)
    Wall = Wall / Wall.sum(axis=1, keepdims=True)
    weights = Wall[:, order]

    pose = rng.normal(0, 0.5, (J, 3))
    Rl = Rotation.from_rotvec(pose).as_matrix()
    Rg = [None] * J
    Wm = [None] * J
    for j in range(J):
        k = order[j]
        W = np.eye(4)
        if parents[j] < 0:
            Rg[j] = Rl[j]
            W[:3, 3] = rest[j]
        else:
            p = parents[j]
            Rg[j] = Rg[p] @ Rl[j]
            W[:3, 3] = Wm[p][:3, 3] + Rg[p] @ (rest[j] - rest[p])
        W[:3, :3] = Rg[j] @ bind[k][:3, :3]
        Wm[j] = W
    # Skinning of the raw data: per skin joint k, W_model(k) @ IBM_k.
    Vall = np.vstack(all_pos)
    ph = np.hstack([Vall, np.ones((len(Vall), 1))])
    skin_mats = np.array([Wm[model_of[k]] @ ibm[k].astype(np.float64) for k in range(J)])
    Wraw = np.vstack(weight_rows)
    posed = np.einsum("vk,kij,vj->vi", Wraw, skin_mats, ph)[:, :3] / Wraw.sum(axis=1, keepdims=True)

    out = {"node_world": world, "v_template": Vall, "faces": np.vstack(all_faces), "order": np.array(order),
           "order_finger": np.array([skin_order[k] for k in order]),
           "parents": np.array(parents), "rest": rest, "weights": weights, "pose": pose, "posed": posed,
           "num_accessors": np.array([len(b.decoded)])}
    for i, d in enumerate(b.decoded):
        out["acc%d" % i] = d
    return out


def main():
    outpath = sys.argv[1]
    rng = np.random.default_rng(20250101)
    arrays = {}
    for k in range(3):
        for name, a in make(k, "%s.%d.glb" % (outpath, k), rng).items():
            arrays["v%d_%s" % (k, name)] = a
    refio.save(outpath, **arrays)


if __name__ == "__main__":
    main()
