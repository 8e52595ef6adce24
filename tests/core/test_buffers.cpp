// core/buffers.hpp: the growth rule of per-frame buffers and the
// default-initialising allocator of the map's lazy caches.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <vector>

#include <semlio/core/buffers.hpp>

TEST_CASE("reserve_with_headroom keeps content and grows by at least half, with an eighth to spare", "[core]") {
  std::vector<int> v;
  semlio::reserve_with_headroom(v, 100);
  CHECK(v.capacity() == 100);  // first use: exact
  v.assign({1, 2, 3});
  semlio::reserve_with_headroom(v, 90);  // fits: untouched
  CHECK(v.capacity() == 100);
  semlio::reserve_with_headroom(v, 120);  // max(120 + 15, 150)
  CHECK(v.capacity() == 150);
  CHECK(v == std::vector<int>{1, 2, 3});
  semlio::reserve_with_headroom(v, 400);  // max(400 + 50, 225)
  CHECK(v.capacity() == 450);
  CHECK(v == std::vector<int>{1, 2, 3});
}

TEST_CASE("reserve_discarding empties a buffer only when it must grow", "[core]") {
  std::vector<int> v{4, 5, 6};
  v.reserve(10);
  semlio::reserve_discarding(v, 8);
  CHECK(v == std::vector<int>{4, 5, 6});
  semlio::reserve_discarding(v, 20);
  CHECK(v.empty());
  CHECK(v.capacity() == 22);  // max(20 + 2, 15)
}

TEST_CASE("DefaultInitAllocator vectors keep values through growth and construct from arguments", "[core]") {
  std::vector<std::uint32_t, semlio::DefaultInitAllocator<std::uint32_t>> v;
  v.push_back(7U);
  v.emplace_back(8U);
  v.resize(1000);  // the added elements are unspecified; the first two are kept
  v[999] = 42U;
  v.reserve(5000);
  CHECK(v.size() == 1000);
  CHECK(v[0] == 7U);
  CHECK(v[1] == 8U);
  CHECK(v[999] == 42U);
  // Every element written before the copy is compared: reading the
  // unspecified ones would be reading uninitialised memory (valgrind).
  std::fill(v.begin() + 2, v.begin() + 999, 5U);
  const std::vector<std::uint32_t, semlio::DefaultInitAllocator<std::uint32_t>> copy(v);
  CHECK(copy == v);
  std::vector<float, semlio::DefaultInitAllocator<float>> f(3, 1.5F);  // explicit value: filled
  CHECK(f == std::vector<float, semlio::DefaultInitAllocator<float>>{1.5F, 1.5F, 1.5F});
}
