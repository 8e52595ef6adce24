// IMU deskew inside LidarInertialOdometry on the simulator's distorted sweeps:
// (1) deskew_sweep_imu from the exact IMU state reproduces the exact
// sweep-start points within 1 cm, with the scan's own times and with times
// from the azimuth under the simulator's convention (sweeps start facing
// backwards) -- and the KITTI convention (start facing forwards) on the same
// scan is off by decimetres, the cause of the LIO losing track on written
// drives. (A whole-drive test of the LIO with IMU deskew in memory is still
// open: on a 30-frame drive it deskewed no frame and lost 2 (ATE 2.9 m); the
// written-drive run of scripts/lio_accuracy.sh is the evidence so far.)
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include <semlio/eval/ate.hpp>
#include <semlio/pipeline/lidar_inertial.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/segment/scan_labels.hpp>
#include <semlio/sim/simulator.hpp>
#include <semlio_test/imu_inertial_drive.hpp>

using namespace semlio;

namespace {

constexpr std::size_t kFrames = 30;

sim::SimulatorConfig drive_config(bool distortion) {
  return semlio_test::small_lidar_drive_config(kFrames, distortion);
}

// Exact IMU state (world frame) at time t.
NavState imu_truth(const sim::Simulator& s, const SE3d& T_imu_lidar, double t) {
  const auto k = s.ego().state(t);
  const SE3d T_body_imu = (T_imu_lidar * s.T_body_lidar().inverse()).inverse();
  const SE3d T_world_imu = k.T_world_body * T_body_imu;
  NavState x;
  x.R_world_imu = T_world_imu.so3();
  x.p_world_m = T_world_imu.translation();
  x.v_world_mps = k.velocity_world_mps +
                  k.T_world_body.rotation() * k.angular_velocity_body_radps.cross(T_body_imu.translation());
  return x;
}

double worst_error(const Scan& scan, const std::vector<Eigen::Vector3d>& expected) {
  double w = 0.0;
  for (std::size_t k = 0; k < scan.size(); ++k) w = std::max(w, (scan.points[k].cast<double>() - expected[k]).norm());
  return w;
}

}  // namespace

TEST_CASE("LIO IMU deskew reproduces the exact sweep-start points within 1 cm", "[imu]") {
  sim::SimulatorConfig sc = drive_config(true);
  sc.lidar.noise = false;
  const sim::Simulator s(sc);
  const SE3d T_imu_lidar = sim::default_T_imu_lidar();
  sim::ImuConfig ic;
  ic.noise = false;
  const std::vector<ImuSample> imu = s.imu(ic, T_imu_lidar).samples;
  LidarInertialConfig c;
  c.T_imu_lidar = T_imu_lidar;
  const Eigen::Vector3d g_world(0.0, 0.0, -ic.gravity_mps2);
  for (const std::size_t i : {std::size_t{3}, std::size_t{17}, std::size_t{28}}) {
    const sim::Frame f = s.frame(i);
    const double stamp = f.scan.stamp_s;
    REQUIRE(f.scan.has_times());
    // The simulator's documented ground truth: p_start = T(stamp)^-1 T(t_i) p_i.
    std::vector<Eigen::Vector3d> expected(f.scan.size());
    const SE3d T_start_world = s.T_world_lidar(stamp).inverse();
    for (std::size_t k = 0; k < f.scan.size(); ++k) {
      expected[k] =
          T_start_world * (s.T_world_lidar(stamp + static_cast<double>(f.scan.times_s[k])) * f.scan.points[k].cast<double>());
    }
    const NavState x = imu_truth(s, T_imu_lidar, stamp);

    Scan own = f.scan;  // the simulator's per-point times
    deskew_sweep_imu(own, imu, x, ImuBias{}, g_world, c);

    Scan sim_az = f.scan;  // times from the azimuth, simulator convention (as read from a written drive)
    sim_az.times_s.clear();
    LidarInertialConfig c_sim = c;
    c_sim.point_times.start_azimuth_rad = std::numbers::pi;
    deskew_sweep_imu(sim_az, imu, x, ImuBias{}, g_world, c_sim);

    Scan kitti_az = f.scan;  // times from the azimuth, KITTI raw's convention: wrong for the simulator
    kitti_az.times_s.clear();
    deskew_sweep_imu(kitti_az, imu, x, ImuBias{}, g_world, c);

    INFO("frame " << i << ": raw " << worst_error(f.scan, expected) << " m, IMU deskew (scan times) "
                  << worst_error(own, expected) << " m, (azimuth, start pi) " << worst_error(sim_az, expected)
                  << " m, (azimuth, start 0) " << worst_error(kitti_az, expected) << " m");
    CHECK(worst_error(f.scan, expected) > 0.3);  // 11 m/s over 0.1 s: ~1.1 m at the sweep end
    CHECK(worst_error(own, expected) < 0.01);
    CHECK(worst_error(sim_az, expected) < 0.01);
    // Half a sweep off for half of the points: ~0.5 m at 11 m/s.
    CHECK(worst_error(kitti_az, expected) > 0.2);
  }
}

