"""`hawor infill` end to end on hand files written here with numpy:
- every method keeps the observed frames bit for bit, marks exactly the missing frames in
  <prefix>filled, keeps the file's layouts ((T,45) or (T,15,3) hand_pose, the valid array) and
  copies the keys without a hand prefix;
- `--method lerp` equals an independent numpy/scipy LERP + Slerp (np.interp, scipy's Slerp; ends
  held) to 1e-9, with and without --model (the canonical space does not change it);
- `--method last` holds the last observed frame; `--method spline` reproduces a linear
  translation and a constant angular velocity exactly and beats LERP on a smooth motion;
- `--joints --model FILE` equals the numpy MANO forward pass (tests/ref/hand_forward.py) of the
  output parameters, right and (mirrored) left;
- a hand with no observed frame is written unchanged with a note on stderr, one observed frame
  is held, a fully observed hand is unchanged; 72-column poses and no betas (the WebXR hand) work;
- `--smooth` moves observed frames by at most 1 cm on jittery input and leaves missing ones to
  the fill;
- `--method transformer` with random weights of the official sizes written here (names and shapes
  from the README's table): observed frames bit for bit, exactly the missing frames filled (both
  hands, one hand absent, a window where one hand is never seen), output unlike LERP, 1 and 2
  threads equal up to float rounding; a truncated weights file, a missing tensor, a wrong shape,
  non-MANO hands and bad --threads give errors naming the problem;
- bad input (missing key, wrong shape, NaN in an observed frame, valid not 0/1, different frame
  counts, no hand) and bad usage (unknown method, --weights without transformer, --joints without
  --model, transformer without --weights) exit non-zero with a message naming the problem.
Run: /usr/bin/python3 test_infill_cli.py path/to/hawor
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "ref"))
import hand_forward as hf  # noqa: E402
import hand_make_mano as hm  # noqa: E402

import cliutil  # noqa: E402  (tests/cli: check, finish)
from cliutil import check  # noqa: E402

HAWOR = os.path.abspath(sys.argv[1])
T = 150


def run(*args):
    p = subprocess.run([HAWOR, *args], capture_output=True, text=True, timeout=120)
    return p.returncode, p.stdout, p.stderr


def smooth_hand(rng, T, K=15, B=10):
    """Sums of sinusoids: trans (T,3), rot (T,3), hand_pose (T,3K); betas constant."""
    t = np.arange(T)[:, None]

    def waves(n, amp):
        p = rng.uniform(40, 150, (2, n))
        ph = rng.uniform(0, 6.28, (2, n))
        return amp * (np.sin(2 * np.pi * t / p[0] + ph[0]) + 0.4 * np.sin(2 * np.pi * t / p[1] + ph[1]))

    return {"trans": waves(3, 0.2) + np.array([0.1, 0.2, 0.4]), "rot": waves(3, 0.7),
            "hand_pose": waves(3 * K, 0.3), "betas": np.tile(rng.normal(0, 1, B), (T, 1))}


def mask(T, gaps):
    v = np.ones(T, bool)
    for a, b in gaps:
        v[a:b] = False
    return v


def write(path, hands, extra=None, nan=True):
    arrays = dict(extra or {})
    for side, h in hands.items():
        for k, v in h.items():
            a = np.array(v, dtype=np.float64) if k != "valid" else np.asarray(v)
            if nan and k in ("trans", "rot", "hand_pose") and k != "valid":
                a = a.copy()
                a[~np.asarray(h["valid"]).astype(bool)] = np.nan
            arrays[side + "_" + k] = a
    np.savez(path, **arrays)


def np_lerp(x, valid):
    """np.interp per column (ends held)."""
    idx = np.flatnonzero(valid)
    return np.stack([np.interp(np.arange(len(x)), idx, x[idx, c]) for c in range(x.shape[1])], 1)


def np_slerp(rv, valid):
    """scipy Slerp per triple between observed frames, ends held."""
    idx = np.flatnonzero(valid)
    out = np.array(rv, dtype=np.float64)
    K = rv.shape[1] // 3
    t = np.arange(len(rv))
    for k in range(K):
        r = Rotation.from_rotvec(rv[idx, 3 * k:3 * k + 3])
        inner = (t > idx[0]) & (t < idx[-1]) & ~valid
        if inner.any():
            out[inner, 3 * k:3 * k + 3] = Slerp(idx, r)(t[inner]).as_rotvec()
        out[t < idx[0], 3 * k:3 * k + 3] = rv[idx[0], 3 * k:3 * k + 3]
        out[t > idx[-1], 3 * k:3 * k + 3] = rv[idx[-1], 3 * k:3 * k + 3]
    return out


def rot_dist(a, b):
    """Largest angle between the rotations of two (T,3K) axis-angle arrays."""
    ra = Rotation.from_rotvec(a.reshape(-1, 3))
    rb = Rotation.from_rotvec(b.reshape(-1, 3))
    return np.abs((ra.inv() * rb).magnitude()).max()


def infill(tmp, name, hands, *args, extra=None):
    fin, fout = os.path.join(tmp, name + "_in.npz"), os.path.join(tmp, name + "_out.npz")
    write(fin, hands, extra)
    rc, out, err = run("infill", "--in", fin, "--out", fout, *args)
    if rc != 0:
        check(name + " runs", False, err)
        return None, None, err
    return dict(np.load(fout)), json.loads(out), err


def basic_cases(tmp, rng):
    left, right = smooth_hand(rng, T), smooth_hand(rng, T)
    left["valid"] = mask(T, [(0, 5), (30, 50), (100, 101), (140, 150)])
    right["valid"] = mask(T, [(60, 120)]).astype(np.uint8)
    right["hand_pose"] = right["hand_pose"].reshape(T, 15, 3)
    extra = {"timestamps": np.arange(T) / 30.0}
    for method in ("last", "lerp", "spline"):
        o, summary, _ = infill(tmp, method, {"left": left, "right": right}, "--method", method, extra=extra)
        if o is None:
            continue
        check(method + " summary", summary["method"] == method and summary["left"]["filled"] == 36 and
              summary["right"]["filled"] == 60 and summary["right"]["valid"] == 90, summary)
        check(method + " timestamps copied", np.array_equal(o["timestamps"], extra["timestamps"]))
        check(method + " pose layouts kept", o["left_hand_pose"].shape == (T, 45) and
              o["right_hand_pose"].shape == (T, 15, 3), (o["left_hand_pose"].shape, o["right_hand_pose"].shape))
        check(method + " valid copied", o["right_valid"].dtype == np.uint8 and
              np.array_equal(o["right_valid"], right["valid"]))
        for side, h in (("left", left), ("right", right)):
            v = np.asarray(h["valid"]).astype(bool)
            f = o[side + "_filled"]
            check("%s %s filled = missing" % (method, side), f.dtype == np.bool_ and np.array_equal(f, ~v))
            for k in ("trans", "rot", "hand_pose", "betas"):
                a, b = o[side + "_" + k].reshape(T, -1), np.asarray(h[k], np.float64).reshape(T, -1)
                check("%s %s %s observed bit for bit" % (method, side, k), np.array_equal(a[v], b[v]))
                check("%s %s %s filled finite" % (method, side, k), np.isfinite(a).all())
        if method == "lerp":
            for side, h in (("left", left), ("right", right)):
                v = np.asarray(h["valid"]).astype(bool)
                e_t = np.abs(o[side + "_trans"] - np_lerp(h["trans"], v)).max()
                e_b = np.abs(o[side + "_betas"] - np_lerp(h["betas"], v)).max()
                e_r = rot_dist(o[side + "_rot"], np_slerp(h["rot"], v))
                e_p = rot_dist(o[side + "_hand_pose"].reshape(T, -1), np_slerp(h["hand_pose"].reshape(T, -1), v))
                check("lerp %s = numpy/scipy" % side, max(e_t, e_b, e_r, e_p) < 1e-9, (e_t, e_b, e_r, e_p))
        if method == "last":
            # (held in canonical space: equal up to the rounding of the round trip)
            check("last holds", np.abs(o["left_trans"][30:50] - left["trans"][29]).max() < 1e-12 and
                  np.abs(o["left_trans"][:5] - left["trans"][5]).max() < 1e-12)
    # the spline beats LERP on this smooth motion (translation error over the filled frames)
    errs = {}
    for method in ("lerp", "spline"):
        o, _, _ = infill(tmp, "cmp_" + method, {"left": left, "right": right}, "--method", method)
        if o is not None:
            miss = ~right["valid"].astype(bool)
            errs[method] = np.linalg.norm(o["right_trans"][miss] - right["trans"][miss], axis=1).mean()
    check("spline beats lerp", len(errs) == 2 and errs["spline"] < errs["lerp"], errs)


def exact_cases(tmp):
    """Linear translation and constant angular velocity (global and joints): spline exact."""
    t = np.arange(T)[:, None]
    r0 = Rotation.from_rotvec([0.3, 1.1, -0.4])
    w = np.array([0.004, -0.006, 0.003])
    rot = (r0 * Rotation.from_rotvec(t * w)).as_rotvec()
    pose = np.concatenate([(Rotation.from_rotvec([0.05 * j, -0.3, 0.1]) *
                            Rotation.from_rotvec(t * w[::-1] * 0.1 * (j + 1))).as_rotvec() for j in range(15)], 1)
    h = {"trans": 0.1 + t * np.array([0.002, -0.001, 0.0015]), "rot": rot, "hand_pose": pose,
         "betas": np.zeros((T, 10)), "valid": mask(T, [(20, 21), (40, 52), (70, 140)])}
    o, _, _ = infill(tmp, "exact", {"right": h}, "--method", "spline")
    if o is not None:
        e = (np.abs(o["right_trans"] - h["trans"]).max(), rot_dist(o["right_rot"], rot),
             rot_dist(o["right_hand_pose"], pose))
        check("spline exact on linear / constant-rate motion", max(e) < 1e-9, e)
        check("only the right hand written", not any(k.startswith("left_") for k in o), list(o))


def model_cases(tmp, rng):
    """--model FILE and --joints against the numpy MANO forward pass (right and mirrored left)."""
    right_model = hm.make_right()
    left_model = hm.mirror(right_model)
    path = os.path.join(tmp, "mano_right.npz")
    hm.dump_npz(right_model, path, compressed=False)
    left, right = smooth_hand(rng, 60), smooth_hand(rng, 60)
    left["valid"] = mask(60, [(10, 30)])
    right["valid"] = mask(60, [(0, 3), (40, 45)])
    o, _, _ = infill(tmp, "joints", {"left": left, "right": right}, "--method", "lerp", "--model", path, "--joints")
    o2, _, _ = infill(tmp, "nomodel", {"left": left, "right": right}, "--method", "lerp")
    if o is None or o2 is None:
        return
    for side, model in (("left", left_model), ("right", right_model)):
        p = side + "_"
        j = o[p + "joints_world"]
        ok = j.shape == (60, 21, 3)
        worst = 0.0
        for t in range(60):
            pz = np.concatenate([o[p + "rot"][t][None], o[p + "hand_pose"][t].reshape(15, 3)], 0)
            kp = hf.mano_forward(model, pz, o[p + "betas"][t], o[p + "trans"][t])[2]
            worst = max(worst, np.abs(kp - j[t]).max())
        check(side + " --joints = numpy forward", ok and worst < 1e-9, (j.shape, worst))
        same = max(np.abs(o[p + "trans"] - o2[p + "trans"]).max(), rot_dist(o[p + "rot"], o2[p + "rot"]))
        check(side + " --model does not change lerp", same < 1e-9, same)


def edge_cases(tmp, rng):
    h = smooth_hand(rng, 40)
    none = dict(h, valid=np.zeros(40, bool))
    one = dict(h, valid=np.eye(1, 40, 17)[0].astype(bool))
    full = dict(h, valid=np.ones(40, bool))
    o, s, err = infill(tmp, "edges", {"left": none, "right": one})
    if o is not None:
        check("no valid: note on stderr", "left hand: no observed frame" in err, err)
        check("no valid: unchanged", np.isnan(o["left_trans"]).all() and not o["left_filled"].any() and
              s["left"]["filled"] == 0)
        check("one valid: held", np.allclose(o["right_trans"], h["trans"][17], atol=1e-12, rtol=0) and
              rot_dist(o["right_rot"], np.tile(h["rot"][17], (40, 1))) < 1e-9 and o["right_filled"].sum() == 39)
    o, s, _ = infill(tmp, "full", {"left": full})
    if o is not None:
        check("all valid: unchanged", np.array_equal(o["left_trans"], h["trans"]) and
              np.array_equal(o["left_hand_pose"], h["hand_pose"]) and not o["left_filled"].any())
    webxr = smooth_hand(rng, 40, K=24, B=0)
    webxr["valid"] = mask(40, [(10, 20)])
    o, _, _ = infill(tmp, "webxr", {"right": webxr})
    if o is not None:
        check("72-column pose, no betas", o["right_hand_pose"].shape == (40, 72) and o["right_betas"].shape == (40, 0)
              and np.isfinite(o["right_hand_pose"]).all())


def smooth_cases(tmp, rng):
    h = smooth_hand(rng, T)
    h["valid"] = mask(T, [(50, 80)])
    truth = h["trans"].copy()
    h["trans"] = h["trans"] + rng.normal(0, 0.003, (T, 3))
    o, s, _ = infill(tmp, "smooth", {"right": h}, "--smooth")
    if o is not None:
        v = h["valid"]
        moved = np.linalg.norm(o["right_trans"][v] - h["trans"][v], axis=1)
        check("--smooth summary", s["smooth"] is True)
        check("--smooth bounded", moved.max() <= 0.01 + 1e-12, moved.max())
        check("--smooth moves observed frames", moved.max() > 1e-4, moved.max())
        before = np.linalg.norm(h["trans"][v] - truth[v], axis=1).mean()
        after = np.linalg.norm(o["right_trans"][v] - truth[v], axis=1).mean()
        check("--smooth reduces jitter", after < 0.8 * before, (before, after))
        check("--smooth fills the gap", o["right_filled"].sum() == 30 and np.isfinite(o["right_trans"]).all())


def error_cases(tmp, rng):
    h = smooth_hand(rng, 20)
    h["valid"] = mask(20, [(5, 8)])
    good = os.path.join(tmp, "good.npz")
    write(good, {"left": h})
    out = os.path.join(tmp, "err_out.npz")

    def bad(name, arrays, needle, code=1, args=()):
        f = os.path.join(tmp, "bad_%s.npz" % "".join(c if c.isalnum() else "_" for c in name))
        np.savez(f, **arrays)
        rc, _, err = run("infill", "--in", f, "--out", out, *args)
        check("error: " + name, rc == code and needle in err, (rc, err))

    base = {"left_" + k: np.asarray(v, np.float64) if k != "valid" else v for k, v in h.items()}
    bad("missing key", {k: v for k, v in base.items() if k != "left_betas"}, "left_betas")
    bad("wrong shape", dict(base, left_trans=base["left_trans"][:, :2]), "left_trans")
    bad("pose not 3K", dict(base, left_hand_pose=base["left_hand_pose"][:, :44]), "hand_pose")
    nan = dict(base)
    nan["left_rot"] = base["left_rot"].copy()
    nan["left_rot"][2, 1] = np.nan
    bad("nan in observed frame", nan, "frame 2")
    bad("valid not 0/1", dict(base, left_valid=np.full(20, 2.0)), "0/1")
    right = {"right_" + k[5:]: v[:15] for k, v in base.items()}
    bad("frame counts differ", dict(base, **right), "frames")
    bad("no hand", {"timestamps": np.zeros(3)}, "no hand")
    rc, _, err = run("infill", "--in", os.path.join(tmp, "nope.npz"), "--out", out)
    check("error: missing file", rc == 1 and "nope.npz" in err, (rc, err))
    for name, args, code, needle in [
            ("unknown method", ["--method", "cubic"], 2, "--method"),
            ("weights without transformer", ["--weights", "w.npz"], 2, "--weights"),
            ("joints without model", ["--joints"], 2, "--model"),
            ("transformer without weights", ["--method", "transformer"], 2, "--weights"),
            ("threads without transformer", ["--threads", "2"], 2, "--threads"),
            ("missing --out", None, 2, "--out")]:
        cmd = ["infill", "--in", good] + (["--out", out] + args if args is not None else [])
        rc, _, err = run(*cmd)
        check("usage: " + name, rc == code and needle in err, (rc, err))
    rc, out_help, _ = run("infill", "--help")
    check("help", rc == 0 and "--method" in out_help and "filled" in out_help)


def infiller_weights(rng, D=384, H=2048, F=218, layers=8):
    """Random float32 weights of the official infiller, named as the README's tensor table."""
    w = {"input_layer.weight": (D, F + 1), "input_layer.bias": (D,),
         "layer_norm.weight": (D,), "layer_norm.bias": (D,), "decoder.weight": (F, D), "decoder.bias": (F,)}
    for i in range(layers):
        a, p, e = "att_layers.%d." % i, "pff_layers.%d." % i, "transformer_encoder.layers.%d." % i
        w.update({a + n: (D, D) for n in ("q_linear.weight", "k_linear.weight", "v_linear.weight",
                                          "out_linear.weight")})
        w.update({a + "layer_norm.weight": (D,), a + "layer_norm.bias": (D,),
                  p + "layer_norm.weight": (D,), p + "layer_norm.bias": (D,),
                  p + "network.0.weight": (H, D), p + "network.0.bias": (H,),
                  p + "network.3.weight": (D, H), p + "network.3.bias": (D,),
                  e + "self_attn.in_proj_weight": (3 * D, D), e + "self_attn.in_proj_bias": (3 * D,),
                  e + "self_attn.out_proj.weight": (D, D), e + "self_attn.out_proj.bias": (D,),
                  e + "linear1.weight": (H, D), e + "linear1.bias": (H,),
                  e + "linear2.weight": (D, H), e + "linear2.bias": (D,),
                  e + "norm1.weight": (D,), e + "norm1.bias": (D,), e + "norm2.weight": (D,), e + "norm2.bias": (D,)})
    out = {}
    for name, shape in w.items():
        if "norm" in name:
            v = rng.uniform(-0.1, 0.1, shape) + (1.0 if name.endswith("weight") else 0.0)
        else:
            b = 1.0 / np.sqrt(shape[1] if len(shape) == 2 else D)
            v = rng.uniform(-b, b, shape)
        out[name] = v.astype(np.float32)
    return out


def transformer_cases(tmp, rng):
    weights = os.path.join(tmp, "infiller.npz")
    w = infiller_weights(rng)
    np.savez(weights, **w)
    Tn = 200  # two windows, the second padded
    left, right = smooth_hand(rng, Tn), smooth_hand(rng, Tn)
    left["valid"] = mask(Tn, [(20, 50), (130, 140)])
    right["valid"] = mask(Tn, [(0, 5), (60, 75), (120, 200)])  # never seen in the second window
    o, s, _ = infill(tmp, "tr2", {"left": left, "right": right}, "--method", "transformer",
                     "--weights", weights, "--threads", "2")
    lerp, _, _ = infill(tmp, "tr_lerp", {"left": left, "right": right}, "--method", "lerp")
    if o is None or lerp is None:
        return
    check("transformer summary", s["method"] == "transformer" and s["threads"] == 2, s)
    for side, h in (("left", left), ("right", right)):
        p, v = side + "_", h["valid"]
        same = all(np.array_equal(o[p + k][v], np.asarray(h[k], np.float64)[v]) for k in ("trans", "rot", "hand_pose"))
        check(side + ": transformer keeps observed frames bit for bit", same)
        check(side + ": transformer fills exactly the missing frames", np.array_equal(o[p + "filled"], ~v))
        check(side + ": transformer fills are finite", all(np.isfinite(o[p + k]).all() for k in ("trans", "rot", "hand_pose", "betas")))
        diff = np.abs(o[p + "trans"][~v] - lerp[p + "trans"][~v]).max()
        check(side + ": transformer output is not LERP", diff > 1e-3, diff)
    o1, _, _ = infill(tmp, "tr1", {"left": left, "right": right}, "--method", "transformer",
                      "--weights", weights, "--threads", "1")
    if o1 is not None:
        d = max(np.abs(o1[side + "_" + k] - o[side + "_" + k]).max() for side in ("left", "right")
                for k in ("trans", "rot", "hand_pose"))
        check("transformer: 1 and 2 threads agree (float rounding)", d < 1e-3, d)
    one, s1, _ = infill(tmp, "tr_one", {"right": right}, "--method", "transformer", "--weights", weights)
    if one is not None:
        check("transformer: one hand", np.array_equal(one["right_filled"], ~right["valid"]) and
              not any(k.startswith("left_") for k in one) and np.isfinite(one["right_trans"]).all(), s1)
    # errors: non-MANO hands, broken weight files, bad --threads
    webxr = smooth_hand(rng, 40, K=24, B=0)
    webxr["valid"] = mask(40, [(10, 20)])
    f = os.path.join(tmp, "tr_webxr.npz")
    write(f, {"right": webxr})
    rc, _, err = run("infill", "--in", f, "--out", os.path.join(tmp, "x.npz"), "--method", "transformer",
                     "--weights", weights)
    check("transformer: non-MANO hands rejected", rc == 1 and "MANO" in err, (rc, err))
    good = os.path.join(tmp, "tr_good.npz")
    write(good, {"left": left})
    trunc = os.path.join(tmp, "trunc.npz")
    with open(weights, "rb") as src, open(trunc, "wb") as dst:
        dst.write(src.read(5_000_000))
    missing = os.path.join(tmp, "missing.npz")
    np.savez(missing, **{k: v for k, v in w.items() if k != "att_layers.3.q_linear.weight"})
    shape = os.path.join(tmp, "shape.npz")
    np.savez(shape, **dict(w, **{"decoder.bias": w["decoder.bias"][:100]}))
    for name, path, needle in [("truncated weights", trunc, "trunc.npz"),
                               ("missing tensor", missing, "att_layers.3.q_linear.weight"),
                               ("wrong shape", shape, "decoder.bias")]:
        rc, _, err = run("infill", "--in", good, "--out", os.path.join(tmp, "x.npz"), "--method", "transformer",
                         "--weights", path)
        check("transformer: " + name, rc == 1 and needle in err, (rc, err[:300]))
    for bad_threads in ("0", "1.5", "x"):
        rc, _, err = run("infill", "--in", good, "--out", os.path.join(tmp, "x.npz"), "--method", "transformer",
                         "--weights", weights, "--threads", bad_threads)
        check("transformer: --threads " + bad_threads, rc == 2 and "--threads" in err, (rc, err))


def main():
    tmp = tempfile.mkdtemp(prefix="hawor_infill_cli_")
    rng = np.random.default_rng(6)
    try:
        basic_cases(tmp, rng)
        exact_cases(tmp)
        model_cases(tmp, rng)
        edge_cases(tmp, rng)
        smooth_cases(tmp, rng)
        error_cases(tmp, rng)
        transformer_cases(tmp, rng)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return cliutil.finish()


if __name__ == "__main__":
    sys.exit(main())
