#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cmath>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/sim/trajectory.hpp>

namespace test_trajectory {  // one namespace per test file: the area compiles as one TU

using semlio::sim::Trajectory;
using semlio::sim::TrajectoryConfig;

namespace {

// A small urban loop: 90 deg corners, a 45 deg bend, a climb of 4 m and back.
std::vector<Eigen::Vector3d> urban_route() {
  return {{0, 0, 0}, {200, 0, 0}, {200, 90, 4}, {140, 150, 4}, {0, 150, 0}, {0, 40, 0}};
}

TrajectoryConfig urban_config() {
  TrajectoryConfig c;
  c.stop_at_arclength_m = {60.0};
  c.stop_duration_s = 4.0;
  return c;
}

}  // namespace

TEST_CASE("trajectory starts and ends on the route, at rest", "[sim]") {
  const auto route = urban_route();
  const Trajectory tr = Trajectory::through(route, urban_config());
  REQUIRE(tr.duration_s() > 30.0);
  CHECK((tr.pose(0.0).translation() - route.front()).norm() < 1e-6);
  CHECK((tr.pose(tr.duration_s()).translation() - route.back()).norm() < 1e-6);
  CHECK(tr.velocity_world_mps(0.0).norm() < 1e-9);
  CHECK(tr.velocity_world_mps(tr.duration_s()).norm() < 1e-9);
  // Path length: the polyline minus what rounding cuts off, plus the climb.
  CHECK(tr.length_m() > 560.0);
  CHECK(tr.length_m() < 630.0);
}

TEST_CASE("trajectory derivatives are the derivatives of the pose (C2, no jumps)", "[sim]") {
  const Trajectory tr = Trajectory::through(urban_route(), urban_config());
  const double dt = 1e-3;
  double max_v_err = 0.0;
  double max_a_err = 0.0;
  double max_w_err = 0.0;
  double max_alpha_err = 0.0;
  double max_jerk = 0.0;
  double max_wdot_step = 0.0;
  for (double t = dt; t < tr.duration_s() - dt; t += 0.0137) {
    const auto s = tr.state(t);
    const Eigen::Vector3d v_fd =
        (tr.pose(t + dt).translation() - tr.pose(t - dt).translation()) / (2.0 * dt);
    const Eigen::Vector3d a_fd = (tr.velocity_world_mps(t + dt) - tr.velocity_world_mps(t - dt)) / (2.0 * dt);
    const semlio::SO3d dR = tr.pose(t - dt).so3().inverse() * tr.pose(t + dt).so3();
    const Eigen::Vector3d w_fd = dR.log() / (2.0 * dt);
    const Eigen::Vector3d alpha_fd =
        (tr.angular_velocity_body_radps(t + dt) - tr.angular_velocity_body_radps(t - dt)) / (2.0 * dt);
    max_v_err = std::max(max_v_err, (v_fd - s.velocity_world_mps).norm());
    max_a_err = std::max(max_a_err, (a_fd - s.acceleration_world_mps2).norm());
    max_w_err = std::max(max_w_err, (w_fd - s.angular_velocity_body_radps).norm());
    max_alpha_err = std::max(max_alpha_err, (alpha_fd - s.angular_acceleration_body_radps2).norm());
    // Continuity: one-sided differences of acceleration stay bounded (a jump
    // of 0.01 m/s^2 over dt would show as 10 m/s^3).
    max_jerk = std::max(max_jerk, (tr.acceleration_world_mps2(t + dt) - s.acceleration_world_mps2).norm() / dt);
    max_wdot_step = std::max(
        max_wdot_step, (tr.angular_velocity_body_radps(t + dt) - s.angular_velocity_body_radps).norm() / dt);
    // Accessors agree with state().
    REQUIRE((tr.velocity_world_mps(t) - s.velocity_world_mps).norm() < 1e-12);
    REQUIRE((tr.angular_acceleration_body_radps2(t) - s.angular_acceleration_body_radps2).norm() < 1e-12);
  }
  CHECK(max_v_err < 1e-5);
  CHECK(max_a_err < 1e-4);
  CHECK(max_w_err < 1e-5);
  CHECK(max_alpha_err < 1e-3);
  CHECK(max_jerk < 2.5);
  CHECK(max_wdot_step < 3.0);
}

TEST_CASE("trajectory: no jumps across every time step boundary", "[sim]") {
  // Scan the whole drive at a step far below any piece duration; joins are
  // somewhere in between, so a jump in position, velocity or acceleration
  // would show as a large difference between neighbouring samples.
  const Trajectory tr = Trajectory::through(urban_route(), urban_config());
  const double dt = 2e-3;
  auto prev = tr.state(0.0);
  double max_dp = 0.0;
  double max_dv = 0.0;
  double max_da = 0.0;
  for (double t = dt; t <= tr.duration_s(); t += dt) {
    const auto s = tr.state(t);
    max_dp = std::max(max_dp, (s.T_world_body.translation() - prev.T_world_body.translation()).norm());
    max_dv = std::max(max_dv, (s.velocity_world_mps - prev.velocity_world_mps).norm());
    max_da = std::max(max_da, (s.acceleration_world_mps2 - prev.acceleration_world_mps2).norm());
    prev = s;
  }
  CHECK(max_dp < 11.5 * dt);       // speed bound
  CHECK(max_dv < 3.0 * dt);        // acceleration bound
  CHECK(max_da < 2.5 * dt);        // jerk bound (no acceleration jumps)
}

TEST_CASE("trajectory respects speed, acceleration and lateral limits", "[sim]") {
  const TrajectoryConfig cfg = urban_config();
  const Trajectory tr = Trajectory::through(urban_route(), cfg);
  double v_max = 0.0;
  double stopped_s = 0.0;
  double lat_max = 0.0;
  double lon_max = 0.0;
  double lon_min = 0.0;
  double t_turn_speed = 1e9;
  const double dt = 0.01;
  for (double t = 0.0; t <= tr.duration_s(); t += dt) {
    const auto s = tr.state(t);
    const double v = s.velocity_world_mps.norm();
    v_max = std::max(v_max, v);
    if (v < 1e-9 && t > 1.0 && t < tr.duration_s() - 1.0) stopped_s += dt;
    if (v > 0.5) {
      const Eigen::Vector3d u = s.velocity_world_mps / v;
      const double lon = s.acceleration_world_mps2.dot(u);
      lon_max = std::max(lon_max, lon);
      lon_min = std::min(lon_min, lon);
      lat_max = std::max(lat_max, (s.acceleration_world_mps2 - lon * u).norm());
      // body x axis is the direction of travel
      REQUIRE(s.T_world_body.rotation().col(0).dot(u) > 1.0 - 1e-9);
    }
    // Near the first corner (200, 0) the vehicle is slow.
    if ((s.T_world_body.translation() - Eigen::Vector3d(200, 0, 0)).norm() < 6.0) {
      t_turn_speed = std::min(t_turn_speed, v);
    }
  }
  CHECK(v_max <= cfg.cruise_speed_mps * 1.01);
  CHECK(v_max > cfg.cruise_speed_mps * 0.95);  // reaches cruise on the long straights
  CHECK(lon_max <= cfg.max_accel_mps2 * 1.03);
  CHECK(lon_min >= -cfg.max_decel_mps2 * 1.03);
  CHECK(lat_max <= cfg.max_lateral_accel_mps2 * 1.05);
  CHECK(t_turn_speed < std::sqrt(cfg.max_lateral_accel_mps2 * cfg.turn_radius_m) * 1.1);
  CHECK(stopped_s == Approx(cfg.stop_duration_s).margin(0.05));
}

TEST_CASE("trajectory stop is at the requested arclength", "[sim]") {
  const TrajectoryConfig cfg = urban_config();
  const Trajectory tr = Trajectory::through(urban_route(), cfg);
  bool found = false;
  for (double t = 1.0; t < tr.duration_s() - 1.0; t += 0.05) {
    if (tr.velocity_world_mps(t).norm() < 1e-9) {
      CHECK(tr.arclength_m(t) == Approx(60.0).margin(1e-6));
      CHECK(tr.pose(t).translation().x() == Approx(60.0).margin(1e-3));
      found = true;
    }
  }
  CHECK(found);
}

TEST_CASE("trajectory pitch follows the slope, roll leans outward in turns", "[sim]") {
  const Trajectory tr = Trajectory::through(urban_route(), urban_config());
  double max_roll_left = 0.0;
  bool saw_climb = false;
  for (double t = 0.0; t <= tr.duration_s(); t += 0.05) {
    const auto s = tr.state(t);
    const Eigen::Matrix3d R = s.T_world_body.rotation();
    const Eigen::Vector3d v = s.velocity_world_mps;
    if (v.norm() > 1.0 && v.z() > 0.05) {
      CHECK(R.col(0).z() > 0.0);  // nose up uphill
      saw_climb = true;
    }
    // Left turn (yaw rate > 0): the left side goes up, body y tilts up.
    if (s.angular_velocity_body_radps.z() > 0.3) max_roll_left = std::max(max_roll_left, R.col(1).z());
    CHECK(std::abs(R.col(1).z()) < 0.05);  // roll stays small (< ~3 deg)
  }
  CHECK(saw_climb);
  CHECK(max_roll_left > 0.005);
}

TEST_CASE("trajectory highway config drives at ~90 km/h", "[sim]") {
  TrajectoryConfig cfg;
  cfg.cruise_speed_mps = 25.0;
  const Trajectory tr = Trajectory::through({{0, 0, 0}, {1500, 0, 0}, {3000, 200, 10}}, cfg);
  double v_max = 0.0;
  for (double t = 0.0; t <= tr.duration_s(); t += 0.1) v_max = std::max(v_max, tr.velocity_world_mps(t).norm());
  CHECK(v_max == Approx(25.0).epsilon(0.01));
}

TEST_CASE("trajectory moving start and end", "[sim]") {
  TrajectoryConfig cfg;
  cfg.start_at_rest = false;
  cfg.end_at_rest = false;
  const Trajectory tr = Trajectory::through({{0, 0, 0}, {200, 0, 0}}, cfg);
  CHECK(tr.velocity_world_mps(0.0).norm() == Approx(cfg.cruise_speed_mps).epsilon(1e-6));
  CHECK(tr.duration_s() == Approx(200.0 / cfg.cruise_speed_mps).epsilon(1e-6));
}

TEST_CASE("trajectory rejects bad input", "[sim]") {
  TrajectoryConfig bad;
  bad.cruise_speed_mps = 0.0;
  CHECK_THROWS_AS(Trajectory::through(urban_route(), bad), semlio::ConfigError);
  CHECK_THROWS_AS(Trajectory::through({{1, 2, 3}, {1, 2, 3}}, TrajectoryConfig{}), semlio::ValueError);
  CHECK_THROWS_AS(Trajectory::through({{0, 0, 0}, {std::nan(""), 0, 0}}, TrajectoryConfig{}), semlio::ValueError);
}

TEST_CASE("trajectory along a densely sampled winding road with hills is smooth", "[sim]") {
  // A sampled curve (2.5 m steps): heading and elevation vary smoothly; the
  // polyline's vertices must not show up as lateral-acceleration ripple.
  std::vector<Eigen::Vector3d> road;
  double heading = 0.0;
  Eigen::Vector3d p(0, 0, 0);
  for (int k = 0; k <= 400; ++k) {
    const double s = 2.5 * k;
    road.push_back(p);
    heading += 2.5 * 0.012 * std::sin(s / 120.0);  // curvature up to 1/83 m
    p += 2.5 * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.0);
    p.z() = 8.0 * std::sin(s / 150.0);  // hills: +-8 m, grade up to ~5%
  }
  TrajectoryConfig cfg;
  cfg.cruise_speed_mps = 16.0;
  cfg.start_at_rest = false;
  const Trajectory tr = Trajectory::through(road, cfg);
  double max_jerk = 0.0;
  double max_lat = 0.0;
  double max_dev = 0.0;
  double max_pitch = 0.0;
  const double dt = 0.01;
  auto prev = tr.state(1.0);
  for (double t = 1.0 + dt; t < tr.duration_s() - 1.0; t += dt) {
    const auto s = tr.state(t);
    max_jerk = std::max(max_jerk, (s.acceleration_world_mps2 - prev.acceleration_world_mps2).norm() / dt);
    const Eigen::Vector3d u = s.velocity_world_mps.normalized();
    max_lat = std::max(max_lat, (s.acceleration_world_mps2 - s.acceleration_world_mps2.dot(u) * u).norm());
    max_pitch = std::max(max_pitch, std::abs(s.T_world_body.rotation()(2, 0)));
    prev = s;
  }
  for (double q = 0.0; q < tr.length_m(); q += 3.0) {
    const Eigen::Vector3d x = tr.position_at_arclength(q);
    double best = 1e9;
    for (std::size_t i = 0; i + 1 < road.size(); ++i) {
      const Eigen::Vector3d ab = road[i + 1] - road[i];
      const double u = std::clamp((x - road[i]).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      best = std::min(best, (road[i] + u * ab - x).norm());
    }
    max_dev = std::max(max_dev, best);
  }
  CHECK(max_jerk < 2.0);
  CHECK(max_lat <= cfg.max_lateral_accel_mps2 * 1.05);
  CHECK(max_dev < 0.05);
  CHECK(max_pitch > 0.03);  // the hills show in the pitch (grade ~5%)
  CHECK(max_pitch < 0.07);
}

TEST_CASE("trajectory for a pedestrian loop (slow, tight corners)", "[sim]") {
  TrajectoryConfig cfg;
  cfg.cruise_speed_mps = 1.3;
  cfg.turn_radius_m = 1.0;
  cfg.max_accel_mps2 = 0.65;
  cfg.max_decel_mps2 = 0.78;
  cfg.min_blend_length_m = 2.0;
  cfg.start_at_rest = false;
  const Trajectory tr =
      Trajectory::through({{0, 0, 0}, {40, 0, 0}, {40, 30, 0}, {0, 30, 0}, {0, 0, 0}, {40, 0, 0}}, cfg);
  double v_max = 0.0;
  double w_max = 0.0;
  for (double t = 0.0; t <= tr.duration_s(); t += 0.05) {
    const auto s = tr.state(t);
    REQUIRE(s.T_world_body.matrix().allFinite());
    REQUIRE(s.angular_acceleration_body_radps2.allFinite());
    v_max = std::max(v_max, s.velocity_world_mps.norm());
    w_max = std::max(w_max, std::abs(s.angular_velocity_body_radps.z()));
  }
  CHECK(v_max <= 1.3 * 1.01);
  CHECK(w_max > 0.3);  // turns at the corners
  CHECK((tr.pose(tr.duration_s()).translation() - Eigen::Vector3d(40, 0, 0)).norm() < 1e-6);
}

TEST_CASE("default-constructed trajectory stands still at the identity", "[sim]") {
  const Trajectory tr;
  CHECK(tr.duration_s() == 0.0);
  CHECK(tr.pose(1.0).matrix().isIdentity());
  CHECK(tr.velocity_world_mps(1.0).norm() == 0.0);
  CHECK(tr.angular_acceleration_body_radps2(1.0).norm() == 0.0);
}

}  // namespace test_trajectory
