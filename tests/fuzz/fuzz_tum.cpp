// libFuzzer target: TUM trajectory parsing in float and double. Any input must parse or throw
// hawor::Error; parsed trajectories must be written and read back with identical values.
#include <hawor/io/tum.hpp>

#include <cstdint>
#include <cstdlib>
#include <string>

template <typename S>
static void check(const std::string& text) {
  std::vector<hawor::TumPose<S>> poses;
  try {
    poses = hawor::parseTum<S>(text, "fuzz.txt");
  } catch (const hawor::Error&) {
    return;
  }
  const auto back = hawor::parseTum<S>(hawor::formatTum(poses), "roundtrip.txt");
  if (back.size() != poses.size()) std::abort();
  for (size_t i = 0; i < poses.size(); ++i) {
    if (back[i].t != poses[i].t || back[i].p != poses[i].p) std::abort();
  }
  if (!poses.empty()) (void)hawor::associateByTimestamp(poses, back, 0.01);
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  check<double>(text);
  check<float>(text);
  return 0;
}
