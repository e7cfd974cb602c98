"""Reference for motion/slerp.hpp: scipy's Slerp between random rotation pairs.

Cases: generic pairs, pairs whose quaternions have a negative dot product (short path needed),
near-identical pairs (the LERP fallback), relative angles close to pi. Saves inputs (quaternions
(w, x, y, z) and rotation vectors), the times, and scipy's interpolated rotation matrices.
"""
import sys

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

import refio

rng = np.random.default_rng(20250101)


def random_quat(n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def main(out):
    pairs = []
    # generic
    for q0, q1 in zip(random_quat(40), random_quat(40)):
        pairs.append((q0, q1))
    # negative dot: flip q1 (same rotation, must take the short path)
    for q0, q1 in zip(random_quat(20), random_quat(20)):
        if np.dot(q0, q1) > 0:
            q1 = -q1
        pairs.append((q0, q1))
    # near-identical (relative angle 1e-9 .. 1e-3 rad)
    for k, q0 in enumerate(random_quat(20)):
        ang = 10.0 ** rng.uniform(-9, -3)
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        r1 = Rotation.from_quat(q0[[1, 2, 3, 0]]) * Rotation.from_rotvec(ang * axis)
        q1 = r1.as_quat()[[3, 0, 1, 2]]
        if k % 2:
            q1 = -q1
        pairs.append((q0, q1))
    # relative angle close to pi
    for q0 in random_quat(10):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        r1 = Rotation.from_quat(q0[[1, 2, 3, 0]]) * Rotation.from_rotvec((np.pi - 1e-3) * axis)
        pairs.append((q0, r1.as_quat()[[3, 0, 1, 2]]))

    n = len(pairs)
    q0 = np.array([p[0] for p in pairs])  # (w, x, y, z)
    q1 = np.array([p[1] for p in pairs])
    t = rng.uniform(0.0, 1.0, size=n)
    t[:5] = 0.0
    t[5:10] = 1.0
    expected = np.zeros((n, 3, 3))
    for i in range(n):
        rots = Rotation.from_quat(np.stack([q0[i][[1, 2, 3, 0]], q1[i][[1, 2, 3, 0]]]))
        expected[i] = Slerp([0.0, 1.0], rots)([t[i]]).as_matrix()[0]
    a0 = Rotation.from_quat(q0[:, [1, 2, 3, 0]]).as_rotvec()
    a1 = Rotation.from_quat(q1[:, [1, 2, 3, 0]]).as_rotvec()
    refio.save(out, q0=q0, q1=q1, a0=a0, a1=a1, t=t, expected=expected)


if __name__ == "__main__":
    main(sys.argv[1])
