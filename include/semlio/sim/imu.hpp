#pragma once
/// \file
/// IMU synthesis along a simulated trajectory: angular rate and specific force
/// of a rigidly mounted IMU, with white noise and bias random walks drawn from
/// a seeded, portable generator (rng.hpp).
///
/// Model (continuous-time densities, as in Kalibr / Forster et al.):
///   gyro  = omega_imu + b_g + n_g,   accel = R_world_imu^T (a_imu - g) + b_a + n_a
///   g = (0, 0, -gravity) in the world frame (z up), so at rest accel = +g up.
/// Discrete white noise per sample: sigma_d = density * sqrt(rate);
/// bias random walk per step: b += walk * sqrt(1 / rate) * N(0, 1).
///
/// Default densities (our choice; documented): near an automotive GNSS/INS of
/// the OXTS RT3003 class (KITTI), whose datasheet figures are roughly 0.2 deg
/// per sqrt(h) angular random walk (5.8e-5 rad/s/sqrt(Hz)) and accelerometer
/// noise of order 100 ug/sqrt(Hz); we take about 2.5x the gyro and 1.5x the
/// accelerometer figure to account for engine and road vibration on a moving
/// car: gyro 1.5e-4 rad/s/sqrt(Hz), accel 1.5e-3 m/s^2/sqrt(Hz); bias walks
/// 2e-6 rad/s^2/sqrt(Hz) and 3e-5 m/s^3/sqrt(Hz) (a well-calibrated unit whose
/// biases drift by ~1e-5 rad/s and ~3e-4 m/s^2 over 100 s); turn-on biases
/// N(0, 1e-5 rad/s) and N(0, 2e-3 m/s^2) per axis.

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/imu/imu_sample.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/sim/rng.hpp>
#include <semlio/sim/trajectory.hpp>

namespace semlio::sim {

/// IMU model settings; defaults documented in the file comment.
struct ImuConfig {
  double rate_hz = 100.0;  ///< sample rate [Hz]
  /// Maps body (lidar) points into the IMU frame: KITTI's Tr_imu_velo when the
  /// body is the lidar. Default: KITTI's lever arm (lidar 0.81 m ahead of,
  /// 0.32 m right of and 0.80 m above the IMU), rotation identity.
  SE3d T_imu_body = SE3d(SO3d(), Eigen::Vector3d(0.81, -0.32, 0.80));
  bool noise = true;                               ///< false: exact measurements, zero biases
  double gyro_noise_density = 1.5e-4;              ///< [rad/s/sqrt(Hz)]
  double accel_noise_density = 1.5e-3;             ///< [m/s^2/sqrt(Hz)]
  double gyro_bias_random_walk = 2.0e-6;           ///< [rad/s^2/sqrt(Hz)]
  double accel_bias_random_walk = 3.0e-5;          ///< [m/s^3/sqrt(Hz)]
  double gyro_bias_initial_sigma_radps = 1.0e-5;   ///< turn-on bias std per axis [rad/s]
  double accel_bias_initial_sigma_mps2 = 2.0e-3;   ///< turn-on bias std per axis [m/s^2]
  double gravity_mps2 = 9.80665;                   ///< |g| [m/s^2]
  std::uint64_t seed = 1;                          ///< noise seed (same seed, same samples)
};

/// A simulated IMU stream plus the ground-truth biases added to each sample.
struct SimulatedImu {
  std::vector<ImuSample> samples;               ///< measurements in the IMU frame
  std::vector<Eigen::Vector3d> gyro_bias_radps;  ///< bias inside samples[i].gyro_radps
  std::vector<Eigen::Vector3d> accel_bias_mps2;  ///< bias inside samples[i].accel_mps2
};

/// Exact (noise-free, bias-free) IMU measurement at time t for an IMU mounted
/// at T_imu_body. Includes the lever-arm terms alpha x r + omega x (omega x r).
inline ImuSample ideal_imu_sample(const Trajectory& trajectory, const SE3d& T_imu_body, double t_s,
                                  double gravity_mps2 = 9.80665) {
  const KinematicState s = trajectory.state(t_s);
  const SE3d T_body_imu = T_imu_body.inverse();
  const Eigen::Vector3d r_body = T_body_imu.translation();  // IMU position in the body frame
  const Eigen::Matrix3d R_world_body = s.T_world_body.rotation();
  const Eigen::Matrix3d R_imu_body = T_imu_body.rotation();
  const Eigen::Vector3d& w = s.angular_velocity_body_radps;
  const Eigen::Vector3d a_imu_world =
      s.acceleration_world_mps2 +
      R_world_body * (s.angular_acceleration_body_radps2.cross(r_body) + w.cross(w.cross(r_body)));
  const Eigen::Vector3d g_world(0.0, 0.0, -gravity_mps2);
  ImuSample out;
  out.stamp_s = t_s;
  out.gyro_radps = R_imu_body * w;
  out.accel_mps2 = R_imu_body * (R_world_body.transpose() * (a_imu_world - g_world));
  return out;
}

/// IMU samples at t_begin + k / rate_hz for every k with t <= t_end (t_end < 0:
/// the whole drive). Deterministic for a seed. Throws ConfigError on a
/// non-positive rate or negative densities.
inline SimulatedImu simulate_imu(const Trajectory& trajectory, const ImuConfig& config, double t_begin_s = 0.0,
                                 double t_end_s = -1.0) {
  auto check = [](double v, const char* field, bool strictly) {
    if (!std::isfinite(v) || v < 0.0 || (strictly && v == 0.0)) {
      throw ConfigError(std::string("ImuConfig.") + field + " must be " + (strictly ? "> 0" : ">= 0") +
                        ", got " + std::to_string(v));
    }
  };
  check(config.rate_hz, "rate_hz", true);
  check(config.gyro_noise_density, "gyro_noise_density", false);
  check(config.accel_noise_density, "accel_noise_density", false);
  check(config.gyro_bias_random_walk, "gyro_bias_random_walk", false);
  check(config.accel_bias_random_walk, "accel_bias_random_walk", false);
  check(config.gyro_bias_initial_sigma_radps, "gyro_bias_initial_sigma_radps", false);
  check(config.accel_bias_initial_sigma_mps2, "accel_bias_initial_sigma_mps2", false);
  check(config.gravity_mps2, "gravity_mps2", false);
  const double t_end = t_end_s < 0.0 ? trajectory.duration_s() : t_end_s;
  const double dt = 1.0 / config.rate_hz;
  const double n_samples = std::floor((t_end - t_begin_s) * config.rate_hz + 1e-9) + 1.0;
  const auto count = n_samples > 0.0 ? static_cast<std::size_t>(n_samples) : std::size_t{0};

  SimulatedImu out;
  out.samples.reserve(count);
  out.gyro_bias_radps.reserve(count);
  out.accel_bias_mps2.reserve(count);
  Xoshiro256 rng(config.seed, 0x494D55ULL);  // stream "IMU"
  auto normal3 = [&rng]() {
    const double x = rng.normal();
    const double y = rng.normal();
    const double z = rng.normal();
    return Eigen::Vector3d(x, y, z);
  };
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();
  if (config.noise) {
    bg = config.gyro_bias_initial_sigma_radps * normal3();
    ba = config.accel_bias_initial_sigma_mps2 * normal3();
  }
  const double sg = config.gyro_noise_density * std::sqrt(config.rate_hz);
  const double sa = config.accel_noise_density * std::sqrt(config.rate_hz);
  const double wg = config.gyro_bias_random_walk * std::sqrt(dt);
  const double wa = config.accel_bias_random_walk * std::sqrt(dt);
  for (std::size_t k = 0; k < count; ++k) {
    const double t = t_begin_s + static_cast<double>(k) * dt;
    ImuSample s = ideal_imu_sample(trajectory, config.T_imu_body, t, config.gravity_mps2);
    if (config.noise) {
      if (k > 0) {
        bg += wg * normal3();
        ba += wa * normal3();
      }
      const Eigen::Vector3d ng = normal3();
      const Eigen::Vector3d na = normal3();
      s.gyro_radps += bg + sg * ng;
      s.accel_mps2 += ba + sa * na;
    }
    out.samples.push_back(s);
    out.gyro_bias_radps.push_back(bg);
    out.accel_bias_mps2.push_back(ba);
  }
  return out;
}

}  // namespace semlio::sim
