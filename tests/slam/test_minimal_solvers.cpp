// Minimal and linear solvers of the SLAM's estimation core on exact data: the 5-point essential
// matrix, essential decomposition, normalised homography DLT and Faugeras' decomposition,
// triangulation (DLT, midpoint) and P3P — each must contain the true answer.
#include <catch2/catch.hpp>

#include "estimation_test_utils.hpp"
#include "hawor/slam/essential.hpp"
#include "hawor/slam/homography.hpp"
#include "hawor/slam/p3p.hpp"
#include "hawor/slam/triangulation.hpp"

using namespace hawor;
using est_test::Rng;

namespace {

// Random motion and n points in front of both cameras, in normalised coordinates.
struct Exact {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  std::vector<Eigen::Vector3d> X;
  std::vector<Vec2<double>> x1, x2;
};

Exact makeExact(Rng& rng, int n, bool planar = false) {
  Exact e;
  e.R = rng.rotation(0.05, 0.6);
  e.t = rng.scaledUnit(0.2, 1.0);
  const Eigen::Vector2d nxy = rng.uniform2(-0.4, 0.4, -0.4, 0.4);
  const Eigen::Vector3d nrm = Eigen::Vector3d(nxy(0), nxy(1), 1).normalized();
  const double d = rng.uniform(3, 6);
  while (static_cast<int>(e.X.size()) < n) {
    const Eigen::Vector2d rxy = rng.uniform2(-0.6, 0.6, -0.5, 0.5);
    const Eigen::Vector3d ray(rxy(0), rxy(1), 1.0);
    const double z = planar ? d / nrm.dot(ray) : rng.uniform(2, 8);
    const Eigen::Vector3d X = z * ray;
    const Eigen::Vector3d X2 = e.R * X + e.t;
    if (z < 0.5 || X2.z() < 0.5) continue;
    e.X.push_back(X);
    e.x1.emplace_back(X.x() / X.z(), X.y() / X.z());
    e.x2.emplace_back(X2.x() / X2.z(), X2.y() / X2.z());
  }
  return e;
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

TEMPLATE_TEST_CASE("essentialFivePoint returns the true essential matrix", "[slam][essential]",
                   float, double) {
  using S = TestType;
  Rng rng(11);
  int found = 0;
  const int trials = 60;
  for (int trial = 0; trial < trials; ++trial) {
    const Exact e = makeExact(rng, 5);
    Eigen::Matrix3d Et = skew(e.t) * e.R;
    Et /= Et.norm();
    Vec2<S> a[5], b[5];
    for (int i = 0; i < 5; ++i) {
      a[i] = e.x1[i].cast<S>();
      b[i] = e.x2[i].cast<S>();
    }
    std::vector<Mat3<S>> Es;
    essentialFivePoint(a, b, Es);
    CHECK(Es.size() <= 10);
    double best = 1e9;
    for (const auto& E : Es) {
      const Eigen::Matrix3d Ed = E.template cast<double>();
      best = std::min({best, (Ed - Et).norm(), (Ed + Et).norm()});
      // every solution satisfies the five epipolar constraints and det E = 0
      for (int i = 0; i < 5; ++i) {
        CHECK(std::abs(double(sampsonErrorSq(E, a[i], b[i]))) < est_test::tol<S>(1e-16, 1e-8));
      }
      CHECK(std::abs(Ed.determinant()) < est_test::tol<S>(1e-8, 1e-4));
    }
    found += best < est_test::tol<S>(1e-6, 1e-3) ? 1 : 0;
  }
  CHECK(found >= trials - 1);  // a rare ill-conditioned sample may lose digits
}

TEST_CASE("essentialFivePoint on degenerate samples returns nothing or valid matrices", "[slam][essential]") {
  Vec2<double> a[5], b[5];
  for (int i = 0; i < 5; ++i) a[i] = b[i] = Vec2<double>(0.1, -0.2);  // all identical
  std::vector<Mat3<double>> Es;
  essentialFivePoint(a, b, Es);
  for (const auto& E : Es) CHECK(E.allFinite());
  a[2](0) = std::numeric_limits<double>::quiet_NaN();
  Es.clear();
  essentialFivePoint(a, b, Es);
  CHECK(Es.empty());
}

TEMPLATE_TEST_CASE("decomposeEssential contains the true motion", "[slam][essential]", float, double) {
  using S = TestType;
  Rng rng(12);
  for (int trial = 0; trial < 20; ++trial) {
    const Exact e = makeExact(rng, 1);
    const Mat3<S> E = (skew(e.t) * e.R * rng.uniform(-3, 3)).cast<S>();
    Mat3<S> R[4];
    Vec3<S> t[4];
    REQUIRE(decomposeEssential(E, R, t));
    double best = 1e9;
    for (int k = 0; k < 4; ++k) {
      CHECK(std::abs(double(R[k].determinant()) - 1.0) < est_test::tol<S>(1e-12, 1e-5));
      best = std::min(best, est_test::rotationErrorDeg(R[k].template cast<double>(), e.R) +
                                est_test::angleDeg(t[k].template cast<double>(), e.t));
    }
    CHECK(best < est_test::tol<S>(1e-6, 1e-2));
  }
}

TEMPLATE_TEST_CASE("homographyDLT recovers a plane-induced homography", "[slam][homography]", float,
                   double) {
  using S = TestType;
  Rng rng(13);
  for (int n : {4, 30}) {
    for (int trial = 0; trial < 10; ++trial) {
      const Exact e = makeExact(rng, n, true);
      std::vector<Vec2<S>> x1 = est_test::castPoints<S>(e.x1), x2 = est_test::castPoints<S>(e.x2);
      Mat3<S> H = Mat3<S>::Identity();
      REQUIRE(homographyDLT(x1, x2, nullptr, n, H));
      const Mat3<S> Hi = H.inverse();
      for (int i = 0; i < n; ++i) {
        S e1, e2;
        homographyTransferErrorsSq(H, Hi, x1[i], x2[i], e1, e2);
        CHECK(double(e1) < est_test::tol<S>(1e-20, 1e-9));
        CHECK(double(e2) < est_test::tol<S>(1e-20, 1e-9));
      }
    }
  }
  // Degenerate: fewer than 4, identical points.
  std::vector<Vec2<double>> p(6, Vec2<double>(0.3, 0.1));
  Mat3<double> H;
  CHECK_FALSE(homographyDLT(p, p, nullptr, 3, H));
  CHECK_FALSE(homographyDLT(p, p, nullptr, 6, H));
}

TEMPLATE_TEST_CASE("decomposeHomography contains the true motion and plane", "[slam][homography]",
                   float, double) {
  using S = TestType;
  Rng rng(14);
  for (int trial = 0; trial < 30; ++trial) {
    const Eigen::Matrix3d R = rng.rotation(0.05, 0.6);
    const Eigen::Vector3d t = rng.scaledUnit(0.2, 1.0);
    const Eigen::Vector2d nxy = rng.uniform2(-0.4, 0.4, -0.4, 0.4);
    const Eigen::Vector3d nrm = Eigen::Vector3d(nxy(0), nxy(1), 1).normalized();
    const double d = rng.uniform(2, 6);
    const double scale = rng.uniform(0.5, 2) * (trial % 2 ? -1 : 1);  // any scale and sign
    const Mat3<S> H = (scale * (R + t * nrm.transpose() / d)).cast<S>();
    Mat3<S> Rc[8];
    Vec3<S> tc[8], nc[8];
    const int k = decomposeHomography(H, Rc, tc, nc);
    REQUIRE(k == 8);
    double best = 1e9;
    for (int i = 0; i < k; ++i) {
      const double err = est_test::rotationErrorDeg(Rc[i].template cast<double>(), R) +
                         est_test::angleDeg(tc[i].template cast<double>(), t) +
                         std::min(est_test::angleDeg(nc[i].template cast<double>(), nrm),
                                  est_test::angleDeg(-nc[i].template cast<double>(), nrm));
      best = std::min(best, err);
    }
    CHECK(best < est_test::tol<S>(1e-5, 0.05));
  }
  // Pure rotation: singular values coincide, no decomposition.
  const Mat3<double> Hr = Rng(1).rotation(0.1, 0.5);
  Mat3<double> Rc[8];
  Vec3<double> tc[8], nc[8];
  CHECK(decomposeHomography(Hr, Rc, tc, nc) == 0);
  Mat3<double> bad = Hr;
  bad(1, 1) = std::numeric_limits<double>::infinity();
  CHECK(decomposeHomography(bad, Rc, tc, nc) == 0);
}

TEMPLATE_TEST_CASE("triangulation (DLT and midpoint) is exact on exact data", "[slam][triangulation]",
                   float, double) {
  using S = TestType;
  Rng rng(15);
  for (int trial = 0; trial < 20; ++trial) {
    // Two general world-to-camera poses.
    const Mat3<S> R1(rng.rotation(0, 0.3).cast<S>());
    const SE3<S> T1(R1, Vec3<S>(rng.unitVector().cast<S>()) * S(0.3));
    const Mat3<S> R2(rng.rotation(0, 0.3).cast<S>());
    const SE3<S> T2(R2, Vec3<S>(rng.unitVector().cast<S>()));
    const Vec3<S> X = Vec3<S>(rng.uniform3(-1, 1, -1, 1, 4, 8).cast<S>());
    const Vec3<S> p1 = T1 * X, p2 = T2 * X;
    if (p1.z() < S(1) || p2.z() < S(1)) continue;
    const Vec2<S> x1(p1.x() / p1.z(), p1.y() / p1.z()), x2(p2.x() / p2.z(), p2.y() / p2.z());
    Vec3<S> Xd, Xm;
    REQUIRE(triangulateDLT(T1, T2, x1, x2, Xd));
    REQUIRE(triangulateMidpoint(T1, T2, x1, x2, Xm));
    CHECK((Xd - X).norm() < est_test::tol<S>(1e-9, 2e-3));
    CHECK((Xm - X).norm() < est_test::tol<S>(1e-9, 2e-3));
    const TriangulationQuality<S> q = triangulationQuality(T1, T2, x1, x2, Xd);
    CHECK(q.depth1 > S(0));
    CHECK(q.depth2 > S(0));
    CHECK(double(q.err1Sq) < est_test::tol<S>(1e-20, 1e-9));
    // parallax = angle between the rays from the two centres
    const Eigen::Vector3d c1 = (T1.inverse().translation()).template cast<double>();
    const Eigen::Vector3d c2 = (T2.inverse().translation()).template cast<double>();
    const Eigen::Vector3d Xw = X.template cast<double>();
    CHECK(std::abs(double(q.parallaxDeg()) - est_test::angleDeg(Xw - c1, Xw - c2)) <
          est_test::tol<S>(1e-6, 0.05));
  }
  // Parallel rays (same centre): midpoint refuses; DLT returns false or a far point.
  const SE3<S> T;
  const Vec2<S> x(S(0.1), S(0.2));
  Vec3<S> X;
  CHECK_FALSE(triangulateMidpoint(T, T, x, x, X));
}

TEMPLATE_TEST_CASE("solveP3P returns the true pose", "[slam][p3p]", float, double) {
  using S = TestType;
  Rng rng(16);
  int found = 0;
  const int trials = 200;
  for (int trial = 0; trial < trials; ++trial) {
    const Eigen::Matrix3d R = rng.rotation(0, 3.0);
    const Eigen::Vector3d t = rng.scaledUnit(0, 3);
    Vec3<S> f[3], P[3];
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d Xc = rng.uniform3(-2, 2, -1.5, 1.5, 2, 6);
      const Eigen::Vector3d Xw = R.transpose() * (Xc - t);  // Xc = R·Xw + t
      f[i] = (Xc * rng.uniform(0.2, 3)).cast<S>();           // any bearing length
      P[i] = Xw.cast<S>();
    }
    std::vector<SE3<S>> sols;
    solveP3P(f, P, sols);
    CHECK(sols.size() <= 4);
    double best = 1e9;
    for (const auto& T : sols) {
      best = std::min(best, est_test::rotationErrorDeg(T.rotationMatrix().template cast<double>(), R) +
                                (T.translation().template cast<double>() - t).norm());
      // every solution reprojects the three points exactly
      for (int i = 0; i < 3; ++i) {
        const Eigen::Vector3d q = (T * P[i]).template cast<double>();
        CHECK(est_test::angleDeg(q, f[i].template cast<double>()) < est_test::tol<S>(1e-5, 0.2));
      }
    }
    found += best < est_test::tol<S>(1e-6, 2e-2) ? 1 : 0;
  }
  CHECK(found >= trials - 2);
  // Degenerate: collinear points, coincident points, NaN.
  Vec3<double> f[3] = {Vec3<double>(0, 0, 1), Vec3<double>(0.1, 0, 1), Vec3<double>(0.2, 0, 1)};
  Vec3<double> P[3] = {Vec3<double>(0, 0, 5), Vec3<double>(1, 0, 5), Vec3<double>(2, 0, 5)};
  std::vector<SE3<double>> sols;
  solveP3P(f, P, sols);
  CHECK(sols.empty());
  P[2] = P[1] = P[0];
  solveP3P(f, P, sols);
  CHECK(sols.empty());
  P[1] = Vec3<double>(1, std::numeric_limits<double>::quiet_NaN(), 5);
  solveP3P(f, P, sols);
  CHECK(sols.empty());
}
