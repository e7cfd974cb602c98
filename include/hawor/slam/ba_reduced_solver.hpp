// hawor/slam/ba_reduced_solver.hpp — the linear solvers of bundle adjustment's reduced camera
// system S·x = b (bundle_adjustment.hpp): S symmetric positive definite, made of 6×6 blocks of
// which only those of co-observing cameras (and prior pairs) are non-zero, given as the upper
// blocks (ci ≤ cj) under sorted keys.
//   Dense:     S assembled into an n×n matrix, Cholesky (LLT) in place; for sliding windows.
//   Sparse:    S as a lower-triangular sparse matrix, simplicial Cholesky with AMD ordering, the
//              pattern analysed once for all the solves of one solver.
//   Iterative: conjugate gradients from x = 0, preconditioned by the inverses of S's 6×6
//              diagonal blocks (block Jacobi; the "iterative Schur" of Agarwal et al. 2010), using
//              only the stored blocks, to ‖S·x − b‖ ≤ tolerance·‖b‖ within maxIterations.
//   Implicit:  the same iteration where S is known only by its product and its diagonal blocks
//              (conjugateGradients; bundle_adjustment.hpp applies S point by point).
// One solver per problem (it keeps the factorisation's pattern and its scratch); not thread-safe.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "hawor/common.hpp"

namespace hawor {

/// Key of block (ci, cj), ci ≤ cj, of a block matrix: sorted keys order the blocks by row, then
/// column.
inline std::uint64_t blockKey(int ci, int cj) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ci)) << 32) | static_cast<std::uint32_t>(cj);
}
inline int blockKeyRow(std::uint64_t key) { return static_cast<int>(key >> 32); }
inline int blockKeyCol(std::uint64_t key) { return static_cast<int>(key & 0xFFFFFFFFu); }

enum class ReducedSolverMethod { Dense, Sparse, Iterative, ImplicitSchur };

template <typename Scalar>
class ReducedCameraSolver {
 public:
  using Block = Eigen::Matrix<Scalar, 6, 6, Eigen::DontAlign>;  ///< unaligned storage (WASM)

  /// `keys`: the sorted keys of the stored blocks (blockKey) of an n×n-block matrix, every
  /// diagonal block among them; `diagBlock[c]`: the index of block (c, c) in `keys`. Both must
  /// outlive the solver.
  ReducedCameraSolver(ReducedSolverMethod method, int n, const std::vector<std::uint64_t>& keys,
                      const std::vector<int>& diagBlock, Scalar cgTolerance = Scalar(1e-8), int cgMaxIterations = 500)
      : method_(method), n_(n), keys_(keys), diag_(diagBlock), cgTolerance_(cgTolerance), cgMaxIterations_(cgMaxIterations) {}

  ReducedSolverMethod method() const { return method_; }

  /// Solves S·x = b with S[b] the block of keys[b]; false when S shows itself not positive
  /// definite (a failed factorisation, a diagonal block, or pᵀSp ≤ 0 in CG) or x is not finite.
  bool solve(const std::vector<Block>& S, const VecX<Scalar>& b, VecX<Scalar>& x) {
    bool ok = false;
    switch (method_) {
      case ReducedSolverMethod::Dense: ok = solveDense(S, b, x); break;
      case ReducedSolverMethod::Sparse: ok = solveSparse(S, b, x); break;
      case ReducedSolverMethod::Iterative: ok = solveCG(S, b, x); break;
      case ReducedSolverMethod::ImplicitSchur: throw Error("ReducedCameraSolver: an implicit S is solved by conjugateGradients");
    }
    return ok && x.allFinite();
  }

  /// Preconditioned conjugate gradients for S·x = b from x = 0, S given only by its product
  /// (`apply(p, q)`: q = S·p) and its 6×6 diagonal blocks (`diagBlock(c)`, their inverses the
  /// block-Jacobi preconditioner); to ‖S·x − b‖ ≤ cgTolerance·‖b‖ within cgMaxIterations. False
  /// when a diagonal block is not positive definite or pᵀSp ≤ 0 (S not positive definite).
  template <typename DiagBlock, typename Apply>
  bool conjugateGradients(const DiagBlock& diagBlock, const VecX<Scalar>& b, VecX<Scalar>& x, const Apply& apply) {
    blockInv_.resize(static_cast<std::size_t>(n_));
    for (int c = 0; c < n_; ++c) {
      const M6 D = diagBlock(c);
      const Eigen::LLT<M6> l(D);
      if (l.info() != Eigen::Success) return false;
      blockInv_[static_cast<std::size_t>(c)] = l.solve(M6::Identity());
    }
    const auto precondition = [&](const VecX<Scalar>& r, VecX<Scalar>& z) {
      z.resize(6 * n_);
      for (int c = 0; c < n_; ++c) {
        z.template segment<6>(6 * c).noalias() = blockInv_[static_cast<std::size_t>(c)] * r.template segment<6>(6 * c);
      }
    };
    x.setZero(6 * n_);
    r_ = b;
    const Scalar bNorm = b.norm();
    if (!(bNorm > Scalar(0))) return std::isfinite(double(bNorm));
    precondition(r_, z_);
    p_ = z_;
    Scalar rz = r_.dot(z_);
    for (int it = 0; it < cgMaxIterations_; ++it) {
      apply(p_, q_);
      const Scalar pq = p_.dot(q_);
      if (!(pq > Scalar(0))) return false;
      const Scalar alpha = rz / pq;
      x.noalias() += alpha * p_;
      r_.noalias() -= alpha * q_;
      if (r_.norm() <= cgTolerance_ * bNorm) break;
      precondition(r_, z_);
      const Scalar rzNew = r_.dot(z_);
      p_ = z_ + (rzNew / rz) * p_;
      rz = rzNew;
    }
    return x.allFinite();
  }

  /// y = S·x from the stored blocks (S symmetric).
  void multiply(const std::vector<Block>& S, const VecX<Scalar>& x, VecX<Scalar>& y) const {
    y.setZero(6 * n_);
    for (std::size_t b = 0; b < keys_.size(); ++b) {
      const int ci = blockKeyRow(keys_[b]), cj = blockKeyCol(keys_[b]);
      y.template segment<6>(6 * ci).noalias() += S[b] * x.template segment<6>(6 * cj);
      if (ci != cj) y.template segment<6>(6 * cj).noalias() += S[b].transpose() * x.template segment<6>(6 * ci);
    }
  }

 private:
  using M6 = Eigen::Matrix<Scalar, 6, 6>;

  bool solveDense(const std::vector<Block>& S, const VecX<Scalar>& b, VecX<Scalar>& x) {
    dense_.setZero(6 * n_, 6 * n_);
    for (std::size_t k = 0; k < keys_.size(); ++k) {
      const int ci = blockKeyRow(keys_[k]), cj = blockKeyCol(keys_[k]);
      dense_.template block<6, 6>(6 * ci, 6 * cj) = S[k];
      if (ci != cj) dense_.template block<6, 6>(6 * cj, 6 * ci) = S[k].transpose();
    }
    // In place (the matrix is rebuilt for every solve): no second n×n copy (11 MB at 200 poses).
    const Eigen::LLT<Eigen::Ref<MatX<Scalar>>> llt(dense_);
    if (llt.info() != Eigen::Success) return false;
    x = llt.solve(b);
    return true;
  }

  bool solveSparse(const std::vector<Block>& S, const VecX<Scalar>& b, VecX<Scalar>& x) {
    triplets_.clear();
    for (std::size_t k = 0; k < keys_.size(); ++k) {
      const int ci = blockKeyRow(keys_[k]), cj = blockKeyCol(keys_[k]);
      // lower triangle: row block cj ≥ column block ci
      for (int c = 0; c < 6; ++c) {
        for (int r = (ci == cj ? c : 0); r < 6; ++r) triplets_.emplace_back(6 * cj + r, 6 * ci + c, S[k](c, r));
      }
    }
    sparse_.resize(6 * n_, 6 * n_);
    sparse_.setFromTriplets(triplets_.begin(), triplets_.end());
    if (!patternAnalysed_) {
      llt_.analyzePattern(sparse_);
      patternAnalysed_ = true;
    }
    llt_.factorize(sparse_);
    if (llt_.info() != Eigen::Success) return false;
    x = llt_.solve(b);
    return true;
  }

  bool solveCG(const std::vector<Block>& S, const VecX<Scalar>& b, VecX<Scalar>& x) {
    return conjugateGradients(
        [&](int c) -> const Block& { return S[static_cast<std::size_t>(diag_[static_cast<std::size_t>(c)])]; }, b, x,
        [&](const VecX<Scalar>& p, VecX<Scalar>& q) { multiply(S, p, q); });
  }

  ReducedSolverMethod method_;
  int n_;
  const std::vector<std::uint64_t>& keys_;
  const std::vector<int>& diag_;
  Scalar cgTolerance_;
  int cgMaxIterations_;
  MatX<Scalar> dense_;
  Eigen::SparseMatrix<Scalar> sparse_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<Scalar>, Eigen::Lower, Eigen::AMDOrdering<int>> llt_;
  bool patternAnalysed_ = false;
  std::vector<Eigen::Triplet<Scalar>> triplets_;
  std::vector<Block> blockInv_;
  VecX<Scalar> r_, z_, p_, q_;
};

}  // namespace hawor
