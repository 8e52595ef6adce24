#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <semlio/io/kitti.hpp>
#include <semlio/search/voxel_grid.hpp>
#include <semlio_test/data.hpp>

namespace test_voxel_grid {  // one namespace per test file: the area compiles as one TU

using semlio::Class;
using Eigen::Vector3f;

TEST_CASE("VoxelGrid centroid, first point, majority label and order", "[search]") {
  // leaf 1 m; voxel A = [0,1)^3, voxel B = [-1,0) x [0,1) x [0,1).
  const std::vector<Vector3f> pts = {
      {0.5F, 0.5F, 0.5F},    // 0 A
      {-0.5F, 0.5F, 0.5F},   // 1 B
      {0.1F, 0.2F, 0.3F},    // 2 A
      {-0.1F, 0.9F, 0.1F},   // 3 B
      {0.9F, 0.8F, 0.7F},    // 4 A
      {5.0F, 5.0F, 5.0F},    // 5 C alone
  };
  const std::vector<Class> labels = {Class::kRoad, Class::kCar, Class::kCar, Class::kBuilding,
                                     Class::kCar, Class::kPole};
  std::vector<Vector3f> out;
  std::vector<Class> out_labels;
  std::vector<std::uint32_t> first;
  SECTION("centroid") {
    semlio::VoxelGrid grid({.leaf_size_m = 1.0});
    grid.downsample(pts, labels, out, out_labels, first);
    REQUIRE(out.size() == 3);
    CHECK(first == std::vector<std::uint32_t>{0, 1, 5});  // ascending first index
    CHECK((out[0] - Vector3f(0.5F, 0.5F, 0.5F)).norm() < 1e-6F);
    CHECK((out[1] - Vector3f(-0.3F, 0.7F, 0.3F)).norm() < 1e-6F);
    CHECK(out[2] == pts[5]);
    CHECK(out_labels[0] == Class::kCar);       // car 2 : road 1
    CHECK(out_labels[1] == Class::kCar);       // tie car (1) / building (13): lowest id
    CHECK(out_labels[2] == Class::kPole);
  }
  SECTION("first point") {
    semlio::VoxelGrid grid({.leaf_size_m = 1.0, .point = semlio::VoxelPoint::kFirst});
    grid.downsample(pts, {}, out, out_labels, first);
    REQUIRE(out.size() == 3);
    CHECK(out[0] == pts[0]);
    CHECK(out[1] == pts[1]);
    CHECK(out_labels.empty());
  }
  SECTION("subset, indices refer to the full cloud") {
    semlio::VoxelGrid grid({.leaf_size_m = 1.0});
    grid.downsample(pts, labels, std::vector<std::uint32_t>{4, 2, 3}, out, out_labels, first);
    REQUIRE(out.size() == 2);
    CHECK(first == std::vector<std::uint32_t>{2, 3});
    CHECK((out[0] - Vector3f(0.5F, 0.5F, 0.5F)).norm() < 1e-6F);
    CHECK(out[1] == pts[3]);
  }
}

TEST_CASE("VoxelGrid counts voxels like brute force, skips non-finite, rejects bad leaves", "[search]") {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-10.0F, 10.0F);
  std::vector<Vector3f> pts(5000);
  for (auto& p : pts) p = Vector3f(u(rng), u(rng), u(rng));
  pts[17] = Vector3f(std::numeric_limits<float>::quiet_NaN(), 0.0F, 0.0F);
  const double leaf = 1.5;
  std::set<std::tuple<long, long, long>> cells;
  std::map<std::tuple<long, long, long>, std::uint32_t> first_of;
  for (std::uint32_t i = 0; i < pts.size(); ++i) {
    if (!pts[i].allFinite()) continue;
    const auto key = std::make_tuple(static_cast<long>(std::floor(static_cast<double>(pts[i].x()) / leaf)),
                                     static_cast<long>(std::floor(static_cast<double>(pts[i].y()) / leaf)),
                                     static_cast<long>(std::floor(static_cast<double>(pts[i].z()) / leaf)));
    cells.insert(key);
    first_of.emplace(key, i);
  }
  semlio::VoxelGrid grid({.leaf_size_m = leaf, .point = semlio::VoxelPoint::kFirst});
  std::vector<Vector3f> out;
  std::vector<Class> out_labels;
  std::vector<std::uint32_t> first;
  grid.downsample(pts, {}, out, out_labels, first);
  CHECK(out.size() == cells.size());
  std::set<std::uint32_t> expected_first;
  for (const auto& [k, i] : first_of) expected_first.insert(i);
  CHECK(std::set<std::uint32_t>(first.begin(), first.end()) == expected_first);
  // Reuse: a second call gives the same result.
  std::vector<std::uint32_t> again;
  grid.downsample(pts, {}, out, out_labels, again);
  CHECK(again == first);
  CHECK_THROWS_AS(semlio::VoxelGrid({.leaf_size_m = 0.0}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::VoxelGrid({.leaf_size_m = std::nan("")}), semlio::ConfigError);
  const std::vector<Class> wrong(3, Class::kCar);
  CHECK_THROWS_AS(grid.downsample(pts, wrong, out, out_labels, first), semlio::ValueError);
}

TEST_CASE("VoxelGrid on the real KITTI scan", "[search]") {
  const semlio::Scan scan =
      semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  semlio::VoxelGrid grid({.leaf_size_m = 0.5});
  std::vector<Vector3f> out;
  std::vector<Class> out_labels;
  std::vector<std::uint32_t> first;
  grid.downsample(scan.points, {}, out, out_labels, first);
  CHECK(out.size() < scan.size() / 2);
  CHECK(out.size() > 10000);
  // One output per voxel: keys of the first points are unique, and each
  // centroid lies inside its voxel.
  std::set<std::uint64_t> keys;
  for (std::size_t k = 0; k < out.size(); ++k) {
    const std::uint64_t key = semlio::voxel_key(scan.points[first[k]], 2.0);
    CHECK(keys.insert(key).second);
    const Vector3f lo = (scan.points[first[k]] * 2.0F).array().floor().matrix() * 0.5F;
    REQUIRE(((out[k] - lo).array() >= -1e-4F).all());
    REQUIRE(((out[k] - lo).array() <= 0.5F + 1e-4F).all());
  }
}

TEST_CASE("A reused VoxelGrid equals a fresh one across calls that grow and shrink its table", "[search]") {
  // The hash table is sized from the previous call's voxel count and doubles
  // mid-call when half full; stale slots of earlier calls must read as empty.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0F, 1.0F);
  semlio::VoxelGrid reused({.leaf_size_m = 0.25});
  for (const float extent : {0.5F, 40.0F, 1.0F, 200.0F, 3.0F, 60.0F}) {
    std::vector<Vector3f> pts(20000);
    std::vector<Class> labels(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      pts[i] = Vector3f(u(rng), u(rng), u(rng)) * extent;
      labels[i] = static_cast<Class>(i % 3);
    }
    semlio::VoxelGrid fresh({.leaf_size_m = 0.25});
    std::vector<Vector3f> a_pts;
    std::vector<Vector3f> b_pts;
    std::vector<Class> a_lab;
    std::vector<Class> b_lab;
    std::vector<std::uint32_t> a_idx;
    std::vector<std::uint32_t> b_idx;
    reused.downsample(pts, labels, a_pts, a_lab, a_idx);
    fresh.downsample(pts, labels, b_pts, b_lab, b_idx);
    CHECK(a_pts == b_pts);
    CHECK(a_lab == b_lab);
    CHECK(a_idx == b_idx);
    // And both count the voxels a set of keys counts.
    std::set<std::uint64_t> keys;
    for (const Vector3f& p : pts) keys.insert(semlio::voxel_key(p, 4.0));
    CHECK(a_pts.size() == keys.size());
  }
}

TEST_CASE("voxel_key equals the floor-and-clamp formula, on cell edges and far points too", "[search]") {
  // The literal key: floor each scaled coordinate, clamp into 21 bits.
  const auto literal = [](const Vector3f& p, double inv_leaf) {
    constexpr std::int64_t kHalf = std::int64_t{1} << 20;
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const double c = std::floor(static_cast<double>(p[a]) * inv_leaf);
      const double clamped = std::clamp(c, -static_cast<double>(kHalf), static_cast<double>(kHalf - 1));
      key = (key << 21) | static_cast<std::uint64_t>(static_cast<std::int64_t>(clamped) + kHalf);
    }
    return key;
  };
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> near(-3.0F, 3.0F);
  std::uniform_int_distribution<int> cell(-2000, 2000);
  std::uniform_real_distribution<double> log_mag(-40.0, 38.0);
  const std::vector<double> inv_leaves = {1.0 / 0.4, 1.0 / 0.2, 5.0, 1.0, 1e-3, 1e6};
  for (const double inv_leaf : inv_leaves) {
    for (int i = 0; i < 20000; ++i) {
      Vector3f p;
      for (int a = 0; a < 3; ++a) {
        switch (rng() % 5) {
          case 0: p[a] = near(rng); break;
          // On a cell boundary, and one float step either side of it.
          case 1: {
            const auto edge = static_cast<float>(cell(rng) / inv_leaf);
            const int step = static_cast<int>(rng() % 3) - 1;
            p[a] = step == 0 ? edge : std::nextafter(edge, step > 0 ? 1e30F : -1e30F);
            break;
          }
          case 2: p[a] = static_cast<float>((rng() % 2 == 0 ? 1.0 : -1.0) * std::pow(10.0, log_mag(rng))); break;
          case 3: p[a] = (rng() % 2 == 0 ? 1.0F : -1.0F) * std::numeric_limits<float>::max(); break;
          default: p[a] = rng() % 2 == 0 ? 0.0F : -0.0F; break;
        }
      }
      REQUIRE(semlio::voxel_key(p, inv_leaf) == literal(p, inv_leaf));
    }
  }
}

// The literal downsampling: one map entry per voxel key, sums in input
// order, majority label (lowest id on ties), outputs by ascending first index.
struct LiteralVoxels {
  std::vector<Vector3f> pts;
  std::vector<Class> labels;
  std::vector<std::uint32_t> first;
};
LiteralVoxels literal_downsample(const std::vector<Vector3f>& pts, const std::vector<Class>& labels,
                                 const std::vector<std::uint32_t>& subset, double leaf) {
  struct Acc {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::uint32_t count = 0;
    std::uint32_t first = std::numeric_limits<std::uint32_t>::max();
    std::map<int, int> votes;
  };
  std::map<std::uint64_t, Acc> cells;
  for (const std::uint32_t i : subset) {
    if (!pts[i].allFinite()) continue;
    Acc& a = cells[semlio::voxel_key(pts[i], 1.0 / leaf)];
    a.sum = a.count == 0 ? pts[i].cast<double>() : Eigen::Vector3d(a.sum + pts[i].cast<double>());
    ++a.count;
    a.first = std::min(a.first, i);
    if (!labels.empty()) ++a.votes[static_cast<int>(labels[i])];
  }
  std::vector<const Acc*> order;
  for (const auto& [key, a] : cells) order.push_back(&a);
  std::sort(order.begin(), order.end(), [](const Acc* a, const Acc* b) { return a->first < b->first; });
  LiteralVoxels out;
  for (const Acc* a : order) {
    out.pts.push_back(a->count > 1 ? Vector3f((a->sum / static_cast<double>(a->count)).cast<float>())
                                   : pts[a->first]);
    out.first.push_back(a->first);
    if (!labels.empty()) {
      int best = -1;
      int votes = 0;
      for (const auto& [c, v] : a->votes) {
        if (v > votes) {
          best = c;
          votes = v;
        }
      }
      out.labels.push_back(static_cast<Class>(best));
    }
  }
  return out;
}

TEST_CASE("VoxelGrid equals the literal downsampling bit for bit, in ring order, shuffled and on subsets",
          "[search]") {
  // Ring order (a real scan as stored) puts runs of points in one voxel, the
  // case the last-voxel shortcut serves; shuffled input has almost no runs.
  for (const char* name : {"000000.bin", "000001.bin"}) {
    const semlio::Scan scan =
        semlio::io::read_kitti_bin(semlio_test::data_path(std::string("kitti/sequences/00/velodyne/") + name));
    // Labels: mixed in nearly every voxel; one label for all (a scan without
    // a segmenter); and by region, in bands of 0.3 m across the 0.4 m voxels,
    // so that most voxels hold one label and the others turn mixed part-way,
    // often after several points of their first label.
    std::vector<Class> mixed(scan.size());
    for (std::size_t i = 0; i < mixed.size(); ++i) mixed[i] = static_cast<Class>((i * 7 + i / 13) % 5);
    const std::vector<Class> uniform(scan.size(), Class::kUnlabeled);
    std::vector<Class> banded(scan.size());
    for (std::size_t i = 0; i < banded.size(); ++i) {
      const auto band = static_cast<long>(std::floor(scan.points[i].x() / 0.3F));
      banded[i] = static_cast<Class>(((band % 4) + 4) % 4 + 1);
    }
    std::vector<std::uint32_t> all(scan.size());
    for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
    std::vector<std::uint32_t> shuffled = all;
    std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(5));
    std::vector<std::uint32_t> every_third;
    for (std::uint32_t i = 0; i < all.size(); i += 3) every_third.push_back(i);
    semlio::VoxelGrid grid({.leaf_size_m = 0.4});
    for (const auto* subset : {&all, &shuffled, &every_third}) {
      const std::vector<Class> no_labels;
      const std::array<const std::vector<Class>*, 4> label_sets{&no_labels, &mixed, &uniform, &banded};
      for (const std::vector<Class>* labels : label_sets) {
        const std::vector<Class>& l = *labels;
        const LiteralVoxels want = literal_downsample(scan.points, l, *subset, 0.4);
        std::vector<Vector3f> got;
        std::vector<Class> got_labels;
        std::vector<std::uint32_t> got_first;
        grid.downsample(scan.points, l, *subset, got, got_labels, got_first);
        REQUIRE(got.size() > 5000);
        CHECK(got_first == want.first);
        CHECK(got_labels == want.labels);
        std::size_t differing = 0;
        for (std::size_t k = 0; k < got.size() && k < want.pts.size(); ++k) {
          if (std::memcmp(got[k].data(), want.pts[k].data(), sizeof(float) * 3) != 0) ++differing;
        }
        CHECK(got.size() == want.pts.size());
        CHECK(differing == 0);
      }
    }
  }
}

}  // namespace test_voxel_grid
