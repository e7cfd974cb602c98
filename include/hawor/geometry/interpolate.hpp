// hawor/geometry/interpolate.hpp — geodesic interpolation on SO(3), SE(3) and Sim(3)
// (after Sophus' interpolate.hpp).
//
// interpolate(a, b, t) = a·exp(t·log(a⁻¹·b)): t = 0 gives a, t = 1 gives b (up to rounding),
// t outside [0, 1] extrapolates along the same geodesic. For SO(3) this is SLERP on the short
// arc (log returns an angle in [0, π]); it stays exact near identical rotations because exp/log
// use Taylor branches there. For SE(3) the path is the screw motion (not LERP of translation:
// the motion module's pre-fill does its own SLERP + LERP, docs/design.md §7).
#pragma once

#include <type_traits>

#include "hawor/geometry/se3.hpp"
#include "hawor/geometry/sim3.hpp"
#include "hawor/geometry/so3.hpp"

namespace hawor {
namespace detail {
template <typename T>
struct NonDeduced {
  using type = T;
};
/// Group-generic a·exp(t·log(a⁻¹b)); exact endpoints are returned as copies.
template <typename Group>
Group geodesic(const Group& a, const Group& b, typename Group::Scalar t) {
  using S = typename Group::Scalar;
  if (t == S(0)) return a;
  if (t == S(1)) return b;
  const typename Group::Tangent d = (a.inverse() * b).log();
  return a * Group::exp(typename Group::Tangent(t * d));
}
}  // namespace detail

/// a·exp(t·log(a⁻¹b)) on SO(3) (SLERP, short arc).
template <typename Scalar>
SO3<Scalar> interpolate(const SO3<Scalar>& a, const SO3<Scalar>& b,
                        typename detail::NonDeduced<Scalar>::type t) {
  return detail::geodesic(a, b, t);
}

/// a·exp(t·log(a⁻¹b)) on SE(3) (constant-twist screw motion).
template <typename Scalar>
SE3<Scalar> interpolate(const SE3<Scalar>& a, const SE3<Scalar>& b,
                        typename detail::NonDeduced<Scalar>::type t) {
  return detail::geodesic(a, b, t);
}

/// a·exp(t·log(a⁻¹b)) on Sim(3) (log-scale interpolates linearly).
template <typename Scalar>
Sim3<Scalar> interpolate(const Sim3<Scalar>& a, const Sim3<Scalar>& b,
                         typename detail::NonDeduced<Scalar>::type t) {
  return detail::geodesic(a, b, t);
}

}  // namespace hawor
