#!/usr/bin/python3
"""The metric-scale benchmark of issue 5 on the synthetic presets.

For every preset (sequences and SLAM outputs of examples/bench_slam.py, made here when missing):
  depth-based   the ground-truth depth maps of the keyframes, corrupted like a depth network's
                output: a global bias per keyframe uniform in +-10 %, 5 % multiplicative noise,
                10 % of the pixels replaced by uniform outliers in [0.1, 5] m, and the hands left
                in (the masks drop them); `hawor scale --metric-depth ... --baseline` gives AdaSM
                and the plain median ("w/o AdaSM").
  hand-anchored no depth at all: `hawor scale --hands` on the ground-truth camera-frame wrists
                with 1 cm noise per axis (a fitted hand's error), only where the hand is valid.
Scale error: |alpha / alpha_true - 1| with alpha_true the Sim(3) scale of the SLAM trajectory onto
the ground truth. ATE-S: the mean error of the scaled trajectory after a rigid (SE(3)) alignment,
next to the Sim(3) ATE (DESIGN section 8).

  bench_scale.py [--presets a,b] [--work DIR] [--hawor PATH] [--seed N] [--json OUT]
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_colmap as bc  # noqa: E402


def run(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise RuntimeError("command failed (%d): %s\n%s" % (p.returncode, " ".join(cmd), p.stderr[-2000:]))
    return p.stdout


def rigid_ate(est, gt):
    """Mean error after the best rotation + translation (no scale)."""
    me, mg = est.mean(0), gt.mean(0)
    u, _, vt = np.linalg.svd((gt - mg).T @ (est - me))
    d = np.eye(3)
    if np.linalg.det(u @ vt) < 0:
        d[2, 2] = -1
    r = u @ d @ vt
    return float(np.linalg.norm((r @ (est - me).T).T + mg - gt, axis=1).mean())


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--presets", default="walk,table_work,fast_turns,pure_rotation,hands_cover")
    ap.add_argument("--work", default="/tmp/hawor_bench_slam")
    ap.add_argument("--hawor", default=os.path.join(here, "..", "build", "native", "examples", "hawor"))
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    rng = np.random.default_rng(a.seed)
    rows, results = [], []
    for preset in a.presets.split(","):
        seq = os.path.join(a.work, "%s_s1_640x480_0" % preset)
        traj = os.path.join(seq, "slam_masked.tum")
        kd = os.path.join(seq, "kd_masked.npz")
        if not os.path.exists(traj) or not os.path.exists(kd):
            run([sys.executable, os.path.join(here, "bench_slam.py"), "--presets", preset, "--no-colmap",
                 "--work", a.work, "--hawor", a.hawor])
        _, gt, _ = bc.read_tum(os.path.join(seq, "camera_gt.tum"))
        _, est, _ = bc.read_tum(traj)
        if np.ptp(est, axis=0).max() < 1e-12:
            rows.append((preset, "no translation estimated (rotation-only SLAM output)", "", "", "", ""))
            continue
        ate = bc.ate_sim3(est, gt)
        true_scale = ate["scale"]
        path = bc.path_length(gt)
        entry = {"preset": preset, "true_scale": true_scale, "ate_m": ate["mean"], "path_m": path}
        # Corrupted metric depth at the keyframes.
        z = np.load(kd)
        ddir = os.path.join(seq, "depth_corrupt_%d" % a.seed)
        os.makedirs(ddir, exist_ok=True)
        for f in z["frames"]:
            g = np.load(os.path.join(seq, "depth", "%06d.npy" % f)).astype(np.float64)
            bias = 1 + rng.uniform(-0.1, 0.1)
            m = g * bias * (1 + 0.05 * rng.standard_normal(g.shape))
            out = rng.uniform(0, 1, g.shape) < 0.1
            m[out] = rng.uniform(0.1, 5.0, out.sum())
            m[~np.isfinite(g)] = np.inf
            np.save(os.path.join(ddir, "%06d.npy" % f), m.astype(np.float32))
        k = open(os.path.join(seq, "intrinsics.txt")).read().split()
        for method in ("depth", "hands"):
            outp = os.path.join(seq, "metric_%s.tum" % method)
            cmd = [a.hawor, "scale", "--traj", traj, "--keyframe-depths", kd, "--out", outp]
            if method == "depth":
                cmd += ["--metric-depth", ddir, "--masks", os.path.join(seq, "mask"), "--baseline"]
            else:
                h = np.load(os.path.join(seq, "hands_gt.npz"))
                noisy = {}
                for side in ("left_", "right_"):
                    j = h[side + "joints_cam"].copy()
                    j += 0.01 * rng.standard_normal(j.shape)
                    noisy[side + "joints_cam"] = j
                    noisy[side + "valid"] = h[side + "valid"]
                hp = os.path.join(seq, "hands_cam_noisy.npz")
                np.savez(hp, **noisy)
                cmd += ["--hands", hp]
            try:
                r = json.loads(run(cmd))
            except RuntimeError as e:
                entry[method] = {"error": str(e)}
                rows.append((preset, method, float("nan"), float("nan"), float("nan"), str(e).splitlines()[0][:60]))
                continue
            _, m, _ = bc.read_tum(outp)
            err = abs(r["scale"] / true_scale - 1)
            ate_s = rigid_ate(m, gt)
            r.update({"scale_error": err, "ate_s_m": ate_s})
            entry[method] = r
            extra = ""
            if method == "depth" and "median_scale" in r:
                r["median_scale_error"] = abs(r["median_scale"] / true_scale - 1)
                med = np.array(est) * r["median_scale"]
                r["median_ate_s_m"] = rigid_ate(med, gt)
                extra = "plain median: error %.2f %%, ATE-S %.4f m" % (100 * r["median_scale_error"], r["median_ate_s_m"])
            rows.append((preset, method, 100 * err, ate_s, ate["mean"], "conf %.2f %s" % (r["confidence"], extra)))
        results.append(entry)
    print("%-14s %-7s %12s %10s %10s  %s" % ("preset", "method", "scale err %", "ATE-S[m]", "ATE[m]", "notes"))
    for r in rows:
        if r[2] == "":
            print("%-14s %s" % (r[0], r[1]))
        else:
            print("%-14s %-7s %12.2f %10.4f %10.4f  %s" % r)
    dep = [e["depth"] for e in results if "depth" in e and "scale_error" in e["depth"]]
    if dep:
        print("depth-based: median scale error %.2f %% (AdaSM) vs %.2f %% (plain median); ATE-S/ATE median %.2f"
              % (100 * np.median([d["scale_error"] for d in dep]),
                 100 * np.median([d.get("median_scale_error", np.nan) for d in dep]),
                 np.median([e["depth"]["ate_s_m"] / e["ate_m"] for e in results if "depth" in e and "ate_s_m" in e["depth"]])))
    hands = [e for e in results if "hands" in e and "scale_error" in e["hands"] and e["path_m"] >= 0.5]
    if hands:
        print("hand-anchored: median scale error %.2f %% over presets with >= 0.5 m of camera path (%s)"
              % (100 * np.median([e["hands"]["scale_error"] for e in hands]), ",".join(e["preset"] for e in hands)))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(results, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
