// Scan: validate, filter_in_place, append_point, label_histogram.
#include <catch2/catch.hpp>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>

#include <cstdint>
#include <string>

namespace test_scan {  // one namespace per test file: the area compiles as one TU

using semlio::Class;
using semlio::Scan;

namespace {

// A scan of n points with every optional field filled from the index.
Scan full_scan(std::size_t n) {
  Scan s;
  for (std::size_t i = 0; i < n; ++i) {
    const auto f = static_cast<float>(i);
    s.points.emplace_back(f, 2.0F * f, -f);
    s.intensity.push_back(0.5F * f);
    s.labels.push_back(semlio::class_from_index(static_cast<int>(i % 20)));
    s.instances.push_back(static_cast<std::uint16_t>(100 + i));
    s.rings.push_back(static_cast<std::uint16_t>(i % 64));
    s.times_s.push_back(0.001F * f);
  }
  s.stamp_s = 12.5;
  return s;
}

}  // namespace

TEST_CASE("Scan: empty and fully populated scans validate", "[core]") {
  Scan empty;
  CHECK(empty.empty());
  CHECK(empty.size() == 0);
  CHECK_NOTHROW(empty.validate());
  const Scan s = full_scan(30);
  CHECK(s.size() == 30);
  CHECK(s.has_intensity());
  CHECK(s.has_labels());
  CHECK(s.has_instances());
  CHECK(s.has_rings());
  CHECK(s.has_times());
  CHECK_NOTHROW(s.validate());
  // Positions only is valid too: optional fields may be absent.
  Scan positions_only;
  positions_only.points.assign(5, semlio::Point3f::Zero());
  CHECK_NOTHROW(positions_only.validate());
  CHECK_FALSE(positions_only.has_labels());
}

TEST_CASE("Scan: validate names the field whose length is wrong", "[core]") {
  const auto expect_bad = [](Scan s, const std::string& field) {
    INFO(field);
    try {
      s.validate();
      FAIL("no exception");
    } catch (const semlio::ValueError& e) {
      const std::string what = e.what();
      CHECK(what.find(field) != std::string::npos);
      CHECK(what.find("10 points") != std::string::npos);
    }
  };
  Scan s = full_scan(10);
  s.intensity.pop_back();
  expect_bad(s, "intensity");
  s = full_scan(10);
  s.labels.push_back(Class::kCar);
  expect_bad(s, "labels");
  s = full_scan(10);
  s.instances.resize(3);
  expect_bad(s, "instances");
  s = full_scan(10);
  s.rings.resize(1);
  expect_bad(s, "rings");
  s = full_scan(10);
  s.times_s.resize(9);
  expect_bad(s, "times_s");
  // It is a semlio::Error, catchable through the base.
  s = full_scan(10);
  s.rings.resize(2);
  CHECK_THROWS_AS(s.validate(), semlio::Error);
}

TEST_CASE("Scan: filter_in_place keeps the chosen points, in order, in every field", "[core]") {
  Scan s = full_scan(40);
  filter_in_place(s, [](std::size_t i) { return i % 3 == 1; });
  REQUIRE(s.size() == 13);  // 1, 4, ..., 37
  CHECK_NOTHROW(s.validate());
  for (std::size_t k = 0; k < s.size(); ++k) {
    const std::size_t i = 3 * k + 1;
    const auto f = static_cast<float>(i);
    CHECK(s.points[k] == semlio::Point3f(f, 2.0F * f, -f));
    CHECK(s.intensity[k] == 0.5F * f);
    CHECK(semlio::index(s.labels[k]) == static_cast<int>(i % 20));
    CHECK(s.instances[k] == 100 + i);
    CHECK(s.rings[k] == i % 64);
    CHECK(s.times_s[k] == 0.001F * f);
  }
  CHECK(s.stamp_s == 12.5);
  // Keep all, keep none.
  Scan all = full_scan(7);
  filter_in_place(all, [](std::size_t) { return true; });
  CHECK(all.size() == 7);
  CHECK(all.labels.size() == 7);
  filter_in_place(all, [](std::size_t) { return false; });
  CHECK(all.empty());
  CHECK(all.intensity.empty());
  CHECK(all.times_s.empty());
}

TEST_CASE("Scan: filter_in_place leaves absent fields absent", "[core]") {
  Scan s;
  for (int i = 0; i < 10; ++i) s.points.emplace_back(static_cast<float>(i), 0.0F, 0.0F);
  s.labels.assign(10, Class::kRoad);
  filter_in_place(s, [](std::size_t i) { return i >= 6; });
  CHECK(s.size() == 4);
  CHECK(s.points.front().x() == 6.0F);
  CHECK(s.labels.size() == 4);
  CHECK_FALSE(s.has_intensity());
  CHECK_FALSE(s.has_rings());
  CHECK_NOTHROW(s.validate());
}

TEST_CASE("Scan: append_point copies one point with its fields", "[core]") {
  const Scan src = full_scan(5);
  Scan dst;
  append_point(src, 3, dst);
  append_point(src, 0, dst);
  REQUIRE(dst.size() == 2);
  CHECK_NOTHROW(dst.validate());
  CHECK(dst.points[0] == src.points[3]);
  CHECK(dst.intensity[1] == src.intensity[0]);
  CHECK(dst.labels[0] == src.labels[3]);
  CHECK(dst.instances[0] == 103);
  CHECK(dst.rings[1] == 0);
  CHECK(dst.times_s[0] == src.times_s[3]);
}

TEST_CASE("Scan: clear empties every field, reserve keeps the fields valid", "[core]") {
  Scan s = full_scan(12);
  s.clear();
  CHECK(s.empty());
  CHECK_FALSE(s.has_labels());
  CHECK_FALSE(s.has_times());
  CHECK(s.stamp_s == 0.0);
  Scan t = full_scan(3);
  t.reserve(1000);
  CHECK(t.points.capacity() >= 1000);
  CHECK(t.labels.capacity() >= 1000);
  CHECK(t.size() == 3);
  CHECK_NOTHROW(t.validate());
}

TEST_CASE("Scan: label_histogram counts points per learning class", "[core]") {
  Scan s;
  const auto add = [&s](Class c, int n) {
    for (int i = 0; i < n; ++i) {
      s.points.emplace_back(0.0F, 0.0F, 0.0F);
      s.labels.push_back(c);
    }
  };
  add(Class::kBuilding, 25);
  add(Class::kVegetation, 17);
  add(Class::kTrunk, 3);
  add(Class::kPole, 2);
  add(Class::kUnlabeled, 3);
  const semlio::LabelHistogram h = semlio::label_histogram(s);
  CHECK(h[static_cast<std::size_t>(semlio::index(Class::kBuilding))] == 25);
  CHECK(h[static_cast<std::size_t>(semlio::index(Class::kVegetation))] == 17);
  CHECK(h[static_cast<std::size_t>(semlio::index(Class::kTrunk))] == 3);
  CHECK(h[static_cast<std::size_t>(semlio::index(Class::kPole))] == 2);
  CHECK(h[0] == 3);
  std::uint32_t total = 0;
  for (const auto v : h) total += v;
  CHECK(total == 50);
  // Every length's tail (the counts are kept in four parts), against one counter.
  for (std::size_t n = 0; n < 11; ++n) {
    Scan t;
    semlio::LabelHistogram want{};
    for (std::size_t i = 0; i < n; ++i) {
      const Class c = i % 3 == 0 ? Class::kCar : (i % 3 == 1 ? Class::kRoad : Class::kPole);
      t.points.emplace_back(0.0F, 0.0F, 0.0F);
      t.labels.push_back(c);
      ++want[static_cast<std::size_t>(semlio::index(c))];
    }
    CHECK(semlio::label_histogram(t) == want);
  }
  // No labels: all zeros.
  Scan unlabeled;
  unlabeled.points.assign(4, semlio::Point3f::Zero());
  for (const auto v : semlio::label_histogram(unlabeled)) CHECK(v == 0);
}

}  // namespace test_scan
