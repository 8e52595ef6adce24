// Local map: keyframe selection by radius, transform into the map frame,
// voxel downsampling with majority labels, movable classes kept out, cached
// normals / line directions (eq. 3-6).
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <set>
#include <thread>
#include <cstddef>
#include <utility>
#include <vector>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/core/error.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/map/feature_map.hpp>
#include <semlio/map/feature_terms.hpp>
#include <semlio/map/local_map.hpp>
#include <semlio/residual/semantic_weighted.hpp>
#include <semlio/search/kdtree.hpp>
#include <semlio_test/associate_scenes.hpp>

namespace test_local_map {  // one namespace per test file: the area compiles as one TU

using semlio::Class;
using semlio::LocalMap;
using semlio::SE3d;
using semlio_test::FeatureCloud;

namespace {

// A 5 m x 5 m plane z = 0 sampled every 0.25 m (one point per 0.4 m voxel or more).
FeatureCloud plane_patch(Class label) {
  FeatureCloud c;
  for (int i = 0; i < 20; ++i) {
    for (int j = 0; j < 20; ++j) {
      c.points.emplace_back(0.25F * static_cast<float>(i) + 0.01F, 0.25F * static_cast<float>(j) + 0.01F, 0.0F);
      c.labels.push_back(label);
    }
  }
  return c;
}

// A vertical line x = y = 0.5, z in [0, 4), every 5 cm.
FeatureCloud vertical_line(Class label) {
  FeatureCloud c;
  for (int k = 0; k < 80; ++k) {
    c.points.emplace_back(0.5F, 0.5F, 0.05F * static_cast<float>(k) + 0.01F);
    c.labels.push_back(label);
  }
  return c;
}

SE3d translation(double x, double y, double z) { return SE3d(semlio::SO3d(), Eigen::Vector3d(x, y, z)); }

}  // namespace

TEST_CASE("Voxel downsampling keeps centroids and majority labels", "[map]") {
  // Leaf 1 m. Voxel (0,0,0): 3 points, 2 road + 1 car -> road, centroid by hand.
  // Voxel (1,0,0): car, building, building, car -> tie 2:2 -> lowest id (car = 1).
  const std::vector<Eigen::Vector3f> pts{{0.1F, 0.2F, 0.3F}, {0.5F, 0.5F, 0.5F}, {0.9F, 0.2F, 0.1F},
                                         {1.1F, 0.1F, 0.1F}, {1.2F, 0.1F, 0.1F}, {1.3F, 0.1F, 0.1F},
                                         {1.4F, 0.1F, 0.1F}, {-0.5F, 0.0F, 0.0F}};
  const std::vector<Class> labels{Class::kRoad, Class::kCar, Class::kRoad, Class::kCar,
                                  Class::kBuilding, Class::kBuilding, Class::kCar, Class::kVegetation};
  std::vector<Eigen::Vector3f> out;
  std::vector<Class> out_labels;
  semlio::detail::downsample_labelled(pts, labels, 1.0, out, out_labels);
  REQUIRE(out.size() == 3);
  // Output is sorted by voxel key: x = -1 first, then x = 0, then x = 1.
  CHECK(out[0].isApprox(Eigen::Vector3f(-0.5F, 0.0F, 0.0F)));
  CHECK(out_labels[0] == Class::kVegetation);
  CHECK(out[1].isApprox(Eigen::Vector3f(1.5F / 3.0F, 0.9F / 3.0F, 0.9F / 3.0F)));
  CHECK(out_labels[1] == Class::kRoad);
  CHECK(out[2].isApprox(Eigen::Vector3f(1.25F, 0.1F, 0.1F)));
  CHECK(out_labels[2] == Class::kCar);
}

TEST_CASE("Voxel downsampling (radix sort) equals its reference bit for bit", "[map]") {
  // The fast path must choose the same voxels, sum their points in the same
  // order and vote the same labels as the straightforward sort of (key,
  // index) pairs: on a real KITTI scan merged from shifted, turned copies (a
  // map rebuild's input), with and without labels, with non-finite points,
  // points beyond +-2^20 leaves, exact duplicates and label ties.
  const semlio::Scan scan = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  std::mt19937 rng(7);
  std::vector<Eigen::Vector3f> merged;
  std::vector<Class> labels;
  for (int k = 0; k < 6; ++k) {
    const Eigen::Matrix3f R = Eigen::AngleAxisf(0.02F * static_cast<float>(k), Eigen::Vector3f::UnitZ()).toRotationMatrix();
    for (std::size_t i = 0; i < scan.points.size(); i += 3) {
      merged.push_back(R * scan.points[i] + Eigen::Vector3f(0.8F * static_cast<float>(k), 0.05F, 0.0F));
      labels.push_back(semlio::class_from_index(static_cast<int>(rng() % 4U)));
    }
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (const Eigen::Vector3f& odd : {Eigen::Vector3f(nan, 0.0F, 0.0F), Eigen::Vector3f(0.0F, inf, 1.0F),
                                     Eigen::Vector3f(3.0e5F, 0.0F, 0.0F), Eigen::Vector3f(-3.0e5F, 1.0F, 1.0F),
                                     Eigen::Vector3f(1.01F, 2.01F, 0.01F), Eigen::Vector3f(1.01F, 2.01F, 0.01F)}) {
    merged.push_back(odd);
    labels.push_back(Class::kCar);
  }
  for (const double leaf : {0.2, 0.4, 1.0}) {
    for (const bool labelled : {true, false}) {
      const std::vector<Class> in_labels = labelled ? labels : std::vector<Class>{};
      std::vector<Eigen::Vector3f> ref, fast;
      std::vector<Class> ref_labels, fast_labels;
      semlio::detail::downsample_labelled_reference(merged, in_labels, leaf, ref, ref_labels);
      semlio::detail::DownsampleWorkspace ws;
      for (int call = 0; call < 2; ++call) {  // the second call reuses the workspace
        semlio::detail::downsample_labelled(merged, in_labels, leaf, fast, fast_labels, ws);
        INFO("leaf " << leaf << ", labelled " << labelled << ", call " << call);
        REQUIRE(fast.size() == ref.size());
        CHECK(fast_labels == ref_labels);
        std::size_t same = 0;
        for (std::size_t i = 0; i < ref.size(); ++i) same += (fast[i].array() == ref[i].array()).all() ? 1U : 0U;
        CHECK(same == ref.size());
      }
      CHECK(ref.size() > 1000);
      // Majority votes were exercised: some voxel holds more than one label.
      if (labelled) CHECK(std::set<Class>(ref_labels.begin(), ref_labels.end()).size() == 4);
    }
  }
  // Degenerate inputs: nothing valid, and everything in one voxel.
  std::vector<Eigen::Vector3f> out{Eigen::Vector3f::Ones()};
  std::vector<Class> out_labels{Class::kCar};
  semlio::detail::downsample_labelled({Eigen::Vector3f(nan, nan, nan)}, {}, 0.4, out, out_labels);
  CHECK(out.empty());
  CHECK(out_labels.empty());
  semlio::detail::downsample_labelled({Eigen::Vector3f(0.1F, 0.1F, 0.1F), Eigen::Vector3f(0.3F, 0.1F, 0.1F)}, {}, 0.4,
                                      out, out_labels);
  REQUIRE(out.size() == 1);
  CHECK(out[0].isApprox(Eigen::Vector3f(0.2F, 0.1F, 0.1F)));
  CHECK(out_labels == std::vector<Class>{Class::kUnlabeled});
}

TEST_CASE("LocalMap rebuilds by merging equal a from-scratch downsampling bit for bit", "[map]") {
  // A drive along x: a keyframe every 3 m, a 20 m radius, so each build
  // gains a newer keyframe and loses old ones (the merge path); then a
  // corrected pose and a return to the start (full rebuilds), and a map
  // capped at max_keyframes. After every build both maps must equal the
  // reference downsampling of the active keyframes merged in id order.
  const semlio_test::KittiFeatures f = semlio_test::kitti_features("kitti/sequences/00/velodyne/000000.bin");
  semlio_test::FeatureCloud corners = f.corners;
  corners.labels.clear();
  for (std::size_t i = 0; i < corners.points.size(); ++i) corners.labels.push_back(semlio::class_from_index(static_cast<int>(i % 3)));
  const semlio_test::FeatureCloud& surfaces = f.surfaces;  // unlabeled
  for (const auto& setting : {std::pair{std::size_t{0}, false}, std::pair{std::size_t{5}, false},
                               std::pair{std::size_t{0}, true}, std::pair{std::size_t{5}, true}}) {
    // Named copies, not a structured binding: lambdas below use them (clang < 16 cannot capture bindings).
    const std::size_t cap = setting.first;
    const bool first_point = setting.second;
    semlio::LocalMapConfig config;
    config.radius_m = 20.0;
    config.max_keyframes = cap;
    config.keep_first_point = first_point;
    LocalMap map(config);
    std::vector<SE3d> poses;
    const auto expect = [&](const LocalMap& m) {
      for (const bool corner : {true, false}) {
        const semlio_test::FeatureCloud& cloud = corner ? corners : surfaces;
        std::vector<Eigen::Vector3f> merged;
        std::vector<Class> labels;
        for (const std::size_t id : m.active_keyframes()) {
          const SE3d& T = poses[id];
          for (std::size_t i = 0; i < cloud.points.size(); ++i) {
            merged.push_back((T.rotation() * cloud.points[i].cast<double>() + T.translation()).cast<float>());
            labels.push_back(cloud.labels.empty() ? Class::kUnlabeled : cloud.labels[i]);
          }
        }
        std::vector<Eigen::Vector3f> ref;
        std::vector<Class> ref_labels;
        semlio::detail::downsample_labelled_reference(merged, labels, corner ? config.corner_leaf_m : config.surface_leaf_m,
                                                      ref, ref_labels, first_point);
        const semlio::FeatureMap& fm = corner ? m.corners() : m.surfaces();
        INFO((corner ? "corners" : "surfaces") << ", cap " << cap << ", first point " << first_point << ", active "
                                                << m.active_keyframes().size());
        REQUIRE(fm.points().size() == ref.size());
        CHECK(fm.points() == ref);
        CHECK(fm.labels() == ref_labels);
      }
    };
    const auto add = [&](const SE3d& T) {
      poses.push_back(T);
      map.add_keyframe(T, corners, surfaces);
      map.build(T.translation());
      expect(map);
    };
    for (int k = 0; k < 12; ++k) {
      add(SE3d(semlio::SO3d::exp(Eigen::Vector3d(0.0, 0.0, 0.01 * k)), Eigen::Vector3d(3.0 * k, 0.2 * k, 0.0)));
      CHECK(map.last_build_merged() == (k > 0));  // the first build has nothing to merge into
    }
    CHECK(map.active_keyframes().size() < 12);  // old keyframes left the radius
    // A corrected pose of an active keyframe (a loop closure would do this).
    const std::size_t last = map.active_keyframes().back();
    poses[last] = SE3d(semlio::SO3d(), poses[last].translation() + Eigen::Vector3d(0.0, 0.3, 0.0));
    map.set_keyframe_pose(last, poses[last]);
    map.build(poses[last].translation());
    CHECK_FALSE(map.last_build_merged());
    expect(map);
    // Back at the start: early keyframes (lower ids) become active again.
    add(SE3d(semlio::SO3d(), Eigen::Vector3d(1.0, 0.5, 0.0)));
    if (cap == 0) {
      CHECK(map.active_keyframes().front() == 0);
      CHECK_FALSE(map.last_build_merged());
    }
    // A step back: no older keyframe enters, the new one is merged in.
    add(SE3d(semlio::SO3d(), Eigen::Vector3d(0.0, 0.5, 0.0)));
    CHECK(map.last_build_merged());
  }
}

TEST_CASE("LocalMap with keep_first_point keeps map points in place as keyframes arrive", "[map]") {
  // Two keyframes whose points share voxels: with centroids the shared
  // voxels' points move when the second arrives; with keep_first_point every
  // point of the first build is still in the map, bit for bit, and the
  // second keyframe only adds points in voxels the first left empty.
  semlio_test::FeatureCloud cloud;
  for (int i = 0; i < 40; ++i) {
    cloud.points.emplace_back(0.05F + 0.1F * static_cast<float>(i), 0.13F, 0.07F);  // a line along x
  }
  const SE3d T0;
  const SE3d T1(semlio::SO3d(), Eigen::Vector3d(0.03, 0.02, 0.0));  // overlaps every voxel of the first
  const SE3d T2(semlio::SO3d(), Eigen::Vector3d(0.0, 0.5, 0.0));    // a parallel line: voxels of its own
  for (const bool first_point : {false, true}) {
    semlio::LocalMapConfig config;
    config.keep_first_point = first_point;
    config.corner_leaf_m = 0.2;
    LocalMap map(config);
    map.add_keyframe(T0, cloud, cloud);
    map.build(T0.translation());
    const std::vector<Eigen::Vector3f> before = map.corners().points();
    map.add_keyframe(T1, cloud, cloud);
    map.add_keyframe(T2, cloud, cloud);
    map.build(T0.translation());
    const std::vector<Eigen::Vector3f>& after = map.corners().points();
    std::size_t kept = 0;
    for (const Eigen::Vector3f& p : before) kept += std::count(after.begin(), after.end(), p) > 0 ? 1U : 0U;
    INFO("first point " << first_point << ": " << kept << " of " << before.size() << " kept");
    REQUIRE(before.size() == 20);
    CHECK(after.size() == 40);  // T2's line adds 20 voxels, T1's none
    if (first_point) {
      CHECK(kept == before.size());
    } else {
      CHECK(kept == 0);  // T1 moved every shared voxel's centroid
    }
  }
}

TEST_CASE("LocalMap selects keyframes by radius and moves them into the map frame", "[map]") {
  LocalMap map({.radius_m = 50.0, .corner_leaf_m = 0.2, .surface_leaf_m = 0.4});
  const FeatureCloud plane = plane_patch(Class::kRoad);
  const FeatureCloud line = vertical_line(Class::kPole);
  map.add_keyframe(translation(0, 0, 0), line, plane);
  map.add_keyframe(translation(30, 0, 0), line, plane);
  map.add_keyframe(translation(80, 0, 0), line, plane);
  REQUIRE(map.keyframe_count() == 3);
  CHECK(map.surfaces().empty());  // nothing before build()

  map.build(Eigen::Vector3d::Zero());
  CHECK(map.active_keyframes() == std::vector<std::size_t>{0, 1});
  // Every map point lies in one of the two moved patches (z = 0, x in [0,5) or [30,35)).
  for (const auto& p : map.surfaces().points()) {
    CHECK(std::abs(p.z()) < 1e-6F);
    const bool first = p.x() >= 0.0F && p.x() < 5.0F;
    const bool second = p.x() >= 30.0F && p.x() < 35.0F;
    CHECK((first || second));
  }
  // x, y in [0.01, 4.76] every 0.25 m into 0.4 m voxels: 12 x 12 voxels, each
  // non-empty (spacing < leaf), per keyframe.
  CHECK(map.surfaces().size() == 2 * 12 * 12);
  // Line: 5 cm steps into 0.2 m voxels: 4 m / 0.2 = 20 voxels per keyframe.
  CHECK(map.corners().size() == 2 * 20);
  for (const Class c : map.surfaces().labels()) CHECK(c == Class::kRoad);

  map.build(Eigen::Vector3d(80, 0, 0));  // 50 m radius: the 30 m and the 80 m keyframes
  CHECK(map.active_keyframes() == std::vector<std::size_t>{1, 2});

  // A corrected pose moves the points (loop closure).
  map.set_keyframe_pose(1, translation(30, 0, 2));
  map.build(Eigen::Vector3d(30, 0, 0));
  bool lifted = false;
  for (const auto& p : map.surfaces().points()) lifted = lifted || std::abs(p.z() - 2.0F) < 1e-5F;
  CHECK(lifted);
  CHECK_THROWS_AS(map.set_keyframe_pose(7, SE3d()), semlio::ValueError);
}

TEST_CASE("LocalMap stores at most max_keyframes, dropping the farthest outside the radius", "[map]") {
  semlio::LocalMapConfig config;
  config.radius_m = 50.0;
  config.max_keyframes = 5;
  LocalMap map(config);
  const FeatureCloud plane = plane_patch(Class::kRoad);
  const FeatureCloud line = vertical_line(Class::kPole);
  // A straight drive, a keyframe every 20 m; the map is rebuilt after each.
  for (int k = 0; k < 12; ++k) {
    CHECK(map.add_keyframe(translation(20.0 * k, 0, 0), line, plane) == static_cast<std::size_t>(k));
    map.build(Eigen::Vector3d(20.0 * k, 0, 0));
    CHECK(map.stored_keyframe_count() <= 5);
  }
  CHECK(map.keyframe_count() == 12);  // ids issued, dropped ones included
  CHECK(map.stored_keyframe_count() == 5);
  // Within 50 m of x = 220: the keyframes at 180, 200, 220 (ids 9, 10, 11).
  CHECK(map.active_keyframes() == std::vector<std::size_t>{9, 10, 11});
  CHECK(map.surfaces().size() == 3 * 12 * 12);
  // The two oldest kept are the nearest ones outside the radius (140, 160 m).
  CHECK(map.keyframe_pose(7).translation().x() == Approx(140.0));
  CHECK_THROWS_AS(map.keyframe_pose(0), semlio::ValueError);  // dropped
  map.set_keyframe_pose(0, translation(0, 0, 5));              // dropped: ignored
  CHECK_THROWS_AS(map.set_keyframe_pose(12, SE3d()), semlio::ValueError);  // never given

  // All inside the radius (standing still): the oldest goes.
  LocalMap still(config);
  for (int k = 0; k < 8; ++k) still.add_keyframe(translation(0.1 * k, 0, 0), line, plane);
  still.build(Eigen::Vector3d::Zero());
  CHECK(still.active_keyframes() == std::vector<std::size_t>{3, 4, 5, 6, 7});

  // 0 keeps everything.
  config.max_keyframes = 0;
  LocalMap all(config);
  for (int k = 0; k < 12; ++k) all.add_keyframe(translation(20.0 * k, 0, 0), line, plane);
  all.build(Eigen::Vector3d::Zero());
  CHECK(all.stored_keyframe_count() == 12);
}

TEST_CASE("LocalMap caches normals of surfaces and directions of corners", "[map]") {
  LocalMap map;
  // A rotated keyframe: the plane's normal and the line's direction rotate too.
  Eigen::Matrix<double, 6, 1> xi;
  xi << 1.0, 2.0, 0.5, 0.3, -0.2, 0.7;
  const SE3d T = SE3d::exp(xi);
  map.add_keyframe(T, vertical_line(Class::kPole), plane_patch(Class::kRoad));
  map.build(T.translation());
  const Eigen::Vector3f normal = (T.rotation() * Eigen::Vector3d::UnitZ()).cast<float>();
  REQUIRE(map.surfaces().axes().size() == map.surfaces().size());
  for (const auto& n : map.surfaces().axes()) CHECK(std::abs(n.dot(normal)) > 0.9999F);
  for (const auto& d : map.corners().axes()) CHECK(std::abs(d.dot(normal)) > 0.9999F);
  CHECK(map.surfaces().kind() == semlio::FeatureKind::kPlane);
  CHECK(map.corners().kind() == semlio::FeatureKind::kLine);
  CHECK(map.surfaces().shape_neighbours() == 10);
}

TEST_CASE("LocalMap can keep movable classes out", "[map]") {
  FeatureCloud mixed = plane_patch(Class::kRoad);
  for (std::size_t i = 0; i < mixed.labels.size(); i += 2) mixed.labels[i] = Class::kCar;
  LocalMap keep_all;
  LocalMap static_only({.exclude_dynamic = true});
  keep_all.add_keyframe(SE3d(), FeatureCloud{}, mixed);
  static_only.add_keyframe(SE3d(), FeatureCloud{}, mixed);
  keep_all.build(Eigen::Vector3d::Zero());
  static_only.build(Eigen::Vector3d::Zero());
  bool any_car = false;
  for (const Class c : keep_all.surfaces().labels()) any_car = any_car || c == Class::kCar;
  CHECK(any_car);
  for (const Class c : static_only.surfaces().labels()) CHECK_FALSE(semlio::is_dynamic(c));
  CHECK(static_only.surfaces().size() > 0);
}

TEST_CASE("LocalMap builds the real KITTI scan deterministically", "[map]") {
  const auto cloud = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000000.bin", 0.1);
  LocalMap a;
  LocalMap b;
  a.add_keyframe(SE3d(), cloud, cloud);
  b.add_keyframe(SE3d(), cloud, cloud);
  a.build(Eigen::Vector3d::Zero());
  b.build(Eigen::Vector3d::Zero());
  REQUIRE(a.surfaces().size() > 10000);
  CHECK(a.corners().size() > a.surfaces().size());  // smaller leaf, more points
  CHECK(a.surfaces().points() == b.surfaces().points());
  CHECK(a.surfaces().axes() == b.surfaces().axes());
  // No two surface map points share a 0.4 m voxel.
  std::vector<Eigen::Vector3f> again;
  std::vector<Class> labels;
  semlio::detail::downsample_labelled(a.surfaces().points(), {}, 0.4, again, labels);
  CHECK(again.size() == a.surfaces().size());
  // Every cached normal is usable (unit length): 10 neighbours always exist.
  std::size_t unit = 0;
  for (const auto& n : a.surfaces().axes()) unit += std::abs(n.norm() - 1.0F) < 1e-4F ? 1U : 0U;
  CHECK(unit == a.surfaces().size());
}

namespace {

// The real scan 000000 reduced to one point per voxel of `leaf_m` (the first
// in input order), sorted by voxel key, with its VoxelIndex: a map as
// LocalMap hands it to FeatureMap (built here without LocalMap's centroids,
// so the index is the only thing under test).
std::pair<std::vector<Eigen::Vector3f>, semlio::VoxelIndex> key_sorted_kitti_cloud(double leaf_m) {
  const auto cloud = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000000.bin", 0.1);
  std::vector<std::pair<std::uint64_t, Eigen::Vector3f>> keyed;
  for (const Eigen::Vector3f& p : cloud.points) {
    std::uint64_t key = 0;
    if (semlio::detail::reference_voxel_key(p, 1.0 / leaf_m, key)) keyed.emplace_back(key, p);
  }
  std::stable_sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Eigen::Vector3f> points;
  semlio::VoxelIndex index{.leaf_m = leaf_m, .keys = {}};
  for (const auto& [key, p] : keyed) {
    if (!index.keys.empty() && index.keys.back() == key) continue;
    index.keys.push_back(key);
    points.push_back(p);
  }
  return {points, index};
}

}  // namespace

TEST_CASE("FeatureMap::nearest equals a k-d tree k-NN cut at the gate", "[map]") {
  // Exactness of the candidate-list shortcut: random queries around the real
  // scan (on, near and away from the map), every k, several gates, lists of
  // several lengths (0 = k-d tree only), anchored by a 1-NN search or by a
  // voxel index lookup (which picks a farther anchor than the nearest).
  const bool with_index = GENERATE(false, true);
  const auto [points, index] = key_sorted_kitti_cloud(0.4);
  const semlio::VoxelIndex voxels = with_index ? index : semlio::VoxelIndex{};
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  std::normal_distribution<float> jitter(0.0F, 0.5F);
  std::vector<Eigen::Vector3f> queries;
  for (int i = 0; i < 3000; ++i) {
    const float scale = i % 3 == 0 ? 0.1F : (i % 3 == 1 ? 1.0F : 4.0F);
    queries.push_back(points[pick(rng)] + scale * Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng)));
  }
  for (const int list : {0, 12, 32}) {
    semlio::FeatureMap map(semlio::FeatureKind::kPlane);
    map.build(points, {}, 10, list, voxels);
    CHECK(map.candidate_list() == static_cast<std::size_t>(list == 0 ? 0 : std::max(list, 10)));
    // nanoflann's tree as the reference: independent of the map's own SmallKdTree3f.
    const semlio::KdTree3f reference(map.points());
    for (const double gate : {0.3, 1.0, std::numeric_limits<double>::infinity()}) {
      for (const std::size_t k : {std::size_t{1}, std::size_t{5}, std::size_t{15}, std::size_t{40}}) {
        std::size_t mismatches = 0;
        for (const auto& q : queries) {
          std::array<std::uint32_t, 64> ia{};
          std::array<float, 64> da{};
          std::array<std::uint32_t, 64> ib{};
          std::array<float, 64> db{};
          const std::size_t na = map.nearest(q, k, gate * gate, ia.data(), da.data());
          std::size_t nb = reference.knn(q, k, ib.data(), db.data());
          while (nb > 0 && !(static_cast<double>(db[nb - 1]) <= gate * gate)) --nb;
          bool same = na == nb;
          for (std::size_t j = 0; same && j < na; ++j) same = ia[j] == ib[j] && da[j] == db[j];
          mismatches += same ? 0U : 1U;
        }
        INFO("index " << with_index << " list " << list << " gate " << gate << " k " << k);
        CHECK(mismatches == 0);
      }
    }
  }
}

TEST_CASE("FeatureMap rejects a voxel index that does not fit its points", "[map]") {
  const auto [points, index] = key_sorted_kitti_cloud(0.4);
  REQUIRE(points.size() > 100);
  semlio::FeatureMap map(semlio::FeatureKind::kPlane);
  CHECK_NOTHROW(map.build(points, {}, 10, 32, index));
  semlio::VoxelIndex shorter = index;
  shorter.keys.pop_back();
  CHECK_THROWS_AS(map.build(points, {}, 10, 32, shorter), semlio::ValueError);
  semlio::VoxelIndex unsorted = index;
  std::swap(unsorted.keys[10], unsorted.keys[11]);
  CHECK_THROWS_AS(map.build(points, {}, 10, 32, unsorted), semlio::ValueError);
  semlio::VoxelIndex repeated = index;
  repeated.keys[11] = repeated.keys[10];
  CHECK_THROWS_AS(map.build(points, {}, 10, 32, repeated), semlio::ValueError);
  semlio::VoxelIndex no_leaf = index;
  no_leaf.leaf_m = 0.0;
  CHECK_THROWS_AS(map.build(points, {}, 10, 32, no_leaf), semlio::ValueError);
}

TEST_CASE("FeatureMap::nearest with a NearestCache equals a k-d tree k-NN cut at the gate", "[map]") {
  // Each query walks in shrinking steps (as Gauss-Newton moves a feature) and
  // sometimes jumps; one cache slot per walk. Every answer must equal the
  // k-d tree's, for several k and gates, and the walk must mostly hit.
  const auto cloud = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000000.bin", 0.4);
  semlio::FeatureMap map(semlio::FeatureKind::kPlane);
  map.build(cloud.points, {}, 10, 32);
  const semlio::KdTree3f reference(map.points());  // nanoflann, independent of the map's tree
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::size_t> pick(0, cloud.points.size() - 1);
  std::normal_distribution<float> jitter(0.0F, 1.0F);
  constexpr std::size_t kWalks = 400;
  for (const std::size_t list : {std::size_t{13}, std::size_t{30}}) {
    for (const double gate : {0.5, 1.0, std::numeric_limits<double>::infinity()}) {
      for (const std::size_t k : {std::size_t{1}, std::size_t{5}, std::size_t{13}}) {
        if (k > list) continue;
        semlio::NearestCache cache;
        cache.reset(kWalks, list);
        std::size_t mismatches = 0;
        for (std::size_t w = 0; w < kWalks; ++w) {
          Eigen::Vector3f q = cloud.points[pick(rng)] + 0.3F * Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng));
          float step = 0.08F;
          for (int it = 0; it < 8; ++it) {
            if (it == 5) q += Eigen::Vector3f(2.0F, 0.0F, 0.0F);  // a jump: the list must not be trusted
            std::array<std::uint32_t, 64> ia{};
            std::array<float, 64> da{};
            std::array<std::uint32_t, 64> ib{};
            std::array<float, 64> db{};
            const std::size_t na = map.nearest(q, k, gate * gate, ia.data(), da.data(), cache, w);
            std::size_t nb = reference.knn(q, k, ib.data(), db.data());
            while (nb > 0 && !(static_cast<double>(db[nb - 1]) <= gate * gate)) --nb;
            bool same = na == nb;
            for (std::size_t j = 0; same && j < na; ++j) same = ia[j] == ib[j] && da[j] == db[j];
            mismatches += same ? 0U : 1U;
            q += step * Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng));
            step *= 0.4F;
          }
        }
        INFO("list " << list << " gate " << gate << " k " << k);
        CHECK(mismatches == 0);
        if (2 * k <= list) CHECK(cache.hits() > cache.refills());  // a list with slack is reused
        CHECK(cache.refills() >= kWalks);  // every slot was filled once at least
      }
    }
  }
}

TEST_CASE("NearestCache::bind_queries empties the slots for a new query set only", "[map]") {
  // A slot filled for one scan's feature answers the same point again from its
  // list; once the cache is bound to another scan's features it refills first,
  // and the answer is the k-d tree's either way.
  const auto cloud = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000000.bin", 0.4);
  semlio::FeatureMap map(semlio::FeatureKind::kPlane);
  map.build(cloud.points, {}, 10, 32);
  const semlio::KdTree3f reference(map.points());
  semlio::NearestCache cache;
  cache.reset(1, 20);
  const Eigen::Vector3f q = cloud.points[cloud.points.size() / 2] + Eigen::Vector3f(0.05F, -0.03F, 0.02F);
  std::array<std::uint32_t, 64> idx{};
  std::array<float, 64> d2{};
  std::array<std::uint32_t, 64> ref_idx{};
  std::array<float, 64> ref_d2{};
  const std::size_t nr = reference.knn(q, 15, ref_idx.data(), ref_d2.data());
  const auto answer_is_reference = [&](std::size_t n) {
    bool same = n == nr;
    for (std::size_t j = 0; same && j < n; ++j) same = idx[j] == ref_idx[j] && d2[j] == ref_d2[j];
    return same;
  };
  const double gate2 = 1e6;  // every candidate inside
  cache.bind_queries(7);
  CHECK(answer_is_reference(map.nearest(q, 15, gate2, idx.data(), d2.data(), cache, 0)));
  CHECK((cache.hits() == 0 && cache.refills() == 1));
  cache.bind_queries(7);  // the same scan again: the slot stays
  CHECK(answer_is_reference(map.nearest(q, 15, gate2, idx.data(), d2.data(), cache, 0)));
  CHECK((cache.hits() == 1 && cache.refills() == 1));
  cache.bind_queries(8);  // another scan: its feature 0 is refilled, even at the same point
  CHECK(answer_is_reference(map.nearest(q, 15, gate2, idx.data(), d2.data(), cache, 0)));
  CHECK((cache.hits() == 1 && cache.refills() == 2));
}

TEST_CASE("FeatureMap::axis with a hint equals the plain fit", "[map]") {
  // The hint (the last fitted neighbourhood) bounds the next search: near
  // the last point (a feature's candidates), far from it (the next feature
  // across the scan) or with no hint yet, the axis must be the plain fit,
  // bit for bit, for several neighbourhood sizes and both kinds.
  const auto cloud = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000000.bin", 0.4);
  std::mt19937 rng(5);
  for (const semlio::FeatureKind kind : {semlio::FeatureKind::kPlane, semlio::FeatureKind::kLine}) {
    for (const int k : {3, 10, 25}) {
      semlio::FeatureMap map(kind);
      map.build(cloud.points, {}, k, 32);
      REQUIRE(map.size() > 1000);
      std::uniform_int_distribution<std::size_t> pick(0, map.size() - 1);
      semlio::FeatureMap::AxisHint hint;
      std::size_t mismatches = 0;
      std::size_t checked = 0;
      for (int feature = 0; feature < 300; ++feature) {
        // A random map point, then its 15 nearest, as Algorithm 1 reads them.
        std::array<std::uint32_t, 64> idx{};
        std::array<float, 64> d2{};
        const std::size_t n = map.tree().knn(map.points()[pick(rng)], 15, idx.data(), d2.data());
        for (std::size_t j = 0; j < n; ++j) {
          const Eigen::Vector3f expected =
              semlio::detail::neighbourhood_axis(map.tree(), kind, map.points()[idx[j]], k);
          mismatches += map.axis(idx[j], hint) == expected ? 0U : 1U;
          ++checked;
        }
      }
      INFO("kind " << static_cast<int>(kind) << " k " << k);
      CHECK(checked == 300U * 15U);
      CHECK(mismatches == 0);
      CHECK(map.fitted_axes() > 1000);  // most were fitted through the hint, not read back
    }
  }
}

TEST_CASE("FeatureMap's lazy axes and candidate lists equal an eager fit", "[map]") {
  // Axes and lists are computed on first use; whatever the access order
  // (axis first, list first via nearest(), or all at once), every axis must
  // equal a direct shape_neighbours-NN fit bit for bit -- what an eager build
  // and NormalConsistencyReference compute -- and a rebuild must forget them.
  const auto cloud = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000000.bin", 0.4);
  for (const semlio::FeatureKind kind : {semlio::FeatureKind::kPlane, semlio::FeatureKind::kLine}) {
    semlio::FeatureMap map(kind);
    map.build(cloud.points, {}, 10, 32);
    REQUIRE(map.size() > 1000);
    CHECK(map.fitted_axes() == 0);  // nothing fitted by build()
    // Lists first: queries at every 7th map point fill lists (and their axes).
    std::array<std::uint32_t, 64> idx{};
    std::array<float, 64> d2{};
    for (std::size_t i = 0; i < map.size(); i += 7) (void)map.nearest(map.points()[i], 15, 1.0, idx.data(), d2.data());
    const std::size_t after_lists = map.fitted_axes();
    CHECK(after_lists > 0);
    CHECK(after_lists < map.size());
    // Then single axes in a scattered order, then all of them.
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < map.size(); i += 3) {
      const Eigen::Vector3f expected =
          semlio::detail::neighbourhood_axis(map.tree(), kind, map.points()[i], map.shape_neighbours());
      mismatches += map.axis(i) == expected ? 0U : 1U;
    }
    const std::vector<Eigen::Vector3f>& all = map.axes();
    REQUIRE(all.size() == map.size());
    CHECK(map.fitted_axes() == map.size());
    for (std::size_t i = 0; i < map.size(); ++i) {
      const Eigen::Vector3f expected =
          semlio::detail::neighbourhood_axis(map.tree(), kind, map.points()[i], map.shape_neighbours());
      mismatches += all[i] == expected && map.axis(i) == expected ? 0U : 1U;
    }
    CHECK(mismatches == 0);
    // A rebuild over other points forgets every cached axis and list.
    std::vector<Eigen::Vector3f> moved = cloud.points;
    for (auto& p : moved) p.z() += 0.05F * p.x();
    map.build(moved, {}, 10, 32);
    CHECK(map.fitted_axes() == 0);
    for (std::size_t i = 0; i < map.size(); i += 5) {
      mismatches += map.axis(i) == semlio::detail::neighbourhood_axis(map.tree(), kind, map.points()[i], 10) ? 0U : 1U;
    }
    CHECK(mismatches == 0);
  }
}

TEST_CASE("FeatureMap's lazy caches are filled consistently by concurrent queries", "[map]") {
  // Four threads query the same map (const) at once, each in its own order;
  // every result must equal the single-threaded one.
  const auto cloud = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000000.bin", 0.4);
  semlio::FeatureMap reference(semlio::FeatureKind::kPlane);
  reference.build(cloud.points, {}, 10, 32);
  const std::vector<Eigen::Vector3f> expected = reference.axes();
  semlio::FeatureMap shared(semlio::FeatureKind::kPlane);
  shared.build(cloud.points, {}, 10, 32);
  std::array<std::size_t, 4> mismatches{};
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      std::array<std::uint32_t, 64> ia{};
      std::array<float, 64> da{};
      std::array<std::uint32_t, 64> ib{};
      std::array<float, 64> db{};
      const std::size_t n = shared.size();
      for (std::size_t j = 0; j < n; ++j) {
        const std::size_t i = (t % 2 == 0) ? (j * 7 + t) % n : n - 1 - (j * 3 + t) % n;
        mismatches[t] += shared.axis(i) == expected[i] ? 0U : 1U;
        const std::size_t na = shared.nearest(shared.points()[i], 15, 1.0, ia.data(), da.data());
        const std::size_t nb = reference.nearest(shared.points()[i], 15, 1.0, ib.data(), db.data());
        mismatches[t] += na == nb && std::equal(ia.begin(), ia.begin() + static_cast<std::ptrdiff_t>(na), ib.begin())
                             ? 0U
                             : 1U;
      }
    });
  }
  for (auto& th : threads) th.join();
  for (const std::size_t m : mismatches) CHECK(m == 0);
  CHECK(shared.axes() == expected);
}

TEST_CASE("LocalMap rejects bad settings and inputs", "[map]") {
  CHECK_THROWS_AS(LocalMap({.candidate_list = 65}), semlio::ConfigError);
  CHECK_THROWS_AS(LocalMap({.radius_m = 0.0}), semlio::ConfigError);
  CHECK_THROWS_AS(LocalMap({.surface_leaf_m = -1.0}), semlio::ConfigError);
  CHECK_THROWS_AS(LocalMap({.shape_neighbours = 2}), semlio::ConfigError);
  LocalMap map;
  FeatureCloud bad = plane_patch(Class::kRoad);
  bad.labels.pop_back();
  CHECK_THROWS_AS(map.add_keyframe(SE3d(), FeatureCloud{}, bad), semlio::ValueError);
}

namespace {

// Along converging poses from `start` (the step xi shrinking by half each
// time, as Gauss-Newton's do), re-associates `features` against `map` with
// NearestK and requires the cached and plain normal equations to be equal
// bit for bit; returns the smallest residual count seen.
template <typename R, typename Cache>
std::size_t require_cached_terms_equal(const FeatureCloud& features, const semlio::FeatureMap& map,
                                       const R& residual, Cache& cache, const SE3d& start,
                                       const Eigen::Matrix<double, 6, 1>& xi) {
  semlio::NearestK nearest;
  nearest.set_map(map);
  nearest.set_scan(features.points);
  semlio::FeatureSet set;
  set.points = features.points;
  set.labels = features.labels;
  semlio::Correspondences matches;
  std::size_t fewest = std::numeric_limits<std::size_t>::max();
  for (int k = 0; k <= 8; ++k) {
    const SE3d T = start * SE3d::exp((1.0 - std::pow(0.5, k)) * xi);
    nearest.associate(T, matches);
    semlio::NormalEquations plain;
    semlio::NormalEquations cached;
    semlio::accumulate_feature_terms(set, matches, map, residual, T, plain);
    semlio::accumulate_feature_terms(set, matches, map, residual, T, cached, cache);
    INFO("iteration " << k);
    CHECK(plain.H == cached.H);
    CHECK(plain.b == cached.b);
    CHECK(plain.cost == cached.cost);
    CHECK(plain.num_residuals == cached.num_residuals);
    fewest = std::min(fewest, plain.num_residuals);
  }
  return fewest;
}

}  // namespace

TEST_CASE("Residual fits reused across iterations give the very same normal equations", "[map][residual]") {
  // Real KITTI pair: scan 000001's features against the map of 000000. The
  // cached path must add exactly the terms the plain path adds, and must
  // actually reuse fits once the matches settle.
  const auto query = semlio_test::kitti_features("kitti/sequences/00/velodyne/000001.bin");
  LocalMap local;
  semlio_test::build_kitti_pair_map(local);
  const SE3d goal = semlio_test::kitti_T_0_1();
  const SE3d start = goal * SE3d::exp((Eigen::Matrix<double, 6, 1>() << 0.12, -0.05, 0.02, 0.0, 0.0, 0.01).finished());
  const Eigen::Matrix<double, 6, 1> xi = (start.inverse() * goal).log();

  // Planes on the surfaces; the same cache then serves the corner map
  // (another build): a stale fit would break the equality there.
  const semlio::SemanticWeighted<semlio::PointToPlane> plane;
  semlio::ResidualFitCache<semlio::PointToPlane::Model> cache;
  CHECK(require_cached_terms_equal(query.surfaces, local.surfaces(), plane, cache, start, xi) > 1000);
  CHECK(cache.hits() > query.surfaces.points.size());  // later iterations reused most fits
  require_cached_terms_equal(query.corners, local.corners(), plane, cache, start, xi);

  // Lines on the corners, with the pose-dependent ring-crossing check on:
  // it must still be applied to a reused line.
  semlio::PointToLineConfig line_config;
  line_config.min_cone_angle_rad = 0.35;
  const semlio::SemanticWeighted<semlio::PointToLine> line{semlio::PointToLine(line_config)};
  semlio::ResidualFitCache<semlio::PointToLine::Model> line_cache;
  CHECK(require_cached_terms_equal(query.corners, local.corners(), line, line_cache, start, xi) > 100);
  CHECK(line_cache.hits() > query.corners.points.size());
}

}  // namespace test_local_map
