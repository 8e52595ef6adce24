// Loop verification on real KITTI scans: a true loop from a perturbed guess
// is accepted and its relative pose recovered; wrong candidates are rejected;
// the LoopCloser wiring and statistics.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <vector>

#include <semlio/features/preprocess.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/features/sensor_model.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/loop/loop_closer.hpp>
#include <semlio_test/data.hpp>

#include "loop_fixtures.hpp"

namespace test_loop_verifier {  // one namespace per test file: the area compiles as one TU

using namespace semlio;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// KITTI 00 frame i as a keyframe (preprocessed, rings inferred), cached.
const LoopKeyframe& kitti_keyframe(int i) {
  static const std::vector<LoopKeyframe> kfs = [] {
    std::vector<LoopKeyframe> out;
    for (const char* name : {"000000.bin", "000001.bin"}) {
      Scan scan = io::read_kitti_bin(semlio_test::data_path(std::string("kitti/sequences/00/velodyne/") + name));
      preprocess(scan, kitti_preprocess_config());
      infer_rings(scan, SensorModel::hdl64e());
      out.push_back(loop_test::make_keyframe(scan, SE3d(), 0.0));
    }
    return out;
  }();
  return kfs.at(static_cast<std::size_t>(i));
}

/// A keyframe list: `old` at T_world_old (stamp 0), `query` at T_world_query (stamp 100 s).
std::vector<LoopKeyframe> pair_of(const LoopKeyframe& old, const SE3d& T_world_old, const LoopKeyframe& query,
                                  const SE3d& T_world_query) {
  std::vector<LoopKeyframe> kfs{old, query};
  kfs[0].T_world_lidar = T_world_old;
  kfs[0].stamp_s = 0.0;
  kfs[1].T_world_lidar = T_world_query;
  kfs[1].stamp_s = 100.0;
  return kfs;
}

}  // namespace

TEST_CASE("verification accepts a true loop from a perturbed guess and recovers the pose (KITTI)", "[loop]") {
  const LoopKeyframe& kf = kitti_keyframe(0);
  REQUIRE(kf.corners.size() > 100);
  REQUIRE(kf.surfaces.size() > 1000);
  const SE3d T_world_old = loop_test::yaw_pose(0.7, Eigen::Vector3d(120.0, -40.0, 3.0));
  // Scan i revisited: the true relative pose is the identity; the estimate
  // (and so the guess) is off by 1.2 m and 5 deg.
  const SE3d perturbation(SO3d::exp(Eigen::Vector3d(0.01, -0.01, 5.0 * kDeg)), Eigen::Vector3d(0.9, -0.7, 0.3));
  const auto kfs = pair_of(kf, T_world_old, kf, T_world_old * perturbation);
  const LoopVerification v = verify_loop(kfs, 0, 1, perturbation);
  INFO("verdict " << to_string(v.verdict) << " fitness " << v.constraint.fitness_m << " inliers "
                  << v.constraint.inlier_ratio << " time " << v.time_ms << " ms");
  REQUIRE(v.accepted());
  const auto [et, er] = loop_test::pose_error(SE3d(), v.constraint.T_from_to);
  CHECK(et < 0.02);
  CHECK(er < 0.2 * kDeg);
  CHECK(v.constraint.fitness_m < 0.1);  // against voxel centroids (0.2 / 0.4 m leaves), not the points themselves
  CHECK(v.constraint.inlier_ratio > 0.6);  // the rest: residuals invalid by design (non-planar clutter, eq. 9 checks)
  CHECK(v.constraint.from == 0);
  CHECK(v.constraint.to == 1);
  CHECK(v.correction_m == Approx(perturbation.translation().norm()).margin(0.02));
  // Information: symmetric positive definite, from the registration Hessian.
  const Eigen::Matrix<double, 6, 6>& I = v.constraint.information;
  CHECK((I - I.transpose()).norm() < 1e-9 * I.norm());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(I);
  CHECK(es.eigenvalues().minCoeff() > 0.0);
  CHECK(es.eigenvalues().maxCoeff() > 100.0);  // thousands of unit-weight residuals
}

TEST_CASE("verification of the next KITTI frame: accepted, ~0.7-0.9 m forward", "[loop]") {
  // Frames 0 and 1 of KITTI 00: the car drives ~0.7 m forward (x of the
  // lidar) between them (tests/data/kitti/README.md), with almost no turn.
  const auto kfs = pair_of(kitti_keyframe(0), SE3d(), kitti_keyframe(1), SE3d());
  const LoopVerification v = verify_loop(kfs, 0, 1, SE3d());
  INFO("verdict " << to_string(v.verdict) << " fitness " << v.constraint.fitness_m);
  REQUIRE(v.accepted());
  const Eigen::Vector3d t = v.constraint.T_from_to.translation();
  CHECK(t.x() > 0.5);
  CHECK(t.x() < 1.0);
  CHECK(std::abs(t.y()) < 0.1);
  CHECK(std::abs(t.z()) < 0.1);
  CHECK(v.constraint.T_from_to.so3().log().norm() < 1.0 * kDeg);
}

TEST_CASE("verification rejects wrong candidates", "[loop]") {
  const LoopKeyframe& kf = kitti_keyframe(0);
  SECTION("the same street seen 90 deg turned, guessed as aligned") {
    // The query is the scan turned by 90 deg; the guess claims no turn. The
    // registration cannot reach the true alignment from there.
    LoopKeyframe turned = kf;
    const Eigen::Matrix3f Rt = loop_test::yaw_pose(90.0 * kDeg).rotation().transpose().cast<float>();
    for (auto& p : turned.corners.points) p = Rt * p;
    for (auto& p : turned.surfaces.points) p = Rt * p;
    const auto kfs = pair_of(kf, SE3d(), turned, SE3d());
    const LoopVerification v = verify_loop(kfs, 0, 1, SE3d());
    INFO("verdict " << to_string(v.verdict) << " fitness " << v.constraint.fitness_m << " inliers "
                    << v.constraint.inlier_ratio);
    CHECK_FALSE(v.accepted());
  }
  SECTION("a scan shifted 40 m along its road") {
    LoopKeyframe shifted = kf;
    for (auto& p : shifted.corners.points) p.x() += 40.0F;
    for (auto& p : shifted.surfaces.points) p.x() += 40.0F;
    const auto kfs = pair_of(kf, SE3d(), shifted, SE3d());
    const LoopVerification v = verify_loop(kfs, 0, 1, SE3d());
    INFO("verdict " << to_string(v.verdict) << " fitness " << v.constraint.fitness_m << " inliers "
                    << v.constraint.inlier_ratio);
    CHECK_FALSE(v.accepted());
  }
  SECTION("a true alignment beyond the drift budget") {
    // The geometry matches perfectly, but the estimate puts the query 8 m and
    // 20 deg away over a 0 m path: more correction than odometry drift allows.
    const SE3d off(SO3d::exp(Eigen::Vector3d(0.0, 0.0, 20.0 * kDeg)), Eigen::Vector3d(6.0, 5.0, 0.0));
    const auto kfs = pair_of(kf, SE3d(), kf, off);
    const LoopVerification v = verify_loop(kfs, 0, 1, SE3d());  // a guess from elsewhere (e.g. Scan Context)
    CHECK(v.verdict == LoopVerdict::kLargeCorrection);
    CHECK(v.correction_m == Approx(off.translation().norm()).margin(0.05));
  }
  SECTION("empty query features") {
    LoopKeyframe empty = kf;
    empty.corners.clear();
    empty.surfaces.clear();
    const auto kfs = pair_of(kf, SE3d(), empty, SE3d());
    CHECK(verify_loop(kfs, 0, 1, SE3d()).verdict == LoopVerdict::kEmptySubmap);
    CHECK(verify_loop(kfs, 0, 7, SE3d()).verdict == LoopVerdict::kEmptySubmap);
  }
}

TEST_CASE("loop closer: detection + verification, statistics", "[loop]") {
  const LoopKeyframe& kf = kitti_keyframe(0);
  const SE3d T_world_old = loop_test::yaw_pose(-0.3, Eigen::Vector3d(5.0, 5.0, 0.0));
  const SE3d drift(SO3d::exp(Eigen::Vector3d(0.0, 0.0, 2.0 * kDeg)), Eigen::Vector3d(-1.5, 0.5, 0.0));
  std::vector<LoopKeyframe> kfs;
  LoopCloser<RadiusLoopDetector> closer;
  kfs.push_back(kf);
  kfs.back().T_world_lidar = T_world_old;
  kfs.back().stamp_s = 0.0;
  CHECK_FALSE(closer.process(kfs).has_value());  // one keyframe: nothing to close
  kfs.push_back(kitti_keyframe(1));
  kfs.back().T_world_lidar = T_world_old * loop_test::yaw_pose(0.0, Eigen::Vector3d(0.8, 0.0, 0.0));
  kfs.back().stamp_s = 0.1;
  CHECK_FALSE(closer.process(kfs).has_value());  // too recent
  kfs.push_back(kf);
  kfs.back().T_world_lidar = T_world_old * drift;
  kfs.back().stamp_s = 60.0;
  const auto loop = closer.process(kfs);
  REQUIRE(loop.has_value());
  CHECK(loop->from == 0);  // the nearest: keyframe 0 is 1.6 m away, keyframe 1 2.4 m
  CHECK(loop->to == 2);
  const auto [et, er] = loop_test::pose_error(SE3d(), loop->T_from_to);
  CHECK(et < 0.05);
  CHECK(er < 0.5 * kDeg);
  const LoopStats& st = closer.stats();
  CHECK(st.queries == 3);
  CHECK(st.candidates >= 1);
  CHECK(st.verified >= 1);
  CHECK(st.accepted == 1);
  CHECK(st.verified == st.accepted + st.rejected());
}

}  // namespace test_loop_verifier
