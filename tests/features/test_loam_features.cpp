#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <random>
#include <vector>

#include <semlio/core/fast_math.hpp>
#include <semlio/features/loam_features.hpp>
#include <semlio/features/preprocess.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/ply.hpp>
#include <semlio_test/data.hpp>

namespace test_loam_features {  // one namespace per test file: the area compiles as one TU

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// Appends a point at (range, azimuth) in the horizontal plane on ring `ring`.
void add_polar(semlio::Scan& scan, double range_m, double az_rad, std::uint16_t ring) {
  scan.points.emplace_back(static_cast<float>(range_m * std::cos(az_rad)),
                           static_cast<float>(range_m * std::sin(az_rad)), 0.0F);
  scan.rings.push_back(ring);
}

semlio::Scan real_kitti(const char* name) {
  semlio::Scan scan =
      semlio::io::read_kitti_bin(semlio_test::data_path(std::string("kitti/sequences/00/velodyne/") + name));
  semlio::infer_rings(scan, semlio::SensorModel::hdl64e());
  semlio::preprocess(scan);
  return scan;
}

}  // namespace

TEST_CASE("curvature of a straight line is zero", "[features]") {
  semlio::Scan scan;
  for (int k = 0; k < 41; ++k) {
    scan.points.emplace_back(-2.0F + 0.1F * static_cast<float>(k), 10.0F, 0.0F);
    scan.rings.push_back(0);
  }
  semlio::LoamFeatureExtractor ex;
  semlio::LoamFeatures f;
  const auto report = ex.extract(scan, f);
  CHECK(report.with_curvature == 31);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (i < 5 || i >= 36) {
      CHECK(ex.curvatures()[i] == -1.0F);  // ring ends: undefined
    } else {
      CHECK(ex.curvatures()[i] < 1e-10F);
    }
  }
  CHECK(f.corners.size() == 0);
  CHECK(report.surfaces_before_voxel == 31);
  CHECK(f.surfaces.size() > 0);
}

TEST_CASE("curvature of a corner equals the hand computation", "[features]") {
  // Apex a = (0, 10, 0); side A: a + 0.1 k (1, 1, 0), side B: a + 0.1 k (-1, 1, 0),
  // k = 1..5. sum_j (a - p_j) = -0.1 * 15 * ((1,1,0) + (-1,1,0)) = (0, -3, 0),
  // so c = 9 / (10 * ||a||) = 9 / 100 = 0.09.
  semlio::Scan scan;
  scan.points.emplace_back(0.0F, 10.0F, 0.0F);
  for (int k = 1; k <= 5; ++k) {
    const float s = 0.1F * static_cast<float>(k);
    scan.points.emplace_back(s, 10.0F + s, 0.0F);
    scan.points.emplace_back(-s, 10.0F + s, 0.0F);
  }
  scan.rings.assign(scan.size(), 3);
  semlio::LoamFeatureExtractor ex;
  semlio::LoamFeatures f;
  ex.extract(scan, f);
  CHECK(ex.curvatures()[0] == Approx(0.09).epsilon(1e-5));
  for (std::size_t i = 1; i < scan.size(); ++i) CHECK(ex.curvatures()[i] == -1.0F);
  REQUIRE(f.corners.size() == 1);
  CHECK(f.corners.indices[0] == 0);
  CHECK(f.corners.points[0] == scan.points[0]);
}

TEST_CASE("occlusion and grazing-beam rejection", "[features]") {
  SECTION("a foreground object occludes the 6 background points beside it") {
    // 100 points 0.2 deg apart; positions 40..59 at 10 m, the rest at 20 m.
    semlio::Scan scan;
    for (int k = 0; k < 100; ++k) add_polar(scan, (k >= 40 && k < 60) ? 10.0 : 20.0, 0.2 * k * kDeg, 0);
    semlio::LoamFeatureExtractor ex;
    semlio::LoamFeatures f;
    const auto report = ex.extract(scan, f);
    for (std::size_t k = 0; k < 100; ++k) {
      INFO("point " << k);
      const bool expect = (k >= 34 && k <= 39) || (k >= 60 && k <= 65);
      CHECK(ex.rejected(k) == expect);
    }
    CHECK(report.occluded == 12);
    // The foreground edges are not rejected and are the sharpest points.
    CHECK(std::find(f.corners.indices.begin(), f.corners.indices.end(), 40U) != f.corners.indices.end());
    CHECK(std::find(f.corners.indices.begin(), f.corners.indices.end(), 59U) != f.corners.indices.end());
    for (const std::uint32_t i : f.corners.indices) CHECK_FALSE(ex.rejected(i));
  }
  SECTION("no occlusion across an azimuth gap") {
    semlio::Scan scan;
    for (int k = 0; k < 40; ++k) add_polar(scan, 20.0, 0.2 * k * kDeg, 0);
    for (int k = 0; k < 40; ++k) add_polar(scan, 10.0, (20.0 + 0.2 * k) * kDeg, 0);  // 12 deg gap
    semlio::LoamFeatureExtractor ex;
    semlio::LoamFeatures f;
    const auto report = ex.extract(scan, f);
    CHECK(report.occluded == 0);
  }
  SECTION("a point whose range jumps against both neighbours is a grazing beam") {
    // Range 10 m except position 30 at 10.25 m: |dr| = 0.25 > 0.02 * 10.25 on
    // both sides, below the 0.3 m occlusion gap.
    semlio::Scan scan;
    for (int k = 0; k < 60; ++k) add_polar(scan, k == 30 ? 10.25 : 10.0, 0.2 * k * kDeg, 0);
    semlio::LoamFeatureExtractor ex;
    semlio::LoamFeatures f;
    const auto report = ex.extract(scan, f);
    CHECK(report.occluded == 0);
    CHECK(report.parallel == 1);
    CHECK(ex.rejected(30));
    CHECK_FALSE(ex.rejected(29));
    CHECK_FALSE(ex.rejected(31));
    CHECK(std::find(f.corners.indices.begin(), f.corners.indices.end(), 30U) == f.corners.indices.end());
  }
}

TEST_CASE("corners per sector respect the cap and are the sharpest", "[features]") {
  // 4 rings of 600 noisy points (range 10 +- 0.1 m): every point is a corner
  // candidate with threshold 0; cap 3 per sector -> exactly 4 * 6 * 3.
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> noise(-0.1, 0.1);
  semlio::Scan scan;
  const int per_ring = 600;
  for (std::uint16_t r = 0; r < 4; ++r) {
    for (int k = 0; k < per_ring; ++k) add_polar(scan, 10.0 + noise(rng), 0.5 * k * kDeg, r);
  }
  semlio::LoamFeatureExtractor ex({.max_corners_per_sector = 3,
                                   .corner_threshold_m = 0.0,
                                   .surface_threshold_m = -1.0,
                                   .parallel_beam_ratio = 1.0});
  semlio::LoamFeatures f;
  ex.extract(scan, f);
  CHECK(f.corners.size() == 4 * 6 * 3);
  CHECK(f.surfaces.size() == 0);
  // Sector s of a ring covers positions 5 + 590 s / 6 .. 5 + 590 (s+1) / 6.
  for (int r = 0; r < 4; ++r) {
    for (int s = 0; s < 6; ++s) {
      const int sp = r * per_ring + 5 + 590 * s / 6;
      const int ep = r * per_ring + 5 + 590 * (s + 1) / 6;
      const auto n = std::count_if(f.corners.indices.begin(), f.corners.indices.end(), [&](std::uint32_t i) {
        return static_cast<int>(i) >= sp && static_cast<int>(i) < ep;
      });
      CHECK(n == 3);
      // The sharpest point of the sector is among them.
      int best = sp;
      for (int i = sp; i < ep; ++i) {
        if (ex.curvatures()[static_cast<std::size_t>(i)] > ex.curvatures()[static_cast<std::size_t>(best)]) best = i;
      }
      CHECK(std::find(f.corners.indices.begin(), f.corners.indices.end(), static_cast<std::uint32_t>(best)) !=
            f.corners.indices.end());
    }
  }
  // Chosen corners are at least 6 positions apart within a ring (neighbour suppression).
  for (std::size_t k = 1; k < f.corners.size(); ++k) {
    const std::uint32_t a = f.corners.indices[k - 1];
    const std::uint32_t b = f.corners.indices[k];
    if (a / per_ring == b / per_ring) CHECK(b - a > 5);
  }
}

TEST_CASE("scan order does not matter: rings are sorted by azimuth", "[features]") {
  semlio::Scan ordered;
  for (int k = 0; k < 80; ++k) add_polar(ordered, (k >= 30 && k < 50) ? 8.0 : 12.0, 0.3 * k * kDeg, 0);
  semlio::Scan reversed;
  for (std::size_t k = ordered.size(); k-- > 0;) {
    reversed.points.push_back(ordered.points[k]);
    reversed.rings.push_back(0);
  }
  semlio::LoamFeatureExtractor ex;
  semlio::LoamFeatures a;
  semlio::LoamFeatures b;
  ex.extract(ordered, a);
  ex.extract(reversed, b);
  REQUIRE(a.corners.size() == b.corners.size());
  for (std::size_t k = 0; k < a.corners.size(); ++k) {
    CHECK(b.corners.indices[a.corners.size() - 1 - k] == 79 - a.corners.indices[k]);
  }
}

namespace {

/// LOAM's selection written out literally (full sorts, no buffers), from the
/// extractor's own curvatures and rejection flags: the corner indices and the
/// surface indices before the voxel, each ascending.
void reference_selection(const semlio::Scan& scan, const semlio::LoamFeatureExtractor& ex,
                         std::vector<std::uint32_t>& corners, std::vector<std::uint32_t>& surfaces) {
  const auto& cfg = ex.config();
  const auto h = static_cast<std::size_t>(cfg.neighbours);
  std::vector<float> az(scan.size());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const double a = semlio::atan2_fast(static_cast<double>(scan.points[i].y()), static_cast<double>(scan.points[i].x()));
    az[i] = static_cast<float>(a < 0.0 ? a + 2.0 * std::numbers::pi : a);
  }
  std::map<std::uint16_t, std::vector<std::uint32_t>> rings;
  for (std::uint32_t i = 0; i < scan.size(); ++i) rings[scan.rings[i]].push_back(i);
  corners.clear();
  surfaces.clear();
  for (auto& ring_points : rings) {
    std::vector<std::uint32_t>& idx = ring_points.second;  // not a binding: lambdas below capture it (clang < 16)
    std::sort(idx.begin(), idx.end(), [&](std::uint32_t a, std::uint32_t b) { return az[a] < az[b] || (az[a] == az[b] && a < b); });
    const std::size_t m = idx.size();
    if (m < 2 * h + 1) continue;
    const auto adjacent = [&](std::size_t k) { return static_cast<double>(az[idx[k + 1]] - az[idx[k]]) <= cfg.max_neighbour_gap_rad; };
    std::vector<bool> picked(m, false);
    const std::size_t valid = m - 2 * h;
    const auto sectors = static_cast<std::size_t>(cfg.sectors);
    for (std::size_t s = 0; s < sectors; ++s) {
      const std::size_t sp = h + valid * s / sectors;
      const std::size_t ep = h + valid * (s + 1) / sectors;
      std::vector<std::size_t> cand;
      for (std::size_t k = sp; k < ep; ++k) {
        if (static_cast<double>(ex.curvatures()[idx[k]]) > cfg.corner_threshold_m) cand.push_back(k);
      }
      std::sort(cand.begin(), cand.end(), [&](std::size_t x, std::size_t y) {
        const float cx = ex.curvatures()[idx[x]];
        const float cy = ex.curvatures()[idx[y]];
        return cx > cy || (cx == cy && x < y);
      });
      std::size_t taken = 0;
      for (const std::size_t k : cand) {
        if (taken >= cfg.max_corners_per_sector) break;
        if (picked[k] || ex.rejected(idx[k])) continue;
        corners.push_back(idx[k]);
        ++taken;
        picked[k] = true;
        for (std::size_t j = 1; j <= h && k + j < m && adjacent(k + j - 1); ++j) picked[k + j] = true;
        for (std::size_t j = 1; j <= h && j <= k && adjacent(k - j); ++j) picked[k - j] = true;
      }
      for (std::size_t k = sp; k < ep; ++k) {
        const float c = ex.curvatures()[idx[k]];
        if (!picked[k] && !ex.rejected(idx[k]) && c >= 0.0F && static_cast<double>(c) < cfg.surface_threshold_m) {
          surfaces.push_back(idx[k]);
        }
      }
    }
  }
  std::sort(corners.begin(), corners.end());
  std::sort(surfaces.begin(), surfaces.end());
}

}  // namespace

TEST_CASE("selection equals a literal LOAM selection on the real scans", "[features]") {
  semlio::Scan pair = semlio::io::read_ply(semlio_test::data_path("scan_pair/source.ply"));
  semlio::infer_rings(pair, semlio::SensorModel::hdl32e());
  semlio::preprocess(pair);
  std::vector<semlio::Scan> scans = {real_kitti("000000.bin"), real_kitti("000001.bin"), pair};
  // The same scan with its points in reverse: every ring far from sorted.
  semlio::Scan reversed;
  for (std::size_t i = scans[0].size(); i-- > 0;) {
    reversed.points.push_back(scans[0].points[i]);
    reversed.rings.push_back(scans[0].rings[i]);
  }
  scans.push_back(reversed);
  for (const semlio::Scan& scan : scans) {
    semlio::LoamFeatureExtractor ex({.surface_leaf_m = 0.0});
    semlio::LoamFeatures f;
    ex.extract(scan, f);
    std::vector<std::uint32_t> corners;
    std::vector<std::uint32_t> surfaces;
    reference_selection(scan, ex, corners, surfaces);
    CHECK(corners.size() > 1000);
    CHECK(f.corners.indices == corners);
    CHECK(f.surfaces.indices == surfaces);
  }
}

TEST_CASE("bad and empty input", "[features]") {
  semlio::LoamFeatureExtractor ex;
  semlio::LoamFeatures f;
  semlio::Scan scan;
  CHECK_NOTHROW(ex.extract(scan, f));
  CHECK(f.corners.size() == 0);
  scan.points.emplace_back(1.0F, 2.0F, 3.0F);
  CHECK_THROWS_AS(ex.extract(scan, f), semlio::ValueError);
  scan.rings = {0};
  const auto report = ex.extract(scan, f);  // a ring too short for eq. 2
  CHECK(report.rings == 0);
  CHECK(f.surfaces.size() == 0);
  CHECK_THROWS_AS(semlio::LoamFeatureExtractor({.neighbours = 0}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::LoamFeatureExtractor({.surface_leaf_m = std::nan("")}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::LoamFeatureExtractor({.corner_leaf_m = std::nan("")}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::LoamFeatureExtractor({.corner_leaf_m = HUGE_VAL}), semlio::ConfigError);
}

TEST_CASE("corner voxel leaf: one corner per occupied voxel, at the centroid of its corners", "[features]") {
  semlio::Scan scan = real_kitti("000000.bin");
  scan.labels.assign(scan.size(), semlio::Class::kPole);
  semlio::LoamFeatureConfig all_cfg;
  all_cfg.corner_leaf_m = 0.0;
  semlio::LoamFeatureConfig leaf_cfg;
  leaf_cfg.corner_leaf_m = 0.2;
  semlio::LoamFeatureExtractor all_ex(all_cfg);
  semlio::LoamFeatureExtractor leaf_ex(leaf_cfg);
  semlio::LoamFeatures all;
  semlio::LoamFeatures leafed;
  all_ex.extract(scan, all);
  leaf_ex.extract(scan, leafed);
  // Surfaces do not depend on the corner leaf.
  CHECK(leafed.surfaces.indices == all.surfaces.indices);
  // Group the undownsampled corners by voxel (as the voxel grid keys them).
  const double inv_leaf = 1.0 / leaf_cfg.corner_leaf_m;
  std::map<std::uint64_t, std::vector<Eigen::Vector3f>> voxels;
  for (const Eigen::Vector3f& p : all.corners.points) voxels[semlio::voxel_key(p, inv_leaf)].push_back(p);
  REQUIRE(leafed.corners.size() == voxels.size());
  CHECK(leafed.corners.size() < all.corners.size());
  REQUIRE(leafed.corners.labels.size() == leafed.corners.size());
  REQUIRE(leafed.corners.indices.size() == leafed.corners.size());
  for (std::size_t k = 0; k < leafed.corners.size(); ++k) {
    const std::uint32_t i = leafed.corners.indices[k];
    REQUIRE(i < scan.size());
    const auto it = voxels.find(semlio::voxel_key(scan.points[i], inv_leaf));
    REQUIRE(it != voxels.end());  // the representative index is one of the voxel's corners
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3f& p : it->second) mean += p.cast<double>();
    mean /= static_cast<double>(it->second.size());
    CHECK((leafed.corners.points[k].cast<double>() - mean).norm() < 1e-5);
    CHECK(leafed.corners.labels[k] == semlio::Class::kPole);
  }
}

TEST_CASE("features of the real KITTI scans", "[features]") {
  semlio::Scan scan = real_kitti("000000.bin");
  // Give the points labels (by ring parity) to check label propagation.
  scan.labels.resize(scan.size());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    scan.labels[i] = (scan.rings[i] % 2 == 0) ? semlio::Class::kRoad : semlio::Class::kBuilding;
  }
  semlio::LoamFeatureExtractor ex;
  semlio::LoamFeatures f;
  const auto report = ex.extract(scan, f);
  const auto& cfg = ex.config();
  CHECK(report.rings == 64);
  CHECK(f.corners.size() > 1000);
  CHECK(f.corners.size() <= 64 * 6 * cfg.max_corners_per_sector);
  CHECK(f.surfaces.size() > 2000);
  CHECK(f.surfaces.size() < report.surfaces_before_voxel);
  REQUIRE(f.corners.labels.size() == f.corners.size());
  REQUIRE(f.surfaces.labels.size() == f.surfaces.size());
  for (std::size_t k = 0; k < f.corners.size(); ++k) {
    const std::uint32_t i = f.corners.indices[k];
    REQUIRE(i < scan.size());
    CHECK(static_cast<double>(ex.curvatures()[i]) > cfg.corner_threshold_m);
    CHECK_FALSE(ex.rejected(i));
    CHECK(f.corners.points[k] == scan.points[i]);
    CHECK(f.corners.labels[k] == scan.labels[i]);
  }
  for (std::size_t k = 0; k < f.surfaces.size(); ++k) {
    const std::uint32_t i = f.surfaces.indices[k];
    REQUIRE(i < scan.size());
    CHECK(static_cast<double>(ex.curvatures()[i]) < cfg.surface_threshold_m);
    CHECK((f.surfaces.points[k] - scan.points[i]).norm() < 0.4F * std::sqrt(3.0F) + 1e-4F);
  }
  // Deterministic and allocation-free on the next scans of similar size: run
  // the same scan again, the outputs keep their buffers and contents.
  const semlio::LoamFeatures first = f;
  const auto* corner_data = f.corners.points.data();
  const auto* surface_data = f.surfaces.points.data();
  ex.extract(scan, f);
  CHECK(f.corners.indices == first.corners.indices);
  CHECK(f.surfaces.indices == first.surfaces.indices);
  CHECK(f.corners.points.data() == corner_data);
  CHECK(f.surfaces.points.data() == surface_data);
  // The neighbouring scan gives a similar number of features.
  const semlio::Scan next = real_kitti("000001.bin");
  semlio::LoamFeatures g;
  ex.extract(next, g);
  CHECK(std::abs(static_cast<double>(g.corners.size()) - static_cast<double>(f.corners.size())) <
        0.2 * static_cast<double>(f.corners.size()));
  CHECK(g.corners.labels.empty());
}

TEST_CASE("features of the real 32-beam scan pair", "[features]") {
  semlio::Scan scan = semlio::io::read_ply(semlio_test::data_path("scan_pair/source.ply"));
  semlio::infer_rings(scan, semlio::SensorModel::hdl32e());
  semlio::preprocess(scan);
  semlio::LoamFeatureExtractor ex;
  semlio::LoamFeatures f;
  const auto report = ex.extract(scan, f);
  CHECK(report.rings == 32);
  CHECK(f.corners.size() > 300);
  CHECK(f.corners.size() <= 32 * 6 * 20);
  CHECK(f.surfaces.size() > 500);
}

TEST_CASE("curvature percentiles on the real scans", "[.percentiles]") {
  // Not run by default: prints the distribution the default thresholds were
  // chosen from (loam_features.hpp). Run with the tag [.percentiles].
  const auto print = [](const char* name, const semlio::Scan& scan) {
    semlio::LoamFeatureExtractor ex;
    semlio::LoamFeatures f;
    ex.extract(scan, f);
    std::vector<float> c;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (ex.curvatures()[i] >= 0.0F && !ex.rejected(i)) c.push_back(ex.curvatures()[i]);
    }
    std::sort(c.begin(), c.end());
    REQUIRE(!c.empty());
    std::printf("%s: %zu points with c; corners %zu, surfaces %zu\n ", name, c.size(), f.corners.size(),
                f.surfaces.size());
    for (const double q : {0.10, 0.25, 0.50, 0.75, 0.80, 0.85, 0.90, 0.93, 0.95, 0.99}) {
      const auto at = static_cast<std::size_t>(q * static_cast<double>(c.size() - 1));
      std::printf(" p%.0f=%.3g", 100.0 * q, static_cast<double>(c[at]));
    }
    std::printf("\n");
  };
  print("kitti 000000", real_kitti("000000.bin"));
  print("kitti 000001", real_kitti("000001.bin"));
  for (const char* name : {"source.ply", "target.ply"}) {
    semlio::Scan scan = semlio::io::read_ply(semlio_test::data_path(std::string("scan_pair/") + name));
    semlio::infer_rings(scan, semlio::SensorModel::hdl32e());
    semlio::preprocess(scan);
    print(name, scan);
  }
}

}  // namespace test_loam_features
