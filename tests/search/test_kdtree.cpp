#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numeric>
#include <random>
#include <thread>
#include <utility>
#include <vector>

#include <semlio/io/kitti.hpp>
#include <semlio/search/kdtree.hpp>
#include <semlio/search/small_kdtree.hpp>
#include <semlio_test/data.hpp>

namespace test_kdtree {  // one namespace per test file: the area compiles as one TU

namespace {

using Eigen::Vector3f;

/// Squared distance summed in the same order as nanoflann's L2 metric, so that
/// float ties are reproduced bit for bit.
float sq(const Vector3f& a, const Vector3f& b) {
  float s = 0.0F;
  for (int i = 0; i < 3; ++i) {
    const float d = a[i] - b[i];
    s += d * d;
  }
  return s;
}

/// Brute force: all indices sorted by (squared distance, index).
std::vector<std::pair<float, std::uint32_t>> brute(const std::vector<Vector3f>& pts,
                                                   const Vector3f& q) {
  std::vector<std::pair<float, std::uint32_t>> all;
  for (std::uint32_t i = 0; i < pts.size(); ++i) all.emplace_back(sq(q, pts[i]), i);
  std::sort(all.begin(), all.end());
  return all;
}

std::vector<Vector3f> random_cloud(std::size_t n, std::mt19937& rng, float extent) {
  std::uniform_real_distribution<float> u(-extent, extent);
  std::vector<Vector3f> pts(n);
  for (auto& p : pts) p = Vector3f(u(rng), u(rng), u(rng));
  return pts;
}

// Query t of a tree comparison: a cloud point, the tie grid's centre, or a
// random point, in turn.
Vector3f tree_comparison_query(int t, const std::vector<Vector3f>& pts, std::uniform_real_distribution<float>& u,
                               std::mt19937& rng) {
  if (t % 4 == 0 && !pts.empty()) return pts[static_cast<std::size_t>(t) % pts.size()];
  if (t % 4 == 1) return Vector3f(0.5F, 0.5F, 1.0F);
  return Vector3f(u(rng), u(rng), u(rng));
}

// n random points and, for n > 100, a 5x5 grid (many equal distances) and
// a duplicate of the first point: the trees' tie rules get exercised.
std::vector<Vector3f> cloud_with_ties(std::size_t n, std::mt19937& rng) {
  std::vector<Vector3f> pts = random_cloud(n, rng, 4.0F);
  if (n > 100) {
    for (int x = 0; x < 5; ++x) {
      for (int y = 0; y < 5; ++y) pts.emplace_back(0.25F * static_cast<float>(x), 0.25F * static_cast<float>(y), 1.0F);
    }
    pts.push_back(pts.front());
  }
  return pts;
}

// Clouds of several sizes (cloud_with_ties), each rebuilt into one
// SmallKdTree3f and put in a KdTree3f, and `queries` queries on each
// (tree_comparison_query): compare(small, big, pts, q) for every pair. 9, 16
// and 17 points: a partly filled leaf, a full one, the first split (the leaf
// loop works in groups of four lanes).
constexpr std::size_t kTreeComparisonSizes = 8;
template <typename Compare>
void for_each_tree_comparison(std::mt19937& rng, int queries, Compare compare) {
  semlio::SmallKdTree3f small;
  for (const std::size_t n : {std::size_t{3000}, std::size_t{1}, std::size_t{9}, std::size_t{700}, std::size_t{0},
                              std::size_t{16}, std::size_t{17}, std::size_t{4000}}) {
    const std::vector<Vector3f> pts = cloud_with_ties(n, rng);
    const semlio::KdTree3f big(pts);
    small.build(pts);
    REQUIRE(small.size() == pts.size());
    std::uniform_real_distribution<float> u(-5.0F, 5.0F);
    for (int t = 0; t < queries; ++t) compare(small, big, pts, tree_comparison_query(t, pts, u, rng));
  }
}

void check_queries(const semlio::KdTree3f& tree, const std::vector<Vector3f>& pts,
                   const Vector3f& q) {
  const auto ref = brute(pts, q);
  for (std::size_t k : {std::size_t{1}, std::size_t{5}, std::size_t{15}, pts.size() + 3}) {
    std::vector<std::uint32_t> idx(k);
    std::vector<float> d(k);
    const std::size_t n = tree.knn(q, k, idx.data(), d.data());
    REQUIRE(n == std::min(k, pts.size()));
    for (std::size_t i = 0; i < n; ++i) {
      CHECK(idx[i] == ref[i].second);
      CHECK(d[i] == ref[i].first);
    }
  }
  for (float r : {0.0F, 0.3F, 1.0F, 2.5F}) {
    std::vector<std::uint32_t> out;
    std::vector<float> dist;
    tree.radius(q, r, out, dist);
    std::vector<std::uint32_t> expected;
    std::vector<float> expected_dist;
    for (const auto& [dd, i] : ref) {
      if (dd <= r * r) {
        expected.push_back(i);
        expected_dist.push_back(dd);
      }
    }
    CHECK(out == expected);
    CHECK(dist == expected_dist);
    std::vector<std::uint32_t> only;
    tree.radius(q, r, only);
    CHECK(only == expected);
  }
}

}  // namespace

TEST_CASE("KdTree3f knn and radius equal brute force on random clouds", "[search]") {
  std::mt19937 rng(1);
  for (std::size_t n : {std::size_t{1}, std::size_t{7}, std::size_t{200}, std::size_t{3000}}) {
    const auto pts = random_cloud(n, rng, 5.0F);
    const semlio::KdTree3f tree(pts);
    REQUIRE(tree.size() == n);
    const auto queries = random_cloud(30, rng, 6.0F);
    for (const auto& q : queries) check_queries(tree, pts, q);
    check_queries(tree, pts, pts[0]);  // query on a point: itself first at distance 0
  }
}

TEST_CASE("KdTree3f bounded knn equals brute force cut at the bound", "[search]") {
  // The bound is inclusive; tested also exactly at existing distances (ties at
  // the bound) and on a grid, where many points share a distance.
  std::mt19937 rng(3);
  std::vector<Vector3f> pts = random_cloud(2000, rng, 5.0F);
  for (int x = 0; x < 6; ++x) {
    for (int y = 0; y < 6; ++y) pts.emplace_back(0.5F * static_cast<float>(x), 0.5F * static_cast<float>(y), 0.0F);
  }
  const semlio::KdTree3f tree(pts);
  std::uniform_real_distribution<float> u(-7.0F, 7.0F);
  std::size_t checked = 0;
  for (int t = 0; t < 300; ++t) {
    const Vector3f q = t % 3 == 0 ? Vector3f(0.5F, 0.5F, 0.0F) : Vector3f(u(rng), u(rng), u(rng));
    const auto ref = brute(pts, q);
    for (const std::size_t k : {std::size_t{1}, std::size_t{5}, std::size_t{30}}) {
      for (const float cap : {0.0F, 0.25F, 1.0F, ref[3].first, ref[10].first, 1e9F}) {
        std::vector<std::uint32_t> idx(k);
        std::vector<float> d(k);
        const std::size_t n = tree.knn(q, k, idx.data(), d.data(), cap);
        std::size_t expected = 0;
        while (expected < k && expected < ref.size() && ref[expected].first <= cap) ++expected;
        REQUIRE(n == expected);
        for (std::size_t i = 0; i < n; ++i) {
          CHECK(idx[i] == ref[i].second);
          CHECK(d[i] == ref[i].first);
        }
        ++checked;
      }
    }
  }
  CHECK(checked == 300U * 3U * 6U);
  std::uint32_t i0 = 0;
  float d0 = 0.0F;
  CHECK(tree.knn(Vector3f::Zero(), 1, &i0, &d0, -1.0F) == 0);  // negative bound: nothing
}

TEST_CASE("SmallKdTree3f knn equals KdTree3f knn, also after rebuilds", "[search]") {
  // Random clouds of several sizes (rebuilt into the same tree), plus a grid
  // with many equal distances and duplicated points: identical indices and
  // distances, in the same (distance, index) order.
  std::mt19937 rng(21);
  std::size_t compared = 0;
  for_each_tree_comparison(rng, 200, [&](const semlio::SmallKdTree3f& small, const semlio::KdTree3f& big,
                                         const std::vector<Vector3f>&, const Vector3f& q) {
    // k = 100 takes the in-place path for k > detail::kKBestMax.
    for (const std::size_t k : {std::size_t{1}, std::size_t{10}, std::size_t{15}, std::size_t{40}, std::size_t{100}}) {
      std::vector<std::uint32_t> ia(k);
      std::vector<float> da(k);
      std::vector<std::uint32_t> ib(k);
      std::vector<float> db(k);
      const std::size_t na = small.knn(q, k, ia.data(), da.data());
      const std::size_t nb = big.knn(q, k, ib.data(), db.data());
      REQUIRE(na == nb);
      for (std::size_t i = 0; i < na; ++i) {
        REQUIRE(ia[i] == ib[i]);
        REQUIRE(da[i] == db[i]);
      }
      ++compared;
    }
  });
  CHECK(compared == kTreeComparisonSizes * 200U * 5U);
}

namespace {

// Bounded knn of SmallKdTree3f and KdTree3f at q for several k (one beyond
// the cloud) and bounds: 0, inf, float max, fixed radii, negative / NaN, and
// bounds equal to distances found (ties at the bound). Requires identical
// counts, indices and distances; returns the number of (k, bound) pairs.
std::size_t require_bounded_equal(const semlio::SmallKdTree3f& small, const semlio::KdTree3f& big,
                                  const Vector3f& q) {
  std::size_t compared = 0;
  const std::size_t n = big.size();
  std::vector<std::uint32_t> ia(64);
  std::vector<float> da(64);
  std::vector<std::uint32_t> ib(64);
  std::vector<float> db(64);
  // Distances at several ranks of the unbounded answer serve as bounds.
  std::array<float, 20> ranked{};
  const std::size_t nr = big.knn(q, ranked.size(), ib.data(), ranked.data());
  std::vector<float> bounds{0.0F, 0.01F, 0.25F, 1.0F, 4.0F, 1e9F, std::numeric_limits<float>::max(),
                            std::numeric_limits<float>::infinity(), -1.0F, std::numeric_limits<float>::quiet_NaN()};
  for (const std::size_t r : {std::size_t{0}, std::size_t{4}, std::size_t{9}, std::size_t{19}}) {
    if (r < nr) {
      bounds.push_back(ranked[r]);
      bounds.push_back(std::nextafter(ranked[r], 0.0F));  // just below a distance found
    }
  }
  for (const std::size_t k : {std::size_t{1}, std::size_t{5}, std::size_t{10}, std::size_t{20}, n + 1}) {
    if (k > ia.size()) continue;
    for (const float cap : bounds) {
      const std::size_t na = small.knn(q, k, ia.data(), da.data(), cap);
      const std::size_t nb = big.knn(q, k, ib.data(), db.data(), cap);
      INFO("k " << k << " bound " << cap << " size " << n);
      REQUIRE(na == nb);
      for (std::size_t i = 0; i < na; ++i) {
        REQUIRE(ia[i] == ib[i]);
        REQUIRE(da[i] == db[i]);
        REQUIRE(da[i] <= cap);
      }
      ++compared;
    }
  }
  return compared;
}

}  // namespace

TEST_CASE("SmallKdTree3f bounded knn equals KdTree3f bounded knn, also after rebuilds", "[search]") {
  // As the unbounded case above: random clouds of several sizes rebuilt into
  // the same tree, a grid of equal distances and a duplicate; then real KITTI
  // points (a map-sized subset of scan 000000, queried with scan 000001).
  std::mt19937 rng(22);
  std::size_t compared = 0;
  for_each_tree_comparison(rng, 100, [&](const semlio::SmallKdTree3f& small, const semlio::KdTree3f& big,
                                         const std::vector<Vector3f>& pts, const Vector3f& q) {
    if (pts.empty()) {
      std::uint32_t i0 = 0;
      float d0 = 0.0F;
      CHECK(small.knn(q, 1, &i0, &d0, 1.0F) == 0);
      return;
    }
    compared += require_bounded_equal(small, big, q);
  });
  CHECK(compared > 4000U);

  const semlio::Scan s0 = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  const semlio::Scan s1 = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000001.bin"));
  std::vector<Vector3f> map;
  for (std::size_t i = 0; i < s0.points.size(); i += 4) map.push_back(s0.points[i]);
  const semlio::KdTree3f big(map);
  semlio::SmallKdTree3f small;
  small.build(map);
  std::size_t real = 0;
  for (std::size_t i = 0; i < s1.points.size(); i += 97) real += require_bounded_equal(small, big, s1.points[i]);
  for (std::size_t i = 0; i < map.size(); i += 211) real += require_bounded_equal(small, big, map[i]);
  CHECK(real > 10000U);
}

TEST_CASE("next_up equals std::nextafter on squared distances", "[search]") {
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(0.0F, 100.0F);
  for (const float d : {0.0F, -0.0F, 1e-45F, 1.0F, 3.4e38F, std::numeric_limits<float>::max(),
                        std::numeric_limits<float>::infinity()}) {
    CHECK(semlio::detail::next_up(d) == std::nextafter(d, std::numeric_limits<float>::infinity()));
  }
  for (int t = 0; t < 10000; ++t) {
    const float d = u(rng) * u(rng);
    REQUIRE(semlio::detail::next_up(d) == std::nextafter(d, std::numeric_limits<float>::infinity()));
  }
}

TEST_CASE("KdTree3f ties in distance come in ascending index order", "[search]") {
  // A 5x5x5 integer grid, duplicated: every distance is repeated many times and
  // every point exists twice; the k-th place cut picks the lowest indices.
  std::vector<Vector3f> pts;
  for (int rep = 0; rep < 2; ++rep) {
    for (int x = 0; x < 5; ++x) {
      for (int y = 0; y < 5; ++y) {
        for (int z = 0; z < 5; ++z) {
          pts.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
        }
      }
    }
  }
  std::mt19937 rng(3);
  std::shuffle(pts.begin(), pts.end(), rng);
  const semlio::KdTree3f tree(pts, 2);  // small leaves: ties cross many nodes
  for (const Vector3f& q : {Vector3f(2, 2, 2), Vector3f(0, 0, 0), Vector3f(2.5F, 2.5F, 2.5F),
                           Vector3f(1, 2, 0.5F)}) {
    check_queries(tree, pts, q);
    std::uint32_t idx[7];
    float d[7];
    REQUIRE(tree.knn(q, 7, idx, d) == 7);
    for (int i = 1; i < 7; ++i) {
      CHECK((d[i - 1] < d[i] || (d[i - 1] == d[i] && idx[i - 1] < idx[i])));
    }
  }
}

TEST_CASE("KdTree3f empty, rebuilt, copied and moved trees", "[search]") {
  semlio::KdTree3f empty;
  std::uint32_t idx[3] = {7, 7, 7};
  float d[3] = {};
  CHECK(empty.knn(Vector3f::Zero(), 3, idx, d) == 0);
  std::vector<std::uint32_t> out{1, 2};
  empty.radius(Vector3f::Zero(), 10.0F, out);
  CHECK(out.empty());
  CHECK(empty.empty());

  semlio::KdTree3f built(std::vector<Vector3f>{});
  CHECK(built.knn(Vector3f::Zero(), 3, idx, d) == 0);

  std::mt19937 rng(5);
  auto pts = random_cloud(100, rng, 2.0F);
  semlio::KdTree3f tree;
  tree.build(pts);
  CHECK(tree.knn(Vector3f::Zero(), 0, idx, d) == 0);
  const semlio::KdTree3f copy = tree;
  const semlio::KdTree3f moved = std::move(tree);
  pts[0] = Vector3f(100, 100, 100);  // the tree owns a copy: no effect
  const auto ref = brute(copy.points(), Vector3f(1, 1, 1));
  REQUIRE(copy.knn(Vector3f(1, 1, 1), 3, idx, d) == 3);
  CHECK(idx[0] == ref[0].second);
  REQUIRE(moved.knn(Vector3f(1, 1, 1), 3, idx, d) == 3);
  CHECK(idx[0] == ref[0].second);

  // Rebuild with different content replaces the old.
  semlio::KdTree3f re(pts);
  re.build(std::vector<Vector3f>{Vector3f(1, 0, 0)});
  REQUIRE(re.knn(Vector3f::Zero(), 3, idx, d) == 1);
  CHECK(idx[0] == 0);
  CHECK(d[0] == 1.0F);
  re.radius(Vector3f::Zero(), -1.0F, out);
  CHECK(out.empty());
}

TEST_CASE("KdTree3f concurrent const queries agree with serial ones", "[search]") {
  std::mt19937 rng(8);
  const auto pts = random_cloud(5000, rng, 10.0F);
  const auto queries = random_cloud(2000, rng, 10.0F);
  const semlio::KdTree3f tree(pts);
  const auto run = [&](std::size_t begin, std::size_t end, std::vector<std::uint32_t>& firsts) {
    std::uint32_t idx[5];
    float d[5];
    std::vector<std::uint32_t> near;
    for (std::size_t q = begin; q < end; ++q) {
      tree.knn(queries[q], 5, idx, d);
      tree.radius(queries[q], 1.0F, near);
      firsts[q] = idx[0] + static_cast<std::uint32_t>(near.size()) * 100000U;
    }
  };
  std::vector<std::uint32_t> serial(queries.size());
  run(0, queries.size(), serial);
  std::vector<std::uint32_t> parallel(queries.size());
  std::thread a(run, 0, queries.size() / 2, std::ref(parallel));
  std::thread b(run, queries.size() / 2, queries.size(), std::ref(parallel));
  a.join();
  b.join();
  CHECK(parallel == serial);
}

TEST_CASE("SmallKdTree3f on lopsided clouds equals brute force", "[search]") {
  // Clouds whose midpoint splits leave less than a quarter on one side, so
  // the build takes its fallbacks: a dense cluster with a few far points
  // (the sampled median), and coordinates mostly equal along the widest axis
  // (the sample's median is that value, the sampled split is lopsided too,
  // and the exact median decides). Also a real KITTI scan cut to a street's
  // clustered points. Every answer equals brute force by (distance, index).
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0F, 1.0F);
  std::vector<std::vector<Vector3f>> clouds(3);
  for (int i = 0; i < 2000; ++i) clouds[0].emplace_back(0.01F * u(rng), 0.01F * u(rng), 0.01F * u(rng));
  for (int i = 0; i < 50; ++i) clouds[0].emplace_back(100.0F * u(rng), 100.0F * u(rng), 100.0F * u(rng));
  for (int i = 0; i < 900; ++i) clouds[1].emplace_back(0.0F, 0.5F * u(rng), 0.0F);
  for (int i = 0; i < 100; ++i) clouds[1].emplace_back(1.0F + 99.0F * u(rng), 0.5F * u(rng), 0.0F);
  const semlio::Scan scan = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  for (std::size_t i = 0; i < scan.points.size(); i += 7) {
    if (scan.points[i].norm() < 30.0F) clouds[2].push_back(scan.points[i]);
  }
  semlio::SmallKdTree3f tree;
  std::size_t compared = 0;
  for (const std::vector<Vector3f>& pts : clouds) {
    tree.build(pts);
    for (int t = 0; t < 60; ++t) {
      // Half the queries at cloud points (inside the cluster), half anywhere.
      const Vector3f q = t % 2 == 0 ? pts[static_cast<std::size_t>(t) * 37 % pts.size()]
                                    : Vector3f(100.0F * u(rng) - 20.0F, 100.0F * u(rng) - 20.0F, 4.0F * u(rng) - 2.0F);
      const auto ref = brute(pts, q);
      for (const std::size_t k : {std::size_t{1}, std::size_t{10}, std::size_t{20}}) {
        std::vector<std::uint32_t> idx(k);
        std::vector<float> d(k);
        const std::size_t n = tree.knn(q, k, idx.data(), d.data());
        REQUIRE(n == k);
        for (std::size_t i = 0; i < n; ++i) {
          REQUIRE(idx[i] == ref[i].second);
          REQUIRE(d[i] == ref[i].first);
        }
        ++compared;
      }
    }
  }
  CHECK(compared == 3U * 60U * 3U);
}

}  // namespace test_kdtree

TEST_CASE("SmallKdTree3f knn_seeded equals knn whatever the seeds", "[search]") {
  // Seeds from the previous query in a walk (near), from a random far point,
  // fewer seeds than k (ignored) and k = 1: every answer is knn's, bit for bit.
  const semlio::Scan s0 = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  std::vector<Eigen::Vector3f> pts;
  for (std::size_t i = 0; i < s0.points.size(); i += 9) pts.push_back(s0.points[i]);
  semlio::SmallKdTree3f tree;
  tree.build(pts);
  std::mt19937 rng(31);
  std::uniform_int_distribution<std::size_t> pick(0, pts.size() - 1);
  std::size_t mismatches = 0;
  std::size_t compared = 0;
  for (const std::size_t k : {std::size_t{1}, std::size_t{10}, std::size_t{25}}) {
    std::array<std::uint32_t, 64> seeded{};
    std::array<float, 64> seeded_d2{};
    std::size_t known = 0;
    for (int step = 0; step < 600; ++step) {
      // Mostly the next point in leaf order (near), every 7th a random one
      // (far), every 11th with too few seeds.
      const std::size_t at =
          step % 7 == 0 ? pick(rng) : tree.leaf_order()[static_cast<std::size_t>(step) % pts.size()];
      const Eigen::Vector3f q = pts[at] + Eigen::Vector3f(0.01F, -0.02F, 0.005F);
      if (step % 11 == 0 && known > 1) known -= 1;
      std::array<std::uint32_t, 64> idx{};
      std::array<float, 64> d2{};
      const std::size_t n = tree.knn(q, k, idx.data(), d2.data());
      known = tree.knn_seeded(q, k, seeded.data(), seeded_d2.data(), known);
      bool same = known == n;
      for (std::size_t j = 0; same && j < n; ++j) same = seeded[j] == idx[j] && seeded_d2[j] == d2[j];
      mismatches += same ? 0U : 1U;
      ++compared;
    }
  }
  CHECK(compared == 1800U);
  CHECK(mismatches == 0);
}
