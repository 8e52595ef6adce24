// In-memory frames: counts, rings, labels, determinism, motion distortion.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>

#include <semlio/sim/simulator.hpp>

namespace test_simulator {  // one namespace per test file: the area compiles as one TU

using namespace semlio::sim;
using semlio::Class;
using semlio::SE3d;

namespace {
SimulatorConfig small_config() {
  SimulatorConfig c;
  c.frames = 30;
  c.traffic = TrafficLevel::kNone;
  return c;
}
bool same_bytes(const Frame& a, const Frame& b) {
  return a.scan.size() == b.scan.size() &&
         std::memcmp(a.scan.points.data(), b.scan.points.data(), a.scan.size() * sizeof(Eigen::Vector3f)) == 0 &&
         a.scan.intensity == b.scan.intensity && a.raw_labels == b.raw_labels && a.scan.times_s == b.scan.times_s;
}
}  // namespace

TEST_CASE("urban frame: point count, rings, elevations and times as configured", "[sim]") {
  const Simulator sim(small_config());
  const Frame f = sim.frame(5);
  f.scan.validate();
  CHECK(f.scan.size() > 95000);   // ~64 x 2160 rays minus sky, self-occlusion and dropouts
  CHECK(f.scan.size() < 64U * 2160U);
  std::array<int, 64> per_ring{};
  for (std::size_t i = 0; i < f.scan.size(); ++i) {
    const int r = f.scan.rings[i];
    REQUIRE(r < 64);
    ++per_ring[static_cast<std::size_t>(r)];
    const Eigen::Vector3f& p = f.scan.points[i];
    // Range noise acts along the beam, so the elevation is the beam's.
    const double el = std::atan2(static_cast<double>(p.z()), std::hypot(static_cast<double>(p.x()), static_cast<double>(p.y())));
    CHECK(std::abs(el - sim.lidar().elevation_rad(r)) < 1e-5);
    CHECK(f.scan.times_s[i] >= 0.0F);
    CHECK(f.scan.times_s[i] < 0.1F);
  }
  for (const int n : per_ring) CHECK(n > 200);
  CHECK(f.scan.stamp_s == Approx(0.5));
  // First point: top ring, straight ahead (KITTI's .bin order).
  CHECK(f.scan.rings.front() == 63);
  CHECK(f.scan.rings.back() == 0);
  // The lidar rides 1.73 m above the flat street.
  CHECK(f.T_world_lidar.translation().z() == Approx(1.73).margin(1e-6));
}

TEST_CASE("urban labels: classes present in plausible proportions, instances on objects", "[sim]") {
  SimulatorConfig c = small_config();
  c.traffic = TrafficLevel::kLight;
  const Simulator sim(c);
  std::array<double, 20> frac{};
  double total = 0.0;
  for (const std::size_t i : {0U, 15U, 29U}) {
    const Frame f = sim.frame(i);
    const auto h = semlio::label_histogram(f.scan);
    for (std::size_t k = 0; k < 20; ++k) frac[k] += h[k];
    total += static_cast<double>(f.scan.size());
    for (std::size_t p = 0; p < f.scan.size(); ++p) {
      if (f.scan.labels[p] == Class::kCar || f.scan.labels[p] == Class::kBuilding) CHECK(f.scan.instances[p] > 0);
      CHECK((f.raw_labels[p] >> 16U) == f.scan.instances[p]);
    }
  }
  for (double& v : frac) v /= total;
  const auto at = [&](Class k) { return frac[static_cast<std::size_t>(semlio::index(k))]; };
  CHECK(at(Class::kUnlabeled) == 0.0);  // every surface has a class
  CHECK(at(Class::kRoad) + at(Class::kParking) + at(Class::kSidewalk) > 0.30);
  CHECK(at(Class::kRoad) > 0.15);
  CHECK(at(Class::kBuilding) > 0.04);
  CHECK(at(Class::kVegetation) > 0.01);
  CHECK(at(Class::kCar) > 0.01);
  CHECK(at(Class::kPole) > 0.0005);
  CHECK(at(Class::kCar) < 0.5);
}

TEST_CASE("same seed, same bytes, thread count does not change the output", "[sim]") {
  SimulatorConfig c = small_config();
  c.traffic = TrafficLevel::kHeavy;
  const Simulator a(c);
  const Simulator b(c);
  c.threads = 2;
  const Simulator threaded(c);
  const Frame fa = a.frame(7);
  CHECK(same_bytes(fa, b.frame(7)));
  CHECK(same_bytes(fa, threaded.frame(7)));
  c.seed = 9;
  CHECK_FALSE(same_bytes(fa, Simulator(c).frame(7)));
}

TEST_CASE("distortion on/off differ exactly by the motion within the sweep", "[sim]") {
  SimulatorConfig c = small_config();
  c.lidar.noise = false;
  const Simulator off(c);
  c.distortion = true;
  const Simulator on(c);
  const std::size_t i = 12;
  const Frame f_off = off.frame(i);
  const Frame f_on = on.frame(i);
  const double stamp = f_on.scan.stamp_s;
  // Every point is the exact cast from the pose at its own time (on) or at the
  // sweep start (off), expressed in that pose's lidar frame.
  const auto recast_range = [&](const Simulator& sim, const SE3d& T, const Eigen::Vector3f& p) {
    const Eigen::Vector3d d = p.cast<double>().normalized();
    const Ray ray = Ray::make(T.translation(), T.rotation() * d);
    Hit hit;
    REQUIRE(sim.world().bvh.cast(ray, 0.0, 200.0, hit));
    return hit.t_m;
  };
  double max_diff = 0.0;
  for (std::size_t k = 0; k < f_on.scan.size(); k += 97) {
    const Eigen::Vector3f& p = f_on.scan.points[k];
    const SE3d T_t = on.T_world_lidar(stamp + static_cast<double>(f_on.scan.times_s[k]));
    CHECK(recast_range(on, T_t, p) == Approx(static_cast<double>(p.norm())).margin(1e-4));
  }
  for (std::size_t k = 0; k < f_off.scan.size(); k += 97) {
    const Eigen::Vector3f& p = f_off.scan.points[k];
    CHECK(recast_range(off, f_off.T_world_lidar, p) == Approx(static_cast<double>(p.norm())).margin(1e-4));
  }
  // Same cells: identical at the sweep start (column 0), different later.
  REQUIRE(f_on.scan.size() > 1000);
  const auto cols = static_cast<std::size_t>(on.lidar().columns());
  std::vector<long> off_index(64 * cols, -1);
  for (std::size_t k = 0; k < f_off.scan.size(); ++k) {
    off_index[f_off.scan.rings[k] * cols + f_off.columns[k]] = static_cast<long>(k);
  }
  std::size_t same_col0 = 0;
  for (std::size_t k = 0; k < f_on.scan.size(); ++k) {
    const long j = off_index[f_on.scan.rings[k] * cols + f_on.columns[k]];
    if (j < 0) continue;
    const double d = static_cast<double>((f_off.scan.points[static_cast<std::size_t>(j)] - f_on.scan.points[k]).norm());
    if (f_on.columns[k] == 0) {
      CHECK(d == 0.0);
      ++same_col0;
    }
    max_diff = std::max(max_diff, d);
  }
  CHECK(same_col0 > 10);
  const double moved = (on.T_world_lidar(stamp + 0.1).translation() - on.T_world_lidar(stamp).translation()).norm();
  REQUIRE(moved > 0.3);
  CHECK(max_diff > 0.1);
}

TEST_CASE("simulator rejects bad configs naming the field", "[sim]") {
  SimulatorConfig c = small_config();
  c.frames = 0;
  CHECK_THROWS_WITH(Simulator(c), Catch::Contains("frames"));
  c = small_config();
  c.label_quality = 1.5;
  CHECK_THROWS_WITH(Simulator(c), Catch::Contains("label_quality"));
  const Simulator sim(small_config());
  CHECK_THROWS_WITH(sim.frame(30), Catch::Contains("30"));
}

TEST_CASE("long urban drives and revisit drives come back to their start", "[sim]") {
  const auto first_return = [](const SimulatorConfig& c) {
    const Simulator sim(c);
    const Eigen::Vector3d p0 = sim.T_world_lidar(0.0).translation();
    double driven = 0.0;
    Eigen::Vector3d prev = p0;
    for (std::size_t i = 1; i < c.frames; ++i) {
      const Eigen::Vector3d p = sim.T_world_lidar(sim.frame_stamp_s(i)).translation();
      driven += (p - prev).norm();
      prev = p;
      if (driven > 100.0 && (p - p0).norm() < 10.0) return static_cast<long>(i);
    }
    return -1L;
  };
  SimulatorConfig c;
  c.traffic = TrafficLevel::kNone;
  c.frames = 1500;  // open urban route: its first loop closes before ~1500 frames
  CHECK(first_return(c) > 0);
  c.frames = 800;
  c.revisit = true;
  CHECK(first_return(c) > 0);
  c.world = WorldKind::kRural;
  c.frames = 700;
  CHECK(first_return(c) > 0);
  c.revisit = false;
  CHECK(first_return(c) < 0);  // open rural road never returns
}

TEST_CASE("in-memory ground truth and IMU match the trajectory", "[sim]") {
  const Simulator sim(small_config());
  const auto poses = sim.lidar_poses();
  REQUIRE(poses.size() == 30);
  CHECK(poses[0].translation().norm() < 1e-12);
  const SE3d expected = sim.frame(10).T_world_lidar;
  const SE3d T0 = sim.T_world_lidar(0.0);
  CHECK(((T0 * poses[10]).translation() - expected.translation()).norm() < 1e-9);
  ImuConfig ic;
  ic.noise = false;
  const auto imu = sim.imu(ic);
  REQUIRE(imu.samples.size() == 301);  // 3 s at 100 Hz, both ends
  // Driving on a flat street: specific force is about +g up, yaw rate small on straights.
  CHECK(imu.samples[150].accel_mps2.z() == Approx(9.80665).margin(0.3));
}

}  // namespace test_simulator
