"""`hawor hand`: the OBJ of a posed model equals the independent numpy forward pass
(tests/ref/hand_forward.py) on synthetic MANO files (tests/ref/hand_make_mano.py) to 1e-9, for .pkl
and .npz, right and left (left faces wound [0,2,1]), single-frame and per-frame pose files; the
model format is recognised from the content whatever the extension; the default hand is found
(when node_modules holds it) and its meshes face outwards; bad models, bad pose files and usage
errors exit non-zero with a message naming the problem.
Run: /usr/bin/python3 test_hand_cli.py path/to/hawor
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(HERE, "..", "ref"))
import gltf_make  # noqa: E402
import hand_forward as hf  # noqa: E402
import hand_make_mano as hm  # noqa: E402

import cliutil  # noqa: E402  (tests/cli: check, finish)
from cliutil import check  # noqa: E402

HAWOR = os.path.abspath(sys.argv[1])
ASSETS = os.path.join(ROOT, "node_modules", "@webxr-input-profiles", "assets", "dist", "profiles", "generic-hand")
TOL = 1e-9


def run(*args, cwd=None, env=None):
    e = dict(os.environ)
    e.pop("HAWOR_HAND_DIR", None)
    if env:
        e.update(env)
    p = subprocess.run([HAWOR, *args], capture_output=True, text=True, timeout=120, cwd=cwd, env=e)
    return p.returncode, p.stdout, p.stderr


def read_obj(path):
    v, f = [], []
    with open(path) as fh:
        for line in fh:
            if line.startswith("v "):
                v.append([float(x) for x in line.split()[1:]])
            elif line.startswith("f "):
                f.append([int(x) for x in line.split()[1:]])
    return np.array(v), np.array(f, dtype=np.int64)


def hand(tmp, model, *extra, name="mesh", **kw):
    """Runs `hawor hand`; returns (summary, vertices, faces) or None."""
    out = os.path.join(tmp, name + ".obj")
    rc, so, se = run("hand", "--model", model, "--out", out, *extra, **kw)
    check("hand %s %s rc" % (os.path.basename(model), " ".join(extra)), rc == 0, se)
    if rc != 0:
        return None
    v, f = read_obj(out)
    return json.loads(so), v, f


def random_pose(rng):
    pose = rng.normal(0, 0.5, (16, 3))
    return pose, rng.normal(0, 1.0, hm.B), rng.normal(0, 0.3, 3)


def outward(v, f):
    """Signed volume of the mesh (positive when the faces wind counter-clockwise seen from outside);
    f holds the OBJ's 1-based indices."""
    a, b, c = v[f[:, 0] - 1], v[f[:, 1] - 1], v[f[:, 2] - 1]
    return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0


def mano_cases(tmp, rng):
    right, left, _ = hm.write_all(tmp)
    for side, model in (("right", right), ("left", left)):
        faces = model["f"].astype(np.int64)
        if side == "left":
            faces = faces[:, [0, 2, 1]]
        pkl = os.path.join(tmp, "MANO_%s.pkl" % side.upper())
        npz = os.path.join(tmp, "mano_%s.npz" % side)
        # Rest pose (no --pose): the template.
        r = hand(tmp, pkl)
        if r:
            s, v, f = r
            check(side + " rest vertices", np.abs(v - model["v_template"]).max() < TOL)
            check(side + " rest faces", np.array_equal(f, faces + 1))
            check(side + " summary", s["kind"] == "mano-pkl" and s["side"] == side and s["vertices"] == hm.V and
                  s["faces"] == hm.F and s["joints"] == hm.J and len(s["keypoints"]) == 21, s)
        for i in range(3):
            pose, betas, transl = random_pose(rng)
            verts, joints, kp = hf.mano_forward(model, pose, betas, transl)
            posefile = os.path.join(tmp, "pose_%s_%d.npz" % (side, i))
            if i == 0:
                np.savez(posefile, global_orient=pose[0], hand_pose=pose[1:], betas=betas, transl=transl)
            elif i == 1:
                np.savez(posefile, rot=pose[0], hand_pose=pose[1:].reshape(-1), betas=betas[:6], trans=transl)
                betas = betas.copy()
                betas[6:] = 0
                verts, joints, kp = hf.mano_forward(model, pose, betas, transl)
            else:
                np.savez_compressed(posefile, hand_pose=pose[1:].astype(np.float32))  # rest: zeros
                pose = pose.copy()
                pose[0] = 0
                pose[1:] = pose[1:].astype(np.float32)
                betas, transl = np.zeros(hm.B), np.zeros(3)
                verts, joints, kp = hf.mano_forward(model, pose, betas, transl)
            for path, kind in ((pkl, "mano-pkl"), (npz, "mano-npz")):
                r = hand(tmp, path, "--pose", posefile)
                if not r:
                    continue
                s, v, f = r
                name = "%s %s pose %d" % (side, kind, i)
                check(name + " kind", s["kind"] == kind, s)
                check(name + " vertices", v.shape == verts.shape and np.abs(v - verts).max() < TOL,
                      np.abs(v - verts).max() if v.shape == verts.shape else v.shape)
                check(name + " faces", np.array_equal(f, faces + 1))
                check(name + " keypoints", np.abs(np.array(s["keypoints"]) - kp).max() < TOL)

    # Per-frame pose arrays (a `hawor fit` output's layout) with --frame; betas shared.
    T = 4
    poses = rng.normal(0, 0.4, (T, 16, 3))
    trans = rng.normal(0, 0.2, (T, 3))
    betas = rng.normal(0, 1, hm.B)
    seq = os.path.join(tmp, "seq.npz")
    np.savez(seq, rot=poses[:, 0], hand_pose=poses[:, 1:].reshape(T, 45), betas=betas, trans=trans)
    seq3 = os.path.join(tmp, "seq3.npz")
    np.savez(seq3, rot=poses[:, 0], hand_pose=poses[:, 1:], betas=np.tile(betas, (T, 1)), trans=trans)
    for path in (seq, seq3):
        for t in (0, 2, 3):
            r = hand(tmp, os.path.join(tmp, "MANO_RIGHT.pkl"), "--pose", path, "--frame", str(t))
            if r:
                verts = hf.mano_forward(right, poses[t], betas, trans[t])[0]
                check("frame %d of %s" % (t, os.path.basename(path)), np.abs(r[1] - verts).max() < TOL)
                check("frame %d summary" % t, r[0]["frame"] == t)

    # Content, not extension: a pickle and an npz under misleading names.
    odd = os.path.join(tmp, "right_model.glb")
    shutil.copy(os.path.join(tmp, "MANO_RIGHT.pkl"), odd)
    r = hand(tmp, odd)
    check("pkl named .glb", r is not None and r[0]["kind"] == "mano-pkl", r and r[0])
    odd = os.path.join(tmp, "weights.pkl")
    shutil.copy(os.path.join(tmp, "mano_left.npz"), odd)
    rc, so, se = run("hand", "--model", odd, "--out", os.path.join(tmp, "x.obj"))
    check("no side in name", rc == 1 and "weights.pkl" in se and "--side" in se, se)
    r = hand(tmp, odd, "--side", "left")
    check("npz named .pkl", r is not None and r[0]["kind"] == "mano-npz" and r[0]["side"] == "left", r and r[0])
    if r:
        check("npz named .pkl faces", np.array_equal(r[2], left["f"].astype(np.int64)[:, [0, 2, 1]] + 1))
    for p in (0, 4):  # other pickle protocols
        r = hand(tmp, os.path.join(tmp, "MANO_RIGHT_p%d.pkl" % p))
        check("protocol %d" % p, r is not None and np.abs(r[1] - right["v_template"]).max() < TOL)
    return right


def glb_cases(tmp, rng):
    """Skinned .glb directly and converted to a hawor model .npz: the same mesh."""
    glb = os.path.join(tmp, "synthetic.glb")
    gltf_make.make(0, glb, rng)
    conv = os.path.join(tmp, "synthetic_model.npz")
    rc, so, se = run("convert-hand", "--glb", glb, "--side", "left", "--out", conv)
    check("convert synthetic", rc == 0, se)
    z = np.load(conv)
    J = len(z["parents"])
    pose = os.path.join(tmp, "glb_pose.npz")
    np.savez(pose, global_orient=rng.normal(0, 0.5, 3), hand_pose=rng.normal(0, 0.4, (J - 1, 3)),
             transl=rng.normal(0, 0.1, 3))
    a = hand(tmp, glb, "--side", "left", "--pose", pose, name="a")
    b = hand(tmp, conv, "--pose", pose, name="b")
    if a and b:
        check("glb kind", a[0]["kind"] == "glb" and b[0]["kind"] == "hawor-npz", (a[0], b[0]))
        check("glb == converted", np.abs(a[1] - b[1]).max() < 1e-12 and np.array_equal(a[2], b[2]))
        check("glb faces", np.array_equal(a[2], z["f"] + 1))
        check("no keypoints", a[0]["keypoints"] == [], a[0])
    rc, so, se = run("hand", "--model", conv, "--side", "right", "--out", os.path.join(tmp, "x.obj"))
    check("side contradicts model", rc == 1 and "left" in se and "synthetic_model.npz" in se, se)
    rc, so, se = run("hand", "--model", glb, "--out", os.path.join(tmp, "x.obj"))
    check("glb without side", rc == 1 and "synthetic.glb" in se and "--side" in se, se)
    return glb


def default_cases(tmp):
    present = all(os.path.exists(os.path.join(ASSETS, s + ".glb")) for s in ("left", "right"))
    if not present:
        print("note: %s not found (run scripts/install.sh): default-hand checks skipped" % ASSETS)
    else:
        for side in ("right", "left"):
            # From the repository root: the build's models/ or ./node_modules.
            r = hand(tmp, "default", "--side", side, cwd=ROOT)
            if r:
                s, v, f = r
                check("default %s summary" % side, s["side"] == side and s["vertices"] == 1360 and s["faces"] == 2314 and
                      len(s["keypoints"]) == 21 and s["kind"] in ("hawor-npz", "glb"), s)
                check("default %s faces outwards" % side, outward(v, f) > 0, outward(v, f))
            # Through HAWOR_HAND_DIR, first in the search order: the npm .glb itself.
            r2 = hand(tmp, "default", "--side", side, env={"HAWOR_HAND_DIR": ASSETS})
            if r2:
                check("HAWOR_HAND_DIR %s" % side, r2[0]["kind"] == "glb" and r2[0]["model"].endswith(side + ".glb"), r2[0])
                if r:
                    check("default %s same mesh" % side, np.abs(r[1] - r2[1]).max() < 1e-12)
        r = hand(tmp, "default", cwd=ROOT)
        check("default is right", r is not None and r[0]["side"] == "right", r and r[0])
    # No default anywhere: a copy of the binary in an empty folder, run from there.
    lone = os.path.join(tmp, "lone", "bin")
    os.makedirs(lone)
    shutil.copy(HAWOR, os.path.join(lone, "hawor"))
    p = subprocess.run([os.path.join(lone, "hawor"), "hand", "--model", "default", "--out", "x.obj"],
                       capture_output=True, text=True, cwd=lone, timeout=60,
                       env={k: v for k, v in os.environ.items() if k != "HAWOR_HAND_DIR"})
    check("no default hand", p.returncode == 1 and "install.sh" in p.stderr and "--model" in p.stderr, p.stderr)


def error_cases(tmp, glb):
    pkl = os.path.join(tmp, "MANO_RIGHT.pkl")
    out = os.path.join(tmp, "err.obj")

    def expect(name, args, code, needle):
        rc, so, se = run("hand", *args)
        check(name, rc == code and needle in se and so == "", (rc, se))

    raw = open(pkl, "rb").read()
    files = {"truncated_right.pkl": raw[: len(raw) // 3], "empty_right.pkl": b"",
             "random_right.pkl": np.random.default_rng(1).bytes(5000),
             "trunc_right.npz": open(os.path.join(tmp, "mano_right.npz"), "rb").read()[:3000],
             "trunc_right.glb": open(glb, "rb").read()[:200],
             "array_right.npy": None, "text_right.gltf": b'{"asset": {"version": "2.0"}}',
             "other_right.npz": None}
    for name, data in files.items():
        path = os.path.join(tmp, name)
        if name == "array_right.npy":
            np.save(path, np.zeros(3))
        elif name == "other_right.npz":
            np.savez(path, a=np.zeros(3), b=np.ones(2))
        else:
            with open(path, "wb") as f:
                f.write(data)
        expect("bad model " + name, ("--model", path, "--out", out), 1, name)
    rc, so, se = run("hand", "--model", os.path.join(tmp, "array_right.npy"), "--out", out)
    check("npy message", "npy" in se, se)
    rc, so, se = run("hand", "--model", os.path.join(tmp, "other_right.npz"), "--out", out)
    check("npz keys message", "'a.npy'" in se or "a.npy" in se, se)
    expect("missing model", ("--model", os.path.join(tmp, "nope.pkl"), "--out", out), 1, "nope.pkl")

    bad = {
        "nan": dict(global_orient=np.array([0.1, np.nan, 0.0])),
        "nan_frame": dict(hand_pose=np.where(np.arange(3 * 45).reshape(3, 45) == 50, np.nan, 0.0)),
        "short_pose": dict(hand_pose=np.zeros((14, 3))),
        "orient4": dict(global_orient=np.zeros(4)),
        "betas11": dict(betas=np.zeros(11)),
        "transl2d": dict(transl=np.zeros((2, 2))),
        "frames": dict(rot=np.zeros((3, 3)), trans=np.zeros((4, 3))),
        "both": dict(rot=np.zeros(3), global_orient=np.zeros(3)),
        "strings": dict(betas=np.array(["a", "b"])),
        "no_keys": dict(pose=np.zeros(48)),
    }
    needles = {"nan": "global_orient", "nan_frame": "frame 1", "short_pose": "hand_pose", "orient4": "global_orient",
               "betas11": "betas", "transl2d": "transl", "frames": "frames", "both": "global_orient", "strings": "betas",
               "no_keys": "holds none"}
    for name, arrays in bad.items():
        path = os.path.join(tmp, "bad_%s.npz" % name)
        np.savez(path, **arrays)
        args = ["--model", pkl, "--pose", path, "--out", out]
        if name == "nan_frame":
            args += ["--frame", "1"]
        expect("bad pose " + name, args, 1, needles[name])
    seq = os.path.join(tmp, "seq.npz")
    expect("frame out of range", ("--model", pkl, "--pose", seq, "--frame", "4", "--out", out), 1, "out of range")
    single = os.path.join(tmp, "pose_right_0.npz")
    expect("frame of single", ("--model", pkl, "--pose", single, "--frame", "1", "--out", out), 1, "single frame")
    expect("missing pose file", ("--model", pkl, "--pose", os.path.join(tmp, "nope.npz"), "--out", out), 1, "nope.npz")
    expect("unwritable out", ("--model", pkl, "--out", os.path.join(tmp, "no", "dir", "x.obj")), 1, "x.obj")
    # Usage errors.
    expect("no model", ("--out", out), 2, "--model")
    expect("no out", ("--model", pkl), 2, "--out")
    expect("bad side", ("--model", pkl, "--side", "up", "--out", out), 2, "--side")
    expect("bad frame", ("--model", pkl, "--pose", seq, "--frame", "-1", "--out", out), 2, "--frame")
    expect("frame without pose", ("--model", pkl, "--frame", "2", "--out", out), 2, "--frame")
    expect("unknown option", ("--model", pkl, "--out", out, "--bogus"), 2, "--bogus")
    rc, so, se = run("hand", "--help")
    check("help", rc == 0 and "hand_pose" in so and "global_orient" in so, so)


def main():
    rng = np.random.default_rng(31)
    with tempfile.TemporaryDirectory() as tmp:
        mano_cases(tmp, rng)
        glb = glb_cases(tmp, rng)
        default_cases(tmp)
        error_cases(tmp, glb)
    sys.exit(cliutil.finish())


if __name__ == "__main__":
    main()
