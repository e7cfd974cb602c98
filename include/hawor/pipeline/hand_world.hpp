// hawor/pipeline/hand_world.hpp — one hand of the pipeline's result taken from the camera frame
// to the world: the camera-frame motion through the camera poses (motion/canonical.hpp,
// cameraToWorld), the unseen frames filled (motion/infill.hpp), and the model's keypoints of the
// world motion (hand/forward.hpp).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/se3.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/motion/canonical.hpp"
#include "hawor/motion/infill.hpp"
#include "hawor/motion/rest_root.hpp"
#include "hawor/pipeline/result.hpp"

namespace hawor {

/// h.world, h.infilled and h.jointsWorld from h.camera and h.valid, with the camera-to-world
/// poses of the (metric) world, one per frame. A hand never seen keeps its camera arrays (NaN)
/// and NaN keypoints. Adds the stages' milliseconds to timings["world" | "infill" | "joints"].
template <typename Scalar>
void handToWorld(const HandModel<Scalar>& model, const std::vector<SE3<Scalar>>& cameraPoses, InfillMethod method, PipelineHand<Scalar>& h,
                 std::map<std::string, double>& timings) {
  using Clock = std::chrono::steady_clock;
  constexpr int K = 21;
  const Eigen::Index T = static_cast<Eigen::Index>(h.valid.size());
  const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
  if (static_cast<Eigen::Index>(cameraPoses.size()) != T) throw Error("handToWorld: one camera pose per frame is needed");
  auto lap = [&](const char* stage, Clock::time_point& t0) {
    const Clock::time_point t1 = Clock::now();
    timings[stage] += std::chrono::duration<double, std::milli>(t1 - t0).count();
    t0 = t1;
  };
  h.infilled.assign(static_cast<std::size_t>(T), 0);
  if (!h.present) {
    h.world = h.camera;
    h.jointsWorld = Sequence<Scalar>::Constant(T, 3 * K, nan);
    return;
  }
  auto t0 = Clock::now();
  // cameraToWorld wants finite numbers everywhere: unobserved frames hold zeros
  HandMotion<Scalar> cam = h.camera;
  for (Sequence<Scalar>* a : {&cam.rot, &cam.trans, &cam.handPose, &cam.betas}) *a = a->unaryExpr([](Scalar v) { return std::isfinite(double(v)) ? v : Scalar(0); });
  std::vector<Mat3<Scalar>> R;
  std::vector<Vec3<Scalar>> t;
  for (const SE3<Scalar>& P : cameraPoses) {
    R.push_back(P.rotationMatrix());
    t.push_back(P.translation());
  }
  HandMotion<Scalar> world = cameraToWorld(cam, R, t, restRootJoints(model, cam));
  lap("world", t0);
  for (Eigen::Index f = 0; f < T; ++f) {
    if (h.valid[static_cast<std::size_t>(f)]) continue;
    for (Sequence<Scalar>* a : {&world.rot, &world.trans, &world.handPose, &world.betas}) a->row(f).setConstant(nan);
  }
  InfillOptions<Scalar> io;
  io.method = method;
  const InfillResult<Scalar> filled = infillHand(world, restRootJoints(model, world), io);
  h.world = filled.motion;
  h.infilled = filled.filled;
  lap("infill", t0);
  h.jointsWorld.resize(T, 3 * K);
  for (Eigen::Index f = 0; f < T; ++f) {
    HandPose<Scalar> p = HandPose<Scalar>::zero(model);
    p.rot = h.world.rot.row(f).transpose();
    p.trans = h.world.trans.row(f).transpose();
    std::copy(h.world.handPose.row(f).data(), h.world.handPose.row(f).data() + h.world.handPose.cols(), p.handPose.data());
    if (h.world.betas.cols() > 0) p.betas = h.world.betas.row(f).transpose();
    const Points3<Scalar> kp = forward(model, p).keypoints;
    h.jointsWorld.row(f) = Eigen::Map<const Eigen::Matrix<Scalar, 1, 3 * K>>(kp.data());
  }
  lap("joints", t0);
}

}  // namespace hawor
