#include <catch2/catch.hpp>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/associate/normal_consistency.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/ply.hpp>
#include <semlio/pipeline/registration.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>
#include <semlio/residual/robust.hpp>
#include <semlio/residual/semantic_weighted.hpp>
#include <semlio/search/kdtree.hpp>
#include <semlio/search/voxel_grid.hpp>
#include <semlio/sim/simulator.hpp>

#include <semlio_test/data.hpp>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <fstream>
#include <numbers>
#include <vector>

namespace test_registration {  // one namespace per test file: the area compiles as one TU

using namespace semlio;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

SE3d read_matrix4(const std::string& path) {
  std::ifstream in(path);
  Eigen::Matrix4d T;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) in >> T(i, j);
  REQUIRE(in);
  return SE3d(T);
}

double angle_deg(const SE3d& a, const SE3d& b) { return (a.inverse() * b).so3().angle() / kDeg; }
double distance_m(const SE3d& a, const SE3d& b) { return (a.translation() - b.translation()).norm(); }

const LoamResiduals<PointToLine, PointToPlane> kPlain{PointToLine{}, PointToPlane{}};
const LoamResiduals<SemanticWeighted<PointToLine>, SemanticWeighted<PointToPlane>> kWeighted{
    SemanticWeighted<PointToLine>{}, SemanticWeighted<PointToPlane>{}};
// Corners with the library's Cauchy kernel at its default scale (0.1 m), the
// semantic weight outside it (the kernel sees the unweighted distance).
using RobustLine = Robust<Cauchy, PointToLine>;
const LoamResiduals<RobustLine, PointToPlane> kPlainRobust{RobustLine{}, PointToPlane{}};
const LoamResiduals<SemanticWeighted<RobustLine>, SemanticWeighted<PointToPlane>> kWeightedRobust{
    SemanticWeighted<RobustLine>{}, SemanticWeighted<PointToPlane>{}};

// An independent point-to-plane ICP (nearest neighbour, PCA normals from
// Eigen's solver, small-angle linearisation), deliberately written without the
// library's features, maps, residuals or solver.
SE3d plane_icp(const std::vector<Eigen::Vector3f>& source, const std::vector<Eigen::Vector3f>& target, SE3d T) {
  const KdTree3f tree(target);
  std::vector<Eigen::Vector3d> normals(target.size(), Eigen::Vector3d::Zero());
  std::vector<bool> planar(target.size(), false);
  std::array<std::uint32_t, 10> idx{};
  std::array<float, 10> d2{};
  for (std::size_t i = 0; i < target.size(); ++i) {
    const std::size_t n = tree.knn(target[i], 10, idx.data(), d2.data());
    if (n < 10 || d2[9] > 1.0F) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < n; ++k) mean += target[idx[k]].cast<double>();
    mean /= static_cast<double>(n);
    Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
    for (std::size_t k = 0; k < n; ++k) {
      const Eigen::Vector3d d = target[idx[k]].cast<double>() - mean;
      C += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
    normals[i] = es.eigenvectors().col(0);
    planar[i] = es.eigenvalues()(0) < 0.05 * es.eigenvalues()(1);
  }
  for (int it = 0; it < 40; ++it) {
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    for (const auto& p : source) {
      const Eigen::Vector3d q = T * p.cast<double>();
      std::uint32_t j = 0;
      float dj = 0.0F;
      if (tree.knn(q.cast<float>(), 1, &j, &dj) != 1 || dj > 0.25F || !planar[j]) continue;
      const Eigen::Vector3d& n = normals[j];
      const double r = n.dot(q - target[j].cast<double>());
      Eigen::Matrix<double, 6, 1> J;  // left perturbation [t; w]: d(q)/dw = -q^
      J.head<3>() = n;
      J.tail<3>() = q.cross(n);
      H += J * J.transpose();
      b += J * r;
    }
    const Eigen::Matrix<double, 6, 1> dx = H.ldlt().solve(-b);
    T = SE3d(SO3d::exp(dx.tail<3>()), dx.head<3>()) * T;
    if (dx.norm() < 1e-7) break;
  }
  return T;
}

std::vector<Eigen::Vector3f> downsample(const Scan& s, double leaf) {
  VoxelGrid grid(VoxelGridConfig{.leaf_size_m = leaf, .point = VoxelPoint::kCentroid});
  std::vector<Eigen::Vector3f> pts;
  std::vector<Class> labels;
  std::vector<std::uint32_t> first;
  grid.downsample(s.points, s.labels, pts, labels, first);
  return pts;
}

// Points where rays of a 64-beam sensor at the origin hit a set of planes
// (n, d): n.x + d = 0; rings filled, nearest hit per ray within 80 m.
Scan cast_planes(const std::vector<std::pair<Eigen::Vector3d, double>>& planes) {
  const SensorModel sensor = SensorModel::hdl64e();
  Scan s;
  for (std::size_t ring = 0; ring < sensor.elevations_rad.size(); ++ring) {
    const double el = sensor.elevations_rad[ring];
    for (int a = 0; a < 900; ++a) {
      const double az = 2.0 * std::numbers::pi * a / 900.0;
      const Eigen::Vector3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      double best = 80.0;
      for (const auto& [n, d] : planes) {
        const double den = n.dot(dir);
        if (std::abs(den) < 1e-9) continue;
        const double t = -d / den;
        if (t > 0.5 && t < best) best = t;
      }
      if (best < 80.0) {
        s.points.push_back((best * dir).cast<float>());
        s.rings.push_back(static_cast<std::uint16_t>(ring));
      }
    }
  }
  return s;
}

template <typename A, typename R>
void check_finite(const RegistrationResult& r) {
  CHECK(r.T_target_source.matrix().allFinite());
  CHECK(r.solve.hessian.allFinite());
  CHECK(r.solve.eigenvalues.allFinite());
  CHECK(std::isfinite(r.solve.final_cost));
}

// The real 32-beam pair registered from identity: NormalConsistency with
// semantic weights or NearestK plain, corners plain or under the Cauchy kernel.
RegistrationResult register_32beam_pair(bool normal, bool robust) {
  RegistrationConfig config;
  config.sensor = SensorModel::hdl32e();
  Scan source = io::read_ply(semlio_test::data_path("scan_pair/source.ply"));
  Scan target = io::read_ply(semlio_test::data_path("scan_pair/target.ply"));
  if (normal) {
    return robust ? register_scan(source, target, SE3d(), NormalConsistency{}, kWeightedRobust, config)
                  : register_scan(source, target, SE3d(), NormalConsistency{}, kWeighted, config);
  }
  return robust ? register_scan(source, target, SE3d(), NearestK{}, kPlainRobust, config)
                : register_scan(source, target, SE3d(), NearestK{}, kPlain, config);
}

}  // namespace

TEST_CASE("Registration of the real 32-beam scan pair from identity", "[pipeline][registration]") {
  const SE3d T_ref = read_matrix4(semlio_test::data_path("scan_pair/T_target_source.txt"));
  for (const bool normal : {true, false}) {
    const RegistrationResult r = register_32beam_pair(normal, /*robust=*/false);
    INFO((normal ? "NormalConsistency" : "NearestK") << ": " << distance_m(r.T_target_source, T_ref) << " m, "
                                                     << angle_deg(r.T_target_source, T_ref) << " deg");
    REQUIRE(r.solve.ok());
    // Issue #4: within 3 cm and 0.25 deg of the reference (itself an estimate).
    CHECK(distance_m(r.T_target_source, T_ref) < 0.03);
    CHECK(angle_deg(r.T_target_source, T_ref) < 0.25);
    CHECK(r.inliers() > 1000);
    CHECK(r.fitness() > 0.5);
    // A well-structured outdoor scene: no direction is degenerate.
    CHECK_FALSE(r.solve.degenerate());
  }
}

TEST_CASE("Registration of the real 32-beam scan pair with robust corners (semlio_register's default)",
          "[pipeline][registration]") {
  // Robust corners bring the translation 4-8x closer to the reference, and
  // leave the rotation 0.25-0.31 deg from it, mostly roll: inside the spread
  // of independent estimators on this pair (plane_icp above, run on it,
  // lands 0.14-0.49 deg from the reference depending on its voxel sizes;
  // small_gicp's GICP 0.33 deg). NormalConsistency with semantic
  // weights, semlio_register's default, is inside issue #4's 0.25 deg; the
  // NearestK variant is not (README, Status).
  const SE3d T_ref = read_matrix4(semlio_test::data_path("scan_pair/T_target_source.txt"));
  for (const bool normal : {true, false}) {
    const RegistrationResult r = register_32beam_pair(normal, /*robust=*/true);
    INFO((normal ? "NormalConsistency" : "NearestK") << ": " << distance_m(r.T_target_source, T_ref) << " m, "
                                                     << angle_deg(r.T_target_source, T_ref) << " deg");
    REQUIRE(r.solve.ok());
    CHECK(distance_m(r.T_target_source, T_ref) < 0.01);
    CHECK(angle_deg(r.T_target_source, T_ref) < (normal ? 0.25 : 0.35));
    CHECK(r.inliers() > 1000);
    CHECK_FALSE(r.solve.degenerate());
  }
}

TEST_CASE("Registration of two consecutive real KITTI scans agrees with an independent plane ICP",
          "[pipeline][registration]") {
  const auto path = [](int i) {
    return semlio_test::data_path("kitti/sequences/00/velodyne/00000" + std::to_string(i) + ".bin");
  };
  const SE3d T_icp = [&] {
    const Scan source = io::read_kitti_bin(path(1));
    const Scan target = io::read_kitti_bin(path(0));
    return plane_icp(downsample(source, 0.5), downsample(target, 0.2), SE3d());
  }();
  // ~0.69 m forward between these frames (data README); the ICP must see it.
  REQUIRE(T_icp.translation().x() == Approx(0.69).margin(0.02));

  SECTION("surface features agree with the ICP within 1.5 cm and 0.1 deg") {
    Scan source = io::read_kitti_bin(path(1));
    Scan target = io::read_kitti_bin(path(0));
    RegistrationConfig config;
    config.features.corner_threshold_m = 1e9;  // no corners
    const RegistrationResult r = register_scan(source, target, SE3d(), NormalConsistency{}, kWeighted, config);
    REQUIRE(r.solve.ok());
    INFO("semlio " << r.T_target_source.translation().transpose() << " icp " << T_icp.translation().transpose());
    CHECK(distance_m(r.T_target_source, T_icp) < 0.015);
    CHECK(angle_deg(r.T_target_source, T_icp) < 0.1);
  }
  SECTION("the default (corners + surfaces) stays within 5 cm") {
    // Known gap, reported in the README: LOAM corner features shorten the
    // forward motion of this pair by 3.4 cm (0.654 m against 0.688 m).
    // Measured cause: point-to-line terms whose line lies in the scan cone of
    // the feature's beam (rows of one ring, mostly on the ground, 0.3-0.9 m
    // residuals at the ICP solution) pull towards zero motion; the
    // ring-crossing check of PointToLine removes them (next section). It is
    // off by default, see point_to_line.hpp. This bound guards against
    // regressions.
    Scan source = io::read_kitti_bin(path(1));
    Scan target = io::read_kitti_bin(path(0));
    const RegistrationResult r = register_scan(source, target, SE3d(), NormalConsistency{}, kWeighted);
    REQUIRE(r.solve.ok());
    INFO("semlio " << r.T_target_source.translation().transpose() << " icp " << T_icp.translation().transpose());
    CHECK(distance_m(r.T_target_source, T_icp) < 0.05);
    CHECK(angle_deg(r.T_target_source, T_icp) < 0.1);
    // An urban street: no direction is degenerate (gauss_newton.hpp's ratio).
    CHECK_FALSE(r.solve.degenerate());
  }
  SECTION("corners + surfaces with robust corners (Cauchy) agree with the ICP within 1 cm and 0.1 deg") {
    // The biased corner terms are large-residual matches (0.45-0.9 m at the
    // ICP pose: horizontal ground lines near the car); a robust kernel
    // removes their pull without any geometric test.
    for (const bool normal : {true, false}) {
      Scan source = io::read_kitti_bin(path(1));
      Scan target = io::read_kitti_bin(path(0));
      const RegistrationResult r = normal ? register_scan(source, target, SE3d(), NormalConsistency{}, kWeightedRobust)
                                          : register_scan(source, target, SE3d(), NearestK{}, kPlainRobust);
      REQUIRE(r.solve.ok());
      INFO((normal ? "NormalConsistency" : "NearestK") << ": semlio " << r.T_target_source.translation().transpose()
                                                       << " icp " << T_icp.translation().transpose());
      CHECK(r.corner_matches > 500);
      CHECK(distance_m(r.T_target_source, T_icp) < 0.01);
      CHECK(angle_deg(r.T_target_source, T_icp) < 0.1);
    }
  }
  SECTION("corners + surfaces with the ring-crossing check agree with the ICP within 1 cm and 0.1 deg") {
    const PointToLine line({.min_cone_angle_rad = 20.0 * kDeg});
    const LoamResiduals<SemanticWeighted<PointToLine>, SemanticWeighted<PointToPlane>> checked{
        SemanticWeighted<PointToLine>(line), SemanticWeighted<PointToPlane>{}};
    for (const bool normal : {true, false}) {
      Scan source = io::read_kitti_bin(path(1));
      Scan target = io::read_kitti_bin(path(0));
      const RegistrationResult r = normal ? register_scan(source, target, SE3d(), NormalConsistency{}, checked)
                                          : register_scan(source, target, SE3d(), NearestK{}, checked);
      REQUIRE(r.solve.ok());
      INFO((normal ? "NormalConsistency" : "NearestK") << ": semlio " << r.T_target_source.translation().transpose()
                                                       << " icp " << T_icp.translation().transpose());
      CHECK(r.corner_matches > 500);
      CHECK(distance_m(r.T_target_source, T_icp) < 0.01);
      CHECK_FALSE(r.solve.degenerate());
      CHECK(angle_deg(r.T_target_source, T_icp) < 0.1);
    }
  }
}

TEST_CASE("Degenerate registration inputs give a status and finite numbers", "[pipeline][registration]") {
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  SECTION("a flat plane: x, y and yaw unconstrained") {
    Scan target = cast_planes({{up, 1.73}});
    Scan source = target;
    const auto r = register_scan(source, target, SE3d(), NormalConsistency{}, kWeighted);
    check_finite<NormalConsistency, int>(r);
    if (r.solve.ok()) CHECK(r.solve.degenerate_directions >= 3);
  }
  SECTION("a long corridor: motion along it is unconstrained") {
    Scan target = cast_planes({{up, 1.73}, {Eigen::Vector3d::UnitY(), 3.0}, {-Eigen::Vector3d::UnitY(), 3.0}});
    Scan source = target;
    const auto r = register_scan(source, target, SE3d(), NearestK{}, kPlain);
    check_finite<NearestK, int>(r);
    if (r.solve.ok()) CHECK(r.solve.degenerate_directions >= 1);
  }
  SECTION("no features: an empty scan") {
    Scan target = cast_planes({{up, 1.73}});
    Scan source;
    const auto r = register_scan(source, target, SE3d(), NormalConsistency{}, kWeighted);
    check_finite<NormalConsistency, int>(r);
    CHECK(r.solve.status == SolveStatus::kTooFewResiduals);
    CHECK(r.source_corners + r.source_surfaces == 0);
  }
  SECTION("all points in one voxel") {
    Scan one;
    for (int i = 0; i < 200; ++i) {
      one.points.emplace_back(10.0F + 0.001F * static_cast<float>(i % 7), 0.002F * static_cast<float>(i % 5), -1.0F);
    }
    Scan target = one;
    const auto r = register_scan(one, target, SE3d(), NormalConsistency{}, kWeighted);
    check_finite<NormalConsistency, int>(r);
    CHECK_FALSE(r.solve.status == SolveStatus::kConverged);
  }
}

namespace {

// Registers simulated frame `first + 1` against frame `first` of a drive,
// starting from the ground truth (what a good prediction gives), with the
// baseline (nearest 5, plain) or the paper's (normal consistency, semantic
// weights) front end. Returns the result and the true motion direction.
RegistrationResult register_sim_pair(sim::WorldKind world, bool distortion, std::size_t first, bool normal,
                                     Eigen::Vector3d& motion_dir) {
  sim::SimulatorConfig c;
  c.world = world;
  c.traffic = sim::TrafficLevel::kNone;
  c.frames = first + 2;
  c.seed = 1;
  c.distortion = distortion;
  const sim::Simulator simulator(c);
  sim::Frame a = simulator.frame(first);
  sim::Frame b = simulator.frame(first + 1);
  const SE3d T_true = a.T_world_lidar.inverse() * b.T_world_lidar;
  motion_dir = T_true.translation().normalized();
  return normal ? register_scan(b.scan, a.scan, T_true, NormalConsistency{}, kWeighted)
                : register_scan(b.scan, a.scan, T_true, NearestK{}, kPlain);
}

}  // namespace

TEST_CASE("Degeneracy is reported along the road on a simulated highway, not in a street",
          "[pipeline][registration]") {
  // Issue 7: on a straight highway (guard rails, flat ground, posts and
  // lights only every few tens of metres) the along-road direction is weakly
  // constrained; the front end must say so, in that direction. A street
  // (buildings, cross streets) must not be reported degenerate.
  for (const bool normal : {false, true}) {
    INFO((normal ? "NormalConsistency" : "NearestK"));
    Eigen::Vector3d along;
    const RegistrationResult highway = register_sim_pair(sim::WorldKind::kHighway, true, 6, normal, along);
    INFO("highway eigenvalues " << highway.solve.eigenvalues.transpose() << " v0 "
                                << highway.solve.eigenvectors.col(0).transpose());
    REQUIRE(highway.solve.ok());
    CHECK(highway.solve.eigenvalues.allFinite());
    // The flag (solve/gauss_newton.hpp: normalised information below 0.12,
    // chosen so that no real or simulated urban frame of either preset is
    // flagged) is raised with the paper's matches; the nearest-5 matches of
    // this pair keep 0.17 of the mean translational information along the
    // road -- weak, just above the threshold (the lidar-only highway drive:
    // 95 of 149 baseline frames flagged, 149 of 149 full; see that file).
    if (normal) CHECK(highway.solve.degenerate_directions >= 1);
    CHECK(highway.solve.normalized_eigenvalues[0] < 0.2);
    // The first reported direction is the weakest (the degenerate one when
    // flagged): mostly a translation, and along the direction of travel.
    const Eigen::Matrix<double, 6, 1> v = highway.solve.eigenvectors.col(0);
    REQUIRE(v.head<3>().norm() > 0.9);
    CHECK(std::abs(v.head<3>().normalized().dot(along)) > 0.9);

    const RegistrationResult street = register_sim_pair(sim::WorldKind::kUrban, false, 10, normal, along);
    INFO("street eigenvalues " << street.solve.eigenvalues.transpose());
    REQUIRE(street.solve.ok());
    CHECK_FALSE(street.solve.degenerate());
    // The street's weakest direction is better constrained than the road's.
    CHECK(street.solve.normalized_eigenvalues[0] > highway.solve.normalized_eigenvalues[0]);
  }
}

TEST_CASE("Simulated street frame pairs from identity with the ring-crossing check or robust corners",
          "[pipeline][registration]") {
  // Without the biased corner terms (ring-crossing check, or a robust kernel
  // on corners) nothing pulls towards zero motion, but from the identity
  // start (1.1 m short at 11 m/s) the first association can leave the
  // forward direction below the degeneracy threshold; with NormalConsistency
  // (fewer corner matches) the association was then a fixed point (x frozen
  // -> same matches -> x still weak) and the solve stayed at the start.
  // register_scan() damps degenerate directions instead of freezing them
  // (gauss_newton.hpp), so both associators must land near the truth on
  // every pair.
  sim::SimulatorConfig c;
  c.world = sim::WorldKind::kUrban;
  c.traffic = sim::TrafficLevel::kNone;
  c.frames = 80;
  c.seed = 1;
  const sim::Simulator simulator(c);
  const PointToLine line({.min_cone_angle_rad = 20.0 * kDeg});
  const LoamResiduals<SemanticWeighted<PointToLine>, SemanticWeighted<PointToPlane>> checked{
      SemanticWeighted<PointToLine>(line), SemanticWeighted<PointToPlane>{}};
  for (const std::size_t first : {20U, 45U, 70U}) {
    const sim::Frame a0 = simulator.frame(first);
    const sim::Frame b0 = simulator.frame(first + 1);
    const SE3d T_true = a0.T_world_lidar.inverse() * b0.T_world_lidar;
    for (const bool robust : {false, true}) {
      for (const bool normal : {true, false}) {
        Scan a = a0.scan;
        Scan b = b0.scan;
        const RegistrationResult r =
            robust ? (normal ? register_scan(b, a, SE3d(), NormalConsistency{}, kWeightedRobust)
                             : register_scan(b, a, SE3d(), NearestK{}, kPlainRobust))
                   : (normal ? register_scan(b, a, SE3d(), NormalConsistency{}, checked)
                             : register_scan(b, a, SE3d(), NearestK{}, checked));
        INFO("frame " << first << (robust ? " robust corners" : " ring check")
                      << (normal ? " NormalConsistency" : " NearestK") << ": " << distance_m(r.T_target_source, T_true)
                      << " m, " << angle_deg(r.T_target_source, T_true) << " deg, true motion "
                      << T_true.translation().norm() << " m, first analysis degenerate "
                      << r.solve.initial_degenerate_directions);
        REQUIRE(r.solve.ok());
        CHECK(distance_m(r.T_target_source, T_true) < 0.03);
        CHECK(angle_deg(r.T_target_source, T_true) < 0.1);
      }
    }
  }
}

}  // namespace test_registration
