// radix_sort_by_key against std::stable_sort: the order LocalMap's voxel
// merge and VoxelGrid's output rely on, duplicates kept in input order.
#include <catch2/catch.hpp>

#include <semlio/core/radix_sort.hpp>

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

namespace test_radix_sort {  // one namespace per test file: the area compiles as one TU

using Item = std::pair<std::uint64_t, std::uint32_t>;  // (key, input position)

TEST_CASE("radix_sort_by_key equals a stable sort by key", "[core][radix_sort]") {
  std::mt19937_64 rng(3);
  semlio::RadixCounts counts;
  std::vector<Item> scratch;
  // Key widths across digit boundaries; few distinct keys (many ties), keys
  // sharing whole digits (skipped passes), and sizes 0..1 (nothing to do).
  for (const int bits : {1, 11, 12, 21, 33, 63, 64}) {
    for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{2}, std::size_t{1000}, std::size_t{50000}}) {
      for (const std::uint64_t distinct_mask : {~std::uint64_t{0}, std::uint64_t{0xF}, std::uint64_t{0xF000F}}) {
        const std::uint64_t width_mask = bits == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;
        std::vector<Item> items(n);
        for (std::uint32_t i = 0; i < n; ++i) items[i] = {rng() & distinct_mask & width_mask, i};
        std::vector<Item> want = items;
        std::stable_sort(want.begin(), want.end(), [](const Item& a, const Item& b) { return a.first < b.first; });
        semlio::radix_sort_by_key(items, scratch, counts, bits, [](const Item& it) { return it.first; });
        INFO("bits " << bits << ", n " << n << ", mask " << distinct_mask);
        CHECK(items == want);
      }
    }
  }
}

}  // namespace test_radix_sort
