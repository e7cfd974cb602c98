"""`hawor slam --camera` and `hawor fit --camera`: lenses end to end.

SLAM: a short `hawor synth --capture aria` sequence (walk, seed 2, 50 frames at 320 x 240, the
Aria-like 150-degree fisheye) and its pinhole twin (the same preset, seed and capture settings
with `--lens pinhole` and the field of view of the pinhole camera with the fisheye's intrinsics,
the virtual camera the SLAM runs in). Through the true fisheye model the ATE must stay within 1.2x
the twin's (plus 0.1 % of the path), and through the wrong (pinhole) model it must be clearly
worse: camera rotation errors of several degrees where the right model has a fraction of one.
`--camera pinhole` gives the same bytes as no --camera. Masks from disk are in the raw image.
Fit: a synthetic MANO hand 0.3-0.6 m away and up to 50 degrees off the axis, its keypoints
projected through the fisheye by OpenCV (cv2.fisheye.projectPoints, an independent reference) plus
1 px noise; `--camera fisheye:...` must fit it as accurately as the pinhole test does, the wrong
model must not; a keypoint beyond the lens' domain is left out and counted.
Bad --camera strings (unknown model, wrong count, not a number, NaN, a lens folding inside the
image) exit 2 with a message naming the problem.
Run: /usr/bin/python3 test_lens_cli.py path/to/hawor
"""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "ref"))
import hand_forward as hf  # noqa: E402
import hand_make_mano as hm  # noqa: E402
import metrics_np as M  # noqa: E402

import cliutil  # noqa: E402  (tests/cli: check, finish)
from cliutil import check  # noqa: E402

HAWOR = os.path.abspath(sys.argv[1])
FISHEYE = "fisheye:-0.0036,0.0368,-0.0343,0.0052"


def run(*args):
    p = subprocess.run([HAWOR, *args], capture_output=True, text=True, timeout=600)
    return p.returncode, p.stdout, p.stderr


def intrinsics(seq):
    lines = open(os.path.join(seq, "intrinsics.txt")).read().splitlines()
    v = lines[0].split()
    lens = lines[1].split()[1] if len(lines) > 1 and lines[1].startswith("lens ") else "pinhole"
    return [float(x) for x in v[:4]], int(v[4]), int(v[5]), lens


def slam(seq, camera, out):
    k, w, h, _ = intrinsics(seq)
    args = ["slam", "--images", os.path.join(seq, "rgb"), "--masks", os.path.join(seq, "mask"),
            "--intrinsics", ",".join("%.17g" % x for x in k), "--out", out]
    if camera is not None:
        args += ["--camera", camera]
    rc, so, se = run(*args)
    check("slam %s %s rc" % (os.path.basename(seq), camera), rc == 0, se)
    if rc != 0:
        return None, None
    rc, mo, me = run("metrics", "camera", "--gt", os.path.join(seq, "camera_gt.tum"), "--est", out)
    check("metrics rc", rc == 0, me)
    return json.loads(so), json.loads(mo) if rc == 0 else None


def slam_cases(tmp):
    fish = os.path.join(tmp, "fish")
    common = ["synth", "--preset", "walk", "--seed", "2", "--frames", "50", "--size", "320x240", "--capture", "aria",
              "--model", "synthetic"]
    rc, so, se = run(*common, "--out", fish)
    check("synth aria", rc == 0, se)
    if rc != 0:
        return
    k, w, h, lens = intrinsics(fish)
    check("aria lens line", lens == FISHEYE, lens)
    # The twin: a pinhole with the fisheye's focal (the SLAM's virtual camera), same capture.
    fov = 2 * math.degrees(math.atan(0.5 * math.hypot(w, h) / k[0]))
    twin = os.path.join(tmp, "twin")
    rc, so, se = run(*common, "--lens", "pinhole", "--fov", "%.9f" % fov, "--out", twin)
    check("synth twin", rc == 0, se)
    if rc != 0:
        return
    kt = intrinsics(twin)[0]
    check("twin focal", abs(kt[0] - k[0]) < 1e-6 * k[0], (kt, k))
    gt = np.loadtxt(os.path.join(fish, "camera_gt.tum"))
    check("same camera path", np.array_equal(gt, np.loadtxt(os.path.join(twin, "camera_gt.tum"))))
    path = np.linalg.norm(np.diff(gt[:, 1:4], axis=0), axis=1).sum()

    s_right, m_right = slam(fish, FISHEYE, os.path.join(tmp, "fish_right.tum"))
    s_wrong, m_wrong = slam(fish, "pinhole", os.path.join(tmp, "fish_wrong.tum"))
    s_twin, m_twin = slam(twin, None, os.path.join(tmp, "twin.tum"))
    if not (m_right and m_wrong and m_twin):
        return
    print("ATE mm: fisheye model %.2f (rot %.2f deg), pinhole twin %.2f (rot %.2f deg), wrong pinhole model %.2f "
          "(rot %.2f deg); path %.3f m" % (1e3 * m_right["ate"], m_right["rot_mean_deg"], 1e3 * m_twin["ate"],
                                           m_twin["rot_mean_deg"], 1e3 * m_wrong["ate"], m_wrong["rot_mean_deg"], path))
    check("summary names the lens", s_right["camera"] == FISHEYE and s_right["rectified_outside"] == 0 and
          s_wrong["camera"] == "pinhole", s_right)
    check("all frames tracked", s_right["tracked"] == 50 and s_right["initialised"], s_right)
    check("fisheye ATE within 1.2x the pinhole twin's", m_right["ate"] <= 1.2 * m_twin["ate"] + 1e-3 * path,
          (m_right["ate"], m_twin["ate"], path))
    check("fisheye rotation as good as the twin's", m_right["rot_mean_deg"] <= 1.5 * m_twin["rot_mean_deg"] + 0.2,
          (m_right["rot_mean_deg"], m_twin["rot_mean_deg"]))
    check("the wrong model is clearly worse", m_wrong["ate"] >= 1.5 * m_right["ate"] and
          m_wrong["rot_mean_deg"] >= 5 and m_wrong["rot_mean_deg"] >= 10 * m_right["rot_mean_deg"],
          (m_wrong, m_right))

    # A pinhole lens is an exact no-op: the same bytes as without --camera.
    a, b = os.path.join(tmp, "a.tum"), os.path.join(tmp, "b.tum")
    ka = ",".join("%.17g" % x for x in kt)
    base = ["slam", "--images", os.path.join(twin, "rgb"), "--masks", os.path.join(twin, "mask"), "--intrinsics", ka,
            "--max-frames", "20"]
    r1 = run(*base, "--out", a)
    r2 = run(*base, "--out", b, "--camera", "pinhole")
    r3 = run(*base, "--out", b + "2", "--camera", "opencv:0,0,0,0")
    check("pinhole runs", r1[0] == 0 and r2[0] == 0 and r3[0] == 0, r1[2] + r2[2] + r3[2])
    if r1[0] == 0 and r2[0] == 0 and r3[0] == 0:
        check("--camera pinhole = no --camera, byte for byte",
              open(a, "rb").read() == open(b, "rb").read() == open(b + "2", "rb").read())

    # Bad --camera strings: exit 2, the problem named.
    kf = ",".join("%.17g" % x for x in k)
    for cam, needle in (("bogus:1,2", "unknown lens model"), ("fisheye:0.1,0.2", "takes 4 coefficients"),
                        ("fisheye:0.1,x,0,0", "is not a number"), ("fisheye:nan,0,0,0", "not finite"),
                        ("opencv:-0.6,0.05,0,0", "folds"), ("pinhole:1", "no coefficients")):
        rc, so, se = run("slam", "--images", os.path.join(fish, "rgb"), "--intrinsics", kf, "--camera", cam,
                         "--out", os.path.join(tmp, "bad.tum"))
        check("slam --camera %s exits 2" % cam, rc == 2 and needle in se and "--camera" in se, (rc, se))
    rc, so, se = run("slam", "--help")
    check("slam help names --camera", rc == 0 and "--camera LENS" in so and "fisheye:k1,k2,k3,k4" in so, so)


def fisheye_project(p, K, D):
    import cv2
    pts, _ = cv2.fisheye.projectPoints(p.reshape(-1, 1, 3).astype(np.float64), np.zeros((3, 1)), np.zeros((3, 1)),
                                       K, D)
    return pts.reshape(p.shape[:-1] + (2,))


def fit_cases(tmp):
    try:
        import cv2  # noqa: F401
    except ImportError:
        print("SKIP fit --camera: no python3-opencv (the reference projection)")
        return
    rng = np.random.default_rng(5)
    right, _, _ = hm.write_all(tmp)
    pkl = os.path.join(tmp, "MANO_RIGHT.pkl")
    FX, CX, CY = 300.0, 319.5, 239.5
    K = np.array([[FX, 0, CX], [0, FX, CY], [0, 0, 1]])
    D = np.array([-0.0036, 0.0368, -0.0343, 0.0052])
    T = 8
    kp = np.zeros((T, 21, 3))
    for t in range(T):
        pose = rng.normal(0, 0.15, (16, 3))
        pose[0] = rng.normal(0, 1.0, 3)
        betas = rng.normal(0, 0.5, hm.B)
        # the wrist 0.3-0.6 m away, 35-50 degrees off the axis
        ang, az, dist = math.radians(rng.uniform(35, 50)), rng.uniform(0, 2 * math.pi), rng.uniform(0.3, 0.6)
        wrist = dist * np.array([math.sin(ang) * math.cos(az), math.sin(ang) * math.sin(az), math.cos(ang)])
        k0 = hf.mano_forward(right, pose, betas, np.zeros(3))[2][0]
        kp[t] = hf.mano_forward(right, pose, betas, wrist - k0)[2]
    kp2d = fisheye_project(kp, K, D) + rng.normal(0, 1.0, (T, 21, 2))
    kp3d = kp - kp[:, :1] + rng.normal(0, 0.003, kp.shape)
    conf = np.ones((T, 21))
    obs = os.path.join(tmp, "obs_fish.npz")
    np.savez(obs, keypoints2d=kp2d, keypoints3d=kp3d, confidence2d=conf)
    intr = "%g,%g,%g,%g" % (FX, FX, CX, CY)

    def fit(name, *extra, obs_path=obs):
        out = os.path.join(tmp, name + ".npz")
        rc, so, se = run("fit", "--model", pkl, "--obs", obs_path, "--intrinsics", intr, "--out", out, *extra)
        check("fit %s rc" % name, rc == 0, se)
        return (json.loads(so), np.load(out)) if rc == 0 else (None, None)

    def errors(res):
        est = res["joints_cam"]
        pa = np.median([M.pa_mpjpe(kp[t:t + 1], est[t:t + 1]) for t in range(T)])
        root = np.median(np.linalg.norm(est[:, 0] - kp[:, 0], axis=1))
        return pa, root

    # The twin: the same hands seen by the pinhole camera with the same intrinsics, the same noise.
    twin = os.path.join(tmp, "obs_twin.npz")
    kp2t = np.stack([FX * kp[..., 0] / kp[..., 2] + CX, FX * kp[..., 1] / kp[..., 2] + CY], -1)
    np.savez(twin, keypoints2d=kp2t + (kp2d - fisheye_project(kp, K, D)), keypoints3d=kp3d, confidence2d=conf)
    s, res = fit("fish", "--camera", FISHEYE, "--cold")
    s_w, res_w = fit("fish_wrong", "--cold")
    s_t, res_t = fit("twin", "--cold", obs_path=twin)
    if res is None or res_w is None or res_t is None:
        return
    pa, root = errors(res)
    pa_w, root_w = errors(res_w)
    pa_t, root_t = errors(res_t)
    print("fit through the fisheye: PA-MPJPE %.2f mm, root %.1f mm (pinhole twin: %.2f mm, %.1f mm; wrong pinhole "
          "model: %.2f mm, %.1f mm)" % (pa, 1e3 * root, pa_t, 1e3 * root_t, pa_w, 1e3 * root_w))
    check("fit summary", s["camera"] == FISHEYE and s["fitted"] == T and s["keypoints_outside_lens"] == 0, s)
    check("fit through the fisheye as good as the pinhole twin", pa < 1.3 * pa_t + 0.5 and root < 1.5 * root_t + 0.005,
          (pa, pa_t, root, root_t))
    check("the wrong model fits worse", root_w > 3 * root and root_w > 0.05, (root_w, root))
    # A keypoint beyond what the lens reaches is left out, the frame still fitted.
    kp_bad = kp2d.copy()
    kp_bad[3, 20] = [1e6, 1e6]
    bad = os.path.join(tmp, "obs_bad.npz")
    np.savez(bad, keypoints2d=kp_bad, keypoints3d=kp3d)
    s_b, res_b = fit("fish_bad", "--camera", FISHEYE, obs_path=bad)
    if res_b is not None:
        check("outside keypoint counted, frame fitted", s_b["keypoints_outside_lens"] == 1 and s_b["fitted"] == T, s_b)
    for cam, needle in (("fisheye:1,2,3", "takes 4 coefficients"), ("opencv:inf,0,0,0", "not finite"),
                        ("wide", "unknown lens model")):
        rc, so, se = run("fit", "--model", pkl, "--obs", obs, "--intrinsics", intr, "--out", os.path.join(tmp, "x.npz"),
                         "--camera", cam)
        check("fit --camera %s exits 2" % cam, rc == 2 and needle in se and "--camera" in se, (rc, se))


def main():
    tmp = tempfile.mkdtemp(prefix="hawor_lens_cli_")
    try:
        slam_cases(tmp)
        fit_cases(tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    sys.exit(cliutil.finish())


if __name__ == "__main__":
    main()
