// Scan Context: yaw invariance of the descriptor and ring key, the column
// shift recovering the yaw, discrimination, the detector, and real KITTI scans.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <semlio/io/kitti.hpp>
#include <semlio/loop/scan_context.hpp>
#include <semlio_test/data.hpp>

#include "loop_fixtures.hpp"

namespace test_scan_context {  // one namespace per test file: the area compiles as one TU

using namespace semlio;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// A street-like synthetic cloud: ground, poles and wall segments of random
/// height at random places within 60 m (lidar frame, lidar 1.73 m up).
std::vector<Eigen::Vector3f> synthetic_cloud(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 3000; ++i) {
    const double r = 3.0 + 57.0 * u(rng);
    const double a = 2.0 * std::numbers::pi * u(rng);
    pts.emplace_back(static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)), -1.73F);
  }
  for (int k = 0; k < 60; ++k) {
    const double r = 4.0 + 50.0 * u(rng);
    const double a = 2.0 * std::numbers::pi * u(rng);
    const double h = 0.5 + 9.0 * u(rng);
    const double len = u(rng) < 0.5 ? 0.0 : 2.0 + 10.0 * u(rng);  // pole or wall
    const double dir = 2.0 * std::numbers::pi * u(rng);
    for (double s = 0.0; s <= len; s += 0.25) {
      const double x = r * std::cos(a) + s * std::cos(dir);
      const double y = r * std::sin(a) + s * std::sin(dir);
      for (double z = -1.73; z <= h - 1.73; z += 0.2) pts.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
    }
  }
  return pts;
}

/// The cloud as seen by a lidar rotated by yaw about z: p_query = Rz(yaw)^T p.
std::vector<Eigen::Vector3f> seen_rotated(const std::vector<Eigen::Vector3f>& cloud, double yaw) {
  const Eigen::Matrix3f Rt = loop_test::yaw_pose(yaw).rotation().transpose().cast<float>();
  std::vector<Eigen::Vector3f> out;
  out.reserve(cloud.size());
  for (const auto& p : cloud) out.push_back(Rt * p);
  return out;
}

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

}  // namespace

TEST_CASE("scan context: descriptor shape and bins", "[loop]") {
  const ScanContextConfig config;
  // One point per known bin: ring 2 (r = 10 m: 10 / 4 = 2.5), straight ahead
  // (azimuth 0: sector 30 of 60), 3 m above the lidar -> 3 + 2 = 5 m.
  const std::vector<Eigen::Vector3f> cloud{{10.0F, 0.1F, 3.0F}, {10.0F, 0.1F, 1.0F}, {200.0F, 0.0F, 1.0F},
                                           {0.0F, -30.0F, -5.0F}};
  const ScanContext sc = make_scan_context(cloud, config);
  REQUIRE(sc.bins.size() == 20U * 60U);
  CHECK(sc.at(2, 30) == Approx(5.0F));  // the max of the two heights
  // (0, -30): ring 7, azimuth -90 deg -> sector 15; height clamped at 0 (empty).
  CHECK(sc.at(7, 15) == 0.0F);
  float total = 0.0F;
  for (const float b : sc.bins) total += b;
  CHECK(total == Approx(5.0F));  // the 200 m point is beyond max_radius_m
  CHECK(sc.ring_key[2] == Approx(5.0F / 60.0F));
}

TEST_CASE("scan context: yaw rotation shifts columns and the shift gives the yaw", "[loop]") {
  const ScanContextConfig config;
  const auto cloud = synthetic_cloud(3);
  const ScanContext cand = make_scan_context(cloud, config);
  // A different place, for scale.
  const ScanContext other = make_scan_context(synthetic_cloud(4), config);
  const double d_other = scan_context_distance(other, cand).distance;
  CHECK(d_other > 0.25);
  for (const double yaw_deg : {0.0, 42.0, -90.0, 180.0, 37.0, -123.0}) {
    const double yaw = yaw_deg * kDeg;
    const ScanContext query = make_scan_context(seen_rotated(cloud, yaw), config);
    const ScanContextMatch m = scan_context_distance(query, cand);
    const double est = scan_context_yaw(m.shift, config.sectors);
    INFO("yaw " << yaw_deg << " deg: distance " << m.distance << ", estimated " << est / kDeg << " deg");
    const bool whole_sectors = std::abs(std::remainder(yaw_deg, 6.0)) < 1e-9;
    if (whole_sectors) {
      // A whole number of sectors: the columns shift exactly (up to float
      // rounding of points on sector borders), the ring key stays.
      for (std::size_t r = 0; r < cand.ring_key.size(); ++r) {
        CHECK(query.ring_key[r] == Approx(cand.ring_key[r]).epsilon(0.02).margin(0.01));
      }
      CHECK(m.distance < 0.02);
      CHECK(std::abs(wrap(est - yaw)) < 1e-9);
    } else {
      // In between: walls and poles regroup across sector borders (this
      // sparse cloud suffers most at half a sector); the best shift is
      // within a sector of the yaw, and still nearer than another place.
      CHECK(m.distance < d_other);
      CHECK(std::abs(wrap(est - yaw)) <= 6.0 * kDeg + 1e-9);
    }
  }
}

TEST_CASE("scan context detector: finds the rotated revisit, respects the time gap", "[loop]") {
  const auto place = synthetic_cloud(11);
  std::vector<LoopKeyframe> kfs(4);
  kfs[0].cloud = place;
  kfs[0].stamp_s = 0.0;
  kfs[1].cloud = synthetic_cloud(12);
  kfs[1].stamp_s = 1.0;
  kfs[2].cloud = synthetic_cloud(13);
  kfs[2].stamp_s = 2.0;
  const double yaw = 150.0 * kDeg;
  kfs[3].cloud = seen_rotated(place, yaw);
  kfs[3].stamp_s = 100.0;
  ScanContextDetector detector;
  std::vector<LoopCandidate> out;
  detector.detect(kfs, out);
  REQUIRE(!out.empty());
  CHECK(out[0].index == 0);
  CHECK(out.size() == 1);  // the other places are beyond max_distance
  CHECK(std::abs(wrap(out[0].T_from_to_guess.so3().log().z() - yaw)) <= 6.0 * kDeg);
  CHECK(out[0].T_from_to_guess.translation().norm() == 0.0);
  CHECK(detector.descriptor_count() == 4);

  SECTION("too recent: no candidate") {
    kfs[3].stamp_s = 20.0;
    ScanContextDetector fresh;
    fresh.detect(kfs, out);
    CHECK(out.empty());
  }
  SECTION("an archived match is no candidate and its descriptor is freed") {
    // What a bounded store (Slam's) does to a keyframe a kept place stands for.
    REQUIRE(!detector.descriptor(0).bins.empty());
    kfs[0].cloud.clear();
    kfs[0].archived = true;
    kfs.push_back(kfs[3]);
    kfs.back().stamp_s = 200.0;
    detector.detect(kfs, out);
    for (const LoopCandidate& c : out) CHECK(c.index != 0);
    CHECK(detector.descriptor(0).bins.empty());
    CHECK(detector.descriptor(0).bins.capacity() == 0);
    CHECK(!detector.descriptor(3).bins.empty());  // the first revisit, kept, now matches the second
    REQUIRE(!out.empty());
    CHECK(out[0].index == 3);
  }
  SECTION("bad settings throw") {
    CHECK_THROWS_AS(ScanContextDetector(ScanContextConfig{.rings = 0}), ConfigError);
    CHECK_THROWS_AS(ScanContextDetector(ScanContextConfig{.max_radius_m = -1.0}), ConfigError);
  }
}

TEST_CASE("scan context on real KITTI scans: self-similarity and the next frame", "[loop]") {
  const ScanContextConfig config;
  const Scan s0 = io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  const Scan s1 = io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000001.bin"));
  const ScanContext d0 = make_scan_context(s0.points, config);
  const ScanContext d1 = make_scan_context(s1.points, config);
  // The same scan seen 90 deg turned: same place, shift = 15 sectors.
  const ScanContext d0r = make_scan_context(seen_rotated(s0.points, 90.0 * kDeg), config);
  const ScanContextMatch self = scan_context_distance(d0r, d0);
  CHECK(self.distance < 0.05);
  CHECK(std::abs(wrap(scan_context_yaw(self.shift, config.sectors) - 90.0 * kDeg)) <= 6.0 * kDeg);
  // Frame 1 is ~0.7 m further along the road, same heading: a match at yaw ~0.
  const ScanContextMatch next = scan_context_distance(d1, d0);
  INFO("frame 1 vs 0: distance " << next.distance << ", shift " << next.shift);
  CHECK(next.distance < config.max_distance);
  CHECK(std::abs(scan_context_yaw(next.shift, config.sectors)) <= 6.0 * kDeg);
  // A synthetic place is not KITTI 00.
  const ScanContext synth = make_scan_context(synthetic_cloud(5), config);
  CHECK(scan_context_distance(synth, d0).distance > next.distance + 0.1);
}

}  // namespace test_scan_context
