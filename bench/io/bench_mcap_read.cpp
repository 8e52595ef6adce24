// Reading + decoding the real KITTI scans from an MCAP file (zstd chunks,
// CDR messages; tests/data/bags/kitti3_zstd.mcap): the must-hold is >= 10x
// the odometry frame rate on one core (scripts/read_speed.sh measures both on
// the same core and prints the ratio). Run: taskset -c 1 build/bench/bench_mcap_read
// Where it stands (2-core AMD EPYC VM, Debian libzstd 1.5.4): libzstd alone
// decodes one 1.93 MB KITTI chunk at 600-700 MB/s (`zstd -b -d` on the
// extracted frame), 2.8-3.2 ms per scan: 10x the full preset's frame rate,
// not the baseline's (about 22 ms a frame there, scripts/read_speed.sh),
// whatever the reader does. perf of crc:1 after
// the PCLMUL CRC: libzstd 64 %, PointCloud2 -> Scan 18 %, CRC-32 5 %,
// file read + message copies ~10 %.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <semlio/core/scan.hpp>
#include <semlio/io/bag/mcap.hpp>
#include <semlio/io/cdr_msgs.hpp>
#include <semlio/io/pointcloud2.hpp>
#include <semlio_test/data.hpp>

namespace {

const std::string& mcap_path() {
  static const std::string path = semlio_test::data_path("bags/kitti3_zstd.mcap");
  return path;
}

/// The three KITTI scans of kitti3_zstd.mcap as an MCAP file without chunks
/// (Messages directly in the data section, no summary), written once to the
/// temp dir: the reader's cost without decompression and CRC, for comparison.
const std::string& plain_mcap_path() {
  static const std::string path = [] {
    std::vector<semlio::io::BagMessage> scans;
    semlio::io::McapReader reader(mcap_path());
    reader.select({"/kitti/velo/pointcloud"});
    semlio::io::BagMessage m;
    while (reader.next(m)) scans.push_back(m);
    const std::string out = (std::filesystem::temp_directory_path() / "semlio_bench_kitti3_plain.mcap").string();
    std::ofstream f(out, std::ios::binary | std::ios::trunc);
    const auto bytes = [&](const void* p, std::size_t n) { f.write(static_cast<const char*>(p), static_cast<std::streamsize>(n)); };
    const auto u16 = [&](std::uint16_t v) { bytes(&v, 2); };
    const auto u32 = [&](std::uint32_t v) { bytes(&v, 4); };
    const auto u64 = [&](std::uint64_t v) { bytes(&v, 8); };
    const auto str = [&](const std::string& s) {
      u32(static_cast<std::uint32_t>(s.size()));
      bytes(s.data(), s.size());
    };
    const auto record = [&](std::uint8_t op, std::uint64_t len) {
      bytes(&op, 1);
      u64(len);
    };
    const unsigned char magic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
    const std::string type = "sensor_msgs/msg/PointCloud2";
    const std::string topic = "/kitti/velo/pointcloud";
    bytes(magic, 8);
    record(0x01, 4 + 4 + 4);  // Header: profile "ros2", library ""
    str("ros2");
    str("");
    record(0x03, 2 + 4 + type.size() + 4 + 7 + 4);  // Schema 1, encoding ros2msg, empty data
    u16(1);
    str(type);
    str("ros2msg");
    u32(0);
    record(0x04, 2 + 2 + 4 + topic.size() + 4 + 3 + 4);  // Channel 1, encoding cdr, no metadata
    u16(1);
    u16(1);
    str(topic);
    str("cdr");
    u32(0);
    std::uint32_t seq = 0;
    for (const semlio::io::BagMessage& s : scans) {
      record(0x05, 2 + 4 + 8 + 8 + s.data.size());
      u16(1);
      u32(seq++);
      u64(static_cast<std::uint64_t>(s.log_time_ns));
      u64(static_cast<std::uint64_t>(s.log_time_ns));
      bytes(s.data.data(), s.data.size());
    }
    record(0x0F, 4);  // DataEnd, CRC not computed
    u32(0);
    record(0x02, 20);  // Footer: no summary
    u64(0);
    u64(0);
    u32(0);
    bytes(magic, 8);
    return out;
  }();
  return path;
}

/// The whole path per scan: next() (chunk read + zstd decompression + CRC-32
/// + copy), CDR deserialisation, PointCloud2 -> Scan. The reader restarts
/// with select(), and its two-chunk cache never holds the next scan's chunk
/// (three chunks in turn), so every scan is decompressed.
void BM_McapReadDecode(benchmark::State& state) {
  semlio::io::McapReader reader(mcap_path(), {.verify_chunk_crc = state.range(0) != 0});
  semlio::io::BagMessage msg;
  semlio::io::PointCloud2Msg cloud;
  semlio::Scan scan;
  std::size_t points = 0;
  std::int64_t scans = 0;
  for (auto _ : state) {
    reader.select({"/kitti/velo/pointcloud"});
    while (reader.next(msg)) {
      semlio::io::parse_cdr_pointcloud2(msg.data.data(), msg.data.size(), cloud);
      semlio::io::pointcloud2_to_scan(cloud, scan);
      points += scan.size();
      ++scans;
    }
    benchmark::DoNotOptimize(scan.points.data());
  }
  state.SetItemsProcessed(scans);  // items/s = scans/s
  state.counters["points_per_scan"] = benchmark::Counter(static_cast<double>(points) / static_cast<double>(scans));
}
BENCHMARK(BM_McapReadDecode)->ArgName("crc")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

/// The same path on the unchunked copy (no decompression, no CRC).
void BM_McapReadDecodeUnchunked(benchmark::State& state) {
  semlio::io::McapReader reader(plain_mcap_path());
  semlio::io::BagMessage msg;
  semlio::io::PointCloud2Msg cloud;
  semlio::Scan scan;
  std::int64_t scans = 0;
  for (auto _ : state) {
    reader.select({"/kitti/velo/pointcloud"});
    while (reader.next(msg)) {
      semlio::io::parse_cdr_pointcloud2(msg.data.data(), msg.data.size(), cloud);
      semlio::io::pointcloud2_to_scan(cloud, scan);
      ++scans;
    }
    benchmark::DoNotOptimize(scan.points.data());
  }
  if (scans != 3 * static_cast<std::int64_t>(state.iterations())) state.SkipWithError("expected 3 scans a pass");
  state.SetItemsProcessed(scans);
}
BENCHMARK(BM_McapReadDecodeUnchunked)->Unit(benchmark::kMillisecond);

/// next() alone: chunk read + zstd decompression (+ CRC-32) + copy of the message bytes.
void BM_McapNext(benchmark::State& state) {
  semlio::io::McapReader reader(mcap_path(), {.verify_chunk_crc = state.range(0) != 0});
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
BENCHMARK(BM_McapNext)->ArgName("crc")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

/// CDR deserialisation alone (mostly the copy of the ~1.9 MB point data).
void BM_CdrParsePointCloud2(benchmark::State& state) {
  semlio::io::McapReader reader(mcap_path());
  reader.select({"/kitti/velo/pointcloud"});
  std::vector<std::vector<std::uint8_t>> messages;
  semlio::io::BagMessage msg;
  while (reader.next(msg)) messages.push_back(msg.data);
  semlio::io::PointCloud2Msg cloud;
  std::int64_t scans = 0;
  for (auto _ : state) {
    for (const auto& m : messages) {
      semlio::io::parse_cdr_pointcloud2(m.data(), m.size(), cloud);
      benchmark::DoNotOptimize(cloud.data.data());
      ++scans;
    }
  }
  state.SetItemsProcessed(scans);
}
BENCHMARK(BM_CdrParsePointCloud2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
