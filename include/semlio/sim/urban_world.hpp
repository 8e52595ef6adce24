#pragma once
/// \file
/// The urban (and aliased) world: a street grid of 8 x 8 blocks. Streets have
/// four 3.5 m lanes (road), 2.5 m parking strips, 3.5 m sidewalks with a
/// 0.15 m curb; blocks hold buildings of varied footprint and height, hedges,
/// fences, parks with trees and bushes; sidewalks carry street lights, trees
/// and traffic signs; parking strips carry parked cars. `aliased` uses equal
/// block spacing and the same content in every block.
///
/// Route: the ego drives in the inner lane of its direction (1.75 m right of
/// the street centreline); cars alongside use the outer lane, oncoming cars
/// the inner and cyclists the outer lane of the other direction. Open route:
/// first a rectangle loop of about 1.3 km (so a drive longer than ~1500
/// frames comes back to its start and revisits streets), then a random walk
/// without U-turns. Revisit (see revisit.hpp): a block loop (a rectangle of
/// streets, driven once or more, stopping at every other turn for a fitted
/// 0.5-20 s) when one fits the drive, else an out-and-back drive along the
/// middle street with U-turns (drives of ~10 s to ~70 s); either way the ego
/// is back at its start pose at the return time.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include <semlio/sim/path.hpp>
#include <semlio/sim/random.hpp>
#include <semlio/sim/revisit.hpp>
#include <semlio/sim/world_builder.hpp>
#include <semlio/sim/world_config.hpp>

namespace semlio::sim::detail {

/// Street cross-section (distances from the street centreline) [m].
inline constexpr double kRoadHalf = 7.0;
inline constexpr double kParkingOuter = 9.5;
inline constexpr double kSidewalkOuter = 13.0;
inline constexpr double kCurb = 0.15;
inline constexpr double kEgoLane = -1.75;    // inner lane of the ego's direction
inline constexpr double kOuterLane = -5.25;  // outer lane (next to parking)

/// Content of one block interior [x0, x1] x [y0, y1] plus its sidewalks and
/// parking strips, drawn from `rng`.
inline void urban_block(WorldBuilder& wb, Rng& rng, double x0, double y0, double x1, double y1) {
  const double w = x1 - x0;
  const double h = y1 - y0;
  // Interior ground.
  const bool paved = rng.chance(0.3);
  wb.box({0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * kCurb}, {0.5 * w, 0.5 * h, 0.5 * kCurb}, 0.0,
         paved ? raw::kOtherGround : raw::kTerrain, 0);
  // Sidewalk ring (3.5 m wide boxes).
  const double sw = kSidewalkOuter - kParkingOuter;
  wb.box({0.5 * (x0 + x1), y0 - 0.5 * sw, 0.5 * kCurb}, {0.5 * w + sw, 0.5 * sw, 0.5 * kCurb}, 0.0, raw::kSidewalk, 0);
  wb.box({0.5 * (x0 + x1), y1 + 0.5 * sw, 0.5 * kCurb}, {0.5 * w + sw, 0.5 * sw, 0.5 * kCurb}, 0.0, raw::kSidewalk, 0);
  wb.box({x0 - 0.5 * sw, 0.5 * (y0 + y1), 0.5 * kCurb}, {0.5 * sw, 0.5 * h, 0.5 * kCurb}, 0.0, raw::kSidewalk, 0);
  wb.box({x1 + 0.5 * sw, 0.5 * (y0 + y1), 0.5 * kCurb}, {0.5 * sw, 0.5 * h, 0.5 * kCurb}, 0.0, raw::kSidewalk, 0);

  const bool park = rng.chance(0.18);
  // Sides: start corner, along u, outward o, length.
  struct Side {
    Eigen::Vector3d start, u, o;
    double length;
  };
  const std::array<Side, 4> sides{{
      {{x0, y0, 0.0}, {1.0, 0.0, 0.0}, {0.0, -1.0, 0.0}, w},
      {{x1, y0, 0.0}, {0.0, 1.0, 0.0}, {1.0, 0.0, 0.0}, h},
      {{x1, y1, 0.0}, {-1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, w},
      {{x0, y1, 0.0}, {0.0, -1.0, 0.0}, {-1.0, 0.0, 0.0}, h},
  }};
  const double max_depth = 0.5 * std::min(w, h) - 1.0;
  for (const Side& s : sides) {
    const double yaw = std::atan2(s.u.y(), s.u.x());
    const auto at = [&](double along, double out, double z) {
      Eigen::Vector3d p = s.start + along * s.u + out * s.o;
      p.z() = z;
      return p;
    };
    // Buildings or park edge.
    if (!park) {
      double a = rng.uniform(0.0, 4.0);
      while (a < s.length - 6.0) {
        if (rng.chance(0.15)) {  // gap with a hedge or nothing
          const double gap = rng.uniform(3.0, 10.0);
          if (rng.chance(0.6)) {
            wb.box(at(a + 0.5 * gap, -1.0, kCurb + 0.6), {0.5 * gap, 0.45, 0.6}, yaw, raw::kVegetation,
                   wb.new_instance());
          }
          a += gap;
          continue;
        }
        const double fw = std::min(rng.uniform(9.0, 30.0), s.length - a);
        const double depth = std::clamp(rng.uniform(10.0, 22.0), 4.0, std::max(4.0, max_depth));
        const double setback = rng.chance(0.4) ? 0.0 : rng.uniform(1.0, 5.0);
        const double bh = rng.chance(0.12) ? rng.uniform(22.0, 40.0) : rng.uniform(6.0, 20.0);
        wb.box(at(a + 0.5 * fw, -(setback + 0.5 * depth), 0.5 * bh), {0.5 * fw, 0.5 * depth, 0.5 * bh}, yaw,
               raw::kBuilding, wb.new_instance(), rng.uniform(0.6, 1.5));
        if (setback > 1.8) {
          if (rng.chance(0.5)) {
            wb.box(at(a + 0.5 * fw, -0.6, kCurb + 0.55), {0.5 * fw - 0.5, 0.4, 0.55}, yaw, raw::kVegetation,
                   wb.new_instance());
          } else if (rng.chance(0.6)) {
            const double fh = rng.uniform(0.9, 1.8);
            wb.box(at(a + 0.5 * fw, -0.3, kCurb + 0.5 * fh), {0.5 * fw, 0.04, 0.5 * fh}, yaw, raw::kFence,
                   wb.new_instance());
          }
        }
        a += fw + (rng.chance(0.5) ? 0.0 : rng.uniform(0.5, 3.0));
      }
    } else if (rng.chance(0.6)) {
      const double fh = rng.uniform(1.0, 2.0);
      wb.box(at(0.5 * s.length, -0.4, kCurb + 0.5 * fh), {0.5 * s.length - 1.0, 0.04, 0.5 * fh}, yaw, raw::kFence,
             wb.new_instance());
    }
    // Sidewalk furniture: street lights, trees, a sign near the corner.
    const double curb_out = sw;  // curb line, measured outward from the interior edge
    for (double a = rng.uniform(5.0, 15.0); a < s.length - 3.0; a += rng.uniform(25.0, 35.0)) {
      // Named draws, in GCC's former argument order (sim/random.hpp).
      const double radius_m = rng.uniform(0.08, 0.14);
      const double height_m = rng.uniform(6.5, 8.5);
      wb.pole(at(a, curb_out - 0.5, kCurb), height_m, radius_m);
    }
    if (rng.chance(0.6)) {
      for (double a = rng.uniform(4.0, 10.0); a < s.length - 3.0; a += rng.uniform(8.0, 15.0)) {
        wb.tree(at(a, curb_out - 1.3, kCurb), rng);
      }
    }
    if (rng.chance(0.7)) wb.sign(at(2.0, curb_out - 0.4, kCurb), yaw + 0.5 * std::numbers::pi, rng);
    // Parking strip with parked cars (~40% of sides, ~45% of slots taken).
    if (rng.chance(0.4)) {
      const Eigen::Vector3d p0 = at(0.0, curb_out, 0.003);
      const Eigen::Vector3d p1 = at(s.length, curb_out, 0.003);
      const Eigen::Vector3d q0 = at(0.0, curb_out + 2.5, 0.003);
      const Eigen::Vector3d q1 = at(s.length, curb_out + 2.5, 0.003);
      wb.quad(p0, p1, q1, q0, raw::kParking);
      for (double a = 4.0; a < s.length - 4.0; a += 6.0) {
        if (!rng.chance(0.45)) continue;
        const double flip = rng.chance(0.5) ? 0.0 : std::numbers::pi;
        const double yaw_jitter = rng.uniform(-0.04, 0.04);  // named draws (sim/random.hpp)
        const double out_jitter = rng.uniform(-0.15, 0.15);
        const double along_jitter = rng.uniform(-0.4, 0.4);
        wb.parked_car(at(a + along_jitter, curb_out + 1.25 + out_jitter, 0.003), yaw + flip + yaw_jitter, rng);
      }
    }
  }
  // Park interior: trees and bushes.
  if (park) {
    const int trees = static_cast<int>(w * h / 160.0);
    for (int k = 0; k < trees; ++k) {
      const double scale = rng.uniform(0.9, 1.5);  // named draws (sim/random.hpp)
      const double x = rng.uniform(x0 + 2.0, x1 - 2.0);
      const double y = rng.uniform(y0 + 2.0, y1 - 2.0);
      wb.tree({x, y, kCurb}, rng, scale);
    }
    const int bushes = static_cast<int>(w * h / 220.0);
    for (int k = 0; k < bushes; ++k) {
      wb.bush({rng.uniform(x0 + 1.0, x1 - 1.0), rng.uniform(y0 + 1.0, y1 - 1.0), kCurb}, rng);
    }
  }
}

/// Corner list of a counter-clockwise rectangle loop over streets
/// [i0, i1] x [j0, j1], starting and ending in the middle of its first edge.
inline std::vector<Eigen::Vector3d> rectangle_loop(const std::vector<double>& X, const std::vector<double>& Y,
                                                   int i0, int j0, int i1, int j1) {
  const auto xi = [&](int i) { return X[static_cast<std::size_t>(i)]; };
  const auto yj = [&](int j) { return Y[static_cast<std::size_t>(j)]; };
  const Eigen::Vector3d mid(0.5 * (xi(i0) + xi(i1)), yj(j0), 0.0);
  return {mid, {xi(i1), yj(j0), 0.0}, {xi(i1), yj(j1), 0.0}, {xi(i0), yj(j1), 0.0}, {xi(i0), yj(j0), 0.0}, mid};
}

/// Length of a polyline [m].
inline double polyline_length(const std::vector<Eigen::Vector3d>& p) {
  double len = 0.0;
  for (std::size_t i = 1; i < p.size(); ++i) len += (p[i] - p[i - 1]).norm();
  return len;
}

/// Stops 12 m before about a quarter of the intersections on the corner
/// route (edges of at least 40 m); `route` is the ego lane of `corners`.
inline std::vector<Eigen::Vector3d> urban_stops(const std::vector<Eigen::Vector3d>& corners,
                                                const std::vector<Eigen::Vector3d>& route, Rng& rng) {
  std::vector<Eigen::Vector3d> stops;
  for (std::size_t k = 1; k + 1 < corners.size(); ++k) {
    if (!rng.chance(0.25)) continue;
    const Eigen::Vector3d dir = (corners[k] - corners[k - 1]).normalized();
    if ((corners[k] - corners[k - 1]).norm() < 40.0) continue;
    stops.push_back(route[k] - 12.0 * dir);
  }
  return stops;
}

/// Revisit by a block loop: a counter-clockwise rectangle of streets driven
/// `laps` times (plus a tail lap) at the urban cruise speed, stopping before
/// every other turn (a left turn at a traffic light); the common stop duration
/// (0.5-20 s) is fitted so the ego is back at its start at `t_return`.
/// Candidates are tried in order of their estimated lap time; returns false
/// when none closes (drives shorter than about one block loop, ~45 s). On
/// success sets the ego route, stops and loop fields of `world`, and
/// `lane_corners` to the centreline corners (two extra laps) traffic follows.
inline bool plan_block_loop(World& world, const std::vector<double>& X, const std::vector<double>& Y, int lo, int hi,
                            double t_return, std::vector<Eigen::Vector3d>& lane_corners) {
  struct Candidate {
    int i0, j0, i1, j1, laps;
    double score;
  };
  std::vector<Candidate> cands;
  double shortest = 1e18;
  for (int i0 = lo; i0 < hi; ++i0) {
    for (int i1 = i0 + 1; i1 <= hi; ++i1) {
      for (int j0 = lo; j0 < hi; ++j0) {
        for (int j1 = j0 + 1; j1 <= hi; ++j1) {
          const double p = 2.0 * (X[static_cast<std::size_t>(i1)] - X[static_cast<std::size_t>(i0)] +
                                  Y[static_cast<std::size_t>(j1)] - Y[static_cast<std::size_t>(j0)]);
          shortest = std::min(shortest, p);
          // Lap time estimate (measured): 11 m/s, plus ~40 s for 4 turns
          // and 2 stops, plus the stops' duration (5 s nominal).
          const double lap_s = p / 11.0 + 40.0 + 2.0 * 5.0;
          for (int laps = 1; laps <= 12; ++laps) {
            cands.push_back({i0, j0, i1, j1, laps, std::abs(laps * lap_s - t_return) / t_return + 0.01 * laps});
          }
        }
      }
    }
  }
  // Even the smallest block at cruise speed without stops takes longer.
  if (shortest / 11.0 > t_return) return false;
  std::stable_sort(cands.begin(), cands.end(), [](const Candidate& a, const Candidate& b) { return a.score < b.score; });
  // Try up to 16 candidates of distinct lap count and perimeter (the aliased
  // grid has many equal rectangles).
  std::vector<std::array<double, 2>> tried;
  for (const Candidate& k : cands) {
    if (tried.size() >= 16) break;
    const double p = 2.0 * (X[static_cast<std::size_t>(k.i1)] - X[static_cast<std::size_t>(k.i0)] +
                            Y[static_cast<std::size_t>(k.j1)] - Y[static_cast<std::size_t>(k.j0)]);
    bool seen = false;
    for (const auto& t : tried) seen = seen || (t[0] == k.laps && std::abs(t[1] - p) < 1.0);
    if (seen) continue;
    tried.push_back({static_cast<double>(k.laps), p});
    const auto lap = rectangle_loop(X, Y, k.i0, k.j0, k.i1, k.j1);
    const auto corners = repeat_lap(lap, k.laps + 1);
    const auto route = offset_corners(corners, kEgoLane);
    // Stop 12 m before every other turn (corners 1 and 3 of each lap; the
    // lap's corner list is mid-edge, 4 corners, mid-edge).
    std::vector<Eigen::Vector3d> stops;
    for (std::size_t q = 1; q + 1 < corners.size(); ++q) {
      if (q % 5 != 1 && q % 5 != 3) continue;
      const Eigen::Vector3d dir = (corners[q] - corners[q - 1]).normalized();
      stops.push_back(route[q] - 12.0 * dir);
    }
    TrajectoryConfig motion = world.ego_motion;
    // Longer stops, less distance driven: fit the negated closure.
    const auto closure = [&](double stop_s) {
      motion.stop_duration_s = stop_s;
      return -lap_closure_m(ego_trajectory(route, motion, stops), t_return, k.laps, k.laps + 1);
    };
    const RevisitFit fit = fit_revisit(closure, 0.5, 20.0, 0.5);
    if (!fit.ok) continue;
    world.ego_motion.stop_duration_s = fit.param;
    world.ego_route = route;
    world.ego_stop_points = stops;
    const Trajectory drive = ego_trajectory(route, world.ego_motion, stops);
    world.loop_length_m = drive.length_m() / (k.laps + 1);
    world.return_error_m = lap_closure_m(drive, t_return, k.laps, k.laps + 1);
    world.revisit_route = "block_loop";
    lane_corners = repeat_lap(lap, k.laps + 3);
    return true;
  }
  return false;
}

/// Revisit by an out-and-back drive along the middle east-west street: out
/// in the outer eastbound lane, a U-turn across the street (radius 5.25 m,
/// outer lane to outer lane, ~13 km/h), back past the start in the outer
/// westbound lane, a second U-turn and back to the start; the straight's
/// length is fitted so the ego is back at `t_return` (from ~9 s up). Cars
/// (no trucks) drive the same kind of loop in the inner lanes when the
/// straight is at least 40 m (inside the ego's loop, so the paths never
/// cross): alongside on the way out, oncoming on the way back.
inline void plan_street_out_and_back(World& world, const std::vector<double>& X, const std::vector<double>& Y,
                                     double t_return) {
  // The loop starts at the intersection of the middle street with street 2
  // and may stretch east up to street 7.
  const double ys = Y[Y.size() / 2];
  const double x0 = X[2];
  const StadiumShape shape{.lane_m = -kOuterLane, .turn_radius_m = -kOuterLane, .swing_m = 0.0, .step_m = 1.0};
  const double max_straight = X[X.size() - 2] - x0;
  const auto to_world = [&](double u, double l) { return Eigen::Vector3d(x0 + u, ys + l, 0.0); };
  const RevisitPlan plan = plan_out_and_back(shape, max_straight, to_world, world.ego_motion, t_return);
  world.ego_route = plan.route;
  world.ego_stop_points.clear();
  world.loop_length_m = plan.lap_length_m;
  world.return_error_m = plan.fit.error_m;
  world.revisit_route = "out_and_back";
  // Traffic: the inner-lane loop of the same straight, repeated to outlast the drive.
  const StadiumShape inner{.lane_m = -kEgoLane, .turn_radius_m = -kEgoLane, .swing_m = 0.0, .step_m = 1.0};
  std::vector<Eigen::Vector3d> lap;
  for (const Eigen::Vector2d& q : stadium_lap(plan.fit.param, inner)) lap.push_back(to_world(q.x(), q.y()));
  const double lap_len = std::max(polyline_length(lap), 1.0);
  const int laps = 2 + static_cast<int>(std::ceil(1.5 * (t_return + 30.0) * 11.0 / lap_len));
  // Tight loops (straights < 40 m, drives under ~25 s) carry no cars: they
  // would spin in the middle of the street. No trucks: their length would
  // sweep into the ego's U-turn.
  world.lanes.alongside = {};
  if (plan.fit.param >= 40.0) world.lanes.alongside = {repeat_lap(lap, laps), 11.0, 1.5};
  world.lanes.oncoming = {};
  world.lanes.bikes = {};
  world.lanes.trucks = false;
}

/// Builds the urban or aliased world.
inline World make_urban_world(const WorldConfig& config) {
  const bool aliased = config.kind == WorldKind::kAliased;
  constexpr int kBlocks = 8;
  Rng rng(config.seed, 1);
  std::vector<double> X(kBlocks + 1, 0.0);
  std::vector<double> Y(kBlocks + 1, 0.0);
  for (int k = 1; k <= kBlocks; ++k) {
    X[static_cast<std::size_t>(k)] = X[static_cast<std::size_t>(k - 1)] + (aliased ? 95.0 : rng.uniform(75.0, 120.0));
    Y[static_cast<std::size_t>(k)] = Y[static_cast<std::size_t>(k - 1)] + (aliased ? 95.0 : rng.uniform(75.0, 120.0));
  }
  WorldBuilder wb;
  const double margin = 300.0;
  // Base terrain under everything, then the road surfaces of every street.
  wb.tiled_rect(X.front() - margin, Y.front() - margin, X.back() + margin, Y.back() + margin, -0.02, raw::kTerrain,
                60.0);
  for (int k = 0; k <= kBlocks; ++k) {
    const double x = X[static_cast<std::size_t>(k)];
    const double y = Y[static_cast<std::size_t>(k)];
    wb.tiled_rect(x - kParkingOuter, Y.front() - 40.0, x + kParkingOuter, Y.back() + 40.0, 0.0, raw::kRoad, 20.0);
    wb.tiled_rect(X.front() - 40.0, y - kParkingOuter, X.back() + 40.0, y + kParkingOuter, 0.0, raw::kRoad, 20.0);
  }
  // Dashed lane markings along every street (bright paint, raw lane-marking).
  for (int k = 0; k <= kBlocks; ++k) {
    for (int b = 0; b < kBlocks; ++b) {
      const double x = X[static_cast<std::size_t>(k)];
      const double y = Y[static_cast<std::size_t>(k)];
      const double a0 = X[static_cast<std::size_t>(b)] + kSidewalkOuter;
      const double a1 = X[static_cast<std::size_t>(b + 1)] - kSidewalkOuter;
      const double c0 = Y[static_cast<std::size_t>(b)] + kSidewalkOuter;
      const double c1 = Y[static_cast<std::size_t>(b + 1)] - kSidewalkOuter;
      for (const double off : {-3.5, 0.0, 3.5}) {
        const double hw = off == 0.0 ? 0.12 : 0.07;
        const double dash = off == 0.0 ? 1e9 : 3.0;
        for (double a = a0; a < a1; a += (off == 0.0 ? (a1 - a0) : 9.0)) {
          const double e = std::min(a + dash, a1);
          wb.flat_rect(a, y + off - hw, e, y + off + hw, 0.002, raw::kLaneMarking);
        }
        for (double c = c0; c < c1; c += (off == 0.0 ? (c1 - c0) : 9.0)) {
          const double e = std::min(c + dash, c1);
          wb.flat_rect(x + off - hw, c, x + off + hw, e, 0.002, raw::kLaneMarking);
        }
      }
    }
  }
  for (int i = 0; i < kBlocks; ++i) {
    for (int j = 0; j < kBlocks; ++j) {
      Rng block_rng(config.seed, aliased ? 1000 : static_cast<std::uint64_t>(1000 + i * kBlocks + j));
      const double bx0 = X[static_cast<std::size_t>(i)] + kSidewalkOuter;
      const double bx1 = X[static_cast<std::size_t>(i + 1)] - kSidewalkOuter;
      const double by0 = Y[static_cast<std::size_t>(j)] + kSidewalkOuter;
      const double by1 = Y[static_cast<std::size_t>(j + 1)] - kSidewalkOuter;
      urban_block(wb, block_rng, bx0, by0, bx1, by1);
    }
  }

  World world;
  world.config = config;
  world.ego_motion.cruise_speed_mps = 11.0;
  world.ego_motion.turn_radius_m = 8.0;
  world.ego_motion.stop_duration_s = 3.0;
  world.ego_motion.start_at_rest = false;

  // Route over street nodes 1..kBlocks-1 (the outer streets border nothing).
  Rng route_rng(config.seed, 2);
  std::vector<Eigen::Vector3d> corners;
  const int lo = 1;
  const int hi = kBlocks - 1;
  // Centreline corners the traffic lanes and walkways follow (the ego's
  // route unless revisit picks an out-and-back drive).
  std::vector<Eigen::Vector3d> lane_corners;
  bool out_and_back = false;
  if (config.revisit) {
    const double t_return = config.return_time_s > 0.0 ? config.return_time_s : config.drive_length_m / 9.0;
    world.return_time_s = t_return;
    world.ego_motion.end_at_rest = false;  // the tail lap is never reached
    if (!plan_block_loop(world, X, Y, lo, hi, t_return, lane_corners)) {
      out_and_back = true;
      plan_street_out_and_back(world, X, Y, t_return);
      const double ys = Y[static_cast<std::size_t>(kBlocks / 2)];
      for (int i = lo; i <= hi; ++i) lane_corners.emplace_back(X[static_cast<std::size_t>(i)], ys, 0.0);
    }
  } else {
    // A first loop of about 950 m, then a random walk.
    int best_a = 1;
    int best_b = 1;
    double best_err = 1e18;
    for (int a = 1; lo + a <= hi; ++a) {
      for (int b = 1; lo + b <= hi; ++b) {
        const double p = 2.0 * (X[static_cast<std::size_t>(lo + a)] - X[static_cast<std::size_t>(lo)] +
                                Y[static_cast<std::size_t>(lo + b)] - Y[static_cast<std::size_t>(lo)]);
        if (std::abs(p - 950.0) < best_err) {
          best_err = std::abs(p - 950.0);
          best_a = a;
          best_b = b;
        }
      }
    }
    const auto loop = rectangle_loop(X, Y, lo, lo, lo + best_a, lo + best_b);
    corners = loop;
    corners.pop_back();  // end at the start node (lo, lo), then walk on
    int ci = lo;
    int cj = lo;
    int di = 1;  // arriving at (lo, lo) heading... the loop's last edge goes -y: continue with a turn
    int dj = 0;
    double len = polyline_length(corners);
    const std::array<std::array<int, 2>, 4> dirs{{{1, 0}, {0, 1}, {-1, 0}, {0, -1}}};
    di = 0;
    dj = -1;
    while (len < 1.3 * config.drive_length_m + 200.0) {
      // Candidate moves: straight, left, right (no U-turn), inside the grid.
      std::array<int, 3> options{};
      int n = 0;
      for (int d = 0; d < 4; ++d) {
        const int ni = ci + dirs[static_cast<std::size_t>(d)][0];
        const int nj = cj + dirs[static_cast<std::size_t>(d)][1];
        const bool uturn = dirs[static_cast<std::size_t>(d)][0] == -di && dirs[static_cast<std::size_t>(d)][1] == -dj;
        if (uturn || ni < lo || ni > hi || nj < lo || nj > hi) continue;
        options[static_cast<std::size_t>(n++)] = d;
      }
      int d = options[static_cast<std::size_t>(route_rng.integer(0, n - 1))];
      // Prefer going straight half of the time.
      for (int k = 0; k < n; ++k) {
        const int dd = options[static_cast<std::size_t>(k)];
        if (dirs[static_cast<std::size_t>(dd)][0] == di && dirs[static_cast<std::size_t>(dd)][1] == dj &&
            route_rng.chance(0.5)) {
          d = dd;
        }
      }
      di = dirs[static_cast<std::size_t>(d)][0];
      dj = dirs[static_cast<std::size_t>(d)][1];
      ci += di;
      cj += dj;
      const Eigen::Vector3d p(X[static_cast<std::size_t>(ci)], Y[static_cast<std::size_t>(cj)], 0.0);
      len += (p - corners.back()).norm();
      corners.push_back(p);
    }
  }
  if (!config.revisit) {
    world.ego_route = offset_corners(corners, kEgoLane);
    world.ego_stop_points = urban_stops(corners, world.ego_route, route_rng);
    lane_corners = corners;
  }
  if (!out_and_back) {
    world.lanes.alongside = {offset_corners(lane_corners, kOuterLane), 11.0, 8.0};
    const auto back = reversed(lane_corners);
    world.lanes.oncoming = {offset_corners(back, kEgoLane), 11.0, 8.0};
    world.lanes.bikes = {offset_corners(back, kOuterLane), 5.0, 6.0};
  }
  // Pedestrian loops on the sidewalks of the blocks beside the route.
  const double walk = kParkingOuter + 1.75;
  const auto block_of = [&](const std::vector<double>& V, double v) {
    const auto b = static_cast<int>(std::upper_bound(V.begin(), V.end(), v) - V.begin()) - 1;
    return std::clamp(b, 0, kBlocks - 1);
  };
  const auto street_of = [&](const std::vector<double>& V, double v) {
    for (std::size_t k = 0; k < V.size(); ++k) {
      if (std::abs(V[k] - v) < 1.0) return static_cast<int>(k);
    }
    return -1;
  };
  for (std::size_t k = 0; k + 1 < lane_corners.size() && world.lanes.walkways.size() < 8; ++k) {
    const Eigen::Vector3d m = 0.5 * (lane_corners[k] + lane_corners[k + 1]);
    const bool along_x = std::abs(lane_corners[k + 1].y() - lane_corners[k].y()) < 1.0;
    std::array<std::array<int, 2>, 2> blocks{};
    if (along_x) {
      const int js = street_of(Y, m.y());
      blocks = {{{block_of(X, m.x()), js - 1}, {block_of(X, m.x()), js}}};
    } else {
      const int is = street_of(X, m.x());
      blocks = {{{is - 1, block_of(Y, m.y())}, {is, block_of(Y, m.y())}}};
    }
    for (const auto& ij : blocks) {
      const int ii = ij[0];
      const int jj = ij[1];
      if (ii < 0 || jj < 0 || ii >= kBlocks || jj >= kBlocks) continue;
      const double x0 = X[static_cast<std::size_t>(ii)] + walk;
      const double x1 = X[static_cast<std::size_t>(ii + 1)] - walk;
      const double y0 = Y[static_cast<std::size_t>(jj)] + walk;
      const double y1 = Y[static_cast<std::size_t>(jj + 1)] - walk;
      Lane lane;
      lane.cruise_speed_mps = 1.3;
      lane.turn_radius_m = 1.0;
      std::vector<Eigen::Vector3d> ring{{x0, y0, kCurb}, {x1, y0, kCurb}, {x1, y1, kCurb}, {x0, y1, kCurb}};
      if (route_rng.chance(0.5)) std::reverse(ring.begin() + 1, ring.end());
      for (int rep = 0; rep < 2; ++rep) lane.points.insert(lane.points.end(), ring.begin(), ring.end());
      lane.points.push_back(ring.front());
      bool dup = false;
      for (const auto& l : world.lanes.walkways) dup = dup || (l.points.front() - lane.points.front()).norm() < 1.0;
      if (!dup && world.lanes.walkways.size() < 8) world.lanes.walkways.push_back(std::move(lane));
    }
  }
  world.bvh.build(std::move(wb.prims));
  return world;
}

}  // namespace semlio::sim::detail
