// libFuzzer target: the symbolic pickle reader and the MANO loader on arbitrary bytes.
// Any outcome other than a parsed value or a hawor::Error (a crash, a sanitizer report, a hang,
// an allocation far beyond the input size) is a bug.
//   clang++ -std=c++17 -g -O1 -fsanitize=fuzzer,address,undefined -I include -I /usr/include/eigen3 \
//       tests/fuzz/fuzz_pickle.cpp -o fuzz_pickle && ./fuzz_pickle -max_len=4096
#include "hawor/hand/mano_loader.hpp"
#include "hawor/hand/pickle.hpp"

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const hawor::pickle::Document doc = hawor::pickle::parse(data, size);
    // Touch every node through the public accessors (bounded: no recursion, cycles are fine).
    for (std::size_t i = 0; i < doc.nodeCount(); ++i) {
      const hawor::pickle::Value v(&doc, static_cast<std::uint32_t>(i));
      (void)v.describe();
      switch (v.kind()) {
        case hawor::pickle::Kind::Dict:
          if (v.size() > 0) (void)v.dictValue(v.size() - 1);
          (void)v.has("x");
          break;
        case hawor::pickle::Kind::Tuple:
        case hawor::pickle::Kind::List:
          if (v.size() > 0) (void)v[0];
          break;
        case hawor::pickle::Kind::Reduce:
        case hawor::pickle::Kind::NewObj:
          (void)v.args();
          if (v.hasState()) (void)v.state().describe();
          break;
        default: break;
      }
    }
  } catch (const hawor::Error&) {
  }
  try {
    hawor::ManoLoadOptions opt;
    opt.side = hawor::HandSide::Right;
    (void)hawor::loadManoPickle<double>(data, size, opt);
  } catch (const hawor::Error&) {
  }
  return 0;
}
