// Cross-check of the lens models (hawor/geometry/lens.hpp, camera_model.hpp) against OpenCV
// (Debian's python3-opencv, run by tests/ref/lens_cv.py): cv2.projectPoints and
// cv2.fisheye.projectPoints (pixels, and their Jacobian with respect to tvec, which at rvec = 0
// is d(u, v)/dp), cv2.undistortPointsIter and cv2.fisheye.undistortPoints (undistorted
// normalised coordinates; bearings). Double precision, ~1e-9 relative. Skipped, with a warning,
// when /usr/bin/python3 cannot import cv2.
#include <catch2/catch.hpp>
#include <cstdio>

#include "../support/ref_data.hpp"
#include "hawor/geometry/geometry.hpp"

using namespace hawor;
using hawor_test::RefArray;

namespace lens_ref {

const hawor_test::RefData& ref() {
  static const hawor_test::RefData data = hawor_test::runReference("lens_cv.py", "lens_cv.txt");
  return data;
}

CameraModel<double> camera(long i) {
  const std::string c = "case" + std::to_string(i) + "_";
  const RefArray& K = ref()[c + "K"];
  const RefArray& size = ref()[c + "size"];
  const RefArray& D = ref()[c + "D"];
  CameraModel<double> cam;
  cam.intrinsics = {K[0], K[1], K[2], K[3], int(size[0]), int(size[1])};
  cam.lens = ref()[c + "kind"][0] == 0 ? Lens<double>::radTan(D[0], D[1], D[2], D[3], D[4])
                                       : Lens<double>::fisheye(D[0], D[1], D[2], D[3]);
  return cam;
}

}  // namespace lens_ref

TEST_CASE("lens models agree with OpenCV", "[geometry][lens][ref]") {
  if (lens_ref::ref()["have_cv2"][0] == 0) {
    WARN("skipped: /usr/bin/python3 cannot import cv2 (apt-get install python3-opencv)");
    return;
  }
  const long cases = static_cast<long>(lens_ref::ref()["case_count"][0]);
  REQUIRE(cases >= 4);
  for (long i = 0; i < cases; ++i) {
    const std::string c = "case" + std::to_string(i) + "_";
    const CameraModel<double> cam = lens_ref::camera(i);
    INFO("case " << i << " " << cam.lens.toString());
    REQUIRE_NOTHROW(cam.validate());

    // project and its Jacobian against cv2.projectPoints / cv2.fisheye.projectPoints.
    const RefArray& P = lens_ref::ref()[c + "points"];
    const RefArray& uv = lens_ref::ref()[c + "uv"];
    const RefArray& Jcv = lens_ref::ref()[c + "J"];
    const long n = P.shape[0];
    REQUIRE(n >= 100);
    double max_uv = 0, max_uv_rel = 0, max_J_rel = 0;
    for (long k = 0; k < n; ++k) {
      const Vec3<double> p(P[3 * k], P[3 * k + 1], P[3 * k + 2]);
      const Vec2<double> expect(uv[2 * k], uv[2 * k + 1]);
      Eigen::Matrix<double, 2, 3> J;
      const Vec2<double> got = cam.project(p, &J);
      INFO("point " << k << " p " << p.transpose());
      const double err = (got - expect).norm(), rel = err / std::max(1.0, expect.norm());
      max_uv = std::max(max_uv, err);
      max_uv_rel = std::max(max_uv_rel, rel);
      CHECK(rel <= 1e-9);
      // OpenCV's fisheye Jacobian treats r <= 1e-8 as r = 1 (its inv_r): its derivatives are
      // compared from there on; the radial-tangential ones everywhere.
      const double r = std::hypot(p(0), p(1)) / p(2);
      if (cam.lens.kind == LensKind::Fisheye && r <= 1e-8) continue;
      Eigen::Matrix<double, 2, 3> Je;
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 3; ++b) Je(a, b) = Jcv[6 * k + 3 * a + b];
      const double jrel = (J - Je).norm() / Je.norm();
      max_J_rel = std::max(max_J_rel, jrel);
      CHECK(jrel <= 1e-9);
    }

    // undistort / unproject against cv2.undistortPointsIter / cv2.fisheye.undistortPoints,
    // where OpenCV's own answer reprojects onto the pixel.
    const RefArray& pix = lens_ref::ref()[c + "pix"];
    const RefArray& xy = lens_ref::ref()[c + "xy"];
    const RefArray& ok = lens_ref::ref()[c + "ok"];
    long compared = 0;
    double max_xy_rel = 0, max_b = 0;
    for (long k = 0; k < pix.shape[0]; ++k) {
      if (ok[k] == 0) continue;
      ++compared;
      const Vec2<double> px(pix[2 * k], pix[2 * k + 1]);
      const Vec2<double> expect(xy[2 * k], xy[2 * k + 1]);
      INFO("pixel " << px.transpose());
      Vec2<double> got;
      REQUIRE(cam.lens.undistort(cam.normalised(px), got));
      const double rel = (got - expect).norm() / std::max(1.0, expect.norm());
      max_xy_rel = std::max(max_xy_rel, rel);
      CHECK(rel <= 1e-9);
      Vec3<double> b;
      REQUIRE(cam.bearing(px, b));
      const Vec3<double> be = Vec3<double>(expect(0), expect(1), 1.0).normalized();
      max_b = std::max(max_b, (b - be).norm());
      CHECK((b - be).norm() <= 1e-9);
      Vec2<double> up;
      REQUIRE(cam.undistortPixel(px, up));
      CHECK((up - cam.intrinsics.project(Vec3<double>(expect(0), expect(1), 1.0))).norm() <=
            1e-9 * std::max(1.0, up.norm()));
    }
    // Every pixel of the radial-tangential cameras and all within 90° of the fisheyes'.
    CHECK(compared >= pix.shape[0] * 7 / 10);
    char line[256];
    std::snprintf(line, sizeof(line),
                  "case %ld %s: project max %.2e px (rel %.2e), J rel %.2e; undistort rel %.2e, "
                  "bearing %.2e (%ld of %ld pixels)",
                  i, cam.lens.toString().c_str(), max_uv, max_uv_rel, max_J_rel, max_xy_rel, max_b,
                  compared, static_cast<long>(pix.shape[0]));
    std::printf("%s\n", line);
  }
}
