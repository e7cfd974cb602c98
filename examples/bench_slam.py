#!/usr/bin/python3
"""The SLAM benchmark table, from files on disk, with COLMAP beside it.

For every preset: `hawor synth` writes the sequence (640x480 by default; reused when the folder
exists), `hawor slam` runs on it with the hand masks and without (--no-mask), and COLMAP
(examples/bench_colmap.py: sequential matching, intrinsics fixed) runs on the same frames. One
table: ATE (docs/design.md §8: mean error after Sim(3) alignment; RMSE beside it) in metres and in %
of the ground-truth path, ms per frame (median and p95 of the SLAM's per-frame time; COLMAP: its
total wall time / frames), keyframes, losses and frame statuses; then the target ratios:
masked / unmasked ATE over the presets where the hands cover >= 30 % of the image on >= 10 % of
the frames, ours / COLMAP ATE and COLMAP / ours time.

  bench_slam.py [--presets a,b] [--frames N] [--seed N] [--size WxH] [--work DIR]
                [--hawor PATH] [--no-colmap] [--colmap-frames N] [--json OUT]
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_colmap as bc  # noqa: E402  (numpy Sim(3), TUM reader, COLMAP runner)


def run(cmd):
    t = time.time()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise RuntimeError("command failed (%d): %s\n%s" % (p.returncode, " ".join(cmd), p.stderr[-2000:]))
    return p.stdout, time.time() - t


def pinhole_intrinsics(seq):
    """The first line of intrinsics.txt as strings (fx fy cx cy width height fps); the sequence
    must have no lens ('lens' line other than pinhole): hawor slam and scale take pinhole
    intrinsics."""
    fx, fy, cx, cy, w, h, fps, lens = bc.read_intrinsics(os.path.join(seq, "intrinsics.txt"))
    if lens != "pinhole":
        raise RuntimeError("%s: lens %s, but hawor slam takes pinhole intrinsics (synthesise without a lens)" % (seq, lens))
    return open(os.path.join(seq, "intrinsics.txt")).readline().split()


def hand_coverage(seq):
    """Per-frame fraction of the image covered by hand pixels, from hands_gt.npz."""
    z = np.load(os.path.join(seq, "hands_gt.npz"))
    w, h = bc.read_intrinsics(os.path.join(seq, "intrinsics.txt"))[4:6]
    return (z["left_visible_pixels"].astype(np.float64) + z["right_visible_pixels"]) / (w * h)


def ate(est_tum, gt_centres):
    _, c, _ = bc.read_tum(est_tum)
    if c.shape[0] != gt_centres.shape[0]:
        raise RuntimeError("%s has %d poses, ground truth %d" % (est_tum, c.shape[0], gt_centres.shape[0]))
    if np.ptp(c, axis=0).max() < 1e-12:
        # Rotation-only output (no map was ever built): the best Sim(3) fit collapses every
        # position onto the ground-truth centroid (scale 0).
        e = np.linalg.norm(gt_centres - gt_centres.mean(0), axis=1)
        return {"mean": float(e.mean()), "rmse": float(np.sqrt((e * e).mean()))}
    return bc.ate_sim3(c, gt_centres)


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--presets", default="walk,table_work,fast_turns,pure_rotation,hands_cover")
    ap.add_argument("--frames", type=int, default=0, help="frames per preset (0: the preset's length)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--work", default="/tmp/hawor_bench_slam")
    ap.add_argument("--hawor", default=os.path.join(here, "..", "build", "native", "examples", "hawor"))
    ap.add_argument("--no-colmap", action="store_true")
    ap.add_argument("--colmap-frames", type=int, default=100, help="COLMAP on the first N frames (0: all)")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    if not os.path.exists(a.hawor):
        print("bench_slam: hawor binary not found at %s (build it first)" % a.hawor, file=sys.stderr)
        return 2
    os.makedirs(a.work, exist_ok=True)
    rows, results = [], []
    for preset in a.presets.split(","):
        seq = os.path.join(a.work, "%s_s%d_%s_%d" % (preset, a.seed, a.size, a.frames))
        if not os.path.exists(os.path.join(seq, "camera_gt.tum")):
            cmd = [a.hawor, "synth", "--preset", preset, "--seed", str(a.seed), "--size", a.size, "--out", seq]
            if a.frames:
                cmd += ["--frames", str(a.frames)]
            run(cmd)
        _, gt, _ = bc.read_tum(os.path.join(seq, "camera_gt.tum"))
        path = bc.path_length(gt)
        k = pinhole_intrinsics(seq)
        cov = hand_coverage(seq)
        entry = {"preset": preset, "frames": int(gt.shape[0]), "path_m": path,
                 "hand_cover30_fraction": float((cov >= 0.3).mean()), "max_hand_cover": float(cov.max())}
        for mode in ("masked", "unmasked"):
            out = os.path.join(seq, "slam_%s.tum" % mode)
            cmd = [a.hawor, "slam", "--images", os.path.join(seq, "rgb"), "--masks", os.path.join(seq, "mask"),
                   "--intrinsics", ",".join(k[:4]), "--out", out, "--fps", k[6],
                   "--keyframe-depths", os.path.join(seq, "kd_%s.npz" % mode)]
            if mode == "unmasked":
                cmd.append("--no-mask")
            stdout, wall = run(cmd)
            s = json.loads(stdout)
            e = ate(out, gt)
            s.update({"ate_m": e["mean"], "ate_rmse_m": e["rmse"], "ate_pct": 100 * e["mean"] / path, "wall_s": wall})
            entry[mode] = s
            rows.append((preset, "ours " + mode, gt.shape[0], e["mean"], e["rmse"], 100 * e["mean"] / path,
                         s["median_ms_per_frame"], s["p95_ms_per_frame"], s["keyframes"], s["losses"],
                         "%d/%d/%d/%d" % (s["tracked"], s["interpolated"], s["lost"], s["relocalised"])))
        if not a.no_colmap:
            # COLMAP's incremental mapper grows superlinearly: it runs on the first N frames
            # (--colmap-frames), and ours is re-run on exactly those frames for the ratios.
            n = min(a.colmap_frames or gt.shape[0], gt.shape[0])
            cmd = [sys.executable, os.path.join(here, "bench_colmap.py"), seq, "--frames", str(n)]
            try:
                stdout, _ = run(cmd)
                c = json.loads(stdout.strip().splitlines()[-1])
                entry["colmap"] = c
                cpath = bc.path_length(gt[:n])
                cmean = c.get("ate_all_mean_m", c["ate_all_m"])
                rows.append((preset, "COLMAP %d fr" % n, n, cmean, c["ate_all_m"], 100 * cmean / cpath,
                             c["ms_per_frame"], float("nan"), c["registered"], n - c["registered"], "-"))
                out = os.path.join(seq, "slam_first%d.tum" % n)
                stdout, wall = run([a.hawor, "slam", "--images", os.path.join(seq, "rgb"), "--masks",
                                 os.path.join(seq, "mask"), "--intrinsics", ",".join(k[:4]), "--out", out,
                                 "--fps", k[6], "--max-frames", str(n)])
                s = json.loads(stdout)
                e = ate(out, gt[:n])
                s.update({"ate_m": e["mean"], "ate_rmse_m": e["rmse"], "ate_pct": 100 * e["mean"] / cpath,
                          "wall_ms_per_frame": 1000.0 * wall / n})
                entry["ours_colmap_frames"] = s
                rows.append((preset, "ours %d fr" % n, n, e["mean"], e["rmse"], 100 * e["mean"] / cpath,
                             s["median_ms_per_frame"], s["p95_ms_per_frame"], s["keyframes"], s["losses"],
                             "%d/%d/%d/%d" % (s["tracked"], s["interpolated"], s["lost"], s["relocalised"])))
            except (RuntimeError, ValueError, KeyError) as err:
                entry["colmap_error"] = str(err)
                rows.append((preset, "COLMAP failed", 0, float("nan"), float("nan"), float("nan"), float("nan"),
                             float("nan"), 0, 0, str(err).splitlines()[0][:40]))
        results.append(entry)
        print("done %s" % preset, file=sys.stderr)

    print("%-14s %-15s %6s %9s %9s %7s %8s %8s %5s %5s %s" % ("preset", "method", "frames", "ATE[m]", "RMSE[m]",
          "ATE[%]", "ms_med", "ms_p95", "KF", "loss", "trk/int/lost/reloc"))
    for r in rows:
        print("%-14s %-15s %6d %9.4f %9.4f %7.3f %8.2f %8.2f %5d %5d %s" % r)
    covered = [e for e in results if e["hand_cover30_fraction"] >= 0.1]
    if covered:
        ratios = [e["masked"]["ate_m"] / max(e["unmasked"]["ate_m"], 1e-12) for e in covered]
        print("masked/unmasked ATE, mean over presets with hands >= 30%% of the image on >= 10%% of frames (%s): %.3f"
              % (",".join(e["preset"] for e in covered), float(np.mean(ratios))))
    with_c = [e for e in results if "ours_colmap_frames" in e]
    if with_c:
        r = [e["ours_colmap_frames"]["ate_m"] / max(e["colmap"].get("ate_all_mean_m", e["colmap"]["ate_all_m"]), 1e-12)
             for e in with_c]
        # Time: COLMAP's wall time against our whole CLI run (PNG decoding and finish() included).
        sp = [e["colmap"]["ms_per_frame"] / max(e["ours_colmap_frames"]["wall_ms_per_frame"], 1e-9) for e in with_c]
        print("ours(masked)/COLMAP ATE per preset: %s; COLMAP/ours wall time: %s"
              % (", ".join("%s %.2f" % (e["preset"], x) for e, x in zip(with_c, r)),
                 ", ".join("%.0fx" % x for x in sp)))
    print("ATE <= 1%% of the path on every preset (masked): %s"
          % all(e["masked"]["ate_pct"] <= 1.0 for e in results))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(results, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
