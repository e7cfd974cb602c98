// Explicit instantiation of every geometry class and function template for float and double,
// so that every member compiles (including ones no test calls).
#include <catch2/catch.hpp>

#include "hawor/geometry/geometry.hpp"

template class hawor::SO3<float>;
template class hawor::SO3<double>;
template class hawor::SE3<float>;
template class hawor::SE3<double>;
template class hawor::Sim3<float>;
template class hawor::Sim3<double>;
template struct hawor::SimilarityTransform<float>;
template struct hawor::SimilarityTransform<double>;
template struct hawor::PinholeCamera<float>;
template struct hawor::PinholeCamera<double>;
template struct hawor::detail::RotationCoefficients<float>;
template struct hawor::detail::RotationCoefficients<double>;
template struct hawor::detail::Sim3WCoefficients<float>;
template struct hawor::detail::Sim3WCoefficients<double>;

#define HAWOR_INSTANTIATE_FUNCTIONS(S)                                                         \
  template hawor::Mat3<S> hawor::hat(const Eigen::MatrixBase<hawor::Vec3<S>>&);                \
  template hawor::Vec3<S> hawor::vee(const Eigen::MatrixBase<hawor::Mat3<S>>&);                \
  template hawor::Mat3<S> hawor::axisAngleToMatrix(const Eigen::MatrixBase<hawor::Vec3<S>>&);  \
  template Eigen::Quaternion<S> hawor::axisAngleToQuaternion(                                  \
      const Eigen::MatrixBase<hawor::Vec3<S>>&);                                               \
  template hawor::Vec3<S> hawor::quaternionToAxisAngle(                                        \
      const Eigen::QuaternionBase<Eigen::Quaternion<S>>&);                                     \
  template Eigen::Quaternion<S> hawor::matrixToQuaternion(                                     \
      const Eigen::MatrixBase<hawor::Mat3<S>>&);                                               \
  template hawor::Mat3<S> hawor::quaternionToMatrix(                                           \
      const Eigen::QuaternionBase<Eigen::Quaternion<S>>&);                                     \
  template hawor::Vec3<S> hawor::matrixToAxisAngle(const Eigen::MatrixBase<hawor::Mat3<S>>&);  \
  template hawor::Vec6<S> hawor::matrixToRot6d(const Eigen::MatrixBase<hawor::Mat3<S>>&);      \
  template hawor::Mat3<S> hawor::rot6dToMatrix(const Eigen::MatrixBase<hawor::Vec6<S>>&);      \
  template hawor::Mat3<S> hawor::projectToSO3(const Eigen::MatrixBase<hawor::Mat3<S>>&);       \
  template hawor::Mat3<S> hawor::detail::sim3W(S, const hawor::Vec3<S>&);                      \
  template hawor::SimilarityTransform<S> hawor::umeyama(                                       \
      const hawor::Points3<S>&, const hawor::Points3<S>&, bool, const hawor::VecX<S>*);        \
  template hawor::SE3<S> hawor::alignSE3(const hawor::Points3<S>&, const hawor::Points3<S>&,   \
                                         const hawor::VecX<S>*);                               \
  template hawor::Sim3<S> hawor::alignSim3(const hawor::Points3<S>&, const hawor::Points3<S>&, \
                                           const hawor::VecX<S>*);                             \
  template hawor::SO3<S> hawor::interpolate(const hawor::SO3<S>&, const hawor::SO3<S>&, S);    \
  template hawor::SE3<S> hawor::interpolate(const hawor::SE3<S>&, const hawor::SE3<S>&, S);    \
  template hawor::Sim3<S> hawor::interpolate(const hawor::Sim3<S>&, const hawor::Sim3<S>&, S);

HAWOR_INSTANTIATE_FUNCTIONS(float)
HAWOR_INSTANTIATE_FUNCTIONS(double)

TEST_CASE("geometry templates instantiate for float and double", "[geometry]") {
  // The instantiations above are the test; this checks the aliases resolve to them.
  CHECK(hawor::SO3f().log().norm() == 0.0f);
  CHECK(hawor::Sim3d().scale() == 1.0);
}
