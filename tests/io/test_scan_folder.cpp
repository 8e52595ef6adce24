// Folders of PCD / PLY / .bin scans: natural order, the stamp rules (times.txt,
// file-name times, nominal period), ground truth (KITTI or TUM), bad folders.
#include <catch2/catch.hpp>

#include <semlio/io/scan_folder.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_kitti_tmp.hpp>

#include <cmath>
#include <exception>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace test_scan_folder {  // one namespace per test file: the area compiles as one TU

namespace {

namespace fs = std::filesystem;
namespace io = semlio::io;
using semlio::Scan;

// A scan of n points (x = 1..n, none dropped).
Scan scan_of(int n) {
  Scan s;
  for (int k = 0; k < n; ++k) {
    s.points.emplace_back(static_cast<float>(k + 1), 2.0F, 3.0F);
    s.intensity.push_back(0.5F);
  }
  return s;
}

// Writes `names` (with extension) into `folder`, file k holding k+1 points.
void write_scans(const semlio_test::KittiTempDir& dir, const std::string& folder,
                 const std::vector<std::string>& names) {
  for (std::size_t k = 0; k < names.size(); ++k) {
    const std::string path = dir.file(folder + "/" + names[k]);
    const Scan s = scan_of(static_cast<int>(k) + 1);
    const std::string ext = fs::path(path).extension().string();
    if (ext == ".pcd") {
      io::write_pcd(path, s);
    } else if (ext == ".ply") {
      io::write_ply(path, s);
    } else {
      io::write_kitti_bin(path, s);
    }
  }
}

io::ScanFolderConfig period(double p) {
  io::ScanFolderConfig c;
  c.nominal_period_s = p;
  return c;
}

}  // namespace

TEST_CASE("scan folder: the real KITTI raw PCD snippet, nominal 10 Hz", "[io]") {
  const io::ScanFolder folder(semlio_test::data_path("kitti_raw/snippet_22/"));
  REQUIRE(folder.size() == 3);
  CHECK(folder.format() == io::ScanFileFormat::pcd);
  CHECK(folder.stamp_source() == io::ScanStampSource::nominal_period);
  CHECK(folder.stamp(0) == 0.0);
  CHECK(folder.stamp(2) == Approx(0.2));
  CHECK_THAT(folder.scan_path(1), Catch::EndsWith("0000000001.pcd"));
  CHECK_FALSE(folder.has_ground_truth());
  CHECK_THROWS_AS(folder.ground_truth_lidar(), semlio::IoError);
  io::ReadStats stats;
  const Scan s = folder.read(0, &stats);
  // The header's POINTS 119978 less the one (0,0,0) point every file holds (tests/data/kitti_raw/README.md).
  CHECK(s.size() == 119977);
  CHECK(stats.dropped_zero == 1);
  CHECK(s.stamp_s == 0.0);
  std::string error = "stale";
  CHECK(folder.read_or_empty(2, error).stamp_s == folder.stamp(2));
  CHECK(error.empty());
  CHECK_THROWS_AS(folder.read(3), semlio::ValueError);
  CHECK_THROWS_AS(folder.read_or_empty(3, error), semlio::ValueError);
}

TEST_CASE("scan folder: natural order, times.txt, gaps keep their frame numbers", "[io]") {
  semlio_test::KittiTempDir dir("folder");
  // Written in this order (file k has k+1 points); natural order is 1, 2, 10.
  write_scans(dir, "a", {"scan_10.bin", "scan_2.bin", "scan_1.bin"});
  semlio_test::write_text(dir.file("a/README"), "not a scan\n");
  {
    const io::ScanFolder folder(dir.file("a"));
    REQUIRE(folder.size() == 3);
    CHECK(folder.format() == io::ScanFileFormat::kitti_bin);
    CHECK_THAT(folder.scan_path(0), Catch::EndsWith("scan_1.bin"));
    CHECK_THAT(folder.scan_path(2), Catch::EndsWith("scan_10.bin"));
    CHECK(folder.read(0).size() == 3);
    CHECK(folder.read(2).size() == 1);
    // Frame numbers 1, 2, 10 at the nominal period: the gap keeps its time.
    CHECK(folder.stamp_source() == io::ScanStampSource::nominal_period);
    CHECK(folder.stamp(0) == Approx(0.1));
    CHECK(folder.stamp(2) == Approx(1.0));
    const io::ScanFolder slow(dir.file("a"), period(0.5));
    CHECK(slow.stamp(1) == Approx(1.0));
  }
  semlio_test::write_text(dir.file("a/times.txt"), "10.5\n10.6\n11.4\n");
  {
    const io::ScanFolder folder(dir.file("a"));
    CHECK(folder.stamp_source() == io::ScanStampSource::times_file);
    CHECK(folder.stamps() == std::vector<double>{10.5, 10.6, 11.4});
    CHECK(folder.read(2).stamp_s == 11.4);
  }
  semlio_test::write_text(dir.file("a/times.txt"), "10.5\n10.6\n");
  CHECK_THROWS_AS(io::ScanFolder(dir.file("a")), semlio::ValueError);
  CHECK_THROWS_WITH(io::ScanFolder(dir.file("a")), Catch::Contains("2 times") && Catch::Contains("3 scans"));
  semlio_test::write_text(dir.file("a/times.txt"), "10.5\nx\n11\n");
  CHECK_THROWS_AS(io::ScanFolder(dir.file("a")), semlio::FormatError);

  // Names that are not frame numbers nor times: ordered, stamped by index.
  write_scans(dir, "b", {"b_7x2.ply", "a_1x1.ply"});
  const io::ScanFolder by_index(dir.file("b"));
  CHECK(by_index.format() == io::ScanFileFormat::ply);
  CHECK_THAT(by_index.scan_path(0), Catch::EndsWith("a_1x1.ply"));
  CHECK(by_index.read(1).size() == 1);
  CHECK(by_index.stamp(1) == Approx(0.2));  // last digit runs 1 and 2: frame numbers
}

TEST_CASE("scan folder: file names that are times (s with fraction, ms, us, ns)", "[io]") {
  semlio_test::KittiTempDir dir("folder");
  // Seconds with a fraction: ordered by value (.05 < .123456 < .2), not by digit runs.
  write_scans(dir, "s", {"1317357625.2.pcd", "1317357625.123456.pcd", "1317357625.05.pcd"});
  const io::ScanFolder s(dir.file("s"));
  CHECK(s.stamp_source() == io::ScanStampSource::file_name);
  CHECK(s.stamp(0) == 1317357625.05);
  CHECK(s.stamp(1) == 1317357625.123456);
  CHECK(s.stamp(2) == 1317357625.2);
  CHECK(s.read(0).size() == 3);  // written third
  // Nanoseconds (19 digits), microseconds (16), milliseconds (13).
  write_scans(dir, "ns", {"1599131415123456789.bin", "1599131415223456789.bin"});
  const io::ScanFolder ns(dir.file("ns"));
  CHECK(ns.stamp_source() == io::ScanStampSource::file_name);
  CHECK(ns.stamp(0) == 1599131415.123456789);
  CHECK(ns.stamp(1) - ns.stamp(0) == Approx(0.1).margin(1e-6));
  write_scans(dir, "us", {"1599131415123456.bin", "1599131415223456.bin"});
  CHECK(io::ScanFolder(dir.file("us")).stamp(0) == 1599131415.123456);
  write_scans(dir, "ms", {"1599131415123.bin", "1599131415223.bin"});
  CHECK(io::ScanFolder(dir.file("ms")).stamp(1) == 1599131415.223);
  // Units differ between files: not times; stamped by index at the nominal period.
  write_scans(dir, "mixed", {"1599131415.bin", "1599131415223.bin"});
  const io::ScanFolder mixed(dir.file("mixed"));
  CHECK(mixed.stamp_source() == io::ScanStampSource::nominal_period);
  CHECK(mixed.stamp(1) == Approx(0.1));
  // KITTI-style 10-digit frame numbers with leading zeros are frame numbers, not times.
  write_scans(dir, "k", {"0000000005.bin", "0000000006.bin"});
  CHECK(io::ScanFolder(dir.file("k")).stamp_source() == io::ScanStampSource::nominal_period);
  CHECK(io::ScanFolder(dir.file("k")).stamp(1) == Approx(0.6));
}

TEST_CASE("scan folder: ground truth from poses.txt, KITTI 3x4 or TUM", "[io]") {
  semlio_test::KittiTempDir dir("folder");
  write_scans(dir, "f", {"000000.bin", "000001.bin"});
  semlio_test::write_text(dir.file("f/poses.txt"), "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0.8 0 1 0 0 0 0 1 0\n");
  {
    const io::ScanFolder folder(dir.file("f"));
    REQUIRE(folder.has_ground_truth());
    const auto gt = folder.ground_truth_lidar();
    REQUIRE(gt.size() == 2);
    CHECK(gt[1].translation().x() == 0.8);
    CHECK(folder.ground_truth().size() == 2);
  }
  // TUM: stamp x y z qx qy qz qw; qz = qw = sqrt(1/2) is 90 deg about z.
  semlio_test::write_text(dir.file("f/poses.txt"),
                          "# t x y z qx qy qz qw\n0 0 0 0 0 0 0 1\n0.1 1 2 3 0 0 0.70710678118654752 "
                          "0.70710678118654752\n");
  {
    const auto gt = io::ScanFolder(dir.file("f")).ground_truth_lidar();
    REQUIRE(gt.size() == 2);
    CHECK(gt[1].translation().y() == 2.0);
    CHECK(gt[1].so3().matrix()(1, 0) == Approx(1.0));
  }
  semlio_test::write_text(dir.file("f/poses.txt"), "1 0 0 0 0 1 0 0 0 0 1 0\n");
  CHECK_THROWS_AS(io::ScanFolder(dir.file("f")).ground_truth_lidar(), semlio::ValueError);
  CHECK_THROWS_WITH(io::ScanFolder(dir.file("f")).ground_truth_lidar(),
                    Catch::Contains("1 poses") && Catch::Contains("2 scans"));
  semlio_test::write_text(dir.file("f/poses.txt"), "1 2 3 4 5\n");
  CHECK_THROWS_AS(io::ScanFolder(dir.file("f")).ground_truth_lidar(), semlio::FormatError);
  // An explicit file wins; a missing explicit file is an IoError.
  semlio_test::write_text(dir.file("gt.txt"), "0 0 0 0 0 0 0 1\n1 5 0 0 0 0 0 1\n");
  io::ScanFolderConfig c;
  c.ground_truth_path = dir.file("gt.txt");
  CHECK(io::ScanFolder(dir.file("f"), c).ground_truth_lidar()[1].translation().x() == 5.0);
  c.ground_truth_path = dir.file("none.txt");
  CHECK_THROWS_AS(io::ScanFolder(dir.file("f"), c), semlio::IoError);
}

TEST_CASE("scan folder: a corrupt file costs one frame, bad folders give typed errors", "[io]") {
  semlio_test::KittiTempDir dir("folder");
  write_scans(dir, "c", {"000000.pcd", "000001.pcd", "000002.pcd"});
  semlio_test::write_text(dir.file("c/000001.pcd"), "VERSION 0.7\nFIELDS x y z\n");  // header cut short
  {
    const io::ScanFolder folder(dir.file("c"));
    REQUIRE(folder.size() == 3);
    std::string error;
    const Scan bad = folder.read_or_empty(1, error);
    CHECK(bad.empty());
    CHECK(bad.stamp_s == folder.stamp(1));
    CHECK_THAT(error, Catch::Contains("000001.pcd"));
    CHECK(folder.read_or_empty(2, error).size() == 3);
    CHECK(error.empty());
    CHECK_THROWS_AS(folder.read(1), semlio::FormatError);
    // A file removed after opening costs its frame too.
    fs::remove(dir.file("c/000000.pcd"));
    CHECK(folder.read_or_empty(0, error).empty());
    CHECK_FALSE(error.empty());
  }
  CHECK_THROWS_AS(io::ScanFolder(dir.file("missing")), semlio::IoError);
  fs::create_directories(dir.file("empty"));
  semlio_test::write_text(dir.file("empty/times.txt"), "0\n");
  CHECK_THROWS_AS(io::ScanFolder(dir.file("empty")), semlio::FormatError);
  CHECK_THROWS_AS(io::ScanFolder(dir.file("c"), period(0.0)), semlio::ConfigError);
  CHECK_THROWS_AS(io::ScanFolder(dir.file("c"), period(-1.0)), semlio::ConfigError);

  write_scans(dir, "mix", {"000000.pcd", "000001.bin"});
  CHECK_THROWS_AS(io::ScanFolder(dir.file("mix")), semlio::FormatError);
  CHECK_THROWS_WITH(io::ScanFolder(dir.file("mix")), Catch::Contains("000000.pcd") && Catch::Contains("000001.bin"));
  write_scans(dir, "map", {"000000.pcd", "GlobalMap.pcd"});
  CHECK_THROWS_WITH(io::ScanFolder(dir.file("map")), Catch::Contains("GlobalMap.pcd") && Catch::Contains("no number"));
  write_scans(dir, "dup", {"1.bin", "01.bin"});
  CHECK_THROWS_AS(io::ScanFolder(dir.file("dup")), semlio::FormatError);
  CHECK_THROWS_WITH(io::ScanFolder(dir.file("dup")), Catch::Contains("same number"));
  write_scans(dir, "dupt", {"1317357625.5.bin", "1317357625.50.bin"});
  CHECK_THROWS_WITH(io::ScanFolder(dir.file("dupt")), Catch::Contains("same number"));
  // Hidden files and other extensions are not scans; upper-case extensions are.
  write_scans(dir, "hid", {"000000.bin", ".000001.bin"});
  fs::rename(dir.file("hid/000000.bin"), dir.file("hid/000000.BIN"));
  const io::ScanFolder hid(dir.file("hid"));
  CHECK(hid.size() == 1);
  CHECK(hid.read(0).size() == 1);
}

TEST_CASE("scan folder: the number in a name, compared exactly", "[io]") {
  namespace d = io::detail;
  const auto num = [](std::string_view s) { return d::scan_name_number(s).value(); };
  CHECK(num("scan_0012").integer == "12");
  CHECK_FALSE(num("scan_0012").whole_name);
  CHECK(num("frame3_v12").integer == "12");
  CHECK(num("000000").integer == "0");
  CHECK(num("1317357625.500").fraction == "5");
  CHECK(num("1317357625.500").whole_name);
  CHECK_FALSE(d::scan_name_number("map").has_value());
  CHECK(d::compare_numbers(num("1317357625.5"), num("1317357625.45")) > 0);
  CHECK(d::compare_numbers(num("9"), num("10")) < 0);
  CHECK(d::compare_numbers(num("0010"), num("10")) == 0);
  // 40-digit names compare without overflow.
  CHECK(d::compare_numbers(num("1000000000000000000000000000000000000001"),
                           num("1000000000000000000000000000000000000000")) > 0);
  CHECK(d::time_unit_digits(num("1000000000000000000000000000000000000001")) == -1);
  CHECK(d::time_unit_digits(num("99999999")) == -1);         // 8 digits: a frame number
  CHECK(d::time_unit_digits(num("100000000")) == 0);         // 9 digits: seconds (1973)
  CHECK(d::time_unit_digits(num("1599131415123.5")) == -1);  // ms with a fraction: not a time
  CHECK(d::time_unit_digits(num("scan_1599131415")) == -1);  // only whole names are times
}

TEST_CASE("scan folder: mutated files and random names give typed errors or data, never anything else", "[io]") {
  semlio_test::KittiTempDir dir("folder");
  std::mt19937 rng(20260413);
  static const std::string kBytes = "0123456789-:. \n\r\tenx+_#\0";
  const auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
  const auto mutate = [&](std::string text) {
    if (text.empty()) return std::string(1, kBytes[pick(kBytes.size())]);
    const std::size_t at = pick(text.size());
    switch (pick(3)) {
      case 0:
        text[at] = kBytes[pick(kBytes.size())];
        break;
      case 1:
        text.resize(at);
        break;
      default:
        text.insert(at, std::string(1 + pick(3), kBytes[pick(kBytes.size())]));
    }
    return text;
  };
  write_scans(dir, "p", {"000000.pcd", "000001.pcd"});
  io::write_pcd(dir.file("p/000000.pcd"), scan_of(4), io::PcdEncoding::kAscii);
  semlio_test::write_text(dir.file("p/times.txt"), "0.0\n0.1\n");
  semlio_test::write_text(dir.file("p/poses.txt"), "0 0 0 0 0 0 0 1\n0.1 1 0 0 0 0 0 1\n");
  write_scans(dir, "y", {"1317357625.1.ply", "1317357625.2.ply"});
  semlio_test::write_text(dir.file("y/poses.txt"), "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n");
  const std::vector<std::string> targets = {dir.file("p/000000.pcd"),       dir.file("p/000001.pcd"),
                                            dir.file("p/times.txt"),        dir.file("p/poses.txt"),
                                            dir.file("y/1317357625.1.ply"), dir.file("y/poses.txt")};
  int opened = 0;
  int typed_errors = 0;
  for (int round = 0; round < 300; ++round) {
    const std::string& target = targets[static_cast<std::size_t>(round) % targets.size()];
    const std::string original = io::detail::read_file(target);
    semlio_test::write_text(target, mutate(original));
    // A random extra scan name in the folder too, every third round.
    std::string extra;
    if (round % 3 == 0) {
      for (std::size_t k = 1 + pick(24); k > 0; --k) extra.push_back("0123456789._-ab"[pick(15)]);
      extra = fs::path(target).parent_path().string() + "/" + extra + fs::path(target).extension().string();
      if (fs::exists(extra)) {
        extra.clear();  // never overwrite (or later remove) a file of the folder
      } else {
        fs::copy_file(target, extra);
      }
    }
    std::string other;
    try {
      const io::ScanFolder folder(fs::path(target).parent_path().string());
      ++opened;
      std::string error;
      for (std::size_t i = 0; i < folder.size(); ++i) {
        (void)folder.read_or_empty(i, error);
        CHECK(std::isfinite(folder.stamp(i)));
      }
      try {
        if (folder.has_ground_truth()) (void)folder.ground_truth_lidar();
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
    if (!extra.empty()) fs::remove(extra);
  }
  CHECK(opened > 50);
  CHECK(typed_errors > 50);
}

}  // namespace test_scan_folder
