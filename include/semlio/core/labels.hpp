#pragma once
/// \file
/// The SemanticKITTI label table: raw ids as stored in `.label` files, the 19
/// learning classes (+ unlabeled) the pipeline works in, the mapping between
/// them, class names, colours, and the static/dynamic split of METHOD.md
/// (eq. 18).

#include <array>
#include <cstdint>
#include <string_view>

namespace semlio {

/// Learning class ids (SemanticKITTI's 19 evaluated classes plus unlabeled).
enum class Class : std::uint8_t {
  kUnlabeled = 0,
  kCar = 1,
  kBicycle = 2,
  kMotorcycle = 3,
  kTruck = 4,
  kOtherVehicle = 5,
  kPerson = 6,
  kBicyclist = 7,
  kMotorcyclist = 8,
  kRoad = 9,
  kParking = 10,
  kSidewalk = 11,
  kOtherGround = 12,
  kBuilding = 13,
  kFence = 14,
  kVegetation = 15,
  kTrunk = 16,
  kTerrain = 17,
  kPole = 18,
  kTrafficSign = 19,
};

/// Number of learning classes including unlabeled (ids 0..19).
inline constexpr int kNumClasses = 20;

/// An 8-bit RGB colour.
struct Rgb {
  std::uint8_t r, g, b;
};

namespace detail {

/// One row of the raw-id table.
struct RawLabelInfo {
  std::uint16_t raw_id;
  Class learning;
  std::string_view name;
  Rgb colour;
};

// SemanticKITTI's semantic-kitti.yaml: raw id, learning class, name, colour
// (given there as BGR; stored here as RGB).
inline constexpr std::array<RawLabelInfo, 34> kRawLabels{{
    {0, Class::kUnlabeled, "unlabeled", {0, 0, 0}},
    {1, Class::kUnlabeled, "outlier", {255, 0, 0}},
    {10, Class::kCar, "car", {100, 150, 245}},
    {11, Class::kBicycle, "bicycle", {100, 230, 245}},
    {13, Class::kOtherVehicle, "bus", {100, 80, 250}},
    {15, Class::kMotorcycle, "motorcycle", {30, 60, 150}},
    {16, Class::kOtherVehicle, "on-rails", {0, 0, 255}},
    {18, Class::kTruck, "truck", {80, 30, 180}},
    {20, Class::kOtherVehicle, "other-vehicle", {0, 0, 255}},
    {30, Class::kPerson, "person", {255, 30, 30}},
    {31, Class::kBicyclist, "bicyclist", {255, 40, 200}},
    {32, Class::kMotorcyclist, "motorcyclist", {150, 30, 90}},
    {40, Class::kRoad, "road", {255, 0, 255}},
    {44, Class::kParking, "parking", {255, 150, 255}},
    {48, Class::kSidewalk, "sidewalk", {75, 0, 75}},
    {49, Class::kOtherGround, "other-ground", {175, 0, 75}},
    {50, Class::kBuilding, "building", {255, 200, 0}},
    {51, Class::kFence, "fence", {255, 120, 50}},
    {52, Class::kUnlabeled, "other-structure", {255, 150, 0}},
    {60, Class::kRoad, "lane-marking", {150, 255, 170}},
    {70, Class::kVegetation, "vegetation", {0, 175, 0}},
    {71, Class::kTrunk, "trunk", {135, 60, 0}},
    {72, Class::kTerrain, "terrain", {150, 240, 80}},
    {80, Class::kPole, "pole", {255, 240, 150}},
    {81, Class::kTrafficSign, "traffic-sign", {255, 0, 0}},
    {99, Class::kUnlabeled, "other-object", {50, 255, 255}},
    {252, Class::kCar, "moving-car", {100, 150, 245}},
    {253, Class::kBicyclist, "moving-bicyclist", {255, 40, 200}},
    {254, Class::kPerson, "moving-person", {255, 30, 30}},
    {255, Class::kMotorcyclist, "moving-motorcyclist", {150, 30, 90}},
    {256, Class::kOtherVehicle, "moving-on-rails", {0, 0, 255}},
    {257, Class::kOtherVehicle, "moving-bus", {100, 80, 250}},
    {258, Class::kTruck, "moving-truck", {80, 30, 180}},
    {259, Class::kOtherVehicle, "moving-other-vehicle", {0, 0, 255}},
}};

/// Per learning class: the raw id it maps back to, its name and colour.
struct ClassInfo {
  std::uint16_t raw_id;
  std::string_view name;
  Rgb colour;
};

inline constexpr std::array<ClassInfo, kNumClasses> kClasses{{
    {0, "unlabeled", {0, 0, 0}},
    {10, "car", {100, 150, 245}},
    {11, "bicycle", {100, 230, 245}},
    {15, "motorcycle", {30, 60, 150}},
    {18, "truck", {80, 30, 180}},
    {20, "other-vehicle", {0, 0, 255}},
    {30, "person", {255, 30, 30}},
    {31, "bicyclist", {255, 40, 200}},
    {32, "motorcyclist", {150, 30, 90}},
    {40, "road", {255, 0, 255}},
    {44, "parking", {255, 150, 255}},
    {48, "sidewalk", {75, 0, 75}},
    {49, "other-ground", {175, 0, 75}},
    {50, "building", {255, 200, 0}},
    {51, "fence", {255, 120, 50}},
    {70, "vegetation", {0, 175, 0}},
    {71, "trunk", {135, 60, 0}},
    {72, "terrain", {150, 240, 80}},
    {80, "pole", {255, 240, 150}},
    {81, "traffic-sign", {255, 0, 0}},
}};

}  // namespace detail

/// Learning class of a raw SemanticKITTI id (semantic part, low 16 bits);
/// unknown raw ids map to unlabeled.
constexpr Class learning_class(std::uint32_t raw_label) noexcept {
  const auto semantic = static_cast<std::uint16_t>(raw_label & 0xFFFFu);
  for (const auto& row : detail::kRawLabels) {
    if (row.raw_id == semantic) return row.learning;
  }
  return Class::kUnlabeled;
}

/// True when the raw id is one SemanticKITTI defines.
constexpr bool is_known_raw_id(std::uint32_t raw_label) noexcept {
  const auto semantic = static_cast<std::uint16_t>(raw_label & 0xFFFFu);
  for (const auto& row : detail::kRawLabels) {
    if (row.raw_id == semantic) return true;
  }
  return false;
}

/// The raw id a learning class is written back as (the static variant:
/// car -> 10, never moving-car 252).
constexpr std::uint16_t raw_id(Class c) noexcept {
  return detail::kClasses[static_cast<std::size_t>(c)].raw_id;
}

/// SemanticKITTI name of a learning class ("car", "road", ...).
constexpr std::string_view class_name(Class c) noexcept {
  return detail::kClasses[static_cast<std::size_t>(c)].name;
}

/// Display colour of a learning class (SemanticKITTI's palette, RGB).
constexpr Rgb class_colour(Class c) noexcept {
  return detail::kClasses[static_cast<std::size_t>(c)].colour;
}

/// Static classes of METHOD.md eq. 18: road, parking, sidewalk, other-ground,
/// building, fence, vegetation, trunk, terrain, pole, traffic-sign.
constexpr bool is_static(Class c) noexcept {
  const auto id = static_cast<int>(c);
  return id >= static_cast<int>(Class::kRoad) && id <= static_cast<int>(Class::kTrafficSign);
}

/// Dynamic (movable) classes of METHOD.md eq. 18: car, bicycle, motorcycle,
/// truck, other-vehicle, person, bicyclist, motorcyclist.
constexpr bool is_dynamic(Class c) noexcept {
  const auto id = static_cast<int>(c);
  return id >= static_cast<int>(Class::kCar) && id <= static_cast<int>(Class::kMotorcyclist);
}

/// True when a map point labelled `match` agrees with a feature labelled
/// `label` in eq. 10: the same class, or (when static_classes_agree) two
/// static classes (residual/semantic_weighted.hpp says why).
constexpr bool labels_agree(Class label, Class match, bool static_classes_agree) noexcept {
  return match == label || (static_classes_agree && is_static(label) && is_static(match));
}

/// Class id as a plain integer, for indexing histograms.
constexpr int index(Class c) noexcept { return static_cast<int>(c); }

/// Learning class from a plain integer; out-of-range values map to unlabeled.
constexpr Class class_from_index(int id) noexcept {
  return (id >= 0 && id < kNumClasses) ? static_cast<Class>(id) : Class::kUnlabeled;
}

}  // namespace semlio
