// libFuzzer target: binary glTF (.glb) reading and the skinned-mesh -> hand-model conversion.
// Any input must convert or throw hawor::Error (anything else, a crash or a sanitizer report is a
// bug). Two input forms, so that the fuzzer need not discover the container first:
//   * starting with "glTF": a whole .glb file;
//   * starting with '{': a JSON chunk (up to the first NUL) and a BIN chunk (the bytes after it),
//     wrapped into a well-formed container here.
#include <hawor/hand/default_hand.hpp>
#include <hawor/io/gltf.hpp>

#include <cstdint>
#include <cstring>
#include <vector>

namespace {

void put32(std::vector<uint8_t>& b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

std::vector<uint8_t> wrap(const uint8_t* data, size_t size) {
  const uint8_t* nul = static_cast<const uint8_t*>(std::memchr(data, 0, size));
  const size_t jn = nul ? static_cast<size_t>(nul - data) : size;
  std::vector<uint8_t> json(data, data + jn), bin;
  if (nul) bin.assign(nul + 1, data + size);
  while (json.size() % 4) json.push_back(' ');
  while (bin.size() % 4) bin.push_back(0);
  std::vector<uint8_t> out;
  put32(out, 0x46546C67u);
  put32(out, 2);
  put32(out, static_cast<uint32_t>(12 + 8 + json.size() + (bin.empty() ? 0 : 8 + bin.size())));
  put32(out, static_cast<uint32_t>(json.size()));
  put32(out, 0x4E4F534Au);
  out.insert(out.end(), json.begin(), json.end());
  if (!bin.empty()) {
    put32(out, static_cast<uint32_t>(bin.size()));
    put32(out, 0x004E4942u);
    out.insert(out.end(), bin.begin(), bin.end());
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> bytes = size && data[0] == '{' ? wrap(data, size) : std::vector<uint8_t>(data, data + size);
  hawor::GltfLimits limits;  // keep the fuzzer inside its memory budget
  limits.maxAccessorValues = size_t(1) << 20;
  try {
    const hawor::Gltf g = hawor::Gltf::fromGlb(bytes, "fuzz.glb", limits);
    for (size_t i = 0; i < g.accessors().size(); ++i) {
      (void)g.readFloats(static_cast<int>(i));
      try {
        (void)g.readUints(static_cast<int>(i));
      } catch (const hawor::Error&) {
      }
    }
    for (size_t i = 0; i < g.nodes().size(); ++i) (void)g.nodeWorld(static_cast<int>(i));
    hawor::DefaultHandLimits hand;
    hand.maxJoints = 64;
    (void)hawor::handFromGltf<float>(g, false, hand);
  } catch (const hawor::Error&) {
  }
  return 0;
}
