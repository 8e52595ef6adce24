// Reading + decoding the real KITTI scans from an MCAP file (zstd chunks,
// CDR messages; tests/data/bags/kitti3_zstd.mcap, written by the reference
// @mcap/core with zstd level 3): the must-hold is >= 10x the odometry frame
// rate on one core (scripts/read_speed.sh measures both on the same core and
// prints the ratios, docs/read_speed.md). Run: taskset -c 1 build/bench/bench_mcap_read
// BM_McapReadDecodeRosbag2 reads the same scans as rosbag2's MCAP storage
// writes them with each of its presets (zstd level and chunk CRC): zstd's
// decompression time depends on the level, and libzstd's own decoding is
// most of this path (perf record on BM_McapReadDecode: libzstd about 70 %,
// PointCloud2 -> Scan 15 %, CRC-32 6 %).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <semlio/core/scan.hpp>
#include <semlio/io/bag/mcap.hpp>
#include <semlio/io/bag/mcap_writer.hpp>
#include <semlio/io/cdr_msgs.hpp>
#include <semlio/io/pointcloud2.hpp>
#include <semlio_test/data.hpp>

namespace {

const std::string& mcap_path() {
  static const std::string path = semlio_test::data_path("bags/kitti3_zstd.mcap");
  return path;
}

/// The fixture's three KITTI cloud messages (CDR bytes and log times), read once.
const std::vector<semlio::io::BagMessage>& fixture_scans() {
  static const std::vector<semlio::io::BagMessage> scans = [] {
    std::vector<semlio::io::BagMessage> out;
    semlio::io::McapReader reader(mcap_path());
    reader.select({"/kitti/velo/pointcloud"});
    semlio::io::BagMessage m;
    while (reader.next(m)) out.push_back(m);
    return out;
  }();
  return scans;
}

/// The three KITTI scans of kitti3_zstd.mcap as an MCAP file without chunks
/// (Messages directly in the data section, no summary), written once to the
/// temp dir: the reader's cost without decompression and CRC, for comparison.
const std::string& plain_mcap_path() {
  static const std::string path = [] {
    const std::vector<semlio::io::BagMessage>& scans = fixture_scans();
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

/// rosbag2's MCAP writer settings (rosbag2_storage_mcap, mcap C++ library):
/// no preset = zstd level 1 (CompressionLevel::Default), chunk CRC, 768 KiB
/// chunks; `zstd_fast` = level -5 (Fastest), no chunk CRC; `zstd_small` =
/// level 19 (Slowest), chunk CRC, 4 MiB chunks.
struct Rosbag2Preset {
  const char* name;
  semlio::io::McapWriterConfig config;
};
const Rosbag2Preset kRosbag2Presets[] = {
    {"default", {.zstd_level = 1, .chunk_bytes = 768 * 1024, .chunk_crc = true}},
    {"zstd_fast", {.zstd_level = -5, .chunk_bytes = 768 * 1024, .chunk_crc = false}},
    {"zstd_small", {.zstd_level = 19, .chunk_bytes = 4 * 1024 * 1024, .chunk_crc = true}},
};
constexpr int kPresetCopies = 3;  ///< the three scans written this many times in turn: 9 messages

/// The three KITTI scans written kPresetCopies times in turn, as rosbag2
/// would with `preset`, to the temp dir. Nine messages make at least three
/// chunks with every preset, so the reader's two-chunk cache never holds the
/// chunk a pass starts with.
std::string write_rosbag2_mcap(const Rosbag2Preset& preset) {
  std::vector<std::pair<std::int64_t, semlio::io::PointCloud2Msg>> clouds;
  for (const semlio::io::BagMessage& m : fixture_scans()) {
    semlio::io::PointCloud2Msg cloud;
    semlio::io::parse_cdr_pointcloud2(m.data.data(), m.data.size(), cloud);
    clouds.emplace_back(m.log_time_ns, std::move(cloud));
  }
  const std::string out =
      (std::filesystem::temp_directory_path() / (std::string("semlio_bench_kitti_rosbag2_") + preset.name + ".mcap"))
          .string();
  semlio::io::McapWriter writer(out, preset.config);
  const std::size_t topic = writer.add_topic("/kitti/velo/pointcloud", semlio::io::RosMessageType::kPointCloud2);
  const std::int64_t span_ns = clouds.back().first - clouds.front().first + 100'000'000;
  for (int copy = 0; copy < kPresetCopies; ++copy) {
    for (const auto& [t, cloud] : clouds) writer.write(topic, t + copy * span_ns, cloud);
  }
  writer.close();
  return out;
}

/// write_rosbag2_mcap once per preset and process (level 19 compresses at a
/// few MB/s, and the benchmark function runs several times).
const std::string& rosbag2_mcap_path(const Rosbag2Preset& preset) {
  static std::map<const Rosbag2Preset*, std::string> written;  // node-based: references stay valid
  auto it = written.find(&preset);
  if (it == written.end()) it = written.emplace(&preset, write_rosbag2_mcap(preset)).first;
  return it->second;
}

/// Reads and decodes every scan of `reader` `state` asks for: next() (chunk
/// read + decompression + CRC-32 + copy), CDR deserialisation, PointCloud2
/// -> Scan. The reader restarts with select() each pass. Fails the benchmark
/// unless each pass gives `scans_per_pass` scans; sets items/s = scans/s.
void read_decode_passes(benchmark::State& state, semlio::io::McapReader& reader, std::int64_t scans_per_pass) {
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
  if (scans != scans_per_pass * static_cast<std::int64_t>(state.iterations())) {
    state.SkipWithError("unexpected number of scans a pass");
    return;
  }
  state.SetItemsProcessed(scans);
  state.counters["points_per_scan"] = benchmark::Counter(static_cast<double>(points) / static_cast<double>(scans));
}

/// The whole path per scan on the committed fixture. Its two-chunk cache
/// never holds the next scan's chunk (three chunks in turn), so every scan
/// is decompressed.
void BM_McapReadDecode(benchmark::State& state) {
  semlio::io::McapReader reader(mcap_path(), {.verify_chunk_crc = state.range(0) != 0});
  read_decode_passes(state, reader, 3);
}
BENCHMARK(BM_McapReadDecode)->ArgName("crc")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

/// The whole path per scan on the scans as rosbag2 writes them with `preset`.
void BM_McapReadDecodeRosbag2(benchmark::State& state, const Rosbag2Preset& preset) {
  const std::string& path = rosbag2_mcap_path(preset);
  semlio::io::McapReader reader(path);
  read_decode_passes(state, reader, 3 * kPresetCopies);
  state.counters["file_mb"] = benchmark::Counter(static_cast<double>(std::filesystem::file_size(path)) / 1e6);
}
[[maybe_unused]] const bool kRosbag2Registered = [] {
  for (const Rosbag2Preset& p : kRosbag2Presets) {
    benchmark::RegisterBenchmark((std::string("BM_McapReadDecodeRosbag2/") + p.name).c_str(),
                                 [&p](benchmark::State& st) { BM_McapReadDecodeRosbag2(st, p); })
        ->Unit(benchmark::kMillisecond);
  }
  return true;
}();

/// The same path on the unchunked copy (no decompression, no CRC).
void BM_McapReadDecodeUnchunked(benchmark::State& state) {
  semlio::io::McapReader reader(plain_mcap_path());
  read_decode_passes(state, reader, 3);
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
  semlio::io::PointCloud2Msg cloud;
  std::int64_t scans = 0;
  for (auto _ : state) {
    for (const semlio::io::BagMessage& m : fixture_scans()) {
      semlio::io::parse_cdr_pointcloud2(m.data.data(), m.data.size(), cloud);
      benchmark::DoNotOptimize(cloud.data.data());
      ++scans;
    }
  }
  state.SetItemsProcessed(scans);
}
BENCHMARK(BM_CdrParsePointCloud2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
