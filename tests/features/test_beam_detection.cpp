#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/features/beam_detection.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/features/sensor_profiles.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/ply.hpp>
#include <semlio_test/data.hpp>

namespace test_beam_detection {  // one namespace per test file: the area compiles as one TU

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// A sweep of `table` inside an axis-aligned room (half sizes hx, hy; floor
// `below` m under the sensor, ceiling `above` over it), `columns` firings per
// beam. Each beam starts `offset_m` from the axis along its azimuth (Ouster's
// beam origin), so near points seen from the origin lean towards the horizon.
semlio::Scan room_sweep(const semlio::SensorModel& table, int columns, double offset_m, double hx = 9.0,
                        double hy = 6.0, double below = 1.5, double above = 2.5,
                        std::vector<std::uint16_t>* beam_of_point = nullptr) {
  semlio::Scan s;
  for (int c = 0; c < columns; ++c) {
    const double az = std::numbers::pi - 2.0 * std::numbers::pi * c / columns;  // clockwise from the rear
    for (std::size_t b = 0; b < table.beams(); ++b) {
      const double el = table.elevations_rad[b];
      if (beam_of_point != nullptr) beam_of_point->push_back(static_cast<std::uint16_t>(b));
      const Eigen::Vector3d o(offset_m * std::cos(az), offset_m * std::sin(az), 0.0);
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      double t = 1e9;
      const auto wall = [&](double oc, double dc, double lo, double hi) {
        if (dc > 1e-12) t = std::min(t, (hi - oc) / dc);
        if (dc < -1e-12) t = std::min(t, (lo - oc) / dc);
      };
      wall(o.x(), d.x(), -hx, hx);
      wall(o.y(), d.y(), -hy, hy);
      wall(o.z(), d.z(), -below, above);
      s.points.push_back((o + t * d).cast<float>());
    }
  }
  return s;
}

}  // namespace

TEST_CASE("beam detection finds the 64 beams of a simulated OS0 despite its beam-origin offset", "[features]") {
  // Ouster's beams leave the sensor 27.67 mm off its axis: at 2 m the
  // elevation seen from the origin is ~0.4 deg closer to the horizon (the
  // satellites of the BALM recording, beam_detection.hpp).
  const semlio::SensorModel table = semlio::sensor_profile("os0-64").beams;
  std::vector<std::uint16_t> beam_of_point;
  const std::vector<semlio::Scan> scans = {room_sweep(table, 1024, 0.02767, 9.0, 6.0, 1.5, 2.5, &beam_of_point)};
  const semlio::BeamDetection d = semlio::detect_beams(scans);
  INFO(d.note);
  CHECK(d.source == semlio::BeamSource::kElevation);
  CHECK(d.separable);
  REQUIRE(d.beams() == 64);
  // Seen from the origin, each beam's points lie between its true elevation
  // and up to ~0.5 deg nearer the horizon (the floor 1.5 m under a -45 deg
  // beam: atan(1.5 / 1.528) = 44.48 deg). The detected beam must sit at the
  // median of its own points' elevations.
  std::vector<std::vector<double>> seen(64);
  for (std::size_t i = 0; i < beam_of_point.size(); ++i) {
    const Eigen::Vector3f& p = scans[0].points[i];
    seen[beam_of_point[i]].push_back(std::atan2(static_cast<double>(p.z()), std::hypot(static_cast<double>(p.x()),
                                                                                       static_cast<double>(p.y()))));
  }
  for (std::size_t b = 0; b < 64; ++b) {
    INFO("beam " << b);
    std::sort(seen[b].begin(), seen[b].end());
    CHECK(d.elevations_rad[b] == Approx(seen[b][seen[b].size() / 2]).margin(0.1 * kDeg));
    CHECK(std::abs(d.elevations_rad[b]) <= std::abs(table.elevations_rad[b]) + 0.01 * kDeg);
  }
  CHECK(d.fit_fraction > 0.9);
  CHECK(d.median_spacing_rad == Approx(90.0 / 63.0 * kDeg).epsilon(0.05));
  // Without the offset every point lies on its beam.
  const semlio::BeamDetection exact = semlio::detect_beams({room_sweep(table, 1024, 0.0)});
  REQUIRE(exact.beams() == 64);
  CHECK(exact.fit_fraction > 0.999);
  CHECK(exact.rms_residual_rad < 0.01 * kDeg);
}

TEST_CASE("beam detection falls back to the best single scan when a smeared one hides the beams", "[features]") {
  // A still sweep and a sweep whose points spread over the whole field of
  // view (a fast turn, motion-compensated): pooled, the peaks explain too few
  // points; the still sweep alone gives the table.
  const semlio::SensorModel table = semlio::sensor_profile("os0-64").beams;
  semlio::Scan smeared;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> el(-45.0 * kDeg, 45.0 * kDeg);
  std::uniform_real_distribution<double> az(-std::numbers::pi, std::numbers::pi);
  for (int i = 0; i < 200000; ++i) {
    const double e = el(rng);
    const double a = az(rng);
    smeared.points.emplace_back(static_cast<float>(6.0 * std::cos(e) * std::cos(a)),
                                static_cast<float>(6.0 * std::cos(e) * std::sin(a)), static_cast<float>(6.0 * std::sin(e)));
  }
  const semlio::BeamDetection d = semlio::detect_beams({smeared, room_sweep(table, 1024, 0.0)});
  INFO(d.note);
  CHECK(d.source == semlio::BeamSource::kElevation);
  REQUIRE(d.beams() == 64);
  CHECK(d.note.find("scan 1 alone") != std::string::npos);
  for (std::size_t i = 0; i < 64; ++i) CHECK(d.elevations_rad[i] == Approx(table.elevations_rad[i]).margin(0.01 * kDeg));
  CHECK(d.fit_fraction < 0.8);  // reported over every point, the smeared ones included
  // The smeared sweep alone: not separable.
  CHECK_FALSE(semlio::detect_beams({smeared}).separable);
}

TEST_CASE("beam detection resolves the VLP-32C's 1/3 deg beams near the horizon", "[features]") {
  const semlio::SensorModel table = semlio::sensor_profile("vlp32c").beams;
  const semlio::BeamDetection d = semlio::detect_beams({room_sweep(table, 1800, 0.0, 30.0, 20.0, 1.8, 30.0)});
  INFO(d.note);
  CHECK(d.source == semlio::BeamSource::kElevation);
  REQUIRE(d.beams() == 32);
  for (std::size_t i = 0; i < 32; ++i) CHECK(d.elevations_rad[i] == Approx(table.elevations_rad[i]).margin(0.02 * kDeg));
}

TEST_CASE("beam detection on the real 32-beam scan pair gives the HDL-32E table", "[features]") {
  std::vector<semlio::Scan> scans;
  for (const char* name : {"source.ply", "target.ply"}) {
    scans.push_back(semlio::io::read_ply(semlio_test::data_path(std::string("scan_pair/") + name)));
  }
  const semlio::BeamDetection d = semlio::detect_beams(scans);
  INFO(d.note);
  CHECK(d.source == semlio::BeamSource::kElevation);
  CHECK(d.scans == 2);
  REQUIRE(d.beams() == 32);
  const semlio::SensorModel hdl32e = semlio::SensorModel::hdl32e();
  for (std::size_t i = 0; i < 32; ++i) CHECK(d.elevations_rad[i] == Approx(hdl32e.elevations_rad[i]).margin(0.02 * kDeg));
  CHECK(d.fit_fraction > 0.99);
  // Only finite, non-zero points are counted.
  std::size_t usable = 0;
  for (const semlio::Scan& s : scans) {
    for (const Eigen::Vector3f& p : s.points) usable += (p.allFinite() && !p.isZero(0.0F)) ? 1U : 0U;
  }
  CHECK(d.points == usable);
}

TEST_CASE("beam detection on real KITTI scans falls back to point order", "[features]") {
  std::vector<semlio::Scan> scans;
  for (const char* name : {"000000.bin", "000001.bin"}) {
    scans.push_back(semlio::io::read_kitti_bin(semlio_test::data_path(std::string("kitti/sequences/00/velodyne/") + name)));
  }
  const semlio::BeamDetection d = semlio::detect_beams(scans);
  INFO(d.note);
  // KITTI's calibrated HDL-64E does not leave gaps between its upper-block
  // beams seen from the origin: elevation peaks cannot explain the points.
  CHECK(d.elevation_fit_fraction < 0.8);
  CHECK(d.source == semlio::BeamSource::kPointOrder);
  CHECK(d.order_rings == 64);
  REQUIRE(d.beams() == 64);
  // The per-ring median elevations span the HDL-64E's field of view (-24.9 .. +2 deg nominal).
  CHECK(d.elevations_rad.front() < -22.0 * kDeg);
  CHECK(d.elevations_rad.back() > 1.0 * kDeg);
  CHECK(d.elevations_rad.back() < 4.0 * kDeg);
  CHECK(d.fit_fraction > 0.0);
  CHECK(d.fit_fraction < 1.0);
  CHECK_NOTHROW(d.sensor_model());
}

TEST_CASE("a non-repetitive pattern is reported as not separable and gets elevation bands", "[features]") {
  // A Livox-like pattern: elevations uniformly random over 38 deg.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> el(-7.0 * kDeg, 31.0 * kDeg);
  std::uniform_real_distribution<double> az(-0.6, 0.6);
  semlio::Scan s;
  for (int i = 0; i < 40000; ++i) {
    const double e = el(rng);
    const double a = az(rng);
    s.points.emplace_back(static_cast<float>(10.0 * std::cos(e) * std::cos(a)),
                          static_cast<float>(10.0 * std::cos(e) * std::sin(a)), static_cast<float>(10.0 * std::sin(e)));
  }
  const semlio::BeamDetection d = semlio::detect_beams({s});
  INFO(d.note);
  CHECK_FALSE(d.separable);
  CHECK(d.source == semlio::BeamSource::kUniformFallback);
  CHECK(d.note.find("not separable") != std::string::npos);
  CHECK(d.beams() >= 30);  // ~1 deg bands over ~37 deg
  CHECK(d.beams() <= 40);
  CHECK(d.median_spacing_rad == Approx(1.0 * kDeg).epsilon(0.1));
  // The bands still work as rings: every point gets one.
  const semlio::SensorModel bands = d.sensor_model();
  semlio::infer_rings(s, bands, semlio::RingConfig{.method = semlio::RingMethod::kElevation});
  CHECK(std::all_of(s.rings.begin(), s.rings.end(), [&](std::uint16_t r) { return r < bands.beams(); }));
}

TEST_CASE("beam detection uses a ring field when the scans carry one", "[features]") {
  const semlio::SensorModel table = semlio::sensor_profile("vlp16").beams;
  semlio::Scan s = room_sweep(table, 900, 0.0);
  for (std::size_t i = 0; i < s.size(); ++i) s.rings.push_back(static_cast<std::uint16_t>(i % 16));
  const semlio::BeamDetection d = semlio::detect_beams({s});
  INFO(d.note);
  CHECK(d.source == semlio::BeamSource::kScanRings);
  REQUIRE(d.beams() == 16);
  for (std::size_t i = 0; i < 16; ++i) CHECK(d.elevations_rad[i] == Approx(table.elevations_rad[i]).margin(1e-4));
  CHECK(d.fit_fraction == 1.0);
}

TEST_CASE("beam detection rejects bad settings and reports empty input", "[features]") {
  CHECK_THROWS_AS(semlio::BeamDetector(semlio::BeamDetectionConfig{.min_fit_fraction = 1.5}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::BeamDetector(semlio::BeamDetectionConfig{.bin_rad = 0.0}), semlio::ConfigError);
  semlio::Scan zeros;
  zeros.points.assign(100, Eigen::Vector3f::Zero());
  const semlio::BeamDetection d = semlio::detect_beams({zeros, semlio::Scan{}});
  CHECK(d.beams() == 0);
  CHECK(d.points == 0);
  CHECK_FALSE(d.separable);
  CHECK(d.note == "no usable points");
  CHECK_THROWS_AS(d.sensor_model(), semlio::ConfigError);
  semlio::Scan bad;
  bad.points.assign(3, Eigen::Vector3f::Ones());
  bad.rings.assign(2, 0);  // inconsistent fields
  semlio::BeamDetector detector;
  CHECK_THROWS_AS(detector.add(bad), semlio::ValueError);
}

}  // namespace test_beam_detection
