#!/usr/bin/python3
"""The metric-scale benchmark on the synthetic presets.

For every preset (sequences and SLAM outputs of examples/bench_slam.py, made here when missing),
repeated for --repeats independent draws of the corruption:
  depth-based   the ground-truth depth maps of the keyframes, corrupted like a depth network's
                output: a global bias per keyframe uniform in +-10 %, 5 % multiplicative noise,
                10 % of the pixels replaced by uniform outliers in [0.1, 5] m, and the hands left
                in (the masks drop them). `hawor scale --metric-depth ... --baseline` gives AdaSM
                with SLAM-depth sampling and the Huber estimate over keyframes (the default), the
                same with the median over keyframes, the official sampling and median, and the
                plain median ("w/o AdaSM" in the paper).
  ground        no depth and no hands: `hawor scale --intrinsics` — the keyframe depths back-
                projected to map points, the cameras' median height above the lowest horizontal
                level (the floor) against the 1.6 m eye-height prior (scale/ground_scale.hpp);
                deterministic, one run per preset. The presets' eyes are 1.55-1.7 m high.
  no-depth      hands and ground together (`--hands --intrinsics`), as the pipeline runs without
                a depth network.
  hand-anchored no depth at all: `hawor scale --hands` on the ground-truth camera-frame wrists
                with a fitted hand's errors: 2 mm white noise across the image, 1.5 % of the
                depth white noise along it plus a slowly varying depth error (1 cm, Gaussian-
                smoothed over 0.5 s), the lateral position moved along the viewing ray with the
                depth; only where the hand is valid.
Scale error: |alpha / alpha_true - 1| with alpha_true the Sim(3) scale of the SLAM trajectory onto
the ground truth (the per-preset figure is the median over the draws). ATE-S: the mean error of the
scaled trajectory after a rigid (SE(3)) alignment, next to the Sim(3) ATE (docs/design.md §8).
Presets whose camera path is under 0.1 m (pure_rotation) have no observable trajectory scale, and
a SLAM trajectory whose ATE exceeds 5 % of the path has no single scale (fast_turns): both are
listed apart; the hand-anchored figure is over presets with >= 0.5 m of camera path.

  bench_scale.py [--presets a,b] [--work DIR] [--hawor PATH] [--seed N] [--repeats N] [--json OUT]
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


def corrupt_depth(rng, seq, frames, ddir):
    os.makedirs(ddir, exist_ok=True)
    for f in frames:
        g = np.load(os.path.join(seq, "depth", "%06d.npy" % f)).astype(np.float64)
        bias = 1 + rng.uniform(-0.1, 0.1)
        m = g * bias * (1 + 0.05 * rng.standard_normal(g.shape))
        out = rng.uniform(0, 1, g.shape) < 0.1
        m[out] = rng.uniform(0.1, 5.0, out.sum())
        m[~np.isfinite(g)] = np.inf
        np.save(os.path.join(ddir, "%06d.npy" % f), m.astype(np.float32))


def smooth_noise(rng, n, sigma_frames):
    """Unit-variance Gaussian-smoothed white noise of length n."""
    k = np.exp(-0.5 * (np.arange(-3 * sigma_frames, 3 * sigma_frames + 1) / sigma_frames) ** 2)
    x = np.convolve(rng.standard_normal(n + len(k)), k / k.sum(), mode="same")[len(k) // 2:len(k) // 2 + n]
    return x / x.std()


def noisy_hands(rng, hands_gt, fps):
    out = {}
    for side in ("left_", "right_"):
        j = hands_gt[side + "joints_cam"].astype(np.float64).copy()
        T = j.shape[0]
        z = j[:, :, 2].copy()
        zn = z * (1 + 0.015 * rng.standard_normal((T, 1))) + 0.01 * smooth_noise(rng, T, 0.5 * fps)[:, None]
        j[:, :, :2] = j[:, :, :2] * (zn / z)[:, :, None] + 0.002 * rng.standard_normal((T, 1, 2))
        j[:, :, 2] = zn
        out[side + "joints_cam"] = j
        out[side + "valid"] = hands_gt[side + "valid"]
    return out


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--presets", default="walk,table_work,fast_turns,pure_rotation,hands_cover")
    ap.add_argument("--work", default="/tmp/hawor_bench_slam")
    ap.add_argument("--hawor", default=os.path.join(here, "..", "build", "native", "examples", "hawor"))
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    rng = np.random.default_rng(a.seed)
    results = []
    print("%-13s %7s %8s | %-43s | %-26s | %-27s | %s" % ("preset", "path[m]", "ATE[m]",
                                              "depth: scale err % AdaSM/kf-median/official/median, ATE-S/ATE",
                                              "hands: err %, cue, conf", "ground: err %, conf, table m",
                                              "no-depth: err %"))
    for preset in a.presets.split(","):
        seq = os.path.join(a.work, "%s_s1_640x480_0" % preset)
        traj = os.path.join(seq, "slam_masked.tum")
        kd = os.path.join(seq, "kd_masked.npz")
        if not os.path.exists(traj) or not os.path.exists(kd):
            run([sys.executable, os.path.join(here, "bench_slam.py"), "--presets", preset, "--no-colmap",
                 "--work", a.work, "--hawor", a.hawor])
        _, gt, _ = bc.read_tum(os.path.join(seq, "camera_gt.tum"))
        _, est, _ = bc.read_tum(traj)
        path = bc.path_length(gt)
        entry = {"preset": preset, "path_m": path}
        results.append(entry)
        if path < 0.1 or np.ptp(est, axis=0).max() < 1e-12:
            entry["skipped"] = "camera path %.3f m: no observable trajectory scale" % path
            print("%-13s %7.3f %8s | %s" % (preset, path, "-", entry["skipped"]))
            continue
        ate = bc.ate_sim3(est, gt)
        true_scale = ate["scale"]
        entry.update({"true_scale": true_scale, "ate_m": ate["mean"]})
        if ate["mean"] > 0.05 * path:
            entry["skipped"] = "SLAM failed (ATE %.1f %% of the path): no single trajectory scale" % (100 * ate["mean"] / path)
            print("%-13s %7.2f %8.4f | %s" % (preset, path, ate["mean"], entry["skipped"]))
            continue
        lens = bc.read_intrinsics(os.path.join(seq, "intrinsics.txt"))[7]
        if lens != "pinhole":
            raise RuntimeError("%s: lens %s, but hawor scale takes pinhole intrinsics" % (seq, lens))
        intr = open(os.path.join(seq, "intrinsics.txt")).readline().split()
        fps = float(intr[6])
        kflag = ["--intrinsics", ",".join(intr[:4])]
        outp = os.path.join(seq, "metric_ground.tum")
        try:
            j = json.loads(run([a.hawor, "scale", "--traj", traj, "--keyframe-depths", kd, "--out", outp] + kflag))
            entry["ground"] = abs(j["scale"] / true_scale - 1)
            entry["ground_conf"] = j["confidence"]
            entry["ground_surface_m"] = j.get("ground_surface_m", float("nan"))
            entry["ground_ambiguous"] = j.get("ground_ambiguous", False)
        except RuntimeError as e:
            entry["ground_error"] = str(e).splitlines()[0]
        frames = np.load(kd)["frames"]
        hands_gt = np.load(os.path.join(seq, "hands_gt.npz"))
        draws = []
        for r in range(a.repeats):
            d = {}
            ddir = os.path.join(seq, "depth_corrupt_%d_%d" % (a.seed, r))
            corrupt_depth(rng, seq, frames, ddir)
            outp = os.path.join(seq, "metric_depth.tum")
            try:
                j = json.loads(run([a.hawor, "scale", "--traj", traj, "--keyframe-depths", kd, "--out", outp,
                                    "--metric-depth", ddir, "--masks", os.path.join(seq, "mask"), "--baseline"]))
                _, m, _ = bc.read_tum(outp)
                d["depth"] = abs(j["scale"] / true_scale - 1)
                d["official"] = abs(j["official_scale"] / true_scale - 1) if "official_scale" in j else float("nan")
                d["median"] = abs(j["median_scale"] / true_scale - 1) if "median_scale" in j else float("nan")
                d["kf_median"] = (abs(j["median_combine_scale"] / true_scale - 1) if "median_combine_scale" in j
                                  else float("nan"))
                d["ate_s_ratio"] = rigid_ate(m, gt) / ate["mean"]
            except RuntimeError as e:
                d["depth_error"] = str(e).splitlines()[0]
            hp = os.path.join(seq, "hands_cam_noisy_%d.npz" % r)
            np.savez(hp, **noisy_hands(rng, hands_gt, fps))
            outp = os.path.join(seq, "metric_hands.tum")
            try:
                j = json.loads(run([a.hawor, "scale", "--traj", traj, "--out", outp, "--hands", hp]))
                d["hands"] = abs(j["scale"] / true_scale - 1)
                d["hand_cue"] = j.get("hand_cue", "")
                d["hand_conf"] = j["confidence"]
            except RuntimeError as e:
                d["hands_error"] = str(e).splitlines()[0]
            try:
                j = json.loads(run([a.hawor, "scale", "--traj", traj, "--keyframe-depths", kd, "--out", outp,
                                    "--hands", hp] + kflag))
                d["no_depth"] = abs(j["scale"] / true_scale - 1)
            except RuntimeError as e:
                d["no_depth_error"] = str(e).splitlines()[0]
            draws.append(d)
        entry["draws"] = draws

        def med(key):
            v = [d[key] for d in draws if key in d]
            return float(np.median(v)) if v else float("nan")
        for k in ("depth", "kf_median", "official", "median", "ate_s_ratio", "hands", "hand_conf", "no_depth"):
            entry[k] = med(k)
        cues = sorted(set(d.get("hand_cue", "error") for d in draws))
        entry["hand_cues"] = cues
        ground = ("%6.2f  %4.2f  %5.2f%s" % (100 * entry["ground"], entry["ground_conf"], entry["ground_surface_m"],
                                              " ambiguous" if entry["ground_ambiguous"] else "")
                  if "ground" in entry else "- (%s)" % entry.get("ground_error", "")[:40])
        print("%-13s %7.2f %8.4f | %6.2f / %6.2f / %6.2f / %6.2f   %5.2f        | %6.2f  %-10s %4.2f | %-27s | %6.2f" %
              (preset, path, ate["mean"], 100 * entry["depth"], 100 * entry["kf_median"], 100 * entry["official"],
               100 * entry["median"],
               entry["ate_s_ratio"], 100 * entry["hands"], ",".join(cues), entry["hand_conf"], ground,
               100 * entry["no_depth"]))
    dep = [e for e in results if "depth" in e and np.isfinite(e["depth"])]
    if dep:
        print("depth-based over %s: median scale error %.2f %% (AdaSM, SLAM-depth sampling, Huber over keyframes) "
              "vs %.2f %% (the same, median over keyframes) vs %.2f %% (official sampling and median) vs %.2f %% "
              "(plain median); median ATE-S/ATE %.2f"
              % (",".join(e["preset"] for e in dep), 100 * np.median([e["depth"] for e in dep]),
                 100 * np.median([e["kf_median"] for e in dep]),
                 100 * np.median([e["official"] for e in dep]), 100 * np.median([e["median"] for e in dep]),
                 np.median([e["ate_s_ratio"] for e in dep])))
    hands = [e for e in results if "hands" in e and np.isfinite(e["hands"]) and e["path_m"] >= 0.5]
    if hands:
        print("hand-anchored over %s (>= 0.5 m of camera path): median scale error %.2f %%"
              % (",".join(e["preset"] for e in hands), 100 * np.median([e["hands"] for e in hands])))
    ground = [e for e in results if "ground" in e and e["path_m"] >= 0.5]
    if ground:
        print("ground-plane over %s (>= 0.5 m of camera path): median scale error %.2f %%; hands and ground fused: %.2f %%"
              % (",".join(e["preset"] for e in ground), 100 * np.median([e["ground"] for e in ground]),
                 100 * np.median([e["no_depth"] for e in ground if np.isfinite(e.get("no_depth", float("nan")))])))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(results, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
