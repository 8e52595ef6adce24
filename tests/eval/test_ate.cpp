// ATE and Umeyama alignment: hand-computed cases (constant offset, known
// rotation, scale), subsets, statuses, and the real KITTI 04 ground truth
// against perturbed copies with analytically known errors.
#include <catch2/catch.hpp>

#include <semlio/core/error.hpp>
#include <semlio/eval/ate.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio_test/data.hpp>

#include <cmath>
#include <numbers>
#include <vector>

namespace test_ate {  // one namespace per test file: the area compiles as one TU

using semlio::SE3d;
using semlio::SO3d;
using semlio::eval::Alignment;
using semlio::eval::AlignmentStatus;
using semlio::eval::AteConfig;
using Vec3 = Eigen::Vector3d;

namespace {

// A small non-planar trajectory: a helix with 20 poses.
std::vector<SE3d> helix() {
  std::vector<SE3d> out;
  for (int i = 0; i < 20; ++i) {
    const double a = 0.3 * i;
    out.emplace_back(SO3d::exp(Vec3(0.0, 0.0, a)), Vec3(5.0 * std::cos(a), 5.0 * std::sin(a), 0.4 * i));
  }
  return out;
}

// Left-multiplies every pose: the whole trajectory moved rigidly.
std::vector<SE3d> moved(const SE3d& G, const std::vector<SE3d>& traj) {
  std::vector<SE3d> out;
  for (const SE3d& T : traj) out.push_back(G * T);
  return out;
}

std::vector<SE3d> kitti04() { return semlio::io::read_kitti_poses(semlio_test::data_path("kitti/poses/04.txt")); }

}  // namespace

TEST_CASE("ATE: identical trajectories give zero for every alignment", "[eval]") {
  const auto gt = helix();
  for (const Alignment a : {Alignment::kSE3, Alignment::kSim3, Alignment::kNone}) {
    const auto r = semlio::eval::ate(gt, gt, AteConfig{.alignment = a});
    CHECK(r.count == 20);
    CHECK(r.rmse_m < 1e-12);
    CHECK(r.max_m < 1e-12);
    CHECK(r.alignment.status == AlignmentStatus::kOk);
    CHECK(std::abs(r.alignment.scale - 1.0) < 1e-12);
  }
}

TEST_CASE("ATE: a constant offset vanishes after SE3 alignment and is exact with none", "[eval]") {
  const auto gt = helix();
  const Vec3 c(1.0, -2.0, 2.0);  // |c| = 3
  const auto est = moved(SE3d(SO3d(), c), gt);
  const auto none = semlio::eval::ate(gt, est, AteConfig{.alignment = Alignment::kNone});
  CHECK(std::abs(none.rmse_m - 3.0) < 1e-12);
  CHECK(std::abs(none.mean_m - 3.0) < 1e-12);
  CHECK(std::abs(none.median_m - 3.0) < 1e-12);
  CHECK(std::abs(none.max_m - 3.0) < 1e-12);
  const auto se3 = semlio::eval::ate(gt, est);
  CHECK(se3.rmse_m < 1e-12);
  CHECK((se3.alignment.T_gt_est.translation() + c).norm() < 1e-12);
  CHECK(se3.alignment.T_gt_est.so3().angle() < 1e-12);
}

TEST_CASE("ATE: a known rotation of the whole trajectory", "[eval]") {
  // gt on the unit circle in the xy plane at four heights; est rotated by 90
  // deg about z: each point moves by |Rz(90) p - p| = sqrt(2) |p_xy| = sqrt(2).
  std::vector<Vec3> p_gt;
  for (int i = 0; i < 12; ++i) {
    const double a = 0.5 * i;
    p_gt.emplace_back(std::cos(a), std::sin(a), 0.25 * i);
  }
  const SO3d Rz = SO3d::exp(Vec3(0.0, 0.0, std::numbers::pi / 2.0));
  std::vector<Vec3> p_est;
  for (const Vec3& p : p_gt) p_est.push_back(Rz * p);
  const auto none = semlio::eval::ate_positions(p_gt, p_est, {.alignment = Alignment::kNone});
  CHECK(std::abs(none.rmse_m - std::sqrt(2.0)) < 1e-12);
  CHECK(std::abs(none.max_m - std::sqrt(2.0)) < 1e-12);
  const auto se3 = semlio::eval::ate_positions(p_gt, p_est);
  CHECK(se3.rmse_m < 1e-12);
  // The fitted rotation undoes Rz.
  CHECK((se3.alignment.T_gt_est.rotation() - Rz.inverse().matrix()).norm() < 1e-12);
  CHECK(se3.alignment.T_gt_est.translation().norm() < 1e-12);
}

TEST_CASE("ATE: Sim3 recovers a scaled, rotated, shifted trajectory", "[eval]") {
  const auto gt = helix();
  const double s = 2.5;
  const SE3d G(SO3d::exp(Vec3(0.2, -0.4, 1.1)), Vec3(10.0, -3.0, 1.0));
  std::vector<SE3d> est;
  for (const SE3d& T : gt) est.emplace_back(G.so3() * T.so3(), s * (G.so3() * T.translation()) + G.translation());
  const auto sim3 = semlio::eval::ate(gt, est, AteConfig{.alignment = Alignment::kSim3});
  CHECK(sim3.rmse_m < 1e-10);
  // p_gt = (1/s) R^T (p_est - t).
  CHECK(std::abs(sim3.alignment.scale - 1.0 / s) < 1e-12);
  CHECK((sim3.alignment.T_gt_est.rotation() - G.rotation().transpose()).norm() < 1e-12);
  CHECK((sim3.alignment.T_gt_est.translation() + (1.0 / s) * (G.so3().inverse() * G.translation())).norm() < 1e-10);
  // SE3 cannot absorb the scale.
  const auto se3 = semlio::eval::ate(gt, est);
  CHECK(se3.rmse_m > 1.0);
  CHECK(se3.alignment.scale == 1.0);
  // Aligned poses land on the ground truth.
  for (std::size_t i = 0; i < gt.size(); ++i) {
    CHECK((sim3.alignment.apply(est[i]).translation() - gt[i].translation()).norm() < 1e-10);
    CHECK((sim3.alignment.apply(est[i]).rotation() - gt[i].rotation()).norm() < 1e-12);
  }
}

TEST_CASE("ATE: statistics of hand-made errors (rmse, mean, even-count median, max)", "[eval]") {
  // Errors 1, 2, 3, 10 along x with no alignment.
  const std::vector<Vec3> p_gt(4, Vec3::Zero());
  const std::vector<Vec3> p_est{Vec3(1, 0, 0), Vec3(0, -2, 0), Vec3(0, 0, 10), Vec3(3, 0, 0)};
  const auto r = semlio::eval::ate_positions(p_gt, p_est, {.alignment = Alignment::kNone});
  CHECK(r.count == 4);
  CHECK(std::abs(r.rmse_m - std::sqrt((1.0 + 4.0 + 100.0 + 9.0) / 4.0)) < 1e-14);
  CHECK(std::abs(r.mean_m - 4.0) < 1e-14);
  CHECK(std::abs(r.median_m - 2.5) < 1e-14);
  CHECK(r.max_m == 10.0);
  CHECK(r.errors_m == std::vector<double>{1.0, 2.0, 10.0, 3.0});
  // Odd count: the middle value.
  const auto odd = semlio::eval::ate_positions(std::vector<Vec3>(3, Vec3::Zero()),
                                               {Vec3(5, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)},
                                               {.alignment = Alignment::kNone});
  CHECK(odd.median_m == 2.0);
}

TEST_CASE("ATE: a subset is aligned and scored on its frames only", "[eval]") {
  const auto gt = helix();
  const SE3d G(SO3d::exp(Vec3(0.0, 0.3, 0.0)), Vec3(1.0, 2.0, 3.0));
  auto est = moved(G, gt);
  est[3] = SE3d(est[3].so3(), est[3].translation() + Vec3(50.0, 0.0, 0.0));  // a gross error off the subset
  const std::vector<std::size_t> keyframes{0, 2, 5, 9, 14, 19};
  const auto sub = semlio::eval::ate(gt, est, keyframes);
  CHECK(sub.count == keyframes.size());
  CHECK(sub.rmse_m < 1e-10);
  const auto all = semlio::eval::ate(gt, est);
  CHECK(all.count == 20);
  CHECK(all.max_m > 1.0);
  // Duplicates count twice, order is kept.
  const auto dup = semlio::eval::ate(gt, est, std::vector<std::size_t>{3, 3}, AteConfig{.alignment = Alignment::kNone});
  CHECK(dup.count == 2);
  CHECK(dup.errors_m[0] == dup.errors_m[1]);
}

TEST_CASE("ATE: bad input throws ValueError naming the problem", "[eval]") {
  const auto gt = helix();
  auto shorter = gt;
  shorter.pop_back();
  CHECK_THROWS_AS(semlio::eval::ate(gt, shorter), semlio::ValueError);
  CHECK_THROWS_WITH(semlio::eval::ate(gt, gt, std::vector<std::size_t>{1, 20}),
                    Catch::Contains("subset index 20") && Catch::Contains("20 poses"));
  CHECK_THROWS_AS(semlio::eval::ate(std::vector<SE3d>{}, std::vector<SE3d>{}), semlio::ValueError);
  CHECK_THROWS_AS(semlio::eval::ate(gt, gt, std::vector<std::size_t>{}), semlio::ValueError);
}

TEST_CASE("ATE: degenerate alignments report a status, never NaN", "[eval]") {
  // One point: rotation free, translation still fitted.
  const auto one = semlio::eval::ate_positions({Vec3(1, 2, 3)}, {Vec3(4, 5, 6)});
  CHECK(one.alignment.status == AlignmentStatus::kRotationUndetermined);
  CHECK(one.rmse_m < 1e-12);
  // Collinear points: the fitted transform is still a minimiser.
  std::vector<Vec3> line_gt;
  std::vector<Vec3> line_est;
  for (int i = 0; i < 10; ++i) {
    line_gt.emplace_back(i, 0.0, 0.0);
    line_est.emplace_back(0.0, i, 1.0);
  }
  const auto line = semlio::eval::ate_positions(line_gt, line_est);
  CHECK(line.alignment.status == AlignmentStatus::kRotationUndetermined);
  CHECK(line.rmse_m < 1e-12);
  // Sim3 with an estimate that never moves: scale 1, status says so.
  const std::vector<Vec3> still(10, Vec3(1, 1, 1));
  const auto sim = semlio::eval::ate_positions(line_gt, still, {.alignment = Alignment::kSim3});
  CHECK(sim.alignment.status == AlignmentStatus::kScaleUndetermined);
  CHECK(sim.alignment.scale == 1.0);
  CHECK(std::isfinite(sim.rmse_m));
  // Error is the spread of gt about its mean: sqrt(mean((i - 4.5)^2)) = sqrt(8.25).
  CHECK(std::abs(sim.rmse_m - std::sqrt(8.25)) < 1e-12);
}

TEST_CASE("ATE on real KITTI 04: a rigid move of the ground truth aligns to zero", "[eval]") {
  const auto gt = kitti04();
  REQUIRE(gt.size() == 271);
  const SE3d G(SO3d::exp(Vec3(0.1, -0.7, 0.3)), Vec3(20.0, -5.0, 7.0));
  const auto est = moved(G, gt);
  const auto se3 = semlio::eval::ate(gt, est);
  CHECK(se3.count == 271);
  CHECK(se3.rmse_m < 1e-9);
  CHECK((se3.alignment.T_gt_est * G).log().norm() < 1e-9);
  // With no alignment every error is |G p - p|, computed here per frame.
  const auto none = semlio::eval::ate(gt, est, AteConfig{.alignment = Alignment::kNone});
  double max_e = 0.0;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const double e = (G * gt[i].translation() - gt[i].translation()).norm();
    CHECK(std::abs(none.errors_m[i] - e) < 1e-9);
    max_e = std::max(max_e, e);
  }
  CHECK(std::abs(none.max_m - max_e) < 1e-9);
}

TEST_CASE("ATE on real KITTI 04: a linear position drift has closed-form statistics", "[eval]") {
  // est_i = gt_i shifted by i * v: without alignment the error of frame i is
  // i |v|, so over n = 271 frames: mean = max/2 = 135 |v|, median = 135 |v|,
  // rmse = |v| sqrt(sum i^2 / n) = |v| sqrt((n - 1)(2n - 1) / 6).
  const auto gt = kitti04();
  const std::size_t n = gt.size();
  const Vec3 v(0.003, -0.001, 0.002);
  std::vector<SE3d> est;
  for (std::size_t i = 0; i < n; ++i) {
    est.emplace_back(gt[i].so3(), gt[i].translation() + static_cast<double>(i) * v);
  }
  const auto r = semlio::eval::ate(gt, est, AteConfig{.alignment = Alignment::kNone});
  const double nv = v.norm();
  const auto nd = static_cast<double>(n);
  CHECK(std::abs(r.mean_m - 135.0 * nv) < 1e-9);
  CHECK(std::abs(r.median_m - 135.0 * nv) < 1e-9);
  CHECK(std::abs(r.max_m - 270.0 * nv) < 1e-9);
  CHECK(std::abs(r.rmse_m - nv * std::sqrt((nd - 1.0) * (2.0 * nd - 1.0) / 6.0)) < 1e-9);
  // A constant scale about frame 0 (which KITTI puts at the origin): Sim3
  // recovers 1/s exactly, SE3 leaves a residual.
  const double s = 1.03;
  std::vector<SE3d> scaled;
  for (const SE3d& T : gt) scaled.emplace_back(T.so3(), s * T.translation());
  const auto sim3 = semlio::eval::ate(gt, scaled, AteConfig{.alignment = Alignment::kSim3});
  CHECK(std::abs(sim3.alignment.scale - 1.0 / s) < 1e-12);
  CHECK(sim3.rmse_m < 1e-9);
  CHECK(semlio::eval::ate(gt, scaled).rmse_m > 0.1);
}

}  // namespace test_ate
