#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include <semlio/core/error.hpp>
#include <semlio/features/profile_match.hpp>

#include "sensor_yaml.hpp"

namespace test_sensor_yaml {  // one namespace per test file: the area compiles as one TU

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

semlio_examples::SensorYaml parse(const std::string& text) {
  return semlio_examples::parse_sensor_yaml(YAML::Load(text), "test.yaml");
}

// The ConfigError message of parsing `text` ("" when none is thrown).
std::string error_of(const std::string& text) {
  try {
    (void)semlio_examples::resolve_sensor(parse(text), nullptr);
  } catch (const semlio::ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("sensor YAML: a named profile and a platform", "[examples]") {
  const auto y = parse("sensor:\n  profile: os0-128\n  platform: hand_held\n");
  REQUIRE(y.sensor);
  CHECK(y.sensor->name == "os0-128");
  CHECK(y.sensor->beams.beams() == 128);
  CHECK(y.motion.name == "hand_held");
  CHECK_FALSE(y.detect);
  const semlio::SensorProfile p = semlio_examples::resolve_sensor(y, nullptr);
  CHECK(p.vertical_fov_rad() == Approx(90.0 * kDeg));
  // A profile refined by one key keeps the rest of the profile.
  const auto r = parse("sensor:\n  profile: vlp16\n  max_range_m: 40\n");
  REQUIRE(r.sensor);
  CHECK(r.sensor->beams.beams() == 16);
  CHECK(r.sensor->max_range_m == 40.0);
  CHECK(r.sensor->header_stamp == semlio::StampMeaning::kSweepEnd);
}

TEST_CASE("sensor YAML: a full table with its facts", "[examples]") {
  const auto y = parse(
      "sensor:\n"
      "  name: my-lidar\n"
      "  elevations_deg: [10, -10, 0, 5]\n"
      "  rotation_rate_hz: 20\n"
      "  min_range_m: 0.5\n"
      "  max_range_m: 80\n"
      "  mount_height_m: 0.6\n"
      "  header_stamp: middle\n"
      "  spin: counter_clockwise\n"
      "  sweep_start_azimuth_deg: 90\n");
  const semlio::SensorProfile p = semlio_examples::resolve_sensor(y, nullptr);
  CHECK(p.name == "my-lidar");
  REQUIRE(p.beams.beams() == 4);
  CHECK(p.beams.elevations_rad.front() == Approx(-10.0 * kDeg));  // sorted ascending
  CHECK(p.beams.elevations_rad.back() == Approx(10.0 * kDeg));
  CHECK(p.sweep_period_s() == Approx(0.05));
  CHECK(p.min_range_m == 0.5);
  CHECK(p.max_range_m == 80.0);
  CHECK(p.mount_height_m == 0.6);
  CHECK(p.header_stamp == semlio::StampMeaning::kSweepMiddle);
  CHECK(p.counter_clockwise);
  CHECK(p.sweep_start_azimuth_rad == Approx(std::numbers::pi / 2.0));
  CHECK_FALSE(p.nominal_table);
}

TEST_CASE("sensor YAML: a LIO-SAM params.yaml as it is", "[examples]") {
  // Values of LIO-SAM's own config/params.yaml (its Velodyne + 9-axis IMU
  // setup), with a translation added to check the convention.
  const std::string lio =
      "lio_sam:\n"
      "  pointCloudTopic: \"points_raw\"\n"
      "  sensor: velodyne\n"
      "  N_SCAN: 16\n"
      "  lidarMinRange: 1.0\n"
      "  lidarMaxRange: 1000.0\n"
      "  imuAccNoise: 3.9939570888238808e-03\n"
      "  imuGyrNoise: 1.5636343949698187e-03\n"
      "  imuAccBiasN: 6.4356659353532566e-05\n"
      "  imuGyrBiasN: 3.5640318696367613e-05\n"
      "  imuGravity: 9.80511\n"
      "  extrinsicTrans: [0.1, 0.2, 0.3]\n"
      "  extrinsicRot: [-1, 0, 0,\n"
      "                  0, 1, 0,\n"
      "                  0, 0, -1]\n"
      "  extrinsicRPY: [0,  1, 0,\n"
      "                 -1, 0, 0,\n"
      "                  0, 0, 1]\n"
      "sensor:\n"
      "  profile: vlp16\n";
  const auto y = parse(lio);
  REQUIRE(y.acc_noise_density);
  CHECK(*y.acc_noise_density == Approx(3.9939570888238808e-03));
  CHECK(*y.gyr_noise_density == Approx(1.5636343949698187e-03));
  CHECK(*y.acc_bias_random_walk == Approx(6.4356659353532566e-05));
  CHECK(*y.gyr_bias_random_walk == Approx(3.5640318696367613e-05));
  CHECK(*y.gravity_mps2 == Approx(9.80511));
  REQUIRE(y.lio_sam_n_scan);
  CHECK(*y.lio_sam_n_scan == 16);
  CHECK(y.ignored_keys == std::vector<std::string>{"lio_sam.pointCloudTopic"});
  // LIO-SAM rotates IMU vectors into the lidar axes with extrinsicRot and
  // puts the lidar at -extrinsicTrans from the IMU in those axes: an IMU
  // vector (1, 0, 0) is (-1, 0, 0) in the lidar frame, and the lidar origin
  // is at R^T t = (-0.1, 0.2, -0.3) in the IMU frame.
  REQUIRE(y.T_imu_lidar);
  const semlio::SE3d& T = *y.T_imu_lidar;
  CHECK((T.rotation().transpose() * Eigen::Vector3d::UnitX() - Eigen::Vector3d(-1, 0, 0)).norm() < 1e-12);
  CHECK((T.translation() - Eigen::Vector3d(-0.1, 0.2, -0.3)).norm() < 1e-12);
  semlio::PreintegrationConfig pc;
  y.apply_imu(pc);
  CHECK(pc.accel_noise_density_mps2_per_sqrthz == Approx(3.9939570888238808e-03));
  CHECK(pc.gyro_bias_walk_radps2_per_sqrthz == Approx(3.5640318696367613e-05));
  CHECK(pc.gravity_world_mps2.z() == Approx(-9.80511));
  // N_SCAN must agree with the table.
  CHECK_NOTHROW(semlio_examples::resolve_sensor(y, nullptr));
  const auto wrong = parse(lio.substr(0, lio.find("sensor:\n  profile")) + "sensor:\n  profile: os1-64\n");
  CHECK_THROWS_WITH(semlio_examples::resolve_sensor(wrong, nullptr),
                    Catch::Contains("N_SCAN = 16") && Catch::Contains("64 beams"));
  // The same keys without the lio_sam: root.
  const auto root = parse("imuAccNoise: 0.01\nextrinsicRot: [1, 0, 0, 0, 1, 0, 0, 0, 1]\nN_SCAN: 64\n");
  REQUIRE(root.acc_noise_density);
  CHECK(*root.acc_noise_density == 0.01);
  CHECK(root.T_imu_lidar->translation().norm() == 0.0);
}

TEST_CASE("sensor YAML: semlio's imu section", "[examples]") {
  const auto y = parse(
      "imu:\n"
      "  T_imu_lidar: [0, -1, 0, 0.5,  1, 0, 0, 0,  0, 0, 1, -0.2,  0, 0, 0, 1]\n"
      "  gyr_noise_density: 2.0e-4\n"
      "  gravity_mps2: 9.81\n");
  REQUIRE(y.T_imu_lidar);
  CHECK((y.T_imu_lidar->translation() - Eigen::Vector3d(0.5, 0.0, -0.2)).norm() < 1e-12);
  CHECK((y.T_imu_lidar->rotation() * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm() < 1e-12);
  CHECK(*y.gyr_noise_density == 2.0e-4);
  CHECK_FALSE(y.acc_noise_density);
}

TEST_CASE("sensor YAML: profile auto takes the detected table", "[examples]") {
  const auto y = parse("sensor:\n  profile: auto\n  platform: hand_held\n  rotation_rate_hz: 20\n");
  CHECK(y.detect);
  semlio::BeamDetection d;
  d.elevations_rad = {-0.2, -0.1, 0.0, 0.1};
  d.separable = true;
  const semlio::SensorProfile p = semlio_examples::resolve_sensor(y, &d);
  CHECK(p.name == "detected-4");
  CHECK(p.beams.elevations_rad == d.elevations_rad);
  CHECK(p.beams.rotation_rate_hz == 20.0);
  CHECK_THROWS_AS(semlio_examples::resolve_sensor(y, nullptr), semlio::ConfigError);
  const auto facts = semlio_examples::sensor_facts(p, y.motion, &d);
  CHECK(facts.front() == std::pair<std::string, std::string>{"profile", "detected-4"});
}

TEST_CASE("sensor YAML: profile auto takes the facts of the named profile the detected table matches",
          "[examples]") {
  const auto y = parse("sensor:\n  profile: auto\n");
  REQUIRE_FALSE(y.sensor);
  // The lower 25 beams of an OS1-32 (the upper ones saw sky), one a little off.
  const semlio::SensorModel os1 = semlio::sensor_profile("os1-32").beams;
  semlio::BeamDetection d;
  d.elevations_rad.assign(os1.elevations_rad.begin(), os1.elevations_rad.begin() + 25);
  d.elevations_rad[3] += 0.05 * kDeg;
  d.separable = true;
  d.source = semlio::BeamSource::kElevation;
  std::optional<semlio::ProfileMatch> match;
  const semlio::SensorProfile p = semlio_examples::resolve_sensor(y, &d, &match);
  REQUIRE(match);
  CHECK(p.name == "os1-32");
  REQUIRE(p.beams.beams() == 32);
  CHECK(p.beams.elevations_rad[3] == d.elevations_rad[3]);
  CHECK(p.beams.elevations_rad[31] == os1.elevations_rad[31]);
  CHECK(p.header_stamp == semlio::StampMeaning::kSweepStart);
  CHECK(p.max_range_m == semlio::sensor_profile("os1-32").max_range_m);
  CHECK(p.nominal_table);  // seven beams keep the datasheet's angles
  const auto facts = semlio_examples::sensor_facts(p, y.motion, &d, &*match);
  CHECK(std::find(facts.begin(), facts.end(), std::pair<std::string, std::string>{"matched_beams", "25 of 32"}) !=
        facts.end());
  // Uniform fallback bands are no sensor's table, even when they happen to fit one.
  semlio::BeamDetection bands = d;
  bands.separable = false;
  bands.source = semlio::BeamSource::kUniformFallback;
  const semlio::SensorProfile generic = semlio_examples::resolve_sensor(y, &bands, &match);
  CHECK_FALSE(match);
  CHECK(generic.name == "detected-25");
  CHECK(generic.max_range_m == 1000.0);
}

TEST_CASE("sensor YAML: configure_sensor detects, resolves and applies the settings", "[examples]") {
  // Four beams 5 deg apart on a 10 m cylinder: detection must find them.
  const auto scan = [](std::size_t) {
    semlio::Scan s;
    for (const double el_deg : {-10.0, -5.0, 0.0, 5.0}) {
      for (int c = 0; c < 720; ++c) {
        const double az = 2.0 * std::numbers::pi * c / 720.0;
        const double el = el_deg * kDeg;
        s.points.emplace_back(static_cast<float>(10.0 * std::cos(az)), static_cast<float>(10.0 * std::sin(az)),
                              static_cast<float>(10.0 * std::tan(el)));
      }
    }
    return s;
  };
  semlio::PipelineSettings settings;
  const auto setup = semlio_examples::configure_sensor(parse("sensor:\n  profile: auto\n  platform: hand_held\n"), 10,
                                                       scan, settings);
  REQUIRE(setup.detection);
  CHECK(setup.detection->separable);
  REQUIRE(setup.profile.beams.beams() == 4);
  CHECK(setup.profile.beams.elevations_rad[1] == Approx(-5.0 * kDeg).margin(1e-3 * kDeg));
  CHECK(settings.odometry.sensor.elevations_rad == setup.profile.beams.elevations_rad);
  CHECK(settings.odometry.max_angular_rate_radps == 2.0);
  CHECK_FALSE(settings.odometry.preprocess.crop_ego_box);
  CHECK(std::find(setup.facts.begin(), setup.facts.end(),
                  std::pair<std::string, std::string>{"detection", "elevation"}) != setup.facts.end());
  // A named profile reads no scan.
  semlio::PipelineSettings named;
  const auto none = [](std::size_t) -> semlio::Scan { throw std::logic_error("no scan expected"); };
  const auto vlp = semlio_examples::configure_sensor(parse("sensor:\n  profile: vlp16\n"), 10, none, named);
  CHECK_FALSE(vlp.detection);
  CHECK(named.odometry.sensor.beams() == 16);
  CHECK(named.odometry.preprocess.crop_ego_box);
}

TEST_CASE("sensor YAML: bad values name the file, the line and the key", "[examples]") {
  const std::string unknown = error_of("sensor:\n  profile: vlp16\n  elevation_deg: [1, 2]\n");
  CHECK_THAT(unknown, Catch::Contains("test.yaml:3") && Catch::Contains("sensor.elevation_deg"));
  CHECK_THAT(error_of("sensor:\n  profile: os3-64\n"),
             Catch::Contains("test.yaml:2") && Catch::Contains("os3-64") && Catch::Contains("os0-128"));
  CHECK_THAT(error_of("lio_sam:\n  imuAccNoise: abc\n"),
             Catch::Contains("test.yaml:2") && Catch::Contains("lio_sam.imuAccNoise"));
  CHECK_THAT(error_of("lio_sam:\n  extrinsicRot: [1, 0, 0, 0, 1, 0, 0, 0]\n"),
             Catch::Contains("lio_sam.extrinsicRot") && Catch::Contains("expected 9 numbers"));
  CHECK_THAT(error_of("lio_sam:\n  extrinsicRot: [1, 0, 0, 0, 1, 0, 0, 0, 2]\n"),
             Catch::Contains("not a rotation"));
  CHECK_THAT(error_of("sensor:\n  profile: vlp16\n  header_stamp: later\n"), Catch::Contains("sensor.header_stamp"));
  CHECK_THAT(error_of("sensor:\n  elevations_deg: [1, 1, 2]\n"), Catch::Contains("ascending"));
  CHECK_THAT(error_of("sensor:\n  profile: vlp16\n  rotation_rate_hz: -5\n"),
             Catch::Contains("sensor.rotation_rate_hz") && Catch::Contains("> 0"));
  CHECK_THAT(error_of("sensor:\n  platform: boat\n  profile: vlp16\n"), Catch::Contains("hand_held"));
  CHECK_THAT(error_of("imu:\n  gravity: 9.8\n"), Catch::Contains("imu.gravity"));
  CHECK_THAT(error_of("sensor:\n  platform: vehicle\n"), Catch::Contains("no beam table"));
  CHECK_THROWS_AS(semlio_examples::load_sensor_yaml("/nonexistent/semlio/sensor.yaml"), semlio::IoError);
  CHECK(semlio_examples::is_sensor_section("lio_sam"));
  CHECK_FALSE(semlio_examples::is_sensor_section("odometry"));
}

}  // namespace test_sensor_yaml
