#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <semlio/search/k_best.hpp>

namespace test_k_best {  // one namespace per test file: the area compiles as one TU

namespace {

/// Offers the stream to a KBest and to insert_by_distance_index (the
/// reference) and compares the lists entry by entry (bits of the distances
/// too), after every offer.
void check_same_as_reference(const std::vector<float>& d, const std::vector<std::uint32_t>& idx, std::size_t k) {
  semlio::detail::KBest best(k);
  std::vector<std::uint32_t> ref_idx(k);
  std::vector<float> ref_d2(k);
  std::size_t ref_count = 0;
  std::vector<std::uint32_t> got_idx(k);
  std::vector<float> got_d2(k);
  std::size_t mismatches = 0;
  for (std::size_t s = 0; s < d.size(); ++s) {
    best.offer(d[s], idx[s]);
    ref_count = semlio::detail::insert_by_distance_index(d[s], idx[s], ref_idx.data(), ref_d2.data(), ref_count, k);
    const std::size_t n = best.write(got_idx.data(), got_d2.data());
    if (n != ref_count || best.size() != ref_count || best.full() != (ref_count == k)) {
      ++mismatches;
      continue;
    }
    for (std::size_t j = 0; j < n; ++j) {
      mismatches += (got_idx[j] == ref_idx[j] && std::bit_cast<std::uint32_t>(got_d2[j]) ==
                                                     std::bit_cast<std::uint32_t>(ref_d2[j]))
                        ? 0U
                        : 1U;
    }
    if (n > 0) {
      mismatches += std::bit_cast<std::uint32_t>(best.worst()) == std::bit_cast<std::uint32_t>(ref_d2[n - 1]) ? 0U : 1U;
    }
  }
  CHECK(mismatches == 0);
}

}  // namespace

TEST_CASE("KBest keeps the k best exactly as insert_by_distance_index", "[search]") {
  std::mt19937 rng(3);
  SECTION("random streams, every k from 1 to 64, many distance ties") {
    for (std::size_t k = 1; k <= semlio::detail::kKBestMax; ++k) {
      std::uniform_int_distribution<int> level(0, 40);  // few distinct distances: ties broken by index
      std::vector<float> d;
      std::vector<std::uint32_t> idx;
      for (std::uint32_t i = 0; i < 300; ++i) {
        d.push_back(0.01F * static_cast<float>(level(rng)));
        idx.push_back((i * 7919U) % 1000U);  // distinct, out of order
      }
      check_same_as_reference(d, idx, k);
    }
  }
  SECTION("distance +0 at index 0 (the key equal to the sentinel), descending and ascending streams") {
    check_same_as_reference({3.0F, 0.0F, 1.0F, 0.0F, 2.0F}, {5, 0, 2, 1, 4}, 3);
    check_same_as_reference({0.0F, 0.0F, 0.0F}, {2, 1, 0}, 2);
    std::vector<float> desc;
    std::vector<std::uint32_t> ids;
    for (std::uint32_t i = 0; i < 100; ++i) {
      desc.push_back(static_cast<float>(100 - i));
      ids.push_back(i);
    }
    check_same_as_reference(desc, ids, 10);
    std::vector<float> asc(desc.rbegin(), desc.rend());
    check_same_as_reference(asc, ids, 10);
  }
  SECTION("NaN and infinite distances sort after every number") {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    check_same_as_reference({nan, 1.0F, inf, 0.5F, nan, 2.0F}, {0, 1, 2, 3, 4, 5}, 4);
    semlio::detail::KBest best(2);
    best.offer(nan, 0);
    best.offer(1.0F, 1);
    std::uint32_t idx[2];
    float d2[2];
    REQUIRE(best.write(idx, d2) == 2);
    CHECK(idx[0] == 1);
    CHECK(std::isnan(d2[1]));
  }
}

namespace {

/// True when sort_keys<N> sorts every 0-1 input of length N: by the 0-1
/// principle a comparator network that sorts all 2^N binary sequences sorts
/// every sequence.
template <std::size_t N>
bool sorts_every_binary_input() {
  std::array<std::uint64_t, N> a{};
  for (std::uint32_t bits = 0; bits < (1U << N); ++bits) {
    for (std::size_t j = 0; j < N; ++j) a[j] = (bits >> j) & 1U;
    semlio::detail::sort_keys<N>(a.data());
    if (!std::is_sorted(a.begin(), a.end())) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("sort_keys sorts like std::sort: Batcher's networks on 4, 8 and 16 keys", "[search]") {
  CHECK(semlio::detail::kBatcherNetwork<4>.size() == 5);
  CHECK(semlio::detail::kBatcherNetwork<8>.size() == 19);
  CHECK(semlio::detail::kBatcherNetwork<16>.size() == 63);
  CHECK(sorts_every_binary_input<4>());
  CHECK(sorts_every_binary_input<8>());
  CHECK(sorts_every_binary_input<16>());
  // Full 64-bit keys: distances with ties, the padding key, permutations.
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> level(0, 6);
  std::size_t mismatches = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::array<std::uint64_t, 16> a{};
    for (std::size_t j = 0; j < a.size(); ++j) {
      a[j] = j % 5 == 4 ? ~std::uint64_t{0}
                        : semlio::detail::distance_index_key(0.5F * static_cast<float>(level(rng)),
                                                             static_cast<std::uint32_t>(rng() % 64U));
    }
    std::array<std::uint64_t, 16> ref = a;
    std::sort(ref.begin(), ref.end());
    semlio::detail::sort_keys<16>(a.data());
    mismatches += a == ref ? 0U : 1U;
  }
  CHECK(mismatches == 0);
}

TEST_CASE("KBest::assign_sorted and assign_unsorted hold what offering the keys one by one holds", "[search]") {
  std::mt19937 rng(6);
  std::uniform_int_distribution<int> level(0, 9);
  std::size_t mismatches = 0;
  for (std::size_t k = 1; k <= 20; ++k) {
    for (std::size_t n = 0; n <= 16; ++n) {
      std::vector<std::uint64_t> keys;
      semlio::detail::KBest offered(k);
      for (std::uint32_t i = 0; i < n; ++i) {
        const float d = 0.25F * static_cast<float>(level(rng));
        const std::uint32_t idx = (i * 37U + static_cast<std::uint32_t>(k)) % 101U;
        keys.push_back(semlio::detail::distance_index_key(d, idx));
        offered.offer(d, idx);
      }
      std::array<std::uint64_t, 16> unsorted{};
      std::copy(keys.begin(), keys.end(), unsorted.begin());  // still in offer order
      std::sort(keys.begin(), keys.end());
      semlio::detail::KBest assigned(k);
      assigned.assign_sorted(keys.data(), keys.size());
      semlio::detail::KBest blocked(k);
      blocked.assign_unsorted(unsorted.data(), n);
      for (std::uint32_t i = 0; i < 10; ++i) {  // later leaves: offers on top of the block
        const float d = 0.25F * static_cast<float>(level(rng));
        assigned.offer(d, 200 + i);
        blocked.offer(d, 200 + i);
        offered.offer(d, 200 + i);
      }
      std::array<std::uint32_t, 20> ia{};
      std::array<float, 20> da{};
      std::array<std::uint32_t, 20> ib{};
      std::array<float, 20> db{};
      const std::size_t na = assigned.write(ia.data(), da.data());
      const std::size_t nb = offered.write(ib.data(), db.data());
      mismatches += na == nb && assigned.full() == offered.full() && ia == ib && da == db ? 0U : 1U;
      if (na > 0) mismatches += assigned.worst() == offered.worst() ? 0U : 1U;
      std::array<std::uint32_t, 20> ic{};
      std::array<float, 20> dc{};
      const std::size_t nc = blocked.write(ic.data(), dc.data());
      mismatches += nc == nb && blocked.full() == offered.full() && ic == ib && dc == db ? 0U : 1U;
    }
  }
  CHECK(mismatches == 0);
}

}  // namespace test_k_best
