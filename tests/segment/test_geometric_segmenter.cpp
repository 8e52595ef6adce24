#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/eval/miou.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/segment/detail/fast_atan2.hpp>
#include <semlio/segment/geometric_segmenter.hpp>
#include <semlio/sim/simulator.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/segment_scene.hpp>

namespace test_geometric_segmenter {  // one namespace per test file: the area compiles as one TU

using semlio::Class;

namespace {

bool is_ground(Class c) {
  return c == Class::kRoad || c == Class::kParking || c == Class::kSidewalk || c == Class::kOtherGround ||
         c == Class::kTerrain;
}

// IoU of a group of classes taken as one (truth and prediction both mapped).
double group_iou(const std::vector<Class>& truth, const std::vector<Class>& pred, std::initializer_list<Class> group) {
  const auto in = [&](Class c) {
    for (const Class g : group) {
      if (g == c) return true;
    }
    return false;
  };
  std::size_t tp = 0, fp = 0, fn = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (truth[i] == Class::kUnlabeled) continue;
    const bool t = in(truth[i]);
    const bool p = in(pred[i]);
    tp += (t && p) ? 1U : 0U;
    fn += (t && !p) ? 1U : 0U;
    fp += (!t && p) ? 1U : 0U;
  }
  const std::size_t d = tp + fp + fn;
  return d == 0 ? 0.0 : static_cast<double>(tp) / static_cast<double>(d);
}

// Classes a SemanticKITTI label is compatible with for the 50-point sanity check.
bool compatible(Class truth, Class pred) {
  if (is_ground(truth)) return is_ground(pred);
  if (truth == Class::kTrunk || truth == Class::kPole) return pred == Class::kTrunk || pred == Class::kPole;
  return truth == pred;
}

}  // namespace

TEST_CASE("fast_atan2 matches std::atan2", "[segment]") {
  double worst = 0.0;
  for (int i = 0; i < 3600; ++i) {
    const double a = -3.14159 + 6.28318 * i / 3600.0;
    for (const double r : {0.01, 1.0, 100.0}) {
      const auto x = static_cast<float>(r * std::cos(a));
      const auto y = static_cast<float>(r * std::sin(a));
      const double err = std::abs(static_cast<double>(semlio::detail::fast_atan2(y, x)) - std::atan2(static_cast<double>(y), static_cast<double>(x)));
      worst = std::max(worst, std::min(err, 2.0 * 3.14159265358979 - err));
    }
  }
  CHECK(worst < 2.5e-4);  // far below the 1 deg (0.017 rad) sectors
  CHECK(semlio::detail::fast_atan2(0.0F, 0.0F) == 0.0F);
}

TEST_CASE("GeometricSegmenter labels a synthetic street scene", "[segment]") {
  semlio::Scan scan = semlio_test::segment_scene();
  const std::vector<Class> truth = scan.labels;
  REQUIRE(scan.size() > 30000);
  const semlio::GeometricSegmenter seg;
  seg.segment(scan);
  REQUIRE(scan.labels.size() == scan.points.size());
  // Documented lower bounds for this scene (README: segmenter quality).
  CHECK(group_iou(truth, scan.labels, {Class::kRoad, Class::kSidewalk, Class::kTerrain}) > 0.95);
  CHECK(group_iou(truth, scan.labels, {Class::kBuilding}) > 0.85);
  CHECK(group_iou(truth, scan.labels, {Class::kCar}) > 0.8);
  CHECK(group_iou(truth, scan.labels, {Class::kVegetation}) > 0.6);
  CHECK(group_iou(truth, scan.labels, {Class::kPole, Class::kTrunk}) > 0.5);
  // The flat road with no curb is road, not sidewalk or terrain.
  std::size_t road = 0, ground = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (truth[i] != Class::kRoad) continue;
    ++ground;
    road += scan.labels[i] == Class::kRoad ? 1U : 0U;
  }
  CHECK(static_cast<double>(road) > 0.95 * static_cast<double>(ground));
}

TEST_CASE("GeometricSegmenter split_ground=false labels all ground as road", "[segment]") {
  semlio::Scan a = semlio_test::segment_scene(600);
  // Raise part of the scene's ground by a curb: points beyond y = 10 m.
  for (auto& p : a.points) {
    if (p.y() > 10.0F && p.z() < -1.7F) p.z() += 0.15F;
  }
  semlio::Scan b = a;
  semlio::GeometricSegmenter(semlio::GeometricSegmenterConfig{.split_ground = false}).segment(a);
  semlio::GeometricSegmenter().segment(b);
  std::size_t sidewalk_a = 0, sidewalk_b = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(a.labels[i] != Class::kSidewalk);
    CHECK(a.labels[i] != Class::kTerrain);
    sidewalk_a += a.labels[i] == Class::kSidewalk ? 1U : 0U;
    sidewalk_b += b.labels[i] == Class::kSidewalk ? 1U : 0U;
  }
  CHECK(sidewalk_a == 0);
  CHECK(sidewalk_b > 500);  // the raised side is found behind the curb
}

TEST_CASE("GeometricSegmenter is deterministic and reusable", "[segment]") {
  semlio::Scan scan = semlio_test::segment_scene(800);
  semlio::Scan other = semlio_test::segment_scene(500);
  const semlio::GeometricSegmenter seg;
  semlio::Scan a = scan;
  seg.segment(a);
  seg.segment(other);  // a different scan in between must not leak state
  semlio::Scan b = scan;
  seg.segment(b);
  semlio::Scan c = scan;
  semlio::GeometricSegmenter().segment(c);
  CHECK(a.labels == b.labels);
  CHECK(a.labels == c.labels);
}

TEST_CASE("GeometricSegmenter handles degenerate scans", "[segment]") {
  const semlio::GeometricSegmenter seg;
  SECTION("empty scan") {
    semlio::Scan s;
    seg.segment(s);
    CHECK(s.labels.empty());
  }
  SECTION("stale labels of another size are replaced") {
    semlio::Scan s;
    s.points.assign(3, Eigen::Vector3f(5.0F, 0.0F, -1.73F));
    s.labels.assign(7, Class::kCar);
    seg.segment(s);
    CHECK(s.labels.size() == 3);
  }
  SECTION("all points in one spot") {
    for (const Eigen::Vector3f& p : {Eigen::Vector3f(0.0F, 0.0F, 0.0F), Eigen::Vector3f(5.0F, 0.0F, -1.73F),
                                    Eigen::Vector3f(5.0F, 0.0F, 3.0F)}) {
      semlio::Scan s;
      s.points.assign(5000, p);
      seg.segment(s);
      REQUIRE(s.labels.size() == 5000);
      for (const Class c : s.labels) CHECK(c == s.labels.front());
      CHECK(semlio::index(s.labels.front()) < semlio::kNumClasses);
    }
  }
  SECTION("non-finite and far points") {
    semlio::Scan s = semlio_test::segment_scene(300);
    const std::size_t n = s.size();
    s.points.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0F, 0.0F);
    s.points.emplace_back(std::numeric_limits<float>::infinity(), 1.0F, 0.0F);
    s.points.emplace_back(5000.0F, -3000.0F, 10.0F);
    s.points.emplace_back(0.0F, 0.0F, -1e6F);
    s.labels.clear();
    seg.segment(s);
    REQUIRE(s.labels.size() == n + 4);
    CHECK(s.labels[n] == Class::kUnlabeled);
    CHECK(s.labels[n + 1] == Class::kUnlabeled);
    for (const Class c : s.labels) CHECK(semlio::index(c) < semlio::kNumClasses);
  }
}

// Flat ground around the sensor and an 8 m long vertical surface 10 m ahead,
// 0.3-3.5 m above the ground (tall, too long for a car or truck): a planar
// wall, or the same footprint with a rough face (points spread uniformly over 0.6 m in depth, std 0.17 m, as foliage).
namespace {
semlio::Scan wall_scene(bool rough) {
  semlio::Scan scan;
  const float ground_z = -static_cast<float>(semlio_test::kSceneSensorHeight);
  for (float x = -9.0F; x <= 9.5F; x += 0.2F) {
    for (float y = -9.0F; y <= 9.0F; y += 0.2F) {
      if (std::hypot(x, y) > 2.0F) scan.points.emplace_back(x, y, ground_z);
    }
  }
  std::uint32_t state = 12345U;
  for (float y = -4.0F; y <= 4.0F; y += 0.05F) {
    for (float h = 0.3F; h <= 3.5F; h += 0.1F) {
      state = state * 1664525U + 1013904223U;  // LCG: a fixed pseudo-random depth
      const float depth = rough ? 0.6F * static_cast<float>(state >> 8) / 16777216.0F : 0.0F;
      scan.points.emplace_back(10.0F + depth, y, ground_z + h);
    }
  }
  return scan;
}
}  // namespace

TEST_CASE("GeometricSegmenter tells a planar wall from a rough hedge of the same shape", "[segment]") {
  const semlio::GeometricSegmenter seg;
  for (const bool rough : {false, true}) {
    semlio::Scan scan = wall_scene(rough);
    seg.segment(scan);
    std::size_t n = 0, building = 0, vegetation = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (scan.points[i].x() < 9.9F) continue;
      ++n;
      building += scan.labels[i] == Class::kBuilding ? 1U : 0U;
      vegetation += scan.labels[i] == Class::kVegetation ? 1U : 0U;
    }
    INFO("rough " << rough << ": " << n << " points, " << building << " building, " << vegetation << " vegetation");
    REQUIRE(n > 2000);
    if (rough) {
      CHECK(vegetation > 9 * n / 10);
    } else {
      CHECK(building > 9 * n / 10);
    }
  }
}

TEST_CASE("GeometricSegmenter finds a pole standing in a bush", "[segment]") {
  // Flat ground, a 1.6 m x 1.6 m bush 0.2-0.9 m high 8 m ahead and a 4 m
  // pole (0.1 m thick) in a gap in its middle: one group of ground-standing
  // cells too wide for a column.
  semlio::Scan scan;
  const float ground_z = -static_cast<float>(semlio_test::kSceneSensorHeight);
  for (float x = -9.0F; x <= 9.5F; x += 0.2F) {
    for (float y = -9.0F; y <= 9.0F; y += 0.2F) {
      if (std::hypot(x, y) > 2.0F) scan.points.emplace_back(x, y, ground_z);
    }
  }
  for (float x = 7.2F; x <= 8.8F; x += 0.1F) {
    for (float y = -0.8F; y <= 0.8F; y += 0.1F) {
      // Not in the pole's own grid cells (x 7.6-8.0, y -0.4-0.4): bush points
      // there would widen the column past a pole's width (it would be a trunk).
      if (std::fabs(x - 8.0F) < 0.45F && std::fabs(y) < 0.45F) continue;
      for (float h = 0.2F; h <= 0.9F; h += 0.1F) scan.points.emplace_back(x, y, ground_z + h);
    }
  }
  const std::size_t pole_begin = scan.points.size();
  for (float h = 0.2F; h <= 4.0F; h += 0.05F) {
    for (const float y : {-0.05F, 0.0F, 0.05F}) scan.points.emplace_back(7.95F, y, ground_z + h);
  }
  const std::size_t pole_end = scan.points.size();
  const semlio::GeometricSegmenter seg;
  seg.segment(scan);
  std::size_t pole = 0;
  for (std::size_t i = pole_begin; i < pole_end; ++i) pole += scan.labels[i] == Class::kPole ? 1U : 0U;
  CHECK(pole > 9 * (pole_end - pole_begin) / 10);
  // The bush away from the pole stays vegetation.
  std::size_t bush = 0, bush_veg = 0;
  for (std::size_t i = 0; i < pole_begin; ++i) {
    const Eigen::Vector3f& q = scan.points[i];
    if (q.z() < ground_z + 0.3F || q.x() < 7.0F) continue;
    ++bush;
    bush_veg += scan.labels[i] == Class::kVegetation ? 1U : 0U;
  }
  REQUIRE(bush > 500);
  CHECK(bush_veg > 9 * bush / 10);
}

namespace {
// Ground sampled on a 0.2 m grid from 3.7 m out (an HDL-64E 1.73 m up
// meets the ground no nearer) to `reach_m` in x and y (y only up to
// `side_m` off the street's edges); points with y below `kerb_right_y` or
// above `kerb_left_y` are raised by `kerb_m` (sidewalks). The road falls
// away from y = 0 by `cross_fall` (rise over run) to both sides (a crowned
// road) and rises ahead by `grade`; the sidewalks start from the road's
// height at their kerbs.
void add_ground(semlio::Scan& scan, float reach_m, float kerb_right_y = -1e9F, float kerb_left_y = 1e9F,
                float kerb_m = 0.0F, float side_m = 1e9F, float cross_fall = 0.0F, float grade = 0.0F) {
  const float ground_z = -static_cast<float>(semlio_test::kSceneSensorHeight);
  for (float x = -reach_m; x <= reach_m; x += 0.2F) {
    for (float y = -reach_m; y <= reach_m; y += 0.2F) {
      if (y < kerb_right_y - side_m || y > kerb_left_y + side_m) continue;
      if (std::hypot(x, y) < 3.7F) continue;
      const bool raised = y < kerb_right_y || y > kerb_left_y;
      const float road_y = std::clamp(y, kerb_right_y, kerb_left_y);  // the road's edge under a sidewalk
      scan.points.emplace_back(x, y, ground_z - cross_fall * std::fabs(road_y) + grade * x + (raised ? kerb_m : 0.0F));
      scan.labels.push_back(raised ? Class::kSidewalk : Class::kRoad);
    }
  }
}
}  // namespace

TEST_CASE("GeometricSegmenter finds the sidewalk beside a vehicle driving close to the kerb", "[segment]") {
  // A 7 m wide street with 0.15 m kerbs (kerbs are 0.10-0.20 m): the vehicle
  // drives 2.8 m from the right kerb, so its lowest ring (3.7 m out) meets
  // only sidewalk to its right. The road ahead and behind sets the road
  // height; an all-round ground fit would sit between road and sidewalk and
  // shrink the step below curb_min_m.
  // Sidewalks 4 m wide; counted: the points beside the vehicle (|x| <= 4 m)
  // up to 2 m behind the kerbs, and the road between them.
  // With a crowned road (3 % cross fall each way, as on the real KITTI 00
  // street), a plane through the lane misses the road's edges by 0.08-0.13 m
  // and the sidewalks stand only 0.02-0.07 m above it: the walk outwards
  // takes them for road; the kerbs crossed along the nearest rings find them.
  // On a street that climbs or falls (1 %), a ring beside the vehicle meets
  // the road at its two kerb crossings 0.1 m apart in height: coming down the
  // far kerb it is back at road height only as the lane's grade says, and
  // otherwise stays "raised" across the road ahead of the vehicle.
  const float cross_fall = GENERATE(0.0F, 0.03F);
  const float grade = GENERATE(0.0F, 0.01F, -0.01F);
  semlio::Scan scan;
  add_ground(scan, 14.0F, -2.8F, 4.2F, 0.15F, 4.0F, cross_fall, grade);
  const std::vector<Class> truth = scan.labels;
  semlio::GeometricSegmenter().segment(scan);
  std::size_t sidewalk = 0, sidewalk_ok = 0, road = 0, road_ok = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const Eigen::Vector3f& q = scan.points[i];
    if (std::fabs(q.x()) > 4.0F || q.y() < -4.8F || q.y() > 6.2F) continue;
    if (truth[i] == Class::kSidewalk) {
      ++sidewalk;
      sidewalk_ok += scan.labels[i] == Class::kSidewalk ? 1U : 0U;
    } else {
      ++road;
      road_ok += scan.labels[i] == Class::kRoad ? 1U : 0U;
    }
  }
  INFO("cross fall " << cross_fall << ", grade " << grade << ": " << sidewalk_ok << " / " << sidewalk << " sidewalk, " << road_ok << " / " << road
                     << " road");
  REQUIRE(sidewalk > 300);
  REQUIRE(road > 300);
  CHECK(sidewalk_ok > 9 * sidewalk / 10);
  CHECK(road_ok > 9 * road / 10);
}

namespace {
// Flat ground and, 10 m ahead, a 0.08 m sign post up to 2.2 m with (when
// `panel`) a 0.6 m x 0.6 m panel facing the sensor on top (2.2-2.8 m), or
// (when `crown`) a rough 1.2 m crown of a young tree instead (points spread
// over 0.6 m in depth). Labels: kPole post, kTrafficSign panel, kVegetation crown.
semlio::Scan sign_scene(bool panel, bool crown) {
  semlio::Scan scan;
  add_ground(scan, 14.0F);
  const float ground_z = -static_cast<float>(semlio_test::kSceneSensorHeight);
  for (float h = 0.1F; h <= 2.2F; h += 0.05F) {
    for (const float y : {-0.04F, 0.0F, 0.04F}) {
      scan.points.emplace_back(10.0F, y, ground_z + h);
      scan.labels.push_back(Class::kPole);
    }
  }
  std::uint32_t state = 777U;
  for (float y = -0.3F; y <= 0.3F; y += 0.03F) {
    for (float h = 2.25F; h <= 2.8F; h += 0.05F) {
      if (panel) {
        scan.points.emplace_back(9.98F, y, ground_z + h);
        scan.labels.push_back(Class::kTrafficSign);
      }
      if (crown) {
        state = state * 1664525U + 1013904223U;  // LCG: a fixed pseudo-random depth
        const float depth = 0.6F * static_cast<float>(state >> 8) / 16777216.0F - 0.3F;
        scan.points.emplace_back(10.0F + depth, 2.0F * y, ground_z + h);
        scan.labels.push_back(Class::kVegetation);
      }
    }
  }
  return scan;
}
}  // namespace

TEST_CASE("GeometricSegmenter finds a sign panel on top of a post", "[segment]") {
  const semlio::GeometricSegmenter seg;
  SECTION("post with a panel: pole below a traffic sign") {
    semlio::Scan scan = sign_scene(true, false);
    const std::vector<Class> truth = scan.labels;
    seg.segment(scan);
    std::size_t panel = 0, panel_ok = 0, post = 0, post_ok = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (truth[i] == Class::kTrafficSign) {
        ++panel;
        panel_ok += scan.labels[i] == Class::kTrafficSign ? 1U : 0U;
      } else if (truth[i] == Class::kPole && scan.points[i].z() > -1.2F) {  // above the ground clutter
        ++post;
        post_ok += scan.labels[i] == Class::kPole ? 1U : 0U;
      }
    }
    INFO(panel_ok << " / " << panel << " panel, " << post_ok << " / " << post << " post");
    REQUIRE(panel > 100);
    CHECK(panel_ok > 9 * panel / 10);
    CHECK(post_ok > 8 * post / 10);
  }
  SECTION("the bare post stays a pole; a rough crown on a thin trunk is no sign") {
    for (const bool crown : {false, true}) {
      semlio::Scan scan = sign_scene(false, crown);
      seg.segment(scan);
      std::size_t signs = 0;
      for (const Class c : scan.labels) signs += c == Class::kTrafficSign ? 1U : 0U;
      INFO("crown " << crown);
      CHECK(signs == 0);
    }
  }
}

namespace {
// Flat road and, 15 m ahead on it, a rider seen from behind: the rider's back
// and rear wheel (a `width_m` wide surface from 0.1 m to `height_m`) and the
// frame behind them (0.3-0.6 m up, 1.7 m long). Label kBicyclist.
semlio::Scan rider_scene(float width_m, float height_m) {
  semlio::Scan scan;
  add_ground(scan, 20.0F);
  const float ground_z = -static_cast<float>(semlio_test::kSceneSensorHeight);
  for (float y = -0.5F * width_m; y <= 0.5F * width_m + 1e-3F; y += 0.03F) {
    for (float h = 0.1F; h <= height_m + 1e-3F; h += 0.05F) {
      scan.points.emplace_back(15.0F, y, ground_z + h);
      scan.labels.push_back(Class::kBicyclist);
    }
  }
  for (float x = 15.1F; x <= 16.7F; x += 0.05F) {
    for (float h = 0.3F; h <= 0.6F; h += 0.1F) {
      scan.points.emplace_back(x, 0.0F, ground_z + h);
      scan.labels.push_back(Class::kBicyclist);
    }
  }
  return scan;
}
}  // namespace

TEST_CASE("GeometricSegmenter finds a rider on the road", "[segment]") {
  const semlio::GeometricSegmenter seg;
  SECTION("a 0.6 m wide, 1.75 m tall rider seen from behind") {
    semlio::Scan scan = rider_scene(0.6F, 1.75F);
    const std::vector<Class> truth = scan.labels;
    seg.segment(scan);
    std::size_t rider = 0, rider_ok = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (truth[i] != Class::kBicyclist) continue;
      ++rider;
      rider_ok += scan.labels[i] == Class::kBicyclist ? 1U : 0U;
    }
    INFO(rider_ok << " / " << rider << " rider points");
    REQUIRE(rider > 500);
    CHECK(rider_ok > 9 * rider / 10);
  }
  SECTION("the configured rider class is used") {
    semlio::Scan scan = rider_scene(0.6F, 1.75F);
    semlio::GeometricSegmenter(semlio::GeometricSegmenterConfig{.rider_class = Class::kMotorcyclist}).segment(scan);
    std::size_t motorcyclist = 0;
    for (const Class c : scan.labels) motorcyclist += c == Class::kMotorcyclist ? 1U : 0U;
    CHECK(motorcyclist > 500);
  }
  SECTION("a car's 1.7 m wide rear, or a 1.4 m tall one, is no rider") {
    for (const auto& [width, height] : {std::pair{1.7F, 1.75F}, std::pair{0.6F, 1.4F}}) {
      semlio::Scan scan = rider_scene(width, height);
      seg.segment(scan);
      std::size_t riders = 0;
      for (const Class c : scan.labels) riders += c == Class::kBicyclist ? 1U : 0U;
      INFO("width " << width << " height " << height);
      CHECK(riders == 0);
    }
  }
}

TEST_CASE("GeometricSegmenter rejects bad configs", "[segment]") {
  CHECK_THROWS_AS(semlio::GeometricSegmenter(semlio::GeometricSegmenterConfig{.cell_size_m = 0.0}), semlio::ConfigError);
  CHECK_THROWS_AS(semlio::GeometricSegmenter(semlio::GeometricSegmenterConfig{.sectors = 0}), semlio::ConfigError);
  CHECK_THROWS_WITH(semlio::GeometricSegmenter(semlio::GeometricSegmenterConfig{.sensor_height_m = -1.0}),
                    Catch::Contains("sensor_height_m"));
  CHECK_NOTHROW(semlio::GeometricSegmenter(semlio::GeometricSegmenterConfig{}));
}

TEST_CASE("GeometricSegmenter on the simulator's urban world", "[segment]") {
  semlio::sim::SimulatorConfig sc;
  sc.world = semlio::sim::WorldKind::kUrban;
  sc.frames = 40;
  sc.seed = 7;
  const semlio::sim::Simulator sim(sc);
  const semlio::GeometricSegmenter seg;
  semlio::eval::ConfusionMatrix cm;
  std::vector<Class> truth_all, pred_all;
  for (const std::size_t f : {0U, 20U, 39U}) {
    semlio::sim::Frame fr = sim.frame(f);
    const std::vector<Class> truth = fr.scan.labels;
    seg.segment(fr.scan);
    cm.add(truth, fr.scan.labels);
    truth_all.insert(truth_all.end(), truth.begin(), truth.end());
    pred_all.insert(pred_all.end(), fr.scan.labels.begin(), fr.scan.labels.end());
  }
  const semlio::eval::MiouReport r = cm.report();
  // Lower bounds well below the README table (urban mIoU ~0.33 over 20 frames).
  CHECK(r.miou > 0.22);
  CHECK(r.iou[static_cast<std::size_t>(semlio::index(Class::kRoad))] > 0.7);
  CHECK(r.iou[static_cast<std::size_t>(semlio::index(Class::kBuilding))] > 0.6);
  CHECK(r.iou[static_cast<std::size_t>(semlio::index(Class::kCar))] > 0.6);
  CHECK(group_iou(truth_all, pred_all,
                  {Class::kRoad, Class::kParking, Class::kSidewalk, Class::kOtherGround, Class::kTerrain}) > 0.9);
}

TEST_CASE("GeometricSegmenter on a real KITTI scan", "[segment]") {
  semlio::Scan scan = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  REQUIRE(scan.size() > 100000);
  const semlio::GeometricSegmenter seg;
  seg.segment(scan);
  REQUIRE(scan.labels.size() == scan.size());
  std::size_t ground = 0, labelled = 0;
  for (const Class c : scan.labels) {
    ground += is_ground(c) ? 1U : 0U;
    labelled += c != Class::kUnlabeled ? 1U : 0U;
  }
  const double ground_fraction = static_cast<double>(ground) / static_cast<double>(scan.size());
  INFO("ground fraction " << ground_fraction);
  CHECK(ground_fraction > 0.35);  // KITTI urban scans: roughly 40-60 % ground
  CHECK(ground_fraction < 0.65);
  CHECK(static_cast<double>(labelled) > 0.8 * static_cast<double>(scan.size()));

  // The 50 SemanticKITTI-labelled points of this scan (they occur bit-exactly
  // in the full scan): most get a compatible class.
  const semlio::Scan subset =
      semlio::io::read_kitti_bin(semlio_test::data_path("kitti/semantickitti_subset/00/velodyne/000000.bin"));
  const std::vector<std::uint32_t> raw = semlio::io::read_label_file(
      semlio_test::data_path("kitti/semantickitti_subset/00/labels/000000.label"), subset.size());
  std::size_t found = 0, evaluated = 0, agree = 0;
  for (std::size_t k = 0; k < subset.size(); ++k) {
    const Class truth = semlio::learning_class(static_cast<std::uint16_t>(raw[k] & 0xFFFFU));
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (scan.points[i] != subset.points[k]) continue;
      ++found;
      if (truth != Class::kUnlabeled) {
        ++evaluated;
        agree += compatible(truth, scan.labels[i]) ? 1U : 0U;
      }
      break;
    }
  }
  INFO("agreement " << agree << " / " << evaluated);
  CHECK(found == subset.size());
  REQUIRE(evaluated > 40);
  CHECK(static_cast<double>(agree) >= 0.6 * static_cast<double>(evaluated));
}

}  // namespace test_geometric_segmenter
