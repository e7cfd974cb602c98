// Lens models (hawor/geometry/lens.hpp) and the camera that combines them with pinhole
// intrinsics (camera_model.hpp): project → unproject round trips over whole images (fisheye
// beyond 90° included), distort ↔ undistort, every Jacobian against central differences (near
// the axis too), pinhole = PinholeCamera, the fold angle against brute force, parse/toString,
// and bad input (NaN, folding models, malformed strings). OpenCV cross-checks: ref_lens.cpp.
#include <catch2/catch.hpp>

#include "geometry_test_utils.hpp"

using namespace hawor;
using geo_test::tol;

template struct hawor::Lens<float>;
template struct hawor::Lens<double>;
template struct hawor::CameraModel<float>;
template struct hawor::CameraModel<double>;

namespace lens_test {

/// Cameras that exercise each model; every one validates (its corners lie before any fold).
template <typename S>
std::vector<CameraModel<S>> cameras() {
  std::vector<CameraModel<S>> c;
  // Radial-tangential: mild, strong barrel (corners near the fold), pincushion (k1 > 0).
  c.push_back({{S(520.3), S(518.7), S(321.4), S(243.9), 640, 480},
               Lens<S>::radTan(S(-0.12), S(0.05), S(1e-3), S(-5e-4), S(-0.01))});
  c.push_back({{S(440.2), S(441.1), S(318.7), S(241.2), 640, 480},
               Lens<S>::radTan(S(-0.28), S(0.075), S(2e-4), S(-3e-4), S(-0.009))});
  c.push_back({{S(410), S(409), S(300), S(250), 640, 480},
               Lens<S>::radTan(S(0.08), S(-0.02), S(-7e-4), S(4e-4))});
  // Fisheye: a typical calibration (folds at 115°, beyond the image); a 190°+ lens whose
  // corners are beyond 90°; an equidistant-like lens whose corners are at ~166°.
  c.push_back({{S(285.7), S(286.1), S(320.3), S(238.8), 640, 480},
               Lens<S>::fisheye(S(-0.013), S(-0.002), S(0.0026), S(-0.0008))});
  c.push_back({{S(250), S(250.5), S(399.5), S(399.5), 800, 800},
               Lens<S>::fisheye(S(0.03), S(-0.01), S(0.002), S(-0.0001))});
  c.push_back({{S(200), S(200), S(399.5), S(399.5), 800, 800},
               Lens<S>::fisheye(S(-0.01), S(0.002), S(0), S(0))});
  return c;
}

/// Angle between a vector and the optical axis.
template <typename S>
double axisAngle(const Vec3<S>& b) {
  const Eigen::Vector3d d = b.template cast<double>();
  return std::atan2(d.head<2>().norm(), d(2));
}

}  // namespace lens_test

TEMPLATE_TEST_CASE("lens: a pinhole lens is PinholeCamera", "[geometry][lens]", float, double) {
  using S = TestType;
  geo_test::Rng rng(71);
  const PinholeCamera<S> cam{S(600), S(580), S(319.5), S(241), 640, 480};
  const CameraModel<S> model{cam, Lens<S>::pinhole()};
  const CameraModel<S> zeros{cam, Lens<S>::radTan(S(0), S(0), S(0), S(0), S(0))};
  CHECK(model.lens.isPinhole());
  CHECK(zeros.lens.isPinhole());
  CHECK_FALSE(Lens<S>::fisheye(S(0), S(0), S(0), S(0)).isPinhole());
  CHECK(model.lens.maxMonotonicAngle() == Approx(geo_test::pi() / 2));
  REQUIRE_NOTHROW(model.validate());
  for (int i = 0; i < 50; ++i) {
    const Vec3<S> p =
        Eigen::Vector3d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.2, 5)).cast<S>();
    Eigen::Matrix<S, 2, 3> J, Jc, Jz;
    const Vec2<S> uv = model.project(p, &J);
    const S e = 4 * std::numeric_limits<S>::epsilon();
    CHECK((uv - cam.project(p, &Jc)).norm() <= e * uv.norm());
    CHECK((J - Jc).norm() <= e * J.norm());
    CHECK((zeros.project(p, &Jz) - uv).norm() <= tol<S>(1e-12, 1e-3));
    CHECK((Jz - J).norm() <= tol<S>(1e-12, 1e-3) * J.norm());
    CHECK(model.isVisible(p) == cam.isVisible(p));
    Vec3<S> b;
    REQUIRE(model.bearing(uv, b));
    CHECK((b - cam.ray(uv).normalized()).norm() <= tol<S>(1e-15, 1e-6));
    REQUIRE(zeros.bearing(uv, b));
    CHECK((b - cam.ray(uv).normalized()).norm() <= tol<S>(1e-15, 1e-6));
    Vec2<S> up;
    REQUIRE(model.undistortPixel(uv, up));
    CHECK(up == uv);
  }
  // Behind the camera: never visible, as PinholeCamera.
  CHECK_FALSE(model.isVisible(Vec3<S>(S(0), S(0), S(-1))));
  // The diagonal field of view of fromFov is twice the largest corner angle.
  const CameraModel<S> fov{PinholeCamera<S>::fromFov(640, 480, S(90)), Lens<S>::pinhole()};
  CHECK(fov.maxFieldAngle() == Approx(geo_test::pi() / 4).epsilon(tol<S>(1e-12, 1e-5)));
}

TEMPLATE_TEST_CASE("lens: project → unproject round trips over the whole image", "[geometry][lens]",
                   float, double) {
  using S = TestType;
  const S px_tol = tol<S>(1e-9, 2e-3);
  for (const CameraModel<S>& cam : lens_test::cameras<S>()) {
    INFO("lens " << cam.lens.toString());
    REQUIRE_NOTHROW(cam.validate());
    const int w = cam.intrinsics.width, h = cam.intrinsics.height;
    double max_err = 0, max_angle = 0;
    // A 21×17 grid over [−0.5, w − 0.5] × [−0.5, h − 0.5], corners and edges included.
    for (int i = 0; i <= 20; ++i) {
      for (int j = 0; j <= 16; ++j) {
        const Vec2<S> uv(S(-0.5) + S(w) * S(i) / S(20), S(-0.5) + S(h) * S(j) / S(16));
        Vec3<S> b;
        INFO("pixel " << uv.transpose());
        REQUIRE(cam.bearing(uv, b));
        CHECK(std::abs(double(b.norm()) - 1.0) <= tol<S>(1e-15, 1e-6) * 4);
        for (S depth : {S(0.3), S(40)}) {
          const Vec3<S> p = depth * b;
          CHECK(cam.isVisible(p, S(-1e-3)));
          const Vec2<S> back = cam.project(p);
          max_err = std::max(max_err, double((back - uv).norm()));
          CHECK((back - uv).norm() <= px_tol);
        }
        max_angle = std::max(max_angle, lens_test::axisAngle(b));
        // The pinhole pixel of the same ray, where there is one.
        Vec2<S> up;
        if (cam.undistortPixel(uv, up)) {
          CHECK(b(2) > S(0));
          const Vec3<S> r = cam.intrinsics.ray(up).normalized();
          CHECK((r - b).norm() <= tol<S>(1e-12, 2e-5));
        } else {
          CHECK(cam.lens.kind == LensKind::Fisheye);
          CHECK(b(2) <= S(1e-6));
        }
      }
    }
    INFO("max error " << max_err << " px, max angle " << max_angle * 180 / geo_test::pi());
    CHECK(double(cam.maxFieldAngle()) == Approx(max_angle).epsilon(tol<S>(1e-12, 1e-5)));
    CHECK(cam.maxFieldAngle() <= cam.lens.maxMonotonicAngle());
  }
}

TEMPLATE_TEST_CASE("lens: fisheye directions beyond 90° round trip", "[geometry][lens]", float,
                   double) {
  using S = TestType;
  geo_test::Rng rng(72);
  const Lens<S> lens = Lens<S>::fisheye(S(-0.01), S(0.002), S(0), S(0));
  REQUIRE(lens.maxMonotonicAngle() == Approx(geo_test::pi()));
  for (double deg : {0.0, 1e-7, 1e-3, 30.0, 89.9, 90.0, 90.1, 100.0, 120.0, 150.0, 170.0, 179.0}) {
    for (int rep = 0; rep < 5; ++rep) {
      const double th = deg * geo_test::pi() / 180, phi = rng.uniform(-3.1, 3.1);
      const Vec3<S> d =
          Eigen::Vector3d(std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi), std::cos(th))
              .cast<S>();
      INFO("angle " << deg << " phi " << phi);
      REQUIRE(lens.inDomain(S(3) * d));
      const Vec2<S> m = lens.project(S(3) * d);
      // |m| = θd(θ) exactly: the equidistant model's defining property.
      const double t2 = th * th, td = th * (1 - 0.01 * t2 + 0.002 * t2 * t2);
      CHECK(double(m.norm()) == Approx(td).epsilon(tol<S>(1e-14, 2e-6)).margin(1e-30));
      Vec3<S> b;
      REQUIRE(lens.unproject(m, b));
      CHECK((b - d).norm() <= tol<S>(1e-14, 2e-5) * (deg > 178 ? 10 : 1));
      Vec2<S> xy;
      if (std::abs(deg - 90) > 0.05) CHECK(lens.undistort(m, xy) == (deg < 90.0));
    }
  }
}

TEMPLATE_TEST_CASE("lens: distort and undistort are inverse inside the monotonic domain",
                   "[geometry][lens]", float, double) {
  using S = TestType;
  geo_test::Rng rng(73);
  for (const CameraModel<S>& cam : lens_test::cameras<S>()) {
    const Lens<S>& lens = cam.lens;
    INFO("lens " << lens.toString());
    // Undistorted radii up to 95% of the fold (and below 85° for the z = 1 form).
    const double amax =
        std::min(0.95 * double(lens.maxMonotonicAngle()), 85 * geo_test::pi() / 180);
    const double rmax = std::tan(amax);
    for (int i = 0; i < 200; ++i) {
      const double r = i < 3 ? std::pow(10.0, -3.0 * (i + 2)) : rmax * std::sqrt(rng.uniform(0, 1));
      const double phi = rng.uniform(-3.2, 3.2);
      const Vec2<S> xy = Eigen::Vector2d(r * std::cos(phi), r * std::sin(phi)).cast<S>();
      INFO("xy " << xy.transpose());
      const Vec2<S> m = lens.distort(xy);
      Vec2<S> back;
      REQUIRE(lens.undistort(m, back));
      CHECK((back - xy).norm() <= tol<S>(1e-12, 5e-5) * (1 + double(xy.norm())) * (1 + r * r));
      Vec2<S> again = lens.distort(back);
      CHECK((again - m).norm() <= tol<S>(4e-15, 2e-6) * (1 + double(m.norm())) * 4);
      // distort is the z = 1 form of project.
      CHECK((lens.project(Vec3<S>(xy(0), xy(1), S(1))) - m).norm() <=
            tol<S>(1e-15, 1e-6) * (1 + double(m.norm())) * 4);
    }
  }
}

TEST_CASE("lens: every Jacobian matches central differences", "[geometry][lens][jacobian]") {
  using V3 = Eigen::Matrix<double, 3, 1>;
  using V2 = Eigen::Matrix<double, 2, 1>;
  geo_test::Rng rng(74);
  std::vector<Lens<double>> lenses = {Lens<double>::pinhole()};
  for (const auto& c : lens_test::cameras<double>()) lenses.push_back(c.lens);
  lenses.push_back(Lens<double>::fisheye(0, 0, 0, 0));
  lenses.push_back(Lens<double>::fisheye(0.4, -0.3, 0.1, -0.02));
  for (const Lens<double>& lens : lenses) {
    const bool fish = lens.kind == LensKind::Fisheye;
    const double amax = std::min(0.9 * lens.maxMonotonicAngle(), fish ? 3.0 : 1.0);
    // Directions from the axis itself (r = 0), through the fisheye's Taylor threshold
    // (θ = 1e-5 in double), to the edge of the domain.
    std::vector<double> angles = {0.0, 1e-12, 1e-9, 1e-7, 9.9e-6, 1.01e-5, 1e-4, 1e-2, 0.3};
    for (int i = 0; i < 12; ++i) angles.push_back(rng.uniform(0, amax));
    for (double th : angles) {
      const double phi = rng.uniform(-3.2, 3.2), depth = rng.uniform(0.3, 4);
      const V3 p =
          depth * V3(std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi), std::cos(th));
      INFO("lens " << lens.toString() << " angle " << th << " p " << p.transpose());
      Eigen::Matrix<double, 2, 3> J;
      lens.project(p, &J);
      auto f = [&](const V3& q) -> V2 { return lens.project(q); };
      const Eigen::Matrix<double, 2, 3> Jn = geo_test::numericJacobian<2, 3>(f, p, 1e-6);
      CHECK((Jn - J).norm() <= 1e-7 * (1 + J.norm()));
      // project without J gives the same value.
      Eigen::Matrix<double, 2, 3> unused;
      CHECK((lens.project(p, &unused) - lens.project(p)).norm() == 0.0);
      if (p(2) > 0) {
        const V2 xy = p.head<2>() / p(2);
        Eigen::Matrix<double, 2, 2> Jd;
        lens.distort(xy, &Jd);
        auto g = [&](const V2& q) -> V2 { return lens.distort(q); };
        CHECK((geo_test::numericJacobian<2, 2>(g, xy, 1e-6) - Jd).norm() <= 1e-7 * (1 + Jd.norm()));
      }
      // The camera's Jacobian in pixels.
      const CameraModel<double> cam{{500, 480, 320, 240, 640, 480}, lens};
      Eigen::Matrix<double, 2, 3> Jc;
      cam.project(p, &Jc);
      auto fc = [&](const V3& q) -> V2 { return cam.project(q); };
      CHECK((geo_test::numericJacobian<2, 3>(fc, p, 1e-6) - Jc).norm() <= 1e-6 * (1 + Jc.norm()));
    }
  }
}

TEST_CASE("lens: float Jacobians agree with double ones", "[geometry][lens][jacobian]") {
  geo_test::Rng rng(75);
  for (const auto& c : lens_test::cameras<double>()) {
    const Lens<double>& ld = c.lens;
    const Lens<float> lf = ld.cast<float>();
    for (double th : {0.0, 1e-6, 1e-3, 3.1e-3, 3.2e-3, 0.1, 0.7, 1.2, 2.0}) {
      if (th > 0.95 * ld.maxMonotonicAngle()) continue;
      const double phi = rng.uniform(-3.2, 3.2);
      const Eigen::Vector3d p(std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi),
                              std::cos(th));
      Eigen::Matrix<double, 2, 3> Jd;
      Eigen::Matrix<float, 2, 3> Jf;
      const Eigen::Vector2d md = ld.project(p, &Jd);
      const Eigen::Vector2f mf = lf.project(p.cast<float>(), &Jf);
      INFO("lens " << ld.toString() << " angle " << th);
      CHECK((mf.cast<double>() - md).norm() <= 1e-6 * (1 + md.norm()));
      CHECK((Jf.cast<double>() - Jd).norm() <= 1e-5 * (1 + Jd.norm()));
    }
  }
}

TEST_CASE("lens: the fold angle is the first root of the radial slope",
          "[geometry][lens][monotonic]") {
  const double pi = geo_test::pi();
  // θd′ = 1 − 0.9 θ²: folds at θ = 1/√0.9 (60.4°).
  const Lens<double> f1 = Lens<double>::fisheye(-0.3, 0, 0, 0);
  CHECK(f1.maxMonotonicAngle() == Approx(1 / std::sqrt(0.9)).epsilon(1e-14));
  // A short dip: θd′ = (1 − θ²)(1 − θ²/1.1) is negative only for θ in (1, 1.0488); a sampled
  // search would miss it, the root isolation does not.
  const Lens<double> dip = Lens<double>::fisheye(-(1 + 1 / 1.1) / 3, 1 / 1.1 / 5, 0, 0);
  CHECK(dip.maxMonotonicAngle() == Approx(1.0).epsilon(1e-13));
  CHECK(dip.monotonicUpTo(0.999));
  CHECK_FALSE(dip.monotonicUpTo(1.001));
  CHECK_FALSE(dip.monotonicUpTo(2.0));  // increasing again there, but past the fold
  // Beyond the fold, unproject refuses the far branch even where θd takes the value again.
  Vec3<double> b;
  const double td_fold = 1.0 * (1 + dip.k[0] + dip.k[1]);
  CHECK(dip.unproject(Eigen::Vector2d(td_fold * 0.999, 0), b));
  CHECK(std::atan2(b.head<2>().norm(), b(2)) < 1.0);
  CHECK_FALSE(dip.unproject(Eigen::Vector2d(td_fold * 1.001, 0), b));
  CHECK(Lens<double>::fisheye(0.1, 0.01, 0, 0).maxMonotonicAngle() == pi);
  // Radial-tangential without tangential terms: dr_d/dr = 1 − 1.5 r² = 0 at r = √(2/3).
  CHECK(Lens<double>::radTan(-0.5, 0, 0, 0).maxMonotonicAngle() ==
        Approx(std::atan(std::sqrt(2.0 / 3.0))).epsilon(1e-14));
  CHECK(Lens<double>::radTan(0.1, 0.01, 0, 0, 0.001).maxMonotonicAngle() == pi / 2);
  // With tangential terms: brute force over directions and radii of the distorted point's
  // component along the ray, d/dr (d · distort(r d)), with distort written out here from
  // OpenCV's formula in plain doubles (fast enough unoptimised and under node).
  for (const Lens<double>& l : {Lens<double>::radTan(-0.28, 0.075, 2e-3, -3e-3, -0.009),
                                Lens<double>::radTan(-0.45, 0.1, 0.03, 0.04),
                                Lens<double>::radTan(-0.4, 0.1, 0.01, 0.02)}) {
    const double k1 = l.k[0], k2 = l.k[1], p1 = l.k[2], p2 = l.k[3], k3 = l.k[4];
    double first = 1e9;
    for (int a = 0; a < 360; ++a) {
      const double c = std::cos(2 * pi * a / 360), s = std::sin(2 * pi * a / 360);
      auto along = [&](double r) {  // d · distort(r d)
        const double x = r * c, y = r * s, r2 = r * r;
        const double rad = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
        const double xd = x * rad + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
        const double yd = y * rad + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
        return c * xd + s * yd;
      };
      auto slope = [&](double r) { return (along(r + 1e-6) - along(r - 1e-6)) / 2e-6; };
      for (double r = 5e-3; r < 3; r += 5e-3) {
        if (slope(r) <= 0) {
          double lo = r - 5e-3, hi = r;  // bisect the crossing
          for (int it = 0; it < 40; ++it) (slope(0.5 * (lo + hi)) > 0 ? lo : hi) = 0.5 * (lo + hi);
          first = std::min(first, hi);
          break;
        }
      }
    }
    INFO("lens " << l.toString());
    if (first < 1e9) {
      CHECK(std::tan(l.maxMonotonicAngle()) == Approx(first).margin(1e-4));
    } else {
      CHECK(l.maxMonotonicAngle() == pi / 2);  // the last lens never folds
    }
  }
}

TEST_CASE("lens: random lenses unproject exactly the image of their monotonic domain",
          "[geometry][lens][monotonic]") {
  geo_test::Rng rng(76);
  for (int trial = 0; trial < 25; ++trial) {
    // Fisheye: unproject succeeds iff θd ≤ θd(θmax), and then inverts project.
    const Lens<double> f =
        Lens<double>::fisheye(rng.uniform(-0.3, 0.3), rng.uniform(-0.1, 0.1),
                              rng.uniform(-0.03, 0.03), rng.uniform(-0.01, 0.01));
    const double tmax = f.maxMonotonicAngle();
    const double t2 = tmax * tmax;
    const double tdmax = tmax * (1 + t2 * (f.k[0] + t2 * (f.k[1] + t2 * (f.k[2] + t2 * f.k[3]))));
    for (int i = 0; i < 20; ++i) {
      const double td = rng.uniform(0, 1.2 * tdmax), phi = rng.uniform(-3.2, 3.2);
      if (std::abs(td - tdmax) < 1e-9 * tdmax) continue;
      const Vec2<double> m(td * std::cos(phi), td * std::sin(phi));
      Vec3<double> b;
      INFO("lens " << f.toString() << " fold " << tmax << " td " << td << " of " << tdmax);
      REQUIRE(f.unproject(m, b) == (td < tdmax));
      if (td < tdmax) {
        CHECK(f.inDomain(b));
        CHECK((f.project(b) - m).norm() <=
              1e-12 * (1 + td) / std::max(1e-3, tmax - std::atan2(b.head<2>().norm(), b(2))));
      }
    }
    // Radial-tangential: a success inverts project inside the domain; every distorted point
    // of the domain (out to 97% of the fold radius) is recovered, strong pincushion lenses
    // included (their edge maps beyond the fold radius, and some rise to a second solution).
    const Lens<double> r = Lens<double>::radTan(rng.uniform(-0.8, 0.8), rng.uniform(-0.3, 0.3),
                                                rng.uniform(-0.03, 0.03), rng.uniform(-0.03, 0.03),
                                                rng.uniform(-0.1, 0.1));
    const double rmax = std::tan(r.maxMonotonicAngle());
    for (int i = 0; i < 20; ++i) {
      const double phi = rng.uniform(-3.2, 3.2);
      const Vec2<double> m = rng.uniform(0, 2.5) * Vec2<double>(std::cos(phi), std::sin(phi));
      Vec2<double> xy;
      INFO("lens " << r.toString() << " fold radius " << rmax << " m " << m.transpose());
      if (r.undistort(m, xy)) {
        CHECK(r.inDomain(Vec3<double>(xy(0), xy(1), 1.0)));
        CHECK((r.distort(xy) - m).norm() <= 1e-13 * (1 + m.norm()));
      }
      const Vec2<double> in =
          std::min(rmax, 5.0) * rng.uniform(0, 0.97) * Vec2<double>(std::cos(phi), std::sin(phi));
      INFO("xy " << in.transpose());
      REQUIRE(r.undistort(r.distort(in), xy));
      CHECK((xy - in).norm() <= 1e-10 * (1 + in.norm()));
    }
  }
}

TEMPLATE_TEST_CASE("lens: parse and toString round trip", "[geometry][lens][parse]", float,
                   double) {
  using S = TestType;
  const std::vector<Lens<S>> lenses = {
      Lens<S>::pinhole(), Lens<S>::radTan(S(-0.28), S(0.075), S(2e-4), S(-3e-4), S(-0.009)),
      Lens<S>::radTan(S(1) / S(3), S(-2) / S(7), S(1e-7), S(-0.0), S(123456.789)),
      Lens<S>::fisheye(S(-0.013), S(-0.002), S(0.0026), S(-0.0008)),
      Lens<S>::fisheye(S(0.1), S(1) / S(3), std::numeric_limits<S>::min(),
                       std::numeric_limits<S>::denorm_min())};
  for (const Lens<S>& l : lenses) {
    const std::string s = l.toString();
    INFO(s);
    const Lens<S> back = Lens<S>::parse(s);
    CHECK(back.kind == l.kind);
    CHECK(back.k == l.k);
    CHECK(back.toString() == s);
    const CameraModel<S> cam =
        CameraModel<S>::fromString({S(300), S(300), S(100), S(80), 200, 160}, s);
    CHECK(cam.lens.k == l.k);
  }
  CHECK(Lens<S>::radTan(S(-0.28), S(0.075), S(2e-4), S(-3e-4), S(-0.009)).toString() ==
        "opencv:-0.28,0.075,0.0002,-0.0003,-0.009");
  CHECK(Lens<S>::fisheye(S(-0.013), S(0), S(1), S(-0.5)).toString() == "fisheye:-0.013,0,1,-0.5");
  CHECK(Lens<S>::pinhole().toString() == "pinhole");
  // Accepted variants: 4 OpenCV coefficients (k3 = 0), spaces, model names in any case.
  const Lens<S> four = Lens<S>::parse(" OpenCV: -0.1, 0.02 ,0.001,  -0.002 ");
  CHECK(four.kind == LensKind::RadTan);
  CHECK(four.k == std::array<S, 5>{S(-0.1), S(0.02), S(0.001), S(-0.002), S(0)});
  CHECK(Lens<S>::parse("PINHOLE").kind == LensKind::Pinhole);
  CHECK(Lens<S>::parse("fisheye:1e-3,-2E-4,0,0").k[1] == S(-2e-4));
  // cast keeps the model.
  const Lens<double> d = lenses[3].template cast<double>();
  CHECK(d.kind == LensKind::Fisheye);
  CHECK(d.k[0] == double(lenses[3].k[0]));
}

TEMPLATE_TEST_CASE("lens: bad strings are errors naming the problem", "[geometry][lens][parse]",
                   float, double) {
  using S = TestType;
  using Catch::Contains;
  auto parse = [](const std::string& s) { return Lens<S>::parse(s); };
  CHECK_THROWS_WITH(parse("opencv:1,2"),
                    Contains("\"opencv:1,2\"") && Contains("4 or 5") && Contains("got 2"));
  CHECK_THROWS_WITH(parse("opencv:1,2,3,4,5,6"), Contains("got 6"));
  CHECK_THROWS_WITH(parse("fisheye:0,0,0"), Contains("takes 4") && Contains("got 3"));
  CHECK_THROWS_WITH(parse("fisheye:a,b,c,d"), Contains("\"fisheye:a,b,c,d\"") &&
                                                  Contains("coefficient 1 (k1)") &&
                                                  Contains("\"a\" is not a number"));
  CHECK_THROWS_WITH(parse("fisheye:0,0,0.1x,0"), Contains("(k3) \"0.1x\" is not a number"));
  CHECK_THROWS_WITH(parse("kb:1,2,3,4"), Contains("\"kb:1,2,3,4\"") &&
                                             Contains("unknown lens model \"kb\"") &&
                                             Contains("fisheye:k1,k2,k3,k4"));
  CHECK_THROWS_WITH(parse("fisheye:nan,0,0,0"), Contains("(k1) is not finite (nan)"));
  CHECK_THROWS_WITH(parse("opencv:0,inf,0,0"), Contains("(k2) is not finite"));
  CHECK_THROWS_WITH(parse("opencv:0,0,1e999,0"), Contains("(p1) is not finite"));
  CHECK_THROWS_WITH(parse("opencv:0,,0,0"), Contains("coefficient 2 (k2) is empty"));
  CHECK_THROWS_WITH(parse(""), Contains("empty lens description"));
  CHECK_THROWS_WITH(parse("   "), Contains("empty lens description"));
  CHECK_THROWS_WITH(parse("pinhole:0"), Contains("takes no coefficients"));
  CHECK_THROWS_WITH(parse("fisheye"), Contains("missing coefficients"));
  CHECK_THROWS_WITH(parse("fisheye:"), Contains("missing coefficients"));
  CHECK_THROWS_WITH((CameraModel<S>::fromString({S(300), S(300), S(100), S(80), 200, 160}, "kb:1")),
                    Contains("unknown lens model"));
  CHECK_THROWS_AS(parse("opencv:1,2"), Error);
}

TEMPLATE_TEST_CASE("lens: NaN and folding models are errors naming the problem",
                   "[geometry][lens][validate]", float, double) {
  using S = TestType;
  using Catch::Contains;
  const S nan = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_WITH(Lens<S>::radTan(nan, S(0), S(0), S(0)).validate(S(0.5)),
                    Contains("k1 is not finite"));
  CHECK_THROWS_WITH(
      Lens<S>::fisheye(S(0), S(0), std::numeric_limits<S>::infinity(), S(0)).validate(S(0.5)),
      Contains("k3 is not finite"));
  CHECK(std::isnan(Lens<S>::radTan(S(0), nan, S(0), S(0)).maxMonotonicAngle()));
  CHECK_FALSE(Lens<S>::fisheye(nan, S(0), S(0), S(0)).monotonicUpTo(S(0.1)));
  Vec3<S> b(S(7), S(7), S(7));
  CHECK_FALSE(Lens<S>::fisheye(nan, S(0), S(0), S(0)).unproject(Vec2<S>(S(0.1), S(0)), b));
  CHECK_FALSE(Lens<S>::radTan(S(0.1), S(0), S(0), S(0)).unproject(Vec2<S>(nan, S(0)), b));
  CHECK_FALSE(Lens<S>::fisheye(S(0), S(0), S(0), S(0)).unproject(Vec2<S>(S(0), nan), b));
  CHECK(b == Vec3<S>(S(7), S(7), S(7)));  // untouched
  const PinholeCamera<S> intr{S(200), S(200), S(319.5), S(239.5), 640, 480};
  CHECK_THROWS_WITH((CameraModel<S>{intr, Lens<S>::fisheye(S(0.1), nan, S(0), S(0))}.validate()),
                    Contains("k2 is not finite"));
  CHECK_THROWS_WITH(CameraModel<S>::fromString(intr, "fisheye:0.1,nan,0,0"),
                    Contains("not finite"));

  // θd′ = 1 − 0.9 θ² folds at 60.4°: a lens asked to cover 68.8° is an error naming both.
  const Lens<S> fold = Lens<S>::fisheye(S(-0.3), S(0), S(0), S(0));
  CHECK_NOTHROW(fold.validate(S(1.0)));
  CHECK_THROWS_WITH(fold.validate(S(1.2)), Contains("folds at 60.4 degrees") &&
                                               Contains("68.8 degrees") &&
                                               Contains("fisheye:-0.3,0,0,0"));
  // In an image whose corners lie beyond what the folding lens reaches: the corner is named.
  const CameraModel<S> cam{intr, fold};
  CHECK_THROWS_WITH(cam.validate(), Contains("corner (-0.5, -0.5)") && Contains("60.4 degrees"));
  CHECK(std::isinf(cam.maxFieldAngle()));
  CHECK_THROWS_AS(CameraModel<S>::fromString(intr, "fisheye:-0.3,0,0,0"), Error);
  // A smaller image (corners at θd = 0.5 < θd(fold) = 0.70) is fine.
  const CameraModel<S> small{{S(200), S(200), S(79.5), S(59.5), 160, 120}, fold};
  CHECK_NOTHROW(small.validate());
  CHECK(small.maxFieldAngle() < fold.maxMonotonicAngle());

  // Radial-tangential: dr_d/dr = 1 − 1.5 r² folds at r = 0.816 (39.2°).
  const Lens<S> barrel = Lens<S>::radTan(S(-0.5), S(0), S(0), S(0));
  CHECK_THROWS_WITH(barrel.validate(S(0.8)), Contains("folds at 39.2 degrees"));
  CHECK_NOTHROW(barrel.validate(S(0.6)));
  CHECK_THROWS_WITH((CameraModel<S>{intr, barrel}.validate()), Contains("corner"));
  // Pinhole-type models cannot see 90°.
  CHECK_THROWS_WITH(Lens<S>::pinhole().validate(S(1.6)), Contains("less than 90 degrees"));
  CHECK_THROWS_WITH(Lens<S>::fisheye(S(0), S(0), S(0), S(0)).validate(S(3.2)),
                    Contains("180 degrees"));
  // Coefficients the model does not use.
  Lens<S> junk = Lens<S>::pinhole();
  junk.k[0] = S(0.1);
  CHECK_THROWS_WITH(junk.validate(S(0.1)), Contains("pinhole lens has no coefficients"));
  junk = Lens<S>::fisheye(S(0), S(0), S(0), S(0));
  junk.k[4] = S(0.1);
  CHECK_THROWS_WITH(junk.validate(S(0.1)), Contains("k[4] must be 0"));
}

TEMPLATE_TEST_CASE("lens: visibility respects the fold; scaling keeps the rays", "[geometry][lens]",
                   float, double) {
  using S = TestType;
  // A barrel lens folds at r = 0.816; a point at r = 1.5 would "project" back near the image
  // centre (r_d = 1.5·(1 − 0.5·2.25) < 0): it is not visible.
  const CameraModel<S> cam{{S(400), S(400), S(319.5), S(239.5), 640, 480},
                           Lens<S>::radTan(S(-0.5), S(0), S(0), S(0))};
  const Vec3<S> far(S(1.5), S(0), S(1));
  CHECK(cam.intrinsics.inImage(cam.project(far)));
  CHECK_FALSE(cam.lens.inDomain(far));
  CHECK_FALSE(cam.isVisible(far));
  CHECK(cam.isVisible(Vec3<S>(S(0.5), S(0.3), S(1))));
  CHECK_FALSE(cam.isVisible(Vec3<S>(S(0.1), S(0), S(-1))));
  // A fisheye sees behind its image plane: 100° from the axis, inside a 190° image.
  const CameraModel<S> fish{{S(200), S(200), S(399.5), S(399.5), 800, 800},
                            Lens<S>::fisheye(S(-0.01), S(0.002), S(0), S(0))};
  const S th = S(100 * geo_test::pi() / 180);
  const Vec3<S> side(std::sin(th), S(0), std::cos(th));
  CHECK(fish.isVisible(side));
  CHECK_FALSE(fish.isVisible(Vec3<S>(S(0), S(0), S(-1))));  // the back axis
  CHECK_FALSE(fish.isVisible(Vec3<S>(S(0), S(0), S(0))));
  // scaled: intrinsics as PinholeCamera::scaled, lens unchanged, continuous pixel coordinates
  // (edges at −0.5) scale by the factor.
  for (const CameraModel<S>& c : lens_test::cameras<S>()) {
    const CameraModel<S> half = c.scaled(S(0.5));
    CHECK(half.lens.k == c.lens.k);
    CHECK(half.intrinsics.width == c.intrinsics.width / 2);
    const Vec3<S> p(S(0.2), S(-0.1), S(1));
    const Vec2<S> a = c.project(p), h = half.project(p);
    CHECK((h + Vec2<S>::Constant(S(0.5)) - S(0.5) * (a + Vec2<S>::Constant(S(0.5)))).norm() <=
          tol<S>(1e-12, 1e-4));
    const CameraModel<double> d = c.template cast<double>();
    CHECK(d.intrinsics.fx == double(c.intrinsics.fx));
    CHECK(d.lens.kind == c.lens.kind);
  }
}
