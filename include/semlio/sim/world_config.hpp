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
  /// Revisit: the route is a closed lap sized so that the ego is back at its
  /// start pose (same heading, at speed) exactly at return_time_s (see
  /// revisit.hpp); the lap is driven twice, the second lap being a tail.
  bool revisit = false;
  double return_time_s = 0.0;          ///< revisit: when the ego must be back [s] (0: drive_length_m / typical speed)
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
  /// > 0: the alongside lane repeats the ego's own loop with about this lap
  /// time [s]; actor time offsets keep >= 2.5 s from its multiples, so no
  /// actor drives on top of the ego.
  double alongside_period_s = 0.0;
};

/// A generated world. The BVH is immutable; casting is thread-safe.
struct World {
  WorldConfig config;                          ///< what it was generated from
  Bvh bvh;                                     ///< static scene
  std::vector<Eigen::Vector3d> ego_route;      ///< ego route points on the road surface (world frame)
  TrajectoryConfig ego_motion;                 ///< ego speeds and turn radius (stops: see ego_stop_points)
  std::vector<Eigen::Vector3d> ego_stop_points;  ///< the ego stops here (world frame; on its route, in order)
  TrafficLanes lanes;                          ///< traffic paths
  double loop_length_m = 0.0;                  ///< revisit: length of one lap of the ego path [m] (0: open route)
  double return_time_s = 0.0;                  ///< revisit: time the ego is back at its start [s] (0: open route)
  double return_error_m = 0.0;                 ///< revisit: distance driven at return_time_s minus loop_length_m [m]
  std::string revisit_route;                   ///< revisit: "block_loop" or "out_and_back" (empty: open route)
};

}  // namespace semlio::sim
