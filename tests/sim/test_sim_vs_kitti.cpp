// Simulated urban sweeps against the real KITTI 00/000000 scan on simple
// statistics. Tolerances (documented in the simulator README section of the
// report): total points and median points per ring within 15%, fraction of
// points below z = -1.3 m within 0.12, mean intensity within 0.06, range
// histogram L1 distance (bins 0/5/10/20/30/40/60/80/120 m) below 0.45 on
// average over three frames.
#include <catch2/catch.hpp>

#include <cmath>

#include <semlio/io/kitti.hpp>
#include <semlio/sim/simulator.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/sim_scan_stats.hpp>

namespace test_sim_vs_kitti {  // one namespace per test file: the area compiles as one TU

TEST_CASE("simulated urban sweeps resemble a real KITTI sweep", "[sim]") {
  const semlio::Scan real = semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  const auto rs = semlio_test::scan_stats(real);
  REQUIRE(rs.points > 100000);
  semlio::sim::SimulatorConfig c;
  c.frames = 101;
  const semlio::sim::Simulator sim(c);
  double points = 0.0;
  double median_ring = 0.0;
  double ground = 0.0;
  double intensity = 0.0;
  double l1 = 0.0;
  const int n = 3;
  for (const std::size_t i : {0U, 50U, 100U}) {
    const auto s = semlio_test::scan_stats(sim.frame(i).scan);
    points += static_cast<double>(s.points) / n;
    median_ring += s.median_ring_count / n;
    ground += s.ground_fraction / n;
    intensity += s.mean_intensity / n;
    l1 += semlio_test::range_l1(s, rs) / n;
  }
  INFO("sim points " << points << " real " << rs.points << "; median/ring " << median_ring << " real "
                     << rs.median_ring_count << "; ground " << ground << " real " << rs.ground_fraction
                     << "; intensity " << intensity << " real " << rs.mean_intensity << "; range L1 " << l1);
  CHECK(std::abs(points / static_cast<double>(rs.points) - 1.0) < 0.15);
  CHECK(std::abs(median_ring / rs.median_ring_count - 1.0) < 0.15);
  CHECK(std::abs(ground - rs.ground_fraction) < 0.12);
  CHECK(std::abs(intensity - rs.mean_intensity) < 0.06);
  CHECK(l1 < 0.45);
  WARN("sim-vs-KITTI: points " << points << " vs " << rs.points << ", median/ring " << median_ring << " vs "
                               << rs.median_ring_count << ", ground " << ground << " vs " << rs.ground_fraction
                               << ", intensity " << intensity << " vs " << rs.mean_intensity << ", range L1 " << l1);
}

}  // namespace test_sim_vs_kitti
