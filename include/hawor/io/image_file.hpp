// hawor/io/image_file.hpp — reading 8-bit images (PNG, JPEG, BMP) through stb_image
// (io/detail/stb.hpp decides how stb is compiled; with HAWOR_NO_STB the functions throw), and
// listing the image files of a folder in name order (the frames of `hawor slam --images DIR`).
// Errors name the file and what is wrong (missing, not an image, truncated, too large).
#pragma once

#include <dirent.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/io/detail/stb.hpp"
#include "hawor/io/file.hpp"
#include "hawor/render/image.hpp"

namespace hawor {
inline namespace HAWOR_IO_DEFLATE_NS {

/// Decodes an image file's bytes. channels = 0 keeps the file's channel count (1–4); 1, 3 or 4
/// converts. `what` names the source in errors. Images over maxPixels are refused.
inline ImageU8 decodeImage(const std::vector<std::uint8_t>& bytes, const std::string& what, int channels = 0,
                           double maxPixels = 100e6) {
  if (channels < 0 || channels > 4) throw Error("decodeImage: channels must be 0..4");
  if (bytes.empty()) throw Error(what + ": empty file");
#if HAWOR_HAVE_STB
  if (bytes.size() > static_cast<std::size_t>(0x7fffffff)) throw Error(what + ": file too large");
  int w = 0, h = 0, c = 0;
  if (!stbi_info_from_memory(bytes.data(), static_cast<int>(bytes.size()), &w, &h, &c)) {
    throw Error(what + ": not a readable PNG, JPEG or BMP image (" + std::string(stbi_failure_reason()) + ")");
  }
  if (double(w) * double(h) > maxPixels) {
    throw Error(what + ": image is " + std::to_string(w) + "x" + std::to_string(h) + ", larger than the limit of " +
                std::to_string(static_cast<long long>(maxPixels)) + " pixels");
  }
  int cw = 0, ch = 0, cc = 0;
  unsigned char* px = stbi_load_from_memory(bytes.data(), static_cast<int>(bytes.size()), &cw, &ch, &cc, channels);
  if (!px) throw Error(what + ": cannot decode image (" + std::string(stbi_failure_reason()) + ")");
  const int outC = channels ? channels : cc;
  ImageU8 img;
  img.width = cw;
  img.height = ch;
  img.channels = outC;
  img.data.assign(px, px + static_cast<std::size_t>(cw) * ch * outC);
  stbi_image_free(px);
  return img;
#else
  (void)maxPixels;
  throw Error(what + ": image decoding needs stb (built with HAWOR_NO_STB)");
#endif
}

/// Reads an image file (see decodeImage).
inline ImageU8 readImage(const std::string& path, int channels = 0) {
  return decodeImage(readFileBytes(path), path, channels);
}

/// Names (not paths) of the .png/.jpg/.jpeg/.bmp files in `dir`, sorted; throws when the folder
/// cannot be opened.
inline std::vector<std::string> listImageFiles(const std::string& dir) {
  DIR* d = opendir(dir.c_str());
  if (!d) throw Error("cannot open image folder '" + dir + "'");
  std::vector<std::string> names;
  while (dirent* e = readdir(d)) {
    std::string n = e->d_name;
    std::string lower = n;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
    auto ends = [&](const std::string& s) { return lower.size() > s.size() && lower.compare(lower.size() - s.size(), s.size(), s) == 0; };
    if (ends(".png") || ends(".jpg") || ends(".jpeg") || ends(".bmp")) names.push_back(n);
  }
  closedir(d);
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace HAWOR_IO_DEFLATE_NS
}  // namespace hawor
