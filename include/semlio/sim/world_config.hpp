#pragma once
/// \file
/// World kinds, the world generation config, and the generated World: the
/// static scene (BVH), the ego route, and the lanes traffic drives on.

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/sim/bvh.hpp>
#include <semlio/sim/trajectory.hpp>

namespace semlio::sim {

/// The procedural world families.
enum class WorldKind : std::uint8_t { kUrban, kRural, kHighway, kAliased };

/// Name used on the command line and in sim.json ("urban", ...).
constexpr std::string_view world_name(WorldKind k) noexcept {
  switch (k) {
    case WorldKind::kUrban: return "urban";
    case WorldKind::kRural: return "rural";
    case WorldKind::kHighway: return "highway";
    case WorldKind::kAliased: return "aliased";
  }
  return "urban";
}

/// Parses a world name; throws ConfigError naming the bad value.
inline WorldKind parse_world(std::string_view name) {
  for (const WorldKind k : {WorldKind::kUrban, WorldKind::kRural, WorldKind::kHighway, WorldKind::kAliased}) {
    if (name == world_name(k)) return k;
  }
  throw ConfigError("world must be urban|rural|highway|aliased, got '" + std::string(name) + "'");
}

/// How a world is generated. Same config -> identical world.
struct WorldConfig {
  WorldKind kind = WorldKind::kUrban;  ///< world family
  std::uint64_t seed = 1;              ///< seed of every random choice
  double drive_length_m = 1200.0;      ///< the route is at least this long (plus margin) [m]
  bool revisit = false;                ///< route is a closed loop no longer than drive_length_m
  double loop_target_m = 0.0;          ///< revisit: longest loop wanted [m] (0: 0.6 * drive_length_m)
};

/// A path traffic drives on (world frame, road surface) and its speed.
struct Lane {
  std::vector<Eigen::Vector3d> points;  ///< corner or dense points (Trajectory rounds corners)
  double cruise_speed_mps = 11.0;       ///< speed on straights [m/s]
  double turn_radius_m = 8.0;           ///< corner rounding radius [m]
};

/// Where traffic of each kind drives.
struct TrafficLanes {
  Lane alongside;               ///< same direction as the ego, adjacent lane (empty points: none)
  Lane oncoming;                ///< opposite direction
  Lane bikes;                   ///< cyclists (empty points: none)
  std::vector<Lane> walkways;   ///< pedestrian loops (empty: none)
  bool trucks = true;           ///< whether trucks appear among cars
  double alongside_first_offset_s = 0.4;  ///< the first alongside actor is this far ahead in time [s]
};

/// A generated world. The BVH is immutable; casting is thread-safe.
struct World {
  WorldConfig config;                          ///< what it was generated from
  Bvh bvh;                                     ///< static scene
  std::vector<Eigen::Vector3d> ego_route;      ///< ego route points on the road surface (world frame)
  TrajectoryConfig ego_motion;                 ///< ego speeds and turn radius (stops: see ego_stop_points)
  std::vector<Eigen::Vector3d> ego_stop_points;  ///< the ego stops here (world frame; on its route, in order)
  TrafficLanes lanes;                          ///< traffic paths
  double loop_length_m = 0.0;                  ///< revisit: length of one loop of the route [m] (0: open route)
};

}  // namespace semlio::sim
