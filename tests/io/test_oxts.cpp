// KITTI raw OXTS reader/writer, timestamps, IMU samples and poses.
#include <catch2/catch.hpp>

#include <semlio/io/oxts.hpp>
#include <semlio_test/io_kitti_tmp.hpp>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace test_oxts {  // one namespace per test file: the area compiles as one TU

namespace {

namespace io = semlio::io;

// A line in the layout of KITTI raw 2011_09_26_drive_0001 (values made up,
// plausible: 49 deg N, stationary-ish, az ~ +g).
const std::string kLine =
    "49.015003823272 8.4342971002335 116.43032836914 0.035752 0.00903 -1.0130890800029 "
    "-0.017141324727 0.008932893 -0.0038 -0.015 -0.0011 0.21 0.13 9.82 0.23 0.12 9.81 "
    "-0.017 0.0021 0.0031 -0.017 0.0022 0.003 0.49 0.02 4 10 4 4 0\n";

io::OxtsRecord make_record(int i) {
  io::OxtsRecord r;
  r.stamp_s = 1317042145.594360375 + 0.01 * i;
  r.lat_deg = 49.015 + 1e-6 * i;
  r.lon_deg = 8.434 + 2e-6 * i;
  r.alt_m = 116.4 - 0.01 * i;
  r.roll_rad = 0.03;
  r.pitch_rad = -0.01 * i;
  r.yaw_rad = -1.01 + 0.001 * i;
  r.vn_mps = 1.0 / 3.0;
  r.ve_mps = -2.5;
  r.velocity_flu_mps = Eigen::Vector3d(10.1, -0.2, 0.01 * i);
  r.accel_body_mps2 = Eigen::Vector3d(0.2, -0.1, 9.81);
  r.accel_flu_mps2 = Eigen::Vector3d(0.21, -0.11, 9.80);
  r.gyro_body_radps = Eigen::Vector3d(0.001 * i, -0.002, 0.05);
  r.gyro_flu_radps = Eigen::Vector3d(0.0011, -0.0021, 0.051);
  r.pos_accuracy_m = 0.49;
  r.vel_accuracy_mps = 0.02;
  r.navstat = 4;
  r.numsats = 10 + i;
  r.posmode = 4;
  r.velmode = 4;
  r.orimode = i % 2;
  return r;
}

void write_dir(const semlio_test::KittiTempDir& dir, const std::vector<std::string>& stamps,
               const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& t : stamps) s += t + "\n";
  semlio_test::write_text(dir.file("oxts/timestamps.txt"), s);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    semlio_test::write_text(
        dir.file("oxts/data/" + std::string(10 - std::to_string(i).size(), '0') + std::to_string(i) + ".txt"),
        lines[i]);
  }
}

}  // namespace

TEST_CASE("OXTS timestamps: Unix-like seconds without time zone", "[io]") {
  // date -u -d "2011-09-26" +%s = 1316995200; 13:02:25 = 46945 s.
  CHECK(io::parse_oxts_timestamp("2011-09-26 13:02:25.594360375") == 1316995200.0 + 46945.594360375);
  CHECK(io::parse_oxts_timestamp("1970-01-01 00:00:00.000000000") == 0.0);
  CHECK(io::parse_oxts_timestamp("2000-02-29 00:00:00") == 951782400.0);  // leap day
  CHECK(io::parse_oxts_timestamp("2000-03-01 00:00:00.5") == 951782400.0 + 86400.5);
  CHECK(io::format_oxts_timestamp(0.0) == "1970-01-01 00:00:00.000000000");
  CHECK(io::format_oxts_timestamp(951782400.5) == "2000-02-29 00:00:00.500000000");
  CHECK(io::format_oxts_timestamp(1316995200.0 + 86399.25) == "2011-09-26 23:59:59.250000000");
  // Small (simulator) stamps come back to within 0.5 ns.
  for (int i = 0; i < 100; ++i) {
    const double t = 0.1 * i + 1e-12 * i;
    CHECK(std::abs(io::parse_oxts_timestamp(io::format_oxts_timestamp(t)) - t) <= 5e-10);
  }
  CHECK_THROWS_AS(io::format_oxts_timestamp(-1.0), semlio::ValueError);
  CHECK_THROWS_AS(io::format_oxts_timestamp(std::nan("")), semlio::ValueError);
  // Round trip: the formatted text reads back to the same double.
  for (int i = 0; i < 1000; ++i) {
    const double t = 1317042145.594360375 + 0.0103 * i + 1e-7 * (i % 7);
    CHECK(io::parse_oxts_timestamp(io::format_oxts_timestamp(t)) == t);
  }
  // Malformed or impossible dates and times.
  for (const char* bad : {"2011-09-26", "2011-13-01 00:00:00", "2011-02-29 00:00:00", "2011-09-26 24:00:00",
                          "2011/09/26 13:02:25.5", "2011-09-26 13:02:2x.5", "2011-09-26 13:60:00",
                          "2011-09-26 13:02:25.", "2011-09-26 13:02:25.5e3", "2011-09-26 13:02:25 x"}) {
    CHECK_THROWS_AS(io::parse_oxts_timestamp(bad, "ts.txt", 3), semlio::FormatError);
  }
  CHECK_THROWS_WITH(io::parse_oxts_timestamp("2011-13-01 00:00:00", "ts.txt", 3),
                    Catch::Contains("ts.txt:3:") && Catch::Contains("2011-13-01"));
}

TEST_CASE("OXTS: one KITTI-layout line parses field by field", "[io]") {
  io::OxtsRecord r;
  io::parse_oxts_line(kLine, "x.txt", 1, r);
  CHECK(r.lat_deg == 49.015003823272);
  CHECK(r.lon_deg == 8.4342971002335);
  CHECK(r.alt_m == 116.43032836914);
  CHECK(r.yaw_rad == -1.0130890800029);
  CHECK(r.velocity_flu_mps == Eigen::Vector3d(-0.0038, -0.015, -0.0011));
  CHECK(r.accel_body_mps2 == Eigen::Vector3d(0.21, 0.13, 9.82));
  CHECK(r.accel_flu_mps2 == Eigen::Vector3d(0.23, 0.12, 9.81));
  CHECK(r.gyro_body_radps == Eigen::Vector3d(-0.017, 0.0021, 0.0031));
  CHECK(r.gyro_flu_radps == Eigen::Vector3d(-0.017, 0.0022, 0.003));
  CHECK(r.pos_accuracy_m == 0.49);
  CHECK(r.vel_accuracy_mps == 0.02);
  CHECK(r.navstat == 4);
  CHECK(r.numsats == 10);
  CHECK(r.orimode == 0);
  const auto imu = io::imu_samples({r});
  REQUIRE(imu.size() == 1);
  CHECK(imu[0].gyro_radps == r.gyro_body_radps);
  CHECK(imu[0].accel_mps2 == r.accel_body_mps2);
}

TEST_CASE("OXTS directory round trip through the writer", "[io]") {
  semlio_test::KittiTempDir dir("oxts");
  std::vector<io::OxtsRecord> recs;
  for (int i = 0; i < 12; ++i) recs.push_back(make_record(i));
  io::write_oxts(dir.file("oxts"), recs);
  CHECK(std::filesystem::exists(dir.file("oxts/data/0000000011.txt")));
  const auto back = io::read_oxts(dir.file("oxts"));
  REQUIRE(back.size() == recs.size());
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const auto& a = recs[i];
    const auto& b = back[i];
    CHECK(b.stamp_s == a.stamp_s);
    CHECK((b.lat_deg == a.lat_deg && b.lon_deg == a.lon_deg && b.alt_m == a.alt_m));
    CHECK((b.roll_rad == a.roll_rad && b.pitch_rad == a.pitch_rad && b.yaw_rad == a.yaw_rad));
    CHECK((b.vn_mps == a.vn_mps && b.ve_mps == a.ve_mps));
    CHECK(b.velocity_flu_mps == a.velocity_flu_mps);
    CHECK(b.accel_body_mps2 == a.accel_body_mps2);
    CHECK(b.accel_flu_mps2 == a.accel_flu_mps2);
    CHECK(b.gyro_body_radps == a.gyro_body_radps);
    CHECK(b.gyro_flu_radps == a.gyro_flu_radps);
    CHECK((b.pos_accuracy_m == a.pos_accuracy_m && b.vel_accuracy_mps == a.vel_accuracy_mps));
    CHECK((b.navstat == a.navstat && b.numsats == a.numsats && b.posmode == a.posmode && b.velmode == a.velmode &&
           b.orimode == a.orimode));
  }
  const auto imu = io::imu_samples(back);
  REQUIRE(imu.size() == 12);
  CHECK(imu[5].stamp_s == recs[5].stamp_s);
  CHECK(imu[5].gyro_radps == recs[5].gyro_body_radps);
}

TEST_CASE("OXTS: bad directories, lines and timestamps give typed errors", "[io]") {
  const std::string t0 = "2011-09-26 13:02:25.594360375";
  const std::string t1 = "2011-09-26 13:02:25.604340375";
  {
    semlio_test::KittiTempDir dir("oxts");
    write_dir(dir, {t0, t1}, {kLine, "1 2 3\n"});
    CHECK_THROWS_AS(io::read_oxts(dir.file("oxts")), semlio::FormatError);
    CHECK_THROWS_WITH(io::read_oxts(dir.file("oxts")),
                      Catch::Contains("0000000001.txt:1:") && Catch::Contains("3 fields"));
  }
  {
    semlio_test::KittiTempDir dir("oxts");
    std::string l = kLine;
    l.replace(l.find("116.43"), 6, "abc.43");
    write_dir(dir, {t0}, {l});
    CHECK_THROWS_WITH(io::read_oxts(dir.file("oxts")),
                      Catch::Contains("0000000000.txt:1:") && Catch::Contains("abc.43"));
  }
  {
    semlio_test::KittiTempDir dir("oxts");
    std::string l = kLine;
    l.replace(l.find("116.43032836914"), 15, "nan");
    write_dir(dir, {t0}, {l});
    CHECK_THROWS_AS(io::read_oxts(dir.file("oxts")), semlio::ValueError);
  }
  {
    semlio_test::KittiTempDir dir("oxts");
    std::string l = kLine;
    l.replace(l.find(" 4 10 "), 6, " 4.5 10 ");
    write_dir(dir, {t0}, {l});
    CHECK_THROWS_WITH(io::read_oxts(dir.file("oxts")), Catch::Contains("must be an integer"));
  }
  {
    semlio_test::KittiTempDir dir("oxts");  // time going backwards, line 2
    write_dir(dir, {t1, t0}, {kLine, kLine});
    CHECK_THROWS_AS(io::read_oxts(dir.file("oxts")), semlio::ValueError);
    CHECK_THROWS_WITH(io::read_oxts(dir.file("oxts")),
                      Catch::Contains("timestamps.txt:2:") && Catch::Contains("backwards"));
  }
  {
    semlio_test::KittiTempDir dir("oxts");  // malformed timestamp, line 2
    write_dir(dir, {t0, "2011-09-26T13:02:25"}, {kLine, kLine});
    CHECK_THROWS_WITH(io::read_oxts(dir.file("oxts")), Catch::Contains("timestamps.txt:2:"));
  }
  {
    semlio_test::KittiTempDir dir("oxts");  // more data files than timestamps
    write_dir(dir, {t0}, {kLine, kLine});
    CHECK_THROWS_WITH(io::read_oxts(dir.file("oxts")), Catch::Contains("2 .txt files") && Catch::Contains("1 lines"));
  }
  {
    semlio_test::KittiTempDir dir("oxts");  // a gap: file 1 missing, file 2 present
    write_dir(dir, {t0, t1}, {kLine, kLine, kLine});
    std::filesystem::remove(dir.file("oxts/data/0000000001.txt"));
    CHECK_THROWS_AS(io::read_oxts(dir.file("oxts")), semlio::IoError);
    CHECK_THROWS_WITH(io::read_oxts(dir.file("oxts")), Catch::Contains("0000000001.txt"));
  }
  {
    semlio_test::KittiTempDir dir("oxts");  // empty data file and empty timestamps
    write_dir(dir, {t0}, {"\n"});
    CHECK_THROWS_WITH(io::read_oxts(dir.file("oxts")), Catch::Contains("empty OXTS data file"));
    write_dir(dir, {}, {});
    CHECK_THROWS_AS(io::read_oxts(dir.file("oxts")), semlio::FormatError);
  }
  {
    semlio_test::KittiTempDir dir("oxts");  // missing timestamps / data directory
    CHECK_THROWS_AS(io::read_oxts(dir.file("oxts")), semlio::IoError);
    semlio_test::write_text(dir.file("oxts/timestamps.txt"), t0 + "\n");
    CHECK_THROWS_AS(io::read_oxts(dir.file("oxts")), semlio::IoError);
  }
}

TEST_CASE("OXTS poses: Mercator projection, relative to the first record", "[io]") {
  constexpr double kPi = 3.14159265358979323846;
  io::OxtsRecord a;
  a.lat_deg = 49.0;
  a.lon_deg = 8.4;
  a.alt_m = 100.0;
  // Facing east (yaw 0), move east by dlon: x_merc = s R dlon, s = cos(lat0).
  io::OxtsRecord b = a;
  b.lon_deg += 1e-4;
  const double east_m = std::cos(49.0 * kPi / 180.0) * io::kOxtsEarthRadius_m * 1e-4 * kPi / 180.0;
  auto poses = io::oxts_poses({a, b});
  REQUIRE(poses.size() == 2);
  CHECK((poses[0].matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff() < 1e-12);
  CHECK((poses[1].translation() - Eigen::Vector3d(east_m, 0, 0)).norm() < 1e-6);
  // Facing north (yaw +90 deg, counter-clockwise from east), move north and up:
  // forward is body x, up is body z. Mercator: dy = s R (ln tan(45+lat1/2) - ln tan(45+lat0/2)).
  a.yaw_rad = kPi / 2;
  b = a;
  b.lat_deg += 1e-4;
  b.alt_m += 2.0;
  const auto merc = [&](double lat) { return std::log(std::tan((90.0 + lat) * kPi / 360.0)); };
  const double north_m = std::cos(49.0 * kPi / 180.0) * io::kOxtsEarthRadius_m * (merc(49.0001) - merc(49.0));
  CHECK(north_m == Approx(11.1).epsilon(0.01));  // 1e-4 deg of latitude ~ 11.1 m
  poses = io::oxts_poses({a, b});
  CHECK((poses[1].translation() - Eigen::Vector3d(north_m, 0, 2.0)).norm() < 1e-6);
  // Roll positive = left side up: body y gets a +z component in the world.
  io::OxtsRecord c = a;
  c.yaw_rad = 0.0;
  c.roll_rad = 0.1;
  const auto T = io::oxts_pose_mercator(c, 1.0);
  CHECK((T.rotation() * Eigen::Vector3d::UnitY()).z() == Approx(std::sin(0.1)));
  // Pitch positive = front down: body x gets a -z component.
  c.roll_rad = 0.0;
  c.pitch_rad = 0.1;
  CHECK((io::oxts_pose_mercator(c, 1.0).rotation() * Eigen::Vector3d::UnitX()).z() == Approx(-std::sin(0.1)));
}

}  // namespace test_oxts

namespace test_oxts {

TEST_CASE("OXTS timestamps with 19 or more fraction digits parse without overflow", "[io]") {
  // Audit issue 8: the fraction digits were accumulated in an int64 only to
  // check that they are digits; 19 and more digits overflowed (UB).
  const double nine = io::parse_oxts_timestamp("2011-09-26 13:02:25.594360375");
  CHECK(io::parse_oxts_timestamp("2011-09-26 13:02:25.5943603750000000000") == nine);             // 19 digits
  CHECK(io::parse_oxts_timestamp("2011-09-26 13:02:25.59436037500000000000000000000000") == nine);  // 32
  CHECK(io::parse_oxts_timestamp("2011-09-26 13:02:25.9999999999999999999") == 1316995200.0 + 46946.0);
  // Still rejected when a digit is not one.
  CHECK_THROWS_AS(io::parse_oxts_timestamp("2011-09-26 13:02:25.99999999999999999999x", "ts.txt", 2),
                  semlio::FormatError);
}

}  // namespace test_oxts
