// A program outside hawor's build that uses the library as a user would: a Lie group, the hand
// model's forward pass on the licence-free default hand, and a metric. Prints one summary line;
// exits 0 only when every check holds.
//
//   consumer HAND_MODEL [stb=on|off]
// HAND_MODEL: the default hand's right.glb (npm @webxr-input-profiles/assets) or a converted
// hand_right.npz; a MANO file works too. The optional second argument is the stb configuration
// the build was meant to have (HAWOR_WITH_STB): off means no stb header may be reachable.
#include <hawor/hawor.hpp>

#include <cmath>
#include <cstdio>
#include <string>

namespace {

int failures = 0;

void check(bool ok, const std::string& what) {
  if (!ok) {
    std::fprintf(stderr, "consumer: FAILED: %s\n", what.c_str());
    ++failures;
  }
}

// Distance of every non-root joint to its parent.
hawor::VecX<double> boneLengths(const hawor::HandModel<double>& model, const hawor::Points3<double>& joints) {
  hawor::VecX<double> len(model.numJoints() - 1);
  for (int j = 1; j < model.numJoints(); ++j) {
    len(j - 1) = (joints.row(j) - joints.row(model.parents[static_cast<std::size_t>(j)])).norm();
  }
  return len;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: consumer HAND_MODEL [stb=on|off]\n");
    return 2;
  }
  try {
    // The version CMake found is the one the headers declare.
    check(std::string(HAWOR_VERSION_STRING) == CONSUMER_EXPECT_VERSION,
          std::string("header version ") + HAWOR_VERSION_STRING + " == CMake package version " + CONSUMER_EXPECT_VERSION);
    const bool stb = HAWOR_HAVE_STB != 0;
#if __has_include(<stb_image.h>)
    const bool stbReachable = true;
#else
    const bool stbReachable = false;
#endif
    if (argc == 3) {
      const std::string want = argv[2];
      check(want == "stb=on" || want == "stb=off", "second argument is stb=on or stb=off");
      check(stb == (want == "stb=on"), "hawor's io/ is built " + want);
      if (want == "stb=off") check(!stbReachable, "no stb header on the include path of a HAWOR_WITH_STB=OFF build");
    }

    // A group: exp/log round trip and composition with the inverse, in double and float.
    const hawor::Vec3<double> w(0.3, -0.2, 0.5);
    const hawor::SO3d R = hawor::SO3d::exp(w);
    check((R.log() - w).norm() < 1e-12, "SO3d: log(exp(w)) == w");
    check(((R * R.inverse()).matrix() - hawor::Mat3<double>::Identity()).norm() < 1e-12, "SO3d: R * R^-1 == I");
    const hawor::SO3f Rf = hawor::SO3f::exp(w.cast<float>());
    check((Rf.matrix().cast<double>() - R.matrix()).norm() < 1e-5, "SO3f agrees with SO3d");

    // The forward pass on the default hand: rest pose, then every joint bent by 0.3 rad and the
    // whole hand rotated by R and moved. Forward kinematics is rigid per bone, so every
    // joint-to-parent distance must stay what it is at rest.
    const hawor::LoadedHandModel<double> loaded = hawor::loadAnyHandModel<double>(argv[1], hawor::HandSide::Right);
    const hawor::HandModel<double>& model = loaded.model;
    check(model.numKeypoints() == 21, "the hand model has 21 keypoints");
    hawor::HandWorkspace<double> ws;
    hawor::HandOutput<double> rest, posed;
    hawor::HandPose<double> pose = hawor::HandPose<double>::zero(model);
    hawor::forward(model, pose, ws, rest);
    for (int j = 0; j + 1 < model.numJoints(); ++j) pose.handPose.row(j) << 0.3, 0.0, 0.1;
    pose.rot = w;
    pose.trans = hawor::Vec3<double>(0.05, -0.02, 0.4);
    hawor::forward(model, pose, ws, posed);
    check(posed.vertices.rows() == model.numVertices() && posed.vertices.allFinite(), "posed vertices are finite");
    const double boneErr = (boneLengths(model, posed.joints) - boneLengths(model, rest.joints)).cwiseAbs().maxCoeff();
    check(boneErr < 1e-9, "bone lengths kept by the pose (max change " + std::to_string(boneErr) + " m)");

    // A metric: PA-MPJPE is 0 against a similarity transform of the same keypoints and clearly
    // not 0 against the rest pose.
    const hawor::Points3<double> moved =
        ((1.7 * (hawor::SO3d::exp(hawor::Vec3<double>(-0.4, 0.9, 0.2)).matrix() * posed.keypoints.transpose())).colwise() +
         hawor::Vec3<double>(1.0, 2.0, 3.0))
            .transpose();
    const auto gt = hawor::toJointSequence<double>({posed.keypoints});
    const double same = hawor::paMpjpe<double>(gt, hawor::toJointSequence<double>({moved}));
    const double bent = hawor::paMpjpe<double>(gt, hawor::toJointSequence<double>({rest.keypoints}));
    check(same < 1e-6, "PA-MPJPE of a similarity copy is 0 (" + std::to_string(same) + " mm)");
    check(bent > 5.0, "PA-MPJPE of the bent hand against the rest pose is above 5 mm (" + std::to_string(bent) + " mm)");

    std::printf("consumer: hawor %s, stb %s, %d joints, %d vertices, PA-MPJPE bent vs rest %.1f mm: %s\n",
                HAWOR_VERSION_STRING, stb ? "on" : "off", model.numJoints(), model.numVertices(), bent,
                failures ? "FAILED" : "ok");
  } catch (const hawor::Error& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 1;
  }
  return failures ? 1 : 0;
}
