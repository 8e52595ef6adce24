// KITTI odometry metric: segment scheme on hand-made trajectories, and the
// real KITTI 04 ground truth against perturbed copies whose per-segment
// errors are known in closed form.
#include <catch2/catch.hpp>

#include <semlio/core/error.hpp>
#include <semlio/eval/kitti_metric.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio_test/data.hpp>

#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

namespace test_kitti_metric {  // one namespace per test file: the area compiles as one TU

using semlio::SE3d;
using semlio::SO3d;
using semlio::eval::KittiMetricConfig;
using semlio::eval::KittiMetricStatus;
using Vec3 = Eigen::Vector3d;

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

// n poses along z, 1 m apart (distances are exact integers in double).
std::vector<SE3d> straight_line(std::size_t n) {
  std::vector<SE3d> out;
  for (std::size_t i = 0; i < n; ++i) out.emplace_back(SO3d(), Vec3(0.0, 0.0, static_cast<double>(i)));
  return out;
}

std::vector<SE3d> kitti04() { return semlio::io::read_kitti_poses(semlio_test::data_path("kitti/poses/04.txt")); }

// Checks that the segments are exactly the devkit's: for every start frame
// 0, 10, 20, ... and every length, a segment exists iff some frame lies
// farther than d_first + length, and it ends at the first such frame.
void check_segment_scheme(const std::vector<SE3d>& gt, const semlio::eval::KittiMetricReport& r) {
  std::vector<double> d{0.0};
  for (std::size_t i = 1; i < gt.size(); ++i) d.push_back(d.back() + (gt[i].translation() - gt[i - 1].translation()).norm());
  std::size_t k = 0;
  for (std::size_t first = 0; first < gt.size(); first += 10) {
    for (int m = 1; m <= 8; ++m) {
      const double len = 100.0 * m;
      std::size_t last = first;
      while (last < gt.size() && !(d[last] > d[first] + len)) ++last;
      if (last == gt.size()) continue;
      REQUIRE(k < r.segments.size());
      CHECK(r.segments[k].first_frame == first);
      CHECK(r.segments[k].last_frame == last);
      CHECK(r.segments[k].length_m == len);
      ++k;
    }
  }
  CHECK(k == r.segments.size());
}

}  // namespace

TEST_CASE("KITTI metric: distances accumulate consecutive ground-truth steps", "[eval]") {
  const std::vector<SE3d> gt{SE3d(SO3d(), Vec3(0, 0, 0)), SE3d(SO3d(), Vec3(3, 4, 0)), SE3d(SO3d(), Vec3(3, 4, 12))};
  const auto d = semlio::eval::trajectory_distances_m(gt);
  REQUIRE(d.size() == 3);
  CHECK(d[0] == 0.0);
  CHECK(d[1] == 5.0);
  CHECK(d[2] == 17.0);
}

TEST_CASE("KITTI metric: segment scheme on a straight line with 1 m steps", "[eval]") {
  // d_i = i, so the segment of length L from frame f ends at f + L + 1 (the
  // first frame strictly farther than L); it exists while f + L + 1 <= 999.
  const auto gt = straight_line(1000);
  const auto r = semlio::eval::kitti_metric(gt, gt);
  std::size_t expected = 0;
  for (int m = 1; m <= 8; ++m) expected += static_cast<std::size_t>((998 - 100 * m) / 10 + 1);
  CHECK(r.segment_count == expected);  // 90 + 80 + ... + 20 = 440
  CHECK(expected == 440);
  CHECK(r.status == KittiMetricStatus::kOk);
  for (const auto& s : r.segments) {
    CHECK(s.last_frame == s.first_frame + static_cast<std::size_t>(s.length_m) + 1);
    CHECK(s.first_frame % 10 == 0);
    CHECK(s.translation_error == 0.0);
    CHECK(s.rotation_error_rad_per_m == 0.0);
  }
  check_segment_scheme(gt, r);
  REQUIRE(r.per_length.size() == 8);
  CHECK(r.per_length[0].count == 90);
  CHECK(r.per_length[7].count == 20);
  CHECK(r.per_length[7].length_m == 800.0);
}

TEST_CASE("KITTI metric: a scaled straight line gives |s - 1| (L + 1) / L per segment", "[eval]") {
  // Relative translations scale by s, so |t_E| = |s - 1| * chord with chord =
  // L + 1 on this line; rotations are untouched.
  const auto gt = straight_line(1000);
  const double s = 1.02;
  std::vector<SE3d> est;
  for (const SE3d& T : gt) est.emplace_back(T.so3(), s * T.translation());
  const auto r = semlio::eval::kitti_metric(gt, est);
  double sum = 0.0;
  std::size_t count = 0;
  for (int m = 1; m <= 8; ++m) {
    const double L = 100.0 * m;
    const auto n = static_cast<std::size_t>((998 - 100 * m) / 10 + 1);
    sum += static_cast<double>(n) * std::abs(s - 1.0) * (L + 1.0) / L;
    count += n;
  }
  CHECK(std::abs(r.translation_error - sum / static_cast<double>(count)) < 1e-12);
  CHECK(std::abs(r.translation_error_pct - 100.0 * sum / static_cast<double>(count)) < 1e-10);
  CHECK(r.rotation_error_rad_per_m == 0.0);
  REQUIRE(r.per_length.size() == 8);
  CHECK(std::abs(r.per_length[0].translation_error_pct - 100.0 * 0.02 * 101.0 / 100.0) < 1e-10);
  CHECK(std::abs(r.per_length[7].translation_error_pct - 100.0 * 0.02 * 801.0 / 800.0) < 1e-10);
}

TEST_CASE("KITTI metric: a constant heading error on a straight line, hand-computed", "[eval]") {
  // est turns the whole path by alpha about y at frame 0 and keeps the
  // orientations: the relative rotation is unchanged (r_err = 0) and the
  // relative translation (L + 1) z-hat turns by alpha: |t_E| = 2 sin(alpha/2) (L + 1).
  const auto gt = straight_line(400);
  const double alpha = 0.05;
  const SO3d Ry = SO3d::exp(Vec3(0.0, alpha, 0.0));
  std::vector<SE3d> est;
  for (const SE3d& T : gt) est.emplace_back(T.so3(), Ry * T.translation());
  const auto r = semlio::eval::kitti_metric(gt, est);
  REQUIRE(r.segment_count > 0);
  for (const auto& seg : r.segments) {
    CHECK(std::abs(seg.translation_error - 2.0 * std::sin(alpha / 2.0) * (seg.length_m + 1.0) / seg.length_m) < 1e-12);
    CHECK(seg.rotation_error_rad_per_m < 1e-9);
  }
}

TEST_CASE("KITTI metric: too short a trajectory has no segments and no NaN", "[eval]") {
  const auto gt = straight_line(100);  // 99 m
  const auto r = semlio::eval::kitti_metric(gt, gt);
  CHECK(r.status == KittiMetricStatus::kNoSegments);
  CHECK(r.segment_count == 0);
  CHECK(r.translation_error_pct == 0.0);
  CHECK(r.rotation_error_deg_per_100m == 0.0);
  CHECK(r.per_length.empty());
  const auto empty = semlio::eval::kitti_metric({}, {});
  CHECK(empty.status == KittiMetricStatus::kNoSegments);
}

TEST_CASE("KITTI metric: bad input and config throw typed errors", "[eval]") {
  const auto gt = straight_line(10);
  auto shorter = gt;
  shorter.pop_back();
  CHECK_THROWS_AS(semlio::eval::kitti_metric(gt, shorter), semlio::ValueError);
  CHECK_THROWS_WITH(semlio::eval::kitti_metric(gt, shorter), Catch::Contains("9 poses") && Catch::Contains("10"));
  CHECK_THROWS_AS(semlio::eval::kitti_metric(gt, gt, KittiMetricConfig{.step_frames = 0}), semlio::ConfigError);
  CHECK_THROWS_WITH(semlio::eval::kitti_metric(gt, gt, KittiMetricConfig{.lengths_m = {100.0, -5.0}}),
                    Catch::Contains("lengths_m") && Catch::Contains("-5"));
  CHECK_THROWS_AS(semlio::eval::kitti_metric(gt, gt, KittiMetricConfig{.lengths_m = {}}), semlio::ConfigError);
}

TEST_CASE("KITTI metric on real KITTI 04: segment scheme and rigid-move invariance", "[eval]") {
  const auto gt = kitti04();
  REQUIRE(gt.size() == 271);
  const auto self = semlio::eval::kitti_metric(gt, gt);
  CHECK(self.status == KittiMetricStatus::kOk);
  check_segment_scheme(gt, self);
  // 04 is ~394 m long: only 100, 200 and 300 m segments fit.
  REQUIRE(self.per_length.size() == 3);
  CHECK(self.per_length[2].length_m == 300.0);
  CHECK(self.translation_error == 0.0);
  CHECK(self.rotation_error_rad_per_m < 1e-9);
  // Moving the whole estimate rigidly changes no relative pose.
  const SE3d G(SO3d::exp(Vec3(0.3, 1.2, -0.4)), Vec3(100.0, -20.0, 3.0));
  std::vector<SE3d> est;
  for (const SE3d& T : gt) est.push_back(G * T);
  const auto r = semlio::eval::kitti_metric(gt, est);
  CHECK(r.segment_count == self.segment_count);
  CHECK(r.translation_error < 1e-12);
  CHECK(r.rotation_error_rad_per_m < 1e-9);
}

TEST_CASE("KITTI metric on real KITTI 04: constant scale s gives |s - 1| chord / L", "[eval]") {
  // est_i = (R_i, s t_i): relative rotations are equal, relative translations
  // scale by s, so |t_E| = |s - 1| |t_last - t_first| per segment.
  const auto gt = kitti04();
  const double s = 0.97;
  std::vector<SE3d> est;
  for (const SE3d& T : gt) est.emplace_back(T.so3(), s * T.translation());
  const auto r = semlio::eval::kitti_metric(gt, est);
  check_segment_scheme(gt, r);
  double sum = 0.0;
  for (const auto& seg : r.segments) {
    const double chord = (gt[seg.last_frame].translation() - gt[seg.first_frame].translation()).norm();
    const double expected = std::abs(s - 1.0) * chord / seg.length_m;
    CHECK(std::abs(seg.translation_error - expected) < 1e-12);
    CHECK(seg.rotation_error_rad_per_m < 1e-9);
    sum += expected;
  }
  const double mean = sum / static_cast<double>(r.segment_count);
  CHECK(std::abs(r.translation_error - mean) < 1e-12);
  CHECK(std::abs(r.translation_error_pct - 100.0 * mean) < 1e-9);
  // 04 is nearly straight, so chord ~ L and the error is close to |s - 1|.
  CHECK(r.translation_error_pct == Approx(3.0).epsilon(0.02));
}

TEST_CASE("KITTI metric on real KITTI 04: linear position drift v per frame gives (l - f)|v| / L", "[eval]") {
  // est_i = (R_i, t_i + i v): relative rotations equal, so
  // |t_E| = |R_f^T (l - f) v| = (l - f) |v|.
  const auto gt = kitti04();
  const Vec3 v(0.01, 0.002, -0.02);
  std::vector<SE3d> est;
  for (std::size_t i = 0; i < gt.size(); ++i) est.emplace_back(gt[i].so3(), gt[i].translation() + static_cast<double>(i) * v);
  const auto r = semlio::eval::kitti_metric(gt, est);
  REQUIRE(r.segment_count > 0);
  double sum = 0.0;
  for (const auto& seg : r.segments) {
    const double expected = static_cast<double>(seg.last_frame - seg.first_frame) * v.norm() / seg.length_m;
    CHECK(std::abs(seg.translation_error - expected) < 1e-12);
    sum += expected;
  }
  CHECK(std::abs(r.translation_error - sum / static_cast<double>(r.segment_count)) < 1e-12);
  CHECK(r.rotation_error_rad_per_m < 1e-9);
}

TEST_CASE("KITTI metric on real KITTI 04: yaw drift a per frame, closed form", "[eval]") {
  // est_i = Q(a i) gt_i with Q a rotation about the camera's vertical y axis
  // through the origin. Then E = gt_l^-1 Q(-a (l - f)) gt_l, so
  // angle(R_E) = a (l - f) and |t_E| = 2 |sin(a (l - f) / 2)| |t_l without its y part|.
  const auto gt = kitti04();
  const double a = 2e-4;  // rad per frame
  std::vector<SE3d> est;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    est.push_back(SE3d(SO3d::exp(Vec3(0.0, a * static_cast<double>(i), 0.0)), Vec3::Zero()) * gt[i]);
  }
  const auto r = semlio::eval::kitti_metric(gt, est);
  check_segment_scheme(gt, r);
  double sum_t = 0.0;
  double sum_r = 0.0;
  for (const auto& seg : r.segments) {
    const double theta = a * static_cast<double>(seg.last_frame - seg.first_frame);
    const Vec3 t = gt[seg.last_frame].translation();
    const double t_expected = 2.0 * std::abs(std::sin(theta / 2.0)) * std::hypot(t.x(), t.z()) / seg.length_m;
    const double r_expected = theta / seg.length_m;
    CHECK(std::abs(seg.translation_error - t_expected) < 1e-12);
    CHECK(std::abs(seg.rotation_error_rad_per_m - r_expected) < 1e-12);
    sum_t += t_expected;
    sum_r += r_expected;
  }
  const auto n = static_cast<double>(r.segment_count);
  CHECK(std::abs(r.translation_error - sum_t / n) < 1e-12);
  CHECK(std::abs(r.rotation_error_rad_per_m - sum_r / n) < 1e-12);
  CHECK(std::abs(r.rotation_error_deg_per_m - kDegPerRad * sum_r / n) < 1e-9);
  CHECK(std::abs(r.rotation_error_deg_per_100m - 100.0 * kDegPerRad * sum_r / n) < 1e-9);
  // Per-length means agree with the segments of that length.
  for (const auto& pl : r.per_length) {
    double s = 0.0;
    std::size_t c = 0;
    for (const auto& seg : r.segments) {
      if (seg.length_m != pl.length_m) continue;
      s += seg.rotation_error_rad_per_m;
      ++c;
    }
    CHECK(pl.count == c);
    CHECK(std::abs(pl.rotation_error_deg_per_100m - 100.0 * kDegPerRad * s / static_cast<double>(c)) < 1e-9);
  }
}

}  // namespace test_kitti_metric
