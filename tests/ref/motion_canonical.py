"""Reference for motion/canonical.hpp: camera -> world -> canonical (docs/design.md §3, §7), numpy/scipy.

MANO rotates about joint 0, so a rigid move (R, p) of a hand acts on its root joint:
  root = trans + J0,  R_hand' = R R_hand,  root' = R root + p,  trans' = root' - J0.
camera -> world: (R, p) = (R_c2w(t), t_c2w(t)) per frame.
world -> canonical (frame o = first valid): R_w2can = R_w(o)^T, t_w2can = -R_w2can root_w(o) + J0(o).
Paper per-frame form (A = R_c(o) Phi_o, Gamma = camera-space root joint):
  Gamma_can(t) = A^-1 (R_c(t) Gamma(t) + t_c(t) - t_c(o) - R_c(o) Gamma(o)),  Phi_can = A^-1 R_c(t) Phi(t).
Rotations are saved as matrices (T, 3, 3).
"""
import sys

import numpy as np
from scipy.spatial.transform import Rotation

import refio

rng = np.random.default_rng(31)


def main(out):
    T = 40
    valid = np.ones(T, dtype=bool)
    valid[:3] = False
    valid[17:25] = False
    R_c2w = Rotation.random(T, random_state=5).as_matrix()
    t_c2w = rng.normal(size=(T, 3))
    rot_c = rng.normal(size=(T, 3))
    trans_c = rng.normal(size=(T, 3)) * 0.2 + np.array([0.0, 0.0, 0.5])
    pose = rng.normal(size=(T, 45)) * 0.3
    betas = rng.normal(size=(T, 10))
    J0 = rng.normal(size=(T, 3)) * 0.05 + np.array([0.09, 0.006, 0.006])  # per-frame J0(beta_t)

    Rc = Rotation.from_rotvec(rot_c).as_matrix()
    Rw = R_c2w @ Rc
    root_w = np.einsum("tij,tj->ti", R_c2w, trans_c + J0) + t_c2w
    trans_w = root_w - J0

    o = int(np.flatnonzero(valid)[0])
    R_w2can = Rw[o].T
    t_w2can = -R_w2can @ root_w[o] + J0[o]
    Rcan = R_w2can @ Rw
    root_can = root_w @ R_w2can.T + t_w2can
    trans_can = root_can - J0

    # paper form with one J0 for all frames (its Gamma is the root joint)
    j0 = J0[o]
    root_c = trans_c + j0
    A_inv = (R_c2w[o] @ Rc[o]).T
    paper_R = A_inv @ R_c2w @ Rc
    paper_trans = np.einsum("ij,tj->ti", A_inv,
                            np.einsum("tij,tj->ti", R_c2w, root_c) + t_c2w - t_c2w[o] - R_c2w[o] @ root_c[o])

    refio.save(out, valid=valid.astype(float), R_c2w=R_c2w, t_c2w=t_c2w, rot_c=rot_c,
               trans_c=trans_c, pose=pose, betas=betas, J0=J0,
               Rw=Rw, trans_w=trans_w, R_w2can=R_w2can, t_w2can=t_w2can, Rcan=Rcan,
               trans_can=trans_can, paper_R=paper_R, paper_trans=paper_trans)


if __name__ == "__main__":
    main(sys.argv[1])
