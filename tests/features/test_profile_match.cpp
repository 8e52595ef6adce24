#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/features/beam_detection.hpp>
#include <semlio/features/profile_match.hpp>
#include <semlio/features/sensor_profiles.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/ply.hpp>
#include <semlio_test/data.hpp>

namespace test_profile_match {  // one namespace per test file: the area compiles as one TU

constexpr double kDeg = std::numbers::pi / 180.0;

std::vector<double> table_of(const std::string& name) { return semlio::sensor_profile(name).beams.elevations_rad; }

TEST_CASE("every named profile's own table matches that profile", "[features]") {
  for (const std::string& name : semlio::sensor_profile_names()) {
    INFO(name);
    const std::optional<semlio::ProfileMatch> m = semlio::match_sensor_profile(table_of(name));
    REQUIRE(m.has_value());
    CHECK(m->profile == name);
    CHECK(m->matched == m->profile_beams);
    CHECK(m->rms_rad == 0.0);
  }
}

TEST_CASE("a real unit's table, up to a degree from the datasheet's, matches its profile", "[features]") {
  // Ouster's nominal OS0-64 moved as the BALM recording's unit is
  // (profile_match.hpp): spacing alternating around the nominal one, up to
  // ~1 deg off at the bottom.
  std::vector<double> unit = table_of("os0-64");
  for (std::size_t i = 0; i < unit.size(); ++i) {
    const double trend = 0.9 * kDeg * std::cos(static_cast<double>(i) / 63.0 * std::numbers::pi);
    unit[i] += trend + (i % 2 == 0 ? 0.15 : -0.15) * kDeg;
  }
  const std::optional<semlio::ProfileMatch> m = semlio::match_sensor_profile(unit);
  REQUIRE(m.has_value());
  CHECK(m->profile == "os0-64");
  CHECK(m->max_rad > 0.9 * kDeg);
  // The completed table is the unit's own: every beam was seen.
  const semlio::SensorModel t = m->completed_table(semlio::sensor_profile("os0-64").beams, unit);
  CHECK(t.elevations_rad == unit);
  // On the 45 deg of an OS1, 1 deg off (2.2 % of the field of view) still
  // matches; 2.5 deg (5.6 %) does not.
  std::vector<double> os1 = table_of("os1-64");
  for (double& e : os1) e += 1.0 * kDeg;
  CHECK(semlio::match_profile(os1, semlio::sensor_profile("os1-64")).matches);
  for (double& e : os1) e += 1.5 * kDeg;
  CHECK_FALSE(semlio::match_profile(os1, semlio::sensor_profile("os1-64")).matches);
}

TEST_CASE("beams the first scans did not see are completed from the profile", "[features]") {
  // An OS0-128 in a street: the upper 35 beams see sky.
  const std::vector<double> full = table_of("os0-128");
  std::vector<double> seen(full.begin(), full.begin() + 93);
  seen[10] += 0.1 * kDeg;  // a unit's own angle, within 0.3 of the 0.71 deg spacing
  const std::optional<semlio::ProfileMatch> m = semlio::match_sensor_profile(seen);
  REQUIRE(m.has_value());
  CHECK(m->profile == "os0-128");
  CHECK(m->matched == 93);
  CHECK(m->profile_beams == 128);
  CHECK(m->matched_fraction() == Approx(93.0 / 128.0));
  const semlio::SensorModel t = m->completed_table(semlio::sensor_profile("os0-128").beams, seen);
  REQUIRE(t.beams() == 128);
  CHECK(t.elevations_rad[10] == seen[10]);
  CHECK(t.elevations_rad[127] == full[127]);
  CHECK_NOTHROW(t.validate());
  // Too few beams seen to say which sensor it is.
  const std::vector<double> half(full.begin(), full.begin() + 70);
  CHECK_FALSE(semlio::match_profile(half, semlio::sensor_profile("os0-128")).matches);
}

TEST_CASE("a VLP-16 is a VLP-16, not half a PandarXT-32 with the same angles", "[features]") {
  const std::vector<double> vlp16 = table_of("vlp16");
  const semlio::ProfileMatch xt32 = semlio::match_profile(vlp16, semlio::sensor_profile("pandar-xt32"));
  CHECK(xt32.matched == 16);  // every VLP-16 angle is a PandarXT-32 angle
  CHECK_FALSE(xt32.matches);  // but 16 of 32 is not enough
  const std::optional<semlio::ProfileMatch> m = semlio::match_sensor_profile(vlp16);
  REQUIRE(m.has_value());
  CHECK(m->profile == "vlp16");
}

TEST_CASE("a table of no known sensor matches none", "[features]") {
  // 40 beams evenly over 30 deg.
  std::vector<double> odd;
  for (int i = 0; i < 40; ++i) odd.push_back((-20.0 + 30.0 * i / 39.0) * kDeg);
  CHECK_FALSE(semlio::match_sensor_profile(odd).has_value());
  // A known table with one beam that sensor does not have.
  std::vector<double> extra = table_of("os1-32");
  extra.push_back(30.0 * kDeg);
  CHECK_FALSE(semlio::match_profile(extra, semlio::sensor_profile("os1-32")).matches);
  // A known table with a beam moved half-way to its neighbour (subset rule).
  const std::vector<double> os0 = table_of("os0-128");
  std::vector<double> moved(os0.begin(), os0.begin() + 100);
  moved[50] += 0.35 * kDeg;
  CHECK_FALSE(semlio::match_profile(moved, semlio::sensor_profile("os0-128")).matches);
  CHECK_FALSE(semlio::match_sensor_profile({}).has_value());
  semlio::ProfileMatch none = semlio::match_profile(odd, semlio::sensor_profile("os1-64"));
  CHECK_THROWS_AS(none.completed_table(semlio::sensor_profile("os1-64").beams, odd), semlio::ValueError);
}

TEST_CASE("detected tables of real scans match their sensors", "[features]") {
  // The real HDL-32E scan pair: elevation clusters, the datasheet table.
  std::vector<semlio::Scan> pair;
  for (const char* name : {"source.ply", "target.ply"}) {
    pair.push_back(semlio::io::read_ply(semlio_test::data_path(std::string("scan_pair/") + name)));
  }
  const std::optional<semlio::ProfileMatch> hdl32 = semlio::match_sensor_profile(semlio::detect_beams(pair).elevations_rad);
  REQUIRE(hdl32.has_value());
  CHECK(hdl32->profile == "hdl32e");
  // Real KITTI: point-order rings whose median elevations (seen from the
  // origin, KITTI's per-unit calibration) lie within 5 % of the field of view
  // of the nominal HDL-64E's.
  std::vector<semlio::Scan> kitti;
  for (const char* name : {"000000.bin", "000001.bin"}) {
    kitti.push_back(
        semlio::io::read_kitti_bin(semlio_test::data_path(std::string("kitti/sequences/00/velodyne/") + name)));
  }
  const semlio::BeamDetection d = semlio::detect_beams(kitti);
  REQUIRE(d.source == semlio::BeamSource::kPointOrder);
  const std::optional<semlio::ProfileMatch> hdl64 = semlio::match_sensor_profile(d.elevations_rad);
  REQUIRE(hdl64.has_value());
  CHECK(hdl64->profile == "hdl64e");
  CHECK(hdl64->max_rad > 0.3 * kDeg);  // not the nominal table: the reason for the index rule
}

TEST_CASE("profile matching rejects bad settings", "[features]") {
  const std::vector<double> t = table_of("vlp16");
  const semlio::SensorProfile p = semlio::sensor_profile("vlp16");
  CHECK_THROWS_AS(semlio::match_profile(t, p, {.spacing_fraction = 0.5}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::match_profile(t, p, {.index_tolerance_fov_fraction = 0.0}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::match_profile(t, p, {.max_tolerance_rad = std::nan("")}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::match_profile(t, p, {.min_matched_fraction = 1.5}), semlio::ConfigError);
}

}  // namespace test_profile_match
