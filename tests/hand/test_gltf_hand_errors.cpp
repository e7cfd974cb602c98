// glTF -> HandModel (hand/default_hand.hpp) on unusable or corrupted skins: every failure is a
// hawor::Error naming the problem. Named test_gltf_* so that the sanitizer build (which keeps
// only the parser tests of hand/, tests/tests.cmake) runs it under ASan/UBSan.
#include <catch2/catch.hpp>

#include <functional>
#include <string>
#include <vector>

#include "gltf_test_util.hpp"
#include "hawor/hand/default_hand.hpp"

namespace {

std::string gltfHandErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const hawor::Error& e) {
    return e.what();
  }
  return "<no error>";
}

}  // namespace

TEST_CASE("default hand: unusable skins are errors", "[hand][gltf][malformed]") {
  const gltf_test::Finger f = gltf_test::makeFinger();
  auto convert = [&](const std::string& from, const std::string& to, const std::vector<uint8_t>* bin = nullptr) {
    return gltfHandErrorOf([&] {
      hawor::handFromGltf<double>(
          hawor::Gltf::fromGlb(gltf_test::makeGlb(gltf_test::replaced(f.json, from, to), bin ? *bin : f.bin), "f.glb"), false);
    });
  };
  CHECK(convert("\"name\":\"mesh\",\"mesh\":0,\"skin\":0,", "\"name\":\"mesh\",\"mesh\":0,").find("no skinned mesh") != std::string::npos);
  CHECK(convert("{\"name\":\"root\",", "{\"name\":\"root\",\"mesh\":0,\"skin\":0,").find("2 skinned mesh nodes") != std::string::npos);
  CHECK(convert("\"inverseBindMatrices\":5,", "").find("no inverseBindMatrices") != std::string::npos);
  CHECK(convert("\"mode\":4", "\"mode\":5").find("only TRIANGLES") != std::string::npos);
  CHECK(convert("\"POSITION\":0,", "").find("no POSITION") != std::string::npos);
  CHECK(convert("\"JOINTS_0\":2,", "").find("only one of JOINTS_0") != std::string::npos);
  CHECK(convert("\"JOINTS_0\":2,\"WEIGHTS_0\":3", "\"X\":2").find("no JOINTS_0") != std::string::npos);
  CHECK(convert("\"POSITION\":0", "\"POSITION\":3").find("expected VEC3") != std::string::npos);
  CHECK(convert("\"JOINTS_0\":2", "\"JOINTS_0\":0").find("VEC4") != std::string::npos);
  CHECK(convert("\"count\":84", "\"count\":83").find("not a multiple of 3") != std::string::npos);
  CHECK(convert("\"WEIGHTS_0\":3", "\"WEIGHTS_0\":3,\"JOINTS_1\":2").find("only one of") != std::string::npos);
  // Binary edits: a joint index past the skin, a negative weight, a vertex without weight,
  // an index past the vertices, a singular inverse bind matrix.
  auto binEdit = [&](size_t off, const std::vector<uint8_t>& bytes) {
    std::vector<uint8_t> b = f.bin;
    for (size_t i = 0; i < bytes.size(); ++i) b[off + i] = bytes[i];
    return convert("\"asset\"", "\"asset\"", &b);
  };
  CHECK(binEdit(384, {7}).find("weighted to joint 7") != std::string::npos);          // JOINTS_0 of vertex 0
  CHECK(binEdit(448 + 3, {0xBF}).find("negative or non-finite") != std::string::npos);  // WEIGHTS_0[0] = -0.5
  CHECK(binEdit(448, {0, 0, 0, 0}).find("vertex 0 has no skinning weight") != std::string::npos);
  CHECK(binEdit(704, {99, 0}).find("index 99 is out of range") != std::string::npos);
  std::vector<uint8_t> zeros(64, 0);
  CHECK(binEdit(872, zeros).find("not affine") != std::string::npos);
  std::vector<uint8_t> nanIbm(4, 0xFF);
  CHECK(binEdit(872, nanIbm).find("non-finite") != std::string::npos);
  // Limits.
  hawor::DefaultHandLimits lim;
  lim.maxJoints = 2;
  CHECK(gltfHandErrorOf([&] { hawor::handFromGltf<double>(hawor::Gltf::fromGlb(f.glb(), "f.glb"), false, lim); }).find("over the limit") !=
        std::string::npos);
  lim = {};
  lim.maxVertices = 10;
  CHECK(gltfHandErrorOf([&] { hawor::handFromGltf<double>(hawor::Gltf::fromGlb(f.glb(), "f.glb"), false, lim); }).find("too large") !=
        std::string::npos);
}

TEST_CASE("default hand: every truncation and random corruption of a valid hand fails cleanly", "[hand][gltf][malformed]") {
  gltf_test::SimpleSkin s = gltf_test::webxrLikeHand(hawor::webxrJointNames(), hawor::webxrParents());
  const std::vector<uint8_t> good = s.build();
  REQUIRE_NOTHROW(hawor::loadDefaultHand<double>(good.data(), good.size(), false));
  for (size_t n = 0; n < good.size(); n += 7) {
    CHECK_THROWS_AS(hawor::loadDefaultHand<double>(good.data(), n, false, "cut.glb"), hawor::Error);
  }
  uint32_t state = 99;
  auto next = [&] {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<uint8_t> b = good;
    for (int k = 0; k < 3; ++k) b[next() % b.size()] = static_cast<uint8_t>(next());
    try {
      hawor::loadDefaultHand<float>(b.data(), b.size(), false, "bad.glb");
    } catch (const hawor::Error&) {
    }
  }
}
