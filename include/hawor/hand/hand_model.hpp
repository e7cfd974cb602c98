// hawor/hand/hand_model.hpp — the data of a MANO-style skinned hand model.
//
// Generic in the number of joints J and vertices V (MANO: J = 16, V = 778, B = 10 shape
// coefficients, 135 = 9·15 pose features, docs/design.md §3). Units: metres, in the model's own frame.
// Layout follows the numpy arrays of the MANO files: a vertex-major flattening v·3 + c for every
// per-vertex quantity, so that `shapedirs` is the (V,3,B) array reshaped to (3V, B) and
// `posedirs` the (V,3,9(J−1)) array reshaped to (3V, 9(J−1)).
//
// After filling or editing the public fields call prepare(): it validates them (throwing
// hawor::Error naming what is wrong) and builds the derived data the forward pass uses (rest
// joints regressed from the template and shape directions, sparse skinning weights).
// Thread-safety: a prepared model is read-only in the forward pass and may be shared by threads,
// each with its own HandWorkspace.
#pragma once

#include "hawor/common.hpp"
#include "hawor/matmul.hpp"

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

namespace hawor {

/// Integer (F,3) triangle list, row-major like numpy's `f`.
using Faces = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// MANO's fingertip vertices, in the order thumb, index, middle, ring, pinky (docs/design.md §3).
inline std::vector<int> manoTipVertices() { return {744, 320, 443, 554, 671}; }

/// The 21 keypoints in OpenPose / MediaPipe order as indices into [16 joints, 5 tips]
/// (16..20 are the tips of manoTipVertices()) (docs/design.md §3, official).
inline std::vector<int> manoKeypointMap() {
  return {0, 13, 14, 15, 16, 1, 2, 3, 17, 4, 5, 6, 18, 10, 11, 12, 19, 7, 8, 9, 20};
}

/// MANO's kinematic tree: 0 wrist; 1–3 index; 4–6 middle; 7–9 pinky; 10–12 ring; 13–15 thumb.
inline std::vector<int> manoParents() { return {-1, 0, 1, 2, 0, 4, 5, 0, 7, 8, 0, 10, 11, 0, 13, 14}; }

template <typename Scalar>
struct HandModel {
  // --- model data (numpy layout, see the file comment) ----------------------------------------
  Points3<Scalar> vTemplate;  ///< (V,3) mean-shape template in the rest pose
  MatX<Scalar> shapedirs;     ///< (3V, B) shape blend shapes; B may be 0
  MatX<Scalar> posedirs;      ///< (3V, 9(J−1)) pose correctives over (R_j − I) features; may be empty
  MatX<Scalar> jRegressor;    ///< (J, V) joint regressor (dense)
  MatX<Scalar> weights;       ///< (V, J) linear-blend-skinning weights (rows normally sum to 1)
  Faces faces;                ///< (F,3) triangles; a left model's winding is already [0,2,1]
  std::vector<int> parents;   ///< (J) parent of each joint; parents[0] = −1, parents[j] < j
  std::vector<int> tipVertices;  ///< extra keypoint vertices appended after the joints
  /// Output keypoints as indices into [joints..., tipVertices...]; empty = no keypoints.
  std::vector<int> keypointMap;
  bool isLeft = false;  ///< handedness (informative; the data already is the left or right hand)

  int numVertices() const { return static_cast<int>(vTemplate.rows()); }
  int numJoints() const { return static_cast<int>(parents.size()); }
  int numBetas() const { return static_cast<int>(shapedirs.cols()); }
  /// 9(J−1) when the model has pose correctives, else 0.
  int numPoseFeatures() const { return static_cast<int>(posedirs.cols()); }
  int numKeypoints() const { return static_cast<int>(keypointMap.size()); }

  /// Throws hawor::Error naming the first inconsistency: shapes, non-finite values, faces or
  /// keypoint indices out of range, a parent table that is not a tree ordered parent-first.
  void validate() const {
    const Eigen::Index V = vTemplate.rows();
    const Eigen::Index J = static_cast<Eigen::Index>(parents.size());
    const std::string m = "hand model: ";
    if (V < 1) throw Error(m + "v_template has no vertices");
    if (J < 1) throw Error(m + "no joints (empty parents / kintree_table)");
    if (!allFinite(vTemplate)) throw Error(m + "v_template has non-finite values");
    if (shapedirs.cols() > 0 && shapedirs.rows() != 3 * V) {
      throw Error(m + "shapedirs has " + std::to_string(shapedirs.rows()) + " rows, expected 3V = " +
                  std::to_string(3 * V));
    }
    if (!allFinite(shapedirs)) throw Error(m + "shapedirs has non-finite values");
    if (posedirs.size() > 0) {
      if (posedirs.rows() != 3 * V || posedirs.cols() != 9 * (J - 1)) {
        throw Error(m + "posedirs is " + std::to_string(posedirs.rows()) + "x" +
                    std::to_string(posedirs.cols()) + ", expected " + std::to_string(3 * V) + "x" +
                    std::to_string(9 * (J - 1)) + " (3V x 9(J-1))");
      }
      if (!allFinite(posedirs)) throw Error(m + "posedirs has non-finite values");
    }
    if (jRegressor.rows() != J || jRegressor.cols() != V) {
      throw Error(m + "J_regressor is " + std::to_string(jRegressor.rows()) + "x" +
                  std::to_string(jRegressor.cols()) + ", expected " + std::to_string(J) + "x" +
                  std::to_string(V) + " (J x V)");
    }
    if (!allFinite(jRegressor)) throw Error(m + "J_regressor has non-finite values");
    if (weights.rows() != V || weights.cols() != J) {
      throw Error(m + "weights is " + std::to_string(weights.rows()) + "x" +
                  std::to_string(weights.cols()) + ", expected " + std::to_string(V) + "x" +
                  std::to_string(J) + " (V x J)");
    }
    if (!allFinite(weights)) throw Error(m + "weights has non-finite values");
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
      for (int k = 0; k < 3; ++k) {
        if (faces(f, k) < 0 || faces(f, k) >= V) {
          throw Error(m + "face " + std::to_string(f) + " has vertex index " +
                      std::to_string(faces(f, k)) + " outside [0, " + std::to_string(V) + ")");
        }
      }
    }
    if (parents[0] != -1) throw Error(m + "joint 0 must be the root (parent -1)");
    for (Eigen::Index j = 1; j < J; ++j) {
      const int p = parents[static_cast<std::size_t>(j)];
      if (p < 0 || p >= j) {
        throw Error(m + "joint " + std::to_string(j) + " has parent " + std::to_string(p) +
                    "; parents must precede their children (0 <= parent < joint)");
      }
    }
    for (int t : tipVertices) {
      if (t < 0 || t >= V) {
        throw Error(m + "keypoint vertex " + std::to_string(t) + " outside [0, " + std::to_string(V) + ")");
      }
    }
    const int nPoints = static_cast<int>(J) + static_cast<int>(tipVertices.size());
    for (int k : keypointMap) {
      if (k < 0 || k >= nPoints) {
        throw Error(m + "keypoint index " + std::to_string(k) + " outside [0, " +
                    std::to_string(nPoints) + ") (joints + tip vertices)");
      }
    }
  }

  /// validate(), then build the derived data below. Call again after editing any field.
  void prepare() {
    validate();
    const Eigen::Index V = vTemplate.rows();
    const Eigen::Index J = static_cast<Eigen::Index>(parents.size());
    const Eigen::Index B = shapedirs.cols();
    // Rest joints are linear in β: J(β) = J_reg·T + Σ_k β_k·(J_reg·S_k), so regress once here.
    jTemplate.resize(J, 3);
    jTemplate.noalias() = jRegressor * vTemplate;
    jShapedirs.resize(3 * J, B);
    if (B > 0) {
      using Strided = Eigen::Map<const MatX<Scalar>, 0, Eigen::Stride<Eigen::Dynamic, 3>>;
      using StridedOut = Eigen::Map<MatX<Scalar>, 0, Eigen::Stride<Eigen::Dynamic, 3>>;
      for (int c = 0; c < 3; ++c) {
        // Rows 3v + c of S (a V x B view) and rows 3j + c of the result (a J x B view).
        const Strided Sc(shapedirs.data() + c, V, B, Eigen::Stride<Eigen::Dynamic, 3>(3 * V, 3));
        StridedOut Jc(jShapedirs.data() + c, J, B, Eigen::Stride<Eigen::Dynamic, 3>(3 * J, 3));
        Jc.noalias() = jRegressor * Sc;
      }
    }
    // Skinning weights are sparse (a few joints per vertex): keep the non-zeros per vertex.
    skinStart.assign(static_cast<std::size_t>(V) + 1, 0);
    skinJoint.clear();
    skinWeight.clear();
    for (Eigen::Index v = 0; v < V; ++v) {
      for (Eigen::Index j = 0; j < J; ++j) {
        if (weights(v, j) != Scalar(0)) {
          skinJoint.push_back(static_cast<int>(j));
          skinWeight.push_back(weights(v, j));
        }
      }
      skinStart[static_cast<std::size_t>(v) + 1] = static_cast<int>(skinJoint.size());
    }
#if !defined(EIGEN_VECTORIZE)
    // Without Eigen's SIMD kernels (WebAssembly) the batched pass multiplies by posedirsᵀ with
    // the packed kernel of matmul.hpp: B(r, j) = posedirs(j, r), column-major storage.
    posedirsPacked.pack(posedirs.data(), posedirs.rows(), 1, posedirs.cols(), posedirs.rows());
#endif
    prepared_ = true;
    revision_ = nextRevision();
  }
  bool prepared() const { return prepared_; }
  /// A number that changes with every prepare() of any model (lets workspaces detect a model
  /// that was edited and prepared again at the same address).
  std::uint64_t revision() const { return revision_; }

  // --- derived data (filled by prepare(); do not edit) ----------------------------------------
  Points3<Scalar> jTemplate;      ///< (J,3) J_reg · v_template
  MatX<Scalar> jShapedirs;        ///< (3J, B) J_reg applied to each shape direction
  std::vector<int> skinStart;     ///< (V+1) CSR row starts into skinJoint / skinWeight
  std::vector<int> skinJoint;     ///< joints with a non-zero weight, per vertex
  std::vector<Scalar> skinWeight;  ///< the matching weights
  /// posedirsᵀ (9(J−1) × 3V) packed for matmulPacked; filled only where Eigen has no SIMD
  /// kernels (EIGEN_VECTORIZE undefined, e.g. WebAssembly), empty otherwise.
  PackedPanels<Scalar> posedirsPacked;

 private:
  bool prepared_ = false;
  std::uint64_t revision_ = 0;
  // Process-wide counter; atomic so that models may be prepared on several threads.
  static std::uint64_t nextRevision() {
    static std::atomic<std::uint64_t> counter{0};
    return ++counter;
  }
};

using HandModelf = HandModel<float>;
using HandModeld = HandModel<double>;

/// Converts a prepared or unprepared model to another scalar type (the result is prepared when
/// the input was).
template <typename To, typename From>
HandModel<To> castHandModel(const HandModel<From>& in) {
  HandModel<To> out;
  out.vTemplate = in.vTemplate.template cast<To>();
  out.shapedirs = in.shapedirs.template cast<To>();
  out.posedirs = in.posedirs.template cast<To>();
  out.jRegressor = in.jRegressor.template cast<To>();
  out.weights = in.weights.template cast<To>();
  out.faces = in.faces;
  out.parents = in.parents;
  out.tipVertices = in.tipVertices;
  out.keypointMap = in.keypointMap;
  out.isLeft = in.isLeft;
  if (in.prepared()) out.prepare();
  return out;
}

}  // namespace hawor
