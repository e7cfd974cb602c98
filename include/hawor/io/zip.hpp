// hawor/io/zip.hpp — a minimal ZIP archive reader and writer (PKWARE APPNOTE 6.3), enough for
// numpy's .npz files: stored (method 0) and deflated (method 8) members, ZIP64 extensions
// (numpy forces a ZIP64 extra on every member's local header), CRC-32 verified on extraction.
//
// Reading trusts only the central directory for sizes and offsets and checks everything against
// the buffer: EOCD / ZIP64 records, entry counts against the directory size, each local header's
// signature and name, member data before the central directory, no overlapping members, no
// duplicate names, no encryption, no multi-disk archives. Extraction caps the inflated size by
// the declared size and by ZipLimits::max_member_size (decompression-bomb guard).
// Thread-safety: a ZipReader is immutable after construction; concurrent extract() calls are safe.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "../common.hpp"
#include "deflate.hpp"
#include "detail/bytes.hpp"

namespace hawor {

namespace detail {
/// The CRC-32 table of ZIP / zlib (reflected polynomial 0xEDB88320), built at compile time.
struct Crc32Table {
  uint32_t v[256];
  constexpr Crc32Table() : v() {
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      v[i] = c;
    }
  }
};
inline constexpr Crc32Table kCrc32Table{};
}  // namespace detail

/// CRC-32 of ZIP / zlib / PNG. Chain calls by passing the previous result as `crc`.
inline uint32_t crc32(const uint8_t* p, size_t n, uint32_t crc = 0) {
  crc = ~crc;
  for (size_t i = 0; i < n; ++i) crc = detail::kCrc32Table.v[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

namespace detail {
constexpr uint32_t kZipLocalSig = 0x04034b50u;
constexpr uint32_t kZipCentralSig = 0x02014b50u;
constexpr uint32_t kZipEocdSig = 0x06054b50u;
constexpr uint32_t kZipEocd64Sig = 0x06064b50u;
constexpr uint32_t kZipLocator64Sig = 0x07064b50u;
constexpr size_t kZipLocalSize = 30, kZipCentralSize = 46, kZipEocdSize = 22;
constexpr size_t kZipEocd64Size = 56, kZipLocator64Size = 20;
constexpr uint32_t kZip32Max = 0xFFFFFFFFu;
constexpr uint16_t kZip16Max = 0xFFFFu;
}  // namespace detail

inline namespace HAWOR_IO_DEFLATE_NS {

/// Resource limits applied when reading archives.
struct ZipLimits {
  /// Largest uncompressed member extract() will produce (the built-in inflater stops below
  /// 2 GiB regardless). Lower it for untrusted input.
  uint64_t max_member_size = uint64_t(2) << 30;
  /// Largest number of central-directory entries accepted.
  uint64_t max_entries = uint64_t(1) << 20;
};

/// One member as described by the central directory.
struct ZipEntry {
  std::string name;
  uint16_t method = 0;  ///< 0 stored, 8 deflate
  uint16_t flags = 0;
  uint32_t crc32 = 0;
  uint64_t compressed_size = 0;
  uint64_t uncompressed_size = 0;
  uint64_t local_header_offset = 0;
  uint64_t data_offset = 0;  ///< first byte of the member's data in the archive
  bool zip64 = false;        ///< the central entry carried a ZIP64 extra field
};


/// Reads a ZIP archive held in memory. Does not own the bytes: they must outlive the reader.
class ZipReader {
 public:
  /// Parses the directory of data[0, n). `what` (usually the file name) prefixes every error.
  ZipReader(const uint8_t* data, size_t n, std::string what, ZipLimits limits = {})
      : data_(data), n_(n), what_(std::move(what)), limits_(limits) {
    parse();
  }

  const std::vector<ZipEntry>& entries() const { return entries_; }
  const std::string& what() const { return what_; }

  /// The entry called `name`, or nullptr.
  const ZipEntry* find(const std::string& name) const {
    for (const auto& e : entries_) {
      if (e.name == name) return &e;
    }
    return nullptr;
  }

  /// The member's uncompressed bytes, CRC-32 verified.
  std::vector<uint8_t> extract(const ZipEntry& e) const {
    const std::string where = what_ + ": member '" + e.name + "'";
    if (e.uncompressed_size > limits_.max_member_size) {
      throw Error(where + " declares " + std::to_string(e.uncompressed_size) +
                  " bytes, over the limit of " + std::to_string(limits_.max_member_size));
    }
    if (!detail::fitsSizeT(e.uncompressed_size)) throw Error(where + " is too large for this platform");
    const uint8_t* src = data_ + e.data_offset;
    const size_t csize = static_cast<size_t>(e.compressed_size);  // within n_ (checked in parse)
    std::vector<uint8_t> out;
    if (e.method == 0) {
      out.assign(src, src + csize);
    } else {
      out = inflateRaw(src, csize, static_cast<size_t>(e.uncompressed_size), where);
    }
    const uint32_t crc = crc32(out.data(), out.size());
    if (crc != e.crc32) {
      throw Error(where + ": CRC-32 mismatch (stored " + hex(e.crc32) + ", computed " + hex(crc) +
                  "): the archive is corrupt");
    }
    return out;
  }

  /// The uncompressed bytes of the member called `name` (error if absent).
  std::vector<uint8_t> extract(const std::string& name) const {
    const ZipEntry* e = find(name);
    if (!e) throw Error(what_ + ": no member named '" + name + "'");
    return extract(*e);
  }

 private:
  static std::string hex(uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%08x", static_cast<unsigned>(v));
    return b;
  }
  [[noreturn]] void fail(const std::string& why) const { throw Error(what_ + ": " + why); }

  uint64_t u16(uint64_t off) const { return detail::loadLE16(data_ + off); }
  uint64_t u32(uint64_t off) const { return detail::loadLE32(data_ + off); }
  uint64_t u64(uint64_t off) const { return detail::loadLE64(data_ + off); }

  void parse() {
    using namespace detail;
    if (n_ < kZipEocdSize || data_ == nullptr) fail("too short for a zip archive");
    // End of central directory: the last signature whose comment reaches exactly the end.
    uint64_t eocd = 0;
    bool found = false;
    const uint64_t lowest = n_ > kZipEocdSize + 0xFFFF ? n_ - kZipEocdSize - 0xFFFF : 0;
    for (uint64_t p = n_ - kZipEocdSize + 1; p-- > lowest;) {
      if (u32(p) == kZipEocdSig && p + kZipEocdSize + u16(p + 20) == n_) {
        eocd = p;
        found = true;
        break;
      }
    }
    if (!found) fail("no end-of-central-directory record (not a zip archive, or truncated)");
    uint64_t disk = u16(eocd + 4), cd_disk = u16(eocd + 6);
    uint64_t entries_disk = u16(eocd + 8), entries = u16(eocd + 10);
    uint64_t cd_size = u32(eocd + 12), cd_offset = u32(eocd + 16);
    uint64_t cd_limit = eocd;  // the central directory must end before this

    const bool has_locator =
        eocd >= kZipLocator64Size && u32(eocd - kZipLocator64Size) == kZipLocator64Sig;
    if (has_locator) {
      const uint64_t loc = eocd - kZipLocator64Size;
      const uint64_t rec = u64(loc + 8);
      if (u32(loc + 4) != 0 || u32(loc + 16) > 1) fail("multi-disk zip archives are not supported");
      if (rec > loc || loc - rec < kZipEocd64Size) fail("ZIP64 end-of-directory locator points outside the archive");
      if (u32(rec) != kZipEocd64Sig) fail("ZIP64 end-of-directory record has a bad signature");
      const uint64_t rec_size = u64(rec + 4);
      if (rec_size < kZipEocd64Size - 12 || rec_size > loc - rec - 12) {
        fail("ZIP64 end-of-directory record has a bad size");
      }
      disk = u32(rec + 16);
      cd_disk = u32(rec + 20);
      entries_disk = u64(rec + 24);
      entries = u64(rec + 32);
      cd_size = u64(rec + 40);
      cd_offset = u64(rec + 48);
      cd_limit = rec;
    } else if (entries == kZip16Max || cd_size == kZip32Max || cd_offset == kZip32Max) {
      fail("end-of-directory record needs ZIP64 values but there is no ZIP64 locator");
    }
    if (disk != 0 || cd_disk != 0 || entries_disk != entries) {
      fail("multi-disk zip archives are not supported");
    }
    uint64_t cd_end = 0;
    if (!checkedAdd(cd_offset, cd_size, &cd_end) || cd_end > cd_limit) {
      fail("central directory (offset " + std::to_string(cd_offset) + ", size " +
           std::to_string(cd_size) + ") lies outside the archive");
    }
    if (entries > limits_.max_entries) fail("too many entries (" + std::to_string(entries) + ")");
    uint64_t min_cd = 0;
    if (!checkedMul(entries, kZipCentralSize, &min_cd) || min_cd > cd_size) {
      fail("central directory of " + std::to_string(cd_size) + " bytes cannot hold " +
           std::to_string(entries) + " entries");
    }
    entries_.reserve(static_cast<size_t>(entries));

    uint64_t p = cd_offset;
    for (uint64_t i = 0; i < entries; ++i) {
      const std::string at = "central directory entry " + std::to_string(i);
      if (cd_end - p < kZipCentralSize) fail(at + " is truncated");
      if (u32(p) != kZipCentralSig) fail(at + " has a bad signature (bad central directory offset?)");
      ZipEntry e;
      e.flags = static_cast<uint16_t>(u16(p + 8));
      e.method = static_cast<uint16_t>(u16(p + 10));
      e.crc32 = static_cast<uint32_t>(u32(p + 16));
      e.compressed_size = u32(p + 20);
      e.uncompressed_size = u32(p + 24);
      const uint64_t name_len = u16(p + 28), extra_len = u16(p + 30), comment_len = u16(p + 32);
      uint64_t start_disk = u16(p + 34);
      e.local_header_offset = u32(p + 42);
      if (cd_end - p - kZipCentralSize < name_len + extra_len + comment_len) fail(at + " is truncated");
      const uint8_t* name = data_ + p + kZipCentralSize;
      e.name.assign(reinterpret_cast<const char*>(name), static_cast<size_t>(name_len));
      if (e.name.empty() || e.name.find('\0') != std::string::npos) fail(at + " has an invalid name");
      const std::string who = "member '" + e.name + "'";
      parseZip64Extra(p + kZipCentralSize + name_len, extra_len, &e, &start_disk, who);
      if (start_disk != 0) fail(who + " lies on another disk (multi-disk archives unsupported)");
      if (e.flags & 0x41u) fail(who + " is encrypted (not supported)");
      if (e.method != 0 && e.method != 8) {
        fail(who + " uses compression method " + std::to_string(e.method) +
             " (only stored and deflate are supported)");
      }
      if (e.method == 0 && e.compressed_size != e.uncompressed_size) {
        fail(who + " is stored but its compressed and uncompressed sizes differ");
      }
      checkLocalHeader(&e, cd_offset, who);
      entries_.push_back(std::move(e));
      p += kZipCentralSize + name_len + extra_len + comment_len;
    }
    checkLayout();
  }

  // ZIP64 extended information (header id 0x0001): 8-byte uncompressed size, compressed size,
  // local header offset, then 4-byte disk number, each present only if its 32-bit field is
  // saturated (APPNOTE 4.5.3).
  void parseZip64Extra(uint64_t off, uint64_t len, ZipEntry* e, uint64_t* disk,
                       const std::string& who) const {
    const bool need_u = e->uncompressed_size == detail::kZip32Max;
    const bool need_c = e->compressed_size == detail::kZip32Max;
    const bool need_o = e->local_header_offset == detail::kZip32Max;
    const bool need_d = *disk == detail::kZip16Max;
    uint64_t q = off;
    const uint64_t end = off + len;
    while (end - q >= 4) {
      const uint64_t id = u16(q), size = u16(q + 2);
      if (size > end - q - 4) fail(who + " has a truncated extra field");
      if (id == 0x0001) {
        uint64_t r = q + 4;
        const uint64_t r_end = r + size;
        const auto take = [&](size_t bytes) -> uint64_t {
          if (r_end - r < bytes) fail(who + " has a ZIP64 extra field that is too short");
          const uint64_t v = detail::loadLE(data_ + r, bytes);
          r += bytes;
          return v;
        };
        if (need_u) e->uncompressed_size = take(8);
        if (need_c) e->compressed_size = take(8);
        if (need_o) e->local_header_offset = take(8);
        if (need_d) *disk = take(4);
        e->zip64 = true;
      }
      q += 4 + size;
    }
    if ((need_u || need_c || need_o || need_d) && !e->zip64) {
      fail(who + " has saturated size/offset fields but no ZIP64 extra field");
    }
  }

  // The local header must be where the directory says, carry the same name, and the data it
  // introduces must end before the central directory.
  void checkLocalHeader(ZipEntry* e, uint64_t cd_offset, const std::string& who) const {
    using namespace detail;
    const uint64_t lho = e->local_header_offset;
    if (lho > cd_offset || cd_offset - lho < kZipLocalSize) {
      fail(who + ": local header offset " + std::to_string(lho) + " lies outside the archive data");
    }
    if (u32(lho) != kZipLocalSig) fail(who + ": bad local header signature (bad offset?)");
    const uint64_t name_len = u16(lho + 26), extra_len = u16(lho + 28);
    const uint64_t data_off = lho + kZipLocalSize + name_len + extra_len;
    uint64_t data_end = 0;
    if (data_off > cd_offset || !checkedAdd(data_off, e->compressed_size, &data_end) ||
        data_end > cd_offset) {
      fail(who + ": member data (" + std::to_string(e->compressed_size) +
           " bytes) runs past the central directory (lying sizes or truncated archive)");
    }
    if (name_len != e->name.size() ||
        std::memcmp(data_ + lho + kZipLocalSize, e->name.data(), e->name.size()) != 0) {
      fail(who + ": local header name differs from the central directory");
    }
    e->data_offset = data_off;
  }

  // Members must not overlap (overlap is the trick behind non-recursive zip bombs) and names
  // must be unique.
  void checkLayout() const {
    std::vector<std::pair<uint64_t, uint64_t>> spans;
    std::vector<std::string> names;
    spans.reserve(entries_.size());
    names.reserve(entries_.size());
    for (const auto& e : entries_) {
      spans.emplace_back(e.local_header_offset, e.data_offset + e.compressed_size);
      names.push_back(e.name);
    }
    std::sort(spans.begin(), spans.end());
    for (size_t i = 1; i < spans.size(); ++i) {
      if (spans[i].first < spans[i - 1].second) fail("members overlap (malformed or zip bomb)");
    }
    std::sort(names.begin(), names.end());
    for (size_t i = 1; i < names.size(); ++i) {
      if (names[i] == names[i - 1]) fail("duplicate member name '" + names[i] + "'");
    }
  }

  const uint8_t* data_;
  size_t n_;
  std::string what_;
  ZipLimits limits_;
  std::vector<ZipEntry> entries_;
};

/// Builds a ZIP archive in memory: add() members, then finish(). Timestamps are fixed
/// (1980-01-01 00:00) so that equal inputs give identical archives. ZIP64 records are written
/// when a size, offset or count needs them, or for every member with force_zip64 (as numpy does).
class ZipWriter {
 public:
  explicit ZipWriter(bool force_zip64 = false) : force_zip64_(force_zip64) {}

  /// Appends a member. compress = deflate, kept only when it is smaller than the data (else
  /// stored, like zip tools do; members of 1 GiB or more are always stored). Throws on duplicate
  /// or invalid names, and when compression is requested in a HAWOR_NO_STB build.
  void add(const std::string& name, const uint8_t* data, size_t n, bool compress) {
    if (name.empty() || name.size() > 0xFFFF || name.find('\0') != std::string::npos) {
      throw Error("zip: invalid member name '" + name + "'");
    }
    for (const auto& it : items_) {
      if (it.name == name) throw Error("zip: duplicate member name '" + name + "'");
    }
    Item it;
    it.name = name;
    it.crc = crc32(data, n);
    it.usize = n;
    it.offset = out_.size();
    std::vector<uint8_t> packed;
    bool deflated = false;
    // The built-in encoder grows int-sized buffers: members of 1 GiB and more are stored.
    const bool fits = n < static_cast<size_t>(std::numeric_limits<int>::max() / 2);
    if (compress && n > 0 && fits) {
      packed = deflateRaw(data, n);
      deflated = packed.size() < n;
    } else if (compress) {
      (void)deflateRaw(data, 0);  // surfaces HAWOR_NO_STB consistently
    }
    it.method = deflated ? 8 : 0;
    it.csize = deflated ? packed.size() : n;
    it.zip64 = force_zip64_ || it.usize >= detail::kZip32Max || it.csize >= detail::kZip32Max;
    it.utf8 = std::any_of(name.begin(), name.end(), [](char c) { return (c & 0x80) != 0; });

    // Local file header.
    detail::appendLE(out_, detail::kZipLocalSig, 4);
    detail::appendLE(out_, it.zip64 ? 45 : 20, 2);  // version needed
    detail::appendLE(out_, it.utf8 ? 0x0800 : 0, 2);
    detail::appendLE(out_, it.method, 2);
    detail::appendLE(out_, 0, 2);      // time 00:00:00
    detail::appendLE(out_, 0x21, 2);   // date 1980-01-01
    detail::appendLE(out_, it.crc, 4);
    detail::appendLE(out_, it.zip64 ? detail::kZip32Max : it.csize, 4);
    detail::appendLE(out_, it.zip64 ? detail::kZip32Max : it.usize, 4);
    detail::appendLE(out_, name.size(), 2);
    detail::appendLE(out_, it.zip64 ? 20 : 0, 2);
    out_.insert(out_.end(), name.begin(), name.end());
    if (it.zip64) {  // the local ZIP64 extra always holds both sizes
      detail::appendLE(out_, 0x0001, 2);
      detail::appendLE(out_, 16, 2);
      detail::appendLE(out_, it.usize, 8);
      detail::appendLE(out_, it.csize, 8);
    }
    if (deflated) {
      out_.insert(out_.end(), packed.begin(), packed.end());
    } else if (n > 0) {
      out_.insert(out_.end(), data, data + n);
    }
    items_.push_back(std::move(it));
  }

  void add(const std::string& name, const std::vector<uint8_t>& data, bool compress) {
    add(name, data.data(), data.size(), compress);
  }

  /// Writes the central directory and end records and returns the archive; the writer is
  /// left empty.
  std::vector<uint8_t> finish() {
    using detail::appendLE;
    const uint64_t cd_offset = out_.size();
    for (const auto& it : items_) {
      const bool big_u = force_zip64_ || it.usize >= detail::kZip32Max;
      const bool big_c = force_zip64_ || it.csize >= detail::kZip32Max;
      const bool big_o = force_zip64_ || it.offset >= detail::kZip32Max;
      const uint64_t extra = 8 * (big_u + big_c + big_o);
      const bool z64 = it.zip64 || extra > 0;
      appendLE(out_, detail::kZipCentralSig, 4);
      appendLE(out_, (3u << 8) | (z64 ? 45u : 20u), 2);  // made by: Unix, spec version
      appendLE(out_, z64 ? 45 : 20, 2);
      appendLE(out_, it.utf8 ? 0x0800 : 0, 2);
      appendLE(out_, it.method, 2);
      appendLE(out_, 0, 2);
      appendLE(out_, 0x21, 2);
      appendLE(out_, it.crc, 4);
      appendLE(out_, big_c ? detail::kZip32Max : it.csize, 4);
      appendLE(out_, big_u ? detail::kZip32Max : it.usize, 4);
      appendLE(out_, it.name.size(), 2);
      appendLE(out_, extra ? extra + 4 : 0, 2);
      appendLE(out_, 0, 2);                        // comment length
      appendLE(out_, 0, 2);                        // disk number start
      appendLE(out_, 0, 2);                        // internal attributes
      appendLE(out_, uint64_t(0100644) << 16, 4);  // external: regular file rw-r--r--
      appendLE(out_, big_o ? detail::kZip32Max : it.offset, 4);
      out_.insert(out_.end(), it.name.begin(), it.name.end());
      if (extra) {
        appendLE(out_, 0x0001, 2);
        appendLE(out_, extra, 2);
        if (big_u) appendLE(out_, it.usize, 8);
        if (big_c) appendLE(out_, it.csize, 8);
        if (big_o) appendLE(out_, it.offset, 8);
      }
    }
    const uint64_t cd_size = out_.size() - cd_offset;
    const uint64_t count = items_.size();
    const bool z64 = force_zip64_ || count >= detail::kZip16Max ||
                     cd_size >= detail::kZip32Max || cd_offset >= detail::kZip32Max;
    if (z64) {
      const uint64_t rec = out_.size();
      appendLE(out_, detail::kZipEocd64Sig, 4);
      appendLE(out_, detail::kZipEocd64Size - 12, 8);
      appendLE(out_, (3u << 8) | 45u, 2);
      appendLE(out_, 45, 2);
      appendLE(out_, 0, 4);
      appendLE(out_, 0, 4);
      appendLE(out_, count, 8);
      appendLE(out_, count, 8);
      appendLE(out_, cd_size, 8);
      appendLE(out_, cd_offset, 8);
      appendLE(out_, detail::kZipLocator64Sig, 4);
      appendLE(out_, 0, 4);
      appendLE(out_, rec, 8);
      appendLE(out_, 1, 4);
    }
    appendLE(out_, detail::kZipEocdSig, 4);
    appendLE(out_, 0, 2);
    appendLE(out_, 0, 2);
    appendLE(out_, z64 ? detail::kZip16Max : count, 2);
    appendLE(out_, z64 ? detail::kZip16Max : count, 2);
    appendLE(out_, z64 ? detail::kZip32Max : cd_size, 4);
    appendLE(out_, z64 ? detail::kZip32Max : cd_offset, 4);
    appendLE(out_, 0, 2);
    items_.clear();
    std::vector<uint8_t> result;
    result.swap(out_);
    return result;
  }

 private:
  struct Item {
    std::string name;
    uint16_t method = 0;
    uint32_t crc = 0;
    uint64_t csize = 0, usize = 0, offset = 0;
    bool zip64 = false, utf8 = false;
  };
  bool force_zip64_;
  std::vector<uint8_t> out_;
  std::vector<Item> items_;
};

}  // namespace HAWOR_IO_DEFLATE_NS
}  // namespace hawor
