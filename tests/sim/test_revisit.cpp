// Revisit routes: even short drives come back to their start pose, in every
// world; open drives do not. Routes and ego trajectories only (no ray casting).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include <semlio/sim/revisit.hpp>
#include <semlio/sim/simulator.hpp>

namespace test_revisit {  // one namespace per test file: the area compiles as one TU

using namespace semlio::sim;

namespace {

struct Drive {
  World world;
  Trajectory ego;
};

Drive drive_for(WorldKind kind, std::size_t frames, bool revisit) {
  SimulatorConfig c;
  c.world = kind;
  c.frames = frames;
  c.revisit = revisit;
  Drive d{make_world(Simulator::world_config(c)), {}};
  d.ego = ego_trajectory(d.world.ego_route, d.world.ego_motion, d.world.ego_stop_points);
  return d;
}

double yaw_of(const semlio::SE3d& T) {
  const Eigen::Matrix3d R = T.rotation();
  return std::atan2(R(1, 0), R(0, 0));
}

double angle_diff(double a, double b) { return std::abs(std::remainder(a - b, 2.0 * 3.141592653589793)); }

}  // namespace

TEST_CASE("revisit: 100- and 300-frame drives end at their start pose in every world", "[sim]") {
  for (const WorldKind kind : {WorldKind::kUrban, WorldKind::kRural, WorldKind::kHighway, WorldKind::kAliased}) {
    for (const std::size_t frames : {std::size_t{100}, std::size_t{300}}) {
      INFO(world_name(kind) << " " << frames << " frames");
      const Drive d = drive_for(kind, frames, true);
      const double t_last = 0.1 * static_cast<double>(frames - 1);
      const semlio::SE3d T0 = d.ego.pose(0.0);
      const semlio::SE3d T1 = d.ego.pose(t_last);
      const double end_m = (T1.translation() - T0.translation()).norm();
      double max_m = 0.0;
      double max_speed = 0.0;
      for (std::size_t i = 0; i < frames; ++i) {
        const double t = 0.1 * static_cast<double>(i);
        max_m = std::max(max_m, (d.ego.pose(t).translation() - T0.translation()).norm());
        max_speed = std::max(max_speed, d.ego.velocity_world_mps(t).norm());
      }
      CHECK(!d.world.revisit_route.empty());
      CHECK(std::abs(d.world.return_error_m) < 0.5);
      CHECK(end_m < 2.0);                                  // back at the start ...
      CHECK(angle_diff(yaw_of(T1), yaw_of(T0)) < 0.12);    // ... heading the same way (< 7 deg)
      CHECK(max_m > 8.0);                                  // after really leaving it
      CHECK(max_m > 10.0 * end_m);
      CHECK(d.ego.arclength_m(t_last) > 30.0);
      // Still moving at the return (passes its start), at a realistic speed.
      CHECK(d.ego.velocity_world_mps(t_last).norm() > 1.0);
      CHECK(max_speed <= d.world.ego_motion.cruise_speed_mps + 0.1);
    }
  }
}

TEST_CASE("revisit: the return pass sees the same place from the same pose", "[sim]") {
  // 300 frames of urban: the last frame's lidar pose equals the first one's
  // within decimetres and degrees, so the same structure is in view.
  const Drive d = drive_for(WorldKind::kUrban, 300, true);
  const semlio::SE3d rel = d.ego.pose(0.0).inverse() * d.ego.pose(29.9);
  CHECK(rel.translation().norm() < 0.3);
  CHECK(rel.so3().log().norm() < 0.05);
}

TEST_CASE("open drives of 100 and 300 frames do not come back", "[sim]") {
  for (const WorldKind kind : {WorldKind::kUrban, WorldKind::kRural, WorldKind::kHighway, WorldKind::kAliased}) {
    for (const std::size_t frames : {std::size_t{100}, std::size_t{300}}) {
      INFO(world_name(kind) << " " << frames << " frames");
      const Drive d = drive_for(kind, frames, false);
      CHECK(d.world.revisit_route.empty());
      CHECK(d.world.loop_length_m == 0.0);
      const double t_last = 0.1 * static_cast<double>(frames - 1);
      const Eigen::Vector3d p0 = d.ego.pose(0.0).translation();
      double closest_late = 1e9;  // closest approach to the start in the second half
      for (std::size_t i = frames / 2; i < frames; ++i) {
        closest_late = std::min(closest_late, (d.ego.pose(0.1 * static_cast<double>(i)).translation() - p0).norm());
      }
      CHECK(closest_late > 25.0);  // a revisit drive ends within 2 m
      CHECK((d.ego.pose(t_last).translation() - p0).norm() > 0.5 * d.ego.arclength_m(t_last));
    }
  }
}

TEST_CASE("revisit routes are deterministic and long drives use block loops", "[sim]") {
  const Drive a = drive_for(WorldKind::kRural, 300, true);
  const Drive b = drive_for(WorldKind::kRural, 300, true);
  CHECK(a.world.ego_route == b.world.ego_route);
  // 1000 urban frames: a block loop of streets (turns, stops), closed.
  const Drive u = drive_for(WorldKind::kUrban, 1000, true);
  CHECK(u.world.revisit_route == "block_loop");
  CHECK(u.world.loop_length_m > 300.0);
  CHECK((u.ego.pose(99.9).translation() - u.ego.pose(0.0).translation()).norm() < 1.0);
  CHECK(!u.world.ego_stop_points.empty());
}

TEST_CASE("revisit traffic never drives into the ego, the lidar stays clear", "[sim]") {
  for (const WorldKind kind : {WorldKind::kUrban, WorldKind::kRural, WorldKind::kHighway}) {
    INFO(world_name(kind));
    SimulatorConfig c;
    c.world = kind;
    c.frames = 300;
    c.revisit = true;
    c.traffic = TrafficLevel::kHeavy;
    const Simulator sim(c);
    REQUIRE(!sim.traffic().actors().empty());
    double closest = 1e9;
    for (std::size_t i = 0; i < c.frames; i += 2) {
      const double t = sim.frame_stamp_s(i);
      const Eigen::Vector3d ego = sim.ego().pose(t).translation();
      for (std::size_t k = 0; k < sim.traffic().actors().size(); ++k) {
        closest = std::min(closest, (sim.traffic().actor_pose(k, t).translation() - ego).norm());
      }
    }
    CHECK(closest > 3.0);
    // Nothing (actor, rail, tree) comes within 1.5 m of the lidar, at the
    // start, on the way and in a U-turn.
    for (const std::size_t i : {std::size_t{0}, std::size_t{75}, std::size_t{150}}) {
      const Frame f = sim.frame(i);
      REQUIRE(f.scan.size() > 50000);
      float min_range = 1e9F;
      for (const Eigen::Vector3f& p : f.scan.points) min_range = std::min(min_range, p.norm());
      CHECK(min_range > 1.5F);
    }
  }
}

TEST_CASE("out-and-back loops are closed and fit by regula falsi", "[sim]") {
  const detail::StadiumShape shape{.lane_m = 1.5, .turn_radius_m = 4.0, .swing_m = 10.0};
  const auto lap = detail::stadium_lap(20.0, shape);
  REQUIRE(lap.size() > 20);
  CHECK((lap.front() - lap.back()).norm() < 1e-9);
  CHECK(lap.front().y() == Approx(-1.5));
  double min_l = 0.0;
  double max_u = 0.0;
  for (const auto& q : lap) {
    min_l = std::min(min_l, q.y());
    max_u = std::max(max_u, q.x());
  }
  CHECK(min_l == Approx(-4.0).margin(0.05));  // swings out to the U-turn radius
  CHECK(max_u == Approx(34.0).margin(0.05));  // straight + swing + radius
  // A linear closure is solved exactly; one without a sign change is not ok.
  const auto fit = detail::fit_revisit([](double x) { return 2.0 * x - 3.0; }, 0.0, 10.0, 0.01);
  CHECK(fit.ok);
  CHECK(fit.param == Approx(1.5).margin(0.01));
  CHECK_FALSE(detail::fit_revisit([](double x) { return x + 1.0; }, 0.0, 10.0, 0.01).ok);
}

}  // namespace test_revisit
