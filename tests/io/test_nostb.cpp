// HAWOR_NO_STB: the io module without stb, linked into the same program as TUs that use stb
// (the deflate-dependent classes live in a configuration-named inline namespace, so no ODR clash).
// Stored archives work; deflated members and compressed writes fail with a clear hawor::Error.
#define HAWOR_NO_STB
#include <catch2/catch.hpp>

#include <hawor/io/io.hpp>

#include <string>
#include <vector>

#include "io_test_util.hpp"

static_assert(!hawor::kHaveDeflate, "HAWOR_NO_STB must disable deflate");
#if defined(STBI_INCLUDE_STB_IMAGE_H)
#error "HAWOR_NO_STB must not include stb"
#endif

TEST_CASE("HAWOR_NO_STB: stored npz works, deflate is a clear error", "[io][npz][nostb]") {
  hawor::Npz z;
  const double d[4] = {1, 2, 3, 4};
  z.set("a", hawor::NpyArray::fromData(d, {2, 2}));
  const auto stored = z.toBuffer(false);
  const hawor::Npz r = hawor::Npz::fromBuffer(stored, "stored.npz");
  CHECK(r.get("a") == z.get("a"));
  CHECK_THAT(io_test::errorOf([&] { z.toBuffer(true); }), Catch::Contains("HAWOR_NO_STB"));

  // A deflated member (written by hand as DEFLATE stored blocks) cannot be read.
  const auto npy = hawor::writeNpy(z.get("a"));
  io_test::RawMember m = io_test::storedMember("a.npy", npy);
  m.method = 8;
  m.data = io_test::deflateStoredBlocks(npy);
  const auto zip = io_test::rawZip({m});
  CHECK_THAT(io_test::errorOf([&] { hawor::Npz::fromBuffer(zip, "deflated.npz"); }),
             Catch::Contains("deflated.npz") && Catch::Contains("HAWOR_NO_STB"));
}
