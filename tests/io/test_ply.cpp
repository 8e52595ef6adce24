// PLY reader/writer: round trips in all three encodings, property layouts, the
// real scan pair, and every malformed input the reader must reject.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <semlio/io/ply.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_cloud_checks.hpp>
#include <semlio_test/io_cloud_files.hpp>

namespace test_ply {  // one namespace per test file: the area compiles as one TU

namespace {

using semlio::Class;
using semlio::Scan;
using semlio::io::PlyEncoding;
using semlio::io::read_ply;
using semlio::io::ReadStats;
using semlio::io::write_ply;
using semlio_test::CloudTempDir;
using semlio_test::require_error;

/// Appends the host (little-endian) bytes of v.
template <typename T>
void put(std::string& out, T v) {
  char raw[sizeof(T)];
  std::memcpy(raw, &v, sizeof(T));
  out.append(raw, sizeof(T));
}

Scan sample_scan() {
  Scan s;
  s.points = {{1.0F, 2.0F, 3.0F},
              {-0.1F, 1e-30F, 3.4e38F},
              {0.0F, 0.0F, -7.25F},
              {123.456F, -78.9F, 0.333F}};
  s.intensity = {0.0F, 0.25F, 1.0F, 187.0F};
  s.labels = {Class::kCar, Class::kVegetation, Class::kUnlabeled, Class::kPole};
  s.instances = {12, 0, 0, 1};
  return s;
}

/// Requires equal sizes and bit-identical fields; reports the first mismatch
/// (one assertion per scan, not per point).
void require_same(const Scan& a, const Scan& b) {
  REQUIRE(a.size() == b.size());
  REQUIRE(a.intensity.size() == b.intensity.size());
  REQUIRE(a.labels.size() == b.labels.size());
  REQUIRE(a.instances.size() == b.instances.size());
  REQUIRE(a.rings.size() == b.rings.size());
  REQUIRE(a.times_s.size() == b.times_s.size());
  std::size_t first_mismatch = a.size();
  for (std::size_t i = 0; i < a.size() && first_mismatch == a.size(); ++i) {
    // Bit-exact: the writers must not lose precision.
    const bool same =
        std::memcmp(a.points[i].data(), b.points[i].data(), 3 * sizeof(float)) == 0 &&
        (a.intensity.empty() || std::memcmp(&a.intensity[i], &b.intensity[i], 4) == 0) &&
        (a.labels.empty() || a.labels[i] == b.labels[i]) &&
        (a.instances.empty() || a.instances[i] == b.instances[i]) &&
        (a.rings.empty() || a.rings[i] == b.rings[i]) &&
        (a.times_s.empty() || std::memcmp(&a.times_s[i], &b.times_s[i], 4) == 0);
    if (!same) first_mismatch = i;
  }
  CHECK(first_mismatch == a.size());
}

}  // namespace

TEST_CASE("PLY writers round-trip bit-exactly in all encodings", "[io]") {
  CloudTempDir dir("ply_roundtrip");
  const Scan in = sample_scan();
  for (const auto enc :
       {PlyEncoding::kBinaryLittleEndian, PlyEncoding::kBinaryBigEndian, PlyEncoding::kAscii}) {
    const std::string path = dir.file("rt.ply");
    write_ply(path, in, enc);
    ReadStats stats;
    require_same(in, read_ply(path, &stats));
    CHECK(stats.dropped() == 0);
  }
  // Without intensity and labels only x y z are written and read back.
  Scan xyz;
  xyz.points = {{1.0F, 2.0F, 3.0F}};
  write_ply(dir.file("xyz.ply"), xyz);
  const Scan back = read_ply(dir.file("xyz.ply"));
  require_same(xyz, back);
  CHECK_FALSE(back.has_intensity());
  CHECK_FALSE(back.has_labels());
  write_ply(dir.file("empty.ply"), Scan{});
  CHECK(read_ply(dir.file("empty.ply")).empty());
}

TEST_CASE("PLY carries ring and per-point time", "[io]") {
  CloudTempDir dir("ply_ring");
  Scan in = sample_scan();
  in.rings = {0, 31, 5, 65535};
  in.times_s = {0.0F, 0.0999F, 0.05F, 1e-7F};
  for (const auto enc :
       {PlyEncoding::kBinaryLittleEndian, PlyEncoding::kBinaryBigEndian, PlyEncoding::kAscii}) {
    const std::string path = dir.file("ring.ply");
    write_ply(path, in, enc);
    CHECK(semlio_test::read_bytes(path).find("property ushort ring\nproperty float time\n") !=
          std::string::npos);
    require_same(in, read_ply(path));
  }
}

TEST_CASE("PLY writer stores the raw label and the SemanticKITTI colour", "[io]") {
  CloudTempDir dir("ply_colour");
  const Scan in = sample_scan();
  const std::string path = dir.file("colour.ply");
  write_ply(path, in);
  const std::string bytes = semlio_test::read_bytes(path);
  const std::string end = "end_header\n";
  const std::size_t data = bytes.find(end) + end.size();
  CHECK(bytes.find("format binary_little_endian 1.0\n") != std::string::npos);
  CHECK(bytes.find("property uint label\nproperty uchar red\nproperty uchar green\n"
                   "property uchar blue\n") != std::string::npos);
  // Records: 4 floats, uint label, 3 uchar = 23 bytes.
  REQUIRE(bytes.size() - data == 23 * in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    const char* rec = bytes.data() + data + 23 * i;
    std::uint32_t raw = 0;
    std::memcpy(&raw, rec + 16, 4);
    CHECK(raw ==
          (semlio::raw_id(in.labels[i]) | (static_cast<std::uint32_t>(in.instances[i]) << 16)));
    const semlio::Rgb c = semlio::class_colour(in.labels[i]);
    CHECK(static_cast<std::uint8_t>(rec[20]) == c.r);
    CHECK(static_cast<std::uint8_t>(rec[21]) == c.g);
    CHECK(static_cast<std::uint8_t>(rec[22]) == c.b);
  }
  // Car is raw 10 in SemanticKITTI (semantic-kitti.yaml).
  std::uint32_t raw0 = 0;
  std::memcpy(&raw0, bytes.data() + data + 16, 4);
  CHECK(raw0 == (10U | (12U << 16)));
}

TEST_CASE("PLY reader drops and counts NaN/Inf and (0,0,0) points", "[io]") {
  CloudTempDir dir("ply_drop");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  Scan s;
  s.points = {{0, 0, 0}, {1, 1, 1}, {inf, 0, 0}, {0, 0, 0}, {2, 0, 0}};
  s.intensity = {1, 2, 3, 4, nan};
  for (const auto enc : {PlyEncoding::kBinaryLittleEndian, PlyEncoding::kAscii}) {
    write_ply(dir.file("drop.ply"), s, enc);
    ReadStats stats;
    const Scan out = read_ply(dir.file("drop.ply"), &stats);
    REQUIRE(out.size() == 1);
    CHECK(out.intensity[0] == 2.0F);
    CHECK(stats.dropped_zero == 2);
    CHECK(stats.dropped_nonfinite == 2);
  }
}

TEST_CASE("PLY reader skips other properties and elements by declared type", "[io]") {
  CloudTempDir dir("ply_layout");
  // A 'camera' element with a list comes before 'vertex'; vertex carries
  // properties of several types; a 'face' element follows.
  const std::string head =
      "property float32 fx\nproperty list uchar int ids\n"
      "element vertex 2\ncomment between\nproperty double x\nproperty uchar flags\n"
      "property int16 y\nproperty float z\nproperty ushort Scalar_Intensity\n"
      "property int label\nproperty uint8 red\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  std::string bin =
      "ply\nformat binary_little_endian 1.0\nobj_info test\nelement camera 2\n" + head;
  for (int k = 0; k < 2; ++k) {  // camera: fx, list of k+1 ints
    put<float>(bin, 500.0F);
    put<std::uint8_t>(bin, static_cast<std::uint8_t>(k + 1));
    for (int j = 0; j <= k; ++j) put<std::int32_t>(bin, 99);
  }
  for (int k = 0; k < 2; ++k) {
    put<double>(bin, k == 0 ? 0.5 : -4.0);
    put<std::uint8_t>(bin, 255);
    put<std::int16_t>(bin, static_cast<std::int16_t>(k == 0 ? -12 : 3));
    put<float>(bin, k == 0 ? 8.0F : 0.0F);
    put<std::uint16_t>(bin, static_cast<std::uint16_t>(k == 0 ? 1000 : 7));
    put<std::int32_t>(bin, k == 0 ? 70 : (81 | (5 << 16)));  // vegetation; traffic-sign #5
    put<std::uint8_t>(bin, 1);
  }
  bin += std::string("\x03\0\0\0\0\x01\0\0\0\x02\0\0\0", 13);  // the face (never read)

  const std::string txt = "ply\nformat ascii 1.0\nelement camera 2\n" + head +
                          "500 1 99\n500 2 99 99\n"
                          "0.5 255 -12 8 1000 70 1\n"
                          "-4 255 3 0 7 327761 1\n"
                          "3 0 1 2\n";
  for (const std::string& bytes : {bin, txt}) {
    const Scan s = read_ply(dir.write("layout.ply", bytes));
    REQUIRE(s.size() == 2);
    CHECK(s.points[0] == Eigen::Vector3f(0.5F, -12.0F, 8.0F));
    CHECK(s.points[1] == Eigen::Vector3f(-4.0F, 3.0F, 0.0F));
    CHECK(s.intensity == std::vector<float>{1000.0F, 7.0F});
    CHECK(s.labels == std::vector<Class>{Class::kVegetation, Class::kTrafficSign});
    CHECK(s.instances == std::vector<std::uint16_t>{0, 5});
  }
}

TEST_CASE("PLY reader rejects bad input with typed errors naming the path", "[io]") {
  CloudTempDir dir("ply_bad");
  const auto ply_error = [&](const std::string& name, const std::string& bytes,
                             const std::string& fragment) {
    const std::string path = dir.write(name, bytes);
    INFO(name);
    require_error<semlio::FormatError>([&] { (void)read_ply(path); }, path, fragment);
  };
  const std::string xyz =
      "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n";

  SECTION("missing file") {
    const std::string missing = dir.file("missing.ply");
    require_error<semlio::IoError>([&] { (void)read_ply(missing); }, missing, "does not exist");
  }
  SECTION("empty file") { ply_error("empty.ply", "", "empty file"); }
  SECTION("truncated binary payload") {
    std::string bin = "ply\nformat binary_little_endian 1.0\n" + xyz + "end_header\n";
    for (int k = 0; k < 5; ++k) put<float>(bin, 1.0F);  // 5 of 6 floats
    ply_error("trunc.ply", bin, "declares 2 vertices (12 bytes each) but only 20 bytes");
    // The real scan cut short by one byte.
    const std::string real =
        semlio_test::read_bytes(semlio_test::data_path("scan_pair/source.ply"));
    ply_error("trunc_real.ply", real.substr(0, real.size() - 1), "declares 69792 vertices");
  }
  SECTION("truncated element before the vertices") {
    std::string bin =
        "ply\nformat binary_big_endian 1.0\nelement cam 1\nproperty list uchar int v\n" + xyz +
        "end_header\n";
    bin += std::string("\x05\0\0\0\0", 5);
    ply_error("trunc_cam.ply", bin, "element 'cam' runs past the end");
  }
  SECTION("truncated and overlong ascii") {
    const std::string h = "ply\nformat ascii 1.0\n" + xyz + "end_header\n";
    ply_error("few.ply", h + "1 2 3\n", "declares 2 'vertex' lines but only 1 follow");
    ply_error("many.ply", h + "1 2 3\n4 5 6\n7 8 9\n", ":10: header lies about its vertex count");
    ply_error("tokens.ply", h + "1 2 3\n4 5\n", ":9: expected 3 vertex values, got 2");
    ply_error("num.ply", h + "1 2 3\n4 five 6\n", ":9: vertex property 'y' value 'five'");
  }
  SECTION("bad header lines") {
    ply_error("magic.ply", "plx\nformat ascii 1.0\n", ":1: not a PLY file");
    ply_error("format.ply", "ply\nformat binary_middle_endian 1.0\n" + xyz + "end_header\n",
              ":2: unknown PLY format 'binary_middle_endian'");
    ply_error("version.ply", "ply\nformat ascii 2.0\n" + xyz + "end_header\n",
              ":2: unsupported PLY version '2.0'");
    ply_error("noend.ply", "ply\nformat ascii 1.0\n" + xyz, "no end_header");
    ply_error("noformat.ply", "ply\n" + xyz + "end_header\n", "no format line");
    ply_error("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\n",
              ":4: unknown property type 'float128'");
    ply_error("keyword.ply", "ply\nformat ascii 1.0\nelemnt vertex 1\n",
              ":3: unknown PLY header keyword 'elemnt'");
    ply_error("count.ply", "ply\nformat ascii 1.0\nelement vertex -3\nend_header\n",
              ":3: element 'vertex' count '-3'");
    ply_error("orphan.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
              ":3: property declared before any element");
    ply_error("novertex.ply", "ply\nformat ascii 1.0\nelement face 0\nend_header\n",
              "no 'vertex' element");
    ply_error(
        "noz.ply",
        "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n",
        ":3: vertex element lacks one of x, y, z");
    ply_error("list.ply",
              "ply\nformat ascii 1.0\n" + xyz + "property list uchar float normal\nend_header\n",
              "list property 'normal' in the vertex element is unsupported");
    ply_error("flabel.ply", "ply\nformat ascii 1.0\n" + xyz + "property float label\nend_header\n",
              "'label' is a float");
    ply_error("fring.ply", "ply\nformat ascii 1.0\n" + xyz + "property double ring\nend_header\n",
              "'ring' is a float");
  }
}

namespace {

/// What the test itself reads from a real PLY of the scan pair: vertex count
/// from the header, header length, and the float32 records.
struct RawPly {
  std::size_t header_bytes = 0;
  std::size_t vertices = 0;
  std::vector<float> values;  // x y z scalar_intensity per vertex
  std::size_t file_bytes = 0;
};

RawPly raw_ply(const std::string& path) {
  const std::string bytes = semlio_test::read_bytes(path);
  RawPly r;
  r.file_bytes = bytes.size();
  const std::string end = "end_header\n";
  r.header_bytes = bytes.find(end) + end.size();
  std::istringstream header(bytes.substr(0, r.header_bytes));
  std::string line;
  std::vector<std::string> props;
  while (std::getline(header, line)) {
    if (line.rfind("element vertex ", 0) == 0) r.vertices = std::stoul(line.substr(15));
    if (line.rfind("property ", 0) == 0) props.push_back(line);
  }
  REQUIRE(props == std::vector<std::string>{"property float x", "property float y",
                                            "property float z", "property float scalar_intensity"});
  REQUIRE(bytes.size() >= r.header_bytes + 16 * r.vertices);
  r.values.resize(4 * r.vertices);
  std::memcpy(r.values.data(), bytes.data() + r.header_bytes, 16 * r.vertices);
  return r;
}

}  // namespace

TEST_CASE("PLY reader on the real scan pair", "[io]") {
  for (const char* name : {"scan_pair/source.ply", "scan_pair/target.ply"}) {
    const std::string path = semlio_test::data_path(name);
    INFO(path);
    const RawPly raw = raw_ply(path);
    // The header's count matches the payload exactly (no padding in these files).
    CHECK(raw.file_bytes == raw.header_bytes + 16 * raw.vertices);
    CHECK(raw.vertices > 60000);  // README: about 70k points each
    CHECK(raw.vertices < 80000);
    std::size_t zeros = 0, nonfinite = 0;
    for (std::size_t i = 0; i < raw.vertices; ++i) {
      const float* v = &raw.values[4 * i];
      if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]) ||
          !std::isfinite(v[3])) {
        ++nonfinite;
      } else if (v[0] == 0.0F && v[1] == 0.0F && v[2] == 0.0F) {
        ++zeros;
      }
    }
    CHECK(zeros > 4500);  // README: about 5 100 exact zeros per scan
    CHECK(zeros < 5700);

    ReadStats stats;
    const Scan scan = read_ply(path, &stats);
    REQUIRE(scan.size() == raw.vertices - zeros - nonfinite);
    CHECK(stats.dropped_zero == zeros);
    CHECK(stats.dropped_nonfinite == nonfinite);
    REQUIRE(scan.intensity.size() == scan.size());  // from 'scalar_intensity'
    CHECK_FALSE(scan.has_labels());
    // Intensities are 8-bit-scaled reflectances: within [0, 255], not constant.
    const auto [lo, hi] = std::minmax_element(scan.intensity.begin(), scan.intensity.end());
    CHECK(*lo >= 0.0F);
    CHECK(*hi <= 255.0F);
    CHECK(*hi > *lo + 10.0F);
    // Every kept point is one of the file's non-zero records, in order.
    std::size_t k = 0;
    bool same = true;
    for (std::size_t i = 0; i < raw.vertices && same; ++i) {
      const float* v = &raw.values[4 * i];
      if (v[0] == 0.0F && v[1] == 0.0F && v[2] == 0.0F) continue;
      same = scan.points[k].x() == v[0] && scan.points[k].y() == v[1] &&
             scan.points[k].z() == v[2] && scan.intensity[k] == v[3];
      ++k;
    }
    CHECK(same);
  }
}

TEST_CASE("PLY writer round-trips the real scan with labels", "[io]") {
  CloudTempDir dir("ply_real");
  Scan in = read_ply(semlio_test::data_path("scan_pair/target.ply"));
  // Synthetic labels by height, so the colour columns vary.
  in.labels.resize(in.size());
  in.instances.assign(in.size(), 0);  // the reader fills instances whenever labels exist
  for (std::size_t i = 0; i < in.size(); ++i) {
    in.labels[i] = in.points[i].z() < -1.0F  ? Class::kRoad
                   : in.points[i].z() < 1.0F ? Class::kCar
                                             : Class::kBuilding;
  }
  for (const auto enc : {PlyEncoding::kBinaryLittleEndian, PlyEncoding::kAscii}) {
    write_ply(dir.file("real.ply"), in, enc);
    ReadStats stats;
    const Scan out = read_ply(dir.file("real.ply"), &stats);
    require_same(in, out);
    CHECK(stats.dropped() == 0);
    CHECK(semlio::label_histogram(out) == semlio::label_histogram(in));
  }
}

}  // namespace test_ply

namespace test_ply {

TEST_CASE("PLY binary reader rejects a vertex count lower than the records present", "[io]") {
  // Audit issue 13: the ascii reader rejected this lie; the binary one kept
  // the first vertices and dropped the rest silently.
  CloudTempDir dir("ply_lie");
  const std::string xyz2 = "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n";
  for (const std::string format : {"binary_little_endian", "binary_big_endian"}) {
    INFO(format);
    std::string bin = "ply\nformat " + format + " 1.0\n" + xyz2 + "end_header\n";
    for (int k = 0; k < 9; ++k) put<float>(bin, 1.0F + static_cast<float>(k));  // 3 vertices
    const std::string path = dir.write("lie.ply", bin);
    require_error<semlio::FormatError>([&] { (void)read_ply(path); }, path,
                                       ":3: header lies about its vertex count: 2 declared (12 bytes each) "
                                       "but 12 more bytes follow");
  }
  // A partial extra record is the same inconsistency.
  std::string bin = "ply\nformat binary_little_endian 1.0\n" + xyz2 + "end_header\n";
  for (int k = 0; k < 7; ++k) put<float>(bin, 1.0F);
  const std::string path = dir.write("partial.ply", bin);
  require_error<semlio::FormatError>([&] { (void)read_ply(path); }, path, "but 4 more bytes follow");
  // An element after the vertices keeps its bytes legitimately.
  std::string with_face = "ply\nformat binary_little_endian 1.0\n" + xyz2 +
                          "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  for (int k = 0; k < 6; ++k) put<float>(with_face, 1.0F);
  with_face += std::string("\x01\x00\x00\x00\x00", 5);
  CHECK(read_ply(dir.write("face.ply", with_face)).size() == 2);
}

}  // namespace test_ply
