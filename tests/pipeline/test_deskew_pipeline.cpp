// SweepDeskew, the presets' deskew slot: off is a no-op (results unchanged),
// constant velocity undoes the simulator's distorted sweeps, and on real KITTI
// raw scans the time convention of features/rings.hpp lowers the residual of
// consecutive-scan registration while the opposite spin raises it.
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/features/pca.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/imu/deskew.hpp>
#include <semlio/io/pcd.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/pipeline/registration.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>
#include <semlio/search/kdtree.hpp>
#include <semlio/segment/scan_labels.hpp>
#include <semlio/sim/simulator.hpp>
#include <semlio_test/data.hpp>

namespace test_deskew_pipeline {  // one namespace per test file: the area compiles as one TU

using semlio::DeskewMode;
using semlio::DeskewTarget;
using semlio::PointTimeSource;
using semlio::Scan;
using semlio::SE3d;
using semlio::SO3d;
using semlio::SweepDeskew;
using semlio::SweepDeskewConfig;

namespace {

std::string raw_scan(int i) {
  return semlio_test::data_path("kitti_raw/snippet_22/000000000" + std::to_string(i) + ".pcd");
}

SE3d::Vector6 twist(double vx, double vy, double wz) {
  SE3d::Vector6 xi;
  xi << vx, vy, 0.02, 0.004, -0.003, wz;
  return xi;
}

// A short simulated drive with distorted sweeps (each point in the lidar frame
// at its own firing time); coarse azimuth steps keep the test fast.
semlio::sim::Simulator distorted_drive() {
  semlio::sim::SimulatorConfig sc;
  sc.frames = 12;
  sc.traffic = semlio::sim::TrafficLevel::kNone;
  sc.distortion = true;
  sc.lidar.noise = false;
  sc.lidar.azimuth_steps = 720;
  return semlio::sim::Simulator(sc);
}

// Largest distance between the scan and the exact points in the lidar frame at
// time stamp + target_s: T(target)^-1 T(t_i) p_i, per the simulator's docs.
double worst_error(const Scan& deskewed, const Scan& raw, const semlio::sim::Simulator& sim, double target_s) {
  const SE3d T_target_world = sim.T_world_lidar(raw.stamp_s + target_s).inverse();
  double worst = 0.0;
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const Eigen::Vector3d expected =
        T_target_world * (sim.T_world_lidar(raw.stamp_s + static_cast<double>(raw.times_s[k])) *
                          raw.points[k].cast<double>());
    worst = std::max(worst, (deskewed.points[k].cast<double>() - expected).norm());
  }
  return worst;
}

// Mean point-to-plane distance of the near vertical structure of `source`
// (range < 20 m, more than 0.5 m above the road) moved by T_target_source to
// planes fitted to the 10 nearest points of `target`: how well two scans
// agree where the motion distortion shows (near objects change azimuth, so
// their points change time between scans).
double near_structure_residual(const Scan& source, const Scan& target, const SE3d& T_target_source) {
  std::vector<Eigen::Vector3f> pts;
  pts.reserve(target.size());
  for (const auto& p : target.points) {
    const float r = p.norm();
    if (r > 3.0F && r < 60.0F) pts.push_back(p);
  }
  const semlio::KdTree3f tree(pts);
  std::array<std::uint32_t, 10> idx{};
  std::array<float, 10> d2{};
  double sum = 0.0;
  std::size_t n = 0;
  for (const auto& p : source.points) {
    const float r = p.head<2>().norm();
    if (r < 3.0F || r > 20.0F || p.z() < -1.2F) continue;
    const Eigen::Vector3d q = T_target_source * p.cast<double>();
    if (tree.knn(q.cast<float>(), idx.size(), idx.data(), d2.data()) < idx.size() || d2.back() > 1.0F) continue;
    const semlio::LocalShape s = semlio::fit_local_shape(idx.size(), [&](std::size_t i) { return pts[idx[i]]; });
    if (!s.valid || s.eigenvalues(0) > 0.05 * s.eigenvalues(1)) continue;  // planar patches only
    const double e = std::abs(s.normal.dot(q - s.mean));
    if (e > 0.3) continue;
    sum += e;
    ++n;
  }
  return n == 0 ? 1e9 : sum / static_cast<double>(n);
}

}  // namespace

TEST_CASE("SweepDeskew off is a no-op and leaves the presets' poses unchanged", "[pipeline]") {
  const Scan raw = semlio::io::read_pcd(raw_scan(0));
  Scan scan = raw;
  const SweepDeskew off;
  CHECK_FALSE(off.active());
  off.deskew(scan, SE3d::exp(0.1 * twist(8.0, 0.1, 0.3)));
  CHECK(scan.points == raw.points);
  CHECK(scan.times_s.empty());

  // The presets now carry a SweepDeskew; off, the poses are bit-identical to an
  // odometry with NoDeskew.
  semlio::PipelineSettings st;
  st.odometry.kitti_vertical_correction = true;
  REQUIRE(st.deskew.mode == DeskewMode::kNone);
  auto preset = semlio::make_baseline_odometry(semlio::NoLabels{}, st);
  semlio::Odometry plain(semlio::NoLabels{}, semlio::NearestK(st.nearest),
                         semlio::LoamResiduals{semlio::preset_corner_residual(st), semlio::PointToPlane(st.plane)},
                         semlio::PoseThreshold(st.pose_threshold), st.odometry);
  for (int i = 0; i < 3; ++i) {
    Scan a = semlio::io::read_pcd(raw_scan(i));
    a.stamp_s = 0.1 * i;
    Scan b = a;
    const auto ra = preset.process(a);
    const auto rb = plain.process(b);
    CHECK(ra.status == rb.status);
    CHECK(ra.T_map_lidar.matrix() == rb.T_map_lidar.matrix());
  }
  CHECK(preset.pose().translation().norm() > 1.0);  // it did move (two ~0.8 m steps)
}

TEST_CASE("SweepDeskew undoes the simulator's distorted sweeps within 1 cm", "[pipeline]") {
  const auto sim = distorted_drive();
  const semlio::sim::Frame f = sim.frame(6);
  const Scan& raw = f.scan;
  REQUIRE(raw.has_times());
  const double stamp = raw.stamp_s;
  // Prediction = the true motion since the previous frame (0.1 s).
  const SE3d T_prev_current = sim.T_world_lidar(stamp - 0.1).inverse() * sim.T_world_lidar(stamp);
  SweepDeskewConfig c;
  c.mode = DeskewMode::kConstantVelocity;
  c.target = DeskewTarget::kStart;
  REQUIRE(worst_error(raw, raw, sim, 0.0) > 0.5);  // ~1.1 m per sweep at 11 m/s

  SECTION("times from the scan, to the sweep start, middle and end") {
    for (const auto& [target, at_s] : {std::pair{DeskewTarget::kStart, 0.0}, std::pair{DeskewTarget::kMiddle, 0.05},
                                      std::pair{DeskewTarget::kEnd, 0.1}}) {
      c.target = target;
      Scan s = raw;
      SweepDeskew(c).deskew(s, T_prev_current);
      INFO("target at " << at_s << " s: worst " << worst_error(s, raw, sim, at_s) << " m");
      CHECK(worst_error(s, raw, sim, at_s) < 0.01);
    }
  }
  SECTION("times from the azimuth: the simulator spins clockwise from the rear") {
    c.point_times = PointTimeSource::kAzimuth;
    c.start_azimuth_rad = std::numbers::pi;
    c.clockwise = true;
    Scan s = raw;
    s.times_s.clear();
    SweepDeskew(c).deskew(s, T_prev_current);
    REQUIRE(s.has_times());
    INFO("worst " << worst_error(s, raw, sim, 0.0) << " m");
    CHECK(worst_error(s, raw, sim, 0.0) < 0.01);
    // The opposite spin is visibly wrong.
    c.clockwise = false;
    Scan w = raw;
    w.times_s.clear();
    SweepDeskew(c).deskew(w, T_prev_current);
    CHECK(worst_error(w, raw, sim, 0.0) > 0.3);
  }
  SECTION("the predicted motion's span comes from the stamps") {
    const SweepDeskew d(c);
    Scan earlier = sim.frame(4).scan;
    d.deskew(earlier, SE3d());  // first call: remembers the stamp (0.2 s before)
    Scan s = raw;
    d.deskew(s, sim.T_world_lidar(stamp - 0.2).inverse() * sim.T_world_lidar(stamp));
    CHECK(worst_error(s, raw, sim, 0.0) < 0.01);
  }
  SECTION("a time-reversed run with the reversed motion gives the same points (target middle)") {
    c.target = DeskewTarget::kMiddle;
    Scan fwd = raw;
    SweepDeskew(c).deskew(fwd, T_prev_current);
    c.reverse_time = true;
    Scan bwd = raw;
    SweepDeskew(c).deskew(bwd, T_prev_current.inverse());
    double worst = 0.0;
    for (std::size_t k = 0; k < raw.size(); ++k) worst = std::max(worst, static_cast<double>((fwd.points[k] - bwd.points[k]).norm()));
    CHECK(worst < 0.005);  // equal up to the curvature of the motion over a sweep
    // Without reverse_time the backward run doubles the distortion instead.
    c.reverse_time = false;
    Scan wrong = raw;
    SweepDeskew(c).deskew(wrong, T_prev_current.inverse());
    CHECK(worst_error(wrong, raw, sim, 0.05) > 0.3);
  }
}

TEST_CASE("SweepDeskew handles scans without times and rejects bad input", "[pipeline]") {
  SweepDeskewConfig c;
  c.mode = DeskewMode::kConstantVelocity;
  Scan s = semlio::io::read_pcd(raw_scan(0));
  REQUIRE_FALSE(s.has_times());
  SECTION("auto: times from the azimuth when the scan has none") {
    SweepDeskew(c).deskew(s, SE3d::exp(0.1 * twist(8.0, 0.0, 0.0)));
    REQUIRE(s.times_s.size() == s.size());
    CHECK(*std::min_element(s.times_s.begin(), s.times_s.end()) >= 0.0F);
    CHECK(*std::max_element(s.times_s.begin(), s.times_s.end()) < 0.1F);
  }
  SECTION("scan times required") {
    c.point_times = PointTimeSource::kScan;
    CHECK_THROWS_AS(SweepDeskew(c).deskew(s, SE3d()), semlio::ValueError);
  }
  SECTION("empty scan") {
    Scan empty;
    CHECK_NOTHROW(SweepDeskew(c).deskew(empty, SE3d::exp(0.1 * twist(8.0, 0.0, 0.0))));
  }
  SECTION("bad settings name the field") {
    c.sweep_period_s = 0.0;
    CHECK_THROWS_WITH(SweepDeskew(c), Catch::Contains("sweep_period_s"));
    c.sweep_period_s = 0.1;
    c.start_azimuth_rad = std::numbers::pi * std::numeric_limits<double>::infinity();
    CHECK_THROWS_WITH(SweepDeskew(c), Catch::Contains("start_azimuth_rad"));
  }
}

TEST_CASE("real KITTI raw scans: the clockwise time convention lowers the registration residual", "[pipeline]") {
  // Frames 0 and 2 (~1.6 m apart). Register without deskew, then deskew both
  // scans with that motion under a time convention and register again.
  const Scan a0 = semlio::io::read_pcd(raw_scan(0));
  const Scan b0 = semlio::io::read_pcd(raw_scan(2));
  semlio::RegistrationConfig rc;
  rc.kitti_vertical_correction = true;
  const semlio::LoamResiduals plain{semlio::PointToLine{}, semlio::PointToPlane{}};
  const auto register_pair = [&](const Scan& source, const Scan& target, const SE3d& init) {
    Scan s = source;
    Scan t = target;
    const auto r = semlio::register_scan(s, t, init, semlio::NearestK{}, plain, rc);
    REQUIRE(r.solve.ok());
    return r.T_target_source;
  };
  const SE3d T_raw = register_pair(b0, a0, SE3d(SO3d(), Eigen::Vector3d(1.6, 0.0, 0.0)));
  REQUIRE(T_raw.translation().x() > 1.4);
  REQUIRE(T_raw.translation().x() < 1.8);

  const auto residual_with = [&](bool deskew, bool clockwise) {
    SE3d T = T_raw;
    Scan a = a0;
    Scan b = b0;
    for (int pass = 0; pass < 2; ++pass) {  // deskew with the motion, re-register, once more
      a = a0;
      b = b0;
      if (deskew) {
        SweepDeskewConfig c;
        c.mode = DeskewMode::kConstantVelocity;
        c.point_times = PointTimeSource::kAzimuth;
        c.clockwise = clockwise;
        c.target = DeskewTarget::kMiddle;
        c.frame_period_s = 0.2;  // T spans two frames
        SweepDeskew(c).deskew(a, T);
        SweepDeskew(c).deskew(b, T);
      }
      T = register_pair(b, a, T);
    }
    return near_structure_residual(b, a, T);
  };
  const double none = residual_with(false, true);
  const double clockwise = residual_with(true, true);
  const double counter = residual_with(true, false);
  INFO("near-structure residual [mm]: raw " << 1e3 * none << ", clockwise " << 1e3 * clockwise
                                            << ", counter-clockwise " << 1e3 * counter);
  CHECK(clockwise < none);
  CHECK(clockwise < counter);
  CHECK(none < counter);  // the wrong spin doubles the distortion
}

}  // namespace test_deskew_pipeline
