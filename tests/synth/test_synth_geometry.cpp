// Geometric ground truth of the synthetic sequences, float and double: depth against ray casting
// through the scene, the mask against separate renders of scene and hands, keypoints against the
// forward pass and the camera poses, projections against the image and the mask.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <vector>

#include "synth_test_util.hpp"

template class hawor::synth::SynthSequence<float>;
template class hawor::synth::SynthSequence<double>;
template class hawor::synth::SceneRenderer<float>;
template class hawor::synth::SceneRenderer<double>;
template class hawor::synth::CameraPath<float>;
template class hawor::synth::CameraPath<double>;
template class hawor::synth::HandPlan<float>;
template class hawor::synth::HandPlan<double>;
template class hawor::synth::HandRig<float>;
template class hawor::synth::HandRig<double>;
template class hawor::synth::SmoothSignal<float>;
template class hawor::synth::SmoothSignal<double>;
template struct hawor::synth::IndoorScene<float>;
template struct hawor::synth::IndoorScene<double>;

namespace {

using namespace synth_test;
using hawor::Mat3;
using hawor::PinholeCamera;

template <typename S>
struct Tol;
template <>
struct Tol<float> {
  static double depthRel() { return 2e-4; }
  static double joint() { return 2e-5; }
};
template <>
struct Tol<double> {
  static double depthRel() { return 1e-5; }
  static double joint() { return 1e-10; }
};

template <typename S>
hs::SynthSequence<S> makeSeq(const std::string& preset, std::uint64_t seed, int w, int frames) {
  const Hands<S>& h = syntheticHands<S>();
  return hs::SynthSequence<S>(hs::findSynthPreset(preset), seed, h.left, h.right, smallOptions(w, frames),
                              sharedScene<S>(seed));
}

}  // namespace

TEMPLATE_TEST_CASE("synth: depth is the distance along z to the first scene surface", "[synth]", float, double) {
  using S = TestType;
  for (const char* preset : {"walk", "table_work", "pure_rotation"}) {
    hs::SynthSequence<S> seq = makeSeq<S>(preset, 7, 96, 40);
    const PinholeCamera<S>& cam = seq.camera();
    hs::SynthFrame<S> fr;
    int tested = 0, bad = 0;
    for (int i : {0, 21, 39}) {
      seq.renderFrame(i, fr);
      const hs::RigidPose<S>& rc = seq.worldFromCamera(i);
      for (int y = 1; y < cam.height; y += 5) {
        for (int x = 2; x < cam.width; x += 5) {
          const float z = fr.images.depth.at(x, y);
          REQUIRE(std::isfinite(z));
          REQUIRE(z > 0.0f);
          if (fr.images.mask.at(x, y) != 0) continue;  // hand pixels: checked below
          // The same pixel ray, cast through the scene in double (z-normalised: s is the depth).
          const Eigen::Vector3d ray((x - double(cam.cx)) / double(cam.fx), (y - double(cam.cy)) / double(cam.fy), 1.0);
          const Eigen::Matrix3d R = rc.R.template cast<double>();
          const double s = castRay(seq.scene(), rc.t.template cast<double>(), R * ray);
          ++tested;
          // The unprojected point lies on the first surface along the ray (pixels on an object's
          // silhouette edge may round to the other side: counted, not failed).
          if (!(std::abs(s - double(z)) <= Tol<S>::depthRel() * s + 1e-6)) ++bad;
        }
      }
    }
    INFO(preset << ": " << bad << " of " << tested << " depth samples off the first surface");
    CHECK(tested > 300);
    CHECK(bad <= tested / 50);
  }
}

TEMPLATE_TEST_CASE("synth: the mask is where a hand mesh is nearer than the scene", "[synth]", float, double) {
  using S = TestType;
  hs::SynthSequence<S> seq = makeSeq<S>("hands_cover", 3, 96, 60);
  const PinholeCamera<S>& cam = seq.camera();
  const Hands<S>& hands = syntheticHands<S>();
  hs::SynthFrame<S> fr;
  int handPixelsSeen = 0;
  for (int i : {0, 17, 34, 59}) {
    seq.renderFrame(i, fr);
    // Separate z-buffers: the scene alone, each hand alone (camera frame, from the world-frame
    // parameters and the ground-truth pose).
    hawor::RasterOptions<S> ro;
    ro.nearPlane = S(0.01);
    hawor::Rasterizer<S> rast(cam, ro);
    const hs::RigidPose<S> cr = seq.worldFromCamera(i).inverse();
    Points3<S> sv(seq.scene().vertices.rows(), 3);
    for (Eigen::Index k = 0; k < sv.rows(); ++k) sv.row(k) = (cr.R * seq.scene().vertices.row(k).transpose() + cr.t).transpose();
    hawor::ImageF sceneDepth, handDepth[2];
    rast.clearDepth(sceneDepth);
    rast.setDepthBuffer(&sceneDepth);
    rast.drawMesh(sv, seq.scene().faces, [](const hawor::Fragment<S>&) {});
    const hs::RigidPose<S> cw = fr.worldFromCamera.inverse();
    for (int s = 0; s < 2; ++s) {
      const HandModel<S>& m = s == 0 ? hands.left : hands.right;
      const hawor::HandOutput<S> o = hawor::forward(m, seq.handPoseWorld(s, i));
      Points3<S> hv(o.vertices.rows(), 3);
      for (Eigen::Index k = 0; k < hv.rows(); ++k) hv.row(k) = (cw.R * o.vertices.row(k).transpose() + cw.t).transpose();
      rast.clearDepth(handDepth[s]);
      rast.setDepthBuffer(&handDepth[s]);
      rast.drawMesh(hv, m.faces, [](const hawor::Fragment<S>&) {});
    }
    int mismatches = 0, counts[2] = {0, 0};
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        const float zs = sceneDepth.at(x, y), zl = handDepth[0].at(x, y), zr = handDepth[1].at(x, y);
        int expect = 0;
        if (std::min(zl, zr) < zs) expect = zl < zr ? hs::SynthSequence<S>::kLeftLabel : hs::SynthSequence<S>::kRightLabel;
        const int got = fr.images.mask.at(x, y);
        if (got != expect) ++mismatches;
        if (got == hs::SynthSequence<S>::kLeftLabel) ++counts[0];
        if (got == hs::SynthSequence<S>::kRightLabel) ++counts[1];
        // The depth image is the nearest of all surfaces.
        REQUIRE(fr.images.depth.at(x, y) == std::min(zs, std::min(zl, zr)));
      }
    }
    CHECK(mismatches == 0);
    CHECK(counts[0] == fr.hands[0].visiblePixels);
    CHECK(counts[1] == fr.hands[1].visiblePixels);
    CHECK(fr.coverage == Approx(double(counts[0] + counts[1]) / (cam.width * cam.height)));
    for (int s = 0; s < 2; ++s) CHECK(fr.hands[s].valid == (fr.hands[s].visiblePixels >= seq.minVisiblePixels()));
    handPixelsSeen += counts[0] + counts[1];
  }
  CHECK(handPixelsSeen > 0);
}

TEMPLATE_TEST_CASE("synth: keypoints, hand parameters and camera poses agree", "[synth]", float, double) {
  using S = TestType;
  const double tol = Tol<S>::joint();
  const Hands<S>& hands = syntheticHands<S>();
  for (const char* preset : {"walk", "fast_turns", "hands_cover"}) {
    hs::SynthSequence<S> seq = makeSeq<S>(preset, 11, 64, 50);
    hs::SynthFrame<S> fr;
    // World frame = the room's: z up, the floor at z = 0, every camera above it and inside the
    // room ([0, 6] × [0, 5] × [0, 2.6], scene.hpp).
    CHECK((seq.gravityWorld() - hawor::Vec3<S>(0, 0, -1)).norm() == 0);
    for (int i = 0; i < seq.numFrames(); ++i) {
      const hawor::Vec3<S> c = seq.worldFromCamera(i).t;
      CHECK((c.x() > 0 && c.x() < 6 && c.y() > 0 && c.y() < 5 && c.z() > 1 && c.z() < 2.6));
    }
    for (int i = 0; i < seq.numFrames(); i += 7) {
      seq.renderFrame(i, fr);
      CHECK(fr.time == Approx(i / seq.fps()));
      const hs::RigidPose<S> cw = fr.worldFromCamera.inverse();
      CHECK((fr.worldFromCamera.R.transpose() * fr.worldFromCamera.R - Mat3<S>::Identity()).norm() < 1e-5);
      for (int s = 0; s < 2; ++s) {
        const HandModel<S>& m = s == 0 ? hands.left : hands.right;
        const hs::SynthHandFrame<S>& h = fr.hands[s];
        REQUIRE(h.jointsWorld.rows() == 21);
        // joints_world = forward(world parameters); joints_cam = T_c_w · joints_world.
        const hawor::HandOutput<S> ow = hawor::forward(m, h.world);
        CHECK((ow.keypoints - h.jointsWorld).cwiseAbs().maxCoeff() <= tol);
        for (int k = 0; k < 21; ++k) {
          const Vec3<S> pw = h.jointsWorld.row(k).transpose();
          const Vec3<S> pc = cw.R * pw + cw.t;
          CHECK((pc - Vec3<S>(h.jointsCam.row(k).transpose())).norm() <= 10 * tol);
        }
        // The camera-frame parameters give joints_cam through the same forward pass.
        const hawor::HandOutput<S> oc = hawor::forward(m, h.camera);
        CHECK((oc.keypoints - h.jointsCam).cwiseAbs().maxCoeff() <= 100 * tol);
        // MANO rotates about J_0: the wrist keypoint is trans + J_0(β).
        hawor::HandWorkspace<S> ws;
        hawor::shapeHand(m, h.world.betas, ws);
        const Vec3<S> wrist = h.world.trans + Vec3<S>(ws.jRest.row(0).transpose());
        CHECK((wrist - Vec3<S>(h.jointsWorld.row(0).transpose())).norm() <= 10 * tol);
        // Both hands share one shape.
        CHECK((fr.hands[0].world.betas - fr.hands[1].world.betas).norm() == 0);
      }
    }
  }
}

TEMPLATE_TEST_CASE("synth: visible keypoints project inside the image and onto their hand", "[synth]", float, double) {
  using S = TestType;
  hs::SynthSequence<S> seq = makeSeq<S>("table_work", 5, 128, 90);
  const PinholeCamera<S>& cam = seq.camera();
  hs::SynthFrame<S> fr;
  int inImage = 0, onMask = 0, validFrames = 0;
  for (int i = 0; i < seq.numFrames(); i += 3) {
    seq.renderFrame(i, fr);
    for (int s = 0; s < 2; ++s) {
      const hs::SynthHandFrame<S>& h = fr.hands[s];
      const int label = s == 0 ? hs::SynthSequence<S>::kLeftLabel : hs::SynthSequence<S>::kRightLabel;
      if (h.valid) ++validFrames;
      for (int k = 0; k < 21; ++k) {
        const Vec3<S> p = h.jointsCam.row(k).transpose();
        // The flag, recomputed independently.
        const double u = double(cam.fx) * p.x() / p.z() + double(cam.cx), v = double(cam.fy) * p.y() / p.z() + double(cam.cy);
        const bool expect = p.z() > S(0.01) && u >= -0.5 && v >= -0.5 && u <= cam.width - 0.5 && v <= cam.height - 0.5;
        REQUIRE(h.inImage[static_cast<std::size_t>(k)] == expect);
        if (!expect || !h.valid) continue;
        ++inImage;
        // Keypoints are inside or on the hand mesh: the pixel (or a neighbour within 2 px) carries
        // the hand's label unless something nearer hides it.
        const int x0 = static_cast<int>(std::lround(u)), y0 = static_cast<int>(std::lround(v));
        const float zImg = fr.images.depth.at(std::min(cam.width - 1, std::max(0, x0)), std::min(cam.height - 1, std::max(0, y0)));
        if (zImg < float(p.z()) - 0.03f && fr.images.mask.at(std::min(cam.width - 1, std::max(0, x0)), std::min(cam.height - 1, std::max(0, y0))) != label) {
          continue;  // occluded by the other hand or the scene
        }
        bool found = false;
        for (int dy = -2; dy <= 2 && !found; ++dy) {
          for (int dx = -2; dx <= 2 && !found; ++dx) {
            const int x = x0 + dx, y = y0 + dy;
            found = x >= 0 && y >= 0 && x < cam.width && y < cam.height && fr.images.mask.at(x, y) == label;
          }
        }
        if (found) ++onMask;
      }
    }
  }
  INFO(onMask << " of " << inImage << " in-image keypoints of valid hands on their mask");
  CHECK(validFrames > 10);
  CHECK(inImage > 100);
  CHECK(onMask >= inImage * 9 / 10);
}
