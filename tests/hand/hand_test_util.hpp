// Test support for tests/hand: random hand models built in C++ (no Python, so the tests also run
// in WASM) and a small pickle writer that emits the object layout of the MANO files.
#pragma once

#include "hawor/hand/forward.hpp"
#include "hawor/hand/hand_model.hpp"

#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace hand_test {

/// A random but well-formed model: joints along a skeleton, vertices around their home joint,
/// sparse skinning weights (rows sum to 1), a sparse positive joint regressor (rows sum to 1),
/// small random shape and pose directions. MANO sizes get the 21-keypoint mapping.
template <typename Scalar>
hawor::HandModel<Scalar> randomModel(int V = 778, std::vector<int> parents = hawor::manoParents(),
                                     int B = 10, bool withPosedirs = true, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const int J = static_cast<int>(parents.size());
  std::vector<Eigen::Vector3d> joints(static_cast<std::size_t>(J));
  joints[0] = Eigen::Vector3d(0.09, 0.005, 0.006);
  for (int j = 1; j < J; ++j) {
    const Eigen::Vector3d d(-0.8 + 0.2 * uni(rng), 0.3 * gauss(rng), 0.3 * gauss(rng));
    joints[static_cast<std::size_t>(j)] = joints[static_cast<std::size_t>(parents[static_cast<std::size_t>(j)])] + 0.03 * d;
  }
  hawor::HandModel<Scalar> m;
  m.parents = parents;
  m.vTemplate.resize(V, 3);
  std::vector<int> home(static_cast<std::size_t>(V));
  for (int v = 0; v < V; ++v) {
    const int j = v < J ? v : static_cast<int>(rng() % static_cast<unsigned>(J));
    home[static_cast<std::size_t>(v)] = j;
    for (int c = 0; c < 3; ++c) {
      m.vTemplate(v, c) = static_cast<Scalar>(joints[static_cast<std::size_t>(j)](c) + 0.008 * gauss(rng));
    }
  }
  m.weights = hawor::MatX<Scalar>::Zero(V, J);
  for (int v = 0; v < V; ++v) {
    const int j = home[static_cast<std::size_t>(v)];
    m.weights(v, j) = static_cast<Scalar>(0.5 + 0.5 * uni(rng));
    if (j > 0 && uni(rng) < 0.6) m.weights(v, parents[static_cast<std::size_t>(j)]) = static_cast<Scalar>(0.5 * uni(rng));
    m.weights.row(v) /= m.weights.row(v).sum();
  }
  m.jRegressor = hawor::MatX<Scalar>::Zero(J, V);
  for (int j = 0; j < J; ++j) {
    int picked = 0;
    for (int v = 0; v < V; ++v) {
      if (home[static_cast<std::size_t>(v)] == j && (picked < 3 || uni(rng) < 0.5)) {
        m.jRegressor(j, v) = static_cast<Scalar>(0.2 + uni(rng));
        ++picked;
      }
    }
    m.jRegressor.row(j) /= m.jRegressor.row(j).sum();
  }
  m.shapedirs.resize(3 * V, B);
  for (Eigen::Index i = 0; i < m.shapedirs.size(); ++i) m.shapedirs.data()[i] = static_cast<Scalar>(0.004 * gauss(rng));
  if (withPosedirs) {
    m.posedirs.resize(3 * V, 9 * (J - 1));
    for (Eigen::Index i = 0; i < m.posedirs.size(); ++i) m.posedirs.data()[i] = static_cast<Scalar>(0.002 * gauss(rng));
  }
  const int F = 2 * V;
  m.faces.resize(F, 3);
  for (int f = 0; f < F; ++f) {
    const int a = static_cast<int>(rng() % static_cast<unsigned>(V));
    m.faces(f, 0) = a;
    m.faces(f, 1) = (a + 1 + static_cast<int>(rng() % 5)) % V;
    m.faces(f, 2) = (a + 7 + static_cast<int>(rng() % 5)) % V;
  }
  if (V == 778 && J == 16) {
    m.tipVertices = hawor::manoTipVertices();
    m.keypointMap = hawor::manoKeypointMap();
  }
  m.prepare();
  return m;
}

/// A random pose: axis-angles of standard deviation `sigma`, betas N(0, 1), translation N(0, 0.2).
template <typename Scalar>
hawor::HandPose<Scalar> randomPose(const hawor::HandModel<Scalar>& m, unsigned seed, double sigma = 0.5) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  hawor::HandPose<Scalar> p = hawor::HandPose<Scalar>::zero(m);
  for (int c = 0; c < 3; ++c) {
    p.rot(c) = static_cast<Scalar>(sigma * g(rng));
    p.trans(c) = static_cast<Scalar>(0.2 * g(rng));
  }
  for (Eigen::Index i = 0; i < p.handPose.size(); ++i) p.handPose.data()[i] = static_cast<Scalar>(sigma * g(rng));
  for (Eigen::Index i = 0; i < p.betas.size(); ++i) p.betas(i) = static_cast<Scalar>(g(rng));
  return p;
}

// --- a minimal pickle writer --------------------------------------------------------------------

/// How raw array bytes are written: Python-2 str, Python-3 bytes, or _codecs.encode(text, 'latin1').
enum class BytesForm { Py2Str, Py3Bytes, Codecs };

struct PickleWriter {
  std::string b;

  void raw(const std::string& s) { b += s; }
  void op(unsigned char c) { b.push_back(static_cast<char>(c)); }
  void le(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) b.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  }
  void proto(int p) {
    op(0x80);
    op(static_cast<unsigned char>(p));
  }
  void mark() { op('('); }
  void stop() { op('.'); }
  void none() { op('N'); }
  void boolean(bool v) { op(v ? 0x88 : 0x89); }
  void global(const std::string& module, const std::string& name) { raw("c" + module + "\n" + name + "\n"); }
  void integer(std::int64_t v) {
    if (v >= 0 && v < 256) {
      op('K');
      le(static_cast<std::uint64_t>(v), 1);
    } else if (v >= INT32_MIN && v <= INT32_MAX) {
      op('J');
      le(static_cast<std::uint64_t>(static_cast<std::uint32_t>(static_cast<std::int32_t>(v))), 4);
    } else {
      op(0x8a);
      op(8);
      le(static_cast<std::uint64_t>(v), 8);
    }
  }
  /// Python-2 str (SHORT_BINSTRING / BINSTRING).
  void str(const std::string& s) {
    if (s.size() < 256) {
      op('U');
      op(static_cast<unsigned char>(s.size()));
    } else {
      op('T');
      le(s.size(), 4);
    }
    raw(s);
  }
  /// Python-3 str (BINUNICODE), UTF-8.
  void unicode(const std::string& s) {
    op('X');
    le(s.size(), 4);
    raw(s);
  }
  void bytes(const std::string& s, BytesForm form) {
    if (form == BytesForm::Py2Str) {
      str(s);
    } else if (form == BytesForm::Py3Bytes) {
      op('B');
      le(s.size(), 4);
      raw(s);
    } else {
      global("_codecs", "encode");
      std::string utf8;
      for (unsigned char c : s) {
        if (c < 0x80) {
          utf8.push_back(static_cast<char>(c));
        } else {
          utf8.push_back(static_cast<char>(0xc0 | (c >> 6)));
          utf8.push_back(static_cast<char>(0x80 | (c & 0x3f)));
        }
      }
      unicode(utf8);
      unicode("latin1");
      op(0x86);  // TUPLE2
      op('R');
    }
  }
  void tuple(const std::vector<std::int64_t>& items) {
    mark();
    for (std::int64_t v : items) integer(v);
    op('t');
  }
};

/// A numpy array exactly as numpy's __reduce__ pickles it (see hand/mano_loader.hpp).
inline void writeNdarray(PickleWriter& w, const std::string& code, char order,
                         const std::vector<std::int64_t>& shape, const std::string& raw,
                         bool fortran = false, BytesForm form = BytesForm::Py2Str) {
  w.global("numpy.core.multiarray", "_reconstruct");
  w.global("numpy", "ndarray");
  w.integer(0);
  w.op(0x85);  // TUPLE1
  w.str("b");
  w.op(0x87);  // TUPLE3
  w.op('R');
  w.mark();
  w.integer(1);
  w.tuple(shape);
  w.global("numpy", "dtype");
  w.str(code);
  w.integer(0);
  w.integer(1);
  w.op(0x87);
  w.op('R');
  w.mark();
  w.integer(3);
  w.str(std::string(1, order));
  w.none();
  w.none();
  w.none();
  w.integer(-1);
  w.integer(-1);
  w.integer(0);
  w.op('t');
  w.op('b');
  w.boolean(fortran);
  w.bytes(raw, form);
  w.op('t');
  w.op('b');
}

template <typename T>
std::string rawLE(const std::vector<T>& v) {
  std::string s(v.size() * sizeof(T), '\0');
  if (!v.empty()) std::memcpy(&s[0], v.data(), s.size());  // the test hosts are little-endian
  return s;
}

/// Options of writeModelPickle: the different forms found in MANO files.
struct ModelPickleForm {
  BytesForm bytes = BytesForm::Py2Str;
  bool chumpyShapedirs = true;   ///< shapedirs as chumpy.ch.Ch (else a plain array)
  bool reconstructorForm = false;  ///< objects via copy_reg._reconstructor (protocol 0/1 style)
  bool sparseRegressor = true;   ///< J_regressor as scipy csc_matrix (else dense)
  std::string shapeKey = "_shape";
  bool fortranWeights = false;
  bool withPosedirs = true;
  std::string extraKey;          ///< if set, an extra entry whose value is `extraGlobal`()
  std::string extraGlobal;       ///< "module name"
};

inline void writeObjectHead(PickleWriter& w, const std::string& module, const std::string& name,
                            bool reconstructorForm) {
  if (reconstructorForm) {
    w.global("copy_reg", "_reconstructor");
    w.mark();
    w.global(module, name);
    w.global("__builtin__", "object");
    w.none();
    w.op('t');
    w.op('R');
  } else {
    w.global(module, name);
    w.op(')');
    w.op(0x81);  // NEWOBJ
  }
}

/// A MANO-layout pickle of `m` (numbers as float64, faces as uint32, kintree as int64 with the
/// root's parent 2^32 − 1 like the official files).
template <typename Scalar>
std::string writeModelPickle(const hawor::HandModel<Scalar>& m, const ModelPickleForm& form = {}) {
  const int V = m.numVertices(), J = m.numJoints(), B = m.numBetas();
  PickleWriter w;
  w.proto(2);
  w.op('}');
  w.mark();
  {  // v_template
    std::vector<double> d(m.vTemplate.data(), m.vTemplate.data() + m.vTemplate.size());
    w.str("v_template");
    writeNdarray(w, "f8", '<', {V, 3}, rawLE(d), false, form.bytes);
  }
  {  // f
    std::vector<std::uint32_t> d;
    for (Eigen::Index i = 0; i < m.faces.size(); ++i) d.push_back(static_cast<std::uint32_t>(m.faces.data()[i]));
    w.str("f");
    writeNdarray(w, "u4", '<', {m.faces.rows(), 3}, rawLE(d), false, form.bytes);
  }
  {  // shapedirs (V,3,B)
    std::vector<double> d;
    for (int r = 0; r < 3 * V; ++r)
      for (int k = 0; k < B; ++k) d.push_back(static_cast<double>(m.shapedirs(r, k)));
    w.str("shapedirs");
    if (form.chumpyShapedirs) {
      writeObjectHead(w, "chumpy.ch", "Ch", form.reconstructorForm);
      w.op('}');
      w.mark();
      w.str("x");
      writeNdarray(w, "f8", '<', {V, 3, B}, rawLE(d), false, form.bytes);
      w.str("_dirty_vars");
      w.global("__builtin__", "set");
      w.op(']');
      w.str("x");
      w.op('a');
      w.op(0x85);
      w.op('R');
      w.op('u');
      w.op('b');
    } else {
      writeNdarray(w, "f8", '<', {V, 3, B}, rawLE(d), false, form.bytes);
    }
  }
  if (form.withPosedirs && m.numPoseFeatures() > 0) {
    const int P = m.numPoseFeatures();
    std::vector<double> d;
    for (int r = 0; r < 3 * V; ++r)
      for (int k = 0; k < P; ++k) d.push_back(static_cast<double>(m.posedirs(r, k)));
    w.str("posedirs");
    writeNdarray(w, "f8", '<', {V, 3, P}, rawLE(d), false, form.bytes);
  }
  {  // J_regressor
    w.str("J_regressor");
    if (form.sparseRegressor) {
      std::vector<double> data;
      std::vector<std::int32_t> indices, indptr{0};
      for (int c = 0; c < V; ++c) {
        for (int r = 0; r < J; ++r) {
          if (m.jRegressor(r, c) != Scalar(0)) {
            data.push_back(static_cast<double>(m.jRegressor(r, c)));
            indices.push_back(r);
          }
        }
        indptr.push_back(static_cast<std::int32_t>(data.size()));
      }
      writeObjectHead(w, "scipy.sparse.csc", "csc_matrix", form.reconstructorForm);
      w.op('}');
      w.mark();
      w.str(form.shapeKey);
      w.integer(J);
      w.integer(V);
      w.op(0x86);
      w.str("data");
      writeNdarray(w, "f8", '<', {static_cast<std::int64_t>(data.size())}, rawLE(data), false, form.bytes);
      w.str("indices");
      writeNdarray(w, "i4", '<', {static_cast<std::int64_t>(indices.size())}, rawLE(indices), false, form.bytes);
      w.str("indptr");
      writeNdarray(w, "i4", '<', {static_cast<std::int64_t>(indptr.size())}, rawLE(indptr), false, form.bytes);
      w.str("maxprint");
      w.integer(50);
      w.op('u');
      w.op('b');
    } else {
      std::vector<double> d;
      for (int r = 0; r < J; ++r)
        for (int c = 0; c < V; ++c) d.push_back(static_cast<double>(m.jRegressor(r, c)));
      writeNdarray(w, "f8", '<', {J, V}, rawLE(d), false, form.bytes);
    }
  }
  {  // weights (V,J), optionally in Fortran order
    std::vector<double> d;
    if (form.fortranWeights) {
      for (int c = 0; c < J; ++c)
        for (int r = 0; r < V; ++r) d.push_back(static_cast<double>(m.weights(r, c)));
    } else {
      for (int r = 0; r < V; ++r)
        for (int c = 0; c < J; ++c) d.push_back(static_cast<double>(m.weights(r, c)));
    }
    w.str("weights");
    writeNdarray(w, "f8", '<', {V, J}, rawLE(d), form.fortranWeights, form.bytes);
  }
  {  // kintree_table (2,J) int64
    std::vector<std::int64_t> d;
    for (int j = 0; j < J; ++j) d.push_back(j == 0 ? 4294967295LL : m.parents[static_cast<std::size_t>(j)]);
    for (int j = 0; j < J; ++j) d.push_back(j);
    w.str("kintree_table");
    writeNdarray(w, "i8", '<', {2, J}, rawLE(d), false, form.bytes);
  }
  w.str("bs_style");
  w.str("lbs");
  w.str("bs_type");
  w.str("lrotmin");
  if (!form.extraKey.empty()) {
    const std::size_t sp = form.extraGlobal.find(' ');
    w.str(form.extraKey);
    w.global(form.extraGlobal.substr(0, sp), form.extraGlobal.substr(sp + 1));
    w.mark();
    w.str("echo pwned");
    w.op('t');
    w.op('R');
  }
  w.op('u');
  w.stop();
  return w.b;
}

}  // namespace hand_test
