// The reduced camera system's solvers (ba_reduced_solver.hpp): on a random symmetric positive
// definite block matrix with a sparse block pattern, the dense, sparse and iterative solutions
// agree with a full-pivoting LU of the assembled matrix, and so do conjugate gradients given only
// S's product; multiply() with the assembled product;
// a matrix that is not positive definite is refused by each.
#include <catch2/catch.hpp>

#include <Eigen/LU>
#include <algorithm>
#include <random>
#include <type_traits>
#include <vector>

#include "hawor/slam/ba_reduced_solver.hpp"

namespace {

template <typename Scalar>
struct BlockSystem {
  int n = 0;
  std::vector<std::uint64_t> keys;
  std::vector<int> diag;
  std::vector<typename hawor::ReducedCameraSolver<Scalar>::Block> S;
  hawor::MatX<double> full;  // the same matrix, assembled, in double
};

// A = BᵀB + shift·I from a random block-sparse B (so A has a block pattern of its own), stored as
// its upper blocks.
template <typename Scalar>
BlockSystem<Scalar> randomSystem(int n, double shift, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  hawor::MatX<double> B = hawor::MatX<double>::Zero(6 * n, 6 * n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      if (i != j && u(rng) > 0.25) continue;  // about a quarter of the blocks
      for (int r = 0; r < 6; ++r) {
        for (int c = 0; c < 6; ++c) B(6 * i + r, 6 * j + c) = g(rng);
      }
    }
  }
  BlockSystem<Scalar> s;
  s.n = n;
  s.full = B.transpose() * B + shift * hawor::MatX<double>::Identity(6 * n, 6 * n);
  for (int i = 0; i < n; ++i) {
    for (int j = i; j < n; ++j) {
      if (i != j && s.full.template block<6, 6>(6 * i, 6 * j).cwiseAbs().maxCoeff() == 0.0) continue;
      s.keys.push_back(hawor::blockKey(i, j));
      s.S.push_back(s.full.template block<6, 6>(6 * i, 6 * j).template cast<Scalar>());
    }
  }
  for (int i = 0; i < n; ++i) {
    s.diag.push_back(static_cast<int>(std::lower_bound(s.keys.begin(), s.keys.end(), hawor::blockKey(i, i)) - s.keys.begin()));
  }
  // the stored blocks, in Scalar, are the matrix: reassemble it from them (float rounding)
  for (std::size_t k = 0; k < s.keys.size(); ++k) {
    const int i = hawor::blockKeyRow(s.keys[k]), j = hawor::blockKeyCol(s.keys[k]);
    s.full.template block<6, 6>(6 * i, 6 * j) = s.S[k].template cast<double>();
    s.full.template block<6, 6>(6 * j, 6 * i) = s.S[k].template cast<double>().transpose();
  }
  return s;
}

}  // namespace

TEMPLATE_TEST_CASE("ReducedCameraSolver: dense, sparse and iterative agree with a full LU", "[slam][ba]", float, double) {
  using S = TestType;
  const double tol = std::is_same<S, float>::value ? 2e-3 : 1e-8;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    BlockSystem<S> sys = randomSystem<S>(12, 2.0, seed);
    CHECK(sys.keys.size() < static_cast<std::size_t>(12 * 13 / 2));  // sparse pattern
    std::mt19937 rng(seed + 100);
    std::normal_distribution<double> g(0.0, 1.0);
    hawor::VecX<double> bd(6 * sys.n);
    for (int i = 0; i < bd.size(); ++i) bd(i) = g(rng);
    const hawor::VecX<double> ref = sys.full.fullPivLu().solve(bd);
    const hawor::VecX<S> b = bd.cast<S>();
    // y = S·x from the blocks equals the assembled product
    hawor::ReducedCameraSolver<S> dense(hawor::ReducedSolverMethod::Dense, sys.n, sys.keys, sys.diag);
    hawor::VecX<S> y;
    dense.multiply(sys.S, b, y);
    CHECK((y.template cast<double>() - sys.full * bd).norm() <= tol * 10 * (sys.full * bd).norm());
    for (const auto method : {hawor::ReducedSolverMethod::Dense, hawor::ReducedSolverMethod::Sparse,
                              hawor::ReducedSolverMethod::Iterative}) {
      hawor::ReducedCameraSolver<S> solver(method, sys.n, sys.keys, sys.diag, S(1e-10), 2000);
      hawor::VecX<S> x;
      REQUIRE(solver.solve(sys.S, b, x));
      CHECK((x.template cast<double>() - ref).norm() <= tol * ref.norm());
      // a second solve with the same pattern (the sparse one analysed once) gives the same
      hawor::VecX<S> x2;
      REQUIRE(solver.solve(sys.S, b, x2));
      CHECK((x2 - x).norm() <= S(tol) * x.norm());
    }
    // S known only by its product and diagonal blocks (the implicit Schur complement's use)
    hawor::ReducedCameraSolver<S> implicit(hawor::ReducedSolverMethod::ImplicitSchur, sys.n, sys.keys, sys.diag, S(1e-10), 2000);
    hawor::VecX<S> xi;
    REQUIRE(implicit.conjugateGradients([&](int c) -> const typename hawor::ReducedCameraSolver<S>::Block& {
                                          return sys.S[static_cast<std::size_t>(sys.diag[static_cast<std::size_t>(c)])];
                                        },
                                        b, xi, [&](const hawor::VecX<S>& p, hawor::VecX<S>& q) { dense.multiply(sys.S, p, q); }));
    CHECK((xi.template cast<double>() - ref).norm() <= tol * ref.norm());
    CHECK_THROWS(implicit.solve(sys.S, b, xi));  // no product given
  }
}

TEMPLATE_TEST_CASE("ReducedCameraSolver: a matrix that is not positive definite is refused", "[slam][ba]", float, double) {
  using S = TestType;
  BlockSystem<S> sys = randomSystem<S>(6, 1.0, 7);
  for (std::size_t k = 0; k < sys.S.size(); ++k) sys.S[k] = -sys.S[k];  // negative definite
  const hawor::VecX<S> b = hawor::VecX<S>::Ones(6 * sys.n);
  for (const auto method : {hawor::ReducedSolverMethod::Dense, hawor::ReducedSolverMethod::Sparse,
                            hawor::ReducedSolverMethod::Iterative}) {
    hawor::ReducedCameraSolver<S> solver(method, sys.n, sys.keys, sys.diag);
    hawor::VecX<S> x;
    CHECK_FALSE(solver.solve(sys.S, b, x));
  }
}
