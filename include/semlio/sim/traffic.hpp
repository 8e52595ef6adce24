#pragma once
/// \file
/// Traffic: moving cars and trucks (alongside the ego at a similar speed and
/// oncoming), cyclists and pedestrians, each with its own smooth path
/// (sim::Trajectory). Actors on one lane share that lane's trajectory, shifted
/// in time by at least 3 s, so they never overlap one another; the ego's lane
/// carries no actors. Moving actors carry the SemanticKITTI "moving-*" raw
/// ids (252 car, 258 truck, 253 bicyclist, 254 person) and instance ids from
/// 60000 upwards.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/sim/geometry.hpp>
#include <semlio/sim/random.hpp>
#include <semlio/sim/trajectory.hpp>
#include <semlio/sim/world_builder.hpp>
#include <semlio/sim/world_config.hpp>

namespace semlio::sim {

/// How much traffic a world carries.
enum class TrafficLevel : std::uint8_t { kNone, kLight, kHeavy };

/// Name used on the command line and in sim.json.
constexpr std::string_view traffic_name(TrafficLevel t) noexcept {
  switch (t) {
    case TrafficLevel::kNone: return "none";
    case TrafficLevel::kLight: return "light";
    case TrafficLevel::kHeavy: return "heavy";
  }
  return "none";
}

/// Parses none|light|heavy; throws ConfigError naming the bad value.
inline TrafficLevel parse_traffic(std::string_view name) {
  for (const TrafficLevel t : {TrafficLevel::kNone, TrafficLevel::kLight, TrafficLevel::kHeavy}) {
    if (name == traffic_name(t)) return t;
  }
  throw ConfigError("traffic must be none|light|heavy, got '" + std::string(name) + "'");
}

/// Kind of a traffic participant.
enum class ActorKind : std::uint8_t { kCar, kTruck, kCyclist, kPedestrian };

/// One traffic participant: which lane trajectory it follows and how far
/// ahead in that lane's schedule it is.
struct Actor {
  ActorKind kind = ActorKind::kCar;
  std::uint16_t instance = 0;   ///< instance id (>= 60000)
  std::size_t lane = 0;         ///< index into Traffic::lanes()
  double time_offset_s = 0.0;   ///< actor pose at time t = lane.pose(t + offset)
  float refl_scale = 1.0F;      ///< paint brightness
};

/// Appends the primitives of an actor of `kind` at pose T_world_body (body
/// origin on the ground, x forward). Cylinders and ellipsoids keep their
/// world-vertical axes (actors barely tilt).
inline void append_actor(ActorKind kind, const SE3d& T_world_body, std::uint16_t instance, float refl_scale,
                         std::vector<Primitive>& out) {
  const Eigen::Matrix3d R = T_world_body.rotation();
  const auto at = [&](double x, double y, double z) { return T_world_body * Eigen::Vector3d(x, y, z); };
  const auto box = [&](const Eigen::Vector3d& c, const Eigen::Vector3d& half, std::uint16_t raw_id) {
    out.push_back(make_box(c, half, R, WorldBuilder::surface(raw_id, instance, static_cast<double>(refl_scale))));
  };
  switch (kind) {
    case ActorKind::kCar:
      box(at(0.0, 0.0, 0.72), {2.2, 0.9, 0.45}, raw::kMovingCar);
      box(at(-0.25, 0.0, 1.43), {1.2, 0.78, 0.27}, raw::kMovingCar);
      break;
    case ActorKind::kTruck:
      box(at(3.3, 0.0, 1.55), {1.1, 1.2, 1.15}, raw::kMovingTruck);
      box(at(-1.3, 0.0, 2.0), {3.3, 1.25, 1.5}, raw::kMovingTruck);
      break;
    case ActorKind::kCyclist: {
      box(at(0.0, 0.0, 0.62), {0.85, 0.06, 0.32}, raw::kMovingBicyclist);
      box(at(-0.1, 0.0, 1.3), {0.2, 0.2, 0.35}, raw::kMovingBicyclist);
      out.push_back(make_ellipsoid(at(-0.05, 0.0, 1.78), {0.11, 0.11, 0.13},
                                   WorldBuilder::surface(raw::kMovingBicyclist, instance, static_cast<double>(refl_scale))));
      break;
    }
    case ActorKind::kPedestrian: {
      out.push_back(make_cylinder(at(0.0, 0.0, 0.0), 0.2, 1.5,
                                  WorldBuilder::surface(raw::kMovingPerson, instance, static_cast<double>(refl_scale))));
      out.push_back(make_ellipsoid(at(0.0, 0.0, 1.62), {0.1, 0.1, 0.12},
                                   WorldBuilder::surface(raw::kMovingPerson, instance, static_cast<double>(refl_scale))));
      break;
    }
  }
}

/// Every actor of a world and the lane trajectories they follow. Immutable
/// after construction; const methods are thread-safe.
class Traffic {
 public:
  Traffic() = default;

  /// Populates the lanes of `world` for `level`; `horizon_s` is the drive
  /// duration actors should cover. Deterministic in `seed`.
  Traffic(const World& world, TrafficLevel level, std::uint64_t seed, double horizon_s) {
    if (level == TrafficLevel::kNone) return;
    const bool heavy = level == TrafficLevel::kHeavy;
    Rng rng(seed, 7);
    std::uint16_t next_id = WorldBuilder::kFirstActorInstance;
    const auto add_lane = [&](const Lane& lane, double lateral_accel) -> long {
      if (lane.points.size() < 2) return -1;
      TrajectoryConfig tc;
      tc.cruise_speed_mps = lane.cruise_speed_mps;
      tc.turn_radius_m = lane.turn_radius_m;
      tc.max_lateral_accel_mps2 = lateral_accel;
      tc.max_accel_mps2 = std::min(1.5, 0.5 * lane.cruise_speed_mps);
      tc.max_decel_mps2 = std::min(2.0, 0.6 * lane.cruise_speed_mps);
      tc.min_blend_length_m = std::min(10.0, 2.0 * lane.turn_radius_m);
      tc.start_at_rest = false;
      tc.end_at_rest = true;
      lanes_.push_back(Trajectory::through(lane.points, tc));
      return static_cast<long>(lanes_.size() - 1);
    };
    // Time offsets spread over the part of the lane's schedule that is still
    // driving during [0, horizon] (so no actor sits parked at a lane's end),
    // at least 3 s apart.
    const auto spread = [&](std::size_t lane, int count, double first_s, ActorKind kind, double truck_share,
                            double period_s = 0.0) {
      const double last_s = lanes_[lane].duration_s() - horizon_s;
      const double span = std::max(last_s - first_s, 1.0);
      const double slot = std::max(span / std::max(count, 1), 3.5);
      for (int k = 0; k < count; ++k) {
        const double base = first_s + slot * k;
        if (k > 0 && base > last_s) break;
        const ActorKind drawn = (kind == ActorKind::kCar && rng.chance(truck_share)) ? ActorKind::kTruck : kind;
        double offset = base + (k == 0 ? 0.0 : rng.uniform(0.0, slot - 3.0));
        if (period_s > 0.0) {
          // The lane is the ego's own loop: stay >= 2.5 s away from it.
          if (period_s < 5.0) break;
          const double m = std::fmod(offset, period_s);
          if (m < 2.5) offset += 2.5 - m;
          if (m > period_s - 2.5) offset += period_s - m + 2.5;
        }
        Actor a;
        a.kind = drawn;
        a.lane = lane;
        a.time_offset_s = offset;
        a.refl_scale = static_cast<float>(rng.uniform(0.6, 1.5));
        a.instance = next_id++;
        actors_.push_back(a);
      }
    };
    const double truck_share = world.lanes.trucks ? 0.25 : 0.0;
    if (const long l = add_lane(world.lanes.alongside, 2.5); l >= 0) {
      // The first one starts beside the ego (heavy) or a little ahead (light),
      // at a similar speed in the adjacent lane.
      spread(static_cast<std::size_t>(l), heavy ? 8 : 3, world.lanes.alongside_first_offset_s * (heavy ? 1.0 : 3.0),
             ActorKind::kCar, truck_share, world.lanes.alongside_period_s);
    }
    if (const long l = add_lane(world.lanes.oncoming, 2.5); l >= 0) {
      spread(static_cast<std::size_t>(l), heavy ? 30 : 10, rng.uniform(0.0, 5.0), ActorKind::kCar, truck_share);
    }
    if (const long l = add_lane(world.lanes.bikes, 1.5); l >= 0) {
      spread(static_cast<std::size_t>(l), heavy ? 8 : 3, rng.uniform(0.0, 10.0), ActorKind::kCyclist, 0.0);
    }
    const int pedestrians = heavy ? 40 : 12;
    std::vector<long> walk_lanes;
    for (const Lane& w : world.lanes.walkways) walk_lanes.push_back(add_lane(w, 0.6));
    if (!walk_lanes.empty()) {
      for (int k = 0; k < pedestrians; ++k) {
        const long l = walk_lanes[static_cast<std::size_t>(rng.integer(0, static_cast<int>(walk_lanes.size()) - 1))];
        if (l < 0) continue;
        Actor a;
        a.kind = ActorKind::kPedestrian;
        a.lane = static_cast<std::size_t>(l);
        a.time_offset_s = rng.uniform(0.0, std::max(0.0, lanes_[a.lane].duration_s() - horizon_s));
        a.refl_scale = static_cast<float>(rng.uniform(0.7, 1.3));
        a.instance = next_id++;
        actors_.push_back(a);
      }
    }
  }

  /// The actors.
  [[nodiscard]] const std::vector<Actor>& actors() const noexcept { return actors_; }
  /// The lane trajectories actors follow.
  [[nodiscard]] const std::vector<Trajectory>& lanes() const noexcept { return lanes_; }
  /// T_world_body of actor k at time t [s].
  [[nodiscard]] SE3d actor_pose(std::size_t k, double t_s) const {
    const Actor& a = actors_[k];
    return lanes_[a.lane].pose(t_s + a.time_offset_s);
  }
  /// Appends the primitives of actor k at time t.
  void append_primitives(std::size_t k, double t_s, std::vector<Primitive>& out) const {
    const Actor& a = actors_[k];
    append_actor(a.kind, actor_pose(k, t_s), a.instance, a.refl_scale, out);
  }

 private:
  std::vector<Trajectory> lanes_;
  std::vector<Actor> actors_;
};

}  // namespace semlio::sim
