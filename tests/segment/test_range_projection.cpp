#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/segment/range_projection.hpp>

namespace test_range_projection {  // one namespace per test file: the area compiles as one TU

using semlio::Class;
using semlio::RangeChannel;
using semlio::RangeProjection;
using semlio::RangeProjectionConfig;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

semlio::Scan scan_of(const std::vector<Eigen::Vector3f>& points) {
  semlio::Scan s;
  s.points = points;
  s.intensity.assign(points.size(), 0.5f);
  return s;
}

// Pixel id of (row, column) on the KITTI card's 2048 columns.
std::int32_t kitti_pixel(int row, int col) { return row * 2048 + col; }

// The small image of the kNN cases: 10 x 40 pixels, rows of 1 deg from +5 to
// -5 deg, columns of 9 deg.
RangeProjectionConfig small_config() {
  RangeProjectionConfig c;
  c.image = {.height_px = 10, .width_px = 40, .fov_up_rad = 5.0 * kDeg, .fov_down_rad = -5.0 * kDeg};
  return c;
}

// A point at the centre of pixel (row, col) of small_config(), at range r:
// the inverse of the projection, written from the pixel grid (pitch of row r
// centre = 5 deg - (r + 0.5) deg; yaw of column c centre = -180 deg + (c + 0.5) 9 deg;
// azimuth atan2(y, x) = -yaw).
Eigen::Vector3f at_pixel(int row, int col, double range_m) {
  const double pitch = (5.0 - (row + 0.5)) * kDeg;
  const double azimuth = -(-180.0 + (col + 0.5) * 9.0) * kDeg;
  return {static_cast<float>(range_m * std::cos(pitch) * std::cos(azimuth)),
          static_cast<float>(range_m * std::cos(pitch) * std::sin(azimuth)),
          static_cast<float>(range_m * std::sin(pitch))};
}

}  // namespace

TEST_CASE("RangeProjection puts known points in RangeNet++'s pixels (KITTI card, hand-computed)", "[segment]") {
  RangeProjection proj;  // 64 x 2048, +3 / -25 deg
  REQUIRE(proj.height_px() == 64);
  REQUIRE(proj.width_px() == 2048);
  // row = floor((3 deg - pitch) / 28 deg * 64), column = floor(0.5 (yaw / pi + 1) 2048), yaw = -atan2(y, x).
  const std::vector<Eigen::Vector3f> pts{
      {10.0f, 0.0f, 0.0f},        // pitch 0: 3/28*64 = 6.86 -> row 6; yaw 0 -> column 1024
      {0.0f, 10.0f, 0.0f},        // left, yaw -90 deg -> 512
      {0.0f, -10.0f, 0.0f},       // right, yaw +90 deg -> 1536
      {-10.0f, 0.001f, 0.0f},     // behind, just left: yaw -180 deg + 1e-4 rad -> 0.03 -> column 0
      {-10.0f, -0.001f, 0.0f},    // behind, just right: 2047.97 -> column 2047
      {10.0f, 0.0f, -1.40541f},   // pitch -8 deg: 11/28*64 = 25.14 -> row 25
      {10.0f, 0.0f, 0.349208f},   // pitch +2 deg: 1/28*64 = 2.29 -> row 2
      {10.0f, 0.0f, -4.55726f},   // pitch -24.5 deg: 27.5/28*64 = 62.86 -> row 62
      {10.0f, 0.0f, 5.0f},        // pitch +26.6 deg, above the FoV: clamped to row 0
      {10.0f, 0.0f, -10.0f},      // pitch -45 deg, below the FoV: clamped to row 63
      {5.0f, 4.0f, -1.12904f},    // yaw -38.66 deg -> 804.07; pitch -10 deg -> 29.71
  };
  proj.project(scan_of(pts));
  const std::vector<std::int32_t> expected{
      kitti_pixel(6, 1024), kitti_pixel(6, 512), kitti_pixel(6, 1536), kitti_pixel(6, 0),    kitti_pixel(6, 2047),
      kitti_pixel(25, 1024), kitti_pixel(2, 1024), kitti_pixel(62, 1024), kitti_pixel(0, 1024), kitti_pixel(63, 1024),
      kitti_pixel(29, 804)};
  REQUIRE(proj.point_pixels().size() == expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    INFO("point " << i);
    CHECK(proj.point_pixels()[i] == expected[i]);
    CHECK(proj.pixel_points()[static_cast<std::size_t>(expected[i])] == static_cast<std::int32_t>(i));
  }
}

TEST_CASE("RangeProjection: the nearest point wins a pixel, ties go to the lower index, invalid points get none",
          "[segment]") {
  RangeProjection proj;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // Three points on the ray straight ahead (pixel (6, 1024)): 20 m, 10 m, 10 m again.
  proj.project(scan_of({{20.0f, 0.0f, 0.0f}, {10.0f, 0.0f, 0.0f}, {10.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f},
                        {nan, 1.0f, 1.0f}}));
  const auto pix = static_cast<std::size_t>(kitti_pixel(6, 1024));
  CHECK(proj.point_pixels()[0] == kitti_pixel(6, 1024));
  CHECK(proj.point_pixels()[1] == kitti_pixel(6, 1024));
  CHECK(proj.point_pixels()[2] == kitti_pixel(6, 1024));
  CHECK(proj.pixel_points()[pix] == 1);
  CHECK(proj.pixel_ranges()[pix] == 10.0f);
  CHECK(proj.point_pixels()[3] == -1);  // at the origin: no direction
  CHECK(proj.point_pixels()[4] == -1);  // non-finite
  std::size_t occupied = 0;
  for (const std::int32_t p : proj.pixel_points()) occupied += p >= 0 ? 1U : 0U;
  CHECK(occupied == 1);
  // The nearer point first: it still wins.
  proj.project(scan_of({{10.0f, 0.0f, 0.0f}, {20.0f, 0.0f, 0.0f}}));
  CHECK(proj.pixel_points()[pix] == 0);
  CHECK(proj.pixel_ranges()[pix] == 10.0f);
}

TEST_CASE("RangeProjection fills the configured channels in order, normalised, 0 where empty", "[segment]") {
  RangeProjectionConfig c;
  c.channels = {RangeChannel::kIntensity, RangeChannel::kZ, RangeChannel::kRange, RangeChannel::kY};
  c.channel_mean = {0.5, -1.0, 10.0, 2.0};
  c.channel_std = {0.25, 2.0, 5.0, 4.0};
  RangeProjection proj(c);
  REQUIRE(proj.channel_count() == 4);
  semlio::Scan s = scan_of({{3.0f, 4.0f, 0.0f}, {6.0f, 8.0f, 0.0f}});  // the second is hidden behind the first
  s.intensity = {0.75f, 0.1f};
  proj.project(s);
  // (3, 4, 0): yaw -53.13 deg -> column 721.75 -> 721, pitch 0 -> row 6.
  const auto pix = static_cast<std::size_t>(kitti_pixel(6, 721));
  const std::size_t hw = proj.pixel_count();
  REQUIRE(hw == 64U * 2048U);
  REQUIRE(proj.input().size() == 4 * hw);
  CHECK(proj.input()[0 * hw + pix] == Approx((0.75 - 0.5) / 0.25));  // intensity
  CHECK(proj.input()[1 * hw + pix] == Approx((0.0 + 1.0) / 2.0));    // z
  CHECK(proj.input()[2 * hw + pix] == Approx((5.0 - 10.0) / 5.0));   // range 5 m
  CHECK(proj.input()[3 * hw + pix] == Approx((4.0 - 2.0) / 4.0));    // y
  std::size_t nonzero = 0;
  for (const float v : proj.input()) nonzero += v != 0.0f ? 1U : 0U;
  CHECK(nonzero == 4);  // every other pixel, the hidden point's included, is 0 in every channel
  // A scan without intensity cannot fill an intensity channel.
  semlio::Scan no_intensity;
  no_intensity.points = {{1.0f, 0.0f, 0.0f}};
  CHECK_THROWS_AS(proj.project(no_intensity), semlio::ValueError);
}

TEST_CASE("RangeProjection back-projects with RangeNet++'s kNN vote (constructed cases)", "[segment]") {
  RangeProjectionConfig c = small_config();
  std::vector<Eigen::Vector3f> pts;
  std::vector<std::int32_t> expected_pixel;
  std::vector<Class> pixel_labels(10 * 40, Class::kUnlabeled);
  const auto add = [&](int row, int col, double range_m) {
    pts.push_back(at_pixel(row, col, range_m));
    expected_pixel.push_back(row * 40 + col);
    return pts.size() - 1;
  };
  const auto label = [&](int row, int col, Class cls) { pixel_labels[static_cast<std::size_t>(row * 40 + col)] = cls; };

  // (a) A hidden point takes its neighbours' label: P0 (10 m, car) hides P1
  // (20 m) in pixel (5, 20); four neighbours at 20.1 m are building (weighted
  // distance <= 0.1 m). P0's neighbours are 10 m away in range: only its own pixel votes.
  const std::size_t p0 = add(5, 20, 10.0);
  const std::size_t p1 = add(5, 20, 20.0);
  label(5, 20, Class::kCar);
  for (const auto& [r, col] : {std::pair{4, 20}, std::pair{6, 20}, std::pair{5, 19}, std::pair{5, 21}}) {
    add(r, col, 20.1);
    label(r, col, Class::kBuilding);
  }
  // (b) Only k vote: centre (10 m) sidewalk, two car pixels at 10.05 m, three
  // building pixels at 10.5 m (weighted 0.42-0.5 m). k = 5 takes the centre,
  // both cars and two buildings: car 2, building 2, tie -> car (lower id);
  // with k = 25 building wins 3 : 2.
  const std::size_t pb = add(5, 5, 10.0);
  label(5, 5, Class::kSidewalk);
  for (const auto& [r, col] : {std::pair{4, 5}, std::pair{6, 6}}) {
    add(r, col, 10.05);
    label(r, col, Class::kCar);
  }
  for (const auto& [r, col] : {std::pair{3, 3}, std::pair{7, 7}, std::pair{5, 7}}) {
    add(r, col, 10.5);
    label(r, col, Class::kBuilding);
  }
  // (c) The cutoff: centre (10 m) pole, four vegetation pixels next to it at
  // 11.5 m: weighted 1.5 (1 - 0.0983) = 1.35 m > 1 m, no vote -> pole; with a
  // 2 m cutoff vegetation wins 4 : 1.
  const std::size_t pc = add(5, 32, 10.0);
  label(5, 32, Class::kPole);
  for (const auto& [r, col] : {std::pair{4, 32}, std::pair{6, 32}, std::pair{5, 31}, std::pair{5, 33}}) {
    add(r, col, 11.5);
    label(r, col, Class::kVegetation);
  }
  // (d) The Gaussian weighting and unlabeled pixels: the centre (10 m) is
  // unlabeled (no vote); a trunk pixel next to it at 11.1 m is weighted
  // 1.1 x 0.9017 = 0.992 m <= 1 m and votes; two fence pixels in the window's
  // corners at 11.1 m are weighted 1.1 x 0.9970 = 1.097 m and do not -> trunk.
  // (Unweighted, nothing would vote; weighted by g instead of 1 - g, fence would win 2 : 1.)
  const std::size_t pd = add(2, 12, 10.0);
  add(2, 13, 11.1);
  label(2, 13, Class::kTrunk);
  for (const auto& [r, col] : {std::pair{0, 10}, std::pair{4, 14}}) {
    add(r, col, 11.1);
    label(r, col, Class::kFence);
  }
  // (e) No wrap-around at the image's left and right edges: road at column 0,
  // a car at the same range in column 39. Wrapped, the tie would go to car.
  const std::size_t pe = add(8, 0, 10.0);
  label(8, 0, Class::kRoad);
  add(8, 39, 10.0);
  label(8, 39, Class::kCar);
  // (f) A point with no direction is unlabeled.
  pts.emplace_back(0.0f, 0.0f, 0.0f);
  expected_pixel.push_back(-1);
  const std::size_t pf = pts.size() - 1;

  const semlio::Scan scan = scan_of(pts);
  std::vector<Class> out(scan.size(), Class::kUnlabeled);
  RangeProjection proj(c);
  proj.project(scan);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    INFO("point " << i);
    REQUIRE(proj.point_pixels()[i] == expected_pixel[i]);  // the constructed points sit where they should
  }
  proj.back_project(pixel_labels, out);
  CHECK(out[p0] == Class::kCar);
  CHECK(out[p1] == Class::kBuilding);
  CHECK(out[p1 + 1] == Class::kBuilding);  // a neighbour: its own pixel and the other three at 20.1 m
  CHECK(out[pb] == Class::kCar);
  CHECK(out[pc] == Class::kPole);
  CHECK(out[pd] == Class::kTrunk);
  CHECK(out[pe] == Class::kRoad);
  CHECK(out[pf] == Class::kUnlabeled);
  // Deterministic: the same scan gives the same labels.
  std::vector<Class> again(scan.size(), Class::kUnlabeled);
  proj.project(scan);
  proj.back_project(pixel_labels, again);
  CHECK(again == out);

  SECTION("more neighbours and a wider cutoff change exactly the cases that depend on them") {
    RangeProjectionConfig wide = c;
    wide.knn.k = 25;
    wide.knn.cutoff_m = 2.0;
    RangeProjection p2(wide);
    p2.project(scan);
    std::vector<Class> out2(scan.size(), Class::kUnlabeled);
    p2.back_project(pixel_labels, out2);
    CHECK(out2[pb] == Class::kBuilding);
    CHECK(out2[pc] == Class::kVegetation);
    CHECK(out2[p0] == Class::kCar);  // 10 m in range from its neighbours: still alone
  }
  SECTION("without the kNN vote each point takes its pixel's label") {
    RangeProjectionConfig off = c;
    off.knn.enabled = false;
    RangeProjection p3(off);
    p3.project(scan);
    std::vector<Class> out3(scan.size(), Class::kUnlabeled);
    p3.back_project(pixel_labels, out3);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      INFO("point " << i);
      const Class own = expected_pixel[i] < 0 ? Class::kUnlabeled : pixel_labels[static_cast<std::size_t>(expected_pixel[i])];
      CHECK(out3[i] == own);
    }
    CHECK(out3[p1] == Class::kCar);  // the hidden point: its occluder's label
  }
  SECTION("sizes that do not match are errors") {
    std::vector<Class> short_labels(10);
    CHECK_THROWS_AS(proj.back_project(short_labels, out), semlio::ValueError);
    std::vector<Class> short_out(3);
    CHECK_THROWS_AS(proj.back_project(pixel_labels, short_out), semlio::ValueError);
    std::vector<Class> bad = pixel_labels;
    bad[static_cast<std::size_t>(5 * 40 + 20)] = static_cast<Class>(200);
    CHECK_THROWS_AS(proj.back_project(bad, out), semlio::ValueError);
  }
}

TEST_CASE("RangeProjectionConfig: unusable settings are ConfigErrors naming the field", "[segment]") {
  const auto throws_naming = [](const RangeProjectionConfig& c, const char* field) {
    INFO(field);
    CHECK_THROWS_WITH(RangeProjection(c), Catch::Contains(field));
    CHECK_THROWS_AS(RangeProjection(c), semlio::ConfigError);
  };
  RangeProjectionConfig c;
  c.image.height_px = 0;
  throws_naming(c, "image.height_px");
  c = {};
  c.image.fov_up_rad = -30.0 * kDeg;
  throws_naming(c, "image.fov_up_rad");
  c = {};
  c.channel_mean.pop_back();
  throws_naming(c, "channel_mean");
  c = {};
  c.channel_std[2] = 0.0;
  throws_naming(c, "channel_std[2]");
  c = {};
  c.channels.clear();
  throws_naming(c, "channels");
  c = {};
  c.knn.search_px = 4;
  throws_naming(c, "knn.search_px");
  c = {};
  c.knn.k = 26;
  throws_naming(c, "knn.k");
  c = {};
  c.knn.cutoff_m = 0.0;
  throws_naming(c, "knn.cutoff_m");
}

}  // namespace test_range_projection
