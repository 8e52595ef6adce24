// semlio_simulate: writes a simulated semantic lidar + IMU drive in KITTI
// layout (see include/semlio/sim/kitti_writer.hpp for the files) and, on
// request, the same drive as a ROS 1 bag and/or an MCAP file.
//
//   semlio_simulate --world urban|rural|highway|aliased --traffic none|light|heavy
//                   --frames N --seed S [--revisit] [--distortion on|off]
//                   [--imu-rate-hz R] [--label-quality MIOU] [--threads T]
//                   [--sensor hdl64e|vlp16|vlp32c|hdl32e|os1-64|os0-128] [--mount-height-m H]
//                   [--bag FILE.bag] [--mcap FILE.mcap] [--mcap-compression zstd|none]
//                   [--fields ring,time | --no-ring-time] [--points-topic T] [--imu-topic T]
//                   [--out DIR]
// Defaults: urban, light, 1000 frames, seed 1, distortion off, 100 Hz, 0.5,
// threads = hardware concurrency (the output does not depend on it), sensor
// hdl64e (KITTI's), topics /points and /imu/data, fields ring,time.
// --revisit: the drive comes back to its start: the last frame is taken at
// the first frame's pose, heading the same way, for any N >= ~100 frames
// (urban/aliased: a block loop with stops, or for drives shorter than ~70 s
// an out-and-back along one street with U-turns; rural: out-and-back with
// U-turns on paved turnarounds; highway: out-and-back in the inner lanes with
// U-turns through median crossings).
//
// Bags (--bag: ROS 1 bag 2.0, uncompressed chunks; --mcap: MCAP, profile
// ros2, CDR, zstd chunks by default): the cloud topic carries
// sensor_msgs/PointCloud2 in the sensor's driver layout (Velodyne: x y z
// intensity, ring uint16, time float32 s; Ouster: ouster_ros's 48-byte point
// with t uint32 ns and ring uint16), header stamp = sweep start, per-point
// times relative to it; the IMU topic carries sensor_msgs/Imu (orientation
// unknown: orientation_covariance[0] = -1), the same samples as oxts/. Stamps
// are epoch + simulation time with KittiWriterConfig's epoch (2011-10-03
// 12:00:00 UTC, as the OXTS timestamps). Log times: a cloud is logged at the
// end of its sweep (when a driver publishes it), an IMU sample at its stamp.
// Frames are simulated again for the bags (same config, same frames).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <algorithm>
#include <string>
#include <string_view>
#include <memory>
#include <thread>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/sim/kitti_writer.hpp>
#include <semlio/sim/lidar.hpp>
#include <semlio/sim/simulator.hpp>
#if SEMLIO_SIMULATE_BAGS
#include <semlio/io/bag/mcap_writer.hpp>
#include <semlio/io/bag/rosbag1_writer.hpp>
#include <semlio/io/bag/ros_writer_msgs.hpp>
#endif

namespace {

void usage() {
  std::fprintf(stderr,
               "usage: semlio_simulate [--world urban|rural|highway|aliased] [--traffic none|light|heavy]\n"
               "                       [--frames N] [--seed S] [--revisit] [--distortion on|off]\n"
               "                       [--imu-rate-hz R] [--label-quality MIOU] [--threads T] --out DIR\n"
               "defaults: urban, light traffic, 1000 frames, seed 1, distortion off, 100 Hz IMU, label quality 0.5\n"
               "--revisit: plan the route so that the last frame is taken at the first frame's pose (same\n"
               "           heading, passing at speed), for any drive of >= ~100 frames: urban/aliased drive\n"
               "           a block loop (stops fitted to the drive) or, when shorter than a block loop\n"
               "           (< ~700 frames), out and back along one street with U-turns; rural drives out\n"
               "           and back with U-turns on paved turnarounds; highway out and back in the inner\n"
               "           lanes with U-turns through median crossings. Without it, drives shorter than\n"
               "           ~1500 frames (urban) never come back to their start.\n"
               "sensor:    [--sensor hdl64e|vlp16|vlp32c|hdl32e|os1-64|os0-128] (default hdl64e, KITTI's)\n"
               "           [--mount-height-m H] (default 1.73 m for hdl64e, 1.8 m for the others)\n"
               "bags:      [--bag FILE.bag] (ROS 1) [--mcap FILE.mcap] (ROS 2 CDR) [--mcap-compression zstd|none]\n"
               "           [--fields ring,time|ring|time|none] [--no-ring-time] (per-point fields, default ring,time)\n"
               "           [--points-topic /points] [--imu-topic /imu/data] [--frame-id lidar] [--imu-frame-id imu]\n"
               "--out DIR may be left out when --bag or --mcap is given.\n");
}

/// What goes into the bags.
struct BagOptions {
  std::string bag;                    // ROS 1 bag path ("" = none)
  std::string mcap;                   // MCAP path ("" = none)
  bool mcap_zstd = true;              // zstd chunks
  bool ring = true;                   // per-point ring field
  bool time = true;                   // per-point time field
  std::string points_topic = "/points";
  std::string imu_topic = "/imu/data";
  std::string frame_id = "lidar";
  std::string imu_frame_id = "imu";
};

void parse_fields(const std::string& text, BagOptions& o) {
  o.ring = false;
  o.time = false;
  if (text == "none" || text.empty()) return;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string f = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (f == "ring") {
      o.ring = true;
    } else if (f == "time") {
      o.time = true;
    } else {
      throw semlio::ConfigError("--fields takes ring,time, ring, time or none; got '" + text + "'");
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
}

#if SEMLIO_SIMULATE_BAGS
/// Writes the drive of `sim` into the requested bags: frames simulated in
/// parallel batches of `threads`, written in order, IMU samples interleaved
/// by log time. Returns the number of messages per container.
std::size_t write_bags(const semlio::sim::Simulator& sim, const std::string& sensor, const BagOptions& o,
                       const semlio::sim::KittiWriterConfig& wc) {
  namespace io = semlio::io;
  std::unique_ptr<io::Rosbag1Writer> bag;
  std::unique_ptr<io::McapWriter> mcap;
  std::size_t bag_points = 0;
  std::size_t bag_imu = 0;
  std::size_t mcap_points = 0;
  std::size_t mcap_imu = 0;
  if (!o.bag.empty()) {
    bag = std::make_unique<io::Rosbag1Writer>(o.bag);
    bag_points = bag->add_topic(o.points_topic, io::RosMessageType::kPointCloud2);
    bag_imu = bag->add_topic(o.imu_topic, io::RosMessageType::kImu);
  }
  if (!o.mcap.empty()) {
    io::McapWriterConfig mc;
    mc.compression = o.mcap_zstd ? io::McapCompression::kZstd : io::McapCompression::kNone;
    mcap = std::make_unique<io::McapWriter>(o.mcap, mc);
    mcap_points = mcap->add_topic(o.points_topic, io::RosMessageType::kPointCloud2);
    mcap_imu = mcap->add_topic(o.imu_topic, io::RosMessageType::kImu);
  }
  io::CloudFieldsConfig fields;
  fields.layout = semlio::sim::lidar_is_ouster(sensor) ? io::CloudLayout::kOuster : io::CloudLayout::kVelodyne;
  fields.ring = o.ring;
  fields.time = o.time;

  // The IMU exactly as the KITTI writer simulates it (same seed and mount).
  semlio::sim::ImuConfig ic;
  ic.noise = wc.imu_noise;
  ic.seed = sim.config().seed;
  const semlio::sim::SimulatedImu imu = sim.imu(ic, wc.T_imu_lidar);
  const double rate = sim.config().imu_rate_hz;
  const double gyro_var = ic.noise ? ic.gyro_noise_density * ic.gyro_noise_density * rate : 0.0;
  const double accel_var = ic.noise ? ic.accel_noise_density * ic.accel_noise_density * rate : 0.0;
  const auto epoch_ns = static_cast<std::int64_t>(std::llround(wc.epoch_s * 1e9));
  const auto to_ns = [&](double t_s) { return epoch_ns + static_cast<std::int64_t>(std::llround(t_s * 1e9)); };
  std::size_t next_imu = 0;
  const auto write_imu_until = [&](std::int64_t log_ns) {
    for (; next_imu < imu.samples.size(); ++next_imu) {
      const auto& s = imu.samples[next_imu];
      const std::int64_t t_ns = to_ns(s.stamp_s);
      if (t_ns > log_ns) break;
      io::ImuMsg m;
      m.stamp_s = wc.epoch_s + s.stamp_s;
      m.frame_id = o.imu_frame_id;
      m.orientation_covariance[0] = -1.0;  // no orientation estimate (a 6-axis IMU)
      m.angular_velocity_radps = s.gyro_radps;
      m.linear_acceleration_mps2 = s.accel_mps2;
      for (int k = 0; k < 3; ++k) {
        m.angular_velocity_covariance[static_cast<std::size_t>(4 * k)] = gyro_var;
        m.linear_acceleration_covariance[static_cast<std::size_t>(4 * k)] = accel_var;
      }
      if (bag) bag->write(bag_imu, t_ns, m);
      if (mcap) mcap->write(mcap_imu, t_ns, m);
    }
  };
  const std::size_t n = sim.frame_count();
  const auto threads = static_cast<std::size_t>(std::max(1, wc.threads));
  std::vector<semlio::sim::Frame> batch;
  for (std::size_t first = 0; first < n; first += threads) {
    const std::size_t count = std::min(threads, n - first);
    batch.assign(count, semlio::sim::Frame{});
    std::vector<std::thread> pool;
    for (std::size_t k = 1; k < count; ++k) pool.emplace_back([&, k] { batch[k] = sim.frame(first + k); });
    batch[0] = sim.frame(first);
    for (auto& t : pool) t.join();
    for (semlio::sim::Frame& f : batch) {
      const double start_s = f.scan.stamp_s;
      const std::int64_t log_ns = to_ns(start_s + sim.lidar().period_s());
      write_imu_until(log_ns);
      f.scan.stamp_s = wc.epoch_s + start_s;
      const io::PointCloud2Msg cloud = io::scan_to_pointcloud2(f.scan, fields, o.frame_id);
      if (bag) bag->write(bag_points, log_ns, cloud);
      if (mcap) mcap->write(mcap_points, log_ns, cloud);
    }
  }
  write_imu_until(std::numeric_limits<std::int64_t>::max());
  std::size_t messages = 0;
  if (bag) {
    messages = bag->message_count();
    bag->close();
  }
  if (mcap) {
    messages = mcap->message_count();
    mcap->close();
  }
  return messages;
}
#endif

double parse_number(std::string_view flag, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0') {
    throw semlio::ConfigError(std::string(flag) + " expects a number, got '" + text + "'");
  }
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    semlio::sim::SimulatorConfig cfg;
    semlio::sim::KittiWriterConfig wc;
    const unsigned hw = std::thread::hardware_concurrency();
    wc.threads = hw == 0 ? 1 : static_cast<int>(hw);
    std::string out;
    std::string sensor = "hdl64e";
    double mount_height_m = -1.0;
    BagOptions bags;
    for (int i = 1; i < argc; ++i) {
      const std::string_view a = argv[i];
      const auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw semlio::ConfigError(std::string(a) + " needs a value");
        return argv[++i];
      };
      if (a == "--world") {
        cfg.world = semlio::sim::parse_world(value());
      } else if (a == "--traffic") {
        cfg.traffic = semlio::sim::parse_traffic(value());
      } else if (a == "--frames") {
        const double f = parse_number(a, value());
        if (!(f >= 1.0) || f != static_cast<double>(static_cast<long long>(f))) {
          throw semlio::ConfigError("--frames must be a positive integer");
        }
        cfg.frames = static_cast<std::size_t>(f);
      } else if (a == "--seed") {
        const double s = parse_number(a, value());
        if (!(s >= 0.0) || s != static_cast<double>(static_cast<long long>(s))) {
          throw semlio::ConfigError("--seed must be a non-negative integer");
        }
        cfg.seed = static_cast<std::uint64_t>(s);
      } else if (a == "--revisit") {
        cfg.revisit = true;
      } else if (a == "--distortion") {
        const std::string v = value();
        if (v != "on" && v != "off") throw semlio::ConfigError("--distortion must be on|off, got '" + v + "'");
        cfg.distortion = v == "on";
      } else if (a == "--imu-rate-hz") {
        cfg.imu_rate_hz = parse_number(a, value());
      } else if (a == "--label-quality") {
        cfg.label_quality = parse_number(a, value());
      } else if (a == "--threads") {
        wc.threads = static_cast<int>(parse_number(a, value()));
      } else if (a == "--out") {
        out = value();
      } else if (a == "--sensor") {
        sensor = value();
        (void)semlio::sim::lidar_config_for(sensor);  // validates the name now
      } else if (a == "--mount-height-m") {
        mount_height_m = parse_number(a, value());
        if (!(mount_height_m > 0.0 && mount_height_m < 10.0)) {
          throw semlio::ConfigError("--mount-height-m must be in (0, 10) m, got " + std::to_string(mount_height_m));
        }
      } else if (a == "--bag") {
        bags.bag = value();
      } else if (a == "--mcap") {
        bags.mcap = value();
      } else if (a == "--mcap-compression") {
        const std::string v = value();
        if (v != "zstd" && v != "none") throw semlio::ConfigError("--mcap-compression must be zstd|none, got '" + v + "'");
        bags.mcap_zstd = v == "zstd";
      } else if (a == "--fields") {
        parse_fields(value(), bags);
      } else if (a == "--no-ring-time") {
        bags.ring = false;
        bags.time = false;
      } else if (a == "--points-topic") {
        bags.points_topic = value();
      } else if (a == "--imu-topic") {
        bags.imu_topic = value();
      } else if (a == "--frame-id") {
        bags.frame_id = value();
      } else if (a == "--imu-frame-id") {
        bags.imu_frame_id = value();
      } else if (a == "--help" || a == "-h") {
        usage();
        return 0;
      } else {
        throw semlio::ConfigError("unknown argument '" + std::string(a) + "'");
      }
    }
    const bool want_bags = !bags.bag.empty() || !bags.mcap.empty();
    if (out.empty() && !want_bags) throw semlio::ConfigError("--out DIR is required (unless --bag or --mcap is given)");
#if !SEMLIO_SIMULATE_BAGS
    if (want_bags) {
      throw semlio::ConfigError("--bag/--mcap: this semlio_simulate was built without the bag component "
                                "(cmake/SemlioBags.cmake: needs libzstd, liblz4, libbz2, libsqlite3)");
    }
#endif
    cfg.lidar = semlio::sim::lidar_config_for(sensor);
    if (mount_height_m > 0.0) cfg.lidar.mount_height_m = mount_height_m;
    const auto t0 = std::chrono::steady_clock::now();
    const semlio::sim::Simulator sim(cfg);
    if (cfg.revisit && std::abs(sim.world().return_error_m) > 1.0) {
      std::fprintf(stderr, "semlio_simulate: warning: --revisit: %zu frames are too short to come back; the drive "
                   "ends %.1f m (of path) from its start (needs ~100 frames or more)\n",
                   cfg.frames, std::abs(sim.world().return_error_m));
    }
    wc.logger = [](semlio::LogLevel, std::string_view msg) {
      std::fprintf(stderr, "%.*s\n", static_cast<int>(msg.size()), msg.data());
    };
    if (!out.empty()) {
      const auto rep = semlio::sim::write_kitti_sequence(sim, out, wc);
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("wrote %zu frames (%llu points, %.0f per frame), %zu IMU samples to %s in %.1f s (sensor %s)\n",
                  rep.frames, static_cast<unsigned long long>(rep.points),
                  static_cast<double>(rep.points) / static_cast<double>(rep.frames), rep.imu_samples, out.c_str(),
                  secs, sensor.c_str());
      std::printf("prediction mIoU %.3f (target %.3f, calibration %.3f)\n", rep.prediction_miou, cfg.label_quality,
                  rep.calibration_miou);
    }
#if SEMLIO_SIMULATE_BAGS
    if (want_bags) {
      const auto t1 = std::chrono::steady_clock::now();
      const std::size_t messages = write_bags(sim, sensor, bags, wc);
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      std::printf("wrote %zu messages (%s, %s) to%s%s%s%s in %.1f s\n", messages, bags.points_topic.c_str(),
                  bags.imu_topic.c_str(), bags.bag.empty() ? "" : " ", bags.bag.c_str(), bags.mcap.empty() ? "" : " ",
                  bags.mcap.c_str(), secs);
    }
#endif
    return 0;
  } catch (const semlio::Error& e) {
    std::fprintf(stderr, "semlio_simulate: %s\n", e.what());
    usage();
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "semlio_simulate: %s\n", e.what());
    return 1;
  }
}
