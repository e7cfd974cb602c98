"""`hawor scale` end to end on scenes built here with numpy (no SLAM involved): a camera walking past
a table at a known metric scale, the "SLAM" trajectory and keyframe depths divided by that scale;
metric depth maps with the depth network's errors (bias, noise, outliers) and a hand region; hands
whose camera-frame wrists follow from world paths (one hand rests on the table for 2 s).
Checks: the depth scale (both samplings, the median baseline), the hand scale (hold cue), the
fused scale in log space, the scaled TUM file; and bad input: missing arrays, wrong shapes, a
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
    def bad(name, args, code=(1, 2), needle=None):
        rc, so, se = run("scale", *args)
        ok = rc in code and "nan" not in so.lower() and (needle is None or needle in se)
        check(name, ok, "rc=%d stdout=%s stderr=%s" % (rc, so, se))

    bad("no cue", ["--traj", traj, "--out", out], needle="--metric-depth")
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
