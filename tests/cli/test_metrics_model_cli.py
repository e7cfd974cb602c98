"""`hawor metrics hands --model`: files holding hand parameters instead of joints give the same
numbers as files holding the joints that the independent numpy forward pass
(tests/ref/hand_forward.py) computes from those parameters (synthetic MANO model of
tests/ref/hand_make_mano.py): world parameters, camera parameters (cam_rot / cam_trans) or none
(camera joints = world joints), hand_pose as (T,45) or (T,15,3), shared or per-frame betas, invalid
frames holding NaN; files with joints keep their exact numbers with and without --model; missing
or inconsistent parameters exit non-zero with a message.
Run: /usr/bin/python3 test_metrics_model_cli.py path/to/hawor
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.spatial.transform import Rotation

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "ref"))
import hand_forward as hf  # noqa: E402
import hand_make_mano as hm  # noqa: E402

import cliutil  # noqa: E402  (tests/cli: check, finish)
from cliutil import check  # noqa: E402

HAWOR = os.path.abspath(sys.argv[1])
KEYS = ("pa_mpjpe", "auc", "w_mpjpe", "wa_mpjpe", "rte", "accel", "n")


def run(*args):
    p = subprocess.run([HAWOR, *args], capture_output=True, text=True, timeout=120)
    return p.returncode, p.stdout, p.stderr


def metrics(name, gt, est, *extra):
    rc, so, se = run("metrics", "hands", "--gt", gt, "--est", est, *extra)
    check(name + " rc", rc == 0, se)
    return json.loads(so) if rc == 0 else None


def same(name, a, b, rtol):
    if a is None or b is None:
        return
    for k in KEYS:
        x, y = a[k], b[k]
        ok = (x is None and y is None) or (x is not None and y is not None and abs(x - y) <= rtol * max(abs(y), 1e-12))
        check("%s %s" % (name, k), ok, (x, y))


def sequence(rng, T):
    """Smooth world-frame parameters and a moving camera."""
    pose = rng.normal(0, 0.3, (1, 16, 3)) + 0.1 * np.sin(0.1 * np.arange(T)[:, None, None] + rng.uniform(0, 6, (16, 3)))
    trans = np.cumsum(rng.normal(0, 0.01, (T, 3)), axis=0) + [0.1, 0.2, 0.5]
    cam_R = Rotation.from_rotvec(np.cumsum(rng.normal(0, 0.02, (T, 3)), axis=0) + rng.normal(0, 1, 3))
    cam_t = np.cumsum(rng.normal(0, 0.01, (T, 3)), axis=0)
    return pose, trans, cam_R, cam_t


def joints(model, pose, betas, trans, valid=None):
    T = len(pose)
    b = np.broadcast_to(betas, (T, hm.B))
    out = np.full((T, 21, 3), np.nan)
    for t in range(T):
        if valid is None or valid[t]:
            out[t] = hf.mano_forward(model, pose[t], b[t], trans[t])[2]
    return out


def camera_params(model, pose, betas, trans, cam_R, cam_t):
    """The same hand in a camera frame X_c = R X_w + t: cam_rot = R∘rot; cam_trans such that the
    posed hand moves rigidly (MANO rotates about joint 0: X = R0 (x - J0) + J0 + trans)."""
    T = len(pose)
    rot_c = (cam_R * Rotation.from_rotvec(pose[:, 0])).as_rotvec()
    trans_c = np.zeros((T, 3))
    b = np.broadcast_to(betas, (T, hm.B))
    for t in range(T):
        j0 = hf.mano_forward(model, np.zeros((16, 3)), b[t], np.zeros(3))[1][0]
        trans_c[t] = cam_R[t].apply(j0 + trans[t]) + cam_t[t] - j0
    return rot_c, trans_c


def main():
    rng = np.random.default_rng(515)
    with tempfile.TemporaryDirectory() as tmp:
        right, _, _ = hm.write_all(tmp)
        pkl = os.path.join(tmp, "MANO_RIGHT.pkl")
        T = 120
        P = lambda n: os.path.join(tmp, n + ".npz")  # noqa: E731

        # Ground truth and an estimate, each as parameters and as joints.
        gt_pose, gt_trans, cam_R, cam_t = sequence(rng, T)
        gt_betas = rng.normal(0, 1, hm.B)
        est_pose = gt_pose + rng.normal(0, 0.05, gt_pose.shape)
        est_trans = gt_trans + rng.normal(0, 0.01, gt_trans.shape)
        est_betas = np.tile(gt_betas + rng.normal(0, 0.2, hm.B), (T, 1))
        gt_cr, gt_ct = camera_params(right, gt_pose, gt_betas, gt_trans, cam_R, cam_t)
        est_cr, est_ct = camera_params(right, est_pose, est_betas, est_trans, cam_R, cam_t)

        gt_w = joints(right, gt_pose, gt_betas, gt_trans)
        gt_c = joints(right, np.concatenate([gt_cr[:, None], gt_pose[:, 1:]], 1), gt_betas, gt_ct)
        # The camera parameters really are the rigidly moved hand.
        moved = np.einsum("tab,tjb->tja", cam_R.as_matrix(), gt_w) + cam_t[:, None]
        check("camera parameters", np.abs(moved - gt_c).max() < 1e-12, np.abs(moved - gt_c).max())
        est_w = joints(right, est_pose, est_betas, est_trans)
        est_c = joints(right, np.concatenate([est_cr[:, None], est_pose[:, 1:]], 1), est_betas, est_ct)

        np.savez(P("gt_j"), joints_world=gt_w, joints_cam=gt_c)
        np.savez(P("est_j"), joints_world=est_w, joints_cam=est_c)
        np.savez(P("gt_p"), rot=gt_pose[:, 0], hand_pose=gt_pose[:, 1:].reshape(T, 45), betas=gt_betas, trans=gt_trans,
                 cam_rot=gt_cr, cam_trans=gt_ct)
        np.savez_compressed(P("est_p"), global_orient=est_pose[:, 0], hand_pose=est_pose[:, 1:], betas=est_betas,
                            transl=est_trans, cam_rot=est_cr, cam_trans=est_ct)
        ref = metrics("joints", P("gt_j"), P("est_j"))
        same("joints with --model", metrics("joints+model", P("gt_j"), P("est_j"), "--model", pkl), ref, 0.0)
        same("params", metrics("params", P("gt_p"), P("est_p"), "--model", pkl), ref, 1e-9)
        same("gt params, est joints", metrics("mixed1", P("gt_p"), P("est_j"), "--model", pkl), ref, 1e-9)
        same("gt joints, est params", metrics("mixed2", P("gt_j"), P("est_p"), "--model", pkl), ref, 1e-9)
        # joints_cam given, joints_world from parameters.
        np.savez(P("est_half"), joints_cam=est_c, rot=est_pose[:, 0], hand_pose=est_pose[:, 1:].reshape(T, 45),
                 betas=est_betas, trans=est_trans)
        same("half", metrics("half", P("gt_j"), P("est_half"), "--model", pkl), ref, 1e-9)

        # No camera parameters: camera joints = world joints.
        np.savez(P("gt_w_only"), rot=gt_pose[:, 0], hand_pose=gt_pose[:, 1:].reshape(T, 45), betas=gt_betas, trans=gt_trans)
        np.savez(P("est_w_only"), rot=est_pose[:, 0], hand_pose=est_pose[:, 1:].reshape(T, 45), trans=est_trans)
        est_w0 = joints(right, est_pose, np.zeros(hm.B), est_trans)  # no betas: zeros
        np.savez(P("gt_jw"), joints_world=gt_w, joints_cam=gt_w)
        np.savez(P("est_jw"), joints_world=est_w0, joints_cam=est_w0)
        ref2 = metrics("world joints", P("gt_jw"), P("est_jw"))
        same("world params", metrics("world params", P("gt_w_only"), P("est_w_only"), "--model", pkl), ref2, 1e-9)

        # Invalid frames hold NaN parameters; only the file's own valid frames are posed.
        valid = rng.uniform(size=T) > 0.2
        bad_pose = est_pose.copy()
        bad_pose[~valid] = np.nan
        np.savez(P("est_nan"), rot=bad_pose[:, 0], hand_pose=bad_pose[:, 1:].reshape(T, 45), betas=est_betas,
                 trans=np.where(valid[:, None], est_trans, np.nan), cam_rot=np.where(valid[:, None], est_cr, np.nan),
                 cam_trans=est_ct, valid=valid.astype(np.uint8))
        np.savez(P("est_nan_j"), joints_world=np.where(valid[:, None, None], est_w, np.nan),
                 joints_cam=np.where(valid[:, None, None], est_c, np.nan), valid=valid)
        ref3 = metrics("nan joints", P("gt_j"), P("est_nan_j"))
        same("nan params", metrics("nan params", P("gt_j"), P("est_nan"), "--model", pkl), ref3, 1e-9)
        check("nan n", ref3 is not None and ref3["n"] == valid.sum(), ref3)

        # Errors.
        def expect(name, gt, est, extra, code, needle):
            rc, so, se = run("metrics", "hands", "--gt", gt, "--est", est, *extra)
            check(name, rc == code and needle in se and so == "", (rc, se))

        expect("params without --model", P("gt_p"), P("est_j"), (), 1, "--model")
        np.savez(P("no_pose"), rot=gt_pose[:, 0], trans=gt_trans)
        expect("incomplete params", P("no_pose"), P("est_j"), ("--model", pkl), 1, "hand_pose")
        np.savez(P("half_cam"), joints_world=gt_w, rot=gt_pose[:, 0], hand_pose=gt_pose[:, 1:].reshape(T, 45),
                 trans=gt_trans, cam_rot=gt_cr)
        expect("cam_rot alone", P("half_cam"), P("est_j"), ("--model", pkl), 1, "cam_trans")
        bad = est_pose.copy()
        bad[7, 3, 1] = np.nan
        np.savez(P("nan_valid"), rot=bad[:, 0], hand_pose=bad[:, 1:].reshape(T, 45), trans=est_trans)
        expect("nan at a valid frame", P("gt_j"), P("nan_valid"), ("--model", pkl), 1, "frame 7")
        np.savez(P("short"), rot=gt_pose[:50, 0], hand_pose=gt_pose[:, 1:].reshape(T, 45), trans=gt_trans)
        expect("frame counts", P("short"), P("est_j"), ("--model", pkl), 1, "frames")
        np.savez(P("pose44"), rot=gt_pose[:, 0], hand_pose=np.zeros((T, 44)), trans=gt_trans)
        expect("hand_pose shape", P("pose44"), P("est_j"), ("--model", pkl), 1, "hand_pose")
        np.savez(P("betas11"), rot=gt_pose[:, 0], hand_pose=gt_pose[:, 1:], trans=gt_trans, betas=np.zeros((T, 11)))
        expect("too many betas", P("betas11"), P("est_j"), ("--model", pkl), 1, "betas")
        expect("bad model", P("gt_p"), P("est_j"), ("--model", P("gt_j")), 1, "gt_j.npz")
        expect("bad side", P("gt_j"), P("est_j"), ("--side", "middle"), 2, "--side")
        rc, so, se = run("metrics", "hands", "--help")
        check("help", rc == 0 and "cam_rot" in so and "hand_pose" in so and "--model" in so, so)
    sys.exit(cliutil.finish())


if __name__ == "__main__":
    main()
