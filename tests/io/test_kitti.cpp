// KITTI .bin / .label / calib.txt / times.txt readers and writers.
#include <catch2/catch.hpp>

#include <sys/stat.h>

#include <semlio/io/kitti.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_kitti_tmp.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace test_kitti {  // one namespace per test file: the area compiles as one TU

namespace {

using semlio::Class;
using semlio::Scan;
namespace io = semlio::io;

std::string bin_bytes(const std::vector<std::array<float, 4>>& pts) {
  std::string b(pts.size() * 16, '\0');
  for (std::size_t i = 0; i < pts.size(); ++i) std::memcpy(b.data() + 16 * i, pts[i].data(), 16);
  return b;
}

std::string label_bytes(const std::vector<std::uint32_t>& raw) {
  std::string b(raw.size() * 4, '\0');
  if (!raw.empty()) std::memcpy(b.data(), raw.data(), b.size());
  return b;
}

template <typename E, typename F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "<no exception>";
}

}  // namespace

TEST_CASE("real KITTI scans: point count equals file size / 16, nothing dropped", "[io]") {
  for (const char* name : {"kitti/sequences/00/velodyne/000000.bin", "kitti/sequences/00/velodyne/000001.bin"}) {
    const std::string path = semlio_test::data_path(name);
    const auto bytes = std::filesystem::file_size(path);
    REQUIRE(bytes % 16 == 0);
    io::ReadStats stats;
    const Scan scan = io::read_kitti_bin(path, &stats);
    CHECK(scan.size() + stats.dropped() == bytes / 16);
    CHECK(stats.dropped() == 0);
    CHECK(scan.intensity.size() == scan.size());
    CHECK_FALSE(scan.has_labels());
    // HDL-64E: ~120k points within 120 m, reflectance in [0, 1].
    CHECK(scan.size() > 100000);
    float max_range = 0.0F;
    std::size_t bad_intensity = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      max_range = std::max(max_range, scan.points[i].norm());
      if (!(scan.intensity[i] >= 0.0F && scan.intensity[i] <= 1.0F)) ++bad_intensity;
    }
    CHECK(bad_intensity == 0);
    CHECK(max_range < 130.0F);
  }
  // Exact counts from the file sizes (1994688 and 1993680 bytes).
  CHECK(io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin")).size() == 124668);
  CHECK(io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000001.bin")).size() == 124605);
}

TEST_CASE("SemanticKITTI subset: 50 labelled points occur bit-exactly in scan 000000", "[io]") {
  const std::string sub_bin = semlio_test::data_path("kitti/semantickitti_subset/00/velodyne/000000.bin");
  const std::string sub_label = semlio_test::data_path("kitti/semantickitti_subset/00/labels/000000.label");
  const Scan sub = io::read_kitti_scan(sub_bin, sub_label);
  REQUIRE(sub.size() == 50);
  REQUIRE(sub.labels.size() == 50);
  REQUIRE(sub.instances.size() == 50);

  const Scan full = io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  const auto key = [](const Scan& s, std::size_t i) {
    std::array<std::uint32_t, 4> k{};
    std::memcpy(&k[0], &s.points[i].x(), 4);
    std::memcpy(&k[1], &s.points[i].y(), 4);
    std::memcpy(&k[2], &s.points[i].z(), 4);
    std::memcpy(&k[3], &s.intensity[i], 4);
    return k;
  };
  std::set<std::array<std::uint32_t, 4>> all;
  for (std::size_t i = 0; i < full.size(); ++i) all.insert(key(full, i));
  std::size_t found = 0;
  for (std::size_t i = 0; i < sub.size(); ++i) found += all.count(key(sub, i));
  CHECK(found == 50);

  // Histogram from the data README: building 25, vegetation 17, trunk 3,
  // pole 2, other-structure 1, unlabeled 2 (raw ids 50, 70, 71, 80, 52, 0).
  const auto raw = io::read_label_file(sub_label, 50);
  std::map<std::uint32_t, int> raw_hist;
  for (const auto r : raw) ++raw_hist[r & 0xFFFFU];
  CHECK(raw_hist == std::map<std::uint32_t, int>{{0, 2}, {50, 25}, {52, 1}, {70, 17}, {71, 3}, {80, 2}});
  // other-structure (52) is not a learning class: it maps to unlabeled.
  const auto h = semlio::label_histogram(sub);
  CHECK(h[semlio::index(Class::kBuilding)] == 25);
  CHECK(h[semlio::index(Class::kVegetation)] == 17);
  CHECK(h[semlio::index(Class::kTrunk)] == 3);
  CHECK(h[semlio::index(Class::kPole)] == 2);
  CHECK(h[semlio::index(Class::kUnlabeled)] == 3);
  std::uint32_t total = 0;
  for (const auto c : h) total += c;
  CHECK(total == 50);
}

TEST_CASE("bin and label round trip through the writers", "[io]") {
  semlio_test::KittiTempDir dir("kitti");
  const Scan real = io::read_kitti_scan(semlio_test::data_path("kitti/semantickitti_subset/00/velodyne/000000.bin"),
                                        semlio_test::data_path("kitti/semantickitti_subset/00/labels/000000.label"));
  io::write_kitti_bin(dir.file("a.bin"), real);
  io::write_label_file(dir.file("a.label"), io::raw_labels(real));
  CHECK(std::filesystem::file_size(dir.file("a.bin")) == 50 * 16);
  CHECK(std::filesystem::file_size(dir.file("a.label")) == 50 * 4);
  const Scan back = io::read_kitti_scan(dir.file("a.bin"), dir.file("a.label"));
  REQUIRE(back.size() == real.size());
  for (std::size_t i = 0; i < real.size(); ++i) {
    CHECK(std::memcmp(back.points[i].data(), real.points[i].data(), 12) == 0);
    CHECK(std::memcmp(&back.intensity[i], &real.intensity[i], 4) == 0);
    CHECK(back.labels[i] == real.labels[i]);
    CHECK(back.instances[i] == real.instances[i]);
  }
  io::write_kitti_scan(dir.file("d.bin"), dir.file("d.label"), real);
  const Scan d = io::read_kitti_scan(dir.file("d.bin"), dir.file("d.label"));
  CHECK(d.points == real.points);
  CHECK(d.labels == real.labels);
  // Real mismatch: the 50 subset labels do not fit the full 124 668-point scan.
  CHECK_THROWS_WITH(io::read_kitti_scan(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"),
                                        semlio_test::data_path("kitti/semantickitti_subset/00/labels/000000.label")),
                    Catch::Contains("50 labels") && Catch::Contains("124668 points"));
  // Raw label words (with instance ids) survive bit-exactly.
  const std::vector<std::uint32_t> raw = {10U | (7U << 16), 40U, 252U | (3U << 16), 0xFFFFFFFFU};
  io::write_label_file(dir.file("b.label"), raw);
  CHECK(io::read_label_file(dir.file("b.label"), 4) == raw);
  // A scan without intensity is written with intensity 0.
  Scan s;
  s.points = {{1.0F, 2.0F, 3.0F}};
  io::write_kitti_bin(dir.file("c.bin"), s);
  const Scan c = io::read_kitti_bin(dir.file("c.bin"));
  REQUIRE(c.size() == 1);
  CHECK(c.intensity[0] == 0.0F);
  CHECK(c.points[0] == s.points[0]);
}

TEST_CASE("bin: size not a multiple of 16, empty and missing files are rejected", "[io]") {
  semlio_test::KittiTempDir dir("kitti");
  std::string b = bin_bytes({{1.0F, 2.0F, 3.0F, 0.5F}});
  b.append(5, '\0');
  semlio_test::write_text(dir.file("odd.bin"), b);
  const std::string msg = message_of<semlio::FormatError>([&] { (void)io::read_kitti_bin(dir.file("odd.bin")); });
  CHECK_THAT(msg, Catch::Contains("odd.bin") && Catch::Contains("21 bytes") && Catch::Contains("16"));
  semlio_test::write_text(dir.file("empty.bin"), "");
  CHECK_THROWS_AS(io::read_kitti_bin(dir.file("empty.bin")), semlio::FormatError);
  CHECK_THROWS_AS(io::read_kitti_bin(dir.file("missing.bin")), semlio::IoError);
  CHECK_THROWS_WITH(io::read_kitti_bin(dir.file("missing.bin")), Catch::Contains("missing.bin"));
}

TEST_CASE("bin: NaN/Inf and exact zero points are dropped, counted, and labels stay aligned", "[io]") {
  semlio_test::KittiTempDir dir("kitti");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<std::array<float, 4>> pts = {
      {1.0F, 0.0F, 0.0F, 0.1F}, {nan, 1.0F, 1.0F, 0.2F},    {0.0F, 0.0F, 0.0F, 0.3F}, {2.0F, 2.0F, 2.0F, 0.4F},
      {3.0F, -inf, 3.0F, 0.5F}, {-0.0F, 0.0F, -0.0F, 0.6F}, {4.0F, 4.0F, 4.0F, nan},  {0.0F, 0.0F, 5.0F, 0.8F}};
  semlio_test::write_text(dir.file("x.bin"), bin_bytes(pts));
  // raw label of point i: semantic 40 (road) for kept even ids, instance i.
  const std::vector<std::uint32_t> raw = {10U | (0U << 16), 40U | (1U << 16), 50U | (2U << 16), 70U | (3U << 16),
                                          80U | (4U << 16), 81U | (5U << 16), 48U | (6U << 16), 72U | (7U << 16)};
  semlio_test::write_text(dir.file("x.label"), label_bytes(raw));

  io::ReadStats stats;
  const Scan s = io::read_kitti_scan(dir.file("x.bin"), dir.file("x.label"), &stats);
  CHECK(stats.dropped_nonfinite == 3);  // NaN x, -Inf y, NaN intensity
  CHECK(stats.dropped_zero == 2);       // (0,0,0) and (-0,0,-0)
  REQUIRE(s.size() == 3);
  CHECK(s.points[0] == Eigen::Vector3f(1.0F, 0.0F, 0.0F));
  CHECK(s.points[1] == Eigen::Vector3f(2.0F, 2.0F, 2.0F));
  CHECK(s.points[2] == Eigen::Vector3f(0.0F, 0.0F, 5.0F));
  CHECK(s.intensity == std::vector<float>{0.1F, 0.4F, 0.8F});
  CHECK(s.labels == std::vector<Class>{Class::kCar, Class::kVegetation, Class::kTerrain});
  CHECK(s.instances == std::vector<std::uint16_t>{0, 3, 7});

  // Stats accumulate over reads.
  (void)io::read_kitti_bin(dir.file("x.bin"), &stats);
  CHECK(stats.dropped() == 10);
}

TEST_CASE("label: count mismatch names both counts and the path, bad size is a FormatError", "[io]") {
  semlio_test::KittiTempDir dir("kitti");
  semlio_test::write_text(dir.file("s.bin"), bin_bytes({{1, 2, 3, 0}, {4, 5, 6, 0}, {7, 8, 9, 0}}));
  semlio_test::write_text(dir.file("s.label"), label_bytes({40, 40}));
  const std::string msg =
      message_of<semlio::ValueError>([&] { (void)io::read_kitti_scan(dir.file("s.bin"), dir.file("s.label")); });
  CHECK_THAT(msg, Catch::Contains("s.label") && Catch::Contains("2 labels") && Catch::Contains("3 points"));
  CHECK_THROWS_AS(io::read_label_file(dir.file("s.label"), 3), semlio::ValueError);
  semlio_test::write_text(dir.file("odd.label"), std::string(7, '\0'));
  CHECK_THROWS_AS(io::read_label_file(dir.file("odd.label"), 1), semlio::FormatError);
  CHECK_THROWS_AS(io::read_label_file(dir.file("none.label"), 1), semlio::IoError);
}

TEST_CASE("calib: real files parse, Tr is camera0-from-velodyne, round trip", "[io]") {
  const auto calib = io::read_kitti_calib(semlio_test::data_path("kitti/calib/calib_00-02_Tr_P0_RECONSTRUCTED.txt"));
  REQUIRE(calib.T_cam0_velo.has_value());
  CHECK_FALSE(calib.T_imu_velo.has_value());
  CHECK(calib.entries.count("P0") == 1);
  CHECK(calib.entries.at("P0").size() == 12);
  CHECK(calib.entries.at("P0")[0] == 718.856);
  // velodyne x (forward) is camera z (forward); velodyne y (left) is camera -x.
  const Eigen::Matrix3d R = calib.T_cam0_velo->rotation();
  CHECK(R(2, 0) == Approx(1.0).margin(1e-3));
  CHECK(R(0, 1) == Approx(-1.0).margin(1e-3));
  CHECK(calib.T_cam0_velo->translation().z() == Approx(-0.2921968648686).margin(1e-9));

  semlio_test::KittiTempDir dir("kitti");
  io::Calibration c2 = calib;
  c2.T_imu_velo = semlio::SE3d::exp((semlio::SE3d::Vector6() << 0.8, -0.3, 0.9, 0.01, -0.02, 0.03).finished());
  c2.entries["P2"] = {1.5, -2.25, 1e-20};
  io::write_kitti_calib(dir.file("calib.txt"), c2);
  const auto back = io::read_kitti_calib(dir.file("calib.txt"));
  CHECK(back.entries.at("P0") == calib.entries.at("P0"));
  CHECK(back.entries.at("P2") == c2.entries.at("P2"));
  REQUIRE(back.T_cam0_velo.has_value());
  REQUIRE(back.T_imu_velo.has_value());
  CHECK((back.T_cam0_velo->matrix() - calib.T_cam0_velo->matrix()).cwiseAbs().maxCoeff() < 1e-12);
  CHECK((back.T_imu_velo->matrix() - c2.T_imu_velo->matrix()).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(back.entries.size() == 4);  // P0, P2, Tr, Tr_imu_velo
}

TEST_CASE("calib: malformed lines are FormatErrors with the line number", "[io]") {
  semlio_test::KittiTempDir dir("kitti");
  const std::string tr = "Tr: 1 0 0 0.1 0 1 0 0.2 0 0 1 0.3\n";
  const auto expect = [&](const std::string& text, const std::string& what) {
    semlio_test::write_text(dir.file("calib.txt"), text);
    CHECK_THROWS_AS(io::read_kitti_calib(dir.file("calib.txt")), semlio::FormatError);
    CHECK_THROWS_WITH(io::read_kitti_calib(dir.file("calib.txt")),
                      Catch::Contains("calib.txt:2:") && Catch::Contains(what));
  };
  expect(tr + "P0 1 2 3\n", "no 'name:'");
  expect(tr + "P0: 1 2 x3\n", "'x3'");
  expect(tr + "P0:\n", "no values");
  expect(tr + "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n", "twice");
  expect("\nTr: 1 0 0 0 0 1 0 0 0 0 1\n", "11 values");
  expect(tr + "bad name: 1\n", "bad name");
  semlio_test::write_text(dir.file("calib.txt"), tr + "Tr_imu_velo: 2 0 0 0 0 1 0 0 0 0 1 0\n");
  CHECK_THROWS_AS(io::read_kitti_calib(dir.file("calib.txt")), semlio::ValueError);
  semlio_test::write_text(dir.file("calib.txt"), tr + "P0: 1 nan\n");
  CHECK_THROWS_AS(io::read_kitti_calib(dir.file("calib.txt")), semlio::ValueError);
  semlio_test::write_text(dir.file("calib.txt"), "\n\n");
  CHECK_THROWS_AS(io::read_kitti_calib(dir.file("calib.txt")), semlio::FormatError);
  CHECK_THROWS_AS(io::read_kitti_calib(dir.file("nope.txt")), semlio::IoError);
  // Tr_imu_velo is parsed into T_imu_velo.
  semlio_test::write_text(dir.file("calib.txt"), tr + "Tr_imu_velo: 1 0 0 -0.8 0 1 0 0.3 0 0 1 -0.9\r\n");
  const auto c = io::read_kitti_calib(dir.file("calib.txt"));
  REQUIRE(c.T_imu_velo.has_value());
  CHECK(c.T_imu_velo->translation() == Eigen::Vector3d(-0.8, 0.3, -0.9));
}

TEST_CASE("times: real prefix reads, round trip, backwards and malformed lines", "[io]") {
  const auto t = io::read_kitti_times(semlio_test::data_path("kitti/times_00_first200.txt"));
  REQUIRE(t.size() == 200);
  CHECK(t[0] == 0.0);
  CHECK(t[1] == 0.1037359);
  for (std::size_t i = 1; i < t.size(); ++i) CHECK((t[i] - t[i - 1] > 0.09 && t[i] - t[i - 1] < 0.12));

  semlio_test::KittiTempDir dir("kitti");
  std::vector<double> times = t;
  times.push_back(t.back() + 1.0 / 3.0);
  io::write_kitti_times(dir.file("times.txt"), times);
  CHECK(io::read_kitti_times(dir.file("times.txt")) == times);

  semlio_test::write_text(dir.file("b.txt"), "0.0\n0.1\n0.05\n");
  CHECK_THROWS_AS(io::read_kitti_times(dir.file("b.txt")), semlio::ValueError);
  CHECK_THROWS_WITH(io::read_kitti_times(dir.file("b.txt")),
                    Catch::Contains("b.txt:3:") && Catch::Contains("backwards"));
  semlio_test::write_text(dir.file("c.txt"), "0.0\n0.1 0.2\n");
  CHECK_THROWS_WITH(io::read_kitti_times(dir.file("c.txt")), Catch::Contains("c.txt:2:"));
  semlio_test::write_text(dir.file("d.txt"), "0.0\nabc\n");
  CHECK_THROWS_AS(io::read_kitti_times(dir.file("d.txt")), semlio::FormatError);
  semlio_test::write_text(dir.file("e.txt"), "0.0\nnan\n");
  CHECK_THROWS_AS(io::read_kitti_times(dir.file("e.txt")), semlio::ValueError);
  semlio_test::write_text(dir.file("f.txt"), "");
  CHECK_THROWS_AS(io::read_kitti_times(dir.file("f.txt")), semlio::FormatError);
  semlio_test::write_text(dir.file("g.txt"), "0\n\n1\n");
  CHECK_THROWS_WITH(io::read_kitti_times(dir.file("g.txt")), Catch::Contains("g.txt:2:"));
  CHECK_THROWS_AS(io::read_kitti_times(dir.file("h.txt")), semlio::IoError);
  // Equal consecutive times and a leading '+' are accepted.
  semlio_test::write_text(dir.file("i.txt"), "+1.5\n1.5\n2e0\n");
  CHECK(io::read_kitti_times(dir.file("i.txt")) == std::vector<double>{1.5, 1.5, 2.0});
}

}  // namespace test_kitti

namespace test_kitti {

TEST_CASE("bin: a file above the 10-million-point limit or not regular is an IoError, not an abort", "[io]") {
  // Audit issue 3: read_file grew without bound (std::bad_alloc escaped).
  semlio_test::KittiTempDir dir("kitti_big");
  const std::string big = dir.file("big.bin");
  semlio_test::write_text(big, "");
  // Sparse: one point more than the limit costs no disk and no memory.
  std::filesystem::resize_file(big, (io::kMaxKittiBinPoints + 1) * 16);
  const std::string msg = message_of<semlio::IoError>([&] { (void)io::read_kitti_bin(big); });
  CHECK_THAT(msg, Catch::Contains("big.bin") && Catch::Contains("160000016 bytes") &&
                      Catch::Contains("10000000 points"));
  // Below the limit the same file reads: its 100 points are all (0,0,0), dropped.
  std::filesystem::resize_file(big, 1600);
  io::ReadStats stats;
  CHECK(io::read_kitti_bin(big, &stats).empty());
  CHECK(stats.dropped_zero == 100);
  // Devices, FIFOs and directories: IoError naming the path.
  CHECK_THROWS_WITH(io::read_kitti_bin("/dev/zero"),
                    Catch::Contains("/dev/zero") && Catch::Contains("not a regular file"));
  CHECK_THROWS_AS(io::read_label_file("/dev/zero", 3), semlio::IoError);
  const std::string fifo = dir.file("fifo.bin");
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  CHECK_THROWS_WITH(io::read_kitti_bin(fifo), Catch::Contains("fifo.bin") && Catch::Contains("not a regular file"));
  CHECK_THROWS_AS(io::read_kitti_times(dir.str()), semlio::IoError);
  CHECK_THROWS_AS(io::read_kitti_calib(fifo), semlio::IoError);
}

}  // namespace test_kitti
