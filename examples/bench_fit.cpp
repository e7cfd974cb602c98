// bench_fit — speed and accuracy of the per-frame hand fit (hand/fit.hpp) on synthetic data.
//
//   bench_fit [--model FILE] [--hands N] [--sequences N] [--frames N] [--seed S] [--float]
//
// Ground truth: poses sampled inside the joint limits (hand/joint_limits.hpp), shapes β ~ U(−1.5,
// 1.5) (models with a shape space), random global orientation, wrist 0.3–0.8 m in front of a
// 640×480 camera with fx = fy = 500; observations: the model's 21 keypoints projected with
// N(0, σ²) pixel noise, σ ~ U(1, 2) px per hand, and the 3D keypoints with N(0, (5 mm)²) noise per
// axis and an arbitrary origin. Model: --model FILE (a MANO .pkl / .npz, a hawor hand-model .npz,
// or a .glb skinned hand), else the procedural MANO-structured hand (hand/synthetic_hand.hpp).
//
// Reported: time per fit (median, p95) for cold starts, warm starts from a nearby previous
// frame (the truth perturbed by 0.05 rad / 1 cm / 0.05 rad per joint) and smooth 30 fps
// sequences fitted with warm starts; 21-keypoint PA-MPJPE (mm, similarity Procrustes per hand,
// docs/design.md §8) and wrist (root) position error (cm, camera frame), medians; heap allocations per
// warm fit (constant: the result's arrays only, none per iteration).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <random>
#include <string>
#include <vector>
#include <time.h>

#include "hawor/geometry/alignment.hpp"
#include "hawor/hand/fit.hpp"
#include "hawor/hand/portable_random.hpp"
#include "hawor/hand/synthetic_hand.hpp"
#ifndef HAWOR_BENCH_NO_MODEL_FILES  // define to build without the model-file readers
#include "hawor/hand/default_hand.hpp"
#include "hawor/hand/mano_loader.hpp"
#include "hawor/hand/model_io.hpp"
#endif

// Heap allocation counter (this executable only): operator new and, with glibc, malloc itself
// (Eigen allocates with malloc), so "allocations per fit" counts every heap allocation.
static std::atomic<long> g_allocations{0};
#if defined(__GLIBC__) && !defined(__EMSCRIPTEN__)
extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);
extern "C" void __libc_free(void*);
extern "C" void* malloc(std::size_t n) {
  ++g_allocations;
  return __libc_malloc(n);
}
extern "C" void* calloc(std::size_t n, std::size_t m) {
  ++g_allocations;
  return __libc_calloc(n, m);
}
extern "C" void* realloc(void* p, std::size_t n) {
  ++g_allocations;
  return __libc_realloc(p, n);
}
extern "C" void free(void* p) { __libc_free(p); }
#define HAWOR_BENCH_COUNTS_MALLOC 1
#endif
void* operator new(std::size_t n) {
#ifndef HAWOR_BENCH_COUNTS_MALLOC
  ++g_allocations;
#endif
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

using Clock = std::chrono::steady_clock;

double ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

// CPU time of this thread in ms (not inflated when other processes share the cores); wall
// time where the platform has no thread clock.
double cpuMs() {
#if defined(CLOCK_THREAD_CPUTIME_ID) && !defined(__EMSCRIPTEN__)
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
#else
  return std::chrono::duration<double, std::milli>(Clock::now().time_since_epoch()).count();
#endif
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(pos);
  const double f = pos - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

template <typename Scalar>
hawor::PinholeCamera<Scalar> camera() {
  hawor::PinholeCamera<Scalar> c;
  c.fx = c.fy = Scalar(500);
  c.cx = Scalar(319.5);
  c.cy = Scalar(239.5);
  c.width = 640;
  c.height = 480;
  return c;
}

template <typename Scalar>
hawor::HandModel<Scalar> loadModel(const std::string& path) {
  if (path.empty()) return hawor::makeSyntheticHand<Scalar>();
#ifdef HAWOR_BENCH_NO_MODEL_FILES
  throw hawor::Error("bench_fit: built without model-file readers (HAWOR_BENCH_NO_MODEL_FILES)");
#else
  auto endsWith = [&](const std::string& s) {
    return path.size() >= s.size() && path.compare(path.size() - s.size(), s.size(), s) == 0;
  };
  std::string lower = path;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const bool left = lower.find("left") != std::string::npos;
  if (endsWith(".glb")) return hawor::loadDefaultHand<Scalar>(path, left).model;
  if (endsWith(".npz")) {
    const hawor::Npz z = hawor::Npz::read(path);
    if (hawor::isHandModelNpz(z)) return hawor::handModelFromNpz<Scalar>(z);
  }
  return hawor::loadMano<Scalar>(path);
#endif
}

template <typename Scalar>
hawor::Vec3<Scalar> randomRotation(std::mt19937& rng) {
  const double w = hawor::standardNormal(rng), x = hawor::standardNormal(rng), y = hawor::standardNormal(rng),
               z = hawor::standardNormal(rng);
  Eigen::Quaterniond q(w, x, y, z);
  q.normalize();
  return hawor::quaternionToAxisAngle(q).cast<Scalar>();
}

// Wrist keypoint at (x, y, z) for pose p (sets transl).
template <typename Scalar>
void placeWrist(const hawor::HandModel<Scalar>& m, hawor::HandPose<Scalar>& p, const Eigen::Vector3d& at) {
  p.trans.setZero();
  const hawor::HandOutput<Scalar> o = hawor::forward(m, p);
  p.trans = at.cast<Scalar>() - o.keypoints.row(0).transpose();
}

Eigen::Vector3d randomWristPosition(std::mt19937& rng) {
  const double z = 0.3 + 0.5 * hawor::uniform01(rng);
  const double u = hawor::uniform01(rng), v = hawor::uniform01(rng);
  return Eigen::Vector3d((u - 0.5) * 0.5 * z * 640.0 / 500.0, (v - 0.5) * 0.5 * z * 480.0 / 500.0, z);
}

template <typename Scalar>
hawor::HandObservation<Scalar> observe(const hawor::HandModel<Scalar>& m, const hawor::HandPose<Scalar>& p,
                                       const hawor::PinholeCamera<Scalar>& cam, double px, double metres,
                                       std::mt19937& rng, hawor::Points3<double>& gt) {
  auto g = [](std::mt19937& r) { return hawor::standardNormal(r); };
  const hawor::HandOutput<Scalar> o = hawor::forward(m, p);
  const int K = static_cast<int>(o.keypoints.rows());
  gt = o.keypoints.template cast<double>();
  hawor::HandObservation<Scalar> obs;
  obs.keypoints2d.resize(K, 2);
  obs.keypoints3d.resize(K, 3);
  for (int k = 0; k < K; ++k) {
    const hawor::Vec2<Scalar> uv = cam.project(hawor::Vec3<Scalar>(o.keypoints.row(k).transpose()));
    obs.keypoints2d(k, 0) = uv(0) + Scalar(px * g(rng));
    obs.keypoints2d(k, 1) = uv(1) + Scalar(px * g(rng));
    for (int c = 0; c < 3; ++c) {
      obs.keypoints3d(k, c) = Scalar(gt(k, c) - gt(0, c) + 0.02 + metres * g(rng));
    }
  }
  obs.confidence2d = hawor::VecX<Scalar>::Ones(K);
  obs.confidence3d = hawor::VecX<Scalar>::Ones(K);
  return obs;
}

struct Errors {
  double paMm, rootCm;
};

template <typename Scalar>
Errors errors(const hawor::Points3<Scalar>& est, const hawor::Points3<double>& gt) {
  const hawor::Points3<double> e = est.template cast<double>();
  const hawor::SimilarityTransform<double> T = hawor::umeyama(e, gt, true);
  const hawor::Points3<double> a = T.apply(e);
  return {1000.0 * (a - gt).rowwise().norm().mean(), 100.0 * (e.row(0) - gt.row(0)).norm()};
}

struct Report {
  std::vector<double> time, cpu, pa, root;
  std::vector<double> iterations;
  void add(double t, double c, const Errors& e, int it) {
    time.push_back(t);
    cpu.push_back(c);
    pa.push_back(e.paMm);
    root.push_back(e.rootCm);
    iterations.push_back(it);
  }
  void print(const char* name) const {
    std::printf("%-32s n=%5zu | wall median %.3f ms p95 %.3f | cpu median %.3f ms p95 %.3f | iters median %.0f "
                "p95 %.0f | PA-MPJPE median %.2f mm p95 %.2f | root err median %.2f cm p95 %.2f\n",
                name, time.size(), quantile(time, 0.5), quantile(time, 0.95), quantile(cpu, 0.5), quantile(cpu, 0.95),
                quantile(iterations, 0.5), quantile(iterations, 0.95), quantile(pa, 0.5), quantile(pa, 0.95),
                quantile(root, 0.5), quantile(root, 0.95));
  }
};

template <typename Scalar>
int run(const std::string& modelPath, int hands, int sequences, int frames, unsigned seed) {
  const hawor::HandModel<Scalar> m = loadModel<Scalar>(modelPath);
  if (m.numKeypoints() != 21) {
    std::fprintf(stderr, "bench_fit: the model has %d keypoints, expected 21\n", m.numKeypoints());
    return 1;
  }
  std::printf("model: %s (J=%d, V=%d, B=%d, pose correctives %s), scalar %s\n",
              modelPath.empty() ? "procedural MANO-structured hand" : modelPath.c_str(), m.numJoints(),
              m.numVertices(), m.numBetas(), m.numPoseFeatures() ? "yes" : "no",
              sizeof(Scalar) == 4 ? "float" : "double");
  hawor::HandFitter<Scalar> fitter(m);
  const hawor::JointLimits<Scalar>& lim = fitter.limits();
  const hawor::PinholeCamera<Scalar> cam = camera<Scalar>();
  std::mt19937 rng(seed);
  auto uni = [](std::mt19937& r) { return hawor::uniform01(r); };
  auto g = [](std::mt19937& r) { return hawor::standardNormal(r); };
  hawor::HandFitOptions<Scalar> opt;
  opt.sigmaPx = Scalar(1.5);
  opt.sigma3d = Scalar(0.005);

  Report cold, warm, seq;
  long warmAllocs = 0;
  int warmFits = 0, warmIterations = 0;
  for (int h = 0; h < hands; ++h) {
    hawor::HandPose<Scalar> truth = hawor::HandPose<Scalar>::zero(m);
    truth.handPose = hawor::sampleJointPose(lim, rng, 0.9);
    truth.rot = randomRotation<Scalar>(rng);
    for (int b = 0; b < truth.betas.size(); ++b) truth.betas(b) = Scalar(-1.5 + 3.0 * uni(rng));
    placeWrist(m, truth, randomWristPosition(rng));
    hawor::Points3<double> gt;
    const double px = 1.0 + uni(rng);
    const hawor::HandObservation<Scalar> obs = observe(m, truth, cam, px, 0.005, rng, gt);
    double c0 = cpuMs();
    auto t0 = Clock::now();
    const hawor::HandFitResult<Scalar> rc = fitter.fit(obs, cam, opt);
    auto t1 = Clock::now();
    cold.add(ms(t0, t1), cpuMs() - c0, errors(rc.keypoints, gt), rc.iterations);
    // Warm start from a nearby previous frame.
    hawor::HandPose<Scalar> prev = truth;
    const double d0 = g(rng), d1 = g(rng), d2 = g(rng);
    prev.rot = hawor::matrixToAxisAngle(hawor::Mat3<Scalar>(
        hawor::axisAngleToMatrix(hawor::Vec3<Scalar>(Scalar(0.03 * d0), Scalar(0.03 * d1), Scalar(0.03 * d2))) *
        hawor::axisAngleToMatrix(truth.rot)));
    for (int c = 0; c < 3; ++c) prev.trans(c) += Scalar(0.006 * g(rng));
    for (Eigen::Index i = 0; i < prev.handPose.size(); ++i) prev.handPose.data()[i] += Scalar(0.03 * g(rng));
    prev.betas = rc.pose.betas;
    const long a0 = g_allocations.load();
    c0 = cpuMs();
    t0 = Clock::now();
    const hawor::HandFitResult<Scalar> rw = fitter.fit(obs, cam, opt, &prev);
    t1 = Clock::now();
    const double c1 = cpuMs();
    warmAllocs += g_allocations.load() - a0;
    warmIterations += rw.iterations;
    ++warmFits;
    warm.add(ms(t0, t1), c1 - c0, errors(rw.keypoints, gt), rw.iterations);
  }

  // Smooth sequences at 30 fps, warm-started from the previous frame's solution.
  for (int s = 0; s < sequences; ++s) {
    hawor::HandPose<Scalar> base = hawor::HandPose<Scalar>::zero(m);
    for (int b = 0; b < base.betas.size(); ++b) base.betas(b) = Scalar(-1.5 + 3.0 * uni(rng));
    const hawor::Vec3<Scalar> orient = randomRotation<Scalar>(rng);
    const Eigen::Vector3d wrist = randomWristPosition(rng);
    const int J = m.numJoints();
    std::vector<double> phase(static_cast<std::size_t>(3 * J + 6)), freq(phase.size());
    for (std::size_t i = 0; i < phase.size(); ++i) {
      phase[i] = 6.283185307179586 * uni(rng);
      freq[i] = 0.15 + 0.5 * uni(rng);  // Hz
    }
    hawor::HandPose<Scalar> prevSolution;
    for (int f = 0; f < frames; ++f) {
      const double t = f / 30.0;
      hawor::HandPose<Scalar> truth = base;
      for (int j = 1; j < J; ++j) {
        if (!lim.limited(j)) continue;
        const hawor::JointRange<Scalar>& r = lim.ranges[static_cast<std::size_t>(j)];
        hawor::Vec3<Scalar> a;
        for (int c = 0; c < 3; ++c) {
          const std::size_t i = static_cast<std::size_t>(3 * j + c);
          const double lo = static_cast<double>(r.lo(c)), hi = static_cast<double>(r.hi(c));
          a(c) = Scalar(0.5 * (lo + hi) + 0.4 * (hi - lo) * std::sin(6.283185307179586 * freq[i] * t + phase[i]));
        }
        truth.handPose.row(j - 1) = lim.axisAngle(j, a).transpose();
      }
      hawor::Vec3<Scalar> dr;
      Eigen::Vector3d dt;
      for (int c = 0; c < 3; ++c) {
        dr(c) = Scalar(0.5 * std::sin(6.283185307179586 * freq[static_cast<std::size_t>(c)] * t + phase[static_cast<std::size_t>(c)]));
        dt(c) = 0.06 * std::sin(6.283185307179586 * freq[static_cast<std::size_t>(3 + c)] * t + phase[static_cast<std::size_t>(3 + c)]);
      }
      truth.rot = hawor::matrixToAxisAngle(hawor::Mat3<Scalar>(hawor::axisAngleToMatrix(dr) * hawor::axisAngleToMatrix(orient)));
      placeWrist(m, truth, wrist + dt);
      hawor::Points3<double> gt;
      const hawor::HandObservation<Scalar> obs = observe(m, truth, cam, 1.0 + uni(rng), 0.005, rng, gt);
      const double c0 = cpuMs();
      const auto t0 = Clock::now();
      const hawor::HandFitResult<Scalar> r = fitter.fit(obs, cam, opt, f == 0 ? nullptr : &prevSolution);
      const auto t1 = Clock::now();
      if (f > 0) seq.add(ms(t0, t1), cpuMs() - c0, errors(r.keypoints, gt), r.iterations);
      prevSolution = r.pose;
    }
  }
  cold.print("single frames, cold start");
  warm.print("single frames, warm start");
  seq.print("sequences (30 fps), warm start");
  std::printf("heap allocations per warm fit: %.2f over %.2f LM iterations on average (the result's arrays)\n",
              warmFits ? static_cast<double>(warmAllocs) / warmFits : 0.0,
              warmFits ? static_cast<double>(warmIterations) / warmFits : 0.0);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string model;
  int hands = 300, sequences = 5, frames = 100;
  unsigned seed = 1;
  bool useFloat = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_fit: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--model") {
      model = next();
    } else if (a == "--hands") {
      hands = std::atoi(next().c_str());
    } else if (a == "--sequences") {
      sequences = std::atoi(next().c_str());
    } else if (a == "--frames") {
      frames = std::atoi(next().c_str());
    } else if (a == "--seed") {
      seed = static_cast<unsigned>(std::atoi(next().c_str()));
    } else if (a == "--float") {
      useFloat = true;
    } else {
      std::fprintf(stderr,
                   "usage: bench_fit [--model FILE] [--hands N] [--sequences N] [--frames N] [--seed S] [--float]\n");
      return 2;
    }
  }
  try {
    return useFloat ? run<float>(model, hands, sequences, frames, seed) : run<double>(model, hands, sequences, frames, seed);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
