// bench_frame_time: per-frame cost of the odometry on a KITTI-layout sequence,
// as wall time AND thread CPU time (CLOCK_THREAD_CPUTIME_ID), so that numbers
// taken on a shared, loaded machine stay meaningful. Scans are read before the
// clock starts (I/O is not part of a frame). Used by scripts/frame_time.sh.
//   bench_frame_time --sequence DIR [--preset baseline|full] [--labels none|labels|predictions]
//                    [--last N] [--repeat R] [--keep-first-point on|off]
// Prints one line per frame: index keyframe wall_ms cpu_ms solve_ms map_ms
// features_ms preprocess_ms iterations, then diagnostics of the surface map:
// map points, axes fitted so far on this map build, and the surface
// association's NearestCache hits and refills so far, then the solve's split:
// scan_shapes_ms associate_ms linearize_ms -- nothing else (the script
// summarises).
#include <time.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <semlio/io/kitti_sequence.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/segment/scan_labels.hpp>

namespace {

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

template <typename Odometry>
void run(Odometry odom, const std::vector<semlio::Scan>& scans, std::size_t repeat) {
  for (std::size_t r = 0; r < repeat; ++r) {
    auto o = odom;  // a fresh copy per repetition: same work every time
    for (std::size_t i = 0; i < scans.size(); ++i) {
      semlio::Scan scan = scans[i];
      const double c0 = thread_cpu_ms();
      const auto w0 = std::chrono::steady_clock::now();
      const semlio::FrameReport rep = o.process(scan);
      const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - w0).count();
      const double cpu = thread_cpu_ms() - c0;
      const semlio::FeatureMap& surfaces = o.local_map().surfaces();
      const semlio::NearestCache& cache = o.problem().surface_cache();
      std::printf("%zu %d %.4f %.4f %.4f %.4f %.4f %.4f %d %zu %zu %zu %zu %.4f %.4f %.4f\n", i, rep.keyframe ? 1 : 0,
                  wall, cpu, rep.timings.solve_ms, rep.timings.map_ms, rep.timings.features_ms,
                  rep.timings.preprocess_ms, rep.solve.iterations, surfaces.size(), surfaces.fitted_axes(), cache.hits(),
                  cache.refills(), rep.timings.scan_shapes_ms, rep.timings.associate_ms, rep.timings.linearize_ms);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string sequence;
  std::string preset = "full";
  std::string labels = "none";
  long last = -1;
  std::size_t repeat = 1;
  std::optional<bool> first_point;  // unset: the library default
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    const std::string v = argv[i + 1];
    if (a == "--sequence") {
      sequence = v;
    } else if (a == "--preset") {
      preset = v;
    } else if (a == "--labels") {
      labels = v;
    } else if (a == "--last") {
      last = std::atol(v.c_str());
    } else if (a == "--repeat") {
      repeat = static_cast<std::size_t>(std::atol(v.c_str()));
    } else if (a == "--keep-first-point") {
      if (v != "on" && v != "off") {
        std::fprintf(stderr, "bench_frame_time: --keep-first-point takes on or off, got %s\n", v.c_str());
        return 2;
      }
      first_point = v == "on";
    } else {
      std::fprintf(stderr, "bench_frame_time: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (sequence.empty()) {
    std::fprintf(stderr, "usage: bench_frame_time --sequence DIR [--preset baseline|full] [--labels none|labels|predictions] [--last N] [--repeat R] [--keep-first-point on|off]\n");
    return 2;
  }
  semlio::io::KittiSequenceConfig sc;
  sc.label_folder = labels == "none" ? "" : labels;
  const semlio::io::KittiSequence seq(sequence, sc);
  const std::size_t n = last < 0 ? seq.size() : std::min(seq.size(), static_cast<std::size_t>(last) + 1);
  std::vector<semlio::Scan> scans;
  scans.reserve(n);
  for (std::size_t i = 0; i < n; ++i) scans.push_back(seq.read(i));
  semlio::PipelineSettings settings;
  if (first_point) settings.odometry.map.keep_first_point = *first_point;
  settings.odometry.kitti_vertical_correction = !std::filesystem::exists(std::filesystem::path(sequence) / "sim.json");
  const bool use_labels = labels != "none" && seq.has_labels();
  const auto go = [&](auto segmenter) {
    if (preset == "baseline") {
      run(semlio::make_baseline_odometry(segmenter, settings), scans, repeat);
    } else {
      run(semlio::make_full_odometry(segmenter, settings), scans, repeat);
    }
  };
  if (use_labels) {
    go(semlio::ScanLabels{});
  } else {
    go(semlio::NoLabels{});
  }
  return 0;
}
