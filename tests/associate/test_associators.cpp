// Associators: NearestK, NormalConsistency (Algorithm 1, fast) and its literal
// reference. The key property: the fast one chooses exactly the reference's
// matches (indices, order, ranks) on real KITTI scans, simulated sweeps and
// synthetic scenes.
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/associate/normal_consistency.hpp>
#include <semlio/associate/normal_consistency_reference.hpp>
#include <semlio/core/error.hpp>
#include <semlio/map/feature_map.hpp>
#include <semlio/map/local_map.hpp>
#include <semlio/search/small_kdtree.hpp>
#include <semlio_test/associate_scenes.hpp>
#include <semlio_test/frontend_sim_pair.hpp>

namespace test_associators {  // one namespace per test file: the area compiles as one TU

using semlio::Class;
using semlio::Correspondences;
using semlio::FeatureKind;
using semlio::FeatureMap;
using semlio::SE3d;

namespace {

// Index of the first feature where a and b differ, or a.size() when equal.
std::size_t first_difference(const Correspondences& a, const Correspondences& b) {
  if (a.size() != b.size()) return 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].count != b[i].count) return i;
    for (int j = 0; j < a[i].count; ++j) {
      const auto k = static_cast<std::size_t>(j);
      if (a[i].index[k] != b[i].index[k] || a[i].rank[k] != b[i].rank[k]) return i;
    }
  }
  return a.size();
}

struct Summary {
  std::size_t matched = 0;       // features with a match
  std::size_t beyond_first = 0;  // features where a candidate was skipped (ranks not 1..count)
  int max_rank = 0;
};

Summary summarise(const Correspondences& c) {
  Summary s;
  for (const auto& m : c) {
    if (m.count == 0) continue;
    ++s.matched;
    if (m.rank[m.count - 1U] != m.count) ++s.beyond_first;
    s.max_rank = std::max(s.max_rank, static_cast<int>(m.rank[m.count - 1U]));
  }
  return s;
}

// Runs fast and reference on (map, features) at each pose and requires equality.
void require_fast_equals_reference(const FeatureMap& map, const std::vector<Eigen::Vector3f>& features,
                                   const std::vector<SE3d>& poses, bool expect_skips,
                                   double min_matched_fraction = 0.25) {
  semlio::NormalConsistency fast;
  semlio::NormalConsistencyReference ref;
  fast.set_map(map);
  fast.set_scan(features);
  ref.set_map(map);
  ref.set_scan(features);
  Correspondences a;
  Correspondences b;
  std::size_t skipped_total = 0;
  for (const SE3d& T : poses) {
    fast.associate(T, a);
    ref.associate(T, b);
    REQUIRE(a.size() == features.size());
    const std::size_t diff = first_difference(a, b);
    INFO("first differing feature " << diff << " of " << a.size());
    REQUIRE(diff == a.size());
    const Summary s = summarise(a);
    // A real overlap, not a vacuous equality.
    CHECK(static_cast<double>(s.matched) > min_matched_fraction * static_cast<double>(features.size()));
    CHECK(s.max_rank <= 15);
    skipped_total += s.beyond_first;
  }
  if (expect_skips) CHECK(skipped_total > 0);  // some candidate was skipped by the axis test
}

SE3d perturbed(const SE3d& T, double dx, double dyaw) {
  Eigen::Matrix<double, 6, 1> xi;
  xi << dx, -0.5 * dx, 0.2 * dx, 0.0, 0.0, dyaw;
  return T * SE3d::exp(xi);
}

// Poses as Gauss-Newton visits them: from `start` towards `goal` in halving
// steps (centimetres, then millimetres, then sub-millimetre), then a jump back
// to `start` and the goal again.
std::vector<SE3d> converging_poses(const SE3d& start, const SE3d& goal) {
  const Eigen::Matrix<double, 6, 1> xi = (start.inverse() * goal).log();
  std::vector<SE3d> poses;
  for (int k = 0; k <= 10; ++k) {
    const double f = 1.0 - std::pow(0.5, k);
    poses.push_back(start * SE3d::exp(f * xi));
  }
  poses.push_back(start);
  poses.push_back(goal);
  return poses;
}

// Along `poses`, with ONE NearestCache carried from call to call:
// NormalConsistency equals the literal reference and NearestK equals its
// uncached self, every time; the cache answers most late queries.
void require_cached_equals_uncached(const FeatureMap& map, const std::vector<Eigen::Vector3f>& features,
                                    const std::vector<SE3d>& poses) {
  semlio::NormalConsistency fast;
  semlio::NormalConsistencyReference ref;
  semlio::NearestK nearest;
  fast.set_map(map);
  fast.set_scan(features);
  ref.set_map(map);
  ref.set_scan(features);
  nearest.set_map(map);
  nearest.set_scan(features);
  semlio::NearestCache nc_cache;
  semlio::NearestCache nk_cache;
  Correspondences a;
  Correspondences b;
  std::size_t matched = 0;
  for (std::size_t p = 0; p < poses.size(); ++p) {
    INFO("pose " << p);
    fast.associate(poses[p], a, nc_cache);
    ref.associate(poses[p], b);
    REQUIRE(first_difference(a, b) == a.size());
    matched += summarise(a).matched;
    nearest.associate(poses[p], a, nk_cache);
    nearest.associate(poses[p], b);
    REQUIRE(first_difference(a, b) == a.size());
  }
  CHECK(matched > features.size());  // a real overlap, not a vacuous equality
  // Most of the 13 poses are close to the previous one: lists were reused.
  CHECK(nc_cache.hits() > nc_cache.refills());
  CHECK(nk_cache.hits() > nk_cache.refills());
  CHECK(nc_cache.refills() >= features.size() / 2);  // the first pose fills (nearly) every slot
}

}  // namespace

TEST_CASE("NormalConsistency equals the literal Algorithm 1 on the real KITTI pair", "[associate]") {
  // Map: the LOAM features of scan 000000 (identity pose); query: those of
  // scan 000001, ~0.7 m further on; poses: identity, the (extrapolated) ground
  // truth as a plausible guess, and a perturbed guess.
  const auto query = semlio_test::kitti_features("kitti/sequences/00/velodyne/000001.bin");
  REQUIRE(query.surfaces.points.size() > 1000);
  REQUIRE(query.corners.points.size() > 500);
  semlio::LocalMap local;
  semlio_test::build_kitti_pair_map(local);
  const SE3d guess = semlio_test::kitti_T_0_1();
  CHECK(guess.translation().norm() > 0.5);
  CHECK(guess.translation().norm() < 1.0);
  const std::vector<SE3d> poses{SE3d(), guess, perturbed(guess, 0.2, 0.01)};
  require_fast_equals_reference(local.surfaces(), query.surfaces.points, poses, true);
  require_fast_equals_reference(local.corners(), query.corners.points, poses, true);
}

TEST_CASE("NormalConsistency's scan axes equal a plain k-NN fit per feature", "[associate]") {
  // set_scan() bounds each feature's k-NN search by the previous feature's
  // neighbours (leaf order); every axis must still be the unbounded search's
  // fit, bit for bit, for both kinds and several neighbourhood sizes.
  const auto query = semlio_test::kitti_features("kitti/sequences/00/velodyne/000001.bin");
  semlio::LocalMap local;
  semlio_test::build_kitti_pair_map(local);
  for (const FeatureMap* map : {&local.surfaces(), &local.corners()}) {
    const std::vector<Eigen::Vector3f>& points =
        map->kind() == FeatureKind::kPlane ? query.surfaces.points : query.corners.points;
    REQUIRE(points.size() > 500);
    semlio::SmallKdTree3f tree;
    tree.build(points);
    for (const int k : {3, 10, 17}) {
      semlio::NormalConsistencyConfig config;
      config.scan_neighbours = k;
      semlio::NormalConsistency fast(config);
      fast.set_map(*map);
      fast.set_scan(points);
      REQUIRE(fast.scan_axes().size() == points.size());
      std::size_t differ = 0;
      std::size_t usable = 0;
      for (std::size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector3f expected = semlio::detail::neighbourhood_axis(tree, map->kind(), points[i], k);
        differ += fast.scan_axes()[i] == expected ? 0U : 1U;
        usable += expected.isZero() ? 0U : 1U;
      }
      INFO("kind " << static_cast<int>(map->kind()) << " k " << k);
      CHECK(differ == 0);
      CHECK(usable > points.size() / 2);
    }
  }
}

TEST_CASE("NormalConsistency equals the literal Algorithm 1 on a dense real map", "[associate]") {
  // Every point of scan 000000 (0.2 m voxels) as map, of 000001 (0.8 m voxels)
  // as features: dense candidates, many rejected by the 10 deg test.
  const auto map_cloud = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000000.bin", 0.2);
  const auto query = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000001.bin", 0.8);
  semlio::LocalMap local;
  local.add_keyframe(SE3d(), map_cloud, map_cloud);
  local.build(Eigen::Vector3d::Zero());
  REQUIRE(local.surfaces().size() > 10000);
  const SE3d guess = semlio_test::kitti_T_0_1();
  // 10-NN scan neighbourhoods of 0.8 m voxels are coarse: fewer features agree.
  require_fast_equals_reference(local.surfaces(), query.points, {guess}, true, 0.1);
  require_fast_equals_reference(local.corners(), query.points, {perturbed(guess, 0.2, 0.01)}, true, 0.1);
}

TEST_CASE("NormalConsistency equals the literal Algorithm 1 on synthetic streets", "[associate]") {
  for (const unsigned seed : {1U, 2U}) {
    const auto scene = semlio_test::street_scene(seed);
    semlio::LocalMap local;
    local.add_keyframe(SE3d(), scene.map_corners, scene.map_surfaces);
    local.build(Eigen::Vector3d::Zero());
    const std::vector<SE3d> poses{scene.T_map_scan, perturbed(scene.T_map_scan, 0.3, 0.02), SE3d()};
    require_fast_equals_reference(local.surfaces(), scene.scan_surfaces.points, poses, true);
    require_fast_equals_reference(local.corners(), scene.scan_corners.points, poses, false);
  }
}

TEST_CASE("NormalConsistency equals the literal Algorithm 1 on simulated urban sweeps", "[associate]") {
  // Two consecutive simulated 64-beam sweeps (semlio::sim, in memory): map =
  // frame 10's LOAM features, query = frame 11's, at the ground truth, a
  // perturbed guess and identity.
  const auto pair = semlio_test::sim_urban_pair();
  REQUIRE(pair.scan_features.surfaces.size() > 1000);
  REQUIRE(pair.scan_features.corners.size() > 300);
  semlio::LocalMap local;
  local.add_keyframe(SE3d(), pair.map_features.corners, pair.map_features.surfaces);
  local.build(Eigen::Vector3d::Zero());
  CHECK(pair.T_map_scan.translation().norm() > 0.3);
  const std::vector<SE3d> poses{pair.T_map_scan, perturbed(pair.T_map_scan, 0.2, 0.01), SE3d()};
  require_fast_equals_reference(local.surfaces(), pair.scan_features.surfaces.points, poses, true);
  // At identity (1.1 m off) only ~20% of the corners find gated candidates.
  require_fast_equals_reference(local.corners(), pair.scan_features.corners.points, poses, true, 0.1);
}

TEST_CASE("NormalConsistency equals the reference with candidate lists", "[associate]") {
  // The optional list path (LocalMapConfig::candidate_list > 0; off by
  // default, the cases above search the k-d tree inside the gate): anchors
  // from the voxel index or a 1-NN bounded at the gate, list scans stopped
  // by the float bound, the tree where the lists cannot prove the answer.
  const semlio::LocalMapConfig lists{.candidate_list = 32};
  {
    const auto query = semlio_test::kitti_features("kitti/sequences/00/velodyne/000001.bin");
    semlio::LocalMap local(lists);
    semlio_test::build_kitti_pair_map(local);
    REQUIRE(local.surfaces().candidate_list() == 32);
    REQUIRE(local.corners().candidate_list() == 32);
    const SE3d guess = semlio_test::kitti_T_0_1();
    const std::vector<SE3d> poses{SE3d(), guess, perturbed(guess, 0.2, 0.01)};
    require_fast_equals_reference(local.surfaces(), query.surfaces.points, poses, true);
    require_fast_equals_reference(local.corners(), query.corners.points, poses, true);
  }
  {
    const auto pair = semlio_test::sim_urban_pair();
    semlio::LocalMap local(lists);
    local.add_keyframe(SE3d(), pair.map_features.corners, pair.map_features.surfaces);
    local.build(Eigen::Vector3d::Zero());
    const std::vector<SE3d> poses{pair.T_map_scan, perturbed(pair.T_map_scan, 0.2, 0.01), SE3d()};
    require_fast_equals_reference(local.surfaces(), pair.scan_features.surfaces.points, poses, true);
    require_fast_equals_reference(local.corners(), pair.scan_features.corners.points, poses, true, 0.1);
  }
  const auto scene = semlio_test::street_scene(4);
  semlio::LocalMap local(lists);
  local.add_keyframe(SE3d(), scene.map_corners, scene.map_surfaces);
  local.build(Eigen::Vector3d::Zero());
  const std::vector<SE3d> poses{scene.T_map_scan, perturbed(scene.T_map_scan, 0.3, 0.02), SE3d()};
  require_fast_equals_reference(local.surfaces(), scene.scan_surfaces.points, poses, true);
  require_fast_equals_reference(local.corners(), scene.scan_corners.points, poses, false);
}

TEST_CASE("Associators with a NearestCache equal the uncached ones along Gauss-Newton poses", "[associate]") {
  // The cross-iteration candidate reuse must not change one match: real KITTI
  // pair (map 000000, features 000001 from identity to the ground truth),
  // simulated urban sweeps, and a synthetic street.
  const auto query = semlio_test::kitti_features("kitti/sequences/00/velodyne/000001.bin");
  semlio::LocalMap local;
  semlio_test::build_kitti_pair_map(local);
  const SE3d guess = semlio_test::kitti_T_0_1();
  const auto kitti_poses = converging_poses(perturbed(guess, 0.15, 0.01), guess);
  require_cached_equals_uncached(local.surfaces(), query.surfaces.points, kitti_poses);
  require_cached_equals_uncached(local.corners(), query.corners.points, kitti_poses);

  const auto pair = semlio_test::sim_urban_pair();
  semlio::LocalMap sim;
  sim.add_keyframe(SE3d(), pair.map_features.corners, pair.map_features.surfaces);
  sim.build(Eigen::Vector3d::Zero());
  const auto sim_poses = converging_poses(perturbed(pair.T_map_scan, 0.2, 0.01), pair.T_map_scan);
  require_cached_equals_uncached(sim.surfaces(), pair.scan_features.surfaces.points, sim_poses);
  require_cached_equals_uncached(sim.corners(), pair.scan_features.corners.points, sim_poses);

  const auto scene = semlio_test::street_scene(3);
  semlio::LocalMap street;
  street.add_keyframe(SE3d(), scene.map_corners, scene.map_surfaces);
  street.build(Eigen::Vector3d::Zero());
  require_cached_equals_uncached(street.surfaces(), scene.scan_surfaces.points,
                                 converging_poses(perturbed(scene.T_map_scan, 0.3, 0.02), scene.T_map_scan));
}

TEST_CASE("A NearestCache is not trusted across a map rebuild or another scan", "[associate]") {
  // Same cache object, then the map is rebuilt in place from other points and
  // the associator gets other features: results must still equal the reference.
  const auto scene = semlio_test::street_scene(1);
  const auto other = semlio_test::street_scene(2);
  semlio::LocalMap local;
  local.add_keyframe(SE3d(), scene.map_corners, scene.map_surfaces);
  local.build(Eigen::Vector3d::Zero());
  semlio::NormalConsistency fast;
  semlio::NormalConsistencyReference ref;
  semlio::NearestCache cache;
  Correspondences a;
  Correspondences b;
  fast.set_map(local.surfaces());
  fast.set_scan(scene.scan_surfaces.points);
  fast.associate(scene.T_map_scan, a, cache);
  const std::size_t first_refills = cache.refills();
  CHECK(first_refills > 0);
  // Rebuild the same LocalMap (same FeatureMap objects) over another scene.
  semlio::LocalMap rebuilt;
  local = rebuilt;
  local.add_keyframe(SE3d(), other.map_corners, other.map_surfaces);
  local.build(Eigen::Vector3d::Zero());
  for (const auto* features : {&scene.scan_surfaces.points, &other.scan_surfaces.points}) {
    fast.set_map(local.surfaces());
    fast.set_scan(*features);
    ref.set_map(local.surfaces());
    ref.set_scan(*features);
    fast.associate(other.T_map_scan, a, cache);
    ref.associate(other.T_map_scan, b);
    CHECK(first_difference(a, b) == a.size());
    CHECK(summarise(a).matched > 0);
  }
  CHECK(cache.refills() > first_refills);  // the stale lists were refilled
}

TEST_CASE("Normal consistency skips a nearer candidate on the wrong plane", "[associate]") {
  // A floor (z = 0, 7 cm grid) and, just above it, a small vertical wall
  // patch (x = 0.12). The scan feature f lies on a horizontal scan surface
  // (normal z) 17 cm above the floor -- an initial-guess error -- and right
  // next to the wall: its nearest map points are wall points.
  std::vector<Eigen::Vector3f> pts;
  std::vector<Class> labels;
  for (int i = -15; i < 15; ++i) {
    for (int j = -15; j < 15; ++j) {
      pts.emplace_back(0.035F + 0.07F * static_cast<float>(i), 0.035F + 0.07F * static_cast<float>(j), 0.0F);
      labels.push_back(Class::kRoad);
    }
  }
  const std::size_t n_floor = pts.size();
  for (int iy = -1; iy <= 1; ++iy) {
    for (int iz = 0; iz < 5; ++iz) {
      pts.emplace_back(0.12F, 0.05F * static_cast<float>(iy), 0.2F + 0.05F * static_cast<float>(iz));
      labels.push_back(Class::kBuilding);
    }
  }
  FeatureMap map(FeatureKind::kPlane);
  map.build(pts, labels, 10);
  // Cached axes: the floor's normal is z, the wall's x (their neighbourhoods do not mix).
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3f expected = i < n_floor ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f::UnitX();
    REQUIRE(std::abs(map.axes()[i].dot(expected)) > 0.999F);
  }
  const Eigen::Vector3f f(0.1F, 0.0F, 0.17F);
  std::vector<Eigen::Vector3f> scan{f};
  for (int i = -2; i <= 2; ++i) {
    for (int j = -2; j <= 2; ++j) {
      if (i != 0 || j != 0) scan.emplace_back(f + Eigen::Vector3f(0.1F * static_cast<float>(i), 0.1F * static_cast<float>(j), 0.0F));
    }
  }
  // Expected, from the geometry alone: the 15 nearest candidates in (distance,
  // index) order; Algorithm 1 keeps the floor ones among them, up to 5.
  std::vector<std::uint32_t> order(pts.size());
  std::iota(order.begin(), order.end(), 0U);
  const auto d2 = [&](std::uint32_t i) { return (pts[i] - f).squaredNorm(); };
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return d2(a) < d2(b); });
  REQUIRE(order[0] >= n_floor);  // the nearest map point is on the wall
  std::vector<std::uint32_t> want_index;
  std::vector<int> want_rank;
  for (int r = 0; r < 15 && want_index.size() < 5; ++r) {
    if (order[static_cast<std::size_t>(r)] < n_floor) {
      want_index.push_back(order[static_cast<std::size_t>(r)]);
      want_rank.push_back(r + 1);
    }
  }
  REQUIRE(want_index.size() >= 3);
  REQUIRE(want_rank.front() > 1);

  semlio::NearestK nearest;
  nearest.set_map(map);
  nearest.set_scan(scan);
  Correspondences nk;
  nearest.associate(SE3d(), nk);
  REQUIRE(nk[0].count == 5);
  CHECK(nk[0].index[0] == order[0]);  // the traditional association takes the wall point
  CHECK(nk[0].rank[0] == 1);

  semlio::NormalConsistency fast;
  fast.set_map(map);
  fast.set_scan(scan);
  Correspondences nc;
  fast.associate(SE3d(), nc);
  REQUIRE(static_cast<std::size_t>(nc[0].count) == want_index.size());
  for (std::size_t k = 0; k < want_index.size(); ++k) {
    CHECK(nc[0].index[k] == want_index[k]);
    CHECK(static_cast<int>(nc[0].rank[k]) == want_rank[k]);
  }
  semlio::NormalConsistencyReference ref;
  ref.set_map(map);
  ref.set_scan(scan);
  Correspondences rc;
  ref.associate(SE3d(), rc);
  CHECK(first_difference(nc, rc) == nc.size());

  // With the axis test off (a frame with no motion estimate: odometry.hpp)
  // the nearest candidates are kept, wall point first: NearestK's matches.
  CHECK(fast.axis_test());
  CHECK(fast.set_axis_test(false));
  fast.associate(SE3d(), nc);
  CHECK(first_difference(nc, nk) == nc.size());
  CHECK_FALSE(fast.set_axis_test(true));
  fast.associate(SE3d(), nc);
  CHECK(nc[0].index[0] == want_index[0]);
}

TEST_CASE("NearestK keeps the gated nearest points in distance order", "[associate]") {
  // A 10 cm grid on z = 0: the query 0.3 m above (0.02, 0.03) sees its
  // neighbours in a known order; a 0.35 m gate leaves the 4 nearest only.
  std::vector<Eigen::Vector3f> pts;
  for (int i = -5; i <= 5; ++i) {
    for (int j = -5; j <= 5; ++j) pts.emplace_back(0.1F * static_cast<float>(i), 0.1F * static_cast<float>(j), 0.0F);
  }
  FeatureMap map(FeatureKind::kPlane);
  map.build(pts, {}, 10);
  const std::vector<Eigen::Vector3f> scan{{0.02F, 0.03F, 0.3F}};
  const auto expect_point = [&](std::uint32_t idx, float x, float y) {
    CHECK(pts[idx].x() == Approx(x).margin(1e-6));
    CHECK(pts[idx].y() == Approx(y).margin(1e-6));
  };
  semlio::NearestK wide;
  wide.set_map(map);
  wide.set_scan(scan);
  Correspondences out;
  wide.associate(SE3d(), out);
  REQUIRE(out[0].count == 5);
  expect_point(out[0].index[0], 0.0F, 0.0F);  // d^2 = .0004+.0009
  expect_point(out[0].index[1], 0.0F, 0.1F);  // .0004+.0049
  expect_point(out[0].index[2], 0.1F, 0.0F);  // .0064+.0009
  expect_point(out[0].index[3], 0.1F, 0.1F);  // .0064+.0049
  expect_point(out[0].index[4], -0.1F, 0.0F);  // .0144+.0009 (before (0, -0.1): .0004+.0169)
  for (int k = 0; k < 5; ++k) CHECK(static_cast<int>(out[0].rank[static_cast<std::size_t>(k)]) == k + 1);

  // Distances: 4th sqrt(0.09 + .0113) = 0.3183 m, 5th sqrt(0.09 + .0153) = 0.3245 m,
  // so a 0.32 m gate keeps 4.
  semlio::NearestK gated({.k = 5, .max_distance_m = 0.32});
  gated.set_map(map);
  gated.set_scan(scan);
  gated.associate(SE3d(), out);
  CHECK(out[0].count == 4);
  // A gate below the nearest (sqrt(0.0913) = 0.3022 m): nothing passes -> no match.
  semlio::NearestK tight({.k = 5, .max_distance_m = 0.301});
  tight.set_map(map);
  tight.set_scan(scan);
  tight.associate(SE3d(), out);
  CHECK(out[0].count == 0);
}

TEST_CASE("Associators return no match when the map cannot support a primitive", "[associate]") {
  const std::vector<Eigen::Vector3f> scan{{0.0F, 0.0F, 0.0F}, {0.1F, 0.0F, 0.0F}, {0.0F, 0.1F, 0.0F}};
  Correspondences out;
  SECTION("empty map") {
    FeatureMap map;
    map.build({}, {}, 10);
    semlio::NormalConsistency nc;
    nc.set_map(map);
    nc.set_scan(scan);
    nc.associate(SE3d(), out);
    REQUIRE(out.size() == 3);
    for (const auto& m : out) CHECK(m.count == 0);
  }
  SECTION("two map points: enough for a line, not for a plane") {
    const std::vector<Eigen::Vector3f> two{{0.0F, 0.0F, 0.0F}, {0.2F, 0.0F, 0.0F}};
    FeatureMap plane(FeatureKind::kPlane);
    plane.build(two, {}, 10);
    FeatureMap line(FeatureKind::kLine);
    line.build(two, {}, 10);
    semlio::NearestK nk;
    nk.set_scan(scan);
    nk.set_map(plane);
    nk.associate(SE3d(), out);
    CHECK(out[0].count == 0);
    nk.set_map(line);
    nk.associate(SE3d(), out);
    CHECK(out[0].count == 2);
  }
  SECTION("no features") {
    FeatureMap map;
    map.build(scan, {}, 10);
    semlio::NormalConsistency nc;
    nc.set_map(map);
    const std::vector<Eigen::Vector3f> none;
    nc.set_scan(none);
    nc.associate(SE3d(), out);
    CHECK(out.empty());
  }
}

TEST_CASE("Associator settings are validated", "[associate]") {
  CHECK_THROWS_AS(semlio::NearestK({.k = 0}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::NearestK({.k = 6}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::NormalConsistency({.candidates = 3, .keep = 5}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::NormalConsistency({.max_angle_rad = 2.0}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::NormalConsistencyReference({.scan_neighbours = 1}), semlio::ConfigError);
  CHECK_NOTHROW(semlio::NormalConsistency(semlio::NormalConsistencyConfig{}));
}

TEST_CASE("Repeated association reuses the output buffer", "[associate]") {
  const auto scene = semlio_test::street_scene(3);
  semlio::LocalMap local;
  local.add_keyframe(SE3d(), scene.map_corners, scene.map_surfaces);
  local.build(Eigen::Vector3d::Zero());
  semlio::NormalConsistency nc;
  nc.set_map(local.surfaces());
  nc.set_scan(scene.scan_surfaces.points);
  Correspondences out;
  nc.associate(scene.T_map_scan, out);
  const auto* data = out.data();
  const Correspondences first = out;
  nc.associate(perturbed(scene.T_map_scan, 0.1, 0.0), out);
  nc.associate(scene.T_map_scan, out);
  CHECK(out.data() == data);
  CHECK(first_difference(out, first) == out.size());  // deterministic
}

}  // namespace test_associators
