#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/features/sensor_profiles.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/segment/scan_labels.hpp>
#include <semlio/sim/lidar.hpp>
#include <semlio/sim/simulator.hpp>

namespace test_sensor_settings {  // one namespace per test file: the area compiles as one TU

namespace {

// Exit distance of a ray from inside the box [lo, hi], entry distance into a
// box the ray starts outside of (infinity when missed).
double exit_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
                const Eigen::Vector3d& hi) {
  double t = 1e9;
  for (int k = 0; k < 3; ++k) {
    if (d[k] > 1e-12) t = std::min(t, (hi[k] - o[k]) / d[k]);
    if (d[k] < -1e-12) t = std::min(t, (lo[k] - o[k]) / d[k]);
  }
  return t;
}

double enter_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
                 const Eigen::Vector3d& hi) {
  double t0 = 0.0;
  double t1 = 1e9;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (o[k] < lo[k] || o[k] > hi[k]) return 1e9;
      continue;
    }
    double a = (lo[k] - o[k]) / d[k];
    double b = (hi[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return t0 <= t1 && t0 > 0.0 ? t0 : 1e9;
}

// A 64-beam, 90-degree sweep (the os0-64 table) taken at T_world_sensor in a
// 16 x 12 x 4.5 m hall with two pillars (no symmetry to confuse yaw).
semlio::Scan hall_sweep(const semlio::SE3d& T_world_sensor) {
  const semlio::SensorModel table = semlio::sensor_profile("os0-64").beams;
  const Eigen::Vector3d lo(-8.0, -6.0, -1.5);
  const Eigen::Vector3d hi(8.0, 6.0, 3.0);
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pillars = {
      {{2.5, 1.5, -1.5}, {3.3, 2.3, 3.0}}, {{-4.0, -3.5, -1.5}, {-2.5, -3.0, 3.0}}};
  semlio::Scan s;
  const Eigen::Vector3d o = T_world_sensor.translation();
  const Eigen::Matrix3d R = T_world_sensor.rotation();
  for (int c = 0; c < 1024; ++c) {
    const double az = std::numbers::pi - 2.0 * std::numbers::pi * c / 1024.0;
    for (const double el : table.elevations_rad) {
      const Eigen::Vector3d d_sensor(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const Eigen::Vector3d d = R * d_sensor;
      double t = exit_box(o, d, lo, hi);
      for (const auto& [plo, phi] : pillars) t = std::min(t, enter_box(o, d, plo, phi));
      s.points.push_back((t * d_sensor).cast<float>());
    }
  }
  return s;
}

}  // namespace

TEST_CASE("Odometry: a drive that starts moving is tracked from its first frame", "[pipeline]") {
  // A simulated VLP-16 recording (urban, heavy traffic) that starts at
  // 40 km/h: the first frame after the start has no motion estimate, so its
  // prediction is 1.1 m short. Both presets must find the 1.1 m, although
  // the 16 sparse rings leave the feature axes of Algorithm 1 noisy
  // (odometry.hpp, steps 5-7).
  // The drive of scripts/accuracy_sensors_bags.sh (1000 frames, seed 1);
  // its first 4 frames.
  semlio::sim::SimulatorConfig c;
  c.frames = 1000;
  c.traffic = semlio::sim::TrafficLevel::kHeavy;
  c.lidar = semlio::sim::lidar_config_for("vlp16");
  const semlio::sim::Simulator sim(c);
  std::vector<semlio::sim::Frame> frames;
  for (std::size_t i = 0; i < 4; ++i) frames.push_back(sim.frame(i));
  const double first_step_m =
      (frames[1].T_world_lidar.translation() - frames[0].T_world_lidar.translation()).norm();
  REQUIRE(first_step_m > 1.0);  // moving from the start
  const semlio::PipelineSettings settings = semlio::settings_for_sensor(semlio::sensor_profile("vlp16"));
  const auto check = [&](auto odo, const char* preset) {
    INFO(preset);
    for (std::size_t i = 0; i < frames.size(); ++i) {
      semlio::Scan scan = frames[i].scan;
      const semlio::FrameReport r = odo.process(scan);
      const semlio::SE3d truth = frames[0].T_world_lidar.inverse() * frames[i].T_world_lidar;
      INFO("frame " << i << " status " << semlio::to_string(r.status) << " at "
                    << r.T_map_lidar.translation().transpose() << ", truth " << truth.translation().transpose());
      CHECK((r.T_map_lidar.translation() - truth.translation()).norm() < 0.1);
    }
  };
  check(semlio::make_baseline_odometry(semlio::NoLabels{}, settings), "baseline");
  check(semlio::make_full_odometry(semlio::NoLabels{}, settings), "full");
}

TEST_CASE("settings for a KITTI HDL-64E on a car are the presets' defaults", "[pipeline]") {
  // Every KITTI result of the project was measured with the defaults: the
  // sensor profile path must not move them.
  const semlio::PipelineSettings d;
  const semlio::PipelineSettings s = semlio::settings_for_sensor(semlio::sensor_profile("hdl64e"));
  CHECK(s.odometry.sensor.elevations_rad == d.odometry.sensor.elevations_rad);
  CHECK(s.odometry.rings.method == semlio::RingMethod::kAuto);
  CHECK(s.odometry.preprocess.min_range_m == d.odometry.preprocess.min_range_m);
  CHECK(s.odometry.preprocess.max_range_m == d.odometry.preprocess.max_range_m);
  CHECK(s.odometry.preprocess.crop_ego_box);
  CHECK(s.odometry.max_correction_m == d.odometry.max_correction_m);
  CHECK(s.odometry.max_correction_rad == d.odometry.max_correction_rad);
  CHECK(s.odometry.max_speed_mps == 0.0);
  CHECK(s.odometry.max_angular_rate_radps == 0.0);
  CHECK(s.odometry.prediction_rotation_scale == 1.0);
  CHECK(s.odometry.solver.max_iterations == d.odometry.solver.max_iterations);
  CHECK(s.deskew.sweep_period_s == Approx(d.deskew.sweep_period_s));
  CHECK(s.deskew.start_azimuth_rad == d.deskew.start_azimuth_rad);
  CHECK(s.deskew.clockwise == d.deskew.clockwise);
}

TEST_CASE("settings for a hand-held OS0 follow the profile and the platform", "[pipeline]") {
  const semlio::SensorProfile os0 = semlio::sensor_profile("os0-64");
  const semlio::PipelineSettings s = semlio::settings_for_sensor(os0, semlio::motion_profile("hand_held"));
  CHECK(s.odometry.sensor.elevations_rad == os0.beams.elevations_rad);
  CHECK(s.odometry.rings.prefer_scan_rings);
  CHECK(s.odometry.preprocess.min_range_m == 1.0);   // the operator, not the sensor's 0.3 m
  CHECK(s.odometry.preprocess.max_range_m == 50.0);  // the OS0's reach
  CHECK_FALSE(s.odometry.preprocess.crop_ego_box);
  CHECK(s.odometry.max_angular_rate_radps == 2.0);
  CHECK(s.odometry.max_speed_mps == 2.0);
  CHECK(s.odometry.prediction_rotation_scale == 0.5);
  CHECK(s.odometry.solver.max_iterations >= 50);
  CHECK(s.deskew.start_azimuth_rad == Approx(std::numbers::pi));
  CHECK(s.deskew.clockwise);
  CHECK_THROWS_AS(semlio::motion_profile("boat"), semlio::ConfigError);
  semlio::SensorProfile bad = os0;
  bad.min_range_m = -1.0;
  CHECK_THROWS_AS(semlio::settings_for_sensor(bad), semlio::ConfigError);
}

TEST_CASE("the odometry rejects a bad motion profile", "[pipeline]") {
  semlio::PipelineSettings s;
  s.odometry.max_angular_rate_radps = -1.0;
  CHECK_THROWS_AS(semlio::make_baseline_odometry(semlio::NoLabels{}, s), semlio::ConfigError);
  s.odometry.max_angular_rate_radps = 0.0;
  s.odometry.prediction_rotation_scale = 1.5;
  CHECK_THROWS_AS(semlio::make_baseline_odometry(semlio::NoLabels{}, s), semlio::ConfigError);
}

TEST_CASE("a hand-held turn beyond the fixed rotation gate is tracked with the motion profile", "[pipeline]") {
  // Two sweeps 0.5 s apart (2 Hz keyframes) with a 23 deg turn and a 0.3 m
  // step: the prediction (no motion yet) is 0.40 rad off, beyond the fixed
  // 0.3 rad gate; a hand-held profile (2 rad/s: gate 2 rad at 0.5 s) lets
  // the solver's answer through.
  const semlio::SE3d T1(semlio::SO3d::exp(Eigen::Vector3d(0.0, 0.05, 0.4)), Eigen::Vector3d(0.3, -0.1, 0.05));
  const semlio::SensorProfile os0 = semlio::sensor_profile("os0-64");
  const auto run = [&](const semlio::MotionProfile& motion) {
    auto odo = semlio::make_baseline_odometry(semlio::NoLabels{}, semlio::settings_for_sensor(os0, motion));
    semlio::Scan a = hall_sweep(semlio::SE3d());
    a.stamp_s = 0.0;
    semlio::Scan b = hall_sweep(T1);
    b.stamp_s = 0.5;
    REQUIRE(odo.process(a).status == semlio::OdometryStatus::kInitialized);
    return odo.process(b);
  };
  const semlio::FrameReport vehicle = run(semlio::vehicle_motion());
  CHECK(vehicle.status == semlio::OdometryStatus::kRejectedJump);
  const semlio::FrameReport hand = run(semlio::hand_held_motion());
  CHECK(hand.status == semlio::OdometryStatus::kTracked);
  const semlio::SE3d err = T1.inverse() * hand.T_map_lidar;
  CHECK(err.translation().norm() < 0.02);
  CHECK(err.so3().angle() < 0.2 * std::numbers::pi / 180.0);
}

TEST_CASE("the full preset tracks hand-held turns its prediction misses by more than the axis test's angle",
          "[pipeline]") {
  // Three sweeps 0.5 s apart: a 23 deg turn, then back. The prediction of
  // the third (half the last rotation, the hand-held profile) is 34 deg off:
  // Algorithm 1 compares axes rotated by that estimate at 10 deg, so the
  // hand-held profile solves with the nearest candidates first
  // (OdometryConfig::coarse_solve_first), then with Algorithm 1.
  const semlio::SE3d T1(semlio::SO3d::exp(Eigen::Vector3d(0.0, 0.05, 0.4)), Eigen::Vector3d(0.3, -0.1, 0.05));
  const semlio::SE3d T2(semlio::SO3d::exp(Eigen::Vector3d(0.0, 0.0, -0.05)), Eigen::Vector3d(0.5, 0.1, 0.0));
  const semlio::SensorProfile os0 = semlio::sensor_profile("os0-64");
  const auto run = [&](bool coarse_first, bool baseline_when_degenerate) {
    semlio::PipelineSettings settings = semlio::settings_for_sensor(os0, semlio::hand_held_motion());
    REQUIRE(settings.odometry.coarse_solve_first);
    settings.odometry.coarse_solve_first = coarse_first;
    settings.odometry.baseline_when_degenerate = baseline_when_degenerate;
    auto odo = semlio::make_full_odometry(semlio::NoLabels{}, settings);
    const semlio::SE3d poses[] = {semlio::SE3d(), T1, T2};
    semlio::FrameReport last;
    for (int i = 0; i < 3; ++i) {
      semlio::Scan s = hall_sweep(poses[i]);
      s.stamp_s = 0.5 * i;
      last = odo.process(s);
    }
    return (T2.inverse() * last.T_map_lidar).so3().angle() * 180.0 / std::numbers::pi;
  };
  CHECK(run(true, false) < 0.2);
  CHECK(run(false, false) > 1.0);  // without the coarse solve the turn back is missed
  // Algorithm 1's solve of the missed turn is weak, so the nearest-candidate
  // solve from there (OdometryConfig::baseline_when_degenerate) runs and finds
  // the turn too.
  CHECK(run(false, true) < 0.2);
}

}  // namespace test_sensor_settings
