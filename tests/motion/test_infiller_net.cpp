// Unit/property tests of hawor/matmul.hpp, motion/infiller_weights.hpp and
// motion/infiller_net.hpp (native and WASM): the packed kernel against plain loops, the network
// against a naive implementation written here from docs/design.md §7 / the official model, the
// attention mask, the positional table, and the weight loader's errors. (The comparison with
// onnxruntime on the official sizes is ref_infiller_net.cpp.)
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "../support/random_infiller.hpp"
#include "hawor/motion/infiller_net.hpp"

template class hawor::Linear<float>;
template class hawor::Linear<double>;
template class hawor::PackedPanels<float>;
template class hawor::PackedPanels<double>;
template class hawor::InfillerNet<float>;
template class hawor::InfillerNet<double>;
template struct hawor::InfillerWorkspace<float>;
template struct hawor::InfillerWorkspace<double>;

namespace infiller_test {

using MatD = hawor::RowMatrixX<double>;

hawor::InfillerConfig smallConfig(int encoderLayers = 2) {
  hawor::InfillerConfig c;
  c.window = 12;
  c.features = 10;
  c.dModel = 16;
  c.heads = 4;
  c.ffDim = 24;
  c.maskedLayers = 2;
  c.encoderLayers = encoderLayers;
  return c;
}

template <typename S>
double tol() {
  return std::is_same<S, float>::value ? 2e-4 : 1e-10;
}

MatD randomMatrix(Eigen::Index rows, Eigen::Index cols, std::mt19937& rng, double lo = -1,
                  double hi = 1) {
  std::uniform_real_distribution<double> u(lo, hi);
  MatD m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = u(rng);
  return m;
}

// Every tensor of `c` with random values (tests/support/random_infiller.hpp).
inline hawor::Npz randomWeightsNpz(const hawor::InfillerConfig& c, unsigned seed) {
  return hawor_test::randomInfillerWeights(c, seed);
}

// Round trip through the archive bytes, as a file would be read.
hawor::Npz reread(const hawor::Npz& npz) {
  return hawor::Npz::fromBuffer(npz.toBuffer(), "weights.npz");
}

// ---- the naive reference (double, plain loops, written from docs/design.md §7 / the official model)

MatD refLinear(const MatD& X, const MatD& W, const hawor::VecX<double>& b) {
  MatD Y(X.rows(), W.rows());
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (Eigen::Index o = 0; o < W.rows(); ++o) {
      double s = b.size() ? b(o) : 0.0;
      for (Eigen::Index k = 0; k < X.cols(); ++k) s += X(i, k) * W(o, k);
      Y(i, o) = s;
    }
  return Y;
}

MatD refLayerNorm(const MatD& X, const hawor::VecX<double>& g, const hawor::VecX<double>& b) {
  MatD Y(X.rows(), X.cols());
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    double mean = 0, var = 0;
    for (Eigen::Index k = 0; k < X.cols(); ++k) mean += X(i, k) / double(X.cols());
    for (Eigen::Index k = 0; k < X.cols(); ++k)
      var += (X(i, k) - mean) * (X(i, k) - mean) / double(X.cols());
    for (Eigen::Index k = 0; k < X.cols(); ++k)
      Y(i, k) = (X(i, k) - mean) / std::sqrt(var + 1e-5) * g(k) + b(k);
  }
  return Y;
}

// Multi-head attention on separate q, k, v (T × D): per head, softmax over keys of q·k·scale,
// keys with valid == 0 skipped when `masked`.
MatD refAttention(const MatD& q, const MatD& k, const MatD& v, int heads, double scale,
                  const hawor::ValidMask* masked) {
  const Eigen::Index T = q.rows(), D = q.cols(), dh = D / heads;
  MatD out = MatD::Zero(T, D);
  for (int h = 0; h < heads; ++h)
    for (Eigen::Index i = 0; i < T; ++i) {
      std::vector<double> s(static_cast<size_t>(T), -std::numeric_limits<double>::infinity());
      double mx = -std::numeric_limits<double>::infinity();
      for (Eigen::Index j = 0; j < T; ++j) {
        if (masked && !(*masked)[static_cast<size_t>(j)]) continue;
        double d = 0;
        for (Eigen::Index c = 0; c < dh; ++c) d += q(i, h * dh + c) * k(j, h * dh + c);
        s[static_cast<size_t>(j)] = d * scale;
        mx = std::max(mx, d * scale);
      }
      double sum = 0;
      for (double& x : s) sum += (x = std::exp(x - mx));
      for (Eigen::Index j = 0; j < T; ++j)
        for (Eigen::Index c = 0; c < dh; ++c)
          out(i, h * dh + c) += s[static_cast<size_t>(j)] / sum * v(j, h * dh + c);
    }
  return out;
}

MatD refForward(const hawor::InfillerWeights<double>& w, const MatD& x,
                const hawor::ValidMask& valid) {
  const auto& c = w.config;
  const Eigen::Index T = x.rows(), D = c.dModel;
  MatD in(T, c.features + 1);
  for (Eigen::Index t = 0; t < T; ++t) {
    in.row(t).head(c.features) = x.row(t);
    in(t, c.features) = valid[static_cast<size_t>(t)] ? 1.0 : 0.0;
  }
  MatD h = refLinear(in, w.inputWeight, w.inputBias);
  for (Eigen::Index t = 0; t < T; ++t)
    for (Eigen::Index k = 0; k < D; ++k) {
      // PE(t, 2i) = sin(t / 10000^(2i/D)), PE(t, 2i+1) = cos(t / 10000^(2i/D))
      const double angle = double(t) / std::pow(10000.0, double(k - k % 2) / double(D));
      h(t, k) +=
          w.positional.size() ? w.positional(t, k) : (k % 2 ? std::cos(angle) : std::sin(angle));
    }
  const hawor::VecX<double> none;
  for (const auto& b : w.maskedBlocks) {
    const MatD n = refLayerNorm(h, b.attnNormWeight, b.attnNormBias);
    const MatD a = refAttention(refLinear(n, b.q, none), refLinear(n, b.k, none),
                                refLinear(n, b.v, none), c.heads, 1 / std::sqrt(double(D)), &valid);
    h = n + refLinear(a, b.out, none);
    MatD f = refLinear(refLayerNorm(h, b.ffNormWeight, b.ffNormBias), b.ff1Weight, b.ff1Bias);
    f = f.cwiseMax(0.0);
    h += refLinear(f, b.ff2Weight, b.ff2Bias);
  }
  h = refLayerNorm(h, w.normWeight, w.normBias);
  for (const auto& e : w.encoderLayers) {
    const MatD qkv = refLinear(h, e.inProjWeight, e.inProjBias);
    const MatD a = refAttention(qkv.leftCols(D), qkv.middleCols(D, D), qkv.rightCols(D), c.heads,
                                1 / std::sqrt(double(D / c.heads)), nullptr);
    h = refLayerNorm(h + refLinear(a, e.outProjWeight, e.outProjBias), e.norm1Weight, e.norm1Bias);
    MatD f = refLinear(h, e.linear1Weight, e.linear1Bias);
    for (Eigen::Index i = 0; i < f.size(); ++i)
      f.data()[i] = 0.5 * f.data()[i] * (1 + std::erf(f.data()[i] / std::sqrt(2.0)));
    h = refLayerNorm(h + refLinear(f, e.linear2Weight, e.linear2Bias), e.norm2Weight, e.norm2Bias);
  }
  return refLinear(h, w.decoderWeight, w.decoderBias);
}

hawor::ValidMask gapMask(Eigen::Index T) {
  hawor::ValidMask v(static_cast<size_t>(T), 1);
  for (Eigen::Index t = 2; t < std::min<Eigen::Index>(T, 7); ++t) v[static_cast<size_t>(t)] = 0;
  if (T > 9) v[static_cast<size_t>(T - 1)] = 0;
  return v;
}

const char* backendName(hawor::MatmulBackend b) {
  return b == hawor::MatmulBackend::Eigen ? "Eigen" : "Packed";
}

}  // namespace infiller_test

TEMPLATE_TEST_CASE("packed matrix product equals plain loops (edges, strides, bias, k slices)",
                   "[motion][infiller][matmul]", float, double) {
  using S = TestType;
  std::mt19937 rng(11);
  for (Eigen::Index n : {1, 3, 4, 5, 9}) {
    for (Eigen::Index k : {0, 1, 7, 300, 530}) {
      for (Eigen::Index m : {1, 3, 4, 8, 9, 17}) {
        for (bool withBias : {false, true}) {
          const infiller_test::MatD A = infiller_test::randomMatrix(n, k + 3, rng);  // lda = k+3
          const infiller_test::MatD B = infiller_test::randomMatrix(k, m, rng);
          const infiller_test::MatD bias = infiller_test::randomMatrix(1, m, rng);
          hawor::RowMatrixX<S> As = A.cast<S>(), Bs = B.cast<S>();
          hawor::PackedPanels<S> P;
          P.pack(Bs.data(), m, 1, k, m);
          // the transpose of a row-major Bᵀ packs to the same panels
          hawor::RowMatrixX<S> Bt = Bs.transpose();
          hawor::PackedPanels<S> Pt;
          Pt.pack(Bt.data(), 1, k, k, m);
          hawor::RowMatrixX<S> C = hawor::RowMatrixX<S>::Constant(n, m + 2, S(7)),
                               Ct = C;  // ldc = m+2
          std::vector<S> scratch(static_cast<size_t>(hawor::packedScratchSize(n, k)));
          const hawor::VecX<S> b = bias.row(0).transpose().cast<S>();
          hawor::matmulPacked(As.data(), k + 3, n, P, C.data(), m + 2,
                              withBias ? b.data() : nullptr, scratch.data());
          hawor::matmulPacked(As.data(), k + 3, n, Pt, Ct.data(), m + 2,
                              withBias ? b.data() : nullptr, scratch.data());
          infiller_test::MatD expect = A.leftCols(k) * B;
          if (withBias) expect.rowwise() += bias.row(0);
          INFO("n " << n << " k " << k << " m " << m << " bias " << withBias);
          const double scale = 1 + std::sqrt(double(k));
          CHECK((C.leftCols(m).template cast<double>() - expect).cwiseAbs().maxCoeff() <=
                infiller_test::tol<S>() * scale);
          CHECK(C.leftCols(m) == Ct.leftCols(m));
          CHECK((C.rightCols(2).array() == S(7)).all());  // nothing written past m
        }
      }
    }
  }
}

TEMPLATE_TEST_CASE("Linear: both backends compute x·Wᵀ + b", "[motion][infiller][matmul]", float,
                   double) {
  using S = TestType;
  std::mt19937 rng(5);
  const infiller_test::MatD W = infiller_test::randomMatrix(13, 21, rng);
  const infiller_test::MatD b = infiller_test::randomMatrix(1, 13, rng);
  const infiller_test::MatD X = infiller_test::randomMatrix(10, 21, rng);
  infiller_test::MatD expect = X * W.transpose();
  expect.rowwise() += b.row(0);
  for (auto backend : {hawor::MatmulBackend::Eigen, hawor::MatmulBackend::Packed}) {
    const hawor::Linear<S> lin(W.cast<S>(), b.row(0).transpose().cast<S>(), backend);
    hawor::RowMatrixX<S> Xs = X.cast<S>(), Y(12, 13);
    std::vector<S> scratch(static_cast<size_t>(hawor::packedScratchSize(10, 21)));
    lin.apply(Xs, Y.topRows(10), scratch.data());
    INFO(infiller_test::backendName(backend));
    CHECK((Y.topRows(10).template cast<double>() - expect).cwiseAbs().maxCoeff() <=
          10 * infiller_test::tol<S>());
    CHECK_THROWS_AS(lin.apply(Xs.leftCols(20), Y.topRows(10), scratch.data()), hawor::Error);
  }
  CHECK_THROWS_AS(
      hawor::Linear<S>(W.cast<S>(), hawor::VecX<S>::Zero(3), hawor::MatmulBackend::Eigen),
      hawor::Error);
}

TEMPLATE_TEST_CASE("positional table follows the sinusoid formula", "[motion][infiller]", float,
                   double) {
  using S = TestType;
  const hawor::RowMatrixX<S> pe = hawor::sinusoidalPositionalEncoding<S>(120, 384);
  REQUIRE(pe.rows() == 120);
  REQUIRE(pe.cols() == 384);
  double worst = 0;
  for (int t = 0; t < 120; ++t)
    for (int i = 0; i < 192; ++i) {
      const double angle = t / std::pow(10000.0, 2.0 * i / 384.0);
      worst = std::max(worst, std::abs(double(pe(t, 2 * i)) - std::sin(angle)));
      worst = std::max(worst, std::abs(double(pe(t, 2 * i + 1)) - std::cos(angle)));
    }
  CHECK(worst <= (std::is_same<S, float>::value ? 1e-7 : 1e-12));
  CHECK(pe(0, 0) == S(0));
  CHECK(pe(0, 1) == S(1));
  CHECK(std::abs(double(pe(1, 0)) - std::sin(1.0)) < 1e-7);
  CHECK(std::abs(double(pe(1, 383)) - std::cos(std::pow(10000.0, -382.0 / 384.0))) < 1e-7);
  // odd widths: the last column is a sine
  const hawor::RowMatrixX<S> odd = hawor::sinusoidalPositionalEncoding<S>(3, 5);
  CHECK(std::abs(double(odd(2, 4)) - std::sin(2.0 / std::pow(10000.0, 4.0 / 5.0))) < 1e-7);
}

TEMPLATE_TEST_CASE("infiller forward equals a naive implementation", "[motion][infiller]", float,
                   double) {
  using S = TestType;
  const hawor::InfillerConfig c = infiller_test::smallConfig();
  const hawor::Npz npz = infiller_test::reread(infiller_test::randomWeightsNpz(c, 3));
  const auto wd = hawor::loadInfillerWeights<double>(npz, c);
  const auto ws = hawor::loadInfillerWeights<S>(npz, c);
  std::mt19937 rng(9);
  for (auto backend : {hawor::MatmulBackend::Eigen, hawor::MatmulBackend::Packed}) {
    const hawor::InfillerNet<S> net(ws, backend);
    hawor::InfillerWorkspace<S> work(c);
    hawor::RowMatrixX<S> y;
    hawor::ThreadPool pool2(2), pool3(3);
    hawor::InfillerWorkspace<S> work3(c, 3);
    for (Eigen::Index T : {Eigen::Index(c.window), Eigen::Index(5), Eigen::Index(1)}) {
      const infiller_test::MatD x = infiller_test::randomMatrix(T, c.features, rng);
      hawor::ValidMask valid = infiller_test::gapMask(T);
      net.forward(x.cast<S>(), valid, y, work);
      const infiller_test::MatD expect = infiller_test::refForward(wd, x, valid);
      INFO(infiller_test::backendName(backend) << " T " << T);
      REQUIRE(y.rows() == T);
      REQUIRE(y.cols() == c.features);
      CHECK((y.template cast<double>() - expect).cwiseAbs().maxCoeff() <= infiller_test::tol<S>());
      // the frames split between 2 and 3 threads (3 row tiles of 4 at T = 12; one at T = 1,
      // 5; a 2-thread pool with a 3-thread workspace, and a 3-thread pool with a 1-thread one)
      hawor::RowMatrixX<S> yt;
      for (auto [pool, wsp] : {std::pair{&pool2, &work3}, std::pair{&pool3, &work3},
                               std::pair{&pool3, &work}}) {
        net.forward(x.cast<S>(), valid, yt, *wsp, pool);
        CHECK((yt.template cast<double>() - expect).cwiseAbs().maxCoeff() <=
              infiller_test::tol<S>());
      }
      // all valid, and the allocating overload
      valid.assign(static_cast<size_t>(T), 1);
      const hawor::RowMatrixX<S> y2 = net.forward(x.cast<S>(), valid);
      CHECK((y2.template cast<double>() - infiller_test::refForward(wd, x, valid))
                .cwiseAbs()
                .maxCoeff() <= infiller_test::tol<S>());
    }
  }
}

TEMPLATE_TEST_CASE("masked keys are invisible to stage 1; stage 2 sees every frame",
                   "[motion][infiller]", float, double) {
  using S = TestType;
  std::mt19937 rng(21);
  for (int encoderLayers : {0, 2}) {
    const hawor::InfillerConfig c = infiller_test::smallConfig(encoderLayers);
    const auto w = hawor::loadInfillerWeights<S>(infiller_test::randomWeightsNpz(c, 4), c);
    for (auto backend : {hawor::MatmulBackend::Eigen, hawor::MatmulBackend::Packed}) {
      const hawor::InfillerNet<S> net(w, backend);
      const hawor::RowMatrixX<S> x =
          infiller_test::randomMatrix(c.window, c.features, rng).cast<S>();
      const hawor::ValidMask valid = infiller_test::gapMask(c.window);
      const hawor::RowMatrixX<S> y = net.forward(x, valid);
      hawor::RowMatrixX<S> x2 = x;
      x2.row(3) = infiller_test::randomMatrix(1, c.features, rng).cast<S>() * S(5);  // invalid
      const hawor::RowMatrixX<S> y2 = net.forward(x2, valid);
      double othersMoved = 0;
      for (Eigen::Index t = 0; t < c.window; ++t)
        if (t != 3)
          othersMoved = std::max(othersMoved, double((y2.row(t) - y.row(t)).cwiseAbs().maxCoeff()));
      const double selfMoved = (y2.row(3) - y.row(3)).cwiseAbs().maxCoeff();
      INFO("encoder layers " << encoderLayers << ", " << infiller_test::backendName(backend));
      CHECK(selfMoved > 1e-3);
      if (encoderLayers == 0) {
        CHECK(othersMoved == 0.0);  // weight exactly 0 on masked keys
      } else {
        CHECK(othersMoved > 1e-4);  // the encoder attends to every frame (no mask officially)
      }
      // a valid frame's content reaches the others already in stage 1
      hawor::RowMatrixX<S> x3 = x;
      x3.row(8) *= S(-1);
      const hawor::RowMatrixX<S> y3 = net.forward(x3, valid);
      CHECK((y3.row(0) - y.row(0)).cwiseAbs().maxCoeff() > 1e-4);
    }
  }
}

TEMPLATE_TEST_CASE("the validity channel and the mask change the output", "[motion][infiller]",
                   float, double) {
  using S = TestType;
  const hawor::InfillerConfig c = infiller_test::smallConfig();
  const hawor::InfillerNet<S> net(
      hawor::loadInfillerWeights<S>(infiller_test::randomWeightsNpz(c, 6), c));
  std::mt19937 rng(2);
  const hawor::RowMatrixX<S> x = infiller_test::randomMatrix(c.window, c.features, rng).cast<S>();
  hawor::ValidMask valid(static_cast<size_t>(c.window), 1);
  const hawor::RowMatrixX<S> y = net.forward(x, valid);
  valid[5] = 0;
  const hawor::RowMatrixX<S> y2 = net.forward(x, valid);
  CHECK((y2 - y).cwiseAbs().maxCoeff() > 1e-3);
  // nonzero values other than 1 mean "valid" too
  valid[5] = 7;
  CHECK((net.forward(x, valid) - y).cwiseAbs().maxCoeff() == 0);
}

TEMPLATE_TEST_CASE("infiller forward rejects bad windows", "[motion][infiller]", float, double) {
  using S = TestType;
  const hawor::InfillerConfig c = infiller_test::smallConfig();
  const hawor::InfillerNet<S> net(
      hawor::loadInfillerWeights<S>(infiller_test::randomWeightsNpz(c, 8), c));
  std::mt19937 rng(4);
  const hawor::RowMatrixX<S> x = infiller_test::randomMatrix(c.window, c.features, rng).cast<S>();
  const hawor::ValidMask valid(static_cast<size_t>(c.window), 1);
  CHECK_THROWS_WITH(net.forward(x, hawor::ValidMask(static_cast<size_t>(c.window), 0)),
                    Catch::Contains("no valid frame"));
  CHECK_THROWS_AS(net.forward(x, hawor::ValidMask(3, 1)), hawor::Error);
  CHECK_THROWS_AS(net.forward(x.leftCols(c.features - 1), valid), hawor::Error);
  const hawor::RowMatrixX<S> tooLong = hawor::RowMatrixX<S>::Zero(c.window + 1, c.features);
  CHECK_THROWS_AS(net.forward(tooLong, hawor::ValidMask(static_cast<size_t>(c.window + 1), 1)),
                  hawor::Error);
  CHECK_THROWS_AS(net.forward(hawor::RowMatrixX<S>(0, c.features), hawor::ValidMask()),
                  hawor::Error);
  hawor::RowMatrixX<S> bad = x;
  bad(4, 2) = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_WITH(net.forward(bad, valid), Catch::Contains("frame 4"));
  hawor::InfillerConfig other = c;
  other.ffDim = 8;
  hawor::InfillerWorkspace<S> wrong(other);
  hawor::RowMatrixX<S> y;
  CHECK_THROWS_WITH(net.forward(x, valid, y, wrong), Catch::Contains("workspace"));
  // the official sizes are the defaults, and they validate
  const hawor::InfillerConfig official;
  CHECK(official.window == 120);
  CHECK(official.inputDim() == 219);
  CHECK(official.headDim() == 48);
  CHECK(hawor::infillerTensorSpecs(official).size() == 2 + 1 + 8 * 6 + 8 * 6 + 2 + 8 * 12 + 2);
  hawor::InfillerConfig badConfig = c;
  badConfig.heads = 3;
  CHECK_THROWS_WITH(badConfig.validate(), Catch::Contains("divisible"));
}

TEMPLATE_TEST_CASE("weights survive the npz round trip", "[motion][infiller][io]", float, double) {
  using S = TestType;
  const hawor::InfillerConfig c = infiller_test::smallConfig();
  const auto w = hawor::loadInfillerWeights<S>(infiller_test::randomWeightsNpz(c, 12), c);
  for (bool asDouble : {false, true}) {
    const hawor::Npz npz = infiller_test::reread(hawor::infillerWeightsToNpz(w, asDouble));
    CHECK(npz.get("decoder.weight").dtype == (asDouble ? "<f8" : "<f4"));
    const auto back = hawor::loadInfillerWeights<S>(npz, c);
    std::mt19937 rng(1);
    const hawor::RowMatrixX<S> x = infiller_test::randomMatrix(c.window, c.features, rng).cast<S>();
    const hawor::ValidMask valid = infiller_test::gapMask(c.window);
    const hawor::RowMatrixX<S> y0 = hawor::InfillerNet<S>(w).forward(x, valid);
    const hawor::RowMatrixX<S> y1 = hawor::InfillerNet<S>(back).forward(x, valid);
    // float32 storage rounds double weights
    CHECK((y1 - y0).cwiseAbs().maxCoeff() <=
          (asDouble || std::is_same<S, float>::value ? 0 : 1e-5));
  }
}

TEST_CASE("malformed infiller weight files name the tensor", "[motion][infiller][io]") {
  const hawor::InfillerConfig c = infiller_test::smallConfig();
  const hawor::Npz good = infiller_test::randomWeightsNpz(c, 13);
  REQUIRE_NOTHROW(hawor::loadInfillerWeights<double>(infiller_test::reread(good), c));
  const auto rebuild = [&](const std::string& skip, const std::string& replace,
                           const hawor::NpyArray* with) {
    hawor::Npz z;
    for (const auto& name : good.names()) {
      if (name == skip) continue;
      z.set(name, name == replace ? *with : good.get(name));
    }
    return infiller_test::reread(z);
  };
  const auto fails = [&](const hawor::Npz& z, const std::vector<std::string>& parts) {
    try {
      hawor::loadInfillerWeights<float>(z, c);
      FAIL("no error");
    } catch (const hawor::Error& e) {
      const std::string msg = e.what();
      INFO(msg);
      CHECK(msg.find("weights.npz") != std::string::npos);
      for (const auto& p : parts) CHECK(msg.find(p) != std::string::npos);
    }
  };
  // missing
  fails(rebuild("att_layers.1.k_linear.weight", "", nullptr),
        {"'att_layers.1.k_linear.weight'", "missing", "(16, 16)"});
  fails(rebuild("decoder.bias", "", nullptr), {"'decoder.bias'", "missing", "(10,)"});
  // wrong shape (transposed weight, bias of the wrong length)
  std::vector<double> v(11 * 16, 0.5);
  hawor::NpyArray transposed = hawor::NpyArray::fromData(v.data(), {11, 16});
  fails(rebuild("", "input_layer.weight", &transposed),
        {"'input_layer.weight'", "shape (11, 16)", "expected (16, 11)"});
  hawor::NpyArray shortBias = hawor::NpyArray::fromData(v.data(), {23});
  fails(rebuild("", "transformer_encoder.layers.0.linear1.bias", &shortBias),
        {"'transformer_encoder.layers.0.linear1.bias'", "(23,)", "(24,)"});
  // NaN / Inf
  std::vector<float> nan(16, 1.0f);
  nan[9] = std::numeric_limits<float>::quiet_NaN();
  hawor::NpyArray nanArray = hawor::NpyArray::fromData(nan.data(), {16});
  fails(rebuild("", "pff_layers.0.layer_norm.bias", &nanArray),
        {"'pff_layers.0.layer_norm.bias'", "non-finite", "element 9"});
  // integer dtype
  std::vector<int32_t> ints(16, 1);
  hawor::NpyArray intArray = hawor::NpyArray::fromData(ints.data(), {16});
  fails(rebuild("", "layer_norm.weight", &intArray), {"'layer_norm.weight'", "dtype", "int32"});
  // a tensor of a deeper model
  hawor::Npz deeper = good;
  deeper.set("transformer_encoder.layers.2.norm1.bias", good.get("layer_norm.bias"));
  fails(infiller_test::reread(deeper), {"transformer_encoder.layers.2.norm1.bias", "not part"});
  // weights built in code are checked by the network's constructor
  auto w = hawor::loadInfillerWeights<float>(infiller_test::reread(good), c);
  w.encoderLayers[1].linear2Weight.resize(16, 23);
  CHECK_THROWS_WITH(
      hawor::InfillerNet<float>(w),
      Catch::Contains("'transformer_encoder.layers.1.linear2.weight'") && Catch::Contains("16x24"));
  w = hawor::loadInfillerWeights<float>(infiller_test::reread(good), c);
  w.maskedBlocks[0].ffNormBias(3) = std::numeric_limits<float>::infinity();
  CHECK_THROWS_WITH(hawor::InfillerNet<float>(w),
                    Catch::Contains("'pff_layers.0.layer_norm.bias'"));
  w = hawor::loadInfillerWeights<float>(infiller_test::reread(good), c);
  w.maskedBlocks.pop_back();
  CHECK_THROWS_WITH(hawor::InfillerNet<float>(w), Catch::Contains("masked"));
  // float64 values beyond float's range
  std::vector<double> huge(16, 1e300);
  hawor::NpyArray hugeArray = hawor::NpyArray::fromData(huge.data(), {16});
  CHECK_THROWS_AS(hawor::loadInfillerWeights<float>(rebuild("", "layer_norm.bias", &hugeArray), c),
                  hawor::Error);
  CHECK_NOTHROW(hawor::loadInfillerWeights<double>(rebuild("", "layer_norm.bias", &hugeArray), c));
  // other floating dtypes (here big-endian float64) are accepted
  std::vector<double> ones(16, 1.0);
  hawor::NpyArray be = hawor::NpyArray::fromData(ones.data(), {16}, false, true);
  CHECK_NOTHROW(hawor::loadInfillerWeights<float>(rebuild("", "layer_norm.weight", &be), c));
}

TEMPLATE_TEST_CASE("a pos_embedding.pe tensor replaces the formula", "[motion][infiller][io]",
                   float, double) {
  using S = TestType;
  const hawor::InfillerConfig c = infiller_test::smallConfig();
  hawor::Npz npz = infiller_test::randomWeightsNpz(c, 14);
  std::mt19937 rng(3);
  const infiller_test::MatD pe = infiller_test::randomMatrix(c.window, c.dModel, rng);
  const hawor::RowMatrixX<S> x = infiller_test::randomMatrix(c.window, c.features, rng).cast<S>();
  const hawor::ValidMask valid = infiller_test::gapMask(c.window);
  const hawor::RowMatrixX<S> yFormula =
      hawor::InfillerNet<S>(hawor::loadInfillerWeights<S>(infiller_test::reread(npz), c))
          .forward(x, valid);
  for (bool threeD : {true, false}) {
    npz.set("pos_embedding.pe",
            hawor::NpyArray::fromData(
                pe.data(), threeD ? std::vector<size_t>{12, 1, 16} : std::vector<size_t>{12, 16}));
    const auto wd = hawor::loadInfillerWeights<double>(infiller_test::reread(npz), c);
    const hawor::InfillerNet<S> net(hawor::loadInfillerWeights<S>(infiller_test::reread(npz), c));
    CHECK((net.positionalTable().template cast<double>() - pe).cwiseAbs().maxCoeff() <= 1e-7);
    const hawor::RowMatrixX<S> y = net.forward(x, valid);
    CHECK((y.template cast<double>() -
           infiller_test::refForward(wd, x.template cast<double>(), valid))
              .cwiseAbs()
              .maxCoeff() <= infiller_test::tol<S>());
    CHECK((y - yFormula).cwiseAbs().maxCoeff() > 1e-3);
  }
  npz.set("pos_embedding.pe", hawor::NpyArray::fromData(pe.data(), {6, 2, 16}));
  CHECK_THROWS_WITH(hawor::loadInfillerWeights<S>(infiller_test::reread(npz), c),
                    Catch::Contains("'pos_embedding.pe'") && Catch::Contains("(12, 1, 16)"));
}
