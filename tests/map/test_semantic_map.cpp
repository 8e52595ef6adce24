// Global semantic map: voxel centroids with majority labels, movable classes
// dropped for the static map, poses applied, PLY round trip with SemanticKITTI
// labels; on a real SemanticKITTI scan as well as constructed clouds.
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/ply.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/map/semantic_map.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_kitti_tmp.hpp>

namespace test_semantic_map {  // one namespace per test file: the area compiles as one TU

using semlio::Class;
using semlio::SE3d;
using semlio::SemanticMap;
using semlio::SO3d;

namespace {

// Index of the map point nearest to p (the map is small).
std::size_t nearest(const semlio::Scan& cloud, const Eigen::Vector3f& p) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < cloud.size(); ++i) {
    if ((cloud.points[i] - p).squaredNorm() < (cloud.points[best] - p).squaredNorm()) best = i;
  }
  return best;
}

}  // namespace

TEST_CASE("semantic map: one point per voxel at the centroid, majority label", "[map]") {
  SemanticMap map({.leaf_size_m = 1.0});
  // Voxel [0,1)^3: 3 building points and 2 vegetation points -> building.
  // Voxel [2,3)x[0,1)x[0,1): 1 road point, 2 pole points -> pole.
  const std::vector<Eigen::Vector3f> pts{{0.1F, 0.2F, 0.3F}, {0.3F, 0.2F, 0.3F}, {0.5F, 0.2F, 0.3F},
                                         {0.7F, 0.8F, 0.9F}, {0.9F, 0.6F, 0.3F}, {2.5F, 0.5F, 0.5F},
                                         {2.1F, 0.1F, 0.1F}, {2.2F, 0.2F, 0.2F}};
  const std::vector<Class> labels{Class::kBuilding,   Class::kBuilding, Class::kBuilding, Class::kVegetation,
                                  Class::kVegetation, Class::kRoad,     Class::kPole,     Class::kPole};
  map.insert(SE3d(), pts, labels);
  const semlio::Scan cloud = map.cloud();
  REQUIRE(cloud.size() == 2);
  REQUIRE(cloud.labels.size() == 2);
  CHECK(cloud.labels[0] == Class::kBuilding);
  CHECK(cloud.labels[1] == Class::kPole);
  // Centroids by hand.
  CHECK(cloud.points[0].x() == Approx(0.5F));
  CHECK(cloud.points[0].y() == Approx(0.4F));
  CHECK(cloud.points[0].z() == Approx(0.42F));
  CHECK(cloud.points[1].x() == Approx(6.8F / 3.0F));
  CHECK(cloud.points[1].y() == Approx(0.8F / 3.0F));
  // A tie (1 car vs 1 road after adding to a fresh voxel) goes to the lowest class id.
  SemanticMap tie({.leaf_size_m = 1.0});
  tie.insert(SE3d(), std::vector<Eigen::Vector3f>{{5.2F, 5.2F, 5.2F}, {5.4F, 5.4F, 5.4F}},
             std::vector<Class>{Class::kRoad, Class::kCar});
  REQUIRE(tie.cloud().labels.size() == 1);
  CHECK(tie.cloud().labels[0] == Class::kCar);  // car (1) < road (9)
}

TEST_CASE("semantic map: labels accumulate over several clouds", "[map]") {
  SemanticMap map({.leaf_size_m = 0.5});
  const std::vector<Eigen::Vector3f> one{{0.1F, 0.1F, 0.1F}};
  map.insert(SE3d(), one, {Class::kFence});
  map.insert(SE3d(), one, {Class::kTerrain});
  map.insert(SE3d(), one, {Class::kTerrain});
  REQUIRE(map.size() == 1);
  CHECK(map.cloud().labels[0] == Class::kTerrain);
  map.insert(SE3d(), one, {Class::kFence});
  map.insert(SE3d(), one, {Class::kFence});
  CHECK(map.cloud().labels[0] == Class::kFence);
}

TEST_CASE("semantic map: drop_dynamic removes the movable classes only", "[map]") {
  std::vector<Eigen::Vector3f> pts;
  std::vector<Class> labels;
  for (int c = 0; c < semlio::kNumClasses; ++c) {
    pts.emplace_back(static_cast<float>(3 * c), 0.0F, 0.0F);  // one voxel per class
    labels.push_back(semlio::class_from_index(c));
  }
  // A voxel with 2 car points and 1 building point: only the building survives.
  pts.emplace_back(100.1F, 0.1F, 0.1F);
  pts.emplace_back(100.2F, 0.1F, 0.1F);
  pts.emplace_back(100.3F, 0.1F, 0.1F);
  labels.insert(labels.end(), {Class::kCar, Class::kCar, Class::kBuilding});

  SemanticMap all({.leaf_size_m = 0.5});
  all.insert(SE3d(), pts, labels);
  CHECK(all.size() == static_cast<std::size_t>(semlio::kNumClasses) + 1);

  SemanticMap clean({.leaf_size_m = 0.5, .drop_dynamic = true});
  clean.insert(SE3d(), pts, labels);
  const semlio::Scan cloud = clean.cloud();
  std::size_t dynamic_classes = 0;
  for (int c = 0; c < semlio::kNumClasses; ++c) dynamic_classes += semlio::is_dynamic(semlio::class_from_index(c)) ? 1 : 0;
  REQUIRE(dynamic_classes == 8);
  CHECK(cloud.size() == static_cast<std::size_t>(semlio::kNumClasses) - dynamic_classes + 1);
  for (const Class c : cloud.labels) CHECK_FALSE(semlio::is_dynamic(c));
  const std::size_t k = nearest(cloud, {100.2F, 0.1F, 0.1F});
  CHECK(cloud.labels[k] == Class::kBuilding);
  CHECK(cloud.points[k].x() == Approx(100.3F));  // the building point alone
}

TEST_CASE("semantic map: clouds are placed at their poses", "[map]") {
  const SE3d T_world_lidar(SO3d::exp(Eigen::Vector3d(0.0, 0.0, M_PI / 2.0)), Eigen::Vector3d(10.0, -5.0, 2.0));
  SemanticMap map({.leaf_size_m = 0.1});
  // Lidar point (4, 0, 0) -> world (10, -1, 2) after a +90 deg yaw.
  map.insert(T_world_lidar, std::vector<Eigen::Vector3f>{{4.0F, 0.0F, 0.0F}, {0.0F, 0.0F, 1.0F}},
             std::vector<Class>{Class::kTrunk, Class::kPole});
  const semlio::Scan cloud = map.cloud();
  REQUIRE(cloud.size() == 2);
  CHECK((cloud.points[0] - Eigen::Vector3f(10.0F, -1.0F, 2.0F)).norm() < 1e-5F);
  CHECK((cloud.points[1] - Eigen::Vector3f(10.0F, -5.0F, 3.0F)).norm() < 1e-5F);
  CHECK(cloud.labels[0] == Class::kTrunk);

  // The same wall seen from two poses merges into one set of voxels.
  std::vector<Eigen::Vector3f> wall_world;
  for (int y = 0; y < 20; ++y) {
    for (int z = 0; z < 10; ++z) wall_world.emplace_back(20.05F, 0.05F + 0.1F * static_cast<float>(y), 0.05F + 0.1F * static_cast<float>(z));
  }
  SemanticMap merged({.leaf_size_m = 0.1});
  for (const SE3d& T : {SE3d(), T_world_lidar, SE3d(SO3d::exp(Eigen::Vector3d(0.1, -0.2, 0.3)), Eigen::Vector3d(3, 4, 5))}) {
    std::vector<Eigen::Vector3f> in_lidar;
    for (const auto& p : wall_world) in_lidar.push_back((T.inverse() * p.cast<double>()).cast<float>());
    merged.insert(T, in_lidar, std::vector<Class>(in_lidar.size(), Class::kBuilding));
  }
  CHECK(merged.size() == wall_world.size());
}

TEST_CASE("semantic map: range limit, non-finite points, unlabeled clouds", "[map]") {
  SemanticMap map({.leaf_size_m = 0.5, .max_range_m = 10.0});
  const float nan = std::nanf("");
  map.insert(SE3d(), std::vector<Eigen::Vector3f>{{1.0F, 0.0F, 0.0F}, {20.0F, 0.0F, 0.0F}, {nan, 0.0F, 0.0F}}, {});
  const semlio::Scan cloud = map.cloud();
  REQUIRE(cloud.size() == 1);
  CHECK(cloud.labels.empty());
  CHECK_NOTHROW(cloud.validate());
  CHECK_NOTHROW(map.insert(SE3d(), std::vector<Eigen::Vector3f>{{1.0F, 0.0F, 0.0F}}, std::vector<Class>{}));
  CHECK_THROWS_AS(map.insert(SE3d(), std::vector<Eigen::Vector3f>{{1.0F, 0.0F, 0.0F}},
                             std::vector<Class>{Class::kRoad, Class::kRoad}),
                  semlio::ValueError);
  CHECK_THROWS_AS(SemanticMap({.leaf_size_m = 0.0}), semlio::ConfigError);
  CHECK_THROWS_AS(SemanticMap({.leaf_size_m = 0.2, .max_range_m = -1.0}), semlio::ConfigError);
  map.clear();
  CHECK(map.empty());
}

TEST_CASE("semantic map: real KITTI scan, static map, PLY round trip", "[map]") {
  // The real 124k-point scan of sequence 00, labelled by a crude rule so that
  // the static-map filter has something to remove: a car-sized box right of
  // the sensor is "car", the ground "road", the rest "building".
  semlio::Scan scan = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  REQUIRE(scan.size() > 100000);
  scan.labels.resize(scan.size());
  std::size_t cars = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const Eigen::Vector3f& p = scan.points[i];
    const bool car = p.x() > 2.0F && p.x() < 12.0F && p.y() < -2.0F && p.y() > -6.0F && p.z() > -1.5F;
    scan.labels[i] = car ? Class::kCar : (p.z() < -1.5F ? Class::kRoad : Class::kBuilding);
    cars += car ? 1 : 0;
  }
  REQUIRE(cars > 100);

  const SE3d T(SO3d::exp(Eigen::Vector3d(0.0, 0.0, 0.4)), Eigen::Vector3d(100.0, 50.0, 1.0));
  SemanticMap full({.leaf_size_m = 0.3});
  full.insert(T, scan);
  SemanticMap clean({.leaf_size_m = 0.3, .drop_dynamic = true});
  clean.insert(T, scan);
  const semlio::Scan map_full = full.cloud();
  const semlio::Scan map_clean = clean.cloud();
  CHECK(map_full.size() < scan.size() / 2);  // voxelised
  CHECK(map_clean.size() < map_full.size());
  const auto hist_full = semlio::label_histogram(map_full);
  const auto hist_clean = semlio::label_histogram(map_clean);
  CHECK(hist_full[static_cast<std::size_t>(Class::kCar)] > 0);
  CHECK(hist_clean[static_cast<std::size_t>(Class::kCar)] == 0);
  CHECK(hist_clean[static_cast<std::size_t>(Class::kRoad)] > 1000);
  // Every map point lies within one voxel diagonal of an input point put at T
  // (spot check on a sample).
  for (std::size_t i = 0; i < map_clean.size(); i += map_clean.size() / 50 + 1) {
    const Eigen::Vector3f p_lidar = (T.inverse() * map_clean.points[i].cast<double>()).cast<float>();
    float best = 1e9F;
    for (const auto& q : scan.points) best = std::min(best, (q - p_lidar).squaredNorm());
    CHECK(std::sqrt(best) < 0.3F * std::sqrt(3.0F));
  }

  semlio_test::KittiTempDir dir("semantic_map");
  const std::string path = dir.file("map.ply");
  semlio::io::write_ply(path, map_full);
  const semlio::Scan back = semlio::io::read_ply(path);
  REQUIRE(back.size() == map_full.size());
  REQUIRE(back.labels.size() == map_full.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < back.size(); ++i) {
    differing += back.points[i] == map_full.points[i] && back.labels[i] == map_full.labels[i] ? 0 : 1;
  }
  CHECK(differing == 0);
}

TEST_CASE("semantic map: real SemanticKITTI labels survive a fine map and the PLY file", "[map]") {
  const semlio::Scan scan = semlio::io::read_kitti_scan(
      semlio_test::data_path("kitti/semantickitti_subset/00/velodyne/000000.bin"),
      semlio_test::data_path("kitti/semantickitti_subset/00/labels/000000.label"));
  REQUIRE(scan.size() == 50);
  SemanticMap map({.leaf_size_m = 0.01});  // the 50 points are far apart: one voxel each
  map.insert(SE3d(), scan);
  const semlio::Scan cloud = map.cloud();
  REQUIRE(cloud.size() == scan.size());
  // Data README: building 25, vegetation 17, trunk 3, pole 2, other-structure 1
  // (-> unlabeled), unlabeled 2.
  const auto hist = semlio::label_histogram(cloud);
  CHECK(hist[static_cast<std::size_t>(Class::kBuilding)] == 25);
  CHECK(hist[static_cast<std::size_t>(Class::kVegetation)] == 17);
  CHECK(hist[static_cast<std::size_t>(Class::kTrunk)] == 3);
  CHECK(hist[static_cast<std::size_t>(Class::kPole)] == 2);
  CHECK(hist[static_cast<std::size_t>(Class::kUnlabeled)] == 3);
  semlio_test::KittiTempDir dir("semantic_map");
  const std::string path = dir.file("subset.ply");
  semlio::io::write_ply(path, cloud);
  CHECK(semlio::label_histogram(semlio::io::read_ply(path)) == hist);
}

}  // namespace test_semantic_map
