// hawor/io/npz.hpp — numpy's .npz archives: a ZIP of "<key>.npy" members (np.savez stores them,
// np.savez_compressed deflates them).
//
// Reading parses every "*.npy" member eagerly; members with other names (and directories) are
// ignored, as they are not arrays. Errors name the file and the member or key.
// Thread-safety: an Npz is a plain value; const member functions may run concurrently.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "../common.hpp"
#include "file.hpp"
#include "npy.hpp"
#include "zip.hpp"

namespace hawor {
inline namespace HAWOR_IO_DEFLATE_NS {

/// A named collection of arrays, read from or written to a .npz file.
class Npz {
 public:
  Npz() = default;

  /// Reads an .npz file; `limits` bounds what a (possibly hostile) archive may inflate to.
  static Npz read(const std::string& path, const ZipLimits& limits = {}) {
    const std::vector<uint8_t> b = readFileBytes(path);
    return fromBuffer(b.data(), b.size(), path, limits);
  }

  /// Parses an .npz archive held in memory; `what` names it in errors.
  static Npz fromBuffer(const uint8_t* data, size_t n, const std::string& what = "npz buffer",
                        const ZipLimits& limits = {}) {
    Npz z;
    z.source_ = what;
    const ZipReader zip(data, n, what, limits);
    const std::string ext = ".npy";
    for (const ZipEntry& e : zip.entries()) {
      if (e.name.size() <= ext.size() ||
          e.name.compare(e.name.size() - ext.size(), ext.size(), ext) != 0) {
        continue;  // not an array member (numpy would hand back raw bytes)
      }
      const std::string key = e.name.substr(0, e.name.size() - ext.size());
      const std::vector<uint8_t> bytes = zip.extract(e);
      z.set(key, parseNpy(bytes.data(), bytes.size(), what + ": member '" + e.name + "'"));
    }
    return z;
  }

  static Npz fromBuffer(const std::vector<uint8_t>& bytes, const std::string& what = "npz buffer",
                        const ZipLimits& limits = {}) {
    return fromBuffer(bytes.data(), bytes.size(), what, limits);
  }

  /// Keys in file (or insertion) order.
  const std::vector<std::string>& names() const { return names_; }
  size_t size() const { return names_.size(); }
  bool has(const std::string& name) const { return arrays_.count(name) != 0; }
  /// The file (or "npz buffer") this archive was read from, for messages.
  const std::string& source() const { return source_; }

  /// The array stored under `name`; throws naming the key, the file and the keys present.
  const NpyArray& get(const std::string& name) const {
    const auto it = arrays_.find(name);
    if (it == arrays_.end()) {
      std::string keys;
      for (size_t i = 0; i < names_.size() && i < 20; ++i) keys += (i ? ", " : "") + names_[i];
      if (names_.size() > 20) keys += ", ...";
      throw Error(source_ + ": no array named '" + name + "' (keys: " +
                  (keys.empty() ? std::string("none") : keys) + ")");
    }
    return it->second;
  }

  /// get(name).as<T>() with the file and key in conversion errors.
  template <typename T>
  std::vector<T> getAs(const std::string& name) const {
    return get(name).as<T>(source_ + ": array '" + name + "'");
  }

  /// Adds or replaces an array (validated).
  void set(const std::string& name, NpyArray a) {
    if (name.empty() || name.find('\0') != std::string::npos) {
      throw Error(source_ + ": invalid array name '" + name + "'");
    }
    a.validate(source_ + ": array '" + name + "'");
    const auto it = arrays_.find(name);
    if (it == arrays_.end()) {
      names_.push_back(name);
      arrays_.emplace(name, std::move(a));
    } else {
      it->second = std::move(a);
    }
  }

  /// The archive bytes: members "<key>.npy" in names() order, deflated when `compressed`
  /// (np.savez_compressed) else stored (np.savez); force_zip64 adds ZIP64 records everywhere.
  std::vector<uint8_t> toBuffer(bool compressed = false, bool force_zip64 = false) const {
    ZipWriter w(force_zip64);
    for (const auto& name : names_) {
      w.add(name + ".npy", writeNpy(arrays_.at(name), source_ + ": array '" + name + "'"),
            compressed);
    }
    return w.finish();
  }

  void write(const std::string& path, bool compressed = false) const {
    writeFileBytes(path, toBuffer(compressed));
  }

 private:
  std::string source_ = "npz";
  std::vector<std::string> names_;
  std::map<std::string, NpyArray> arrays_;
};

}  // namespace HAWOR_IO_DEFLATE_NS
}  // namespace hawor
