// Unit/property tests of eval/camera_metrics.hpp (native and WASM).
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "hawor/eval/eval.hpp"

template struct hawor::CameraMetrics<float>;
template struct hawor::CameraMetrics<double>;
template struct hawor::PartAlignment<float>;
template struct hawor::PartAlignment<double>;

namespace {

template <typename S>
S tol() {
  return std::is_same<S, float>::value ? S(5e-3) : S(1e-8);  // mm
}

template <typename S>
hawor::Points3<S> cameraTrack(Eigen::Index T) {
  hawor::Points3<S> p(T, 3);
  for (Eigen::Index t = 0; t < T; ++t) {
    const S s = S(t) / S(30);
    p.row(t) << std::sin(S(0.4) * s), S(0.3) * std::cos(S(0.9) * s), S(0.2) * s;
  }
  return p;
}

template <typename S>
hawor::SimilarityTransform<S> someSim(S scale, unsigned seed) {
  std::srand(seed);
  hawor::SimilarityTransform<S> x;
  x.R = hawor::axisAngleToMatrix(hawor::Vec3<S>(hawor::Vec3<S>::Random() * S(2)));
  x.t = hawor::Vec3<S>::Random();
  x.s = scale;
  return x;
}

}  // namespace

TEMPLATE_TEST_CASE("ATE and ATE-S of transformed trajectories", "[eval][camera]", float, double) {
  using S = TestType;
  const hawor::Points3<S> gt = cameraTrack<S>(120);
  // a similarity (scale 0.5) of the ground truth: ATE 0, scale 2, ATE-S large
  const hawor::Points3<S> est = someSim<S>(S(0.5), 1).apply(gt);
  const auto m = hawor::evaluateCameras(gt, est);
  CHECK(m.ate < tol<S>());
  CHECK(m.scale == Approx(2.0).epsilon(1e-4));
  CHECK(m.ate_s > S(10));
  CHECK(m.n == 120);
  // a rigid motion: both zero, scale 1
  const hawor::Points3<S> rigid = someSim<S>(S(1), 2).apply(gt);
  const auto r = hawor::evaluateCameras(gt, rigid);
  CHECK(r.ate < tol<S>());
  CHECK(r.ate_s < tol<S>());
  CHECK(r.scale == Approx(1.0).epsilon(1e-4));
  // hand-computed: a straight track 0, 1, 2 m along x against the same with a 3 mm bump in y at
  // the middle frame
  hawor::Points3<S> line(3, 3), bumped(3, 3);
  line << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  bumped = line;
  bumped(1, 1) = S(0.003);
  const S e = hawor::ateSE3(line, bumped);
  // optimum: shift −1 mm in y (centroid), no rotation (the bump is symmetric): errors 1, 2, 1 mm
  CHECK(e == Approx(4.0 / 3.0).epsilon(1e-3));
  CHECK_THROWS_AS(hawor::ateSim3(gt, hawor::Points3<S>(gt.topRows(100))), hawor::Error);
  CHECK_THROWS_AS(hawor::ateSE3(hawor::Points3<S>(gt.topRows(2)), hawor::Points3<S>(gt.topRows(2))),
                  hawor::Error);
}

TEMPLATE_TEST_CASE("per-part rigid camera alignment", "[eval][camera]", float, double) {
  using S = TestType;
  const Eigen::Index T = 251;
  const hawor::Points3<S> gt = cameraTrack<S>(T);
  hawor::Points3<S> est(T, 3);
  // a different rigid motion on each 100-frame part; the last part [200, 251) too
  for (Eigen::Index p = 0; p < 3; ++p) {
    const Eigen::Index b = 100 * p, n = std::min<Eigen::Index>(100, T - b);
    est.middleRows(b, n) =
        someSim<S>(S(1), 30 + unsigned(p)).apply(hawor::Points3<S>(gt.middleRows(b, n)));
  }
  const auto align = hawor::alignCameraParts(gt, est, 100);
  CHECK(align.parts.size() == 3);
  const hawor::Points3<S> back = hawor::alignPositionsByParts(align, est);
  CHECK((back - gt).cwiseAbs().maxCoeff() < S(1e-3) * tol<S>() * S(1000));
  // joints ride along with their frame's camera
  hawor::JointSequence<S> joints(T, 6);
  for (Eigen::Index t = 0; t < T; ++t) {
    const hawor::Vec3<S> a = est.row(t).transpose();
    joints.row(t) << est.row(t), (a + hawor::Vec3<S>(S(0), S(0.1), S(0))).transpose();
  }
  const hawor::JointSequence<S> aligned = hawor::alignJointsByParts(align, joints);
  CHECK((aligned.leftCols(3) - back).cwiseAbs().maxCoeff() < tol<S>());
  CHECK(std::abs((aligned.rightCols(3) - aligned.leftCols(3)).row(120).norm() - S(0.1)) < tol<S>());
  // a trailing part of 1 frame (T = 201) reuses the previous part's transform
  const auto a201 = hawor::alignCameraParts(hawor::Points3<S>(gt.topRows(201)),
                                            hawor::Points3<S>(est.topRows(201)), 100);
  CHECK(a201.parts.size() == 2);
  CHECK(&a201.forFrame(200) == &a201.parts[1]);
  CHECK_THROWS_AS(a201.forFrame(201), hawor::Error);
  CHECK_THROWS_AS(hawor::alignJointsByParts(a201, joints), hawor::Error);
  CHECK_THROWS_AS(hawor::alignCameraParts(gt, est, 2), hawor::Error);
}

TEMPLATE_TEST_CASE("camera rotation error after the best global rotation", "[eval][camera]", float, double) {
  using S = TestType;
  const S degTol = std::is_same<S, float>::value ? S(2e-3) : S(1e-9);
  const S rad = S(EIGEN_PI) / S(180);
  std::vector<hawor::Mat3<S>> gt, est;
  // Frames in equal pairs (2k, 2k + 1): a head turning 0.1 rad every two frames.
  for (int t = 0; t < 90; ++t) {
    const S k = S(t / 2);
    gt.push_back(hawor::axisAngleToMatrix(hawor::Vec3<S>(S(0.3) * std::sin(k / S(10)), S(0.1) * k, S(0.1))));
  }
  // The estimate in another world, A·E_t = G_t: every error 0, and the alignment is A's inverse.
  const hawor::Mat3<S> W = hawor::axisAngleToMatrix(hawor::Vec3<S>(S(0.7), S(-1.9), S(0.4)));
  for (const auto& g : gt) est.push_back(W * g);
  const auto exact = hawor::rotationErrors(gt, est);
  CHECK(exact.mean_deg < degTol);
  CHECK(exact.max_deg < degTol);
  CHECK((exact.align - W.transpose()).cwiseAbs().maxCoeff() < S(10) * degTol);
  // Errors of +θ and −θ about the camera's y axis on the two frames of each pair: a pair adds
  // G·(R_y(−θ) + R_y(θ))·Gᵀ·Wᵀ = G·diag(2cos θ, 2, 2cos θ)·Gᵀ·Wᵀ to Σ G_t·E_tᵀ, a symmetric
  // positive definite matrix times Wᵀ, whose projection onto SO(3) is Wᵀ: each frame is θ off.
  const S theta = S(4);
  for (size_t t = 0; t < gt.size(); ++t) {
    const S a = (t % 2 == 0 ? theta : -theta) * rad;
    est[t] = W * gt[t] * hawor::axisAngleToMatrix(hawor::Vec3<S>(S(0), a, S(0)));
  }
  const auto sym = hawor::rotationErrors(gt, est);
  CHECK(std::abs(sym.mean_deg - theta) < degTol);
  CHECK(std::abs(sym.max_deg - theta) < degTol);
  CHECK((sym.align - W.transpose()).cwiseAbs().maxCoeff() < S(10) * degTol);
  // One frame turned by 90° more: the max sees it, the alignment barely moves.
  est[10] = est[10] * hawor::axisAngleToMatrix(hawor::Vec3<S>(S(90) * rad, S(0), S(0)));
  const auto out = hawor::rotationErrors(gt, est);
  CHECK(out.max_deg > S(85));
  CHECK_THROWS_AS(hawor::rotationErrors(gt, std::vector<hawor::Mat3<S>>(gt.begin(), gt.begin() + 5)), hawor::Error);
  CHECK_THROWS_AS(hawor::rotationErrors(std::vector<hawor::Mat3<S>>{}, std::vector<hawor::Mat3<S>>{}), hawor::Error);
  est[3](0, 0) = std::numeric_limits<S>::quiet_NaN();
  CHECK_THROWS_AS(hawor::rotationErrors(gt, est), hawor::Error);
}
