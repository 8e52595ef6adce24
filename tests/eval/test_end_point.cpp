// End-point error: a constant world transform of the whole estimate cancels,
// a drift of the last pose is measured in the first pose's frame, and
// mismatched inputs are ValueErrors.
#include <catch2/catch.hpp>

#include <semlio/core/error.hpp>
#include <semlio/eval/end_point.hpp>

#include <cmath>
#include <vector>

namespace test_end_point {  // one namespace per test file: the area compiles as one TU

using semlio::SE3d;
using semlio::SO3d;
using Vec3 = Eigen::Vector3d;

namespace {

// A 20-pose arc: 1 m steps turning 3 deg each, climbing 0.05 m.
std::vector<SE3d> arc() {
  std::vector<SE3d> out;
  for (int i = 0; i < 20; ++i) {
    const double yaw = 0.0523598775598 * i;
    out.emplace_back(SO3d::exp(Vec3(0.0, 0.0, yaw)), Vec3(10.0 * std::sin(yaw), 10.0 * (1.0 - std::cos(yaw)), 0.05 * i));
  }
  return out;
}

}  // namespace

TEST_CASE("end-point error: a world transform of the estimate cancels, a drift of the last pose does not",
          "[eval]") {
  const std::vector<SE3d> gt = arc();
  // The estimate in another world frame (its first pose is not the identity).
  const SE3d W(SO3d::exp(Vec3(0.1, -0.2, 0.7)), Vec3(3.0, -1.0, 2.0));
  std::vector<SE3d> est;
  for (const SE3d& p : gt) est.push_back(W * p);
  const semlio::eval::EndPointError same = semlio::eval::end_point_error(gt, est);
  CHECK(same.translation_m < 1e-9);
  CHECK(same.rotation_deg < 1e-6);

  // The last pose drifted by D in its own frame: gt_n D. The error is D itself.
  const SE3d D(SO3d::exp(Vec3(0.0, 0.0, 2.0 * 3.14159265358979 / 180.0)), Vec3(0.3, -0.4, 0.0));
  est.back() = W * gt.back() * D;
  const semlio::eval::EndPointError drift = semlio::eval::end_point_error(gt, est);
  CHECK(drift.translation_m == Approx(0.5).margin(1e-9));
  CHECK(drift.rotation_deg == Approx(2.0).margin(1e-9));

  // A drift of an intermediate pose does not count.
  est = gt;
  est[10] = est[10] * D;
  CHECK(semlio::eval::end_point_error(gt, est).translation_m < 1e-9);
}

TEST_CASE("end-point error: empty or mismatched trajectories are ValueErrors", "[eval]") {
  const std::vector<SE3d> gt = arc();
  CHECK_THROWS_AS(semlio::eval::end_point_error({}, {}), semlio::ValueError);
  CHECK_THROWS_AS(semlio::eval::end_point_error(gt, std::vector<SE3d>(gt.begin(), gt.end() - 1)), semlio::ValueError);
}

}  // namespace test_end_point
