"""`hawor slam` end to end: a short synthetic sequence from `hawor synth` through the SLAM with and
without masks; the trajectory against the ground truth (Sim(3) Umeyama written here in numpy,
mean error as in docs/design.md §8), the TUM layout (first pose the identity, timestamps frame/fps),
the keyframe-depth npz against the rendered depth maps (up to the same Sim(3) scale), the stats
JSON, --refine-focal from a wrong and a right guess; and bad input: a missing folder, too few frames, a corrupt image, frames of different sizes,
a mask of the wrong size, bad intrinsics (clear message, exit code 1 or 2, no crash). `--set NAME=VALUE`:
the names it knows against the option structs' declarations parsed here from the headers (every
numeric and boolean field settable), a setting taking effect (`--set useMasks=false` gives the
`--no-mask` trajectory to the bit), and malformed settings refused.
Run: /usr/bin/python3 test_slam_cli.py path/to/hawor
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

import cliutil  # noqa: E402  (tests/cli: check, finish)
from cliutil import check  # noqa: E402

HAWOR = os.path.abspath(sys.argv[1])


def run(*args):
    p = subprocess.run([HAWOR, *args], capture_output=True, text=True, timeout=600)
    return p.returncode, p.stdout, p.stderr


def read_tum(path):
    rows = [l.split() for l in open(path) if l.strip() and not l.startswith("#")]
    return np.array(rows, dtype=np.float64)


def umeyama(src, dst):
    """Similarity (s, R, t) minimising sum |s R src + t - dst|^2 (Umeyama 1991)."""
    ms, md = src.mean(0), dst.mean(0)
    a, b = src - ms, dst - md
    cov = b.T @ a / len(src)
    u, d, vt = np.linalg.svd(cov)
    sgn = np.eye(3)
    if np.linalg.det(u @ vt) < 0:
        sgn[2, 2] = -1
    r = u @ sgn @ vt
    s = np.trace(np.diag(d) @ sgn) / (a * a).sum() * len(src)
    return s, r, md - s * r @ ms


def declared_options():
    """The int/Scalar/float/bool fields of SlamOptions and of its nested option structs,
    parsed from the headers: what `--set` must accept."""
    inc = os.path.join(os.path.dirname(__file__), "..", "..", "include", "hawor", "slam")

    def fields(header, struct, end):
        text = open(os.path.join(inc, header)).read()
        body = text[text.index("struct %s {" % struct):]
        body = body[:body.index(end)]
        return re.findall(r"^\s+(?:int|Scalar|float|bool)\s+(\w+)\s*=", body, re.M)

    names = set(fields("slam_options.hpp", "SlamOptions", "  /// Throws"))
    for prefix, header, struct in (("init", "slam_options.hpp", "SlamInitOptions"),
                                   ("turn", "slam_options.hpp", "SlamTurnOptions"),
                                   ("reloc", "slam_options.hpp", "SlamRelocOptions"),
                                   ("revisit", "slam_options.hpp", "SlamRevisitOptions"),
                                   ("link", "slam_options.hpp", "SlamLinkOptions"),
                                   ("place", "slam_options.hpp", "SlamPlaceOptions"),
                                   ("finish", "slam_options.hpp", "SlamFinishOptions"),
                                   ("join", "slam_options.hpp", "SlamJoinOptions"),
                                   ("keyframe", "keyframe_policy.hpp", "KeyframePolicyOptions"),
                                   ("corners", "corners.hpp", "CornerOptions"), ("klt", "klt.hpp", "KltOptions"),
                                   ("twoView", "two_view.hpp", "TwoViewOptions"),
                                   ("pnp", "pnp_ransac.hpp", "PnPRansacOptions"),
                                   ("bridge", "turn_bridge.hpp", "TurnBridgeOptions"),
                                   ("sequence", "sequence_refine.hpp", "SequenceRefineOptions"),
                                   ("headModel", "head_motion.hpp", "HeadModelOptions"),
                                   ("focal", "focal_refine.hpp", "FocalRefineOptions")):
        names |= {prefix + "." + n for n in fields(header, struct, "};")}
    return names


def check_set_option(seq, intr, tmp):
    rgb, masks = os.path.join(seq, "rgb"), os.path.join(seq, "mask")
    base = ["slam", "--images", rgb, "--intrinsics", intr, "--max-frames", "30"]
    rc, _, err = run(*base, "--out", os.path.join(tmp, "s.tum"), "--set", "noSuchOption=1")
    check("--set unknown name", rc == 2 and "noSuchOption" in err and "known:" in err, err)
    known = set(err.split("known: ", 1)[1].split(")", 1)[0].split(", ")) if "known: " in err else set()
    declared = declared_options()
    check("--set knows every declared option", known == declared,
          ("missing", sorted(declared - known), "extra", sorted(known - declared)))
    for bad, word in (("minInliers=2.5", "integer"), ("useMasks=yes", "true"), ("init.minFlowPx=nan", "number"),
                      ("klt.maxResidual=", "number"), ("minInliers", "NAME=VALUE"), ("=3", "NAME=VALUE"),
                      ("reloc.enabled=false", "revisit.enabled needs reloc.enabled"), ("minInliers=2", "minInliers")):
        rc, _, err = run(*base, "--out", os.path.join(tmp, "s.tum"), "--set", bad)
        check("--set %s refused" % bad, rc == 2 and word in err, err)
    outs = []
    for extra in (["--no-mask"], ["--set", "useMasks=false,minInliers=25"], ["--set", "useMasks=false", "--set", "minInliers=25"]):
        traj = os.path.join(tmp, "set%d.tum" % len(outs))
        rc, _, err = run(*base, "--masks", masks, "--out", traj, *extra)
        check("--set run %s" % extra, rc == 0, err)
        outs.append(open(traj).read() if rc == 0 else None)
    check("--set useMasks=false is --no-mask", outs[0] is not None and outs[0] == outs[1])
    check("repeated --set flags all apply", outs[0] is not None and outs[0] == outs[2])


def main():
    tmp = tempfile.mkdtemp(prefix="hawor_slam_cli_")
    try:
        seq = os.path.join(tmp, "seq")
        rc, out, err = run("synth", "--preset", "walk", "--seed", "3", "--frames", "60", "--model", "synthetic",
                           "--out", seq)
        check("synth", rc == 0, err)
        k = open(os.path.join(seq, "intrinsics.txt")).read().split()
        intr = ",".join(k[:4])
        gt = read_tum(os.path.join(seq, "camera_gt.tum"))
        path = np.linalg.norm(np.diff(gt[:, 1:4], axis=0), axis=1).sum()
        for mode in ("masked", "unmasked"):
            traj = os.path.join(tmp, mode + ".tum")
            kd = os.path.join(tmp, mode + "_kd.npz")
            stats = os.path.join(tmp, mode + "_stats.json")
            args = ["slam", "--images", os.path.join(seq, "rgb"), "--masks", os.path.join(seq, "mask"),
                    "--intrinsics", intr, "--out", traj, "--keyframe-depths", kd, "--stats", stats, "--fps", k[6]]
            if mode == "unmasked":
                args.append("--no-mask")
            rc, out, err = run(*args)
            check(mode + " runs", rc == 0, err)
            if rc != 0:
                continue
            summary = json.loads(out)
            check(mode + " summary", summary["frames"] == 60 and summary["initialised"] and
                  summary["masked"] == (mode == "masked"), out)
            est = read_tum(traj)
            check(mode + " tum rows", est.shape == (60, 8), est.shape)
            check(mode + " timestamps", np.allclose(est[:, 0], np.arange(60) / float(k[6])))
            check(mode + " first pose identity", np.allclose(est[0, 1:], [0, 0, 0, 0, 0, 0, 1], atol=1e-9), est[0])
            s, r, t = umeyama(est[:, 1:4], gt[:, 1:4])
            e = np.linalg.norm((s * (r @ est[:, 1:4].T)).T + t - gt[:, 1:4], axis=1)
            check(mode + " ATE < 2% of path", e.mean() < 0.02 * path, (e.mean(), path))
            st = json.load(open(stats))
            check(mode + " stats", len(st["status"]) == 60 and len(st["keyframe"]) == 60 and
                  set(st["status"]) <= {"tracked", "interpolated", "lost", "relocalised"} and
                  sum(st["keyframe"]) == summary["keyframes"], st["summary"])
            z = np.load(kd)
            check(mode + " kd keys", set(z.files) == {"frames", "kf", "uv", "depth"}, z.files)
            frames, kf, uv, depth = z["frames"], z["kf"], z["uv"], z["depth"]
            check(mode + " kd shapes", uv.shape == (len(depth), 2) and kf.shape == depth.shape and
                  len(frames) == summary["keyframes"] and (depth > 0).all(), (uv.shape, depth.shape))
            # Depths up to the trajectory's Sim(3) scale against the rendered depth maps.
            ratios = []
            for j, f in enumerate(frames):
                d = np.load(os.path.join(seq, "depth", "%06d.npy" % f))
                sel = kf == j
                x = np.clip(np.round(uv[sel, 0]).astype(int), 0, d.shape[1] - 1)
                y = np.clip(np.round(uv[sel, 1]).astype(int), 0, d.shape[0] - 1)
                g = d[y, x]
                ok = np.isfinite(g)
                ratios.extend(list(s * depth[sel][ok] / g[ok]))
            ratios = np.array(ratios)
            check(mode + " kd depths match ground truth", len(ratios) > 50 and abs(np.median(ratios) - 1) < 0.05,
                  (len(ratios), np.median(ratios) if len(ratios) else None))

        # Focal self-calibration from a guess 0.75 x the truth (the masked run): refined toward the
        # truth, the guess and a reason reported; a right guess is kept.
        for factor in (0.75, 1.0):
            f = factor * float(k[0])
            rc, out, err = run("slam", "--images", os.path.join(seq, "rgb"), "--masks", os.path.join(seq, "mask"),
                               "--intrinsics", "%r,%r,%s,%s" % (f, f, k[2], k[3]), "--out",
                               os.path.join(tmp, "focal.tum"), "--refine-focal")
            check("refine-focal %.2f runs" % factor, rc == 0, err)
            if rc != 0:
                continue
            sm = json.loads(out)
            check("refine-focal %.2f fields" % factor, sm["focal_guess_fx"] == f and len(sm["focal_reason"]) > 0, out)
            if factor == 1.0:
                check("right focal kept", not sm["focal_refined"] and sm["focal_fx"] == f, out)
            else:
                check("wrong focal refined", sm["focal_refined"] and abs(sm["focal_fx"] / float(k[0]) - 1) < 0.1 and
                      0 < sm["focal_std"] < 0.05, out)

        check_set_option(seq, intr, tmp)

        # Bad input.
        out_tum = os.path.join(tmp, "x.tum")
        rc, _, err = run("slam", "--images", os.path.join(tmp, "nope"), "--intrinsics", intr, "--out", out_tum)
        check("missing folder", rc == 1 and "nope" in err, err)
        rc, _, err = run("slam", "--images", os.path.join(seq, "rgb"), "--intrinsics", "1,2,3", "--out", out_tum)
        check("bad intrinsics", rc == 2 and "intrinsics" in err, err)
        rc, _, err = run("slam", "--images", os.path.join(seq, "rgb"), "--out", out_tum)
        check("missing intrinsics", rc == 2 and "intrinsics" in err, err)
        rc, _, err = run("slam", "--images", os.path.join(seq, "rgb"), "--intrinsics", intr, "--out", out_tum,
                         "--focal-prior", "0.1")
        check("focal prior without refinement", rc == 2 and "--refine-focal" in err, err)
        rc, _, err = run("slam", "--images", os.path.join(seq, "rgb"), "--intrinsics", intr, "--out", out_tum,
                         "--refine-focal", "--focal-prior", "0")
        check("focal prior not positive", rc == 2 and "--focal-prior" in err, err)
        one = os.path.join(tmp, "one")
        os.makedirs(one)
        shutil.copy(os.path.join(seq, "rgb", "000000.png"), one)
        rc, _, err = run("slam", "--images", one, "--intrinsics", intr, "--out", out_tum)
        check("too few frames", rc == 1 and "at least 2" in err, err)
        bad = os.path.join(tmp, "bad")
        os.makedirs(bad)
        for i in range(4):
            shutil.copy(os.path.join(seq, "rgb", "%06d.png" % i), bad)
        open(os.path.join(bad, "000002.png"), "wb").write(b"\x89PNG\r\n\x1a\nbroken")
        rc, _, err = run("slam", "--images", bad, "--intrinsics", intr, "--out", out_tum)
        check("corrupt image named", rc == 1 and "000002.png" in err, err)
        small = os.path.join(tmp, "small")
        os.makedirs(small)
        for i in range(3):
            shutil.copy(os.path.join(seq, "rgb", "%06d.png" % i), small)
        rc, _, err = run("synth", "--preset", "walk", "--seed", "1", "--frames", "1", "--size", "320x240", "--model",
                         "synthetic", "--out", os.path.join(tmp, "tiny"))
        shutil.copy(os.path.join(tmp, "tiny", "rgb", "000000.png"), os.path.join(small, "000003.png"))
        rc, _, err = run("slam", "--images", small, "--intrinsics", intr, "--out", out_tum)
        check("size mismatch", rc == 1 and "320x240" in err, err)
        masks = os.path.join(tmp, "masks")
        os.makedirs(masks)
        shutil.copy(os.path.join(tmp, "tiny", "mask", "000000.png"), os.path.join(masks, "000001.png"))
        rc, _, err = run("slam", "--images", small, "--masks", masks, "--intrinsics", intr, "--out", out_tum,
                         "--max-frames", "3")
        check("mask size mismatch", rc == 1 and "mask" in err and "000001.png" in err, err)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return cliutil.finish()


if __name__ == "__main__":
    sys.exit(main())
