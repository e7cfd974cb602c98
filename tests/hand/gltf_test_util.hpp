// Test support for the glTF tests: a tiny GLB writer written independently of the reader, and a
// small skinned "finger" (3 joints, 16 vertices in 4 rings, 28 triangles) in several encodings
// (accessor types, interleaving, node matrix vs TRS), with the values it encodes kept on the
// side so that tests can compare what the reader returns with what was written.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "hawor/common.hpp"

namespace gltf_test {

constexpr double kPi = 3.14159265358979323846;

inline void put32(std::vector<uint8_t>& b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
inline void putF(std::vector<uint8_t>& b, float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  put32(b, u);
}
inline void put16(std::vector<uint8_t>& b, uint16_t v) {
  b.push_back(static_cast<uint8_t>(v));
  b.push_back(static_cast<uint8_t>(v >> 8));
}
inline void pad4(std::vector<uint8_t>& b, uint8_t fill = 0) {
  while (b.size() % 4) b.push_back(fill);
}

/// header + JSON chunk (space padded) + optional BIN chunk (zero padded).
inline std::vector<uint8_t> makeGlb(const std::string& json, const std::vector<uint8_t>& bin, bool withBin = true) {
  std::vector<uint8_t> j(json.begin(), json.end());
  pad4(j, ' ');
  std::vector<uint8_t> b = bin;
  pad4(b, 0);
  std::vector<uint8_t> out;
  const uint32_t total = static_cast<uint32_t>(12 + 8 + j.size() + (withBin ? 8 + b.size() : 0));
  put32(out, 0x46546C67u);
  put32(out, 2);
  put32(out, total);
  put32(out, static_cast<uint32_t>(j.size()));
  put32(out, 0x4E4F534Au);
  out.insert(out.end(), j.begin(), j.end());
  if (withBin) {
    put32(out, static_cast<uint32_t>(b.size()));
    put32(out, 0x004E4942u);
    out.insert(out.end(), b.begin(), b.end());
  }
  return out;
}

/// Replaces the first occurrence of `from` (which must exist) in `s`.
inline std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const size_t at = s.find(from);
  if (at == std::string::npos) throw std::runtime_error("test: '" + from + "' not in the JSON");
  return s.replace(at, from.size(), to);
}

/// Encoding choices of the small finger.
struct Spec {
  int weights = 5126;        ///< 5126 float, 5121 normalized ubyte, 5123 normalized ushort
  int joints = 5121;         ///< 5121 ubyte, 5123 ushort
  int indices = 5123;        ///< 5121, 5123, 5125
  bool interleaved = false;  ///< POSITION + NORMAL in one strided view (byteStride 24)
  bool armatureMatrix = true;  ///< armature node uses "matrix" (else TRS)
  bool skinOrderShuffled = false;  ///< skin lists joints as [tip, root, mid]
};

/// The finger: what it encodes (in double, as the reader should return it) and its files.
struct Finger {
  std::string json;
  std::vector<uint8_t> bin;
  std::vector<uint8_t> glb() const { return makeGlb(json, bin); }
  Eigen::MatrixXd positions;            ///< (16,3) float-exact
  Eigen::MatrixXd weightsDecoded;       ///< (16,4) as stored (normalised ints decoded)
  Eigen::MatrixXi jointIds;             ///< (16,4) skin joint indices
  std::vector<int> indices;             ///< 84
  std::vector<Eigen::Matrix4d> jointWorld;  ///< bind world transform of joints root, mid, tip
  std::vector<Eigen::Matrix4f> ibm;     ///< in skin order, as stored
  std::vector<int> skinOrder;           ///< skin joint k is finger joint skinOrder[k] (0 root, 1 mid, 2 tip)
  Eigen::Matrix4d armature;
};

inline Eigen::Matrix4d trs(const Eigen::Vector3d& t, const Eigen::Quaterniond& q, const Eigen::Vector3d& s) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = q.normalized().toRotationMatrix() * s.asDiagonal();
  m.topRightCorner<3, 1>() = t;
  return m;
}

inline std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

inline Finger makeFinger(const Spec& spec = {}) {
  Finger f;
  // Armature: scale 0.5, rotation 90° about z, translation (0.1, 0.2, 0.3); joints along its +y.
  const Eigen::Quaterniond qa(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()));
  f.armature = trs(Eigen::Vector3d(0.1, 0.2, 0.3), qa, Eigen::Vector3d(0.5, 0.5, 0.5));
  const Eigen::Quaterniond qtip(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 0, 0)));
  const Eigen::Matrix4d root = trs(Eigen::Vector3d(0, 0, 0), Eigen::Quaterniond::Identity(), Eigen::Vector3d::Ones());
  const Eigen::Matrix4d mid = trs(Eigen::Vector3d(0, 0.125, 0), Eigen::Quaterniond::Identity(), Eigen::Vector3d::Ones());
  const Eigen::Matrix4d tip = trs(Eigen::Vector3d(0, 0.125, 0), qtip, Eigen::Vector3d::Ones());
  f.jointWorld = {f.armature * root, f.armature * root * mid, f.armature * root * mid * tip};
  f.skinOrder = spec.skinOrderShuffled ? std::vector<int>{2, 0, 1} : std::vector<int>{0, 1, 2};

  // Vertices in the bind (world) frame: rings of 4 around the finger axis at 4 heights.
  // The finger axis in world: armature maps local +y to world −x (90° about z), scaled 0.5.
  f.positions.resize(16, 3);
  for (int r = 0; r < 4; ++r) {
    for (int k = 0; k < 4; ++k) {
      const double a = k * kPi / 2;
      const Eigen::Vector4d local(0.03125 * std::cos(a), 0.0625 * r, 0.03125 * std::sin(a), 1.0);
      const Eigen::Vector4d w = f.armature * local;
      for (int c = 0; c < 3; ++c) f.positions(4 * r + k, c) = static_cast<double>(static_cast<float>(w(c)));
    }
  }
  // Skinning: ring 0 root, ring 1 root/mid, ring 2 mid/tip, ring 3 tip (finger joint ids).
  f.weightsDecoded = Eigen::MatrixXd::Zero(16, 4);
  f.jointIds = Eigen::MatrixXi::Zero(16, 4);
  std::vector<uint8_t> wbytes;
  const int skinOf[3] = {spec.skinOrderShuffled ? 1 : 0, spec.skinOrderShuffled ? 2 : 1, spec.skinOrderShuffled ? 0 : 2};
  for (int v = 0; v < 16; ++v) {
    const int r = v / 4;
    const int ja = r <= 1 ? 0 : 1, jb = r == 0 ? 0 : r == 3 ? 2 : r == 1 ? 1 : 2;
    // Raw weights as integers out of 255 / 65535, or floats.
    const double fa = r == 0 || r == 3 ? 1.0 : 0.75, fb = 1.0 - fa;
    f.jointIds(v, 0) = skinOf[ja];
    f.jointIds(v, 1) = skinOf[jb];
    f.jointIds(v, 2) = 0;  // unused slots: joint 0 with weight 0
    f.jointIds(v, 3) = 0;
    if (spec.weights == 5126) {
      f.weightsDecoded(v, 0) = fa;
      f.weightsDecoded(v, 1) = fb;
      putF(wbytes, static_cast<float>(fa));
      putF(wbytes, static_cast<float>(fb));
      putF(wbytes, 0.f);
      putF(wbytes, 0.f);
    } else if (spec.weights == 5121) {
      const int ia = static_cast<int>(std::lround(fa * 255)), ib = 255 - ia;
      f.weightsDecoded(v, 0) = ia / 255.0;
      f.weightsDecoded(v, 1) = ib / 255.0;
      for (int x : {ia, ib, 0, 0}) wbytes.push_back(static_cast<uint8_t>(x));
    } else {
      const int ia = static_cast<int>(std::lround(fa * 65535)), ib = 65535 - ia;
      f.weightsDecoded(v, 0) = ia / 65535.0;
      f.weightsDecoded(v, 1) = ib / 65535.0;
      for (int x : {ia, ib, 0, 0}) put16(wbytes, static_cast<uint16_t>(x));
    }
  }
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 4; ++k) {
      const int a = 4 * r + k, b = 4 * r + (k + 1) % 4, c = a + 4, d = b + 4;
      for (int i : {a, b, d, a, d, c}) f.indices.push_back(i);
    }
  }
  for (int i : {0, 2, 1, 0, 3, 2, 12, 13, 14, 12, 14, 15}) f.indices.push_back(i);

  // --- binary layout ------------------------------------------------------------------------
  std::vector<uint8_t>& bin = f.bin;
  std::string views, accessors;
  int nview = 0;
  auto addView = [&](const std::vector<uint8_t>& bytes, int stride) {
    pad4(bin);
    const size_t off = bin.size();
    bin.insert(bin.end(), bytes.begin(), bytes.end());
    if (nview) views += ",";
    views += "{\"buffer\":0,\"byteOffset\":" + std::to_string(off) + ",\"byteLength\":" + std::to_string(bytes.size()) +
             (stride ? ",\"byteStride\":" + std::to_string(stride) : std::string()) + "}";
    return nview++;
  };
  int nacc = 0;
  auto addAccessor = [&](int view, size_t offset, int ctype, int count, const char* type, bool normalized) {
    if (nacc) accessors += ",";
    accessors += "{\"bufferView\":" + std::to_string(view) + (offset ? ",\"byteOffset\":" + std::to_string(offset) : std::string()) +
                 ",\"componentType\":" + std::to_string(ctype) + (normalized ? ",\"normalized\":true" : "") +
                 ",\"count\":" + std::to_string(count) + ",\"type\":\"" + type + "\"}";
    return nacc++;
  };
  std::vector<uint8_t> pbytes, nbytes, inter;
  for (int v = 0; v < 16; ++v) {
    std::vector<uint8_t> p, n;
    for (int c = 0; c < 3; ++c) putF(p, static_cast<float>(f.positions(v, c)));
    for (int c = 0; c < 3; ++c) putF(n, c == 1 ? 1.f : 0.f);
    pbytes.insert(pbytes.end(), p.begin(), p.end());
    nbytes.insert(nbytes.end(), n.begin(), n.end());
    inter.insert(inter.end(), p.begin(), p.end());
    inter.insert(inter.end(), n.begin(), n.end());
  }
  int accPos, accNrm;
  if (spec.interleaved) {
    const int view = addView(inter, 24);
    accPos = addAccessor(view, 0, 5126, 16, "VEC3", false);
    accNrm = addAccessor(view, 12, 5126, 16, "VEC3", false);
  } else {
    accPos = addAccessor(addView(pbytes, 0), 0, 5126, 16, "VEC3", false);
    accNrm = addAccessor(addView(nbytes, 0), 0, 5126, 16, "VEC3", false);
  }
  std::vector<uint8_t> jbytes;
  for (int v = 0; v < 16; ++v) {
    for (int k = 0; k < 4; ++k) {
      if (spec.joints == 5121) {
        jbytes.push_back(static_cast<uint8_t>(f.jointIds(v, k)));
      } else {
        put16(jbytes, static_cast<uint16_t>(f.jointIds(v, k)));
      }
    }
  }
  const int accJ = addAccessor(addView(jbytes, 0), 0, spec.joints, 16, "VEC4", false);
  const int accW = addAccessor(addView(wbytes, 0), 0, spec.weights, 16, "VEC4", spec.weights != 5126);
  std::vector<uint8_t> ibytes;
  for (int i : f.indices) {
    if (spec.indices == 5121) {
      ibytes.push_back(static_cast<uint8_t>(i));
    } else if (spec.indices == 5123) {
      put16(ibytes, static_cast<uint16_t>(i));
    } else {
      put32(ibytes, static_cast<uint32_t>(i));
    }
  }
  const int accI = addAccessor(addView(ibytes, 0), 0, spec.indices, static_cast<int>(f.indices.size()), "SCALAR", false);
  std::vector<uint8_t> mbytes;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Matrix4f inv = f.jointWorld[static_cast<size_t>(f.skinOrder[static_cast<size_t>(k)])].inverse().cast<float>();
    f.ibm.push_back(inv);
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) putF(mbytes, inv(r, c));
    }
  }
  const int accM = addAccessor(addView(mbytes, 0), 0, 5126, 3, "MAT4", false);

  // --- nodes: 0 armature (children 1 mesh, 2 root), 2 root -> 3 mid -> 4 tip -----------------
  std::string arm;
  if (spec.armatureMatrix) {
    arm = "\"matrix\":[";
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) arm += (c || r ? "," : "") + num(f.armature(r, c));
    }
    arm += "]";
  } else {
    arm = "\"translation\":[0.1,0.2,0.3],\"rotation\":[0,0," + num(qa.z()) + "," + num(qa.w()) + "],\"scale\":[0.5,0.5,0.5]";
  }
  const std::string tipRot = "\"rotation\":[" + num(qtip.x()) + ",0,0," + num(qtip.w()) + "]";
  const int nodeOf[3] = {2, 3, 4};
  std::string skinJoints;
  for (int k = 0; k < 3; ++k) skinJoints += (k ? "," : "") + std::to_string(nodeOf[f.skinOrder[static_cast<size_t>(k)]]);
  f.json = std::string("{\"asset\":{\"version\":\"2.0\",\"generator\":\"hawor test\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],") +
           "\"nodes\":[{\"name\":\"Armature\",\"children\":[1,2]," + arm + "}," +
           "{\"name\":\"mesh\",\"mesh\":0,\"skin\":0,\"translation\":[5,5,5]}," +
           "{\"name\":\"root\",\"children\":[3]}," +
           "{\"name\":\"mid\",\"children\":[4],\"translation\":[0,0.125,0]}," +
           "{\"name\":\"tip\",\"translation\":[0,0.125,0]," + tipRot + "}]," +
           "\"meshes\":[{\"name\":\"finger\",\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(accPos) +
           ",\"NORMAL\":" + std::to_string(accNrm) + ",\"JOINTS_0\":" + std::to_string(accJ) + ",\"WEIGHTS_0\":" +
           std::to_string(accW) + "},\"indices\":" + std::to_string(accI) + ",\"mode\":4}]}]," +
           "\"skins\":[{\"name\":\"Armature\",\"inverseBindMatrices\":" + std::to_string(accM) + ",\"joints\":[" + skinJoints + "]}]," +
           "\"accessors\":[" + accessors + "],\"bufferViews\":[" + views + "],\"buffers\":[{\"byteLength\":" +
           std::to_string(bin.size()) + "}]}";
  return f;
}

/// A generic small skinned mesh: joints are nodes with translation-only transforms (world
/// positions given), parented to another joint or (parent −1) to an armature node; the skin
/// lists the joints in `skinOrder`; float attributes, uint16 joints, uint32 indices.
struct SimpleSkin {
  std::vector<std::string> names;
  std::vector<int> parent;                 ///< per joint: parent joint or −1 (armature child)
  std::vector<Eigen::Vector3d> position;   ///< per joint: bind world position
  std::vector<int> skinOrder;              ///< skin joint k = joint skinOrder[k]
  Eigen::MatrixXd vertices;                ///< (V,3)
  Eigen::MatrixXi joints;                  ///< (V,4) skin joint indices
  Eigen::MatrixXd weights;                 ///< (V,4)
  std::vector<int> indices;
  std::string json;                        ///< filled by build()
  std::vector<uint8_t> bin;

  /// Writes json and bin; returns the GLB.
  std::vector<uint8_t> build() {
    bin.clear();
    std::string views, accessors;
    int nview = 0;
    auto add = [&](const std::vector<uint8_t>& bytes, int ctype, size_t count, const char* type) {
      pad4(bin);
      const size_t off = bin.size();
      bin.insert(bin.end(), bytes.begin(), bytes.end());
      if (nview) {
        views += ",";
        accessors += ",";
      }
      views += "{\"buffer\":0,\"byteOffset\":" + std::to_string(off) + ",\"byteLength\":" + std::to_string(bytes.size()) + "}";
      accessors += "{\"bufferView\":" + std::to_string(nview) + ",\"componentType\":" + std::to_string(ctype) +
                   ",\"count\":" + std::to_string(count) + ",\"type\":\"" + type + "\"}";
      return nview++;
    };
    const size_t V = static_cast<size_t>(vertices.rows()), J = names.size();
    std::vector<uint8_t> pb, jb, wb, ib, mb;
    for (size_t v = 0; v < V; ++v) {
      for (int c = 0; c < 3; ++c) putF(pb, static_cast<float>(vertices(static_cast<Eigen::Index>(v), c)));
      for (int k = 0; k < 4; ++k) {
        put16(jb, static_cast<uint16_t>(joints(static_cast<Eigen::Index>(v), k)));
        putF(wb, static_cast<float>(weights(static_cast<Eigen::Index>(v), k)));
      }
    }
    for (int i : indices) put32(ib, static_cast<uint32_t>(i));
    for (size_t k = 0; k < J; ++k) {
      const Eigen::Vector3d t = position[static_cast<size_t>(skinOrder[k])];
      const float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, static_cast<float>(-t(0)), static_cast<float>(-t(1)),
                           static_cast<float>(-t(2)), 1};
      for (float x : m) putF(mb, x);
    }
    const int ap = add(pb, 5126, V, "VEC3"), aj = add(jb, 5123, V, "VEC4"), aw = add(wb, 5126, V, "VEC4");
    const int ai = add(ib, 5125, indices.size(), "SCALAR"), am = add(mb, 5126, J, "MAT4");
    // Nodes: 0 armature, 1 mesh, 2 + j joint j.
    std::string nodes = "{\"name\":\"Armature\",\"children\":[1";
    for (size_t j = 0; j < J; ++j) {
      if (parent[j] < 0) nodes += "," + std::to_string(2 + j);
    }
    nodes += "]},{\"name\":\"mesh\",\"mesh\":0,\"skin\":0}";
    for (size_t j = 0; j < J; ++j) {
      const Eigen::Vector3d t = position[j] - (parent[j] < 0 ? Eigen::Vector3d::Zero() : position[static_cast<size_t>(parent[j])]);
      nodes += ",{\"name\":\"" + names[j] + "\",\"translation\":[" + num(t(0)) + "," + num(t(1)) + "," + num(t(2)) + "]";
      std::string kids;
      for (size_t c = 0; c < J; ++c) {
        if (parent[c] == static_cast<int>(j)) kids += (kids.empty() ? "" : ",") + std::to_string(2 + c);
      }
      if (!kids.empty()) nodes += ",\"children\":[" + kids + "]";
      nodes += "}";
    }
    std::string sj;
    for (size_t k = 0; k < J; ++k) sj += (k ? "," : "") + std::to_string(2 + skinOrder[k]);
    json = "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[" + nodes + "],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":" +
           std::to_string(ap) + ",\"JOINTS_0\":" + std::to_string(aj) + ",\"WEIGHTS_0\":" + std::to_string(aw) +
           "},\"indices\":" + std::to_string(ai) + "}]}],\"skins\":[{\"inverseBindMatrices\":" + std::to_string(am) +
           ",\"joints\":[" + sj + "]}],\"accessors\":[" + accessors + "],\"bufferViews\":[" + views +
           "],\"buffers\":[{\"byteLength\":" + std::to_string(bin.size()) + "}]}";
    return makeGlb(json, bin);
  }
};

/// A WebXR-named hand skeleton (25 joints, names prefixed "r_"), every joint a direct child of the
/// armature (as in the WebXR generic hands), listed in reverse order in the skin; each joint gets
/// a tetrahedron of 4 vertices around it, weighted to it and its parent.
inline SimpleSkin webxrLikeHand(const std::vector<std::string>& xrNames, const std::vector<int>& xrParents) {
  SimpleSkin s;
  const size_t J = xrNames.size();
  for (size_t j = 0; j < J; ++j) {
    s.names.push_back("r_" + xrNames[j]);
    s.parent.push_back(-1);
  }
  // Positions: wrist at origin; chain c (0 thumb .. 4 pinky) fans out in x, extends along −y.
  s.position.resize(J);
  for (size_t j = 0; j < J; ++j) {
    if (j == 0) {
      s.position[0] = Eigen::Vector3d(0, 0, 0);
      continue;
    }
    const int chain = static_cast<int>((j - 1) / 5), link = static_cast<int>((j - 1) % 5);
    s.position[j] = Eigen::Vector3d(0.02 * (chain - 2) * (1 + 0.2 * link), -0.02 - 0.025 * link - 0.003 * chain, 0.001 * link);
  }
  for (size_t k = 0; k < J; ++k) s.skinOrder.push_back(static_cast<int>(J - 1 - k));
  std::vector<int> skinOf(J);
  for (size_t k = 0; k < J; ++k) skinOf[static_cast<size_t>(s.skinOrder[k])] = static_cast<int>(k);
  s.vertices.resize(static_cast<Eigen::Index>(4 * J), 3);
  s.joints = Eigen::MatrixXi::Zero(static_cast<Eigen::Index>(4 * J), 4);
  s.weights = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(4 * J), 4);
  const double d = 0.004;
  const double off[4][3] = {{d, d, d}, {d, -d, -d}, {-d, d, -d}, {-d, -d, d}};
  for (size_t j = 0; j < J; ++j) {
    for (int q = 0; q < 4; ++q) {
      const Eigen::Index v = static_cast<Eigen::Index>(4 * j + static_cast<size_t>(q));
      for (int c = 0; c < 3; ++c) s.vertices(v, c) = s.position[j](c) + off[q][c];
      const int p = xrParents[j] < 0 ? 0 : xrParents[j];
      s.joints(v, 0) = skinOf[j];
      s.joints(v, 1) = skinOf[static_cast<size_t>(p)];
      s.weights(v, 0) = 0.75;
      s.weights(v, 1) = 0.25;
    }
    const int b = static_cast<int>(4 * j);
    for (int i : {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2}) s.indices.push_back(b + i);
  }
  return s;
}

}  // namespace gltf_test
