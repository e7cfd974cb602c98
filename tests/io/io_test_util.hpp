// Helpers shared by the io tests: temp paths, error capture, and a deliberately naive ZIP and
// DEFLATE encoder written independently of the library, for crafting valid and malformed input.
#pragma once

#include <hawor/common.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace io_test {

/// A scratch file path inside the build tree's reference folder (native and WASM alike).
inline std::string tempPath(const std::string& name) { return std::string(HAWOR_REF_DIR) + "/io_" + name; }

/// The hawor::Error message thrown by f, or "<no error>" (other exception types propagate and
/// fail the test).
inline std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const hawor::Error& e) {
    return e.what();
  }
  return "<no error>";
}

/// Runs f and reports how it ended: 0 = returned, 1 = hawor::Error, 2 = other exception.
inline int outcome(const std::function<void()>& f) {
  try {
    f();
  } catch (const hawor::Error&) {
    return 1;
  } catch (...) {
    return 2;
  }
  return 0;
}

inline void putLE(std::vector<uint8_t>& b, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
inline void patchLE(std::vector<uint8_t>& b, size_t off, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) b.at(off + i) = static_cast<uint8_t>(v >> (8 * i));
}
inline uint64_t getLE(const std::vector<uint8_t>& b, size_t off, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v |= static_cast<uint64_t>(b.at(off + i)) << (8 * i);
  return v;
}

/// Bitwise CRC-32 (reflected 0xEDB88320), independent of the library's table version.
inline uint32_t slowCrc32(const uint8_t* p, size_t n) {
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}
inline uint32_t slowCrc32(const std::vector<uint8_t>& b) { return slowCrc32(b.data(), b.size()); }

/// One member of a hand-built archive: `data` is written as is (already deflated if method 8).
struct RawMember {
  std::string name;
  std::vector<uint8_t> data;
  uint16_t method = 0;
  uint32_t crc = 0;
  uint64_t usize = 0;
  uint16_t flags = 0;
  std::string local_name;  ///< empty: same as name
};

/// A plain (non-ZIP64) archive from RawMembers, laid out exactly as APPNOTE describes.
inline std::vector<uint8_t> rawZip(const std::vector<RawMember>& ms) {
  std::vector<uint8_t> b, cd;
  for (const auto& m : ms) {
    const std::string& ln = m.local_name.empty() ? m.name : m.local_name;
    const uint64_t off = b.size();
    putLE(b, 0x04034b50, 4);
    putLE(b, 20, 2);
    putLE(b, m.flags, 2);
    putLE(b, m.method, 2);
    putLE(b, 0, 4);
    putLE(b, m.crc, 4);
    putLE(b, m.data.size(), 4);
    putLE(b, m.usize, 4);
    putLE(b, ln.size(), 2);
    putLE(b, 0, 2);
    b.insert(b.end(), ln.begin(), ln.end());
    b.insert(b.end(), m.data.begin(), m.data.end());
    putLE(cd, 0x02014b50, 4);
    putLE(cd, 20, 2);
    putLE(cd, 20, 2);
    putLE(cd, m.flags, 2);
    putLE(cd, m.method, 2);
    putLE(cd, 0, 4);
    putLE(cd, m.crc, 4);
    putLE(cd, m.data.size(), 4);
    putLE(cd, m.usize, 4);
    putLE(cd, m.name.size(), 2);
    putLE(cd, 0, 2);
    putLE(cd, 0, 2);
    putLE(cd, 0, 2);
    putLE(cd, 0, 2);
    putLE(cd, 0, 4);
    putLE(cd, off, 4);
    cd.insert(cd.end(), m.name.begin(), m.name.end());
  }
  const uint64_t cd_off = b.size();
  b.insert(b.end(), cd.begin(), cd.end());
  putLE(b, 0x06054b50, 4);
  putLE(b, 0, 4);
  putLE(b, ms.size(), 2);
  putLE(b, ms.size(), 2);
  putLE(b, cd.size(), 4);
  putLE(b, cd_off, 4);
  putLE(b, 0, 2);
  return b;
}

/// A stored member with the right CRC and size.
inline RawMember storedMember(const std::string& name, const std::vector<uint8_t>& data) {
  RawMember m;
  m.name = name;
  m.data = data;
  m.crc = slowCrc32(data);
  m.usize = data.size();
  return m;
}

/// DEFLATE "stored" blocks (BTYPE 00) wrapping `data`: valid method-8 data without compression.
inline std::vector<uint8_t> deflateStoredBlocks(const std::vector<uint8_t>& data) {
  std::vector<uint8_t> out;
  size_t pos = 0;
  do {
    const size_t len = std::min<size_t>(65535, data.size() - pos);
    const bool last = pos + len == data.size();
    out.push_back(last ? 1 : 0);
    putLE(out, len, 2);
    putLE(out, ~len & 0xFFFF, 2);
    out.insert(out.end(), data.begin() + pos, data.begin() + pos + len);
    pos += len;
  } while (pos < data.size());
  return out;
}

/// Fixed-Huffman DEFLATE of `count` zero bytes: literal 0 then runs of (length 258, distance 1).
/// `count` must be 1 + 258 k. A compact decompression bomb (13 bits per 258 output bytes).
inline std::vector<uint8_t> deflateZeroRuns(size_t runs) {
  std::vector<uint8_t> out;
  uint64_t acc = 0;
  int nbits = 0;
  const auto put = [&](uint32_t v, int n) {  // LSB-first bit stream
    acc |= static_cast<uint64_t>(v) << nbits;
    nbits += n;
    while (nbits >= 8) {
      out.push_back(static_cast<uint8_t>(acc));
      acc >>= 8;
      nbits -= 8;
    }
  };
  const auto huff = [&](uint32_t code, int n) {  // Huffman codes go most significant bit first
    uint32_t r = 0;
    for (int i = 0; i < n; ++i) r |= ((code >> i) & 1u) << (n - 1 - i);
    put(r, n);
  };
  put(1, 1);                  // BFINAL
  put(1, 2);                  // BTYPE 01, fixed codes
  huff(0x30, 8);              // literal 0
  for (size_t i = 0; i < runs; ++i) {
    huff(0xC0 + (285 - 280), 8);  // length code 285 = 258
    huff(0, 5);                   // distance code 0 = 1
  }
  huff(0, 7);  // end of block (256)
  if (nbits) put(0, 8 - nbits);
  return out;
}

}  // namespace io_test
