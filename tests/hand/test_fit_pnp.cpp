// Metric PnP (geometry/pnp.hpp) and robust losses (geometry/robust_loss.hpp): exact recovery,
// robustness to outliers, rotation refinement, bad input.
#include <catch2/catch.hpp>

#include <random>

#include "fit_test_util.hpp"
#include "hawor/geometry/pnp.hpp"
#include "hawor/geometry/robust_loss.hpp"

template struct hawor::PnPOptions<float>;
template struct hawor::PnPOptions<double>;
template struct hawor::PnPResult<float>;
template struct hawor::PnPResult<double>;

using namespace hawor;

namespace {

template <typename Scalar>
struct PnPCase {
  Points3<Scalar> X;
  Pixels<Scalar> uv;
  Mat3<Scalar> R;
  Vec3<Scalar> t;
};

// 21 points spread like a hand (±9 cm), a pose at 0.3–0.8 m.
template <typename Scalar>
PnPCase<Scalar> makeCase(unsigned seed, double noisePx = 0.0, bool rotate = false) {
  std::mt19937 rng(seed);
  auto g = [](std::mt19937& r) { return standardNormal(r); };
  auto uni = [](std::mt19937& r) { return uniform01(r); };
  const PinholeCamera<Scalar> cam = fit_test::camera<Scalar>();
  PnPCase<Scalar> c;
  c.X.resize(21, 3);
  for (int i = 0; i < 21; ++i)
    for (int k = 0; k < 3; ++k) c.X(i, k) = Scalar(0.045 * g(rng) + 0.3);  // arbitrary origin
  c.R = rotate ? axisAngleToMatrix(Vec3<Scalar>(Scalar(0.1), Scalar(-0.15), Scalar(0.2))) : Mat3<Scalar>::Identity();
  const double z = 0.3 + 0.5 * uni(rng);
  const double tx = g(rng), ty = g(rng);
  c.t = Vec3<Scalar>(Scalar(0.05 * tx), Scalar(0.05 * ty), Scalar(z)) - c.R * Vec3<Scalar>::Constant(Scalar(0.3));
  c.uv.resize(21, 2);
  for (int i = 0; i < 21; ++i) {
    const Vec2<Scalar> p = cam.project(Vec3<Scalar>(c.R * c.X.row(i).transpose() + c.t));
    c.uv(i, 0) = p(0) + Scalar(noisePx * g(rng));
    c.uv(i, 1) = p(1) + Scalar(noisePx * g(rng));
  }
  return c;
}

template <typename Scalar>
double tolT() {
  return std::is_same<Scalar, float>::value ? 2e-4 : 1e-9;
}

}  // namespace

TEMPLATE_TEST_CASE("pnp: exact data recovers the metric translation", "[hand][fit][pnp]", float, double) {
  using S = TestType;
  const PinholeCamera<S> cam = fit_test::camera<S>();
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const auto c = makeCase<S>(seed);
    Vec3<S> t = Vec3<S>::Zero();
    REQUIRE(pnpTranslationLinear(c.X, c.uv, static_cast<const VecX<S>*>(nullptr), c.R, cam, t));
    CHECK((t - c.t).norm() <= tolT<S>());
    const PnPResult<S> r = solvePnPMetric(c.X, c.uv, nullptr, cam, c.R);
    REQUIRE(r.ok);
    CHECK((r.t - c.t).norm() <= tolT<S>());
    CHECK(r.rmsPx <= (std::is_same<S, float>::value ? 1e-2 : 1e-6));
  }
}

TEMPLATE_TEST_CASE("pnp: rotation refinement from a perturbed rotation", "[hand][fit][pnp]", float, double) {
  using S = TestType;
  const PinholeCamera<S> cam = fit_test::camera<S>();
  const auto c = makeCase<S>(9, 0.0, true);
  PnPOptions<S> o;
  o.refineRotation = true;
  o.maxIterations = 50;
  const PnPResult<S> r = solvePnPMetric(c.X, c.uv, nullptr, cam, Mat3<S>(Mat3<S>::Identity()), o);
  REQUIRE(r.ok);
  CHECK((r.t - c.t).norm() <= 10 * tolT<S>());
  CHECK((r.R - c.R).norm() <= (std::is_same<S, float>::value ? 1e-3 : 1e-8));
}

TEST_CASE("pnp: weights and robust losses against outliers", "[hand][fit][pnp]") {
  const PinholeCamera<double> cam = fit_test::camera<double>();
  auto c = makeCase<double>(4, 1.0);
  const PnPResult<double> clean = solvePnPMetric(c.X, c.uv, nullptr, cam, c.R);
  // Three wrong pixels, 60–90 px off.
  c.uv(3, 0) += 60;
  c.uv(8, 1) -= 75;
  c.uv(15, 0) += 90;
  PnPOptions<double> plain;
  plain.loss = RobustLoss::None;
  const double errPlain = (solvePnPMetric(c.X, c.uv, nullptr, cam, c.R, plain).t - c.t).norm();
  for (RobustLoss loss : {RobustLoss::Huber, RobustLoss::Cauchy}) {
    PnPOptions<double> o;
    o.loss = loss;
    const PnPResult<double> r = solvePnPMetric(c.X, c.uv, nullptr, cam, c.R, o);
    REQUIRE(r.ok);
    INFO("loss " << static_cast<int>(loss) << " plain error " << errPlain);
    CHECK((r.t - c.t).norm() < 0.5 * errPlain);
    // Cauchy ignores the outliers; Huber's bounded pull still moves the depth a little.
    CHECK((r.t - c.t).norm() < (loss == RobustLoss::Cauchy ? 0.01 : 0.03));
  }
  // Zero weights remove the outliers exactly.
  VecX<double> w = VecX<double>::Ones(21);
  w(3) = w(8) = w(15) = 0;
  const PnPResult<double> rw = solvePnPMetric(c.X, c.uv, &w, cam, c.R, plain);
  CHECK((rw.t - c.t).norm() <= (clean.t - c.t).norm() + 0.005);
}

TEST_CASE("pnp: bad input", "[hand][fit][pnp]") {
  const PinholeCamera<double> cam = fit_test::camera<double>();
  auto c = makeCase<double>(2);
  Pixels<double> short_uv = c.uv.topRows(5);
  CHECK_THROWS_AS(solvePnPMetric(c.X, short_uv, nullptr, cam, c.R), Error);
  VecX<double> w = VecX<double>::Ones(3);
  CHECK_THROWS_AS(solvePnPMetric(c.X, c.uv, &w, cam, c.R), Error);
  auto bad = c;
  bad.X(0, 0) = std::nan("");
  CHECK_THROWS_AS(solvePnPMetric(bad.X, bad.uv, nullptr, cam, c.R), Error);
  PinholeCamera<double> cam0 = cam;
  cam0.fx = 0;
  CHECK_THROWS_AS(solvePnPMetric(c.X, c.uv, nullptr, cam0, c.R), Error);
  // All weights zero: no pose, no exception.
  VecX<double> z = VecX<double>::Zero(21);
  CHECK_FALSE(solvePnPMetric(c.X, c.uv, &z, cam, c.R).ok);
}

TEMPLATE_TEST_CASE("robust losses: values and IRLS weights", "[hand][fit][robust]", float, double) {
  using S = TestType;
  const S k = S(2);
  for (S s : {S(0), S(0.5), S(4), S(9), S(100)}) {
    CHECK(robustCost(RobustLoss::None, s, k) == s);
    CHECK(robustWeight(RobustLoss::None, s, k) == S(1));
    CHECK(robustCost(RobustLoss::Huber, s, k) <= s + S(1e-6));
    CHECK(robustCost(RobustLoss::Cauchy, s, k) <= s + S(1e-6));
    // ρ' by central differences.
    const S h = S(1e-3);
    for (RobustLoss l : {RobustLoss::Huber, RobustLoss::Cauchy}) {
      if (s < h || std::abs(s - k * k) < 2 * h) continue;
      const S num = (robustCost(l, s + h, k) - robustCost(l, s - h, k)) / (2 * h);
      CHECK(std::abs(num - robustWeight(l, s, k)) <= S(2e-3));
    }
  }
  CHECK(robustWeight(RobustLoss::Huber, S(100), k) == Approx(0.2));
  CHECK(robustWeight(RobustLoss::Cauchy, S(4), k) == Approx(0.5));
}
