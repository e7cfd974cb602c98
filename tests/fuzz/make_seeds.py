"""Seed corpora for the pickle and GLB fuzz targets (run at build time by tests/fuzz/CMakeLists.txt):

    /usr/bin/python3 make_seeds.py <seeds dir>

writes <dir>/pickle/*.pkl: small files with the MANO pickle layout (a dict of numpy arrays, a
chumpy.ch.Ch shape matrix, a scipy.sparse.csc csc_matrix regressor; stand-in classes from
tests/ref/hand_make_mano.py) at protocols 0, 2 (Python 2 strings) and 4, plus refused inputs (a
reduce of os.system, deep nesting); and <dir>/glb/*.glb: the skinned test hands of
tests/ref/gltf_make.py. Small on purpose (libFuzzer runs with -max_len=8192).
"""
import os
import pickle
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "ref"))
import gltf_make  # noqa: E402
import hand_make_mano as hm  # noqa: E402


class _System:
    """Pickles as a call of os.system: the reader must refuse it, never run it."""

    def __reduce__(self):
        return (os.system, ("echo pwned",))


def tiny_model(rng, V=6, J=3, B=2):
    return {
        "v_template": rng.normal(0, 0.05, (V, 3)),
        "f": np.array([[0, 1, 2], [2, 3, 4]], dtype=np.uint32),
        "shapedirs": rng.normal(0, 0.01, (V, 3, B)),
        "posedirs": rng.normal(0, 0.01, (V, 3, 9 * (J - 1))),
        "J_regressor": np.abs(rng.normal(0, 1, (J, V))) * (rng.random((J, V)) < 0.5),
        "weights": np.full((V, J), 1.0 / J),
        "kintree_table": np.array([[4294967295, 0, 1], [0, 1, 2]], dtype=np.int64),
        "hands_components": rng.normal(0, 1, (2, 9 * (J - 1))),
        "hands_mean": np.zeros(9 * (J - 1)),
        "bs_style": "lbs",
        "bs_type": "lrotmin",
    }


def main():
    out = sys.argv[1]
    rng = np.random.default_rng(11)
    pk, gl = os.path.join(out, "pickle"), os.path.join(out, "glb")
    os.makedirs(pk, exist_ok=True)
    os.makedirs(gl, exist_ok=True)
    model = tiny_model(rng)
    hm.dump_py2(hm.pickle_layout(model), os.path.join(pk, "mano_py2.pkl"))
    for p in (0, 2, 4):
        hm.dump_std(hm.pickle_layout(model), os.path.join(pk, "mano_p%d.pkl" % p), p)
    with open(os.path.join(pk, "reduce_os_system.pkl"), "wb") as f:
        pickle.dump({"v_template": _System()}, f, protocol=2)
    nested = []
    for _ in range(200):
        nested = [nested]
    with open(os.path.join(pk, "nested.pkl"), "wb") as f:
        pickle.dump(nested, f, protocol=2)
    grng = np.random.default_rng(20250101)
    for k in range(3):
        gltf_make.make(k, os.path.join(gl, "hand%d.glb" % k), grng)


if __name__ == "__main__":
    main()
