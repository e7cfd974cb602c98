// bench_hand — time of the MANO forward pass (hand/forward.hpp), float and double.
//
//   bench_hand [MANO_RIGHT.pkl | model.npz]
//
// Without a file it uses a random model of MANO's sizes (778 vertices, 16 joints, 10 betas,
// 135 pose features) twice: with sparse skinning weights (3 joints per vertex) and dense ones
// (all 16), since the skinning cost depends on the number of non-zero weights.
// Also checks that repeated calls do not allocate (Eigen's runtime malloc guard).
#define EIGEN_RUNTIME_NO_MALLOC
#include "hawor/hand/forward.hpp"
#include "hawor/hand/mano_loader.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <random>
#include <string>
#include <vector>

namespace {

template <typename Scalar>
hawor::HandModel<Scalar> randomMano(int jointsPerVertex, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  const int V = 778, J = 16, B = 10;
  hawor::HandModel<Scalar> m;
  m.parents = hawor::manoParents();
  m.vTemplate.resize(V, 3);
  for (Eigen::Index i = 0; i < m.vTemplate.size(); ++i) m.vTemplate.data()[i] = Scalar(0.05 * g(rng));
  m.shapedirs.resize(3 * V, B);
  for (Eigen::Index i = 0; i < m.shapedirs.size(); ++i) m.shapedirs.data()[i] = Scalar(0.004 * g(rng));
  m.posedirs.resize(3 * V, 9 * (J - 1));
  for (Eigen::Index i = 0; i < m.posedirs.size(); ++i) m.posedirs.data()[i] = Scalar(0.002 * g(rng));
  m.jRegressor = hawor::MatX<Scalar>::Zero(J, V);
  for (int j = 0; j < J; ++j)
    for (int k = 0; k < 20; ++k) m.jRegressor(j, static_cast<int>(rng() % V)) += Scalar(0.05);
  m.weights = hawor::MatX<Scalar>::Zero(V, J);
  for (int v = 0; v < V; ++v) {
    for (int k = 0; k < jointsPerVertex; ++k) m.weights(v, (v + 5 * k) % J) += Scalar(1 + (rng() % 3));
    m.weights.row(v) /= m.weights.row(v).sum();
  }
  m.faces = hawor::Faces::Zero(1538, 3);
  m.tipVertices = hawor::manoTipVertices();
  m.keypointMap = hawor::manoKeypointMap();
  m.prepare();
  return m;
}

struct Timing {
  double wallUs, cpuUs;  // medians over batches, per call
};

// Median over batches of the wall-clock and CPU time per call, in microseconds (CPU time is the
// fairer number on a loaded machine: it excludes time the process was not running).
template <typename F>
Timing timeUs(F&& f, int perBatch = 200, int batches = 15) {
  std::vector<double> w, c;
  for (int b = 0; b < batches; ++b) {
    const std::clock_t c0 = std::clock();
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < perBatch; ++i) f(i);
    const auto t1 = std::chrono::steady_clock::now();
    const std::clock_t c1 = std::clock();
    w.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count() / perBatch);
    c.push_back(1e6 * double(c1 - c0) / CLOCKS_PER_SEC / perBatch);
  }
  std::sort(w.begin(), w.end());
  std::sort(c.begin(), c.end());
  return {w[w.size() / 2], c[c.size() / 2]};
}

template <typename Scalar>
void bench(const hawor::HandModel<Scalar>& m, const char* label) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 0.5);
  std::vector<hawor::HandPose<Scalar>> poses;
  for (int k = 0; k < 16; ++k) {
    auto p = hawor::HandPose<Scalar>::zero(m);
    for (int c = 0; c < 3; ++c) p.rot(c) = Scalar(g(rng));
    for (Eigen::Index i = 0; i < p.handPose.size(); ++i) p.handPose.data()[i] = Scalar(g(rng));
    for (Eigen::Index i = 0; i < p.betas.size(); ++i) p.betas(i) = Scalar(g(rng));
    poses.push_back(p);
  }
  hawor::HandWorkspace<Scalar> ws;
  hawor::HandOutput<Scalar> out;
  hawor::forward(m, poses[0], ws, out);  // sizes the buffers
  double sink = 0;
  Eigen::internal::set_is_malloc_allowed(false);
  const Timing full = timeUs([&](int i) {
    hawor::forward(m, poses[static_cast<std::size_t>(i % 16)], ws, out);
    sink += double(out.vertices(0, 0));
  });
  const Timing posed = timeUs([&](int i) {
    hawor::poseHand(m, ws.rot.data(), poses[static_cast<std::size_t>(i % 16)].trans, ws, out);
    sink += double(out.vertices(1, 0));
  });
  // The pose-corrective product alone (3V x 9(J-1) matrix times the feature vector).
  hawor::VecX<Scalar> y(m.posedirs.rows());
  const Timing gemv = timeUs([&](int i) {
    ws.poseFeature(i % ws.poseFeature.size()) += Scalar(1e-9);
    y.noalias() = m.posedirs * ws.poseFeature;
    sink += double(y(0));
  });
  // Reading the corrective matrix once (a sum over it): the floor of any single-frame pass
  // that uses it, set by how fast this core streams 3V x 9(J-1) scalars from its caches / memory.
  const Timing floorRead = timeUs([&](int) { sink += double(m.posedirs.sum()); });
  Eigen::internal::set_is_malloc_allowed(true);
  // Many frames at once (the corrective product becomes a matrix–matrix product): with a new β
  // in every frame, and with one β for the whole sequence (one hand's shape over a clip).
  const int n = 256;
  std::vector<hawor::HandPose<Scalar>> batch, batchFixed;
  for (int i = 0; i < n; ++i) {
    batch.push_back(poses[static_cast<std::size_t>(i % 16)]);
    batchFixed.push_back(poses[static_cast<std::size_t>(i % 16)]);
    batchFixed.back().betas = poses[0].betas;
  }
  std::vector<hawor::HandOutput<Scalar>> outs(static_cast<std::size_t>(n));
  hawor::HandBatchWorkspace<Scalar> bws;
  hawor::forwardBatch(m, batch.data(), n, bws, outs.data());  // sizes the buffers
  Eigen::internal::set_is_malloc_allowed(false);
  const Timing perBatch = timeUs([&](int) {
    hawor::forwardBatch(m, batch.data(), n, bws, outs.data());
    sink += double(outs[0].vertices(0, 0));
  }, 2, 9);
  const Timing perBatchFixed = timeUs([&](int) {
    hawor::forwardBatch(m, batchFixed.data(), n, bws, outs.data());
    sink += double(outs[0].vertices(0, 0));
  }, 2, 9);
  Eigen::internal::set_is_malloc_allowed(true);
  const char* type = sizeof(Scalar) == 4 ? "float" : "double";
  std::printf("%-26s %-6s  forwardBatch(%d), fixed beta %7.2f us per frame (cpu %7.2f)\n", label, type, n,
              perBatchFixed.wallUs / n, perBatchFixed.cpuUs / n);
  std::printf("%-26s %-6s  forwardBatch(%d), new beta   %7.2f us per frame (cpu %7.2f)\n", label, type, n,
              perBatch.wallUs / n, perBatch.cpuUs / n);
  std::printf("%-26s %-6s  forward %7.2f us (cpu %7.2f)  poseHand %7.2f (cpu %7.2f)  correctives %7.2f (cpu %7.2f)"
              "  read floor %7.2f%s\n",
              label, type, full.wallUs, full.cpuUs, posed.wallUs, posed.cpuUs, gemv.wallUs, gemv.cpuUs,
              floorRead.wallUs, sink == 12345.0 ? " " : "");
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc > 1) {
      hawor::ManoLoadOptions opt;
      opt.side = hawor::HandSide::Right;
      const auto md = hawor::loadMano<double>(argv[1], opt);
      bench(md, argv[1]);
      bench(hawor::castHandModel<float>(md), argv[1]);
      return 0;
    }
    bench(randomMano<double>(3, 1), "random, 3 weights/vertex");
    bench(randomMano<float>(3, 1), "random, 3 weights/vertex");
    bench(randomMano<double>(16, 1), "random, dense weights");
    bench(randomMano<float>(16, 1), "random, dense weights");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
