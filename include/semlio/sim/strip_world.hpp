#pragma once
/// \file
/// Road-following worlds: `rural` (a winding two-lane road over hills with
/// tens of metres of elevation change, terrain, forest patches, bushes,
/// utility poles, fences, a few houses) and `highway` (a long straight
/// dual carriageway, 3 x 3.5 m lanes each way, guard rails on the median and
/// the shoulders, flat terrain, few features along the road).
///
/// The ground is one triangle strip along the road centreline: a
/// cross-section of lateral samples (road bands, shoulders, terrain out to
/// about 100 m) swept along the road every 2.5 m, its height the road's
/// elevation profile blended into hills away from the road. On the inner
/// side of curves the cross-section is shortened to 80% of the curve radius,
/// so the strip never folds. Revisit (see revisit.hpp): the road stays open
/// and the ego drives out and back, its straight fitted to the drive. Rural:
/// in its lanes, U-turning (6 m radius) on paved turnarounds where the road
/// is widened to ~8.5 m each side and kept clear of objects; drives too short
/// for that (< ~20 s) circle on the turnaround itself. Highway: in the inner
/// lanes, U-turning (4.75 m radius) through median crossings (median paved,
/// guard rails and lights left out); traffic stays in the middle lanes.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <semlio/sim/path.hpp>
#include <semlio/sim/random.hpp>
#include <semlio/sim/revisit.hpp>
#include <semlio/sim/world_builder.hpp>
#include <semlio/sim/world_config.hpp>

namespace semlio::sim::detail {

/// A smooth scalar field of a few sinusoids (hills, elevation profiles).
struct Waves {
  struct Wave {
    double kx, ky, phase, amplitude;
  };
  std::vector<Wave> waves;
  /// Value at (x, y).
  [[nodiscard]] double operator()(double x, double y) const {
    double v = 0.0;
    for (const Wave& w : waves) v += w.amplitude * std::sin(w.kx * x + w.ky * y + w.phase);
    return v;
  }
};

/// One band of the cross-section: from lateral offset `l0` to `l1` (left
/// positive), its class.
struct Band {
  double l0, l1;
  std::uint16_t raw_id;
};

/// Centreline of an open road: points every `ds`.
struct Centreline {
  std::vector<Eigen::Vector3d> points;
};

/// Winding rural road of `length_m`: heading a sum of two sinusoids of
/// arclength (700 m and 330 m periods).
inline Centreline rural_centreline(Rng& rng, double length_m, double ds) {
  Centreline c;
  const double p1 = rng.uniform(0.0, 6.28);
  const double p2 = rng.uniform(0.0, 6.28);
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  const int n = static_cast<int>(std::ceil(length_m / ds));
  for (int k = 0; k <= n; ++k) {
    c.points.push_back(p);
    const double s = k * ds;
    const double heading = 0.5 * std::sin(2.0 * std::numbers::pi * s / 700.0 + p1) +
                           0.15 * std::sin(2.0 * std::numbers::pi * s / 330.0 + p2);
    p += ds * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.0);
  }
  return c;
}

/// Nearly straight highway of `length_m` (heading within +-0.04 rad).
inline Centreline highway_centreline(double length_m, double ds) {
  Centreline c;
  const int n = static_cast<int>(std::ceil(length_m / ds));
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k <= n; ++k) {
    c.points.push_back(p);
    const double heading = 0.04 * std::sin(2.0 * std::numbers::pi * k * ds / 3000.0);
    p += ds * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.0);
  }
  return c;
}

/// Road coordinates (u along the centreline from `s0`, l to its left) on an
/// open centreline with elevation `road_z`: the world point, z on the road.
template <typename RoadZ>
Eigen::Vector3d road_point(const Polyline& centre, const RoadZ& road_z, double s0, double u, double l) {
  const double s = s0 + u;
  Eigen::Vector3d t = centre.at(s + 1.0) - centre.at(s - 1.0);
  t.z() = 0.0;
  t.normalize();
  Eigen::Vector3d p = centre.at(s) + l * Eigen::Vector3d(-t.y(), t.x(), 0.0);
  p.z() = road_z(s);
  return p;
}

/// Builds the rural or highway world.
inline World make_strip_world(const WorldConfig& config) {
  const bool rural = config.kind == WorldKind::kRural;
  const double ds = 2.5;
  Rng rng(config.seed, 11);
  const double cruise = rural ? 16.0 : 25.0;
  // Roads start 150 m behind the ego so the first sweeps see road behind.
  const double lead_in = 150.0;
  const double open_length = 1.3 * config.drive_length_m + 300.0 + lead_in;
  const Centreline cl = rural ? rural_centreline(rng, open_length, ds) : highway_centreline(open_length, ds);
  const std::size_t n = cl.points.size();
  const auto idx = [&](long i) { return static_cast<std::size_t>(std::clamp(i, 0L, static_cast<long>(n) - 1)); };
  // Arclength, tangent, left normal, signed curvature per sample.
  std::vector<double> s(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) s[i] = s[i - 1] + (cl.points[i] - cl.points[i - 1]).norm();
  const double total = s.back();
  std::vector<Eigen::Vector3d> left(n);
  std::vector<double> kappa(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto il = static_cast<long>(i);
    const Eigen::Vector3d a = cl.points[idx(il - 1)];
    const Eigen::Vector3d b = cl.points[i];
    const Eigen::Vector3d c = cl.points[idx(il + 1)];
    const Eigen::Vector3d t = (c - a).normalized();
    left[i] = Eigen::Vector3d(-t.y(), t.x(), 0.0);
    const Eigen::Vector3d d1 = (b - a).normalized();
    const Eigen::Vector3d d2 = (c - b).normalized();
    const double cross = d1.x() * d2.y() - d1.y() * d2.x();
    const double seg = 0.5 * ((b - a).norm() + (c - b).norm());
    kappa[i] = seg > 0.0 ? cross / seg : 0.0;
  }
  // Elevation profile of the road and hills around it.
  const double l1 = rural ? 1000.0 : 2000.0;
  const double l2 = rural ? 400.0 : 900.0;
  const double a1 = rural ? 9.0 : 2.0;
  const double a2 = rural ? 3.0 : 0.5;
  const double ph1 = rng.uniform(0.0, 6.28);
  const double ph2 = rng.uniform(0.0, 6.28);
  const auto road_z = [&](double sv) {
    return a1 * std::sin(2.0 * std::numbers::pi * sv / l1 + ph1) + a2 * std::sin(2.0 * std::numbers::pi * sv / l2 + ph2);
  };
  Waves hills;
  const double hill_amp = rural ? 1.0 : 0.15;
  for (const auto& [wavelength, amp] : {std::pair{520.0, 9.0}, std::pair{260.0, 6.0}, std::pair{110.0, 3.0}}) {
    const double dir = rng.uniform(0.0, 6.28);
    const double k = 2.0 * std::numbers::pi / wavelength;
    hills.waves.push_back({k * std::cos(dir), k * std::sin(dir), rng.uniform(0.0, 6.28), amp * hill_amp});
  }
  // Cross-section.
  std::vector<Band> bands;
  double road_edge = 0.0;
  if (rural) {
    road_edge = 3.25;
    bands = {{-3.25, 0.0, raw::kRoad}, {0.0, 3.25, raw::kRoad}};
  } else {
    road_edge = 16.0;
    bands = {{-16.0, -13.5, raw::kRoad}, {-13.5, -3.0, raw::kRoad}, {-3.0, -2.5, raw::kRoad},
             {-2.5, 2.5, raw::kTerrain}, {2.5, 3.0, raw::kRoad},     {3.0, 13.5, raw::kRoad},
             {13.5, 16.0, raw::kRoad}};
  }

  World world;
  world.config = config;
  world.ego_motion.cruise_speed_mps = cruise;
  world.ego_motion.turn_radius_m = 50.0;
  world.ego_motion.min_blend_length_m = 1.0;
  world.ego_motion.start_at_rest = false;

  // Revisit: an out-and-back drive starting `lead_in` into the road. Its
  // U-turns need room: rural roads get a paved turnaround (the road widened
  // to ~8.5 m each side over the U-turn), highways a median crossing (median
  // paved, its guard rails and lights left out).
  std::vector<std::array<double, 2>> turn_zones;  // centreline arclength ranges of the U-turns [m]
  const double widen = rural ? 5.25 : 0.0;         // extra paved width each side in turn zones [m]
  RevisitPlan plan;
  if (config.revisit) {
    const double t_return = config.return_time_s > 0.0 ? config.return_time_s : config.drive_length_m / cruise;
    world.return_time_s = t_return;
    world.ego_motion.end_at_rest = false;  // the tail lap is never reached
    const Polyline centre(cl.points);
    const auto to_world = [&](double u, double l) { return road_point(centre, road_z, lead_in, u, l); };
    // Rural: out and back in the two lanes, swinging onto the turnaround for
    // a 6 m U-turn; short drives run on the turnaround itself. Highway: the
    // inner lanes, U-turn (4.75 m) through the median.
    // Straights are sampled every 5 m (the Trajectory rounds the gentle road
    // curvature between samples; fitting is several times faster).
    const StadiumShape lanes_shape =
        rural ? StadiumShape{.lane_m = 1.625, .turn_radius_m = 6.0, .swing_m = 16.0, .step_m = 1.0, .straight_step_m = 5.0}
              : StadiumShape{.lane_m = 4.75, .turn_radius_m = 4.75, .swing_m = 0.0, .step_m = 1.0, .straight_step_m = 5.0};
    const StadiumShape tight_shape{.lane_m = 5.25, .turn_radius_m = 5.25, .swing_m = 0.0, .step_m = 1.0,
                                   .straight_step_m = 5.0};
    const double max_straight = total - lead_in - 200.0;
    plan = plan_out_and_back(lanes_shape, max_straight, to_world, world.ego_motion, t_return);
    StadiumShape used = lanes_shape;
    if (rural && !plan.fit.ok) {
      plan = plan_out_and_back(tight_shape, max_straight, to_world, world.ego_motion, t_return);
      used = tight_shape;
    }
    const double L = plan.fit.param;
    const double reach = used.swing_m + used.turn_radius_m;
    if (used.lane_m >= used.turn_radius_m && rural) {
      turn_zones.push_back({lead_in - reach - 4.0, lead_in + L + reach + 4.0});
    } else {
      turn_zones.push_back({lead_in - reach - 4.0, lead_in + 4.0});
      turn_zones.push_back({lead_in + L - 4.0, lead_in + L + reach + 4.0});
    }
    world.ego_route = plan.route;
    world.loop_length_m = plan.lap_length_m;
    world.return_error_m = plan.fit.error_m;
    world.revisit_route = "out_and_back";
  }
  // Weight of the turn zones at arclength sv: 1 inside, smooth to 0 over `ramp` m.
  const auto zone_weight = [&](double sv, double ramp) {
    double w = 0.0;
    for (const auto& z : turn_zones) {
      const double d = std::max({z[0] - sv, sv - z[1], 0.0});
      const double x = std::clamp(1.0 - d / ramp, 0.0, 1.0);
      w = std::max(w, x * x * (3.0 - 2.0 * x));
    }
    return w;
  };
  std::vector<double> edge(n, road_edge);  // paved half-width per sample
  for (std::size_t i = 0; i < n; ++i) edge[i] = road_edge + widen * zone_weight(s[i], 8.0);
  // Objects keep clear of the turn zones (and of the widened road).
  const auto clear = [&](std::size_t i, double l) {
    return turn_zones.empty() || zone_weight(s[i], 12.0) <= 0.0 || std::abs(l) > road_edge + widen + 4.0;
  };
  const auto median_open = [&](std::size_t i) { return !rural && zone_weight(s[i], 1.0) > 0.0; };

  const std::vector<double> outward{0.0, 0.6, 1.6, 3.0, 5.0, 7.5, 10.5, 14.0, 18.0, 23.0,
                                    29.0, 36.0, 44.0, 53.0, 63.0, 74.0, 86.0, 100.0};
  std::vector<double> lat;
  for (auto it = outward.rbegin(); it != outward.rend(); ++it) {
    if (*it > 0.0) lat.push_back(-(road_edge + *it));
  }
  for (const Band& b : bands) lat.push_back(b.l0);
  for (const double d : outward) lat.push_back(road_edge + d);
  const auto band_class = [&](std::size_t i, double l0, double l1v) -> std::uint16_t {
    const double m = 0.5 * (l0 + l1v);
    if (std::abs(m) < edge[i] && std::abs(m) > road_edge) return raw::kRoad;  // turnaround
    if (median_open(i) && std::abs(m) < road_edge) return raw::kRoad;       // median crossing
    for (const Band& b : bands) {
      if (m > b.l0 && m < b.l1) return b.raw_id;
    }
    return raw::kTerrain;
  };
  // Height of the ground at sample i, lateral offset l, position p.
  const auto ground_z = [&](std::size_t i, double l, const Eigen::Vector3d& p) {
    const double d = std::abs(l) - edge[i];
    double z = road_z(s[i]);
    if (d > 0.0) {
      const double u = std::clamp(d / 35.0, 0.0, 1.0);
      const double w = u * u * (3.0 - 2.0 * u);
      z += w * (hills(p.x(), p.y()) - hills(cl.points[i].x(), cl.points[i].y()));
      z -= 0.25 * std::clamp(d / 1.5, 0.0, 1.0);  // shallow verge below the road
    }
    return z;
  };
  // Lateral scale on the inner side of curves so the strip never folds.
  const auto vertex = [&](std::size_t i, double l) {
    const double k = kappa[i];
    double scale = 1.0;
    const double reach = std::abs(l);
    if (k * l > 0.0 && reach > road_edge) {
      const double limit = 0.8 / std::abs(k);
      const double far = road_edge + outward.back();
      if (far > limit) scale = std::max(0.0, (limit - road_edge) / (far - road_edge));
      const double ll = road_edge + (reach - road_edge) * scale;
      l = l > 0.0 ? ll : -ll;
    }
    Eigen::Vector3d p = cl.points[i] + l * left[i];
    p.z() = ground_z(i, l, p);
    return p;
  };

  WorldBuilder wb;
  // Base plane far below, visible only through holes of the strip.
  double zmin = 1e9;
  for (std::size_t i = 0; i < n; ++i) zmin = std::min(zmin, road_z(s[i]));
  Eigen::Vector3d lo = cl.points.front();
  Eigen::Vector3d hi = cl.points.front();
  for (const auto& p : cl.points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  wb.tiled_rect(lo.x() - 400.0, lo.y() - 400.0, hi.x() + 400.0, hi.y() + 400.0, zmin - 30.0, raw::kTerrain, 200.0);

  const std::size_t segments = n - 1;
  std::vector<Eigen::Vector3d> row0(lat.size());
  std::vector<Eigen::Vector3d> row1(lat.size());
  for (std::size_t j = 0; j < lat.size(); ++j) row0[j] = vertex(0, lat[j]);
  for (std::size_t i = 0; i < segments; ++i) {
    const std::size_t i1 = idx(static_cast<long>(i) + 1);
    for (std::size_t j = 0; j < lat.size(); ++j) row1[j] = vertex(i1, lat[j]);
    for (std::size_t j = 0; j + 1 < lat.size(); ++j) {
      wb.quad(row0[j], row1[j], row1[j + 1], row0[j + 1], band_class(i, lat[j], lat[j + 1]));
    }
    // Lane markings: dashed centre (rural) or lane dividers (highway), solid edges.
    const auto mark = [&](double l, double half_width, bool dashed) {
      if (dashed && i % 3 != 0) return;
      const double z0 = road_z(s[i]) + 0.003;
      const double z1 = road_z(s[i1]) + 0.003;
      Eigen::Vector3d a = cl.points[i] + (l - half_width) * left[i];
      Eigen::Vector3d b = cl.points[i1] + (l - half_width) * left[i1];
      Eigen::Vector3d c = cl.points[i1] + (l + half_width) * left[i1];
      Eigen::Vector3d d = cl.points[i] + (l + half_width) * left[i];
      a.z() = z0;
      d.z() = z0;
      b.z() = z1;
      c.z() = z1;
      wb.quad(a, b, c, d, raw::kLaneMarking);
    };
    if (rural) {
      mark(0.0, 0.06, true);
      mark(-3.1, 0.06, false);
      mark(3.1, 0.06, false);
    } else {
      for (const double l : {-10.0, -6.5, 6.5, 10.0}) mark(l, 0.07, true);
      for (const double l : {-13.35, -3.15, 3.15, 13.35}) mark(l, 0.08, false);
    }
    row0.swap(row1);
  }

  // Objects along the road.
  const auto place = [&](std::size_t i, double l) { return vertex(i, l); };
  const double forest_phase = rng.uniform(0.0, 6.28);
  for (std::size_t i = 0; i < n; ++i) {
    const double sv = s[i];
    const Eigen::Vector3d t(left[i].y(), -left[i].x(), 0.0);
    const double yaw = std::atan2(t.y(), t.x());
    if (rural) {
      const double forest = 0.5 + 0.5 * std::sin(2.0 * std::numbers::pi * sv / 450.0 + forest_phase);
      for (const double side : {-1.0, 1.0}) {
        if (rng.chance(0.35 + 0.9 * forest)) {
          const double l = side * (road_edge + rng.uniform(3.5, 70.0));
          if (!clear(i, l)) continue;
          if (rng.chance(0.75)) wb.tree(place(i, l), rng, rng.uniform(0.9, 1.6));
          else wb.bush(place(i, l), rng);
        }
        if (rng.chance(0.25)) {
          const double l = side * (road_edge + rng.uniform(2.0, 8.0));
          if (clear(i, l)) wb.bush(place(i, l), rng);
        }
      }
      if (i % 20 == 0 && clear(i, road_edge + 2.5)) wb.pole(place(i, -(road_edge + 2.5)), 9.0, 0.13);
      if (i % 160 == 40 && clear(i, road_edge + 1.5)) wb.sign(place(i, -(road_edge + 1.5)), yaw, rng);
      if (i % 240 == 120 && clear(i, 0.0) && rng.chance(0.7)) {  // a house with a fence
        const double side = rng.chance(0.5) ? 1.0 : -1.0;
        const double l = side * (road_edge + rng.uniform(18.0, 35.0));
        const Eigen::Vector3d g = place(i, l);
        const double bh = rng.uniform(5.0, 9.0);
        // Named draws, in GCC's former argument order (sim/random.hpp).
        const double reflectivity = rng.uniform(0.7, 1.3);
        const std::uint16_t instance = wb.new_instance();
        const double yaw_jitter = rng.uniform(-0.3, 0.3);
        const double half_x = rng.uniform(4.0, 8.0);
        const double half_y = rng.uniform(4.0, 7.0);
        wb.box(g + Eigen::Vector3d(0.0, 0.0, 0.5 * bh - 1.0), {half_x, half_y, 0.5 * bh + 1.0}, yaw + yaw_jitter,
               raw::kBuilding, instance, reflectivity);
      }
      // Field fences along some stretches.
      if (std::sin(2.0 * std::numbers::pi * sv / 700.0 + forest_phase) > 0.6 && i + 1 < n && clear(i, road_edge + 6.0)) {
        const Eigen::Vector3d a = place(i, road_edge + 6.0);
        const Eigen::Vector3d b = place(idx(static_cast<long>(i) + 1), road_edge + 6.0);
        const Eigen::Vector3d m = 0.5 * (a + b);
        wb.box(m + Eigen::Vector3d(0.0, 0.0, 0.6), {0.5 * (b - a).norm(), 0.03, 0.6}, yaw, raw::kFence, 0);
      }
    } else {
      // Guard rails (fence) on the median and both shoulders, as boxes per segment.
      const std::size_t i1 = idx(static_cast<long>(i) + 1);
      if (i + 1 < n) {
        for (const double l : {-16.3, -2.3, 2.3, 16.3}) {
          if (std::abs(l) < 3.0 && (median_open(i) || median_open(i1))) continue;  // median crossing
          Eigen::Vector3d a = cl.points[i] + l * left[i];
          Eigen::Vector3d b = cl.points[i1] + l * left[i1];
          a.z() = road_z(s[i]);
          b.z() = road_z(s[i1]);
          const Eigen::Vector3d m = 0.5 * (a + b);
          const Eigen::Vector3d dir = b - a;
          wb.box(m + Eigen::Vector3d(0.0, 0.0, 0.6), {0.5 * dir.norm(), 0.15, 0.2}, std::atan2(dir.y(), dir.x()),
                 raw::kFence, 0);
          if (i % 2 == 0) wb.box(a + Eigen::Vector3d(0.0, 0.0, 0.3), {0.06, 0.06, 0.4}, yaw, raw::kFence, 0);
        }
      }
      if (i % 200 == 100) wb.sign(place(i, -(road_edge + 1.5)), yaw, rng);
      if (i % 24 == 0 && clear(i, 0.0)) wb.pole(place(i, 0.0), 10.0, 0.15);
      if (rng.chance(0.08)) {
        const double side = rng.chance(0.5) ? 1.0 : -1.0;
        const double scale = rng.uniform(1.0, 1.6);  // named draws (sim/random.hpp)
        const double offset = rng.uniform(15.0, 80.0);
        wb.tree(place(i, side * (road_edge + offset)), rng, scale);
      }
    }
  }

  // Route: lane centres as dense points.
  const double ego_lane = rural ? -1.625 : -8.25;
  std::vector<Eigen::Vector3d> centre;
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Vector3d p = cl.points[i];
    p.z() = road_z(s[i]);
    centre.push_back(p);
  }
  const auto lane_points = [&](const std::vector<Eigen::Vector3d>& path, double l) {
    std::vector<Eigen::Vector3d> out = offset_path(path, l);
    for (std::size_t i = 0; i < out.size(); ++i) out[i].z() = path[i].z();
    return out;
  };
  const auto from = [&](double sv) {
    const auto k = static_cast<std::ptrdiff_t>(std::clamp(sv / ds, 0.0, static_cast<double>(n - 2)));
    return std::vector<Eigen::Vector3d>(centre.begin() + k, centre.end());
  };
  if (!config.revisit) {
    const auto ahead = from(lead_in);
    world.ego_route = lane_points(ahead, ego_lane);
    world.lanes.alongside = {lane_points(ahead, rural ? ego_lane : -4.75), cruise, 50.0};
    const auto back = reversed(ahead);
    world.lanes.oncoming = {lane_points(back, rural ? -1.625 : -8.25), cruise, 50.0};
    if (rural) world.lanes.bikes = {lane_points(back, -3.9), 6.0, 50.0};
  } else if (rural) {
    // One lane per direction and U-turns across both: traffic follows the
    // ego's own loop ahead of it (never on it, see alongside_period_s); it
    // is seen oncoming on the way back. No bikes.
    // Loops shorter than 80 m (drives under ~25 s) carry no traffic.
    if (plan.lap_length_m >= 80.0) {
      std::vector<Eigen::Vector3d> lap(plan.route.begin(),
                                       plan.route.begin() + static_cast<std::ptrdiff_t>(plan.route.size() / 2 + 1));
      world.lanes.alongside = {repeat_lap(lap, 4), cruise, 50.0};
      world.lanes.alongside_period_s = ego_trajectory(world.ego_route, world.ego_motion, {}).duration_s() / 2.0;
    }
  } else {
    // Highway: traffic in the middle lanes, clear of the ego's inner-lane loop.
    const auto ahead = from(lead_in + 0.5 * plan.fit.param);
    world.lanes.alongside = {lane_points(ahead, -8.25), cruise, 50.0};
    world.lanes.oncoming = {lane_points(reversed(from(0.0)), -8.25), cruise, 50.0};
  }
  world.lanes.trucks = true;
  // Rural has one lane per direction: the "alongside" car drives ahead of the ego.
  world.lanes.alongside_first_offset_s = rural ? 2.5 : 0.4;
  world.bvh.build(std::move(wb.prims));
  return world;
}

}  // namespace semlio::sim::detail
