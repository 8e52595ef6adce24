// Lazy KITTI sequence reader: frame listing, labels folder, calib/times, ground-truth discovery.
#include <catch2/catch.hpp>

#include <semlio/io/kitti_sequence.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_kitti_tmp.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace test_kitti_sequence {  // one namespace per test file: the area compiles as one TU

namespace {

// GCC 12 warns (-Wmissing-field-initializers) on partial designated
// initializers, so configs are built field by field here.
semlio::io::KittiSequenceConfig labels_from(const std::string& folder) {
  semlio::io::KittiSequenceConfig c;
  c.label_folder = folder;
  return c;
}

semlio::io::KittiSequenceConfig gt_from(const std::string& path) {
  semlio::io::KittiSequenceConfig c;
  c.ground_truth_path = path;
  return c;
}

namespace io = semlio::io;
using semlio::Class;
using semlio::Scan;
using semlio::SE3d;

// Writes frames 0..n-1 (skipping `skip`) with i+1 points each.
void make_scans(const semlio_test::KittiTempDir& dir, const std::string& seq, const std::vector<int>& frames) {
  for (const int f : frames) {
    Scan s;
    for (int k = 0; k <= f; ++k) {
      s.points.emplace_back(static_cast<float>(k + 1), 2.0F, 3.0F);
      s.intensity.push_back(0.5F);
    }
    io::write_kitti_bin(dir.file(seq + "/velodyne/" + io::detail::frame_stem(static_cast<std::size_t>(f), 6) + ".bin"),
                        s);
  }
}

std::string identity_poses(int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += "1 0 0 " + std::to_string(i) + " 0 1 0 0 0 0 1 0\n";
  return s;
}

}  // namespace

TEST_CASE("real sequence 00 (two scans) with calib, times and poses.txt", "[io]") {
  const io::KittiSequence seq(semlio_test::data_path("kitti/sequences/00/"));
  REQUIRE(seq.size() == 2);
  CHECK_FALSE(seq.has_labels());
  REQUIRE(seq.calibration().has_value());
  CHECK(seq.calibration()->T_cam0_velo.has_value());
  CHECK(seq.times() == std::vector<double>{0.0, 0.1037359});
  CHECK(seq.stamp(1) == 0.1037359);
  REQUIRE(seq.has_ground_truth());
  CHECK_THAT(seq.ground_truth_path(), Catch::EndsWith("poses.txt"));
  const auto gt_cam = seq.ground_truth_camera();
  const auto gt_lidar = seq.ground_truth_lidar();
  REQUIRE(gt_lidar.size() == 2);
  // Camera z forward 0.859 m becomes lidar x forward 0.859 m (Tr maps lidar x to camera z).
  CHECK(gt_lidar[1].translation().x() == Approx(gt_cam[1].translation().z()).margin(0.02));
  io::ReadStats stats;
  std::size_t frames = 0;
  std::size_t points = 0;
  for (auto it = seq.begin(&stats); it != seq.end(); ++it) {
    const Scan s = *it;
    CHECK(s.stamp_s == seq.times()[it.index()]);
    points += s.size();
    ++frames;
  }
  CHECK(frames == 2);
  CHECK(points == (1994688 + 1993680) / 16);  // file sizes / 16 bytes
  CHECK(stats.dropped() == 0);
}

TEST_CASE("real SemanticKITTI subset read as a sequence with labels", "[io]") {
  const io::KittiSequence seq(semlio_test::data_path("kitti/semantickitti_subset/00"));
  REQUIRE(seq.size() == 1);
  REQUIRE(seq.has_labels());
  CHECK_FALSE(seq.has_ground_truth());
  CHECK_FALSE(seq.calibration().has_value());
  CHECK(seq.stamp(0) == 0.0);
  int n = 0;
  for (const Scan& s : seq) {
    CHECK(s.size() == 50);
    const auto h = semlio::label_histogram(s);
    CHECK(h[semlio::index(Class::kBuilding)] == 25);
    CHECK(h[semlio::index(Class::kVegetation)] == 17);
    ++n;
  }
  CHECK(n == 1);
  // Another label folder that does not exist: scans come without labels.
  const io::KittiSequence no_pred(semlio_test::data_path("kitti/semantickitti_subset/00"), labels_from("predictions"));
  CHECK_FALSE(no_pred.has_labels());
  CHECK_FALSE(no_pred.read(0).has_labels());
  // An empty label folder name never reads labels.
  CHECK_FALSE(io::KittiSequence(semlio_test::data_path("kitti/semantickitti_subset/00"), labels_from("")).has_labels());
}

TEST_CASE("sequence: ground truth discovery order", "[io]") {
  semlio_test::KittiTempDir dir("seq");
  const std::string seq_dir = "dataset/sequences/05";
  make_scans(dir, seq_dir, {0, 1, 2});
  // No ground truth at all.
  CHECK_FALSE(io::KittiSequence(dir.file(seq_dir)).has_ground_truth());
  CHECK_THROWS_AS(io::KittiSequence(dir.file(seq_dir)).ground_truth_camera(), semlio::IoError);
  // Official layout dataset/poses/05.txt.
  semlio_test::write_text(dir.file("dataset/poses/05.txt"), identity_poses(3));
  {
    const io::KittiSequence seq(dir.file(seq_dir));
    CHECK(std::filesystem::equivalent(seq.ground_truth_path(), dir.file("dataset/poses/05.txt")));
    // No calib: poses stay in their own (lidar) frame.
    CHECK(seq.ground_truth_lidar()[2].translation().x() == 2.0);
    CHECK(seq.stamp(2) == Approx(0.2));  // nominal 10 Hz without times.txt
  }
  // poses.txt inside the sequence wins over the official layout.
  semlio_test::write_text(dir.file(seq_dir + "/poses.txt"), identity_poses(3));
  CHECK(std::filesystem::equivalent(io::KittiSequence(dir.file(seq_dir)).ground_truth_path(),
                                    dir.file(seq_dir + "/poses.txt")));
  // An explicit path wins over both; a missing explicit path is an IoError.
  semlio_test::write_text(dir.file("mine.txt"), identity_poses(4));
  const io::KittiSequence seq(dir.file(seq_dir), gt_from(dir.file("mine.txt")));
  CHECK(seq.ground_truth_path() == dir.file("mine.txt"));
  CHECK_THROWS_AS(seq.ground_truth_camera(), semlio::ValueError);  // 4 poses, 3 frames
  CHECK_THROWS_WITH(seq.ground_truth_camera(), Catch::Contains("4 poses") && Catch::Contains("3 frames"));
  CHECK_THROWS_AS(io::KittiSequence(dir.file(seq_dir), gt_from(dir.file("nope.txt"))), semlio::IoError);
}

TEST_CASE("sequence: gaps, missing and empty files, bad names, label folder", "[io]") {
  {
    semlio_test::KittiTempDir dir("seq");
    make_scans(dir, "s", {0, 1, 3, 4});
    CHECK_THROWS_AS(io::KittiSequence(dir.file("s")), semlio::FormatError);
    CHECK_THROWS_WITH(io::KittiSequence(dir.file("s")), Catch::Contains("000002.bin") && Catch::Contains("gap"));
  }
  {
    semlio_test::KittiTempDir dir("seq");
    make_scans(dir, "s", {1, 2});
    CHECK_THROWS_WITH(io::KittiSequence(dir.file("s")), Catch::Contains("000000.bin"));
  }
  {
    semlio_test::KittiTempDir dir("seq");
    make_scans(dir, "s", {0});
    semlio_test::write_text(dir.file("s/velodyne/scan_a.bin"), "");
    CHECK_THROWS_WITH(io::KittiSequence(dir.file("s")),
                      Catch::Contains("scan_a.bin") && Catch::Contains("frame number"));
  }
  {
    semlio_test::KittiTempDir dir("seq");
    std::filesystem::create_directories(dir.file("s/velodyne"));
    CHECK_THROWS_AS(io::KittiSequence(dir.file("s")), semlio::FormatError);  // no scans
    CHECK_THROWS_AS(io::KittiSequence(dir.file("t")), semlio::IoError);      // no velodyne/
  }
  {
    semlio_test::KittiTempDir dir("seq");
    make_scans(dir, "s", {0, 1});
    semlio_test::write_text(dir.file("s/velodyne/000002.bin"), "");  // empty scan file
    const io::KittiSequence seq(dir.file("s"));
    REQUIRE(seq.size() == 3);
    CHECK(seq.read(1).size() == 2);
    CHECK_THROWS_AS(seq.read(2), semlio::FormatError);
    CHECK_THROWS_AS(seq.read(3), semlio::ValueError);  // out of range
    // The degraded mode: an unreadable frame is an empty scan at its stamp, with the reason.
    std::string error = "stale";
    CHECK(seq.read_or_empty(1, error).size() == 2);
    CHECK(error.empty());
    const Scan empty = seq.read_or_empty(2, error);
    CHECK(empty.empty());
    CHECK(empty.stamp_s == seq.stamp(2));
    CHECK_THAT(error, Catch::Contains("000002.bin") && Catch::Contains("empty"));
    CHECK_THROWS_AS(seq.read_or_empty(3, error), semlio::ValueError);  // out of range is a caller bug
    semlio_test::write_text(dir.file("s/velodyne/000002.bin"), std::string(20, '\0'));  // truncated: 20 bytes
    CHECK(seq.read_or_empty(2, error).empty());
    CHECK_THAT(error, Catch::Contains("multiple of 16"));
    std::filesystem::remove(dir.file("s/velodyne/000001.bin"));
    CHECK_THROWS_AS(seq.read(1), semlio::IoError);  // vanished after listing
    CHECK(seq.read_or_empty(1, error).empty());
    CHECK_THAT(error, Catch::Contains("000001.bin"));
  }
  {
    semlio_test::KittiTempDir dir("seq");
    make_scans(dir, "s", {0, 1});
    // Labels from a chosen folder: predictions/. Frame 1's file is missing.
    io::write_label_file(dir.file("s/predictions/000000.label"), {40U | (9U << 16)});
    const io::KittiSequence seq(dir.file("s"), labels_from("predictions"));
    REQUIRE(seq.has_labels());
    const Scan s0 = seq.read(0);
    REQUIRE(s0.labels.size() == 1);
    CHECK(s0.labels[0] == Class::kRoad);
    CHECK(s0.instances[0] == 9);
    CHECK_THROWS_AS(seq.read(1), semlio::IoError);
    io::write_label_file(dir.file("s/predictions/000001.label"), {40U});  // 1 label, 2 points
    CHECK_THROWS_AS(seq.read(1), semlio::ValueError);
    std::string error;
    const Scan unreadable = seq.read_or_empty(1, error);
    CHECK(unreadable.empty());
    CHECK(unreadable.labels.empty());
    CHECK_THAT(error, Catch::Contains("1 labels") && Catch::Contains("2 points"));
  }
  {
    semlio_test::KittiTempDir dir("seq");
    make_scans(dir, "s", {0, 1});
    semlio_test::write_text(dir.file("s/times.txt"), "0\n0.1\n0.2\n");
    CHECK_THROWS_WITH(io::KittiSequence(dir.file("s")), Catch::Contains("3 times") && Catch::Contains("2 scans"));
    semlio_test::write_text(dir.file("s/times.txt"), "0\n-0.1\n");
    CHECK_THROWS_AS(io::KittiSequence(dir.file("s")), semlio::ValueError);
    semlio_test::write_text(dir.file("s/times.txt"), "0\n0.1\n");
    semlio_test::write_text(dir.file("s/calib.txt"), "Tr: 1 2 3\n");
    CHECK_THROWS_AS(io::KittiSequence(dir.file("s")), semlio::FormatError);
  }
}

}  // namespace test_kitti_sequence
