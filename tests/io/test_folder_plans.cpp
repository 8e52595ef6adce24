// The in-memory entry points of the folder readers: plan_scan_folder /
// parse_scan_folder_ground_truth (io/scan_folder.hpp) and plan_kitti_raw_drive
// (io/kitti_raw.hpp) decide exactly what ScanFolder and KittiRawDrive decide
// from the same names and texts; a timestamps_start.txt that disagrees with
// timestamps.txt where a line is blank is a ValueError (the stamps would go
// backwards).
#include <catch2/catch.hpp>

#include <semlio/core/error.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/io/kitti_raw.hpp>
#include <semlio/io/scan_folder.hpp>
#include <semlio_test/data.hpp>

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace test_folder_plans {  // one namespace per test file: the area compiles as one TU

namespace {

namespace fs = std::filesystem;
namespace io = semlio::io;

const std::string kDrive = "kitti_raw/2011_09_26/2011_09_26_drive_0009_sync";

std::string real(const std::string& relative) { return semlio_test::data_path(kDrive + "/" + relative); }

/// Names in a folder (any order).
std::vector<std::string> names_in(const std::string& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  return out;
}

}  // namespace

TEST_CASE("scan folder plan: the real PCD snippet plans as ScanFolder reads it", "[io][plan]") {
  const std::string dir = semlio_test::data_path("kitti_raw/snippet_22");
  const io::ScanFolder folder(dir);
  const io::ScanFolderPlan plan = io::plan_scan_folder(names_in(dir), std::nullopt, folder.directory());
  REQUIRE(plan.files.size() == folder.size());
  CHECK(plan.format == folder.format());
  CHECK(plan.stamp_source == folder.stamp_source());
  CHECK(plan.stamps == folder.stamps());
  for (std::size_t i = 0; i < plan.files.size(); ++i) {
    CHECK((fs::path(folder.directory()) / plan.files[i]).string() == folder.scan_path(i));
  }
}

TEST_CASE("scan folder plan: order, stamps and typed errors from names and times.txt alone", "[io][plan]") {
  // Natural order by the last run of digits; README, times.txt, hidden files ignored.
  const std::vector<std::string> names = {"scan_10.ply", "scan_9.ply", ".scan_1.ply", "README", "times.txt",
                                          "scan_100.PLY"};
  io::ScanFolderPlan p = io::plan_scan_folder(names, std::nullopt, "d");
  CHECK(p.format == io::ScanFileFormat::ply);
  CHECK(p.files == std::vector<std::string>{"scan_9.ply", "scan_10.ply", "scan_100.PLY"});
  // Integer frame numbers times the nominal 0.1 s: 0.9, 1.0, 10.0.
  REQUIRE(p.stamps.size() == 3);
  CHECK(p.stamps[0] == Approx(0.9));
  CHECK(p.stamps[1] == Approx(1.0));
  CHECK(p.stamps[2] == Approx(10.0));
  CHECK(p.stamp_source == io::ScanStampSource::nominal_period);
  // times.txt, in frame order, wins over the names.
  p = io::plan_scan_folder(names, std::string_view("5\n6.5\n7\n"), "d");
  CHECK(p.stamps == std::vector<double>{5.0, 6.5, 7.0});
  CHECK(p.stamp_source == io::ScanStampSource::times_file);
  // Names that are nanosecond stamps.
  p = io::plan_scan_folder({"1599131415223456789.pcd", "1599131415123456789.pcd"}, std::nullopt, "d");
  REQUIRE(p.stamps.size() == 2);
  CHECK(p.stamp_source == io::ScanStampSource::file_name);
  CHECK(p.stamps[1] - p.stamps[0] == Approx(0.1).margin(1e-6));
  // Typed errors, naming the file.
  CHECK_THROWS_WITH(io::plan_scan_folder(names, std::string_view("5\n6\n"), "d"),
                    Catch::Contains("times.txt") && Catch::Contains("has 2 times but the folder has 3 scans"));
  CHECK_THROWS_AS(io::plan_scan_folder(names, std::string_view("5\n4\n3\n"), "d"), semlio::ValueError);
  CHECK_THROWS_WITH(io::plan_scan_folder({"1.pcd", "01.pcd"}, std::nullopt, "d"),
                    Catch::Contains("has the same number as"));
  CHECK_THROWS_WITH(io::plan_scan_folder({"0.pcd", "1.bin"}, std::nullopt, "d"), Catch::Contains("mixes scan formats"));
  CHECK_THROWS_WITH(io::plan_scan_folder({"map.pcd"}, std::nullopt, "d"), Catch::Contains("map.pcd"));
  CHECK_THROWS_AS(io::plan_scan_folder({"README", "times.txt"}, std::nullopt, "d"), semlio::FormatError);
  io::ScanFolderConfig bad;
  bad.nominal_period_s = std::nan("");
  CHECK_THROWS_AS(io::plan_scan_folder({"0.bin"}, std::nullopt, "d", bad), semlio::ConfigError);
}

TEST_CASE("scan folder plan: ground truth text, KITTI or TUM, one pose per frame", "[io][plan]") {
  const std::string kitti = "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 2 0 1 0 0 0 0 1 0\n";
  const auto k = io::parse_scan_folder_ground_truth(kitti, "poses.txt", 2);
  REQUIRE(k.size() == 2);
  CHECK(k[1].translation().x() == 2.0);
  const std::string tum = "# t x y z qx qy qz qw\n0 0 0 0 0 0 0 1\n0.1 0 3 0 0 0 0 1\n";
  const auto t = io::parse_scan_folder_ground_truth(tum, "poses.txt", 2);
  REQUIRE(t.size() == 2);
  CHECK(t[1].translation().y() == 3.0);
  CHECK_THROWS_WITH(io::parse_scan_folder_ground_truth(kitti, "poses.txt", 3),
                    Catch::Contains("poses.txt") && Catch::Contains("has 2 poses but the folder has 3 scans"));
}

TEST_CASE("KITTI raw plan: the real drive's listing plans as KittiRawDrive reads it", "[io][plan]") {
  const io::KittiRawDrive drive(semlio_test::data_path(kDrive));
  const std::string mid = io::detail::read_file(real("velodyne_points/timestamps.txt"));
  const std::string start = io::detail::read_file(real("velodyne_points/timestamps_start.txt"));
  const std::string oxts = io::detail::read_file(real("oxts/timestamps.txt"));
  io::KittiRawDriveListing in;
  in.timestamps = mid;
  in.timestamps_start = start;
  in.scan_names = names_in(real("velodyne_points/data"));
  in.oxts_timestamps = oxts;
  in.oxts_names = names_in(real("oxts/data"));
  const io::KittiRawDrivePlan plan = io::plan_kitti_raw_drive(in, drive.directory());
  REQUIRE(plan.stems.size() == drive.size());
  CHECK(plan.missing == drive.missing_frame_count());
  CHECK(plan.period_s == drive.sweep_period_s());
  CHECK(plan.middle_lines.size() == drive.timestamp_line_count());
  CHECK(plan.oxts_stems.size() == drive.oxts_packet_count());
  // Fewer scans (3) than OXTS packets (12) and timestamps lines (447).
  CHECK(plan.stems.size() < plan.oxts_stems.size());
  for (std::size_t i = 0; i < plan.stems.size(); ++i) {
    CHECK(plan.stamps[i] == drive.stamp(i));
    CHECK(plan.interpolated[i] == drive.stamp_interpolated(i));
  }
}

TEST_CASE("KITTI raw plan: blank lines, gaps, and start stamps that disagree with timestamps.txt", "[io][plan]") {
  const std::string mid =
      "2011-09-26 13:08:42.0\n2011-09-26 13:08:42.1\n\n\n2011-09-26 13:08:42.4\n2011-09-26 13:08:42.5\n";
  io::KittiRawDriveListing in;
  in.timestamps = mid;
  in.scan_names = std::vector<std::string>{"0000000000.bin", "0000000003.bin", "0000000005.bin", "README"};
  io::KittiRawDrivePlan p = io::plan_kitti_raw_drive(in, "drive");
  REQUIRE(p.stems.size() == 6);
  CHECK(p.missing == 3);
  CHECK(p.stems[3] == "0000000003");
  CHECK(p.stems[1].empty());
  CHECK(p.period_s == Approx(0.1));
  // Blank lines 3-4: interpolated between 42.1 and 42.4 (sweep start = middle - 0.05 s).
  CHECK(p.interpolated == std::vector<bool>{false, false, true, true, false, false});
  CHECK(p.stamps[2] - p.stamps[1] == Approx(0.1).margin(1e-6));
  CHECK(p.stamps[3] - p.stamps[1] == Approx(0.2).margin(1e-6));
  // A start file blank on line 2 whose neighbours are far later than
  // timestamps.txt's line 2: the start stamps would go backwards.
  const std::string start =
      "2011-09-26 13:08:43.0\n\n\n\n2011-09-26 13:08:43.4\n2011-09-26 13:08:43.5\n";
  in.timestamps_start = start;
  CHECK_THROWS_AS(io::plan_kitti_raw_drive(in, "drive"), semlio::ValueError);
  CHECK_THROWS_WITH(io::plan_kitti_raw_drive(in, "drive"),
                    Catch::Contains("timestamps_start.txt:2") && Catch::Contains("earlier than line 1"));
  // Consistent files pass (start = middle - 0.05 s, one line blank in the start file only).
  const std::string start_ok =
      "2011-09-26 13:08:41.95\n\n\n\n2011-09-26 13:08:42.35\n2011-09-26 13:08:42.45\n";
  in.timestamps_start = start_ok;
  p = io::plan_kitti_raw_drive(in, "drive");
  CHECK_FALSE(p.interpolated[1]);  // timestamps.txt has line 2
  CHECK(p.stamps[1] - p.stamps[0] == Approx(0.1).margin(1e-6));
  // Typed errors naming the file.
  in.timestamps_start.reset();
  in.scan_names = std::vector<std::string>{"0000000009.bin"};
  CHECK_THROWS_WITH(io::plan_kitti_raw_drive(in, "drive"), Catch::Contains("0000000009.bin") &&
                                                               Catch::Contains("has no line in timestamps.txt"));
  in.scan_names.reset();
  CHECK_THROWS_AS(io::plan_kitti_raw_drive(in, "drive"), semlio::IoError);
  in.scan_names = std::vector<std::string>{"x1.bin"};
  CHECK_THROWS_WITH(io::plan_kitti_raw_drive(in, "drive"), Catch::Contains("is not a frame number"));
}

}  // namespace test_folder_plans
