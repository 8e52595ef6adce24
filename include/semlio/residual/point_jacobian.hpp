#pragma once
/// \file
/// The Jacobian every point residual shares: how a scan point moved into the
/// map frame changes under the right perturbation of T_map_scan.

#include <Eigen/Core>

#include <semlio/lie/se3.hpp>
#include <semlio/lie/so3.hpp>

namespace semlio::detail {

/// d(T exp(xi) p) / d xi at xi = 0, xi = [rho; phi]: [R, -R hat(p_scan)] (3x6).
/// From T exp(xi) p ~= R (p + rho + phi x p) + t.
inline Eigen::Matrix<double, 3, 6> moved_point_jacobian(const Eigen::Matrix3d& R, const Eigen::Vector3d& p_scan) {
  Eigen::Matrix<double, 3, 6> J;
  J.leftCols<3>() = R;
  J.rightCols<3>() = -R * hat(p_scan);
  return J;
}

/// A unit vector orthogonal to unit u, chosen deterministically (u crossed
/// with the coordinate axis least aligned with it).
inline Eigen::Vector3d line_orthogonal_unit(const Eigen::Vector3d& u) {
  const Eigen::Vector3d a = u.cwiseAbs();
  const Eigen::Vector3d axis = (a.x() <= a.y() && a.x() <= a.z()) ? Eigen::Vector3d::UnitX()
                               : (a.y() <= a.z())                 ? Eigen::Vector3d::UnitY()
                                                                  : Eigen::Vector3d::UnitZ();
  return u.cross(axis).normalized();
}

}  // namespace semlio::detail
