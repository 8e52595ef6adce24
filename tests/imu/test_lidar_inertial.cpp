// LidarInertialOdometry on a short simulated urban drive held in memory
// (distortion off, then on with deskew): initialisation while moving, IMU
// prediction, velocity and gravity; IMU gaps, an IMU that stops, samples going
// backwards -> documented lidar-only fallback per frame, never a crash.
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include <semlio/pipeline/lidar_inertial.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/segment/scan_labels.hpp>
#include <semlio/sim/simulator.hpp>
#include <semlio_test/imu_inertial_drive.hpp>

using namespace semlio;

namespace {

constexpr std::size_t kFrames = 30;

struct Drive {
  std::vector<Scan> scans;
  std::vector<SE3d> gt;                   // T_lidar0_lidar at the sweep starts
  std::vector<Eigen::Vector3d> v_map;     // true IMU velocity in the map (lidar-0) frame
  Eigen::Vector3d g_map;                  // true gravity in the map frame
  std::vector<ImuSample> imu;             // noisy simulated IMU
  SE3d T_imu_lidar;
};

Drive make_drive(bool distortion) {
  const sim::SimulatorConfig c = semlio_test::small_lidar_drive_config(kFrames, distortion);
  const sim::Simulator s(c);
  Drive d;
  d.gt = s.lidar_poses();
  for (std::size_t i = 0; i < kFrames; ++i) d.scans.push_back(s.frame(i).scan);
  d.T_imu_lidar = sim::default_T_imu_lidar();
  d.imu = s.imu({}, d.T_imu_lidar).samples;
  const SE3d T_lidar0_world = s.T_world_lidar(0.0).inverse();
  const SE3d T_body_imu = (d.T_imu_lidar * s.T_body_lidar().inverse()).inverse();
  for (std::size_t i = 0; i < kFrames; ++i) {
    const auto k = s.ego().state(s.frame_stamp_s(i));
    const Eigen::Vector3d v_world = k.velocity_world_mps + k.T_world_body.rotation() *
                                                               k.angular_velocity_body_radps.cross(T_body_imu.translation());
    d.v_map.push_back(T_lidar0_world.rotation() * v_world);
  }
  d.g_map = T_lidar0_world.rotation() * Eigen::Vector3d(0.0, 0.0, -9.80665);
  return d;
}

const Drive& clean_drive() {
  static const Drive d = make_drive(false);
  return d;
}

LidarInertialConfig lio_config(const Drive& d, bool deskew) {
  LidarInertialConfig c;
  c.T_imu_lidar = d.T_imu_lidar;
  c.deskew = deskew;
  c.init.min_frames = 15;  // a short drive: 1.5 s of poses
  c.init.min_duration_s = 1.4;
  return c;
}

auto make_lio(const Drive& d, bool deskew) {
  PipelineSettings s;
  s.odometry.kitti_vertical_correction = false;
  return LidarInertialOdometry([s] { return make_baseline_odometry(ScanLabels{}, s); }, lio_config(d, deskew));
}

bool finite(const SE3d& T) { return T.matrix().allFinite(); }

}  // namespace

TEST_CASE("LIO: initialises while moving, predicts with the IMU, estimates velocity and gravity", "[imu]") {
  const Drive& d = clean_drive();
  auto lio = make_lio(d, false);
  std::size_t next = 0;
  std::size_t imu_frames = 0;
  double worst_v = 0.0;
  double worst_p = 0.0;
  std::size_t init_frame = kFrames;
  for (std::size_t i = 0; i < kFrames; ++i) {
    Scan scan = d.scans[i];
    while (next < d.imu.size() && d.imu[next].stamp_s <= scan.stamp_s + 0.1 + 1e-9) lio.push_imu(d.imu[next++]);
    const LidarInertialReport r = lio.process(scan);
    REQUIRE(finite(r.T_map_lidar));
    CHECK_FALSE(r.imu_fallback);
    if (r.initialized && init_frame == kFrames) init_frame = i;
    if (r.prediction == PredictionSource::kImu) {
      ++imu_frames;
      worst_v = std::max(worst_v, (r.state.v_world_mps - d.v_map[i]).norm());
    }
    worst_p = std::max(worst_p, (r.T_map_lidar.translation() - d.gt[i].translation()).norm());
  }
  INFO("initialised at frame " << init_frame << ", IMU-predicted frames " << imu_frames << ", worst velocity error "
                               << worst_v << " m/s, worst position error " << worst_p << " m");
  CHECK(lio.initialized());
  CHECK(init_frame == 14);  // min_frames = 15: the first attempt succeeds
  CHECK(imu_frames + init_frame + 1 == kFrames);
  CHECK(worst_v < 0.15);
  CHECK(worst_p < 0.3);
  const Eigen::Vector3d g = lio.gravity_map_mps2();
  CHECK(std::atan2(g.cross(d.g_map).norm(), g.dot(d.g_map)) < 1.0 * std::numbers::pi / 180.0);
}

TEST_CASE("LIO: IMU gaps, an IMU that stops and samples going backwards fall back per frame", "[imu]") {
  const Drive& d = clean_drive();
  auto lio = make_lio(d, false);
  // Initialised at frame 14. Gap of 0.3 s after frame 19's stamp, IMU ends
  // at 2.65 s; one sample going backwards and a NaN are pushed at frame 16.
  std::vector<ImuSample> imu;
  for (const ImuSample& s : d.imu) {
    if (s.stamp_s > 1.92 && s.stamp_s < 2.22) continue;
    if (s.stamp_s > 2.65) break;
    imu.push_back(s);
  }
  std::size_t next = 0;
  for (std::size_t i = 0; i < kFrames; ++i) {
    Scan scan = d.scans[i];
    while (next < imu.size() && imu[next].stamp_s <= scan.stamp_s + 0.1 + 1e-9) lio.push_imu(imu[next++]);
    if (i == 16) {
      ImuSample back = imu[next - 5];
      CHECK_FALSE(lio.push_imu(back));
      ImuSample bad = imu[next - 1];
      bad.stamp_s += 0.001;
      bad.gyro_radps.x() = std::nan("");
      CHECK_FALSE(lio.push_imu(bad));
    }
    const LidarInertialReport r = lio.process(scan);
    CAPTURE(i, r.imu_issue);
    REQUIRE(finite(r.T_map_lidar));
    REQUIRE(r.state.v_world_mps.allFinite());
    if (i == 16) CHECK(r.imu_rejected == 2);
    if (i == 16 || i == 17 || i == 19 || i == 24 || i == 26) {  // IMU intact between the states
      CHECK(r.prediction == PredictionSource::kImu);
      CHECK_FALSE(r.imu_fallback);
    }
    if (i >= 20 && i <= 23) {  // the window from the last state (or its bracketing samples) crosses the gap
      CHECK(r.imu_fallback);
      CHECK(r.prediction == PredictionSource::kConstantVelocity);
      CHECK((r.imu_issue.find("gap") != std::string::npos || r.imu_issue.find("cover") != std::string::npos));
    }
    if (i >= 27) {  // the IMU stopped
      CHECK(r.imu_fallback);
      CHECK(r.imu_issue.find("cover") != std::string::npos);
    }
    CHECK((r.T_map_lidar.translation() - d.gt[i].translation()).norm() < 0.5);
  }
  CHECK(lio.last_imu_rejection().find("non-finite") != std::string::npos);
}
