#pragma once
// Inputs for the association / local-map / residual tests and benchmarks:
// feature clouds from the real KITTI scans in tests/data, and a synthetic
// street scene (ground, facades, cars, poles, vegetation) sampled twice, once
// as the map and once as a scan seen from a known pose.
#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <random>
#include <string>
#include <vector>

#include <semlio/core/labels.hpp>
#include <semlio/features/loam_features.hpp>
#include <semlio/features/preprocess.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/features/sensor_model.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/map/local_map.hpp>
#include <semlio_test/data.hpp>

namespace semlio_test {

/// A labelled feature cloud (satisfies semlio::LabelledCloud).
struct FeatureCloud {
  std::vector<Eigen::Vector3f> points;
  std::vector<semlio::Class> labels;
};

/// The KITTI scan at tests/data/<relative>, points nearer than 2 m (the car)
/// dropped, voxel-downsampled at leaf_m: a stand-in for LOAM surface features
/// (LIO-SAM downsamples its surface features at 0.4 m too).
inline FeatureCloud kitti_cloud(const std::string& relative, double leaf_m) {
  const semlio::Scan scan = semlio::io::read_kitti_bin(data_path(relative));
  std::vector<Eigen::Vector3f> kept;
  kept.reserve(scan.size());
  for (const Eigen::Vector3f& p : scan.points) {
    if (p.squaredNorm() >= 4.0F) kept.push_back(p);
  }
  FeatureCloud out;
  semlio::detail::downsample_labelled(kept, {}, leaf_m, out.points, out.labels);
  return out;
}

/// LOAM corner and surface features of one scan.
struct KittiFeatures {
  FeatureCloud corners;
  FeatureCloud surfaces;
};

/// The LOAM features (library defaults: preprocessing, HDL-64E rings, eq. 2
/// thresholds, 0.4 m surface voxels) of the KITTI scan at tests/data/<relative>.
inline KittiFeatures kitti_features(const std::string& relative) {
  semlio::Scan scan = semlio::io::read_kitti_bin(data_path(relative));
  semlio::preprocess(scan);
  semlio::infer_rings(scan, semlio::SensorModel::hdl64e());
  semlio::LoamFeatureExtractor extractor;
  semlio::LoamFeatures features;
  extractor.extract(scan, features);
  KittiFeatures out;
  out.corners.points = features.corners.points;
  out.corners.labels = features.corners.labels;
  out.surfaces.points = features.surfaces.points;
  out.surfaces.labels = features.surfaces.labels;
  return out;
}

/// Lidar-frame motion T_0_1 from scan 000001 to scan 000000 of KITTI sequence
/// 00 per the bundled ground truth (camera poses moved to the lidar frame).
/// Ground truth is extrapolated for these frames: a plausible initial guess,
/// not a reference.
inline semlio::SE3d kitti_T_0_1() {
  const auto calib = semlio::io::read_kitti_calib(data_path("kitti/sequences/00/calib.txt"));
  const auto poses = semlio::io::camera_to_lidar(
      semlio::io::read_kitti_poses(data_path("kitti/sequences/00/poses.txt")), *calib.T_cam0_velo);
  return poses.at(0).inverse() * poses.at(1);
}

/// Adds the LOAM features of KITTI 00 scan 000000 (identity pose) to `map`
/// and builds it: the map side of the real pair that the associator tests and
/// the front-end benchmarks query with scan 000001's features.
inline void build_kitti_pair_map(semlio::LocalMap& map) {
  const KittiFeatures f = kitti_features("kitti/sequences/00/velodyne/000000.bin");
  map.add_keyframe(semlio::SE3d(), f.corners, f.surfaces);
  map.build(Eigen::Vector3d::Zero());
}

/// Synthetic street: the same world sampled as a map (map frame) and as a
/// scan (scan frame, seen from T_map_scan).
struct StreetScene {
  FeatureCloud map_surfaces, map_corners;
  FeatureCloud scan_surfaces, scan_corners;
  semlio::SE3d T_map_scan;  ///< true pose of the scan
};

namespace detail {

/// Samples the street world (map frame) into surfaces / corners with the given
/// density scale; deterministic for a given seed.
inline void sample_street(std::mt19937& rng, double density, FeatureCloud& surfaces, FeatureCloud& corners) {
  using semlio::Class;
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  const auto uni = [&](double a, double b) { return a + (b - a) * u01(rng); };
  const auto add = [&](FeatureCloud& c, double x, double y, double z, Class label) {
    c.points.emplace_back(static_cast<float>(x + noise(rng)), static_cast<float>(y + noise(rng)),
                          static_cast<float>(z + noise(rng)));
    c.labels.push_back(label);
  };
  const auto count = [&](double n) { return static_cast<int>(n * density); };
  // Ground (road) and two facades (building).
  for (int i = 0; i < count(5000); ++i) add(surfaces, uni(-25, 25), uni(-9, 9), 0.0, Class::kRoad);
  for (int i = 0; i < count(2500); ++i) add(surfaces, uni(-25, 25), 9.0, uni(0, 6), Class::kBuilding);
  for (int i = 0; i < count(2500); ++i) add(surfaces, uni(-25, 25), -9.0, uni(0, 6), Class::kBuilding);
  // Parked cars: boxes 4 x 1.8 x 1.5 m, sides and roof.
  const double car_x[] = {-12.0, -4.0, 5.0, 14.0};
  const double car_y[] = {6.0, -6.5, 6.2, -6.0};
  for (int c = 0; c < 4; ++c) {
    const double x0 = car_x[c] - 2.0, x1 = car_x[c] + 2.0, y0 = car_y[c] - 0.9, y1 = car_y[c] + 0.9;
    for (int i = 0; i < count(150); ++i) {
      add(surfaces, uni(x0, x1), y0, uni(0.3, 1.5), Class::kCar);
      add(surfaces, uni(x0, x1), y1, uni(0.3, 1.5), Class::kCar);
      add(surfaces, x0, uni(y0, y1), uni(0.3, 1.5), Class::kCar);
      add(surfaces, x1, uni(y0, y1), uni(0.3, 1.5), Class::kCar);
      add(surfaces, uni(x0, x1), uni(y0, y1), 1.5, Class::kCar);
    }
    for (int i = 0; i < count(15); ++i) {  // vertical edges
      add(corners, x0, y0, uni(0.3, 1.5), Class::kCar);
      add(corners, x1, y1, uni(0.3, 1.5), Class::kCar);
    }
  }
  // Vegetation: filled blobs, normals point anywhere (Algorithm 1 rejects often).
  const double bush_x[] = {-18.0, 0.0, 19.0};
  for (const double bx : bush_x) {
    for (int i = 0; i < count(600); ++i) {
      add(surfaces, bx + uni(-1.5, 1.5), 7.5 + uni(-1.0, 1.0), uni(0.0, 2.5), Class::kVegetation);
    }
  }
  // Poles (lines) and the facade-ground edges.
  const double pole_x[] = {-20.0, -8.0, 2.0, 10.0, 22.0};
  for (const double px : pole_x) {
    for (int i = 0; i < count(60); ++i) add(corners, px, 8.0, uni(0.0, 5.0), Class::kPole);
    for (int i = 0; i < count(60); ++i) add(corners, px + 1.0, -8.0, uni(0.0, 5.0), Class::kPole);
  }
  for (int i = 0; i < count(300); ++i) add(corners, uni(-25, 25), 9.0, 6.0, Class::kBuilding);
  for (int i = 0; i < count(300); ++i) add(corners, uni(-25, 25), -9.0, 6.0, Class::kBuilding);
}

/// Moves a map-frame cloud into the scan frame.
inline void to_scan_frame(const semlio::SE3d& T_map_scan, FeatureCloud& c) {
  const semlio::SE3d T_scan_map = T_map_scan.inverse();
  for (Eigen::Vector3f& p : c.points) p = (T_scan_map * p.cast<double>()).cast<float>();
}

}  // namespace detail

/// The street sampled as a dense map and a sparser scan seen from a pose
/// 0.8 m ahead, slightly yawed; deterministic for a given seed.
inline StreetScene street_scene(unsigned seed) {
  StreetScene s;
  std::mt19937 rng(seed);
  detail::sample_street(rng, 2.0, s.map_surfaces, s.map_corners);
  detail::sample_street(rng, 0.6, s.scan_surfaces, s.scan_corners);
  Eigen::Matrix<double, 6, 1> xi;
  xi << 0.8, 0.05, 0.02, 0.002, -0.003, 0.02;
  s.T_map_scan = semlio::SE3d::exp(xi);
  detail::to_scan_frame(s.T_map_scan, s.scan_surfaces);
  detail::to_scan_frame(s.T_map_scan, s.scan_corners);
  return s;
}

}  // namespace semlio_test
