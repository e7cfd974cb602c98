// hawor/io/gltf.hpp — binary glTF 2.0 (.glb) files: the scene graph, skins, meshes and the typed
// accessor data that a skinned mesh needs (glTF 2.0 specification, "GLB File Format
// Specification" and "Binary Data Storage" / "Accessors" / "Nodes" / "Skins" sections).
//
// Layout of a .glb: a 12-byte header (magic "glTF", version 2, total length), then chunks of
// (uint32 length, uint32 type, data): first the JSON chunk ("JSON"), optionally the binary chunk
// ("BIN\0"), which backs buffer 0 when that buffer has no uri; other chunk types are skipped.
// Everything is little-endian.
//
// What is read: asset.version (2.x) and extensionsRequired (only KHR_mesh_quantization, which
// only widens accessor types, is accepted); buffers; bufferViews (byteOffset, byteLength,
// byteStride); accessors (componentType byte/ubyte/short/ushort/uint/float, normalized, count,
// type SCALAR…MAT4, byteOffset; sparse accessors are refused); nodes (name, children, mesh,
// skin, matrix or translation/rotation/scale); skins (joints, inverseBindMatrices, skeleton);
// meshes (primitives: attributes, indices, mode). Materials, textures, animations, cameras and
// scenes are not interpreted. Buffers with a uri (external files, data URIs) are recorded but
// cannot be read: a .glb hand model keeps its data in the BIN chunk.
//
// Safety: the file is untrusted. Every index is range-checked and every byte range is checked
// against its bufferView and buffer when the file is opened (with overflow-safe arithmetic), so
// reads afterwards cannot go out of bounds; sizes and counts are capped by GltfLimits; the node
// graph must be a forest (one parent per node, no cycles) and is walked iteratively. Any
// violation throws hawor::Error naming the file, the object (e.g. "accessors[3]") and the problem.
//
// Transforms are column-vector 4×4 matrices in the glTF frame (right-handed, +y up, metres);
// node rotations are unit quaternions (x, y, z, w) — renormalised here.
// Thread-safety: a Gltf is an immutable value after construction; const methods may run
// concurrently.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <locale>
#include <sstream>
#include <string>
#include <vector>

#include "../common.hpp"
#include "file.hpp"
#include "json.hpp"

namespace hawor {

/// Resource limits of the glTF reader (defaults are far above any hand or body model).
struct GltfLimits {
  JsonLimits json;                          ///< limits of the JSON chunk
  size_t maxObjects = size_t(1) << 16;      ///< nodes, accessors, meshes, ... of each kind
  size_t maxAccessorCount = size_t(1) << 24;  ///< elements of one accessor
  size_t maxAccessorValues = size_t(1) << 24;  ///< count × components of one accessor
};

/// glTF constants (componentType, primitive mode).
namespace gltf {
constexpr int kByte = 5120;
constexpr int kUnsignedByte = 5121;
constexpr int kShort = 5122;
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;
constexpr int kFloat = 5126;
constexpr int kModeTriangles = 4;
constexpr uint32_t kMagic = 0x46546C67u;      // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534Au;  // "JSON"
constexpr uint32_t kChunkBin = 0x004E4942u;   // "BIN\0"

/// Bytes of one component of `componentType` (0 when unknown).
inline size_t componentSize(int componentType) {
  switch (componentType) {
    case kByte:
    case kUnsignedByte: return 1;
    case kShort:
    case kUnsignedShort: return 2;
    case kUnsignedInt:
    case kFloat: return 4;
    default: return 0;
  }
}

inline const char* componentName(int componentType) {
  switch (componentType) {
    case kByte: return "BYTE";
    case kUnsignedByte: return "UNSIGNED_BYTE";
    case kShort: return "SHORT";
    case kUnsignedShort: return "UNSIGNED_SHORT";
    case kUnsignedInt: return "UNSIGNED_INT";
    case kFloat: return "FLOAT";
    default: return "unknown";
  }
}
}  // namespace gltf

struct GltfBuffer {
  size_t byteLength = 0;
  std::string uri;       ///< empty: the GLB binary chunk (buffer 0 only)
  bool inBinChunk = false;
};

struct GltfBufferView {
  size_t buffer = 0;
  size_t byteOffset = 0;
  size_t byteLength = 0;
  size_t byteStride = 0;  ///< 0: elements tightly packed
};

struct GltfAccessor {
  int bufferView = -1;     ///< −1: all zeros (glTF allows accessors without data)
  size_t byteOffset = 0;
  int componentType = gltf::kFloat;
  bool normalized = false;
  size_t count = 0;
  std::string type;        ///< "SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"
  int components = 1;      ///< values per element (MAT4: 16)
  int columns = 1;         ///< matrix columns (1 for scalars and vectors)

  /// Bytes of one column: rows × component size, padded to 4 bytes for matrices (glTF
  /// "Data Alignment": matrix columns start on 4-byte boundaries).
  size_t columnBytes() const {
    const size_t raw = static_cast<size_t>(components / columns) * gltf::componentSize(componentType);
    return columns > 1 ? (raw + 3) / 4 * 4 : raw;
  }
  size_t elementBytes() const { return columnBytes() * static_cast<size_t>(columns); }
};

struct GltfNode {
  std::string name;
  int parent = -1;              ///< derived from the children lists
  std::vector<int> children;
  int mesh = -1;
  int skin = -1;
  Mat4<double> local = Mat4<double>::Identity();  ///< matrix, or T·R·S
};

struct GltfSkin {
  std::string name;
  std::vector<int> joints;       ///< node indices
  int inverseBindMatrices = -1;  ///< accessor (MAT4 float) or −1 (identity matrices)
  int skeleton = -1;
};

struct GltfPrimitive {
  std::vector<std::string> attributeNames;
  std::vector<int> attributeAccessors;
  int indices = -1;  ///< accessor or −1 (non-indexed)
  int mode = gltf::kModeTriangles;

  /// The accessor of attribute `name` ("POSITION", "JOINTS_0", ...) or −1.
  int attribute(const std::string& name) const {
    for (size_t i = 0; i < attributeNames.size(); ++i) {
      if (attributeNames[i] == name) return attributeAccessors[i];
    }
    return -1;
  }
};

struct GltfMesh {
  std::string name;
  std::vector<GltfPrimitive> primitives;
};

/// A parsed .glb file. Construct with Gltf::fromGlb (bytes) or Gltf::readGlb (path).
class Gltf {
 public:
  static Gltf fromGlb(const uint8_t* data, size_t n, const std::string& what = "GLB",
                      const GltfLimits& limits = {}) {
    Gltf g;
    g.what_ = what;
    g.parseContainer(data, n, limits);
    g.parseDocument(limits);
    return g;
  }
  static Gltf fromGlb(const std::vector<uint8_t>& bytes, const std::string& what = "GLB",
                      const GltfLimits& limits = {}) {
    return fromGlb(bytes.data(), bytes.size(), what, limits);
  }
  static Gltf readGlb(const std::string& path, const GltfLimits& limits = {}) {
    const std::vector<uint8_t> b = readFileBytes(path);
    return fromGlb(b.data(), b.size(), path, limits);
  }

  /// The file (or name) used in error messages.
  const std::string& source() const { return what_; }
  const JsonValue& json() const { return json_; }
  const std::vector<GltfBuffer>& buffers() const { return buffers_; }
  const std::vector<GltfBufferView>& bufferViews() const { return views_; }
  const std::vector<GltfAccessor>& accessors() const { return accessors_; }
  const std::vector<GltfNode>& nodes() const { return nodes_; }
  const std::vector<GltfSkin>& skins() const { return skins_; }
  const std::vector<GltfMesh>& meshes() const { return meshes_; }
  /// The binary chunk (empty when the file has none).
  const std::vector<uint8_t>& binChunk() const { return bin_; }

  /// World transform of a node: the product of the local transforms from its root down.
  const Mat4<double>& nodeWorld(int node) const {
    checkIndex(node, nodes_.size(), "node");
    return world_[static_cast<size_t>(node)];
  }

  /// Values of an accessor as doubles, count × components, element by element (matrices
  /// column-major as stored). Normalised integers map to [0,1] / [−1,1] (glTF "Animations"
  /// normalisation: c/255, max(c/127, −1), ...); other integers keep their value.
  std::vector<double> readFloats(int accessor) const {
    const GltfAccessor& a = accessorAt(accessor);
    std::vector<double> out(a.count * static_cast<size_t>(a.components), 0.0);
    if (a.bufferView < 0) return out;
    const int rows = a.components / a.columns;
    const size_t cs = gltf::componentSize(a.componentType);
    size_t k = 0;
    forEachElement(a, [&](const uint8_t* e) {
      for (int c = 0; c < a.columns; ++c) {
        const uint8_t* col = e + static_cast<size_t>(c) * a.columnBytes();
        for (int r = 0; r < rows; ++r) out[k++] = decode(col + static_cast<size_t>(r) * cs, a);
      }
    });
    return out;
  }

  /// Values of an unsigned-integer accessor (UNSIGNED_BYTE/SHORT/INT, not normalised), as used
  /// for indices and JOINTS_n. Throws for any other component type.
  std::vector<uint32_t> readUints(int accessor) const {
    const GltfAccessor& a = accessorAt(accessor);
    const std::string w = what_ + ": accessors[" + std::to_string(accessor) + "]";
    if (a.componentType != gltf::kUnsignedByte && a.componentType != gltf::kUnsignedShort &&
        a.componentType != gltf::kUnsignedInt) {
      throw Error(w + " has component type " + gltf::componentName(a.componentType) +
                  ", expected an unsigned integer type (UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT)");
    }
    if (a.normalized) throw Error(w + " is normalized, expected plain integers");
    std::vector<uint32_t> out(a.count * static_cast<size_t>(a.components), 0u);
    if (a.bufferView < 0) return out;
    const int rows = a.components / a.columns;
    const size_t cs = gltf::componentSize(a.componentType);
    size_t k = 0;
    forEachElement(a, [&](const uint8_t* e) {
      for (int c = 0; c < a.columns; ++c) {
        const uint8_t* col = e + static_cast<size_t>(c) * a.columnBytes();
        for (int r = 0; r < rows; ++r) out[k++] = static_cast<uint32_t>(loadUint(col + static_cast<size_t>(r) * cs, cs));
      }
    });
    return out;
  }

  /// Index of the first node called `name`, or −1.
  int findNode(const std::string& name) const {
    for (size_t i = 0; i < nodes_.size(); ++i) {
      if (nodes_[i].name == name) return static_cast<int>(i);
    }
    return -1;
  }

 private:
  Gltf() = default;

  [[noreturn]] void fail(const std::string& msg) const { throw Error(what_ + ": " + msg); }

  void checkIndex(int i, size_t n, const char* kind) const {
    if (i < 0 || static_cast<size_t>(i) >= n) {
      fail(std::string("no ") + kind + " " + std::to_string(i) + " (the file has " + std::to_string(n) + ")");
    }
  }

  const GltfAccessor& accessorAt(int i) const {
    checkIndex(i, accessors_.size(), "accessor");
    return accessors_[static_cast<size_t>(i)];
  }

  static uint64_t loadUint(const uint8_t* p, size_t n) {
    uint64_t v = 0;
    for (size_t i = 0; i < n; ++i) v |= static_cast<uint64_t>(p[i]) << (8 * i);
    return v;
  }

  static double decode(const uint8_t* p, const GltfAccessor& a) {
    switch (a.componentType) {
      case gltf::kFloat: {
        const uint32_t bits = static_cast<uint32_t>(loadUint(p, 4));
        float f;
        std::memcpy(&f, &bits, 4);
        return static_cast<double>(f);
      }
      case gltf::kUnsignedByte: {
        const double c = static_cast<double>(p[0]);
        return a.normalized ? c / 255.0 : c;
      }
      case gltf::kByte: {
        const double c = static_cast<double>(static_cast<int8_t>(p[0]));
        return a.normalized ? std::max(c / 127.0, -1.0) : c;
      }
      case gltf::kUnsignedShort: {
        const double c = static_cast<double>(loadUint(p, 2));
        return a.normalized ? c / 65535.0 : c;
      }
      case gltf::kShort: {
        const double c = static_cast<double>(static_cast<int16_t>(static_cast<uint16_t>(loadUint(p, 2))));
        return a.normalized ? std::max(c / 32767.0, -1.0) : c;
      }
      case gltf::kUnsignedInt: return static_cast<double>(loadUint(p, 4));
      default: return 0.0;
    }
  }

  /// Calls fn(pointer to element e) for every element of a (validated) accessor with data.
  template <typename Fn>
  void forEachElement(const GltfAccessor& a, Fn&& fn) const {
    const GltfBufferView& v = views_[static_cast<size_t>(a.bufferView)];
    if (!buffers_[v.buffer].inBinChunk) {
      fail("an accessor uses buffer " + std::to_string(v.buffer) + " with uri '" + buffers_[v.buffer].uri.substr(0, 64) +
           "': external and data-URI buffers are not supported (use a .glb with a binary chunk)");
    }
    const uint8_t* base = bin_.data() + v.byteOffset + a.byteOffset;
    const size_t stride = v.byteStride ? v.byteStride : a.elementBytes();
    for (size_t e = 0; e < a.count; ++e) fn(base + e * stride);
  }

  // --- container -----------------------------------------------------------------------------

  void parseContainer(const uint8_t* d, size_t n, const GltfLimits& limits) {
    if (d == nullptr && n != 0) fail("null input");
    if (n < 12) fail("too short for a GLB header (" + std::to_string(n) + " bytes, need 12)");
    const uint32_t magic = static_cast<uint32_t>(loadUint(d, 4));
    if (magic != gltf::kMagic) {
      if (d[0] == '{' || d[0] == ' ' || d[0] == '\n' || d[0] == '\r' || d[0] == '\t') {
        fail("not a binary glTF file (looks like a .gltf JSON file; only .glb is supported)");
      }
      fail("not a binary glTF file (the first 4 bytes are not \"glTF\")");
    }
    const uint32_t version = static_cast<uint32_t>(loadUint(d + 4, 4));
    if (version != 2) fail("GLB container version " + std::to_string(version) + " is not supported (only 2)");
    const uint64_t length = loadUint(d + 8, 4);
    if (length > n) {
      fail("truncated: the header declares " + std::to_string(length) + " bytes, the file has " + std::to_string(n));
    }
    if (length < 20) fail("the header declares a length of " + std::to_string(length) + " bytes, too short for a JSON chunk");
    size_t off = 12;
    int chunkIndex = 0;
    bool haveJson = false, haveBin = false;
    while (off < length) {
      if (length - off < 8) {
        fail("chunk " + std::to_string(chunkIndex) + " header at byte " + std::to_string(off) +
             " is cut off by the declared length " + std::to_string(length));
      }
      const uint64_t clen = loadUint(d + off, 4);
      const uint32_t ctype = static_cast<uint32_t>(loadUint(d + off + 4, 4));
      if (clen > length - off - 8) {
        fail("chunk " + std::to_string(chunkIndex) + " at byte " + std::to_string(off) + " declares " +
             std::to_string(clen) + " bytes but only " + std::to_string(length - off - 8) + " remain");
      }
      const uint8_t* cdata = d + off + 8;
      if (chunkIndex == 0) {
        if (ctype != gltf::kChunkJson) fail("the first chunk is not the JSON chunk");
        if (clen > limits.json.maxBytes) {
          fail("JSON chunk of " + std::to_string(clen) + " bytes is over the limit of " +
               std::to_string(limits.json.maxBytes));
        }
        // Trailing spaces (the chunk padding) and NULs written by some exporters are not JSON.
        size_t jn = static_cast<size_t>(clen);
        while (jn > 0 && (cdata[jn - 1] == ' ' || cdata[jn - 1] == 0)) --jn;
        json_ = parseJson(reinterpret_cast<const char*>(cdata), jn, what_ + ": JSON chunk", limits.json);
        haveJson = true;
      } else if (ctype == gltf::kChunkJson) {
        fail("a second JSON chunk (chunk " + std::to_string(chunkIndex) + ")");
      } else if (ctype == gltf::kChunkBin) {
        if (haveBin) fail("a second BIN chunk (chunk " + std::to_string(chunkIndex) + ")");
        if (chunkIndex != 1) fail("the BIN chunk must directly follow the JSON chunk");
        bin_.assign(cdata, cdata + clen);
        haveBin = true;
      }  // other chunk types: skipped, as the specification asks
      off += 8 + static_cast<size_t>(clen);
      ++chunkIndex;
    }
    if (!haveJson) fail("no JSON chunk");
    hasBinChunk_ = haveBin;
  }

  // --- JSON helpers ------------------------------------------------------------------------------

  const std::vector<JsonValue>& arrayOf(const char* key, const GltfLimits& limits) const {
    static const std::vector<JsonValue> empty;
    const JsonValue* v = json_.find(key);
    if (!v) return empty;
    const auto& items = v->items(what_ + ": '" + key + "'");
    if (items.size() > limits.maxObjects) {
      fail(std::string("'") + key + "' has " + std::to_string(items.size()) + " entries, over the limit of " +
           std::to_string(limits.maxObjects));
    }
    return items;
  }

  /// A non-negative integer (JSON number with no fraction) no larger than `maxValue`.
  size_t integer(const JsonValue& v, const std::string& where, size_t maxValue) const {
    const double d = v.asNumber(what_ + ": " + where);
    if (!(d >= 0) || d != std::floor(d) || d > static_cast<double>(maxValue)) {
      fail(where + " must be an integer in [0, " + std::to_string(maxValue) + "], found " + numberText(d));
    }
    return static_cast<size_t>(d);
  }
  static std::string numberText(double d) {
    std::ostringstream s;
    s.imbue(std::locale::classic());
    s.precision(17);
    s << d;
    return s.str();
  }
  /// An optional integer member; `dflt` when absent.
  size_t optInteger(const JsonValue& obj, const char* key, const std::string& where, size_t maxValue,
                    size_t dflt) const {
    const JsonValue* v = obj.find(key);
    return v ? integer(*v, where + "." + key, maxValue) : dflt;
  }
  size_t reqInteger(const JsonValue& obj, const char* key, const std::string& where, size_t maxValue) const {
    const JsonValue* v = obj.find(key);
    if (!v) fail(where + " has no '" + key + "'");
    return integer(*v, where + "." + key, maxValue);
  }
  /// An optional index into an array of n objects; −1 when absent.
  int optIndex(const JsonValue& obj, const char* key, const std::string& where, size_t n, const char* kind) const {
    const JsonValue* v = obj.find(key);
    if (!v) return -1;
    const size_t i = integer(*v, where + "." + key, std::numeric_limits<uint32_t>::max());
    if (i >= n) {
      fail(where + "." + key + " = " + std::to_string(i) + " refers to a missing " + kind + " (the file has " +
           std::to_string(n) + ")");
    }
    return static_cast<int>(i);
  }
  void numbers(const JsonValue& obj, const char* key, const std::string& where, size_t count, double* out) const {
    const JsonValue* v = obj.find(key);
    if (!v) return;
    const auto& items = v->items(what_ + ": " + where + "." + key);
    if (items.size() != count) {
      fail(where + "." + key + " has " + std::to_string(items.size()) + " numbers, expected " + std::to_string(count));
    }
    for (size_t i = 0; i < count; ++i) {
      out[i] = items[i].asNumber(what_ + ": " + where + "." + key + "[" + std::to_string(i) + "]");
      if (!std::isfinite(out[i])) fail(where + "." + key + " has a non-finite value");
    }
  }
  static std::string at(const char* kind, size_t i) { return std::string(kind) + "[" + std::to_string(i) + "]"; }
  const JsonValue& object(const JsonValue& v, const std::string& where) const {
    if (!v.isObject()) fail(where + " must be an object, found " + JsonValue::typeName(v.type()));
    return v;
  }

  // --- document ------------------------------------------------------------------------------

  void parseDocument(const GltfLimits& limits) {
    if (!json_.isObject()) fail("the JSON chunk is " + std::string(JsonValue::typeName(json_.type())) + ", expected an object");
    parseAsset();
    parseBuffers(limits);
    parseViews(limits);
    parseAccessors(limits);
    parseMeshes(limits);
    parseSkins(limits);
    parseNodes(limits);
    computeWorld();
  }

  void parseAsset() {
    const JsonValue* asset = json_.find("asset");
    if (!asset) fail("no 'asset' object (not a glTF 2.0 file)");
    object(*asset, "asset");
    const JsonValue* version = asset->find("version");
    if (!version) fail("asset has no 'version'");
    const std::string& ver = version->asString(what_ + ": asset.version");
    if (ver.size() < 2 || ver[0] != '2' || ver[1] != '.') fail("glTF version '" + ver + "' is not supported (only 2.x)");
    if (const JsonValue* minv = asset->find("minVersion")) {
      const std::string& mv = minv->asString(what_ + ": asset.minVersion");
      if (mv != "2.0") fail("asset.minVersion '" + mv + "' is newer than the supported 2.0");
    }
    if (const JsonValue* req = json_.find("extensionsRequired")) {
      for (const auto& e : req->items(what_ + ": extensionsRequired")) {
        const std::string& name = e.asString(what_ + ": extensionsRequired[]");
        if (name != "KHR_mesh_quantization") fail("requires the unsupported extension '" + name + "'");
      }
    }
  }

  void parseBuffers(const GltfLimits& limits) {
    const auto& items = arrayOf("buffers", limits);
    for (size_t i = 0; i < items.size(); ++i) {
      const std::string w = at("buffers", i);
      object(items[i], w);
      GltfBuffer b;
      b.byteLength = reqInteger(items[i], "byteLength", w, std::numeric_limits<uint32_t>::max());
      if (const JsonValue* uri = items[i].find("uri")) b.uri = uri->asString(what_ + ": " + w + ".uri");
      if (items[i].find("uri") == nullptr) {
        if (i != 0) fail(w + " has no uri; only buffer 0 may refer to the GLB binary chunk");
        if (!hasBinChunk_) fail(w + " refers to the binary chunk, but the file has none");
        // The BIN chunk may carry up to 3 bytes of padding beyond the buffer.
        if (b.byteLength > bin_.size()) {
          fail(w + ".byteLength " + std::to_string(b.byteLength) + " exceeds the " + std::to_string(bin_.size()) +
               "-byte binary chunk");
        }
        b.inBinChunk = true;
      }
      buffers_.push_back(std::move(b));
    }
  }

  void parseViews(const GltfLimits& limits) {
    const auto& items = arrayOf("bufferViews", limits);
    for (size_t i = 0; i < items.size(); ++i) {
      const std::string w = at("bufferViews", i);
      object(items[i], w);
      GltfBufferView v;
      const int buf = optIndex(items[i], "buffer", w, buffers_.size(), "buffer");
      if (buf < 0) fail(w + " has no 'buffer'");
      v.buffer = static_cast<size_t>(buf);
      const size_t blen = buffers_[v.buffer].byteLength;
      v.byteOffset = optInteger(items[i], "byteOffset", w, blen, 0);
      v.byteLength = reqInteger(items[i], "byteLength", w, blen);
      if (v.byteLength < 1) fail(w + ".byteLength must be at least 1");
      if (v.byteLength > blen - v.byteOffset) {
        fail(w + " [" + std::to_string(v.byteOffset) + ", +" + std::to_string(v.byteLength) + ") runs past the end of buffer " +
             std::to_string(v.buffer) + " (" + std::to_string(blen) + " bytes)");
      }
      v.byteStride = optInteger(items[i], "byteStride", w, 252, 0);
      if (items[i].find("byteStride") && (v.byteStride < 4 || v.byteStride % 4 != 0)) {
        fail(w + ".byteStride " + std::to_string(v.byteStride) + " must be a multiple of 4 in [4, 252]");
      }
      views_.push_back(v);
    }
  }

  void parseAccessors(const GltfLimits& limits) {
    const auto& items = arrayOf("accessors", limits);
    for (size_t i = 0; i < items.size(); ++i) {
      const std::string w = at("accessors", i);
      object(items[i], w);
      const JsonValue& o = items[i];
      GltfAccessor a;
      if (o.find("sparse")) fail(w + " is a sparse accessor (not supported)");
      a.bufferView = optIndex(o, "bufferView", w, views_.size(), "bufferView");
      a.componentType = static_cast<int>(reqInteger(o, "componentType", w, 99999));
      if (gltf::componentSize(a.componentType) == 0) {
        fail(w + ".componentType " + std::to_string(a.componentType) + " is not a glTF component type");
      }
      if (const JsonValue* nv = o.find("normalized")) a.normalized = nv->asBool(what_ + ": " + w + ".normalized");
      if (a.normalized && (a.componentType == gltf::kFloat || a.componentType == gltf::kUnsignedInt)) {
        fail(w + " is normalized with component type " + gltf::componentName(a.componentType) + " (not allowed)");
      }
      a.count = reqInteger(o, "count", w, std::numeric_limits<uint32_t>::max());
      if (a.count < 1) fail(w + ".count must be at least 1");
      if (a.count > limits.maxAccessorCount) {
        fail(w + ".count " + std::to_string(a.count) + " is over the limit of " + std::to_string(limits.maxAccessorCount));
      }
      const JsonValue* type = o.find("type");
      if (!type) fail(w + " has no 'type'");
      a.type = type->asString(what_ + ": " + w + ".type");
      static const char* names[] = {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"};
      static const int comps[] = {1, 2, 3, 4, 4, 9, 16};
      static const int cols[] = {1, 1, 1, 1, 2, 3, 4};
      int t = -1;
      for (int k = 0; k < 7; ++k) {
        if (a.type == names[k]) t = k;
      }
      if (t < 0) fail(w + ".type '" + a.type.substr(0, 32) + "' is not a glTF accessor type");
      a.components = comps[t];
      a.columns = cols[t];
      if (static_cast<uint64_t>(a.count) * static_cast<uint64_t>(a.components) > limits.maxAccessorValues) {
        fail(w + " holds " + std::to_string(a.count) + " " + a.type + " elements, over the limit of " +
             std::to_string(limits.maxAccessorValues) + " values");
      }
      a.byteOffset = optInteger(o, "byteOffset", w, std::numeric_limits<uint32_t>::max(), 0);
      if (a.bufferView < 0) {
        if (o.find("byteOffset")) fail(w + " has a byteOffset but no bufferView");
      } else {
        const GltfBufferView& v = views_[static_cast<size_t>(a.bufferView)];
        const uint64_t elem = a.elementBytes();
        const uint64_t stride = v.byteStride ? v.byteStride : elem;
        if (v.byteStride && v.byteStride < elem) {
          fail(w + ": bufferView " + std::to_string(a.bufferView) + " has byteStride " + std::to_string(v.byteStride) +
               ", smaller than the " + std::to_string(elem) + "-byte element");
        }
        // Last byte used: byteOffset + stride·(count − 1) + element size (counts are < 2^32,
        // strides ≤ 2^32: no 64-bit overflow).
        const uint64_t end = static_cast<uint64_t>(a.byteOffset) + stride * (a.count - 1) + elem;
        if (end > v.byteLength) {
          fail(w + " needs " + std::to_string(end) + " bytes of bufferView " + std::to_string(a.bufferView) +
               ", which has " + std::to_string(v.byteLength) + " (offset, stride or count out of bounds)");
        }
      }
      accessors_.push_back(std::move(a));
    }
  }

  void parseMeshes(const GltfLimits& limits) {
    const auto& items = arrayOf("meshes", limits);
    for (size_t i = 0; i < items.size(); ++i) {
      const std::string w = at("meshes", i);
      object(items[i], w);
      GltfMesh m;
      if (const JsonValue* name = items[i].find("name")) m.name = name->asString(what_ + ": " + w + ".name");
      const JsonValue* prims = items[i].find("primitives");
      if (!prims) fail(w + " has no 'primitives'");
      const auto& plist = prims->items(what_ + ": " + w + ".primitives");
      if (plist.empty()) fail(w + ".primitives is empty");
      if (plist.size() > limits.maxObjects) fail(w + " has too many primitives");
      for (size_t p = 0; p < plist.size(); ++p) {
        const std::string wp = w + ".primitives[" + std::to_string(p) + "]";
        object(plist[p], wp);
        GltfPrimitive prim;
        const JsonValue* attrs = plist[p].find("attributes");
        if (!attrs) fail(wp + " has no 'attributes'");
        const auto& keys = attrs->keys(what_ + ": " + wp + ".attributes");
        const auto& vals = attrs->values(what_ + ": " + wp + ".attributes");
        for (size_t k = 0; k < keys.size(); ++k) {
          const size_t acc = integer(vals[k], wp + ".attributes." + keys[k], std::numeric_limits<uint32_t>::max());
          if (acc >= accessors_.size()) {
            fail(wp + ".attributes." + keys[k] + " = " + std::to_string(acc) + " refers to a missing accessor (the file has " +
                 std::to_string(accessors_.size()) + ")");
          }
          prim.attributeNames.push_back(keys[k]);
          prim.attributeAccessors.push_back(static_cast<int>(acc));
        }
        prim.indices = optIndex(plist[p], "indices", wp, accessors_.size(), "accessor");
        prim.mode = static_cast<int>(optInteger(plist[p], "mode", wp, 6, gltf::kModeTriangles));
        m.primitives.push_back(std::move(prim));
      }
      meshes_.push_back(std::move(m));
    }
  }

  void parseSkins(const GltfLimits& limits) {
    const auto& items = arrayOf("skins", limits);
    const size_t nNodes = json_.find("nodes") ? json_.find("nodes")->size() : 0;
    for (size_t i = 0; i < items.size(); ++i) {
      const std::string w = at("skins", i);
      object(items[i], w);
      GltfSkin s;
      if (const JsonValue* name = items[i].find("name")) s.name = name->asString(what_ + ": " + w + ".name");
      const JsonValue* joints = items[i].find("joints");
      if (!joints) fail(w + " has no 'joints'");
      const auto& jl = joints->items(what_ + ": " + w + ".joints");
      if (jl.empty()) fail(w + ".joints is empty");
      for (size_t k = 0; k < jl.size(); ++k) {
        const size_t j = integer(jl[k], w + ".joints[" + std::to_string(k) + "]", std::numeric_limits<uint32_t>::max());
        if (j >= nNodes) {
          fail(w + ".joints[" + std::to_string(k) + "] = " + std::to_string(j) + " refers to a missing node (the file has " +
               std::to_string(nNodes) + ")");
        }
        s.joints.push_back(static_cast<int>(j));
      }
      std::vector<int> sorted = s.joints;
      std::sort(sorted.begin(), sorted.end());
      if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) fail(w + ".joints lists a node twice");
      s.inverseBindMatrices = optIndex(items[i], "inverseBindMatrices", w, accessors_.size(), "accessor");
      if (s.inverseBindMatrices >= 0) {
        const GltfAccessor& a = accessors_[static_cast<size_t>(s.inverseBindMatrices)];
        if (a.type != "MAT4" || a.componentType != gltf::kFloat) {
          fail(w + ".inverseBindMatrices must be a FLOAT MAT4 accessor, found " + gltf::componentName(a.componentType) +
               " " + a.type);
        }
        if (a.count < s.joints.size()) {
          fail(w + ".inverseBindMatrices has " + std::to_string(a.count) + " matrices for " +
               std::to_string(s.joints.size()) + " joints");
        }
      }
      s.skeleton = optIndex(items[i], "skeleton", w, nNodes, "node");
      skins_.push_back(std::move(s));
    }
  }

  void parseNodes(const GltfLimits& limits) {
    const auto& items = arrayOf("nodes", limits);
    nodes_.resize(items.size());
    for (size_t i = 0; i < items.size(); ++i) {
      const std::string w = at("nodes", i);
      object(items[i], w);
      const JsonValue& o = items[i];
      GltfNode& n = nodes_[i];
      if (const JsonValue* name = o.find("name")) n.name = name->asString(what_ + ": " + w + ".name");
      n.mesh = optIndex(o, "mesh", w, meshes_.size(), "mesh");
      n.skin = optIndex(o, "skin", w, skins_.size(), "skin");
      if (n.skin >= 0 && n.mesh < 0) fail(w + " has a skin but no mesh");
      if (const JsonValue* ch = o.find("children")) {
        const auto& cl = ch->items(what_ + ": " + w + ".children");
        for (size_t k = 0; k < cl.size(); ++k) {
          const size_t c = integer(cl[k], w + ".children[" + std::to_string(k) + "]", std::numeric_limits<uint32_t>::max());
          if (c >= items.size()) {
            fail(w + ".children[" + std::to_string(k) + "] = " + std::to_string(c) + " refers to a missing node (the file has " +
                 std::to_string(items.size()) + ")");
          }
          if (c == i) fail(w + " lists itself as a child");
          if (nodes_[c].parent >= 0) {
            fail("node " + std::to_string(c) + " has two parents (nodes " + std::to_string(nodes_[c].parent) + " and " +
                 std::to_string(i) + "); the node hierarchy must be a forest");
          }
          nodes_[c].parent = static_cast<int>(i);
          n.children.push_back(static_cast<int>(c));
        }
      }
      const bool trs = o.find("translation") || o.find("rotation") || o.find("scale");
      if (o.find("matrix")) {
        if (trs) fail(w + " has both a matrix and translation/rotation/scale");
        double m[16];
        numbers(o, "matrix", w, 16, m);
        for (int c = 0; c < 4; ++c) {
          for (int r = 0; r < 4; ++r) n.local(r, c) = m[4 * c + r];  // column-major
        }
      } else {
        double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
        numbers(o, "translation", w, 3, t);
        numbers(o, "rotation", w, 4, q);
        numbers(o, "scale", w, 3, s);
        const double qn = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (!(qn > 1e-6)) fail(w + ".rotation is not a unit quaternion (norm " + numberText(qn) + ")");
        const double x = q[0] / qn, y = q[1] / qn, z = q[2] / qn, ww = q[3] / qn;
        Mat3<double> R;
        R << 1 - 2 * (y * y + z * z), 2 * (x * y - z * ww), 2 * (x * z + y * ww),  //
            2 * (x * y + z * ww), 1 - 2 * (x * x + z * z), 2 * (y * z - x * ww),    //
            2 * (x * z - y * ww), 2 * (y * z + x * ww), 1 - 2 * (x * x + y * y);
        n.local.setIdentity();
        for (int c = 0; c < 3; ++c) {
          n.local.block<3, 1>(0, c) = R.col(c) * s[c];
          n.local(c, 3) = t[c];
        }
      }
    }
    for (const GltfSkin& s : skins_) {
      if (s.skeleton >= 0 && static_cast<size_t>(s.skeleton) >= nodes_.size()) fail("skin skeleton out of range");
    }
  }

  /// World transforms by walking each node's parent chain (iteratively) down from its root;
  /// a chain longer than the node count means a cycle.
  void computeWorld() {
    const size_t N = nodes_.size();
    world_.assign(N, Mat4<double>::Identity());
    std::vector<char> done(N, 0);
    std::vector<int> chain;
    for (size_t i = 0; i < N; ++i) {
      chain.clear();
      int k = static_cast<int>(i);
      while (k >= 0 && !done[static_cast<size_t>(k)]) {
        chain.push_back(k);
        if (chain.size() > N) fail("the node hierarchy has a cycle through node " + std::to_string(i));
        k = nodes_[static_cast<size_t>(k)].parent;
      }
      for (size_t c = chain.size(); c-- > 0;) {
        const size_t nk = static_cast<size_t>(chain[c]);
        const int p = nodes_[nk].parent;
        world_[nk] = p >= 0 ? Mat4<double>(world_[static_cast<size_t>(p)] * nodes_[nk].local) : nodes_[nk].local;
        done[nk] = 1;
      }
    }
  }

  std::string what_;
  JsonValue json_;
  std::vector<uint8_t> bin_;
  bool hasBinChunk_ = false;
  std::vector<GltfBuffer> buffers_;
  std::vector<GltfBufferView> views_;
  std::vector<GltfAccessor> accessors_;
  std::vector<GltfMesh> meshes_;
  std::vector<GltfSkin> skins_;
  std::vector<GltfNode> nodes_;
  std::vector<Mat4<double>> world_;
};

}  // namespace hawor
