// Helpers shared by the motion reference tests: RefArray -> Eigen.
#pragma once

#include "../support/ref_data.hpp"
#include "hawor/motion/motion.hpp"

namespace hawor_test {

inline hawor::Sequence<double> toSeq(const RefArray& a) {
  const long rows = a.shape.empty() ? 1 : a.shape[0];
  const long cols = rows ? a.size() / rows : 0;
  hawor::Sequence<double> m(rows, cols);
  for (long i = 0; i < a.size(); ++i) m.data()[i] = a[i];
  return m;
}

inline hawor::ValidMask toMask(const RefArray& a) {
  hawor::ValidMask v(static_cast<size_t>(a.size()));
  for (long i = 0; i < a.size(); ++i) v[static_cast<size_t>(i)] = a[i] != 0.0 ? 1 : 0;
  return v;
}

inline hawor::Mat3<double> matAt(const RefArray& a, long i) {
  hawor::Mat3<double> m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = a[9 * i + 3 * r + c];
  return m;
}

inline hawor::Vec3<double> vecAt(const RefArray& a, long i) {
  return hawor::Vec3<double>(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
}

}  // namespace hawor_test
