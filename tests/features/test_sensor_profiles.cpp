#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <string>

#include <semlio/core/error.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/features/sensor_profiles.hpp>

namespace test_sensor_profiles {  // one namespace per test file: the area compiles as one TU

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double deg(double rad) { return rad / kDeg; }

}  // namespace

TEST_CASE("every named sensor profile is valid and has the beam count of its name", "[features]") {
  for (const std::string& name : semlio::sensor_profile_names()) {
    INFO(name);
    const semlio::SensorProfile p = semlio::sensor_profile(name);
    CHECK(p.name == name);
    CHECK_NOTHROW(p.validate());
    // The number at the end of the name is the beam count, except for the
    // Velodyne models whose names carry none (hdl64e 64, hdl32e 32, vlp16 16, vlp32c 32).
    std::size_t expected = 0;
    if (name == "hdl64e") expected = 64;
    else if (name == "hdl32e" || name == "vlp32c") expected = 32;
    else if (name == "vlp16") expected = 16;
    else expected = static_cast<std::size_t>(std::stoi(name.substr(name.find_last_not_of("0123456789") + 1)));
    CHECK(p.beams.beams() == expected);
    CHECK(p.sweep_period_s() == Approx(0.1));
  }
}

TEST_CASE("Ouster profiles spread their beams uniformly over the published field of view", "[features]") {
  const struct {
    const char* family;
    double fov_deg;
  } families[] = {{"os0", 90.0}, {"os1", 45.0}, {"os2", 22.5}};
  for (const auto& f : families) {
    for (const int beams : {32, 64, 128}) {
      const std::string name = std::string(f.family) + "-" + std::to_string(beams);
      INFO(name);
      const semlio::SensorProfile p = semlio::sensor_profile(name);
      CHECK(deg(p.vertical_fov_rad()) == Approx(f.fov_deg).margin(1e-9));
      CHECK(deg(p.beams.elevations_rad.front()) == Approx(-f.fov_deg / 2.0).margin(1e-9));
      const double step = f.fov_deg / (beams - 1);
      for (std::size_t i = 1; i < p.beams.beams(); ++i) {
        CHECK(deg(p.beams.elevations_rad[i] - p.beams.elevations_rad[i - 1]) == Approx(step).margin(1e-9));
      }
      CHECK(p.nominal_table);
      CHECK(p.header_stamp == semlio::StampMeaning::kSweepStart);
    }
  }
}

TEST_CASE("Velodyne and Hesai tables match their manuals", "[features]") {
  const semlio::SensorProfile vlp16 = semlio::sensor_profile("vlp16");
  for (std::size_t i = 0; i < 16; ++i) CHECK(deg(vlp16.beams.elevations_rad[i]) == Approx(-15.0 + 2.0 * i));
  CHECK(vlp16.header_stamp == semlio::StampMeaning::kSweepEnd);

  const semlio::SensorProfile vlp32c = semlio::sensor_profile("vlp32c");
  CHECK(deg(vlp32c.beams.elevations_rad.front()) == Approx(-25.0));
  CHECK(deg(vlp32c.beams.elevations_rad.back()) == Approx(15.0));
  // Densest near the horizon: 1/3 deg between -4 and +1.667 deg (VLP-32C manual).
  CHECK(deg(vlp32c.beams.elevations_rad[21] - vlp32c.beams.elevations_rad[20]) == Approx(0.333).margin(1e-3));
  CHECK(deg(vlp32c.beams.elevations_rad[1] - vlp32c.beams.elevations_rad[0]) > 9.0);

  const semlio::SensorProfile xt32 = semlio::sensor_profile("pandar-xt32");
  CHECK(deg(xt32.beams.elevations_rad.front()) == Approx(-16.0));
  CHECK(deg(xt32.beams.elevations_rad.back()) == Approx(15.0));

  const semlio::SensorProfile p64 = semlio::sensor_profile("pandar64");
  CHECK(deg(p64.beams.elevations_rad.front()) == Approx(-24.897));
  CHECK(deg(p64.beams.elevations_rad.back()) == Approx(14.882));

  const semlio::SensorProfile hdl64e = semlio::sensor_profile("hdl64e");
  CHECK(hdl64e.beams.elevations_rad == semlio::SensorModel::hdl64e().elevations_rad);
  CHECK(semlio::sensor_profile("hdl32e").beams.elevations_rad == semlio::SensorModel::hdl32e().elevations_rad);
}

TEST_CASE("an unknown sensor profile names the known ones", "[features]") {
  try {
    (void)semlio::sensor_profile("os3-64");
    FAIL("no error");
  } catch (const semlio::ConfigError& e) {
    const std::string what = e.what();
    CHECK(what.find("os3-64") != std::string::npos);
    CHECK(what.find("os0-128") != std::string::npos);
    CHECK(what.find("pandar64") != std::string::npos);
  }
  semlio::SensorProfile bad = semlio::sensor_profile("vlp16");
  bad.max_range_m = 0.1;
  CHECK_THROWS_AS(bad.validate(), semlio::ConfigError);
  bad = semlio::sensor_profile("vlp16");
  bad.beams.elevations_rad[3] = bad.beams.elevations_rad[2];  // not ascending
  CHECK_THROWS_AS(bad.validate(), semlio::ConfigError);
}

TEST_CASE("per-point time from a profile's spin and start azimuth", "[features]") {
  // Ouster: clockwise from the rear (azimuth pi) at 10 Hz. A point just
  // clockwise of the rear is early in the sweep, one just counter-clockwise
  // of it late; straight ahead is half a sweep in.
  const semlio::SensorProfile os0 = semlio::sensor_profile("os0-64");
  semlio::Scan scan;
  const auto at = [](double az) {
    return Eigen::Vector3f(static_cast<float>(5.0 * std::cos(az)), static_cast<float>(5.0 * std::sin(az)), 0.5F);
  };
  scan.points = {at(std::numbers::pi - 0.1), at(-std::numbers::pi + 0.1), at(0.0), at(std::numbers::pi / 2.0)};
  semlio::assign_times_from_azimuth(scan, os0.point_time_config());
  REQUIRE(scan.times_s.size() == 4);
  CHECK(scan.times_s[0] == Approx(0.1 * 0.1 / (2.0 * std::numbers::pi)).margin(1e-5));
  CHECK(scan.times_s[1] == Approx(0.1 - 0.1 * 0.1 / (2.0 * std::numbers::pi)).margin(1e-5));
  CHECK(scan.times_s[2] == Approx(0.05).margin(1e-5));
  CHECK(scan.times_s[3] == Approx(0.025).margin(1e-5));  // a quarter turn clockwise from the rear: +y

  // Velodyne: clockwise from the front, as KITTI raw.
  const semlio::PointTimeConfig v = semlio::sensor_profile("vlp16").point_time_config();
  CHECK(v.start_azimuth_rad == 0.0);
  CHECK_FALSE(v.counter_clockwise);
  CHECK(v.sweep_period_s == Approx(0.1));
}

}  // namespace test_sensor_profiles
