// Tests of the AMX backend of hawor/matmul.hpp (bf16 tiles, the bf16x3 split) and of the
// infiller network on it. Built as its own target (test_motion_amx, tests/tests.cmake) with
// -mamx-tile -mamx-bf16 where the compiler has them, so that the kernel is compiled in; every
// case skips with a warning where the CPU or the kernel do not allow AMX (amxAvailable()).
//   * the product against a brute-force double product on shapes around the tile sizes (16 rows,
//     16 columns, k steps of 32) and the network's own, with strides and a bias: error within
//     the bf16x3 bound, and plain bf16 within its (much larger) bound;
//   * Linear and InfillerNet on the AMX backend (a small network with edge sizes against the
//     double Eigen network; 1 and 2 threads);
//   * [ref] the official-size network against onnxruntime (tests/support/infiller_ref.hpp):
//     ≤ 1e-4, as the Eigen and packed backends in ref_infiller_net.cpp.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "../support/infiller_ref.hpp"
#include "../support/random_infiller.hpp"
#include "hawor/matmul.hpp"
#include "hawor/motion/infiller_net.hpp"

namespace amx_test {

using MatD = hawor::RowMatrixX<double>;

bool skipWithoutAmx() {
#if defined(HAWOR_HAS_AMX)
  if (hawor::amxAvailable()) return false;
  WARN("AMX tiles not available on this CPU / kernel (or HAWOR_AMX=0): AMX test skipped");
#else
  WARN("built without AMX (-mamx-tile -mamx-bf16): AMX test skipped");
#endif
  return true;
}

MatD randomMatrix(Eigen::Index rows, Eigen::Index cols, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  MatD m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = u(rng);
  return m;
}

}  // namespace amx_test

TEST_CASE("backend resolution: AMX for float only, where it runs", "[motion][matmul][amx]") {
  using hawor::MatmulBackend;
  const MatmulBackend fallback = hawor::defaultMatmulBackend();
  CHECK(hawor::resolveMatmulBackend<double>(MatmulBackend::Amx) == fallback);
  CHECK(hawor::resolveMatmulBackend<double>(MatmulBackend::Auto) == fallback);
  CHECK(hawor::resolveMatmulBackend<float>(MatmulBackend::Packed) == MatmulBackend::Packed);
  const MatmulBackend amx = hawor::amxAvailable() ? MatmulBackend::Amx : fallback;
  CHECK(hawor::resolveMatmulBackend<float>(MatmulBackend::Auto) == amx);
  CHECK(hawor::resolveMatmulBackend<float>(MatmulBackend::Amx) == amx);
  CHECK(std::string(hawor::matmulBackendName(MatmulBackend::AmxBf16)) == "AmxBf16");
#if defined(HAWOR_HAS_AMX)
  if (!hawor::amxAvailable()) {  // e.g. HAWOR_AMX=0: the kernel refuses instead of faulting
    hawor::AmxPanels P;
    const float a[2] = {1, 2}, b[2] = {3, 4};
    float c[1] = {0}, scratch[2048];
    P.pack(b, 1, 1, 2, 1);
    CHECK_THROWS_AS(hawor::matmulAmx(a, 2, 1, P, c, 1, nullptr, scratch), hawor::Error);
  }
#endif
}

TEST_CASE("bf16 rounding and the hi/lo split", "[motion][matmul][amx]") {
  using hawor::detail::bf16Round;
  using hawor::detail::bf16ToFloat;
  CHECK(bf16Round(1.0f) == 0x3f80);
  CHECK(bf16Round(-2.0f) == 0xc000);
  CHECK(bf16Round(1.0f + 1.0f / 256) == 0x3f80);      // a tie: to even
  CHECK(bf16Round(1.0f + 3.0f / 256) == 0x3f82);      // a tie: to even (up)
  CHECK(bf16Round(1.0f + 1.5f / 256) == 0x3f81);      // above the tie
  CHECK(std::isnan(bf16ToFloat(bf16Round(std::nanf("")))));
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1000, 1000);
  double worst = 0;
  for (int i = 0; i < 10000; ++i) {
    const float x = u(rng);
    hawor::detail::Bf16 hi, lo;
    hawor::detail::bf16Split(x, &hi, &lo);
    const double rest = double(x) - double(bf16ToFloat(hi)) - double(bf16ToFloat(lo));
    worst = std::max(worst, std::abs(rest) / std::abs(double(x)));
  }
  CHECK(worst <= std::ldexp(1.0, -16));
}

#if defined(HAWOR_HAS_AMX)

TEST_CASE("AMX product vs a double brute-force product (bf16x3 and plain bf16 bounds)",
          "[motion][matmul][amx]") {
  if (amx_test::skipWithoutAmx()) return;
  std::mt19937 rng(17);
  // Per entry, with S = Σ_r |a_r·b_r| + |bias|: the split drops a_lo·b_lo and the residues of
  // the two splits, each ≤ 2⁻¹⁶·|a·b| (bf16 keeps 8 significant bits), and the tiles add in
  // fp32 (≤ k·2⁻²⁴·S, worst case); plain bf16 rounds each operand once (2·2⁻⁸ + 2⁻¹⁶).
  double worst3 = 0, worst1 = 0;  // largest error / S seen, for the log
  const std::vector<Eigen::Index> sizes{1, 15, 16, 17, 31, 33, 120, 384, 2048};
  int products = 0;
  for (Eigen::Index n : {1, 15, 17, 33, 120})
    for (Eigen::Index k : sizes)
      for (Eigen::Index m : sizes) {
        if (double(n) * double(k) * double(m) > 1.2e8) continue;  // keep the reference quick
        if (k == 2048 && m == 2048) continue;
        const bool withBias = (n + k + m) % 2 == 0;
        const amx_test::MatD A = amx_test::randomMatrix(n, k + 3, rng);  // lda = k + 3
        const amx_test::MatD B = amx_test::randomMatrix(k, m, rng);
        const amx_test::MatD bias = amx_test::randomMatrix(1, m, rng);
        const hawor::RowMatrixX<float> Af = A.cast<float>(), Bf = B.cast<float>();
        const hawor::VecX<float> bf = bias.row(0).transpose().cast<float>();
        hawor::AmxPanels P;
        P.pack(Bf.data(), m, 1, k, m);
        std::vector<float> scratch(static_cast<size_t>(hawor::amxScratchSize(n, k)));
        hawor::RowMatrixX<float> C3 = hawor::RowMatrixX<float>::Constant(n, m + 2, 7.0f), C1 = C3;
        hawor::matmulAmx(Af.data(), k + 3, n, P, C3.data(), m + 2, withBias ? bf.data() : nullptr,
                         scratch.data(), true);
        hawor::matmulAmx(Af.data(), k + 3, n, P, C1.data(), m + 2, withBias ? bf.data() : nullptr,
                         scratch.data(), false);
        bool ok3 = true, ok1 = true;
        const double fp32 = double(k + 1) * std::ldexp(1.0, -24);
        for (Eigen::Index i = 0; i < n; ++i)
          for (Eigen::Index j = 0; j < m; ++j) {
            double exact = withBias ? double(bf(j)) : 0.0, S = std::abs(exact);
            for (Eigen::Index r = 0; r < k; ++r) {
              const double p = double(Af(i, r)) * double(Bf(r, j));
              exact += p;
              S += std::abs(p);
            }
            const double e3 = std::abs(double(C3(i, j)) - exact);
            const double e1 = std::abs(double(C1(i, j)) - exact);
            if (S > 0) {
              worst3 = std::max(worst3, e3 / S);
              worst1 = std::max(worst1, e1 / S);
            }
            ok3 = ok3 && e3 <= (3 * std::ldexp(1.0, -16) + fp32) * S + 1e-30;
            ok1 = ok1 && e1 <= (std::ldexp(2.0, -8) + std::ldexp(1.0, -16) + fp32) * S + 1e-30;
          }
        INFO("n " << n << " k " << k << " m " << m << " bias " << withBias);
        CHECK(ok3);
        CHECK(ok1);
        CHECK((C3.rightCols(2).array() == 7.0f).all());  // nothing written past column m
        CHECK((C1.rightCols(2).array() == 7.0f).all());
        ++products;
      }
  std::printf("AMX vs double on %d shapes: max |error| / sum|a·b|: bf16x3 %.3g, plain bf16 %.3g\n",
              products, worst3, worst1);
  CHECK(worst3 <= 3 * std::ldexp(1.0, -16));  // the split's part of the bound
  CHECK(worst1 > 1e-3);                       // plain bf16 really is coarser
}

TEST_CASE("AMX product: k = 0 gives the bias; a transposed source packs the same",
          "[motion][matmul][amx]") {
  if (amx_test::skipWithoutAmx()) return;
  std::mt19937 rng(4);
  const hawor::RowMatrixX<float> A = amx_test::randomMatrix(5, 40, rng).cast<float>();
  const hawor::RowMatrixX<float> B = amx_test::randomMatrix(40, 19, rng).cast<float>();
  const hawor::RowMatrixX<float> Bt = B.transpose();
  const hawor::VecX<float> bias = amx_test::randomMatrix(19, 1, rng).col(0).cast<float>();
  hawor::AmxPanels P, Pt, P0;
  P.pack(B.data(), 19, 1, 40, 19);
  Pt.pack(Bt.data(), 1, 40, 40, 19);
  P0.pack(B.data(), 19, 1, 0, 19);
  std::vector<float> scratch(static_cast<size_t>(hawor::amxScratchSize(5, 40)));
  hawor::RowMatrixX<float> C(5, 19), Ct(5, 19), C0(5, 19);
  hawor::matmulAmx(A.data(), 40, 5, P, C.data(), 19, bias.data(), scratch.data());
  hawor::matmulAmx(A.data(), 40, 5, Pt, Ct.data(), 19, bias.data(), scratch.data());
  hawor::matmulAmx(A.data(), 40, 5, P0, C0.data(), 19, bias.data(), scratch.data());
  CHECK(C == Ct);
  for (Eigen::Index i = 0; i < 5; ++i) CHECK(C0.row(i) == bias.transpose());
}

TEST_CASE("Linear and the infiller network on AMX equal the double network",
          "[motion][infiller][amx]") {
  if (amx_test::skipWithoutAmx()) return;
  std::mt19937 rng(8);
  // Linear: x·Wᵀ + b into rows of a wider block
  const amx_test::MatD W = amx_test::randomMatrix(37, 50, rng), X = amx_test::randomMatrix(21, 50, rng);
  const amx_test::MatD b = amx_test::randomMatrix(1, 37, rng);
  amx_test::MatD expect = X * W.transpose();
  expect.rowwise() += b.row(0);
  for (auto backend : {hawor::MatmulBackend::Amx, hawor::MatmulBackend::AmxBf16}) {
    const hawor::Linear<float> lin(W.cast<float>(), b.row(0).transpose().cast<float>(), backend);
    REQUIRE(lin.backend() == backend);
    hawor::RowMatrixX<float> Xf = X.cast<float>(), Y(21, 40);
    std::vector<float> scratch(static_cast<size_t>(hawor::matmulScratchSize(21, 50)));
    lin.apply(Xf, Y.leftCols(37), scratch.data());
    const double d = (Y.leftCols(37).cast<double>() - expect).cwiseAbs().maxCoeff();
    INFO(hawor::matmulBackendName(backend) << " max |diff| " << d);
    CHECK(d <= (backend == hawor::MatmulBackend::Amx ? 1e-4 : 0.1));
  }
  // a network with sizes off the tiles: D = 48 (6 heads of 8), H = 70, F = 13, window 37
  hawor::InfillerConfig c;
  c.window = 37;
  c.features = 13;
  c.dModel = 48;
  c.heads = 6;
  c.ffDim = 70;
  c.maskedLayers = 2;
  c.encoderLayers = 2;
  const hawor::Npz npz = hawor_test::randomInfillerWeights(c, 12);
  const hawor::InfillerNet<double> ref(hawor::loadInfillerWeights<double>(npz, c),
                                       hawor::MatmulBackend::Eigen);
  const hawor::InfillerNet<float> net(hawor::loadInfillerWeights<float>(npz, c));  // Auto
  REQUIRE(net.backend() == hawor::MatmulBackend::Amx);
  const hawor::InfillerNet<float> plain(hawor::loadInfillerWeights<float>(npz, c),
                                        hawor::MatmulBackend::AmxBf16);
  hawor::ThreadPool pool(2);
  hawor::InfillerWorkspace<float> ws(c, 2);
  for (Eigen::Index T : {Eigen::Index(37), Eigen::Index(20), Eigen::Index(1)}) {
    const amx_test::MatD x = amx_test::randomMatrix(T, c.features, rng);
    hawor::ValidMask valid(static_cast<size_t>(T), 1);
    for (Eigen::Index t = T / 3; t < T / 2; ++t) valid[static_cast<size_t>(t)] = 0;
    const hawor::RowMatrixX<double> expectY = ref.forward(x, valid);
    hawor::RowMatrixX<float> y, y2, yb;
    net.forward(x.cast<float>(), valid, y, ws);
    net.forward(x.cast<float>(), valid, y2, ws, &pool);
    plain.forward(x.cast<float>(), valid, yb, ws);
    const double d = (y.cast<double>() - expectY).cwiseAbs().maxCoeff();
    const double d2 = (y2.cast<double>() - expectY).cwiseAbs().maxCoeff();
    const double db = (yb.cast<double>() - expectY).cwiseAbs().maxCoeff();
    INFO("T " << T << ": bf16x3 " << d << ", 2 threads " << d2 << ", plain bf16 " << db);
    CHECK(d <= 1e-4);
    CHECK(d2 <= 1e-4);
    CHECK(db <= 0.5);  // a sanity bound: plain bf16 is ~1e-2 here
  }
}

TEST_CASE("infiller network on AMX matches onnxruntime (official sizes, random weights)",
          "[motion][infiller][amx][ref]") {
  if (amx_test::skipWithoutAmx()) return;
  const int windows = 3;
  const auto ref =
      infiller_ref::runNodeReference("infiller_onnx_amx.txt", "--windows 3 --seed 7");
  const std::string path = std::string(HAWOR_REF_DIR) + "/infiller_onnx_amx.txt.npz";
  const hawor::Npz npz = hawor::Npz::read(path);
  std::remove(path.c_str());  // 139 MB of random weights
  const hawor::InfillerConfig official;
  const auto weights = hawor::loadInfillerWeights<float>(npz, official);
  double yMax = 0;
  for (auto backend : {hawor::MatmulBackend::Amx, hawor::MatmulBackend::AmxBf16})
    for (int threads : {1, 2}) {
      const hawor::InfillerNet<float> net(weights, backend);
      REQUIRE(net.backend() == backend);
      hawor::ThreadPool pool(threads);
      const double d = infiller_ref::maxDiff(net, ref, windows, &yMax, &pool);
      std::printf("infiller vs onnxruntime (|y| <= %.3g): max |diff| float/%s/%d thread%s %.3g\n",
                  yMax, hawor::matmulBackendName(backend), threads, threads > 1 ? "s" : "", d);
      if (backend == hawor::MatmulBackend::Amx) {
        CHECK(d <= 1e-4);
      } else {
        CHECK(d <= 0.5);  // plain bf16: reported, a sanity bound only
      }
    }
}

#endif  // HAWOR_HAS_AMX
