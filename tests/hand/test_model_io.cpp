// The library's hand-model .npz (hand/model_io.hpp): round trips of every field for float and
// double models (MANO-sized with shape and pose spaces, and a converted glTF hand without them),
// compressed and stored archives, and clear errors for missing or inconsistent arrays.
#include <catch2/catch.hpp>

#include <functional>
#include <string>
#include <vector>

#include "gltf_test_util.hpp"
#include "hand_test_util.hpp"
#include "hawor/hand/default_hand.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/model_io.hpp"

template hawor::Npz hawor::handModelToNpz<float>(const hawor::HandModel<float>&, const std::vector<std::string>&);
template hawor::Npz hawor::handModelToNpz<double>(const hawor::HandModel<double>&, const std::vector<std::string>&);
template hawor::HandModel<float> hawor::handModelFromNpz<float>(const hawor::Npz&, std::vector<std::string>*);
template hawor::HandModel<double> hawor::handModelFromNpz<double>(const hawor::Npz&, std::vector<std::string>*);

namespace {

std::string modelIoErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const hawor::Error& e) {
    return e.what();
  }
  return "<no error>";
}

template <typename DA, typename DB>
bool same(const Eigen::MatrixBase<DA>& a, const Eigen::MatrixBase<DB>& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         (a.size() == 0 || a.template cast<double>() == b.template cast<double>());
}

template <typename A, typename B>
void checkSame(const hawor::HandModel<A>& a, const hawor::HandModel<B>& b) {
  CHECK(same(a.vTemplate, b.vTemplate));
  CHECK(same(a.shapedirs, b.shapedirs));
  CHECK(a.posedirs.size() == b.posedirs.size());
  if (a.posedirs.size()) CHECK(same(a.posedirs, b.posedirs));
  CHECK(same(a.jRegressor, b.jRegressor));
  CHECK(same(a.weights, b.weights));
  CHECK(same(a.faces, b.faces));
  CHECK(a.parents == b.parents);
  CHECK(a.tipVertices == b.tipVertices);
  CHECK(a.keypointMap == b.keypointMap);
  CHECK(a.isLeft == b.isLeft);
}

std::string tmp(const std::string& name) { return std::string(HAWOR_REF_DIR) + "/model_io_" + name; }

}  // namespace

TEMPLATE_TEST_CASE("model io: a MANO-sized model round-trips exactly", "[hand][model_io]", float, double) {
  using S = TestType;
  hawor::HandModel<S> m = hand_test::randomModel<S>();
  m.isLeft = true;
  for (bool compressed : {false, true}) {
    if (compressed && !hawor::kHaveDeflate) continue;
    INFO("compressed " << compressed);
    const std::vector<uint8_t> bytes = hawor::handModelToBuffer(m, {}, compressed);
    std::vector<std::string> names = {"stale"};
    const hawor::HandModel<S> back = hawor::loadHandModel<S>(bytes.data(), bytes.size(), "m.npz", &names);
    CHECK(back.prepared());
    CHECK(names.empty());
    checkSame(m, back);
    // The forward pass of the loaded model is that of the original.
    auto pose = hawor::HandPose<S>::zero(m);
    pose.betas.setConstant(S(0.5));
    pose.handPose.setConstant(S(0.2));
    CHECK(same(hawor::forward(m, pose).vertices, hawor::forward(back, pose).vertices));
  }
  // Stored arrays keep the model's precision; a float model reads back as double exactly.
  const hawor::Npz z = hawor::handModelToNpz(m);
  CHECK(z.get("v_template").dtype == (std::is_same<S, float>::value ? "<f4" : "<f8"));
  CHECK(z.get("shapedirs").shape == std::vector<size_t>{778, 3, 10});
  CHECK(z.get("posedirs").shape == std::vector<size_t>{778, 3, 135});
  CHECK(z.get("f").dtype == "<i4");
  checkSame(m, hawor::handModelFromNpz<double>(z));
  // MANO layout: shapedirs[v, c, k] = shapedirs(3v + c, k).
  const std::vector<double> sd = z.getAs<double>("shapedirs");
  CHECK(sd[(5 * 3 + 2) * 10 + 7] == static_cast<double>(m.shapedirs(3 * 5 + 2, 7)));
}

TEST_CASE("model io: files, joint names and the converted glTF hand", "[hand][model_io]") {
  gltf_test::SimpleSkin s = gltf_test::webxrLikeHand(hawor::webxrJointNames(), hawor::webxrParents());
  const std::vector<uint8_t> glb = s.build();
  const hawor::DefaultHand<double> h = hawor::loadDefaultHand<double>(glb.data(), glb.size(), true);
  const std::string path = tmp("xr.npz");
  hawor::saveHandModel(h.model, path, h.jointNames);
  std::vector<std::string> names;
  const hawor::HandModel<double> back = hawor::loadHandModel<double>(path, &names);
  checkSame(h.model, back);
  CHECK(names == h.jointNames);
  CHECK(back.numBetas() == 0);
  CHECK(back.numPoseFeatures() == 0);
  const hawor::HandModel<float> backf = hawor::loadHandModel<float>(path);
  CHECK(backf.numKeypoints() == 21);
  CHECK((backf.vTemplate.cast<double>() - h.model.vTemplate).cwiseAbs().maxCoeff() < 1e-8);
  // Names: non-ASCII UTF-8 survives; empty names are allowed; a newline is refused.
  std::vector<std::string> odd(25, "");
  odd[0] = "poignet \xC3\xA9";
  std::vector<std::string> got;
  const std::vector<uint8_t> b = hawor::handModelToBuffer(h.model, odd);
  hawor::loadHandModel<double>(b.data(), b.size(), "b", &got);
  CHECK(got == odd);
  odd[1] = "a\nb";
  CHECK(modelIoErrorOf([&] { hawor::handModelToBuffer(h.model, odd); }).find("newline") != std::string::npos);
  CHECK(modelIoErrorOf([&] { hawor::handModelToBuffer(h.model, std::vector<std::string>(3, "x")); }).find("3 joint names for 25") !=
        std::string::npos);
  CHECK_THROWS_AS(hawor::loadHandModel<double>(tmp("missing.npz")), hawor::Error);
}

TEST_CASE("model io: missing and inconsistent arrays name the key", "[hand][model_io][malformed]") {
  const hawor::HandModel<double> m = hand_test::randomModel<double>(60, {-1, 0, 1, 0, 3}, 2, true, 3);
  const hawor::Npz good = hawor::handModelToNpz(m, {"a", "b", "c", "d", "e"});
  auto loadErr = [](const hawor::Npz& z) { return modelIoErrorOf([&] { hawor::handModelFromNpz<double>(z); }); };
  CHECK(loadErr(good) == "<no error>");
  for (const std::string& key : good.names()) {
    INFO(key);
    hawor::Npz z;
    for (const std::string& k : good.names()) {
      if (k != key) z.set(k, good.get(k));
    }
    const std::string e = loadErr(z);
    CHECK(e.find("'" + key + "'") != std::string::npos);
  }
  auto with = [&](const std::string& key, hawor::NpyArray a) {
    hawor::Npz z = good;
    z.set(key, std::move(a));
    return loadErr(z);
  };
  const int32_t two = 2;
  CHECK(with("hawor_hand_model", hawor::NpyArray::fromData(&two, {})).find("version 2 is not supported") != std::string::npos);
  const std::vector<double> v(60 * 4, 0.0);
  CHECK(with("v_template", hawor::NpyArray::fromData(v.data(), {60, 4})).find("'v_template' has shape (60, 4)") != std::string::npos);
  CHECK(with("weights", hawor::NpyArray::fromData(v.data(), {60, 4})).find("'weights'") != std::string::npos);
  CHECK(with("J_regressor", hawor::NpyArray::fromData(v.data(), {4, 60})).find("'J_regressor'") != std::string::npos);
  CHECK(with("shapedirs", hawor::NpyArray::fromData(v.data(), {60, 4})).find("3 dimension(s)") != std::string::npos);
  const std::vector<int32_t> badParents = {-1, 0, 1, 3, 3};
  CHECK(with("parents", hawor::NpyArray::fromData(badParents.data(), {5})).find("parents must precede") != std::string::npos);
  const std::vector<double> fparents = {-1, 0, 1, 0, 3};
  CHECK(with("parents", hawor::NpyArray::fromData(fparents.data(), {5})).find("must hold integers") != std::string::npos);
  const std::vector<int32_t> badFaces = {0, 1, 60};
  CHECK(with("f", hawor::NpyArray::fromData(badFaces.data(), {1, 3})).find("outside [0, 60)") != std::string::npos);
  const std::vector<int32_t> badMap = {0, 99};
  CHECK(with("keypoint_map", hawor::NpyArray::fromData(badMap.data(), {2})).find("keypoint index 99") != std::string::npos);
  const uint8_t three = 3;
  CHECK(with("is_left", hawor::NpyArray::fromData(&three, {})).find("0 or 1") != std::string::npos);
  const std::string names = "a\nb";
  CHECK(with("joint_names", hawor::NpyArray::fromData(reinterpret_cast<const uint8_t*>(names.data()), {names.size()}))
            .find("2 names for 5 joints") != std::string::npos);
  std::vector<double> nanT(60 * 3, 0.0);
  nanT[7] = std::nan("");
  CHECK(with("v_template", hawor::NpyArray::fromData(nanT.data(), {60, 3})).find("non-finite") != std::string::npos);
  hawor::Npz noMarker;
  noMarker.set("v_template", good.get("v_template"));
  CHECK(loadErr(noMarker).find("not a hawor hand model file") != std::string::npos);
  const std::vector<uint8_t> junk = {1, 2, 3};
  CHECK_THROWS_AS(hawor::loadHandModel<double>(junk.data(), junk.size()), hawor::Error);
}
