// ZIP and DEFLATE: CRC-32 check values, inflate of streams from an independent encoder, writer /
// reader round trips (stored, deflated, ZIP64), and malformed archives: bad offsets, lying sizes,
// CRC mismatches, overlapping members, decompression bombs, truncation at every length.
#include <catch2/catch.hpp>

#include <hawor/io/zip.hpp>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "io_test_util.hpp"

using hawor::ZipReader;
using hawor::ZipWriter;
using io_test::errorOf;
using io_test::getLE;
using io_test::patchLE;

namespace {

std::vector<uint8_t> bytesOf(const std::string& s) { return std::vector<uint8_t>(s.begin(), s.end()); }

std::vector<uint8_t> randomBytes(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<uint8_t> b(n);
  for (auto& x : b) x = static_cast<uint8_t>(rng());
  return b;
}

std::vector<uint8_t> compressible(size_t n) {
  std::vector<uint8_t> b(n);
  for (size_t i = 0; i < n; ++i) b[i] = static_cast<uint8_t>((i / 7) % 13 + (i % 3));
  return b;
}

// Reads every member of an archive (the full reading path).
void readAll(const std::vector<uint8_t>& z, hawor::ZipLimits limits = {}) {
  const ZipReader r(z.data(), z.size(), "test.zip", limits);
  for (const auto& e : r.entries()) (void)r.extract(e);
}

std::string zipError(const std::vector<uint8_t>& z, hawor::ZipLimits limits = {}) {
  return errorOf([&] { readAll(z, limits); });
}

// Offsets in a plain archive without comment (as ZipWriter and rawZip write it).
size_t eocdOf(const std::vector<uint8_t>& z) { return z.size() - 22; }
size_t cdOf(const std::vector<uint8_t>& z) { return getLE(z, eocdOf(z) + 16, 4); }

// A three-member archive: stored text, deflated compressible data, empty member.
std::vector<uint8_t> sampleArchive(bool zip64) {
  ZipWriter w(zip64);
  w.add("a.txt", bytesOf("hello, zip"), false);
  w.add("dir/b.bin", compressible(3000), true);
  w.add("empty", std::vector<uint8_t>(), true);
  return w.finish();
}

}  // namespace

TEST_CASE("crc32 check values", "[io][zip]") {
  const std::string s = "123456789";
  const auto* p = reinterpret_cast<const uint8_t*>(s.data());
  CHECK(hawor::crc32(p, s.size()) == 0xCBF43926u);  // the standard CRC-32 check value
  CHECK(hawor::crc32(p, 0) == 0u);
  CHECK(hawor::crc32(p + 4, 5, hawor::crc32(p, 4)) == 0xCBF43926u);
  const auto r = randomBytes(10000, 3);
  CHECK(hawor::crc32(r.data(), r.size()) == io_test::slowCrc32(r));
}

TEST_CASE("deflate and inflate round trip", "[io][zip]") {
  for (size_t n : {0, 1, 2, 3, 4, 100, 1000, 70000}) {
    for (int kind = 0; kind < 2; ++kind) {
      const auto src = kind ? randomBytes(n, static_cast<uint32_t>(n)) : compressible(n);
      CAPTURE(n, kind);
      const auto z = hawor::deflateRaw(src.data(), src.size());
      if (kind == 0 && n >= 1000) CHECK(z.size() < n / 3);
      CHECK(hawor::inflateRaw(z.data(), z.size(), n, "s") == src);
      if (n > 0) {
        CHECK_THAT(errorOf([&] { hawor::inflateRaw(z.data(), z.size(), n - 1, "s"); }),
                   Catch::Contains("declared"));
      }
      CHECK_THAT(errorOf([&] { hawor::inflateRaw(z.data(), z.size(), n + 1, "s"); }),
                 Catch::Contains("declares " + std::to_string(n + 1)));
    }
  }
}

TEST_CASE("inflate reads streams of an independent encoder", "[io][zip]") {
  const auto data = randomBytes(150000, 11);  // three stored blocks
  const auto stored = io_test::deflateStoredBlocks(data);
  CHECK(hawor::inflateRaw(stored.data(), stored.size(), data.size(), "s") == data);
  const size_t runs = 1000;
  const auto zeros = io_test::deflateZeroRuns(runs);
  const auto out = hawor::inflateRaw(zeros.data(), zeros.size(), 1 + 258 * runs, "z");
  CHECK(out == std::vector<uint8_t>(1 + 258 * runs, 0));
}

TEST_CASE("inflate rejects corrupt streams and impossible sizes", "[io][zip]") {
  for (uint32_t seed = 0; seed < 200; ++seed) {
    const auto junk = randomBytes(1 + seed % 64, seed);
    CHECK(io_test::outcome([&] { hawor::inflateRaw(junk.data(), junk.size(), 100, "junk"); }) != 2);
  }
  const uint8_t reserved[2] = {0x07, 0x00};  // BTYPE 11 is reserved
  CHECK(io_test::outcome([&] { hawor::inflateRaw(reserved, 2, 0, "r"); }) == 1);
  // A declared size no deflate stream of this length can produce is refused before allocating.
  const auto small = hawor::deflateRaw(reinterpret_cast<const uint8_t*>("abc"), 3);
  CHECK_THAT(errorOf([&] { hawor::inflateRaw(small.data(), small.size(), size_t(1) << 30, "b"); }),
             Catch::Contains("more than deflate can encode"));
  CHECK(io_test::outcome([&] { hawor::inflateRaw(small.data(), small.size(), ~size_t(0), "b"); }) == 1);
}

TEST_CASE("zip writer and reader round trip", "[io][zip]") {
  for (bool zip64 : {false, true}) {
    CAPTURE(zip64);
    const auto z = sampleArchive(zip64);
    const ZipReader r(z.data(), z.size(), "t.zip");
    REQUIRE(r.entries().size() == 3);
    const auto& e = r.entries();
    CHECK(e[0].name == "a.txt");
    CHECK(e[0].method == 0);
    CHECK(e[1].name == "dir/b.bin");
    CHECK(e[1].method == 8);
    CHECK(e[1].compressed_size < 3000);
    CHECK(e[2].method == 0);  // deflating nothing gains nothing: stored
    CHECK(e[0].zip64 == zip64);
    CHECK(r.extract("a.txt") == bytesOf("hello, zip"));
    CHECK(r.extract(e[1]) == compressible(3000));
    CHECK(r.extract("empty").empty());
    CHECK(r.find("nope") == nullptr);
    CHECK_THAT(errorOf([&] { r.extract("nope"); }), Catch::Contains("no member named 'nope'"));
    for (const auto& x : e) CHECK(x.crc32 == io_test::slowCrc32(r.extract(x)));
    // Local headers per APPNOTE: signature at 0; ZIP64 archives end with locator + EOCD.
    CHECK(getLE(z, 0, 4) == 0x04034b50u);
    if (zip64) {
      CHECK(getLE(z, z.size() - 22 - 20, 4) == 0x07064b50u);
      CHECK(getLE(z, eocdOf(z) + 10, 2) == 0xFFFFu);
      CHECK(getLE(z, 18, 4) == 0xFFFFFFFFu);  // local compressed size saturated
    }
  }
  // Incompressible data stays stored even when compression is asked for.
  ZipWriter w;
  w.add("r", randomBytes(5000, 1), true);
  const auto z = w.finish();
  CHECK(ZipReader(z.data(), z.size(), "r.zip").entries()[0].method == 0);
  // Names with non-ASCII bytes get the UTF-8 flag (bit 11).
  ZipWriter u;
  u.add("h\xC3\xA4nd.npy", bytesOf("x"), false);
  const auto zu = u.finish();
  CHECK(getLE(zu, 6, 2) == 0x0800u);
  CHECK(ZipReader(zu.data(), zu.size(), "u.zip").entries()[0].name == "h\xC3\xA4nd.npy");
  // Writer argument checks.
  ZipWriter d;
  d.add("x", bytesOf("1"), false);
  CHECK_THAT(errorOf([&] { d.add("x", bytesOf("2"), false); }), Catch::Contains("duplicate"));
  CHECK_THAT(errorOf([&] { d.add("", bytesOf("2"), false); }), Catch::Contains("invalid member name"));
}

TEST_CASE("zip reader accepts hand-built archives", "[io][zip]") {
  const auto data = compressible(5000);
  io_test::RawMember st = io_test::storedMember("s.bin", data);
  io_test::RawMember df = io_test::storedMember("d.bin", data);
  df.method = 8;
  df.data = io_test::deflateStoredBlocks(data);
  const auto z = io_test::rawZip({st, df});
  const ZipReader r(z.data(), z.size(), "raw.zip");
  CHECK(r.extract("s.bin") == data);
  CHECK(r.extract("d.bin") == data);
  // An archive comment after the EOCD record is allowed.
  auto commented = z;
  patchLE(commented, eocdOf(z) + 20, 5, 2);
  for (char c : std::string("hello")) commented.push_back(static_cast<uint8_t>(c));
  CHECK(zipError(commented) == "<no error>");
}

TEST_CASE("zip reader rejects malformed archives", "[io][zip]") {
  const auto data = compressible(2000);
  const auto base = sampleArchive(false);
  REQUIRE(zipError(base) == "<no error>");
  const size_t eocd = eocdOf(base), cd = cdOf(base);

  CHECK_THAT(zipError(randomBytes(500, 5)), Catch::Contains("end-of-central-directory"));
  CHECK_THAT(zipError({}), Catch::Contains("too short"));
  {
    auto z = base;  // comment length that does not reach the end
    patchLE(z, eocd + 20, 3, 2);
    CHECK_THAT(zipError(z), Catch::Contains("end-of-central-directory"));
  }
  {
    auto z = base;  // central directory offset beyond the file
    patchLE(z, eocd + 16, 0x7FFFFFF0, 4);
    CHECK_THAT(zipError(z), Catch::Contains("outside the archive"));
  }
  {
    auto z = base;  // central directory offset pointing at member data
    patchLE(z, eocd + 16, 0, 4);
    patchLE(z, eocd + 12, cd, 4);
    CHECK_THAT(zipError(z), Catch::Contains("bad signature"));
  }
  {
    auto z = base;  // more entries than the directory can hold
    patchLE(z, eocd + 8, 1000, 2);
    patchLE(z, eocd + 10, 1000, 2);
    CHECK_THAT(zipError(z), Catch::Contains("cannot hold"));
  }
  {
    auto z = base;  // entries on this disk != total
    patchLE(z, eocd + 8, 2, 2);
    CHECK_THAT(zipError(z), Catch::Contains("multi-disk"));
  }
  {
    auto z = base;  // saturated EOCD fields without ZIP64 records
    patchLE(z, eocd + 16, 0xFFFFFFFF, 4);
    CHECK_THAT(zipError(z), Catch::Contains("ZIP64"));
  }
  {
    auto z = base;  // one entry fewer: still consistent, just reads two
    patchLE(z, eocd + 8, 2, 2);
    patchLE(z, eocd + 10, 2, 2);
    CHECK(zipError(z) == "<no error>");
  }
  {
    auto z = base;  // CRC mismatch: corrupt a stored data byte
    z[30 + 5] ^= 0x20;
    CHECK_THAT(zipError(z), Catch::Contains("CRC-32 mismatch") && Catch::Contains("a.txt"));
  }
  {
    auto z = base;  // CRC field itself wrong
    patchLE(z, cd + 16, 0x12345678, 4);
    CHECK_THAT(zipError(z), Catch::Contains("CRC-32 mismatch"));
  }
  {
    auto z = base;  // lying compressed size
    patchLE(z, cd + 20, 0x7FFFFFFF, 4);
    patchLE(z, cd + 24, 0x7FFFFFFF, 4);
    CHECK_THAT(zipError(z), Catch::Contains("runs past the central directory"));
  }
  {
    auto z = base;  // stored member with different sizes
    patchLE(z, cd + 24, 3, 4);
    CHECK_THAT(zipError(z), Catch::Contains("sizes differ"));
  }
  {
    // Deflated member with a lying uncompressed size (smaller, larger, absurd).
    const ZipReader r(base.data(), base.size(), "t");
    const size_t second = cd + 46 + r.entries()[0].name.size();
    for (uint64_t lie : {uint64_t(10), uint64_t(2999), uint64_t(3001), uint64_t(0x7FFFFFFF)}) {
      auto z = base;
      patchLE(z, second + 24, lie, 4);
      CAPTURE(lie);
      CHECK(io_test::outcome([&] { readAll(z); }) == 1);
    }
  }
  {
    auto z = base;  // local header offset into the middle of data
    patchLE(z, cd + 42, 7, 4);
    CHECK_THAT(zipError(z), Catch::Contains("bad local header signature"));
  }
  {
    auto z = base;  // local header offset past the directory
    patchLE(z, cd + 42, static_cast<uint32_t>(cd + 10), 4);
    CHECK_THAT(zipError(z), Catch::Contains("outside the archive data"));
  }
  {
    auto z = base;  // encryption flag
    patchLE(z, cd + 8, 1, 2);
    CHECK_THAT(zipError(z), Catch::Contains("encrypted"));
  }
  {
    auto z = base;  // unsupported method (bzip2)
    patchLE(z, cd + 10, 12, 2);
    CHECK_THAT(zipError(z), Catch::Contains("method 12"));
  }
  {
    auto z = base;  // central entry truncated by a huge name length
    patchLE(z, cd + 28, 0xFFFF, 2);
    CHECK_THAT(zipError(z), Catch::Contains("truncated"));
  }
  {
    auto z = base;  // start disk != 0
    patchLE(z, cd + 34, 1, 2);
    CHECK_THAT(zipError(z), Catch::Contains("another disk"));
  }
  {
    io_test::RawMember m = io_test::storedMember("x.npy", data);
    m.local_name = "y.npy";
    CHECK_THAT(zipError(io_test::rawZip({m})), Catch::Contains("local header name differs"));
    m.local_name = "x.npyz";
    CHECK_THAT(zipError(io_test::rawZip({m})), Catch::Contains("local header name differs"));
  }
  {
    const auto m = io_test::storedMember("same", data);
    CHECK_THAT(zipError(io_test::rawZip({m, m})), Catch::Contains("overlap") || Catch::Contains("duplicate"));
    auto m2 = io_test::storedMember("same", bytesOf("other"));
    CHECK_THAT(zipError(io_test::rawZip({m, m2})), Catch::Contains("duplicate member name"));
  }
  {
    // Overlapping members: a stored member whose data is itself a local header + data, with a
    // second directory entry pointing inside it (the trick of non-recursive zip bombs).
    const auto inner = io_test::rawZip({io_test::storedMember("b", data)});
    const size_t inner_cd = cdOf(inner);
    const std::vector<uint8_t> inner_local(inner.begin(), inner.begin() + inner_cd);
    std::vector<uint8_t> inner_entry(inner.begin() + inner_cd, inner.begin() + inner_cd + 46 + 1);
    patchLE(inner_entry, 42, 30 + 1, 4);  // points into member "a"'s data
    auto outer = io_test::rawZip({io_test::storedMember("a", inner_local)});
    const size_t oe = eocdOf(outer);
    std::vector<uint8_t> tail(outer.begin() + oe, outer.end());
    outer.resize(oe);
    outer.insert(outer.end(), inner_entry.begin(), inner_entry.end());
    patchLE(tail, 8, 2, 2);
    patchLE(tail, 10, 2, 2);
    patchLE(tail, 12, getLE(tail, 12, 4) + inner_entry.size(), 4);
    outer.insert(outer.end(), tail.begin(), tail.end());
    CHECK_THAT(zipError(outer), Catch::Contains("overlap"));
  }
  {
    hawor::ZipLimits lim;
    lim.max_entries = 2;
    CHECK_THAT(zipError(base, lim), Catch::Contains("too many entries"));
  }
}

TEST_CASE("zip ZIP64 records are validated", "[io][zip]") {
  const auto base = sampleArchive(true);
  REQUIRE(zipError(base) == "<no error>");
  const size_t loc = base.size() - 22 - 20, rec = loc - 56;
  REQUIRE(getLE(base, rec, 4) == 0x06064b50u);
  {
    auto z = base;  // locator points past itself
    patchLE(z, loc + 8, loc + 100, 8);
    CHECK_THAT(zipError(z), Catch::Contains("locator points outside"));
  }
  {
    auto z = base;  // ZIP64 record signature broken
    z[rec] ^= 1;
    CHECK_THAT(zipError(z), Catch::Contains("bad signature"));
  }
  {
    auto z = base;  // 2^64-ish directory offset
    patchLE(z, rec + 48, ~uint64_t(0) - 5, 8);
    CHECK_THAT(zipError(z), Catch::Contains("outside the archive"));
  }
  {
    auto z = base;  // 2^40 entries
    patchLE(z, rec + 24, uint64_t(1) << 40, 8);
    patchLE(z, rec + 32, uint64_t(1) << 40, 8);
    CHECK(io_test::outcome([&] { readAll(z); }) == 1);
  }
  {
    auto z = base;  // multi-disk locator
    patchLE(z, loc + 16, 3, 4);
    CHECK_THAT(zipError(z), Catch::Contains("multi-disk"));
  }
  {
    // Central ZIP64 extra shorter than its saturated fields need.
    auto z = base;
    const size_t cd = getLE(z, rec + 48, 8);
    const size_t name_len = getLE(z, cd + 28, 2);
    patchLE(z, cd + 46 + name_len + 2, 8, 2);  // extra data size 24 -> 8
    CHECK(io_test::outcome([&] { readAll(z); }) == 1);
  }
  {
    // Saturated central sizes without any ZIP64 extra.
    io_test::RawMember m = io_test::storedMember("m", bytesOf("abc"));
    auto z = io_test::rawZip({m});
    patchLE(z, cdOf(z) + 24, 0xFFFFFFFF, 4);
    CHECK_THAT(zipError(z), Catch::Contains("no ZIP64 extra"));
  }
}

TEST_CASE("zip decompression bombs are stopped", "[io][zip]") {
  const size_t runs = 8000;  // ~2 MB of zeros in ~13 KB
  const size_t full = 1 + 258 * runs;
  io_test::RawMember m;
  m.name = "bomb.npy";
  m.method = 8;
  m.data = io_test::deflateZeroRuns(runs);
  m.crc = io_test::slowCrc32(std::vector<uint8_t>(full, 0));
  // Declared small: inflation stops at the declared size.
  m.usize = 1000;
  CHECK_THAT(zipError(io_test::rawZip({m})), Catch::Contains("more than the declared"));
  // Declared huge: refused before allocating (deflate's ratio bound).
  m.usize = 0x7FFFFFF0u;
  CHECK_THAT(zipError(io_test::rawZip({m})), Catch::Contains("more than deflate can encode"));
  // Declared truthfully: readable, unless the caller's cap is lower.
  m.usize = full;
  const auto z = io_test::rawZip({m});
  CHECK(zipError(z) == "<no error>");
  hawor::ZipLimits lim;
  lim.max_member_size = 1 << 20;
  CHECK_THAT(zipError(z, lim), Catch::Contains("over the limit"));
}

TEST_CASE("zip truncated at every length throws hawor::Error", "[io][zip]") {
  for (bool zip64 : {false, true}) {
    const auto z = sampleArchive(zip64);
    int not_thrown = 0, others = 0;
    for (size_t k = 0; k < z.size(); ++k) {
      const std::vector<uint8_t> prefix(z.begin(), z.begin() + k);
      const int r = io_test::outcome([&] { readAll(prefix); });
      not_thrown += r == 0;
      others += r == 2;
    }
    CHECK(not_thrown == 0);
    CHECK(others == 0);
  }
}

TEST_CASE("zip random corruption never crashes", "[io][zip]") {
  std::mt19937 rng(2024);
  for (bool zip64 : {false, true}) {
    const auto base = sampleArchive(zip64);
    int others = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      auto z = base;
      const int edits = 1 + static_cast<int>(rng() % 3);
      for (int e = 0; e < edits; ++e) z[rng() % z.size()] = static_cast<uint8_t>(rng());
      if (rng() % 10 == 0) z.resize(rng() % z.size());
      others += io_test::outcome([&] { readAll(z); }) == 2;
    }
    CHECK(others == 0);
  }
}
