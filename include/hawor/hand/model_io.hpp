// hawor/hand/model_io.hpp — the library's own hand-model file: an .npz holding every field of a
// HandModel (any J, V, B), so that a converted model (the default glTF hand, a MANO file, a
// user's model) loads without its original format. MANO's key names are reused where they mean
// the same thing (v_template, f, shapedirs, posedirs, J_regressor, weights).
//
//   hawor_hand_model  int32 ()       format version, 1 (marks the file as this format)
//   v_template        (V,3)          float64 (float32 for a float model), metres
//   f                 (F,3) int32    triangles
//   shapedirs         (V,3,B)        shape blend shapes (B may be 0)
//   posedirs          (V,3,P)        pose correctives, P = 9(J−1) or 0
//   J_regressor       (J,V)
//   weights           (V,J)
//   parents           (J,) int32     parents[0] = −1, parents first (MANO stores kintree_table)
//   tip_vertices      (T,) int32     extra keypoint vertices (may be empty)
//   keypoint_map      (K,) int32     indices into [joints, tip vertices] (may be empty)
//   is_left           uint8 ()       0 or 1
//   joint_names       (N,) uint8     UTF-8 names joined by '\n'; N = 0 when the names are unknown
//
// Loading checks the marker and version, every key's presence, dtype kind and shape, and then
// HandModel::validate(); errors name the file and the key. The model comes back prepared.
// Thread-safety: functions only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/io/npz.hpp"

namespace hawor {
// The functions take or build an Npz, whose ABI depends on the stb configuration (io/npz.hpp):
// live in the same tagged inline namespace so that differently configured TUs cannot clash.
inline namespace HAWOR_IO_DEFLATE_NS {

/// Format version written by saveHandModel and accepted by loadHandModel.
constexpr int kHandModelFormatVersion = 1;

namespace model_io_detail {

/// (rows, cols) column-major Eigen matrix -> C-order values.
template <typename Derived>
std::vector<typename Derived::Scalar> rowMajor(const Eigen::MatrixBase<Derived>& m) {
  std::vector<typename Derived::Scalar> out(static_cast<size_t>(m.rows() * m.cols()));
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) out[static_cast<size_t>(r * m.cols() + c)] = m(r, c);
  }
  return out;
}

inline std::vector<int32_t> toInt32(const std::vector<int>& v) { return std::vector<int32_t>(v.begin(), v.end()); }

inline const NpyArray& need(const Npz& z, const char* key) {
  if (!z.has(key)) throw Error(z.source() + ": hand model file has no '" + key + "' array");
  return z.get(key);
}

inline std::string where(const Npz& z, const char* key) { return z.source() + ": '" + key + "'"; }

/// Requires `key` to have the given number of dimensions; returns its shape.
inline const std::vector<size_t>& shapeOf(const Npz& z, const char* key, size_t ndim) {
  const NpyArray& a = need(z, key);
  if (a.shape.size() != ndim) {
    throw Error(where(z, key) + " must have " + std::to_string(ndim) + " dimension(s), found shape " + shapeString(a.shape));
  }
  return a.shape;
}

inline void requireDim(const Npz& z, const char* key, size_t axis, size_t expected, const char* meaning) {
  const std::vector<size_t>& s = need(z, key).shape;
  if (s[axis] != expected) {
    throw Error(where(z, key) + " has shape " + shapeString(s) + ", axis " + std::to_string(axis) + " must be " +
                std::to_string(expected) + " (" + meaning + ")");
  }
}

inline void requireInteger(const Npz& z, const char* key) {
  const NpyType t = need(z, key).type(where(z, key));
  if (t.kind != NpyKind::Int && t.kind != NpyKind::UInt && t.kind != NpyKind::Bool) {
    throw Error(where(z, key) + " must hold integers, found dtype " + need(z, key).dtype);
  }
}

/// A 0-d or one-element integer array.
inline long long scalarInt(const Npz& z, const char* key) {
  const NpyArray& a = need(z, key);
  if (a.size() != 1 || a.shape.size() > 1) {
    throw Error(where(z, key) + " must be a single value, found shape " + shapeString(a.shape));
  }
  requireInteger(z, key);
  return z.getAs<long long>(key)[0];
}

inline std::vector<int> intVector(const Npz& z, const char* key) {
  shapeOf(z, key, 1);
  requireInteger(z, key);
  const std::vector<long long> v = z.getAs<long long>(key);
  std::vector<int> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) {
    if (v[i] < -(1LL << 31) || v[i] >= (1LL << 31)) throw Error(where(z, key) + " has an out-of-range value");
    out[i] = static_cast<int>(v[i]);
  }
  return out;
}

/// A 2-D or 3-D array of `rows` rows as a (rows, rest) column-major Eigen matrix.
template <typename Scalar>
MatX<Scalar> matrix(const Npz& z, const char* key, size_t rows, size_t cols) {
  const std::vector<Scalar> v = z.getAs<Scalar>(key);
  MatX<Scalar> m(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  for (size_t r = 0; r < rows; ++r) {
    for (size_t c = 0; c < cols; ++c) m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = v[r * cols + c];
  }
  return m;
}

}  // namespace model_io_detail

/// The hand model as named arrays (see the file comment). `jointNames` is empty or one name per
/// joint without '\n'. The model need not be prepared but must be valid.
template <typename Scalar>
Npz handModelToNpz(const HandModel<Scalar>& m, const std::vector<std::string>& jointNames = {}) {
  using namespace model_io_detail;
  m.validate();
  const size_t V = static_cast<size_t>(m.numVertices()), J = static_cast<size_t>(m.numJoints());
  const size_t B = static_cast<size_t>(m.numBetas()), P = static_cast<size_t>(m.numPoseFeatures());
  if (!jointNames.empty() && jointNames.size() != J) {
    throw Error("saveHandModel: " + std::to_string(jointNames.size()) + " joint names for " + std::to_string(J) + " joints");
  }
  std::string names;
  for (size_t j = 0; j < jointNames.size(); ++j) {
    if (jointNames[j].find('\n') != std::string::npos) throw Error("saveHandModel: joint name " + std::to_string(j) + " contains a newline");
    names += (j ? "\n" : "") + jointNames[j];
  }
  Npz z;
  const int32_t version = kHandModelFormatVersion;
  z.set("hawor_hand_model", NpyArray::fromData(&version, {}));
  z.set("v_template", NpyArray::fromData(m.vTemplate.data(), {V, 3}));  // row-major already
  const Faces& f = m.faces;
  std::vector<int32_t> faces(static_cast<size_t>(f.rows()) * 3);
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    for (int c = 0; c < 3; ++c) faces[static_cast<size_t>(3 * i + c)] = f(i, c);
  }
  z.set("f", NpyArray::fromData(faces.data(), {static_cast<size_t>(f.rows()), 3}));
  // (3V, B) with row 3v + c is the (V, 3, B) array in C order.
  z.set("shapedirs", NpyArray::fromData(rowMajor(m.shapedirs).data(), {V, 3, B}));
  z.set("posedirs", NpyArray::fromData(rowMajor(m.posedirs).data(), {V, 3, P}));
  z.set("J_regressor", NpyArray::fromData(rowMajor(m.jRegressor).data(), {J, V}));
  z.set("weights", NpyArray::fromData(rowMajor(m.weights).data(), {V, J}));
  z.set("parents", NpyArray::fromData(toInt32(m.parents).data(), {J}));
  z.set("tip_vertices", NpyArray::fromData(toInt32(m.tipVertices).data(), {m.tipVertices.size()}));
  z.set("keypoint_map", NpyArray::fromData(toInt32(m.keypointMap).data(), {m.keypointMap.size()}));
  const uint8_t left = m.isLeft ? 1 : 0;
  z.set("is_left", NpyArray::fromData(&left, {}));
  z.set("joint_names", NpyArray::fromData(reinterpret_cast<const uint8_t*>(names.data()), {names.size()}));
  return z;
}

/// True when `z` carries the hand-model marker (of any version).
inline bool isHandModelNpz(const Npz& z) { return z.has("hawor_hand_model"); }

/// Reads a hand model from named arrays; `jointNames` (optional) receives the stored names
/// (empty when none were stored). The result is prepared.
template <typename Scalar = double>
HandModel<Scalar> handModelFromNpz(const Npz& z, std::vector<std::string>* jointNames = nullptr) {
  using namespace model_io_detail;
  if (!isHandModelNpz(z)) {
    throw Error(z.source() + ": not a hawor hand model file (no 'hawor_hand_model' marker; a MANO file needs the MANO loader)");
  }
  const long long version = scalarInt(z, "hawor_hand_model");
  if (version != kHandModelFormatVersion) {
    throw Error(z.source() + ": hand model format version " + std::to_string(version) + " is not supported (this library reads " +
                std::to_string(kHandModelFormatVersion) + ")");
  }
  const size_t V = shapeOf(z, "v_template", 2)[0];
  requireDim(z, "v_template", 1, 3, "x, y, z");
  const size_t J = shapeOf(z, "parents", 1)[0];
  const size_t F = shapeOf(z, "f", 2)[0];
  requireDim(z, "f", 1, 3, "triangles");
  requireInteger(z, "f");
  shapeOf(z, "shapedirs", 3);
  requireDim(z, "shapedirs", 0, V, "vertices");
  requireDim(z, "shapedirs", 1, 3, "x, y, z");
  shapeOf(z, "posedirs", 3);
  requireDim(z, "posedirs", 0, V, "vertices");
  requireDim(z, "posedirs", 1, 3, "x, y, z");
  shapeOf(z, "J_regressor", 2);
  requireDim(z, "J_regressor", 0, J, "joints, from 'parents'");
  requireDim(z, "J_regressor", 1, V, "vertices");
  shapeOf(z, "weights", 2);
  requireDim(z, "weights", 0, V, "vertices");
  requireDim(z, "weights", 1, J, "joints, from 'parents'");
  const size_t B = need(z, "shapedirs").shape[2], P = need(z, "posedirs").shape[2];

  HandModel<Scalar> m;
  const MatX<Scalar> vt = matrix<Scalar>(z, "v_template", V, 3);
  m.vTemplate = vt;
  const std::vector<long long> f = z.getAs<long long>("f");
  m.faces.resize(static_cast<Eigen::Index>(F), 3);
  for (size_t i = 0; i < f.size(); ++i) {
    if (f[i] < 0 || f[i] >= static_cast<long long>(V)) {
      throw Error(where(z, "f") + " holds vertex index " + std::to_string(f[i]) + " outside [0, " + std::to_string(V) + ")");
    }
    m.faces(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3)) = static_cast<int>(f[i]);
  }
  m.shapedirs = matrix<Scalar>(z, "shapedirs", 3 * V, B);
  m.posedirs = P ? matrix<Scalar>(z, "posedirs", 3 * V, P) : MatX<Scalar>();
  m.jRegressor = matrix<Scalar>(z, "J_regressor", J, V);
  m.weights = matrix<Scalar>(z, "weights", V, J);
  m.parents = intVector(z, "parents");
  m.tipVertices = intVector(z, "tip_vertices");
  m.keypointMap = intVector(z, "keypoint_map");
  const long long left = scalarInt(z, "is_left");
  if (left != 0 && left != 1) throw Error(where(z, "is_left") + " must be 0 or 1, found " + std::to_string(left));
  m.isLeft = left == 1;
  shapeOf(z, "joint_names", 1);
  requireInteger(z, "joint_names");
  const std::vector<uint8_t> nb = z.getAs<uint8_t>("joint_names");
  std::vector<std::string> names;
  if (!nb.empty()) {
    std::string cur;
    for (uint8_t b : nb) {
      if (b == '\n') {
        names.push_back(cur);
        cur.clear();
      } else {
        cur += static_cast<char>(b);
      }
    }
    names.push_back(cur);
    if (names.size() != J) {
      throw Error(where(z, "joint_names") + " holds " + std::to_string(names.size()) + " names for " + std::to_string(J) + " joints");
    }
  }
  try {
    m.prepare();
  } catch (const Error& e) {
    throw Error(z.source() + ": " + std::string(e.what()).substr(7));  // drop the inner "hawor: "
  }
  if (jointNames) *jointNames = std::move(names);
  return m;
}

/// Reads a hand-model .npz from memory; `what` names it in errors.
template <typename Scalar = double>
HandModel<Scalar> loadHandModel(const uint8_t* data, size_t n, const std::string& what = "hand model buffer",
                                std::vector<std::string>* jointNames = nullptr) {
  return handModelFromNpz<Scalar>(Npz::fromBuffer(data, n, what), jointNames);
}

/// Reads a hand-model .npz file.
template <typename Scalar = double>
HandModel<Scalar> loadHandModel(const std::string& path, std::vector<std::string>* jointNames = nullptr) {
  return handModelFromNpz<Scalar>(Npz::read(path), jointNames);
}

/// The .npz bytes of a hand model (deflated members when `compressed` and the build has stb).
template <typename Scalar>
std::vector<uint8_t> handModelToBuffer(const HandModel<Scalar>& m, const std::vector<std::string>& jointNames = {},
                                       bool compressed = kHaveDeflate) {
  return handModelToNpz(m, jointNames).toBuffer(compressed);
}

/// Writes a hand model to an .npz file (see the file comment for the keys).
template <typename Scalar>
void saveHandModel(const HandModel<Scalar>& m, const std::string& path, const std::vector<std::string>& jointNames = {},
                   bool compressed = kHaveDeflate) {
  writeFileBytes(path, handModelToBuffer(m, jointNames, compressed));
}

}  // namespace HAWOR_IO_DEFLATE_NS
}  // namespace hawor
