"""Writes SYNTHETIC MANO model files with the structure of the official ones (docs/design.md §3).

The real MANO_RIGHT.pkl / MANO_LEFT.pkl are licence-restricted, so the tests use random but
well-formed stand-ins: the same keys, shapes, dtypes and Python object layout (numpy arrays via
numpy.core.multiarray._reconstruct, shapedirs as a `chumpy.ch.Ch` object whose state dict holds the
array under 'x' next to noise such as a `_dirty_vars` set, J_regressor as a
`scipy.sparse.csc.csc_matrix` with data/indices/indptr/_shape), pickled at protocol 2 with the
opcodes of Python 2 for strings (SHORT_BINSTRING / BINSTRING, not `_codecs.encode`). The stand-in
classes are created on the fly under those module names; neither chumpy nor scipy is imported.

The left model is the exact mirror of the right one under x -> -x (see hand/mirror.hpp) and its
file carries the known bug of the released MANO_LEFT.pkl: shapedirs[:, 0, :] not negated.

    /usr/bin/python3 hand_make_mano.py <out.txt> <dir>

writes <dir>/MANO_RIGHT.pkl, MANO_LEFT.pkl, protocol variants of the right file, mano_right.npz,
mano_left.npz (compressed), and to <out.txt> (tests/ref/refio.py format) the arrays a loader must
produce (the left ones with the bug fixed, prefixed L_).
"""
import os
import pickle
import struct
import sys
import types

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import refio  # noqa: E402

PARENTS = [-1, 0, 1, 2, 0, 4, 5, 0, 7, 8, 0, 10, 11, 0, 13, 14]
TIPS = [744, 320, 443, 554, 671]  # thumb, index, middle, ring, pinky
V, J, B, F = 778, 16, 10, 1538
NPOSE = 9 * (J - 1)


def make_right(seed=7):
    """A random right hand with MANO's sizes: skeleton-like joints, vertices around them."""
    rng = np.random.default_rng(seed)
    joints = np.zeros((J, 3))
    joints[0] = [0.09, 0.005, 0.006]
    bases = {1: [0.0, 0.0, 0.025], 4: [-0.005, 0.0, 0.005], 10: [0.0, 0.0, -0.015],
             7: [0.01, 0.0, -0.032], 13: [0.06, -0.012, 0.03]}
    for b, p in bases.items():
        joints[b] = p
        d = np.array([-1.0, 0.0, 0.0]) if b != 13 else np.array([-0.7, -0.3, 0.6])
        d /= np.linalg.norm(d)
        for k, seg in enumerate([0.035, 0.025]):
            joints[b + k + 1] = joints[b + k] + seg * d
    joints += rng.normal(0, 0.002, joints.shape)

    # Each vertex hangs off a home joint; the fingertip vertices sit beyond the last joints.
    home = np.concatenate([np.arange(J), rng.integers(0, J, V - J)])
    rng.shuffle(home)
    tip_joint = {744: 15, 320: 3, 443: 6, 554: 12, 671: 9}
    for v, j in tip_joint.items():
        home[v] = j
    child = {j: PARENTS.index(j) if j in PARENTS else None for j in range(J)}
    v_template = np.zeros((V, 3))
    for v in range(V):
        j = home[v]
        c = child[j]
        seg = (joints[c] - joints[j]) if c is not None else (joints[j] - joints[PARENTS[j]]) * 0.6
        v_template[v] = joints[j] + rng.uniform(0, 1) * seg + rng.normal(0, 0.007, 3)
    for v, j in tip_joint.items():
        v_template[v] = joints[j] + 0.8 * (joints[j] - joints[PARENTS[j]])

    # Sparse skinning weights: home joint plus up to two neighbours, rows sum to 1.
    weights = np.zeros((V, J))
    for v in range(V):
        j = home[v]
        weights[v, j] = rng.uniform(0.5, 1.0)
        nbrs = [PARENTS[j]] if j > 0 else []
        if child[j] is not None:
            nbrs.append(child[j])
        for n in nbrs:
            if rng.uniform() < 0.6:
                weights[v, n] = rng.uniform(0.0, 0.5)
    weights /= weights.sum(axis=1, keepdims=True)

    # Sparse joint regressor: 8..24 of the joint's own vertices, positive, rows sum to 1.
    j_reg = np.zeros((J, V))
    for j in range(J):
        own = np.flatnonzero(home == j)
        k = min(len(own), int(rng.integers(8, 25)))
        pick = rng.choice(own, size=k, replace=False)
        j_reg[j, pick] = rng.uniform(0.2, 1.0, k)
        j_reg[j] /= j_reg[j].sum()

    faces = np.zeros((F, 3), dtype=np.uint32)
    for i in range(F):
        faces[i] = rng.choice(V, size=3, replace=False)

    return dict(
        v_template=v_template,
        f=faces,
        shapedirs=rng.normal(0, 0.004, (V, 3, B)),
        posedirs=rng.normal(0, 0.002, (V, 3, NPOSE)),
        J_regressor=j_reg,
        weights=weights,
        kintree_table=np.array([[4294967295] + PARENTS[1:], list(range(J))], dtype=np.int64),
        J=j_reg @ v_template,
        hands_components=rng.normal(0, 0.3, (45, 45)),
        hands_mean=rng.normal(0, 0.2, 45),
        hands_coeffs=rng.normal(0, 0.5, (12, 45)),
        bs_style="lbs",
        bs_type="lrotmin",
    )


def mirror(model):
    """The mirror image under M = diag(-1, 1, 1): x of every point / direction negated, the pose
    correctives conjugated (feature (r, c) of R - I changes sign by m_r * m_c under R -> M R M)."""
    m = dict(model)
    vt = model["v_template"].copy()
    vt[:, 0] *= -1
    sd = model["shapedirs"].copy()
    sd[:, 0, :] *= -1
    sign = np.array([-1.0, 1.0, 1.0])
    feat = np.tile(np.outer(sign, sign).reshape(9), J - 1)       # k_f = m_r m_c
    pd = model["posedirs"] * sign[None, :, None] * feat[None, None, :]
    m.update(v_template=vt, shapedirs=sd, posedirs=pd, J=model["J_regressor"] @ vt)
    return m


def with_left_bug(left):
    """What the released MANO_LEFT.pkl looks like: shapedirs[:, 0, :] not mirrored."""
    m = dict(left)
    sd = left["shapedirs"].copy()
    sd[:, 0, :] *= -1
    m["shapedirs"] = sd
    return m


# --- Python object layout of the official files ---------------------------------------------------
_CLASSES = {}


def _stand_in_class(module, name):
    if (module, name) in _CLASSES:
        return _CLASSES[(module, name)]
    parts = module.split(".")
    for i in range(1, len(parts) + 1):
        mod = ".".join(parts[:i])
        if mod not in sys.modules or not getattr(sys.modules[mod], "_hawor_stand_in", False):
            sys.modules[mod] = types.ModuleType(mod)
            sys.modules[mod]._hawor_stand_in = True
        if i > 1:
            setattr(sys.modules[".".join(parts[:i - 1])], parts[i - 1], sys.modules[mod])
    cls = type(name, (object,), {})
    cls.__module__ = module
    cls.__qualname__ = name
    setattr(sys.modules[module], name, cls)
    _CLASSES[(module, name)] = cls
    return cls


def _csc(dense, shape_key="_shape"):
    cls = _stand_in_class("scipy.sparse.csc", "csc_matrix")
    obj = cls.__new__(cls)
    rows, cols = dense.shape
    data, indices, indptr = [], [], [0]
    for c in range(cols):
        nz = np.flatnonzero(dense[:, c])
        data.extend(dense[nz, c])
        indices.extend(nz)
        indptr.append(len(data))
    obj.__dict__.update({shape_key: (rows, cols), "data": np.array(data, dtype=np.float64),
                         "indices": np.array(indices, dtype=np.int32),
                         "indptr": np.array(indptr, dtype=np.int32), "maxprint": 50, "format": "csc"})
    return obj


def _chumpy(x):
    cls = _stand_in_class("chumpy.ch", "Ch")
    obj = cls.__new__(cls)
    obj.__dict__.update({"x": x, "_dirty_vars": set(["x"]), "_itr": None, "_depends_on_deps": {}})
    return obj


def pickle_layout(model, shape_key="_shape"):
    d = dict(model)
    d["shapedirs"] = _chumpy(model["shapedirs"])
    d["J_regressor"] = _csc(model["J_regressor"], shape_key)
    return d


class Py2Pickler(pickle._Pickler):
    """The pure-Python pickler, writing str and bytes as Python 2 did (SHORT_BINSTRING /
    BINSTRING) instead of BINUNICODE and `_codecs.encode` reduces."""
    dispatch = pickle._Pickler.dispatch.copy()

    def save_py2_string(self, obj):
        data = obj.encode("latin-1") if isinstance(obj, str) else bytes(obj)
        if len(data) < 256:
            self.write(pickle.SHORT_BINSTRING + bytes([len(data)]) + data)
        else:
            self.write(pickle.BINSTRING + struct.pack("<i", len(data)) + data)
        self.memoize(obj)

    dispatch[bytes] = save_py2_string
    dispatch[str] = save_py2_string


def dump_py2(obj, path):
    with open(path, "wb") as f:
        Py2Pickler(f, protocol=2).dump(obj)


def dump_std(obj, path, protocol):
    with open(path, "wb") as f:
        pickle._Pickler(f, protocol=protocol).dump(obj)


def dump_npz(model, path, compressed):
    arrays = {k: np.asarray(v) for k, v in model.items()}
    (np.savez_compressed if compressed else np.savez)(path, **arrays)


def write_all(outdir, seed=7):
    right = make_right(seed)
    left = mirror(right)
    os.makedirs(outdir, exist_ok=True)
    dump_py2(pickle_layout(right), os.path.join(outdir, "MANO_RIGHT.pkl"))
    dump_py2(pickle_layout(with_left_bug(left)), os.path.join(outdir, "MANO_LEFT.pkl"))
    # Variants of the right file: Python-3 pickler at protocols 0, 2, 4; old 'shape' key;
    # Fortran-ordered and big-endian arrays.
    for p in (0, 2, 4):
        dump_std(pickle_layout(right), os.path.join(outdir, "MANO_RIGHT_p%d.pkl" % p), p)
    odd = dict(right)
    odd["weights"] = np.asfortranarray(right["weights"])
    odd["v_template"] = right["v_template"].astype(">f8")
    odd["posedirs"] = right["posedirs"].astype(np.float32).astype(np.float64)  # exact in float32
    odd_layout = pickle_layout(odd, shape_key="shape")
    odd_layout["posedirs"] = odd["posedirs"].astype(np.float32)
    dump_py2(odd_layout, os.path.join(outdir, "MANO_RIGHT_odd.pkl"))
    dump_npz(right, os.path.join(outdir, "mano_right.npz"), compressed=False)
    dump_npz(with_left_bug(left), os.path.join(outdir, "mano_left.npz"), compressed=True)
    return right, left, odd


def reference_arrays(model, prefix):
    probe = np.sin(np.arange(NPOSE) * 0.37)
    return {
        prefix + "v_template": model["v_template"],
        prefix + "faces": model["f"].astype(np.float64),
        prefix + "shapedirs": model["shapedirs"],
        prefix + "J_regressor": model["J_regressor"],
        prefix + "weights": model["weights"],
        prefix + "parents": np.array(PARENTS, dtype=np.float64),
        prefix + "posedirs_probe": model["posedirs"].reshape(3 * V, NPOSE) @ probe,
    }


def main():
    out, outdir = sys.argv[1], sys.argv[2]
    right, left, odd = write_all(outdir)
    arrays = {}
    arrays.update(reference_arrays(right, ""))
    arrays.update(reference_arrays(left, "L_"))
    arrays["odd_posedirs_probe"] = reference_arrays(odd, "")["posedirs_probe"]
    arrays["probe"] = np.sin(np.arange(NPOSE) * 0.37)
    refio.save(out, **arrays)


if __name__ == "__main__":
    main()
