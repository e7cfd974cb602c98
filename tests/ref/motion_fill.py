"""Reference for motion/sequence.hpp and motion/prefill.hpp: gap filling with a validity mask.

Rules (docs/design.md §7 pre-fill and the paper's last-pose baseline), implemented here with numpy and
scipy's Slerp independently of the C++ code:
  linear     interior gap between valid a < b: x_t = x_a + (t-a)/(b-a) (x_b - x_a)
  rotations  the same fraction, scipy Slerp per axis-angle triple
  last pose  a gap repeats the last valid frame before it
  leading gaps hold the first valid frame, trailing gaps the last one (all rules).
A HandMotion-shaped set (rot T x 3, trans T x 3, hand_pose T x 45, betas T x 10) is also filled:
trans/betas linearly, rot/hand_pose by SLERP.
"""
import sys

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

import refio

rng = np.random.default_rng(7)


def fill_linear(x, valid):
    out = x.copy()
    idx = np.flatnonzero(valid)
    for t in np.flatnonzero(~valid):
        prev = idx[idx < t]
        nxt = idx[idx > t]
        if prev.size == 0:
            out[t] = x[nxt[0]]
        elif nxt.size == 0:
            out[t] = x[prev[-1]]
        else:
            a, b = prev[-1], nxt[0]
            f = (t - a) / (b - a)
            out[t] = x[a] + f * (x[b] - x[a])
    return out


def fill_rot(x, valid):
    out = x.copy()
    idx = np.flatnonzero(valid)
    K = x.shape[1] // 3
    for t in np.flatnonzero(~valid):
        prev = idx[idx < t]
        nxt = idx[idx > t]
        if prev.size == 0:
            out[t] = x[nxt[0]]
        elif nxt.size == 0:
            out[t] = x[prev[-1]]
        else:
            a, b = prev[-1], nxt[0]
            for k in range(K):
                sl = slice(3 * k, 3 * k + 3)
                s = Slerp([a, b], Rotation.from_rotvec(np.stack([x[a, sl], x[b, sl]])))
                out[t, sl] = s([t]).as_rotvec()[0]
    return out


def fill_last(x, valid):
    out = x.copy()
    idx = np.flatnonzero(valid)
    for t in np.flatnonzero(~valid):
        prev = idx[idx < t]
        out[t] = x[prev[-1]] if prev.size else x[idx[0]]
    return out


def main(out):
    T = 60
    valid = np.ones(T, dtype=bool)
    valid[:4] = False          # leading gap
    valid[10] = False          # single-frame gap
    valid[20:31] = False       # long gap
    valid[40:42] = False
    valid[55:] = False         # trailing gap
    lin = rng.normal(size=(T, 5))
    rot = rng.normal(size=(T, 6)) * 1.2  # two axis-angle triples, angles up to ~pi
    invalid_content = rng.normal(size=(T, 1)) * 100.0
    lin_in = np.where(valid[:, None], lin, invalid_content)
    rot_in = np.where(valid[:, None], rot, 0.0)

    hand = dict(
        h_rot=rng.normal(size=(T, 3)),
        h_trans=rng.normal(size=(T, 3)) * 0.3,
        h_pose=rng.normal(size=(T, 45)) * 0.5,
        h_betas=rng.normal(size=(T, 10)),
    )
    for k in hand:
        hand[k][~valid] = 0.0

    refio.save(
        out,
        valid=valid.astype(float),
        lin=lin_in,
        rot=rot_in,
        lin_linear=fill_linear(lin_in, valid),
        lin_last=fill_last(lin_in, valid),
        rot_slerp=fill_rot(rot_in, valid),
        rot_last=fill_last(rot_in, valid),
        **hand,
        h_rot_fill=fill_rot(hand["h_rot"], valid),
        h_trans_fill=fill_linear(hand["h_trans"], valid),
        h_pose_fill=fill_rot(hand["h_pose"], valid),
        h_betas_fill=fill_linear(hand["h_betas"], valid),
    )


if __name__ == "__main__":
    main(sys.argv[1])
