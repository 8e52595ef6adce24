// The SemanticKITTI label table against semantic-kitti.yaml (learning_map,
// learning_map_inv, labels, color_map) and METHOD.md eq. 18.
#include <catch2/catch.hpp>

#include <semlio/core/labels.hpp>
#include <semlio_test/data.hpp>

#include <array>
#include <cstdint>
#include <fstream>
#include <map>
#include <set>
#include <string_view>
#include <vector>

namespace test_labels {  // one namespace per test file: the area compiles as one TU

using semlio::Class;

namespace {

// One row of semantic-kitti.yaml, typed in from the dataset's config:
// raw id, learning id (learning_map), name (labels), colour as the yaml
// stores it (color_map is BGR).
struct YamlRow {
  std::uint32_t raw;
  int learning;
  std::string_view name;
  std::array<int, 3> bgr;
};

constexpr std::array<YamlRow, 34> kYaml{{
    {0, 0, "unlabeled", {0, 0, 0}},
    {1, 0, "outlier", {0, 0, 255}},
    {10, 1, "car", {245, 150, 100}},
    {11, 2, "bicycle", {245, 230, 100}},
    {13, 5, "bus", {250, 80, 100}},
    {15, 3, "motorcycle", {150, 60, 30}},
    {16, 5, "on-rails", {255, 0, 0}},
    {18, 4, "truck", {180, 30, 80}},
    {20, 5, "other-vehicle", {255, 0, 0}},
    {30, 6, "person", {30, 30, 255}},
    {31, 7, "bicyclist", {200, 40, 255}},
    {32, 8, "motorcyclist", {90, 30, 150}},
    {40, 9, "road", {255, 0, 255}},
    {44, 10, "parking", {255, 150, 255}},
    {48, 11, "sidewalk", {75, 0, 75}},
    {49, 12, "other-ground", {75, 0, 175}},
    {50, 13, "building", {0, 200, 255}},
    {51, 14, "fence", {50, 120, 255}},
    {52, 0, "other-structure", {0, 150, 255}},
    {60, 9, "lane-marking", {170, 255, 150}},
    {70, 15, "vegetation", {0, 175, 0}},
    {71, 16, "trunk", {0, 60, 135}},
    {72, 17, "terrain", {80, 240, 150}},
    {80, 18, "pole", {150, 240, 255}},
    {81, 19, "traffic-sign", {0, 0, 255}},
    {99, 0, "other-object", {255, 255, 50}},
    {252, 1, "moving-car", {245, 150, 100}},
    {253, 7, "moving-bicyclist", {200, 40, 255}},
    {254, 6, "moving-person", {30, 30, 255}},
    {255, 8, "moving-motorcyclist", {90, 30, 150}},
    {256, 5, "moving-on-rails", {255, 0, 0}},
    {257, 5, "moving-bus", {250, 80, 100}},
    {258, 4, "moving-truck", {180, 30, 80}},
    {259, 5, "moving-other-vehicle", {255, 0, 0}},
}};

// learning_map_inv of the yaml: learning id -> raw id.
constexpr std::array<std::uint16_t, 20> kLearningMapInv{0,  10, 11, 15, 18, 20, 30, 31, 32, 40,
                                                        44, 48, 49, 50, 51, 70, 71, 72, 80, 81};

}  // namespace

TEST_CASE("labels: every raw id of semantic-kitti.yaml maps to its learning class", "[core]") {
  for (const YamlRow& row : kYaml) {
    INFO("raw id " << row.raw << " (" << row.name << ")");
    CHECK(semlio::index(semlio::learning_class(row.raw)) == row.learning);
    CHECK(semlio::is_known_raw_id(row.raw));
    // The instance id lives in the high 16 bits and must not change the class.
    CHECK(semlio::index(semlio::learning_class(row.raw | (7U << 16))) == row.learning);
    CHECK(semlio::index(semlio::learning_class(row.raw | 0xFFFF0000U)) == row.learning);
  }
}

TEST_CASE("labels: the library's raw table is exactly the yaml's", "[core]") {
  REQUIRE(semlio::detail::kRawLabels.size() == kYaml.size());
  for (std::size_t i = 0; i < kYaml.size(); ++i) {
    const auto& lib = semlio::detail::kRawLabels[i];
    const YamlRow& yaml = kYaml[i];
    INFO("row " << i << " raw " << yaml.raw);
    CHECK(lib.raw_id == yaml.raw);
    CHECK(semlio::index(lib.learning) == yaml.learning);
    CHECK(lib.name == yaml.name);
    // RGB in the library, BGR in the yaml.
    CHECK(int{lib.colour.r} == yaml.bgr[2]);
    CHECK(int{lib.colour.g} == yaml.bgr[1]);
    CHECK(int{lib.colour.b} == yaml.bgr[0]);
  }
}

TEST_CASE("labels: unknown raw ids map to unlabeled", "[core]") {
  for (const std::uint32_t raw : {2U, 9U, 12U, 100U, 251U, 260U, 1000U, 65535U}) {
    INFO("raw id " << raw);
    CHECK(semlio::learning_class(raw) == Class::kUnlabeled);
    CHECK_FALSE(semlio::is_known_raw_id(raw));
  }
}

TEST_CASE("labels: inverse mapping (learning_map_inv) and round trip", "[core]") {
  for (int id = 0; id < semlio::kNumClasses; ++id) {
    const Class c = semlio::class_from_index(id);
    INFO("class " << id);
    CHECK(semlio::index(c) == id);
    CHECK(semlio::raw_id(c) == kLearningMapInv[static_cast<std::size_t>(id)]);
    CHECK(semlio::learning_class(semlio::raw_id(c)) == c);
  }
  // Moving variants write back as the static raw id.
  CHECK(semlio::raw_id(semlio::learning_class(252)) == 10);
  CHECK(semlio::raw_id(semlio::learning_class(258)) == 18);
  CHECK(semlio::class_from_index(-1) == Class::kUnlabeled);
  CHECK(semlio::class_from_index(20) == Class::kUnlabeled);
  static_assert(semlio::kNumClasses == 20);
  static_assert(semlio::learning_class(10) == Class::kCar);  // usable at compile time
}

TEST_CASE("labels: class names are the yaml names of learning_map_inv", "[core]") {
  for (int id = 0; id < semlio::kNumClasses; ++id) {
    const auto raw = kLearningMapInv[static_cast<std::size_t>(id)];
    std::string_view expected;
    for (const YamlRow& row : kYaml) {
      if (row.raw == raw) expected = row.name;
    }
    CHECK(semlio::class_name(semlio::class_from_index(id)) == expected);
  }
  CHECK(semlio::class_name(Class::kTrafficSign) == "traffic-sign");
  CHECK(semlio::class_name(Class::kOtherGround) == "other-ground");
}

TEST_CASE("labels: colours of a few classes match the SemanticKITTI palette (RGB)", "[core]") {
  const auto rgb = [](Class c) {
    const semlio::Rgb v = semlio::class_colour(c);
    return std::array<int, 3>{v.r, v.g, v.b};
  };
  CHECK(rgb(Class::kCar) == std::array<int, 3>{100, 150, 245});
  CHECK(rgb(Class::kRoad) == std::array<int, 3>{255, 0, 255});
  CHECK(rgb(Class::kBuilding) == std::array<int, 3>{255, 200, 0});
  CHECK(rgb(Class::kVegetation) == std::array<int, 3>{0, 175, 0});
  CHECK(rgb(Class::kPerson) == std::array<int, 3>{255, 30, 30});
  CHECK(rgb(Class::kTrafficSign) == std::array<int, 3>{255, 0, 0});
  CHECK(rgb(Class::kUnlabeled) == std::array<int, 3>{0, 0, 0});
  CHECK(rgb(Class::kSidewalk) == std::array<int, 3>{75, 0, 75});
}

TEST_CASE("labels: static and dynamic sets are exactly METHOD.md eq. 18", "[core]") {
  const std::set<Class> statics{Class::kRoad,       Class::kParking, Class::kSidewalk,   Class::kOtherGround,
                                Class::kBuilding,   Class::kFence,   Class::kVegetation, Class::kTrunk,
                                Class::kTerrain,    Class::kPole,    Class::kTrafficSign};
  const std::set<Class> dynamics{Class::kCar,        Class::kBicycle, Class::kMotorcycle, Class::kTruck,
                                 Class::kOtherVehicle, Class::kPerson, Class::kBicyclist, Class::kMotorcyclist};
  REQUIRE(statics.size() == 11);
  REQUIRE(dynamics.size() == 8);
  for (int id = 0; id < semlio::kNumClasses; ++id) {
    const Class c = semlio::class_from_index(id);
    INFO("class " << semlio::class_name(c));
    CHECK(semlio::is_static(c) == (statics.count(c) == 1));
    CHECK(semlio::is_dynamic(c) == (dynamics.count(c) == 1));
    CHECK_FALSE((semlio::is_static(c) && semlio::is_dynamic(c)));
  }
  // Unlabeled is neither.
  CHECK_FALSE(semlio::is_static(Class::kUnlabeled));
  CHECK_FALSE(semlio::is_dynamic(Class::kUnlabeled));
  // Moving raw ids land in dynamic classes.
  for (const std::uint32_t raw : {252U, 253U, 254U, 255U, 256U, 257U, 258U, 259U}) {
    CHECK(semlio::is_dynamic(semlio::learning_class(raw)));
  }
}

TEST_CASE("labels: labels_agree merges the static classes only when asked", "[core]") {
  using semlio::labels_agree;
  // Static with static agrees; movable or unlabelled agrees only with itself.
  CHECK(labels_agree(Class::kRoad, Class::kSidewalk, true));
  CHECK(labels_agree(Class::kTrunk, Class::kVegetation, true));
  CHECK(labels_agree(Class::kTrafficSign, Class::kBuilding, true));
  CHECK_FALSE(labels_agree(Class::kRoad, Class::kSidewalk, false));
  CHECK_FALSE(labels_agree(Class::kRoad, Class::kCar, true));
  CHECK_FALSE(labels_agree(Class::kCar, Class::kTruck, true));
  CHECK_FALSE(labels_agree(Class::kPerson, Class::kBicyclist, true));
  CHECK_FALSE(labels_agree(Class::kRoad, Class::kUnlabeled, true));
  CHECK_FALSE(labels_agree(Class::kUnlabeled, Class::kRoad, true));
  CHECK(labels_agree(Class::kCar, Class::kCar, true));
  CHECK(labels_agree(Class::kUnlabeled, Class::kUnlabeled, false));
  // Every pair: unmerged is equality; merged is symmetric, keeps every
  // unmerged agreement, and never joins a movable class to another class.
  for (int i = 0; i < semlio::kNumClasses; ++i) {
    for (int j = 0; j < semlio::kNumClasses; ++j) {
      const Class a = semlio::class_from_index(i);
      const Class b = semlio::class_from_index(j);
      CHECK(labels_agree(a, b, false) == (a == b));
      CHECK(labels_agree(a, b, true) == labels_agree(b, a, true));
      if (a == b) CHECK(labels_agree(a, b, true));
      if (a != b && (semlio::is_dynamic(a) || a == Class::kUnlabeled)) CHECK_FALSE(labels_agree(a, b, true));
    }
  }
}

TEST_CASE("labels: real SemanticKITTI labels of 50 points of 00/000000", "[core]") {
  // The data README documents the raw classes of these 50 points: building 25,
  // vegetation 17, trunk 3, pole 2, other-structure 1, unlabeled 2.
  std::ifstream in(semlio_test::data_path("kitti/semantickitti_subset/00/labels/000000.label"), std::ios::binary);
  REQUIRE(in);
  std::vector<std::uint32_t> raw;
  std::array<unsigned char, 4> b{};
  while (in.read(reinterpret_cast<char*>(b.data()), 4)) {  // little-endian uint32
    raw.push_back(std::uint32_t{b[0]} | (std::uint32_t{b[1]} << 8) | (std::uint32_t{b[2]} << 16) |
                  (std::uint32_t{b[3]} << 24));
  }
  REQUIRE(raw.size() == 50);
  std::map<std::uint32_t, int> by_raw;
  std::array<int, semlio::kNumClasses> hist{};
  for (const std::uint32_t r : raw) {
    CHECK(semlio::is_known_raw_id(r));
    ++by_raw[r & 0xFFFFU];
    ++hist[static_cast<std::size_t>(semlio::index(semlio::learning_class(r)))];
  }
  CHECK(by_raw[50] == 25);
  CHECK(by_raw[70] == 17);
  CHECK(by_raw[71] == 3);
  CHECK(by_raw[80] == 2);
  CHECK(by_raw[52] == 1);
  CHECK(by_raw[0] == 2);
  CHECK(hist[static_cast<std::size_t>(semlio::index(Class::kBuilding))] == 25);
  CHECK(hist[static_cast<std::size_t>(semlio::index(Class::kVegetation))] == 17);
  CHECK(hist[static_cast<std::size_t>(semlio::index(Class::kTrunk))] == 3);
  CHECK(hist[static_cast<std::size_t>(semlio::index(Class::kPole))] == 2);
  CHECK(hist[0] == 3);  // other-structure maps to unlabeled
}

}  // namespace test_labels
