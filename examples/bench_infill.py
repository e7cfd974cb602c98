#!/usr/bin/python3
"""Infiller benchmark: the paper's infiller ablation table in form, on synthetic hands.

For each preset and seed, `hawor synth` makes a sequence (only hands_gt.npz is used: world-space
MANO-style parameters and the 21 keypoints of both hands, every frame, with the frames where the
hand is visible marked valid). In each draw, gaps of 10-90 frames are cut at random into the
visible frames of each hand (inside runs of visible frames, at least 3 visible frames kept on
each side and between gaps); the cut frames and the frames where the hand was out of view are
given to `hawor infill` as missing (NaN), and each method fills them:
  last pose  repeat the last observed frame        (--method last)
  LERP       LERP / SLERP, the paper's baseline     (--method lerp)
  spline     the data-free spline infiller          (--method spline, the default)
The keypoints of the filled parameters come from the same hand model as the ground truth
(`--model default --joints`: the shipped WebXR hands, whose forward pass reproduces the
generator's joints_world exactly at observed frames; checked). Errors are measured on the CUT
frames only (the ground truth of out-of-view frames is not used), with the definitions of
docs/design.md §8 restricted to those frames:
  W-MPJPE   per 100-frame chunk, similarity (Umeyama with scale) fitted on the chunk's first two
            observed frames (all 21 joints; the world anchor), error of the chunk's cut frames, mm
  WA-MPJPE  per 100-frame chunk, similarity fitted on the chunk's cut frames, their error, mm
  RTE       root joint: rigid (SE3) alignment over the visible frames (observed + cut), error of
            the cut frames divided by the ground-truth path length of the sequence, %
  Accel     |Δ²p − Δ²g|·fps² averaged over joints, over the frames whose second difference
            involves a cut frame (t−1, t or t+1 cut: the joins included), m/s²
  Accel-in  the same over the cut frames t only (the joins excluded)
Means are over all cut frames of the benchmark (frame-weighted). --noise adds Gaussian noise to
the observed frames (translation metres, rotation radians per axis-angle component as a random
rotation), as a robustness check; --smooth-row adds a row for `spline --smooth` then.

Run (from the repository root, after building hawor_cli and the default hands):
  /usr/bin/python3 examples/bench_infill.py --hawor build/<dir>/examples/hawor
Options: --presets walk,table_work,... --seeds 1,2 --draws 4 --size 160x120 --noise 0.002,0.015
         --smooth-row --json OUT.json --keep DIR
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zlib

import numpy as np
from scipy.spatial.transform import Rotation

FPS = 30.0
CHUNK = 100
METHODS = [("last pose", ["--method", "last"]), ("LERP", ["--method", "lerp"]),
           ("spline", ["--method", "spline"])]


def run(hawor, *args):
    p = subprocess.run([hawor, *args], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError("hawor %s failed (%d): %s" % (" ".join(args), p.returncode, p.stderr.strip()))
    return p.stdout


def umeyama(src, dst, scale=True):
    """(s, R, t) minimising sum |s R src_i + t - dst_i|^2 (Umeyama 1991; s = 1 without scale)."""
    ms, md = src.mean(0), dst.mean(0)
    a, b = src - ms, dst - md
    u, d, vt = np.linalg.svd(b.T @ a / len(src))
    e = np.eye(3)
    if np.linalg.det(u @ vt) < 0:
        e[2, 2] = -1
    r = u @ e @ vt
    s = np.trace(np.diag(d) @ e) / ((a * a).sum() / len(src)) if scale else 1.0
    return s, r, md - s * r @ ms


def apply(sim, p):
    s, r, t = sim
    return s * p @ r.T + t


def cut_gaps(valid, rng, lo, hi, margin=3, tries=300):
    """Random gaps of lo..hi frames inside runs of valid frames, `margin` valid frames kept on each
    side of a gap and between gaps. Returns the cut mask and the gap lengths."""
    T = len(valid)
    cut = np.zeros(T, bool)
    lengths = []
    for _ in range(tries):
        L = int(rng.integers(lo, hi + 1))
        if T - L - 2 * margin <= 0:
            continue
        s = int(rng.integers(margin, T - L - margin + 1))
        if valid[s - margin:s + L + margin].all() and not cut[max(0, s - 2 * margin):s + L + 2 * margin].any():
            cut[s:s + L] = True
            lengths.append(L)
    return cut, lengths


def noisy_rotvec(rv, rng, sigma):
    return (Rotation.from_rotvec(rv) * Rotation.from_rotvec(rng.normal(0, sigma, rv.shape))).as_rotvec()


class Tally:
    """Frame-weighted sums of the metrics of one method."""

    def __init__(self):
        self.sums = {}

    def add(self, key, total, count):
        s, n = self.sums.get(key, (0.0, 0))
        self.sums[key] = (s + float(total), n + int(count))

    def mean(self, key):
        s, n = self.sums.get(key, (0.0, 0))
        return s / n if n else float("nan")


def evaluate(gt, est, observed, cut, gap_len, tally):
    """Adds one hand's errors on the cut frames. gt/est (T,21,3); observed/cut (T,) bool;
    gap_len (T,) the length of the gap a cut frame belongs to."""
    T = len(gt)
    if not cut.any():
        return
    for c0 in range(0, T, CHUNK):
        idx = np.arange(c0, min(T, c0 + CHUNK))
        ev = idx[cut[idx]]
        if len(ev) == 0:
            continue
        anchor = idx[observed[idx]][:2]
        if len(anchor) < 2:
            anchor = idx[:2]
        sim = umeyama(est[anchor].reshape(-1, 3), gt[anchor].reshape(-1, 3))
        e = np.linalg.norm(apply(sim, est[ev].reshape(-1, 3)) - gt[ev].reshape(-1, 3), axis=1) * 1000
        e_frame = e.reshape(len(ev), -1).mean(1)
        tally.add("w_mpjpe", e.sum(), e.size)
        for lo, hi in ((10, 30), (31, 60), (61, 90)):
            m = (gap_len[ev] >= lo) & (gap_len[ev] <= hi)
            tally.add("w_mpjpe_%d_%d" % (lo, hi), e_frame[m].sum(), m.sum())
        sim = umeyama(est[ev].reshape(-1, 3), gt[ev].reshape(-1, 3))
        e = np.linalg.norm(apply(sim, est[ev].reshape(-1, 3)) - gt[ev].reshape(-1, 3), axis=1) * 1000
        tally.add("wa_mpjpe", e.sum(), e.size)
    vis = observed | cut
    path = np.linalg.norm(np.diff(gt[:, 0], axis=0), axis=1).sum()
    se3 = umeyama(est[vis, 0], gt[vis, 0], scale=False)
    e = np.linalg.norm(apply(se3, est[cut, 0]) - gt[cut, 0], axis=1)
    tally.add("rte", (e / path * 100).sum(), e.size)
    d2 = lambda p: p[:-2] - 2 * p[1:-1] + p[2:]  # noqa: E731
    acc = np.linalg.norm(d2(est) - d2(gt), axis=2).mean(1) * FPS * FPS  # frames 1..T-2
    touch = cut[:-2] | cut[1:-1] | cut[2:]
    tally.add("accel", acc[touch].sum(), touch.sum())
    tally.add("accel_in", acc[cut[1:-1]].sum(), cut[1:-1].sum())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hawor", default="build/native/examples/hawor")
    ap.add_argument("--presets", default="walk,table_work,fast_turns,pure_rotation,hands_cover")
    ap.add_argument("--seeds", default="1,2")
    ap.add_argument("--draws", type=int, default=4, help="gap draws per sequence")
    ap.add_argument("--size", default="160x120", help="image size of the synthetic sequences")
    ap.add_argument("--frames", type=int, default=0, help="frames per sequence (0: the preset's)")
    ap.add_argument("--gap", default="10,90", help="gap lengths lo,hi (frames)")
    ap.add_argument("--noise", default="", help="observation noise: translation_m,rotation_rad")
    ap.add_argument("--smooth-row", action="store_true", help="add a `spline --smooth` row")
    ap.add_argument("--json", default="")
    ap.add_argument("--keep", default="", help="keep the sequences and files in this folder")
    a = ap.parse_args()
    hawor = os.path.abspath(a.hawor)
    lo, hi = (int(v) for v in a.gap.split(","))
    noise = [float(v) for v in a.noise.split(",")] if a.noise else [0.0, 0.0]
    methods = list(METHODS)
    if a.smooth_row:
        methods.append(("spline --smooth", ["--method", "spline", "--smooth"]))
    work = a.keep or tempfile.mkdtemp(prefix="hawor_bench_infill_")
    os.makedirs(work, exist_ok=True)
    tallies = {name: Tally() for name, _ in methods}
    n_gaps, n_frames, t_infill, n_calls = 0, 0, 0.0, 0
    try:
        for preset in a.presets.split(","):
            for seed in a.seeds.split(","):
                seq = os.path.join(work, "%s_%s" % (preset, seed))
                if not os.path.exists(os.path.join(seq, "hands_gt.npz")):
                    args = ["synth", "--preset", preset, "--seed", seed, "--size", a.size, "--out", seq]
                    if a.frames:
                        args += ["--frames", str(a.frames)]
                    run(hawor, *args)
                gt = dict(np.load(os.path.join(seq, "hands_gt.npz")))
                for d in range(a.draws):
                    key = ("%s/%s/%d/%s" % (preset, seed, d, a.gap)).encode()
                    rng = np.random.default_rng(zlib.crc32(key))  # the gaps: the same with and without noise
                    nrng = np.random.default_rng(zlib.crc32(key + b"/noise"))
                    inp, cuts, lens = {}, {}, {}
                    for side in ("left", "right"):
                        p = side + "_"
                        valid = gt[p + "valid"].astype(bool)
                        cut, lengths = cut_gaps(valid, rng, lo, hi)
                        gl = np.zeros(len(valid), int)
                        s = 0
                        for t in range(len(valid)):  # the length of the gap each cut frame is in
                            if cut[t] and (t == 0 or not cut[t - 1]):
                                s = t
                            if cut[t] and (t + 1 == len(valid) or not cut[t + 1]):
                                gl[s:t + 1] = t + 1 - s
                        observed = valid & ~cut
                        cuts[side], lens[side] = (observed, cut), gl
                        n_gaps += len(lengths)
                        n_frames += int(cut.sum())
                        trans, rot = gt[p + "trans"].copy(), gt[p + "rot"].copy()
                        pose = gt[p + "hand_pose"].copy()
                        if noise[0] > 0 or noise[1] > 0:
                            trans = trans + nrng.normal(0, noise[0], trans.shape)
                            rot = noisy_rotvec(rot, nrng, noise[1])
                            K = pose.shape[1] // 3
                            pose = noisy_rotvec(pose.reshape(-1, 3), nrng, noise[1]).reshape(-1, 3 * K)
                        for arr in (trans, rot, pose):
                            arr[~observed] = np.nan
                        inp.update({p + "trans": trans, p + "rot": rot, p + "hand_pose": pose,
                                    p + "betas": gt[p + "betas"], p + "valid": observed})
                    fin = os.path.join(work, "in_%s_%s_%d.npz" % (preset, seed, d))
                    np.savez(fin, **inp)
                    for name, margs in methods:
                        fout = os.path.join(work, "out_%s_%s_%d_%s.npz" % (preset, seed, d, margs[1]))
                        t0 = time.time()
                        run(hawor, "infill", "--in", fin, "--out", fout, "--model", "default", "--joints", *margs)
                        t_infill += time.time() - t0
                        n_calls += 1
                        out = np.load(fout)
                        for side in ("left", "right"):
                            p = side + "_"
                            observed, cut = cuts[side]
                            est = out[p + "joints_world"]
                            g = gt[p + "joints_world"]
                            if noise[0] == 0 and noise[1] == 0 and observed.any():
                                err = np.abs(est[observed] - g[observed]).max()
                                if err > 1e-9:
                                    raise RuntimeError("the forward pass does not reproduce the ground-truth "
                                                       "joints at observed frames (%.3g m)" % err)
                            if not (out[p + "filled"].astype(bool) >= cut).all():
                                raise RuntimeError("a cut frame was not filled")
                            evaluate(g, est, observed, cut, lens[side], tallies[name])
    finally:
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)

    keys = [("w_mpjpe", "W-MPJPE"), ("wa_mpjpe", "WA-MPJPE"), ("rte", "RTE %"), ("accel", "Accel"),
            ("accel_in", "Accel-in")]
    print("Infiller ablation on synthetic hands (%s; seeds %s; %d draws; gaps %d-%d frames; noise %s)"
          % (a.presets, a.seeds, a.draws, lo, hi, a.noise or "none"))
    print("%d gaps, %d infilled frames (both hands); mm, %%, m/s^2; means over infilled frames" % (n_gaps, n_frames))
    print("%-16s" % "method" + "".join("%11s" % k[1] for k in keys))
    res = {}
    for name, _ in methods:
        res[name] = {k: tallies[name].mean(k) for k, _ in keys}
        print("%-16s" % name + "".join("%11.3f" % res[name][k] for k, _ in keys))
    ratio = {k: res["spline"][k] / res["LERP"][k] for k, _ in keys}
    print("%-16s" % "spline / LERP" + "".join("%11.3f" % ratio[k] for k, _ in keys))
    print("\nW-MPJPE by gap length (mm)")
    buckets = [("w_mpjpe_10_30", "10-30"), ("w_mpjpe_31_60", "31-60"), ("w_mpjpe_61_90", "61-90")]
    print("%-16s" % "method" + "".join("%11s" % b[1] for b in buckets))
    for name, _ in methods:
        print("%-16s" % name + "".join("%11.2f" % tallies[name].mean(b) for b, _ in buckets))
    targets = {"w_mpjpe": 0.9, "accel": 0.7}
    print("\nTargets: spline <= 0.9 x LERP W-MPJPE: %.3f %s; spline <= 0.7 x LERP Accel: %.3f %s"
          % (ratio["w_mpjpe"], "PASS" if ratio["w_mpjpe"] <= targets["w_mpjpe"] else "FAIL",
             ratio["accel"], "PASS" if ratio["accel"] <= targets["accel"] else "FAIL"))
    print("(Accel-in, the joins excluded: %.3f)" % ratio["accel_in"])
    print("hawor infill: %.1f ms per call (two hands, %d calls, process start included)"
          % (1000 * t_infill / max(n_calls, 1), n_calls))
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"presets": a.presets, "seeds": a.seeds, "draws": a.draws, "gap": [lo, hi],
                       "noise": noise, "gaps": n_gaps, "frames": n_frames, "results": res,
                       "spline_over_lerp": ratio,
                       "w_mpjpe_by_gap": {name: {b: tallies[name].mean(b) for b, _ in buckets}
                                          for name, _ in methods}}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
