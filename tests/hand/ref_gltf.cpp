// Cross-check of the GLB reader and the glTF -> hand-model conversion against files and
// expectations written by tests/ref/gltf_make.py (numpy/scipy, struct + json): every accessor
// decodes exactly (strided, interleaved, normalised ubyte/ushort, byteOffset), node world
// transforms, the converted model, and a posed forward pass against glTF skinning of the raw data.
#include <catch2/catch.hpp>

#include <string>

#include "hawor/hand/default_hand.hpp"
#include "hawor/hand/forward.hpp"
#include "../support/ref_data.hpp"

namespace {

double maxDiff(const Eigen::MatrixXd& a, const hawor_test::RefArray& r) {
  REQUIRE(static_cast<long>(a.size()) == r.size());
  double m = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    for (Eigen::Index j = 0; j < a.cols(); ++j) m = std::max(m, std::abs(a(i, j) - r[i * a.cols() + j]));
  }
  return m;
}

}  // namespace

TEST_CASE("gltf ref: synthetic skinned files match numpy", "[hand][gltf][ref]") {
  const std::string out = "gltf_make.txt";
  const hawor_test::RefData ref = hawor_test::runReference("gltf_make.py", out);
  for (int k = 0; k < 3; ++k) {
    INFO("variant " << k);
    const std::string p = "v" + std::to_string(k) + "_";
    const hawor::Gltf g = hawor::Gltf::readGlb(std::string(HAWOR_REF_DIR) + "/" + out + "." + std::to_string(k) + ".glb");
    const int nacc = static_cast<int>(ref[p + "num_accessors"][0]);
    REQUIRE(static_cast<int>(g.accessors().size()) == nacc);
    for (int i = 0; i < nacc; ++i) {
      INFO("accessor " << i);
      const hawor_test::RefArray& a = ref[p + "acc" + std::to_string(i)];
      const std::vector<double> got = g.readFloats(i);
      REQUIRE(static_cast<long>(got.size()) == a.size());
      for (long e = 0; e < a.size(); ++e) CHECK(got[static_cast<size_t>(e)] == a[e]);  // exact
    }
    const hawor_test::RefArray& nw = ref[p + "node_world"];
    REQUIRE(static_cast<long>(g.nodes().size()) == nw.shape[0]);
    for (size_t n = 0; n < g.nodes().size(); ++n) {
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) CHECK(std::abs(g.nodeWorld(static_cast<int>(n))(r, c) - nw[static_cast<long>(16 * n + 4 * r + c)]) < 1e-13);
      }
    }

    const hawor::DefaultHand<double> h = hawor::handFromGltf<double>(g, false);
    const hawor::HandModel<double>& m = h.model;
    CHECK(maxDiff(m.vTemplate, ref[p + "v_template"]) == 0.0);
    CHECK(maxDiff(m.faces.cast<double>(), ref[p + "faces"]) == 0.0);
    const hawor_test::RefArray& order = ref[p + "order"];
    const hawor_test::RefArray& parents = ref[p + "parents"];
    REQUIRE(m.numJoints() == order.size());
    for (int j = 0; j < m.numJoints(); ++j) {
      CHECK(h.skinJoint[static_cast<size_t>(j)] == static_cast<int>(order[j]));
      CHECK(m.parents[static_cast<size_t>(j)] == static_cast<int>(parents[j]));
    }
    CHECK(maxDiff(m.weights, ref[p + "weights"]) < 1e-15);
    const Eigen::MatrixXd joints = m.jRegressor * m.vTemplate;
    CHECK(maxDiff(joints, ref[p + "rest"]) < 1e-14);
    // Posed: the forward pass equals glTF skinning of the raw file data.
    auto pose = hawor::HandPose<double>::zero(m);
    const hawor_test::RefArray& aa = ref[p + "pose"];
    pose.rot = hawor::Vec3<double>(aa[0], aa[1], aa[2]);
    for (int j = 1; j < m.numJoints(); ++j) {
      for (int c = 0; c < 3; ++c) pose.handPose(j - 1, c) = aa[3 * j + c];
    }
    CHECK(maxDiff(hawor::forward(m, pose).vertices, ref[p + "posed"]) < 1e-12);
  }
}
