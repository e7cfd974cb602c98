"""Driver of the metric cross-check (tests/eval/ref_metrics.cpp): random inputs + expected values
from metrics_np (numpy, written from docs/design.md §8 independently of the C++ library).

Hands: T = 250 frames (chunks 100, 100, 50) of 21 joints; the estimate is a random similarity of
the ground truth plus a drift and per-joint noise, so every metric is non-trivial. Computed with
all frames valid and with a mask that has gaps (one whole chunk partially missing).
Cameras: T = 250 and T = 201 positions; per-part rigid alignment with part length 100 (so the
201-frame case has a 1-frame trailing part, merged into the previous one); camera rotations in a
rotated world with noise and one outlier frame for the rotation error.
"""
import os
import sys

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import metrics_np as M  # noqa: E402
import refio  # noqa: E402

rng = np.random.default_rng(8)


def hand_track(T):
    """Ground-truth world joints (T, 21, 3): a fixed hand shape moved smoothly."""
    shape = rng.normal(size=(21, 3)) * 0.04
    time = np.arange(T) / 30.0
    root = np.stack([0.3 * np.sin(0.7 * time), 0.2 * np.cos(0.5 * time), 0.1 * time], axis=1)
    rv = np.stack([0.5 * np.sin(0.3 * time), 0.4 * np.cos(0.2 * time), 0.3 * time], axis=1)
    R = Rotation.from_rotvec(rv).as_matrix()
    return np.einsum("tij,nj->tni", R, shape) + root[:, None, :]


def random_sim():
    return (rng.uniform(0.7, 1.4), Rotation.random(random_state=int(rng.integers(1 << 30))).as_matrix(),
            rng.normal(size=3))


def main(out):
    T = 250
    gt_w = hand_track(T)
    s, R, t = random_sim()
    drift = np.cumsum(rng.normal(size=(T, 1, 3)) * 0.002, axis=0)
    est_w = s * np.einsum("ij,tnj->tni", R, gt_w) + t + drift + rng.normal(size=(T, 21, 3)) * 0.005
    # camera-space joints: another rigid frame per frame, noise for the estimate
    Rc = Rotation.random(T, random_state=3).as_matrix()
    gt_c = np.einsum("tij,tnj->tni", Rc, gt_w) + rng.normal(size=(T, 1, 3))
    sc, Rr, tc = random_sim()
    est_c = sc * np.einsum("ij,tnj->tni", Rr, gt_c) + tc + rng.normal(size=(T, 21, 3)) * 0.006

    valid = np.ones(T, dtype=bool)
    valid[0] = False
    valid[30:45] = False
    valid[101:180] = False
    valid[240] = False

    res = {}
    for tag, v in (("all", None), ("mask", valid)):
        res["pa_" + tag] = M.pa_mpjpe(gt_c, est_c, v)
        res["auc_" + tag] = M.auc(gt_c, est_c, v)
        res["w_" + tag] = M.w_mpjpe(gt_w, est_w, v)
        res["wa_" + tag] = M.wa_mpjpe(gt_w, est_w, v)
        res["rte_" + tag] = M.rte(gt_w, est_w, v)
        res["accel_" + tag] = M.accel(gt_w, est_w, v, fps=30.0)
    res["accel_fps60"] = M.accel(gt_w, est_w, None, fps=60.0)
    pa_err = M.pa_errors(gt_c, est_c, valid)

    # cameras
    cams = {}
    for tag, Tc in (("c250", 250), ("c201", 201)):
        time = np.arange(Tc) / 30.0
        gp = np.stack([np.sin(0.4 * time), 0.3 * np.cos(0.9 * time), 0.2 * time], axis=1)
        s2, R2, t2 = random_sim()
        ep = (np.einsum("ij,tj->ti", R2, gp) + t2) / s2 + rng.normal(size=(Tc, 3)) * 0.01
        a, scale = M.ate(gp, ep)
        Rs, ts = M.camera_part_alignment(gp, ep, part=100)
        pts = rng.normal(size=(Tc, 21, 3))
        cams[tag + "_gt"] = gp
        cams[tag + "_est"] = ep
        cams[tag + "_ate"] = a
        cams[tag + "_scale"] = scale
        cams[tag + "_ate_s"] = M.ate_s(gp, ep)
        cams[tag + "_pts"] = pts.reshape(Tc, 63)
        cams[tag + "_pts_aligned"] = M.apply_part_alignment(Rs, ts, pts).reshape(Tc, 63)
        # Camera-to-world rotations: a smooth head turn, the estimate in a randomly rotated world
        # with a per-frame error of a few degrees (and one frame 150 deg off, an outlier).
        gR = Rotation.from_rotvec(np.stack([0.3 * np.sin(time), 1.2 * np.sin(0.5 * time), 0.1 * time], 1))
        noise = Rotation.from_rotvec(rng.normal(size=(Tc, 3)) * 0.04)
        eR = Rotation.random(random_state=int(rng.integers(1 << 30))) * gR * noise
        eR_m = eR.as_matrix()
        eR_m[7] = eR_m[7] @ Rotation.from_rotvec([0.0, np.radians(150.0), 0.0]).as_matrix()
        mean_deg, max_deg, A = M.rotation_errors(gR.as_matrix(), eR_m)
        cams[tag + "_gR"] = gR.as_matrix().reshape(Tc, 9)
        cams[tag + "_eR"] = eR_m.reshape(Tc, 9)
        cams[tag + "_rot_mean"] = mean_deg
        cams[tag + "_rot_max"] = max_deg
        cams[tag + "_rot_align"] = A.reshape(1, 9)

    refio.save(out, gt_w=gt_w.reshape(T, 63), est_w=est_w.reshape(T, 63),
               gt_c=gt_c.reshape(T, 63), est_c=est_c.reshape(T, 63), valid=valid.astype(float),
               pa_err_mask=pa_err, **res, **cams)


if __name__ == "__main__":
    main(sys.argv[1])
