// The README's library example ("Using semlio as a library"), compiled and
// run on the two real KITTI scans; test_docs.cpp checks that the README
// shows exactly the lines between the markers. Its main() is renamed here
// (the test executable has Catch2's).
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <semlio_test/data.hpp>

#define main readme_example_main
// [readme-example-begin]
#include <cstdio>
#include <semlio/semlio.hpp>

int main(int argc, char** argv) {
  using namespace semlio;
  // The paper's pipeline, with one policy swapped: the baseline's nearest-5
  // association instead of Algorithm 1 (normal consistency).
  Odometry odom(GeometricSegmenter{},                    // labels without a network
                NearestK{},                              // <- was NormalConsistency{}
                LoamResiduals{SemanticWeighted<PointToLine>{}, SemanticWeighted<PointToPlane>{}},
                SemanticAdaptive{},                      // semantic keyframes (eq. 14-22)
                OdometryConfig{.kitti_vertical_correction = true});
  for (int i = 1; i < argc; ++i) {                       // KITTI .bin scans, 10 Hz
    Scan scan = io::read_kitti_bin(argv[i]);
    scan.stamp_s = 0.1 * (i - 1);
    const FrameReport r = odom.process(scan);
    const auto t = r.T_map_lidar.translation();
    std::printf("%s %s %.3f %.3f %.3f%s\n", argv[i], to_string(r.status), t.x(), t.y(), t.z(),
                r.keyframe ? " keyframe" : "");
  }
  return 0;
}
// [readme-example-end]
#undef main

namespace test_readme_example {

TEST_CASE("README.md's library example tracks the two real KITTI scans", "[docs]") {
  std::string a = semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin");
  std::string b = semlio_test::data_path("kitti/sequences/00/velodyne/000001.bin");
  char prog[] = "readme_example";
  char* argv[] = {prog, a.data(), b.data(), nullptr};
  // Its output goes to stdout: send fd 1 to a file for the call.
  const std::string path = "semlio_readme_example_out.txt";
  std::fflush(stdout);
  const int saved = dup(1);
  REQUIRE(saved >= 0);
  std::FILE* f = std::fopen(path.c_str(), "w");
  REQUIRE(f != nullptr);
  dup2(fileno(f), 1);
  const int rc = readme_example_main(3, argv);
  std::fflush(stdout);
  dup2(saved, 1);
  close(saved);
  std::fclose(f);
  CHECK(rc == 0);
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string out = ss.str();
  INFO(out);
  // One line per scan: the first initialises the map (a keyframe), the second
  // is tracked about 0.69 m forward (tests/data README; test_odometry.cpp's bound).
  CHECK(out.find("000000.bin initialized 0.000 0.000 0.000 keyframe") != std::string::npos);
  const auto line2 = out.find("000001.bin ");
  REQUIRE(line2 != std::string::npos);
  std::istringstream second(out.substr(line2));
  std::string name, status;
  double x = 0.0, y = 0.0, z = 0.0;
  second >> name >> status >> x >> y >> z;
  CHECK((status == "tracked" || status == "degenerate"));
  CHECK(x == Approx(0.69).margin(0.08));
  CHECK(std::abs(y) < 0.1);
}

}  // namespace test_readme_example
