// PCD v0.7 reader/writer: round trips, field layouts, real KITTI raw scans and
// every malformed input the reader must reject.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <semlio/io/pcd.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_cloud_checks.hpp>
#include <semlio_test/io_cloud_files.hpp>

namespace test_pcd {  // one namespace per test file: the area compiles as one TU

namespace {

using semlio::Class;
using semlio::Scan;
using semlio::io::PcdEncoding;
using semlio::io::read_pcd;
using semlio::io::ReadStats;
using semlio::io::write_pcd;
using semlio_test::CloudTempDir;
using semlio_test::require_error;

/// Appends the host (little-endian) bytes of v.
template <typename T>
void put(std::string& out, T v) {
  char raw[sizeof(T)];
  std::memcpy(raw, &v, sizeof(T));
  out.append(raw, sizeof(T));
}

/// A small labelled scan with awkward float values.
Scan sample_scan() {
  Scan s;
  s.points = {{1.0F, 2.0F, 3.0F},
              {-0.1F, 1e-30F, 3.4e38F},
              {0.0F, 0.0F, -7.25F},
              {123.456F, -78.9F, std::numeric_limits<float>::denorm_min()},
              {-0.0F, 5.0F, 0.0F}};
  s.intensity = {0.0F, 0.25F, 1.0F, 0.1F, 255.0F};
  s.labels = {Class::kCar, Class::kRoad, Class::kUnlabeled, Class::kPerson, Class::kTrafficSign};
  s.instances = {7, 0, 0, 65535, 3};
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

std::string header(const std::string& fields, const std::string& size, const std::string& type,
                   const std::string& count, std::size_t n, const std::string& data) {
  const std::string ns = std::to_string(n);
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " + fields + "\nSIZE " +
         size + "\nTYPE " + type + "\nCOUNT " + count + "\nWIDTH " + ns +
         "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + ns + "\nDATA " + data + "\n";
}

}  // namespace

TEST_CASE("PCD binary and ascii writers round-trip bit-exactly", "[io]") {
  CloudTempDir dir("pcd_roundtrip");
  const Scan in = sample_scan();
  for (const auto enc : {PcdEncoding::kBinary, PcdEncoding::kAscii}) {
    const std::string path = dir.file(enc == PcdEncoding::kBinary ? "b.pcd" : "a.pcd");
    write_pcd(path, in, enc);
    ReadStats stats;
    const Scan out = read_pcd(path, &stats);
    require_same(in, out);
    CHECK(stats.dropped() == 0);
  }
  // The binary file is exactly header + 20 bytes per point (x y z i label).
  const std::string bytes = semlio_test::read_bytes(dir.file("b.pcd"));
  const std::size_t data = bytes.find("DATA binary\n") + std::strlen("DATA binary\n");
  CHECK(bytes.size() - data == in.size() * 20);
  // The label column holds the raw SemanticKITTI id with the instance on top:
  // car is raw 10, instance 7.
  std::uint32_t raw0 = 0;
  std::memcpy(&raw0, bytes.data() + data + 16, 4);
  CHECK(raw0 == (10U | (7U << 16)));
}

TEST_CASE("PCD writer omits absent fields and handles empty scans", "[io]") {
  CloudTempDir dir("pcd_fields");
  Scan xyz;
  xyz.points = {{1.0F, 2.0F, 3.0F}, {4.0F, 5.0F, 6.0F}};
  for (const auto enc : {PcdEncoding::kBinary, PcdEncoding::kAscii}) {
    const std::string path = dir.file("xyz.pcd");
    write_pcd(path, xyz, enc);
    CHECK(semlio_test::read_bytes(path).find("FIELDS x y z\n") != std::string::npos);
    const Scan out = read_pcd(path);
    require_same(xyz, out);
    CHECK_FALSE(out.has_intensity());
    CHECK_FALSE(out.has_labels());

    const std::string empty_path = dir.file("empty.pcd");
    write_pcd(empty_path, Scan{}, enc);
    CHECK(read_pcd(empty_path).empty());
  }
  Scan bad = xyz;
  bad.intensity = {1.0F};  // wrong length
  CHECK_THROWS_AS(write_pcd(dir.file("bad.pcd"), bad), semlio::ValueError);
  CHECK_THROWS_AS(write_pcd(dir.file("no_such_dir/x.pcd"), xyz), semlio::IoError);
}

TEST_CASE("PCD reader drops and counts NaN/Inf and (0,0,0) points", "[io]") {
  CloudTempDir dir("pcd_drop");
  Scan s;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  s.points = {{1, 1, 1}, {nan, 0, 0}, {0, 0, 0}, {2, 2, 2}, {0, -inf, 0}, {-0.0F, 0, 0}, {3, 0, 0}};
  s.intensity = {0.5F, 0.5F, 0.5F, nan, 0.5F, 0.5F, 0.5F};
  for (const auto enc : {PcdEncoding::kBinary, PcdEncoding::kAscii}) {
    const std::string path = dir.file("drop.pcd");
    write_pcd(path, s, enc);
    ReadStats stats;
    stats.dropped_zero = 10;  // readers add to the counters, never reset them
    const Scan out = read_pcd(path, &stats);
    REQUIRE(out.size() == 2);
    CHECK(out.points[0].x() == 1.0F);
    CHECK(out.points[1].x() == 3.0F);
    CHECK(stats.dropped_nonfinite == 3);  // NaN x, NaN intensity, -Inf y
    CHECK(stats.dropped_zero == 10 + 2);  // (0,0,0) and (-0,0,0)
  }
}

TEST_CASE("PCD ascii text beyond float range saturates instead of failing", "[io]") {
  CloudTempDir dir("pcd_range");
  const std::string h = header("x y z", "4 4 4", "F F F", "1 1 1", 3, "ascii");
  ReadStats stats;
  const Scan s = read_pcd(dir.write("range.pcd", h + "1e39 0 0\n1e-50 2 3\n-1e39 1 1\n"), &stats);
  REQUIRE(s.size() == 1);
  CHECK(s.points[0] == Eigen::Vector3f(0.0F, 2.0F, 3.0F));  // underflow -> 0
  CHECK(stats.dropped_nonfinite == 2);                      // overflow -> +-inf, dropped
}

TEST_CASE("PCD reader handles any field order, extra fields and types", "[io]") {
  CloudTempDir dir("pcd_layout");
  // rgb (U4, skipped), x (F8), label (U4), _ (3 x I2 padding, skipped),
  // y (I2), intensity (U1), z (F4), normal (F4 x 3, skipped).
  const std::string h = header("rgb x label _ y intensity z normal", "4 8 4 2 2 1 4 4",
                               "U F U I I U F F", "1 1 1 3 1 1 1 3", 2, "binary");
  std::string bin = h;
  for (int k = 0; k < 2; ++k) {
    put<std::uint32_t>(bin, 0xFFAA5500U);
    put<double>(bin, k == 0 ? 1.5 : -2.25);
    put<std::uint32_t>(bin, k == 0 ? (252U | (9U << 16)) : 40U);  // moving-car #9, road
    for (int j = 0; j < 3; ++j) put<std::int16_t>(bin, -1);
    put<std::int16_t>(bin, static_cast<std::int16_t>(k == 0 ? -300 : 7));
    put<std::uint8_t>(bin, static_cast<std::uint8_t>(k == 0 ? 200 : 3));
    put<float>(bin, k == 0 ? 0.5F : 9.0F);
    for (int j = 0; j < 3; ++j) put<float>(bin, 1.0F);
  }
  const Scan b = read_pcd(dir.write("layout_b.pcd", bin));

  std::string txt = header("rgb x label _ y intensity z normal", "4 8 4 2 2 1 4 4",
                           "U F U I I U F F", "1 1 1 3 1 1 1 3", 2, "ascii");
  txt += "4289352960 1.5 590076 -1 -1 -1 -300 200 0.5 1 1 1\r\n";  // CRLF tolerated
  txt += " \t\n";                                                  // blank line tolerated
  txt += "4289352960 -2.25 40 -1 -1 -1 7 3 9 1 1 1\n";
  const Scan a = read_pcd(dir.write("layout_a.pcd", txt));

  for (const Scan* s : {&b, &a}) {
    REQUIRE(s->size() == 2);
    CHECK(s->points[0] == Eigen::Vector3f(1.5F, -300.0F, 0.5F));
    CHECK(s->points[1] == Eigen::Vector3f(-2.25F, 7.0F, 9.0F));
    CHECK(s->intensity == std::vector<float>{200.0F, 3.0F});
    CHECK(s->labels == std::vector<Class>{Class::kCar, Class::kRoad});  // 252 -> car
    CHECK(s->instances == std::vector<std::uint16_t>{9, 0});
  }
}

TEST_CASE("PCD carries ring and per-point time (Velodyne/LIO-SAM layout)", "[io]") {
  CloudTempDir dir("pcd_ring");
  Scan in = sample_scan();
  in.rings = {0, 63, 7, 65535, 1};
  in.times_s = {0.0F, 0.0999F, 0.05F, 1e-7F, 0.1F};
  for (const auto enc : {PcdEncoding::kBinary, PcdEncoding::kAscii}) {
    const std::string path = dir.file("ring.pcd");
    write_pcd(path, in, enc);
    CHECK(semlio_test::read_bytes(path).find("FIELDS x y z intensity label ring time\n") !=
          std::string::npos);
    require_same(in, read_pcd(path));
  }
  // The layout LIO-SAM's Velodyne driver writes: x y z, 4 padding bytes,
  // intensity, ring (U2), 2 padding bytes, time (F4); a NaN time drops the point.
  std::string bin = header("x y z _ intensity ring _ time", "4 4 4 1 4 2 1 4", "F F F U F U U F",
                           "1 1 1 4 1 1 2 1", 2, "binary");
  for (int k = 0; k < 2; ++k) {
    put<float>(bin, 1.0F);
    put<float>(bin, 2.0F);
    put<float>(bin, 3.0F);
    put<std::uint32_t>(bin, 0);
    put<float>(bin, 40.0F);
    put<std::uint16_t>(bin, 31);
    put<std::uint16_t>(bin, 0);
    put<float>(bin, k == 0 ? 0.025F : std::numeric_limits<float>::quiet_NaN());
  }
  ReadStats stats;
  const Scan s = read_pcd(dir.write("liosam.pcd", bin), &stats);
  REQUIRE(s.size() == 1);
  CHECK(s.rings == std::vector<std::uint16_t>{31});
  CHECK(s.times_s == std::vector<float>{0.025F});
  CHECK(s.intensity == std::vector<float>{40.0F});
  CHECK(stats.dropped_nonfinite == 1);
}

TEST_CASE("PCD reader tolerates trailing padding after the binary payload", "[io]") {
  CloudTempDir dir("pcd_padding");
  const std::string path = dir.file("pad.pcd");
  const Scan in = sample_scan();
  write_pcd(path, in, PcdEncoding::kBinary);
  const std::string padded = semlio_test::read_bytes(path) + std::string(3906, '\0');
  require_same(in, read_pcd(dir.write("padded.pcd", padded)));
}

TEST_CASE("PCD reader rejects bad input with typed errors naming the path", "[io]") {
  CloudTempDir dir("pcd_bad");
  const auto pcd_error = [&](const std::string& name, const std::string& bytes,
                             const std::string& fragment) {
    const std::string path = dir.write(name, bytes);
    INFO(name);
    require_error<semlio::FormatError>([&] { (void)read_pcd(path); }, path, fragment);
  };
  const std::string xyz_bin = header("x y z", "4 4 4", "F F F", "1 1 1", 3, "binary");
  std::string three_points = xyz_bin;
  for (int k = 0; k < 9; ++k) put<float>(three_points, 1.0F + static_cast<float>(k));

  SECTION("missing file and directory") {
    const std::string missing = dir.file("missing.pcd");
    require_error<semlio::IoError>([&] { (void)read_pcd(missing); }, missing, "does not exist");
    const std::string d = dir.file("");
    CHECK_THROWS_AS(read_pcd(d), semlio::IoError);
  }
  SECTION("empty file") { pcd_error("empty.pcd", "", "empty file"); }
  SECTION("truncated binary payload") {
    pcd_error("trunc.pcd", three_points.substr(0, three_points.size() - 5),
              "POINTS 3 (12 bytes each) but only 31 bytes");
  }
  SECTION("POINTS larger than the data") {
    std::string lie = three_points;
    lie.replace(lie.find("WIDTH 3"), 7, "WIDTH 9");
    lie.replace(lie.find("POINTS 3"), 8, "POINTS 9");
    pcd_error("lie.pcd", lie, "POINTS 9 (12 bytes each) but only 36 bytes");
  }
  SECTION("POINTS disagrees with WIDTH * HEIGHT") {
    std::string lie = three_points;
    lie.replace(lie.find("POINTS 3"), 8, "POINTS 2");
    pcd_error("wh.pcd", lie, "POINTS 2 but WIDTH 3 * HEIGHT 1 = 3");
  }
  SECTION("ascii with fewer or more lines than POINTS") {
    const std::string h = header("x y z", "4 4 4", "F F F", "1 1 1", 2, "ascii");
    pcd_error("few.pcd", h + "1 2 3\n", "POINTS 2 but only 1 data lines");
    pcd_error("many.pcd", h + "1 2 3\n4 5 6\n7 8 9\n", ":14: header lies about its point count");
  }
  SECTION("unsupported encodings and versions") {
    pcd_error("comp.pcd", header("x y z", "4 4 4", "F F F", "1 1 1", 0, "binary_compressed"),
              "binary_compressed is unsupported");
    pcd_error("enc.pcd", header("x y z", "4 4 4", "F F F", "1 1 1", 0, "base64"),
              ":11: unknown DATA encoding 'base64'");
    std::string v = xyz_bin;
    v.replace(v.find("VERSION 0.7"), 11, "VERSION 9.1");
    pcd_error("ver.pcd", v, ":2: unsupported PCD VERSION '9.1'");
  }
  SECTION("bad header lines") {
    pcd_error("key.pcd", "VERSION 0.7\nFIELDS x y z\nCOLOUR blue\n",
              ":3: unknown PCD header key 'COLOUR'");
    pcd_error("nodata.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n", "no DATA line");
    pcd_error("size.pcd", header("x y z", "4 4", "F F F", "1 1 1", 0, "ascii"),
              ":4: SIZE has 2 values but FIELDS (line 3) has 3");
    pcd_error("type.pcd", header("x y z", "4 4 4", "F Q F", "1 1 1", 0, "ascii"),
              ":5: TYPE of field 'y' is 'Q'");
    pcd_error("fsize.pcd", header("x y z", "4 3 4", "F F F", "1 1 1", 0, "ascii"),
              "field 'y' has SIZE 3");
    pcd_error("count.pcd", header("x y z", "4 4 4", "F F F", "1 2 1", 0, "ascii"),
              "field 'y' has COUNT 2");
    pcd_error("noz.pcd", header("x y intensity", "4 4 4", "F F F", "1 1 1", 0, "ascii"),
              "lacks one of x, y, z");
    pcd_error("flabel.pcd", header("x y z label", "4 4 4 4", "F F F F", "1 1 1 1", 0, "ascii"),
              "'label' has TYPE F");
    pcd_error("fring.pcd", header("x y z ring", "4 4 4 4", "F F F F", "1 1 1 1", 0, "ascii"),
              "'ring' has TYPE F");
    pcd_error("twice.pcd", header("x y z X", "4 4 4 4", "F F F F", "1 1 1 1", 0, "ascii"),
              "field 'X' is declared twice");
    std::string w = xyz_bin;
    w.replace(w.find("WIDTH 3"), 7, "WIDTH x3");
    pcd_error("width.pcd", w, ":7: WIDTH value 'x3'");
    std::string vp = xyz_bin;
    vp.replace(vp.find("VIEWPOINT 0 0 0 1 0 0 0"), 23, "VIEWPOINT 0 0 0 1");
    pcd_error("vp.pcd", vp, ":9: VIEWPOINT expects 7 value(s), got 4");
  }
  SECTION("bad ascii values") {
    const std::string h = header("x y z label", "4 4 4 2", "F F F U", "1 1 1 1", 1, "ascii");
    pcd_error("num.pcd", h + "1 2 abc 3\n", ":12: field 'z' value 'abc'");
    pcd_error("range.pcd", h + "1 2 3 70000\n", "field 'label' value '70000'");
    pcd_error("tokens.pcd", h + "1 2 3\n", ":12: expected 4 values, got 3");
  }
}

namespace {

/// What the test itself reads from a real KITTI raw PCD, independently of the
/// reader: header length, POINTS, the float32 records and the padding.
struct RawPcd {
  std::size_t header_bytes = 0;
  std::size_t points = 0;
  std::vector<float> values;  // x y z intensity per point
  std::string padding;
};

RawPcd raw_pcd(const std::string& path) {
  const std::string bytes = semlio_test::read_bytes(path);
  RawPcd r;
  const std::string marker = "\nDATA binary\n";
  const std::size_t at = bytes.find(marker);
  REQUIRE(at != std::string::npos);
  r.header_bytes = at + marker.size();
  std::istringstream header(bytes.substr(0, r.header_bytes));
  std::string line;
  while (std::getline(header, line)) {
    if (line.rfind("FIELDS", 0) == 0) REQUIRE(line == "FIELDS x y z intensity");
    if (line.rfind("SIZE", 0) == 0) REQUIRE(line == "SIZE 4 4 4 4");
    if (line.rfind("POINTS ", 0) == 0) r.points = std::stoul(line.substr(7));
  }
  REQUIRE(bytes.size() >= r.header_bytes + 16 * r.points);
  r.values.resize(4 * r.points);
  std::memcpy(r.values.data(), bytes.data() + r.header_bytes, 16 * r.points);
  r.padding = bytes.substr(r.header_bytes + 16 * r.points);
  return r;
}

}  // namespace

TEST_CASE("PCD reader on three real KITTI raw scans", "[io]") {
  ReadStats total;
  for (const char* name : {"0000000000.pcd", "0000000001.pcd", "0000000002.pcd"}) {
    const std::string path = semlio_test::data_path(std::string("kitti_raw/snippet_22/") + name);
    INFO(path);
    const RawPcd raw = raw_pcd(path);
    // README: about 98k-124k points, ~3906 trailing zero bytes, one (0,0,0).
    CHECK(raw.points > 90000);
    CHECK(raw.points < 130000);
    CHECK(raw.padding.size() == 3906);
    CHECK(raw.padding.find_first_not_of('\0') == std::string::npos);
    std::size_t zeros = 0, nonfinite = 0;
    for (std::size_t i = 0; i < raw.points; ++i) {
      const float* v = &raw.values[4 * i];
      if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]) ||
          !std::isfinite(v[3])) {
        ++nonfinite;
      } else if (v[0] == 0.0F && v[1] == 0.0F && v[2] == 0.0F) {
        ++zeros;
      }
    }
    CHECK(zeros == 1);

    ReadStats stats;
    const Scan scan = read_pcd(path, &stats);
    REQUIRE(scan.size() == raw.points - zeros - nonfinite);
    CHECK(stats.dropped_zero == 1);
    CHECK(stats.dropped_nonfinite == nonfinite);
    REQUIRE(scan.intensity.size() == scan.size());
    CHECK_FALSE(scan.has_labels());
    // The first kept point is the file's first non-zero record, bit for bit.
    std::size_t first = 0;
    while (raw.values[4 * first] == 0.0F && raw.values[4 * first + 1] == 0.0F &&
           raw.values[4 * first + 2] == 0.0F) {
      ++first;
    }
    CHECK(scan.points[0].x() == raw.values[4 * first]);
    CHECK(scan.intensity[0] == raw.values[4 * first + 3]);
    // KITTI raw reflectance is in [0, 1]; HDL-64E range is below ~130 m.
    float lo = 1e9F, hi = -1e9F, far = 0.0F;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      lo = std::min(lo, scan.intensity[i]);
      hi = std::max(hi, scan.intensity[i]);
      far = std::max(far, scan.points[i].norm());
    }
    CHECK(lo >= 0.0F);
    CHECK(hi <= 1.0F);
    CHECK(hi > 0.5F);  // not all dark
    CHECK(far < 130.0F);
    (void)read_pcd(path, &total);
  }
  CHECK(total.dropped_zero == 3);  // counters accumulate over files
}

TEST_CASE("PCD writers round-trip a real KITTI raw scan", "[io]") {
  CloudTempDir dir("pcd_real");
  const Scan in = read_pcd(semlio_test::data_path("kitti_raw/snippet_22/0000000000.pcd"));
  for (const auto enc : {PcdEncoding::kBinary, PcdEncoding::kAscii}) {
    const std::string path = dir.file("real.pcd");
    write_pcd(path, in, enc);
    require_same(in, read_pcd(path));
  }
}

}  // namespace test_pcd

namespace test_pcd {

TEST_CASE("PCD reader rejects a COUNT whose sums overflow, in both encodings", "[io]") {
  // Audit issue 1: a 20-digit COUNT wrapped SIZE*COUNT and the token sum, so
  // later fields were read from outside the record (SIGSEGV or garbage).
  CloudTempDir dir("pcd_count");
  const auto pcd_error = [&](const std::string& name, const std::string& bytes,
                             const std::string& fragment) {
    const std::string path = dir.write(name, bytes);
    INFO(name);
    require_error<semlio::FormatError>([&] { (void)read_pcd(path); }, path, fragment);
  };
  SECTION("ascii: the token sum wraps to the 2 tokens present") {
    // 3 + (2^64 - 1) tokens wraps to 2, so "1 2" used to pass the count check
    // and z was read from token index 2 of a 2-token line.
    const std::string h = header("x y z pad", "4 4 4 4", "F F F F", "1 1 1 18446744073709551615", 1, "ascii");
    pcd_error("ascii_wrap.pcd", h + "1 2\n", ":6: COUNT of field 'pad' is 18446744073709551615");
  }
  SECTION("binary: SIZE*COUNT wraps so x sits before the record") {
    // 4 * (2^62 - 1) = 2^64 - 4: x's offset wrapped to -4 and the record to 8 bytes.
    std::string b = header("pad x y z", "4 4 4 4", "U F F F", "4611686018427387903 1 1 1", 1, "binary");
    put<float>(b, 1.0F);
    put<float>(b, 2.0F);
    pcd_error("binary_wrap.pcd", b, ":6: COUNT of field 'pad' is 4611686018427387903");
  }
  SECTION("a COUNT above the file size is refused even without a wrap") {
    const std::string h = header("x y z pad", "4 4 4 8", "F F F F", "1 1 1 100000", 0, "binary");
    pcd_error("big_count.pcd", h, "more values per point than the file has bytes");
  }
  SECTION("a large but honest COUNT of a skipped field still reads") {
    std::string b = header("x y z pad", "4 4 4 1", "F F F U", "1 1 1 40", 1, "binary");
    put<float>(b, 1.0F);
    put<float>(b, 2.0F);
    put<float>(b, 3.0F);
    b += std::string(40, '\x7f');
    const Scan s = read_pcd(dir.write("honest.pcd", b));
    REQUIRE(s.size() == 1);
    CHECK(s.points[0].z() == 3.0F);
  }
}

TEST_CASE("PCD reader refuses non-regular files instead of reading them", "[io]") {
  // Audit issue 3: a device or FIFO must cost an IoError, not a hang or an
  // unbounded read.
  require_error<semlio::IoError>([] { (void)read_pcd("/dev/zero"); }, "/dev/zero", "not a regular file");
}

}  // namespace test_pcd
