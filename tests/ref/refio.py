"""Writes named numpy arrays in the plain-text format read by tests/support/ref_data.hpp."""
import numpy as np


def save(path, **arrays):
    with open(path, "w") as f:
        for name, a in arrays.items():
            a = np.asarray(a, dtype=np.float64)
            f.write("%s %d %s\n" % (name, a.ndim, " ".join(str(d) for d in a.shape)))
            f.write(" ".join("%.17g" % v for v in a.ravel(order="C")) + "\n")


def load(path):
    out = {}
    with open(path) as f:
        toks = f.read().split()
    i = 0
    while i < len(toks):
        name = toks[i]; ndim = int(toks[i + 1]); i += 2
        shape = tuple(int(t) for t in toks[i:i + ndim]); i += ndim
        n = int(np.prod(shape)) if ndim else 1
        out[name] = np.array([float(t) for t in toks[i:i + n]]).reshape(shape); i += n
    return out
