#include <catch2/catch.hpp>

#include <semlio/lie/se3.hpp>

using semlio::SE3d;

TEST_CASE("SE3 right Jacobian matches central differences (smoke)", "[lie]") {
  SE3d::Vector6 xi;
  xi << 0.3, -0.2, 0.5, 0.4, -0.7, 0.9;
  const SE3d::Matrix6 J = SE3d::right_jacobian(xi);
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    SE3d::Vector6 d = SE3d::Vector6::Zero();
    d[k] = h;
    const SE3d::Vector6 col =
        ((SE3d::exp(xi).inverse() * SE3d::exp(xi + d)).log() - (SE3d::exp(xi).inverse() * SE3d::exp(xi - d)).log()) / (2 * h);
    CHECK((col - J.col(k)).norm() < 1e-7);
  }
  CHECK((SE3d::right_jacobian_inverse(xi) * J - SE3d::Matrix6::Identity()).norm() < 1e-10);
  CHECK((SE3d::exp(xi).log() - xi).norm() < 1e-12);
}
