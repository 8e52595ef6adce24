#pragma once
/// \file
/// The preintegrated IMU factor (Forster et al. TRO 2017, eq. 45) and the
/// bias random-walk factor between two navigation states, with analytic
/// Jacobians in semlio's 15-dimensional navigation tangent.
///
/// Navigation tangent (one convention for the inertial graph, stated once):
///   xi = [rho (0..2); phi (3..5); dv (6..8); dbg (9..11); dba (12..14)]
/// - pose: right perturbation T_world_imu (+) [rho; phi] = T * SE3d::exp([rho; phi])
///   (translation first, as everywhere in semlio); to first order
///   R <- R Exp(phi), p <- p + R rho;
/// - velocity (world frame) and both biases: plain addition.
/// The IMU residual keeps the preintegration's order (phi, v, p) so that its
/// covariance() is the factor's covariance unchanged.

#include <Eigen/Core>

#include <semlio/imu/nav_state.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/lie/so3.hpp>

namespace semlio {

/// 15-vector in the navigation tangent [rho; phi; v; b_g; b_a].
using Vector15d = Eigen::Matrix<double, 15, 1>;
/// 15x15 matrix in the navigation tangent.
using Matrix15d = Eigen::Matrix<double, 15, 15>;
/// Jacobian of the 9-dim IMU residual (phi, v, p) w.r.t. one navigation tangent.
using Matrix9x15d = Eigen::Matrix<double, 9, 15>;
/// Jacobian of the 6-dim bias residual w.r.t. one navigation tangent.
using Matrix6x15d = Eigen::Matrix<double, 6, 15>;

/// Applies a navigation-tangent increment (see the file comment) in place.
inline void retract(NavState& x, ImuBias& b, const Vector15d& dx) {
  const SE3d T = x.pose() * SE3d::exp(dx.head<6>());
  x.R_world_imu = T.so3();
  x.p_world_m = T.translation();
  x.v_world_mps += dx.segment<3>(6);
  b.gyro_radps += dx.segment<3>(9);
  b.accel_mps2 += dx.segment<3>(12);
}

/// Difference x (-) x_ref in the navigation tangent: [log(T_ref^-1 T); v - v_ref;
/// b - b_ref], and (optionally) its Jacobian w.r.t. an increment of x.
inline Vector15d nav_difference(const NavState& x, const ImuBias& b, const NavState& x_ref, const ImuBias& b_ref,
                                Matrix15d* J_d_xi = nullptr) {
  Vector15d d;
  d.head<6>() = (x_ref.pose().inverse() * x.pose()).log();
  d.segment<3>(6) = x.v_world_mps - x_ref.v_world_mps;
  d.segment<3>(9) = b.gyro_radps - b_ref.gyro_radps;
  d.segment<3>(12) = b.accel_mps2 - b_ref.accel_mps2;
  if (J_d_xi != nullptr) {
    J_d_xi->setIdentity();
    J_d_xi->topLeftCorner<6, 6>() = SE3d::right_jacobian_inverse(d.head<6>());
  }
  return d;
}

/// Preintegrated IMU residual (eq. 45, order (phi, v, p)) between state i
/// (with its bias b_i, the bias held over the window) and state j, plus its
/// analytic Jacobians w.r.t. the navigation tangents of i (pose, velocity,
/// bias) and j (pose, velocity; its bias columns are zero). Thread-safe.
inline Vector9d imu_factor_error(const ImuPreintegration& pim, const NavState& xi, const ImuBias& bi,
                                 const NavState& xj, Matrix9x15d* J_r_i = nullptr, Matrix9x15d* J_r_j = nullptr) {
  const Vector9d r = pim.residual(xi, xj, bi);
  if (J_r_i == nullptr && J_r_j == nullptr) return r;
  const double dt = pim.delta_t_s();
  const Eigen::Vector3d& g = pim.config().gravity_world_mps2;
  const Eigen::Matrix3d Ri = xi.R_world_imu.matrix();
  const Eigen::Matrix3d Rj = xj.R_world_imu.matrix();
  const Eigen::Matrix3d Rit = Ri.transpose();
  const Eigen::Vector3d rR = r.head<3>();
  const Eigen::Matrix3d Jr_inv = SO3d::right_jacobian_inverse(rR);
  const PreintegrationJacobians& J = pim.jacobians();
  const Eigen::Vector3d dbg = bi.gyro_radps - pim.bias().gyro_radps;
  const Eigen::Vector3d v_term = Rit * (xj.v_world_mps - xi.v_world_mps - g * dt);
  const Eigen::Vector3d p_term =
      Rit * (xj.p_world_m - xi.p_world_m - xi.v_world_mps * dt - 0.5 * dt * dt * g);
  if (J_r_i != nullptr) {
    Matrix9x15d& A = *J_r_i;
    A.setZero();
    // rotation row: r_R = Log(dR(b)^T R_i^T R_j)
    A.block<3, 3>(0, 3) = -Jr_inv * (Rj.transpose() * Ri);
    A.block<3, 3>(0, 9) =
        -Jr_inv * SO3d::exp(rR).matrix().transpose() * SO3d::right_jacobian(J.J_dR_bg * dbg) * J.J_dR_bg;
    // velocity row
    A.block<3, 3>(3, 3) = hat(v_term);
    A.block<3, 3>(3, 6) = -Rit;
    A.block<3, 3>(3, 9) = -J.J_dv_bg;
    A.block<3, 3>(3, 12) = -J.J_dv_ba;
    // position row: p_i + R_i rho moves the position by R_i rho
    A.block<3, 3>(6, 0) = -Eigen::Matrix3d::Identity();
    A.block<3, 3>(6, 3) = hat(p_term);
    A.block<3, 3>(6, 6) = -Rit * dt;
    A.block<3, 3>(6, 9) = -J.J_dp_bg;
    A.block<3, 3>(6, 12) = -J.J_dp_ba;
  }
  if (J_r_j != nullptr) {
    Matrix9x15d& B = *J_r_j;
    B.setZero();
    B.block<3, 3>(0, 3) = Jr_inv;
    B.block<3, 3>(3, 6) = Rit;
    B.block<3, 3>(6, 0) = Rit * Rj;
  }
  return r;
}

/// Bias random-walk residual b_j - b_i (order (b_g, b_a)); its covariance is
/// ImuPreintegration::bias_walk_covariance(). Jacobians: -I / +I on the bias
/// columns of i / j.
inline Eigen::Matrix<double, 6, 1> bias_walk_error(const ImuBias& bi, const ImuBias& bj, Matrix6x15d* J_r_i = nullptr,
                                                   Matrix6x15d* J_r_j = nullptr) {
  Eigen::Matrix<double, 6, 1> r;
  r.head<3>() = bj.gyro_radps - bi.gyro_radps;
  r.tail<3>() = bj.accel_mps2 - bi.accel_mps2;
  if (J_r_i != nullptr) {
    J_r_i->setZero();
    J_r_i->rightCols<6>() = -Eigen::Matrix<double, 6, 6>::Identity();
  }
  if (J_r_j != nullptr) {
    J_r_j->setZero();
    J_r_j->rightCols<6>() = Eigen::Matrix<double, 6, 6>::Identity();
  }
  return r;
}

}  // namespace semlio
