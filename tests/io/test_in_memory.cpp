// In-memory entry points of the readers (parse_X(bytes, name)) and writers
// (format_X): the path-taking readers are thin wrappers around them, so a
// parse of a fixture's bytes must give exactly what reading its path gives,
// and format_X must give exactly the bytes write_X writes. Errors from the
// in-memory forms name the `name` they were given.
#include <catch2/catch.hpp>

#include <semlio/io/detail/text.hpp>
#include <semlio/io/g2o.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/kitti_raw.hpp>
#include <semlio/io/oxts.hpp>
#include <semlio/io/pcd.hpp>
#include <semlio/io/ply.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_kitti_tmp.hpp>

#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace test_in_memory {  // one namespace per test file: the area compiles as one TU

namespace {

namespace io = semlio::io;
using semlio::Scan;

std::string bytes_of(const std::string& path) { return io::detail::read_file(path); }

/// Field by field, bit for bit (floats compared as bytes: NaN-safe, -0 != 0).
bool same_scan(const Scan& a, const Scan& b) {
  if (a.size() != b.size() || a.intensity.size() != b.intensity.size() || a.labels != b.labels ||
      a.instances != b.instances || a.rings != b.rings || a.times_s.size() != b.times_s.size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::memcmp(a.points[i].data(), b.points[i].data(), 3 * sizeof(float)) != 0) return false;
  }
  const auto same_bytes = [](const auto& x, const auto& y) {
    return x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
  };
  return same_bytes(a.intensity, b.intensity) && same_bytes(a.times_s, b.times_s);
}

bool same_poses(const std::vector<semlio::SE3d>& a, const std::vector<semlio::SE3d>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].matrix() != b[i].matrix()) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("parse_kitti_bin / parse_kitti_scan equal the path readers on SemanticKITTI data", "[io][memory]") {
  const std::string bin = semlio_test::data_path("kitti/semantickitti_subset/00/velodyne/000000.bin");
  const std::string label = semlio_test::data_path("kitti/semantickitti_subset/00/labels/000000.label");
  io::ReadStats from_path;
  io::ReadStats from_bytes;
  const Scan a = io::read_kitti_bin(bin, &from_path);
  const std::string bin_bytes = bytes_of(bin);
  const Scan b = io::parse_kitti_bin(bin_bytes, "mem.bin", &from_bytes);
  REQUIRE(a.size() == 50);  // the subset holds 50 points, none dropped
  CHECK(same_scan(a, b));
  CHECK(from_path.dropped() == from_bytes.dropped());
  CHECK(a.size() + from_path.dropped() == bin_bytes.size() / 16);

  const std::string label_bytes = bytes_of(label);
  const Scan la = io::read_kitti_scan(bin, label);
  const Scan lb = io::parse_kitti_scan(bin_bytes, "mem.bin", label_bytes, "mem.label");
  REQUIRE(la.labels.size() == la.size());
  CHECK(same_scan(la, lb));
  CHECK(io::parse_label_file(label_bytes, "mem.label", bin_bytes.size() / 16) ==
        io::read_label_file(label, bin_bytes.size() / 16));

  // format_* are the bytes write_* writes.
  semlio_test::KittiTempDir tmp("memory");
  const std::string out = tmp.file("w.bin");
  io::write_kitti_bin(out, a);
  CHECK(bytes_of(out) == io::format_kitti_bin(a));
  const std::vector<std::uint32_t> raw = io::raw_labels(la);
  io::write_label_file(tmp.file("w.label"), raw);
  CHECK(bytes_of(tmp.file("w.label")) == io::format_label_file(raw));
}

TEST_CASE("KITTI in-memory errors name the given name and keep the path readers' rules", "[io][memory]") {
  using Catch::Matchers::Contains;
  CHECK_THROWS_AS(io::parse_kitti_bin("", "mem.bin"), semlio::FormatError);
  CHECK_THROWS_WITH(io::parse_kitti_bin(std::string(17, 'x'), "mem.bin"),
                    Contains("mem.bin") && Contains("17 bytes is not a multiple of 16"));
  CHECK_THROWS_WITH(io::parse_label_file(std::string(6, '\0'), "mem.label", 1), Contains("mem.label"));
  CHECK_THROWS_AS(io::parse_label_file(std::string(8, '\0'), "mem.label", 3), semlio::ValueError);
  CHECK_THROWS_AS(io::parse_kitti_scan(std::string(32, '\1'), "mem.bin", std::string_view(std::string(4, '\0')),
                                       "mem.label"),
                  semlio::ValueError);
  CHECK_THROWS_WITH(io::parse_kitti_times("1\n\n2\n", "mem_times.txt"),
                    Contains("mem_times.txt:2") && Contains("blank line"));
  CHECK_THROWS_WITH(io::parse_kitti_calib("Tr: 1 2 3\n", "mem_calib.txt"), Contains("mem_calib.txt:1"));
  CHECK_THROWS_WITH(io::parse_kitti_poses("1 0 0 0\n", "mem_poses.txt"), Contains("mem_poses.txt:1"));
  CHECK_THROWS_WITH(io::parse_tum_trajectory("# only a comment\n", "mem.tum"), Contains("mem.tum"));
}

TEST_CASE("parse_kitti_calib / times / poses / TUM equal the path readers, format_* equal write_*",
          "[io][memory]") {
  semlio_test::KittiTempDir tmp("memory");
  for (const char* rel : {"kitti/sequences/00/calib.txt", "kitti/calib/calib_04-10_Tr_RECONSTRUCTED.txt"}) {
    const std::string path = semlio_test::data_path(rel);
    const io::Calibration a = io::read_kitti_calib(path);
    const io::Calibration b = io::parse_kitti_calib(bytes_of(path), "mem");
    CHECK(a.entries == b.entries);
    REQUIRE(a.T_cam0_velo.has_value());
    REQUIRE(b.T_cam0_velo.has_value());
    CHECK(a.T_cam0_velo->matrix() == b.T_cam0_velo->matrix());
    io::write_kitti_calib(tmp.file("calib.txt"), a);
    CHECK(bytes_of(tmp.file("calib.txt")) == io::format_kitti_calib(a));
  }

  const std::string times_path = semlio_test::data_path("kitti/times_00_first200.txt");
  const std::vector<double> times = io::read_kitti_times(times_path);
  CHECK(times.size() == 200);
  CHECK(io::parse_kitti_times(bytes_of(times_path), "mem") == times);
  io::write_kitti_times(tmp.file("times.txt"), times);
  CHECK(bytes_of(tmp.file("times.txt")) == io::format_kitti_times(times));

  const std::string poses_path = semlio_test::data_path("kitti/poses/04.txt");
  const std::vector<semlio::SE3d> poses = io::read_kitti_poses(poses_path);
  REQUIRE(poses.size() > 100);
  CHECK(same_poses(io::parse_kitti_poses(bytes_of(poses_path), "mem"), poses));
  io::write_kitti_poses(tmp.file("poses.txt"), poses);
  CHECK(bytes_of(tmp.file("poses.txt")) == io::format_kitti_poses(poses));

  std::vector<io::StampedPose> tum;
  for (std::size_t i = 0; i < poses.size(); ++i) tum.push_back({0.1 * static_cast<double>(i), poses[i]});
  io::write_tum_trajectory(tmp.file("traj.tum"), tum);
  const std::string tum_text = bytes_of(tmp.file("traj.tum"));
  CHECK(tum_text == io::format_tum_trajectory(tum));
  const auto ta = io::read_tum_trajectory(tmp.file("traj.tum"));
  const auto tb = io::parse_tum_trajectory(tum_text, "mem");
  REQUIRE(ta.size() == tum.size());
  REQUIRE(tb.size() == tum.size());
  for (std::size_t i = 0; i < ta.size(); ++i) {
    CHECK(ta[i].stamp_s == tb[i].stamp_s);
    CHECK(ta[i].pose.matrix() == tb[i].pose.matrix());
  }
}

TEST_CASE("parse_pcd / parse_ply equal the path readers, format_pcd / format_ply equal the writers",
          "[io][memory]") {
  semlio_test::KittiTempDir tmp("memory");
  const std::string pcd = semlio_test::data_path("kitti_raw/snippet_22/0000000000.pcd");
  io::ReadStats sa;
  io::ReadStats sb;
  const Scan a = io::read_pcd(pcd, &sa);
  const Scan b = io::parse_pcd(bytes_of(pcd), "mem.pcd", &sb);
  REQUIRE(a.size() > 1000);
  CHECK(same_scan(a, b));
  CHECK(sa.dropped() == sb.dropped());
  for (const auto enc : {io::PcdEncoding::kBinary, io::PcdEncoding::kAscii}) {
    io::write_pcd(tmp.file("w.pcd"), a, enc);
    const std::string text = io::format_pcd(a, enc);
    CHECK(bytes_of(tmp.file("w.pcd")) == text);
    CHECK(same_scan(io::parse_pcd(text, "rt.pcd"), a));
  }

  const std::string ply = semlio_test::data_path("scan_pair/source.ply");
  const Scan pa = io::read_ply(ply);
  const Scan pb = io::parse_ply(bytes_of(ply), "mem.ply");
  REQUIRE(!pa.empty());
  CHECK(same_scan(pa, pb));
  for (const auto enc :
       {io::PlyEncoding::kBinaryLittleEndian, io::PlyEncoding::kBinaryBigEndian, io::PlyEncoding::kAscii}) {
    io::write_ply(tmp.file("w.ply"), pa, enc);
    const std::string text = io::format_ply(pa, enc);
    CHECK(bytes_of(tmp.file("w.ply")) == text);
    CHECK(same_scan(io::parse_ply(text, "rt.ply"), pa));
  }

  using Catch::Matchers::Contains;
  CHECK_THROWS_WITH(io::parse_pcd("VERSION 0.7\nFIELDS x\n", "mem.pcd"), Contains("mem.pcd"));
  CHECK_THROWS_WITH(io::parse_ply("not a ply\n", "mem.ply"), Contains("mem.ply"));
}

TEST_CASE("parse_oxts equals read_oxts on the KITTI raw drive 0009 excerpt", "[io][memory]") {
  // The excerpt holds the first 12 data files of 447 timestamps: a directory
  // of those 12 records (timestamps cut to 12 lines) is what read_oxts reads.
  const std::string src = semlio_test::data_path("kitti_raw/2011_09_26/2011_09_26_drive_0009_sync/oxts");
  semlio_test::KittiTempDir tmp("memory");
  const std::string dir = tmp.str() + "/oxts";
  constexpr std::size_t kRecords = 12;
  std::string stamps;
  io::detail::for_each_line(bytes_of(src + "/timestamps.txt"), [&](long line, std::string_view s) {
    if (line <= static_cast<long>(kRecords)) stamps.append(s).push_back('\n');
  });
  std::filesystem::create_directories(dir + "/data");
  io::detail::write_file(dir + "/timestamps.txt", stamps);
  std::vector<std::string> files;
  for (std::size_t i = 0; i < kRecords; ++i) {
    const std::string rel = "/data/" + io::detail::frame_stem(i, 10) + ".txt";
    files.push_back(bytes_of(src + rel));
    io::detail::write_file(dir + rel, files.back());
  }
  const std::vector<io::OxtsRecord> a = io::read_oxts(dir);
  REQUIRE(a.size() == kRecords);
  const std::vector<std::string_view> views(files.begin(), files.end());
  const std::vector<io::OxtsRecord> b = io::parse_oxts(stamps, views, dir);
  REQUIRE(b.size() == a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(b[i].stamp_s == a[i].stamp_s);
    CHECK(b[i].lat_deg == a[i].lat_deg);
    CHECK(b[i].gyro_body_radps == a[i].gyro_body_radps);
    CHECK(b[i].accel_body_mps2 == a[i].accel_body_mps2);
    CHECK(b[i].orimode == a[i].orimode);
  }
  const std::vector<double> s = io::parse_oxts_timestamps(stamps, "mem_stamps.txt");
  REQUIRE(s.size() == a.size());
  CHECK(s.front() == a.front().stamp_s);

  // One data file fewer than timestamps: the count check of read_oxts.
  using Catch::Matchers::Contains;
  const std::vector<std::string_view> fewer(views.begin(), views.end() - 1);
  CHECK_THROWS_WITH(io::parse_oxts(stamps, fewer, "mem_oxts"), Contains("mem_oxts") && Contains("timestamps.txt has"));
  io::OxtsRecord rec;
  CHECK_THROWS_WITH(io::parse_oxts_data(files[0] + files[1], "mem_data.txt", rec),
                    Contains("mem_data.txt:2") && Contains("more than one OXTS line"));

  // format_oxts_timestamps is the timestamps.txt write_oxts writes.
  io::write_oxts(tmp.str() + "/written", a);
  CHECK(bytes_of(tmp.str() + "/written/timestamps.txt") == io::format_oxts_timestamps(a));
}

TEST_CASE("parse_g2o equals read_g2o, format_g2o equals write_g2o", "[io][memory]") {
  semlio_test::KittiTempDir tmp("memory");
  for (const char* rel : {"posegraphs/tinyGrid3D.g2o", "posegraphs/M3500.g2o"}) {
    const std::string path = semlio_test::data_path(rel);
    const io::G2oGraph a = io::read_g2o(path);
    const io::G2oGraph b = io::parse_g2o(bytes_of(path), "mem.g2o");
    REQUIRE(a.vertices3.size() + a.vertices2.size() > 0);
    CHECK(b.dimension == a.dimension);
    CHECK(b.vertices3.size() == a.vertices3.size());
    CHECK(b.edges3.size() == a.edges3.size());
    CHECK(b.vertices2.size() == a.vertices2.size());
    CHECK(b.edges2.size() == a.edges2.size());
    CHECK(b.fixed == a.fixed);
    io::write_g2o(tmp.file("w.g2o"), a);
    const std::string text = io::format_g2o(a);
    CHECK(bytes_of(tmp.file("w.g2o")) == text);
    CHECK(io::parse_g2o(text, "rt.g2o").edges3.size() + io::parse_g2o(text, "rt.g2o").edges2.size() ==
          a.edges3.size() + a.edges2.size());
  }
  using Catch::Matchers::Contains;
  CHECK_THROWS_WITH(io::parse_g2o("VERTEX_SE2 0 1 2\n", "mem.g2o"), Contains("mem.g2o:1"));
}

TEST_CASE("parse_kitti_raw_calib / parse_raw_stamp_lines equal the path readers on drive 0009", "[io][memory]") {
  const std::string date = semlio_test::data_path("kitti_raw/2011_09_26/");
  for (const char* name : {"calib_velo_to_cam.txt", "calib_imu_to_velo.txt"}) {
    const semlio::SE3d a = io::read_kitti_raw_calib(date + name);
    const semlio::SE3d b = io::parse_kitti_raw_calib(bytes_of(date + name), "mem_calib.txt");
    CHECK(a.matrix() == b.matrix());
    CHECK(a.translation().norm() > 0.0);
  }
  const std::string stamps = date + "2011_09_26_drive_0009_sync/velodyne_points/timestamps.txt";
  const auto a = io::detail::read_raw_stamp_lines(stamps);
  const auto b = io::detail::parse_raw_stamp_lines(bytes_of(stamps), "mem_stamps.txt");
  REQUIRE(a.size() > 180);
  CHECK(a == b);
  CHECK(!a[177].has_value());  // line 178: a sweep the recorder dropped (see kitti_raw.hpp)
  using Catch::Matchers::Contains;
  CHECK_THROWS_WITH(io::parse_kitti_raw_calib("R: 1 0 0 0 1 0 0 0 1\n", "mem_calib.txt"),
                    Contains("mem_calib.txt") && Contains("no 'T:' line"));
  CHECK_THROWS_WITH(io::detail::parse_raw_stamp_lines("2011-09-26 13:08:43.0\n2011-09-26 13:08:42.0\n", "mem.txt"),
                    Contains("mem.txt:2"));
}

}  // namespace test_in_memory
