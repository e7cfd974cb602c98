"""Reference data for tests/geometry/ref_rotations.cpp.

Usage: geometry_rotations.py <out.txt>

Inputs are generated here with a fixed seed; expected outputs come from independent sources:
  - scipy.spatial.transform.Rotation (from_rotvec, as_matrix, as_quat, from_matrix, as_rotvec),
  - numpy Gram-Schmidt for rot6d (docs/design.md §2 layout [R00, R01, R10, R11, R20, R21]),
  - Umeyama alignment: rotation from scipy's Rotation.align_vectors (weighted Kabsch), scale and
    translation from the closed forms given that rotation; cross-checked in this script against
    a numpy SVD implementation written from the paper,
  - the SO(3)/SE(3) coefficient functions and the Sim(3) W coefficients evaluated with Python's
    decimal module at 100 digits from their closed forms (series for sin/cos written here).
"""
import sys
from decimal import Decimal, getcontext

import numpy as np
from scipy.spatial.transform import Rotation

from refio import save

getcontext().prec = 100


def main(out):
    rng = np.random.default_rng(20240611)
    arrays = {}

    # --- axis-angle / matrix / quaternion ------------------------------------------------------
    def unit(n):
        v = rng.normal(size=(n, 3))
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    angles = np.concatenate([
        [0.0, 1e-15, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3, 0.01, 0.3, 0.999, 1.001],
        rng.uniform(0, np.pi, 40),
        np.pi - np.array([1e-3, 1e-6, 1e-8, 1e-10, 1e-12]),
    ])
    rotvec = unit(len(angles)) * angles[:, None]
    rot = Rotation.from_rotvec(rotvec)
    q = rot.as_quat()  # scipy: (x, y, z, w)
    arrays["rotvec"] = rotvec
    arrays["rotvec_matrix"] = rot.as_matrix()
    arrays["rotvec_quat_wxyz"] = np.concatenate([q[:, 3:], q[:, :3]], axis=1)
    # Matrix -> rotation vector through scipy's own from_matrix path.
    arrays["rotvec_back"] = Rotation.from_matrix(rot.as_matrix()).as_rotvec()

    # Angles beyond pi: scipy returns the shortest rotation vector.
    big = unit(10) * rng.uniform(np.pi + 0.01, 2 * np.pi - 0.01, 10)[:, None]
    arrays["big_rotvec"] = big
    arrays["big_rotvec_short"] = Rotation.from_rotvec(big).as_rotvec()

    # Random rotation matrices (uniform) -> quaternion (w >= 0) and rotation vector.
    mats = Rotation.random(30, random_state=7).as_matrix()
    qm = Rotation.from_matrix(mats).as_quat()
    qm = qm * np.where(qm[:, 3:] < 0, -1.0, 1.0)
    arrays["mats"] = mats
    arrays["mats_quat_wxyz"] = np.concatenate([qm[:, 3:], qm[:, :3]], axis=1)
    arrays["mats_rotvec"] = Rotation.from_matrix(mats).as_rotvec()

    # --- rot6d ---------------------------------------------------------------------------------
    r6 = np.stack([m[:, :2].reshape(6) for m in mats])  # row-major of the first two columns
    noisy6 = r6 * rng.uniform(0.5, 2.0, (len(r6), 1)) + rng.normal(scale=0.2, size=r6.shape)
    gs = []
    for v in noisy6:
        a, b = v.reshape(3, 2)[:, 0], v.reshape(3, 2)[:, 1]
        c0 = a / np.linalg.norm(a)
        c1 = b - (c0 @ b) * c0
        c1 /= np.linalg.norm(c1)
        gs.append(np.stack([c0, c1, np.cross(c0, c1)], axis=1))
    arrays["rot6d"] = r6
    arrays["rot6d_noisy"] = noisy6
    arrays["rot6d_noisy_matrix"] = np.array(gs)

    # --- Umeyama -------------------------------------------------------------------------------
    cases = []
    for n, noise, weighted, with_scale in [(5, 0.0, False, True), (5, 0.0, True, False),
                                           (21, 0.01, False, True), (21, 0.01, True, True),
                                           (21, 0.01, False, False), (21, 0.01, True, False),
                                           (100, 0.2, True, True), (100, 0.2, False, False),
                                           (8, 0.5, True, True)]:
        src = rng.normal(size=(n, 3)) * rng.uniform(0.1, 2.0)
        R0 = Rotation.random(random_state=int(rng.integers(1 << 30))).as_matrix()
        s0 = rng.uniform(0.2, 5.0)
        t0 = rng.normal(size=3) * 2
        dst = s0 * src @ R0.T + t0 + rng.normal(scale=noise, size=(n, 3))
        w = rng.uniform(0.0, 2.0, n) if weighted else np.ones(n)
        if weighted:
            w[rng.integers(n)] = 0.0
        cases.append((src, dst, w, weighted, with_scale))
    arrays["umeyama_count"] = np.array([len(cases)])
    for i, (src, dst, w, weighted, with_scale) in enumerate(cases):
        wn = w / w.sum()
        mx, my = wn @ src, wn @ dst
        X, Y = src - mx, dst - my
        # Independent rotation: scipy's weighted Kabsch, R minimising sum w |Y - R X|^2.
        rot_k, _ = Rotation.align_vectors(Y, X, weights=w)
        R = rot_k.as_matrix()
        s = float(np.sum(wn * np.einsum("ij,ij->i", X @ R.T, Y)) / np.sum(wn * np.sum(X * X, 1))) \
            if with_scale else 1.0
        t = my - s * R @ mx
        # Cross-check with a numpy SVD Umeyama (reflection fix included).
        U, D, Vt = np.linalg.svd((Y * wn[:, None]).T @ X)
        Sfix = np.diag([1.0, 1.0, -1.0 if np.linalg.det(U) * np.linalg.det(Vt) < 0 else 1.0])
        R2 = U @ Sfix @ Vt
        assert np.allclose(R, R2, atol=1e-9), (R, R2)
        if with_scale:
            s2 = np.trace(np.diag(D) @ Sfix) / np.sum(wn * np.sum(X * X, 1))
            assert abs(s - s2) < 1e-9 * s2
        arrays["umeyama_%d_src" % i] = src
        arrays["umeyama_%d_dst" % i] = dst
        arrays["umeyama_%d_w" % i] = w
        arrays["umeyama_%d_flags" % i] = np.array([float(weighted), float(with_scale)])
        arrays["umeyama_%d_R" % i] = R
        arrays["umeyama_%d_t" % i] = t
        arrays["umeyama_%d_s" % i] = np.array([s])

    # --- coefficient functions at 100 digits --------------------------------------------------
    def sin_cos(x):
        s, c, term, k = Decimal(0), Decimal(0), Decimal(1), 0
        # term = x^k / k!
        while True:
            if k % 4 == 0:
                c += term
            elif k % 4 == 1:
                s += term
            elif k % 4 == 2:
                c -= term
            else:
                s -= term
            k += 1
            term = term * x / k
            if abs(term) < Decimal(10) ** -110 and k > 4:
                break
        return s, c

    thetas = [1e-8, 1e-6, 1e-4, 1e-3, 0.01, 0.05, 0.1, 0.3, 0.5, 0.9, 0.999, 1.001, 1.5, 2.0,
              2.5, 3.0, 3.14, np.pi - 1e-6, 4.0, 5.5]
    coeffs = []
    for th in thetas:
        x = Decimal(th)
        s, c = sin_cos(x)
        hs, hc = sin_cos(x / 2)
        x2 = x * x
        A = s / x
        B = (1 - c) / x2
        C = (x - s) / (x2 * x)
        E = 1 / x2 - hc / (2 * x * hs)
        D2 = (x2 + 2 * c - 2) / (2 * x2 * x2)
        D3 = (2 * x - 3 * s + x * c) / (2 * x2 * x2 * x)
        coeffs.append([float(v) for v in (A, B, C, E, D2, D3)])
    arrays["coef_theta"] = np.array(thetas)
    arrays["coef_values"] = np.array(coeffs)

    grid_s = [0.0, 1e-12, -1e-9, 1e-6, -1e-4, 0.01, -0.05, 0.0707, 0.0999, -0.1001, 0.3,
              0.999, -0.999, 1.0, -1.0, 1.001, -1.001, 2.0, -3.0, 3.0, 5.0, -6.0, 9.0]
    grid_t = [0.0, 1e-12, 1e-9, 1e-6, 1e-4, 0.01, 0.05, 0.0707, 0.0999, 0.1001, 0.3, 1.0, 2.0,
              3.1, np.pi - 1e-6]
    wrows = []
    for sg in grid_s:
        for th in grid_t:
            sd, x = Decimal(sg), Decimal(th)
            r2 = sd * sd + x * x
            if r2 == 0:
                a, b, cc = Decimal(1), Decimal(1) / 2, Decimal(1) / 6
            else:
                s, c = sin_cos(x)
                if x == 0:
                    A, B = Decimal(1), Decimal(1) / 2
                else:
                    A, B = s / x, (1 - c) / (x * x)
                es = sd.exp()
                a = (es - 1) / sd if sd != 0 else Decimal(1)
                b = (sd * es * A - (es * c - 1)) / r2
                cc = (sd * es * B + a - es * A) / r2
            wrows.append([sg, th, float(a), float(b), float(cc)])
    arrays["sim3w"] = np.array(wrows)

    save(out, **arrays)


if __name__ == "__main__":
    main(sys.argv[1])
