// hawor/slam/klt.hpp — pyramidal Lucas–Kanade feature tracking (Bouguet 2000, "Pyramidal
// implementation of the Lucas Kanade feature tracker"), inverse-compositional for speed (Baker &
// Matthews 2004): the template's gradients and Hessian are computed once per level.
//
// Per point and level l (coarsest first), template T = prev at p/2^l over a (2h+1)² window,
//   H = Σ ∇T ∇Tᵀ,  repeat: e = I(q + x) − T(x),  q ← q − H⁻¹ Σ ∇T·e   until |Δq| < ε,
// then q ← 2q on the next finer level. Rejected: a window leaving the image, an ill-conditioned
// H (λ_min per pixel below minEigen: no texture to track), a mean absolute residual above
// maxResidual (occluded — typically by a hand — or changed appearance), and, with the
// forward–backward check (Kalal et al. 2010), a point that tracked back from the result lands
// more than maxFbError pixels from where it started.
// Patches are sampled with one set of bilinear weights (all samples of a window share the
// sub-pixel fraction), which makes a window a few multiply-adds per pixel.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/slam/image_pyramid.hpp"

namespace hawor {

struct KltOptions {
  int halfWindow = 4;         ///< window (2h+1)²
  int maxIterations = 12;     ///< per level
  float epsilon = 0.02f;      ///< convergence on |Δq| (pixels of the level)
  float minEigen = 2.0f;      ///< λ_min(H) per window pixel (grey levels²)
  float maxResidual = 14.0f;  ///< mean |I − T| over the window at level 0 (grey levels)
  bool forwardBackward = true;
  float maxFbError = 0.75f;   ///< pixels (level 0)
};

namespace klt_detail {

/// Samples a (2h+1+2b)² patch centred at (x, y) (b = border for gradients). True when the
/// patch lies inside the image (no clamping needed).
inline bool samplePatch(const ImageF& im, float x, float y, int half, float* out) {
  const int fx = int(std::floor(x)), fy = int(std::floor(y));
  const float ax = x - float(fx), ay = y - float(fy);
  const int x0 = fx - half, y0 = fy - half, n = 2 * half + 1;
  if (x0 < 0 || y0 < 0 || x0 + n >= im.width || y0 + n >= im.height) return false;
  const float w00 = (1 - ax) * (1 - ay), w10 = ax * (1 - ay), w01 = (1 - ax) * ay, w11 = ax * ay;
  for (int j = 0; j < n; ++j) {
    const float* r0 = im.row(y0 + j) + x0;
    const float* r1 = r0 + im.width;
    float* o = out + j * n;
    for (int i = 0; i < n; ++i) o[i] = w00 * r0[i] + w10 * r0[i + 1] + w01 * r1[i] + w11 * r1[i + 1];
  }
  return true;
}

struct Workspace {
  std::vector<float> tpl, gx, gy, cur;
};

/// Tracks one point from `prev` at p to `cur` starting at guess q (both at level 0). Returns
/// false when lost; q holds the result; *residual the mean |e| at level 0.
inline bool trackPoint(const ImagePyramid& prev, const ImagePyramid& cur, float px, float py,
                       float& qx, float& qy, const KltOptions& o, Workspace& ws, float* residual) {
  const int h = o.halfWindow, n = 2 * h + 1, nn = n * n, nb = n + 2;
  ws.tpl.resize(static_cast<std::size_t>(nb) * nb);
  ws.gx.resize(static_cast<std::size_t>(nn));
  ws.gy.resize(static_cast<std::size_t>(nn));
  ws.cur.resize(static_cast<std::size_t>(nn));
  const int L = std::min(prev.numLevels(), cur.numLevels());
  float s = std::ldexp(1.0f, -(L - 1));
  float gxq = qx * s, gyq = qy * s;
  float meanAbs = 0.0f;
  for (int l = L - 1; l >= 0; --l, s *= 2.0f) {
    const ImageF& P = prev.level(l);
    const ImageF& C = cur.level(l);
    const float tx = px * s, ty = py * s;
    if (!samplePatch(P, tx, ty, h + 1, ws.tpl.data())) {
      if (l == 0) return false;
      gxq *= 2.0f, gyq *= 2.0f;  // the coarse level cannot hold the window: skip it
      continue;
    }
    double a = 0, b = 0, c = 0;
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const float* t = ws.tpl.data() + (j + 1) * nb + (i + 1);
        const float dx = 0.5f * (t[1] - t[-1]), dy = 0.5f * (t[nb] - t[-nb]);
        ws.gx[static_cast<std::size_t>(j * n + i)] = dx;
        ws.gy[static_cast<std::size_t>(j * n + i)] = dy;
        a += double(dx) * dx, b += double(dx) * dy, c += double(dy) * dy;
      }
    }
    const double hd = 0.5 * (a - c);
    const double lmin = 0.5 * (a + c) - std::sqrt(hd * hd + b * b);
    if (!(lmin / nn >= o.minEigen)) {
      if (l == 0) return false;
      gxq *= 2.0f, gyq *= 2.0f;
      continue;
    }
    const double det = a * c - b * b;
    const double ia = c / det, ib = -b / det, ic = a / det;
    bool inside = true;
    for (int it = 0; it < o.maxIterations; ++it) {
      if (!samplePatch(C, gxq, gyq, h, ws.cur.data())) {
        inside = false;
        break;
      }
      double ex = 0, ey = 0, sa = 0;
      for (int j = 0; j < n; ++j) {
        const float* t = ws.tpl.data() + (j + 1) * nb + 1;
        const float* q = ws.cur.data() + j * n;
        const float* dx = ws.gx.data() + j * n;
        const float* dy = ws.gy.data() + j * n;
        float fx = 0, fy = 0, fa = 0;
        for (int i = 0; i < n; ++i) {
          const float e = q[i] - t[i];
          fx += dx[i] * e, fy += dy[i] * e, fa += std::fabs(e);
        }
        ex += fx, ey += fy, sa += fa;
      }
      const float ux = float(ia * ex + ib * ey), uy = float(ib * ex + ic * ey);
      gxq -= ux, gyq -= uy;
      meanAbs = float(sa / nn);
      if (!std::isfinite(gxq) || !std::isfinite(gyq)) return false;
      if (ux * ux + uy * uy < o.epsilon * o.epsilon) break;
    }
    if (!inside) {
      if (l == 0) return false;
      return false;
    }
    if (l > 0) gxq *= 2.0f, gyq *= 2.0f;
  }
  qx = gxq, qy = gyq;
  // Residual at the final position (level 0).
  if (!samplePatch(cur.level(0), qx, qy, h, ws.cur.data())) return false;
  double sa = 0;
  for (int j = 0; j < n; ++j) {
    const float* t = ws.tpl.data() + (j + 1) * nb + 1;
    for (int i = 0; i < n; ++i) sa += std::fabs(ws.cur[static_cast<std::size_t>(j * n + i)] - t[i]);
  }
  meanAbs = float(sa / nn);
  if (residual) *residual = meanAbs;
  return meanAbs <= o.maxResidual;
}

}  // namespace klt_detail

/// Tracks points `from` (in prev) into cur. `to` holds the initial guesses on input (same size as
/// from; e.g. the points themselves, or predictions) and the tracked positions on output; ok[i]
/// says whether point i was tracked (all the checks of the file comment).
template <typename Vec2T>
void trackKlt(const ImagePyramid& prev, const ImagePyramid& cur, const std::vector<Vec2T>& from,
              std::vector<Vec2T>& to, std::vector<char>& ok, const KltOptions& o = {}) {
  if (to.size() != from.size()) throw Error("trackKlt: guesses and points differ in number");
  if (prev.numLevels() == 0 || cur.numLevels() == 0 || prev.level(0).width != cur.level(0).width ||
      prev.level(0).height != cur.level(0).height) {
    throw Error("trackKlt: the two pyramids differ in size or are empty");
  }
  if (o.halfWindow < 1 || o.halfWindow > 15 || o.maxIterations < 1) throw Error("trackKlt: invalid options");
  ok.assign(from.size(), 0);
  klt_detail::Workspace ws;
  for (std::size_t i = 0; i < from.size(); ++i) {
    const float px = float(from[i][0]), py = float(from[i][1]);
    float qx = float(to[i][0]), qy = float(to[i][1]);
    if (!std::isfinite(px) || !std::isfinite(py) || !std::isfinite(qx) || !std::isfinite(qy)) continue;
    float res = 0;
    if (!klt_detail::trackPoint(prev, cur, px, py, qx, qy, o, ws, &res)) continue;
    if (o.forwardBackward) {
      float bx = px, by = py;
      if (!klt_detail::trackPoint(cur, prev, qx, qy, bx, by, o, ws, nullptr)) continue;
      if ((bx - px) * (bx - px) + (by - py) * (by - py) > o.maxFbError * o.maxFbError) continue;
    }
    to[i][0] = static_cast<typename std::decay<decltype(to[i][0])>::type>(qx);
    to[i][1] = static_cast<typename std::decay<decltype(to[i][1])>::type>(qy);
    ok[i] = 1;
  }
}

}  // namespace hawor
