// libFuzzer target: .npy parsing. Any input must either parse or throw hawor::Error; whatever
// parses must convert without crashing and survive a write/parse round trip unchanged.
#include <hawor/io/npy.hpp>

#include <cstdint>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  hawor::NpyArray a;
  try {
    a = hawor::parseNpy(data, size, "fuzz.npy");
  } catch (const hawor::Error&) {
    return 0;
  }
  try {
    (void)a.as<double>();
    (void)a.as<int32_t>();
    (void)a.as<bool>();
  } catch (const hawor::Error&) {  // value conversions may legitimately refuse
  }
  const auto bytes = hawor::writeNpy(a);  // must not throw for a parsed array
  if (!(hawor::parseNpy(bytes.data(), bytes.size(), "roundtrip.npy") == a)) std::abort();
  return 0;
}
