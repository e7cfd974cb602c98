#!/usr/bin/python3
"""COLMAP side of the SLAM benchmark: run COLMAP's sequential SfM on the first N
frames of a `hawor synth` sequence and measure its camera trajectory against ground truth.

    bench_colmap.py SEQ_DIR [--masked] [--frames N] [--work DIR] [--out-tum F] [--json F]
                            [--threads N] [--colmap PATH]
    bench_colmap.py --self-test

Pipeline (Debian colmap 3.8, CPU only): feature_extractor (one camera with the known
intrinsics: PINHOLE, or the sequence's lens from intrinsics.txt's 'lens' line as OPENCV,
FULL_OPENCV or OPENCV_FISHEYE; with --masked the hand masks, inverted, as COLMAP ignores features where its mask
is 0) -> sequential_matcher (default overlap, no loop detection) -> mapper (intrinsics fixed)
-> model_converter (largest model to TXT) -> images.txt parsed into camera-to-world poses.

Metrics: Sim(3) Umeyama alignment of the registered camera centres to ground truth; ATE is the
RMSE of the aligned centres (ate_mean_m: the mean, the library's ATE definition, docs/design.md §8),
in metres and in % of the ground-truth path length over all N frames. ate_all_*: the same over
all N frames after filling every unregistered frame with the nearest registered frame's pose
(Sim(3) re-fitted over all frames), so frames COLMAP could not register count against it.
Times: wall clock per COLMAP stage; `total` and ms_per_frame cover the COLMAP stages only
(the mask conversion is reported separately as `mask_prep`).

Prints one JSON object (also to --json); exit code 2 with a message on stderr on bad input or
when COLMAP reconstructs nothing. Needs only numpy (run with /usr/bin/python3).
"""
import argparse
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

import numpy as np


class BenchError(Exception):
    """A failure reported to the user as 'bench_colmap: ...' with exit code 2."""


# ----------------------------------------------------------------------------------------------
# Pure numpy parts (checked by --self-test)
# ----------------------------------------------------------------------------------------------

def umeyama_sim3(src, dst):
    """Similarity (s, R, t) minimising sum ||dst_i - (s R src_i + t)||^2 (Umeyama 1991).

    src, dst: (n, 3). With centred sets X, Y and Sigma = Y^T X / n = U D V^T:
    R = U S V^T, S = diag(1, 1, sign(det U det V)); s = tr(D S) / var(X); t = mu_y - s R mu_x.
    """
    src = np.asarray(src, dtype=np.float64)
    dst = np.asarray(dst, dtype=np.float64)
    if src.shape != dst.shape or src.ndim != 2 or src.shape[1] != 3:
        raise BenchError("umeyama: expected two (n, 3) arrays of the same shape, got %s and %s"
                         % (src.shape, dst.shape))
    n = src.shape[0]
    if n < 3:
        raise BenchError("umeyama: need at least 3 points, got %d" % n)
    mu_x = src.mean(axis=0)
    mu_y = dst.mean(axis=0)
    x = src - mu_x
    y = dst - mu_y
    var_x = float((x * x).sum()) / n
    if var_x <= 1e-300:
        raise BenchError("umeyama: the source points are all identical (no spread)")
    sigma = y.T @ x / n
    u, d, vt = np.linalg.svd(sigma)
    signs = np.ones(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0.0:
        signs[2] = -1.0
    rot = u @ np.diag(signs) @ vt
    scale = float((d * signs).sum()) / var_x
    trans = mu_y - scale * rot @ mu_x
    return scale, rot, trans


def apply_sim3(scale, rot, trans, pts):
    """s R p + t for each row p of pts (n, 3)."""
    return scale * np.asarray(pts, dtype=np.float64) @ rot.T + trans


def path_length(centres):
    """Sum of the distances between consecutive centres (n, 3)."""
    c = np.asarray(centres, dtype=np.float64)
    if c.shape[0] < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(c, axis=0), axis=1).sum())


def ate_sim3(est, gt):
    """ATE after Sim(3) alignment of est onto gt: dict(rmse, mean, max, scale)."""
    scale, rot, trans = umeyama_sim3(est, gt)
    err = np.linalg.norm(apply_sim3(scale, rot, trans, est) - np.asarray(gt, dtype=np.float64), axis=1)
    return {"rmse": float(np.sqrt((err * err).mean())), "mean": float(err.mean()),
            "max": float(err.max()), "scale": scale}


def fill_nearest(indices, n):
    """For each frame 0..n-1, the position in the sorted list `indices` of the nearest
    registered frame (ties go to the earlier one)."""
    idx = np.asarray(indices, dtype=np.int64)
    if idx.size == 0:
        raise BenchError("fill_nearest: no registered frame")
    frames = np.arange(n)
    right = np.clip(np.searchsorted(idx, frames), 0, idx.size - 1)
    left = np.clip(right - 1, 0, idx.size - 1)
    take_left = np.abs(frames - idx[left]) <= np.abs(idx[right] - frames)
    return np.where(take_left, left, right)


def quat_to_rot(qw, qx, qy, qz):
    """Rotation matrix of a (normalised) unit quaternion w + xi + yj + zk."""
    q = np.array([qw, qx, qy, qz], dtype=np.float64)
    nrm = np.linalg.norm(q)
    if not np.isfinite(nrm) or nrm < 1e-12:
        raise BenchError("quaternion with zero or non-finite norm: %s" % q)
    w, x, y, z = q / nrm
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def parse_images_txt(text):
    """COLMAP images.txt -> {name: (centre (3,), q_c2w (qw, qx, qy, qz))}, camera-to-world.

    Each image takes two lines: 'IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME' (world-to-camera:
    x_cam = R(q) x_world + t) and its 2D points line, which may be empty; '#' lines are comments.
    Camera-to-world: centre C = -R^T t, rotation R^T, i.e. the conjugate quaternion.
    """
    lines = [ln for ln in text.splitlines() if not ln.lstrip().startswith("#")]
    poses = {}
    for k in range(0, len(lines), 2):
        head = lines[k].split()
        if not head:
            if k + 1 >= len(lines) or not lines[k + 1].strip():
                continue  # trailing blank lines
            raise BenchError("images.txt: empty image line %d" % (k + 1))
        if len(head) < 10:
            raise BenchError("images.txt: image line '%s' has %d fields, expected 10"
                             % (lines[k].strip(), len(head)))
        try:
            qw, qx, qy, qz, tx, ty, tz = (float(v) for v in head[1:8])
        except ValueError:
            raise BenchError("images.txt: non-numeric pose in '%s'" % lines[k].strip())
        name = " ".join(head[9:])
        rot = quat_to_rot(qw, qx, qy, qz)
        centre = -rot.T @ np.array([tx, ty, tz])
        nrm = np.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
        poses[name] = (centre, np.array([qw, -qx, -qy, -qz]) / nrm)
    return poses


def read_tum(path):
    """TUM file -> (timestamps (n,), centres (n, 3), quats (n, 4) as qx qy qz qw)."""
    rows = []
    with open(path) as f:
        for no, line in enumerate(f, 1):
            s = line.strip()
            if not s or s.startswith("#"):
                continue
            parts = s.split()
            if len(parts) != 8:
                raise BenchError("%s:%d: expected 8 fields 't tx ty tz qx qy qz qw', got %d"
                                 % (path, no, len(parts)))
            try:
                rows.append([float(v) for v in parts])
            except ValueError:
                raise BenchError("%s:%d: non-numeric field" % (path, no))
    if not rows:
        raise BenchError("%s: no poses" % path)
    a = np.array(rows)
    if not np.all(np.isfinite(a)):
        raise BenchError("%s: non-finite values" % path)
    return a[:, 0], a[:, 1:4], a[:, 4:8]


def format_tum(stamps, centres, quats_wxyz):
    """TUM text 't tx ty tz qx qy qz qw' per line from timestamps, centres and (w, x, y, z)."""
    out = []
    for t, c, q in zip(stamps, centres, quats_wxyz):
        out.append("%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n"
                   % (t, c[0], c[1], c[2], q[1], q[2], q[3], q[0]))
    return "".join(out)


# --- minimal PNG codec (8-bit, non-interlaced), enough for the synth masks ---

_PNG_SIG = b"\x89PNG\r\n\x1a\n"
_PNG_CHANNELS = {0: 1, 2: 3, 4: 2, 6: 4}


def _unfilter_row(ftype, row, prev, bpp):
    """Undo one PNG filter (0 None, 1 Sub, 2 Up, 3 Average, 4 Paeth) on a uint8 row."""
    if ftype == 0:
        return row
    if ftype == 2:
        return row + prev  # uint8 wraps mod 256
    if ftype == 1:
        # x[i] = f[i] + x[i - bpp]: a cumulative sum along each channel's stride.
        out = np.empty_like(row)
        for c in range(bpp):
            out[c::bpp] = np.cumsum(row[c::bpp], dtype=np.uint64).astype(np.uint8)
        return out
    if ftype not in (3, 4):
        raise BenchError("PNG: unknown filter type %d" % ftype)
    f = row.tolist()
    b = prev.tolist()
    x = [0] * len(f)
    for i in range(len(f)):
        a = x[i - bpp] if i >= bpp else 0
        if ftype == 3:
            x[i] = (f[i] + ((a + b[i]) >> 1)) & 255
        else:
            c = b[i - bpp] if i >= bpp else 0
            p = a + b[i] - c
            pa, pb, pc = abs(p - a), abs(p - b[i]), abs(p - c)
            pred = a if (pa <= pb and pa <= pc) else (b[i] if pb <= pc else c)
            x[i] = (f[i] + pred) & 255
    return np.array(x, dtype=np.uint8)


def png_decode(data):
    """PNG bytes -> uint8 array (h, w) or (h, w, channels). 8-bit, non-interlaced, no palette."""
    if data[:8] != _PNG_SIG:
        raise BenchError("not a PNG file")
    pos = 8
    width = height = ctype = None
    idat = []
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            width, height, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or ctype not in _PNG_CHANNELS or interlace != 0:
                raise BenchError("PNG: only 8-bit non-interlaced grey/RGB(A) is supported "
                                 "(depth %d, colour type %d, interlace %d)" % (depth, ctype, interlace))
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
    if width is None or not idat:
        raise BenchError("PNG: missing IHDR or IDAT")
    bpp = _PNG_CHANNELS[ctype]
    stride = width * bpp
    raw = np.frombuffer(zlib.decompress(b"".join(idat)), dtype=np.uint8)
    if raw.size != height * (stride + 1):
        raise BenchError("PNG: image data has %d bytes, expected %d" % (raw.size, height * (stride + 1)))
    raw = raw.reshape(height, stride + 1)
    img = np.empty((height, stride), dtype=np.uint8)
    prev = np.zeros(stride, dtype=np.uint8)
    for r in range(height):
        prev = _unfilter_row(int(raw[r, 0]), raw[r, 1:], prev, bpp)
        img[r] = prev
    return img.reshape(height, width) if bpp == 1 else img.reshape(height, width, bpp)


def _filter_row(ftype, row, prev, bpp):
    """Apply PNG filter ftype to a uint8 row (used by the encoder's self-test path)."""
    r = row.astype(np.int64)
    b = prev.astype(np.int64)
    a = np.concatenate([np.zeros(bpp, np.int64), r[:-bpp]])
    c = np.concatenate([np.zeros(bpp, np.int64), b[:-bpp]])
    if ftype == 0:
        pred = np.zeros_like(r)
    elif ftype == 1:
        pred = a
    elif ftype == 2:
        pred = b
    elif ftype == 3:
        pred = (a + b) >> 1
    else:
        p = a + b - c
        pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
        pred = np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))
    return ((r - pred) & 255).astype(np.uint8)


def png_encode(img, filters=(0,)):
    """uint8 (h, w) grey image -> PNG bytes; row r uses filter filters[r % len(filters)]."""
    img = np.ascontiguousarray(img, dtype=np.uint8)
    if img.ndim != 2:
        raise BenchError("png_encode: expected a 2D grey image")
    h, w = img.shape
    rows = []
    prev = np.zeros(w, dtype=np.uint8)
    for r in range(h):
        ft = filters[r % len(filters)]
        rows.append(bytes([ft]) + _filter_row(ft, img[r], prev, 1).tobytes())
        prev = img[r]

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xffffffff)

    return (_PNG_SIG + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"".join(rows), 6)) + chunk(b"IEND", b""))


# ----------------------------------------------------------------------------------------------
# Self-test
# ----------------------------------------------------------------------------------------------

def _random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def _rot_to_quat(rot):
    """(w, x, y, z) of a rotation matrix (for building test data only)."""
    w = np.sqrt(max(0.0, 1 + np.trace(rot))) / 2
    x = np.copysign(np.sqrt(max(0.0, 1 + rot[0, 0] - rot[1, 1] - rot[2, 2])) / 2, rot[2, 1] - rot[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1 - rot[0, 0] + rot[1, 1] - rot[2, 2])) / 2, rot[0, 2] - rot[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1 - rot[0, 0] - rot[1, 1] + rot[2, 2])) / 2, rot[1, 0] - rot[0, 1])
    return np.array([w, x, y, z])


def self_test():
    rng = np.random.default_rng(7)
    results = []

    def check(name, ok, detail=""):
        results.append(ok)
        print("%s %s%s" % ("PASS" if ok else "FAIL", name, (": " + detail) if detail else ""))

    # Umeyama recovers a random similarity exactly (noise-free), for several sizes.
    for trial, n in enumerate((3, 10, 500)):
        traj = np.cumsum(rng.normal(size=(n, 3)) * 0.1, axis=0)
        s_true = float(rng.uniform(0.1, 10.0))
        r_true = _random_rotation(rng)
        t_true = rng.normal(size=3) * 5
        dst = apply_sim3(s_true, r_true, t_true, traj)
        s, r, t = umeyama_sim3(traj, dst)
        err = max(abs(s - s_true), np.abs(r - r_true).max(), np.abs(t - t_true).max() / 5)
        check("umeyama recovers Sim3 (n=%d)" % n, err < 1e-9, "max err %.2e" % err)
        a = ate_sim3(traj, dst)
        check("ate of an exact similarity is 0 (n=%d)" % n, a["rmse"] < 1e-9 * max(1.0, s_true), "%.2e" % a["rmse"])
    # Reflection guard: a mirrored target must still give a proper rotation.
    traj = rng.normal(size=(50, 3))
    s, r, t = umeyama_sim3(traj, traj * np.array([1.0, 1.0, -1.0]))
    check("umeyama returns a rotation (det +1) for a mirrored target", abs(np.linalg.det(r) - 1) < 1e-12)
    # Noisy case: optimum is a stationary point (perturbing s, R, t never lowers the cost).
    dst = apply_sim3(2.0, _random_rotation(rng), np.ones(3), traj) + rng.normal(size=traj.shape) * 0.05
    s, r, t = umeyama_sim3(traj, dst)
    cost = lambda s_, r_, t_: float(((apply_sim3(s_, r_, t_, traj) - dst) ** 2).sum())
    c0 = cost(s, r, t)
    worse = all(cost(s * (1 + e), r, t) >= c0 and cost(s, r, t + e) >= c0
                and cost(s, quat_to_rot(1, e, -e, e) @ r, t) >= c0 for e in (1e-4, -1e-4))
    check("umeyama is optimal on noisy data", worse)
    # RMSE / mean on a known offset, path length.
    check("path length", abs(path_length([[0, 0, 0], [3, 4, 0], [3, 4, 12]]) - 17.0) < 1e-12)
    check("fill_nearest", list(fill_nearest([2, 5, 9], 12)) == [0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2])

    # images.txt parser: generated poses (world-to-camera) with comments and empty point lines.
    n = 6
    truth = {}
    lines = ["# Image list with two lines of data per image:",
             "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME",
             "#   POINTS2D[] as (X, Y, POINT3D_ID)",
             "# Number of images: %d, mean observations per image: 1" % n]
    for i in range(n):
        r_wc = _random_rotation(rng)  # world-to-camera rotation
        q = _rot_to_quat(r_wc)
        if i % 2:
            q = -q  # q and -q are the same rotation
        t_wc = rng.normal(size=3)
        name = "%06d.png" % (10 * i)
        truth[name] = (-r_wc.T @ t_wc, r_wc.T)
        lines.append("%d %.17g %.17g %.17g %.17g %.17g %.17g %.17g 1 %s"
                     % (i + 1, q[0], q[1], q[2], q[3], t_wc[0], t_wc[1], t_wc[2], name))
        lines.append("" if i % 3 == 0 else "12.5 30.25 -1 100.0 7.5 %d" % (i + 3))
    poses = parse_images_txt("\n".join(lines) + "\n")
    ok = set(poses) == set(truth)
    worst = 0.0
    for name, (centre, q_c2w) in poses.items() if ok else []:
        worst = max(worst, np.abs(centre - truth[name][0]).max(),
                    np.abs(quat_to_rot(*q_c2w) - truth[name][1]).max())
    check("images.txt parser (names, centres, camera-to-world rotations)", ok and worst < 1e-9,
          "max err %.2e" % worst)
    try:
        parse_images_txt("1 1 0 0 0 1 2\n\n")
        check("images.txt parser rejects a short line", False)
    except BenchError:
        check("images.txt parser rejects a short line", True)

    # TUM round trip.
    path = os.path.join(tempfile.mkdtemp(prefix="bench_colmap_selftest_"), "t.tum")
    centres = rng.normal(size=(4, 3))
    quats = np.array([_rot_to_quat(_random_rotation(rng)) for _ in range(4)])
    with open(path, "w") as f:
        f.write(format_tum(np.arange(4) / 30.0, centres, quats))
    stamps, c2, q2 = read_tum(path)
    shutil.rmtree(os.path.dirname(path))
    check("TUM write/read round trip", np.abs(c2 - centres).max() < 1e-8
          and np.abs(q2 - quats[:, [1, 2, 3, 0]]).max() < 1e-8 and abs(stamps[3] - 0.1) < 1e-9)

    # PNG codec round trip through every filter type (the decoder must undo all five).
    img = (rng.random((23, 37)) < 0.3).astype(np.uint8) * 255
    img[5:9, 3:20] = 128
    img[10] = rng.integers(0, 256, size=37)
    dec = png_decode(png_encode(img, filters=(0, 1, 2, 3, 4)))
    check("PNG round trip over filters 0-4", dec.shape == img.shape and np.array_equal(dec, img))

    # intrinsics.txt: one line, or with hawor synth --capture a 'lens' line; COLMAP's models.
    d = tempfile.mkdtemp(prefix="bench_colmap_selftest_")
    path = os.path.join(d, "intrinsics.txt")
    with open(path, "w") as f:
        f.write("400 400 319.5 239.5 640 480 30\n")
    plain = read_intrinsics(path)
    with open(path, "w") as f:
        f.write("300 300 319.5 239.5 640 480 30\nlens fisheye:-0.0036,0.0368,-0.0343,0.0052\n")
    fish = read_intrinsics(path)
    with open(path, "w") as f:
        f.write("300 300 319.5 239.5 640 480 30\nfocal 300\n")
    try:
        read_intrinsics(path)
        bad = False
    except BenchError:
        bad = True
    shutil.rmtree(d)
    check("intrinsics.txt without a lens line is pinhole", plain[7] == "pinhole" and plain[4] == 640)
    check("intrinsics.txt lens line", fish[7].startswith("fisheye:") and fish[0] == 300)
    check("intrinsics.txt rejects other lines", bad)
    check("COLMAP camera models", colmap_camera(1, 1, 0, 0, "pinhole")[0] == "PINHOLE"
          and colmap_camera(1, 1, 0, 0, fish[7]) == ("OPENCV_FISHEYE", [1, 1, 0, 0, -0.0036, 0.0368, -0.0343, 0.0052])
          and colmap_camera(1, 1, 0, 0, "opencv:-0.2,0.05,0,0,0")[0] == "OPENCV"
          and len(colmap_camera(1, 1, 0, 0, "opencv:-0.26,0.07,0.0004,-0.0003,-0.0065")[1]) == 12)

    passed = sum(results)
    failed = len(results) - passed
    print("%d passed, %d failed" % (passed, failed))
    return 0 if failed == 0 else 1


# ----------------------------------------------------------------------------------------------
# COLMAP pipeline
# ----------------------------------------------------------------------------------------------

def run_stage(colmap, stage, args, log_dir):
    """Run `colmap stage args...`, return wall seconds; on failure raise with the log's tail."""
    log_path = os.path.join(log_dir, stage + ".log")
    t0 = time.perf_counter()
    with open(log_path, "w") as log:
        try:
            rc = subprocess.call([colmap, stage] + [str(a) for a in args], stdout=log, stderr=subprocess.STDOUT)
        except OSError as e:
            raise BenchError("cannot run %s: %s" % (colmap, e))
    dt = time.perf_counter() - t0
    if rc != 0:
        with open(log_path, errors="replace") as log:
            tail = "".join(log.readlines()[-15:])
        raise BenchError("colmap %s failed (exit code %d); last lines of its log:\n%s" % (stage, rc, tail))
    return dt


def read_intrinsics(path):
    """fx, fy, cx, cy, width, height, fps from the first line of a hawor synth intrinsics.txt, and
    the lens: "pinhole" unless a second line 'lens SPEC' names one (hawor synth --capture:
    "opencv:k1,k2,p1,p2,k3" or "fisheye:k1,k2,k3,k4", include/hawor/geometry/lens.hpp)."""
    try:
        with open(path) as f:
            lines = [l.split() for l in f.read().splitlines() if l.strip()]
    except OSError as e:
        raise BenchError("cannot read intrinsics %s: %s" % (path, e.strerror))
    vals = lines[0] if lines else []
    if len(vals) != 7:
        raise BenchError("%s: expected 7 numbers 'fx fy cx cy width height fps' on the first line, got %d" % (path, len(vals)))
    try:
        fx, fy, cx, cy, w, h, fps = (float(v) for v in vals)
    except ValueError:
        raise BenchError("%s: non-numeric value in '%s'" % (path, " ".join(vals)))
    if not all(np.isfinite([fx, fy, cx, cy, w, h, fps])) or fx <= 0 or fy <= 0 or w < 1 or h < 1 or fps <= 0:
        raise BenchError("%s: invalid intrinsics %s" % (path, vals))
    lens = "pinhole"
    for l in lines[1:]:
        if len(l) != 2 or l[0] != "lens":
            raise BenchError("%s: expected 'lens SPEC' after the first line, got '%s'" % (path, " ".join(l)))
        lens = l[1]
    return fx, fy, cx, cy, int(w), int(h), fps, lens


def colmap_camera(fx, fy, cx, cy, lens):
    """COLMAP's camera model and parameters for intrinsics and a hawor lens string: PINHOLE,
    OPENCV (k3 = 0) or FULL_OPENCV (k1, k2, p1, p2, k3, k4..k6 = 0), OPENCV_FISHEYE (the same
    equidistant Kannala-Brandt k1..k4)."""
    base = [fx, fy, cx, cy]
    if lens == "pinhole":
        return "PINHOLE", base
    name, _, rest = lens.partition(":")
    try:
        k = [float(v) for v in rest.split(",")]
    except ValueError:
        raise BenchError("lens '%s': coefficients are not numbers" % lens)
    if name == "opencv" and len(k) in (4, 5):
        k = k + [0.0] * (5 - len(k))
        if k[4] == 0:
            return "OPENCV", base + k[:4]
        return "FULL_OPENCV", base + k + [0.0, 0.0, 0.0]
    if name == "fisheye" and len(k) == 4:
        return "OPENCV_FISHEYE", base + k
    raise BenchError("lens '%s': expected pinhole, opencv:k1,k2,p1,p2[,k3] or fisheye:k1,k2,k3,k4" % lens)


def colmap_version(colmap):
    try:
        out = subprocess.run([colmap, "help"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             timeout=30).stdout.decode(errors="replace")
    except (OSError, subprocess.TimeoutExpired):
        return None
    for line in out.splitlines():
        if line.startswith("COLMAP"):
            return line.split("--")[0].replace("COLMAP", "").strip()
    return None


def prepare_masks(seq, names, mask_dir):
    """Write COLMAP masks: mask_dir/<image name>.png, 255 = keep features, 0 = hand (ignored)."""
    os.makedirs(mask_dir)
    covered = []
    for name in names:
        src = os.path.join(seq, "mask", name)
        try:
            with open(src, "rb") as f:
                m = png_decode(f.read())
        except OSError as e:
            raise BenchError("cannot read mask %s: %s" % (src, e.strerror))
        except BenchError as e:
            raise BenchError("mask %s: %s" % (src, e))
        if m.ndim == 3:
            m = m[..., :3].max(axis=2) if m.shape[2] >= 3 else m[..., 0]
        hand = m != 0
        covered.append(float(hand.mean()))
        with open(os.path.join(mask_dir, name + ".png"), "wb") as f:
            f.write(png_encode(np.where(hand, 0, 255).astype(np.uint8)))
    return covered


def model_image_count(model_dir):
    """Registered images of a binary COLMAP model (images.bin starts with a uint64 count)."""
    path = os.path.join(model_dir, "images.bin")
    try:
        with open(path, "rb") as f:
            head = f.read(8)
    except OSError:
        return -1
    return struct.unpack("<Q", head)[0] if len(head) == 8 else -1


def bench(opts):
    seq = opts.seq_dir
    if not os.path.isdir(seq):
        raise BenchError("sequence directory %s does not exist" % seq)
    colmap = shutil.which(opts.colmap)
    if colmap is None:
        raise BenchError("colmap executable '%s' not found (Debian: apt-get install colmap)" % opts.colmap)
    fx, fy, cx, cy, width, height, fps, lens = read_intrinsics(os.path.join(seq, "intrinsics.txt"))
    camera_model, camera_params = colmap_camera(fx, fy, cx, cy, lens)
    rgb_dir = os.path.join(seq, "rgb")
    if not os.path.isdir(rgb_dir):
        raise BenchError("%s has no rgb/ folder" % seq)
    names = sorted(n for n in os.listdir(rgb_dir) if n.endswith(".png"))
    if not names:
        raise BenchError("%s contains no .png frames" % rgb_dir)
    n = len(names) if opts.frames is None else opts.frames
    if n < 3:
        raise BenchError("--frames must be at least 3, got %d" % n)
    if n > len(names):
        raise BenchError("--frames %d but %s has only %d frames" % (n, rgb_dir, len(names)))
    names = names[:n]
    gt_path = os.path.join(seq, "camera_gt.tum")
    if not os.path.isfile(gt_path):
        raise BenchError("%s is missing (ground-truth camera trajectory)" % gt_path)
    _, gt_all, _ = read_tum(gt_path)
    if gt_all.shape[0] < n:
        raise BenchError("%s has %d poses, fewer than the %d frames" % (gt_path, gt_all.shape[0], n))
    gt = gt_all[:n]
    preset = None
    meta_path = os.path.join(seq, "meta.json")
    if os.path.isfile(meta_path):
        try:
            with open(meta_path) as f:
                preset = json.load(f).get("preset")
        except (OSError, ValueError, AttributeError):
            preset = None
    if opts.masked and not os.path.isdir(os.path.join(seq, "mask")):
        raise BenchError("--masked but %s has no mask/ folder" % seq)

    # Fresh workspace (only our own entries are removed when --work already exists).
    own_tmp = opts.work is None
    work = tempfile.mkdtemp(prefix="bench_colmap_") if own_tmp else os.path.abspath(opts.work)
    os.makedirs(work, exist_ok=True)
    for entry in ("database.db", "database.db-shm", "database.db-wal", "image_list.txt", "masks",
                  "sparse", "model_txt", "logs"):
        p = os.path.join(work, entry)
        if os.path.isdir(p):
            shutil.rmtree(p)
        elif os.path.exists(p):
            os.remove(p)
    db = os.path.join(work, "database.db")
    logs = os.path.join(work, "logs")
    sparse = os.path.join(work, "sparse")
    os.makedirs(logs)
    os.makedirs(sparse)
    with open(os.path.join(work, "image_list.txt"), "w") as f:
        f.write("".join(nm + "\n" for nm in names))

    try:
        seconds = {}
        threads = str(opts.threads)
        extract = ["--database_path", db, "--image_path", os.path.abspath(rgb_dir),
                   "--image_list_path", os.path.join(work, "image_list.txt"),
                   "--ImageReader.single_camera", 1, "--ImageReader.camera_model", camera_model,
                   "--ImageReader.camera_params", ",".join("%.17g" % v for v in camera_params),
                   "--SiftExtraction.use_gpu", 0, "--SiftExtraction.num_threads", threads]
        coverage = None
        if opts.masked:
            t0 = time.perf_counter()
            coverage = prepare_masks(seq, names, os.path.join(work, "masks"))
            seconds["mask_prep"] = time.perf_counter() - t0
            extract += ["--ImageReader.mask_path", os.path.join(work, "masks")]
        seconds["feature_extractor"] = run_stage(colmap, "feature_extractor", extract, logs)
        seconds["sequential_matcher"] = run_stage(colmap, "sequential_matcher", [
            "--database_path", db, "--SequentialMatching.loop_detection", 0,
            "--SiftMatching.use_gpu", 0, "--SiftMatching.num_threads", threads], logs)
        nothing = "COLMAP reconstructed nothing from %d frames of %s" % (n, seq)
        try:
            seconds["mapper"] = run_stage(colmap, "mapper", [
                "--database_path", db, "--image_path", os.path.abspath(rgb_dir), "--output_path", sparse,
                "--Mapper.num_threads", threads, "--Mapper.ba_refine_focal_length", 0,
                "--Mapper.ba_refine_principal_point", 0, "--Mapper.ba_refine_extra_params", 0], logs)
        except BenchError as e:
            # colmap 3.8's mapper exits with 1 and "failed to create sparse model" when no model.
            if "failed to create sparse model" in str(e):
                raise BenchError(nothing + " (mapper: no initial image pair / no model)")
            raise

        models = [d for d in os.listdir(sparse) if os.path.isdir(os.path.join(sparse, d))]
        counts = {d: model_image_count(os.path.join(sparse, d)) for d in models}
        counts = {d: c for d, c in counts.items() if c > 0}
        if not counts:
            raise BenchError(nothing)
        best = max(sorted(counts), key=lambda d: counts[d])
        txt_dir = os.path.join(work, "model_txt")
        os.makedirs(txt_dir)
        seconds["model_converter"] = run_stage(colmap, "model_converter", [
            "--input_path", os.path.join(sparse, best), "--output_path", txt_dir, "--output_type", "TXT"], logs)
        seconds["total"] = sum(v for k, v in seconds.items() if k != "mask_prep")

        with open(os.path.join(txt_dir, "images.txt")) as f:
            poses = parse_images_txt(f.read())
    except BenchError as e:
        if own_tmp and not opts.keep:
            raise BenchError("%s\n(temporary workspace removed; rerun with --keep or --work DIR to inspect "
                             "the COLMAP logs)" % e)
        raise BenchError("%s\n(COLMAP logs in %s)" % (e, logs))
    finally:
        if own_tmp and not opts.keep:
            shutil.rmtree(work, ignore_errors=True)

    index = {nm: i for i, nm in enumerate(names)}
    reg = sorted(index[nm] for nm in poses if nm in index)
    if len(reg) < 3:
        raise BenchError("COLMAP registered only %d of %d frames (need 3 for Sim(3) alignment)" % (len(reg), n))
    est = np.array([poses[names[i]][0] for i in reg])
    quats = np.array([poses[names[i]][1] for i in reg])
    path_m = path_length(gt)
    a = ate_sim3(est, gt[reg])
    fill = fill_nearest(reg, n)
    a_all = ate_sim3(est[fill], gt)

    if opts.out_tum:
        with open(opts.out_tum, "w") as f:
            f.write(format_tum(np.array(reg) / fps, est, quats))

    pct = (lambda v: 100.0 * v / path_m) if path_m > 0 else (lambda v: None)
    result = {
        "preset": preset,
        "seq": os.path.abspath(seq),
        "frames": n,
        "registered": len(reg),
        "unregistered": n - len(reg),
        "models": len(counts),
        "ate_m": a["rmse"],
        "ate_pct": pct(a["rmse"]),
        "ate_mean_m": a["mean"],
        "ate_max_m": a["max"],
        "ate_all_m": a_all["rmse"],
        "ate_all_mean_m": a_all["mean"],
        "ate_all_pct": pct(a_all["rmse"]),
        "ate_all_note": "all frames; unregistered frames take the nearest registered frame's pose; Sim3 re-fitted",
        "path_m": path_m,
        "sim3_scale": a["scale"],
        "seconds": {k: round(v, 3) for k, v in seconds.items()},
        "ms_per_frame": 1000.0 * seconds["total"] / n,
        "masked": bool(opts.masked),
        "mask_coverage_mean": None if coverage is None else float(np.mean(coverage)),
        "threads": opts.threads,
        "size": [width, height],
        "colmap": colmap_version(colmap),
        "work": None if own_tmp and not opts.keep else work,
    }
    return result


def main(argv):
    p = argparse.ArgumentParser(description="COLMAP baseline for the hawor SLAM benchmark.")
    p.add_argument("seq_dir", nargs="?", help="sequence written by 'hawor synth'")
    p.add_argument("--masked", action="store_true", help="ignore features on hand pixels (DIR/mask)")
    p.add_argument("--frames", type=int, default=None, help="use the first N frames (default: all)")
    p.add_argument("--work", default=None, help="workspace folder (default: a temporary one, removed)")
    p.add_argument("--keep", action="store_true", help="keep the temporary workspace")
    p.add_argument("--out-tum", default=None, help="write COLMAP's camera-to-world trajectory (TUM)")
    p.add_argument("--json", default=None, help="also write the JSON result here")
    p.add_argument("--threads", type=int, default=1, help="COLMAP threads per stage (default 1)")
    p.add_argument("--colmap", default="colmap", help="colmap executable (default: colmap on PATH)")
    p.add_argument("--self-test", action="store_true", help="check the numpy parts and exit")
    opts = p.parse_args(argv)
    if opts.self_test:
        return self_test()
    if opts.seq_dir is None:
        p.print_usage(sys.stderr)
        print("bench_colmap: missing SEQ_DIR", file=sys.stderr)
        return 2
    if opts.threads < 1:
        print("bench_colmap: --threads must be >= 1", file=sys.stderr)
        return 2
    try:
        result = bench(opts)
    except BenchError as e:
        print("bench_colmap: %s" % e, file=sys.stderr)
        return 2
    text = json.dumps(result)
    print(text)
    if opts.json:
        with open(opts.json, "w") as f:
            f.write(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
