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
/// so the strip never folds. Revisit: the road is a closed loop (rural: a
/// perturbed circle of at least ~950 m; highway: a stadium of two straights
/// joined by 250 m-radius bends, at least ~1570 m).

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <semlio/sim/path.hpp>
#include <semlio/sim/random.hpp>
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

/// Centreline of the road: points every `ds` (closed loops without the
/// repeated end point).
struct Centreline {
  std::vector<Eigen::Vector3d> points;
  bool closed = false;
};

inline Centreline rural_centreline(Rng& rng, double length_m, bool closed, double ds) {
  Centreline c;
  c.closed = closed;
  if (closed) {
    const double R0 = std::max(length_m, 950.0) / (2.0 * std::numbers::pi);
    const double a = rng.uniform(0.0, 6.28);
    const double b = rng.uniform(0.0, 6.28);
    // Sample the perturbed circle densely, then resample at ds.
    std::vector<Eigen::Vector3d> dense;
    for (int k = 0; k < 4000; ++k) {
      const double phi = 2.0 * std::numbers::pi * k / 4000.0;
      const double r = R0 * (1.0 + 0.08 * std::sin(2.0 * phi + a) + 0.03 * std::sin(3.0 * phi + b));
      dense.emplace_back(r * std::cos(phi), r * std::sin(phi), 0.0);
    }
    dense.push_back(dense.front());
    // Rescale so the loop has exactly the requested length.
    const double scale = std::max(length_m, 950.0) / Polyline(dense).length();
    for (auto& q : dense) q *= scale;
    const Polyline pl(dense);
    const int n = std::max(8, static_cast<int>(std::round(pl.length() / ds)));
    for (int k = 0; k < n; ++k) c.points.push_back(pl.at(pl.length() * k / n));
    return c;
  }
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

inline Centreline highway_centreline(double length_m, bool closed, double ds) {
  Centreline c;
  c.closed = closed;
  if (closed) {
    const double R = 250.0;
    const double straight = std::max(0.0, 0.5 * (length_m - 2.0 * std::numbers::pi * R));
    std::vector<Eigen::Vector3d> dense;
    const auto add_line = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / ds)));
      for (int k = 0; k < n; ++k) dense.push_back(a + (b - a) * (static_cast<double>(k) / n));
    };
    const auto add_arc = [&](const Eigen::Vector3d& centre, double a0) {
      const int n = static_cast<int>(std::ceil(std::numbers::pi * R / ds));
      for (int k = 0; k < n; ++k) {
        const double a = a0 + std::numbers::pi * k / n;
        dense.push_back(centre + R * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0));
      }
    };
    add_line({0.0, -R, 0.0}, {straight, -R, 0.0});
    add_arc({straight, 0.0, 0.0}, -0.5 * std::numbers::pi);
    add_line({straight, R, 0.0}, {0.0, R, 0.0});
    add_arc({0.0, 0.0, 0.0}, 0.5 * std::numbers::pi);
    c.points = dense;
    return c;
  }
  const int n = static_cast<int>(std::ceil(length_m / ds));
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k <= n; ++k) {
    c.points.push_back(p);
    const double heading = 0.04 * std::sin(2.0 * std::numbers::pi * k * ds / 3000.0);
    p += ds * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.0);
  }
  return c;
}

/// Builds the rural or highway world.
inline World make_strip_world(const WorldConfig& config) {
  const bool rural = config.kind == WorldKind::kRural;
  const double ds = 2.5;
  Rng rng(config.seed, 11);
  const double cruise = rural ? 16.0 : 25.0;
  const double loop_target = config.loop_target_m > 0.0 ? config.loop_target_m : 0.6 * config.drive_length_m;
  // Open roads start 150 m behind the ego so the first sweeps see road behind.
  const double lead_in = 150.0;
  const double open_length = 1.3 * config.drive_length_m + 300.0 + lead_in;
  Centreline cl = rural ? rural_centreline(rng, config.revisit ? loop_target : open_length, config.revisit, ds)
                        : highway_centreline(config.revisit ? loop_target : open_length, config.revisit, ds);
  const std::size_t n = cl.points.size();
  const auto idx = [&](long i) {
    const auto nn = static_cast<long>(n);
    return static_cast<std::size_t>(cl.closed ? ((i % nn) + nn) % nn : std::clamp(i, 0L, nn - 1));
  };
  // Arclength, tangent, left normal, signed curvature per sample.
  std::vector<double> s(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) s[i] = s[i - 1] + (cl.points[i] - cl.points[i - 1]).norm();
  const double total = cl.closed ? s.back() + (cl.points.front() - cl.points.back()).norm() : s.back();
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
  // Elevation profile of the road (periodic on loops) and hills around it.
  const auto period = [&](double want) { return cl.closed ? total / std::max(1.0, std::round(total / want)) : want; };
  const double l1 = period(rural ? 1000.0 : 2000.0);
  const double l2 = period(rural ? 400.0 : 900.0);
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
  const std::vector<double> outward{0.0, 0.6, 1.6, 3.0, 5.0, 7.5, 10.5, 14.0, 18.0, 23.0,
                                    29.0, 36.0, 44.0, 53.0, 63.0, 74.0, 86.0, 100.0};
  std::vector<double> lat;
  for (auto it = outward.rbegin(); it != outward.rend(); ++it) {
    if (*it > 0.0) lat.push_back(-(road_edge + *it));
  }
  for (const Band& b : bands) lat.push_back(b.l0);
  for (const double d : outward) lat.push_back(road_edge + d);
  const auto band_class = [&](double l0, double l1v) -> std::uint16_t {
    const double m = 0.5 * (l0 + l1v);
    for (const Band& b : bands) {
      if (m > b.l0 && m < b.l1) return b.raw_id;
    }
    return raw::kTerrain;
  };
  // Height of the ground at sample i, lateral offset l, position p.
  const auto ground_z = [&](std::size_t i, double l, const Eigen::Vector3d& p) {
    const double d = std::abs(l) - road_edge;
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

  const std::size_t segments = cl.closed ? n : n - 1;
  std::vector<Eigen::Vector3d> row0(lat.size());
  std::vector<Eigen::Vector3d> row1(lat.size());
  for (std::size_t j = 0; j < lat.size(); ++j) row0[j] = vertex(0, lat[j]);
  for (std::size_t i = 0; i < segments; ++i) {
    const std::size_t i1 = idx(static_cast<long>(i) + 1);
    for (std::size_t j = 0; j < lat.size(); ++j) row1[j] = vertex(i1, lat[j]);
    for (std::size_t j = 0; j + 1 < lat.size(); ++j) {
      wb.quad(row0[j], row1[j], row1[j + 1], row0[j + 1], band_class(lat[j], lat[j + 1]));
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
          if (rng.chance(0.75)) wb.tree(place(i, l), rng, rng.uniform(0.9, 1.6));
          else wb.bush(place(i, l), rng);
        }
        if (rng.chance(0.25)) wb.bush(place(i, side * (road_edge + rng.uniform(2.0, 8.0))), rng);
      }
      if (i % 20 == 0) wb.pole(place(i, -(road_edge + 2.5)), 9.0, 0.13);
      if (i % 160 == 40) wb.sign(place(i, -(road_edge + 1.5)), yaw, rng);
      if (i % 240 == 120 && rng.chance(0.7)) {  // a house with a fence
        const double side = rng.chance(0.5) ? 1.0 : -1.0;
        const double l = side * (road_edge + rng.uniform(18.0, 35.0));
        const Eigen::Vector3d g = place(i, l);
        const double bh = rng.uniform(5.0, 9.0);
        wb.box(g + Eigen::Vector3d(0.0, 0.0, 0.5 * bh - 1.0), {rng.uniform(4.0, 8.0), rng.uniform(4.0, 7.0), 0.5 * bh + 1.0},
               yaw + rng.uniform(-0.3, 0.3), raw::kBuilding, wb.new_instance(), rng.uniform(0.7, 1.3));
      }
      // Field fences along some stretches.
      if (std::sin(2.0 * std::numbers::pi * sv / 700.0 + forest_phase) > 0.6 && i + 1 < n) {
        const Eigen::Vector3d a = place(i, road_edge + 6.0);
        const Eigen::Vector3d b = place(idx(static_cast<long>(i) + 1), road_edge + 6.0);
        const Eigen::Vector3d m = 0.5 * (a + b);
        wb.box(m + Eigen::Vector3d(0.0, 0.0, 0.6), {0.5 * (b - a).norm(), 0.03, 0.6}, yaw, raw::kFence, 0);
      }
    } else {
      // Guard rails (fence) on the median and both shoulders, as boxes per segment.
      const std::size_t i1 = idx(static_cast<long>(i) + 1);
      if (cl.closed || i + 1 < n) {
        for (const double l : {-16.3, -2.3, 2.3, 16.3}) {
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
      if (i % 24 == 0) wb.pole(place(i, 0.0), 10.0, 0.15);
      if (rng.chance(0.08)) {
        const double side = rng.chance(0.5) ? 1.0 : -1.0;
        wb.tree(place(i, side * (road_edge + rng.uniform(15.0, 80.0))), rng, rng.uniform(1.0, 1.6));
      }
    }
  }

  World world;
  world.config = config;
  world.ego_motion.cruise_speed_mps = cruise;
  world.ego_motion.turn_radius_m = 50.0;
  world.ego_motion.min_blend_length_m = 1.0;
  world.ego_motion.start_at_rest = false;
  // Route: lane centres as dense points (loops repeated to cover the drive).
  const double ego_lane = rural ? -1.625 : -8.25;
  std::vector<Eigen::Vector3d> centre;
  const int loops = cl.closed ? std::max(2, static_cast<int>(std::ceil(1.3 * config.drive_length_m / total)) + 1) : 1;
  const auto first = cl.closed ? std::size_t{0} : static_cast<std::size_t>(lead_in / ds);
  for (int k = 0; k < loops; ++k) {
    for (std::size_t i = (k == 0 ? first : 0); i < n; ++i) {
      Eigen::Vector3d p = cl.points[i];
      p.z() = road_z(s[i]);
      centre.push_back(p);
    }
  }
  if (cl.closed) {
    Eigen::Vector3d p = cl.points.front();
    p.z() = road_z(0.0);
    centre.push_back(p);
    world.loop_length_m = total;
  }
  const auto lane_points = [&](const std::vector<Eigen::Vector3d>& path, double l) {
    std::vector<Eigen::Vector3d> out = offset_path(path, l);
    for (std::size_t i = 0; i < out.size(); ++i) out[i].z() = path[i].z();
    return out;
  };
  world.ego_route = lane_points(centre, ego_lane);
  world.lanes.alongside = {lane_points(centre, rural ? ego_lane : -4.75), cruise, 50.0};
  const auto back = reversed(centre);
  world.lanes.oncoming = {lane_points(back, rural ? -1.625 : -8.25), cruise, 50.0};
  if (rural) world.lanes.bikes = {lane_points(back, -3.9), 6.0, 50.0};
  world.lanes.trucks = true;
  // Rural has one lane per direction: the "alongside" car drives ahead of the ego.
  world.lanes.alongside_first_offset_s = rural ? 2.5 : 0.4;
  world.bvh.build(std::move(wb.prims));
  return world;
}

}  // namespace semlio::sim::detail
