"""`hawor scale` end to end on scenes built here with numpy (no SLAM involved): a camera walking past
a table at a known metric scale, the "SLAM" trajectory and keyframe depths divided by that scale;
metric depth maps with the depth network's errors (bias, noise, outliers) and a hand region; hands
whose camera-frame wrists follow from world paths (one hand rests on the table for 2 s).
Checks: the depth scale (both samplings, the median baseline), the hand scale (hold cue), the
fused scale in log space, the scaled TUM file; the ground cue on keyframe depths ray-cast here onto
a floor and a table top (the cameras' height above the floor in map units against the eye-height
prior); and bad input: missing arrays, wrong shapes, a
depth map of the wrong size, NaN maps, no usable cue, an unknown --sampling (clear message,
exit code 1 or 2, never a NaN scale).
Run: /usr/bin/python3 test_scale_cli.py path/to/hawor
"""
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.spatial.transform import Rotation

import cliutil  # noqa: E402  (tests/cli: check, finish)
from cliutil import check  # noqa: E402

HAWOR = os.path.abspath(sys.argv[1])


def run(*args):
    p = subprocess.run([HAWOR, *args], capture_output=True, text=True, timeout=300)
    return p.returncode, p.stdout, p.stderr


def write_tum(path, t, pos, quat_xyzw):
    with open(path, "w") as f:
        for i in range(len(t)):
            f.write("%.6f %s %s\n" % (t[i], " ".join("%.9f" % v for v in pos[i]), " ".join("%.9f" % v for v in quat_xyzw[i])))


def read_tum(path):
    return np.array([l.split() for l in open(path) if l.strip() and not l.startswith("#")], dtype=np.float64)


def main():
    rng = np.random.default_rng(3)
    tmp = tempfile.mkdtemp(prefix="hawor_scale_cli_")
    T, fps, W, H = 240, 30.0, 80, 60
    alpha = 0.42                      # metres per map unit: the scale to recover
    t = np.arange(T) / fps
    # Camera: walks 0.3 m/s along x with a bob, looks along +z (world), small yaw.
    c = np.stack([0.3 * t, 0.02 * np.sin(2 * np.pi * 1.5 * t), 0.05 * np.sin(0.7 * t)], 1)
    R = Rotation.from_rotvec(np.stack([0.05 * np.sin(1.1 * t), 0.1 * np.sin(0.5 * t), 0 * t], 1))
    traj = os.path.join(tmp, "traj.tum")
    write_tum(traj, t, c / alpha, R.as_quat())

    # Keyframes every 20 frames: a scene of points at metric depths 0.3..3 m seen by each.
    frames = np.arange(0, T, 20)
    kf, uv, dep = [], [], []
    ddir = os.path.join(tmp, "depth")
    mdir = os.path.join(tmp, "mask")
    os.makedirs(ddir), os.makedirs(mdir)
    from zlib import crc32, compress
    import struct

    def png_gray(path, img):
        raw = b"".join(b"\x00" + bytes(row) for row in img.astype(np.uint8))
        def chunk(tag, data):
            return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", crc32(tag + data) & 0xFFFFFFFF)
        with open(path, "wb") as f:
            f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", img.shape[1], img.shape[0], 8, 0, 0, 0, 0))
                    + chunk(b"IDAT", compress(raw)) + chunk(b"IEND", b""))

    for k, f in enumerate(frames):
        truth = 0.3 + 2.7 * rng.uniform(size=(H, W)) ** 1.5      # metric depth map
        net = truth * (1 + rng.uniform(-0.1, 0.1)) * (1 + 0.05 * rng.standard_normal((H, W)))
        out = rng.uniform(size=(H, W)) < 0.1
        net[out] = rng.uniform(0.1, 5.0, out.sum())
        mask = np.zeros((H, W))
        mask[H // 2:, W // 3:W // 2] = 255                          # a hand: metric depth there is wrong
        net[mask > 0] = 0.2
        np.save(os.path.join(ddir, "%06d.npy" % f), net.astype(np.float32))
        png_gray(os.path.join(mdir, "%06d.png" % f), mask)
        n = 150
        px = np.stack([rng.integers(0, W, n), rng.integers(0, H, n)], 1)
        kf += [k] * n
        uv.append(px.astype(np.float64))
        dep.append(truth[px[:, 1], px[:, 0]] / alpha * (1 + 0.01 * rng.standard_normal(n)))
    kd = os.path.join(tmp, "kd.npz")
    np.savez(kd, frames=frames.astype(np.int64), kf=np.array(kf, np.int64), uv=np.concatenate(uv), depth=np.concatenate(dep))

    # Hands: world wrist paths; the left one rests on the table for frames [30, 90).
    left_w = np.stack([0.3 * t + 0.2 * np.sin(1.7 * t), -0.2 + 0.05 * np.sin(2.3 * t), 0.45 + 0 * t], 1)
    left_w[30:90] = left_w[30]
    right_w = np.stack([0.3 * t + 0.1 + 0.1 * np.cos(1.3 * t), 0.15 + 0 * t, 0.4 + 0.05 * np.sin(1.9 * t)], 1)
    hands = {}
    for side, w in (("left_", left_w), ("right_", right_w)):
        cam = R.inv().apply(w - c) + 0.001 * rng.standard_normal((T, 3))
        j = np.repeat(cam[:, None, :], 21, axis=1)
        hands[side + "joints_cam"] = j
        hands[side + "valid"] = np.ones(T, np.uint8)
    hp = os.path.join(tmp, "hands.npz")
    np.savez(hp, **hands)
    out = os.path.join(tmp, "metric.tum")

    # Depth only (default sampling), with the baseline and the official sampling beside it.
    rc, so, se = run("scale", "--traj", traj, "--keyframe-depths", kd, "--metric-depth", ddir, "--masks", mdir,
                     "--out", out, "--baseline")
    check("depth: exit 0", rc == 0, se)
    if rc == 0:
        j = json.loads(so)
        check("depth: method", j["method"] == "depth", so)
        check("depth: scale within 3 %", abs(j["scale"] / alpha - 1) < 0.03, so)
        check("depth: official sampling within 5 %", abs(j["official_scale"] / alpha - 1) < 0.05, so)
        check("depth: median baseline reported", math.isfinite(j["median_scale"]), so)
        check("depth: confidence in (0, 1]", 0 < j["confidence"] <= 1, so)
        m = read_tum(out)
        check("depth: TUM positions scaled", np.allclose(m[:, 1:4], c / alpha * j["scale"], atol=1e-6))
        check("depth: TUM rotations and times kept", np.allclose(m[:, 4:8], read_tum(traj)[:, 4:8], atol=1e-9)
              and np.allclose(m[:, 0], t, atol=1e-6))

    # Hands only: the hold gives the scale.
    rc, so, se = run("scale", "--traj", traj, "--hands", hp, "--out", out)
    check("hands: exit 0", rc == 0, se)
    if rc == 0:
        j = json.loads(so)
        check("hands: method/cue", j["method"] == "hands" and j["hand_cue"] == "holds", so)
        check("hands: scale within 2 %", abs(j["scale"] / alpha - 1) < 0.02, so)

    # Both: fused in log space by confidence.
    rc, so, se = run("scale", "--traj", traj, "--keyframe-depths", kd, "--metric-depth", ddir, "--masks", mdir,
                     "--hands", hp, "--out", out)
    check("fused: exit 0", rc == 0, se)
    if rc == 0:
        j = json.loads(so)
        ds, dc = j["depth_scale"], j["depth_confidence"]
        ref = math.exp((dc * math.log(ds) + j["hand_confidence"] * math.log(j["hand_scale"])) / (dc + j["hand_confidence"]))
        check("fused: method", j["method"] == "fused", so)
        check("fused: log-space weighted mean", abs(j["scale"] / ref - 1) < 1e-9, so)

    # Bad input.
    # Ground cue: a head-worn camera 1.6 m above a floor (room z up), walking along x, looking
    # down 30-60 degrees; keyframe depths where its rays meet the floor z = 0 or a table top
    # z = 0.75 (x in [1, 2.5], y in [0.8, 1.6]); the map is the room / alpha.
    gt = np.arange(150) / fps
    gc = np.stack([0.4 * gt, 0.1 * np.sin(gt), 1.6 + 0.01 * np.sin(9 * gt)], 1)
    fx, fy, cx, cy = 60.0, 60.0, 40.0, 30.0
    g_rot = []
    for i in range(len(gt)):
        yaw, pitch = 0.3 * np.sin(0.8 * gt[i]) + np.pi / 2 * (i // 50 % 2), -0.5 - 0.25 * np.sin(1.3 * gt[i])
        f = np.array([np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw), np.sin(pitch)])
        rt = np.array([np.sin(yaw), -np.cos(yaw), 0.0])
        g_rot.append(np.stack([rt, np.cross(f, rt), f], 1))   # camera-to-room: x right, y down, z forward
    g_rot = Rotation.from_matrix(np.array(g_rot))
    gtraj = os.path.join(tmp, "traj_ground.tum")
    write_tum(gtraj, gt, gc / alpha, g_rot.as_quat())
    gframes = np.arange(0, len(gt), 10)
    gkf, guv, gdep = [], [], []
    for k, f in enumerate(gframes):
        px = np.stack([rng.uniform(0, W, 120), rng.uniform(0, H, 120)], 1)
        rays = g_rot[f].apply(np.stack([(px[:, 0] - cx) / fx, (px[:, 1] - cy) / fy, np.ones(len(px))], 1))
        for u, d in zip(px, rays):
            if d[2] >= -1e-3:
                continue
            lam = (0.75 - gc[f, 2]) / d[2]                     # the table top first, then the floor
            hit = gc[f] + lam * d
            if not (1 <= hit[0] <= 2.5 and 0.8 <= hit[1] <= 1.6):
                lam = -gc[f, 2] / d[2]
            gkf.append(k), guv.append(u), gdep.append(lam / alpha * (1 + 0.003 * rng.standard_normal()))
    gkd = os.path.join(tmp, "kd_ground.npz")
    np.savez(gkd, frames=gframes.astype(np.int64), kf=np.array(gkf, np.int64), uv=np.array(guv), depth=np.array(gdep))
    intr = "%g,%g,%g,%g" % (fx, fy, cx, cy)
    rc, so, se = run("scale", "--traj", gtraj, "--keyframe-depths", gkd, "--intrinsics", intr, "--out", out)
    check("ground: exit 0", rc == 0, se)
    if rc == 0:
        j = json.loads(so)
        check("ground: method", j["method"] == "ground", so)
        check("ground: scale within 2 %", abs(j["scale"] / alpha - 1) < 0.02, so)
        check("ground: the table top found at 0.75 m", abs(j.get("ground_surface_m", 0) - 0.75) < 0.05, so)
        check("ground: not ambiguous, confidence in (0, 0.5]", not j["ground_ambiguous"] and 0 < j["confidence"] <= 0.5, so)
    rc, so, se = run("scale", "--traj", gtraj, "--keyframe-depths", gkd, "--intrinsics", intr, "--eye-height", "1.2",
                     "--out", out)
    check("ground: --eye-height scales the answer", rc == 0 and abs(json.loads(so)["scale"] / alpha - 0.75) < 0.02, so + se)

    def bad(name, args, code=(1, 2), needle=None):
        rc, so, se = run("scale", *args)
        ok = rc in code and "nan" not in so.lower() and (needle is None or needle in se)
        check(name, ok, "rc=%d stdout=%s stderr=%s" % (rc, so, se))

    bad("no cue", ["--traj", traj, "--out", out], needle="--metric-depth")
    bad("ground: bad intrinsics", ["--traj", gtraj, "--keyframe-depths", gkd, "--intrinsics", "60,60", "--out", out],
        needle="--intrinsics")
    bad("ground: eye below the table", ["--traj", gtraj, "--keyframe-depths", gkd, "--intrinsics", intr,
                                        "--eye-height", "0.5", "--out", out], needle="--eye-height")
    bad("ground: no keyframe depths", ["--traj", gtraj, "--intrinsics", intr, "--out", out], needle="keyframe-depths")
    # The depths of the walking scene (a random cloud, no floor): a reason, no scale, no crash.
    bad("ground: no floor in the map", ["--traj", traj, "--keyframe-depths", kd, "--intrinsics", intr, "--out", out],
        needle="no metric scale")
    bad("unknown sampling", ["--traj", traj, "--hands", hp, "--out", out, "--sampling", "magic"], needle="sampling")
    np.savez(os.path.join(tmp, "kd_missing.npz"), frames=frames, kf=np.zeros(3, np.int64))
    bad("kd missing arrays", ["--traj", traj, "--keyframe-depths", os.path.join(tmp, "kd_missing.npz"),
                              "--metric-depth", ddir, "--out", out], needle="missing array")
    short = dict(hands)
    short["left_joints_cam"] = short["left_joints_cam"][:-5]
    np.savez(os.path.join(tmp, "hands_short.npz"), **short)
    bad("hands of the wrong length", ["--traj", traj, "--hands", os.path.join(tmp, "hands_short.npz"), "--out", out],
        needle="joints_cam")
    nan_dir = os.path.join(tmp, "depth_nan")
    os.makedirs(nan_dir)
    for f in frames:
        np.save(os.path.join(nan_dir, "%06d.npy" % f), np.full((H, W), np.nan, np.float32))
    bad("all-NaN depth maps", ["--traj", traj, "--keyframe-depths", kd, "--metric-depth", nan_dir, "--out", out],
        needle="no metric scale")
    wrong = os.path.join(tmp, "depth_wrong")
    os.makedirs(wrong)
    for f in frames:
        np.save(os.path.join(wrong, "%06d.npy" % f), np.ones((H, W, 2), np.float32))
    bad("3-D depth map", ["--traj", traj, "--keyframe-depths", kd, "--metric-depth", wrong, "--out", out],
        needle="(H,W)")
    bad("missing depth folder", ["--traj", traj, "--keyframe-depths", kd, "--metric-depth", os.path.join(tmp, "nope"),
                                 "--out", out])
    # NaN depth maps with a usable hand cue: the hands answer, no NaN anywhere.
    rc, so, se = run("scale", "--traj", traj, "--keyframe-depths", kd, "--metric-depth", nan_dir, "--hands", hp,
                     "--out", out)
    check("NaN depth + hands: hands answer", rc == 0 and json.loads(so)["method"] == "hands", so + se)

    return cliutil.finish()


if __name__ == "__main__":
    sys.exit(main())
