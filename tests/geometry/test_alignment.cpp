// Umeyama alignment (hawor/geometry/alignment.hpp): exact recovery of known Sim3/SE3 from
// noise-free points (weighted and unweighted), reflection fix, optimality on noisy data,
// weights as multiplicities, and rejection of bad input.
#include <catch2/catch.hpp>

#include "geometry_test_utils.hpp"

using namespace hawor;
using geo_test::tol;

namespace {

template <typename S>
Points3<S> randomPoints(geo_test::Rng& rng, int n, double r = 1.0) {
  Points3<S> P(n, 3);
  for (int i = 0; i < n; ++i) P.row(i) = rng.vec3(r).cast<S>().transpose();
  return P;
}

template <typename S>
S weightedCost(const SimilarityTransform<S>& T, const Points3<S>& src, const Points3<S>& dst,
               const VecX<S>* w) {
  const Points3<S> m = T.apply(src);
  S c = S(0);
  for (Eigen::Index i = 0; i < src.rows(); ++i) {
    c += (w ? (*w)(i) : S(1)) * (m.row(i) - dst.row(i)).squaredNorm();
  }
  return c;
}

}  // namespace

TEMPLATE_TEST_CASE("umeyama recovers a known Sim3 and SE3 from exact points",
                   "[geometry][alignment]", float, double) {
  using S = TestType;
  geo_test::Rng rng(31);
  for (int rep = 0; rep < 20; ++rep) {
    const int n = 3 + rep;  // from the minimum (3 non-collinear points) up
    const Points3<S> src = randomPoints<S>(rng, n);
    const Vec7<S> xi = geo_test::Sampler<Sim3<S>>::tangent(rng, rng.uniform(0, 3.1));
    const Sim3<S> T = Sim3<S>::exp(xi);
    Points3<S> dst(n, 3);
    for (int i = 0; i < n; ++i) dst.row(i) = (T * Vec3<S>(src.row(i).transpose())).transpose();

    const SimilarityTransform<S> est = umeyama(src, dst, true);
    INFO("rep " << rep);
    CHECK(est.s == Approx(T.scale()).epsilon(tol<S>(1e-12, 2e-5)));
    CHECK((est.R - T.rotationMatrix()).norm() <= tol<S>(1e-12, 4e-5));
    CHECK((est.t - T.translation()).norm() <= tol<S>(1e-12, 4e-5) * (1 + T.translation().norm()));
    CHECK((est.apply(src) - dst).norm() <= tol<S>(1e-12, 4e-5) * dst.norm());
    CHECK(alignSim3(src, dst).isApprox(T, tol<S>(1e-11, 1e-4)));

    // Rigid data: the no-scale fit recovers the SE3.
    const SE3<S> E(T.rotation(), T.translation());
    Points3<S> dst_e(n, 3);
    for (int i = 0; i < n; ++i) dst_e.row(i) = (E * Vec3<S>(src.row(i).transpose())).transpose();
    const SimilarityTransform<S> est_e = umeyama(src, dst_e, false);
    CHECK(est_e.s == S(1));
    CHECK((est_e.R - E.rotationMatrix()).norm() <= tol<S>(1e-12, 4e-5));
    CHECK((est_e.t - E.translation()).norm() <= tol<S>(1e-12, 4e-5) * (1 + E.translation().norm()));
    CHECK(alignSE3(src, dst_e).isApprox(E, tol<S>(1e-11, 1e-4)));
    // With scale on rigid data: s = 1.
    CHECK(umeyama(src, dst_e, true).s == Approx(S(1)).epsilon(tol<S>(1e-12, 2e-5)));
  }
}

TEMPLATE_TEST_CASE("weighted umeyama: zero weights ignore outliers, weights are multiplicities",
                   "[geometry][alignment]", float, double) {
  using S = TestType;
  geo_test::Rng rng(32);
  for (int rep = 0; rep < 10; ++rep) {
    const int n = 12;
    const Points3<S> src = randomPoints<S>(rng, n);
    const Sim3<S> T = Sim3<S>::exp(geo_test::Sampler<Sim3<S>>::tangent(rng, rng.uniform(0, 3)));
    Points3<S> dst(n, 3);
    for (int i = 0; i < n; ++i) dst.row(i) = (T * Vec3<S>(src.row(i).transpose())).transpose();
    // Corrupt 4 points and give them weight 0; the rest get arbitrary positive weights.
    VecX<S> w(n);
    for (int i = 0; i < n; ++i) w(i) = S(rng.uniform(0.1, 3.0));
    for (int i = 0; i < 4; ++i) {
      dst.row(3 * i) += rng.vec3(5).cast<S>().transpose();
      w(3 * i) = S(0);
    }
    const SimilarityTransform<S> est = umeyama(src, dst, true, &w);
    CHECK(est.s == Approx(T.scale()).epsilon(tol<S>(1e-12, 2e-5)));
    CHECK((est.R - T.rotationMatrix()).norm() <= tol<S>(1e-12, 4e-5));
    CHECK((est.t - T.translation()).norm() <= tol<S>(1e-12, 4e-5) * (1 + T.translation().norm()));
    CHECK(alignSim3(src, dst, &w).isApprox(T, tol<S>(1e-11, 1e-4)));

    // Noisy data: integer weights equal repeating points; the weighted result is also a
    // minimum of the weighted cost (no perturbation lowers it).
    Points3<S> noisy = dst;
    for (int i = 0; i < n; ++i) noisy.row(i) += rng.vec3(0.05).cast<S>().transpose();
    VecX<S> wi(n);
    int total = 0;
    for (int i = 0; i < n; ++i) total += int(wi(i) = S(1 + (i % 3)));
    Points3<S> src_rep(total, 3), dst_rep(total, 3);
    for (int i = 0, k = 0; i < n; ++i) {
      for (int j = 0; j < int(wi(i)); ++j, ++k) {
        src_rep.row(k) = src.row(i);
        dst_rep.row(k) = noisy.row(i);
      }
    }
    for (bool with_scale : {false, true}) {
      const SimilarityTransform<S> a = umeyama(src, noisy, with_scale, &wi);
      const SimilarityTransform<S> b = umeyama(src_rep, dst_rep, with_scale);
      CHECK(a.s == Approx(b.s).epsilon(tol<S>(1e-12, 1e-5)));
      CHECK((a.R - b.R).norm() <= tol<S>(1e-12, 1e-5));
      CHECK((a.t - b.t).norm() <= tol<S>(1e-12, 1e-5) * (1 + b.t.norm()));
      const S c0 = weightedCost(a, src, noisy, &wi);
      for (int k = 0; k < 20; ++k) {
        SimilarityTransform<S> p = a;
        p.R = (SO3<S>::exp(rng.vec3(1e-2).cast<S>()) * SO3<S>::fromMatrix(a.R)).matrix();
        p.t += rng.vec3(1e-2).cast<S>();
        if (with_scale) p.s *= S(1 + rng.uniform(-1e-2, 1e-2));
        CHECK(weightedCost(p, src, noisy, &wi) >= c0 * (1 - tol<S>(1e-12, 1e-5)));
      }
    }
  }
}

TEMPLATE_TEST_CASE("umeyama never returns a reflection", "[geometry][alignment]", float, double) {
  using S = TestType;
  geo_test::Rng rng(33);
  for (int rep = 0; rep < 10; ++rep) {
    const Points3<S> src = randomPoints<S>(rng, 10);
    Points3<S> dst = src;
    dst.col(2) *= S(-1);  // mirror image: the best proper rotation is not the mirror
    for (bool with_scale : {false, true}) {
      const SimilarityTransform<S> est = umeyama(src, dst, with_scale);
      CHECK(est.R.determinant() == Approx(S(1)).epsilon(tol<S>(1e-12, 1e-5)));
      CHECK((est.R * est.R.transpose() - Mat3<S>::Identity()).norm() <= tol<S>(1e-12, 1e-5));
    }
  }
}

TEMPLATE_TEST_CASE("umeyama degenerate and bad input", "[geometry][alignment]", float, double) {
  using S = TestType;
  geo_test::Rng rng(34);
  const Points3<S> src = randomPoints<S>(rng, 5);
  const Points3<S> dst = randomPoints<S>(rng, 5);
  CHECK_THROWS_AS(umeyama(src, Points3<S>(randomPoints<S>(rng, 4)), true), Error);
  CHECK_THROWS_AS(umeyama(Points3<S>(0, 3), Points3<S>(0, 3), false), Error);
  Points3<S> nan = dst;
  nan(2, 1) = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_AS(umeyama(src, nan, false), Error);
  CHECK_THROWS_AS(umeyama(nan, src, false), Error);
  VecX<S> w = VecX<S>::Ones(5);
  w(1) = S(-1);
  CHECK_THROWS_AS(umeyama(src, dst, true, &w), Error);
  w.setZero();
  CHECK_THROWS_AS(umeyama(src, dst, true, &w), Error);
  VecX<S> w4 = VecX<S>::Ones(4);
  CHECK_THROWS_AS(umeyama(src, dst, true, &w4), Error);
  w.setOnes();
  w(0) = std::numeric_limits<S>::infinity();
  CHECK_THROWS_AS(umeyama(src, dst, true, &w), Error);

  // All source points equal: scale undefined -> error; rigid fit is a pure translation.
  Points3<S> same(4, 3);
  for (int i = 0; i < 4; ++i) same.row(i) = Eigen::RowVector3d(0.3, -1, 2).cast<S>();
  CHECK_THROWS_WITH(umeyama(same, dst.topRows(4).eval(), true),
                    Catch::Contains("zero variance"));
  const SimilarityTransform<S> one = umeyama(same, dst.topRows(4).eval(), false);
  CHECK((one.R - Mat3<S>::Identity()).norm() <= tol<S>(1e-15, 1e-6));
  CHECK((one.apply(Vec3<S>(same.row(0).transpose())) - dst.topRows(4).colwise().mean().transpose())
            .norm() <= tol<S>(1e-14, 1e-5));
  // Only one point with non-zero weight and scale requested: also degenerate.
  VecX<S> w1 = VecX<S>::Zero(5);
  w1(2) = S(1);
  CHECK_THROWS_AS(umeyama(src, dst, true, &w1), Error);
  // Target collapsed to a point: umeyama gives s = 0, alignSim3 refuses.
  Points3<S> dst_same = same.topRows(4);
  const Points3<S> src4 = src.topRows(4);
  CHECK(umeyama(src4, dst_same, true).s == Approx(S(0)).margin(tol<S>(1e-14, 1e-6)));
  CHECK_THROWS_AS(alignSim3(src4, dst_same), Error);

  // Collinear points, no scale: a valid rotation that maps the line exactly.
  Points3<S> line(5, 3);
  for (int i = 0; i < 5; ++i) line.row(i) = (double(i) * Eigen::RowVector3d(1, 2, -1)).template cast<S>();
  const SE3<S> E = SE3<S>::exp(geo_test::Sampler<SE3<S>>::tangent(rng, 1.0));
  Points3<S> line_dst(5, 3);
  for (int i = 0; i < 5; ++i) line_dst.row(i) = (E * Vec3<S>(line.row(i).transpose())).transpose();
  const SimilarityTransform<S> lt = umeyama(line, line_dst, true);
  CHECK(lt.R.determinant() == Approx(S(1)).epsilon(tol<S>(1e-12, 1e-5)));
  CHECK((lt.apply(line) - line_dst).norm() <= tol<S>(1e-12, 1e-4) * line_dst.norm());
}
