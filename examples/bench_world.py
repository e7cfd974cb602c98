#!/usr/bin/python3
"""The output's world against the synthetic room: gravity, floor and metric scale, not aligned away.

Each preset x seed is rendered by `hawor synth` and its ground-truth camera-frame hands
(hands_gt.npz) are fed with the frames through `hawor world` (the pipeline without perception:
masks, SLAM, metric scale, the gravity-aligned world, infilling). The ground truth is in the
room's frame (z up, the floor at z = 0), the output's convention up to a rotation about z and
the placement of the origin. The estimate is aligned by 4 degrees of freedom only (a yaw and a
translation, fitted on the camera centres, least squares): no scale and no tilt, so gravity and
the metric scale must come from the method.

Per run: where up came from (floor / camera) and the worst angle between the estimated and true
up over the frames (each in the camera's frame: independent of the alignment); the first
camera's height above the floor, estimated (0 when the floor was not found: the origin is then
the first camera) and true; the camera's position error after the 4-DoF alignment (RMS, % of the
path) and the wrists' (median over observed hand-frames, cm); the metric scale's cue. One table;
--json writes the rows.

--input joints feeds the ground truth's camera-frame 3D joints (joints_cam) instead of its MANO
parameters (the model is then fitted to them). --hand-noise MM jitters the given hands as a
regressor's error would, per frame and hand: the whole hand moved by N(0, MM) across the view and
N(0, 3·MM) in depth, and with joints each joint by N(0, MM/2) more (seeded, reproducible).

  bench_world.py [--presets walk,table_work,hands_cover,fast_turns] [--seeds 1-2] [--frames 150]
      [--size 640x480] [--input params|joints] [--hand-noise MM] [--hawor build/native/examples/hawor]
      [--work DIR] [--jobs 2] [--json F]
"""
import argparse
import json
import math
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def read_tum(path):
    rows = [l.split() for l in open(path) if l.strip() and not l.startswith("#")]
    a = np.array(rows, float)
    return a[:, 1:4], a[:, 4:8]  # positions, quaternions x y z w


def quat_to_R(q):
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def fit_yaw_translation(src, dst):
    """Yaw about z and a translation taking src (N,3) onto dst (N,3), least squares."""
    ms, md = src.mean(0), dst.mean(0)
    a, b = src[:, :2] - ms[:2], dst[:, :2] - md[:2]
    th = math.atan2((a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum(), (a * b).sum())
    R = np.array([[math.cos(th), -math.sin(th), 0], [math.sin(th), math.cos(th), 0], [0, 0, 1]])
    return R, md - R @ ms


def noisy_hands(src, dst, mm, seed, joints):
    """hands_gt.npz with the given hands jittered (see the module's doc), written to dst."""
    z = dict(np.load(src))
    rng = np.random.default_rng(seed)
    sigma = np.array([1.0, 1.0, 3.0]) * mm / 1000
    for side in ("left", "right"):
        T = z[side + "_valid"].shape[0]
        move = rng.normal(size=(T, 3)) * sigma
        if joints:
            z[side + "_joints_cam"] = z[side + "_joints_cam"] + move[:, None, :] + rng.normal(size=(T, 21, 3)) * mm / 2000
            for k in ("cam_rot", "cam_trans", "hand_pose", "betas"):
                z.pop(side + "_" + k, None)
        else:
            z[side + "_cam_trans"] = z[side + "_cam_trans"] + move
    np.savez(dst, **z)


def run_one(o, preset, seed):
    d = os.path.join(o.work, "%s_s%d" % (preset, seed))
    if not os.path.exists(os.path.join(d, "meta.json")):
        subprocess.run([o.hawor, "synth", "--preset", preset, "--seed", str(seed), "--frames", str(o.frames), "--size", o.size, "--out", d],
                       check=True, stdout=subprocess.DEVNULL)
    fx, fy, cx, cy = open(os.path.join(d, "intrinsics.txt")).read().split()[:4]
    out = os.path.join(d, "world_%s_%g" % (o.input, o.hand_noise))
    hands = os.path.join(d, "hands_gt.npz")
    if o.hand_noise > 0:
        hands = os.path.join(d, "hands_noisy_%s_%g.npz" % (o.input, o.hand_noise))
        noisy_hands(os.path.join(d, "hands_gt.npz"), hands, o.hand_noise, seed, o.input == "joints")
    env = dict(os.environ, HAWOR_HAND_DIR=os.environ.get("HAWOR_HAND_DIR", os.path.join(os.path.dirname(os.path.dirname(o.hawor)), "models")))
    r = subprocess.run([o.hawor, "world", "--images", os.path.join(d, "rgb"), "--hands", hands, "--hands-input", o.input,
                        "--intrinsics", ",".join([fx, fy, cx, cy]), "--out", out], capture_output=True, text=True, env=env)
    if r.returncode != 0:
        return {"preset": preset, "seed": seed, "error": r.stderr.strip().splitlines()[-1]}
    summary = json.loads(r.stdout.strip().splitlines()[-1])
    meta = json.load(open(os.path.join(d, "meta.json")))
    up = -np.array(meta["gravity_world"], float)  # (0, 0, 1): the room is z up, floor at z = 0
    gt, gq = read_tum(os.path.join(d, "camera_gt.tum"))
    ep, eq = read_tum(os.path.join(out, "camera.tum"))
    h0 = float(gt[0, 2])
    # up in each camera's frame: estimated (z of the output world) against true
    worst = 0.0
    for t in range(len(gq)):
        u_est = quat_to_R(eq[t]).T @ np.array([0, 0, 1.0])
        u_gt = quat_to_R(gq[t]).T @ up
        worst = max(worst, math.degrees(math.acos(min(1.0, float(u_est.dot(u_gt))))))
    R, t = fit_yaw_translation(ep, gt)
    err = np.linalg.norm((R @ ep.T).T + t - gt, axis=1)
    path = np.linalg.norm(np.diff(gt, axis=0), axis=1).sum()
    gh = np.load(os.path.join(d, "hands_gt.npz"))
    eh = np.load(os.path.join(out, "world.npz"))
    werr = []
    for side in ("left", "right"):
        v = gh[side + "_valid"].astype(bool) & eh[side + "_valid"].astype(bool)
        if not v.any():
            continue
        g = gh[side + "_joints_world"][v, 0, :]
        e = (R @ eh[side + "_joints_world"][v, 0, :].T).T + t
        werr += list(np.linalg.norm(e - g, axis=1))
    return {"preset": preset, "seed": seed, "up": summary["up"], "up_confidence": summary["up_confidence"], "up_err_deg": worst,
            "origin": summary["origin"], "height_est": float(ep[0, 2]), "height_true": h0,
            "camera_pct": 100 * float(np.sqrt((err ** 2).mean())) / path, "path_m": path,
            "wrist_cm": 100 * float(np.median(werr)) if werr else float("nan"), "scale": summary["method"],
            "scale_confidence": summary["confidence"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--presets", default="walk,table_work,hands_cover,fast_turns")
    ap.add_argument("--seeds", default="1-2")
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--input", choices=("params", "joints"), default="params")
    ap.add_argument("--hand-noise", type=float, default=0.0, metavar="MM")
    ap.add_argument("--hawor", default=os.path.join(ROOT, "build", "native", "examples", "hawor"))
    ap.add_argument("--work", default=os.path.join(os.environ.get("TMPDIR", "/tmp"), "hawor_bench_world"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--json")
    o = ap.parse_args()
    if not os.path.exists(o.hawor):
        sys.exit("%s: no such file (cmake --build build/native --target hawor_cli default_hands)" % o.hawor)
    a, _, b = o.seeds.partition("-")
    seeds = list(range(int(a), int(b or a) + 1))
    os.makedirs(o.work, exist_ok=True)
    jobs = [(p, s) for p in o.presets.split(",") for s in seeds]
    with ThreadPoolExecutor(o.jobs) as ex:
        rows = list(ex.map(lambda j: run_one(o, *j), jobs))
    print("%-12s %4s  %-6s %6s %9s  %-6s %14s  %9s %8s  %s" % ("preset", "seed", "up", "conf", "up err °", "origin", "height m (true)",
                                                              "camera %", "wrist cm", "scale cue"))
    for r in rows:
        if "error" in r:
            print("%-12s %4d  error: %s" % (r["preset"], r["seed"], r["error"]))
            continue
        print("%-12s %4d  %-6s %6.2f %9.2f  %-6s %6.2f (%5.2f)  %9.2f %8.1f  %s %.2f" % (
            r["preset"], r["seed"], r["up"], r["up_confidence"], r["up_err_deg"], "floor" if r["origin"] == "floor" else "camera",
            r["height_est"], r["height_true"], r["camera_pct"], r["wrist_cm"], r["scale"], r["scale_confidence"]))
    ok = [r for r in rows if "error" not in r]
    if ok:
        fl = [r for r in ok if r["up"] == "floor"]
        print("up from the floor on %d of %d runs, worst up error there %.2f deg; camera <= 3 %% of the path on %d of %d; wrists <= 5 cm on %d of %d"
              % (len(fl), len(ok), max([r["up_err_deg"] for r in fl] or [float("nan")]), sum(r["camera_pct"] <= 3 for r in ok), len(ok),
                 sum(r["wrist_cm"] <= 5 for r in ok), len(ok)))
    if o.json:
        json.dump(rows, open(o.json, "w"), indent=1)


if __name__ == "__main__":
    main()
