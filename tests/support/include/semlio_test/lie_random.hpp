#pragma once
// Deterministic random tangent vectors for the Lie group tests.
#include <Eigen/Core>

#include <cmath>
#include <random>

namespace semlio_test {

/// A fixed-seed generator of vectors, directions and angles.
class LieRandom {
 public:
  explicit LieRandom(unsigned seed = 20260421U) : gen_(seed) {}

  /// Uniform scalar in [lo, hi).
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(gen_); }

  /// Unit vector, uniform on the sphere.
  Eigen::Vector3d direction() {
    std::normal_distribution<double> n(0.0, 1.0);
    Eigen::Vector3d v;
    do {
      v = Eigen::Vector3d(n(gen_), n(gen_), n(gen_));
    } while (v.norm() < 1e-3);
    return v.normalized();
  }

  /// Rotation vector with angle uniform in [lo, hi) about a random axis.
  Eigen::Vector3d rotation_vector(double lo_rad, double hi_rad) { return uniform(lo_rad, hi_rad) * direction(); }

  /// Vector with components uniform in [-half, half).
  Eigen::Vector3d box(double half) { return {uniform(-half, half), uniform(-half, half), uniform(-half, half)}; }

  /// SE(3) tangent [rho; phi]: rho in a box of half-width rho_half, angle in [lo, hi).
  Eigen::Matrix<double, 6, 1> tangent(double rho_half, double lo_rad, double hi_rad) {
    Eigen::Matrix<double, 6, 1> xi;
    xi.head<3>() = box(rho_half);
    xi.tail<3>() = rotation_vector(lo_rad, hi_rad);
    return xi;
  }

 private:
  std::mt19937 gen_;
};

}  // namespace semlio_test
