// libFuzzer target: ZIP and .npz parsing (central directory, ZIP64, inflate, CRC, members).
// Any input must read or throw hawor::Error; what reads must round-trip through the writer.
#include <hawor/io/npz.hpp>

#include <cstdint>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  hawor::ZipLimits limits;
  limits.max_member_size = 64u << 20;  // keep the fuzzer inside its memory budget
  try {
    const hawor::ZipReader zip(data, size, "fuzz.zip", limits);
    for (const auto& e : zip.entries()) {
      try {
        (void)zip.extract(e);
      } catch (const hawor::Error&) {
      }
    }
  } catch (const hawor::Error&) {
  }
  hawor::Npz z;
  try {
    z = hawor::Npz::fromBuffer(data, size, "fuzz.npz", limits);
    for (const auto& n : z.names()) (void)z.getAs<double>(n);
  } catch (const hawor::Error&) {
    return 0;
  }
  const bool compressed = size % 2 == 1;
  const auto bytes = z.toBuffer(compressed, size % 3 == 0);  // must not throw
  const hawor::Npz back = hawor::Npz::fromBuffer(bytes, "roundtrip.npz");
  if (back.names() != z.names()) std::abort();
  for (const auto& n : z.names()) {
    if (back.get(n) != z.get(n)) std::abort();
  }
  return 0;
}
