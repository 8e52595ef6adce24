#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>
#include <random>
#include <vector>

#include <semlio/features/rings.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/ply.hpp>
#include <semlio_test/data.hpp>

namespace test_rings {  // one namespace per test file: the area compiles as one TU

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double elevation(const Eigen::Vector3f& p) {
  return std::atan2(static_cast<double>(p.z()),
                    std::hypot(static_cast<double>(p.x()), static_cast<double>(p.y())));
}

double azimuth(const Eigen::Vector3f& p) {
  return std::atan2(static_cast<double>(p.y()), static_cast<double>(p.x()));
}

/// A synthetic sweep from a sensor table: ring after ring (lowest first or
/// highest first), counter-clockwise from azimuth ~0, ranges varying.
semlio::Scan synthetic_sweep(const semlio::SensorModel& sensor, int columns, bool top_down,
                             std::vector<std::uint16_t>& truth) {
  semlio::Scan scan;
  truth.clear();
  const int beams = static_cast<int>(sensor.beams());
  for (int rr = 0; rr < beams; ++rr) {
    const int ring = top_down ? beams - 1 - rr : rr;
    const double el = sensor.elevations_rad[static_cast<std::size_t>(ring)];
    for (int c = 0; c < columns; ++c) {
      const double az = (c + 0.5) * 2.0 * std::numbers::pi / columns;
      const double range = 5.0 + 3.0 * std::sin(3.0 * az) + 0.1 * ring;
      scan.points.emplace_back(static_cast<float>(range * std::cos(el) * std::cos(az)),
                               static_cast<float>(range * std::cos(el) * std::sin(az)),
                               static_cast<float>(range * std::sin(el)));
      truth.push_back(static_cast<std::uint16_t>(ring));
    }
  }
  return scan;
}

}  // namespace

TEST_CASE("rings from point order on the real KITTI scans", "[features]") {
  for (const char* name : {"000000.bin", "000001.bin"}) {
    semlio::Scan scan =
        semlio::io::read_kitti_bin(semlio_test::data_path(std::string("kitti/sequences/00/velodyne/") + name));
    const semlio::RingReport report = semlio::infer_rings(scan, semlio::SensorModel::hdl64e());
    CHECK(report.used == semlio::RingMethod::kPointOrder);
    CHECK(report.order_rings == 64);
    REQUIRE(scan.rings.size() == scan.size());
    // Every ring 0..63 present with a plausible count: at most one revolution
    // at the HDL-64E's ~0.17 deg step (~2100), at least half of one.
    std::vector<std::size_t> count(64, 0);
    std::vector<double> mean_el(64, 0.0);
    for (std::size_t i = 0; i < scan.size(); ++i) {
      REQUIRE(scan.rings[i] < 64);
      ++count[scan.rings[i]];
      mean_el[scan.rings[i]] += elevation(scan.points[i]);
    }
    for (std::size_t r = 0; r < 64; ++r) {
      INFO("ring " << r);
      CHECK(count[r] > 1000);
      CHECK(count[r] < 2300);
      mean_el[r] /= static_cast<double>(count[r]);
      if (r > 0) CHECK(mean_el[r] > mean_el[r - 1]);  // ring 0 = lowest beam
    }
    CHECK(mean_el[0] < -20.0 * kDeg);
    CHECK(mean_el[63] > 1.0 * kDeg);
    // Each ring is contiguous in the file (highest first) and sweeps the
    // azimuth counter-clockwise: almost all steps inside a ring are positive.
    std::size_t changes = 0;
    std::size_t ccw = 0;
    std::size_t steps = 0;
    for (std::size_t i = 1; i < scan.size(); ++i) {
      if (scan.rings[i] != scan.rings[i - 1]) {
        ++changes;
        CHECK(scan.rings[i] + 1 == scan.rings[i - 1]);
        continue;
      }
      double d = azimuth(scan.points[i]) - azimuth(scan.points[i - 1]);
      if (d < -std::numbers::pi) d += 2.0 * std::numbers::pi;
      ++steps;
      if (d > 0.0) ++ccw;
    }
    CHECK(changes == 63);
    CHECK(static_cast<double>(ccw) > 0.99 * static_cast<double>(steps));
  }
}

TEST_CASE("rings from elevation on the real 32-beam scan pair", "[features]") {
  const semlio::SensorModel sensor = semlio::SensorModel::hdl32e();
  for (const char* name : {"source.ply", "target.ply"}) {
    semlio::Scan scan = semlio::io::read_ply(semlio_test::data_path(std::string("scan_pair/") + name));
    const semlio::RingReport report = semlio::infer_rings(scan, sensor);
    // Stored column by column: point order cannot give 32 rings.
    CHECK(report.used == semlio::RingMethod::kElevation);
    CHECK(report.order_rings != 32);
    std::vector<std::size_t> count(32, 0);
    double worst = 0.0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      ++count[scan.rings[i]];
      worst = std::max(worst, std::abs(elevation(scan.points[i]) - sensor.elevations_rad[scan.rings[i]]));
    }
    CHECK(worst < 0.05 * kDeg);  // every point sits on its beam
    for (std::size_t r = 0; r < 32; ++r) {
      INFO("ring " << r);
      CHECK(count[r] > 1500);  // ~2000 per beam, minus the no-return points
      CHECK(count[r] < 2300);
    }
  }
}

TEST_CASE("rings on synthetic sweeps from a sensor table", "[features]") {
  std::vector<std::uint16_t> truth;
  for (const semlio::SensorModel& sensor : {semlio::SensorModel::hdl64e(), semlio::SensorModel::hdl32e()}) {
    for (const bool top_down : {true, false}) {
      INFO("beams " << sensor.beams() << " top_down " << top_down);
      semlio::Scan scan = synthetic_sweep(sensor, 500, top_down, truth);
      {  // point order
        const auto report = semlio::infer_rings(scan, sensor, {.method = semlio::RingMethod::kPointOrder});
        CHECK(report.used == semlio::RingMethod::kPointOrder);
        CHECK(scan.rings == truth);
      }
      {  // elevation
        const auto report = semlio::infer_rings(scan, sensor, {.method = semlio::RingMethod::kElevation});
        CHECK(report.used == semlio::RingMethod::kElevation);
        CHECK(scan.rings == truth);
      }
      {  // auto falls back to elevation on shuffled points
        std::vector<std::size_t> perm(scan.size());
        for (std::size_t i = 0; i < perm.size(); ++i) perm[i] = i;
        std::mt19937 rng(9);
        std::shuffle(perm.begin(), perm.end(), rng);
        semlio::Scan shuffled;
        std::vector<std::uint16_t> shuffled_truth;
        for (const std::size_t i : perm) {
          shuffled.points.push_back(scan.points[i]);
          shuffled_truth.push_back(truth[i]);
        }
        semlio::Scan copy = shuffled;
        const auto report = semlio::infer_rings(shuffled, sensor);
        CHECK(report.used == semlio::RingMethod::kElevation);
        CHECK(shuffled.rings == shuffled_truth);
        CHECK_THROWS_AS(semlio::infer_rings(copy, sensor, {.method = semlio::RingMethod::kPointOrder}),
                        semlio::ValueError);
      }
    }
  }
}

TEST_CASE("a ring field the scan carries is kept when asked and valid", "[features]") {
  std::vector<std::uint16_t> truth;
  const semlio::SensorModel sensor = semlio::SensorModel::hdl32e();
  semlio::Scan scan = synthetic_sweep(sensor, 300, /*top_down=*/true, truth);
  // A driver's ring field that differs from what inference gives (Ouster
  // counts from the top): kept as is, since only the grouping matters.
  std::vector<std::uint16_t> driver(truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i) driver[i] = static_cast<std::uint16_t>(31 - truth[i]);
  scan.rings = driver;
  {
    semlio::Scan s = scan;
    const auto report = semlio::infer_rings(s, sensor, {.method = semlio::RingMethod::kAuto, .prefer_scan_rings = true});
    CHECK(report.used == semlio::RingMethod::kFromScan);
    CHECK(s.rings == driver);
  }
  {
    semlio::Scan s = scan;
    const auto report = semlio::infer_rings(s, sensor, {.method = semlio::RingMethod::kFromScan});
    CHECK(report.used == semlio::RingMethod::kFromScan);
    CHECK(s.rings == driver);
  }
  {  // default: re-inferred (an earlier call's rings are not a driver's)
    semlio::Scan s = scan;
    const auto report = semlio::infer_rings(s, sensor);
    CHECK(report.used == semlio::RingMethod::kPointOrder);
    CHECK(s.rings == truth);
  }
  {  // a ring beyond the table: inferred instead, or an error for kFromScan
    semlio::Scan s = scan;
    s.rings[5] = 32;
    const auto report = semlio::infer_rings(s, sensor, {.method = semlio::RingMethod::kAuto, .prefer_scan_rings = true});
    CHECK(report.used == semlio::RingMethod::kPointOrder);
    CHECK(s.rings == truth);
    semlio::Scan t = scan;
    t.rings[5] = 40;
    CHECK_THROWS_AS(semlio::infer_rings(t, sensor, {.method = semlio::RingMethod::kFromScan}), semlio::ValueError);
    semlio::Scan none = scan;
    none.rings.clear();
    CHECK_THROWS_AS(semlio::infer_rings(none, sensor, {.method = semlio::RingMethod::kFromScan}), semlio::ValueError);
  }
}

TEST_CASE("a stray point just below 2pi does not split a ring", "[features]") {
  semlio::SensorModel sensor;
  sensor.elevations_rad = {-0.1, 0.1};
  semlio::Scan scan;
  const auto add = [&](double el, double az_deg) {
    scan.points.emplace_back(static_cast<float>(10 * std::cos(el) * std::cos(az_deg * kDeg)),
                             static_cast<float>(10 * std::cos(el) * std::sin(az_deg * kDeg)),
                             static_cast<float>(10 * std::sin(el)));
  };
  // Upper ring first: a stray point at azimuth -0.1 deg (359.9 deg), then
  // 0 .. 359 deg; then the lower ring 0 .. 359 deg.
  add(0.1, -0.1);
  for (int a = 0; a < 360; ++a) add(0.1, a);
  for (int a = 0; a < 360; ++a) add(-0.1, a);
  const auto report = semlio::infer_rings(scan, sensor, {.method = semlio::RingMethod::kPointOrder});
  CHECK(report.order_rings == 2);
  CHECK(std::count(scan.rings.begin(), scan.rings.end(), 1) == 361);
  CHECK(scan.rings.front() == 1);
  CHECK(scan.rings.back() == 0);
}

/// ring_starts_from_order as first written: every point's azimuth compared.
std::vector<std::size_t> literal_ring_starts(const std::vector<Eigen::Vector3f>& pts) {
  std::vector<std::size_t> begins;
  if (pts.empty()) return begins;
  begins.push_back(0);
  constexpr double kPi = std::numbers::pi;
  bool passed_rear = false;
  double prev = semlio::detail::azimuth_0_2pi(pts[0]);
  for (std::size_t i = 1; i < pts.size(); ++i) {
    if (prev > kPi / 2.0 && prev < 1.5 * kPi) passed_rear = true;
    const double s = semlio::detail::azimuth_0_2pi(pts[i]);
    if (s < prev - kPi && passed_rear) {
      begins.push_back(i);
      passed_rear = false;
    }
    prev = s;
  }
  return begins;
}

TEST_CASE("ring starts from sign tests equal those from every point's azimuth", "[features]") {
  std::vector<std::size_t> begins;
  SECTION("the real KITTI scans") {
    for (const char* name : {"000000.bin", "000001.bin"}) {
      const semlio::Scan scan =
          semlio::io::read_kitti_bin(semlio_test::data_path(std::string("kitti/sequences/00/velodyne/") + name));
      semlio::ring_starts_from_order(scan.points, begins);
      CHECK(begins.size() == 64);
      CHECK(begins == literal_ring_starts(scan.points));
    }
  }
  SECTION("random and adversarial points") {
    // Points on and next to both axes (the fast path's boundaries), signed
    // zeros, tiny and huge coordinates, NaN and infinities, in random order:
    // every transition the fast path shortcuts meets its boundary cases.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    const float tiny = std::numeric_limits<float>::denorm_min();
    const std::vector<float> special = {0.0F, -0.0F, 1e-30F, -1e-30F, 1e-7F, -1e-7F, 1e-6F, -1e-6F, 1.0F, -1.0F,
                                        50.0F, -50.0F, 1e30F, -1e30F, nan, inf, -inf, tiny, -tiny};
    std::mt19937 rng(7);
    std::uniform_int_distribution<std::size_t> pick(0, special.size() - 1);
    std::uniform_real_distribution<float> uni(-1.0F, 1.0F);
    std::uniform_real_distribution<double> az(0.0, 2.0 * std::numbers::pi);
    std::size_t total_rings = 0;
    for (int trial = 0; trial < 1000; ++trial) {
      std::vector<Eigen::Vector3f> pts;
      const int n = 500;
      for (int i = 0; i < n; ++i) {
        const int kind = static_cast<int>(rng() % 4);
        float x = 0.0F;
        float y = 0.0F;
        if (kind == 0) {  // special values on either coordinate
          x = special[pick(rng)];
          y = special[pick(rng)];
        } else if (kind == 1) {  // next to an axis: one coordinate ~1e-6 of the other
          const float big = 10.0F * uni(rng);
          const float small = big * 1e-6F * (1.0F + uni(rng));
          if (rng() % 2 == 0) {
            x = small;
            y = big;
          } else {
            x = big;
            y = small;
          }
        } else {  // a sweep-like azimuth (wraps often) or anything
          const double a = kind == 2 ? az(rng) : 0.0;
          x = kind == 2 ? static_cast<float>(10.0 * std::cos(a)) : 10.0F * uni(rng);
          y = kind == 2 ? static_cast<float>(10.0 * std::sin(a)) : 10.0F * uni(rng);
        }
        pts.emplace_back(x, y, uni(rng));
      }
      semlio::ring_starts_from_order(pts, begins);
      REQUIRE(begins == literal_ring_starts(pts));
      total_rings += begins.size();
    }
    CHECK(total_rings > 1000 * 20);  // the comparison saw many ring starts, not only the first
  }
}

TEST_CASE("sensor tables", "[features]") {
  const auto h64 = semlio::SensorModel::hdl64e();
  REQUIRE(h64.beams() == 64);
  h64.validate();
  CHECK(h64.elevations_rad.front() == Approx(-24.33 * kDeg));
  CHECK(h64.elevations_rad.back() == Approx(2.0 * kDeg));
  const auto h32 = semlio::SensorModel::hdl32e();
  REQUIRE(h32.beams() == 32);
  CHECK(h32.elevations_rad.front() == Approx(-30.67 * kDeg));
  CHECK(h32.elevations_rad.back() == Approx(10.67 * kDeg).epsilon(1e-3));
  CHECK(h32.nearest_ring(-90.0 * kDeg) == 0);
  CHECK(h32.nearest_ring(45.0 * kDeg) == 31);
  CHECK(h32.nearest_ring(h32.elevations_rad[7] + 0.6 * kDeg) == 7);
  CHECK(h32.nearest_ring(h32.elevations_rad[7] + 0.7 * kDeg) == 8);
  semlio::SensorModel bad;
  CHECK_THROWS_AS(bad.validate(), semlio::ConfigError);
  bad.elevations_rad = {0.1, 0.0};
  CHECK_THROWS_AS(bad.validate(), semlio::ConfigError);
}

TEST_CASE("per-point time from azimuth", "[features]") {
  semlio::Scan scan;
  for (const double az_deg : {0.0, 90.0, 180.0, 270.0, -45.0}) {
    scan.points.emplace_back(static_cast<float>(std::cos(az_deg * kDeg)),
                             static_cast<float>(std::sin(az_deg * kDeg)), 0.0F);
  }
  SECTION("KITTI raw default: clockwise from the front, 10 Hz") {
    semlio::assign_times_from_azimuth(scan);
    REQUIRE(scan.times_s.size() == 5);
    CHECK(scan.times_s[0] == Approx(0.0).margin(1e-7));
    CHECK(scan.times_s[1] == Approx(0.075));  // +90 deg (left) is reached after three quarters
    CHECK(scan.times_s[2] == Approx(0.05));
    CHECK(scan.times_s[3] == Approx(0.025));  // right side after a quarter
    CHECK(scan.times_s[4] == Approx(0.0125));  // -45 deg
  }
  SECTION("the simulator: clockwise from the rear") {
    semlio::assign_times_from_azimuth(scan, {.start_azimuth_rad = 180.0 * kDeg});
    CHECK(scan.times_s[2] == Approx(0.0).margin(1e-7));
    CHECK(scan.times_s[1] == Approx(0.025));
    CHECK(scan.times_s[0] == Approx(0.05));
    CHECK(scan.times_s[3] == Approx(0.075));
    CHECK(scan.times_s[4] == Approx(0.0625));
  }
  SECTION("counter-clockwise from the front") {
    semlio::assign_times_from_azimuth(scan, {.counter_clockwise = true});
    CHECK(scan.times_s[0] == Approx(0.0).margin(1e-7));
    CHECK(scan.times_s[1] == Approx(0.025));
    CHECK(scan.times_s[3] == Approx(0.075));
    CHECK(scan.times_s[4] == Approx(0.0875));
  }
  SECTION("clockwise from +y at 20 Hz") {
    semlio::assign_times_from_azimuth(
        scan, {.sweep_period_s = 0.05, .start_azimuth_rad = 90.0 * kDeg, .counter_clockwise = false});
    // Clockwise angle from +y: 0 deg -> 90, 90 -> 0, 180 -> 270, 270 -> 180, -45 -> 135.
    CHECK(scan.times_s[1] == Approx(0.0).margin(1e-7));
    CHECK(scan.times_s[0] == Approx(0.0125));
    CHECK(scan.times_s[2] == Approx(0.0375));
    CHECK(scan.times_s[3] == Approx(0.025));
    CHECK(scan.times_s[4] == Approx(0.01875));
  }
  CHECK_THROWS_AS(semlio::assign_times_from_azimuth(scan, {.sweep_period_s = 0.0}), semlio::ConfigError);
}

TEST_CASE("per-point times on the real KITTI scan run against the point order", "[features]") {
  // Each ring is stored counter-clockwise from the front while the sensor
  // spins clockwise (see rings.hpp), so within a ring time decreases.
  semlio::Scan scan = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  semlio::infer_rings(scan, semlio::SensorModel::hdl64e());
  semlio::assign_times_from_azimuth(scan);
  std::size_t decreasing = 0;
  std::size_t steps = 0;
  for (std::size_t i = 1; i < scan.size(); ++i) {
    CHECK((scan.times_s[i] >= 0.0F && scan.times_s[i] < 0.1F));
    if (scan.rings[i] != scan.rings[i - 1]) continue;
    ++steps;
    if (scan.times_s[i] <= scan.times_s[i - 1]) ++decreasing;
  }
  CHECK(static_cast<double>(decreasing) > 0.99 * static_cast<double>(steps));
}

TEST_CASE("KITTI vertical-angle correction rotates by 0.205 deg about the horizontal axis", "[features]") {
  const double theta = semlio::kKittiVerticalCorrectionRad;
  CHECK(theta == Approx(0.205 * kDeg));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-30.0, 30.0);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3f p(static_cast<float>(u(rng)), static_cast<float>(u(rng)),
                            static_cast<float>(0.2 * u(rng)));
    const Eigen::Vector3f q = semlio::correct_vertical_angle(p, theta);
    const Eigen::Vector3d pd = p.cast<double>();
    const Eigen::Vector3d qd = q.cast<double>();
    // Angle between p and q is theta; the rotation axis p x q is horizontal,
    // perpendicular to the azimuth, along (y, -x, 0) (so elevation grows).
    const double angle = std::atan2(pd.cross(qd).norm(), pd.dot(qd));
    CHECK(angle == Approx(theta).epsilon(1e-3));
    const Eigen::Vector3d axis = pd.cross(qd).normalized();
    const Eigen::Vector3d expected = Eigen::Vector3d(pd.y(), -pd.x(), 0.0).normalized();
    CHECK((axis - expected).norm() < 1e-4);
    CHECK(qd.norm() == Approx(pd.norm()).epsilon(1e-6));
    CHECK(elevation(q) - elevation(p) == Approx(theta).epsilon(1e-3));
  }
  // A point on the z axis has no azimuth: unchanged.
  CHECK(semlio::correct_vertical_angle(Eigen::Vector3f(0, 0, 5), theta) == Eigen::Vector3f(0, 0, 5));
  semlio::Scan scan;
  scan.points = {Eigen::Vector3f(10, 0, 0)};
  semlio::correct_kitti_vertical_angle(scan);
  CHECK(scan.points[0].z() == Approx(10.0 * std::sin(theta)));
  CHECK(scan.points[0].y() == 0.0F);
}

// The scan-wide correction runs two points at a time where SSE2 allows; it
// must equal the per-point form bit for bit: on both real KITTI scans (odd
// and even lengths) and on points on and next to the z axis, with signed
// zeros, NaN, huge and subnormal coordinates, in every pairing.
TEST_CASE("the scan-wide vertical correction equals the per-point form bit for bit", "[features]") {
  const double theta = semlio::kKittiVerticalCorrectionRad;
  const auto same_bits = [](const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    return std::memcmp(a.data(), b.data(), sizeof(float) * 3) == 0;
  };
  const auto check_scan = [&](const std::vector<Eigen::Vector3f>& pts) {
    semlio::Scan scan;
    scan.points = pts;
    semlio::correct_kitti_vertical_angle(scan, theta);
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (!same_bits(scan.points[i], semlio::correct_vertical_angle(pts[i], theta))) ++mismatches;
    }
    return mismatches;
  };
  for (const char* name : {"000000.bin", "000001.bin"}) {
    const semlio::Scan real =
        semlio::io::read_kitti_bin(semlio_test::data_path(std::string("kitti/sequences/00/velodyne/") + name));
    REQUIRE(real.size() > 100000);
    CHECK(check_scan(real.points) == 0);
    std::vector<Eigen::Vector3f> odd(real.points.begin() + 1, real.points.end());
    if (odd.size() % 2 == 0) odd.pop_back();
    CHECK(check_scan(odd) == 0);
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float tiny = std::numeric_limits<float>::denorm_min();
  const float big = std::numeric_limits<float>::max();
  const std::vector<Eigen::Vector3f> special = {
      {0.0F, 0.0F, 5.0F},  {-0.0F, 0.0F, -3.0F}, {0.0F, -0.0F, 0.0F}, {tiny, 0.0F, 1.0F}, {0.0F, -tiny, 2.0F},
      {1e-20F, 1e-20F, 7.0F}, {nan, 1.0F, 1.0F}, {1.0F, nan, 1.0F}, {1.0F, 1.0F, nan}, {big, big, big},
      {-big, 3.0F, -big}, {12.5F, -7.25F, -1.75F}, {-40.0F, 0.0F, 2.0F}};
  std::vector<Eigen::Vector3f> pairs;
  for (const auto& a : special) {
    for (const auto& b : special) {
      pairs.push_back(a);
      pairs.push_back(b);
    }
  }
  CHECK(pairs.size() == 2 * special.size() * special.size());
  CHECK(check_scan(pairs) == 0);
}

}  // namespace test_rings
