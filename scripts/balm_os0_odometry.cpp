// A small driver for scripts/balm_os0.sh: the library's sensor path on a
// KITTI-layout folder (velodyne/*.bin, times.txt) -- the beam table from the
// sensor YAML (a profile, or profile: auto = BeamDetector over the first
// frames), settings_for_sensor(profile, platform), the baseline or full
// odometry -- until semlio_kitti reads the YAML's sensor section itself.
// Writes OUT/poses.txt (KITTI 3x4, lidar frame, first pose = identity),
// OUT/status.txt (one status per frame) and OUT/sensor.txt (key value lines).
//
// Build: g++ -O2 -DNDEBUG -std=c++20 -I include -I examples/common -isystem /usr/include/eigen3
//        scripts/balm_os0_odometry.cpp -lyaml-cpp
// Usage: balm_os0_odometry SEQUENCE_DIR SENSOR_YAML OUT_DIR [baseline|full]

#include <cstdio>
#include <fstream>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/io/kitti.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/segment/scan_labels.hpp>

#include "sensor_yaml.hpp"

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: balm_os0_odometry SEQUENCE_DIR SENSOR_YAML OUT_DIR [baseline|full]\n";
    return 2;
  }
  const std::string dir = argv[1];
  const std::string out = argv[3];
  const std::string preset = argc > 4 ? argv[4] : "baseline";
  try {
    const std::vector<double> times = semlio::io::read_kitti_times(dir + "/times.txt");
    const auto bin = [&](std::size_t i) {
      char name[32];
      std::snprintf(name, sizeof name, "/velodyne/%06zu.bin", i);
      return dir + name;
    };
    const semlio_examples::SensorYaml y = semlio_examples::load_sensor_yaml(argv[2]);
    semlio::PipelineSettings settings;
    const semlio_examples::SensorSetup setup = semlio_examples::configure_sensor(
        y, times.size(), [&](std::size_t i) { return semlio::io::read_kitti_bin(bin(i)); }, settings);
    std::ofstream facts(out + "/sensor.txt");
    for (const auto& [k, v] : setup.facts) facts << k << " " << v << "\n";
    if (setup.detection) {
      facts << "detection_beams " << setup.detection->beams() << "\n";
      facts << "detection_median_spacing_deg " << setup.detection->median_spacing_rad * 180.0 / std::numbers::pi << "\n";
    }

    std::vector<semlio::SE3d> poses;
    std::ofstream status(out + "/status.txt");
    const auto run = [&](auto odometry) {
      for (std::size_t i = 0; i < times.size(); ++i) {
        semlio::Scan scan = semlio::io::read_kitti_bin(bin(i));
        scan.stamp_s = times[i];
        const semlio::FrameReport r = odometry.process(scan);
        poses.push_back(r.T_map_lidar);
        status << semlio::to_string(r.status) << "\n";
      }
    };
    if (preset == "full") {
      run(semlio::make_full_odometry(semlio::NoLabels{}, settings));
    } else {
      run(semlio::make_baseline_odometry(semlio::NoLabels{}, settings));
    }
    semlio::io::write_kitti_poses(out + "/poses.txt", poses);
  } catch (const std::exception& e) {
    std::cerr << "balm_os0_odometry: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
