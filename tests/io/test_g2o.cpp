#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <limits>
#include <unistd.h>
#include <string>

#include <semlio/graph/pose_graph.hpp>
#include <semlio/io/g2o.hpp>
#include <semlio/io/g2o_graph.hpp>
#include <semlio_test/data.hpp>

namespace test_g2o {  // one namespace per test file: the area compiles as one TU

namespace fs = std::filesystem;
using semlio::io::G2oGraph;
using semlio::io::read_g2o;

namespace {

// A scratch file under the system temp directory, removed on destruction.
struct TempFile {
  fs::path path;
  explicit TempFile(const std::string& name, const std::string& content = "") {
    path = fs::temp_directory_path() / ("semlio_test_g2o_" + std::to_string(::getpid()) + "_" + name);
    if (!content.empty()) std::ofstream(path) << content;
  }
  ~TempFile() {
    std::error_code ec;
    fs::remove(path, ec);
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
};

const std::string kVertices3 =
    "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n"
    "VERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n";
// Upper triangle of the 6x6 identity.
const std::string kIdentity6 = "1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1";

std::string format_error_of(const std::string& content, bool strict = false) {
  TempFile f("bad.g2o", content);
  try {
    read_g2o(f.path.string(), {.strict = strict});
  } catch (const semlio::FormatError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("g2o: reads the real tinyGrid3D and M3500 files", "[io]") {
  const G2oGraph tiny = read_g2o(semlio_test::data_path("posegraphs/tinyGrid3D.g2o"));
  CHECK(tiny.dimension == 3);
  CHECK(tiny.vertices3.size() == 9);
  CHECK(tiny.edges3.size() == 11);
  CHECK(tiny.repaired_information == 0);
  // The first edge of the file: 0 -> 1, information diag(100, 100, 100, 25, 25, 25).
  CHECK(tiny.edges3[0].from == 0);
  CHECK(tiny.edges3[0].to == 1);
  CHECK(tiny.edges3[0].measured.translation().x() == Approx(1.033099));
  CHECK(tiny.edges3[0].information(0, 0) == 100.0);
  CHECK(tiny.edges3[0].information(5, 5) == 25.0);
  CHECK(tiny.edges3[0].information(0, 5) == 0.0);
  const G2oGraph m3500 = read_g2o(semlio_test::data_path("posegraphs/M3500.g2o"));
  CHECK(m3500.dimension == 2);
  CHECK(m3500.vertices2.size() == 3500);
  CHECK(m3500.edges2.size() == 5453);
  CHECK(m3500.vertices2[1].pose.translation().x() == Approx(1.030390));
  CHECK(m3500.vertices2[1].pose.theta() == Approx(-0.012958));
}

TEST_CASE("g2o: write then read round-trips every number", "[io]") {
  for (const char* name : {"posegraphs/smallGrid3D.g2o", "posegraphs/M3500.g2o"}) {
    const G2oGraph a = read_g2o(semlio_test::data_path(name));
    TempFile f("roundtrip.g2o");
    semlio::io::write_g2o(f.path.string(), a);
    const G2oGraph b = read_g2o(f.path.string());
    REQUIRE(a.dimension == b.dimension);
    REQUIRE(a.vertices3.size() == b.vertices3.size());
    REQUIRE(a.edges3.size() == b.edges3.size());
    REQUIRE(a.vertices2.size() == b.vertices2.size());
    REQUIRE(a.edges2.size() == b.edges2.size());
    for (std::size_t k = 0; k < a.vertices3.size(); ++k) {
      // Quaternions are re-normalised on reading: equal to the last bits.
      CHECK((a.vertices3[k].pose.matrix() - b.vertices3[k].pose.matrix()).cwiseAbs().maxCoeff() < 1e-15);
    }
    for (std::size_t k = 0; k < a.edges3.size(); ++k) {
      CHECK(a.edges3[k].information == b.edges3[k].information);
      CHECK(a.edges3[k].measured.translation() == b.edges3[k].measured.translation());
    }
    for (std::size_t k = 0; k < a.edges2.size(); ++k) {
      CHECK(a.edges2[k].measured.theta() == b.edges2[k].measured.theta());
      CHECK(a.edges2[k].information == b.edges2[k].information);
    }
  }
}

TEST_CASE("g2o: an indefinite information matrix is projected to PSD and counted", "[io]") {
  // diag(4, -1, 2, 1, 1, 1): nearest PSD matrix is diag(4, 0, 2, 1, 1, 1).
  const std::string edge = "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 4 0 0 0 0 0 -1 0 0 0 0 2 0 0 0 1 0 0 1 0 1\n";
  TempFile f("indefinite.g2o", kVertices3 + edge);
  const G2oGraph g = read_g2o(f.path.string());
  CHECK(g.repaired_information == 1);
  Eigen::Matrix<double, 6, 1> expected;
  expected << 4, 0, 2, 1, 1, 1;
  CHECK((g.edges3[0].information - Eigen::Matrix<double, 6, 6>(expected.asDiagonal())).norm() < 1e-12);
  // Strict: FormatError with path, line and the smallest eigenvalue.
  const std::string msg = format_error_of(kVertices3 + edge, true);
  CHECK(msg.find("bad.g2o:3:") != std::string::npos);
  CHECK(msg.find("smallest eigenvalue -1") != std::string::npos);
}

TEST_CASE("g2o: a coupled indefinite matrix is projected to the nearest PSD matrix", "[io]") {
  // [[1, 2], [2, 1]] in the (x, y) block has eigenvalues 3 and -1 with
  // eigenvectors (1, 1)/sqrt2, (1, -1)/sqrt2: projection = 1.5 [[1, 1], [1, 1]].
  const std::string edge = "EDGE_SE2 0 1 1 0 0 1 2 0 1 0 1\n";
  TempFile f("coupled.g2o", "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n" + edge);
  const G2oGraph g = read_g2o(f.path.string());
  CHECK(g.repaired_information == 1);
  Eigen::Matrix3d expected;
  expected << 1.5, 1.5, 0, 1.5, 1.5, 0, 0, 0, 1;
  CHECK((g.edges2[0].information - expected).norm() < 1e-12);
  CHECK(g.edges2[0].information.selfadjointView<Eigen::Lower>().eigenvalues().minCoeff() > -1e-12);
}

TEST_CASE("g2o: a NaN information entry is repaired (set to 0) or rejected in strict mode", "[io]") {
  const std::string edge = "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 nan 0 0 0 1 0 0 1 0 1\n";
  TempFile f("nan.g2o", kVertices3 + edge);
  const G2oGraph g = read_g2o(f.path.string());
  CHECK(g.repaired_information == 1);
  CHECK(g.edges3[0].information.allFinite());
  CHECK(g.edges3[0].information(2, 2) == Approx(0.0).margin(1e-12));
  CHECK(g.edges3[0].information(0, 0) == Approx(1.0));
  const std::string msg = format_error_of(kVertices3 + edge, true);
  CHECK(msg.find("bad.g2o:3:") != std::string::npos);
  CHECK(msg.find("non-finite") != std::string::npos);
}

TEST_CASE("g2o: a repaired graph still solves, with the repair visible in the count", "[io]") {
  // Edge 0-1 has an indefinite rotation block; a second, good edge keeps the system regular.
  const std::string content = kVertices3 +
                              "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 -3 0 0 1 0 1\n"
                              "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 " +
                              kIdentity6 + "\n";
  TempFile f("repaired.g2o", content);
  const G2oGraph g = read_g2o(f.path.string());
  CHECK(g.repaired_information == 1);
  semlio::PoseGraph3d graph = semlio::io::make_pose_graph3(g);
  const semlio::GraphSolveReport r = graph.optimize();
  CHECK(r.status == semlio::GraphSolveStatus::converged);
  CHECK(r.final_chi2 < 1e-16);
}

TEST_CASE("g2o: malformed lines throw FormatError naming path and line", "[io]") {
  CHECK(format_error_of("VERTEX_SE3:QUAT 0 0 0 0 0 0 0\n").find("bad.g2o:1:") != std::string::npos);
  CHECK(format_error_of(kVertices3 + "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 1 0\n").find("bad.g2o:3:") != std::string::npos);
  CHECK(format_error_of("VERTEX_SE2 0 0 zero 0\n").find("not a number: 'zero'") != std::string::npos);
  CHECK(format_error_of("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 0 1 0 0\n").find("bad.g2o:2: duplicate vertex id 0") !=
        std::string::npos);
  CHECK(format_error_of("VERTEX_SE2 0 0 0 0\nVERTEX_SE3:QUAT 1 0 0 0 0 0 0 1\n").find("mixes 2D and 3D") !=
        std::string::npos);
  CHECK(
      format_error_of("VERTEX_SE2 0 0 0 0\nEDGE_SE2 0 5 1 0 0 1 0 0 1 0 1\n").find("bad.g2o:2: unknown vertex id 5") !=
      std::string::npos);
  CHECK(format_error_of("VERTEX_SE3:QUAT 0 0 0 0 0 0 0 2\n").find("quaternion norm") != std::string::npos);
  CHECK(format_error_of("VERTEX_SE2 0 0 nan 0\n").find("non-finite") != std::string::npos);
  CHECK_THROWS_AS(read_g2o("/nonexistent/semlio/graph.g2o"), semlio::IoError);
}

TEST_CASE("g2o: FIX lines choose the gauge, other tags are skipped and counted", "[io]") {
  const std::string content =
      "# comment\n"
      "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0\n"
      "FIX 2\nPARAMS_SOMETHING 1 2 3\n"
      "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2 1 2 1 0 0 1 0 0 1 0 1\n";
  TempFile f("fix.g2o", content);
  const G2oGraph g = read_g2o(f.path.string());
  CHECK(g.fixed == std::vector<long>{2});
  CHECK(g.skipped_lines == 1);
  semlio::PoseGraph2d graph = semlio::io::make_pose_graph2(g);
  CHECK_FALSE(graph.is_fixed(0));
  CHECK(graph.is_fixed(2));
  REQUIRE(graph.optimize().status == semlio::GraphSolveStatus::converged);
  CHECK(graph.pose(2).translation().x() == 2.0);  // held
  CHECK(graph.pose(0).translation().x() == Approx(0.0).margin(1e-9));
  // The solution written back and re-read keeps the FIX line.
  G2oGraph out = g;
  semlio::io::store_poses(graph, out);
  TempFile f2("fix_out.g2o");
  semlio::io::write_g2o(f2.path.string(), out);
  CHECK(read_g2o(f2.path.string()).fixed == std::vector<long>{2});
}

}  // namespace test_g2o
