#include <catch2/catch.hpp>

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

}  // namespace test_k_best
