// Skinned glTF -> HandModel (hand/default_hand.hpp): the synthetic finger and a WebXR-named
// skeleton built by an independent writer, glTF skinning semantics reproduced by the forward
// pass, errors for unusable skins, and the real WebXR generic hands when present
// (node_modules/@webxr-input-profiles/assets, see docs/design.md §3).
#include <catch2/catch.hpp>

#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "gltf_test_util.hpp"
#include "hawor/geometry/rotation.hpp"
#include "hawor/hand/default_hand.hpp"
#include "hawor/hand/forward.hpp"

template struct hawor::DefaultHand<float>;
template struct hawor::DefaultHand<double>;
template hawor::DefaultHand<float> hawor::handFromGltf<float>(const hawor::Gltf&, bool, const hawor::DefaultHandLimits&);
template hawor::DefaultHand<double> hawor::handFromGltf<double>(const hawor::Gltf&, bool, const hawor::DefaultHandLimits&);

namespace {

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const hawor::Error& e) {
    return e.what();
  }
  return "<no error>";
}

template <typename Scalar>
double tol() {
  return std::is_same<Scalar, float>::value ? 2e-6 : 1e-12;
}

Eigen::Matrix4d ibmOf(const hawor::Gltf& g, int k) {
  const std::vector<double> m = g.readFloats(g.skins()[0].inverseBindMatrices);
  Eigen::Matrix4d M;
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) M(r, c) = m[static_cast<size_t>(16 * k + 4 * c + r)];
  }
  return M;
}

/// glTF skinning of the file's raw data, v = Σ w_k·W_k·IBM_k·p (weights renormalised), with the
/// posed joint world transforms W_j = [Rg_j·Q_j | g_j] of the model's kinematic chain under the
/// local rotations `rot` (model order; rot[0] is the global orientation about joint 0):
/// Rg_j = Rg_p·R_j, g_j = g_p + Rg_p·(J_j − J_p), J_j and Q_j from IBM⁻¹ of the joint's skin entry.
Eigen::MatrixXd gltfSkinning(const hawor::Gltf& g, const std::vector<int>& skinJoint, const std::vector<int>& parents,
                             const std::vector<Eigen::Matrix3d>& rot) {
  const size_t J = skinJoint.size();
  std::vector<Eigen::Matrix4d> bind(J), W(J), ibm(J);
  std::vector<Eigen::Matrix3d> Rg(J);
  std::vector<int> modelOf(J);
  for (size_t j = 0; j < J; ++j) {
    ibm[j] = ibmOf(g, skinJoint[j]);
    bind[j] = ibm[j].inverse();
    modelOf[static_cast<size_t>(skinJoint[j])] = static_cast<int>(j);
  }
  for (size_t j = 0; j < J; ++j) {
    const int p = parents[j];
    const Eigen::Vector3d Jj = bind[j].block<3, 1>(0, 3);
    W[j].setIdentity();
    if (p < 0) {
      Rg[j] = rot[j];
      W[j].block<3, 1>(0, 3) = Jj;
    } else {
      const size_t ps = static_cast<size_t>(p);
      Rg[j] = Rg[ps] * rot[j];
      W[j].block<3, 1>(0, 3) = W[ps].block<3, 1>(0, 3) + Rg[ps] * (Jj - bind[ps].block<3, 1>(0, 3));
    }
    W[j].topLeftCorner<3, 3>() = Rg[j] * bind[j].topLeftCorner<3, 3>();
  }
  const hawor::GltfPrimitive& prim = g.meshes()[0].primitives[0];
  const std::vector<double> P = g.readFloats(prim.attribute("POSITION"));
  const std::vector<double> w = g.readFloats(prim.attribute("WEIGHTS_0"));
  const std::vector<uint32_t> ji = g.readUints(prim.attribute("JOINTS_0"));
  const size_t V = P.size() / 3;
  Eigen::MatrixXd out(static_cast<Eigen::Index>(V), 3);
  for (size_t v = 0; v < V; ++v) {
    const Eigen::Vector4d p(P[3 * v], P[3 * v + 1], P[3 * v + 2], 1.0);
    Eigen::Vector4d acc = Eigen::Vector4d::Zero();
    double sum = 0;
    for (size_t q = 0; q < 4; ++q) {
      const double wk = w[4 * v + q];
      if (wk == 0) continue;
      const size_t j = static_cast<size_t>(modelOf[ji[4 * v + q]]);
      acc += wk * (W[j] * ibm[j] * p);
      sum += wk;
    }
    out.row(static_cast<Eigen::Index>(v)) = (acc.head<3>() / sum).transpose();
  }
  return out;
}

std::vector<Eigen::Matrix3d> randomRotations(size_t J, unsigned seed, double scale = 0.6) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, scale);
  std::vector<Eigen::Matrix3d> R(J);
  for (auto& r : R) r = Eigen::AngleAxisd(std::abs(n(rng)) + 0.1, Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized()).toRotationMatrix();
  return R;
}

/// Forward pass of the converted model under the same local rotations (as axis-angles).
template <typename Scalar>
hawor::HandOutput<Scalar> poseModel(const hawor::HandModel<Scalar>& m, const std::vector<Eigen::Matrix3d>& R) {
  auto pose = hawor::HandPose<Scalar>::zero(m);
  const Eigen::AngleAxisd a0(R[0]);
  pose.rot = (a0.axis() * a0.angle()).cast<Scalar>();
  for (int j = 1; j < m.numJoints(); ++j) {
    const Eigen::AngleAxisd a(R[static_cast<size_t>(j)]);
    pose.handPose.row(j - 1) = (a.axis() * a.angle()).transpose().cast<Scalar>();
  }
  return hawor::forward(m, pose);
}

template <typename A, typename B>
double maxAbs(const A& a, const B& b) {
  return (a.template cast<double>() - b.template cast<double>()).cwiseAbs().maxCoeff();
}

}  // namespace

TEMPLATE_TEST_CASE("default hand: the finger converts in every encoding", "[hand][gltf]", float, double) {
  using S = TestType;
  for (int weights : {5126, 5121, 5123}) {
    for (bool shuffled : {false, true}) {
      for (bool interleaved : {false, true}) {
        gltf_test::Spec spec;
        spec.weights = weights;
        spec.skinOrderShuffled = shuffled;
        spec.interleaved = interleaved;
        spec.armatureMatrix = !interleaved;
        INFO("weights " << weights << " shuffled " << shuffled << " interleaved " << interleaved);
        const gltf_test::Finger f = gltf_test::makeFinger(spec);
        const hawor::Gltf g = hawor::Gltf::fromGlb(f.glb(), "finger.glb");
        const hawor::DefaultHand<S> h = hawor::handFromGltf<S>(g, shuffled);
        const hawor::HandModel<S>& m = h.model;
        REQUIRE(m.prepared());
        REQUIRE(m.numVertices() == 16);
        REQUIRE(m.faces.rows() == 28);
        REQUIRE(m.numJoints() == 3);
        CHECK(m.numBetas() == 0);
        CHECK(m.numPoseFeatures() == 0);
        CHECK(m.numKeypoints() == 0);
        CHECK(!h.webxrJoints);
        CHECK(m.isLeft == shuffled);
        CHECK(m.parents == std::vector<int>{-1, 0, 1});
        CHECK(h.jointNames == std::vector<std::string>{"root", "mid", "tip"});
        // skinJoint: model joint j is the skin entry holding finger joint j.
        for (int j = 0; j < 3; ++j) CHECK(f.skinOrder[static_cast<size_t>(h.skinJoint[static_cast<size_t>(j)])] == j);
        // The template is POSITION unchanged (the mesh node's translation (5,5,5) is ignored).
        for (int v = 0; v < 16; ++v) {
          for (int c = 0; c < 3; ++c) CHECK(static_cast<double>(m.vTemplate(v, c)) == static_cast<double>(static_cast<S>(f.positions(v, c))));
        }
        for (int t = 0; t < 28; ++t) {
          for (int c = 0; c < 3; ++c) CHECK(m.faces(t, c) == f.indices[static_cast<size_t>(3 * t + c)]);
        }
        // Weights: decoded values at the model joint columns, rows renormalised.
        for (int v = 0; v < 16; ++v) {
          Eigen::Vector3d expect = Eigen::Vector3d::Zero();
          for (int k = 0; k < 4; ++k) {
            const int skinK = f.jointIds(v, k);
            const int finger = f.skinOrder[static_cast<size_t>(skinK)];
            expect(finger) += f.weightsDecoded(v, k);
          }
          expect /= expect.sum();
          for (int j = 0; j < 3; ++j) CHECK(std::abs(static_cast<double>(m.weights(v, j)) - expect(j)) <= tol<S>());
        }
        // Rest joints = bind positions (float IBMs: ~1e-7), regressed exactly from the template.
        const Eigen::MatrixXd jr = (m.jRegressor * m.vTemplate).template cast<double>();
        for (int j = 0; j < 3; ++j) {
          const Eigen::Vector3d expect = f.jointWorld[static_cast<size_t>(j)].block<3, 1>(0, 3);
          CHECK((jr.row(j).transpose() - expect).cwiseAbs().maxCoeff() < 1e-6);
          const Eigen::Matrix3d Q = f.jointWorld[static_cast<size_t>(j)].topLeftCorner<3, 3>();
          CHECK((h.bindRotations[static_cast<size_t>(j)].template cast<double>() - Q).cwiseAbs().maxCoeff() < 1e-6);
        }
        for (int j = 0; j < 3; ++j) {
          const Eigen::Vector3d exact = ibmOf(g, h.skinJoint[static_cast<size_t>(j)]).inverse().template block<3, 1>(0, 3);
          CHECK((jr.row(j).transpose() - exact).cwiseAbs().maxCoeff() <= (std::is_same<S, float>::value ? 1e-7 : 1e-15));
        }
        for (int j = 0; j < 3; ++j) CHECK(std::abs(static_cast<double>(m.jRegressor.row(j).sum()) - 1.0) <= tol<S>());
        // At rest the forward pass returns the template; posed, it matches glTF skinning.
        const auto rest = hawor::forward(m, hawor::HandPose<S>::zero(m));
        CHECK(maxAbs(rest.vertices, m.vTemplate) <= tol<S>());
        const auto R = randomRotations(3, 7);
        const auto posed = poseModel(m, R);
        CHECK(maxAbs(posed.vertices, gltfSkinning(g, h.skinJoint, m.parents, R)) <= 10 * tol<S>());
      }
    }
  }
}

TEST_CASE("default hand: WebXR names on a flat skeleton give the WebXR tree, order and keypoints", "[hand][gltf]") {
  gltf_test::SimpleSkin s = gltf_test::webxrLikeHand(hawor::webxrJointNames(), hawor::webxrParents());
  const hawor::Gltf g = hawor::Gltf::fromGlb(s.build(), "xr.glb");
  const hawor::DefaultHand<double> h = hawor::handFromGltf<double>(g, true);
  const hawor::HandModel<double>& m = h.model;
  CHECK(h.webxrJoints);
  CHECK(m.isLeft);
  REQUIRE(m.numJoints() == 25);
  CHECK(m.parents == hawor::webxrParents());
  const std::vector<std::string> xr = hawor::webxrJointNames();
  for (size_t j = 0; j < 25; ++j) CHECK(h.jointNames[j] == "r_" + xr[j]);
  CHECK(m.keypointMap == hawor::webxrKeypointMap());
  CHECK(m.numKeypoints() == 21);
  // Rest joints and keypoints where the skeleton put them.
  const auto rest = hawor::forward(m, hawor::HandPose<double>::zero(m));
  for (size_t j = 0; j < 25; ++j) CHECK((rest.joints.row(static_cast<Eigen::Index>(j)).transpose() - s.position[j]).cwiseAbs().maxCoeff() < 1e-7);
  CHECK((rest.keypoints.row(12) - rest.joints.row(14)).cwiseAbs().maxCoeff() == 0.0);  // middle tip
  CHECK((rest.keypoints.row(5) - rest.joints.row(6)).cwiseAbs().maxCoeff() == 0.0);    // index MCP = proximal
  CHECK(maxAbs(rest.vertices, m.vTemplate) < 1e-15);
  const auto R = randomRotations(25, 3, 0.3);
  CHECK(maxAbs(poseModel(m, R).vertices, gltfSkinning(g, h.skinJoint, m.parents, R)) < 1e-12);
  CHECK(std::abs(hawor::restHandLength(m) - s.position[14].norm()) < 1e-7);

  // Names with '_' instead of '-' and upper case are recognised too; unknown names are not.
  std::vector<std::string> underscored = xr;
  for (auto& n : underscored) {
    for (char& c : n) c = c == '-' ? '_' : static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  gltf_test::SimpleSkin s2 = gltf_test::webxrLikeHand(underscored, hawor::webxrParents());
  CHECK(hawor::handFromGltf<double>(hawor::Gltf::fromGlb(s2.build(), "xr2.glb"), false).webxrJoints);
  std::vector<std::string> renamed = xr;
  renamed[3] = "thumbtip-x";
  gltf_test::SimpleSkin s3 = gltf_test::webxrLikeHand(renamed, hawor::webxrParents());
  CHECK(errorOf([&] { hawor::handFromGltf<double>(hawor::Gltf::fromGlb(s3.build(), "xr3.glb"), false); })
            .find("25 separate trees") != std::string::npos);
  // A name that is a WebXR name glued to letters ("xwrist") is not a match either.
  renamed = xr;
  renamed[0] = "xwrist";
  gltf_test::SimpleSkin s4 = gltf_test::webxrLikeHand(renamed, hawor::webxrParents());
  CHECK_THROWS_AS(hawor::handFromGltf<double>(hawor::Gltf::fromGlb(s4.build(), "xr4.glb"), false), hawor::Error);
}

TEST_CASE("default hand: a nested hierarchy is used as is and made parent-first", "[hand][gltf]") {
  // Skin order [tip, root, mid] with a nested hierarchy: the model order is root, mid, tip.
  gltf_test::Spec spec;
  spec.skinOrderShuffled = true;
  const gltf_test::Finger f = gltf_test::makeFinger(spec);
  const hawor::DefaultHand<double> h = hawor::handFromGltf<double>(hawor::Gltf::fromGlb(f.glb(), "f.glb"), false);
  CHECK(h.skinJoint == std::vector<int>{1, 2, 0});
  CHECK(h.model.parents == std::vector<int>{-1, 0, 1});
}

TEST_CASE("default hand: exactJointRegressor reproduces points inside and outside the mesh", "[hand][gltf]") {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  hawor::Points3<double> verts(200, 3), joints(30, 3);
  for (Eigen::Index i = 0; i < verts.size(); ++i) verts.data()[i] = 0.05 * n(rng);
  for (Eigen::Index i = 0; i < joints.size(); ++i) joints.data()[i] = 0.03 * n(rng) + (i % 3 == 0 ? 0.2 * (i % 2) : 0.0);
  const hawor::MatX<double> R = hawor::exactJointRegressor<double>(verts, joints);
  CHECK(((R * verts) - joints).cwiseAbs().maxCoeff() < 1e-15);
  for (Eigen::Index j = 0; j < R.rows(); ++j) {
    CHECK(std::abs(R.row(j).sum() - 1.0) < 1e-14);
    CHECK((R.row(j).array() != 0).count() == 4);
  }
  // Degenerate meshes.
  hawor::Points3<double> flat = verts;
  flat.col(2).setZero();
  CHECK(errorOf([&] { hawor::exactJointRegressor<double>(flat, joints); }).find("non-coplanar") != std::string::npos);
  CHECK_THROWS_AS(hawor::exactJointRegressor<double>(verts.topRows(3), joints), hawor::Error);
}

// --- the real WebXR generic hands -------------------------------------------------------------------

namespace {

std::string assetPath(const std::string& side) {
  return std::string(HAWOR_SOURCE_DIR) + "/node_modules/@webxr-input-profiles/assets/dist/profiles/generic-hand/" + side + ".glb";
}

bool haveAsset(const std::string& side) {
  std::FILE* f = std::fopen(assetPath(side).c_str(), "rb");
  if (!f) return false;
  std::fclose(f);
  return true;
}

}  // namespace

TEMPLATE_TEST_CASE("default hand: the WebXR generic hands", "[hand][gltf][asset]", float, double) {
  using S = TestType;
  if (!haveAsset("right") || !haveAsset("left")) {
    WARN("skipped: " << assetPath("right") << " not found (npm install @webxr-input-profiles/assets@1.0.20)");
    return;
  }
  double tripleRight = 0, tripleLeft = 0;
  for (const std::string side : {"right", "left"}) {
    INFO(side);
    const hawor::Gltf g = hawor::Gltf::readGlb(assetPath(side));
    const hawor::DefaultHand<S> h = hawor::handFromGltf<S>(g, side == "left");
    const hawor::HandModel<S>& m = h.model;
    CHECK(m.numVertices() == 1360);
    CHECK(m.faces.rows() == 2314);
    CHECK(m.numJoints() == 25);
    CHECK(m.numKeypoints() == 21);
    CHECK(m.numBetas() == 0);
    CHECK(m.numPoseFeatures() == 0);
    CHECK(h.webxrJoints);
    CHECK(h.jointNames == hawor::webxrJointNames());  // the files use the bare names
    CHECK(m.parents == hawor::webxrParents());
    CHECK(m.isLeft == (side == "left"));
    // Every row of the regressor is convex here (each joint lies inside its tetrahedron).
    const Eigen::MatrixXd jr = (m.jRegressor * m.vTemplate).template cast<double>();
    for (int j = 0; j < 25; ++j) {
      const Eigen::Vector3d exact = ibmOf(g, h.skinJoint[static_cast<size_t>(j)]).inverse().template block<3, 1>(0, 3);
      CHECK((jr.row(j).transpose() - exact).cwiseAbs().maxCoeff() <= (std::is_same<S, float>::value ? 1e-7 : 1e-15));
      CHECK(m.jRegressor.row(j).minCoeff() >= S(-1e-6));
    }
    const auto rest = hawor::forward(m, hawor::HandPose<S>::zero(m));
    CHECK(maxAbs(rest.vertices, m.vTemplate) <= tol<S>());
    const auto R = randomRotations(25, 11, 0.3);
    CHECK(maxAbs(poseModel(m, R).vertices, gltfSkinning(g, h.skinJoint, m.parents, R)) <= 10 * tol<S>());

    // Anatomy of the 21 keypoints (metres).
    const Eigen::MatrixXd kp = rest.keypoints.template cast<double>();
    auto d = [&](int a, int b) { return (kp.row(a) - kp.row(b)).norm(); };
    const double length = static_cast<double>(hawor::restHandLength(m));
    CHECK(length == Approx(d(0, 12)).epsilon(1e-6));
    CHECK(length > 0.15);
    CHECK(length < 0.22);
    for (int finger = 0; finger < 5; ++finger) {
      const int b = 1 + 4 * finger;
      CHECK(d(0, b) < d(0, b + 1));  // each chain moves away from the wrist
      CHECK(d(0, b + 1) < d(0, b + 2));
      CHECK(d(0, b + 2) < d(0, b + 3));
      CHECK(d(b, b + 1) > 0.01);  // bones are at least 1 cm
    }
    for (int tip : {4, 8, 16, 20}) CHECK(d(0, 12) > d(0, tip));  // the middle finger is longest
    CHECK(d(4, 20) > d(8, 12));                                 // thumb tip far from pinky tip
    CHECK(d(5, 17) > d(5, 13));                                 // MCPs in order across the palm
    CHECK(d(5, 13) > d(5, 9));
    CHECK(d(9, 17) > d(13, 17));
    CHECK(d(1, 5) < d(1, 17));  // the thumb is on the index side
    // Handedness: the triple product of (wrist→middle MCP, pinky MCP→index MCP, wrist→thumb IP)
    // changes sign between a hand and its mirror image.
    const Eigen::Vector3d up = (kp.row(9) - kp.row(0)).transpose(), across = (kp.row(5) - kp.row(17)).transpose(),
                          thumb = (kp.row(3) - kp.row(0)).transpose();
    (side == "right" ? tripleRight : tripleLeft) = up.cross(across).dot(thumb);
  }
  CHECK(tripleRight * tripleLeft < 0);
}
