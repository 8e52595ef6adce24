// The --imu oxts reading path (as semlio_kitti / semlio_lio use it): IMU
// samples from a written KITTI raw oxts/ folder into LidarInertialOdometry.
// Defects in the folder give the documented outcome, never a crash:
// - a gap, or samples ending before the drive does -> that frame falls back
//   to the lidar-only prediction, flagged in the report (imu_fallback, reason);
// - repeated stamps (read_oxts accepts equal times) -> push_imu rejects the
//   repeat and counts it;
// - time going backwards in timestamps.txt -> read_oxts throws ValueError
//   naming the file and line (semlio_kitti prints it and exits 1).
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/oxts.hpp>
#include <semlio/pipeline/lidar_inertial.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/segment/scan_labels.hpp>
#include <semlio/sim/simulator.hpp>

using namespace semlio;
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kFrames = 30;

fs::path temp_dir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("semlio_test_oxts_fallback_" + name);
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

std::vector<io::OxtsRecord> records_of(const std::vector<ImuSample>& imu, double epoch_s) {
  std::vector<io::OxtsRecord> out;
  for (const ImuSample& s : imu) {
    io::OxtsRecord r;
    r.stamp_s = epoch_s + s.stamp_s;
    r.gyro_body_radps = s.gyro_radps;
    r.accel_body_mps2 = s.accel_mps2;
    out.push_back(r);
  }
  return out;
}

}  // namespace

TEST_CASE("OXTS folder with a gap, a repeated stamp and an early end: per-frame fallback, no crash", "[imu]") {
  sim::SimulatorConfig c;
  c.world = sim::WorldKind::kUrban;
  c.traffic = sim::TrafficLevel::kNone;
  c.frames = kFrames;
  c.seed = 4;
  c.lidar.azimuth_steps = 720;
  c.threads = 2;
  const sim::Simulator s(c);
  const SE3d T_imu_lidar = sim::default_T_imu_lidar();
  const std::vector<ImuSample> truth = s.imu({}, T_imu_lidar).samples;
  // KITTI-like date stamps, as the simulator writes them (the epoch is arbitrary).
  const double epoch = 1317020000.0;
  std::vector<ImuSample> defective;
  for (const ImuSample& x : truth) {
    if (x.stamp_s > 1.92 && x.stamp_s < 2.22) continue;  // 0.3 s gap (> max_gap_s 0.15 s)
    if (x.stamp_s > 2.65) break;                          // the IMU stops before the drive ends (3.0 s)
    defective.push_back(x);
    if (defective.size() == 170) defective.push_back(x);  // one repeated stamp, at 1.69 s
  }
  const fs::path dir = temp_dir("defects");
  io::write_oxts((dir / "oxts").string(), records_of(defective, epoch));
  const std::vector<ImuSample> imu = io::imu_samples(io::read_oxts((dir / "oxts").string()));
  REQUIRE(imu.size() == defective.size());

  LidarInertialConfig lc;
  lc.T_imu_lidar = T_imu_lidar;
  lc.imu_time_offset_s = epoch;  // t_imu = t_lidar + offset
  lc.init.min_frames = 15;
  lc.init.min_duration_s = 1.4;
  PipelineSettings ps;
  ps.odometry.kitti_vertical_correction = false;
  LidarInertialOdometry lio([ps] { return make_baseline_odometry(ScanLabels{}, ps); }, lc);
  const std::vector<SE3d> gt = s.lidar_poses();
  std::size_t next = 0;
  std::size_t fallbacks = 0;
  for (std::size_t i = 0; i < kFrames; ++i) {
    Scan scan = s.frame(i).scan;
    while (next < imu.size() && imu[next].stamp_s <= scan.stamp_s + epoch + 0.1 + 1e-6) lio.push_imu(imu[next++]);
    LidarInertialReport r;
    REQUIRE_NOTHROW(r = lio.process(scan));
    CAPTURE(i, r.imu_issue);
    REQUIRE(r.T_map_lidar.matrix().allFinite());
    REQUIRE(r.state.v_world_mps.allFinite());
    if (r.imu_fallback) {
      ++fallbacks;
      CHECK(r.prediction == PredictionSource::kConstantVelocity);
      CHECK((r.imu_issue.find("gap") != std::string::npos || r.imu_issue.find("cover") != std::string::npos));
    }
    if (i >= 27) CHECK(r.imu_fallback);  // no samples after 2.65 s
    if (i == 17) CHECK(r.prediction == PredictionSource::kImu);  // IMU intact from 1.6 to 1.8 s
    // The fallback keeps tracking: lidar-only accuracy on this short drive.
    CHECK((r.T_map_lidar.translation() - gt[i].translation()).norm() < 0.5);
  }
  CHECK(lio.initialized());
  CHECK(lio.imu_rejected() == 1);  // the repeated stamp
  CHECK(lio.last_imu_rejection().find("after") != std::string::npos);
  CHECK(fallbacks >= 4);  // the gap (frames 20-23) and the end (27-29)
  fs::remove_all(dir);
}

TEST_CASE("OXTS timestamps going backwards: a ValueError naming the file and line", "[imu]") {
  std::vector<ImuSample> imu;
  for (int k = 0; k < 5; ++k) {
    imu.push_back({0.01 * k, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, 9.81)});
  }
  const fs::path dir = temp_dir("backwards");
  io::write_oxts((dir / "oxts").string(), records_of(imu, 1317020000.0));
  // Swap lines 3 and 4 of timestamps.txt: time goes backwards at line 4.
  const fs::path stamps = dir / "oxts" / "timestamps.txt";
  std::vector<std::string> lines;
  {
    std::ifstream in(stamps);
    for (std::string l; std::getline(in, l);) lines.push_back(l);
  }
  REQUIRE(lines.size() == 5);
  std::swap(lines[2], lines[3]);
  {
    std::ofstream out(stamps);
    for (const std::string& l : lines) out << l << '\n';
  }
  try {
    (void)io::read_oxts((dir / "oxts").string());
    FAIL("read_oxts accepted time going backwards");
  } catch (const ValueError& e) {
    const std::string what = e.what();
    CHECK(what.find("timestamps.txt:4") != std::string::npos);
    CHECK(what.find("backwards") != std::string::npos);
  }
  fs::remove_all(dir);
}
