#pragma once
/// \file
/// The 6x6 normal equations of a pose problem, accumulated residual by
/// residual. Lives below the policy layer: it knows residual vectors and
/// Jacobians, not the Residual policies that produce them.

#include <Eigen/Core>

#include <cstddef>

namespace semlio {

/// Accumulated Gauss-Newton system H dx = -b for a right perturbation of a
/// pose: H = sum w J^T J, b = sum w J^T r, cost = sum w r^T r.
struct NormalEquations {
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
  double cost = 0.0;                ///< sum of weighted squared residuals (no 1/2)
  std::size_t num_residuals = 0;    ///< residual blocks added

  /// Clears the system for a new linearisation.
  void reset() noexcept {
    H.setZero();
    b.setZero();
    cost = 0.0;
    num_residuals = 0;
  }

  /// Adds one residual block r (D x 1) with Jacobian J (D x 6) and an IRLS
  /// weight w on its squared cost.
  template <int D>
  void add(const Eigen::Matrix<double, D, 1>& r, const Eigen::Matrix<double, D, 6>& J,
           double w = 1.0) noexcept {
    H.noalias() += w * J.transpose() * J;
    b.noalias() += w * J.transpose() * r;
    cost += w * r.squaredNorm();
    ++num_residuals;
  }

  /// Adds another system (e.g. a per-thread partial sum, or a prior term).
  NormalEquations& operator+=(const NormalEquations& other) noexcept {
    H += other.H;
    b += other.b;
    cost += other.cost;
    num_residuals += other.num_residuals;
    return *this;
  }
};

}  // namespace semlio
