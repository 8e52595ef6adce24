// Named lidar models (sim/lidar.hpp lidar_config_for): beam layouts against
// the datasheets, per-point ring and time of simulated scans, firing order.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/sim/lidar.hpp>
#include <semlio/sim/simulator.hpp>

namespace test_sensors {  // one namespace per test file: the area compiles as one TU

using semlio::sim::Lidar;
using semlio::sim::LidarConfig;
using semlio::sim::lidar_config_for;

namespace {

double deg(double rad) { return rad * 180.0 / std::numbers::pi; }

std::vector<double> elevations_deg(const Lidar& lidar) {
  std::vector<double> out;
  for (int r = 0; r < lidar.rings(); ++r) out.push_back(deg(lidar.elevation_rad(r)));
  return out;
}

}  // namespace

TEST_CASE("uniform sensors: beam count, extent and spacing from their datasheets", "[sim][sensors]") {
  struct Expect {
    const char* name;
    int beams;
    double bottom_deg;
    double step_deg;
    int columns;
    double max_range_m;
  };
  // Datasheet figures, typed in independently of lidar.hpp's formulas.
  const Expect cases[] = {
      {"vlp16", 16, -15.0, 2.0, 1800, 100.0},       // VLP-16: -15..+15 by 2 deg, 0.2 deg at 10 Hz
      {"hdl32e", 32, -30.67, 4.0 / 3.0, 2170, 100.0},  // HDL-32E: -30.67..+10.67 by 4/3 deg
      {"os1-64", 64, -22.5, 45.0 / 63.0, 1024, 120.0},  // OS1-64: 45 deg uniform
      {"os0-128", 128, -45.0, 90.0 / 127.0, 1024, 50.0},  // OS0-128: 90 deg uniform
  };
  for (const Expect& e : cases) {
    INFO(e.name);
    const Lidar lidar(lidar_config_for(e.name));
    REQUIRE(lidar.rings() == e.beams);
    CHECK(lidar.columns() == e.columns);
    CHECK(lidar.period_s() == Approx(0.1));
    CHECK(lidar.config().max_range_m == e.max_range_m);
    CHECK(lidar.config().mount_height_m == Approx(1.8));
    const std::vector<double> el = elevations_deg(lidar);
    for (int r = 0; r < e.beams; ++r) {
      CHECK(el[static_cast<std::size_t>(r)] == Approx(e.bottom_deg + e.step_deg * r).margin(1e-9));
    }
  }
  // The extents the datasheets quote.
  CHECK(deg(Lidar(lidar_config_for("vlp16")).elevation_rad(15)) == Approx(15.0));
  // The datasheet's "+10.67" is -30.67 + 31 * 4/3 = 10.663 rounded (the real
  // HDL-32E pair in tests/data/scan_pair sits on the 4/3 grid to 0.01 deg).
  CHECK(deg(Lidar(lidar_config_for("hdl32e")).elevation_rad(31)) == Approx(10.67).margin(0.01));
  CHECK(deg(Lidar(lidar_config_for("os1-64")).elevation_rad(63)) == Approx(22.5));
  CHECK(deg(Lidar(lidar_config_for("os0-128")).elevation_rad(127)) == Approx(45.0));
}

TEST_CASE("VLP-32C: the manual's non-uniform table, dense around the horizon", "[sim][sensors]") {
  const Lidar lidar(lidar_config_for("vlp32c"));
  REQUIRE(lidar.rings() == 32);
  CHECK(lidar.columns() == 1800);
  CHECK(lidar.config().max_range_m == 200.0);
  const std::vector<double> el = elevations_deg(lidar);
  // VLP-32C user manual, vertical angles by laser id (sorted here): lowest
  // -25, then -15.639, -11.31; 0 deg is the 21st beam; highest 10.333, 15.
  CHECK(el.front() == Approx(-25.0));
  CHECK(el[1] == Approx(-15.639));
  CHECK(el[2] == Approx(-11.31));
  CHECK(el[20] == Approx(0.0).margin(1e-12));
  CHECK(el[30] == Approx(10.333));
  CHECK(el.back() == Approx(15.0));
  for (std::size_t r = 1; r < el.size(); ++r) CHECK(el[r] > el[r - 1]);
  // Non-uniform: 1/3 deg apart near the horizon, ~9.6 deg apart at the bottom.
  CHECK(el[21] - el[20] == Approx(0.333));
  CHECK(el[1] - el[0] == Approx(9.361));
}

TEST_CASE("hdl64e by name is exactly the default model", "[sim][sensors]") {
  const Lidar by_name(lidar_config_for("hdl64e"));
  const Lidar default_model;
  REQUIRE(by_name.rings() == default_model.rings());
  for (int r = 0; r < 64; ++r) CHECK(by_name.elevation_rad(r) == default_model.elevation_rad(r));
  CHECK(by_name.columns() == default_model.columns());
  CHECK(by_name.config().mount_height_m == 1.73);
  for (const auto name : semlio::sim::kLidarSensors) CHECK_NOTHROW(Lidar(lidar_config_for(name)));
  CHECK(semlio::sim::lidar_is_ouster("os1-64"));
  CHECK_FALSE(semlio::sim::lidar_is_ouster("vlp16"));
}

TEST_CASE("bad sensor names and beam tables throw ConfigError naming the value", "[sim][sensors]") {
  try {
    (void)lidar_config_for("vlp64");
    FAIL("no exception");
  } catch (const semlio::ConfigError& e) {
    CHECK_THAT(e.what(), Catch::Contains("vlp64") && Catch::Contains("os0-128"));
  }
  LidarConfig c = lidar_config_for("vlp32c");
  c.beams = 31;
  CHECK_THROWS_AS(Lidar(c), semlio::ConfigError);
  c = lidar_config_for("vlp32c");
  std::swap(c.elevations_deg[3], c.elevations_deg[4]);  // not ascending
  try {
    (void)Lidar(c);
    FAIL("no exception");
  } catch (const semlio::ConfigError& e) {
    CHECK_THAT(e.what(), Catch::Contains("elevations_deg[4]"));
  }
  c = lidar_config_for("vlp32c");
  c.elevations_deg.back() = 95.0;
  CHECK_THROWS_AS(Lidar(c), semlio::ConfigError);
}

TEST_CASE("simulated scans: ring and time per point follow the beam table and the clockwise spin",
          "[sim][sensors]") {
  for (const char* name : {"vlp16", "vlp32c", "os1-64"}) {
    INFO(name);
    semlio::sim::SimulatorConfig c;
    c.frames = 3;
    c.traffic = semlio::sim::TrafficLevel::kNone;
    c.lidar = lidar_config_for(name);
    const semlio::sim::Simulator sim(c);
    const semlio::sim::Frame f = sim.frame(1);
    const semlio::Scan& s = f.scan;
    const int rings = sim.lidar().rings();
    const double period = sim.lidar().period_s();
    REQUIRE(s.size() > 1000);
    REQUIRE(s.rings.size() == s.size());
    REQUIRE(s.times_s.size() == s.size());
    CHECK(s.stamp_s == Approx(0.1));
    std::vector<int> per_ring(static_cast<std::size_t>(rings), 0);
    double worst_elevation = 0.0;
    double worst_time = 0.0;
    for (std::size_t i = 0; i < s.size(); ++i) {
      const Eigen::Vector3d p = s.points[i].cast<double>();
      const int r = s.rings[i];
      REQUIRE(r < rings);
      ++per_ring[static_cast<std::size_t>(r)];
      const double el = std::atan2(p.z(), std::hypot(p.x(), p.y()));
      worst_elevation = std::max(worst_elevation, std::abs(el - sim.lidar().elevation_rad(r)));
      // Clockwise from azimuth +180 deg: t = period * ((pi - az) mod 2 pi) / 2 pi.
      double a = std::numbers::pi - std::atan2(p.y(), p.x());
      a -= 2.0 * std::numbers::pi * std::floor(a / (2.0 * std::numbers::pi));
      const double t_expect = period * a / (2.0 * std::numbers::pi);
      double d = std::abs(static_cast<double>(s.times_s[i]) - t_expect);
      d = std::min(d, period - d);  // the seam behind the car
      worst_time = std::max(worst_time, d);
      REQUIRE(s.times_s[i] >= 0.0F);
      REQUIRE(s.times_s[i] < static_cast<float>(period));
    }
    CHECK(worst_elevation < 1e-5);  // float points: ~1e-7 relative
    CHECK(worst_time < 1e-6);
    // Every beam that looks at the world returns points (the lowest beams of
    // the OS1 partly hit the car body).
    const auto empty = std::count(per_ring.begin(), per_ring.end(), 0);
    CHECK(empty == 0);
  }
}

TEST_CASE("firing order: one time per column, all beams of a column together", "[sim][sensors]") {
  const Lidar ouster(lidar_config_for("os1-64"));
  // 1024 columns at 10 Hz: 97.66 us apart; the 512th faces forward at 50 ms.
  CHECK(ouster.column_time_s(1) == Approx(0.1 / 1024.0));
  CHECK(ouster.column_time_s(512) == Approx(0.05));
  CHECK(ouster.direction(32, 512).x() > 0.99);
  CHECK(ouster.direction(32, 0).x() < -0.99);
  CHECK(ouster.direction(32, 256).y() > 0.99);  // a quarter turn clockwise from behind: left
  const Lidar vlp(lidar_config_for("vlp16"));
  CHECK(vlp.column_time_s(900) == Approx(0.05));
  // Simulated VLP-16 scan: points of one column share their time across rings.
  semlio::sim::SimulatorConfig c;
  c.frames = 2;
  c.traffic = semlio::sim::TrafficLevel::kNone;
  c.lidar = lidar_config_for("vlp16");
  const semlio::sim::Simulator sim(c);
  const semlio::sim::Frame f = sim.frame(0);
  std::vector<float> column_time(static_cast<std::size_t>(sim.lidar().columns()), -1.0F);
  std::size_t shared = 0;
  std::size_t differ = 0;
  std::size_t off_column = 0;
  for (std::size_t i = 0; i < f.scan.size(); ++i) {
    float& t = column_time[f.columns[i]];
    if (t >= 0.0F) {
      differ += t != f.scan.times_s[i] ? 1U : 0U;
      ++shared;
    }
    t = f.scan.times_s[i];
    off_column += f.scan.times_s[i] != static_cast<float>(sim.lidar().column_time_s(f.columns[i])) ? 1U : 0U;
  }
  CHECK(shared > f.scan.size() / 2);
  CHECK(differ == 0);
  CHECK(off_column == 0);
}

}  // namespace test_sensors
