// hawor/io/detail/bytes.hpp — explicit little/big-endian loads and stores and overflow-checked
// size arithmetic, shared by the .npy and ZIP parsers.
//
// Every multi-byte field of a file is assembled byte by byte, so the parsers behave the same on
// any host byte order and never read through a misaligned pointer (WASM and UBSan both care).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace hawor {
namespace detail {

/// Loads an unsigned little-endian integer of `n` bytes (n <= 8).
inline uint64_t loadLE(const uint8_t* p, size_t n) {
  uint64_t v = 0;
  for (size_t i = 0; i < n; ++i) v |= static_cast<uint64_t>(p[i]) << (8 * i);
  return v;
}

/// Loads an unsigned big-endian integer of `n` bytes (n <= 8).
inline uint64_t loadBE(const uint8_t* p, size_t n) {
  uint64_t v = 0;
  for (size_t i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

inline uint16_t loadLE16(const uint8_t* p) { return static_cast<uint16_t>(loadLE(p, 2)); }
inline uint32_t loadLE32(const uint8_t* p) { return static_cast<uint32_t>(loadLE(p, 4)); }
inline uint64_t loadLE64(const uint8_t* p) { return loadLE(p, 8); }

/// Appends the `n` low bytes of `v`, least significant first.
inline void appendLE(std::vector<uint8_t>& out, uint64_t v, size_t n) {
  for (size_t i = 0; i < n; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

/// Writes the `n` low bytes of `v` at `p`, least (little) or most (big) significant first.
inline void storeBytes(uint8_t* p, uint64_t v, size_t n, bool big_endian) {
  for (size_t i = 0; i < n; ++i) {
    const uint8_t b = static_cast<uint8_t>(v >> (8 * i));
    p[big_endian ? n - 1 - i : i] = b;
  }
}

/// True on little-endian hosts (x86, ARM in its usual mode, WebAssembly).
inline bool hostIsLittleEndian() {
  const uint16_t one = 1;
  uint8_t b[2];
  std::memcpy(b, &one, 2);
  return b[0] == 1;
}

/// a * b without wrap-around; false on overflow.
inline bool checkedMul(uint64_t a, uint64_t b, uint64_t* out) {
  if (a != 0 && b > std::numeric_limits<uint64_t>::max() / a) return false;
  *out = a * b;
  return true;
}

/// a + b without wrap-around; false on overflow.
inline bool checkedAdd(uint64_t a, uint64_t b, uint64_t* out) {
  if (b > std::numeric_limits<uint64_t>::max() - a) return false;
  *out = a + b;
  return true;
}

/// True when a 64-bit size fits this platform's size_t (32 bits in WebAssembly).
inline bool fitsSizeT(uint64_t v) {
  return v <= static_cast<uint64_t>(std::numeric_limits<size_t>::max());
}

/// A printable, length-limited rendering of raw bytes for error messages.
inline std::string printable(const uint8_t* p, size_t n, size_t max_len = 40) {
  std::string s;
  for (size_t i = 0; i < n && i < max_len; ++i) {
    const char c = static_cast<char>(p[i]);
    s += (p[i] >= 32 && p[i] < 127) ? c : '?';
  }
  if (n > max_len) s += "...";
  return s;
}

}  // namespace detail
}  // namespace hawor
