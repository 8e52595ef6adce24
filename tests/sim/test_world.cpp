// Procedural worlds: determinism, routes, content.
#include <catch2/catch.hpp>

#include <algorithm>
#include <set>

#include <semlio/core/labels.hpp>
#include <semlio/sim/world.hpp>

namespace test_world {  // one namespace per test file: the area compiles as one TU

using namespace semlio::sim;

namespace {
std::set<std::uint16_t> raw_ids(const World& w) {
  std::set<std::uint16_t> ids;
  for (const auto& p : w.bvh.primitives()) ids.insert(p.surface.raw_label);
  return ids;
}
double route_length(const World& w) {
  double len = 0.0;
  for (std::size_t i = 1; i < w.ego_route.size(); ++i) len += (w.ego_route[i] - w.ego_route[i - 1]).norm();
  return len;
}
}  // namespace

TEST_CASE("urban world: every class of a city street, long enough route, deterministic", "[sim]") {
  WorldConfig c;
  c.drive_length_m = 800.0;
  const World w = make_world(c);
  const auto ids = raw_ids(w);
  for (const std::uint16_t id : {raw::kRoad, raw::kParking, raw::kSidewalk, raw::kBuilding, raw::kFence,
                                 raw::kVegetation, raw::kTrunk, raw::kTerrain, raw::kPole, raw::kTrafficSign,
                                 raw::kCar, raw::kLaneMarking}) {
    CHECK(ids.count(id) == 1);
  }
  CHECK(route_length(w) >= 1.3 * c.drive_length_m);
  CHECK(!w.lanes.walkways.empty());
  // Objects carry instance ids, ground stuff does not.
  for (const auto& p : w.bvh.primitives()) {
    if (p.surface.raw_label == raw::kCar || p.surface.raw_label == raw::kBuilding) CHECK(p.surface.instance > 0);
    if (p.surface.raw_label == raw::kRoad) CHECK(p.surface.instance == 0);
  }
  const World again = make_world(c);
  REQUIRE(again.bvh.primitives().size() == w.bvh.primitives().size());
  CHECK(again.ego_route == w.ego_route);
  c.seed = 2;
  CHECK(make_world(c).ego_route != w.ego_route);
}

TEST_CASE("revisit routes are loops that return to their start", "[sim]") {
  for (const WorldKind kind : {WorldKind::kUrban, WorldKind::kRural, WorldKind::kHighway}) {
    WorldConfig c;
    c.kind = kind;
    c.revisit = true;
    c.drive_length_m = 600.0;  // return time: drive length / typical speed
    const World w = make_world(c);
    REQUIRE(w.loop_length_m > 0.0);
    CHECK(w.return_time_s > 0.0);
    CHECK(std::abs(w.return_error_m) < 0.5);
    // Some later route point coincides with the start (the loop closes).
    double closest = 1e9;
    double along = 0.0;
    for (std::size_t i = 1; i < w.ego_route.size(); ++i) {
      along += (w.ego_route[i] - w.ego_route[i - 1]).norm();
      if (along > 0.5 * w.loop_length_m) closest = std::min(closest, (w.ego_route[i] - w.ego_route[0]).norm());
    }
    CHECK(closest < 1.0);
  }
}

TEST_CASE("rural world has hills of tens of metres, highway has guard rails", "[sim]") {
  WorldConfig c;
  c.kind = WorldKind::kRural;
  c.drive_length_m = 1500.0;
  const World rural = make_world(c);
  double zmin = 1e9;
  double zmax = -1e9;
  for (const auto& p : rural.ego_route) {
    zmin = std::min(zmin, p.z());
    zmax = std::max(zmax, p.z());
  }
  CHECK(zmax - zmin > 10.0);
  const auto rids = raw_ids(rural);
  CHECK(rids.count(raw::kTerrain) == 1);
  CHECK(rids.count(raw::kTrunk) == 1);
  CHECK(rids.count(raw::kVegetation) == 1);

  c.kind = WorldKind::kHighway;
  const World hw = make_world(c);
  const auto hids = raw_ids(hw);
  CHECK(hids.count(raw::kFence) == 1);
  CHECK(hids.count(raw::kBuilding) == 0);
  // Straight: the route heading barely changes.
  const Eigen::Vector3d d0 = (hw.ego_route[10] - hw.ego_route[0]).normalized();
  const Eigen::Vector3d d1 = (hw.ego_route[300] - hw.ego_route[290]).normalized();
  CHECK(d0.dot(d1) > 0.99);
}

TEST_CASE("aliased world repeats identical blocks", "[sim]") {
  WorldConfig c;
  c.kind = WorldKind::kAliased;
  const World w = make_world(c);
  // Count buildings: every block has the same set, so the count is a multiple of 64.
  std::size_t buildings = 0;
  for (const auto& p : w.bvh.primitives()) buildings += p.surface.raw_label == raw::kBuilding ? 1U : 0U;
  CHECK(buildings > 0);
  CHECK(buildings % 64 == 0);
  CHECK_THROWS_WITH(parse_world("moon"), Catch::Contains("moon"));
}

}  // namespace test_world
