// HDL-64E model: beam layout, firing times, return model.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include <semlio/sim/lidar.hpp>

namespace test_lidar {  // one namespace per test file: the area compiles as one TU

using semlio::sim::Lidar;
using semlio::sim::LidarConfig;

namespace {
double deg(double rad) { return rad * 180.0 / std::numbers::pi; }
}  // namespace

TEST_CASE("beam elevations follow KITTI's two-block layout", "[sim]") {
  const Lidar lidar;
  REQUIRE(lidar.rings() == 64);
  CHECK(deg(lidar.elevation_rad(0)) == Approx(-24.9));
  CHECK(deg(lidar.elevation_rad(31)) == Approx(-8.83));
  CHECK(deg(lidar.elevation_rad(32)) == Approx(-8.33));
  CHECK(deg(lidar.elevation_rad(63)) == Approx(2.0));
  // Lower block ~0.52 deg apart, upper block ~1/3 deg apart, monotone.
  CHECK(deg(lidar.elevation_rad(1) - lidar.elevation_rad(0)) == Approx(16.07 / 31.0));
  CHECK(deg(lidar.elevation_rad(40) - lidar.elevation_rad(39)) == Approx(10.33 / 31.0));
  for (int r = 1; r < 64; ++r) CHECK(lidar.elevation_rad(r) > lidar.elevation_rad(r - 1));
  // Directions are unit and carry the elevation.
  const Eigen::Vector3d d = lidar.direction(10, 123);
  CHECK(d.norm() == Approx(1.0));
  CHECK(std::asin(d.z()) == Approx(lidar.elevation_rad(10)));
}

TEST_CASE("clockwise spin: sweep starts facing backwards, forward at half period", "[sim]") {
  const Lidar lidar;
  const int n = lidar.columns();
  CHECK(lidar.period_s() == Approx(0.1));
  CHECK(lidar.column_time_s(0) == 0.0);
  CHECK(lidar.column_time_s(n / 2) == Approx(0.05));
  CHECK(lidar.direction(40, 0).x() < -0.9);      // backwards at the start
  CHECK(lidar.direction(40, n / 2).x() > 0.9);   // forward at mid-sweep
  CHECK(lidar.direction(40, n / 4).y() > 0.9);   // left a quarter in (clockwise from behind)
  CHECK(lidar.azimuth_rad(1) < lidar.azimuth_rad(0));
}

TEST_CASE("return model: exact without noise, 2 cm sigma with noise", "[sim]") {
  LidarConfig exact_cfg;
  exact_cfg.noise = false;
  const Lidar exact(exact_cfg);
  const auto m = exact.measure(25.0, 0.8, 0.5, 1);
  CHECK(m.keep);
  CHECK(m.range_m == 25.0);
  CHECK_FALSE(exact.measure(130.0, 1.0, 0.5, 1).keep);  // beyond max range
  CHECK_FALSE(exact.measure(1.0, 1.0, 0.5, 1).keep);    // below min range
  // Brighter at normal incidence than at grazing incidence.
  CHECK(exact.measure(20.0, 1.0, 0.5, 1).intensity > exact.measure(20.0, 0.2, 0.5, 1).intensity);

  const Lidar noisy;
  double sum = 0.0;
  double sum2 = 0.0;
  int kept = 0;
  int kept_grazing = 0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    const auto r = noisy.measure(20.0, 0.9, 0.5, static_cast<std::uint64_t>(k));
    if (r.keep) {
      ++kept;
      sum += r.range_m - 20.0;
      sum2 += (r.range_m - 20.0) * (r.range_m - 20.0);
    }
    if (noisy.measure(20.0, 0.03, 0.5, static_cast<std::uint64_t>(k)).keep) ++kept_grazing;
  }
  const double mean = sum / kept;
  const double sigma = std::sqrt(sum2 / kept - mean * mean);
  CHECK(std::abs(mean) < 0.001);
  CHECK(sigma == Approx(0.02).epsilon(0.05));
  CHECK(kept > 0.97 * n);            // 1% base dropout
  CHECK(kept_grazing < 0.5 * n);     // grazing returns drop
  // Same key, same draw (determinism).
  CHECK(noisy.measure(20.0, 0.9, 0.5, 77).range_m == noisy.measure(20.0, 0.9, 0.5, 77).range_m);
}

TEST_CASE("the ego body hides the lowest beams ahead and behind, never the upper block", "[sim]") {
  const Lidar lidar;
  const int n = lidar.columns();
  CHECK(lidar.self_occluded(0, n / 2));       // lowest beam straight ahead
  CHECK(lidar.self_occluded(0, 0));           // and straight back
  CHECK_FALSE(lidar.self_occluded(0, n / 4)); // not sideways
  for (int c = 0; c < n; c += 7) CHECK_FALSE(lidar.self_occluded(40, c));
}

TEST_CASE("invalid lidar config names the field", "[sim]") {
  LidarConfig c;
  c.beams = 3;
  CHECK_THROWS_WITH(Lidar(c), Catch::Contains("beams"));
  c = LidarConfig{};
  c.rate_hz = 0.0;
  CHECK_THROWS_WITH(Lidar(c), Catch::Contains("rate_hz"));
}

}  // namespace test_lidar
