// bench_infiller — time of one forward pass of the infiller network (motion/infiller_net.hpp):
// one 120-frame, two-hand window at the official sizes, float and double, on 1 and 2 threads
// (hawor::ThreadPool: the window's frames split between the threads) in the same run.
//
//   bench_infiller [--repeats N] [--weights W.npz] [--all-backends] [--backends LIST]
//                  [--threads 1,2]
//
// Without --weights the network has random weights (the speed does not depend on them). The
// default matrix-product backend is the network's own (Auto: AMX tiles with the bf16x3 split for
// float where the build and CPU have AMX, else Eigen natively and the packed SIMD kernel in
// WebAssembly); --all-backends times every backend that runs here (Eigen, Packed, Amx, AmxBf16;
// Eigen in WebAssembly takes seconds per window); --backends eigen,packed,amx,amx-bf16 picks.
// The AMX backends are float only (double lines are Eigen/Packed). Prints the median, 95th
// percentile and minimum wall time and the median CPU time (all threads) per window over N timed
// runs (after two warm-up runs), the arithmetic rate per median wall second, the largest
// |y − y_ref| against one double-precision Eigen forward on the same input (float lines), and
// (natively, glibc) the heap allocations per forward pass. Where the build has no threads
// (WebAssembly without -pthread) a pool of any size runs on one thread, and the line says so.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "hawor/motion/infiller_net.hpp"

// Heap allocation counter (this executable only): operator new and, with glibc, malloc itself
// (Eigen allocates with malloc).
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

// CPU time of the process in ms, every thread (wall time where there is no CPU clock, as in
// WebAssembly).
double cpuMs() {
#if defined(CLOCK_PROCESS_CPUTIME_ID) && !defined(__EMSCRIPTEN__)
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return 1e3 * double(ts.tv_sec) + 1e-6 * double(ts.tv_nsec);
#else
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
#endif
}

// Multiply-adds ×2 of one forward pass over T frames (products only; the rest is < 1 %).
double forwardFlops(const hawor::InfillerConfig& c, double T) {
  const double D = c.dModel, H = c.ffDim, F = c.features;
  const double attention = 2 * T * T * D;  // q·kᵀ and p·v, all heads
  const double block = T * D * 3 * D + attention + T * D * D + 2 * T * D * H;
  return 2 * (T * (F + 1) * D + (c.maskedLayers + c.encoderLayers) * block + T * D * F);
}

// Random weights of the official sizes, as float32 tensors (what a converted checkpoint holds).
hawor::Npz randomWeights(const hawor::InfillerConfig& c) {
  std::mt19937 rng(1);
  hawor::Npz npz;
  for (const auto& s : hawor::infillerTensorSpecs(c)) {
    if (s.optional) continue;
    size_t n = 1;
    for (size_t d : s.shape) n *= d;
    const bool norm = s.name.find("norm") != std::string::npos;
    const float bound =
        norm ? 0.1f : 1.0f / std::sqrt(float(s.shape.size() == 2 ? s.shape[1] : c.dModel));
    std::uniform_real_distribution<float> u(-bound, bound);
    std::vector<float> v(n);
    const bool gain = norm && s.name.compare(s.name.size() - 6, 6, "weight") == 0;
    for (float& x : v) x = (gain ? 1.0f : 0.0f) + u(rng);
    npz.set(s.name, hawor::NpyArray::fromData(v.data(), s.shape));
  }
  return npz;
}

// The benchmark's window: random features, a 30-frame and a 12-frame gap.
template <typename Scalar>
hawor::RowMatrixX<Scalar> benchInput(const hawor::InfillerConfig& c, hawor::ValidMask& valid) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  hawor::RowMatrixX<Scalar> x(c.window, c.features);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = Scalar(u(rng));
  valid.assign(static_cast<size_t>(c.window), 1);
  for (int t = 30; t < 60; ++t) valid[static_cast<size_t>(t)] = 0;  // a 30-frame gap
  for (int t = 100; t < 112; ++t) valid[static_cast<size_t>(t)] = 0;
  return x;
}

template <typename Scalar>
void bench(const hawor::Npz& npz, hawor::MatmulBackend backend, int repeats, int threads,
           const hawor::RowMatrixX<double>& reference) {
  const hawor::InfillerConfig c;
  const hawor::InfillerNet<Scalar> net(hawor::loadInfillerWeights<Scalar>(npz, c), backend);
  hawor::ValidMask valid;
  const hawor::RowMatrixX<Scalar> x = benchInput<Scalar>(c, valid);
  hawor::RowMatrixX<Scalar> y;
  hawor::ThreadPool pool(threads);
  hawor::InfillerWorkspace<Scalar> ws(c, pool.size());
  net.forward(x, valid, y, ws, &pool);  // warm-up: sizes y, pages in the weights, tiers up wasm
  net.forward(x, valid, y, ws, &pool);
  std::vector<double> wall, cpu;
  wall.reserve(static_cast<size_t>(repeats));
  cpu.reserve(static_cast<size_t>(repeats));
  double sink = 0;
  const long alloc0 = g_allocations.load();
  for (int r = 0; r < repeats; ++r) {
    const double c0 = cpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    net.forward(x, valid, y, ws, &pool);
    const auto t1 = std::chrono::steady_clock::now();
    cpu.push_back(cpuMs() - c0);
    wall.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    sink += double(y(0, 0));
  }
  const double allocations = double(g_allocations.load() - alloc0) / repeats;
  std::sort(wall.begin(), wall.end());
  std::sort(cpu.begin(), cpu.end());
  const double medWall = wall[wall.size() / 2], medCpu = cpu[cpu.size() / 2];
  const double p95 = wall[std::min(wall.size() - 1, (wall.size() * 95 + 99) / 100 - 1)];
  const double diff = (y.template cast<double>() - reference).cwiseAbs().maxCoeff();
  std::printf(
      "infiller forward, %d frames x %d features: %-6s %-7s %d thread%s%s median %7.1f ms (p95 "
      "%7.1f, min %7.1f, cpu %7.1f)  %5.1f GFLOP/s  max|y-y_double| %.2g  allocations/forward "
      "%s%s\n",
      c.window, c.features, sizeof(Scalar) == 4 ? "float" : "double",
      hawor::matmulBackendName(net.backend()), pool.size(), pool.size() == 1 ? " " : "s",
      pool.size() < threads ? " (no threads here)" : "", medWall, p95, wall.front(), medCpu,
      forwardFlops(c, c.window) / medWall * 1e-6, diff,
#ifdef HAWOR_BENCH_COUNTS_MALLOC
      std::to_string(allocations).substr(0, 4).c_str(),
#else
      "n/a",
#endif
      sink == 12345.0 ? " " : "");
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  try {
#ifdef __EMSCRIPTEN__
    int repeats = 7;
#else
    int repeats = 15;
#endif
    std::string weights;
    bool all = false;
    std::vector<hawor::MatmulBackend> chosen;
    std::vector<int> threadCounts{1, 2};
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--repeats" && i + 1 < argc) {
        repeats = std::max(1, std::atoi(argv[++i]));
      } else if (a == "--weights" && i + 1 < argc) {
        weights = argv[++i];
      } else if (a == "--all-backends") {
        all = true;
      } else if (a == "--backends" && i + 1 < argc) {
        const std::string list = std::string(argv[++i]) + ",";
        for (size_t p = 0, q; (q = list.find(',', p)) != std::string::npos; p = q + 1) {
          const std::string name = list.substr(p, q - p);
          if (name == "eigen") {
            chosen.push_back(hawor::MatmulBackend::Eigen);
          } else if (name == "packed") {
            chosen.push_back(hawor::MatmulBackend::Packed);
          } else if (name == "amx") {
            chosen.push_back(hawor::MatmulBackend::Amx);
          } else if (name == "amx-bf16") {
            chosen.push_back(hawor::MatmulBackend::AmxBf16);
          } else if (!name.empty()) {
            std::fprintf(stderr, "bench_infiller: unknown backend %s\n", name.c_str());
            return 2;
          }
        }
      } else if (a == "--threads" && i + 1 < argc) {
        threadCounts.clear();
        for (const char* p = argv[++i]; *p;) {
          char* end = nullptr;
          const long n = std::strtol(p, &end, 10);
          if (end == p || n < 1 || n > 64) {
            std::fprintf(stderr, "bench_infiller: --threads wants counts like 1,2\n");
            return 2;
          }
          threadCounts.push_back(static_cast<int>(n));
          p = *end == ',' ? end + 1 : end;
        }
      } else {
        std::fprintf(stderr,
                     "usage: bench_infiller [--repeats N] [--weights W.npz] [--all-backends] "
                     "[--backends eigen,packed,amx,amx-bf16] [--threads 1,2]\n");
        return 2;
      }
    }
    const hawor::InfillerConfig c;
    std::printf("infiller network: %.2f GFLOP per %d-frame window\n",
                forwardFlops(c, c.window) * 1e-9, c.window);
    const hawor::Npz npz = weights.empty() ? randomWeights(c) : hawor::Npz::read(weights);
    std::vector<hawor::MatmulBackend> backends = chosen;
    if (all) {
      backends = {hawor::defaultMatmulBackend(),
                  hawor::defaultMatmulBackend() == hawor::MatmulBackend::Eigen
                      ? hawor::MatmulBackend::Packed
                      : hawor::MatmulBackend::Eigen,
                  hawor::MatmulBackend::Amx, hawor::MatmulBackend::AmxBf16};
    } else if (backends.empty()) {
      backends = {hawor::MatmulBackend::Auto};
    }
    std::printf("AMX (bf16 tiles): %s\n",
                hawor::amxAvailable() ? "available"
#if defined(HAWOR_HAS_AMX)
                                      : "compiled in, not available on this CPU / kernel"
#else
                                      : "not compiled in (no -mamx-tile -mamx-bf16)"
#endif
    );
    // The reference output: one double-precision Eigen forward on the benchmark's input.
    hawor::RowMatrixX<double> reference;
    {
      const hawor::InfillerNet<double> ref(hawor::loadInfillerWeights<double>(npz, c),
                                           hawor::MatmulBackend::Eigen);
      hawor::ValidMask valid;
      reference = ref.forward(benchInput<double>(c, valid), valid);
    }
    for (auto b : backends) {
      const bool amx = b == hawor::MatmulBackend::Amx || b == hawor::MatmulBackend::AmxBf16;
      if (amx && hawor::resolveMatmulBackend<float>(b) != b) continue;  // not here
      for (int t : threadCounts) bench<float>(npz, b, repeats, t, reference);
      if (amx) continue;  // float only
      for (int t : threadCounts) bench<double>(npz, b, repeats, t, reference);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
