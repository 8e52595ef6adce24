// KITTI-layout writer: files, round trips through the io readers, determinism.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <semlio/io/kitti.hpp>
#include <semlio/io/oxts.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/sim/kitti_writer.hpp>

namespace test_kitti_writer {  // one namespace per test file: the area compiles as one TU

namespace fs = std::filesystem;
using namespace semlio::sim;

namespace {
SimulatorConfig tiny() {
  SimulatorConfig c;
  c.frames = 4;
  c.lidar.azimuth_steps = 360;  // small sweeps keep the test fast
  c.chunks = 12;
  c.imu_rate_hz = 50.0;
  return c;
}
std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

TEST_CASE("writer produces a KITTI sequence the io readers accept", "[sim]") {
  const fs::path dir = fs::temp_directory_path() / "semlio_sim_writer_a";
  fs::remove_all(dir);
  const Simulator sim(tiny());
  const auto rep = write_kitti_sequence(sim, dir.string());
  CHECK(rep.frames == 4);
  CHECK(rep.prediction_miou > 0.2);
  CHECK(rep.prediction_miou < 0.9);
  // Scans and labels: same point counts; labels equal the in-memory frame.
  const Frame f2 = sim.frame(2);
  const semlio::Scan scan = semlio::io::read_kitti_bin((dir / "velodyne" / "000002.bin").string());
  REQUIRE(scan.size() == f2.scan.size());
  CHECK(semlio::io::read_label_file((dir / "labels" / "000002.label").string(), scan.size()) == f2.raw_labels);
  CHECK(semlio::io::read_label_file((dir / "predictions" / "000002.label").string(), scan.size()).size() == scan.size());
  // Poses: camera-0 convention with Tr of sequence 00; back in the lidar frame
  // they equal the simulator's relative ground truth.
  const auto calib = semlio::io::read_kitti_calib((dir / "calib.txt").string());
  REQUIRE(calib.T_cam0_velo.has_value());
  REQUIRE(calib.T_imu_velo.has_value());
  CHECK((calib.T_imu_velo->translation() - Eigen::Vector3d(0.81, -0.32, 0.80)).norm() < 1e-12);
  const auto P = semlio::io::read_kitti_poses((dir / "poses.txt").string());
  REQUIRE(P.size() == 4);
  const auto T = semlio::io::camera_to_lidar(P, *calib.T_cam0_velo);
  const semlio::SE3d expected = sim.T_world_lidar(sim.frame_stamp_s(0)).inverse() * sim.T_world_lidar(sim.frame_stamp_s(3));
  CHECK((T[3].translation() - expected.translation()).norm() < 1e-9);
  CHECK((T[0].translation()).norm() < 1e-12);
  const auto times = semlio::io::read_kitti_times((dir / "times.txt").string());
  REQUIRE(times.size() == 4);
  CHECK(times[3] == Approx(0.3));
  // OXTS at the IMU rate over the frames' span.
  const auto oxts = semlio::io::read_oxts((dir / "oxts").string());
  CHECK(oxts.size() == 21);  // 0.4 s at 50 Hz, both ends
  CHECK(oxts[1].stamp_s - oxts[0].stamp_s == Approx(0.02).margin(1e-6));
  CHECK(oxts[5].accel_body_mps2.z() == Approx(9.81).margin(0.5));
  const std::string json = slurp(dir / "sim.json");
  CHECK(json.find("\"world\": \"urban\"") != std::string::npos);
  CHECK(json.find("\"achieved_label_miou\"") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("writer output is byte-identical for the same seed and any thread count", "[sim]") {
  const fs::path a = fs::temp_directory_path() / "semlio_sim_writer_b";
  const fs::path b = fs::temp_directory_path() / "semlio_sim_writer_c";
  fs::remove_all(a);
  fs::remove_all(b);
  write_kitti_sequence(Simulator(tiny()), a.string());
  KittiWriterConfig wc;
  wc.threads = 2;
  write_kitti_sequence(Simulator(tiny()), b.string(), wc);
  for (const char* f : {"velodyne/000003.bin", "labels/000001.label", "predictions/000002.label", "poses.txt",
                        "times.txt", "calib.txt", "sim.json", "oxts/timestamps.txt", "oxts/data/0000000007.txt"}) {
    INFO(f);
    CHECK(slurp(a / f) == slurp(b / f));
    CHECK(!slurp(a / f).empty());
  }
  fs::remove_all(a);
  fs::remove_all(b);
}

}  // namespace test_kitti_writer
