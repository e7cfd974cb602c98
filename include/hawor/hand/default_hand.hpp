// hawor/hand/default_hand.hpp — a HandModel from a skinned glTF hand: the licence-free default
// hand (docs/design.md §3: npm `@webxr-input-profiles/assets`, MIT, dist/profiles/generic-hand/
// {left,right}.glb: 1,360 vertices, 2,314 triangles, 25 joints named after the WebXR hand joints,
// linear blend skinning, no shape space, no pose correctives) or any similar skinned mesh.
//
// Frame. glTF skinning poses a vertex p as Σ_j w_j · W_j · IBM_j · p, with W_j the joint's world
// transform and IBM_j its inverse bind matrix; the transform of the skinned mesh's own node is
// ignored (glTF 2.0, "Skins"). In the bind pose W_j = IBM_j⁻¹ and every vertex stays at p, so
// POSITION is already the bind-pose mesh in the world frame of the bind pose, the frame of the
// IBM_j⁻¹. That frame is the model's frame here: v_template = POSITION unchanged, rest joint j =
// translation of IBM_j⁻¹ (the file's node transforms are not needed and may hold another pose).
// glTF's frame is right-handed, +y up, metres. In the WebXR generic hands the fingers point
// along −y (wrist y ≈ +0.056 m, middle tip y ≈ −0.122 m), the index lies towards −z and the
// pinky towards +z, the back of the right hand faces +x (left: −x; the left file is the right
// one mirrored in x); the wrist-to-middle-tip length is ≈ 0.178 m; the triangles wind
// counter-clockwise seen from outside in both files.
//
// Model. As MANO (hand/forward.hpp): rest frames world-aligned, G_j(rest) = [I | J_j], pose =
// per-joint axis-angle in the parent's frame. The bind rotations of the glTF joints (their bone
// axes) do not enter the skinning at rest, and are returned in DefaultHand::bindRotations for
// whoever wants to express a pose about the bone axes (a rotation R_bone about joint j's bind
// axes is R_model = Q_j · R_bone · Q_jᵀ here).
//   v_template  (V,3)  bind-pose POSITION of all triangle primitives of the skinned mesh
//   faces       (F,3)  their indices (glTF front faces are counter-clockwise; kept as is)
//   parents     (J)    the node hierarchy restricted to the skin's joints (nearest ancestor that
//                      is a joint) when it forms a single tree; otherwise, when the joint names
//                      are the 25 WebXR hand joints, the WebXR hand topology (the WebXR hands
//                      store every joint as a direct child of the armature: a flat list)
//   joint order        WebXR order (wrist, thumb-metacarpal, …, pinky-finger-tip) when the names
//                      are recognised and that order lists parents first; else the skin's order,
//                      made parent-first by a stable topological sort
//   weights     (V,J)  JOINTS_n / WEIGHTS_n (n = 0, 1, …), rows normalised to sum 1
//   J_regressor (J,V)  affine weights (sum 1) over 4 nearby non-coplanar vertices chosen so that
//                      J_reg · v_template reproduces the rest joints exactly (see
//                      exactJointRegressor); the joints need not be on or inside the mesh
//   shapedirs   (3V,0), posedirs empty, tipVertices empty
//   keypointMap (21)   for WebXR names: MediaPipe / OpenPose order 0 wrist; 1–4 thumb metacarpal
//                      (CMC), phalanx-proximal (MCP), phalanx-distal (IP), tip; 5–8 index
//                      phalanx-proximal (MCP), intermediate (PIP), distal (DIP), tip; 9–12 middle;
//                      13–16 ring; 17–20 pinky (the finger metacarpals are not keypoints);
//                      empty for other names.
// Joint names are matched after lower-casing and mapping '_' to '-', as the whole name or as a
// suffix after a separator ("r_wrist", "Armature:index-finger-tip").
// Thread-safety: functions only; no shared state.
#pragma once

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "hawor/common.hpp"
#include "hawor/hand/hand_model.hpp"
#include "hawor/io/gltf.hpp"

namespace hawor {

/// The 25 WebXR hand joints in XRHand order (WebXR Hand Input, "Skeleton joints").
inline std::vector<std::string> webxrJointNames() {
  return {"wrist",
          "thumb-metacarpal", "thumb-phalanx-proximal", "thumb-phalanx-distal", "thumb-tip",
          "index-finger-metacarpal", "index-finger-phalanx-proximal", "index-finger-phalanx-intermediate",
          "index-finger-phalanx-distal", "index-finger-tip",
          "middle-finger-metacarpal", "middle-finger-phalanx-proximal", "middle-finger-phalanx-intermediate",
          "middle-finger-phalanx-distal", "middle-finger-tip",
          "ring-finger-metacarpal", "ring-finger-phalanx-proximal", "ring-finger-phalanx-intermediate",
          "ring-finger-phalanx-distal", "ring-finger-tip",
          "pinky-finger-metacarpal", "pinky-finger-phalanx-proximal", "pinky-finger-phalanx-intermediate",
          "pinky-finger-phalanx-distal", "pinky-finger-tip"};
}

/// Parents of the WebXR joints in XRHand order: each chain hangs from the wrist.
inline std::vector<int> webxrParents() {
  return {-1, 0, 1, 2, 3, 0, 5, 6, 7, 8, 0, 10, 11, 12, 13, 0, 15, 16, 17, 18, 0, 20, 21, 22, 23};
}

/// The 21 MediaPipe / OpenPose keypoints as indices into the WebXR joints (XRHand order).
inline std::vector<int> webxrKeypointMap() {
  return {0, 1, 2, 3, 4, 6, 7, 8, 9, 11, 12, 13, 14, 16, 17, 18, 19, 21, 22, 23, 24};
}

/// A hand model converted from glTF with what the HandModel fields cannot hold.
template <typename Scalar>
struct DefaultHand {
  HandModel<Scalar> model;               ///< prepared
  std::vector<std::string> jointNames;   ///< node names, in the model's joint order
  std::vector<int> skinJoint;            ///< model joint j is skin.joints[skinJoint[j]]
  std::vector<Mat3<Scalar>> bindRotations;  ///< 3×3 part of IBM_j⁻¹ per model joint (bone axes)
  bool webxrJoints = false;              ///< the names were recognised as the 25 WebXR joints
};

/// Resource limits of the conversion (dense V×J matrices are built).
struct DefaultHandLimits {
  size_t maxVertices = size_t(1) << 20;
  size_t maxJoints = 512;
  size_t maxDenseEntries = size_t(1) << 25;  ///< V·J
};

namespace default_hand_detail {

inline std::string normaliseName(const std::string& s) {
  std::string o = s;
  for (char& c : o) {
    c = c == '_' ? '-' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return o;
}

/// Index of the WebXR joint that `name` denotes, or −1 (whole name, or suffix after a
/// non-alphanumeric separator).
inline int webxrIndex(const std::string& name, const std::vector<std::string>& xr) {
  const std::string n = normaliseName(name);
  for (size_t k = 0; k < xr.size(); ++k) {
    const std::string& w = xr[k];
    if (n == w) return static_cast<int>(k);
    if (n.size() > w.size() && n.compare(n.size() - w.size(), w.size(), w) == 0) {
      const unsigned char sep = static_cast<unsigned char>(n[n.size() - w.size() - 1]);
      if (!std::isalnum(sep)) return static_cast<int>(k);
    }
  }
  return -1;
}

}  // namespace default_hand_detail

/// A (J,V) regressor whose rows are affine weights (summing to 1) over 4 vertices each, with
/// R · verts = joints up to rounding (≈1e-16 relative in double). Candidates for joint x are its
/// `neighbours` nearest vertices plus the nearest vertex in each octant around x (so that vertices
/// on all sides are present); among all their non-degenerate tetrahedra (relative volume
/// |det| / L³ ≥ 1e-3), the one whose barycentric coordinates of x have the smallest largest
/// magnitude is used (≤ 1 when x lies inside it), then one step of iterative refinement. Throws
/// when no 4 non-coplanar vertices are found among the 32 nearest (and the octant ones).
template <typename Scalar>
MatX<Scalar> exactJointRegressor(const Points3<double>& verts, const Points3<double>& joints,
                                 int neighbours = 12) {
  const Eigen::Index V = verts.rows(), J = joints.rows();
  if (V < 4) throw Error("joint regressor: needs at least 4 vertices, the mesh has " + std::to_string(V));
  MatX<double> R = MatX<double>::Zero(J, V);
  std::vector<std::pair<double, Eigen::Index>> dist(static_cast<size_t>(V));
  std::vector<Eigen::Index> cand;
  std::vector<double> rel;
  for (Eigen::Index j = 0; j < J; ++j) {
    const Eigen::Vector3d x = joints.row(j).transpose();
    Eigen::Index octant[8];
    double octantDist[8];
    for (int o = 0; o < 8; ++o) {
      octant[o] = -1;
      octantDist[o] = std::numeric_limits<double>::infinity();
    }
    for (Eigen::Index v = 0; v < V; ++v) {
      const Eigen::Vector3d d = verts.row(v).transpose() - x;
      const double d2 = d.squaredNorm();
      dist[static_cast<size_t>(v)] = {d2, v};
      const int o = (d(0) >= 0 ? 1 : 0) | (d(1) >= 0 ? 2 : 0) | (d(2) >= 0 ? 4 : 0);
      if (d2 < octantDist[o]) {
        octantDist[o] = d2;
        octant[o] = v;
      }
    }
    bool found = false;
    for (int k = std::max(4, neighbours);; k *= 2) {
      const size_t K = static_cast<size_t>(std::min<Eigen::Index>(k, V));
      std::partial_sort(dist.begin(), dist.begin() + static_cast<std::ptrdiff_t>(K), dist.end());
      cand.clear();
      for (size_t q = 0; q < K; ++q) cand.push_back(dist[q].second);
      for (int o = 0; o < 8; ++o) {
        if (octant[o] >= 0 && std::find(cand.begin(), cand.end(), octant[o]) == cand.end()) cand.push_back(octant[o]);
      }
      // Candidate positions relative to x, as plain arrays (this loop is O(C⁴)).
      const size_t C = cand.size();
      rel.resize(3 * C);
      for (size_t q = 0; q < C; ++q) {
        for (int c = 0; c < 3; ++c) rel[3 * q + static_cast<size_t>(c)] = verts(cand[q], c) - x(c);
      }
      double best = std::numeric_limits<double>::infinity();
      size_t bi[4] = {0, 0, 0, 0};
      for (size_t a = 0; a < C; ++a) {
        const double* pa = &rel[3 * a];
        for (size_t b = a + 1; b < C; ++b) {
          const double eb[3] = {rel[3 * b] - pa[0], rel[3 * b + 1] - pa[1], rel[3 * b + 2] - pa[2]};
          const double lb = eb[0] * eb[0] + eb[1] * eb[1] + eb[2] * eb[2];
          for (size_t c = b + 1; c < C; ++c) {
            const double ec[3] = {rel[3 * c] - pa[0], rel[3 * c + 1] - pa[1], rel[3 * c + 2] - pa[2]};
            const double lc = ec[0] * ec[0] + ec[1] * ec[1] + ec[2] * ec[2];
            const double bxc[3] = {eb[1] * ec[2] - eb[2] * ec[1], eb[2] * ec[0] - eb[0] * ec[2], eb[0] * ec[1] - eb[1] * ec[0]};
            // −a·(b−a)×(c−a): numerator of w_d.
            const double nd = -(pa[0] * bxc[0] + pa[1] * bxc[1] + pa[2] * bxc[2]);
            for (size_t d = c + 1; d < C; ++d) {
              // Barycentric coordinates of x (the origin of rel) by Cramer's rule, with
              // det = (d−a)·((b−a)×(c−a)) and w_b = −a·((c−a)×(d−a))/det, w_c = −a·((d−a)×(b−a))/det.
              const double ed[3] = {rel[3 * d] - pa[0], rel[3 * d + 1] - pa[1], rel[3 * d + 2] - pa[2]};
              const double det = ed[0] * bxc[0] + ed[1] * bxc[1] + ed[2] * bxc[2];
              const double ld = ed[0] * ed[0] + ed[1] * ed[1] + ed[2] * ed[2];
              const double L2 = std::max(lb, std::max(lc, ld));
              // Skip slivers: relative volume |det| / L³ below 1e-3.
              if (!(L2 > 0) || !(std::abs(det) >= 1e-3 * L2 * std::sqrt(L2))) continue;
              const double cxd[3] = {ec[1] * ed[2] - ec[2] * ed[1], ec[2] * ed[0] - ec[0] * ed[2], ec[0] * ed[1] - ec[1] * ed[0]};
              const double dxb[3] = {ed[1] * eb[2] - ed[2] * eb[1], ed[2] * eb[0] - ed[0] * eb[2], ed[0] * eb[1] - ed[1] * eb[0]};
              const double wb = -(pa[0] * cxd[0] + pa[1] * cxd[1] + pa[2] * cxd[2]) / det;
              const double wc = -(pa[0] * dxb[0] + pa[1] * dxb[1] + pa[2] * dxb[2]) / det;
              const double wd = nd / det;
              const double wa = 1.0 - wb - wc - wd;
              const double score = std::max(std::max(std::abs(wa), std::abs(wb)), std::max(std::abs(wc), std::abs(wd)));
              if (score < best) {
                best = score;
                bi[0] = a;
                bi[1] = b;
                bi[2] = c;
                bi[3] = d;
              }
            }
          }
        }
      }
      if (std::isfinite(best)) {
        // Solve the chosen tetrahedron with pivoted LU, then refine once on the residual.
        const Eigen::Vector3d pa = verts.row(cand[bi[0]]).transpose();
        Eigen::Matrix3d M;
        for (int q = 0; q < 3; ++q) M.col(q) = verts.row(cand[bi[q + 1]]).transpose() - pa;
        const Eigen::FullPivLU<Eigen::Matrix3d> lu(M);
        Eigen::Vector3d bc = lu.solve(x - pa);
        Eigen::Vector3d r = x - pa - M * bc;
        bc += lu.solve(r);
        const Eigen::Vector4d w(1.0 - bc.sum(), bc(0), bc(1), bc(2));
        for (int q = 0; q < 4; ++q) R(j, cand[bi[q]]) = w(q);
        found = true;
        break;
      }
      // Widen the search (16 → 32 nearest) only for degenerate neighbourhoods; the cost grows
      // as the 4th power of the candidates, so it stops there.
      if (static_cast<Eigen::Index>(K) >= V || K >= 32) break;
    }
    if (!found) {
      throw Error("joint regressor: no 4 non-coplanar vertices near joint " + std::to_string(j) +
                  " (is the mesh flat?)");
    }
  }
  return R.cast<Scalar>();
}

/// Converts the skinned mesh of `g` (its only node with both a mesh and a skin) into a hand model
/// (see the file comment). `isLeft` records the handedness. Throws hawor::Error naming the file
/// and the problem.
template <typename Scalar = double>
DefaultHand<Scalar> handFromGltf(const Gltf& g, bool isLeft, const DefaultHandLimits& limits = {}) {
  const std::string& src = g.source();
  auto fail = [&](const std::string& m) -> Error { return Error(src + ": " + m); };

  // --- the skinned mesh ------------------------------------------------------------------------
  int meshNode = -1, count = 0;
  for (size_t i = 0; i < g.nodes().size(); ++i) {
    if (g.nodes()[i].mesh >= 0 && g.nodes()[i].skin >= 0) {
      if (meshNode < 0) meshNode = static_cast<int>(i);
      ++count;
    }
  }
  if (meshNode < 0) throw fail("no skinned mesh (no node has both a mesh and a skin)");
  if (count > 1) throw fail(std::to_string(count) + " skinned mesh nodes; a hand model needs exactly one");
  const GltfNode& mn = g.nodes()[static_cast<size_t>(meshNode)];
  const GltfSkin& skin = g.skins()[static_cast<size_t>(mn.skin)];
  const GltfMesh& mesh = g.meshes()[static_cast<size_t>(mn.mesh)];
  const size_t J = skin.joints.size();
  if (J > limits.maxJoints) throw fail("the skin has " + std::to_string(J) + " joints, over the limit of " + std::to_string(limits.maxJoints));

  // --- bind pose: rest joints from the inverse bind matrices -------------------------------------
  if (skin.inverseBindMatrices < 0) {
    throw fail("the skin has no inverseBindMatrices, so its bind pose (the rest pose) is unknown");
  }
  const std::vector<double> ibm = g.readFloats(skin.inverseBindMatrices);
  std::vector<Eigen::Matrix4d> bind(J);
  for (size_t k = 0; k < J; ++k) {
    Eigen::Matrix4d M;
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) M(r, c) = ibm[16 * k + static_cast<size_t>(4 * c + r)];  // column-major
    }
    const std::string w = "inverse bind matrix " + std::to_string(k);
    if (!M.allFinite()) throw fail(w + " has non-finite values");
    const double scale = 1.0 + M.cwiseAbs().maxCoeff();
    if ((M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6 * scale) {
      throw fail(w + " is not affine (last row is not 0 0 0 1)");
    }
    const double det = M.topLeftCorner<3, 3>().determinant();
    if (!(std::abs(det) > 1e-12)) throw fail(w + " is singular");
    bind[k] = M.inverse();
  }

  // --- joint names, parents and order ----------------------------------------------------------
  const std::vector<std::string> xr = webxrJointNames();
  std::vector<int> xrOfSkin(J, -1), skinOfXr(xr.size(), -1);
  bool webxr = J == xr.size();
  for (size_t k = 0; k < J; ++k) {
    const int x = default_hand_detail::webxrIndex(g.nodes()[static_cast<size_t>(skin.joints[k])].name, xr);
    xrOfSkin[k] = x;
    if (x < 0 || skinOfXr[static_cast<size_t>(x)] >= 0) {
      webxr = false;
    } else {
      skinOfXr[static_cast<size_t>(x)] = static_cast<int>(k);
    }
  }
  // Parents from the node hierarchy: nearest ancestor that is one of the skin's joints.
  std::vector<int> skinOfNode(g.nodes().size(), -1);
  for (size_t k = 0; k < J; ++k) skinOfNode[static_cast<size_t>(skin.joints[k])] = static_cast<int>(k);
  std::vector<int> parentSkin(J, -1);
  int roots = 0;
  for (size_t k = 0; k < J; ++k) {
    int p = g.nodes()[static_cast<size_t>(skin.joints[k])].parent;
    while (p >= 0 && skinOfNode[static_cast<size_t>(p)] < 0) p = g.nodes()[static_cast<size_t>(p)].parent;
    parentSkin[k] = p >= 0 ? skinOfNode[static_cast<size_t>(p)] : -1;
    if (parentSkin[k] < 0) ++roots;
  }
  if (roots != 1) {
    if (!webxr) {
      throw fail("the skin's joints form " + std::to_string(roots) +
                 " separate trees in the node hierarchy and are not named as the WebXR hand joints, so "
                 "no kinematic tree can be derived");
    }
    const std::vector<int> xp = webxrParents();
    for (size_t k = 0; k < J; ++k) {
      const int px = xp[static_cast<size_t>(xrOfSkin[k])];
      parentSkin[k] = px < 0 ? -1 : skinOfXr[static_cast<size_t>(px)];
    }
  }
  // Order: WebXR order when recognised and parent-first, else a stable topological sort.
  std::vector<int> order;  // model joint -> skin joint
  if (webxr) {
    std::vector<int> rank(J);
    for (size_t x = 0; x < xr.size(); ++x) rank[static_cast<size_t>(skinOfXr[x])] = static_cast<int>(x);
    bool ok = true;
    for (size_t k = 0; k < J; ++k) {
      if (parentSkin[k] >= 0 && rank[static_cast<size_t>(parentSkin[k])] > rank[k]) ok = false;
    }
    if (parentSkin[static_cast<size_t>(skinOfXr[0])] >= 0) ok = false;  // the wrist must be the root
    if (ok) order = skinOfXr;
  }
  if (order.empty()) {
    std::vector<std::vector<int>> kids(J);
    std::priority_queue<int, std::vector<int>, std::greater<int>> ready;
    for (size_t k = 0; k < J; ++k) {
      if (parentSkin[k] < 0) {
        ready.push(static_cast<int>(k));
      } else {
        kids[static_cast<size_t>(parentSkin[k])].push_back(static_cast<int>(k));
      }
    }
    while (!ready.empty()) {
      const int k = ready.top();
      ready.pop();
      order.push_back(k);
      for (int c : kids[static_cast<size_t>(k)]) ready.push(c);
    }
    if (order.size() != J) throw fail("the skin's joint hierarchy is not a tree");
  }
  std::vector<int> modelOfSkin(J, -1);
  for (size_t j = 0; j < J; ++j) modelOfSkin[static_cast<size_t>(order[j])] = static_cast<int>(j);

  // --- vertices, faces, weights of every primitive ----------------------------------------------
  std::vector<double> pos;
  std::vector<int> tri;
  std::vector<std::vector<std::pair<int, double>>> influences;  // per vertex: (model joint, w)
  for (size_t p = 0; p < mesh.primitives.size(); ++p) {
    const GltfPrimitive& prim = mesh.primitives[p];
    const std::string wp = "mesh " + std::to_string(mn.mesh) + " primitive " + std::to_string(p);
    if (prim.mode != gltf::kModeTriangles) {
      throw fail(wp + " has mode " + std::to_string(prim.mode) + "; only TRIANGLES (4) is supported");
    }
    const int ap = prim.attribute("POSITION");
    if (ap < 0) throw fail(wp + " has no POSITION");
    const GltfAccessor& pa = g.accessors()[static_cast<size_t>(ap)];
    if (pa.type != "VEC3") throw fail(wp + " POSITION is " + pa.type + ", expected VEC3");
    const size_t nv = pa.count;
    const size_t base = pos.size() / 3;
    if (base + nv > limits.maxVertices || (base + nv) * J > limits.maxDenseEntries) {
      throw fail("the mesh has more than " + std::to_string(base + nv - 1) + " vertices: too large for a dense hand model");
    }
    const std::vector<double> P = g.readFloats(ap);
    pos.insert(pos.end(), P.begin(), P.end());
    influences.resize(base + nv);
    for (int set = 0;; ++set) {
      const int aj = prim.attribute("JOINTS_" + std::to_string(set));
      const int aw = prim.attribute("WEIGHTS_" + std::to_string(set));
      if (aj < 0 && aw < 0) {
        if (set == 0) throw fail(wp + " has no JOINTS_0 / WEIGHTS_0 (not a skinned mesh)");
        break;
      }
      if (aj < 0 || aw < 0) throw fail(wp + " has only one of JOINTS_" + std::to_string(set) + " and WEIGHTS_" + std::to_string(set));
      const GltfAccessor& ja = g.accessors()[static_cast<size_t>(aj)];
      const GltfAccessor& wa = g.accessors()[static_cast<size_t>(aw)];
      if (ja.type != "VEC4" || wa.type != "VEC4") throw fail(wp + " JOINTS/WEIGHTS_" + std::to_string(set) + " must be VEC4");
      if (ja.count != nv || wa.count != nv) {
        throw fail(wp + " JOINTS/WEIGHTS_" + std::to_string(set) + " have " + std::to_string(ja.count) + "/" +
                   std::to_string(wa.count) + " elements for " + std::to_string(nv) + " vertices");
      }
      const std::vector<uint32_t> jv = g.readUints(aj);
      const std::vector<double> wv = g.readFloats(aw);
      for (size_t v = 0; v < nv; ++v) {
        for (size_t q = 0; q < 4; ++q) {
          const double w = wv[4 * v + q];
          const uint32_t sj = jv[4 * v + q];
          if (!std::isfinite(w) || w < 0) {
            throw fail(wp + " vertex " + std::to_string(v) + " has a negative or non-finite skinning weight");
          }
          if (w == 0) continue;
          if (sj >= J) {
            throw fail(wp + " vertex " + std::to_string(v) + " is weighted to joint " + std::to_string(sj) +
                       " but the skin has " + std::to_string(J));
          }
          influences[base + v].push_back({modelOfSkin[sj], w});
        }
      }
    }
    if (prim.indices >= 0) {
      const GltfAccessor& ia = g.accessors()[static_cast<size_t>(prim.indices)];
      if (ia.type != "SCALAR") throw fail(wp + " indices must be SCALAR");
      if (ia.count % 3 != 0) throw fail(wp + " has " + std::to_string(ia.count) + " indices, not a multiple of 3");
      const std::vector<uint32_t> iv = g.readUints(prim.indices);
      for (uint32_t i : iv) {
        if (i >= nv) throw fail(wp + " index " + std::to_string(i) + " is out of range (" + std::to_string(nv) + " vertices)");
        tri.push_back(static_cast<int>(base + i));
      }
    } else {
      if (nv % 3 != 0) throw fail(wp + " is non-indexed with " + std::to_string(nv) + " vertices, not a multiple of 3");
      for (size_t i = 0; i < nv; ++i) tri.push_back(static_cast<int>(base + i));
    }
  }
  const Eigen::Index V = static_cast<Eigen::Index>(pos.size() / 3);

  // --- assemble ------------------------------------------------------------------------------------
  DefaultHand<Scalar> out;
  HandModel<Scalar>& m = out.model;
  Points3<double> vt(V, 3);
  for (Eigen::Index v = 0; v < V; ++v) {
    for (int c = 0; c < 3; ++c) vt(v, c) = pos[static_cast<size_t>(3 * v + c)];
  }
  if (!vt.allFinite()) throw fail("POSITION has non-finite values");
  m.vTemplate = vt.cast<Scalar>();
  m.faces.resize(static_cast<Eigen::Index>(tri.size() / 3), 3);
  for (size_t i = 0; i < tri.size(); ++i) m.faces(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3)) = tri[i];
  MatX<double> W = MatX<double>::Zero(V, static_cast<Eigen::Index>(J));
  for (Eigen::Index v = 0; v < V; ++v) {
    double sum = 0;
    for (const auto& jw : influences[static_cast<size_t>(v)]) {
      W(v, jw.first) += jw.second;
      sum += jw.second;
    }
    if (!(sum > 0)) throw fail("vertex " + std::to_string(v) + " has no skinning weight");
    W.row(v) /= sum;
  }
  m.weights = W.cast<Scalar>();
  Points3<double> rest(static_cast<Eigen::Index>(J), 3);
  m.parents.resize(J);
  out.jointNames.resize(J);
  out.skinJoint = order;
  out.bindRotations.resize(J);
  for (size_t j = 0; j < J; ++j) {
    const size_t k = static_cast<size_t>(order[j]);
    rest.row(static_cast<Eigen::Index>(j)) = bind[k].block<3, 1>(0, 3).transpose();
    m.parents[j] = parentSkin[k] < 0 ? -1 : modelOfSkin[static_cast<size_t>(parentSkin[k])];
    out.jointNames[j] = g.nodes()[static_cast<size_t>(skin.joints[k])].name;
    out.bindRotations[j] = bind[k].topLeftCorner<3, 3>().cast<Scalar>();
  }
  const MatX<double> Rd = exactJointRegressor<double>(vt, rest);
  const double err = (Rd * vt - rest).cwiseAbs().maxCoeff();
  if (!(err <= 1e-9 * (1.0 + rest.cwiseAbs().maxCoeff()))) {
    throw fail("internal: the joint regressor misses the rest joints by " + std::to_string(err));
  }
  m.jRegressor = Rd.cast<Scalar>();
  m.shapedirs.resize(3 * V, 0);
  m.posedirs.resize(0, 0);
  m.isLeft = isLeft;
  out.webxrJoints = webxr;
  if (webxr) {
    for (int x : webxrKeypointMap()) m.keypointMap.push_back(modelOfSkin[static_cast<size_t>(skinOfXr[static_cast<size_t>(x)])]);
  }
  m.prepare();
  return out;
}

/// Reads a .glb file and converts its skinned mesh (handFromGltf).
template <typename Scalar = double>
DefaultHand<Scalar> loadDefaultHand(const std::string& glbPath, bool isLeft, const GltfLimits& glbLimits = {},
                                    const DefaultHandLimits& limits = {}) {
  return handFromGltf<Scalar>(Gltf::readGlb(glbPath, glbLimits), isLeft, limits);
}

/// The same from .glb bytes; `what` names them in errors.
template <typename Scalar = double>
DefaultHand<Scalar> loadDefaultHand(const uint8_t* data, size_t n, bool isLeft, const std::string& what = "GLB",
                                    const GltfLimits& glbLimits = {}, const DefaultHandLimits& limits = {}) {
  return handFromGltf<Scalar>(Gltf::fromGlb(data, n, what, glbLimits), isLeft, limits);
}

/// Rest-pose distance from keypoint 0 (wrist) to keypoint 12 (middle fingertip) of a model with
/// the 21 keypoints, in metres; NaN when the model has no such keypoints.
template <typename Scalar>
Scalar restHandLength(const HandModel<Scalar>& m) {
  if (m.numKeypoints() != 21) return std::numeric_limits<Scalar>::quiet_NaN();
  const Points3<Scalar> joints = m.jRegressor * m.vTemplate;
  auto point = [&](int k) -> Vec3<Scalar> {
    const int idx = m.keypointMap[static_cast<size_t>(k)];
    if (idx < m.numJoints()) return joints.row(idx).transpose();
    return m.vTemplate.row(m.tipVertices[static_cast<size_t>(idx - m.numJoints())]).transpose();
  };
  return (point(12) - point(0)).norm();
}

}  // namespace hawor
