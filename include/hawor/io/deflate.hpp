// hawor/io/deflate.hpp — raw DEFLATE (RFC 1951) streams, as stored in ZIP members (method 8).
//
// Decoding uses stb_image's zlib decoder without header; encoding uses stb_image_write's zlib
// compressor (fixed Huffman codes, LZ77 with a 32 KiB window) with the 2-byte zlib header and the
// 4-byte Adler-32 trailer stripped. Built with HAWOR_NO_STB both throw hawor::Error.
// Decompression-bomb safety: the output buffer is exactly the declared size (+1 to detect
// overrun), the declared size is checked against deflate's maximum ratio (1032:1) before any
// allocation, and the caller's cap applies on top.
#pragma once

#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "../common.hpp"
#include "detail/stb.hpp"

namespace hawor {
inline namespace HAWOR_IO_DEFLATE_NS {

/// True when this build can inflate and deflate (not HAWOR_NO_STB).
constexpr bool kHaveDeflate = HAWOR_HAVE_STB != 0;

/// Largest output per input byte that a DEFLATE stream can encode: a 258-byte match coded with a
/// 1-bit length code and a 1-bit distance code, i.e. 258 bytes per 2 bits.
constexpr uint64_t kDeflateMaxRatio = 1032;

/// Inflates the raw deflate stream src[0, n) and requires it to produce exactly `expected_size`
/// bytes. `what` names the stream in errors (file and member).
inline std::vector<uint8_t> inflateRaw(const uint8_t* src, size_t n, size_t expected_size,
                                       const std::string& what) {
#if HAWOR_HAVE_STB
  const size_t int_max = static_cast<size_t>(std::numeric_limits<int>::max());
  if (n > int_max - 8 || expected_size >= int_max) {
    throw Error(what + ": deflate stream too large (over 2 GiB) for the built-in decoder");
  }
  if (static_cast<uint64_t>(expected_size) > kDeflateMaxRatio * n + 1024) {
    throw Error(what + ": declares " + std::to_string(expected_size) + " bytes from " +
                std::to_string(n) + " compressed bytes, more than deflate can encode (corrupt size)");
  }
  // stb_image 2.27 refuses a Huffman code that ends in the last two input bytes (it expects
  // zlib's Adler-32 trailer after the stream), so decode from a copy with 8 zero bytes appended.
  // Harmless: decoding stops at the final block, and size and CRC checks catch truncation.
  std::vector<uint8_t> padded(n + 8, 0);
  if (n) std::memcpy(padded.data(), src, n);
  std::vector<uint8_t> out(expected_size + 1);
  const int got = stbi_zlib_decode_noheader_buffer(
      reinterpret_cast<char*>(out.data()), static_cast<int>(out.size()),
      reinterpret_cast<const char*>(padded.data()), static_cast<int>(padded.size()));
  if (got < 0 || static_cast<size_t>(got) > expected_size) {
    throw Error(what + ": corrupt deflate data, or it inflates to more than the declared " +
                std::to_string(expected_size) + " bytes");
  }
  if (static_cast<size_t>(got) != expected_size) {
    throw Error(what + ": inflates to " + std::to_string(got) + " bytes but declares " +
                std::to_string(expected_size));
  }
  out.resize(expected_size);
  return out;
#else
  (void)src;
  (void)n;
  (void)expected_size;
  throw Error(what + ": is deflate-compressed, but hawor was built with HAWOR_NO_STB "
              "(only stored members can be read)");
#endif
}

/// Compresses src[0, n) into a raw deflate stream (stb_image_write's encoder at `quality`,
/// its hash-chain length; 8 is stb's PNG default).
inline std::vector<uint8_t> deflateRaw(const uint8_t* src, size_t n, int quality = 8) {
#if HAWOR_HAVE_STB
  // stb doubles int-sized buffers while encoding: stay well below INT_MAX.
  if (n >= static_cast<size_t>(std::numeric_limits<int>::max() / 2)) {
    throw Error("deflate: input too large (1 GiB or more) for the built-in encoder");
  }
  // stb 1.16 emits no deflate data at all for empty input; the valid empty stream is one final
  // fixed-Huffman block holding only end-of-block: bits 1, 01, 0000000.
  if (n == 0) return {0x03, 0x00};
  int zlen = 0;
  // stb takes a non-const pointer but only reads.
  unsigned char* z = stbi_zlib_compress(const_cast<unsigned char*>(src), static_cast<int>(n),
                                        &zlen, quality);
  if (!z) throw Error("deflate: out of memory");
  if (zlen < 6) {
    HAWOR_STBIW_FREE(z);
    throw Error("deflate: encoder returned a malformed zlib stream");
  }
  // zlib stream = 2-byte header (CMF, FLG), raw deflate, 4-byte Adler-32.
  std::vector<uint8_t> out(z + 2, z + zlen - 4);
  HAWOR_STBIW_FREE(z);
  return out;
#else
  (void)src;
  (void)n;
  (void)quality;
  throw Error("deflate: compression unavailable (hawor built with HAWOR_NO_STB)");
#endif
}

}  // namespace HAWOR_IO_DEFLATE_NS
}  // namespace hawor
