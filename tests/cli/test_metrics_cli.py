"""`hawor metrics camera|hands` against the independent numpy metrics (tests/ref/metrics_np.py).

Random ground truth and estimates (several sizes, partial 100-frame chunks, invalid frames,
np.savez and np.savez_compressed, jittered TUM timestamps); the JSON must agree to
1e-9 relative. Also: usage and bad-input errors exit non-zero with a message on stderr.
Run: /usr/bin/python3 test_metrics_cli.py path/to/hawor
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "ref"))
import metrics_np as M  # noqa: E402

import cliutil  # noqa: E402  (tests/cli: check, finish)
from cliutil import check  # noqa: E402

HAWOR = sys.argv[1]
RTOL = 1e-9


def run(*args):
    p = subprocess.run([HAWOR, *args], capture_output=True, text=True, timeout=120)
    return p.returncode, p.stdout, p.stderr


def close(a, b):
    if a is None or b is None or not np.isfinite(b):
        return a is None and (b is None or not np.isfinite(b))
    return abs(a - b) <= RTOL * max(abs(b), 1e-300) or abs(a - b) <= 1e-12


def write_tum(path, t, pos, quat_xyzw, order=None):
    idx = np.arange(len(t)) if order is None else order
    with open(path, "w") as f:
        f.write("# timestamp tx ty tz qx qy qz qw\n")
        for i in idx:
            f.write(" ".join("%.17g" % v for v in [t[i], *pos[i], *quat_xyzw[i]]) + "\n")


def random_traj(rng, T):
    steps = rng.normal(scale=0.02, size=(T, 3)) + np.array([0.0, 0.0, 0.01])
    pos = np.cumsum(steps, axis=0)
    rot = Rotation.from_rotvec(np.cumsum(rng.normal(scale=0.02, size=(T, 3)), axis=0))
    return pos, rot


def camera_case(rng, tmp, T, name):
    t = np.arange(T) / 30.0
    pos, rot = random_traj(rng, T)
    # Estimate: a random similarity of the truth plus noise, written in shuffled line order with
    # sub-millisecond timestamp jitter (matching is by timestamp).
    R = Rotation.random(random_state=rng.integers(1 << 31))
    s = rng.uniform(0.3, 3.0)
    est = s * R.apply(pos) + rng.normal(size=3) + rng.normal(scale=0.01, size=(T, 3))
    est_rot = R * rot * Rotation.from_rotvec(rng.normal(scale=0.03, size=(T, 3)))
    gt_path, est_path = os.path.join(tmp, name + "_gt.tum"), os.path.join(tmp, name + "_est.tum")
    write_tum(gt_path, t, pos, rot.as_quat())
    write_tum(est_path, t + rng.uniform(-4e-4, 4e-4, T), est, est_rot.as_quat())
    rc, out, err = run("metrics", "camera", "--gt", gt_path, "--est", est_path)
    check(name + " rc", rc == 0, err)
    if rc != 0:
        return
    j = json.loads(out)
    ate_mm, scale = M.ate(pos, est)
    rot_mean, rot_max, _ = M.rotation_errors(rot.as_matrix(), est_rot.as_matrix())
    ref = {"ate": ate_mm / 1000.0, "ate_s": M.ate_s(pos, est) / 1000.0, "scale": scale, "n": T,
           "rot_mean_deg": rot_mean, "rot_max_deg": rot_max}
    for k, v in ref.items():
        check("%s %s" % (name, k), close(j[k], v), "hawor %r numpy %r" % (j[k], v))


def hands_case(rng, tmp, T, name, compressed, with_valid):
    gt_cam = rng.normal(scale=0.05, size=(T, 21, 3)) + np.array([0.0, 0.1, 0.4])
    gt_world = np.cumsum(rng.normal(scale=0.01, size=(T, 1, 3)), axis=0) + gt_cam
    est_cam = gt_cam + rng.normal(scale=0.01, size=gt_cam.shape)
    est_world = gt_world + rng.normal(scale=0.02, size=gt_world.shape) + 0.1
    save = np.savez_compressed if compressed else np.savez
    gt_path, est_path = os.path.join(tmp, name + "_gt.npz"), os.path.join(tmp, name + "_est.npz")
    valid = None
    if with_valid:
        valid = rng.uniform(size=T) > 0.2
        est_valid = rng.uniform(size=T) > 0.1
        save(gt_path, joints_world=gt_world, joints_cam=gt_cam, valid=valid)
        save(est_path, joints_world=est_world.astype(np.float32), joints_cam=est_cam, valid=est_valid.astype(np.uint8))
        valid = valid & est_valid
    else:
        save(gt_path, joints_world=gt_world, joints_cam=gt_cam)
        save(est_path, joints_world=est_world.astype(np.float32), joints_cam=est_cam)
    est_world = est_world.astype(np.float32).astype(np.float64)
    rc, out, err = run("metrics", "hands", "--gt", gt_path, "--est", est_path, "--fps", "30")
    check(name + " rc", rc == 0, err)
    if rc != 0:
        return
    j = json.loads(out)
    ref = {"pa_mpjpe": M.pa_mpjpe(gt_cam, est_cam, valid), "auc": M.auc(gt_cam, est_cam, valid),
           "w_mpjpe": M.w_mpjpe(gt_world, est_world, valid),
           "wa_mpjpe": M.wa_mpjpe(gt_world, est_world, valid),
           "rte": M.rte(gt_world, est_world, valid), "accel": M.accel(gt_world, est_world, valid, 30.0),
           "n": int(T if valid is None else valid.sum())}
    for k, v in ref.items():
        check("%s %s" % (name, k), close(j[k], v), "hawor %r numpy %r" % (j[k], v))


def error_cases(tmp):
    rc, out, err = run("metrics", "camera", "--help")
    check("camera --help", rc == 0 and "usage" in out)
    rc, out, err = run("metrics", "hands", "--help")
    check("hands --help", rc == 0 and "usage" in out)
    rc, out, err = run("metrics", "camera", "--gt", os.path.join(tmp, "missing.tum"), "--est", "x")
    check("missing file", rc != 0 and "missing.tum" in err, err)
    rc, out, err = run("metrics", "camera", "--gt", "a")
    check("missing option", rc == 2 and "--est" in err, err)
    rc, out, err = run("metrics", "volume")
    check("unknown kind", rc == 2 and "volume" in err, err)
    bad = os.path.join(tmp, "bad.tum")
    with open(bad, "w") as f:
        f.write("0 1 2 3 0 0 0 1\n0.1 1 2 nan 0 0 0 1\n")
    rc, out, err = run("metrics", "camera", "--gt", bad, "--est", bad)
    check("nan in tum", rc != 0 and "bad.tum" in err, err)
    np.savez(os.path.join(tmp, "shape.npz"), joints_world=np.zeros((5, 21, 2)), joints_cam=np.zeros((5, 21, 3)))
    rc, out, err = run("metrics", "hands", "--gt", os.path.join(tmp, "shape.npz"), "--est", os.path.join(tmp, "shape.npz"))
    check("wrong shape", rc != 0 and "joints_world" in err, err)
    with open(os.path.join(tmp, "junk.npz"), "wb") as f:
        f.write(b"PK\x03\x04 definitely not a zip archive")
    rc, out, err = run("metrics", "hands", "--gt", os.path.join(tmp, "junk.npz"), "--est", os.path.join(tmp, "junk.npz"))
    check("corrupt npz", rc != 0 and "junk.npz" in err, err)


def main():
    rng = np.random.default_rng(20261122)
    with tempfile.TemporaryDirectory() as tmp:
        for i, T in enumerate([3, 17, 250, 1234]):
            camera_case(rng, tmp, T, "camera%d" % i)
        for i, T in enumerate([5, 100, 257]):
            hands_case(rng, tmp, T, "hands%d" % i, compressed=bool(i % 2), with_valid=i > 0)
        error_cases(tmp)
    sys.exit(cliutil.finish())


main()
