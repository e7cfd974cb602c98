// Explicit instantiation of the SLAM estimation core's class templates and main function
// templates for float and double, so that every member compiles (including ones no test calls).
#include <catch2/catch.hpp>

#include "hawor/slam/bundle_adjustment.hpp"
#include "hawor/slam/essential.hpp"
#include "hawor/slam/homography.hpp"
#include "hawor/slam/p3p.hpp"
#include "hawor/slam/pnp_ransac.hpp"
#include "hawor/slam/ransac.hpp"
#include "hawor/slam/triangulation.hpp"
#include "hawor/slam/two_view.hpp"

template struct hawor::RansacOptions<float>;
template struct hawor::RansacOptions<double>;
template struct hawor::TriangulationQuality<float>;
template struct hawor::TriangulationQuality<double>;
template struct hawor::BAObservation<float>;
template struct hawor::BAObservation<double>;
template struct hawor::BAScalePrior<float>;
template struct hawor::BAScalePrior<double>;
template struct hawor::BAProblem<float>;
template struct hawor::BAProblem<double>;
template struct hawor::BAOptions<float>;
template struct hawor::BAOptions<double>;
template struct hawor::BAReport<float>;
template struct hawor::BAReport<double>;
template struct hawor::PoseRefineOptions<float>;
template struct hawor::PoseRefineOptions<double>;
template struct hawor::PoseRefineReport<float>;
template struct hawor::PoseRefineReport<double>;
template struct hawor::PnPRansacOptions<float>;
template struct hawor::PnPRansacOptions<double>;
template struct hawor::PnPRansacResult<float>;
template struct hawor::PnPRansacResult<double>;
template struct hawor::TwoViewOptions<float>;
template struct hawor::TwoViewOptions<double>;
template struct hawor::TwoViewResult<float>;
template struct hawor::TwoViewResult<double>;

#define HAWOR_INSTANTIATE_SLAM_CORE(S)                                                          \
  template hawor::BAReport<S> hawor::bundleAdjust(hawor::BAProblem<S>&,                         \
                                                  const hawor::BAOptions<S>&);                  \
  template std::vector<S> hawor::baReprojectionErrors(const hawor::BAProblem<S>&, S);          \
  template hawor::PnPRansacResult<S> hawor::solvePnPRansac(                                     \
      const std::vector<hawor::Vec3<S>>&, const std::vector<hawor::Vec2<S>>&,                   \
      const hawor::PinholeCamera<S>&, const hawor::PnPRansacOptions<S>&);                       \
  template hawor::PoseRefineReport<S> hawor::refinePose(                                        \
      const std::vector<hawor::Vec3<S>>&, const std::vector<hawor::Vec2<S>>&,                   \
      const std::vector<S>*, const hawor::PinholeCamera<S>&, hawor::SE3<S>&,                    \
      const hawor::PoseRefineOptions<S>&);                                                      \
  template hawor::TwoViewResult<S> hawor::initializeTwoView(                                    \
      const std::vector<hawor::Vec2<S>>&, const std::vector<hawor::Vec2<S>>&,                   \
      const hawor::TwoViewOptions<S>&, const std::vector<std::vector<hawor::Vec2<S>>>*);        \
  template void hawor::essentialFivePoint(const hawor::Vec2<S>*, const hawor::Vec2<S>*,         \
                                          std::vector<hawor::Mat3<S>>&);                        \
  template void hawor::solveP3P(const hawor::Vec3<S>*, const hawor::Vec3<S>*,                   \
                                std::vector<hawor::SE3<S>>&);                                   \
  template bool hawor::homographyDLT(const std::vector<hawor::Vec2<S>>&,                        \
                                     const std::vector<hawor::Vec2<S>>&, const int*, int,       \
                                     hawor::Mat3<S>&);                                          \
  template int hawor::decomposeHomography(const hawor::Mat3<S>&, hawor::Mat3<S>*,               \
                                          hawor::Vec3<S>*, hawor::Vec3<S>*, double);            \
  template bool hawor::decomposeEssential(const hawor::Mat3<S>&, hawor::Mat3<S>*,               \
                                          hawor::Vec3<S>*);                                     \
  template bool hawor::triangulateDLT(const hawor::SE3<S>&, const hawor::SE3<S>&,               \
                                      const hawor::Vec2<S>&, const hawor::Vec2<S>&,             \
                                      hawor::Vec3<S>&);                                         \
  template bool hawor::triangulateMidpoint(const hawor::SE3<S>&, const hawor::SE3<S>&,          \
                                           const hawor::Vec2<S>&, const hawor::Vec2<S>&,        \
                                           hawor::Vec3<S>&);

HAWOR_INSTANTIATE_SLAM_CORE(float)
HAWOR_INSTANTIATE_SLAM_CORE(double)

TEST_CASE("slam estimation core templates instantiate for float and double", "[slam]") {
  SUCCEED();
}
