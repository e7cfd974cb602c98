// .npz: stored and compressed round trips of mixed arrays, ZIP64, key handling and errors that
// name the file and the key, malformed archives and members.
#include <catch2/catch.hpp>

#include <hawor/io/npz.hpp>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "io_test_util.hpp"

using hawor::NpyArray;
using hawor::Npz;
using io_test::errorOf;

template std::vector<double> Npz::getAs<double>(const std::string&) const;
template std::vector<int32_t> Npz::getAs<int32_t>(const std::string&) const;

namespace {

Npz sampleNpz() {
  Npz z;
  std::vector<double> d(60);
  for (size_t i = 0; i < d.size(); ++i) d[i] = 0.25 * static_cast<double>(i % 17) - 1.0;
  z.set("v_template", NpyArray::fromData(d.data(), {20, 3}));
  z.set("fortran", NpyArray::fromData(d.data(), {3, 4, 5}, true));
  const int32_t faces[6] = {0, 1, 2, 2, 1, 3};
  z.set("f", NpyArray::fromData(faces, {2, 3}, false, true));
  const bool mask[4] = {true, false, false, true};
  z.set("mask", NpyArray::fromData(mask, {4}));
  const float scalar = 2.5f;
  z.set("scalar", NpyArray::fromData(&scalar, {}));
  z.set("empty", NpyArray::fromData(d.data(), {0, 3}));
  const uint16_t u[3] = {1, 65535, 7};
  z.set("nested/key", NpyArray::fromData(u, {3}));
  return z;
}

std::string npzError(const std::vector<uint8_t>& b) {
  return errorOf([&] { Npz::fromBuffer(b, "bad.npz"); });
}

}  // namespace

TEST_CASE("npz round trip, stored and compressed", "[io][npz]") {
  const Npz z = sampleNpz();
  for (bool compressed : {false, true}) {
    for (bool zip64 : {false, true}) {
      CAPTURE(compressed, zip64);
      const auto buf = z.toBuffer(compressed, zip64);
      const Npz r = Npz::fromBuffer(buf, "mem.npz");
      REQUIRE(r.names() == z.names());
      for (const auto& n : z.names()) CHECK(r.get(n) == z.get(n));
      // Member names are "<key>.npy"; compressible members are deflated when asked.
      const hawor::ZipReader zr(buf.data(), buf.size(), "mem.npz");
      REQUIRE(zr.entries().size() == z.size());
      CHECK(zr.entries()[0].name == "v_template.npy");
      CHECK(zr.entries()[0].method == (compressed ? 8 : 0));
      CHECK(zr.entries()[0].zip64 == zip64);
    }
  }
  CHECK(z.toBuffer(true).size() < z.toBuffer(false).size());
  const Npz r = Npz::fromBuffer(z.toBuffer(), "mem.npz");
  CHECK(r.getAs<double>("fortran") == z.get("fortran").as<double>());
  CHECK(r.getAs<int32_t>("f") == std::vector<int32_t>{0, 1, 2, 2, 1, 3});
  CHECK((r.get("mask").as<bool>() == std::vector<bool>{true, false, false, true}));
  CHECK(r.get("scalar").as<float>() == std::vector<float>{2.5f});
  CHECK(r.get("empty").shape == std::vector<size_t>{0, 3});
  CHECK(r.has("nested/key"));
  CHECK(!r.has("nested"));
}

TEST_CASE("npz files on disk", "[io][npz]") {
  const Npz z = sampleNpz();
  for (bool compressed : {false, true}) {
    const std::string path = io_test::tempPath(compressed ? "c.npz" : "s.npz");
    z.write(path, compressed);
    const Npz r = Npz::read(path);
    CHECK(r.source() == path);
    REQUIRE(r.names() == z.names());
    for (const auto& n : z.names()) CHECK(r.get(n) == z.get(n));
    // Errors name the key, the file and the keys present.
    CHECK_THAT(errorOf([&] { r.get("betas"); }),
               Catch::Contains(path) && Catch::Contains("'betas'") && Catch::Contains("v_template"));
    CHECK_THAT(errorOf([&] { r.getAs<int32_t>("v_template"); }),
               Catch::Contains(path) && Catch::Contains("'v_template'") && Catch::Contains("not an integer"));
  }
  CHECK_THAT(errorOf([] { Npz::read(io_test::tempPath("missing.npz")); }), Catch::Contains("missing.npz"));
}

TEST_CASE("npz keys and arrays are validated", "[io][npz]") {
  Npz z;
  const double d[2] = {1, 2};
  z.set("a", NpyArray::fromData(d, {2}));
  z.set("b", NpyArray::fromData(d, {1}));
  z.set("a", NpyArray::fromData(d, {1}));  // replaces, keeps position
  CHECK(z.names() == std::vector<std::string>{"a", "b"});
  CHECK(z.get("a").shape == std::vector<size_t>{1});
  CHECK_THAT(errorOf([&] { z.set("", NpyArray::fromData(d, {2})); }), Catch::Contains("invalid array name"));
  NpyArray broken = NpyArray::fromData(d, {2});
  broken.bytes.pop_back();
  CHECK_THAT(errorOf([&] { z.set("c", broken); }), Catch::Contains("'c'"));
  CHECK_THAT(errorOf([] { Npz().get("x"); }), Catch::Contains("keys: none"));
}

TEST_CASE("npz members: non-arrays ignored, bad arrays named", "[io][npz]") {
  const double d[3] = {1, 2, 3};
  const auto npy = hawor::writeNpy(NpyArray::fromData(d, {3}));
  const std::vector<uint8_t> text = {'h', 'i'};
  {
    const auto z = io_test::rawZip({io_test::storedMember("readme.txt", text),
                                    io_test::storedMember("dir/", {}),
                                    io_test::storedMember("x.npy", npy)});
    const Npz r = Npz::fromBuffer(z, "mixed.npz");
    CHECK(r.names() == std::vector<std::string>{"x"});
  }
  {
    const auto z = io_test::rawZip({io_test::storedMember("x.npy", text)});
    CHECK_THAT(npzError(z), Catch::Contains("bad.npz") && Catch::Contains("member 'x.npy'"));
  }
  {
    auto bad = npy;
    bad.back() ^= 1;  // valid archive CRC over a valid npy: still a valid array
    const auto z = io_test::rawZip({io_test::storedMember("x.npy", bad)});
    CHECK(npzError(z) == "<no error>");
    auto truncated = npy;
    truncated.pop_back();
    const auto z2 = io_test::rawZip({io_test::storedMember("x.npy", truncated)});
    CHECK_THAT(npzError(z2), Catch::Contains("member 'x.npy'") && Catch::Contains("truncated"));
  }
}

TEST_CASE("npz truncated at every length throws hawor::Error", "[io][npz]") {
  Npz z;
  const double d[6] = {1, 2, 3, 4, 5, 6};
  z.set("a", NpyArray::fromData(d, {2, 3}, true));
  z.set("b", NpyArray::fromData(d, {6}));
  for (bool compressed : {false, true}) {
    const auto buf = z.toBuffer(compressed, compressed);
    REQUIRE(npzError(buf) == "<no error>");
    int not_thrown = 0, others = 0;
    for (size_t k = 0; k < buf.size(); ++k) {
      const std::vector<uint8_t> prefix(buf.begin(), buf.begin() + k);
      const int r = io_test::outcome([&] { Npz::fromBuffer(prefix, "t.npz"); });
      not_thrown += r == 0;
      others += r == 2;
    }
    CHECK(not_thrown == 0);
    CHECK(others == 0);
  }
}

TEST_CASE("npz random corruption never crashes", "[io][npz]") {
  const auto base = sampleNpz().toBuffer(true);
  std::mt19937 rng(5);
  int others = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    auto b = base;
    const int edits = 1 + static_cast<int>(rng() % 3);
    for (int e = 0; e < edits; ++e) b[rng() % b.size()] = static_cast<uint8_t>(rng());
    others += io_test::outcome([&] {
      const Npz r = Npz::fromBuffer(b, "fuzz.npz");
      for (const auto& n : r.names()) (void)r.getAs<double>(n);
    }) == 2;
  }
  CHECK(others == 0);
}
