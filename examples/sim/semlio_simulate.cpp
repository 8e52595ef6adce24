// semlio_simulate: writes a simulated semantic lidar + IMU drive in KITTI
// layout (see include/semlio/sim/kitti_writer.hpp for the files).
//
//   semlio_simulate --world urban|rural|highway|aliased --traffic none|light|heavy
//                   --frames N --seed S [--revisit] [--distortion on|off]
//                   [--imu-rate-hz R] [--label-quality MIOU] [--threads T] --out DIR
// Defaults: urban, light, 1000 frames, seed 1, distortion off, 100 Hz, 0.5,
// threads = hardware concurrency (the output does not depend on it).
// --revisit: the drive comes back to its start: the last frame is taken at
// the first frame's pose, heading the same way, for any N >= ~100 frames
// (urban/aliased: a block loop with stops, or for drives shorter than ~70 s
// an out-and-back along one street with U-turns; rural: out-and-back with
// U-turns on paved turnarounds; highway: out-and-back in the inner lanes with
// U-turns through median crossings).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>
#include <thread>

#include <semlio/core/error.hpp>
#include <semlio/sim/kitti_writer.hpp>
#include <semlio/sim/simulator.hpp>

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
               "           ~1500 frames (urban) never come back to their start.\n");
}

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
      } else if (a == "--help" || a == "-h") {
        usage();
        return 0;
      } else {
        throw semlio::ConfigError("unknown argument '" + std::string(a) + "'");
      }
    }
    if (out.empty()) throw semlio::ConfigError("--out DIR is required");
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
    const auto rep = semlio::sim::write_kitti_sequence(sim, out, wc);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("wrote %zu frames (%llu points, %.0f per frame), %zu IMU samples to %s in %.1f s\n", rep.frames,
                static_cast<unsigned long long>(rep.points),
                static_cast<double>(rep.points) / static_cast<double>(rep.frames), rep.imu_samples, out.c_str(), secs);
    std::printf("prediction mIoU %.3f (target %.3f, calibration %.3f)\n", rep.prediction_miou, cfg.label_quality,
                rep.calibration_miou);
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
