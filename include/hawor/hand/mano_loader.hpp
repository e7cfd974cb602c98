// hawor/hand/mano_loader.hpp — loads MANO_RIGHT.pkl / MANO_LEFT.pkl (or their .npz conversions)
// into a HandModel without Python and without executing anything (docs/design.md §3).
//
// The pickle is parsed symbolically (hand/pickle.hpp); this file then reads exactly the layout of
// the official files: a dict with v_template (V,3), f (F,3), shapedirs (V,3,B), posedirs
// (V,3,9(J−1)), J_regressor (J,V), weights (V,J), kintree_table (2,J), plus keys that are ignored
// (J, hands_components, hands_mean, hands_coeffs, bs_style, bs_type: the method uses the full
// axis-angle pose, no PCA, no hands_mean). Arrays may be
//   * numpy arrays: REDUCE of numpy.core.multiarray._reconstruct (numpy._core in numpy 2) with a
//     BUILD state (version, shape, dtype, is_fortran, raw bytes) or the 4-tuple without version;
//     the dtype a REDUCE of numpy.dtype (type string) with BUILD state (version, byte order, ...);
//     raw bytes a Python-2 str, Python-3 bytes, or `_codecs.encode(text, 'latin1')` (how a
//     Python-3 pickler writes bytes at protocols 0–2);
//   * chumpy `chumpy.ch.Ch` objects: their BUILD state dict holds the array under 'x';
//   * `scipy.sparse.csc.csc_matrix` (or scipy.sparse._csc): state dict with data, indices, indptr
//     and `_shape` (older files: `shape`), densified.
// Objects may be made by NEWOBJ or by `copy_reg._reconstructor(cls, object, None)` (protocols
// 0/1). By default every global in the file must be one of allowedManoGlobals() (the types of
// the layout in docs/design.md §3); the error names the first other one (`os.system`, `builtins.eval` ...).
// Nothing is ever imported or called either way: the check is a clear refusal of files that are
// not MANO models. Should a genuine file name another harmless type in a key that is not read,
// ManoLoadOptions::strictGlobals = false checks only the values that are interpreted.
//
// Left hands: the side is ManoLoadOptions::side, or with HandSide::Auto the word "left" / "right"
// in the file name (MANO_LEFT.pkl, MANO_RIGHT.pkl). For a left model the known bug of the released
// file is fixed (`shapedirs[:,0,:] *= −1`, option fixLeftShapedirs, on by default) and faces get
// the [0,2,1] winding (option flipLeftFaces): see hand/mirror.hpp for the conventions.
// For MANO sizes (V = 778, J = 16) the 21 OpenPose keypoints are set up (hand_model.hpp).
//
// Entry points: loadMano(path) (format from the content: ZIP → .npz, else pickle),
// loadManoFromMemory(bytes, size, options, name) for the browser, loadManoPickle / loadManoNpz.
// Memory stays proportional to the input: the pickle parser's limits, a cap on how far a sparse
// matrix may be densified, and a cap on inflated .npz members.
#pragma once

#include "hawor/common.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/hand/mirror.hpp"
#include "hawor/hand/pickle.hpp"
#include "hawor/io/file.hpp"
#include "hawor/io/npy.hpp"
#include "hawor/io/zip.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace hawor {

/// Which hand a model file holds.
enum class HandSide { Auto, Right, Left };

struct ManoLoadOptions {
  /// Auto: decided from the file name ("left" / "right" in the base name, any case).
  HandSide side = HandSide::Auto;
  /// Apply `shapedirs[:,0,:] *= −1` to left models: the released MANO_LEFT file's shape directions
  /// were not mirrored in x (docs/design.md §3). Turn off for files that were already fixed.
  bool fixLeftShapedirs = true;
  /// Store left faces with the winding [0,2,1] so that normals point outwards.
  bool flipLeftFaces = true;
  /// Refuse pickles that mention any global outside allowedManoGlobals(). When false, only the
  /// globals of the values that are interpreted are checked.
  bool strictGlobals = true;
  /// Resource limits of the pickle parser.
  pickle::Limits limits;
};

/// The globals a MANO pickle may name ("module.name").
inline const std::vector<std::string>& allowedManoGlobals() {
  static const std::vector<std::string> names = {
      "numpy.core.multiarray._reconstruct", "numpy._core.multiarray._reconstruct",
      "numpy.core.multiarray.scalar",       "numpy._core.multiarray.scalar",
      "numpy.ndarray",                      "numpy.dtype",
      "chumpy.ch.Ch",                       "scipy.sparse.csc.csc_matrix",
      "scipy.sparse._csc.csc_matrix",       "__builtin__.set",
      "builtins.set",                       "copy_reg._reconstructor",
      "copyreg._reconstructor",             "__builtin__.object",
      "builtins.object",                    "_codecs.encode"};
  return names;
}

namespace mano_detail {

inline bool allowed(const std::string& qualified) {
  const std::vector<std::string>& a = allowedManoGlobals();
  return std::find(a.begin(), a.end(), qualified) != a.end();
}

[[noreturn]] inline void refuseGlobal(const std::string& qualified, std::size_t offset) {
  throw Error("MANO pickle: refusing global '" + qualified + "' at byte offset " +
              std::to_string(offset) +
              ": not a numpy / chumpy / scipy type of a MANO model file (nothing was executed)");
}

// Checks a value that we interpret as a callable / class: a Global on the allowlist.
inline std::string globalName(const pickle::Value& g, const std::string& what) {
  if (!g.is(pickle::Kind::Global)) {
    throw Error("MANO pickle: " + what + " is made by a " + g.describe() + ", expected a named type");
  }
  const std::string q = g.qualifiedName();
  if (!allowed(q)) refuseGlobal(q, g.offset());
  return q;
}

// The class of an object record, seen through copy_reg._reconstructor(cls, base, state).
inline std::string objectClass(const pickle::Value& v, const std::string& what) {
  const std::string c = globalName(v.callable(), what);
  if (v.is(pickle::Kind::Reduce) &&
      (c == "copy_reg._reconstructor" || c == "copyreg._reconstructor")) {
    const pickle::Value args = v.args();
    if (!args.is(pickle::Kind::Tuple) || args.size() < 1) {
      throw Error("MANO pickle: " + what + ": malformed _reconstructor arguments");
    }
    return globalName(args[0], what);
  }
  return c;
}

// Python-2 str, Python-3 bytes, or _codecs.encode(text, 'latin1') → raw bytes.
inline std::string rawBytes(const pickle::Value& v, const std::string& what) {
  if (v.isString()) return v.asString();
  if (v.is(pickle::Kind::Reduce) && globalName(v.callable(), what) == "_codecs.encode") {
    const pickle::Value a = v.args();
    if (!a.is(pickle::Kind::Tuple) || a.size() != 2 || !a[0].is(pickle::Kind::Str) ||
        !a[1].isString()) {
      throw Error("MANO pickle: " + what + ": malformed _codecs.encode arguments");
    }
    const std::string enc = a[1].asString();
    if (enc != "latin1" && enc != "latin-1" && enc != "iso-8859-1") {
      throw Error("MANO pickle: " + what + ": unsupported byte encoding '" + enc + "'");
    }
    // UTF-8 text whose code points are all ≤ U+00FF → one byte each.
    const std::string& t = a[0].asString();
    std::string out;
    out.reserve(t.size());
    for (std::size_t i = 0; i < t.size(); ++i) {
      const unsigned char c = static_cast<unsigned char>(t[i]);
      if (c < 0x80) {
        out.push_back(static_cast<char>(c));
      } else if ((c == 0xc2 || c == 0xc3) && i + 1 < t.size() &&
                 (static_cast<unsigned char>(t[i + 1]) & 0xc0) == 0x80) {
        out.push_back(static_cast<char>(((c & 0x1f) << 6) | (static_cast<unsigned char>(t[i + 1]) & 0x3f)));
        ++i;
      } else {
        throw Error("MANO pickle: " + what + ": latin-1 text holds a character beyond U+00FF");
      }
    }
    return out;
  }
  throw Error("MANO pickle: " + what + ": expected raw bytes, got " + v.describe());
}

// numpy.dtype REDUCE + BUILD → a numpy descr string such as "<f8".
inline std::string dtypeDescr(const pickle::Value& d, const std::string& what) {
  if (!d.is(pickle::Kind::Reduce) || globalName(d.callable(), what + " dtype") != "numpy.dtype") {
    throw Error("MANO pickle: " + what + ": expected a numpy.dtype, got " + d.describe());
  }
  const pickle::Value a = d.args();
  if (!a.is(pickle::Kind::Tuple) || a.size() < 1 || !a[0].isString()) {
    throw Error("MANO pickle: " + what + ": malformed numpy.dtype arguments");
  }
  std::string code = a[0].asString();
  char order = '|';
  if (!code.empty() && (code[0] == '<' || code[0] == '>' || code[0] == '|' || code[0] == '=')) {
    order = code[0];
    code.erase(0, 1);
  }
  if (d.hasState()) {
    const pickle::Value st = d.state();
    // (version, byteorder, subarray, names, fields, elsize, alignment, flags[, metadata])
    if (st.is(pickle::Kind::Tuple) && st.size() >= 2 && st[1].isString() && st[1].asString().size() == 1) {
      order = st[1].asString()[0];
    }
  }
  if (order == '|' && !code.empty() && code != "b1" && code != "u1" && code != "i1") order = '<';
  if (order == '=') order = '<';  // the official files were written on little-endian machines
  return std::string(1, order) + code;
}

// One array from any of the forms in the file comment, as an NpyArray (C or Fortran order).
// `maxDense` bounds the elements a sparse matrix may expand to (memory stays proportional to the
// input: a tiny file cannot declare a huge empty csc_matrix).
inline NpyArray toArray(const pickle::Value& v, const std::string& what, std::size_t maxDense, int depth = 0) {
  if (depth > 4) throw Error("MANO pickle: " + what + ": arrays nested too deeply");
  if (!v.is(pickle::Kind::Reduce) && !v.is(pickle::Kind::NewObj)) {
    throw Error("MANO pickle: " + what + ": expected an array, got " + v.describe());
  }
  const std::string cls = objectClass(v, what);
  if (cls == "numpy.core.multiarray._reconstruct" || cls == "numpy._core.multiarray._reconstruct") {
    if (!v.hasState()) throw Error("MANO pickle: " + what + ": numpy array without a BUILD state");
    const pickle::Value st = v.state();
    if (!st.is(pickle::Kind::Tuple) || (st.size() != 5 && st.size() != 4)) {
      throw Error("MANO pickle: " + what + ": malformed numpy array state (expected a 4- or 5-tuple)");
    }
    const std::size_t o = st.size() == 5 ? 1 : 0;  // version field present?
    const pickle::Value shape = st[o];
    if (!shape.is(pickle::Kind::Tuple)) throw Error("MANO pickle: " + what + ": array shape is not a tuple");
    NpyArray a;
    for (std::size_t i = 0; i < shape.size(); ++i) {
      const std::int64_t d = shape[i].asInt();
      if (d < 0) throw Error("MANO pickle: " + what + ": negative array dimension");
      a.shape.push_back(static_cast<std::size_t>(d));
    }
    a.dtype = dtypeDescr(st[o + 1], what);
    a.fortran_order = st[o + 2].asBool();
    const std::string bytes = rawBytes(st[o + 3], what);
    a.bytes.assign(bytes.begin(), bytes.end());
    a.validate("MANO pickle: " + what);
    return a;
  }
  if (cls == "chumpy.ch.Ch") {
    if (!v.hasState() || !v.state().is(pickle::Kind::Dict)) {
      throw Error("MANO pickle: " + what + ": chumpy object without a state dict");
    }
    pickle::Value x;
    if (!v.state().find("x", x)) throw Error("MANO pickle: " + what + ": chumpy object has no 'x'");
    return toArray(x, what, maxDense, depth + 1);
  }
  if (cls == "scipy.sparse.csc.csc_matrix" || cls == "scipy.sparse._csc.csc_matrix") {
    if (!v.hasState() || !v.state().is(pickle::Kind::Dict)) {
      throw Error("MANO pickle: " + what + ": csc_matrix without a state dict");
    }
    const pickle::Value st = v.state();
    pickle::Value shp;
    if (!st.find("_shape", shp) && !st.find("shape", shp)) {
      throw Error("MANO pickle: " + what + ": csc_matrix has no '_shape' / 'shape'");
    }
    if (!shp.is(pickle::Kind::Tuple) || shp.size() != 2) {
      throw Error("MANO pickle: " + what + ": csc_matrix shape is not a pair");
    }
    const std::int64_t rows = shp[0].asInt(), cols = shp[1].asInt();
    if (rows < 0 || cols < 0 || rows > (1 << 24) || cols > (1 << 24) ||
        static_cast<std::uint64_t>(rows * cols) > maxDense) {
      throw Error("MANO pickle: " + what + ": csc_matrix shape " + std::to_string(rows) + "x" +
                  std::to_string(cols) + " is out of range");
    }
    const std::vector<double> data = toArray(st.at("data"), what + ".data", maxDense, depth + 1).as<double>(what + ".data");
    const std::vector<std::int64_t> indices =
        toArray(st.at("indices"), what + ".indices", maxDense, depth + 1).as<std::int64_t>(what + ".indices");
    const std::vector<std::int64_t> indptr =
        toArray(st.at("indptr"), what + ".indptr", maxDense, depth + 1).as<std::int64_t>(what + ".indptr");
    if (indptr.size() != static_cast<std::size_t>(cols) + 1 || indptr[0] != 0 ||
        indices.size() != data.size() || indptr.back() != static_cast<std::int64_t>(data.size())) {
      throw Error("MANO pickle: " + what + ": inconsistent csc_matrix (indptr / indices / data sizes)");
    }
    // Dense (rows, cols) float64, C order.
    std::vector<double> dense(static_cast<std::size_t>(rows * cols), 0.0);
    for (std::int64_t c = 0; c < cols; ++c) {
      const std::int64_t b = indptr[static_cast<std::size_t>(c)], e = indptr[static_cast<std::size_t>(c) + 1];
      if (b > e || e > static_cast<std::int64_t>(data.size())) {
        throw Error("MANO pickle: " + what + ": csc_matrix indptr is not monotone");
      }
      for (std::int64_t k = b; k < e; ++k) {
        const std::int64_t r = indices[static_cast<std::size_t>(k)];
        if (r < 0 || r >= rows) throw Error("MANO pickle: " + what + ": csc_matrix row index out of range");
        dense[static_cast<std::size_t>(r * cols + c)] += data[static_cast<std::size_t>(k)];
      }
    }
    NpyArray a;
    a.dtype = "<f8";
    a.shape = {static_cast<std::size_t>(rows), static_cast<std::size_t>(cols)};
    a.bytes.resize(dense.size() * 8);
    for (std::size_t i = 0; i < dense.size(); ++i) {
      std::uint64_t u;
      std::memcpy(&u, &dense[i], 8);
      for (int k = 0; k < 8; ++k) a.bytes[8 * i + static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(u >> (8 * k));
    }
    return a;
  }
  throw Error("MANO pickle: " + what + ": '" + cls + "' is not an array type");
}

// Rejects the first global outside the allowlist anywhere in the document.
inline void checkAllGlobals(const pickle::Document& doc) {
  for (std::size_t i = 0; i < doc.nodeCount(); ++i) {
    const pickle::Value v(&doc, static_cast<std::uint32_t>(i));
    if (v.is(pickle::Kind::Global) && !allowed(v.qualifiedName())) refuseGlobal(v.qualifiedName(), v.offset());
  }
}

inline std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// Left or right from the options, else from the base name of `name`.
inline bool resolveLeft(const ManoLoadOptions& opt, const std::string& name) {
  if (opt.side == HandSide::Left) return true;
  if (opt.side == HandSide::Right) return false;
  const std::size_t slash = name.find_last_of("/\\");
  const std::string base = lower(slash == std::string::npos ? name : name.substr(slash + 1));
  const bool l = base.find("left") != std::string::npos;
  const bool r = base.find("right") != std::string::npos;
  if (l != r) return l;
  throw Error("MANO model '" + name +
              "': cannot tell a left from a right hand model by its name; set ManoLoadOptions::side");
}

// The arrays of a MANO model in numpy layout, whatever file they came from.
struct ManoArrays {
  NpyArray vTemplate, faces, shapedirs, posedirs, jRegressor, weights, kintree;
  bool hasShapedirs = false, hasPosedirs = false;
};

inline std::string shapeText(const NpyArray& a) { return shapeString(a.shape); }

template <typename Scalar>
HandModel<Scalar> buildModel(const ManoArrays& in, bool left, const ManoLoadOptions& opt,
                             const std::string& what) {
  const auto bad = [&](const std::string& key, const NpyArray& a, const std::string& want) {
    return Error(what + ": '" + key + "' has shape " + shapeText(a) + ", expected " + want);
  };
  const NpyArray& vt = in.vTemplate;
  if (vt.ndim() != 2 || vt.shape[1] != 3 || vt.shape[0] == 0) throw bad("v_template", vt, "(V, 3)");
  const std::size_t V = vt.shape[0];
  const NpyArray& kt = in.kintree;
  if (kt.ndim() != 2 || kt.shape[0] != 2 || kt.shape[1] == 0) throw bad("kintree_table", kt, "(2, J)");
  const std::size_t J = kt.shape[1];
  HandModel<Scalar> m;
  const std::vector<double> t = vt.as<double>(what + ": v_template");
  m.vTemplate.resize(static_cast<Eigen::Index>(V), 3);
  for (std::size_t i = 0; i < t.size(); ++i) m.vTemplate.data()[i] = static_cast<Scalar>(t[i]);

  if (in.hasShapedirs) {
    const NpyArray& s = in.shapedirs;
    if (s.ndim() != 3 || s.shape[0] != V || s.shape[1] != 3) throw bad("shapedirs", s, "(V, 3, B)");
    const std::size_t B = s.shape[2];
    const std::vector<double> d = s.as<double>(what + ": shapedirs");
    m.shapedirs.resize(static_cast<Eigen::Index>(3 * V), static_cast<Eigen::Index>(B));
    for (std::size_t r = 0; r < 3 * V; ++r) {
      for (std::size_t k = 0; k < B; ++k) {
        m.shapedirs(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k)) = static_cast<Scalar>(d[r * B + k]);
      }
    }
  } else {
    m.shapedirs.resize(static_cast<Eigen::Index>(3 * V), 0);
  }
  if (in.hasPosedirs) {
    const NpyArray& p = in.posedirs;
    if (p.ndim() != 3 || p.shape[0] != V || p.shape[1] != 3 || p.shape[2] != 9 * (J - 1)) {
      throw bad("posedirs", p, "(V, 3, 9(J-1)) = (" + std::to_string(V) + ", 3, " + std::to_string(9 * (J - 1)) + ")");
    }
    const std::size_t P = p.shape[2];
    const std::vector<double> d = p.as<double>(what + ": posedirs");
    m.posedirs.resize(static_cast<Eigen::Index>(3 * V), static_cast<Eigen::Index>(P));
    for (std::size_t r = 0; r < 3 * V; ++r) {
      for (std::size_t k = 0; k < P; ++k) {
        m.posedirs(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k)) = static_cast<Scalar>(d[r * P + k]);
      }
    }
  }
  const NpyArray& jr = in.jRegressor;
  if (jr.ndim() != 2 || jr.shape[0] != J || jr.shape[1] != V) throw bad("J_regressor", jr, "(J, V)");
  const std::vector<double> jd = jr.as<double>(what + ": J_regressor");
  m.jRegressor.resize(static_cast<Eigen::Index>(J), static_cast<Eigen::Index>(V));
  for (std::size_t j = 0; j < J; ++j) {
    for (std::size_t v = 0; v < V; ++v) {
      m.jRegressor(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(v)) = static_cast<Scalar>(jd[j * V + v]);
    }
  }
  const NpyArray& w = in.weights;
  if (w.ndim() != 2 || w.shape[0] != V || w.shape[1] != J) throw bad("weights", w, "(V, J)");
  const std::vector<double> wd = w.as<double>(what + ": weights");
  m.weights.resize(static_cast<Eigen::Index>(V), static_cast<Eigen::Index>(J));
  for (std::size_t v = 0; v < V; ++v) {
    for (std::size_t j = 0; j < J; ++j) {
      m.weights(static_cast<Eigen::Index>(v), static_cast<Eigen::Index>(j)) = static_cast<Scalar>(wd[v * J + j]);
    }
  }
  const NpyArray& f = in.faces;
  if (f.ndim() != 2 || f.shape[1] != 3) throw bad("f", f, "(F, 3)");
  const std::vector<std::int64_t> fd = f.as<std::int64_t>(what + ": f");
  m.faces.resize(static_cast<Eigen::Index>(f.shape[0]), 3);
  for (std::size_t i = 0; i < fd.size(); ++i) {
    if (fd[i] < 0 || fd[i] >= static_cast<std::int64_t>(V)) {
      throw Error(what + ": face vertex index " + std::to_string(fd[i]) + " outside [0, " + std::to_string(V) + ")");
    }
    m.faces.data()[i] = static_cast<int>(fd[i]);
  }
  // kintree_table: row 1 the joint ids (0..J−1 in order), row 0 their parents' ids (the root's
  // is −1 or 2^32−1 in the official files and is ignored).
  const std::vector<std::int64_t> kd = kt.as<std::int64_t>(what + ": kintree_table");
  m.parents.assign(J, -1);
  for (std::size_t j = 0; j < J; ++j) {
    if (kd[J + j] != static_cast<std::int64_t>(j)) {
      throw Error(what + ": kintree_table row 1 must list the joints 0..J-1 in order");
    }
    if (j > 0) {
      const std::int64_t p = kd[j];
      if (p < 0 || p >= static_cast<std::int64_t>(j)) {
        throw Error(what + ": kintree_table gives joint " + std::to_string(j) + " the parent " +
                    std::to_string(p) + " (parents must precede their children)");
      }
      m.parents[j] = static_cast<int>(p);
    }
  }
  if (V == 778 && J == 16) {
    m.tipVertices = manoTipVertices();
    m.keypointMap = manoKeypointMap();
  }
  m.isLeft = left;
  if (left) {
    if (opt.fixLeftShapedirs) fixLeftShapedirs(m);
    if (opt.flipLeftFaces) m.faces = flipFaceWinding(m.faces);
  }
  m.prepare();
  return m;
}

}  // namespace mano_detail

/// Loads a MANO model from pickle bytes (see the file comment). `name` (a file name) is used for
/// HandSide::Auto and in error messages.
template <typename Scalar = double>
HandModel<Scalar> loadManoPickle(const std::uint8_t* data, std::size_t size, const ManoLoadOptions& opt = {},
                                 const std::string& name = "MANO pickle") {
  const bool left = mano_detail::resolveLeft(opt, name);
  const pickle::Document doc = pickle::parse(data, size, opt.limits);
  if (opt.strictGlobals) mano_detail::checkAllGlobals(doc);
  const pickle::Value root = doc.root();
  if (!root.is(pickle::Kind::Dict)) {
    throw Error(name + ": the pickle holds a " + root.describe() + ", expected the dict of a MANO model");
  }
  const std::size_t maxDense = std::max<std::size_t>(std::size_t(1) << 16, 4 * size);
  mano_detail::ManoArrays a;
  const auto get = [&](const char* key) {
    pickle::Value v;
    if (!root.find(key, v)) throw Error(name + ": key '" + std::string(key) + "' is missing (not a MANO model?)");
    return mano_detail::toArray(v, name + ": " + key, maxDense);
  };
  a.vTemplate = get("v_template");
  a.faces = get("f");
  a.jRegressor = get("J_regressor");
  a.weights = get("weights");
  a.kintree = get("kintree_table");
  if (root.has("shapedirs")) {
    a.shapedirs = get("shapedirs");
    a.hasShapedirs = true;
  }
  if (root.has("posedirs")) {
    a.posedirs = get("posedirs");
    a.hasPosedirs = true;
  }
  return mano_detail::buildModel<Scalar>(a, left, opt, name);
}

/// Loads a MANO model from the bytes of an .npz conversion (same key names, dense arrays; stored
/// or deflated members). Only the members the model needs are decoded, so string members such as
/// bs_style do not matter.
template <typename Scalar = double>
HandModel<Scalar> loadManoNpz(const std::uint8_t* data, std::size_t size, const ManoLoadOptions& opt = {},
                              const std::string& name = "MANO npz") {
  const bool left = mano_detail::resolveLeft(opt, name);
  ZipLimits limits;
  limits.max_member_size = std::uint64_t(1) << 28;  // MANO members are a few MB
  const ZipReader zip(data, size, name, limits);
  const auto get = [&](const std::string& key) {
    const ZipEntry* e = zip.find(key + ".npy");
    if (e == nullptr) throw Error(name + ": array '" + key + "' is missing (not a MANO model?)");
    const std::vector<std::uint8_t> b = zip.extract(*e);
    return parseNpy(b.data(), b.size(), name + ": " + key);
  };
  mano_detail::ManoArrays a;
  a.vTemplate = get("v_template");
  a.faces = get("f");
  a.jRegressor = get("J_regressor");
  a.weights = get("weights");
  a.kintree = get("kintree_table");
  a.hasShapedirs = zip.find("shapedirs.npy") != nullptr;
  if (a.hasShapedirs) a.shapedirs = get("shapedirs");
  a.hasPosedirs = zip.find("posedirs.npy") != nullptr;
  if (a.hasPosedirs) a.posedirs = get("posedirs");
  return mano_detail::buildModel<Scalar>(a, left, opt, name);
}

/// Loads a MANO model from an .npz file (see the overload above).
template <typename Scalar = double>
HandModel<Scalar> loadManoNpz(const std::string& path, const ManoLoadOptions& opt = {}) {
  const std::vector<std::uint8_t> bytes = readFileBytes(path);
  return loadManoNpz<Scalar>(bytes.data(), bytes.size(), opt, path);
}

/// Loads a MANO model held in memory (the browser's case): a ZIP ("PK") is read as .npz, anything
/// else as a pickle. `name` is the file name, for HandSide::Auto and messages.
template <typename Scalar = double>
HandModel<Scalar> loadManoFromMemory(const std::uint8_t* data, std::size_t size, const ManoLoadOptions& opt = {},
                                     const std::string& name = "MANO model") {
  if (size >= 2 && data[0] == 'P' && data[1] == 'K') return loadManoNpz<Scalar>(data, size, opt, name);
  return loadManoPickle<Scalar>(data, size, opt, name);
}

/// Loads MANO_RIGHT.pkl / MANO_LEFT.pkl or an .npz conversion from a file (content decides the
/// format; the name decides the side unless ManoLoadOptions::side says it).
template <typename Scalar = double>
HandModel<Scalar> loadMano(const std::string& path, const ManoLoadOptions& opt = {}) {
  const std::vector<std::uint8_t> bytes = readFileBytes(path);
  return loadManoFromMemory<Scalar>(bytes.data(), bytes.size(), opt, path);
}

}  // namespace hawor
