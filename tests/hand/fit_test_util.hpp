// Test support for the hand fit (tests/hand/test_fit*.cpp): a 25-joint model with the WebXR joint
// layout, ground-truth poses in front of a camera, and observations made from them.
#pragma once

#include <random>
#include <vector>

#include "hand_test_util.hpp"
#include "hawor/geometry/camera.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/hand/fit.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/joint_limits.hpp"
#include "hawor/hand/portable_random.hpp"

namespace fit_test {

/// WebXR hand joints: 0 wrist; per finger (thumb, index, middle, ring, pinky) a chain of
/// metacarpal, proximal, [intermediate,] distal, tip; the thumb has no intermediate (4 joints),
/// the other fingers 5: 1 + 4 + 4·5 = 25.
inline std::vector<int> webxrParents() {
  std::vector<int> p{-1};
  int next = 1;
  for (int f = 0; f < 5; ++f) {
    const int n = f == 0 ? 4 : 5;
    for (int i = 0; i < n; ++i) {
      p.push_back(i == 0 ? 0 : next - 1);
      ++next;
    }
  }
  return p;
}

/// The 21 keypoints of the WebXR joints: the thumb's 4 joints, then per finger all but the
/// metacarpal.
inline std::vector<int> webxrKeypointMap() {
  return {0, 1, 2, 3, 4, 6, 7, 8, 9, 11, 12, 13, 14, 16, 17, 18, 19, 21, 22, 23, 24};
}

/// A random well-formed 25-joint model without shape space or pose correctives.
template <typename Scalar>
hawor::HandModel<Scalar> randomWebxrModel(unsigned seed = 3) {
  hawor::HandModel<Scalar> m = hand_test::randomModel<Scalar>(300, webxrParents(), 0, false, seed);
  m.keypointMap = webxrKeypointMap();
  m.prepare();
  return m;
}

template <typename Scalar>
hawor::PinholeCamera<Scalar> camera() {
  hawor::PinholeCamera<Scalar> c;
  c.fx = c.fy = Scalar(500);
  c.cx = Scalar(319.5);
  c.cy = Scalar(239.5);
  c.width = 640;
  c.height = 480;
  return c;
}

/// A uniformly random rotation vector (via a random unit quaternion).
template <typename Scalar, typename Rng>
hawor::Vec3<Scalar> randomRotation(Rng& rng) {
  auto g = [](Rng& r) { return hawor::standardNormal(r); };
  const double w = g(rng), x = g(rng), y = g(rng), z = g(rng);  // in this order on every compiler
  Eigen::Quaterniond q(w, x, y, z);
  q.normalize();
  return hawor::quaternionToAxisAngle(q).cast<Scalar>();
}

/// A pose inside the joint limits (`fraction` of each range), random orientation, the wrist at
/// depth 0.3–0.8 m projecting inside the central part of the image; β ~ U(−1.5, 1.5).
template <typename Scalar, typename Rng>
hawor::HandPose<Scalar> randomHandPose(const hawor::HandModel<Scalar>& m, const hawor::JointLimits<Scalar>& lim,
                                       Rng& rng, double fraction = 0.8) {
  auto uni = [](Rng& r) { return hawor::uniform01(r); };
  hawor::HandPose<Scalar> p = hawor::HandPose<Scalar>::zero(m);
  p.handPose = hawor::sampleJointPose(lim, rng, fraction);
  p.rot = randomRotation<Scalar>(rng);
  for (int b = 0; b < p.betas.size(); ++b) p.betas(b) = static_cast<Scalar>(-1.5 + 3.0 * uni(rng));
  const double z = 0.3 + 0.5 * uni(rng);
  const double x = (uni(rng) - 0.5) * 0.5 * z * 640.0 / 500.0;
  const double y = (uni(rng) - 0.5) * 0.5 * z * 480.0 / 500.0;
  // Place the wrist (J0(β) + transl) at (x, y, z).
  const hawor::HandOutput<Scalar> o = hawor::forward(m, p);
  p.trans = hawor::Vec3<Scalar>(Scalar(x), Scalar(y), Scalar(z)) - o.joints.row(0).transpose();
  return p;
}

/// Observation of `p`: projected keypoints + N(0, px) noise, 3D keypoints + N(0, mm) noise per axis
/// plus an arbitrary common offset (the landmarks' origin is unknown).
template <typename Scalar, typename Rng>
hawor::HandObservation<Scalar> observe(const hawor::HandModel<Scalar>& m, const hawor::HandPose<Scalar>& p,
                                       const hawor::PinholeCamera<Scalar>& cam, Rng& rng, double px = 0.0,
                                       double metres = 0.0) {
  auto g = [](Rng& r) { return hawor::standardNormal(r); };
  const hawor::HandOutput<Scalar> o = hawor::forward(m, p);
  const int K = static_cast<int>(o.keypoints.rows());
  hawor::HandObservation<Scalar> obs;
  obs.keypoints2d.resize(K, 2);
  obs.keypoints3d.resize(K, 3);
  const hawor::Vec3<Scalar> offset(Scalar(0.1), Scalar(-0.2), Scalar(0.05));
  for (int k = 0; k < K; ++k) {
    const hawor::Vec3<Scalar> x = o.keypoints.row(k).transpose();
    const hawor::Vec2<Scalar> uv = cam.project(x);
    obs.keypoints2d(k, 0) = uv(0) + Scalar(px * g(rng));
    obs.keypoints2d(k, 1) = uv(1) + Scalar(px * g(rng));
    for (int c = 0; c < 3; ++c) obs.keypoints3d(k, c) = x(c) - o.keypoints(0, c) + offset(c) + Scalar(metres * g(rng));
  }
  obs.confidence2d = hawor::VecX<Scalar>::Ones(K);
  obs.confidence3d = hawor::VecX<Scalar>::Ones(K);
  return obs;
}

/// Largest per-keypoint distance between two (K,3) arrays.
template <typename A, typename B>
double maxPointError(const A& a, const B& b) {
  return (a.template cast<double>() - b.template cast<double>()).rowwise().norm().maxCoeff();
}

/// Options with every prior that biases the optimum away from an exact solution switched off, and
/// the joint limits too: they are zero at poses sampled inside them, but their stiffness on the
/// barely observed twists and abductions of distal joints can make LM crawl along a limit for
/// hundreds of iterations (fixed joints stay: they are zero at the truth).
template <typename Scalar>
hawor::HandFitOptions<Scalar> exactOptions() {
  hawor::HandFitOptions<Scalar> o;
  o.sigmaPose = Scalar(0);
  o.sigmaShape = Scalar(0);
  o.sigmaLimit = Scalar(0);
  o.loss = hawor::RobustLoss::None;
  o.functionTolerance = Scalar(1e-14);
  o.stepTolerance = Scalar(1e-12);
  o.maxIterations = 100;
  return o;
}

}  // namespace fit_test
