// Cross-checks of the geometry module against tests/ref/geometry_rotations.py: scipy's Rotation
// (rotation vectors, matrices, quaternions, incl. tiny and near-π angles), numpy rot6d,
// Umeyama against scipy's weighted Kabsch, and the series/closed-form coefficient functions
// against 100-digit decimal evaluations. Double precision, ~1e-12.
#include <catch2/catch.hpp>

#include "../support/ref_data.hpp"
#include "hawor/geometry/geometry.hpp"

using namespace hawor;
using hawor_test::RefArray;

namespace {

const hawor_test::RefData& ref() {
  static const hawor_test::RefData data =
      hawor_test::runReference("geometry_rotations.py", "geometry_rotations.txt");
  return data;
}

Vec3<double> row3(const RefArray& a, long i) {
  return Vec3<double>(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
}
Mat3<double> mat3(const RefArray& a, long i) {
  Mat3<double> m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = a[9 * i + 3 * r + c];
  return m;
}
Points3<double> points(const RefArray& a) {
  Points3<double> P(a.shape[0], 3);
  for (long i = 0; i < a.shape[0]; ++i) P.row(i) = row3(a, i).transpose();
  return P;
}

}  // namespace

TEST_CASE("rotation vectors, matrices and quaternions agree with scipy", "[geometry][ref]") {
  const RefArray& rv = ref()["rotvec"];
  const RefArray& mats = ref()["rotvec_matrix"];
  const RefArray& quats = ref()["rotvec_quat_wxyz"];
  const RefArray& back = ref()["rotvec_back"];
  const long n = rv.shape[0];
  REQUIRE(n > 50);
  for (long i = 0; i < n; ++i) {
    const Vec3<double> w = row3(rv, i);
    INFO("i " << i << " angle " << w.norm());
    CHECK((axisAngleToMatrix(w) - mat3(mats, i)).norm() <= 1e-15 * 4);
    const Eigen::Quaterniond q = axisAngleToQuaternion(w);
    const Eigen::Vector4d qe(quats[4 * i], quats[4 * i + 1], quats[4 * i + 2], quats[4 * i + 3]);
    CHECK((Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()) - qe).norm() <= 1e-15 * 2);
    // Relative accuracy at every angle (series branches for tiny ones, atan2 near π).
    const double tol = 1e-14 * w.norm();
    CHECK((matrixToAxisAngle(mat3(mats, i)) - row3(back, i)).norm() <= tol);
    CHECK((matrixToAxisAngle(mat3(mats, i)) - w).norm() <= tol);
    CHECK((quaternionToAxisAngle(q) - w).norm() <= tol);
  }
  const RefArray& big = ref()["big_rotvec"];
  const RefArray& big_short = ref()["big_rotvec_short"];
  for (long i = 0; i < big.shape[0]; ++i) {
    CHECK((matrixToAxisAngle(axisAngleToMatrix(row3(big, i))) - row3(big_short, i)).norm() <=
          1e-14);
    CHECK((quaternionToAxisAngle(axisAngleToQuaternion(row3(big, i))) - row3(big_short, i))
              .norm() <= 1e-14);
  }
  const RefArray& rm = ref()["mats"];
  const RefArray& rq = ref()["mats_quat_wxyz"];
  const RefArray& rr = ref()["mats_rotvec"];
  for (long i = 0; i < rm.shape[0]; ++i) {
    const Eigen::Quaterniond q = matrixToQuaternion(mat3(rm, i));
    CHECK((Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()) -
           Eigen::Vector4d(rq[4 * i], rq[4 * i + 1], rq[4 * i + 2], rq[4 * i + 3]))
              .norm() <= 1e-15 * 4);
    CHECK((matrixToAxisAngle(mat3(rm, i)) - row3(rr, i)).norm() <= 1e-14);
    CHECK((SO3d::fromMatrix(mat3(rm, i)).log() - row3(rr, i)).norm() <= 1e-14);
  }
}

TEST_CASE("rot6d agrees with numpy", "[geometry][ref]") {
  const RefArray& r6 = ref()["rot6d"];
  const RefArray& mats = ref()["mats"];
  const RefArray& noisy = ref()["rot6d_noisy"];
  const RefArray& gs = ref()["rot6d_noisy_matrix"];
  for (long i = 0; i < r6.shape[0]; ++i) {
    Vec6<double> expect, in;
    for (int k = 0; k < 6; ++k) {
      expect(k) = r6[6 * i + k];
      in(k) = noisy[6 * i + k];
    }
    CHECK((matrixToRot6d(mat3(mats, i)) - expect).norm() == 0.0);
    CHECK((rot6dToMatrix(in) - mat3(gs, i)).norm() <= 1e-14);
  }
}

TEST_CASE("umeyama agrees with scipy's weighted Kabsch", "[geometry][ref][alignment]") {
  const long count = static_cast<long>(ref()["umeyama_count"][0]);
  REQUIRE(count > 5);
  for (long i = 0; i < count; ++i) {
    const std::string p = "umeyama_" + std::to_string(i) + "_";
    const Points3<double> src = points(ref()[p + "src"]);
    const Points3<double> dst = points(ref()[p + "dst"]);
    const RefArray& wa = ref()[p + "w"];
    const bool weighted = ref()[p + "flags"][0] != 0.0;
    const bool with_scale = ref()[p + "flags"][1] != 0.0;
    VecX<double> w(src.rows());
    for (long k = 0; k < src.rows(); ++k) w(k) = wa[k];
    const SimilarityTransform<double> T = umeyama(src, dst, with_scale, weighted ? &w : nullptr);
    INFO("case " << i << " weighted " << weighted << " scale " << with_scale);
    CHECK((T.R - mat3(ref()[p + "R"], 0)).norm() <= 1e-12);
    CHECK((T.t - row3(ref()[p + "t"], 0)).norm() <= 1e-12 * (1 + T.t.norm()));
    CHECK(T.s == Approx(ref()[p + "s"][0]).epsilon(1e-12));
  }
}

TEST_CASE("rotation coefficient functions agree with 100-digit references", "[geometry][ref]") {
  const RefArray& th = ref()["coef_theta"];
  const RefArray& v = ref()["coef_values"];
  for (long i = 0; i < th.shape[0]; ++i) {
    const double t = th[i];
    const detail::RotationCoefficients<double> k(t * t);
    const double got[6] = {k.A, k.B, k.C, k.E, k.D2, k.D3};
    for (int j = 0; j < 6; ++j) {
      INFO("theta " << t << " coefficient " << "ABCEXY"[j]);
      CHECK(got[j] == Approx(v[6 * i + j]).epsilon(1e-14));
    }
    // float: ~single-precision relative accuracy at every angle.
    const detail::RotationCoefficients<float> kf(float(t) * float(t));
    const float gotf[6] = {kf.A, kf.B, kf.C, kf.E, kf.D2, kf.D3};
    for (int j = 0; j < 6; ++j) {
      INFO("float theta " << t << " coefficient " << "ABCEXY"[j]);
      CHECK(gotf[j] == Approx(v[6 * i + j]).epsilon(t < 3.5 ? 1e-5 : 1e-4).margin(1e-6));
    }
  }
}

TEST_CASE("Sim3 W coefficients agree with 100-digit references", "[geometry][ref][sim3]") {
  const RefArray& g = ref()["sim3w"];
  for (long i = 0; i < g.shape[0]; ++i) {
    const double sigma = g[5 * i], theta = g[5 * i + 1];
    const detail::Sim3WCoefficients<double> k(sigma, theta * theta);
    INFO("sigma " << sigma << " theta " << theta);
    CHECK(k.a == Approx(g[5 * i + 2]).epsilon(1e-15));
    CHECK(k.b == Approx(g[5 * i + 3]).epsilon(4e-15));
    CHECK(k.c == Approx(g[5 * i + 4]).epsilon(4e-15));
  }
}
