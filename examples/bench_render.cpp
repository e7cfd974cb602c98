// bench_render — timings of the hand-mask path at 640×480 (median and p95 over repeats).
//
// Mesh: a MANO-size closed-ish mesh (778 vertices, 1538 faces, like MANO's open wrist): a
// level-3 icosphere (642 v, 1280 f) with 136 faces split at their centroid (778 v, 1552 f),
// 14 faces removed, radially deformed and scaled to a hand-sized blob (~0.18 m) at 0.4 m depth,
// seen by a 640×480 camera with f = 600 px (the official default), so that it covers ~20 %.
//
//   bench_render [repeats=500]
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <map>
#include <utility>
#include <vector>

#include "hawor/render/render.hpp"

namespace {

using hawor::Points3;
using hawor::TriangleList;

void handSizedMesh(Points3<double>& V, TriangleList& F) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> v = {
      {-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
      {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {
      {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  auto normalise = [](std::array<double, 3>& p) {
    const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (auto& c : p) c /= n;
  };
  for (auto& p : v) normalise(p);
  for (int level = 0; level < 3; ++level) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      std::array<double, 3> p{};
      for (int c = 0; c < 3; ++c) p[c] = 0.5 * (v[a][c] + v[b][c]);
      normalise(p);
      v.push_back(p);
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]),
                c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f.swap(g);
  }
  // 136 centroid splits: 642 + 136 = 778 vertices, 1280 + 2·136 = 1552 faces.
  for (int i = 0; i < 136; ++i) {
    const std::array<int, 3> tri = f[static_cast<std::size_t>(i) * 9];
    std::array<double, 3> p{};
    for (int c = 0; c < 3; ++c) p[c] = (v[tri[0]][c] + v[tri[1]][c] + v[tri[2]][c]) / 3.0;
    normalise(p);
    v.push_back(p);
    const int m = static_cast<int>(v.size()) - 1;
    f[static_cast<std::size_t>(i) * 9] = {tri[0], tri[1], m};
    f.push_back({tri[1], tri[2], m});
    f.push_back({tri[2], tri[0], m});
  }
  f.resize(f.size() - 14);  // an open "wrist", as MANO's 1538 faces
  // Hand-sized blob: ~0.18 m long, flattened, bumpy, 0.4 m in front of the camera.
  V.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) {
    const auto& p = v[i];
    const double r = 1.0 + 0.08 * std::sin(4 * p[0] + 1) * std::cos(3 * p[1]) + 0.05 * std::sin(6 * p[2]);
    V.row(static_cast<Eigen::Index>(i)) << 0.01 + 0.092 * r * p[0], -0.02 + 0.098 * r * p[1],
        0.4 + 0.05 * r * p[2];
  }
  F.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) {
    F.row(static_cast<Eigen::Index>(i)) << f[i][0], f[i][1], f[i][2];
  }
}

struct Stats {
  double median, p95, cpuMedian;
};

/// Thread CPU time in ms (immune to preemption on a shared machine); wall time under WASM.
double cpuMs() {
#if defined(CLOCK_THREAD_CPUTIME_ID) && !defined(__EMSCRIPTEN__)
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
#else
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
#endif
}

template <typename Fn>
Stats timeIt(int repeats, Fn&& fn) {
  for (int i = 0; i < 10; ++i) fn();  // warm-up
  std::vector<double> ms(static_cast<std::size_t>(repeats)), cpu(ms.size());
  for (int i = 0; i < repeats; ++i) {
    const double c0 = cpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    const auto t1 = std::chrono::steady_clock::now();
    cpu[static_cast<std::size_t>(i)] = cpuMs() - c0;
    ms[static_cast<std::size_t>(i)] = std::chrono::duration<double, std::milli>(t1 - t0).count();
  }
  std::sort(ms.begin(), ms.end());
  std::sort(cpu.begin(), cpu.end());
  return {ms[ms.size() / 2], ms[std::min(ms.size() - 1, ms.size() * 95 / 100)], cpu[cpu.size() / 2]};
}

void report(const char* what, const Stats& s) {
  std::printf("%-44s median %7.3f ms   p95 %7.3f ms   (cpu median %7.3f ms)\n", what, s.median,
              s.p95, s.cpuMedian);
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 500;
  Points3<double> Vd;
  TriangleList F;
  handSizedMesh(Vd, F);
  const Points3<float> Vf = Vd.cast<float>();
  hawor::PinholeCamera<double> camd;
  camd.fx = camd.fy = 600;
  camd.cx = 319.5;
  camd.cy = 239.5;
  camd.width = 640;
  camd.height = 480;
  const hawor::PinholeCamera<float> camf = camd.cast<float>();

  hawor::Mask mask, dil, small;
  hawor::renderMask(Vd, F, camd, mask);
  std::printf("mesh: %d vertices, %d faces; image 640x480; mask coverage %.1f %%; %d repeats\n",
              static_cast<int>(Vd.rows()), static_cast<int>(F.rows()),
              100.0 * hawor::maskCoverage(mask), repeats);

  volatile unsigned sink = 0;
  report("mask (double), incl. projection",
         timeIt(repeats, [&] { hawor::renderMask(Vd, F, camd, mask); sink += mask.data[0]; }));
  report("mask (float), incl. projection",
         timeIt(repeats, [&] { hawor::renderMask(Vf, F, camf, mask); sink += mask.data[0]; }));
  hawor::RasterOptions<double> cullBack;
  cullBack.cull = hawor::CullMode::Back;
  report("mask (double), back faces culled", timeIt(repeats, [&] {
           hawor::renderMask(Vd, F, camd, mask, 255, cullBack);
           sink += mask.data[0];
         }));
  report("mask (double) + dilate r=4", timeIt(repeats, [&] {
           hawor::renderMask(Vd, F, camd, mask);
           hawor::dilateMask(mask, 4, dil);
           sink += dil.data[0];
         }));
  report("dilate r=4 alone", timeIt(repeats, [&] { hawor::dilateMask(mask, 4, dil); sink += dil.data[0]; }));
  report("dilate r=16 alone", timeIt(repeats, [&] { hawor::dilateMask(mask, 16, dil); sink += dil.data[0]; }));
  report("resize area 640x480 -> 320x240", timeIt(repeats, [&] {
           hawor::resizeMask(mask, 320, 240, small, hawor::MaskResize::Area);
           sink += small.data[0];
         }));
  const Points3<double> V2 = Vd.rowwise() + Eigen::RowVector3d(0.08, 0.02, 0.05);
  report("two meshes, labelled (z-buffer)", timeIt(repeats, [&] {
           hawor::renderMask<double>({{&Vd, &F, 1}, {&V2, &F, 2}}, camd, mask);
           sink += mask.data[0];
         }));
  // The synthetic-sequence path: z-buffer, face id and barycentrics per pixel.
  hawor::Rasterizer<float> r(camf);
  hawor::Image<float> depth;
  hawor::Image<int> faceId(640, 480, 1, -1);
  hawor::Image<float> bary(640, 480, 3, 0.f);
  report("depth + face id + barycentrics (float)", timeIt(repeats, [&] {
           r.clearDepth(depth);
           r.setDepthBuffer(&depth);
           r.drawMesh(Vf, F, [&](const hawor::Fragment<float>& f) {
             faceId.at(f.x, f.y) = f.face;
             const hawor::Vec3<float> b = f.barycentric();
             for (int c = 0; c < 3; ++c) bary.at(f.x, f.y, c) = b(c);
           });
           sink += static_cast<unsigned>(faceId.data[0]);
         }));
  return sink == 12345u ? 1 : 0;
}
