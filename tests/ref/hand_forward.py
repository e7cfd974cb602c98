"""Independent numpy implementation of the MANO forward pass (docs/design.md §3: `lbs` + `lrotmin`, full
axis-angle pose, no PCA, no hands_mean), evaluated on the synthetic models of hand_make_mano.py.

    /usr/bin/python3 hand_forward.py <out.txt> <dir>

writes the model files into <dir> (hand_make_mano.write_all) and to <out.txt> the inputs
(pose (N,16,3) with row 0 the global orientation, betas (N,10), transl (N,3)) and the outputs of
the right model (R_verts, R_joints, R_kp) and of the true left model (L_*) for the same inputs.
"""
import os
import sys

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hand_make_mano as hm  # noqa: E402
import refio  # noqa: E402

KP_ORDER = [0, 13, 14, 15, 16, 1, 2, 3, 17, 4, 5, 6, 18, 10, 11, 12, 19, 7, 8, 9, 20]


def mano_forward(model, pose, betas, transl):
    """pose (16,3) axis-angles (row 0 = global orientation), betas (10,), transl (3,)."""
    parents = hm.PARENTS
    nj = len(parents)
    v_shaped = model["v_template"] + np.einsum("vck,k->vc", model["shapedirs"], betas)
    j_rest = model["J_regressor"] @ v_shaped
    rot = Rotation.from_rotvec(pose).as_matrix()  # (16,3,3)
    feat = (rot[1:] - np.eye(3)[None]).reshape(-1)  # row-major (R - I) per joint, 135
    v_posed = v_shaped + (model["posedirs"].reshape(-1, feat.size) @ feat).reshape(-1, 3)
    world = np.zeros((nj, 4, 4))
    for j in range(nj):
        local = np.eye(4)
        local[:3, :3] = rot[j]
        local[:3, 3] = j_rest[j] - (j_rest[parents[j]] if j > 0 else 0.0)
        world[j] = local if j == 0 else world[parents[j]] @ local
    rel = world.copy()
    rel[:, :3, 3] -= np.einsum("jab,jb->ja", world[:, :3, :3], j_rest)
    per_vertex = np.einsum("vj,jab->vab", model["weights"], rel)
    homog = np.concatenate([v_posed, np.ones((v_posed.shape[0], 1))], axis=1)
    verts = np.einsum("vab,vb->va", per_vertex[:, :3, :], homog) + transl
    joints = world[:, :3, 3] + transl
    kp = np.concatenate([joints, verts[hm.TIPS]], axis=0)[KP_ORDER]
    return verts, joints, kp


def inputs(rng, n):
    pose = rng.normal(0, 0.6, (n, 16, 3))
    betas = rng.normal(0, 1.5, (n, hm.B))
    transl = rng.normal(0, 0.3, (n, 3))
    pose[0] = 0
    betas[0] = 0
    transl[0] = 0                          # rest pose: the template
    pose[1] = 0                            # shape only
    pose[2] *= 1e-9                        # tiny angles (series branch of Rodrigues)
    axes = rng.normal(0, 1, (n, 16, 3))
    axes /= np.linalg.norm(axes, axis=2, keepdims=True)
    pose[3] = axes[3] * (np.pi - 1e-7)     # near pi
    pose[4] = axes[4] * rng.uniform(2.5, 3.1, (16, 1))
    return pose, betas, transl


def main():
    out, outdir = sys.argv[1], sys.argv[2]
    right, left, _ = hm.write_all(outdir)
    rng = np.random.default_rng(2024)
    n = 7
    pose, betas, transl = inputs(rng, n)
    res = {"pose": pose, "betas": betas, "transl": transl}
    for name, model in (("R_", right), ("L_", left)):
        outs = [mano_forward(model, pose[i], betas[i], transl[i]) for i in range(n)]
        res[name + "verts"] = np.stack([o[0] for o in outs])
        res[name + "joints"] = np.stack([o[1] for o in outs])
        res[name + "kp"] = np.stack([o[2] for o in outs])
    # Sanity of the reference itself: the mirror identity of hand/mirror.hpp.
    for i in range(n):
        mp = pose[i] * np.array([1.0, -1.0, -1.0])
        mt = transl[i] * np.array([-1.0, 1.0, 1.0])
        lv = mano_forward(left, mp, betas[i], mt)[0]
        rv = res["R_verts"][i] * np.array([-1.0, 1.0, 1.0])
        assert np.abs(lv - rv).max() < 1e-12, "mirror identity fails in the reference"
    refio.save(out, **res)


if __name__ == "__main__":
    main()
