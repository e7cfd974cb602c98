// bench_ba — timings of the SLAM's geometric estimation core (median and p95 over repeats):
//   * sliding-window bundle adjustment: 10 keyframes, 1500 points, 6000 observations (each point
//     seen by 4 consecutive keyframes), 640×480, f = 500 px, 0.7 px noise, start perturbed by
//     0.3° / 1 cm per pose and 3 cm per point, first two keyframes fixed, Huber loss;
//   * global bundle adjustment (sparse reduced system): 200 keyframes, 20000 points, 80000
//     observations, same construction;
//   * PnP-RANSAC (P3P + MSAC + refinement): 300 correspondences, 30 % outliers, 1 px noise;
//   * two-view initialisation (5-point E and H by MSAC, selection, triangulation, refinement):
//     500 correspondences, 30 % outliers, 1 px noise.
//
// Times are the thread's CPU time natively (clock_gettime(CLOCK_THREAD_CPUTIME_ID): stable on a
// shared, loaded machine) and wall-clock time under WebAssembly.
//
//   bench_ba [repeats=30]
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "hawor/geometry/camera.hpp"
#include "hawor/hand/portable_random.hpp"
#include "hawor/slam/bundle_adjustment.hpp"
#include "hawor/slam/pnp_ransac.hpp"
#include "hawor/slam/two_view.hpp"

namespace {

/// Milliseconds of this thread's CPU time (wall clock where that clock is not available).
double nowMs() {
#if defined(CLOCK_THREAD_CPUTIME_ID) && !defined(__EMSCRIPTEN__)
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
#else
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
#endif
}

struct Rng {
  std::mt19937 gen{12345u};
  double uniform(double lo, double hi) { return lo + (hi - lo) * hawor::uniform01(gen); }
  double normal() { return hawor::standardNormal(gen); }
  // Components drawn in order (argument evaluation order is unspecified: GCC and clang differ),
  // so native and WebAssembly builds time the same problems.
  Eigen::Vector2d uniform2(double lo0, double hi0, double lo1, double hi1) {
    const double a = uniform(lo0, hi0);
    const double b = uniform(lo1, hi1);
    return Eigen::Vector2d(a, b);
  }
  Eigen::Vector2d normal2() {
    const double a = normal();
    const double b = normal();
    return Eigen::Vector2d(a, b);
  }
  Eigen::Vector3d unit() {
    const double a = normal();
    const double b = normal();
    const double c = normal();
    return Eigen::Vector3d(a, b, c).normalized();
  }
};

hawor::PinholeCamera<double> camera() {
  hawor::PinholeCamera<double> c;
  c.fx = c.fy = 500;
  c.cx = 319.5;
  c.cy = 239.5;
  c.width = 640;
  c.height = 480;
  return c;
}

// Keyframes 8 cm apart along a gentle curve, rotating ~1° each; every point is created from a
// pixel of keyframe k and observed by keyframes k..k+obsPerPoint−1 where visible.
hawor::BAProblem<double> makeProblem(Rng& rng, int nKf, int nPoints, int obsPerPoint) {
  const auto cam = camera();
  hawor::BAProblem<double> P;
  P.camera = cam;
  std::vector<hawor::SE3<double>> truth;
  for (int i = 0; i < nKf; ++i) {
    const double a = 0.02 * i;
    const hawor::SO3<double> R = hawor::SO3<double>::exp(hawor::Vec3<double>(0.003 * i, a, 0.0));
    truth.emplace_back(R, hawor::Vec3<double>(0.08 * i, 0.01 * std::sin(0.3 * i), 0.02 * std::cos(0.2 * i)));
  }
  std::vector<hawor::Vec3<double>> pts;
  while (static_cast<int>(pts.size()) < nPoints) {
    const int k = static_cast<int>(rng.uniform(0, std::max(1, nKf - obsPerPoint + 1)));
    const hawor::Vec2<double> px(rng.uniform2(20, 620, 20, 460));
    const hawor::Vec3<double> X = truth[static_cast<std::size_t>(k)] * cam.unproject(px, rng.uniform(2.0, 8.0));
    std::vector<hawor::BAObservation<double>> obs;
    for (int i = k; i < std::min(nKf, k + obsPerPoint); ++i) {
      const hawor::Vec3<double> Xc = truth[static_cast<std::size_t>(i)].inverse() * X;
      if (!cam.isVisible(Xc, 1.0)) continue;
      hawor::BAObservation<double> o;
      o.pose = i;
      o.point = static_cast<int>(pts.size());
      const hawor::Vec2<double> uv = cam.project(Xc);
      o.uv = hawor::Vec2<double>(uv + 0.7 * rng.normal2());
      obs.push_back(o);
    }
    if (obs.size() < 2) continue;
    pts.push_back(X);
    for (const auto& o : obs) P.observations.push_back(o);
  }
  for (std::size_t i = 0; i < truth.size(); ++i) {
    hawor::Vec6<double> d;
    d.head<3>() = 0.01 * rng.unit();
    d.tail<3>() = 0.3 * 3.14159265 / 180.0 * rng.unit();
    P.poses.push_back(i < 2 ? truth[i] : truth[i] * hawor::SE3<double>::exp(d));
  }
  for (const auto& X : pts) P.points.push_back(X + 0.03 * rng.unit());
  P.poseFixed.assign(truth.size(), 0);
  P.poseFixed[0] = P.poseFixed[1] = 1;
  return P;
}

template <typename S>
hawor::BAProblem<S> castProblem(const hawor::BAProblem<double>& p) {
  hawor::BAProblem<S> q;
  q.camera = p.camera.cast<S>();
  for (const auto& T : p.poses) q.poses.push_back(T.cast<S>());
  for (const auto& X : p.points) q.points.push_back(X.cast<S>());
  for (const auto& o : p.observations) {
    hawor::BAObservation<S> r;
    r.pose = o.pose;
    r.point = o.point;
    r.uv = o.uv.cast<S>();
    r.weight = static_cast<S>(o.weight);
    q.observations.push_back(r);
  }
  q.poseFixed = p.poseFixed;
  return q;
}

struct Stats {
  double median = 0, p95 = 0;
};
Stats stats(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  Stats s;
  s.median = v[v.size() / 2];
  s.p95 = v[std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(v.size()))) - 1)];
  return s;
}

template <typename S>
void benchBA(const char* name, const hawor::BAProblem<double>& base, int maxIter, int repeats) {
  const hawor::BAProblem<S> problem = castProblem<S>(base);
  hawor::BAOptions<S> opt;
  opt.maxIterations = maxIter;
  std::vector<double> ms;
  hawor::BAReport<S> rep;
  for (int r = 0; r < repeats; ++r) {
    hawor::BAProblem<S> p = problem;  // copied outside the timed region
    const double t0 = nowMs();
    rep = hawor::bundleAdjust(p, opt);
    ms.push_back(nowMs() - t0);
  }
  const Stats s = stats(ms);
  std::printf("%-34s %6zu kf %6zu pts %7zu obs  %8.2f ms  %8.2f ms  it %2d/%2d  rms %.3f -> %.3f px%s\n",
              name, base.poses.size(), base.points.size(), base.observations.size(), s.median, s.p95,
              rep.iterations, rep.successfulSteps, static_cast<double>(rep.initialRmsPx),
              static_cast<double>(rep.finalRmsPx), rep.sparseSolver ? "  (sparse)" : "");
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 30;
  Rng rng;
  std::printf("%-34s %27s %7s  %11s  %11s\n", "case", "size", "", "median", "p95");

  const hawor::BAProblem<double> window = makeProblem(rng, 10, 1500, 4);
  benchBA<double>("sliding-window BA, double, ≤10 it", window, 10, repeats);
  benchBA<float>("sliding-window BA, float, ≤10 it", window, 10, repeats);
  benchBA<double>("sliding-window BA, double, ≤5 it", window, 5, repeats);
  benchBA<double>("sliding-window BA, double, 1 it", window, 1, repeats);

  const hawor::BAProblem<double> global = makeProblem(rng, 200, 20000, 4);
  benchBA<double>("global BA, double, ≤10 it", global, 10, std::max(1, repeats / 10));

  // PnP-RANSAC.
  {
    const auto cam = camera();
    const hawor::SE3<double> T(hawor::SO3<double>::exp(hawor::Vec3<double>(0.1, -0.2, 0.05)),
                               hawor::Vec3<double>(0.3, -0.1, 0.2));
    std::vector<hawor::Vec3<double>> X;
    std::vector<hawor::Vec2<double>> uv;
    for (int i = 0; i < 300; ++i) {
      const hawor::Vec2<double> px(rng.uniform2(0, 639, 0, 479));
      X.push_back(T * cam.unproject(px, rng.uniform(1, 6)));
      uv.emplace_back(i % 10 < 3 ? hawor::Vec2<double>(rng.uniform2(0, 639, 0, 479))
                                 : hawor::Vec2<double>(px + rng.normal2()));
    }
    std::vector<double> ms;
    hawor::PnPRansacResult<double> res;
    for (int r = 0; r < repeats; ++r) {
      const double t0 = nowMs();
      res = hawor::solvePnPRansac(X, uv, cam);
      ms.push_back(nowMs() - t0);
    }
    const Stats s = stats(ms);
    std::printf("%-34s %27s %7s  %8.2f ms  %8.2f ms  ransac it %d, inliers %d\n", "PnP-RANSAC, double",
                "300 corr., 30 % out", "", s.median, s.p95, res.ransacIterations, res.numInliers);
  }
  // Two-view initialisation.
  {
    const double f = 500;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
    const Eigen::Vector3d t(0.4, 0.05, 0.1);
    std::vector<hawor::Vec2<double>> x1, x2;
    while (x1.size() < 500) {
      const Eigen::Vector2d xy = rng.uniform2(-3, 3, -2, 2);
      const Eigen::Vector3d X(xy(0), xy(1), rng.uniform(3, 8));
      const Eigen::Vector3d X2 = R * X + t;
      const double u1 = X.x() / X.z(), v1 = X.y() / X.z(), u2 = X2.x() / X2.z(), v2 = X2.y() / X2.z();
      if (std::abs(u1) > 0.64 || std::abs(v1) > 0.48 || std::abs(u2) > 0.64 || std::abs(v2) > 0.48) continue;
      const Eigen::Vector2d n1 = rng.normal2() / f;
      x1.emplace_back(u1 + n1(0), v1 + n1(1));
      x2.emplace_back(x1.size() % 10 < 3 ? hawor::Vec2<double>(rng.uniform2(-0.64, 0.64, -0.48, 0.48))
                                         : hawor::Vec2<double>(Eigen::Vector2d(u2, v2) + rng.normal2() / f));
    }
    std::vector<double> ms;
    hawor::TwoViewResult<double> res;
    for (int r = 0; r < repeats; ++r) {
      const double t0 = nowMs();
      res = hawor::initializeTwoView(x1, x2, hawor::TwoViewOptions<double>{});
      ms.push_back(nowMs() - t0);
    }
    const Stats s = stats(ms);
    std::printf("%-34s %27s %7s  %8.2f ms  %8.2f ms  status %d, model %d, triangulated %d\n",
                "two-view init, double", "500 corr., 30 % out", "", s.median, s.p95,
                static_cast<int>(res.status), static_cast<int>(res.model), res.numTriangulated);
  }
  return 0;
}
