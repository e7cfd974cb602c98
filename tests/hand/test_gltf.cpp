// GLB reader and JSON parser: values written by an independent writer come back exactly, and
// malformed, truncated or hostile files fail with hawor::Error (never a crash or a huge
// allocation). Runs natively, in WASM and under ASan/UBSan.
#include <catch2/catch.hpp>

#include <functional>
#include <string>
#include <vector>

#include "gltf_test_util.hpp"
#include "hawor/io/gltf.hpp"
#include "hawor/io/json.hpp"

namespace {

std::string gltfErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const hawor::Error& e) {
    return e.what();
  }
  return "<no error>";
}

hawor::Gltf parseGlb(const std::vector<uint8_t>& b) { return hawor::Gltf::fromGlb(b, "t.glb"); }

std::string glbError(const std::string& json, const std::vector<uint8_t>& bin) {
  return gltfErrorOf([&] { parseGlb(gltf_test::makeGlb(json, bin)); });
}

/// Error of parsing the finger with one JSON edit, and of reading every accessor.
std::string editError(const std::string& from, const std::string& to, const gltf_test::Spec& spec = {}) {
  const gltf_test::Finger f = gltf_test::makeFinger(spec);
  return gltfErrorOf([&] {
    const hawor::Gltf g = parseGlb(gltf_test::makeGlb(gltf_test::replaced(f.json, from, to), f.bin));
    for (size_t i = 0; i < g.accessors().size(); ++i) g.readFloats(static_cast<int>(i));
  });
}

}  // namespace

// --- JSON ----------------------------------------------------------------------------------------

TEST_CASE("json: values, escapes and numbers", "[gltf][json]") {
  const hawor::JsonValue v = hawor::parseJson(
      " {\"a\": [1, -2.5e3, 0.1, 1E-2, -0, 12345678901234567890], \"s\": \"x\\\"\\\\\\/\\b\\f\\n\\r\\t\\u00e9\\ud83d\\ude00\","
      " \"t\": true, \"f\": false, \"n\": null, \"o\": {}} \n");
  REQUIRE(v.isObject());
  const auto& a = v.find("a")->items("a");
  REQUIRE(a.size() == 6);
  CHECK(a[0].asNumber("") == 1.0);
  CHECK(a[1].asNumber("") == -2500.0);
  CHECK(a[2].asNumber("") == 0.1);  // correctly rounded, like Python's float('0.1')
  CHECK(a[3].asNumber("") == 0.01);
  CHECK(a[4].asNumber("") == 0.0);
  CHECK(a[5].asNumber("") == 12345678901234567890.0);
  CHECK(v.find("s")->asString("") == std::string("x\"\\/\b\f\n\r\t\xC3\xA9\xF0\x9F\x98\x80"));
  CHECK(v.find("t")->asBool(""));
  CHECK(!v.find("f")->asBool(""));
  CHECK(v.find("n")->isNull());
  CHECK(v.find("o")->size() == 0);
  CHECK(v.find("missing") == nullptr);
  CHECK(hawor::parseJson("1e-400").asNumber("") == 0.0);  // underflow is zero
  CHECK(hawor::parseJson("0.03912608325481415").asNumber("") == 0.03912608325481415);
  CHECK(hawor::parseJson("[]").items("").empty());
}

TEST_CASE("json: jsonQuote writes literals that parse back to the same bytes", "[gltf][json]") {
  const std::vector<std::string> samples = {"", "plain", "a \"quoted\" word", "back\\slash", std::string("nul\0in", 6),
                                            "tab\tnew\nline\r\x01\x1f", "caf\xc3\xa9 \xe2\x9c\x93", "/slash/"};
  for (const std::string& s : samples) {
    const std::string lit = hawor::jsonQuote(s);
    INFO(lit);
    CHECK(lit.front() == '"');
    CHECK(lit.back() == '"');
    for (char c : lit) CHECK(static_cast<unsigned char>(c) >= 0x20);  // no raw control character
    CHECK(hawor::parseJson(lit).asString("sample") == s);
  }
}

TEST_CASE("json: malformed documents are errors", "[gltf][json]") {
  const char* bad[] = {"",         "  ",        "{",           "[1,]",       "[1 2]",      "{\"a\" 1}",  "{\"a\":1,}",
                       "{a:1}",    "01",        "1.",          ".5",         "-",          "1e",         "+1",
                       "tru",      "nul",       "\"abc",       "\"\\x\"",    "\"\\u12G4\"", "\"\\ud800\"", "\"\\udc00\"",
                       "\"a\nb\"", "[1] x",     "{\"a\":1,\"a\":2}", "1e400",   "-1e400",     "NaN",        "[\"\\u00\"]",
                       "\xEF\xBB\xBF{}", "{\"a\":[1,2}"};
  for (const char* s : bad) {
    INFO("input: " << s);
    const std::string e = gltfErrorOf([&] { hawor::parseJson(s, "doc"); });
    CHECK(e.find("hawor: doc") == 0);
  }
  CHECK(gltfErrorOf([] { hawor::parseJson("{\"a\":1,\"a\":2}"); }).find("duplicate key \"a\"") != std::string::npos);
  CHECK(gltfErrorOf([] { hawor::parseJson("[1 2]"); }).find("at byte 3") != std::string::npos);
}

TEST_CASE("json: depth, size and value-count limits", "[gltf][json]") {
  const std::string deep(100000, '[');
  CHECK(gltfErrorOf([&] { hawor::parseJson(deep); }).find("nesting deeper than 64") != std::string::npos);
  std::string ok = std::string(64, '[') + std::string(64, ']');
  CHECK_NOTHROW(hawor::parseJson(ok));
  std::string tooDeep = std::string(65, '[') + std::string(65, ']');
  CHECK_THROWS_AS(hawor::parseJson(tooDeep), hawor::Error);
  std::string objDeep;
  for (int i = 0; i < 70; ++i) objDeep += "{\"a\":";
  objDeep += "1" + std::string(70, '}');
  CHECK_THROWS_AS(hawor::parseJson(objDeep), hawor::Error);
  hawor::JsonLimits lim;
  lim.maxValues = 10;
  CHECK(gltfErrorOf([&] { hawor::parseJson("[1,2,3,4,5,6,7,8,9,10]", "doc", lim); }).find("more than 10 values") != std::string::npos);
  CHECK_NOTHROW(hawor::parseJson("[1,2,3,4,5,6,7,8,9]", "doc", lim));
  lim.maxBytes = 4;
  CHECK_THROWS_AS(hawor::parseJson("[1,2]", "doc", lim), hawor::Error);
}

TEST_CASE("json: typed access names the value", "[gltf][json]") {
  const hawor::JsonValue v = hawor::parseJson("{\"a\":\"s\"}");
  CHECK(gltfErrorOf([&] { v.find("a")->asNumber("f.glb: nodes[0].a"); }) ==
        "hawor: f.glb: nodes[0].a must be a number, found a string");
  CHECK_THROWS_AS(v.items("x"), hawor::Error);
}

// --- GLB reader: valid files ----------------------------------------------------------------------

TEST_CASE("gltf: the finger reads back exactly in every encoding", "[gltf]") {
  for (int weights : {5126, 5121, 5123}) {
    for (int indices : {5121, 5123, 5125}) {
      for (bool interleaved : {false, true}) {
        for (bool matrix : {false, true}) {
          gltf_test::Spec spec;
          spec.weights = weights;
          spec.indices = indices;
          spec.joints = indices == 5125 ? 5123 : 5121;
          spec.interleaved = interleaved;
          spec.armatureMatrix = matrix;
          INFO("weights " << weights << " indices " << indices << " interleaved " << interleaved << " matrix " << matrix);
          const gltf_test::Finger f = gltf_test::makeFinger(spec);
          const hawor::Gltf g = parseGlb(f.glb());
          REQUIRE(g.nodes().size() == 5);
          REQUIRE(g.meshes().size() == 1);
          REQUIRE(g.skins().size() == 1);
          const hawor::GltfPrimitive& p = g.meshes()[0].primitives[0];
          const std::vector<double> pos = g.readFloats(p.attribute("POSITION"));
          REQUIRE(pos.size() == 48);
          for (int v = 0; v < 16; ++v) {
            for (int c = 0; c < 3; ++c) CHECK(pos[static_cast<size_t>(3 * v + c)] == f.positions(v, c));
          }
          const std::vector<double> nrm = g.readFloats(p.attribute("NORMAL"));
          for (int v = 0; v < 16; ++v) CHECK(nrm[static_cast<size_t>(3 * v + 1)] == 1.0);
          const std::vector<double> w = g.readFloats(p.attribute("WEIGHTS_0"));
          const std::vector<uint32_t> j = g.readUints(p.attribute("JOINTS_0"));
          for (int v = 0; v < 16; ++v) {
            for (int k = 0; k < 4; ++k) {
              CHECK(w[static_cast<size_t>(4 * v + k)] == f.weightsDecoded(v, k));
              CHECK(j[static_cast<size_t>(4 * v + k)] == static_cast<uint32_t>(f.jointIds(v, k)));
            }
          }
          const std::vector<uint32_t> idx = g.readUints(p.indices);
          REQUIRE(idx.size() == f.indices.size());
          for (size_t i = 0; i < idx.size(); ++i) CHECK(idx[i] == static_cast<uint32_t>(f.indices[i]));
          const std::vector<double> m = g.readFloats(g.skins()[0].inverseBindMatrices);
          REQUIRE(m.size() == 48);
          for (int k = 0; k < 3; ++k) {
            for (int c = 0; c < 4; ++c) {
              for (int r = 0; r < 4; ++r) CHECK(m[static_cast<size_t>(16 * k + 4 * c + r)] == static_cast<double>(f.ibm[static_cast<size_t>(k)](r, c)));
            }
          }
          // Node world transforms: armature, then the chain root -> mid -> tip.
          CHECK((g.nodeWorld(0) - f.armature).cwiseAbs().maxCoeff() < 1e-15);
          for (int k = 0; k < 3; ++k) {
            CHECK((g.nodeWorld(2 + k) - f.jointWorld[static_cast<size_t>(k)]).cwiseAbs().maxCoeff() < 1e-15);
          }
          CHECK(g.nodes()[3].parent == 2);
          CHECK(g.nodes()[1].parent == 0);
          CHECK(g.nodes()[0].parent == -1);
          CHECK(g.findNode("tip") == 4);
          CHECK(g.findNode("nope") == -1);
        }
      }
    }
  }
}

TEST_CASE("gltf: matrices with padded columns, signed normalized, bufferView-less accessors", "[gltf]") {
  // MAT2 of UNSIGNED_BYTE: each 2-byte column padded to 4 bytes (8 bytes per element);
  // VEC2 of normalized BYTE (−128 clamps to −1); an accessor without bufferView is zeros.
  std::vector<uint8_t> bin = {1, 2, 0, 0, 3, 4, 0, 0, 5, 6, 0, 0, 7, 8, 0, 0, 0x80, 0x7F, 0x81, 0x00};
  const std::string json =
      "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":20}],"
      "\"bufferViews\":[{\"buffer\":0,\"byteLength\":16},{\"buffer\":0,\"byteOffset\":16,\"byteLength\":4}],"
      "\"accessors\":[{\"bufferView\":0,\"componentType\":5121,\"count\":2,\"type\":\"MAT2\"},"
      "{\"bufferView\":1,\"componentType\":5120,\"normalized\":true,\"count\":2,\"type\":\"VEC2\"},"
      "{\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
      "{\"bufferView\":1,\"componentType\":5122,\"count\":1,\"type\":\"VEC2\"}]}";
  const hawor::Gltf g = parseGlb(gltf_test::makeGlb(json, bin));
  CHECK(g.readFloats(0) == std::vector<double>{1, 2, 3, 4, 5, 6, 7, 8});
  const std::vector<double> sn = g.readFloats(1);
  CHECK(sn[0] == -1.0);
  CHECK(sn[1] == 1.0);
  CHECK(sn[2] == -127.0 / 127.0);
  CHECK(sn[3] == 0.0);
  CHECK(g.readFloats(2) == std::vector<double>(9, 0.0));
  CHECK(g.readFloats(3) == std::vector<double>{static_cast<double>(int16_t(0x7F80)), 0x81});
  CHECK(gltfErrorOf([&] { g.readUints(1); }).find("expected an unsigned integer type") != std::string::npos);
  CHECK_THROWS_AS(g.readFloats(7), hawor::Error);
  CHECK_THROWS_AS(g.nodeWorld(0), hawor::Error);
}

TEST_CASE("gltf: unknown chunks are skipped, trailing padding and NULs in the JSON chunk", "[gltf]") {
  const gltf_test::Finger f = gltf_test::makeFinger();
  std::vector<uint8_t> b = f.glb();
  // Append an unknown chunk and fix the total length.
  const uint32_t extra = 8 + 4;
  b.insert(b.end(), {4, 0, 0, 0, 'X', 'T', 'R', 'A', 1, 2, 3, 4});
  const uint32_t total = static_cast<uint32_t>(b.size());
  for (int i = 0; i < 4; ++i) b[static_cast<size_t>(8 + i)] = static_cast<uint8_t>(total >> (8 * i));
  (void)extra;
  CHECK_NOTHROW(parseGlb(b));
  // JSON chunk padded with NULs instead of spaces.
  std::string json = f.json;
  std::vector<uint8_t> j(json.begin(), json.end());
  while (j.size() % 4) j.push_back(0);
  j.push_back(0);
  j.push_back(0);
  j.push_back(0);
  j.push_back(0);
  std::vector<uint8_t> out;
  gltf_test::put32(out, 0x46546C67u);
  gltf_test::put32(out, 2);
  gltf_test::put32(out, static_cast<uint32_t>(12 + 8 + j.size() + 8 + f.bin.size()));
  gltf_test::put32(out, static_cast<uint32_t>(j.size()));
  gltf_test::put32(out, 0x4E4F534Au);
  out.insert(out.end(), j.begin(), j.end());
  gltf_test::put32(out, static_cast<uint32_t>(f.bin.size()));
  gltf_test::put32(out, 0x004E4942u);
  out.insert(out.end(), f.bin.begin(), f.bin.end());
  CHECK_NOTHROW(parseGlb(out));
}

// --- GLB reader: malformed files --------------------------------------------------------------------

TEST_CASE("gltf: container errors", "[gltf][malformed]") {
  const gltf_test::Finger f = gltf_test::makeFinger();
  const std::vector<uint8_t> good = f.glb();
  CHECK(gltfErrorOf([] { parseGlb({}); }).find("too short for a GLB header") != std::string::npos);
  std::vector<uint8_t> b = good;
  b[0] = 'x';
  CHECK(gltfErrorOf([&] { parseGlb(b); }).find("not a binary glTF file") != std::string::npos);
  const std::string text = "{\"asset\":{\"version\":\"2.0\"}}";
  CHECK(gltfErrorOf([&] { parseGlb(std::vector<uint8_t>(text.begin(), text.end())); }).find("looks like a .gltf JSON file") !=
        std::string::npos);
  b = good;
  b[4] = 1;
  CHECK(gltfErrorOf([&] { parseGlb(b); }).find("version 1 is not supported") != std::string::npos);
  b = good;
  b[8] += 4;  // declared length beyond the data
  CHECK(gltfErrorOf([&] { parseGlb(b); }).find("truncated") != std::string::npos);
  b = good;
  b[12] = 0xFF;  // JSON chunk length lies
  b[13] = 0xFF;
  CHECK(gltfErrorOf([&] { parseGlb(b); }).find("declares") != std::string::npos);
  b = good;
  b[16] = 'B';  // first chunk not JSON
  CHECK(gltfErrorOf([&] { parseGlb(b); }).find("first chunk is not the JSON chunk") != std::string::npos);
  // BIN chunk length lies (too long).
  b = good;
  const size_t jl = static_cast<size_t>(b[12]) | static_cast<size_t>(b[13]) << 8;
  const size_t binHeader = 20 + jl;
  b[binHeader + 2] = 0x10;
  CHECK(gltfErrorOf([&] { parseGlb(b); }).find("remain") != std::string::npos);
  // No BIN chunk although buffer 0 needs it.
  CHECK(gltfErrorOf([&] { parseGlb(gltf_test::makeGlb(f.json, f.bin, false)); }).find("the file has none") != std::string::npos);
  // BIN chunk shorter than buffer 0.
  std::vector<uint8_t> shortBin(f.bin.begin(), f.bin.end() - 8);
  CHECK(gltfErrorOf([&] { parseGlb(gltf_test::makeGlb(f.json, shortBin)); }).find("exceeds the") != std::string::npos);
  // JSON garbage and a JSON array at top level.
  CHECK(glbError("{\"asset\":", f.bin).find("JSON chunk") != std::string::npos);
  CHECK(glbError("[1,2,3]", f.bin).find("expected an object") != std::string::npos);
  CHECK(glbError(std::string(5000, '['), f.bin).find("nesting deeper") != std::string::npos);
  CHECK(glbError("{}", f.bin).find("no 'asset'") != std::string::npos);
  CHECK(glbError("{\"asset\":{\"version\":\"1.0\"}}", f.bin).find("not supported") != std::string::npos);
  CHECK(glbError("{\"asset\":{\"version\":\"2.0\"},\"extensionsRequired\":[\"KHR_draco_mesh_compression\"]}", f.bin)
            .find("KHR_draco_mesh_compression") != std::string::npos);
  // A JSON chunk over the configured limit.
  hawor::GltfLimits lim;
  lim.json.maxBytes = 100;
  CHECK(gltfErrorOf([&] { hawor::Gltf::fromGlb(good, "t.glb", lim); }).find("over the limit") != std::string::npos);
}

TEST_CASE("gltf: document errors name the object", "[gltf][malformed]") {
  struct Case {
    const char* from;
    const char* to;
    const char* expect;
  };
  const Case cases[] = {
      {"\"count\":16,\"type\":\"VEC3\"", "\"count\":17,\"type\":\"VEC3\"", "accessors[0] needs"},
      {"\"count\":16,\"type\":\"VEC3\"", "\"count\":4294967295,\"type\":\"VEC3\"", "over the limit"},
      {"\"count\":16,\"type\":\"VEC3\"", "\"count\":1e300,\"type\":\"VEC3\"", "must be an integer"},
      {"\"count\":16,\"type\":\"VEC3\"", "\"count\":-1,\"type\":\"VEC3\"", "must be an integer"},
      {"\"count\":16,\"type\":\"VEC3\"", "\"count\":1.5,\"type\":\"VEC3\"", "must be an integer"},
      {"\"count\":16,\"type\":\"VEC3\"", "\"count\":0,\"type\":\"VEC3\"", "count must be at least 1"},
      {"\"count\":16,\"type\":\"VEC3\"", "\"count\":\"16\",\"type\":\"VEC3\"", "must be a number"},
      {"\"count\":16,\"type\":\"VEC3\"", "\"count\":16,\"type\":\"VEC5\"", "not a glTF accessor type"},
      {"\"componentType\":5126,\"count\":16", "\"componentType\":5127,\"count\":16", "not a glTF component type"},
      {"\"componentType\":5126,\"count\":16", "\"componentType\":5126,\"normalized\":true,\"count\":16", "normalized with component type FLOAT"},
      {"{\"bufferView\":0,\"componentType\":5126", "{\"bufferView\":99,\"componentType\":5126", "missing bufferView"},
      {"{\"bufferView\":0,\"componentType\":5126", "{\"bufferView\":0,\"byteOffset\":4,\"componentType\":5126", "accessors[0] needs"},
      {"{\"bufferView\":0,\"componentType\":5126", "{\"bufferView\":0,\"sparse\":{},\"componentType\":5126", "sparse"},
      {"{\"buffer\":0,\"byteOffset\":0,\"byteLength\":192}", "{\"buffer\":0,\"byteOffset\":0,\"byteLength\":999999}", "bufferViews[0]"},
      {"{\"buffer\":0,\"byteOffset\":0,\"byteLength\":192}", "{\"buffer\":1,\"byteOffset\":0,\"byteLength\":192}", "missing buffer"},
      {"{\"buffer\":0,\"byteOffset\":0,\"byteLength\":192}", "{\"buffer\":0,\"byteOffset\":0,\"byteLength\":192,\"byteStride\":3}", "byteStride 3"},
      {"{\"buffer\":0,\"byteOffset\":0,\"byteLength\":192}", "{\"buffer\":0,\"byteOffset\":0,\"byteLength\":192,\"byteStride\":8}", "smaller than the 12-byte element"},
      {"{\"buffer\":0,\"byteOffset\":0,\"byteLength\":192}", "{\"buffer\":0,\"byteOffset\":0,\"byteLength\":192,\"byteStride\":256}", "byteStride"},
      {"{\"buffer\":0,\"byteOffset\":0,\"byteLength\":192}", "{\"buffer\":0,\"byteOffset\":0,\"byteLength\":0}", "at least 1"},
      {"{\"buffer\":0,\"byteOffset\":0,\"byteLength\":192}", "{\"byteOffset\":0,\"byteLength\":192}", "has no 'buffer'"},
      {"\"buffers\":[{\"byteLength\":", "\"buffers\":[{\"uri\":\"x.bin\",\"byteLength\":", "not supported"},
      {"\"buffers\":[{", "\"buffers\":[7,{", "must be an object"},
      {"\"children\":[1,2]", "\"children\":[1,2,2]", "two parents"},
      {"\"children\":[1,2]", "\"children\":[1,2,0]", "lists itself"},
      {"\"children\":[1,2]", "\"children\":[1,2,9]", "missing node"},
      {"\"name\":\"tip\",", "\"name\":\"tip\",\"children\":[0],", "cycle"},
      {"\"name\":\"tip\",", "\"name\":\"tip\",\"matrix\":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1],", "both a matrix"},
      {"\"name\":\"tip\",", "\"name\":\"tip\",\"scale\":[1,1],", "expected 3"},
      {"\"name\":\"mesh\",\"mesh\":0", "\"name\":\"mesh\",\"mesh\":3", "missing mesh"},
      {"\"skin\":0,", "\"skin\":2,", "missing skin"},
      {"\"name\":\"mesh\",\"mesh\":0,", "\"name\":\"mesh\",", "has a skin but no mesh"},
      {"\"joints\":[", "\"joints\":[2,", "lists a node twice"},
      {"\"joints\":[", "\"joints\":[70,", "missing node"},
      {"\"joints\":[2,3,4]", "\"joints\":[]", "joints is empty"},
      {"\"joints\":[2,3,4]", "\"joints\":[2,3,4,1]", "3 matrices for 4 joints"},
      {"\"inverseBindMatrices\":5", "\"inverseBindMatrices\":0", "FLOAT MAT4"},
      {"\"indices\":4", "\"indices\":50", "missing accessor"},
      {"\"POSITION\":0", "\"POSITION\":80", "missing accessor"},
      {"\"primitives\":[", "\"primitives\":[7,", "must be an object"},
      {"\"primitives\":[{\"attributes\":{", "\"primitives\":[{\"attributes\":[],\"x\":{", "must be an object"},
      {"\"mode\":4", "\"mode\":9", "mode"},
  };
  for (const Case& c : cases) {
    INFO("edit " << c.from << " -> " << c.to);
    const std::string e = editError(c.from, c.to);
    INFO("error: " << e);
    CHECK(e.find("hawor: t.glb: ") == 0);
    CHECK(e.find(c.expect) != std::string::npos);
  }
  // Rotation quaternion of zero length.
  gltf_test::Spec trs;
  trs.armatureMatrix = false;
  CHECK(editError("\"rotation\":[0,0,", "\"rotation\":[0,0,0,0],\"x\":[0,0,", trs).find("unit quaternion") != std::string::npos);
  CHECK(editError("\"matrix\":[", "\"matrix\":[1e999,").find("out of the range") != std::string::npos);
}

TEST_CASE("gltf: every truncation of a valid file is an error", "[gltf][malformed]") {
  const std::vector<uint8_t> good = gltf_test::makeFinger().glb();
  REQUIRE_NOTHROW(parseGlb(good));
  for (size_t n = 0; n < good.size(); ++n) {
    const std::vector<uint8_t> prefix(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(n));
    const std::string e = gltfErrorOf([&] { parseGlb(prefix); });
    INFO("prefix " << n << ": " << e);
    CHECK(e.find("hawor: t.glb: ") == 0);
  }
}

TEST_CASE("gltf: random byte corruption never escapes as anything but hawor::Error", "[gltf][malformed]") {
  const std::vector<uint8_t> good = gltf_test::makeFinger().glb();
  uint32_t state = 12345;
  auto next = [&] {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  int errors = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    std::vector<uint8_t> b = good;
    const int flips = 1 + static_cast<int>(next() % 4);
    for (int k = 0; k < flips; ++k) b[next() % b.size()] = static_cast<uint8_t>(next());
    try {
      const hawor::Gltf g = parseGlb(b);
      for (size_t i = 0; i < g.accessors().size(); ++i) {
        g.readFloats(static_cast<int>(i));
        try {
          g.readUints(static_cast<int>(i));
        } catch (const hawor::Error&) {
        }
      }
      for (size_t i = 0; i < g.nodes().size(); ++i) g.nodeWorld(static_cast<int>(i));
    } catch (const hawor::Error&) {
      ++errors;
    }
  }
  CHECK(errors > 0);
}
