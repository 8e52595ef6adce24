#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <vector>

#include <semlio/features/preprocess.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio_test/data.hpp>

namespace test_preprocess {  // one namespace per test file: the area compiles as one TU

TEST_CASE("preprocess drops bad points, counts each reason and keeps fields in step", "[features]") {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  semlio::Scan scan;
  // Each point tagged with its intensity = its original index.
  const std::vector<Eigen::Vector3f> pts = {
      {10.0F, 0.0F, 0.0F},   // 0 kept
      {nan, 1.0F, 1.0F},     // 1 non-finite
      {0.0F, 0.0F, 0.0F},    // 2 zero
      {0.5F, 0.5F, 0.0F},    // 3 too near (0.71 m)
      {150.0F, 0.0F, 0.0F},  // 4 too far
      {1.5F, 0.0F, -1.0F},   // 5 in ego box (range 1.8 m)
      {-20.0F, 5.0F, 1.0F},  // 6 kept
      {1.0F, inf, 0.0F},     // 7 non-finite
      {0.0F, 3.0F, 0.0F},    // 8 kept (y = 3 m is beside the box)
      {2.5F, 0.0F, -1.0F},   // 9 kept (ahead of the box)
  };
  for (std::size_t i = 0; i < pts.size(); ++i) {
    scan.points.push_back(pts[i]);
    scan.intensity.push_back(static_cast<float>(i));
    scan.labels.push_back(semlio::class_from_index(static_cast<int>(i)));
  }
  const semlio::PreprocessReport r = semlio::preprocess(scan);
  CHECK(r.input == 10);
  CHECK(r.kept == 4);
  CHECK(r.dropped_nonfinite == 2);
  CHECK(r.dropped_zero == 1);
  CHECK(r.dropped_min_range == 1);
  CHECK(r.dropped_max_range == 1);
  CHECK(r.dropped_ego_box == 1);
  REQUIRE(scan.size() == 4);
  CHECK(scan.intensity == std::vector<float>{0.0F, 6.0F, 8.0F, 9.0F});
  CHECK(scan.labels[1] == semlio::class_from_index(6));
  CHECK(scan.points[2] == Eigen::Vector3f(0.0F, 3.0F, 0.0F));
}

TEST_CASE("preprocess options and config validation", "[features]") {
  semlio::Scan scan;
  scan.points = {{1.5F, 0.0F, -1.0F}, {50.0F, 0.0F, 0.0F}, {0.2F, 0.0F, 0.0F}};
  semlio::Scan copy = scan;
  const auto r = semlio::preprocess(
      copy, {.min_range_m = 0.1, .max_range_m = 40.0, .crop_ego_box = false});
  CHECK(r.dropped_ego_box == 0);
  CHECK(r.dropped_max_range == 1);
  CHECK(r.kept == 2);
  CHECK_THROWS_AS(semlio::preprocess(scan, {.min_range_m = -1.0}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::preprocess(scan, {.min_range_m = 5.0, .max_range_m = 4.0}), semlio::ConfigError);
  semlio::PreprocessConfig bad_box;
  bad_box.ego_box_min_m = Eigen::Vector3d(1, 0, 0);
  bad_box.ego_box_max_m = Eigen::Vector3d(0, 1, 1);
  CHECK_THROWS_AS(semlio::preprocess(scan, bad_box), semlio::ConfigError);
  semlio::Scan empty;
  CHECK(semlio::preprocess(empty).kept == 0);
  CHECK_THROWS_AS(semlio::preprocess(scan, {.vertical_correction_rad = 1.0}), semlio::ConfigError);
}

TEST_CASE("preprocess applies the KITTI vertical correction when asked", "[features]") {
  semlio::Scan scan;
  scan.points = {{20.0F, 0.0F, 0.0F}, {0.0F, -30.0F, 1.0F}};
  semlio::Scan plain = scan;
  semlio::preprocess(plain);
  CHECK(plain.points[0] == scan.points[0]);
  const auto config = semlio::kitti_preprocess_config();
  CHECK(config.vertical_correction_rad == semlio::kKittiVerticalCorrectionRad);
  semlio::preprocess(scan, config);
  for (std::size_t i = 0; i < 2; ++i) {
    CHECK(scan.points[i] == semlio::correct_vertical_angle(plain.points[i], semlio::kKittiVerticalCorrectionRad));
  }
  CHECK(scan.points[0].z() == Approx(20.0 * std::sin(semlio::kKittiVerticalCorrectionRad)));
}

TEST_CASE("preprocess on the real KITTI scan keeps almost everything", "[features]") {
  semlio::Scan scan = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  const std::size_t n = scan.size();
  const auto r = semlio::preprocess(scan);
  CHECK(r.input == n);
  CHECK(r.kept + r.dropped_nonfinite + r.dropped_zero + r.dropped_min_range + r.dropped_max_range +
            r.dropped_ego_box ==
        n);
  CHECK(r.dropped_nonfinite == 0);  // the reader already dropped them
  CHECK(r.dropped_zero == 0);
  CHECK(static_cast<double>(r.kept) > 0.99 * static_cast<double>(n));
  for (const auto& p : scan.points) {
    const float d = p.norm();
    REQUIRE((d >= 1.0F && d <= 100.0F));
  }
}

TEST_CASE("ring inference before or after preprocessing gives the same rings on KITTI", "[features]") {
  for (const char* name : {"000000.bin", "000001.bin"}) {
    const semlio::Scan raw =
        semlio::io::read_kitti_bin(semlio_test::data_path(std::string("kitti/sequences/00/velodyne/") + name));
    semlio::Scan rings_first = raw;
    semlio::infer_rings(rings_first, semlio::SensorModel::hdl64e());
    semlio::preprocess(rings_first, semlio::kitti_preprocess_config());
    semlio::Scan rings_after = raw;
    semlio::preprocess(rings_after, semlio::kitti_preprocess_config());
    const auto report = semlio::infer_rings(rings_after, semlio::SensorModel::hdl64e());
    CHECK(report.used == semlio::RingMethod::kPointOrder);
    CHECK(rings_after.rings == rings_first.rings);
  }
}

}  // namespace test_preprocess
