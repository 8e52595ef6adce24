#pragma once
// Test support for the lidar-inertial tests: a small simulated drive that
// starts while moving, the exact IMU navigation state along it, and IMU
// samples with a known constant bias (no lidar involved: cheap).

#include <Eigen/Core>

#include <cstddef>
#include <vector>

#include <semlio/imu/imu_sample.hpp>
#include <semlio/imu/nav_state.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/sim/imu.hpp>
#include <semlio/sim/simulator.hpp>
#include <semlio/sim/trajectory.hpp>

namespace semlio_test {

// A short lidar drive for the lidar-inertial pipeline tests: urban, no
// traffic, 720 columns per sweep (small scans keep the tests fast).
inline semlio::sim::SimulatorConfig small_lidar_drive_config(std::size_t frames, bool distortion) {
  semlio::sim::SimulatorConfig c;
  c.world = semlio::sim::WorldKind::kUrban;
  c.traffic = semlio::sim::TrafficLevel::kNone;
  c.frames = frames;
  c.seed = 4;
  c.distortion = distortion;
  c.lidar.azimuth_steps = 720;
  c.threads = 2;
  return c;
}

// Starts at cruise speed, turns, climbs and brakes into a stop (~55 s).
inline const semlio::sim::Trajectory& inertial_drive() {
  static const semlio::sim::Trajectory tr = [] {
    semlio::sim::TrajectoryConfig c;
    c.start_at_rest = false;
    c.stop_at_arclength_m = {330.0};
    c.stop_duration_s = 2.0;
    return semlio::sim::Trajectory::through(
        {{0, 0, 0}, {60, 0, 0}, {110, 50, 3}, {110, 130, 6}, {40, 160, 4}, {0, 120, 0}, {0, 60, -1}}, c);
  }();
  return tr;
}

// A rotated, offset IMU (body -> IMU), so lever-arm and frame mistakes show.
inline semlio::SE3d inertial_T_imu_body() {
  return semlio::SE3d(semlio::SO3d::exp(Eigen::Vector3d(0.02, -0.03, 0.4)), Eigen::Vector3d(0.81, -0.32, 0.8));
}

// Exact IMU navigation state at t (IMU at T_imu_body on the trajectory's body).
inline semlio::NavState inertial_truth(const semlio::sim::Trajectory& tr, const semlio::SE3d& T_imu_body, double t) {
  const auto s = tr.state(t);
  const semlio::SE3d T_body_imu = T_imu_body.inverse();
  const semlio::SE3d T_world_imu = s.T_world_body * T_body_imu;
  semlio::NavState x;
  x.R_world_imu = T_world_imu.so3();
  x.p_world_m = T_world_imu.translation();
  x.v_world_mps = s.velocity_world_mps +
                  s.T_world_body.rotation() * s.angular_velocity_body_radps.cross(T_body_imu.translation());
  return x;
}

// Noise-free IMU samples over [t0, t1] at rate_hz plus a constant bias.
inline std::vector<semlio::ImuSample> inertial_samples(const semlio::sim::Trajectory& tr,
                                                       const semlio::SE3d& T_imu_body, double t0, double t1,
                                                       double rate_hz, const Eigen::Vector3d& gyro_bias,
                                                       const Eigen::Vector3d& accel_bias) {
  semlio::sim::ImuConfig c;
  c.noise = false;
  c.rate_hz = rate_hz;
  c.T_imu_body = T_imu_body;
  auto imu = semlio::sim::simulate_imu(tr, c, t0, t1);
  for (auto& s : imu.samples) {
    s.gyro_radps += gyro_bias;
    s.accel_mps2 += accel_bias;
  }
  return imu.samples;
}

}  // namespace semlio_test
