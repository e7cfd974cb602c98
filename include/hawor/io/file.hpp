// hawor/io/file.hpp — whole-file binary read and write with errors that name the path.
//
// The parsers of this module work on byte buffers; these two functions are the only place that
// touches the file system, so the WASM build (NODERAWFS or MEMFS) needs nothing else.
#pragma once

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "../common.hpp"

namespace hawor {

/// Reads a whole file into memory. Throws hawor::Error naming the path on any failure
/// (missing file, directory, read error).
inline std::vector<uint8_t> readFileBytes(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    throw Error("cannot open '" + path + "' for reading: " + std::strerror(errno));
  }
  std::vector<uint8_t> out;
  // Read in chunks: no reliance on ftell (32-bit long in WASM) and works on pipes.
  const size_t chunk = size_t(1) << 20;
  size_t used = 0;
  bool failed = false;
  for (;;) {
    out.resize(used + chunk);
    const size_t got = std::fread(out.data() + used, 1, chunk, f);
    used += got;
    if (got < chunk) {
      failed = std::ferror(f) != 0;
      break;
    }
  }
  const int err = errno;
  std::fclose(f);
  if (failed) throw Error("cannot read '" + path + "': " + std::strerror(err));
  out.resize(used);
  out.shrink_to_fit();
  return out;
}

/// Reads a whole file as text (bytes unchanged, no newline translation).
inline std::string readFileText(const std::string& path) {
  const std::vector<uint8_t> b = readFileBytes(path);
  return std::string(b.begin(), b.end());
}

/// Writes `n` bytes to a file, replacing it. Throws hawor::Error naming the path on failure.
inline void writeFileBytes(const std::string& path, const void* data, size_t n) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) {
    throw Error("cannot open '" + path + "' for writing: " + std::strerror(errno));
  }
  const size_t put = n ? std::fwrite(data, 1, n, f) : 0;
  const int err = errno;
  const bool closed = std::fclose(f) == 0;
  if (put != n || !closed) {
    throw Error("cannot write '" + path + "': " + std::strerror(put != n ? err : errno));
  }
}

inline void writeFileBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  writeFileBytes(path, bytes.data(), bytes.size());
}

inline void writeFileText(const std::string& path, const std::string& text) {
  writeFileBytes(path, text.data(), text.size());
}

}  // namespace hawor
