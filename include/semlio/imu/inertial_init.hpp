#pragma once
/// \file
/// Inertial initialisation while moving (METHOD.md, "Initialisation while
/// moving"): gravity direction, gyroscope bias and the IMU velocity at every
/// frame from the first seconds of lidar odometry poses and IMU samples,
/// without requiring the vehicle to stand still. Lidar poses are metric, so
/// unlike visual-inertial initialisation there is no scale to recover.
///
/// Steps (VINS-Mono-style alignment, adapted to metric poses):
/// 1. Gyro bias: minimise sum_k |Log(dR_k(b_g)^T R_k^T R_k+1)|^2 over the
///    consecutive frame pairs (IMU orientations from the lidar poses and the
///    extrinsic), Gauss-Newton with the preintegration's bias Jacobian,
///    re-preintegrating after each step.
/// 2. Velocities and gravity: with the gyro bias fixed, every pair gives
///    (Forster eq. 33, world = the lidar map frame)
///        v_i dt + g dt^2 / 2 (+ R_i J_p,ba b_a) = p_j - p_i - R_i dp
///        v_j - v_i - g dt   (- R_i J_v,ba b_a) = R_i dv,
///    linear in (v_0..v_K, g[, b_a]); solved by weighted least squares
///    (position rows 1 / position_sigma_m, velocity rows 1 / velocity_sigma_mps).
/// 3. Gravity refinement: |g| is known; g = |g| normalise(g_hat + B w) with a
///    2-D tangent w (B spans the plane orthogonal to g_hat), the system
///    re-solved for (v, w[, b_a]) a few times.
///
/// Statuses (data-dependent, never exceptions, never NaN):
/// - kTooFewFrames: fewer than min_frames poses or a span below min_duration_s;
/// - kImuError: the IMU does not cover the frames, goes backwards or has gaps
///   (message from find_imu_range);
/// - kNotExciting: the least-squares system is rank-deficient; with
///   estimate_accel_bias also when the orientation changed by less than
///   min_rotation_rad over the window (the accelerometer bias is then
///   indistinguishable from a gravity tilt). Without accel-bias estimation
///   gravity and velocities are observable from any motion, standstill included
///   (an accelerometer bias b then tilts gravity by about |b| / 9.8 rad);
/// - kInconsistent: the unconstrained |g| differs from the configured one by
///   more than max_gravity_error_mps2 (wrong extrinsic, time offset or scale),
///   the rotation residual after the gyro-bias fit exceeds max_rotation_rms_rad,
///   or the position residual of the final fit exceeds max_position_rms_m.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/imu/imu_sample.hpp>
#include <semlio/imu/nav_state.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/lie/so3.hpp>

namespace semlio {

/// Settings of initialize_inertial().
struct InertialInitConfig {
  std::size_t min_frames = 10;             ///< lidar poses needed (>= 3): 1 s at 10 Hz (scripts/kitti_raw_drive.sh: the real drive initialises by frame 10)
  double min_duration_s = 0.9;             ///< time span they must cover [s]
  double position_sigma_m = 0.05;          ///< lidar position noise (weights the position rows) [m]
  double velocity_sigma_mps = 0.01;        ///< IMU delta-velocity noise (weights the velocity rows) [m/s]
  bool estimate_accel_bias = false;        ///< also solve for the accelerometer bias (needs rotation)
  double min_rotation_rad = 0.35;          ///< orientation change needed to estimate the accel bias (20 deg)
  double max_gravity_error_mps2 = 0.5;     ///< allowed | |g_free| - |g| | before kInconsistent
  double max_rotation_rms_rad = 0.01;      ///< allowed RMS rotation residual after the gyro fit
  double max_position_rms_m = 0.1;         ///< allowed RMS position residual of the final fit
  int gyro_iterations = 3;                 ///< Gauss-Newton steps of step 1
  int refine_iterations = 4;               ///< steps of the |g|-constrained refinement
  double min_pivot_ratio = 1e-12;          ///< LDL^T pivot ratio below which the system is rank-deficient
};

/// Outcome of initialize_inertial().
enum class InertialInitStatus {
  kOk,             ///< gravity, gyro bias and velocities estimated
  kTooFewFrames,   ///< not enough poses or too short a span
  kImuError,       ///< IMU does not cover the frames / goes backwards / has gaps
  kNotExciting,    ///< the motion does not determine the unknowns
  kInconsistent,   ///< the data disagree (|g| or rotations): extrinsic, time offset or scale wrong
};

/// Name of a status.
constexpr const char* to_string(InertialInitStatus s) noexcept {
  switch (s) {
    case InertialInitStatus::kOk: return "ok";
    case InertialInitStatus::kTooFewFrames: return "too_few_frames";
    case InertialInitStatus::kImuError: return "imu_error";
    case InertialInitStatus::kNotExciting: return "not_exciting";
    case InertialInitStatus::kInconsistent: return "inconsistent";
  }
  return "unknown";
}

/// Result of initialize_inertial(). On a failure status the estimates hold
/// whatever was reached (finite; zero when nothing was) and must not be used.
struct InertialInitResult {
  InertialInitStatus status = InertialInitStatus::kTooFewFrames;  ///< outcome
  std::string message;                                            ///< why, on failure
  Eigen::Vector3d gravity_map_mps2 = Eigen::Vector3d::Zero();     ///< gravity in the lidar map frame
  ImuBias bias;                                                   ///< gyro bias (+ accel bias when estimated)
  std::vector<Eigen::Vector3d> velocities_map_mps;                ///< IMU velocity at each frame (map frame)
  std::vector<NavState> states;                                   ///< IMU navigation state at each frame (map frame)
  double gravity_free_norm_mps2 = 0.0;                            ///< |g| before the magnitude constraint
  double rotation_rms_rad = 0.0;                                  ///< RMS rotation residual after the gyro fit
  double rotation_span_rad = 0.0;                                 ///< largest orientation change from the first frame
  double position_rms_m = 0.0;                                    ///< RMS position residual of the final fit
  /// True on success.
  [[nodiscard]] bool ok() const noexcept { return status == InertialInitStatus::kOk; }
};

namespace detail {

// Orthonormal basis (3x2) of the plane orthogonal to unit vector n.
inline Eigen::Matrix<double, 3, 2> tangent_basis(const Eigen::Vector3d& n) {
  const Eigen::Vector3d a = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d b1 = n.cross(a).normalized();
  Eigen::Matrix<double, 3, 2> B;
  B.col(0) = b1;
  B.col(1) = n.cross(b1);
  return B;
}

// Solves the normal equations; false when rank-deficient.
inline bool solve_normal(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, double pivot_ratio, Eigen::VectorXd& x) {
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(H);
  if (ldlt.info() != Eigen::Success) return false;
  const Eigen::VectorXd d = ldlt.vectorD().cwiseAbs();
  if (!d.allFinite() || d.size() == 0 || d.minCoeff() <= pivot_ratio * d.maxCoeff()) return false;
  x = ldlt.solve(b);
  return x.allFinite();
}

}  // namespace detail

/// Estimates gravity (map frame), gyro bias and IMU velocities from lidar
/// poses T_map_lidar[k] at lidar stamps stamps_s[k] (increasing) and IMU
/// samples (IMU clock: t_imu = t_lidar + imu_time_offset_s). T_imu_lidar maps
/// lidar points into the IMU frame (KITTI Tr_imu_velo). The gravity magnitude
/// is |imu.gravity_world_mps2|. Throws ValueError when the two spans differ
/// in length (misuse); data problems are statuses (see the file comment).
inline InertialInitResult initialize_inertial(std::span<const double> stamps_s, std::span<const SE3d> T_map_lidar,
                                              std::span<const ImuSample> samples, const SE3d& T_imu_lidar,
                                              double imu_time_offset_s, const PreintegrationConfig& imu,
                                              const InertialInitConfig& config = {}) {
  if (stamps_s.size() != T_map_lidar.size()) {
    throw ValueError("initialize_inertial: " + std::to_string(stamps_s.size()) + " stamps but " +
                     std::to_string(T_map_lidar.size()) + " poses");
  }
  InertialInitResult out;
  const std::size_t n = T_map_lidar.size();
  const double G = imu.gravity_world_mps2.norm();
  if (n < std::max<std::size_t>(3, config.min_frames) ||
      !(stamps_s[n - 1] - stamps_s[0] >= config.min_duration_s)) {
    out.message = "initialize_inertial: " + std::to_string(n) + " frames over " +
                  std::to_string(n > 0 ? stamps_s[n - 1] - stamps_s[0] : 0.0) + " s; need " +
                  std::to_string(std::max<std::size_t>(3, config.min_frames)) + " frames over " +
                  std::to_string(config.min_duration_s) + " s";
    return out;
  }
  for (std::size_t k = 1; k < n; ++k) {
    if (!(stamps_s[k] > stamps_s[k - 1])) {
      out.status = InertialInitStatus::kTooFewFrames;
      out.message = "initialize_inertial: frame stamps not increasing at frame " + std::to_string(k);
      return out;
    }
  }
  // IMU poses in the map frame.
  const SE3d T_lidar_imu = T_imu_lidar.inverse();
  std::vector<SE3d> T(n);
  for (std::size_t k = 0; k < n; ++k) T[k] = T_map_lidar[k] * T_lidar_imu;
  for (std::size_t k = 1; k < n; ++k) {
    out.rotation_span_rad = std::max(out.rotation_span_rad, (T[0].so3().inverse() * T[k].so3()).angle());
  }

  std::vector<ImuPreintegration> pims(n - 1, ImuPreintegration(imu));
  ImuBias bias;
  const auto integrate_all = [&]() -> bool {
    try {
      for (std::size_t k = 0; k + 1 < n; ++k) {
        pims[k].integrate(samples, stamps_s[k] + imu_time_offset_s, stamps_s[k + 1] + imu_time_offset_s, bias);
      }
    } catch (const ValueError& e) {
      out.status = InertialInitStatus::kImuError;
      out.message = e.what();
      return false;
    }
    return true;
  };

  // 1. Gyro bias from the rotations.
  for (int it = 0; it < std::max(1, config.gyro_iterations); ++it) {
    if (!integrate_all()) return out;
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    double sq = 0.0;
    for (std::size_t k = 0; k + 1 < n; ++k) {
      const Eigen::Vector3d r =
          (pims[k].delta_R().inverse() * (T[k].so3().inverse() * T[k + 1].so3())).log();
      const Eigen::Matrix3d J = -SO3d::right_jacobian_inverse(r) * pims[k].jacobians().J_dR_bg;
      H += J.transpose() * J;
      b -= J.transpose() * r;
      sq += r.squaredNorm();
    }
    out.rotation_rms_rad = std::sqrt(sq / static_cast<double>(n - 1));
    Eigen::VectorXd dx;
    if (!detail::solve_normal(H, b, config.min_pivot_ratio, dx)) {
      out.status = InertialInitStatus::kNotExciting;
      out.message = "initialize_inertial: the gyro-bias system is rank-deficient";
      return out;
    }
    bias.gyro_radps += dx;
  }
  if (!integrate_all()) return out;
  {
    double sq = 0.0;
    for (std::size_t k = 0; k + 1 < n; ++k) {
      sq += (pims[k].delta_R().inverse() * (T[k].so3().inverse() * T[k + 1].so3())).log().squaredNorm();
    }
    out.rotation_rms_rad = std::sqrt(sq / static_cast<double>(n - 1));
  }
  out.bias = bias;
  if (!(out.rotation_rms_rad <= config.max_rotation_rms_rad)) {
    out.status = InertialInitStatus::kInconsistent;
    out.message = "initialize_inertial: lidar and gyro rotations disagree (RMS " +
                  std::to_string(out.rotation_rms_rad) + " rad after the gyro-bias fit)";
    return out;
  }
  if (config.estimate_accel_bias && out.rotation_span_rad < config.min_rotation_rad) {
    out.status = InertialInitStatus::kNotExciting;
    out.message = "initialize_inertial: orientation changed by only " + std::to_string(out.rotation_span_rad) +
                  " rad (< min_rotation_rad " + std::to_string(config.min_rotation_rad) +
                  "): the accelerometer bias is not observable";
    return out;
  }

  // 2./3. Velocities, gravity (free, then |g|-constrained), accel bias.
  const bool with_ba = config.estimate_accel_bias;
  const Eigen::Index nv = static_cast<Eigen::Index>(3 * n);
  const double wp = 1.0 / config.position_sigma_m;
  const double wv = 1.0 / config.velocity_sigma_mps;
  // Unknowns: v (3n), gravity part (3 free / 2 tangent), b_a (3, optional).
  const auto solve = [&](bool constrained, const Eigen::Vector3d& g_hat, Eigen::VectorXd& x) -> bool {
    const Eigen::Index ng = constrained ? 2 : 3;
    const Eigen::Index nb = with_ba ? 3 : 0;
    const Eigen::Index m = nv + ng + nb;
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m, m);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m);
    const Eigen::Matrix<double, 3, 2> B = detail::tangent_basis(g_hat);
    for (std::size_t k = 0; k + 1 < n; ++k) {
      const double dt = pims[k].delta_t_s();
      const Eigen::Matrix3d Ri = T[k].rotation();
      const Eigen::Vector3d pi = T[k].translation();
      const Eigen::Vector3d pj = T[k + 1].translation();
      const auto i = static_cast<Eigen::Index>(3 * k);
      const auto j = i + 3;
      // Rows: A x = y, for position (3) and velocity (3).
      Eigen::Matrix<double, 6, Eigen::Dynamic> A = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, m);
      Eigen::Matrix<double, 6, 1> y;
      A.block<3, 3>(0, i) = dt * Eigen::Matrix3d::Identity();
      A.block<3, 3>(3, i) = -Eigen::Matrix3d::Identity();
      A.block<3, 3>(3, j) = Eigen::Matrix3d::Identity();
      y.head<3>() = pj - pi - Ri * pims[k].delta_p_m();
      y.tail<3>() = Ri * pims[k].delta_v_mps();
      if (constrained) {  // g = G g_hat + G B w (first order in w)
        A.block<3, 2>(0, nv) = 0.5 * dt * dt * G * B;
        A.block<3, 2>(3, nv) = -dt * G * B;
        y.head<3>() -= 0.5 * dt * dt * G * g_hat;
        y.tail<3>() += dt * G * g_hat;
      } else {
        A.block<3, 3>(0, nv) = 0.5 * dt * dt * Eigen::Matrix3d::Identity();
        A.block<3, 3>(3, nv) = -dt * Eigen::Matrix3d::Identity();
      }
      if (with_ba) {
        A.block<3, 3>(0, nv + ng) = Ri * pims[k].jacobians().J_dp_ba;
        A.block<3, 3>(3, nv + ng) = -Ri * pims[k].jacobians().J_dv_ba;
      }
      A.topRows<3>() *= wp;
      y.head<3>() *= wp;
      A.bottomRows<3>() *= wv;
      y.tail<3>() *= wv;
      H += A.transpose() * A;
      rhs += A.transpose() * y;
    }
    return detail::solve_normal(H, rhs, config.min_pivot_ratio, x);
  };
  Eigen::VectorXd x;
  if (!solve(false, Eigen::Vector3d::UnitZ(), x)) {
    out.status = InertialInitStatus::kNotExciting;
    out.message = "initialize_inertial: the velocity/gravity system is rank-deficient";
    return out;
  }
  Eigen::Vector3d g = x.segment<3>(nv);
  out.gravity_free_norm_mps2 = g.norm();
  if (!std::isfinite(g.norm()) || std::abs(g.norm() - G) > config.max_gravity_error_mps2 || g.norm() == 0.0) {
    out.status = InertialInitStatus::kInconsistent;
    out.message = "initialize_inertial: estimated |g| = " + std::to_string(g.norm()) + " m/s^2, configured " +
                  std::to_string(G) + " (check the extrinsic, time offset and pose scale)";
    out.gravity_map_mps2 = std::isfinite(g.norm()) ? g : Eigen::Vector3d::Zero();
    return out;
  }
  Eigen::Vector3d g_hat = g.normalized();
  for (int it = 0; it < std::max(1, config.refine_iterations); ++it) {
    if (!solve(true, g_hat, x)) {
      out.status = InertialInitStatus::kNotExciting;
      out.message = "initialize_inertial: the gravity-refinement system is rank-deficient";
      return out;
    }
    g_hat = (g_hat + detail::tangent_basis(g_hat) * x.segment<2>(nv)).normalized();
  }
  // Final velocities (and accel bias) at the refined direction: one more
  // solve, whose tangent step is below first order by now.
  if (!solve(true, g_hat, x)) {
    out.status = InertialInitStatus::kNotExciting;
    out.message = "initialize_inertial: the gravity-refinement system is rank-deficient";
    return out;
  }
  out.gravity_map_mps2 = G * g_hat;
  if (with_ba) out.bias.accel_mps2 = x.segment<3>(nv + 2);
  {
    double sq = 0.0;
    for (std::size_t k = 0; k + 1 < n; ++k) {
      const double dt = pims[k].delta_t_s();
      const Eigen::Vector3d vi = x.segment<3>(static_cast<Eigen::Index>(3 * k));
      const Eigen::Vector3d dp = pims[k].delta_p_m() + pims[k].jacobians().J_dp_ba * out.bias.accel_mps2;
      const Eigen::Vector3d e = T[k + 1].translation() - T[k].translation() - vi * dt -
                                0.5 * dt * dt * out.gravity_map_mps2 - T[k].rotation() * dp;
      sq += e.squaredNorm();
    }
    out.position_rms_m = std::sqrt(sq / static_cast<double>(n - 1));
  }
  if (!(out.position_rms_m <= config.max_position_rms_m)) {
    out.status = InertialInitStatus::kInconsistent;
    out.message = "initialize_inertial: lidar positions and IMU disagree (RMS " + std::to_string(out.position_rms_m) +
                  " m; check the pose scale and time offset)";
    return out;
  }
  out.velocities_map_mps.resize(n);
  out.states.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    out.velocities_map_mps[k] = x.segment<3>(static_cast<Eigen::Index>(3 * k));
    out.states[k].R_world_imu = T[k].so3();
    out.states[k].p_world_m = T[k].translation();
    out.states[k].v_world_mps = out.velocities_map_mps[k];
  }
  out.status = InertialInitStatus::kOk;
  return out;
}

}  // namespace semlio
