// KITTI and TUM trajectory files and the camera <-> lidar frame conversion.
#include <catch2/catch.hpp>

#include <semlio/io/kitti.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_kitti_tmp.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace test_trajectory {  // one namespace per test file: the area compiles as one TU

namespace {

namespace io = semlio::io;
using semlio::SE3d;

SE3d pose_of(double a, double b, double c, double d, double e, double f) {
  return SE3d::exp((SE3d::Vector6() << a, b, c, d, e, f).finished());
}

double max_diff(const SE3d& A, const SE3d& B) { return (A.matrix() - B.matrix()).cwiseAbs().maxCoeff(); }

}  // namespace

TEST_CASE("real KITTI ground truth reads: 04 full (271 poses), 00 prefix (200 poses)", "[io]") {
  const auto p04 = io::read_kitti_poses(semlio_test::data_path("kitti/poses/04.txt"));
  CHECK(p04.size() == 271);  // data README: sequence 04 has 271 poses
  const auto p00 = io::read_kitti_poses(semlio_test::data_path("kitti/poses/00_first200.txt"));
  REQUIRE(p00.size() == 200);
  // First pose of 00 is the identity (to printing precision); the second is
  // 0.8586941 m ahead along camera z (line 2 of 00.txt).
  CHECK(max_diff(p00[0], SE3d()) < 1e-6);
  CHECK(p00[1].translation().z() == Approx(0.8586941).margin(1e-12));
  CHECK(p00[1].translation().x() == Approx(-0.04690294).margin(1e-12));
  // Sequence 04 drives about 390 m: far more than 300 m, less than 500 m.
  double length = 0.0;
  for (std::size_t i = 1; i < p04.size(); ++i) length += (p04[i].translation() - p04[i - 1].translation()).norm();
  CHECK(length > 300.0);
  CHECK(length < 500.0);
}

TEST_CASE("KITTI poses round trip through the writer", "[io]") {
  semlio_test::KittiTempDir dir("traj");
  const auto poses = io::read_kitti_poses(semlio_test::data_path("kitti/poses/00_first200.txt"));
  io::write_kitti_poses(dir.file("p.txt"), poses);
  const auto back = io::read_kitti_poses(dir.file("p.txt"));
  REQUIRE(back.size() == poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) CHECK(max_diff(back[i], poses[i]) < 1e-12);
  // Synthetic poses with large rotations and translations.
  std::vector<SE3d> synth;
  for (int i = 0; i < 20; ++i) synth.push_back(pose_of(10.0 * i, -3.0, 0.5 * i, 0.1 * i, -0.2, 0.15 * i));
  io::write_kitti_poses(dir.file("q.txt"), synth);
  const auto back2 = io::read_kitti_poses(dir.file("q.txt"));
  REQUIRE(back2.size() == synth.size());
  for (std::size_t i = 0; i < synth.size(); ++i) CHECK(max_diff(back2[i], synth[i]) < 1e-12);
}

TEST_CASE("KITTI poses: malformed lines give typed errors with path and line", "[io]") {
  semlio_test::KittiTempDir dir("traj");
  const std::string good = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  const auto check_throws = [&](const std::string& body, auto tag, const std::string& what) {
    using E = decltype(tag);
    semlio_test::write_text(dir.file("p.txt"), good + body);
    CHECK_THROWS_AS(io::read_kitti_poses(dir.file("p.txt")), E);
    CHECK_THROWS_WITH(io::read_kitti_poses(dir.file("p.txt")), Catch::Contains("p.txt:2:") && Catch::Contains(what));
  };
  check_throws("1 0 0 0 0 1 0 0 0 0 1\n", semlio::FormatError{""}, "11 fields");
  check_throws("1 0 0 0 0 1 0 0 0 0 1 0 7\n", semlio::FormatError{""}, "13 fields");
  check_throws("1 0 0 0 0 1 0 0 0 0 1 abc\n", semlio::FormatError{""}, "'abc'");
  check_throws("1 0 0 0 0 1 0 0 0 0 1 1,5\n", semlio::FormatError{""}, "'1,5'");
  check_throws("1 0 0 nan 0 1 0 0 0 0 1 0\n", semlio::ValueError{""}, "not finite");
  check_throws("1 0 0 0 0 1 0 inf 0 0 1 0\n", semlio::ValueError{""}, "not finite");
  check_throws("1.01 0 0 0 0 1 0 0 0 0 1 0\n", semlio::ValueError{""}, "orthonormal");
  check_throws("1 0.1 0 0 0 1 0 0 0 0 1 0\n", semlio::ValueError{""}, "orthonormal");
  check_throws("-1 0 0 0 0 1 0 0 0 0 1 0\n", semlio::ValueError{""}, "reflection");
  check_throws("\n" + good, semlio::FormatError{""}, "blank line");
  // Just inside and just outside the documented tolerance (1e-5 on R^T R - I):
  // scaling R by (1 + s) changes its diagonal by about 2 s.
  semlio_test::write_text(dir.file("t.txt"), "1.000004 0 0 0 0 1 0 0 0 0 1 0\n");
  CHECK(io::read_kitti_poses(dir.file("t.txt")).size() == 1);
  semlio_test::write_text(dir.file("t.txt"), "1.000006 0 0 0 0 1 0 0 0 0 1 0\n");
  CHECK_THROWS_AS(io::read_kitti_poses(dir.file("t.txt")), semlio::ValueError);
  // Missing and empty files; trailing blank lines and CRLF are fine.
  CHECK_THROWS_AS(io::read_kitti_poses(dir.file("none.txt")), semlio::IoError);
  semlio_test::write_text(dir.file("e.txt"), "");
  CHECK_THROWS_AS(io::read_kitti_poses(dir.file("e.txt")), semlio::FormatError);
  semlio_test::write_text(dir.file("e.txt"), "\n  \n");
  CHECK_THROWS_AS(io::read_kitti_poses(dir.file("e.txt")), semlio::FormatError);
  semlio_test::write_text(dir.file("c.txt"), "1 0 0 0 0 1 0 0 0 0 1 0\r\n1 0 0 1 0 1 0 0 0 0 1 0\r\n\r\n");
  const auto c = io::read_kitti_poses(dir.file("c.txt"));
  REQUIRE(c.size() == 2);
  CHECK(c[1].translation().x() == 1.0);
}

TEST_CASE("TUM trajectory: round trip, detection and bad input", "[io]") {
  semlio_test::KittiTempDir dir("traj");
  std::vector<io::StampedPose> traj;
  for (int i = 0; i < 30; ++i) {
    traj.push_back({1317384506.40 + 0.1 * i, pose_of(i, 0.5 * i, -0.1, 0.3, -0.02 * i, 0.5 + 0.2 * i)});
  }
  io::write_tum_trajectory(dir.file("t.tum"), traj);
  const auto back = io::read_tum_trajectory(dir.file("t.tum"));
  REQUIRE(back.size() == traj.size());
  for (std::size_t i = 0; i < traj.size(); ++i) {
    CHECK(back[i].stamp_s == traj[i].stamp_s);
    CHECK(max_diff(back[i].pose, traj[i].pose) < 1e-12);
  }
  CHECK(io::looks_like_tum(dir.file("t.tum")));
  CHECK_FALSE(io::looks_like_tum(semlio_test::data_path("kitti/poses/04.txt")));

  // Hand-written line: 90 deg about z (qz = qw = sqrt(1/2)), comments skipped.
  semlio_test::write_text(dir.file("h.tum"), "# timestamp tx ty tz qx qy qz qw\n\n0.5 1 2 3 0 0 0.7071068 0.7071068\n");
  CHECK(io::looks_like_tum(dir.file("h.tum")));
  const auto h = io::read_tum_trajectory(dir.file("h.tum"));
  REQUIRE(h.size() == 1);
  CHECK(h[0].stamp_s == 0.5);
  CHECK((h[0].pose * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(1, 3, 3)).norm() < 1e-6);

  const auto bad = [&](const std::string& text, auto tag, const std::string& what) {
    using E = decltype(tag);
    semlio_test::write_text(dir.file("b.tum"), "0 0 0 0 0 0 0 1\n" + text);
    CHECK_THROWS_AS(io::read_tum_trajectory(dir.file("b.tum")), E);
    CHECK_THROWS_WITH(io::read_tum_trajectory(dir.file("b.tum")), Catch::Contains("b.tum:2:") && Catch::Contains(what));
  };
  bad("1 0 0 0 0 0 1\n", semlio::FormatError{""}, "7 fields");
  bad("1 0 0 x 0 0 0 1\n", semlio::FormatError{""}, "'x'");
  bad("1 0 0 nan 0 0 0 1\n", semlio::ValueError{""}, "not finite");
  bad("1 0 0 0 0 0 0 2\n", semlio::ValueError{""}, "norm");
  bad("-1 0 0 0 0 0 0 1\n", semlio::ValueError{""}, "backwards");
  semlio_test::write_text(dir.file("e.tum"), "# only a comment\n");
  CHECK_THROWS_AS(io::read_tum_trajectory(dir.file("e.tum")), semlio::FormatError);
  CHECK_THROWS_AS(io::read_tum_trajectory(dir.file("none.tum")), semlio::IoError);
  CHECK_THROWS_AS(io::looks_like_tum(dir.file("none.tum")), semlio::IoError);
}

TEST_CASE("camera <-> lidar conversion: T_i = Tr^-1 P_i Tr and back", "[io]") {
  const auto calib = io::read_kitti_calib(semlio_test::data_path("kitti/calib/calib_04-10_Tr_RECONSTRUCTED.txt"));
  REQUIRE(calib.T_cam0_velo.has_value());
  const SE3d Tr = *calib.T_cam0_velo;
  const auto P = io::read_kitti_poses(semlio_test::data_path("kitti/poses/04.txt"));
  const auto T = io::camera_to_lidar(P, Tr);
  REQUIRE(T.size() == P.size());
  for (std::size_t i = 0; i < P.size(); i += 10) {
    // Definition: a lidar point of frame i, seen in lidar frame 0, equals the
    // same point taken through camera coordinates.
    const Eigen::Vector3d p_lidar_i(3.0, -1.0, 0.5);
    const Eigen::Vector3d via_camera = Tr.inverse() * (P[i] * (Tr * p_lidar_i));
    CHECK((T[i] * p_lidar_i - via_camera).norm() < 1e-9);
  }
  // The vehicle drives forward: lidar x (forward) grows, lidar z stays small
  // compared with the distance driven (camera z is lidar x).
  CHECK(T.back().translation().x() > 300.0);
  CHECK(std::abs(T.back().translation().x() - P.back().translation().z()) < 5.0);
  const auto back = io::lidar_to_camera(T, Tr);
  for (std::size_t i = 0; i < P.size(); ++i) CHECK(max_diff(back[i], P[i]) < 1e-9);
}

}  // namespace test_trajectory
