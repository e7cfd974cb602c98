// hawor/synth/png.hpp — PNG encoding of 8-bit images (grey, grey+alpha, RGB, RGBA) through
// stb_image_write (io/detail/stb.hpp decides how stb is compiled; with HAWOR_NO_STB the
// functions throw). The encoder is deterministic: the same image gives the same bytes.
// Thread-safety: functions only (stb's PNG writer keeps no state between calls).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/io/detail/stb.hpp"
#include "hawor/io/file.hpp"
#include "hawor/render/image.hpp"

namespace hawor {
// Depends on the stb configuration: the tagged namespace of io/detail/stb.hpp.
inline namespace HAWOR_IO_DEFLATE_NS {

/// The PNG file bytes of an 8-bit image with 1–4 channels.
inline std::vector<std::uint8_t> encodePng(const ImageU8& img) {
  if (!img.consistent() || img.width < 1 || img.height < 1 || img.channels < 1 || img.channels > 4) {
    throw Error("encodePng: need a non-empty image with 1-4 channels, got " + std::to_string(img.width) + "x" +
                std::to_string(img.height) + "x" + std::to_string(img.channels));
  }
#if HAWOR_HAVE_STB
  std::vector<std::uint8_t> out;
  auto sink = [](void* ctx, void* data, int size) {
    auto* v = static_cast<std::vector<std::uint8_t>*>(ctx);
    const auto* p = static_cast<const std::uint8_t*>(data);
    v->insert(v->end(), p, p + size);
  };
  const int ok = stbi_write_png_to_func(sink, &out, img.width, img.height, img.channels, img.data.data(),
                                        img.width * img.channels);
  if (!ok || out.empty()) throw Error("encodePng: stb_image_write failed");
  return out;
#else
  throw Error("encodePng: PNG writing needs stb (this build defines HAWOR_NO_STB)");
#endif
}

/// Writes an image as a PNG file; errors name the path.
inline void writePng(const std::string& path, const ImageU8& img) {
  writeFileBytes(path, encodePng(img));
}

}  // namespace HAWOR_IO_DEFLATE_NS
}  // namespace hawor
