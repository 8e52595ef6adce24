#pragma once
/// \file
/// Building blocks for procedural worlds: SemanticKITTI raw ids, default
/// reflectivities, and helpers that add labelled objects (trees, poles,
/// signs, cars, buildings, quads) with fresh instance ids.

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <vector>

#include <semlio/sim/geometry.hpp>
#include <semlio/sim/random.hpp>

namespace semlio::sim {

/// Raw SemanticKITTI ids used by the simulator (semantic-kitti.yaml).
namespace raw {
inline constexpr std::uint16_t kCar = 10;
inline constexpr std::uint16_t kTruck = 18;
inline constexpr std::uint16_t kOtherVehicle = 20;
inline constexpr std::uint16_t kPerson = 30;
inline constexpr std::uint16_t kBicyclist = 31;
inline constexpr std::uint16_t kRoad = 40;
inline constexpr std::uint16_t kParking = 44;
inline constexpr std::uint16_t kSidewalk = 48;
inline constexpr std::uint16_t kOtherGround = 49;
inline constexpr std::uint16_t kBuilding = 50;
inline constexpr std::uint16_t kFence = 51;
inline constexpr std::uint16_t kLaneMarking = 60;
inline constexpr std::uint16_t kVegetation = 70;
inline constexpr std::uint16_t kTrunk = 71;
inline constexpr std::uint16_t kTerrain = 72;
inline constexpr std::uint16_t kPole = 80;
inline constexpr std::uint16_t kTrafficSign = 81;
inline constexpr std::uint16_t kMovingCar = 252;
inline constexpr std::uint16_t kMovingBicyclist = 253;
inline constexpr std::uint16_t kMovingPerson = 254;
inline constexpr std::uint16_t kMovingTruck = 258;
}  // namespace raw

/// Typical lidar reflectivity of a surface class (0..1), tuned so the mean
/// intensity of an urban sweep is near KITTI's (~0.29).
inline float default_reflectivity(std::uint16_t raw_id) {
  switch (raw_id) {
    case raw::kRoad: return 0.34F;
    case raw::kLaneMarking: return 0.85F;
    case raw::kParking: return 0.36F;
    case raw::kSidewalk: return 0.45F;
    case raw::kOtherGround: return 0.42F;
    case raw::kBuilding: return 0.48F;
    case raw::kFence: return 0.45F;
    case raw::kVegetation: return 0.55F;
    case raw::kTrunk: return 0.45F;
    case raw::kTerrain: return 0.52F;
    case raw::kPole: return 0.55F;
    case raw::kTrafficSign: return 0.98F;
    case raw::kCar:
    case raw::kMovingCar: return 0.40F;
    case raw::kTruck:
    case raw::kMovingTruck: return 0.45F;
    default: return 0.45F;
  }
}

/// Accumulates static primitives and hands out instance ids (1, 2, ...;
/// 0 is "no instance", used for ground stuff). Ids of static objects stay
/// below `kFirstActorInstance`, which traffic actors start from.
class WorldBuilder {
 public:
  static constexpr std::uint16_t kFirstActorInstance = 60000;

  /// The primitives added so far.
  std::vector<Primitive> prims;

  /// A fresh instance id for a new object (wraps before the actor range).
  std::uint16_t new_instance() {
    if (next_ >= kFirstActorInstance) next_ = 1;
    return next_++;
  }
  /// Surface of `raw_id` with its default reflectivity scaled by `refl_scale`.
  static Surface surface(std::uint16_t raw_id, std::uint16_t instance, double refl_scale = 1.0) {
    return {raw_id, instance, static_cast<float>(static_cast<double>(default_reflectivity(raw_id)) * refl_scale)};
  }

  /// Quad a-b-c-d (counter-clockwise) as two triangles; stuff (instance 0).
  void quad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
            const Eigen::Vector3d& d, std::uint16_t raw_id) {
    const Surface s = surface(raw_id, 0);
    prims.push_back(make_triangle(a, b, c, s));
    prims.push_back(make_triangle(a, c, d, s));
  }
  /// Axis-aligned (with yaw) rectangle at height z between corners lo and hi (x, y).
  void flat_rect(double x0, double y0, double x1, double y1, double z, std::uint16_t raw_id) {
    quad({x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}, raw_id);
  }
  /// Like flat_rect, split into tiles of at most `tile_m` (keeps the BVH tight).
  void tiled_rect(double x0, double y0, double x1, double y1, double z, std::uint16_t raw_id, double tile_m) {
    const int nx = std::max(1, static_cast<int>(std::ceil((x1 - x0) / tile_m)));
    const int ny = std::max(1, static_cast<int>(std::ceil((y1 - y0) / tile_m)));
    for (int i = 0; i < nx; ++i) {
      for (int j = 0; j < ny; ++j) {
        flat_rect(x0 + (x1 - x0) * i / nx, y0 + (y1 - y0) * j / ny, x0 + (x1 - x0) * (i + 1) / nx,
                  y0 + (y1 - y0) * (j + 1) / ny, z, raw_id);
      }
    }
  }
  /// Box of stuff or an object (pass instance 0 for stuff).
  void box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, double yaw_rad,
           std::uint16_t raw_id, std::uint16_t instance, double refl_scale = 1.0) {
    prims.push_back(make_box(centre, half, yaw_rad, surface(raw_id, instance, refl_scale)));
  }

  /// Tree: trunk (cylinder) and canopy (ellipsoid) sharing one instance.
  void tree(const Eigen::Vector3d& ground, Rng& rng, double scale = 1.0) {
    const std::uint16_t id = new_instance();
    const double trunk_r = rng.uniform(0.12, 0.28) * scale;
    const double trunk_h = rng.uniform(2.0, 3.4) * scale;
    const double crx = rng.uniform(1.6, 3.0) * scale;
    const double crz = rng.uniform(1.4, 2.6) * scale;
    // The trunk starts 0.3 m below ground so it never floats on sloped terrain.
    prims.push_back(make_cylinder(ground - Eigen::Vector3d(0.0, 0.0, 0.3), trunk_r, trunk_h + 0.3 + 0.5 * crz,
                                  surface(raw::kTrunk, id)));
    prims.push_back(make_ellipsoid(ground + Eigen::Vector3d(0.0, 0.0, trunk_h + crz),
                                   Eigen::Vector3d(crx, crx * rng.uniform(0.85, 1.15), crz),
                                   surface(raw::kVegetation, id)));
  }
  /// Bush: a low ellipsoid of vegetation.
  void bush(const Eigen::Vector3d& ground, Rng& rng) {
    const std::uint16_t id = new_instance();
    const double r = rng.uniform(0.6, 1.6);
    const double h = rng.uniform(0.5, 1.2);
    prims.push_back(make_ellipsoid(ground + Eigen::Vector3d(0.0, 0.0, 0.5 * h),
                                   Eigen::Vector3d(r, r * rng.uniform(0.7, 1.3), h),
                                   surface(raw::kVegetation, id)));
  }
  /// Street light or utility pole.
  void pole(const Eigen::Vector3d& ground, double height_m, double radius_m = 0.1) {
    prims.push_back(make_cylinder(ground - Eigen::Vector3d(0.0, 0.0, 0.2), radius_m, height_m + 0.2,
                                  surface(raw::kPole, new_instance())));
  }
  /// Traffic sign: a thin pole and a plate facing along `facing_yaw_rad`.
  void sign(const Eigen::Vector3d& ground, double facing_yaw_rad, Rng& rng) {
    const std::uint16_t id = new_instance();
    const double h = rng.uniform(2.0, 2.6);
    prims.push_back(make_cylinder(ground - Eigen::Vector3d(0.0, 0.0, 0.2), 0.04, h + 0.2, surface(raw::kPole, id)));
    const double half = rng.uniform(0.3, 0.45);
    prims.push_back(make_box(ground + Eigen::Vector3d(0.0, 0.0, h + half), Eigen::Vector3d(0.02, half, half),
                             facing_yaw_rad, surface(raw::kTrafficSign, id)));
  }
  /// Parked car (static, raw id car): body and cabin boxes with one instance.
  void parked_car(const Eigen::Vector3d& ground, double yaw_rad, Rng& rng) {
    append_car(prims, ground, yaw_rad, raw::kCar, new_instance(), rng.uniform(0.6, 1.4));
  }

  /// Car geometry (body + cabin) at `ground` with heading `yaw_rad`.
  static void append_car(std::vector<Primitive>& out, const Eigen::Vector3d& ground, double yaw_rad,
                         std::uint16_t raw_id, std::uint16_t instance, double refl_scale) {
    const Surface s = surface(raw_id, instance, refl_scale);
    const Eigen::Vector3d fwd(std::cos(yaw_rad), std::sin(yaw_rad), 0.0);
    out.push_back(make_box(ground + Eigen::Vector3d(0.0, 0.0, 0.72), Eigen::Vector3d(2.2, 0.9, 0.45), yaw_rad, s));
    out.push_back(make_box(ground - 0.25 * fwd + Eigen::Vector3d(0.0, 0.0, 1.43), Eigen::Vector3d(1.2, 0.78, 0.27),
                           yaw_rad, s));
  }

 private:
  std::uint16_t next_ = 1;
};

}  // namespace semlio::sim
