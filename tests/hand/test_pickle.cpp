// The symbolic pickle reader: every opcode form on hand-written byte strings, and malformed,
// truncated and malicious inputs (all must end in hawor::Error, never in a crash).
#include <catch2/catch.hpp>

#include "hand_test_util.hpp"
#include "hawor/hand/pickle.hpp"

#include <string>

using hawor::pickle::Kind;
using hawor::pickle::parse;

namespace {

std::string B(const char* s, std::size_t n) { return std::string(s, n); }
#define PK(lit) B(lit, sizeof(lit) - 1)

// Parses and returns a copy of the root's description plus checks via a callback.
template <typename F>
void withRoot(const std::string& bytes, F&& check) {
  const hawor::pickle::Document doc = parse(bytes);
  check(doc.root());
}

void expectError(const std::string& bytes, const std::string& fragment = "") {
  try {
    (void)parse(bytes);
    FAIL("no error for input of " << bytes.size() << " bytes");
  } catch (const hawor::Error& e) {
    if (!fragment.empty()) {
      INFO(e.what());
      CHECK(std::string(e.what()).find(fragment) != std::string::npos);
    }
    CHECK(std::string(e.what()).find("byte offset") != std::string::npos);
  }
}

}  // namespace

TEST_CASE("pickle: scalars in every opcode form", "[hand][pickle]") {
  withRoot(PK("N."), [](auto v) { CHECK(v.isNone()); });
  withRoot(PK("I42\n."), [](auto v) { CHECK(v.asInt() == 42); CHECK(v.is(Kind::Int)); });
  withRoot(PK("I-7\n."), [](auto v) { CHECK(v.asInt() == -7); });
  withRoot(PK("I01\n."), [](auto v) { CHECK(v.is(Kind::Bool)); CHECK(v.asBool()); });
  withRoot(PK("I00\n."), [](auto v) { CHECK(v.is(Kind::Bool)); CHECK(!v.asBool()); });
  withRoot(PK("L123456789012L\n."), [](auto v) { CHECK(v.asInt() == 123456789012LL); });
  withRoot(PK("L-9223372036854775808\n."), [](auto v) { CHECK(v.asInt() == INT64_MIN); });
  withRoot(PK("F1.5\n."), [](auto v) { CHECK(v.asFloat() == 1.5); });
  withRoot(PK("F-2.5e-3\n."), [](auto v) { CHECK(v.asFloat() == -2.5e-3); });
  withRoot(PK("Fnan\n."), [](auto v) { CHECK(std::isnan(v.asFloat())); });
  withRoot(PK("Finf\n."), [](auto v) { CHECK(std::isinf(v.asFloat())); });
  withRoot(PK("J\xff\xff\xff\xff."), [](auto v) { CHECK(v.asInt() == -1); });
  withRoot(PK("K\xfe."), [](auto v) { CHECK(v.asInt() == 254); });
  withRoot(PK("M\x01\x02."), [](auto v) { CHECK(v.asInt() == 0x0201); });
  withRoot(PK("G\x3f\xf8\x00\x00\x00\x00\x00\x00."), [](auto v) { CHECK(v.asFloat() == 1.5); });
  withRoot(PK("\x80\x02\x88."), [](auto v) { CHECK(v.asBool()); });
  withRoot(PK("\x80\x02\x89."), [](auto v) { CHECK(!v.asBool()); CHECK(v.asInt() == 0); });
  // LONG1 / LONG4: little-endian two's complement.
  withRoot(PK("\x8a\x00."), [](auto v) { CHECK(v.asInt() == 0); });
  withRoot(PK("\x8a\x01\xff."), [](auto v) { CHECK(v.asInt() == -1); });
  withRoot(PK("\x8a\x02\xff\x7f."), [](auto v) { CHECK(v.asInt() == 32767); });
  withRoot(PK("\x8a\x05\xff\xff\xff\xff\x00."), [](auto v) { CHECK(v.asInt() == 4294967295LL); });
  withRoot(PK("\x8a\x09\xfe\xff\xff\xff\xff\xff\xff\xff\xff."), [](auto v) { CHECK(v.asInt() == -2); });
  withRoot(PK("\x8b\x02\x00\x00\x00\x00\x01."), [](auto v) { CHECK(v.asInt() == 256); });
}

TEST_CASE("pickle: strings in every opcode form", "[hand][pickle]") {
  // Python-2 str forms are Bytes; unicode forms are Str (UTF-8).
  withRoot(PK("S'ab\\x41\\n\\'\\\\'\n."), [](auto v) {
    CHECK(v.is(Kind::Bytes));
    CHECK(v.asString() == "abA\n'\\");
  });
  withRoot(PK("S\"q\\101\\7z\"\n."), [](auto v) { CHECK(v.asString() == std::string("qA\x07z")); });
  withRoot(PK("T\x03\x00\x00\x00" "abc."), [](auto v) { CHECK(v.is(Kind::Bytes)); CHECK(v.asString() == "abc"); });
  withRoot(PK("U\x02hi."), [](auto v) { CHECK(v.is(Kind::Bytes)); CHECK(v.asString() == "hi"); });
  withRoot(PK("U\x00."), [](auto v) { CHECK(v.asString().empty()); });
  withRoot(PK("V\\u00e9x\\U0001F600\n."), [](auto v) {
    CHECK(v.is(Kind::Str));
    CHECK(v.asString() == "\xc3\xa9x\xf0\x9f\x98\x80");
  });
  withRoot(PK("V\xe9\n."), [](auto v) { CHECK(v.asString() == "\xc3\xa9"); });  // latin-1 byte
  withRoot(PK("X\x02\x00\x00\x00hi."), [](auto v) { CHECK(v.is(Kind::Str)); CHECK(v.asString() == "hi"); });
  withRoot(PK("\x8c\x03" "abc."), [](auto v) { CHECK(v.is(Kind::Str)); CHECK(v.asString() == "abc"); });
  withRoot(PK("\x8d\x01\x00\x00\x00\x00\x00\x00\x00z."), [](auto v) { CHECK(v.asString() == "z"); });
  withRoot(PK("C\x01z."), [](auto v) { CHECK(v.is(Kind::Bytes)); CHECK(v.asString() == "z"); });
  withRoot(PK("B\x02\x00\x00\x00\x00\xff."), [](auto v) { CHECK(v.asString() == std::string("\x00\xff", 2)); });
  withRoot(PK("\x8e\x01\x00\x00\x00\x00\x00\x00\x00y."), [](auto v) { CHECK(v.is(Kind::Bytes)); });
  withRoot(PK("\x96\x01\x00\x00\x00\x00\x00\x00\x00w."), [](auto v) { CHECK(v.asString() == "w"); });
}

TEST_CASE("pickle: containers, marks and the memo", "[hand][pickle]") {
  withRoot(PK("(K\x01K\x02t."), [](auto v) {
    REQUIRE(v.is(Kind::Tuple));
    REQUIRE(v.size() == 2);
    CHECK(v[1].asInt() == 2);
  });
  withRoot(PK(")."), [](auto v) { CHECK(v.size() == 0); });
  withRoot(PK("K\x01\x85."), [](auto v) { CHECK(v.size() == 1); });
  withRoot(PK("K\x01K\x02\x86."), [](auto v) { CHECK(v[0].asInt() == 1); });
  withRoot(PK("K\x01K\x02K\x03\x87."), [](auto v) { CHECK(v[2].asInt() == 3); });
  withRoot(PK("]K\x01" "aK\x02" "a."), [](auto v) { CHECK(v.is(Kind::List)); CHECK(v.size() == 2); });
  withRoot(PK("](K\x01K\x02K\x03" "e."), [](auto v) { CHECK(v.size() == 3); });
  withRoot(PK("(K\x01l."), [](auto v) { CHECK(v.is(Kind::List)); CHECK(v.size() == 1); });
  withRoot(PK("}U\x01" "aK\x01s."), [](auto v) { CHECK(v.at("a").asInt() == 1); });
  withRoot(PK("}(U\x01" "aK\x01X\x01\x00\x00\x00" "bK\x02U\x01" "aK\x03u."), [](auto v) {
    CHECK(v.size() == 3);
    CHECK(v.at("a").asInt() == 3);  // the last write wins, as in Python
    CHECK(v.at("b").asInt() == 2);  // unicode keys match too
    CHECK(!v.has("c"));
    CHECK_THROWS_AS(v.at("c"), hawor::Error);
  });
  withRoot(PK("(U\x01" "aK\x01" "d."), [](auto v) { CHECK(v.is(Kind::Dict)); CHECK(v.dictKey(0).asString() == "a"); });
  withRoot(PK("\x8f(K\x01K\x02\x90."), [](auto v) { CHECK(v.is(Kind::Set)); CHECK(v.size() == 2); });
  withRoot(PK("(K\x01\x91."), [](auto v) { CHECK(v.is(Kind::FrozenSet)); });
  // DUP, POP, POP_MARK; POP on an empty segment drops the MARK.
  withRoot(PK("(K\x01" "2t."), [](auto v) { CHECK(v.size() == 2); CHECK(v[1].asInt() == 1); });
  withRoot(PK("K\x01K\x02" "0."), [](auto v) { CHECK(v.asInt() == 1); });
  withRoot(PK("K\x01(K\x02K\x03" "1."), [](auto v) { CHECK(v.asInt() == 1); });
  withRoot(PK("K\x01(0."), [](auto v) { CHECK(v.asInt() == 1); });
  // Memo in all forms; shared references are the same node, mutation is visible.
  withRoot(PK("]q\x00K\x05" "ah\x00\x86."), [](auto v) {
    REQUIRE(v.size() == 2);
    CHECK(v[0].index() == v[1].index());
    CHECK(v[0].size() == 1);
  });
  withRoot(PK("K\x05p3\n0g3\n."), [](auto v) { CHECK(v.asInt() == 5); });
  withRoot(PK("K\x07r\x10\x00\x00\x00" "0j\x10\x00\x00\x00."), [](auto v) { CHECK(v.asInt() == 7); });
  withRoot(PK("\x80\x04K\x09\x94" "0h\x00."), [](auto v) { CHECK(v.asInt() == 9); });
  // A list that contains itself (a cycle) is representable.
  withRoot(PK("]q\x00h\x00" "a."), [](auto v) { CHECK(v[0].index() == v.index()); });
  // PROTO, FRAME, trailing bytes after STOP.
  {
    const auto doc = parse(PK("\x80\x04\x95\x02\x00\x00\x00\x00\x00\x00\x00N.garbage"));
    CHECK(doc.protocol() == 4);
    CHECK(doc.root().isNone());
    CHECK(doc.endOffset() == 13);
  }
}

TEST_CASE("pickle: globals and object records are inert", "[hand][pickle]") {
  // The classic exploit parses into a record; nothing runs.
  withRoot(PK("cos\nsystem\n(S'echo pwned'\ntR."), [](auto v) {
    REQUIRE(v.is(Kind::Reduce));
    CHECK(v.callable().is(Kind::Global));
    CHECK(v.callable().qualifiedName() == "os.system");
    CHECK(v.args()[0].asString() == "echo pwned");
    CHECK(v.describe() == "call of os.system");
    CHECK(!v.hasState());
  });
  withRoot(PK("\x8c\x02os\x8c\x06system\x93."), [](auto v) {
    CHECK(v.module() == "os");
    CHECK(v.name() == "system");
  });
  withRoot(PK("cfoo\nBar\n)\x81}U\x01xK\x01sb."), [](auto v) {
    REQUIRE(v.is(Kind::NewObj));
    CHECK(v.callable().name() == "Bar");
    REQUIRE(v.hasState());
    CHECK(v.state().at("x").asInt() == 1);
    CHECK(v.describe() == "object of foo.Bar");
  });
  withRoot(PK("(K\x01ifoo\nBar\n."), [](auto v) {
    REQUIRE(v.is(Kind::NewObj));
    CHECK(v.callable().qualifiedName() == "foo.Bar");
    CHECK(v.args()[0].asInt() == 1);
  });
  withRoot(PK("(cfoo\nBar\nK\x01o."), [](auto v) {
    REQUIRE(v.is(Kind::NewObj));
    CHECK(v.args().size() == 1);
  });
  withRoot(PK("cfoo\nBar\n)}\x92."), [](auto v) { CHECK(v.is(Kind::NewObj)); });
  // BUILD on a memoised object is visible through the memo (in-place, as in Python).
  withRoot(PK("cfoo\nBar\n)\x81q\x01}b0h\x01."), [](auto v) { CHECK(v.hasState()); });
}

TEST_CASE("pickle: accessor misuse throws", "[hand][pickle]") {
  withRoot(PK("U\x01x."), [](auto v) {
    CHECK_THROWS_AS(v.asInt(), hawor::Error);
    CHECK_THROWS_AS(v.size(), hawor::Error);
    CHECK_THROWS_AS(v[0], hawor::Error);
    CHECK_THROWS_AS(v.module(), hawor::Error);
    CHECK_THROWS_AS(v.callable(), hawor::Error);
    CHECK_THROWS_AS(v.state(), hawor::Error);
  });
  withRoot(PK("(K\x01t."), [](auto v) { CHECK_THROWS_AS(v[1], hawor::Error); });
  CHECK_THROWS_AS(hawor::pickle::Value().kind(), hawor::Error);
}

TEST_CASE("pickle: malformed input is a hawor::Error with the offset", "[hand][pickle]") {
  expectError("", "no STOP");
  expectError(PK("N"), "no STOP");
  expectError(PK("\xff."), "unknown opcode 0xff");
  expectError(PK("."), "stack underflow");
  expectError(PK("K\x01(."), "stack underflow");  // STOP cannot pop below a MARK
  expectError(PK("]a."), "stack underflow");
  expectError(PK("K\x01t."), "MARK");
  expectError(PK("1."), "MARK");
  expectError(PK("0."), "MARK");
  expectError(PK("h\x05."), "memo key 5");
  expectError(PK("g12\n."), "memo key 12");
  expectError(PK("gx\n."), "integer");
  expectError(PK("p-1\nN."), "negative memo key");
  expectError(PK("q\x00."), "stack underflow");
  expectError(PK("\x94."), "stack underflow");
  expectError(PK("Pid\n."), "persistent");
  expectError(PK("N\x82\x01."), "extension");
  expectError(PK("\x97."), "out-of-band");
  expectError(PK("\x80\x06N."), "protocol 6");
  expectError(PK("]Nb."), "BUILD on a list");
  expectError(PK("}K\x01" "a."), "APPEND on a dict");
  expectError(PK("]K\x01K\x02s."), "SETITEM on a list");
  expectError(PK("(K\x01" "d."), "odd");
  expectError(PK("}(K\x01u."), "odd");
  expectError(PK("K\x01\x90."), "MARK");
  expectError(PK("(o."), "OBJ without a class");
  expectError(PK("K\x01K\x02\x93."), "STACK_GLOBAL");
  expectError(PK("Sabc\n."), "quoted");
  expectError(PK("S'\\x4'\n."), "\\x escape");
  expectError(PK("S'abc\\'\n."), "backslash");
  expectError(PK("V\\u12\n."), "\\u escape");
  expectError(PK("V\\U00110000\n."), "U+10FFFF");
  expectError(PK("I1x\n."), "integer");
  expectError(PK("I99999999999999999999\n."), "integer");
  expectError(PK("F1.5x\n."), "float");
  expectError(PK("Fx\n."), "float");
  expectError(PK("\x8a\x09\x00\x00\x00\x00\x00\x00\x00\x00\x01."), "64 bits");
  expectError(PK("\x8a\x09\x00\x00\x00\x00\x00\x00\x00\x80\x00."), "64 bits");
  expectError(PK("cos\nsystem"), "newline");
  expectError(PK("I12"), "newline");
}

TEST_CASE("pickle: declared lengths beyond the input fail before allocating", "[hand][pickle]") {
  expectError(PK("T\xff\xff\xff\x7f" "abc."), "truncated");
  expectError(PK("T\xff\xff\xff\xff."), "negative");
  expectError(PK("X\xff\xff\xff\xff."), "truncated");
  expectError(PK("B\xff\xff\xff\xff."), "truncated");
  expectError(PK("\x8d\xff\xff\xff\xff\xff\xff\xff\xff."), "truncated");  // LONG_BINUNICODE8
  expectError(PK("\x8e\x00\x00\x00\x00\x00\x00\x00\x80."), "truncated");
  expectError(PK("\x96\xff\xff\xff\xff\xff\xff\xff\x7f."), "truncated");
  expectError(PK("\x8b\xff\xff\xff\x7f."), "truncated");
  expectError(PK("\x8b\xff\xff\xff\xff."), "negative");
  expectError(PK("\x95\xff\xff\xff\xff\xff\xff\xff\xff."), "truncated");
  expectError(PK("U\x05" "ab."), "truncated");
}

TEST_CASE("pickle: nesting, node and memo abuse", "[hand][pickle]") {
  // 100k MARKs: the MARK limit stops it long before.
  expectError(std::string(100000, '(') + ".", "MARKs open");
  // 100k nested lists via APPEND: the depth limit.
  expectError(std::string(100000, ']') + std::string(99999, 'a') + ".", "nested deeper");
  // 100k sibling lists are fine (no nesting), and the last one is the root.
  withRoot(std::string(100000, ']') + ".", [](auto v) { CHECK(v.is(Kind::List)); });
  // A list appended to itself over and over grows in depth until the limit.
  {
    std::string s = PK("]q\x00");
    for (int i = 0; i < 300; ++i) s += PK("h\x00" "a");
    expectError(s + ".", "nested deeper");
  }
  // Nested tuples through TUPLE1.
  expectError("N" + std::string(1000, '\x85') + ".", "nested deeper");
  // The node limit.
  hawor::pickle::Limits small;
  small.maxNodes = 10;
  CHECK_THROWS_AS(parse(std::string(20, ']') + ".", small), hawor::Error);
  small.maxDepth = 3;
  small.maxNodes = 0;
  CHECK_THROWS_AS(parse(PK("]]]]aaa."), small), hawor::Error);
  CHECK_NOTHROW(parse(PK("]]]aa."), small));
  // Huge memo keys do not allocate anything proportional to the key.
  withRoot(PK("K\x01r\xff\xff\xff\xff" "0j\xff\xff\xff\xff."), [](auto v) { CHECK(v.asInt() == 1); });
  withRoot(PK("K\x01p99999999999999\n0g99999999999999\n."), [](auto v) { CHECK(v.asInt() == 1); });
  expectError(PK("K\x01r\xff\xff\xff\xff" "0j\xfe\xff\xff\xff."), "memo key");
}

TEST_CASE("pickle: every prefix of a valid pickle fails cleanly, mutations never crash", "[hand][pickle]") {
  // A small pickle with most opcode kinds, as the MANO files use them.
  hand_test::PickleWriter w;
  w.proto(2);
  w.op('}');
  w.op('q');
  w.op(0);
  w.mark();
  w.str("v_template");
  hand_test::writeNdarray(w, "f8", '<', {2, 3}, hand_test::rawLE(std::vector<double>{1, 2, 3, 4, 5, 6}));
  w.str("shapedirs");
  w.global("chumpy.ch", "Ch");
  w.op(')');
  w.op(0x81);
  w.op('}');
  w.str("x");
  w.integer(-5);
  w.op('s');
  w.op('b');
  w.str("m");
  w.op('h');
  w.op(0);
  w.unicode("u");
  w.raw(PK("G\x3f\xf8\x00\x00\x00\x00\x00\x00"));
  w.op('u');
  w.stop();
  const std::string full = w.b;
  {
    const auto doc = parse(full);
    REQUIRE(doc.root().is(Kind::Dict));
    CHECK(doc.root().at("u").asFloat() == 1.5);
    CHECK(doc.root().at("m").index() == doc.root().index());
  }
  for (std::size_t n = 0; n < full.size(); ++n) {
    INFO("prefix " << n);
    CHECK_THROWS_AS(parse(full.substr(0, n)), hawor::Error);
  }
  // Single-byte mutations: either a valid parse or a hawor::Error (ASan / UBSan watch the rest).
  const unsigned char values[] = {0x00, 0x01, 0x7f, 0x80, 0xff, '(', '.', 'a', 'b', 'R', 0x85, 0x8a};
  std::size_t errors = 0, parsed = 0;
  for (std::size_t i = 0; i < full.size(); ++i) {
    for (unsigned char c : values) {
      std::string m = full;
      m[i] = static_cast<char>(c);
      try {
        const auto doc = parse(m);
        (void)doc.root().describe();
        ++parsed;
      } catch (const hawor::Error&) {
        ++errors;
      }
    }
  }
  CHECK(errors + parsed == full.size() * sizeof(values));
  CHECK(errors > 0);
}
