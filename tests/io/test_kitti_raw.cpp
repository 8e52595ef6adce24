// KITTI raw drives as published: frames, stamps (start file, blank lines, gaps),
// calibration discovery, OXTS as IMU samples and as a lidar reference trajectory.
#include <catch2/catch.hpp>

#include <semlio/io/kitti_raw.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_kitti_tmp.hpp>

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace test_kitti_raw {  // one namespace per test file: the area compiles as one TU

namespace {

namespace fs = std::filesystem;
namespace io = semlio::io;
using semlio::Scan;
using semlio::SE3d;

const std::string kDrive = "kitti_raw/2011_09_26/2011_09_26_drive_0009_sync";

std::string real(const std::string& relative) { return semlio_test::data_path(kDrive + "/" + relative); }

// Line `number` (1-based) of a text file, without its newline.
std::string line_of(const std::string& path, long number) {
  const std::string text = io::detail::read_file(path);
  std::string out;
  io::detail::for_each_line(text, [&](long line, std::string_view s) {
    if (line == number) out = std::string(s);
  });
  return out;
}

// A scan file of n points (x = k + 1, so none is dropped).
void write_bin(const std::string& path, int n) {
  Scan s;
  for (int k = 0; k < n; ++k) {
    s.points.emplace_back(static_cast<float>(k + 1), 0.5F, -1.0F);
    s.intensity.push_back(0.25F);
  }
  io::write_kitti_bin(path, s);
}

// A drive `<root>/2011_09_26/2011_09_26_drive_0009_sync` in a temp dir with the
// real timestamps files, the real OXTS packets 0..11 and tiny scans `frames`.
std::string make_drive(const semlio_test::KittiTempDir& dir, const std::vector<int>& frames, bool with_calib = true) {
  const std::string drive = "2011_09_26/2011_09_26_drive_0009_sync/";
  for (const char* f : {"velodyne_points/timestamps.txt", "velodyne_points/timestamps_start.txt",
                        "velodyne_points/timestamps_end.txt", "oxts/timestamps.txt"}) {
    fs::copy_file(real(f), dir.file(drive + f));
  }
  for (int k = 0; k < 12; ++k) {
    const std::string f = "oxts/data/" + io::detail::frame_stem(static_cast<std::size_t>(k), 10) + ".txt";
    fs::copy_file(real(f), dir.file(drive + f));
  }
  for (const int f : frames) {
    write_bin(
        dir.file(drive + "velodyne_points/data/" + io::detail::frame_stem(static_cast<std::size_t>(f), 10) + ".bin"),
        f + 1);
  }
  if (with_calib) {
    for (const char* f : {"calib_imu_to_velo.txt", "calib_velo_to_cam.txt"}) {
      fs::copy_file(semlio_test::data_path(std::string("kitti_raw/2011_09_26/") + f),
                    dir.file(std::string("2011_09_26/") + f));
    }
  }
  return dir.file(drive);
}

// Mutates `text` once: a byte replaced by one that matters to the parsers, a
// cut, an inserted or a repeated line.
std::string mutate(std::string text, std::mt19937& rng) {
  static const std::string kBytes = "0123456789-:. \n\r\tenx+\0";
  const auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
  if (text.empty()) return std::string(1, kBytes[pick(kBytes.size())]);
  const std::size_t at = pick(text.size());
  switch (pick(4)) {
    case 0:
      text[at] = kBytes[pick(kBytes.size())];
      break;
    case 1:
      text.resize(at);
      break;
    case 2:
      text.insert(at, std::string(1 + pick(3), kBytes[pick(kBytes.size())]));
      break;
    default: {
      const std::size_t end = text.find('\n', at);
      text.insert(at, text.substr(at, end == std::string::npos ? std::string::npos : end - at + 1));
    }
  }
  return text;
}

io::KittiRawDriveConfig calib_from(const std::string& path) {
  io::KittiRawDriveConfig c;
  c.calib_dir = path;
  return c;
}

}  // namespace

TEST_CASE("KITTI raw drive 0009 as published: 3 scans of a 447-line drive", "[io]") {
  const io::KittiRawDrive drive(semlio_test::data_path(kDrive + "/"));
  REQUIRE(drive.size() == 3);
  CHECK(drive.missing_frame_count() == 0);
  CHECK(drive.timestamp_line_count() == 447);
  CHECK(drive.interpolated_stamp_count() == 0);
  CHECK(drive.stamp_source() == io::KittiRawStampSource::sweep_start);
  // Stamps are the sweep starts, exactly as timestamps_start.txt reads.
  for (long i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(i);
    CHECK(drive.stamp(k) == io::parse_oxts_timestamp(line_of(real("velodyne_points/timestamps_start.txt"), i + 1)));
    CHECK(drive.sweep_middle_stamp(k) ==
          io::parse_oxts_timestamp(line_of(real("velodyne_points/timestamps.txt"), i + 1)));
    CHECK_FALSE(drive.stamp_interpolated(k));
  }
  // HDL-64E in KITTI: a sweep takes about 0.1035 s (start stamps 0.10344 and 0.10348 s apart here).
  CHECK(drive.sweep_period_s() == Approx(0.1035).margin(0.0005));
  CHECK_THAT(drive.scan_path(2), Catch::EndsWith("velodyne_points/data/0000000002.bin"));

  // Calibration from the parent folder (the published layout).
  CHECK(fs::path(drive.calib_dir()).filename() == "2011_09_26");
  const SE3d T_vi = drive.T_velo_imu();
  CHECK(T_vi.translation().x() == Approx(-8.086759e-01));  // calib_imu_to_velo.txt "T:" values
  CHECK(T_vi.translation().y() == Approx(3.195559e-01));
  CHECK(T_vi.translation().z() == Approx(-7.997231e-01));
  CHECK(T_vi.so3().matrix()(1, 2) == Approx(-1.482298e-02));
  const SE3d T_cv = drive.T_cam0_velo();
  CHECK(T_cv.so3().matrix()(0, 1) == Approx(-9.999714e-01));  // calib_velo_to_cam.txt R[0][1]
  CHECK(T_cv.translation().z() == Approx(-2.717806e-01));

  // The first scan: every 16-byte record but the dropped ones.
  io::ReadStats stats;
  const Scan s0 = drive.read(0, &stats);
  CHECK(s0.size() + stats.dropped() == 1957120 / 16);
  CHECK(s0.has_intensity());
  CHECK(s0.stamp_s == drive.stamp(0));
  std::string error = "stale";
  const Scan s2 = drive.read_or_empty(2, error);
  CHECK(error.empty());
  CHECK(s2.size() > 100000);
  CHECK_THROWS_AS(drive.read(3), semlio::ValueError);

  // OXTS: 12 packets downloaded out of 447 stamps; stamped 12-22 ms after the sweep middle.
  CHECK(drive.has_oxts());
  CHECK(drive.oxts_packet_count() == 12);
  // 13:08:24.969505176 - 13:08:24.957314930 (the two files' first lines).
  CHECK(drive.oxts_minus_scan_stamp_s(0).value() == Approx(0.012190246).margin(1e-6));
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(*drive.oxts_minus_scan_stamp_s(i) > 0.012 - 1e-3);
    CHECK(*drive.oxts_minus_scan_stamp_s(i) < 0.022);
  }
  const auto imu = drive.imu_samples();
  REQUIRE(imu.size() == 12);
  CHECK(imu[0].stamp_s == io::parse_oxts_timestamp(line_of(real("oxts/timestamps.txt"), 1)));
  // Packet 0's ax ay az and wx wy wz (fields 12-14, 18-20 of oxts/data/0000000000.txt).
  CHECK(imu[0].accel_mps2.z() == Approx(9.9149729634473));
  CHECK(imu[0].accel_mps2.y() == Approx(0.845164147132));
  CHECK(imu[0].gyro_radps.x() == Approx(0.016662646247367));
  for (std::size_t k = 1; k < imu.size(); ++k) CHECK(imu[k].stamp_s > imu[k - 1].stamp_s);

  // Reference poses: frame 0 is the identity; the car drives forward (lidar
  // x) at the OXTS forward speed vf = 10.70 m/s, about 1.1 m per sweep.
  REQUIRE(drive.has_ground_truth());
  const auto poses = drive.reference_poses_lidar();
  REQUIRE(poses.size() == 3);
  CHECK(poses[0].translation().norm() < 1e-9);
  CHECK(poses[0].so3().log().norm() < 1e-12);
  const double step = (poses[1].translation() - poses[0].translation()).norm();
  CHECK(step == Approx(10.70 * drive.sweep_period_s()).margin(0.1));
  CHECK(poses[2].translation().x() > 2.0);
  CHECK(std::abs(poses[2].translation().y()) < 0.2);
  CHECK(drive.ground_truth_lidar().size() == 3);
}

TEST_CASE("KITTI raw: blank timestamp lines and a gap among the downloaded scans", "[io]") {
  semlio_test::KittiTempDir dir("raw");
  // Frames 0-2 and 180: 3..179 missing; timestamps lines 178-181 (frames 177-180) are blank.
  const std::string path = make_drive(dir, {0, 1, 2, 180});
  const io::KittiRawDrive drive(path);
  REQUIRE(drive.size() == 181);
  CHECK(drive.missing_frame_count() == 177);
  CHECK(drive.has_scan(2));
  CHECK_FALSE(drive.has_scan(3));
  CHECK(drive.has_scan(180));
  CHECK(drive.interpolated_stamp_count() == 4);
  for (std::size_t i = 177; i <= 180; ++i) {
    CHECK(drive.stamp_interpolated(i));
    CHECK_FALSE(drive.sweep_middle_stamp(i).has_value());
    CHECK_FALSE(drive.oxts_minus_scan_stamp_s(i).has_value());
  }
  CHECK_FALSE(drive.stamp_interpolated(176));
  // Linear between the stamped lines 177 (frame 176) and 182 (frame 181).
  const std::string start = path + "/velodyne_points/timestamps_start.txt";
  const double a = io::parse_oxts_timestamp(line_of(start, 177));
  const double b = io::parse_oxts_timestamp(line_of(start, 182));
  CHECK(drive.stamp(176) == a);
  for (std::size_t i = 177; i <= 180; ++i) {
    CHECK(drive.stamp(i) == Approx(a + static_cast<double>(i - 176) / 5.0 * (b - a)).epsilon(1e-15));
    CHECK(drive.stamp(i) > drive.stamp(i - 1));
  }
  // A missing frame costs that frame only.
  CHECK_THROWS_AS(drive.read(100), semlio::IoError);
  CHECK_THROWS_WITH(drive.read(100), Catch::Contains("0000000100.bin") && Catch::Contains("missing"));
  std::string error;
  const Scan empty = drive.read_or_empty(100, error);
  CHECK(empty.empty());
  CHECK(empty.stamp_s == drive.stamp(100));
  CHECK_THAT(error, Catch::Contains("missing"));
  const Scan last = drive.read_or_empty(180, error);
  CHECK(error.empty());
  CHECK(last.size() == 181);
  CHECK(last.stamp_s == drive.stamp(180));
  // Only 12 OXTS packets: no reference trajectory over 181 frames, but IMU samples.
  CHECK_FALSE(drive.has_ground_truth());
  CHECK_THROWS_AS(drive.reference_poses_lidar(), semlio::IoError);
  CHECK_THROWS_WITH(drive.reference_poses_lidar(), Catch::Contains("0000000012.txt"));
  CHECK(drive.imu_samples().size() == 12);
}

TEST_CASE("KITTI raw: the stamp is the sweep middle minus half the period without timestamps_start.txt", "[io]") {
  semlio_test::KittiTempDir dir("raw");
  const std::string path = make_drive(dir, {0, 1});
  fs::remove(path + "/velodyne_points/timestamps_start.txt");
  semlio_test::write_text(path + "/velodyne_points/timestamps.txt",
                          "2011-09-26 13:08:24.950000000\n2011-09-26 13:08:25.050000000\n"
                          "2011-09-26 13:08:25.150000000\n\n2011-09-26 13:08:25.350000000\n");
  const io::KittiRawDrive drive(path);
  CHECK(drive.stamp_source() == io::KittiRawStampSource::sweep_middle_shifted);
  CHECK(drive.sweep_period_s() == Approx(0.1).margin(1e-6));  // stamps near 1.3e9 s carry ~0.24 us
  const double t0 = io::parse_oxts_timestamp("2011-09-26 13:08:24.900000000");
  CHECK(drive.stamp(0) == Approx(t0).epsilon(1e-15));
  CHECK(drive.stamp(1) == Approx(t0 + 0.1).epsilon(1e-15));
  // One stamped line only: the configured nominal period.
  semlio_test::write_text(path + "/velodyne_points/timestamps.txt", "\n2011-09-26 13:08:25.000000000\n");
  io::KittiRawDriveConfig c;
  c.nominal_period_s = 0.2;
  const io::KittiRawDrive one(path, c);
  CHECK(one.sweep_period_s() == 0.2);
  CHECK(one.stamp(1) == Approx(io::parse_oxts_timestamp("2011-09-26 13:08:24.900000000")).epsilon(1e-15));
  CHECK(one.stamp_interpolated(0));  // extrapolated one period back
  CHECK(one.stamp(0) == Approx(one.stamp(1) - 0.2).epsilon(1e-15));
  c.nominal_period_s = 0.0;
  CHECK_THROWS_AS(io::KittiRawDrive(path, c), semlio::ConfigError);
}

TEST_CASE("KITTI raw: calibration found beside, in a calib_YYYY_MM_DD sibling, or where configured", "[io]") {
  semlio_test::KittiTempDir dir("raw");
  const std::string path = make_drive(dir, {0}, false);
  {
    const io::KittiRawDrive none(path);
    CHECK_FALSE(none.has_calibration());
    CHECK(none.calib_dir().empty());
    CHECK_THROWS_AS(none.T_velo_imu(), semlio::IoError);
    CHECK_THROWS_AS(none.T_cam0_velo(), semlio::IoError);
    CHECK_FALSE(none.has_ground_truth());
    CHECK_THROWS_AS(none.reference_poses_lidar(), semlio::IoError);
  }
  // The layout of the shared data: calib_2011_09_26 beside the drive; only imu_to_velo.
  fs::copy_file(semlio_test::data_path("kitti_raw/2011_09_26/calib_imu_to_velo.txt"),
                dir.file("2011_09_26/calib_2011_09_26/calib_imu_to_velo.txt"));
  {
    const io::KittiRawDrive sibling(path);
    CHECK(fs::path(sibling.calib_dir()).filename() == "calib_2011_09_26");
    CHECK(sibling.T_velo_imu().translation().x() == Approx(-8.086759e-01));
    CHECK_THROWS_AS(sibling.T_cam0_velo(), semlio::IoError);
    CHECK(sibling.has_ground_truth());
    CHECK(sibling.reference_poses_lidar().size() == 1);
  }
  // An explicit folder wins; one without the file is an error naming it.
  fs::copy_file(semlio_test::data_path("kitti_raw/2011_09_26/calib_imu_to_velo.txt"),
                dir.file("elsewhere/calib_imu_to_velo.txt"));
  CHECK(fs::path(io::KittiRawDrive(path, calib_from(dir.file("elsewhere"))).calib_dir()).filename() == "elsewhere");
  CHECK_THROWS_AS(io::KittiRawDrive(path, calib_from(dir.file("nowhere"))), semlio::IoError);
  CHECK_THROWS_WITH(io::KittiRawDrive(path, calib_from(dir.file("nowhere"))), Catch::Contains("calib_imu_to_velo.txt"));
}

TEST_CASE("KITTI raw: reference lidar poses follow the devkit convention (hand-computed case)", "[io]") {
  semlio_test::KittiTempDir dir("raw");
  const std::string drive = dir.file("2011_09_26_drive_0001_sync");
  semlio_test::write_text(dir.file("2011_09_26_drive_0001_sync/velodyne_points/timestamps.txt"),
                          "2011-09-26 13:00:00.05\n2011-09-26 13:00:00.15\n");
  write_bin(dir.file("2011_09_26_drive_0001_sync/velodyne_points/data/0000000000.bin"), 1);
  write_bin(dir.file("2011_09_26_drive_0001_sync/velodyne_points/data/0000000001.bin"), 1);
  // IMU 1 m behind the lidar: T_velo_imu = translation (1, 0, 0), no rotation.
  semlio_test::write_text(dir.file("calib_imu_to_velo.txt"),
                          "calib_time: 25-May-2012 16:47:16\nR: 1 0 0 0 1 0 0 0 1\nT: 1 0 0\n");
  // Packet 0 at lat 0 lon 0 heading east; packet 1 10 m east (Mercator scale
  // cos 0 = 1: 10 m = 10 / (pi R / 180) deg) heading north (yaw pi/2).
  const double kPi = 3.14159265358979323846;
  const double dlon = 10.0 / (kPi * io::kOxtsEarthRadius_m / 180.0);
  const auto packet = [](double lon, double yaw) {
    char text[128];
    std::snprintf(text, sizeof(text), "0 %.17g 0 0 0 %.17g", lon, yaw);
    std::string s = text;
    for (int k = 6; k < 25; ++k) s += " 0";
    return s + " 4 7 4 4 0\n";
  };
  semlio_test::write_text(dir.file("2011_09_26_drive_0001_sync/oxts/data/0000000000.txt"), packet(0.0, 0.0));
  semlio_test::write_text(dir.file("2011_09_26_drive_0001_sync/oxts/data/0000000001.txt"), packet(dlon, kPi / 2));
  semlio_test::write_text(dir.file("2011_09_26_drive_0001_sync/oxts/timestamps.txt"),
                          "2011-09-26 13:00:00.06\n2011-09-26 13:00:00.16\n");
  const io::KittiRawDrive d(drive, calib_from(dir.str()));
  const auto poses = d.reference_poses_lidar();
  REQUIRE(poses.size() == 2);
  // T_w_velo1 = T_w_imu1 T_imu_velo: (10, 0, 0) + Rz(90)(-1, 0, 0) = (10, -1, 0);
  // T_w_velo0 = (-1, 0, 0); so T_velo0_velo1 = ((11, -1, 0), Rz(90)).
  CHECK(poses[1].translation().x() == Approx(11.0).margin(1e-6));
  CHECK(poses[1].translation().y() == Approx(-1.0).margin(1e-6));
  CHECK(poses[1].translation().z() == Approx(0.0).margin(1e-9));
  const Eigen::Matrix3d R = poses[1].so3().matrix();
  CHECK(R(0, 1) == Approx(-1.0).margin(1e-9));
  CHECK(R(1, 0) == Approx(1.0).margin(1e-9));
  CHECK(d.oxts_minus_scan_stamp_s(1).value() == Approx(0.01).margin(1e-6));
  CHECK(d.stamp(0) == Approx(io::parse_oxts_timestamp("2011-09-26 13:00:00.00")).epsilon(1e-15));
}

TEST_CASE("KITTI raw: bad folders, names, stamps, calibrations and packets give typed errors", "[io]") {
  semlio_test::KittiTempDir dir("raw");
  const std::string path = make_drive(dir, {0, 1, 2});
  const std::string velo = path + "/velodyne_points/";
  CHECK_THROWS_AS(io::KittiRawDrive(dir.file("nope")), semlio::IoError);
  {
    semlio_test::KittiTempDir empty("raw");
    semlio_test::write_text(empty.file("d/velodyne_points/timestamps.txt"), "2011-09-26 13:00:00.05\n");
    CHECK_THROWS_AS(io::KittiRawDrive(empty.file("d")), semlio::IoError);  // no data/ folder
    fs::create_directories(empty.file("d/velodyne_points/data"));
    CHECK_THROWS_AS(io::KittiRawDrive(empty.file("d")), semlio::FormatError);  // no scans
  }
  // A scan numbered beyond timestamps.txt; a non-numeric and a duplicate name.
  write_bin(velo + "data/0000000447.bin", 1);
  CHECK_THROWS_AS(io::KittiRawDrive(path), semlio::FormatError);
  CHECK_THROWS_WITH(io::KittiRawDrive(path), Catch::Contains("0000000447.bin") && Catch::Contains("447 lines"));
  fs::remove(velo + "data/0000000447.bin");
  write_bin(velo + "data/scan.bin", 1);
  CHECK_THROWS_AS(io::KittiRawDrive(path), semlio::FormatError);
  fs::remove(velo + "data/scan.bin");
  write_bin(velo + "data/1.bin", 1);
  CHECK_THROWS_WITH(io::KittiRawDrive(path), Catch::Contains("appears twice"));
  fs::remove(velo + "data/1.bin");
  REQUIRE_NOTHROW(io::KittiRawDrive(path));

  // Stamps: malformed, backwards, a start file of another length, all blank.
  const std::string good = io::detail::read_file(velo + "timestamps.txt");
  semlio_test::write_text(velo + "timestamps.txt", "2011-09-26 13:00:00.05\n2011-09-26 13:0x:00.15\n\n");
  CHECK_THROWS_AS(io::KittiRawDrive(path), semlio::FormatError);
  CHECK_THROWS_WITH(io::KittiRawDrive(path), Catch::Contains("timestamps.txt:2") && Catch::Contains("13:0x:00.15"));
  semlio_test::write_text(velo + "timestamps.txt", "2011-09-26 13:00:00.05\n2011-09-26 12:00:00.15\n\n");
  CHECK_THROWS_AS(io::KittiRawDrive(path), semlio::ValueError);
  semlio_test::write_text(velo + "timestamps.txt", good);
  const std::string good_start = io::detail::read_file(velo + "timestamps_start.txt");
  semlio_test::write_text(velo + "timestamps_start.txt", "2011-09-26 13:00:00.05\n");
  CHECK_THROWS_WITH(io::KittiRawDrive(path), Catch::Contains("1 lines") && Catch::Contains("447"));
  fs::remove(velo + "timestamps_start.txt");
  semlio_test::write_text(velo + "timestamps.txt", "\n\n\n");
  CHECK_THROWS_AS(io::KittiRawDrive(path), semlio::FormatError);
  semlio_test::write_text(velo + "timestamps.txt", "");
  CHECK_THROWS_AS(io::KittiRawDrive(path), semlio::FormatError);
  fs::remove(velo + "timestamps.txt");
  CHECK_THROWS_AS(io::KittiRawDrive(path), semlio::IoError);
  semlio_test::write_text(velo + "timestamps.txt", good);
  semlio_test::write_text(velo + "timestamps_start.txt", good_start);

  // A truncated scan costs that frame; the next one reads.
  semlio_test::write_text(velo + "data/0000000001.bin", std::string(17, '\0'));
  const io::KittiRawDrive drive(path);
  std::string error;
  CHECK(drive.read_or_empty(1, error).empty());
  CHECK_THAT(error, Catch::Contains("0000000001.bin") && Catch::Contains("17"));
  CHECK(drive.read_or_empty(2, error).size() == 3);
  CHECK(error.empty());

  // A malformed OXTS packet: an error naming the file and line.
  semlio_test::write_text(path + "/oxts/data/0000000005.txt", "1 2 3\n");
  CHECK_THROWS_AS(drive.imu_samples(), semlio::FormatError);
  CHECK_THROWS_WITH(drive.imu_samples(), Catch::Contains("0000000005.txt:1") && Catch::Contains("3 fields"));
  CHECK(drive.reference_poses_lidar().size() == 3);  // frames 0-2 need packets 0-2 only
  semlio_test::write_text(path + "/oxts/data/0000000005.txt", "");
  CHECK_THROWS_WITH(drive.imu_samples(), Catch::Contains("empty OXTS"));
}

TEST_CASE("KITTI raw calibration files: R and T, other keys ignored, typed errors", "[io]") {
  semlio_test::KittiTempDir dir("raw");
  const std::string f = dir.file("calib.txt");
  const auto write = [&](const std::string& text) { semlio_test::write_text(f, text); };
  write("calib_time: 15-Mar-2012 11:37:16\nR: 0 -1 0 1 0 0 0 0 1\nT: 1 2 3\ndelta_f: 0 0\n");
  const SE3d T = io::read_kitti_raw_calib(f);
  CHECK(T.translation() == Eigen::Vector3d(1, 2, 3));
  CHECK(T.so3().matrix()(0, 1) == -1.0);
  CHECK(T.so3().matrix()(1, 0) == 1.0);
  write("R: 1 0 0 0 1 0 0 0 1\n");
  CHECK_THROWS_WITH(io::read_kitti_raw_calib(f), Catch::Contains("no 'T:'"));
  write("R: 1 0 0 0 1 0 0 0\nT: 0 0 0\n");
  CHECK_THROWS_AS(io::read_kitti_raw_calib(f), semlio::FormatError);
  CHECK_THROWS_WITH(io::read_kitti_raw_calib(f), Catch::Contains("calib.txt:1") && Catch::Contains("8 values"));
  write("R: 1 0 0 0 1 0 0 0 1\nT: 0 x 0\n");
  CHECK_THROWS_WITH(io::read_kitti_raw_calib(f), Catch::Contains("calib.txt:2") && Catch::Contains("'x'"));
  write("R: 1 0 0 0 1 0 0 0 1\nR: 1 0 0 0 1 0 0 0 1\nT: 0 0 0\n");
  CHECK_THROWS_WITH(io::read_kitti_raw_calib(f), Catch::Contains("twice"));
  write("R: 2 0 0 0 1 0 0 0 1\nT: 0 0 0\n");
  CHECK_THROWS_AS(io::read_kitti_raw_calib(f), semlio::ValueError);
  write("R: nan 0 0 0 1 0 0 0 1\nT: 0 0 0\n");
  CHECK_THROWS_AS(io::read_kitti_raw_calib(f), semlio::ValueError);
  write("R 1 0 0 0 1 0 0 0 1\n");
  CHECK_THROWS_AS(io::read_kitti_raw_calib(f), semlio::FormatError);
  CHECK_THROWS_AS(io::read_kitti_raw_calib(dir.file("none.txt")), semlio::IoError);
}

TEST_CASE("KITTI raw: mutated files give typed errors or data, never anything else", "[io]") {
  semlio_test::KittiTempDir dir("raw");
  const std::string path = make_drive(dir, {0, 1, 2});
  const std::vector<std::string> targets = {path + "/velodyne_points/timestamps.txt",
                                            path + "/velodyne_points/timestamps_start.txt",
                                            path + "/oxts/timestamps.txt",
                                            path + "/oxts/data/0000000001.txt",
                                            path + "/velodyne_points/data/0000000002.bin",
                                            dir.file("2011_09_26/calib_imu_to_velo.txt"),
                                            dir.file("2011_09_26/calib_velo_to_cam.txt")};
  std::mt19937 rng(20260412);
  int opened = 0;
  int typed_errors = 0;
  for (int round = 0; round < 400; ++round) {
    const std::string& target = targets[static_cast<std::size_t>(round) % targets.size()];
    const std::string original = io::detail::read_file(target);
    semlio_test::write_text(target, mutate(original, rng));
    std::string other;
    try {
      const io::KittiRawDrive drive(path);
      ++opened;
      std::string error;
      for (std::size_t i = 0; i < drive.size(); ++i) {
        (void)drive.read_or_empty(i, error);
        (void)drive.oxts_minus_scan_stamp_s(i);
        CHECK(std::isfinite(drive.stamp(i)));
      }
      try {
        (void)drive.imu_samples();
        (void)drive.reference_poses_lidar();
      } catch (const semlio::Error&) {
        ++typed_errors;
      }
    } catch (const semlio::Error&) {
      ++typed_errors;
    } catch (const std::exception& e) {
      other = e.what();
    }
    CHECK(other.empty());  // only semlio::Error may escape
    semlio_test::write_text(target, original);
  }
  // Both outcomes occur: the mutations are neither all harmless nor all fatal.
  CHECK(opened > 50);
  CHECK(typed_errors > 50);
}

}  // namespace test_kitti_raw
