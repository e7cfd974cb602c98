// Tests of motion/transformer_infill.hpp (native and WASM): the network as the window infiller of
// the two-hand pipeline. The window's features and validity reach the network as the file
// comment says (both hands observed; either hand where no frame has both; nothing observed: the
// pre-fill), the output is taken as it is, sizes are checked, and through infillWindowed the
// observed frames stay bit for bit while exactly the missing ones are filled.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "../support/random_infiller.hpp"
#include "hawor/motion/infill_window.hpp"
#include "hawor/motion/transformer_infill.hpp"

namespace transformer_infill_test {

// A small network for hands of K joint rotations and B betas (two hands per window).
hawor::InfillerConfig config(const hawor::HandFeatureLayout& l, int window) {
  hawor::InfillerConfig c;
  c.window = window;
  c.features = static_cast<int>(2 * l.size());
  c.dModel = 16;
  c.heads = 2;
  c.ffDim = 24;
  c.maskedLayers = 2;
  c.encoderLayers = 1;
  return c;
}

template <typename S>
hawor::InfillerNet<S> randomNet(const hawor::InfillerConfig& c, unsigned seed) {
  return hawor::InfillerNet<S>(hawor::loadInfillerWeights<S>(hawor_test::randomInfillerWeights(c, seed), c));
}

// A smooth random world-space hand of T frames.
template <typename S>
hawor::HandMotion<S> smoothHand(Eigen::Index T, const hawor::HandFeatureLayout& l, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  hawor::HandMotion<S> m;
  m.rot.resize(T, 3);
  m.trans.resize(T, 3);
  m.handPose.resize(T, 3 * l.joints);
  m.betas.resize(T, l.betas);
  const double f = 0.05 + 0.02 * u(rng), ph = u(rng);
  for (Eigen::Index t = 0; t < T; ++t) {
    const double a = std::sin(f * double(t) + ph);
    for (int i = 0; i < 3; ++i) {
      m.rot(t, i) = S(0.5 * a + 0.1 * i);
      m.trans(t, i) = S(0.2 * std::cos(f * double(t) + i));
    }
    for (Eigen::Index j = 0; j < m.handPose.cols(); ++j) m.handPose(t, j) = S(0.3 * a * double(j % 3 + 1) / 3);
    for (Eigen::Index b = 0; b < l.betas; ++b) m.betas(t, b) = S(0.1 * double(b));
  }
  m.valid.assign(static_cast<size_t>(T), 1);
  return m;
}

}  // namespace transformer_infill_test

TEMPLATE_TEST_CASE("TransformerWindowInfiller: the network sees the window as documented",
                   "[motion][infill][infiller]", float, double) {
  using S = TestType;
  namespace tt = transformer_infill_test;
  hawor::HandFeatureLayout l;
  l.joints = 2;
  l.betas = 1;
  const int W = 12;
  const hawor::InfillerConfig c = tt::config(l, W);
  const hawor::InfillerNet<S> net = tt::randomNet<S>(c, 5);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  hawor::InfillWindow<double> w;
  w.layout = l;
  w.features.resize(W, c.features);
  for (Eigen::Index i = 0; i < w.features.size(); ++i) w.features.data()[i] = u(rng);
  w.frames = W;
  const auto expect = [&](const hawor::ValidMask& v) {
    return net.forward(w.features.cast<S>(), v).template cast<double>().eval();
  };
  hawor::ThreadPool pool(2);
  for (hawor::ThreadPool* p : {static_cast<hawor::ThreadPool*>(nullptr), &pool}) {
    const hawor::TransformerWindowInfiller<double, S> infiller(net, p);
    // both hands observed at frames 0-3 and 8: those are the valid frames
    w.valid[0] = {1, 1, 1, 1, 1, 1, 0, 0, 1, 0, 0, 0};
    w.valid[1] = {1, 1, 1, 1, 0, 0, 0, 0, 1, 1, 1, 0};
    hawor::ValidMask both = {1, 1, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0};
    CHECK((infiller.infillWindow(w) - expect(both)).cwiseAbs().maxCoeff() <= 1e-5);
    // no frame with both hands: either hand counts
    w.valid[1].assign(W, 0);
    CHECK((infiller.infillWindow(w) - expect(w.valid[0])).cwiseAbs().maxCoeff() <= 1e-5);
    // nothing observed: the pre-fill comes back unchanged
    w.valid[0].assign(W, 0);
    CHECK(infiller.infillWindow(w) == w.features);
  }
  // sizes: another layout, another window length
  const hawor::TransformerWindowInfiller<double, S> infiller(net);
  hawor::HandFeatureLayout mano;
  CHECK_THROWS_WITH(infiller.checkLayout(mano), Catch::Contains("15 joint rotations"));
  w.valid[0].assign(W, 1);
  w.layout = mano;
  CHECK_THROWS_WITH(infiller.infillWindow(w), Catch::Contains("MANO"));
  w.layout = l;
  w.features.conservativeResize(W - 2, Eigen::NoChange);
  CHECK_THROWS_WITH(infiller.infillWindow(w), Catch::Contains("windows of 10 frames"));
}

TEMPLATE_TEST_CASE("infillWindowed with the network: observed frames kept, missing filled",
                   "[motion][infill][infiller]", float, double) {
  using S = TestType;
  namespace tt = transformer_infill_test;
  hawor::HandFeatureLayout l;
  l.joints = 3;
  l.betas = 2;
  const int W = 16;
  const hawor::InfillerNet<S> net = tt::randomNet<S>(tt::config(l, W), 8);
  std::mt19937 rng(4);
  const Eigen::Index T = 40;  // windows of 16, 16 and 8 (+ 8 padded)
  std::array<hawor::HandMotion<double>, 2> hands = {tt::smoothHand<double>(T, l, rng),
                                                    tt::smoothHand<double>(T, l, rng)};
  for (Eigen::Index t = 5; t < 12; ++t) hands[0].valid[static_cast<size_t>(t)] = 0;
  for (Eigen::Index t = 20; t < 40; ++t) hands[1].valid[static_cast<size_t>(t)] = 0;  // gone at the end
  hands[0].valid[0] = 0;
  const std::array<hawor::Points3<double>, 2> J0 = {hawor::Points3<double>::Zero(1, 3),
                                                    hawor::Points3<double>::Zero(1, 3)};
  hawor::ThreadPool pool(2);
  const hawor::TransformerWindowInfiller<double, S> infiller(net, &pool);
  std::array<hawor::ValidMask, 2> filled;
  const auto out = hawor::infillWindowed(hands, J0, infiller, W, &filled);
  for (int h = 0; h < 2; ++h) {
    INFO("hand " << h);
    for (Eigen::Index t = 0; t < T; ++t) {
      const bool seen = hands[h].valid[static_cast<size_t>(t)] != 0;
      CHECK((filled[h][static_cast<size_t>(t)] != 0) == !seen);
      if (seen) {
        CHECK(out[h].trans.row(t) == hands[h].trans.row(t));
        CHECK(out[h].rot.row(t) == hands[h].rot.row(t));
        CHECK(out[h].handPose.row(t) == hands[h].handPose.row(t));
      } else {
        CHECK(out[h].trans.row(t).allFinite());
        CHECK(out[h].handPose.row(t).allFinite());
      }
    }
  }
  // a hand of another size is refused before any window runs
  hawor::HandFeatureLayout other = l;
  other.joints = 4;
  std::array<hawor::HandMotion<double>, 2> big = {tt::smoothHand<double>(T, other, rng),
                                                  tt::smoothHand<double>(T, other, rng)};
  big[0].valid[3] = 0;
  CHECK_THROWS_AS(hawor::infillWindowed(big, J0, infiller, W), hawor::Error);
}
