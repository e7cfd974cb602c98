#!/usr/bin/python3
"""The SLAM under real capture: synthetic presets x capture profiles x seeds through `hawor slam`.

bench_slam (and bench_slam_seeds.py over seeds) renders the generator's clean frames in memory.
Real video is blurred in motion, read out by a rolling shutter, noisy, drifting in exposure,
seen through a lens and compressed. Here each sequence is rendered by `hawor synth --capture
PROFILE` (synth/capture.hpp; docs/cli.md lists the profiles), encoded and decoded as that device
would (capture.json's ffmpeg arguments: `ffmpeg -framerate FPS -i rgb/%06d.png ARGS out.mp4`,
then decoded; profiles without an encoding keep the lossless frames), made grey (BT.601, as the
pipeline's SLAM sees it), and tracked by `hawor slam --camera LENS` (the lens of intrinsics.txt;
frames and masks rectified to the virtual pinhole camera) with and without the hand masks. An
encoding that shrinks the frames (webcam_360p: at most 360 rows) scales the intrinsics and the
masks (nearest) with them.

Outputs per preset and profile: the median over seeds of the ATE in % of the ground-truth path
(Sim(3)-aligned mean position error, `hawor metrics camera`), masked / unmasked, and how many
runs are <= 1 %; on hands_cover (the hands-heavy preset) masked / unmasked as the ratio of the
mean ATEs over seeds; the median over runs of `hawor slam`'s median ms per frame; where it was
initialised and how many frames it lost (per run in --json).

The rendered, encoded and grey frames are cached in --work (rendering costs 100-600 ms a frame
per profile): WORK/PRESET_PROFILE_sSEED/{frames/, mask/, camera_gt.tum, meta.json}. The SLAM
runs again on every call (a few ms a frame) unless --reuse-slam; its outputs go to
WORK/.../slam_{masked,unmasked}/. Extra arguments after `--` go to every `hawor slam`.
--readout gives each run its profile's rolling-shutter readout (`hawor slam --readout`, the
readout_s of the profile's capture.json; clean: 0).

  bench_slam_capture.py [--presets walk,table_work,fast_turns,hands_cover]
      [--profiles clean,phone,action_cam,aria,low_light,webcam_360p] [--seeds 1-4]
      [--frames 150] [--size 640x480] [--model default|synthetic] [--jobs 2]
      [--work DIR] [--hawor BIN] [--reuse-slam] [--masked-only] [--readout] [--json OUT] [-- slam flags]

The presets default to the moving ones whose targets are judged (pure_rotation has no
observable translation for this front end; bench_slam reports it). Cost at the defaults on two
busy cores: about 40-60 min to render and encode once, then 3-6 min a SLAM round (both modes).
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

PRESETS = ["walk", "table_work", "fast_turns", "hands_cover"]
PROFILES = ["clean", "phone", "action_cam", "aria", "low_light", "webcam_360p"]
HANDS_PRESET = "hands_cover"


def parse_seeds(text):
    out = set()
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        if "-" in part:
            a, b = part.split("-", 1)
            out.update(range(int(a), int(b) + 1))
        else:
            out.add(int(part))
    if not out:
        raise ValueError("no seeds in %r" % text)
    return sorted(out)


def run(cmd, **kw):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)
    if p.returncode != 0:
        raise RuntimeError("%s failed (%d): %s" % (" ".join(cmd[:3]), p.returncode, p.stderr.strip()[-600:]))
    return p.stdout


def read_tum(path):
    rows = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith("#"):
                rows.append([float(x) for x in line.split()])
    return np.asarray(rows)


def path_length(tum):
    p = tum[:, 1:4]
    return float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))


def prepare(a, preset, profile, seed):
    """Renders, encodes/decodes and greys one sequence into WORK/NAME (kept when complete)."""
    import cv2  # noqa: E402 (python3-opencv, installed by scripts/install.sh)

    name = "%s_%s_s%d" % (preset, profile, seed)
    out = os.path.join(a.work, name)
    if os.path.exists(os.path.join(out, "meta.json")):
        return name
    shutil.rmtree(out, ignore_errors=True)
    tmp = out + ".part"
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    t0 = time.time()
    cmd = [a.hawor, "synth", "--preset", preset, "--seed", str(seed), "--frames", str(a.frames), "--size", a.size,
           "--model", a.model, "--out", os.path.join(tmp, "synth")]
    if profile != "clean":
        cmd += ["--capture", profile]
    summary = json.loads(run(cmd).strip().splitlines()[-1])
    render_s = time.time() - t0
    syn = os.path.join(tmp, "synth")
    with open(os.path.join(syn, "intrinsics.txt")) as f:
        lines = f.read().split("\n")
    fx, fy, cx, cy, w, h, fps = (float(x) for x in lines[0].split())
    lens = "pinhole"
    for line in lines[1:]:
        if line.startswith("lens "):
            lens = line.split(None, 1)[1].strip()
    enc = {}
    cap = os.path.join(syn, "capture.json")
    if os.path.exists(cap):
        with open(cap) as f:
            enc = json.load(f).get("encode", {}) or {}
    rgb_dir = os.path.join(syn, "rgb")
    frames_dir = os.path.join(tmp, "frames")
    os.makedirs(frames_dir)
    t1 = time.time()
    kbps = None
    if enc.get("ffmpeg_args"):
        mp4 = os.path.join(tmp, "video.mp4")
        run(["ffmpeg", "-v", "error", "-nostdin", "-y", "-framerate", "%g" % fps, "-i", os.path.join(rgb_dir, "%06d.png"),
             "-threads", "1"] + list(enc["ffmpeg_args"]) + [mp4])
        dec = os.path.join(tmp, "decoded")
        os.makedirs(dec)
        run(["ffmpeg", "-v", "error", "-nostdin", "-threads", "1", "-i", mp4, "-pix_fmt", "rgb24", "-start_number", "0",
             os.path.join(dec, "%06d.png")])
        src_dir = dec
        kbps = os.path.getsize(mp4) * 8 / 1000 / (a.frames / fps)
    else:
        src_dir = rgb_dir
    names = sorted(n for n in os.listdir(src_dir) if n.endswith(".png"))
    if len(names) != a.frames:
        raise RuntimeError("%s: %d frames after encoding, expected %d" % (name, len(names), a.frames))
    ow, oh = None, None
    for n in names:
        img = cv2.imread(os.path.join(src_dir, n), cv2.IMREAD_COLOR)
        grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
        ow, oh = grey.shape[1], grey.shape[0]
        cv2.imwrite(os.path.join(frames_dir, n), grey)
    s = ow / w
    if abs(oh / h - s) > 1e-3:
        raise RuntimeError("%s: the encoding changed the aspect (%dx%d from %dx%d)" % (name, ow, oh, w, h))
    mask_dir = os.path.join(tmp, "mask")
    os.makedirs(mask_dir)
    for n in sorted(os.listdir(os.path.join(syn, "mask"))):
        m = cv2.imread(os.path.join(syn, "mask", n), cv2.IMREAD_GRAYSCALE)
        if not np.any(m):
            continue  # a frame without a mask file has no hands
        if s != 1:
            m = cv2.resize(m, (ow, oh), interpolation=cv2.INTER_NEAREST)
        cv2.imwrite(os.path.join(mask_dir, n), m)
    encode_s = time.time() - t1
    gt = read_tum(os.path.join(syn, "camera_gt.tum"))
    shutil.copy(os.path.join(syn, "camera_gt.tum"), os.path.join(tmp, "camera_gt.tum"))
    # pixel centres at integers: x' = s (x + 0.5) - 0.5
    intr = [fx * s, fy * s, s * (cx + 0.5) - 0.5, s * (cy + 0.5) - 0.5]
    meta = {"preset": preset, "profile": profile, "seed": seed, "frames": a.frames, "width": ow, "height": oh, "fps": fps,
            "intrinsics": intr, "lens": lens, "encode": enc.get("spec", "none"), "video_kbps": kbps,
            "path_m": path_length(gt), "render_s": render_s, "encode_s": encode_s,
            "render_ms_mean": summary.get("render_ms_mean"), "subframes_mean": summary.get("subframes_mean"),
            "coverage_mean": summary.get("coverage_mean")}
    shutil.rmtree(syn)  # the lossless frames, depth and hand ground truth are not needed again
    shutil.rmtree(os.path.join(tmp, "decoded"), ignore_errors=True)
    with open(os.path.join(tmp, "meta.json"), "w") as f:
        json.dump(meta, f, indent=1)
    os.replace(tmp, out)
    return name


_readouts = {}


def profile_readout(a, profile):
    """The profile's rolling-shutter readout (seconds), from the capture.json of a one-frame render."""
    if profile not in _readouts:
        with tempfile.TemporaryDirectory() as t:
            run([a.hawor, "synth", "--preset", "walk", "--seed", "1", "--frames", "1", "--size", "64x48", "--capture", profile,
                 "--out", os.path.join(t, "s")])
            cj = os.path.join(t, "s", "capture.json")
            _readouts[profile] = json.load(open(cj))["readout_s"] if os.path.exists(cj) else 0.0
    return _readouts[profile]


def slam(a, name, masked, extra):
    d = os.path.join(a.work, name)
    with open(os.path.join(d, "meta.json")) as f:
        meta = json.load(f)
    od = os.path.join(d, "slam_masked" if masked else "slam_unmasked")
    if a.reuse_slam and os.path.exists(os.path.join(od, "result.json")):
        with open(os.path.join(od, "result.json")) as f:
            return json.load(f)
    os.makedirs(od, exist_ok=True)
    cmd = [a.hawor, "slam", "--images", os.path.join(d, "frames"), "--masks", os.path.join(d, "mask"),
           "--intrinsics", ",".join("%.10g" % x for x in meta["intrinsics"]), "--camera", meta["lens"],
           "--out", os.path.join(od, "camera.tum"), "--stats", os.path.join(od, "stats.json"), "--fps", "%g" % meta["fps"]]
    if not masked:
        cmd.append("--no-mask")
    if a.readout:
        cmd += ["--readout", "%.10g" % profile_readout(a, meta["profile"])]
    summary = json.loads(run(cmd + extra).strip().splitlines()[-1])
    est = read_tum(os.path.join(od, "camera.tum"))
    if np.all(est[:, 1:4] == est[0, 1:4]):
        # never initialised: one held pose, no Sim(3); the error of the best fit with scale 0
        gt = read_tum(os.path.join(d, "camera_gt.tum"))[:, 1:4]
        m = {"ate": float(np.mean(np.linalg.norm(gt - gt.mean(axis=0), axis=1))), "rot_mean_deg": None, "rot_max_deg": None,
             "held": True}
    else:
        m = json.loads(run([a.hawor, "metrics", "camera", "--gt", os.path.join(d, "camera_gt.tum"), "--est",
                            os.path.join(od, "camera.tum")]).strip().splitlines()[-1])
    with open(os.path.join(od, "stats.json")) as f:
        st = json.load(f)["status"]
    first = next((i for i, x in enumerate(st) if x in ("tracked", "relocalised")), None)
    res = {"name": name, "preset": meta["preset"], "profile": meta["profile"], "seed": meta["seed"],
           "mode": "masked" if masked else "unmasked", "ate_m": m["ate"], "ate_pct": 100.0 * m["ate"] / meta["path_m"],
           "rot_mean_deg": m["rot_mean_deg"], "rot_max_deg": m["rot_max_deg"], "held": bool(m.get("held")), "first_tracked": first,
           "lost": st.count("lost"), "interpolated": st.count("interpolated"), "resets": summary.get("resets"),
           "keyframes": summary.get("keyframes"), "ms_median": summary.get("median_ms_per_frame"),
           "status": "".join({"tracked": "T", "interpolated": "i", "lost": "L", "relocalised": "R"}.get(x, "?") for x in st)}
    with open(os.path.join(od, "result.json"), "w") as f:
        json.dump(res, f)
    return res


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    extra = []
    if "--" in argv:
        k = argv.index("--")
        argv, extra = argv[:k], argv[k + 1:]
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--presets", default=",".join(PRESETS))
    ap.add_argument("--profiles", default=",".join(PROFILES))
    ap.add_argument("--seeds", default="1-4")
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--model", default="default", help="the hands: default or synthetic (hawor synth --model)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "hawor_bench_slam_capture"))
    ap.add_argument("--hawor", default=os.path.join(here, "..", "build", "native-clang", "examples", "hawor"))
    ap.add_argument("--reuse-slam", action="store_true", help="reuse the SLAM results already in --work")
    ap.add_argument("--masked-only", action="store_true", help="skip the unmasked runs")
    ap.add_argument("--readout", action="store_true",
                    help="give hawor slam each profile's rolling-shutter readout (--readout S)")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    presets = [p for p in a.presets.split(",") if p]
    profiles = [p for p in a.profiles.split(",") if p]
    seeds = parse_seeds(a.seeds)
    if not os.access(a.hawor, os.X_OK):
        print("bench_slam_capture: %s is not executable (cmake --build DIR --target hawor_cli; --hawor BIN)" % a.hawor,
              file=sys.stderr)
        return 2
    os.makedirs(a.work, exist_ok=True)
    items = [(p, c, s) for p in presets for c in profiles for s in seeds]
    t0 = time.time()
    failed = []

    def prep(it):
        try:
            return prepare(a, *it)
        except Exception as e:  # noqa: BLE001 (reported, the others go on)
            failed.append("%s_%s_s%d: %s" % (it + (e,)))
            print(failed[-1], file=sys.stderr)
            return None

    with ThreadPoolExecutor(max_workers=a.jobs) as ex:
        names = list(ex.map(prep, items))
    t_prep = time.time() - t0
    jobs = [(n, m) for n in names if n for m in ([True] if a.masked_only else [True, False])]

    def go(job):
        try:
            return slam(a, job[0], job[1], extra)
        except Exception as e:  # noqa: BLE001
            failed.append("%s %s: %s" % (job[0], "masked" if job[1] else "unmasked", e))
            print(failed[-1], file=sys.stderr)
            return None

    t1 = time.time()
    with ThreadPoolExecutor(max_workers=a.jobs) as ex:
        results = [r for r in ex.map(go, jobs) if r]
    t_slam = time.time() - t1
    by = {}
    for r in results:
        by.setdefault((r["preset"], r["profile"], r["mode"]), {})[r["seed"]] = r

    def med(v):
        return float(np.median(v)) if v else float("nan")

    summary = {"seeds": seeds, "frames": a.frames, "size": a.size, "presets": presets, "profiles": profiles, "cells": {}}
    print("camera ATE in %% of the path, median over seeds %s (%d frames, %s): masked / unmasked [runs <= 1 %%]"
          % (",".join(map(str, seeds)), a.frames, a.size))
    w = max(len(p) for p in presets + ["preset"])
    cw = 22
    print("%-*s %s" % (w, "preset", " ".join("%*s" % (cw, c) for c in profiles)))
    for p in presets:
        cells = []
        for c in profiles:
            cell = {}
            for m in ("masked", "unmasked"):
                v = [r["ate_pct"] for r in by.get((p, c, m), {}).values()]
                cell[m] = {"median": med(v), "within_1pct": sum(x <= 1.0 for x in v), "runs": len(v),
                           "per_seed": {str(s): r["ate_pct"] for s, r in by.get((p, c, m), {}).items()}}
            summary["cells"]["%s/%s" % (p, c)] = cell
            um = cell["unmasked"]["median"]
            cells.append("%*s" % (cw, "%.2f / %s [%d/%d]" % (cell["masked"]["median"], "-" if np.isnan(um) else "%.2f" % um,
                                                             cell["masked"]["within_1pct"], cell["masked"]["runs"])))
        print("%-*s %s" % (w, p, " ".join(cells)))
    if HANDS_PRESET in presets and not a.masked_only:
        print("%s masked / unmasked (ratio of the mean ATEs over seeds; mean of the per-seed ratios):" % HANDS_PRESET)
        ratios = {}
        for c in profiles:
            rm = by.get((HANDS_PRESET, c, "masked"), {})
            ru = by.get((HANDS_PRESET, c, "unmasked"), {})
            common = sorted(set(rm) & set(ru))
            if not common:
                continue
            pm = np.array([rm[s]["ate_pct"] for s in common])
            pu = np.array([ru[s]["ate_pct"] for s in common])
            ratios[c] = {"ratio_of_means": float(pm.mean() / max(pu.mean(), 1e-12)),
                         "mean_of_ratios": float(np.mean(pm / np.maximum(pu, 1e-12)))}
            print("  %-12s %.2f  %.2f" % (c, ratios[c]["ratio_of_means"], ratios[c]["mean_of_ratios"]))
        summary["hands_masked_over_unmasked"] = ratios
    print("first tracked frame (median over runs, masked) and lost frames (mean):")
    for p in presets:
        row = []
        for c in profiles:
            v = list(by.get((p, c, "masked"), {}).values())
            ft = [r["first_tracked"] if r["first_tracked"] is not None else a.frames for r in v]
            row.append("%*s" % (cw, "%s / %.1f" % ("%.0f" % med(ft) if ft else "-", np.mean([r["lost"] for r in v]) if v else float("nan"))))
        print("%-*s %s" % (w, p, " ".join(row)))
    ms = [r["ms_median"] for r in results if r.get("ms_median") is not None]
    summary["ms_per_frame"] = {"median_of_run_medians": med(ms), "p95_of_run_medians": float(np.percentile(ms, 95)) if ms else None}
    print("hawor slam ms per frame (median of the runs' medians, %d runs, %d at a time): %.2f (p95 %.2f)"
          % (len(ms), a.jobs, med(ms), summary["ms_per_frame"]["p95_of_run_medians"] or float("nan")))
    moving = [p for p in presets if p in PRESETS]
    worst = max(((summary["cells"]["%s/%s" % (p, c)]["masked"]["median"], p, c) for p in moving for c in profiles), default=None)
    if worst:
        print("target: median ATE <= 1 %% on every moving preset and profile (masked): %s (highest %.2f %% on %s/%s)"
              % (worst[0] <= 1.0, worst[0], worst[1], worst[2]))
    if summary.get("hands_masked_over_unmasked"):
        hi = max(summary["hands_masked_over_unmasked"].items(), key=lambda kv: kv[1]["ratio_of_means"])
        print("target: %s masked / unmasked <= 0.9 under every profile: %s (highest %.2f on %s)"
              % (HANDS_PRESET, hi[1]["ratio_of_means"] <= 0.9, hi[1]["ratio_of_means"], hi[0]))
    print("time: rendering and encoding %.0f s (cached), SLAM %.0f s" % (t_prep, t_slam))
    summary["runs"] = results
    if failed:
        print("%d failed: %s" % (len(failed), "; ".join(failed)))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(summary, f, indent=1)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
