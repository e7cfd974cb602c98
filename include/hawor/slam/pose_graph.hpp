// hawor/slam/pose_graph.hpp — a Sim(3) pose graph over keyframes, the loop closure of monocular
// SLAM that corrects scale drift as well as pose drift (Strasdat, Montiel & Davison 2010,
// "Scale drift-aware large scale monocular SLAM"; ORB-SLAM's essential graph).
//
// Nodes: S_i ∈ Sim(3), camera i's frame to the world (X_w = S_i·P_i; a tracked keyframe's
// T_w_c with scale 1). Edges: a measured relative similarity M_ij ≈ S_i⁻¹·S_j, with residual
//   r_ij = log(M_ij⁻¹ · S_i⁻¹ · S_j) ∈ ℝ⁷   ((ρ, φ, σ): translation, rotation, log-scale),
// weighted per component (w: the information, 1/σ², of each). Cost ½ Σ r_ijᵀ diag(w_ij) r_ij.
// Levenberg–Marquardt over right perturbations S_i ← S_i·exp(δ_i) of the free nodes; the
// Jacobians by central differences (the residual is a few group products); the normal equations
// sparse (one 7×7 block per node and per edge), solved by Eigen's SimplicialLDLT. Computed in
// double whatever Scalar is. Free nodes not connected to a fixed one are an error (the gauge).
// Pure function of its inputs.
#pragma once

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cmath>
#include <string>
#include <vector>

#include "hawor/common.hpp"
#include "hawor/geometry/sim3.hpp"

namespace hawor {

template <typename Scalar>
struct PoseGraphEdge {
  int i = 0, j = 0;
  Sim3<Scalar> M;  ///< measured S_i⁻¹·S_j
  Vec7<Scalar> weight = Vec7<Scalar>::Ones();  ///< information of (ρ, φ, σ), each ≥ 0
};

struct PoseGraphOptions {
  int maxIterations = 30;
  double relativeTolerance = 1e-10;  ///< stop when the cost falls by less than this fraction
};

struct PoseGraphResult {
  double initialCost = 0, finalCost = 0;
  int iterations = 0;
};

/// Optimises `nodes` in place (fixed[i] != 0: held; at least one). Throws hawor::Error for an edge
/// naming a node out of range, a negative or non-finite weight, no fixed node, or a free node
/// not connected to a fixed one.
template <typename Scalar>
PoseGraphResult optimisePoseGraph(std::vector<Sim3<Scalar>>& nodes, const std::vector<PoseGraphEdge<Scalar>>& edges,
                                  const std::vector<char>& fixed, const PoseGraphOptions& opt = {}) {
  using S3 = Sim3<double>;
  using V7 = Eigen::Matrix<double, 7, 1>;
  using M7 = Eigen::Matrix<double, 7, 7>;
  const int n = static_cast<int>(nodes.size());
  if (fixed.size() != nodes.size()) throw Error("optimisePoseGraph: one fixed flag per node");
  // the gauge: every free node reaches a fixed one
  std::vector<int> comp(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) comp[static_cast<std::size_t>(i)] = i;
  auto find = [&](int i) {
    while (comp[static_cast<std::size_t>(i)] != i) i = comp[static_cast<std::size_t>(i)] = comp[static_cast<std::size_t>(comp[static_cast<std::size_t>(i)])];
    return i;
  };
  for (const auto& e : edges) {
    if (e.i < 0 || e.j < 0 || e.i >= n || e.j >= n || e.i == e.j) throw Error("optimisePoseGraph: an edge names a node out of range (or itself)");
    for (int c = 0; c < 7; ++c) {
      if (!(e.weight(c) >= Scalar(0)) || !std::isfinite(double(e.weight(c)))) throw Error("optimisePoseGraph: weights must be finite and >= 0");
    }
    comp[static_cast<std::size_t>(find(e.i))] = find(e.j);
  }
  std::vector<char> anchored(static_cast<std::size_t>(n), 0);
  bool anyFixed = false;
  for (int i = 0; i < n; ++i) {
    if (fixed[static_cast<std::size_t>(i)]) anchored[static_cast<std::size_t>(find(i))] = 1, anyFixed = true;
  }
  if (!anyFixed) throw Error("optimisePoseGraph: no fixed node (the gauge)");
  for (int i = 0; i < n; ++i) {
    if (!anchored[static_cast<std::size_t>(find(i))]) throw Error("optimisePoseGraph: node " + std::to_string(i) + " is not connected to a fixed node");
  }
  std::vector<int> var(static_cast<std::size_t>(n), -1);
  int nv = 0;
  for (int i = 0; i < n; ++i) {
    if (!fixed[static_cast<std::size_t>(i)]) var[static_cast<std::size_t>(i)] = nv++;
  }
  std::vector<S3> X(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) X[static_cast<std::size_t>(i)] = nodes[static_cast<std::size_t>(i)].template cast<double>();
  std::vector<S3> Minv(edges.size());
  for (std::size_t k = 0; k < edges.size(); ++k) Minv[k] = edges[k].M.template cast<double>().inverse();
  auto residual = [&](std::size_t k, const S3& Si, const S3& Sj) -> V7 { return (Minv[k] * Si.inverse() * Sj).log(); };
  auto cost = [&](const std::vector<S3>& P) {
    double c = 0;
    for (std::size_t k = 0; k < edges.size(); ++k) {
      const V7 r = residual(k, P[static_cast<std::size_t>(edges[k].i)], P[static_cast<std::size_t>(edges[k].j)]);
      for (int a = 0; a < 7; ++a) c += 0.5 * double(edges[k].weight(a)) * r(a) * r(a);
    }
    return c;
  };
  PoseGraphResult res;
  res.initialCost = res.finalCost = cost(X);
  if (nv == 0 || edges.empty()) return res;
  const double h = 1e-6;
  double lambda = 1e-4;
  for (int it = 0; it < opt.maxIterations; ++it) {
    std::vector<Eigen::Triplet<double>> trip;
    Eigen::VectorXd b = Eigen::VectorXd::Zero(7 * nv);
    for (std::size_t k = 0; k < edges.size(); ++k) {
      const auto& e = edges[k];
      const S3& Si = X[static_cast<std::size_t>(e.i)];
      const S3& Sj = X[static_cast<std::size_t>(e.j)];
      const V7 r = residual(k, Si, Sj);
      M7 Ji, Jj;
      for (int a = 0; a < 7; ++a) {
        V7 d = V7::Zero();
        d(a) = h;
        Ji.col(a) = (residual(k, Si * S3::exp(d), Sj) - residual(k, Si * S3::exp(-d), Sj)) / (2 * h);
        Jj.col(a) = (residual(k, Si, Sj * S3::exp(d)) - residual(k, Si, Sj * S3::exp(-d))) / (2 * h);
      }
      const M7 W = e.weight.template cast<double>().asDiagonal();
      const int vi = var[static_cast<std::size_t>(e.i)], vj = var[static_cast<std::size_t>(e.j)];
      auto add = [&](int va, int vb, const M7& B) {
        for (int a = 0; a < 7; ++a)
          for (int c = 0; c < 7; ++c) {
            if (B(a, c) != 0.0) trip.emplace_back(7 * va + a, 7 * vb + c, B(a, c));
          }
      };
      if (vi >= 0) {
        add(vi, vi, Ji.transpose() * W * Ji);
        b.segment<7>(7 * vi) += Ji.transpose() * W * r;
      }
      if (vj >= 0) {
        add(vj, vj, Jj.transpose() * W * Jj);
        b.segment<7>(7 * vj) += Jj.transpose() * W * r;
      }
      if (vi >= 0 && vj >= 0) {
        add(vi, vj, Ji.transpose() * W * Jj);
        add(vj, vi, Jj.transpose() * W * Ji);
      }
    }
    Eigen::SparseMatrix<double> H(7 * nv, 7 * nv);
    H.setFromTriplets(trip.begin(), trip.end());
    const Eigen::VectorXd diag = H.diagonal();
    bool improved = false;
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      Eigen::SparseMatrix<double> A = H;
      for (int a = 0; a < 7 * nv; ++a) A.coeffRef(a, a) += lambda * std::max(diag(a), 1e-9);
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
      if (ldlt.info() != Eigen::Success) {
        lambda *= 10;
        continue;
      }
      const Eigen::VectorXd dx = ldlt.solve(-b);
      std::vector<S3> Y = X;
      for (int i = 0; i < n; ++i) {
        const int v = var[static_cast<std::size_t>(i)];
        if (v >= 0) Y[static_cast<std::size_t>(i)] = X[static_cast<std::size_t>(i)] * S3::exp(V7(dx.segment<7>(7 * v)));
      }
      const double c = cost(Y);
      if (std::isfinite(c) && c < res.finalCost) {
        const bool small = res.finalCost - c <= opt.relativeTolerance * res.finalCost;
        X.swap(Y);
        res.finalCost = c;
        lambda = std::max(lambda / 10, 1e-12);
        improved = true;
        if (small) it = opt.maxIterations;
      } else {
        lambda *= 10;
      }
    }
    res.iterations = std::min(it + 1, opt.maxIterations);
    if (!improved) break;
  }
  for (int i = 0; i < n; ++i) nodes[static_cast<std::size_t>(i)] = X[static_cast<std::size_t>(i)].template cast<Scalar>();
  return res;
}

}  // namespace hawor
