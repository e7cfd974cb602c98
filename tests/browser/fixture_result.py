#!/usr/bin/python3
"""Test fixture: a `hawor synth` sequence's ground truth written as a result.json of the app
(the pipeline's result shape, version 1), so that the views, the "open a result.json" path and the
glTF export can be tested on known data independently of the pipeline.

    /usr/bin/python3 tests/browser/fixture_result.py SYNTH_DIR OUT.json [--infill-every N]

Frames where a hand is not visible are marked infilled (their pose is the ground truth); with
--infill-every N every N-th visible frame is also marked infilled (to exercise that drawing).
The points are 400 back-projected pixels of frame 0's depth map."""
import json
import sys

import numpy as np


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    src, out = args[0], args[1]
    every = int(args[args.index('--infill-every') + 1]) if '--infill-every' in args else 0
    intr = open(f'{src}/intrinsics.txt').read().splitlines()
    fx, fy, cx, cy, w, h, fps = intr[0].split()
    lens = [l.split() for l in intr[1:] if l.startswith('lens ')]
    if lens and lens[0][1] != 'pinhole':  # hawor synth --capture with a lens: the projections below are pinhole
        print(f'fixture_result: {src} has lens {lens[0][1]}; the fixture needs a pinhole sequence', file=sys.stderr)
        return 2
    fx, fy, cx, cy, fps = float(fx), float(fy), float(cx), float(cy), float(fps)
    w, h = int(w), int(h)
    tum = np.array([[float(x) for x in l.split()] for l in open(f'{src}/camera_gt.tum') if l.strip() and not l.startswith('#')])
    T = len(tum)
    d = np.load(f'{src}/hands_gt.npz')
    hands = {}
    for side in ('left', 'right'):
        valid = d[f'{side}_valid'].astype(bool)
        jc = d[f'{side}_joints_cam']
        kp = np.stack([fx * jc[..., 0] / jc[..., 2] + cx, fy * jc[..., 1] / jc[..., 2] + cy], -1)
        kp[~valid] = np.nan
        infilled = ~valid
        obs = valid.copy()
        if every:
            idx = np.flatnonzero(valid)[every // 2::every]
            infilled[idx] = True
            obs[idx] = False
            kp[idx] = np.nan
        nan = lambda a: [[None if not np.isfinite(v) else float(v) for v in r] for r in a.reshape(T, -1)]
        hands[side] = {
            'valid': obs.astype(int).tolist(), 'infilled': (infilled & ~obs).astype(int).tolist(),
            'trans': d[f'{side}_trans'].tolist(), 'rot': d[f'{side}_rot'].tolist(),
            'handPose': d[f'{side}_hand_pose'].tolist(), 'betas': d[f'{side}_betas'].tolist(),
            'jointsWorld': d[f'{side}_joints_world'].reshape(T, -1).tolist(),
            'jointsCam': d[f'{side}_joints_cam'].reshape(T, -1).tolist(),
            'keypoints2d': nan(kp),
        }
    depth = np.load(f'{src}/depth/000000.npy')
    rng = np.random.default_rng(1)
    v = rng.integers(0, h, 400); u = rng.integers(0, w, 400)
    z = depth[v, u]
    ok = np.isfinite(z) & (z > 0)
    pts = np.stack([(u - cx) / fx * z, (v - cy) / fy * z, z], -1)[ok]
    result = {
        'version': 1, 'width': w, 'height': h, 'fps': fps, 'frameCount': T,
        'intrinsics': {'fx': fx, 'fy': fy, 'cx': cx, 'cy': cy, 'focalSource': 'fixture'},
        'camera': {'positions': tum[:, 1:4].tolist(), 'quaternions': tum[:, 4:8].tolist(), 'status': [0] * T},
        'points': pts.tolist(),
        'scale': {'scale': 1.0, 'method': 'fixture', 'confidence': 1.0},
        'hands': hands, 'timings': {}, 'warnings': ['fixture: ground truth of a synthetic sequence'], 'noHands': False,
    }
    with open(out, 'w') as f:
        json.dump(result, f)
    return 0


if __name__ == '__main__':
    sys.exit(main())
