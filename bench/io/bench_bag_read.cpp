// Reading + decoding the real KITTI scans from a ROS 1 bag (lz4 chunks,
// tests/data/bags/kitti3_lz4.bag): the must-hold is >= 10x the odometry frame
// rate on one core; scripts/read_speed.sh measures both on the same core and
// prints the ratio. Run: taskset -c 1 build/bench/bench_bag_read
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include <semlio/core/scan.hpp>
#include <semlio/io/bag/rosbag1.hpp>
#include <semlio/io/pointcloud2.hpp>
#include <semlio/io/ros1_msgs.hpp>
#include <semlio_test/data.hpp>

namespace {

const std::string& bag_path() {
  static const std::string path = semlio_test::data_path("bags/kitti3_lz4.bag");
  return path;
}

/// The whole path per scan: next() (chunk read + LZ4 decompression + copy),
/// ROS 1 deserialisation, PointCloud2 -> Scan (arg 0: through a
/// PointCloud2Msg, as MCAP/CDR readers do; arg 1: ros1_pointcloud2_to_scan,
/// straight from the message bytes). The reader restarts with select(), and
/// its two-chunk cache never holds the next scan's chunk (three chunks in
/// turn), so every scan is decompressed.
void BM_Ros1BagReadDecode(benchmark::State& state) {
  semlio::io::RosBag1Reader reader(bag_path());
  semlio::io::BagMessage msg;
  semlio::io::PointCloud2Msg cloud;
  semlio::Scan scan;
  std::size_t points = 0;
  std::int64_t scans = 0;
  const bool direct = state.range(0) != 0;
  for (auto _ : state) {
    reader.select({"/kitti/velo/pointcloud"});
    while (reader.next(msg)) {
      if (direct) {
        semlio::io::ros1_pointcloud2_to_scan(msg.data.data(), msg.data.size(), scan);
      } else {
        semlio::io::parse_ros1_pointcloud2(msg.data.data(), msg.data.size(), cloud);
        semlio::io::pointcloud2_to_scan(cloud, scan);
      }
      points += scan.size();
      ++scans;
    }
    benchmark::DoNotOptimize(scan.points.data());
  }
  state.SetItemsProcessed(scans);  // items/s = scans/s
  state.counters["points_per_scan"] = benchmark::Counter(static_cast<double>(points) / static_cast<double>(scans));
}
BENCHMARK(BM_Ros1BagReadDecode)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

/// next() alone: chunk read + LZ4 decompression + copy of the message bytes.
void BM_Ros1BagNext(benchmark::State& state) {
  semlio::io::RosBag1Reader reader(bag_path());
  semlio::io::BagMessage msg;
  std::int64_t scans = 0;
  for (auto _ : state) {
    reader.select({"/kitti/velo/pointcloud"});
    while (reader.next(msg)) {
      benchmark::DoNotOptimize(msg.data.data());
      ++scans;
    }
  }
  state.SetItemsProcessed(scans);
}
BENCHMARK(BM_Ros1BagNext)->Unit(benchmark::kMillisecond);

/// PointCloud2 -> Scan alone, on the three deserialised scans.
void BM_PointCloud2ToScan(benchmark::State& state) {
  semlio::io::RosBag1Reader reader(bag_path());
  reader.select({"/kitti/velo/pointcloud"});
  std::vector<semlio::io::PointCloud2Msg> clouds;
  semlio::io::BagMessage msg;
  while (reader.next(msg)) clouds.push_back(semlio::io::parse_ros1_pointcloud2(msg.data));
  semlio::Scan scan;
  std::int64_t scans = 0;
  for (auto _ : state) {
    for (const auto& c : clouds) {
      semlio::io::pointcloud2_to_scan(c, scan);
      benchmark::DoNotOptimize(scan.points.data());
      ++scans;
    }
  }
  state.SetItemsProcessed(scans);
}
BENCHMARK(BM_PointCloud2ToScan)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
