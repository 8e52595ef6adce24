#pragma once
/// \file
/// Revisit routes: closed drives sized so that a drive of a given duration
/// is back at its start pose, heading the same way, at a given time.
///
/// A revisit route is one lap of a closed route repeated (laps + 1 times:
/// the last lap is a tail the drive never reaches, so the vehicle passes its
/// start at speed instead of braking to a stop). The lap is sized by regula
/// falsi on one continuous parameter until the distance driven at the return
/// time equals `laps` laps of the smoothed path (closure error < 0.5 m,
/// typically < 1 cm). Two route families exist:
/// - block loops (urban, aliased): a rectangle of streets, counter-clockwise,
///   stopping before every other turn; the stop duration (0.5-20 s) is the
///   fitted parameter (urban_world.hpp);
/// - out-and-back loops (every world): drive along a road, U-turn, drive back
///   past the start on the other side, U-turn again and return to the start.
///   The straight's length (>= 0) is the fitted parameter, so even a ~10 s
///   drive returns (a U-turn at ~12 km/h takes ~4.5 s).
/// Return pose: same position (within the closure error) and, when the start
/// lies on a straight (drives >= ~15 s), the same heading; on the shortest
/// drives the start transient of the path leaves up to ~6 deg of heading.
///
/// The ego's trajectory (`ego_trajectory`) is shared with the Simulator so
/// that the fitted and the simulated drives are the same function.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <semlio/sim/trajectory.hpp>

namespace semlio::sim {

/// The ego drive along `route` with `motion`, stopping (for
/// motion.stop_duration_s) at the path points nearest to `stop_points`, in
/// order (points farther than 2 m from the path are ignored). Deterministic.
inline Trajectory ego_trajectory(const std::vector<Eigen::Vector3d>& route, TrajectoryConfig motion,
                                 const std::vector<Eigen::Vector3d>& stop_points) {
  motion.stop_at_arclength_m.clear();
  const Trajectory free_drive = Trajectory::through(route, motion);
  if (stop_points.empty()) return free_drive;
  // Stop arclengths: the first path sample within 2 m of each stop point,
  // searched forward from the previous stop.
  double s = 0.0;
  const double L = free_drive.length_m();
  for (const Eigen::Vector3d& p : stop_points) {
    double best = -1.0;
    double best_d = 2.0;
    for (double q = s; q < L; q += 0.5) {
      const double d = (free_drive.position_at_arclength(q) - p).head<2>().norm();
      if (d < best_d) {
        best_d = d;
        best = q;
      } else if (best >= 0.0 && d > best_d + 5.0) {
        break;
      }
    }
    if (best >= 0.0) {
      motion.stop_at_arclength_m.push_back(best);
      s = best + 1.0;
    }
  }
  return motion.stop_at_arclength_m.empty() ? free_drive : Trajectory::through(route, motion);
}

namespace detail {

/// Result of fitting a revisit route.
struct RevisitFit {
  bool ok = false;        ///< a parameter with |error_m| <= tolerance was found
  double param = 0.0;     ///< the fitted parameter
  double error_m = 1e18;  ///< distance driven at the return time minus the lap length [m]
};

/// Fits `param` in [lo, hi] so that closure(param) == 0, for a closure error
/// that increases with param (distance driven minus lap length). Regula
/// falsi (Illinois variant: the closure is nearly linear, so a handful of
/// evaluations suffice) within `iterations` steps; keeps the best parameter
/// seen. Not ok when the sign does not change over [lo, hi] or the best
/// error exceeds `tolerance_m`.
template <typename Closure>
RevisitFit fit_revisit(Closure closure, double lo, double hi, double tolerance_m, int iterations = 30) {
  RevisitFit fit;
  double f_lo = closure(lo);
  double f_hi = closure(hi);
  fit.param = std::abs(f_lo) < std::abs(f_hi) ? lo : hi;
  fit.error_m = std::min(std::abs(f_lo), std::abs(f_hi));
  if (f_lo > 0.0 || f_hi < 0.0) {
    fit.ok = fit.error_m <= tolerance_m;
    return fit;
  }
  int side = 0;  // which end was kept last time (Illinois halving)
  for (int k = 0; k < iterations && fit.error_m > 0.01; ++k) {
    double x = f_hi > f_lo ? lo + (hi - lo) * (-f_lo) / (f_hi - f_lo) : 0.5 * (lo + hi);
    // Guard against stagnation at an end: fall back to bisection.
    if (!(x > lo + 1e-6 * (hi - lo) && x < hi - 1e-6 * (hi - lo))) x = 0.5 * (lo + hi);
    const double f = closure(x);
    if (std::abs(f) < fit.error_m) {
      fit.error_m = std::abs(f);
      fit.param = x;
    }
    if (f < 0.0) {
      lo = x;
      f_lo = f;
      if (side == -1) f_hi *= 0.5;
      side = -1;
    } else {
      hi = x;
      f_hi = f;
      if (side == 1) f_lo *= 0.5;
      side = 1;
    }
  }
  fit.ok = fit.error_m <= tolerance_m;
  return fit;
}

/// Closure error of a route made of `total_laps` identical laps that should
/// be back at its start after `laps` of them at `return_time_s`: distance
/// driven minus `laps` laps of the smoothed path [m].
inline double lap_closure_m(const Trajectory& drive, double return_time_s, int laps, int total_laps) {
  return drive.arclength_m(return_time_s) - drive.length_m() * laps / total_laps;
}

/// Shape of an out-and-back loop in road coordinates (u along the road, l to
/// its left): straights at l = -lane_m (out, +u) and l = +lane_m (back, -u);
/// U-turns are half circles of radius turn_radius_m about l = 0, reached by
/// a lateral swing over swing_m when turn_radius_m > lane_m.
struct StadiumShape {
  double lane_m = 5.25;         ///< lateral offset of the straights [m]
  double turn_radius_m = 5.25;  ///< U-turn radius [m] (>= lane_m)
  double swing_m = 0.0;         ///< length of the swing out to the U-turn radius [m]
  double step_m = 1.0;          ///< sample spacing on U-turns and swings [m]
  double straight_step_m = 1.0; ///< sample spacing on straights [m] (coarser is faster to fit on curved roads)
};

/// One lap of the out-and-back loop with straights of `straight_m` between
/// u = 0 and u = straight_m, as (u, l) samples: it starts and ends at
/// (straight_m / 2, -lane_m) heading +u; the U-turns turn left.
inline std::vector<Eigen::Vector2d> stadium_lap(double straight_m, const StadiumShape& shape) {
  std::vector<Eigen::Vector2d> out;
  const double h = shape.step_m;
  const double R = std::max(shape.turn_radius_m, shape.lane_m);
  const double w = shape.swing_m > 0.0 && R > shape.lane_m ? shape.swing_m : 0.0;
  const auto push = [&](double u, double l) {
    const Eigen::Vector2d p(u, l);
    if (out.empty() || (p - out.back()).norm() > 1e-6) out.push_back(p);
  };
  const auto line = [&](double u0, double u1, double l) {
    const int n = std::max(1, static_cast<int>(std::ceil(std::abs(u1 - u0) / shape.straight_step_m)));
    for (int k = 0; k <= n; ++k) push(u0 + (u1 - u0) * k / n, l);
  };
  // Lateral swing from l0 to l1 while u moves from u0 to u1 (quintic smooth step).
  const auto swing = [&](double u0, double u1, double l0, double l1) {
    if (w <= 0.0) return;
    const int n = std::max(2, static_cast<int>(std::ceil(std::abs(u1 - u0) / h)));
    for (int k = 0; k <= n; ++k) {
      const double x = static_cast<double>(k) / n;
      const double s = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
      push(u0 + (u1 - u0) * x, l0 + (l1 - l0) * s);
    }
  };
  const auto half_circle = [&](double uc, double a0) {
    const int n = std::max(8, static_cast<int>(std::ceil(std::numbers::pi * R / h)));
    for (int k = 0; k <= n; ++k) {
      const double a = a0 + std::numbers::pi * k / n;
      push(uc + R * std::cos(a), R * std::sin(a));
    }
  };
  const double L = std::max(0.0, straight_m);
  line(0.5 * L, L, -shape.lane_m);
  swing(L, L + w, -shape.lane_m, -R);
  half_circle(L + w, -0.5 * std::numbers::pi);
  swing(L + w, L, R, shape.lane_m);
  line(L, 0.0, shape.lane_m);
  swing(0.0, -w, shape.lane_m, R);
  half_circle(-w, 0.5 * std::numbers::pi);
  swing(-w, 0.0, -R, -shape.lane_m);
  line(0.0, 0.5 * L, -shape.lane_m);
  return out;
}

/// `laps` copies of a closed lap (first point == last point), joined.
inline std::vector<Eigen::Vector3d> repeat_lap(const std::vector<Eigen::Vector3d>& lap, int laps) {
  std::vector<Eigen::Vector3d> out;
  for (int k = 0; k < laps; ++k) out.insert(out.end(), lap.begin() + (k == 0 ? 0 : 1), lap.end());
  return out;
}

/// A fitted revisit route.
struct RevisitPlan {
  RevisitFit fit;                        ///< the closure fit
  int laps = 1;                          ///< laps driven before the return
  std::vector<Eigen::Vector3d> route;    ///< laps + 1 laps (world frame)
  double lap_length_m = 0.0;             ///< one lap of the smoothed path [m]
};

/// Fits an out-and-back loop (straights in [0, max_straight_m], the fewest
/// laps up to `max_laps`) whose ego drive with `motion` is back at its start
/// at `return_time_s`. `to_world(u, l)` maps road coordinates to the world.
/// When nothing closes, returns the best fit of the last lap count tried
/// (fit.ok false).
template <typename ToWorld>
RevisitPlan plan_out_and_back(const StadiumShape& shape, double max_straight_m, ToWorld to_world,
                              const TrajectoryConfig& motion, double return_time_s, int max_laps = 16) {
  RevisitPlan plan;
  const auto route_for = [&](double straight_m, int laps) {
    std::vector<Eigen::Vector3d> lap;
    for (const Eigen::Vector2d& q : stadium_lap(straight_m, shape)) lap.push_back(to_world(q.x(), q.y()));
    return repeat_lap(lap, laps + 1);
  };
  for (int laps = 1; laps <= max_laps; ++laps) {
    // The closure error decreases with the straight's length: fit its negative.
    const auto closure = [&](double straight_m) {
      const Trajectory drive = ego_trajectory(route_for(straight_m, laps), motion, {});
      return -lap_closure_m(drive, return_time_s, laps, laps + 1);
    };
    plan.fit = fit_revisit(closure, 0.0, std::max(0.0, max_straight_m), 0.5);
    plan.laps = laps;
    // Too short for one lap even with no straight: more laps cannot help.
    if (plan.fit.ok || closure(0.0) > 0.0) break;
  }
  plan.route = route_for(plan.fit.param, plan.laps);
  const Trajectory drive = ego_trajectory(plan.route, motion, {});
  plan.lap_length_m = drive.length_m() / (plan.laps + 1);
  plan.fit.error_m = lap_closure_m(drive, return_time_s, plan.laps, plan.laps + 1);
  return plan;
}

}  // namespace detail
}  // namespace semlio::sim
