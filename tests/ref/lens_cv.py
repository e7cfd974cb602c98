"""Reference data for tests/geometry/ref_lens.cpp: OpenCV's own lens models.

Usage: lens_cv.py <out.txt>

For a few radial-tangential ("plumb bob", k1, k2, p1, p2, k3) and fisheye (Kannala-Brandt,
k1..k4) cameras, with inputs generated here from a fixed seed:
  - cv2.projectPoints / cv2.fisheye.projectPoints with rvec = tvec = 0: the pixels of 3D points
    and the Jacobian of the pixels with respect to tvec, which at rvec = 0 is d(u, v)/dp;
  - cv2.undistortPointsIter (radial-tangential; many iterations, not undistortPoints' default 5)
    and cv2.fisheye.undistortPoints: the undistorted normalised (x, y) of pixels, with a flag
    per pixel saying whether OpenCV's result reprojects onto the pixel (its fixed-point
    iteration can stop short near the edge of strong lenses; those are not compared).
Writes have_cv2 = 0 (and nothing else) when cv2 cannot be imported: Debian's python3-opencv
installs it for /usr/bin/python3.
"""
import sys

import numpy as np

from refio import save

RADTAN, FISHEYE = 0.0, 1.0

# kind, (fx, fy, cx, cy), (width, height), coefficients (5; fisheye: k1..k4, 0)
CASES = [
    (RADTAN, (520.3, 518.7, 321.4, 243.9), (640, 480), (-0.12, 0.05, 1e-3, -5e-4, -0.01)),
    (RADTAN, (440.2, 441.1, 318.7, 241.2), (640, 480), (-0.28, 0.075, 2e-4, -3e-4, -0.009)),
    (RADTAN, (410.0, 409.0, 300.0, 250.0), (640, 480), (0.08, -0.02, -7e-4, 4e-4, 0.0)),
    (FISHEYE, (285.7, 286.1, 320.3, 238.8), (640, 480), (-0.013, -0.002, 0.0026, -0.0008, 0.0)),
    (FISHEYE, (250.0, 250.5, 399.5, 399.5), (800, 800), (0.03, -0.01, 0.002, -0.0001, 0.0)),
]


def main(out):
    try:
        import cv2
    except Exception as e:  # noqa: BLE001 - any import failure means "no reference"
        print("lens_cv.py: cannot import cv2 (%s)" % e, file=sys.stderr)
        save(out, have_cv2=np.array([0.0]))
        return
    rng = np.random.default_rng(20240917)
    arrays = {"have_cv2": np.array([1.0]), "case_count": np.array([float(len(CASES))])}
    for i, (kind, (fx, fy, cx, cy), (w, h), coeffs) in enumerate(CASES):
        K = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])
        fish = kind == FISHEYE
        D = np.array(coeffs[:4] if fish else coeffs, dtype=np.float64)
        rvec = np.zeros(3)
        tvec = np.zeros(3)

        # 3D points: directions that land in (or near) the image, at depths 0.2-20, plus the
        # optical axis and points very close to it.
        n = 300
        if fish:
            theta = np.sqrt(rng.uniform(0, 1, n)) * np.deg2rad(80)
        else:
            # undistorted radius up to that of the image corners (barrel lenses: beyond them)
            rmax = 0.9 * np.hypot(w / 2 / fx, h / 2 / fy)
            theta = np.arctan(np.sqrt(rng.uniform(0, 1, n)) * rmax)
        theta[:6] = [0.0, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3]
        phi = rng.uniform(-np.pi, np.pi, n)
        depth = np.exp(rng.uniform(np.log(0.2), np.log(20), n))
        P = depth[:, None] * np.stack(
            [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)
        if fish:
            uv, jac = cv2.fisheye.projectPoints(P.reshape(-1, 1, 3), rvec, tvec, K, D)
            # columns: f (2), c (2), k (4), rvec (3), tvec (3), skew (1)
            dT = jac[:, 11:14]
        else:
            uv, jac = cv2.projectPoints(P.reshape(-1, 1, 3), rvec, tvec, K, D)
            # columns: rvec (3), tvec (3), f (2), c (2), distortion (5)
            dT = jac[:, 3:6]
        arrays["case%d_kind" % i] = np.array([kind])
        arrays["case%d_K" % i] = np.array([fx, fy, cx, cy])
        arrays["case%d_size" % i] = np.array([float(w), float(h)])
        arrays["case%d_D" % i] = np.array(coeffs, dtype=np.float64)
        arrays["case%d_points" % i] = P
        arrays["case%d_uv" % i] = uv.reshape(-1, 2)
        arrays["case%d_J" % i] = dT.reshape(n, 2, 3)

        # Pixels over the image (and the principal point) -> undistorted normalised (x, y).
        m = 300
        pix = np.stack([rng.uniform(-0.5, w - 0.5, m), rng.uniform(-0.5, h - 0.5, m)], axis=1)
        pix[0] = [cx, cy]
        pix[1:5] = [[-0.5, -0.5], [w - 0.5, -0.5], [-0.5, h - 0.5], [w - 0.5, h - 0.5]]
        src = pix.reshape(-1, 1, 2)
        if fish:
            # COUNT only: with EPS, OpenCV marks points whose last Newton step is not below eps
            # as failed (-1e6); the reprojection check below decides instead.
            crit = (cv2.TERM_CRITERIA_COUNT, 50, 0.0)
            xy = cv2.fisheye.undistortPoints(src, K, D, criteria=crit).reshape(-1, 2)
            back, _ = cv2.fisheye.projectPoints(
                np.concatenate([xy, np.ones((m, 1))], axis=1).reshape(-1, 1, 3), rvec, tvec, K, D)
        else:
            crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 2000, 1e-14)
            xy = cv2.undistortPointsIter(src, K, D, None, None, crit).reshape(-1, 2)
            back, _ = cv2.projectPoints(
                np.concatenate([xy, np.ones((m, 1))], axis=1).reshape(-1, 1, 3), rvec, tvec, K, D)
        resid = np.linalg.norm(back.reshape(-1, 2) - pix, axis=1)
        ok = np.isfinite(resid) & (resid < 1e-9)
        arrays["case%d_pix" % i] = pix
        arrays["case%d_xy" % i] = xy
        arrays["case%d_ok" % i] = ok.astype(np.float64)
        arrays["case%d_resid" % i] = np.where(np.isfinite(resid), resid, 1e300)
    save(out, **arrays)


if __name__ == "__main__":
    main(sys.argv[1])
