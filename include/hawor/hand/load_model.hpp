// hawor/hand/load_model.hpp — one entry point for every hand-model file the library reads, the
// format recognised from the CONTENT (never from the extension alone):
//
//   first bytes          format                      reader
//   "glTF"               binary glTF 2.0 (.glb)      default_hand.hpp (skinned-mesh conversion)
//   "PK\3\4" / "PK\5\6"  ZIP = numpy .npz, then by its member names:
//                          hawor_hand_model.npy      model_io.hpp (the library's own format)
//                          v_template.npy, f.npy ... mano_loader.hpp (MANO-key .npz)
//   0x80 0x02..0x05,     Python pickle (protocol 2–5, or 0/1 starting with a dict / mark)
//   '(' or '}'                                       mano_loader.hpp (MANO_RIGHT/LEFT.pkl)
// Anything else is refused with a hawor::Error that names the file and says what was found
// (too short, a single .npy array, JSON text such as a .gltf, an .npz without model keys, ...).
//
// Side: HandSide::Left / Right as asked; HandSide::Auto takes "left" / "right" from the file's
// base name for MANO and glTF files (MANO_LEFT.pkl, left.glb) and the stored flag for hawor
// models. A hawor model whose stored side contradicts an explicit request is an error.
//
// findDefaultHandModel() locates the shipped, licence-free default hand (docs/design.md §3: the WebXR
// generic hands, converted by `hawor convert-hand` into hand_{left,right}.npz at build time).
// Thread-safety: functions only (findDefaultHandModel reads the environment).
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/hand/default_hand.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/hand/mano_loader.hpp"
#include "hawor/hand/model_io.hpp"
#include "hawor/io/file.hpp"
#include "hawor/io/zip.hpp"

namespace hawor {
// Calls model_io.hpp, whose functions depend on the stb configuration: same tagged namespace.
inline namespace HAWOR_IO_DEFLATE_NS {

/// The file formats loadAnyHandModel() recognises.
enum class HandModelKind { ManoPickle, ManoNpz, HaworNpz, Glb };

/// Short name of a format, as printed by the command-line tools.
inline const char* handModelKindName(HandModelKind k) {
  switch (k) {
    case HandModelKind::ManoPickle: return "mano-pkl";
    case HandModelKind::ManoNpz: return "mano-npz";
    case HandModelKind::HaworNpz: return "hawor-npz";
    case HandModelKind::Glb: return "glb";
  }
  return "unknown";
}

/// A loaded model and where it came from.
template <typename Scalar>
struct LoadedHandModel {
  HandModel<Scalar> model;               ///< prepared
  HandModelKind kind = HandModelKind::HaworNpz;
  std::vector<std::string> jointNames;   ///< one per joint when the file names them, else empty
  std::string source;                    ///< the file name (or the name given for a buffer)
};

namespace load_model_detail {

inline std::string stripPrefix(const std::string& m) {
  const std::string p = "hawor: ";
  return m.compare(0, p.size(), p) == 0 ? m.substr(p.size()) : m;
}

// Rethrows a reader's error with the file name and format in front unless it names the file.
[[noreturn]] inline void rethrowNamed(const Error& e, const std::string& name, const char* format) {
  const std::string m = stripPrefix(e.what());
  if (m.find(name) != std::string::npos) throw e;
  throw Error(name + " (" + format + "): " + m);
}

// The first bytes of a buffer for a message: hex, plus the text when printable.
inline std::string firstBytes(const std::uint8_t* data, std::size_t n) {
  const std::size_t k = n < 8 ? n : 8;
  std::string hex, text;
  bool printable = k > 0;
  for (std::size_t i = 0; i < k; ++i) {
    char b[4];
    std::snprintf(b, sizeof b, "%02x", data[i]);
    hex += (i ? " " : "") + std::string(b);
    const unsigned char c = data[i];
    if (c < 0x20 || c > 0x7e) printable = false;
    text += static_cast<char>(c);
  }
  return printable ? hex + " (\"" + text + "\")" : hex;
}

// Left (true) / right (false) from a file's base name; `undecided` when it says neither or both.
inline bool sideFromName(const std::string& name, bool& undecided) {
  const std::size_t slash = name.find_last_of("/\\");
  const std::string base = mano_detail::lower(slash == std::string::npos ? name : name.substr(slash + 1));
  const bool l = base.find("left") != std::string::npos, r = base.find("right") != std::string::npos;
  undecided = l == r;
  return l && !r;
}

inline bool resolveSide(HandSide side, const std::string& name, const char* format) {
  if (side == HandSide::Left) return true;
  if (side == HandSide::Right) return false;
  bool undecided = false;
  const bool left = sideFromName(name, undecided);
  if (undecided) {
    throw Error(name + " (" + std::string(format) +
                "): cannot tell a left from a right hand by the file name; give the side explicitly "
                "(--side left|right)");
  }
  return left;
}

inline bool isZip(const std::uint8_t* d, std::size_t n) {
  return n >= 4 && d[0] == 'P' && d[1] == 'K' && ((d[2] == 3 && d[3] == 4) || (d[2] == 5 && d[3] == 6));
}
inline bool isGlb(const std::uint8_t* d, std::size_t n) {
  return n >= 4 && d[0] == 'g' && d[1] == 'l' && d[2] == 'T' && d[3] == 'F';
}
// Protocol 2+ starts with PROTO (0x80, version); protocols 0 and 1 of a dict start with MARK '('
// ("(dp0") or EMPTY_DICT '}'.
inline bool isPickle(const std::uint8_t* d, std::size_t n) {
  if (n >= 2 && d[0] == 0x80 && d[1] >= 2 && d[1] <= 5) return true;
  return n >= 2 && (d[0] == '(' || d[0] == '}');
}

// What a buffer that is no model looks like, for the error message.
inline std::string describeUnknown(const std::uint8_t* d, std::size_t n) {
  if (n >= 6 && d[0] == 0x93 && d[1] == 'N' && d[2] == 'U' && d[3] == 'M' && d[4] == 'P' && d[5] == 'Y') {
    return "a single numpy .npy array, not a model";
  }
  std::size_t i = 0;
  while (i < n && (d[i] == ' ' || d[i] == '\t' || d[i] == '\r' || d[i] == '\n')) ++i;
  if (i < n && d[i] == '{') return "JSON text (a .gltf file? only binary .glb is supported)";
  if (n >= 1 && d[0] == 0x80) return "a pickle of unsupported protocol " + std::to_string(n >= 2 ? d[1] : 0);
  return "unrecognised content, first bytes " + firstBytes(d, n);
}

}  // namespace load_model_detail

/// The format of a hand-model file's bytes (see the file comment). Throws hawor::Error naming
/// `name` and what the bytes look like when they are none of the formats.
inline HandModelKind detectHandModelKind(const std::uint8_t* data, std::size_t n, const std::string& name) {
  using namespace load_model_detail;
  const std::string accepted =
      " (expected a MANO .pkl / .npz, a hawor hand-model .npz or a skinned binary glTF .glb)";
  if (n < 4) throw Error(name + ": " + std::to_string(n) + " bytes, too short to be a hand model" + accepted);
  if (isGlb(data, n)) return HandModelKind::Glb;
  if (isPickle(data, n)) return HandModelKind::ManoPickle;
  if (isZip(data, n)) {
    ZipLimits limits;
    limits.max_member_size = std::uint64_t(1) << 28;
    const ZipReader zip = [&]() {
      try {
        return ZipReader(data, n, name, limits);
      } catch (const Error& e) {
        rethrowNamed(e, name, "npz");
      }
    }();
    if (zip.find("hawor_hand_model.npy")) return HandModelKind::HaworNpz;
    if (zip.find("v_template.npy")) return HandModelKind::ManoNpz;
    std::string keys;
    std::size_t shown = 0;
    for (const ZipEntry& e : zip.entries()) {
      if (shown == 12) {
        keys += ", ...";
        break;
      }
      keys += (shown++ ? ", " : "") + e.name;
    }
    throw Error(name + ": an .npz / ZIP archive with members [" + keys +
                "] that is no hand model: neither 'hawor_hand_model' (hawor model) nor 'v_template' (MANO) "
                "is present" + accepted);
  }
  throw Error(name + ": " + describeUnknown(data, n) + accepted);
}

/// Loads a hand model from the bytes of any supported file (see the file comment); `name` (the
/// file name) decides HandSide::Auto for MANO and glTF files and names the file in errors.
template <typename Scalar = double>
LoadedHandModel<Scalar> loadAnyHandModel(const std::uint8_t* data, std::size_t n, HandSide side = HandSide::Auto,
                                         const std::string& name = "hand model") {
  using namespace load_model_detail;
  LoadedHandModel<Scalar> out;
  out.source = name;
  out.kind = detectHandModelKind(data, n, name);
  switch (out.kind) {
    case HandModelKind::Glb: {
      const bool left = resolveSide(side, name, "glTF");
      DefaultHand<Scalar> h = [&]() {
        try {
          return loadDefaultHand<Scalar>(data, n, left, name);
        } catch (const Error& e) {
          rethrowNamed(e, name, "glTF");
        }
      }();
      out.model = std::move(h.model);
      out.jointNames = std::move(h.jointNames);
      break;
    }
    case HandModelKind::ManoPickle:
    case HandModelKind::ManoNpz: {
      const bool pkl = out.kind == HandModelKind::ManoPickle;
      const char* format = pkl ? "MANO pickle" : "MANO npz";
      ManoLoadOptions opt;
      opt.side = resolveSide(side, name, format) ? HandSide::Left : HandSide::Right;
      try {
        out.model = pkl ? loadManoPickle<Scalar>(data, n, opt, name) : loadManoNpz<Scalar>(data, n, opt, name);
      } catch (const Error& e) {
        rethrowNamed(e, name, format);
      }
      break;
    }
    case HandModelKind::HaworNpz: {
      try {
        out.model = loadHandModel<Scalar>(data, n, name, &out.jointNames);
      } catch (const Error& e) {
        rethrowNamed(e, name, "hawor hand model");
      }
      if (side != HandSide::Auto && (side == HandSide::Left) != out.model.isLeft) {
        throw Error(name + ": holds a " + std::string(out.model.isLeft ? "left" : "right") + " hand model but a " +
                    std::string(side == HandSide::Left ? "left" : "right") + " hand was asked for");
      }
      break;
    }
  }
  return out;
}

/// Reads a hand-model file of any supported format (see the file comment).
template <typename Scalar = double>
LoadedHandModel<Scalar> loadAnyHandModel(const std::string& path, HandSide side = HandSide::Auto) {
  const std::vector<std::uint8_t> bytes = readFileBytes(path);
  return loadAnyHandModel<Scalar>(bytes.data(), bytes.size(), side, path);
}

/// Path of the default hand of `side` (Auto means Right): the first existing file among
/// `<dir>/hand_<side>.npz` (converted at build time) and `<dir>/<side>.glb` (the npm asset) for
/// dir = $HAWOR_HAND_DIR (when set), then each of `dirs` in order. Throws hawor::Error listing
/// where it looked and how to get a model when there is none.
inline std::string findDefaultHandModel(HandSide side, const std::vector<std::string>& dirs = {}) {
  const std::string s = side == HandSide::Left ? "left" : "right";
  std::vector<std::string> where;
  if (const char* env = std::getenv("HAWOR_HAND_DIR")) {
    if (*env) where.push_back(env);
  }
  where.insert(where.end(), dirs.begin(), dirs.end());
  std::string looked;
  for (const std::string& d : where) {
    const std::string base = d.empty() || d.back() == '/' ? d : d + "/";
    for (const std::string& f : {base + "hand_" + s + ".npz", base + s + ".glb"}) {
      if (std::FILE* fp = std::fopen(f.c_str(), "rb")) {
        std::fclose(fp);
        return f;
      }
      looked += (looked.empty() ? "" : ", ") + f;
    }
  }
  throw Error("no default " + s + " hand model found (looked for " + (looked.empty() ? std::string("nothing: no folder given") : looked) +
              "). Run scripts/install.sh (installs the npm package @webxr-input-profiles/assets) and build "
              "(the default_hands target writes <build>/models/hand_{left,right}.npz), or set HAWOR_HAND_DIR to a "
              "folder holding hand_" + s + ".npz or " + s + ".glb, or pass --model FILE (a MANO .pkl / .npz, a hawor "
              "hand-model .npz or a skinned .glb)");
}

}  // namespace HAWOR_IO_DEFLATE_NS
}  // namespace hawor
