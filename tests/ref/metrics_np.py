"""Reference implementation (numpy) of the evaluation metrics of docs/design.md §8.

Written from the definitions, independently of include/hawor/eval; used by the C++ cross-check
(tests/ref/eval_metrics.py) and by CLI tests. Import with tests/ref on sys.path:

    import metrics_np as M
    M.pa_mpjpe(gt_cam, est_cam)            # mm

Conventions
- Joint arrays are (T, J, 3) in metres (J = 21 for hands); camera positions are (T, 3) in metres.
- `valid` is an optional length-T boolean array; None means every frame is valid.
- Lengths are returned in millimetres, RTE in percent, accel in m/s^2, AUC in [0, 1].
- Rules for `valid` (the C++ library follows the same ones):
  * PA-MPJPE / AUC: only valid frames.
  * W-MPJPE / WA-MPJPE: chunks of 100 frames in the ORIGINAL frame indexing; inside a chunk only
    its valid frames are used (W fits on the first two valid frames of the chunk); chunks without
    a valid frame are skipped; the mean is over all frames' joint errors (not a mean of chunks).
  * RTE: the valid frames form the track (path length over consecutive valid frames).
  * Accel: the second difference centred on frame t counts only if t-1, t, t+1 are all valid.
- Undefined values (no sample, zero ground-truth path length) are NaN.
"""
import numpy as np

M2MM = 1000.0
CHUNK = 100          # W-MPJPE / WA-MPJPE chunk length (frames)
CAMERA_PART = 1000   # rigid camera alignment part length before world metrics (frames)


def umeyama(src, dst, with_scale=True):
    """Least-squares similarity (s, R, t) with dst ~ s R src + t; src, dst (N, 3).

    Umeyama (1991): covariance of the centred sets, SVD, reflection fix on the smallest singular
    direction; the scale is trace(D S) / (mean squared norm of centred src).
    """
    src = np.asarray(src, dtype=np.float64).reshape(-1, 3)
    dst = np.asarray(dst, dtype=np.float64).reshape(-1, 3)
    mu_s = src.mean(axis=0)
    mu_d = dst.mean(axis=0)
    xs = src - mu_s
    xd = dst - mu_d
    sigma = xd.T @ xs / src.shape[0]
    u, d, vt = np.linalg.svd(sigma)
    fix = np.ones(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        fix[2] = -1.0
    R = u @ np.diag(fix) @ vt
    if with_scale:
        var_s = (xs ** 2).sum() / src.shape[0]
        s = (d * fix).sum() / var_s
    else:
        s = 1.0
    t = mu_d - s * R @ mu_s
    return s, R, t


def apply_sim(s, R, t, pts):
    return s * np.einsum("ij,...j->...i", R, pts) + t


def _mask(valid, T):
    if valid is None:
        return np.ones(T, dtype=bool)
    valid = np.asarray(valid).astype(bool).reshape(-1)
    assert valid.shape[0] == T
    return valid


def pa_errors(gt, pred, valid=None):
    """Per-joint errors (n_valid, J) in mm after per-frame similarity Procrustes."""
    gt = np.asarray(gt, dtype=np.float64)
    pred = np.asarray(pred, dtype=np.float64)
    keep = _mask(valid, gt.shape[0])
    out = []
    for g, p in zip(gt[keep], pred[keep]):
        s, R, t = umeyama(p, g, True)
        out.append(np.linalg.norm(apply_sim(s, R, t, p) - g, axis=-1))
    return np.array(out) * M2MM


def pa_mpjpe(gt, pred, valid=None):
    e = pa_errors(gt, pred, valid)
    return float(e.mean()) if e.size else float("nan")


def auc(gt, pred, valid=None, lo=0.0, hi=50.0, steps=100):
    """Area under the PCK curve of the PA-aligned joint errors, thresholds linspace(0, 50, 100) mm.

    PCK per keypoint (fraction of frames with error <= threshold), averaged over keypoints;
    area by the trapezoid rule divided by the threshold range (so a perfect curve gives 1).
    """
    e = pa_errors(gt, pred, valid)
    if e.size == 0:
        return float("nan")
    th = np.linspace(lo, hi, steps)
    pck = np.array([(e <= x).mean(axis=0).mean() for x in th])
    return float(np.trapz(pck, th) / np.trapz(np.ones_like(th), th))


def _chunk_errors(gt, pred, valid, first_two):
    gt = np.asarray(gt, dtype=np.float64)
    pred = np.asarray(pred, dtype=np.float64)
    T = gt.shape[0]
    keep = _mask(valid, T)
    errs = []
    for start in range(0, T, CHUNK):
        idx = np.arange(start, min(T, start + CHUNK))
        idx = idx[keep[idx]]
        if idx.size == 0:
            continue
        g, p = gt[idx], pred[idx]
        fit = slice(0, 2) if first_two else slice(None)
        s, R, t = umeyama(p[fit].reshape(-1, 3), g[fit].reshape(-1, 3), True)
        errs.append(np.linalg.norm(apply_sim(s, R, t, p) - g, axis=-1).ravel())
    if not errs:
        return np.zeros(0)
    return np.concatenate(errs) * M2MM


def w_mpjpe(gt, pred, valid=None):
    """World MPJPE (mm): per 100-frame chunk, similarity fitted on the chunk's first 2 frames."""
    e = _chunk_errors(gt, pred, valid, True)
    return float(e.mean()) if e.size else float("nan")


def wa_mpjpe(gt, pred, valid=None):
    """World-aligned MPJPE (mm): per 100-frame chunk, similarity fitted on the whole chunk."""
    e = _chunk_errors(gt, pred, valid, False)
    return float(e.mean()) if e.size else float("nan")


def rte(gt, pred, valid=None):
    """Root translation error (%): rigid (no scale) alignment of the joint-0 track, per-frame error
    divided by the ground-truth path length, times 100, averaged over frames."""
    gt = np.asarray(gt, dtype=np.float64)
    pred = np.asarray(pred, dtype=np.float64)
    keep = _mask(valid, gt.shape[0])
    g = gt[keep, 0, :]
    p = pred[keep, 0, :]
    if g.shape[0] == 0:
        return float("nan")
    path = np.linalg.norm(np.diff(g, axis=0), axis=-1).sum()
    if not path > 0:
        return float("nan")
    _, R, t = umeyama(p, g, False)
    err = np.linalg.norm(apply_sim(1.0, R, t, p) - g, axis=-1)
    return float((err / path).mean() * 100.0)


def accel(gt, pred, valid=None, fps=30.0):
    """Acceleration error (m/s^2): || d2 pred - d2 gt || per joint, mean over joints and over the
    second-difference samples (first and last frame dropped), times fps^2."""
    gt = np.asarray(gt, dtype=np.float64)
    pred = np.asarray(pred, dtype=np.float64)
    T = gt.shape[0]
    keep = _mask(valid, T)
    if T < 3:
        return float("nan")
    a_gt = gt[:-2] - 2.0 * gt[1:-1] + gt[2:]
    a_pr = pred[:-2] - 2.0 * pred[1:-1] + pred[2:]
    per = np.linalg.norm(a_pr - a_gt, axis=-1).mean(axis=-1)
    ok = keep[:-2] & keep[1:-1] & keep[2:]
    if not ok.any():
        return float("nan")
    return float(per[ok].mean() * fps * fps)


def ate(gt_pos, est_pos):
    """Camera ATE (mm) after Sim(3) Umeyama alignment of positions; returns (ate, scale)."""
    s, R, t = umeyama(est_pos, gt_pos, True)
    err = np.linalg.norm(apply_sim(s, R, t, np.asarray(est_pos)) - gt_pos, axis=-1)
    return float(err.mean() * M2MM), float(s)


def ate_s(gt_pos, est_pos):
    """Camera ATE-S (mm) after SE(3) alignment (no scale): sensitive to the metric scale."""
    _, R, t = umeyama(est_pos, gt_pos, False)
    err = np.linalg.norm(apply_sim(1.0, R, t, np.asarray(est_pos)) - gt_pos, axis=-1)
    return float(err.mean() * M2MM)


def rotation_errors(gt_R, est_R):
    """Camera rotation error (degrees) after the best global rotation A of the estimate's world.

    A minimises sum |A E_t - G_t|_F^2 = sum |A - G_t E_t^T|_F^2: the chordal L2 mean of the
    rotations G_t E_t^T, here by scipy's Rotation.mean (Markley's quaternion eigenvector method,
    not an SVD). Frame t's error is the angle of G_t^T A E_t. Returns (mean, max, A)."""
    from scipy.spatial.transform import Rotation
    gt_R = np.asarray(gt_R, dtype=np.float64).reshape(-1, 3, 3)
    est_R = np.asarray(est_R, dtype=np.float64).reshape(-1, 3, 3)
    A = Rotation.from_matrix(np.einsum("tij,tkj->tik", gt_R, est_R)).mean().as_matrix()
    err = Rotation.from_matrix(np.einsum("tji,jk,tkl->til", gt_R, A, est_R)).magnitude()
    deg = np.degrees(err)
    return float(deg.mean()), float(deg.max()), A


def camera_part_alignment(gt_pos, est_pos, part=CAMERA_PART):
    """Rigid (no scale) alignment of estimated to ground-truth camera positions per `part` frames.
    Returns per-frame (R (T,3,3), t (T,3)) to apply to estimated world points of that frame.
    A trailing part shorter than 3 frames (rotation undetermined) reuses the previous part's fit."""
    gt_pos = np.asarray(gt_pos, dtype=np.float64)
    est_pos = np.asarray(est_pos, dtype=np.float64)
    T = gt_pos.shape[0]
    Rs = np.zeros((T, 3, 3))
    ts = np.zeros((T, 3))
    R = t = None
    for start in range(0, T, part):
        sl = slice(start, min(T, start + part))
        if sl.stop - start >= 3 or R is None:
            _, R, t = umeyama(est_pos[sl], gt_pos[sl], False)
        Rs[sl] = R
        ts[sl] = t
    return Rs, ts


def apply_part_alignment(Rs, ts, pts):
    """Applies per-frame rigid transforms to (T, J, 3) points."""
    return np.einsum("tij,tnj->tni", Rs, pts) + ts[:, None, :]
