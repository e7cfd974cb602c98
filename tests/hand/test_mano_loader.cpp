// MANO loader on pickles written in C++ with the official object layout (hand_test_util.hpp),
// in the variants found in the wild, and on files that are not MANO models.
#include <catch2/catch.hpp>

#include "hand_test_util.hpp"
#include "hawor/hand/forward.hpp"
#include "hawor/hand/mano_loader.hpp"
#include "hawor/hand/mirror.hpp"

#include <string>

namespace {

// A byte string from a literal, embedded NULs included.
template <std::size_t N>
std::string lit(const char (&s)[N]) {
  return std::string(s, N - 1);
}

hawor::HandModeld load(const std::string& bytes, hawor::HandSide side = hawor::HandSide::Right,
                       bool strict = true) {
  hawor::ManoLoadOptions opt;
  opt.side = side;
  opt.strictGlobals = strict;
  return hawor::loadManoPickle<double>(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), opt,
                                       "test.pkl");
}

void expectSame(const hawor::HandModeld& a, const hawor::HandModeld& b) {
  CHECK(a.vTemplate == b.vTemplate);
  CHECK(a.shapedirs == b.shapedirs);
  CHECK(a.posedirs == b.posedirs);
  CHECK(a.jRegressor == b.jRegressor);
  CHECK(a.weights == b.weights);
  CHECK(a.faces == b.faces);
  CHECK(a.parents == b.parents);
  CHECK(a.tipVertices == b.tipVertices);
  CHECK(a.keypointMap == b.keypointMap);
}

void expectLoadError(const std::string& bytes, const std::string& fragment, bool strict = true) {
  try {
    (void)load(bytes, hawor::HandSide::Right, strict);
    FAIL("no error, expected: " << fragment);
  } catch (const hawor::Error& e) {
    INFO(e.what());
    CHECK(std::string(e.what()).find(fragment) != std::string::npos);
  }
}

}  // namespace

TEST_CASE("mano loader: official layout round trip", "[hand][loader]") {
  const auto m = hand_test::randomModel<double>();
  const std::string bytes = hand_test::writeModelPickle(m);
  const auto loaded = load(bytes);
  expectSame(loaded, m);
  CHECK(loaded.prepared());
  CHECK(!loaded.isLeft);
  CHECK(loaded.numKeypoints() == 21);
  const auto p = hand_test::randomPose(m, 3);
  CHECK(hawor::forward(loaded, p).vertices == hawor::forward(m, p).vertices);
  // float models from the same file.
  hawor::ManoLoadOptions opt;
  opt.side = hawor::HandSide::Right;
  const auto f = hawor::loadManoPickle<float>(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), opt);
  CHECK((f.vTemplate.cast<double>() - m.vTemplate).cwiseAbs().maxCoeff() < 1e-6);
}

TEST_CASE("mano loader: variants of the object layout", "[hand][loader]") {
  const auto m = hand_test::randomModel<double>(60, {-1, 0, 1, 0, 3, 4}, 3, true, 5);
  hand_test::ModelPickleForm form;
  SECTION("Python-3 bytes") { form.bytes = hand_test::BytesForm::Py3Bytes; }
  SECTION("_codecs.encode bytes") { form.bytes = hand_test::BytesForm::Codecs; }
  SECTION("plain shapedirs, dense J_regressor") {
    form.chumpyShapedirs = false;
    form.sparseRegressor = false;
  }
  SECTION("copy_reg._reconstructor objects") { form.reconstructorForm = true; }
  SECTION("old 'shape' key") { form.shapeKey = "shape"; }
  SECTION("Fortran-ordered weights") { form.fortranWeights = true; }
  SECTION("unused allowlisted noise") {
    form.extraKey = "noise";
    form.extraGlobal = "__builtin__ set";
  }
  const auto loaded = load(hand_test::writeModelPickle(m, form));
  expectSame(loaded, m);
  CHECK(loaded.numKeypoints() == 0);  // not MANO-sized: no 21-keypoint map
}

TEST_CASE("mano loader: no posedirs means no correctives", "[hand][loader]") {
  const auto m = hand_test::randomModel<double>(30, {-1, 0, 1}, 2, true, 6);
  hand_test::ModelPickleForm form;
  form.withPosedirs = false;
  const auto loaded = load(hand_test::writeModelPickle(m, form));
  CHECK(loaded.numPoseFeatures() == 0);
  CHECK(loaded.vTemplate == m.vTemplate);
}

TEST_CASE("mano loader: left models", "[hand][loader]") {
  const auto right = hand_test::randomModel<double>(778, hawor::manoParents(), 10, true, 11);
  const auto left = hawor::mirrorHandModel(right);
  // The released left file: shapedirs x not mirrored, faces as in the right file.
  auto released = left;
  for (int v = 0; v < 778; ++v) released.shapedirs.row(3 * v) = right.shapedirs.row(3 * v);
  released.faces = right.faces;
  released.prepare();
  const std::string bytes = hand_test::writeModelPickle(released);
  const auto* data = reinterpret_cast<const std::uint8_t*>(bytes.data());

  hawor::ManoLoadOptions opt;  // Auto: from the name
  const auto l = hawor::loadManoPickle<double>(data, bytes.size(), opt, "/models/MANO_LEFT.pkl");
  CHECK(l.isLeft);
  CHECK(l.shapedirs == left.shapedirs);
  CHECK(l.faces == left.faces);  // winding [0,2,1]
  const auto p = hand_test::randomPose(right, 12);
  const auto r = hawor::forward(right, p);
  const auto lo = hawor::forward(l, hawor::mirrorPose(p));
  const Eigen::RowVector3d M(-1, 1, 1);
  const hawor::Points3<double> mv = r.vertices.array().rowwise() * M.array();
  CHECK((lo.vertices - mv).cwiseAbs().maxCoeff() < 1e-12);

  opt.fixLeftShapedirs = false;
  opt.flipLeftFaces = false;
  const auto raw = hawor::loadManoPickle<double>(data, bytes.size(), opt, "mano_left.pkl");
  CHECK(raw.isLeft);
  CHECK(raw.shapedirs == released.shapedirs);
  CHECK(raw.faces == released.faces);

  opt = {};
  opt.side = hawor::HandSide::Left;
  CHECK(hawor::loadManoPickle<double>(data, bytes.size(), opt, "model.pkl").isLeft);
  opt.side = hawor::HandSide::Right;
  CHECK(!hawor::loadManoPickle<double>(data, bytes.size(), opt, "MANO_LEFT.pkl").isLeft);
  opt.side = hawor::HandSide::Auto;
  CHECK(!hawor::loadManoPickle<double>(data, bytes.size(), opt, "C:\\x\\MANO_RIGHT.pkl").isLeft);
  CHECK_THROWS_AS(hawor::loadManoPickle<double>(data, bytes.size(), opt, "model.pkl"), hawor::Error);
  CHECK_THROWS_AS(hawor::loadManoPickle<double>(data, bytes.size(), opt, "left_right.pkl"), hawor::Error);
}

TEST_CASE("mano loader: malicious and foreign pickles are refused", "[hand][loader]") {
  // The classic exploit: refused by name, and nothing ran.
  expectLoadError(lit("cos\nsystem\n(S'echo pwned'\ntR."), "os.system");
  expectLoadError(lit("cos\nsystem\n(S'echo pwned'\ntR."), "os.system", false);
  expectLoadError(lit("\x80\x04\x8c\x08" "builtins\x8c\x04" "eval\x93\x8c\x03" "1+1\x85R."),
                  "builtins.eval");
  // A MANO dict with a hostile value: named whether it is interpreted or only present.
  const auto m = hand_test::randomModel<double>(30, {-1, 0, 1}, 2, true, 7);
  hand_test::ModelPickleForm form;
  form.extraKey = "noise";
  form.extraGlobal = "posix system";
  expectLoadError(hand_test::writeModelPickle(m, form), "posix.system");
  CHECK_NOTHROW(load(hand_test::writeModelPickle(m, form), hawor::HandSide::Right, false));
  form.extraKey = "v_template";  // a later duplicate key wins, as in Python
  expectLoadError(hand_test::writeModelPickle(m, form), "posix.system", false);
  // Not a dict / missing keys / wrong shapes.
  expectLoadError(lit("\x80\x02]q\x00."), "expected the dict");
  expectLoadError(lit("}U\x01xK\x01s."), "v_template");
  hand_test::PickleWriter w;
  w.op('}');
  w.mark();
  w.str("v_template");
  hand_test::writeNdarray(w, "f8", '<', {2, 2}, hand_test::rawLE(std::vector<double>{1, 2, 3, 4}));
  w.str("f");
  w.integer(3);
  w.op('u');
  w.stop();
  expectLoadError(w.b, "expected an array");
  // Bytes shorter than the shape needs.
  hand_test::PickleWriter s;
  s.op('}');
  s.mark();
  s.str("v_template");
  hand_test::writeNdarray(s, "f8", '<', {4, 3}, hand_test::rawLE(std::vector<double>{1, 2, 3}));
  s.op('u');
  s.stop();
  expectLoadError(s.b, "bytes");
  // Unsupported dtype.
  hand_test::PickleWriter o;
  o.op('}');
  o.mark();
  o.str("v_template");
  hand_test::writeNdarray(o, "O8", '|', {1, 3}, std::string(24, '\0'));
  o.op('u');
  o.stop();
  expectLoadError(o.b, "object array");
  // A tiny file declaring a huge sparse matrix: refused before densifying.
  hand_test::PickleWriter h;
  h.op('}');
  h.mark();
  h.str("J_regressor");
  hand_test::writeObjectHead(h, "scipy.sparse.csc", "csc_matrix", false);
  h.op('}');
  h.str("_shape");
  h.integer(20000);
  h.integer(20000);
  h.op(0x86);
  h.op('s');
  h.op('b');
  h.str("v_template");
  hand_test::writeNdarray(h, "f8", '<', {1, 3}, hand_test::rawLE(std::vector<double>{1, 2, 3}));
  h.str("f");
  hand_test::writeNdarray(h, "u4", '<', {1, 3}, hand_test::rawLE(std::vector<std::uint32_t>{0, 0, 0}));
  h.op('u');
  h.stop();
  expectLoadError(h.b, "out of range");
}

TEST_CASE("mano loader: truncated and mutated model files", "[hand][loader]") {
  const auto m = hand_test::randomModel<double>(12, {-1, 0, 1}, 2, true, 8);
  const std::string full = hand_test::writeModelPickle(m);
  REQUIRE_NOTHROW(load(full));
  for (std::size_t n = 0; n < full.size(); n += 7) {
    INFO("prefix " << n);
    CHECK_THROWS_AS(load(full.substr(0, n)), hawor::Error);
  }
  std::size_t ok = 0, errors = 0;
  for (std::size_t i = 0; i < full.size(); i += 3) {
    for (unsigned char c : {0x00, 0x7f, 0xff, 0x10}) {
      std::string b = full;
      b[i] = static_cast<char>(c);
      try {
        (void)load(b);
        ++ok;
      } catch (const hawor::Error&) {
        ++errors;
      }
    }
  }
  CHECK(ok + errors > 0);
  CHECK(errors > 0);
}
