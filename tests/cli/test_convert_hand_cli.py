"""`hawor convert-hand`: synthetic skinned .glb files (tests/ref/gltf_make.py) and, when installed,
the WebXR generic hands (node_modules/@webxr-input-profiles/assets) become hand-model .npz files
that numpy reads with the documented keys and shapes; the JSON summary matches them; usage and
bad-input errors exit non-zero with a message on stderr.
Run: /usr/bin/python3 test_convert_hand_cli.py path/to/hawor
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "ref"))
import gltf_make  # noqa: E402

import cliutil  # noqa: E402  (tests/cli: check, finish)
from cliutil import check  # noqa: E402

HAWOR = sys.argv[1]
ASSETS = os.path.join(HERE, "..", "..", "node_modules", "@webxr-input-profiles", "assets", "dist", "profiles",
                      "generic-hand")


def run(*args):
    p = subprocess.run([HAWOR, *args], capture_output=True, text=True, timeout=120)
    return p.returncode, p.stdout, p.stderr


def convert(glb, side, out):
    rc, so, se = run("convert-hand", "--glb", glb, "--side", side, "--out", out)
    check("convert %s exit 0" % os.path.basename(glb), rc == 0, se)
    return json.loads(so) if rc == 0 else None


def check_model(name, path, summary, V, F, J, K, left):
    z = np.load(path)
    check(name + " marker", int(z["hawor_hand_model"]) == 1)
    check(name + " v_template", z["v_template"].shape == (V, 3) and z["v_template"].dtype == np.float64)
    check(name + " f", z["f"].shape == (F, 3) and z["f"].dtype == np.int32 and z["f"].min() >= 0 and z["f"].max() < V)
    check(name + " shapedirs", z["shapedirs"].shape == (V, 3, 0))
    check(name + " posedirs", z["posedirs"].shape == (V, 3, 0))
    check(name + " J_regressor", z["J_regressor"].shape == (J, V))
    check(name + " weights", z["weights"].shape == (V, J) and np.allclose(z["weights"].sum(1), 1, atol=1e-12))
    parents = z["parents"]
    check(name + " parents", parents.shape == (J,) and parents[0] == -1 and all(0 <= parents[j] < j for j in range(1, J)))
    check(name + " keypoint_map", z["keypoint_map"].shape == (K,))
    check(name + " is_left", int(z["is_left"]) == int(left))
    names = bytes(z["joint_names"]).decode().split("\n")
    check(name + " joint_names", len(names) == J, names)
    check(name + " summary", summary == {"vertices": V, "faces": F, "joints": J, "keypoints": K,
                                         "hand_length": summary["hand_length"], "side": "left" if left else "right"},
          summary)
    joints = z["J_regressor"] @ z["v_template"]
    if K == 21:
        length = np.linalg.norm(joints[z["keypoint_map"][12]] - joints[z["keypoint_map"][0]])
        check(name + " hand_length", abs(summary["hand_length"] - length) < 1e-12, (summary["hand_length"], length))
    else:
        check(name + " hand_length null", summary["hand_length"] is None)
    return z, joints, names


def main():
    with tempfile.TemporaryDirectory() as tmp:
        # Synthetic files: the converted model's arrays equal gltf_make's expectations.
        rng = np.random.default_rng(7)
        for k in range(3):
            glb = os.path.join(tmp, "s%d.glb" % k)
            exp = gltf_make.make(k, glb, rng)
            out = os.path.join(tmp, "s%d.npz" % k)
            summary = convert(glb, "left" if k == 1 else "right", out)
            if summary is None:
                continue
            J = len(exp["order"])
            z, joints, names = check_model("synthetic %d" % k, out, summary, len(exp["v_template"]), len(exp["faces"]),
                                           J, 0, k == 1)
            check("synthetic %d v_template" % k, np.array_equal(z["v_template"], exp["v_template"]))
            check("synthetic %d faces" % k, np.array_equal(z["f"], exp["faces"]))
            check("synthetic %d parents" % k, np.array_equal(z["parents"], exp["parents"]))
            check("synthetic %d weights" % k, np.abs(z["weights"] - exp["weights"]).max() < 1e-15)
            check("synthetic %d rest joints" % k, np.abs(joints - exp["rest"]).max() < 1e-14)
            check("synthetic %d names" % k, names == ["j%d" % exp["order_finger"][j] for j in range(J)], names)

        # The real WebXR hands, when installed.
        for side in ("right", "left"):
            glb = os.path.join(ASSETS, side + ".glb")
            if not os.path.exists(glb):
                print("skipped: %s not found (npm install)" % glb)
                continue
            out = os.path.join(tmp, side + ".npz")
            summary = convert(glb, side, out)
            if summary is None:
                continue
            z, joints, names = check_model(side, out, summary, 1360, 2314, 25, 21, side == "left")
            check(side + " names", names[0] == "wrist" and names[24] == "pinky-finger-tip", names)
            check(side + " length", 0.15 < summary["hand_length"] < 0.22, summary)

        # Errors: usage (2) and bad input (1), with a message.
        glb = os.path.join(tmp, "s0.glb")
        for args, code in [((), 2), (("--glb", glb, "--side", "up", "--out", "x.npz"), 2),
                           (("--glb", glb, "--out", "x.npz"), 2), (("--glb", glb, "--side", "left"), 2),
                           (("--glb", glb, "--side", "left", "--out", "x", "--bogus", "1"), 2),
                           (("--glb", os.path.join(tmp, "missing.glb"), "--side", "left", "--out", "x.npz"), 1)]:
            rc, so, se = run("convert-hand", *args)
            check("error %s" % (args,), rc == code and se.strip() != "" and so == "", (rc, se))
        bad = os.path.join(tmp, "bad.glb")
        with open(bad, "wb") as f:
            f.write(open(glb, "rb").read()[:100])
        rc, so, se = run("convert-hand", "--glb", bad, "--side", "left", "--out", os.path.join(tmp, "b.npz"))
        check("truncated glb", rc == 1 and "bad.glb" in se, se)
        rc, so, se = run("convert-hand", "--help")
        check("help", rc == 0 and "convert-hand" in so)

    sys.exit(cliutil.finish())


if __name__ == "__main__":
    main()
