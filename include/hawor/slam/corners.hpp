// hawor/slam/corners.hpp — Shi–Tomasi corners with spatial bucketing, the SLAM's feature
// detector (Shi & Tomasi 1994, "Good features to track").
//
// Score: the smaller eigenvalue of the structure tensor over a (2r+1)² box (r = 2),
//   M = Σ [gx², gx·gy; gx·gy, gy²],  λ_min = (a + c)/2 − √(((a − c)/2)² + b²),
// with central-difference gradients gx = (I(x+1) − I(x−1))/2, reported per pixel of the box
// (λ_min / (2r+1)²) so that the threshold reads in grey levels² (noise of σ grey levels gives
// λ ≈ σ²/2). A corner is a 3×3 local maximum of λ_min above minEigen, away from the border.
// Bucketing: the image is cut into cellSize² cells; a cell already holding maxPerCell features
// (existing tracks) gets no new one, others get their best candidates, and candidates closer than
// minDistance to any feature are dropped (greedy, strongest first) — an even spread over the
// image, which pose estimation needs more than the strongest corners. Pixels set in `blocked`
// (the dilated hand mask: docs/design.md §5's front-end masking) never get a corner.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/render/image.hpp"

namespace hawor {

struct CornerOptions {
  int cellSize = 32;        ///< bucketing cell (pixels)
  int maxPerCell = 2;       ///< features per cell, existing ones included
  float minEigen = 6.0f;    ///< λ_min per pixel of the box (grey levels²)
  int minDistance = 8;      ///< pixels between features
  int border = 12;          ///< no corner closer than this to the image border (KLT window)
  int boxRadius = 2;        ///< structure-tensor box radius r
};

struct CornerScratch {
  std::vector<float> gxx, gxy, gyy, tmp, score;
  std::vector<int> occupancy;
};

/// Detects up to maxNew corners on `grey` (level 0) given the `existing` features; appends their
/// positions to `out` (x, y in pixels). `blocked` may be null or a binary mask of the same size.
template <typename Vec2T>
void detectCorners(const ImageF& grey, const ImageU8* blocked, const std::vector<Vec2T>& existing,
                   int maxNew, const CornerOptions& opt, std::vector<Vec2T>& out, CornerScratch& s) {
  if (!grey.consistent() || grey.channels != 1) throw Error("detectCorners: expected a grey image");
  if (blocked && !blocked->empty() && !blocked->sameSize(grey.width, grey.height, 1)) {
    throw Error("detectCorners: mask size differs from the image");
  }
  if (opt.cellSize < 4 || opt.maxPerCell < 1 || opt.minDistance < 1 || opt.boxRadius < 1 ||
      opt.border < opt.boxRadius + 2 || !(opt.minEigen >= 0)) {
    throw Error("detectCorners: invalid options");
  }
  const int w = grey.width, h = grey.height, r = opt.boxRadius;
  if (maxNew <= 0 || w < 2 * opt.border + 3 || h < 2 * opt.border + 3) return;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  s.gxx.assign(n, 0.0f);
  s.gxy.assign(n, 0.0f);
  s.gyy.assign(n, 0.0f);
  // Gradient products (zero on the outermost ring).
  for (int y = 1; y < h - 1; ++y) {
    const float* rm = grey.row(y - 1);
    const float* r0 = grey.row(y);
    const float* rp = grey.row(y + 1);
    float* axx = s.gxx.data() + static_cast<std::size_t>(y) * w;
    float* axy = s.gxy.data() + static_cast<std::size_t>(y) * w;
    float* ayy = s.gyy.data() + static_cast<std::size_t>(y) * w;
    for (int x = 1; x < w - 1; ++x) {
      const float gx = 0.5f * (r0[x + 1] - r0[x - 1]);
      const float gy = 0.5f * (rp[x] - rm[x]);
      axx[x] = gx * gx;
      axy[x] = gx * gy;
      ayy[x] = gy * gy;
    }
  }
  // Separable box sums (running sums), in place through tmp.
  auto box = [&](std::vector<float>& a) {
    s.tmp.assign(n, 0.0f);
    for (int y = 0; y < h; ++y) {
      const float* src = a.data() + static_cast<std::size_t>(y) * w;
      float* dst = s.tmp.data() + static_cast<std::size_t>(y) * w;
      float acc = 0.0f;
      for (int x = 0; x < std::min(w, 2 * r + 1); ++x) acc += src[x];
      for (int x = r; x + r < w; ++x) {
        dst[x] = acc;
        if (x + r + 1 < w) acc += src[x + r + 1] - src[x - r];
      }
    }
    std::fill(a.begin(), a.end(), 0.0f);
    for (int x = 0; x < w; ++x) {
      float acc = 0.0f;
      for (int y = 0; y < std::min(h, 2 * r + 1); ++y) acc += s.tmp[static_cast<std::size_t>(y) * w + x];
      for (int y = r; y + r < h; ++y) {
        a[static_cast<std::size_t>(y) * w + x] = acc;
        if (y + r + 1 < h) {
          acc += s.tmp[static_cast<std::size_t>(y + r + 1) * w + x] - s.tmp[static_cast<std::size_t>(y - r) * w + x];
        }
      }
    }
  };
  box(s.gxx);
  box(s.gxy);
  box(s.gyy);
  const float norm = 1.0f / float((2 * r + 1) * (2 * r + 1));
  s.score.assign(n, 0.0f);
  for (int y = opt.border - 1; y < h - opt.border + 1; ++y) {
    for (int x = opt.border - 1; x < w - opt.border + 1; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const float a = s.gxx[i] * norm, b = s.gxy[i] * norm, c = s.gyy[i] * norm;
      const float hd = 0.5f * (a - c);
      s.score[i] = 0.5f * (a + c) - std::sqrt(hd * hd + b * b);
    }
  }
  // Cell occupancy by the existing features.
  const int cw = (w + opt.cellSize - 1) / opt.cellSize, ch = (h + opt.cellSize - 1) / opt.cellSize;
  s.occupancy.assign(static_cast<std::size_t>(cw) * ch, 0);
  auto cellOf = [&](float x, float y) -> int {
    const int cx = std::min(std::max(int(x) / opt.cellSize, 0), cw - 1);
    const int cy = std::min(std::max(int(y) / opt.cellSize, 0), ch - 1);
    return cy * cw + cx;
  };
  for (const Vec2T& p : existing) {
    if (std::isfinite(double(p[0])) && std::isfinite(double(p[1]))) ++s.occupancy[static_cast<std::size_t>(cellOf(float(p[0]), float(p[1])))];
  }
  // Candidates: per free cell, its best 3×3 local maxima above threshold.
  struct Cand { float score; int x, y; };
  std::vector<Cand> cands, cell;
  for (int cy = 0; cy < ch; ++cy) {
    for (int cx = 0; cx < cw; ++cx) {
      const int room = opt.maxPerCell - s.occupancy[static_cast<std::size_t>(cy * cw + cx)];
      if (room <= 0) continue;
      cell.clear();
      const int x0 = std::max(cx * opt.cellSize, opt.border), x1 = std::min((cx + 1) * opt.cellSize, w - opt.border);
      const int y0 = std::max(cy * opt.cellSize, opt.border), y1 = std::min((cy + 1) * opt.cellSize, h - opt.border);
      for (int y = y0; y < y1; ++y) {
        const float* sr = s.score.data() + static_cast<std::size_t>(y) * w;
        const unsigned char* br = (blocked && !blocked->empty()) ? blocked->row(y) : nullptr;
        for (int x = x0; x < x1; ++x) {
          const float v = sr[x];
          if (!(v > opt.minEigen)) continue;
          if (br && br[x]) continue;
          if (v < sr[x - 1] || v <= sr[x + 1] || v < sr[x - w] || v <= sr[x + w] || v < sr[x - w - 1] ||
              v < sr[x - w + 1] || v <= sr[x + w - 1] || v <= sr[x + w + 1]) {
            continue;
          }
          cell.push_back({v, x, y});
        }
      }
      const std::size_t k = std::min<std::size_t>(cell.size(), static_cast<std::size_t>(room));
      std::partial_sort(cell.begin(), cell.begin() + static_cast<std::ptrdiff_t>(k), cell.end(),
                        [](const Cand& a, const Cand& b) { return a.score > b.score; });
      cands.insert(cands.end(), cell.begin(), cell.begin() + static_cast<std::ptrdiff_t>(k));
    }
  }
  std::sort(cands.begin(), cands.end(), [](const Cand& a, const Cand& b) {
    return a.score > b.score || (a.score == b.score && (a.y < b.y || (a.y == b.y && a.x < b.x)));
  });
  // Greedy minimum distance on a grid of minDistance cells (3×3 neighbourhood check).
  const int d = opt.minDistance;
  const int gw = (w + d - 1) / d, gh = (h + d - 1) / d;
  std::vector<std::vector<Vec2T>> grid(static_cast<std::size_t>(gw) * gh);
  auto gridAdd = [&](float x, float y, const Vec2T& p) {
    const int gx = std::min(std::max(int(x) / d, 0), gw - 1), gy = std::min(std::max(int(y) / d, 0), gh - 1);
    grid[static_cast<std::size_t>(gy) * gw + gx].push_back(p);
  };
  auto nearFeature = [&](float x, float y) {
    const int gx = int(x) / d, gy = int(y) / d;
    for (int yy = std::max(gy - 1, 0); yy <= std::min(gy + 1, gh - 1); ++yy) {
      for (int xx = std::max(gx - 1, 0); xx <= std::min(gx + 1, gw - 1); ++xx) {
        for (const Vec2T& q : grid[static_cast<std::size_t>(yy) * gw + xx]) {
          const float dx = float(q[0]) - x, dy = float(q[1]) - y;
          if (dx * dx + dy * dy < float(d * d)) return true;
        }
      }
    }
    return false;
  };
  for (const Vec2T& p : existing) {
    if (std::isfinite(double(p[0])) && std::isfinite(double(p[1]))) gridAdd(float(p[0]), float(p[1]), p);
  }
  int added = 0;
  for (const Cand& c : cands) {
    if (added >= maxNew) break;
    if (nearFeature(float(c.x), float(c.y))) continue;
    Vec2T p;
    p[0] = static_cast<typename std::decay<decltype(p[0])>::type>(c.x);
    p[1] = static_cast<typename std::decay<decltype(p[1])>::type>(c.y);
    gridAdd(float(c.x), float(c.y), p);
    out.push_back(p);
    ++added;
  }
}

}  // namespace hawor
