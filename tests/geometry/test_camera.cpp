// Pinhole camera (hawor/geometry/camera.hpp): project/unproject round trip, projection
// Jacobian, field-of-view construction, visibility at the image border, validation.
#include <catch2/catch.hpp>

#include "geometry_test_utils.hpp"

using namespace hawor;
using geo_test::tol;

TEMPLATE_TEST_CASE("pinhole project/unproject round trip", "[geometry][camera]", float, double) {
  using S = TestType;
  geo_test::Rng rng(41);
  const PinholeCamera<S> cam{S(600), S(580), S(319.5), S(241), 640, 480};
  REQUIRE_NOTHROW(cam.validate());
  for (int i = 0; i < 50; ++i) {
    const Vec3<S> p = Eigen::Vector3d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.2, 5))
                          .cast<S>();
    const Vec2<S> uv = cam.project(p);
    CHECK((cam.unproject(uv, p(2)) - p).norm() <= tol<S>(1e-14, 1e-5) * p.norm());
    const Vec3<S> r = cam.ray(uv);
    CHECK(r(2) == S(1));
    CHECK((r * p(2) - p).norm() <= tol<S>(1e-14, 1e-5) * p.norm());
    // The pinhole equations, written out.
    CHECK(uv(0) == Approx(cam.fx * p(0) / p(2) + cam.cx).margin(tol<S>(1e-12, 1e-4)));
    CHECK(uv(1) == Approx(cam.fy * p(1) / p(2) + cam.cy).margin(tol<S>(1e-12, 1e-4)));
    CHECK((cam.K() * p / p(2)).template head<2>().isApprox(uv, tol<S>(1e-14, 1e-5)));
  }
  // The principal point is the projection of the optical axis.
  CHECK((cam.project(Vec3<S>(S(0), S(0), S(2))) - Vec2<S>(cam.cx, cam.cy)).norm() == S(0));
}

TEST_CASE("pinhole projection Jacobian matches central differences", "[geometry][camera][jacobian]") {
  geo_test::Rng rng(42);
  const PinholeCamera<double> cam{500, 520, 300, 250, 640, 480};
  for (int i = 0; i < 30; ++i) {
    const Eigen::Vector3d p(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.2, 5));
    Eigen::Matrix<double, 2, 3> J;
    cam.project(p, &J);
    auto f = [&](const Eigen::Vector3d& q) -> Eigen::Vector2d { return cam.project(q); };
    CHECK((geo_test::numericJacobian<2, 3>(f, p, 1e-7) - J).norm() <= 1e-5 * J.norm());
  }
}

TEMPLATE_TEST_CASE("fromFov puts the diagonal field of view between opposite corners",
                   "[geometry][camera]", float, double) {
  using S = TestType;
  for (auto wh : {std::pair<int, int>{640, 480}, {1920, 1080}, {101, 77}}) {
    for (S fov : {S(60), S(90), S(120)}) {
      const auto cam = PinholeCamera<S>::fromFov(wh.first, wh.second, fov);
      REQUIRE_NOTHROW(cam.validate());
      CHECK(cam.fx == cam.fy);
      CHECK(cam.cx == S(wh.first - 1) / S(2));
      CHECK(cam.cy == S(wh.second - 1) / S(2));
      // Pixel centres at integers: the image corners are at (−0.5, −0.5) and (w−0.5, h−0.5).
      const Vec3<S> a = cam.ray(Vec2<S>(S(-0.5), S(-0.5))).normalized();
      const Vec3<S> b =
          cam.ray(Vec2<S>(S(wh.first) - S(0.5), S(wh.second) - S(0.5))).normalized();
      const S angle = std::atan2(a.cross(b).norm(), a.dot(b)) * S(180) / Constants<S>::pi();
      CHECK(angle == Approx(fov).epsilon(tol<S>(1e-12, 1e-5)));
      CHECK(cam.diagonalFovDeg() == Approx(fov).epsilon(tol<S>(1e-12, 1e-5)));
    }
  }
  CHECK_THROWS_AS(PinholeCamera<S>::fromFov(0, 480, S(60)), Error);
  CHECK_THROWS_AS(PinholeCamera<S>::fromFov(640, 480, S(0)), Error);
  CHECK_THROWS_AS(PinholeCamera<S>::fromFov(640, 480, S(180)), Error);
  CHECK_THROWS_AS(PinholeCamera<S>::fromFov(640, 480, std::numeric_limits<S>::quiet_NaN()),
                  Error);
}

TEMPLATE_TEST_CASE("visibility, scaling and validation", "[geometry][camera]", float, double) {
  using S = TestType;
  const PinholeCamera<S> cam{S(100), S(100), S(49.5), S(29.5), 100, 60};
  // Just inside / outside the image border (border at −0.5 and w − 0.5).
  auto at = [&](S u, S v, S z) { return cam.unproject(Vec2<S>(u, v), z); };
  CHECK(cam.isVisible(at(S(-0.49), S(10), S(2))));
  CHECK_FALSE(cam.isVisible(at(S(-0.51), S(10), S(2))));
  CHECK(cam.isVisible(at(S(99.49), S(59.49), S(2))));
  CHECK_FALSE(cam.isVisible(at(S(99.51), S(10), S(2))));
  CHECK_FALSE(cam.isVisible(at(S(10), S(59.51), S(2))));
  CHECK_FALSE(cam.isVisible(at(S(10), S(10), S(2)), S(10.6)));
  CHECK(cam.isVisible(at(S(10), S(10), S(2)), S(10.4)));
  // Behind the camera or on the camera plane: never visible (the mirrored pixel is inside).
  CHECK_FALSE(cam.isVisible(Vec3<S>(S(0), S(0), S(-1))));
  CHECK_FALSE(cam.isVisible(Vec3<S>(S(0), S(0), S(0))));
  CHECK_FALSE(PinholeCamera<S>::inFront(Vec3<S>(S(0), S(0), S(0.1)), S(0.2)));
  CHECK(PinholeCamera<S>::inFront(Vec3<S>(S(0), S(0), S(0.1))));

  // Scaling keeps the ray through corresponding pixel positions.
  const PinholeCamera<S> half = cam.scaled(S(0.5));
  CHECK(half.width == 50);
  CHECK(half.height == 30);
  const Vec3<S> p(S(0.3), S(-0.2), S(1.7));
  const Vec2<S> uv = cam.project(p), uv2 = half.project(p);
  // Continuous image coordinates (pixel edges at −0.5) scale by the factor.
  CHECK((uv2 + Vec2<S>::Constant(S(0.5)) - S(0.5) * (uv + Vec2<S>::Constant(S(0.5)))).norm() <=
        tol<S>(1e-13, 1e-4));
  CHECK_THROWS_AS(cam.scaled(S(0)), Error);

  PinholeCamera<S> bad = cam;
  bad.fx = S(0);
  CHECK_THROWS_AS(bad.validate(), Error);
  bad = cam;
  bad.fy = std::numeric_limits<S>::infinity();
  CHECK_THROWS_AS(bad.validate(), Error);
  bad = cam;
  bad.cx = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_AS(bad.validate(), Error);
  bad = cam;
  bad.height = 0;
  CHECK_THROWS_AS(bad.validate(), Error);
  CHECK_THROWS_AS(PinholeCamera<S>{}.validate(), Error);
  const PinholeCamera<double> d = cam.template cast<double>();
  CHECK(d.fx == double(cam.fx));
  CHECK(d.width == cam.width);
}
