"""`hawor world`: camera-frame hands from another regressor, with a regressor's error, to a metric
gravity-aligned world.

A `hawor synth` sequence (table_work, seed 2, 60 frames at 640 x 480; the ground truth in the
room's frame: z up, the floor at z = 0) and its ground-truth camera-frame hands, jittered as a
regressor's would be (examples/bench_world.py's noisy_hands: the whole hand moved per frame by
5 mm across the view and 15 mm in depth, each joint by 2.5 mm more), given as MANO parameters and
as 3D joints. The output is judged by numpy against the room after a 4-DoF alignment (a yaw and a
translation: scale and tilt must come from the method): up within 2 degrees of the truth, the
camera within 3 % of its path, the wrists within 5 cm (median), the first camera's height within
15 % of the truth. The two inputs give nearly the same world.
Bad hands files exit 1 naming the file and the key: a side given under two names, joints of the
wrong shape, non-finite joints on a frame marked valid, --hands-input joints without joints.
Run: /usr/bin/python3 test_world_cli.py path/to/hawor
"""
import os
import shutil
import subprocess
import sys
import tempfile
from types import SimpleNamespace

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "examples"))
import bench_world  # noqa: E402

import cliutil  # noqa: E402  (tests/cli: check, finish)
from cliutil import check  # noqa: E402

HAWOR = os.path.abspath(sys.argv[1])


def main():
    work = tempfile.mkdtemp(prefix="hawor-world-cli-")
    try:
        rows = {}
        for inp in ("params", "joints"):
            o = SimpleNamespace(work=work, hawor=HAWOR, frames=60, size="640x480", input=inp, hand_noise=5.0)
            r = bench_world.run_one(o, "table_work", 2)
            rows[inp] = r
            if not check(inp + ": ran", "error" not in r, r):
                continue
            print("%s: up %s %.2f deg, height %.3f m (true %.3f), camera %.2f %% of %.2f m, wrists %.1f cm, scale %s" % (
                inp, r["up"], r["up_err_deg"], r["height_est"], r["height_true"], r["camera_pct"], r["path_m"], r["wrist_cm"], r["scale"]))
            check(inp + ": up from the floor", r["up"] == "floor" and r["origin"] == "floor", r)
            check(inp + ": up within 2 deg", r["up_err_deg"] < 2.0, r)
            check(inp + ": camera within 3 % of the path", r["camera_pct"] < 3.0, r)
            check(inp + ": wrists within 5 cm", r["wrist_cm"] < 5.0, r)
            check(inp + ": first camera's height", abs(r["height_est"] - r["height_true"]) < 0.15 * r["height_true"], r)
        if "error" not in rows["params"] and "error" not in rows["joints"]:
            a = np.load(os.path.join(work, "table_work_s2", "world_params_5", "world.npz"))
            b = np.load(os.path.join(work, "table_work_s2", "world_joints_5", "world.npz"))
            d = np.linalg.norm(a["left_joints_world"][:, 0] - b["left_joints_world"][:, 0], axis=1)
            check("params and joints give nearly the same wrists", np.nanmedian(d) < 0.03, np.nanmedian(d))

        # bad hands files
        seq = os.path.join(work, "table_work_s2")
        gt = dict(np.load(os.path.join(seq, "hands_gt.npz")))
        env = dict(os.environ, HAWOR_HAND_DIR=os.path.join(os.path.dirname(os.path.dirname(HAWOR)), "models"))

        def world(name, z, extra=()):
            path = os.path.join(work, name)
            np.savez(path, **z)
            r = subprocess.run([HAWOR, "world", "--images", os.path.join(seq, "rgb"), "--hands", path, "--out", os.path.join(work, "bad"), *extra],
                               capture_output=True, text=True, env=env)
            return r.returncode, r.stderr

        z = dict(gt, left_global_orient=gt["left_cam_rot"])
        rc, err = world("twice.npz", z)
        check("a side given twice", rc == 1 and "twice.npz: both 'left_cam_rot' and 'left_global_orient' are present" in err, (rc, err))
        z = dict(gt, right_joints_cam=gt["right_joints_cam"][:, :20])
        rc, err = world("shape.npz", z, ["--hands-input", "joints"])
        check("joints of the wrong shape", rc == 1 and "shape.npz: 'right_joints_cam' has shape (60, 20, 3), expected (60, 21, 3)" in err, (rc, err))
        z = dict(gt)
        z["left_valid"] = np.ones(60, bool)
        z["left_joints_cam"] = z["left_joints_cam"].copy()
        z["left_joints_cam"][7, 3, 1] = np.nan
        rc, err = world("nan.npz", z, ["--hands-input", "joints"])
        check("non-finite joints marked valid", rc == 1 and "nan.npz: 'left_joints_cam' holds a non-finite value at frame 7" in err, (rc, err))
        z = {k: v for k, v in gt.items() if "joints_cam" not in k}
        rc, err = world("nojoints.npz", z, ["--hands-input", "joints"])
        check("joints asked for, none given", rc == 1 and "nojoints.npz: no hand joints" in err, (rc, err))
        rc, err = world("any.npz", gt, ["--hands-input", "mesh"])
        check("unknown --hands-input", rc == 2 and "--hands-input" in err, (rc, err))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return cliutil.finish()


if __name__ == "__main__":
    sys.exit(main())
