"""`hawor fit`: observations synthesised with the independent numpy forward pass
(tests/ref/hand_forward.py) of a synthetic MANO model (tests/ref/hand_make_mano.py): a smooth
sequence of plausible poses (small joint angles, random global orientation, random shape), wrist
0.3-0.8 m in front of the camera, keypoints projected with the intrinsics plus 1 px noise, 3D
landmarks with an arbitrary origin plus 3 mm noise. The fit must reach PA-MPJPE < 5 mm and a root
(wrist) error < 2 cm (medians), its FIT.npz must be self-consistent (joints_cam = the numpy forward
pass of its parameters), frames with valid = 0 or unusable observations must be skipped and the
next frame cold-started, `metrics hands --model` must read the output, and bad inputs must exit
non-zero with a message. With node_modules present the default hand is fitted too (its truth from
`hawor hand`, itself checked against numpy in test_hand_cli.py).
Run: /usr/bin/python3 test_fit_cli.py path/to/hawor
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.spatial.transform import Rotation

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(HERE, "..", "ref"))
import gltf_make  # noqa: E402
import hand_forward as hf  # noqa: E402
import hand_make_mano as hm  # noqa: E402
import metrics_np as M  # noqa: E402

import cliutil  # noqa: E402  (tests/cli: check, finish)
from cliutil import check  # noqa: E402

HAWOR = os.path.abspath(sys.argv[1])
ASSETS = os.path.join(ROOT, "node_modules", "@webxr-input-profiles", "assets", "dist", "profiles", "generic-hand")
FX, FY, CX, CY = 550.0, 540.0, 320.0, 240.0
INTR = "%g,%g,%g,%g" % (FX, FY, CX, CY)


def run(*args, cwd=None):
    env = {k: v for k, v in os.environ.items() if k != "HAWOR_HAND_DIR"}
    p = subprocess.run([HAWOR, *args], capture_output=True, text=True, timeout=300, cwd=cwd, env=env)
    return p.returncode, p.stdout, p.stderr


def project(p):
    return np.stack([FX * p[..., 0] / p[..., 2] + CX, FY * p[..., 1] / p[..., 2] + CY], axis=-1)


def trajectory(rng, T, njoints):
    """Smooth per-frame parameters: small joint angles, a random global orientation, and wrist
    targets 0.3-0.8 m deep inside the field of view."""
    base = rng.normal(0, 0.15, (njoints, 3))
    phase = rng.uniform(0, 2 * np.pi, (njoints, 3))
    t = np.arange(T)[:, None, None]
    pose = base[None] + 0.08 * np.sin(0.3 * t + phase[None])
    r0 = Rotation.random(random_state=int(rng.integers(1 << 30)))
    pose[:, 0] = (r0 * Rotation.from_rotvec(0.2 * np.sin(0.2 * np.arange(T))[:, None] * np.array([0.3, 1.0, 0.2]))).as_rotvec()
    # A hand moving at about 0.2 m/s (at 30 fps), somewhere 0.3-0.8 m deep.
    z = rng.uniform(0.3, 0.8 - 0.007 * T) + 0.007 * np.arange(T)
    xy = rng.uniform(-0.1, 0.1, 2) * z[0] / 0.5 + np.outer(np.arange(T), rng.normal(0, 0.003, 2))
    wrist = np.column_stack([xy, z])
    return pose, wrist


def observations(rng, kp):
    kp2d = project(kp) + rng.normal(0, 1.0, kp.shape[:-1] + (2,))
    kp3d = kp - kp[:, :1] + np.array([0.01, -0.02, 0.03]) + rng.normal(0, 0.003, kp.shape)
    return kp2d, kp3d


def fit(tmp, model, obs, name, *extra):
    out = os.path.join(tmp, name + "_fit.npz")
    rc, so, se = run("fit", "--model", model, "--obs", obs, "--intrinsics", INTR, "--out", out, *extra)
    check(name + " rc", rc == 0, se)
    if rc != 0:
        return None, None
    return json.loads(so), np.load(out)


def accuracy(name, kp, res, valid=None, pa_mm=5.0, root_m=0.02):
    v = np.ones(len(kp), bool) if valid is None else valid
    est = res["joints_cam"]
    pa = np.array([M.pa_mpjpe(kp[t:t + 1], est[t:t + 1]) for t in range(len(kp)) if v[t]])
    root = np.linalg.norm(est[v, 0] - kp[v, 0], axis=1)
    check(name + " PA-MPJPE", np.median(pa) < pa_mm, "median %.3f mm, max %.3f" % (np.median(pa), pa.max()))
    check(name + " root error", np.median(root) < root_m, "median %.4f m, max %.4f" % (np.median(root), root.max()))
    print("%s: PA-MPJPE median %.2f mm, root error median %.1f mm" % (name, np.median(pa), 1000 * np.median(root)))


def mano_case(tmp, rng):
    right, _, _ = hm.write_all(tmp)
    pkl = os.path.join(tmp, "MANO_RIGHT.pkl")
    T = 10
    pose, wrist = trajectory(rng, T, 16)
    betas = rng.normal(0, 0.5, hm.B)
    kp = np.zeros((T, 21, 3))
    transl = np.zeros((T, 3))
    for t in range(T):
        k0 = hf.mano_forward(right, pose[t], betas, np.zeros(3))[2][0]
        transl[t] = wrist[t] - k0
        kp[t] = hf.mano_forward(right, pose[t], betas, transl[t])[2]
    kp2d, kp3d = observations(rng, kp)
    check("truth in front of the camera", (kp[..., 2] > 0.1).all() and (np.abs(kp2d - [CX, CY]) < [2 * CX, 2 * CY]).all())

    obs = os.path.join(tmp, "obs.npz")
    np.savez(obs, keypoints2d=kp2d, keypoints3d=kp3d, confidence2d=np.ones((T, 21)), confidence3d=np.ones((T, 21)))
    s, res = fit(tmp, pkl, obs, "mano")
    if res is not None:
        check("summary", s["frames"] == T and s["fitted"] == T and s["skipped"] == 0 and s["failed"] == 0 and
              s["kind"] == "mano-pkl" and 0 < s["median_reproj_rms_px"] < 3 and s["median_ms_per_frame"] > 0, s)
        shapes = {"rot": (T, 3), "hand_pose": (T, 45), "betas": (T, hm.B), "trans": (T, 3), "joints_cam": (T, 21, 3),
                  "valid": (T,), "reproj_rms_px": (T,), "iterations": (T,)}
        check("keys", sorted(res.files) == sorted(shapes), res.files)
        check("shapes", all(res[k].shape == v for k, v in shapes.items()), {k: res[k].shape for k in res.files})
        check("dtypes", res["valid"].dtype == np.uint8 and res["iterations"].dtype == np.int32 and
              res["rot"].dtype == np.float64)
        check("valid", (res["valid"] == 1).all() and (res["iterations"] > 0).all())
        check("reprojection", np.median(res["reproj_rms_px"]) == s["median_reproj_rms_px"] or
              abs(np.median(res["reproj_rms_px"]) - s["median_reproj_rms_px"]) < 1e-12)
        # joints_cam is the forward pass of the written parameters.
        err = max(np.abs(hf.mano_forward(right, np.vstack([res["rot"][t], res["hand_pose"][t].reshape(15, 3)]),
                                         res["betas"][t], res["trans"][t])[2] - res["joints_cam"][t]).max()
                  for t in range(T))
        check("joints_cam = forward(params)", err < 1e-9, err)
        accuracy("mano 2D+3D", kp, res)
        # Cold starts everywhere: as accurate.
        s2, res2 = fit(tmp, pkl, obs, "mano_cold", "--cold")
        if res2 is not None:
            accuracy("mano cold", kp, res2)

        # metrics hands reads the FIT.npz (joints_world from its parameters, a static camera).
        gt = os.path.join(tmp, "gt.npz")
        np.savez(gt, joints_world=kp, joints_cam=kp)
        rc, so, se = run("metrics", "hands", "--gt", gt, "--est", os.path.join(tmp, "mano_fit.npz"), "--model", pkl)
        check("metrics on FIT.npz", rc == 0, se)
        if rc == 0:
            j = json.loads(so)
            ref = M.pa_mpjpe(kp, res["joints_cam"])
            check("metrics pa_mpjpe", abs(j["pa_mpjpe"] - ref) < 1e-9 * ref, (j["pa_mpjpe"], ref))
            ref = M.wa_mpjpe(kp, res["joints_cam"])
            check("metrics wa_mpjpe", abs(j["wa_mpjpe"] - ref) < 1e-6 * ref, (j["wa_mpjpe"], ref))

    # 2D keypoints only: the fit runs on every frame (depth and pose are weakly observed: its
    # accuracy is the library's business, bench_fit measures it; printed for information).
    obs2 = os.path.join(tmp, "obs2d.npz")
    np.savez(obs2, keypoints2d=kp2d)
    s, res = fit(tmp, pkl, obs2, "mano_2d")
    if res is not None:
        check("2D only fitted", s["fitted"] == T and np.isfinite(res["joints_cam"]).all(), s)
        print("mano 2D only: median reprojection RMS %.2f px" % s["median_reproj_rms_px"])

    # Skipped and unusable frames: valid = 0 (NaN there is fine), a frame with every confidence
    # 0 (fails, reported), a NaN keypoint with confidence 0 (ignored).
    kp2n, kp3n = kp2d.copy(), kp3d.copy()
    c2 = np.ones((T, 21))
    valid = np.ones(T, np.uint8)
    valid[3] = 0
    kp2n[3] = np.nan
    kp3n[3] = np.nan
    c2[6] = 0
    kp2n[8, 7] = np.nan
    c2[8, 7] = 0
    obs3 = os.path.join(tmp, "obs_valid.npz")
    np.savez(obs3, keypoints2d=kp2n, keypoints3d=kp3n, confidence2d=c2, valid=valid)
    p = subprocess.run([HAWOR, "fit", "--model", pkl, "--obs", obs3, "--intrinsics", INTR, "--out",
                        os.path.join(tmp, "v_fit.npz")], capture_output=True, text=True, timeout=300)
    check("valid rc", p.returncode == 0 and "frame 6" in p.stderr, p.stderr)
    if p.returncode == 0:
        s = json.loads(p.stdout)
        res = np.load(os.path.join(tmp, "v_fit.npz"))
        check("valid summary", s["fitted"] == T - 2 and s["skipped"] == 1 and s["failed"] == 1, s)
        expect = np.ones(T, np.uint8)
        expect[[3, 6]] = 0
        check("valid flags", np.array_equal(res["valid"], expect), res["valid"])
        check("invalid rows NaN", np.isnan(res["joints_cam"][[3, 6]]).all() and np.isnan(res["rot"][[3, 6]]).all() and
              (res["iterations"][[3, 6]] == 0).all())
        check("valid rows finite", np.isfinite(res["joints_cam"][expect == 1]).all())
        accuracy("mano with gaps", kp, res, expect == 1)
    return pkl, kp2d, kp3d


def default_case(tmp, rng):
    if not all(os.path.exists(os.path.join(ASSETS, s + ".glb")) for s in ("left", "right")):
        print("note: %s not found (run scripts/install.sh): default-hand fit skipped" % ASSETS)
        return
    T = 5
    pose, wrist = trajectory(rng, T, 25)
    pose[:, 1:] *= 0.5
    pose[:, [5, 10, 15, 20]] = 0  # the finger metacarpals (WebXR joint order) do not bend
    for side in ("left", "right"):
        kp = np.zeros((T, 21, 3))
        for t in range(T):
            pf = os.path.join(tmp, "dpose.npz")
            np.savez(pf, global_orient=pose[t, 0], hand_pose=pose[t, 1:])
            rc, so, se = run("hand", "--model", "default", "--side", side, "--pose", pf, "--out",
                             os.path.join(tmp, "d.obj"), cwd=ROOT)
            k = np.array(json.loads(so)["keypoints"]) if rc == 0 else np.zeros((21, 3))
            kp[t] = k - k[0] + wrist[t]
        kp2d, kp3d = observations(rng, kp)
        obs = os.path.join(tmp, "dobs.npz")
        np.savez(obs, keypoints2d=kp2d, keypoints3d=kp3d)
        out = os.path.join(tmp, "dfit.npz")
        rc, so, se = run("fit", "--model", "default", "--side", side, "--obs", obs, "--intrinsics", INTR, "--out", out,
                         cwd=ROOT)
        check("default %s rc" % side, rc == 0, se)
        if rc == 0:
            s = json.loads(so)
            res = np.load(out)
            check("default %s summary" % side, s["fitted"] == T and s["side"] == side and res["betas"].shape == (T, 0), s)
            accuracy("default " + side, kp, res)


def error_cases(tmp, rng, pkl, kp2d, kp3d):
    T = len(kp2d)
    out = os.path.join(tmp, "err_fit.npz")

    def expect(name, args, code, needle):
        rc, so, se = run("fit", *args)
        check(name, rc == code and needle in se and so == "", (rc, se))

    cases = {
        "k20": (dict(keypoints2d=kp2d[:, :20]), "keypoints2d"),
        "no_kp2d": (dict(keypoints3d=kp3d), "keypoints2d"),
        "nan_kp": (dict(keypoints2d=np.where(np.arange(T)[:, None, None] == 2, np.nan, kp2d)), "frame 2"),
        "conf_range": (dict(keypoints2d=kp2d, confidence2d=np.full((T, 21), 1.5)), "confidence2d"),
        "conf_shape": (dict(keypoints2d=kp2d, confidence2d=np.ones((T, 20))), "confidence2d"),
        "c3_alone": (dict(keypoints2d=kp2d, confidence3d=np.ones((T, 21))), "confidence3d"),
        "kp3_shape": (dict(keypoints2d=kp2d, keypoints3d=kp3d[:, :, :2]), "keypoints3d"),
        "nan_kp3": (dict(keypoints2d=kp2d, keypoints3d=np.where(np.arange(T)[:, None, None] == 1, np.inf, kp3d)),
                    "keypoints3d"),
        "valid_shape": (dict(keypoints2d=kp2d, valid=np.ones(T + 1)), "valid"),
        "valid_values": (dict(keypoints2d=kp2d, valid=np.full(T, 2)), "valid"),
        "all_zero": (dict(keypoints2d=kp2d, confidence2d=np.zeros((T, 21))), "no frame could be fitted"),
    }
    for name, (arrays, needle) in cases.items():
        path = os.path.join(tmp, "bad_%s.npz" % name)
        np.savez(path, **arrays)
        expect("bad obs " + name, ("--model", pkl, "--obs", path, "--intrinsics", INTR, "--out", out), 1, needle)
    good = os.path.join(tmp, "obs.npz")
    expect("missing obs", ("--model", pkl, "--obs", os.path.join(tmp, "nope.npz"), "--intrinsics", INTR, "--out", out), 1,
           "nope.npz")
    glb = os.path.join(tmp, "nokp.glb")
    gltf_make.make(0, glb, rng)
    expect("model without keypoints", ("--model", glb, "--side", "right", "--obs", good, "--intrinsics", INTR, "--out", out),
           1, "keypoints")
    expect("bad model", ("--model", good, "--obs", good, "--intrinsics", INTR, "--out", out), 1, "obs.npz")
    for intr in ("1,2,3", "a,b,c,d", "0,500,320,240", "500,500,nan,240"):
        expect("intrinsics " + intr, ("--model", pkl, "--obs", good, "--intrinsics", intr, "--out", out), 2, "--intrinsics")
    expect("no out", ("--model", pkl, "--obs", good, "--intrinsics", INTR), 2, "--out")
    expect("no intrinsics", ("--model", pkl, "--obs", good, "--out", out), 2, "--intrinsics")
    expect("no model", ("--obs", good, "--intrinsics", INTR, "--out", out), 2, "--model")
    rc, so, se = run("fit", "--help")
    check("help", rc == 0 and "keypoints2d" in so and "joints_cam" in so, so)


def main():
    rng = np.random.default_rng(77)
    with tempfile.TemporaryDirectory() as tmp:
        pkl, kp2d, kp3d = mano_case(tmp, rng)
        default_case(tmp, rng)
        error_cases(tmp, rng, pkl, kp2d, kp3d)
    sys.exit(cliutil.finish())


if __name__ == "__main__":
    main()
