// hawor/geometry/robust_loss.hpp — robust losses ρ(s) of a squared, scale-normalised residual,
// for iteratively reweighted least squares (IRLS).
//
// With s = ‖e‖²/σ² (e a residual block, σ its noise scale) and k the loss scale in units of σ:
//   None:    ρ(s) = s                                   ρ'(s) = 1
//   Huber:   ρ(s) = s (s ≤ k²),  2k√s − k² (s > k²)     ρ'(s) = min(1, k/√s)
//   Cauchy:  ρ(s) = k² ln(1 + s/k²)                     ρ'(s) = 1/(1 + s/k²)
// Each loss equals s for small s, so k = ∞ gives back least squares. In IRLS a residual block and
// its Jacobian are scaled by √ρ'(s) (the Gauss–Newton step of Σρ without the second-order
// correction of Triggs et al.), and Σρ(s) is the cost a step must decrease.
// Pure functions, thread-safe.
#pragma once

#include <cmath>

#include "hawor/common.hpp"

namespace hawor {

enum class RobustLoss { None, Huber, Cauchy };

/// ρ(s) for the squared normalised residual s ≥ 0 and scale k > 0 (see the file comment).
template <typename Scalar>
Scalar robustCost(RobustLoss loss, Scalar s, Scalar k) {
  using std::log;
  using std::sqrt;
  switch (loss) {
    case RobustLoss::Huber:
      return s <= k * k ? s : Scalar(2) * k * sqrt(s) - k * k;
    case RobustLoss::Cauchy:
      return k * k * log(Scalar(1) + s / (k * k));
    case RobustLoss::None:
    default:
      return s;
  }
}

/// ρ'(s), the IRLS weight of a residual block (see the file comment).
template <typename Scalar>
Scalar robustWeight(RobustLoss loss, Scalar s, Scalar k) {
  using std::sqrt;
  switch (loss) {
    case RobustLoss::Huber:
      return s <= k * k ? Scalar(1) : k / sqrt(s);
    case RobustLoss::Cauchy:
      return Scalar(1) / (Scalar(1) + s / (k * k));
    case RobustLoss::None:
    default:
      return Scalar(1);
  }
}

}  // namespace hawor
