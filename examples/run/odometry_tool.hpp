#pragma once
// The run shared by semlio_kitti and semlio_run: the odometry (and, with
// --loop on, the back end: pose graph + loop closure; with --imu, the
// lidar-inertial odometry) over the frames of a FrameSource, with the same
// options, outputs, progress line, summary and report.json for every input.
//
// Outputs are guarded and atomic: OUT is created and probed before the first
// frame; an OUT holding another run's outputs is refused unless --overwrite
// (which removes those outputs first); each file is written under a
// temporary name and renamed when complete; the trajectories are rewritten
// every kCheckpointEvery frames; SIGINT / SIGTERM finish the current frame
// and write everything for the frames done ("status": "interrupted", exit 130).

#include <CLI/CLI.hpp>
#include <unistd.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <numbers>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include <semlio/eval/ate.hpp>
#include <semlio/eval/end_point.hpp>
#include <semlio/eval/kitti_metric.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/ply.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/pipeline/interpolate.hpp>
#include <semlio/pipeline/lidar_inertial.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/pipeline/slam.hpp>
#include <semlio/segment/geometric_segmenter.hpp>
#include <semlio/segment/scan_labels.hpp>
#if SEMLIO_HAVE_ONNX
#include "model_card_yaml.hpp"
#endif

#include "frame_source.hpp"
#include "json_writer.hpp"
#include "segmenter_choice.hpp"
#include "settings_yaml.hpp"

namespace semlio_examples {

namespace fs = std::filesystem;
using semlio::SE3d;

/// Every option semlio_kitti and semlio_run share (the input options are each tool's own).
struct RunOptions {
  std::string labels = "labels";  // labels|predictions|geometric|onnx|none
  std::string model;              // --labels onnx: the model card (YAML)
  std::string preset = "full";    // baseline|full
  std::string config;
  std::string kitti_correction = "auto";  // on|off|auto
  long first = 0;
  long last = -1;
  std::string out;
  bool overwrite = false;
  bool quiet = false;
  std::string loop;           // on|off; empty = the YAML's slam.loop_closure (default off)
  std::string loop_detector;  // radius|scancontext; empty = the YAML's (default radius)
  bool map_static = false;    // drop movable classes from map.ply
  std::string map = "on";     // write map.ply
  std::string imu = "none";   // none|oxts|on
  std::string deskew;         // on|off; empty = the YAML's deskew.mode
  std::string imu_time_offset = "auto";  // t_imu = t_lidar + offset [s], or auto
  std::string velocity_hint = "oxts";    // oxts|none: INS velocity while the LIO initialises
  std::string bad_scans = "skip";        // skip|stop: an unreadable frame is an empty scan, or ends the run
  std::string missing_frames = "empty";  // empty|stop: a gap in the numbering is an empty frame, or an error
};

/// The files a run writes into OUT (and --overwrite removes).
inline const std::vector<std::string>& output_names() {
  static const std::vector<std::string> names{"poses.txt", "poses_odom.txt", "poses_tum.txt",
                                              "keyframes.txt", "map.ply", "report.json"};
  return names;
}

/// Adds the options every odometry tool shares to `app`.
inline void add_run_options(CLI::App& app, RunOptions& opt) {
  app.add_option("--labels", opt.labels, "label source: labels/predictions (a SemanticKITTI folder), geometric (the "
                                         "GeometricSegmenter), onnx (a range-image network, --model), none")
      ->check(CLI::IsMember({"labels", "predictions", "geometric", "onnx", "none"}));
  app.add_option("--model", opt.model, "with --labels onnx: the network's model card (YAML: model, image, channels, "
                                       "classes, knn; docs/guide.md)");
  app.add_option("--preset", opt.preset, "baseline (LIO-SAM-like) or full (the paper)")
      ->check(CLI::IsMember({"baseline", "full"}));
  app.add_option("--config", opt.config, "YAML file overriding preset settings");
  app.add_option("--kitti-correction", opt.kitti_correction,
                 "KITTI vertical-angle correction (auto: on for real KITTI HDL-64E scans only)")
      ->check(CLI::IsMember({"on", "off", "auto"}));
  app.add_option("--first", opt.first, "first frame (inclusive, >= 0)");
  app.add_option("--last", opt.last, "last frame (inclusive; default -1: the last)");
  app.add_option("--out", opt.out, "output directory (created; must not hold another run's outputs)")->required();
  app.add_flag("--overwrite", opt.overwrite, "replace another run's outputs in OUT (they are removed first)");
  app.add_flag("--quiet", opt.quiet, "no progress line");
  app.add_option("--loop", opt.loop,
                 "loop closure + pose graph (with --imu: keyframe graph with velocity/bias states and IMU factors; "
                 "default off: poses.txt is then the odometry; YAML slam.loop_closure)")
      ->check(CLI::IsMember({"on", "off"}));
  app.add_option("--loop-detector", opt.loop_detector, "loop candidates: radius (LIO-SAM, default) or scancontext")
      ->check(CLI::IsMember({"radius", "scancontext"}));
  app.add_option("--map", opt.map, "write OUT/map.ply, the semantic map (default on)")
      ->check(CLI::IsMember({"on", "off"}));
  app.add_flag("--map-static", opt.map_static, "leave movable classes (cars, people, ...) out of map.ply");
  app.add_option("--imu", opt.imu,
                 "on (or oxts): lidar-inertial odometry with the input's IMU (KITTI oxts/ folder, a bag's Imu topic) "
                 "and its lidar-IMU extrinsic (with --loop on: + keyframe graph with IMU factors); none (default): "
                 "lidar only")
      ->check(CLI::IsMember({"none", "oxts", "on"}));
  app.add_option("--deskew", opt.deskew,
                 "deskew sweeps (raw data): on = constant-velocity deskew (with --imu: IMU deskew); default: the "
                 "YAML's deskew.mode")
      ->check(CLI::IsMember({"on", "off"}));
  app.add_option("--imu-time-offset", opt.imu_time_offset,
                 "t_imu = t_lidar + offset [s]; auto: 0, or first IMU stamp - first scan stamp when the clocks "
                 "are more than 1000 s apart");
  app.add_option("--velocity-hint", opt.velocity_hint,
                 "with --imu: oxts (default) = the OXTS INS velocity guides the front end while the LIO "
                 "initialises (when the input has one); none = lidar + IMU only")
      ->check(CLI::IsMember({"oxts", "none"}));
  app.add_option("--bad-scans", opt.bad_scans,
                 "a frame whose scan or label file cannot be read: skip (default) = process it as an empty scan on "
                 "the odometry's prediction and record why in report.json; stop = end the run with the error")
      ->check(CLI::IsMember({"skip", "stop"}));
  app.add_option("--missing-frames", opt.missing_frames,
                 "a gap in the frame numbering (a deleted scan): empty (default) = an empty frame with status "
                 "missing; stop = refuse the input before the first frame")
      ->check(CLI::IsMember({"empty", "stop"}));
}

// Per-frame input facts kept for the report: why a frame could not be read,
// whether its file was missing, and what the reader dropped.
struct InputFrame {
  std::string error;
  bool missing = false;
  semlio::io::ReadStats dropped;
};

// Lidar-inertial facts of a run (--imu oxts).
struct ImuRunFacts {
  bool used = false;
  double time_offset_s = 0.0;
  std::size_t samples = 0;
  long initialized_at = -1;           // frame index (relative to --first), -1: never
  std::size_t imu_predicted = 0;      // frames whose initial guess came from the IMU
  std::size_t fallbacks = 0;          // frames with unusable IMU (constant-velocity prediction)
  std::size_t imu_deskewed = 0;       // sweeps deskewed with the IMU
  std::size_t rejected = 0;           // samples push_imu rejected (non-finite, not after the previous one)
  std::string last_issue;             // last fallback / rejection reason
  std::vector<char> fallback_frame;   // per frame
  std::size_t imu_factors = 0;        // IMU factors in the keyframe graph (--loop on)
};

// Counts one LIO frame into the facts (frame index relative to --first).
inline void count_lio_frame(ImuRunFacts& f, const semlio::LidarInertialReport& r, std::size_t frame) {
  if (r.initialized && f.initialized_at < 0) f.initialized_at = static_cast<long>(frame);
  f.imu_predicted += r.prediction == semlio::PredictionSource::kImu ? 1U : 0U;
  f.fallbacks += r.imu_fallback ? 1U : 0U;
  f.imu_deskewed += r.deskew == semlio::DeskewSource::kImu ? 1U : 0U;
  f.fallback_frame.push_back(r.imu_fallback ? 1 : 0);
  if (!r.imu_issue.empty()) f.last_issue = r.imu_issue;
}

// IMU input of a run: samples, INS velocities and the LIO's settings.
struct ImuFeed {
  const std::vector<semlio::ImuSample>& imu;
  const std::vector<OxtsVelocity>& velocities;
  const semlio::LidarInertialConfig& lc;
  std::size_t next = 0;    // next sample to push
  std::size_t next_v = 0;  // next velocity to push

  // Pushes everything up to the sweep's end (IMU clock) into `sink`, and the
  // first sample after it: the LIO predicts and deskews a sweep only with
  // samples on both sides of it, and a 10 Hz IMU (KITTI raw's OXTS) has its
  // next sample up to 0.1 s after the sweep's end; an online system waits
  // for that sample too.
  template <typename Sink>
  void feed(Sink& sink, double scan_stamp_s) {
    const double until = scan_stamp_s + lc.imu_time_offset_s + lc.sweep_period_s + 1e-6;
    while (next < imu.size() && imu[next].stamp_s <= until) sink.push_imu(imu[next++]);
    if (next < imu.size() && (next == 0 || imu[next - 1].stamp_s <= until)) sink.push_imu(imu[next++]);
    for (; next_v < velocities.size() && velocities[next_v].stamp_s <= until; ++next_v) {
      sink.push_velocity(velocities[next_v].stamp_s, velocities[next_v].v_imu_mps);
    }
  }
};

// Either shipped loop detector behind one type, so that each front end is
// instantiated once (the detector is chosen at run time).
struct AnyLoopDetector {
  std::variant<semlio::RadiusLoopDetector, semlio::ScanContextDetector> detector;
  void detect(const std::vector<semlio::LoopKeyframe>& keyframes, std::vector<semlio::LoopCandidate>& out) {
    std::visit([&](auto& d) { d.detect(keyframes, out); }, detector);
  }
};
static_assert(semlio::LoopDetector<AnyLoopDetector>);

// Per-frame back-end facts kept for the report.
struct BackEndFrame {
  bool loop_checked = false;
  bool loop_closed = false;
  double backend_ms = 0.0;
  double total_ms = 0.0;
  double cpu_ms = 0.0;  // thread CPU time of the whole frame (read + process)
};

struct RunResult {
  std::vector<semlio::FrameReport> reports;
  std::vector<InputFrame> inputs;  // per frame: read errors, missing file, dropped points
  std::vector<BackEndFrame> back_end;
  semlio::RankHistogram ranks{};
  double wall_s = 0.0;
  std::vector<SE3d> optimised;  // one per frame, world (graph) frame
  std::vector<SE3d> odometry;   // one per frame, odometry only
  std::vector<semlio::SlamLoop> loops;
  semlio::LoopStats loop_stats;
  double graph_ms = 0.0;
  double graph_full_ms = 0.0;
  std::size_t graph_nodes = 0;
  std::size_t graph_factors = 0;
  std::size_t keyframe_bytes = 0;
  std::size_t place_bytes = 0;        // data of the retired keyframes kept as places
  std::size_t places = 0;
  std::size_t archived = 0;           // retired keyframes whose data was dropped
  double place_spacing_m = 0.0;       // final place spacing (grows with each thinning)
  std::size_t place_thinnings = 0;
  long peak_rss_before_map_kb = 0;    // VmHWM before the semantic map was built
  std::size_t map_build_bytes = 0;    // SemanticMap while building
  // Every kMemoryTraceEvery frames and at the end: frame, keyframe store, resident set.
  struct MemorySample {
    std::size_t frame = 0;
    std::size_t store_bytes = 0;
    std::size_t place_bytes = 0;
    long rss_kb = 0;
    std::size_t heap_live_bytes = 0;  // malloc's bytes in use (glibc mallinfo2; 0 elsewhere)
  };
  std::vector<MemorySample> memory_trace;
  semlio::Scan map;
  ImuRunFacts imu;
  bool interrupted = false;  // SIGINT / SIGTERM ended the run early
};

// Writes the outputs of the frames done so far (every kCheckpointEvery
// frames), so that a run killed without a chance to clean up keeps them.
using Checkpoint = std::function<void(const RunResult&)>;
constexpr std::size_t kCheckpointEvery = 100;

// Set by SIGINT / SIGTERM: the run finishes the current frame, then writes
// everything for the frames done (report.json status "interrupted").
inline volatile std::sig_atomic_t g_stop_requested = 0;
extern "C" inline void request_stop(int /*signal*/) { g_stop_requested = 1; }

// SEMLIO_INTERRUPT_AFTER_FRAMES=N makes the run send itself SIGINT after N
// frames: the interrupt tests (tests/examples/run_tool_check.cmake,
// scripts/interrupt_check.sh) exercise the real signal path at a known frame.
inline void self_interrupt_after(std::size_t done) {
  static const long after = [] {
    const char* v = std::getenv("SEMLIO_INTERRUPT_AFTER_FRAMES");
    return v == nullptr ? -1L : std::strtol(v, nullptr, 10);
  }();
  if (after > 0 && done == static_cast<std::size_t>(after)) std::raise(SIGINT);
}

// Reads the frames of a run from a FrameSource. With skip_bad a frame whose
// files cannot be read (empty, truncated or missing scan; bad labels; every
// point NaN or at the origin) becomes an empty scan at its stamp -- the
// odometry reports too_few_features and keeps going on its prediction -- and
// the reason goes to stderr and report.json; without it the error ends the run.
class FrameReader {
 public:
  FrameReader(FrameSource& input, bool skip_unreadable, const char* tool_name, double period_s)
      : source(input), skip_bad(skip_unreadable), tool(tool_name), nominal_period_s(period_s) {}

  FrameSource& source;
  bool skip_bad = true;
  const char* tool = "semlio_run";
  double nominal_period_s = 0.1;  // stamp of an unreadable frame that has none: previous + this

  semlio::Scan read(std::size_t i, std::vector<InputFrame>& inputs) const {
    SourceFrame f = source.read(i);
    if (f.error.empty() && f.scan.empty() && f.dropped.dropped() > 0) {
      f.error = "no valid point: " + std::to_string(f.dropped.dropped_nonfinite) + " NaN/Inf and " +
                std::to_string(f.dropped.dropped_zero) + " at (0,0,0) dropped";
    }
    if (!f.error.empty()) {
      if (!skip_bad) throw semlio::IoError("frame " + std::to_string(i) + ": " + f.error);
      std::cerr << "\n" << tool << ": warning: frame " << i << (f.missing ? " is missing" : " is unreadable")
                << ", processed as an empty scan: " << f.error << "\n";
      if (f.scan.stamp_s == 0.0 && !stamps_.empty()) f.scan.stamp_s = stamps_.back() + nominal_period_s;
    }
    stamps_.push_back(f.scan.stamp_s);
    inputs.push_back({std::move(f.error), f.missing, f.dropped});
    return std::move(f.scan);
  }

 private:
  mutable std::vector<double> stamps_;
};

// CPU time of the calling thread [ms]: unlike wall time it does not grow
// when other processes share the machine, so long runs stay comparable.
inline double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// Peak (VmHWM) or current (VmRSS) resident set size [kB] from
// /proc/self/status; 0 when unknown.
inline long status_kb(const char* field) {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == field) {
      long kb = 0;
      status >> kb;
      return kb;
    }
    status.ignore(4096, '\n');
  }
  return 0;
}
inline long peak_rss_kb() { return status_kb("VmHWM:"); }
// Bytes the allocator has handed out and not got back (live heap + mmapped
// blocks): tells live growth from fragmentation in the resident set.
inline std::size_t heap_live_bytes() {
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  const struct mallinfo2 mi = mallinfo2();
  return mi.uordblks + mi.hblkhd;
#else
  return 0;
#endif
}
inline long rss_kb() { return status_kb("VmRSS:"); }
constexpr std::size_t kMemoryTraceEvery = 250;

// Terminal progress line (frame i/N, Hz, ETA), refreshed every 5 frames.
inline void show_progress(const char* tool, std::size_t done, std::size_t n, std::chrono::steady_clock::time_point start) {
  if (done % 5 != 0 && done != n) return;
  const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double hz = static_cast<double>(done) / std::max(el, 1e-9);
  std::fprintf(stderr, "\r[%s] frame %zu/%zu  %.1f Hz  ETA %.0f s   ", tool, done, n, hz,
               static_cast<double>(n - done) / hz);
}

inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

// Front end + back end (Slam). With a lidar-inertial front end (--imu oxts
// --loop on), `imu` feeds it before each scan.
template <typename Odometry>
RunResult run(Odometry odom, const BackEndSettings& be, bool write_map,
              const FrameReader& frames, std::size_t first, std::size_t last, bool quiet, const Checkpoint& checkpoint,
              [[maybe_unused]] ImuFeed* imu = nullptr) {
  RunResult result;
  const std::size_t n = last - first + 1;
  result.reports.reserve(n);
  result.back_end.reserve(n);
  AnyLoopDetector detector{be.loop_detector == "scancontext"
                               ? decltype(AnyLoopDetector::detector)(semlio::ScanContextDetector(be.scan_context))
                               : decltype(AnyLoopDetector::detector)(semlio::RadiusLoopDetector(be.radius))};
  semlio::Slam slam(std::move(odom), std::move(detector), be.slam);
  const bool tty = !quiet && isatty(STDERR_FILENO) != 0;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = first; i <= last; ++i) {
    const double cpu_start_ms = thread_cpu_ms();
    semlio::Scan scan = frames.read(i, result.inputs);
    if constexpr (decltype(slam)::kInertial) {
      if (imu != nullptr) imu->feed(slam, scan.stamp_s);
    }
    const semlio::SlamFrameReport r = slam.process(scan);
    if constexpr (decltype(slam)::kInertial) count_lio_frame(result.imu, slam.odometry().last_report(), i - first);
    result.reports.push_back(r.odometry);
    result.back_end.push_back({r.loop_checked, r.loop_closed, r.backend_ms, r.total_ms, thread_cpu_ms() - cpu_start_ms});
    const std::size_t done = i - first + 1;
    if (done % kMemoryTraceEvery == 0 || i == last) {
      result.memory_trace.push_back({done, slam.keyframe_bytes(), slam.place_bytes(), rss_kb(), heap_live_bytes()});
    }
    if (tty) show_progress(frames.tool, done, n, start);
    self_interrupt_after(done);
    if (g_stop_requested != 0) {
      result.interrupted = true;
      break;
    }
    if (done % kCheckpointEvery == 0 && i != last) {
      result.optimised = slam.trajectory();
      result.odometry = slam.odometry_trajectory();
      checkpoint(result);
    }
  }
  if (tty) std::fprintf(stderr, "\n");
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.ranks = slam.odometry().rank_histogram();
  result.optimised = slam.trajectory();
  result.odometry = slam.odometry_trajectory();
  result.loops = slam.loops();
  result.loop_stats = slam.loop_stats();
  result.graph_ms = slam.graph_ms();
  result.graph_full_ms = slam.graph_full_ms();
  result.graph_nodes = slam.graph().num_nodes();
  result.graph_factors = slam.graph().num_factors();
  if constexpr (decltype(slam)::kInertial) {
    result.imu.used = true;
    result.imu.time_offset_s = slam.odometry().lio().config().imu_time_offset_s;
    result.imu.samples = imu != nullptr ? imu->imu.size() : 0;
    result.imu.imu_factors = slam.imu_factors();
    result.imu.rejected = slam.odometry().lio().imu_rejected();
    const std::string& why = slam.odometry().lio().last_imu_rejection();
    if (!why.empty() && result.imu.last_issue.empty()) result.imu.last_issue = why;
  }
  result.keyframe_bytes = slam.keyframe_bytes();
  result.place_bytes = slam.place_bytes();
  result.places = slam.places().size();
  result.archived = slam.archived_count();
  result.place_spacing_m = slam.place_spacing_m();
  result.place_thinnings = slam.place_thinnings();
  result.peak_rss_before_map_kb = peak_rss_kb();
  if (write_map) {
    semlio::SemanticMap map(be.map);
    slam.build_semantic_map(map);
    result.map_build_bytes = map.memory_bytes();
    result.map = map.cloud();
  }
  return result;
}

// Lidar-inertial run: the LIO around the front end `make` builds, IMU samples
// pushed up to each sweep's end. poses: the LIO's (inertial graph);
// odometry: the front end's scan-to-map poses. No back end, no map.
template <typename Make>
RunResult run_lio(Make make, const semlio::LidarInertialConfig& lc, const std::vector<semlio::ImuSample>& imu,
                  const std::vector<OxtsVelocity>& velocities, const FrameReader& frames,
                  std::size_t first, std::size_t last, bool quiet, const Checkpoint& checkpoint) {
  RunResult result;
  const std::size_t n = last - first + 1;
  result.reports.reserve(n);
  result.back_end.reserve(n);
  result.imu.used = true;
  result.imu.time_offset_s = lc.imu_time_offset_s;
  result.imu.samples = imu.size();
  semlio::LidarInertialOdometry lio(make, lc);
  const bool tty = !quiet && isatty(STDERR_FILENO) != 0;
  ImuFeed feed{imu, velocities, lc};
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = first; i <= last; ++i) {
    const double cpu_start_ms = thread_cpu_ms();
    semlio::Scan scan = frames.read(i, result.inputs);
    feed.feed(lio, scan.stamp_s);
    const semlio::LidarInertialReport r = lio.process(scan);
    result.reports.push_back(r.frame);
    result.optimised.push_back(r.T_map_lidar);
    result.odometry.push_back(r.frame.T_map_lidar);
    result.back_end.push_back({false, false, 0.0, r.frame.timings.total_ms, thread_cpu_ms() - cpu_start_ms});
    count_lio_frame(result.imu, r, i - first);
    if (tty) show_progress(frames.tool, i - first + 1, n, start);
    self_interrupt_after(i - first + 1);
    if (g_stop_requested != 0) {
      result.interrupted = true;
      break;
    }
    if ((i - first + 1) % kCheckpointEvery == 0 && i != last) checkpoint(result);
  }
  if (tty) std::fprintf(stderr, "\n");
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.ranks = lio.odometry().rank_histogram();
  result.keyframe_bytes = 0;
  result.imu.rejected = lio.imu_rejected();
  if (!lio.last_imu_rejection().empty() && result.imu.last_issue.empty()) result.imu.last_issue = lio.last_imu_rejection();
  return result;
}

inline void write_timings(JsonWriter& j, const semlio::StageTimings& t) {
  j.key("timings_ms").begin_object();
  j.field("preprocess", t.preprocess_ms).field("segment", t.segment_ms).field("features", t.features_ms);
  j.field("solve", t.solve_ms).field("scan_shapes", t.scan_shapes_ms).field("associate", t.associate_ms);
  j.field("linearize", t.linearize_ms).field("keyframe", t.keyframe_ms).field("map", t.map_ms).field("total", t.total_ms);
  j.end_object();
}


/// Refuses an OUT holding another run's outputs (unless `overwrite`, which
/// removes them), creates OUT and probes that files can be created in it --
/// all before the first frame, so a bad OUT costs nothing. Throws IoError.
inline void prepare_output_dir(const std::string& out, bool overwrite) {
  const fs::path dir(out);
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) {
    throw semlio::IoError(out + ": --out exists and is not a directory");
  }
  std::vector<std::string> found;
  for (const std::string& name : output_names()) {
    if (fs::exists(dir / name, ec)) found.push_back(name);
  }
  if (!found.empty()) {
    if (!overwrite) {
      std::string list;
      for (const std::string& f : found) list += (list.empty() ? "" : ", ") + f;
      throw semlio::IoError(out + ": holds another run's outputs (" + list +
                            "); pass --overwrite to replace them, or choose another --out");
    }
    for (const std::string& f : found) {
      if (!fs::remove(dir / f, ec) || ec) {
        throw semlio::IoError((dir / f).string() + ": cannot remove the previous run's output (" + ec.message() + ")");
      }
    }
  }
  fs::create_directories(dir, ec);
  if (ec) throw semlio::IoError(out + ": cannot create the output directory (" + ec.message() + ")");
  const fs::path probe = dir / ".semlio_write_probe";
  {
    std::ofstream p(probe);
    p << "probe\n";
    if (!p) throw semlio::IoError(out + ": cannot write into the output directory");
  }
  fs::remove(probe, ec);
}

/// Writes a file through `write(temporary_path)` and renames it to `path`
/// when complete, so that OUT never holds a truncated output.
template <typename Write>
void write_atomically(const fs::path& path, Write&& write) {
  const fs::path tmp = path.parent_path() / ("." + path.filename().string() + ".partial");
  write(tmp.string());
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) throw semlio::IoError(path.string() + ": cannot rename the finished output into place (" + ec.message() + ")");
}

/// Everything a run decided before its first frame.
struct RunContext {
  RunContext(const char* tool_name, const RunOptions& options, FrameSource& input)
      : tool(tool_name), opt(options), source(input) {}
  const char* tool = "semlio_run";
  const RunOptions& opt;
  FrameSource& source;
  semlio::PipelineSettings settings;
  BackEndSettings back_end;
  std::optional<SE3d> Tr;                      // outputs in KITTI's camera-0 frame when set
  std::optional<std::vector<SE3d>> gt_lidar;   // ground truth of the selected frames, re-based on the first
  std::size_t first = 0;
  std::size_t last = 0;
  bool use_imu = false;
  bool lio_back_end = false;
  bool use_labels = false;
  bool write_map = true;
  semlio::LidarInertialConfig lc;
  std::string imu_source;
  std::vector<std::pair<std::string, std::string>> sensor_facts;  // summary + report.json "sensor"
  std::optional<SE3d> T_imu_lidar;  // lidar -> IMU extrinsic given beside the data (sensor YAML), else the input's
  semlio::GeometricSegmenterConfig segmenter;  // --labels geometric; its sensor height follows the sensor profile
  std::string onnx_model;  // --labels onnx: the .onnx file the model card names
};

/// One pose per frame done: skipped frames interpolated by stamp, deskewed
/// frames posed at the sweep start.
struct FinalPoses {
  std::vector<SE3d> poses;
  std::vector<SE3d> poses_odom;
  std::vector<double> stamps;
  std::vector<std::size_t> keyframes;
};

inline FinalPoses final_poses(const RunContext& ctx, const RunResult& result) {
  FinalPoses f;
  const std::size_t n = result.reports.size();
  f.poses.assign(result.optimised.begin(), result.optimised.begin() + static_cast<long>(std::min(n, result.optimised.size())));
  f.poses_odom.assign(result.odometry.begin(), result.odometry.begin() + static_cast<long>(std::min(n, result.odometry.size())));
  f.poses.resize(n);
  f.poses_odom.resize(n);
  f.stamps.resize(n);
  std::vector<bool> processed(n);
  for (std::size_t i = 0; i < n; ++i) {
    f.stamps[i] = result.reports[i].stamp_s;
    processed[i] = result.reports[i].status != semlio::OdometryStatus::kSkipped;
    if (result.reports[i].keyframe) f.keyframes.push_back(i);
  }
  semlio::fill_skipped_poses(f.poses, f.stamps, processed);
  semlio::fill_skipped_poses(f.poses_odom, f.stamps, processed);
  if (ctx.settings.deskew.mode != semlio::DeskewMode::kNone) {
    // Deskewed frames are posed at their target time (default: mid-sweep);
    // outputs keep the meaning stamps have everywhere else: the sweep start.
    f.poses = semlio::poses_at_sweep_start(f.poses, f.stamps, ctx.settings.deskew.target, ctx.settings.deskew.sweep_period_s);
    f.poses_odom =
        semlio::poses_at_sweep_start(f.poses_odom, f.stamps, ctx.settings.deskew.target, ctx.settings.deskew.sweep_period_s);
  }
  return f;
}

/// Length of the path through the poses' positions [m].
inline double path_length_m(const std::vector<SE3d>& poses) {
  double len = 0.0;
  for (std::size_t i = 1; i < poses.size(); ++i) len += (poses[i].translation() - poses[i - 1].translation()).norm();
  return len;
}

/// Status name of frame i in report.json: the odometry's, or "missing" for a
/// frame whose scan file does not exist.
inline const char* frame_status(const RunResult& result, std::size_t i) {
  if (i < result.inputs.size() && result.inputs[i].missing) return "missing";
  return semlio::to_string(result.reports[i].status);
}

/// Writes every output for the frames in `result` (atomically). `run_status`:
/// "complete", "interrupted" or "running" (a checkpoint: no map, no summary).
inline void write_outputs(const RunContext& ctx, const RunResult& result, const char* run_status, bool print_summary) {
  const RunOptions& opt = ctx.opt;
  const std::size_t first = ctx.first;
  const std::size_t n = result.reports.size();
  const std::size_t last_done = n == 0 ? first : first + n - 1;
  const FinalPoses fp = final_poses(ctx, result);
  const fs::path out(opt.out);
  const bool final_write = std::string(run_status) != "running";
  const std::optional<SE3d>& Tr = ctx.Tr;

  write_atomically(out / "poses.txt", [&](const std::string& p) {
    semlio::io::write_kitti_poses(p, Tr ? semlio::io::lidar_to_camera(fp.poses, *Tr) : fp.poses);
  });
  write_atomically(out / "poses_tum.txt", [&](const std::string& p) {
    std::vector<semlio::io::StampedPose> tum(n);
    for (std::size_t i = 0; i < n; ++i) tum[i] = {fp.stamps[i], fp.poses[i]};
    semlio::io::write_tum_trajectory(p, tum);
  });
  write_atomically(out / "poses_odom.txt", [&](const std::string& p) {
    semlio::io::write_kitti_poses(p, Tr ? semlio::io::lidar_to_camera(fp.poses_odom, *Tr) : fp.poses_odom);
  });
  const bool map_written = final_write && ctx.write_map && (!ctx.use_imu || ctx.lio_back_end);
  if (map_written) {
    write_atomically(out / "map.ply", [&](const std::string& p) { semlio::io::write_ply(p, result.map); });
  }
  write_atomically(out / "keyframes.txt", [&](const std::string& p) {
    std::ofstream kf(p);
    kf.precision(9);
    for (const std::size_t i : fp.keyframes) kf << (first + i) << ' ' << std::fixed << fp.stamps[i] << '\n';
    if (!kf) throw semlio::IoError(p + ": write error");
  });

  // Evaluation against the selected frames' ground truth.
  std::optional<semlio::eval::AteReport> ate_all;
  std::optional<semlio::eval::AteReport> ate_kf;
  std::optional<semlio::eval::AteReport> ate_odom;
  std::optional<semlio::eval::KittiMetricReport> kitti;
  semlio::eval::EndPointError end_point;
  if (ctx.gt_lidar && n >= 1) {
    const std::vector<SE3d> gt(ctx.gt_lidar->begin(), ctx.gt_lidar->begin() + static_cast<long>(n));
    ate_all = semlio::eval::ate(gt, fp.poses);
    end_point = semlio::eval::end_point_error(gt, fp.poses);
    ate_odom = semlio::eval::ate(gt, fp.poses_odom);
    if (fp.keyframes.size() >= 3) ate_kf = semlio::eval::ate(gt, fp.poses, fp.keyframes);
    kitti = Tr ? semlio::eval::kitti_metric(semlio::io::lidar_to_camera(gt, *Tr), semlio::io::lidar_to_camera(fp.poses, *Tr))
               : semlio::eval::kitti_metric(gt, fp.poses);
  }

  const double gt_path_m =
      ctx.gt_lidar ? path_length_m(std::vector<SE3d>(ctx.gt_lidar->begin(), ctx.gt_lidar->begin() + static_cast<long>(n)))
                   : 0.0;
  std::vector<double> totals;
  std::vector<std::size_t> status_counts(8, 0);
  std::size_t missing = 0;
  std::size_t unreadable = 0;
  std::size_t baseline_fallbacks = 0;
  semlio::io::ReadStats dropped;
  for (std::size_t i = 0; i < n; ++i) {
    const auto& r = result.reports[i];
    baseline_fallbacks += r.baseline_fallback ? 1U : 0U;
    if (r.status != semlio::OdometryStatus::kSkipped) totals.push_back(result.back_end[i].total_ms);
    const InputFrame& in = result.inputs[i];
    if (in.missing) ++missing;
    else ++status_counts[static_cast<std::size_t>(r.status)];
    if (!in.error.empty() && !in.missing) ++unreadable;
    dropped.dropped_nonfinite += in.dropped.dropped_nonfinite;
    dropped.dropped_zero += in.dropped.dropped_zero;
  }
  const long peak_kb = peak_rss_kb();
  const bool loops_on = ctx.back_end.slam.loop_closure;
  const SourceFacts& facts = ctx.source.facts();

  write_atomically(out / "report.json", [&](const std::string& path) {
    std::ofstream os(path);
    JsonWriter j(os);
    j.begin_object();
    j.field("schema", "semlio_run/1");
    j.field("tool", ctx.tool).field("status", run_status);
    j.key("input").begin_object();
    j.field("format", facts.format).field("path", facts.path);
    for (const auto& [k, v] : facts.decided) j.field(k.c_str(), v);
    j.field("ground_truth", ctx.source.ground_truth_source());
    j.end_object();
    if (!ctx.sensor_facts.empty()) {
      j.key("sensor").begin_object();
      for (const auto& [k, v] : ctx.sensor_facts) j.field(k.c_str(), v);
      j.end_object();
    }
    j.field("sequence", facts.path).field("preset", opt.preset).field("labels", ctx.use_labels ? opt.labels : "none");
    if (opt.labels == "onnx") j.field("label_model_card", opt.model).field("label_model", ctx.onnx_model);
    j.field("first_frame", static_cast<long long>(first)).field("last_frame", static_cast<long long>(last_done));
    j.field("frames_requested", static_cast<long long>(ctx.last - ctx.first + 1));
    j.field("frames_done", n);
    j.field("frame", Tr ? "camera0" : "lidar");
    j.field("kitti_vertical_correction", ctx.settings.odometry.kitti_vertical_correction);
    j.field("keyframe_count", fp.keyframes.size());
    j.field("unreadable_frames", unreadable).field("missing_frames", missing);
    j.key("dropped_points").begin_object();
    j.field("nonfinite", dropped.dropped_nonfinite).field("at_origin", dropped.dropped_zero).end_object();
    j.field("loop_closure", loops_on);
    j.field("wall_time_s", result.wall_s);
    j.key("frame_time_ms").begin_object();
    j.field("median", percentile(totals, 0.5)).field("p95", percentile(totals, 0.95));
    j.field("mean", totals.empty() ? 0.0 : std::accumulate(totals.begin(), totals.end(), 0.0) / static_cast<double>(totals.size()));
    j.field("max", percentile(totals, 1.0)).end_object();
    j.key("status_counts").begin_object();
    for (std::size_t s = 0; s < status_counts.size(); ++s) {
      j.field(semlio::to_string(static_cast<semlio::OdometryStatus>(s)), status_counts[s]);
    }
    j.field("missing", missing);
    j.end_object();
    j.field("baseline_fallback_frames", baseline_fallbacks);
    j.key("association_rank_histogram").begin_array();
    for (std::size_t r = 1; r < result.ranks.size(); ++r) j.value(static_cast<unsigned long long>(result.ranks[r]));
    j.end_array();
    if (ate_all) {
      j.key("evaluation").begin_object();
      const auto ate_json = [&j](const char* name, const semlio::eval::AteReport& a) {
        j.key(name).begin_object();
        j.field("count", a.count).field("rmse_m", a.rmse_m).field("mean_m", a.mean_m);
        j.field("median_m", a.median_m).field("max_m", a.max_m).end_object();
      };
      ate_json("ate_all_frames", *ate_all);
      if (ate_kf) ate_json("ate_keyframes", *ate_kf);
      ate_json("ate_all_frames_odometry", *ate_odom);
      j.field("path_length_m", path_length_m(fp.poses)).field("ground_truth_path_length_m", gt_path_m);
      j.key("end_point").begin_object();
      j.field("translation_m", end_point.translation_m).field("rotation_deg", end_point.rotation_deg).end_object();
      j.key("kitti").begin_object();
      j.field("segments", kitti->segment_count).field("translation_error_pct", kitti->translation_error_pct);
      j.field("rotation_error_deg_per_m", kitti->rotation_error_deg_per_m);
      j.field("rotation_error_deg_per_100m", kitti->rotation_error_deg_per_100m).end_object();
      j.end_object();
    }
    j.key("loop").begin_object();
    j.field("enabled", loops_on).field("detector", ctx.back_end.loop_detector);
    const semlio::LoopStats& ls = result.loop_stats;
    j.field("queries", ls.queries).field("candidates", ls.candidates).field("verified", ls.verified);
    j.field("accepted", ls.accepted).field("rejected", ls.rejected());
    j.key("rejected_by_reason").begin_object();
    j.field("empty_submap", ls.rejected_empty).field("not_converged", ls.rejected_not_converged);
    j.field("degenerate", ls.rejected_degenerate).field("poor_fitness", ls.rejected_fitness);
    j.field("few_inliers", ls.rejected_inliers).field("large_correction", ls.rejected_correction).end_object();
    j.field("detect_ms", ls.detect_ms).field("verify_ms", ls.verify_ms);
    j.key("graph").begin_object();
    j.field("nodes", result.graph_nodes).field("factors", result.graph_factors);
    j.field("solve_ms_total", result.graph_ms).field("full_solve_ms_total", result.graph_full_ms).end_object();
    j.key("loops").begin_array();
    for (const semlio::SlamLoop& l : result.loops) {
      j.begin_object();
      j.field("from_frame", static_cast<long long>(first + l.from_frame));
      j.field("to_frame", static_cast<long long>(first + l.to_frame));
      j.field("from_keyframe", l.from_keyframe).field("to_keyframe", l.to_keyframe);
      j.field("fitness_m", l.fitness_m).field("inlier_ratio", l.inlier_ratio).field("correction_m", l.correction_m);
      j.field("solve_ms", l.solve_ms).field("solve_iterations", l.solve.iterations);
      j.field("solve_status", semlio::to_string(l.solve.status));
      j.field("chi2_before", l.solve.initial_chi2).field("chi2_after", l.solve.final_chi2);
      j.end_object();
    }
    j.end_array();
    j.end_object();
    j.key("memory").begin_object();
    j.field("peak_rss_mb", static_cast<double>(peak_kb) / 1024.0);
    j.field("keyframe_store_mb", static_cast<double>(result.keyframe_bytes) / (1024.0 * 1024.0));
    j.field("keyframe_store_bytes_per_keyframe",
            fp.keyframes.empty() ? 0.0 : static_cast<double>(result.keyframe_bytes) / static_cast<double>(fp.keyframes.size()));
    constexpr double kMiB = 1024.0 * 1024.0;
    const semlio::SlamConfig& sc = ctx.back_end.slam;
    j.field("recent_keyframes", sc.max_keyframe_clouds);
    j.field("place_store_mb", static_cast<double>(result.place_bytes) / kMiB);
    j.field("place_ceiling_mb", static_cast<double>(sc.max_keyframe_clouds == 0 ? 0 : sc.max_place_bytes) / kMiB);
    j.field("places", result.places).field("archived_keyframes", result.archived);
    j.field("place_spacing_m", result.place_spacing_m).field("place_thinnings", result.place_thinnings);
    j.field("peak_rss_before_map_mb", static_cast<double>(result.peak_rss_before_map_kb) / 1024.0);
    j.field("map_build_mb", static_cast<double>(result.map_build_bytes) / kMiB);
    j.key("trace").begin_array();
    for (const RunResult::MemorySample& m : result.memory_trace) {
      j.begin_object();
      j.field("frames", m.frame).field("keyframe_store_mb", static_cast<double>(m.store_bytes) / kMiB);
      j.field("place_store_mb", static_cast<double>(m.place_bytes) / kMiB);
      j.field("rss_mb", static_cast<double>(m.rss_kb) / 1024.0);
      j.field("heap_live_mb", static_cast<double>(m.heap_live_bytes) / kMiB).end_object();
    }
    j.end_array();
    j.end_object();
    if (ctx.use_imu) {
      const ImuRunFacts& f = result.imu;
      j.key("imu").begin_object();
      j.field("source", ctx.imu_source).field("samples", f.samples).field("time_offset_s", f.time_offset_s);
      j.field("deskew", ctx.lc.deskew ? "imu" : "off").field("velocity_hint", opt.velocity_hint);
      j.field("initialized_at_frame",
              static_cast<long long>(f.initialized_at < 0 ? -1 : f.initialized_at + static_cast<long>(first)));
      j.field("imu_predicted_frames", f.imu_predicted).field("fallback_frames", f.fallbacks);
      j.field("imu_deskewed_frames", f.imu_deskewed).field("rejected_samples", f.rejected);
      j.field("last_issue", f.last_issue).field("graph_imu_factors", f.imu_factors);
      j.end_object();
    }
    if (map_written) {
      j.key("map").begin_object();
      j.field("points", result.map.size()).field("leaf_size_m", ctx.back_end.map.leaf_size_m);
      j.field("static_only", ctx.back_end.map.drop_dynamic).end_object();
    }
    j.key("frames").begin_array();
    for (std::size_t i = 0; i < n; ++i) {
      const auto& r = result.reports[i];
      const InputFrame& in = result.inputs[i];
      j.begin_object();
      j.field("index", static_cast<long long>(first + i)).field("stamp_s", r.stamp_s);
      j.field("status", frame_status(result, i)).field("keyframe", r.keyframe);
      j.field("points", r.points).field("corners", r.corners).field("surfaces", r.surfaces);
      j.field("corner_matches", r.corner_matches).field("surface_matches", r.surface_matches);
      if (std::isfinite(r.corner_label_kappa)) j.field("corner_label_kappa", r.corner_label_kappa);
      if (std::isfinite(r.surface_label_kappa)) j.field("surface_label_kappa", r.surface_label_kappa);
      j.field("iterations", r.solve.iterations).field("solver_status", semlio::to_string(r.solve.status));
      j.field("degenerate_directions", r.solve.degenerate_directions).field("baseline_fallback", r.baseline_fallback);
      j.array_field("eigenvalues", std::vector<double>(r.solve.eigenvalues.data(), r.solve.eigenvalues.data() + 6));
      // Per-axis observability: the normalised eigenvalues the degeneracy
      // flag tests (solve/gauss_newton.hpp) and the weakest direction
      // [rho; phi] (eigenvectors' first column).
      j.array_field("normalized_eigenvalues", std::vector<double>(r.solve.normalized_eigenvalues.data(),
                                                                  r.solve.normalized_eigenvalues.data() + 6));
      const Eigen::Matrix<double, 6, 1> weakest = r.solve.eigenvectors.col(0);
      j.array_field("weakest_direction", std::vector<double>(weakest.data(), weakest.data() + 6));
      write_timings(j, r.timings);
      j.field("backend_ms", result.back_end[i].backend_ms).field("total_ms", result.back_end[i].total_ms);
      j.field("cpu_ms", result.back_end[i].cpu_ms);
      j.field("loop_checked", result.back_end[i].loop_checked).field("loop_closed", result.back_end[i].loop_closed);
      if (ctx.use_imu && i < result.imu.fallback_frame.size()) j.field("imu_fallback", result.imu.fallback_frame[i] != 0);
      if (in.dropped.dropped() > 0) {
        j.field("dropped_nonfinite", in.dropped.dropped_nonfinite).field("dropped_at_origin", in.dropped.dropped_zero);
      }
      if (!in.error.empty()) j.field("input_error", in.error);
      j.end_object();
    }
    j.end_array();
    j.end_object();
    os << '\n';
    os.flush();
    if (!os) throw semlio::IoError(path + ": write error");
  });

  if (!print_summary) return;
  std::printf("%s  %s (%s)  preset=%s labels=%s  frames %zu..%zu (%zu)%s\n", ctx.tool, facts.path.c_str(),
              facts.format.c_str(), opt.preset.c_str(), ctx.use_labels ? opt.labels.c_str() : "none", first, last_done, n,
              result.interrupted ? "  INTERRUPTED" : "");
  for (const auto& [k, v] : facts.decided) std::printf("  %-19s %s\n", k.c_str(), v.c_str());
  for (const auto& [k, v] : ctx.sensor_facts) std::printf("  sensor %-12s %s\n", k.c_str(), v.c_str());
  std::printf("  keyframes           %zu\n", fp.keyframes.size());
  std::printf("  frame time [ms]     median %.1f  p95 %.1f  (%.1f Hz overall)\n", percentile(totals, 0.5),
              percentile(totals, 0.95), static_cast<double>(n) / std::max(result.wall_s, 1e-9));
  std::printf("  statuses           ");
  for (std::size_t s = 0; s < status_counts.size(); ++s) {
    if (status_counts[s] > 0) std::printf(" %s=%zu", semlio::to_string(static_cast<semlio::OdometryStatus>(s)), status_counts[s]);
  }
  if (missing > 0) std::printf(" missing=%zu", missing);
  if (baseline_fallbacks > 0) std::printf("  (solved again as baseline: %zu)", baseline_fallbacks);
  std::printf("\n");
  if (missing > 0) {
    std::printf("  missing frames     ");
    std::size_t shown = 0;
    for (std::size_t i = 0; i < n && shown < 20; ++i) {
      if (result.inputs[i].missing) {
        std::printf(" %zu", first + i);
        ++shown;
      }
    }
    std::printf("%s (empty scans on the prediction)\n", missing > shown ? " ..." : "");
  }
  if (unreadable > 0) {
    std::printf("  unreadable frames   %zu, processed as empty scans (input_error in report.json)\n", unreadable);
  }
  if (dropped.dropped() > 0) {
    std::printf("  dropped points      %zu NaN/Inf, %zu at (0,0,0) (per frame in report.json)\n",
                dropped.dropped_nonfinite, dropped.dropped_zero);
  }
  if (loops_on) {
    std::printf("  loops               %zu accepted of %zu verified (%zu candidates, detector %s)\n",
                result.loop_stats.accepted, result.loop_stats.verified, result.loop_stats.candidates,
                ctx.back_end.loop_detector.c_str());
  }
  if (ctx.use_imu) {
    const ImuRunFacts& f = result.imu;
    std::printf("  IMU (%s)  %zu samples, offset %.6f s, deskew %s; initialised at frame %ld, "
                "IMU-predicted frames %zu, fallbacks %zu, rejected samples %zu\n",
                ctx.imu_source.c_str(), f.samples, f.time_offset_s, ctx.lc.deskew ? "imu" : "off",
                f.initialized_at < 0 ? -1L : f.initialized_at + static_cast<long>(first), f.imu_predicted, f.fallbacks,
                f.rejected);
    if (!f.last_issue.empty()) std::printf("  last IMU issue      %s\n", f.last_issue.c_str());
  }
  std::printf("  memory              peak RSS %.0f MB (%.0f MB before the map), keyframe store %.1f MB "
              "(places %.1f MB: %zu places at %.1f m, %zu archived)\n",
              static_cast<double>(peak_kb) / 1024.0, static_cast<double>(result.peak_rss_before_map_kb) / 1024.0,
              static_cast<double>(result.keyframe_bytes) / (1024.0 * 1024.0),
              static_cast<double>(result.place_bytes) / (1024.0 * 1024.0), result.places, result.place_spacing_m,
              result.archived);
  if (ate_all) {
    if (loops_on) std::printf("  ATE RMSE [m]        %.3f odometry only\n", ate_odom->rmse_m);
    std::printf("  ATE RMSE [m]        %.3f all frames", ate_all->rmse_m);
    if (ate_kf) std::printf(", %.3f keyframes", ate_kf->rmse_m);
    std::printf("\n  KITTI metric        %.3f %%  %.4f deg/100m  (%zu segments)\n", kitti->translation_error_pct,
                kitti->rotation_error_deg_per_100m, kitti->segment_count);
    std::printf("  path length [m]     %.2f (ground truth %.2f)\n", path_length_m(fp.poses), gt_path_m);
    std::printf("  end point error     %.3f m, %.3f deg (last frame relative to the first, no alignment)\n",
                end_point.translation_m, end_point.rotation_deg);
  } else {
    std::printf("  no ground truth found: not evaluated\n");
  }
  std::printf("  wrote %s/{poses.txt,poses_odom.txt,poses_tum.txt,keyframes.txt,report.json%s} (%s frame)\n",
              opt.out.c_str(), map_written ? ",map.ply" : "", Tr ? "camera-0" : "lidar");
}

/// Checks that every ground-truth pose is finite with an orthonormal rotation.
inline void check_ground_truth(const std::vector<SE3d>& gt, const std::string& where) {
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const Eigen::Matrix4d M = gt[i].matrix();
    const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
    if (!M.allFinite() || (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-3 || R.determinant() < 0.0) {
      throw semlio::ValueError(where + ": ground-truth pose " + std::to_string(i) +
                               " is not finite or its rotation is not orthonormal");
    }
  }
}

/// Parses t_imu - t_lidar from --imu-time-offset (a number of seconds).
inline double parse_time_offset(const std::string& text) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument("not a finite number");
    return v;
  } catch (const std::exception&) {
    throw semlio::ConfigError("--imu-time-offset must be auto or a finite number of seconds, got '" + text + "'");
  }
}

/// Settings a tool decided from its input before the common run (sensor
/// profile, ring method, ...): applied to the pipeline settings after the
/// defaults and before the user's YAML.
using SettingsHook = std::function<void(FrameSource&, RunContext&)>;

/// The whole run: options checked, OUT prepared, settings and ground truth
/// validated before the first frame; the odometry; the outputs. Returns the
/// process exit status (0, 1 on an error, 2 on a usage error, 130 when
/// interrupted). Errors are printed with the tool's name.
int run_tool(const char* tool, const RunOptions& opt, const std::function<std::unique_ptr<FrameSource>()>& open,
             const SettingsHook& sensor_settings = {});

#if defined(SEMLIO_RUN_TOOL_DEFINITION)
// Defined in one translation unit, odometry_tool.cpp, which semlio_run and
// semlio_kitti both link: the odometry's instantiations are the longest
// compile of the tools, and this way it runs once.
int run_tool(const char* tool, const RunOptions& opt, const std::function<std::unique_ptr<FrameSource>()>& open,
             const SettingsHook& sensor_settings) {
  if (opt.last < -1) {
    std::cerr << tool << ": --last " << opt.last << " is not a frame (use -1 for the last frame)\n";
    return 2;
  }
  if (opt.first < 0) {
    std::cerr << tool << ": --first " << opt.first << " is not a frame (frames count from 0)\n";
    return 2;
  }
  try {
    // --labels onnx: the model card and the network are checked before OUT is touched.
    std::optional<SegmenterChoice::Variant> network;
    if (opt.labels == "onnx") {
      if (opt.model.empty()) {
        throw semlio::ConfigError("--labels onnx needs --model CARD.yaml (the network's model card, docs/guide.md)");
      }
#if SEMLIO_HAVE_ONNX
      network.emplace(semlio::OnnxSegmenter(load_model_card_yaml(opt.model)));
#else
      throw semlio::ConfigError("--labels onnx: this build has no ONNX segmenter (it needs OpenCV's dnn module, "
                                "Debian libopencv-dnn-dev, when semlio is configured)");
#endif
    } else if (!opt.model.empty()) {
      std::cerr << tool << ": warning: --model is only used with --labels onnx\n";
    }
    prepare_output_dir(opt.out, opt.overwrite);
    const std::unique_ptr<FrameSource> source_ptr = open();
    FrameSource& source = *source_ptr;
    if (opt.labels != "none" && opt.labels != "geometric" && opt.labels != "onnx" && !source.has_labels()) {
      std::cerr << tool << ": warning: " << source.facts().path << " has no " << opt.labels
                << " labels; running without labels\n";
    }
    const long n_frames = static_cast<long>(source.size());
    if (n_frames == 0) throw semlio::FormatError(source.facts().path + ": no frames to process");
    const long last = opt.last < 0 ? n_frames - 1 : std::min(opt.last, n_frames - 1);
    if (opt.first > last) {
      std::cerr << tool << ": --first " << opt.first << " / --last " << opt.last << " select no frame of " << n_frames
                << "\n";
      return 2;
    }
    const auto first = static_cast<std::size_t>(opt.first);
    const auto last_u = static_cast<std::size_t>(last);

    RunContext ctx(tool, opt, source);
#if SEMLIO_HAVE_ONNX
    if (network) ctx.onnx_model = std::get<semlio::OnnxSegmenter>(*network).card().model_path;
#endif
    ctx.first = first;
    ctx.last = last_u;
    ctx.Tr = source.T_cam0_lidar();
    const bool simulated = source.simulated();

    semlio::PipelineSettings& settings = ctx.settings;
    settings.odometry.kitti_vertical_correction = source.kitti_scans();
    // The simulator's sweeps start facing backwards (KITTI raw: forwards); both
    // spin clockwise. Only used when deskew is switched on.
    if (simulated) settings.deskew.start_azimuth_rad = std::numbers::pi;
    if (sensor_settings) sensor_settings(source, ctx);
    BackEndSettings& back_end = ctx.back_end;
    back_end.slam.loop_closure = false;  // the odometry comparison is the main job
    if (!opt.config.empty()) load_settings_yaml(opt.config, settings, &back_end);
    if (!opt.loop.empty()) back_end.slam.loop_closure = opt.loop == "on";
    if (!opt.loop_detector.empty()) back_end.loop_detector = opt.loop_detector;
    if (back_end.loop_detector != "radius" && back_end.loop_detector != "scancontext") {
      throw semlio::ConfigError(opt.config + ": slam.loop_detector must be radius or scancontext, got '" +
                                back_end.loop_detector + "'");
    }
    if (opt.map_static) back_end.map.drop_dynamic = true;
    back_end.slam.validate();
    ctx.write_map = opt.map == "on";
    if (opt.kitti_correction != "auto") settings.odometry.kitti_vertical_correction = opt.kitti_correction == "on";
    if (opt.deskew == "on") settings.deskew.mode = semlio::DeskewMode::kConstantVelocity;
    if (opt.deskew == "off") settings.deskew.mode = semlio::DeskewMode::kNone;
    ctx.use_imu = opt.imu != "none";
    // With an IMU, directions the solver finds weak stay at the IMU
    // prediction instead of following the lidar's weak solution (as
    // semlio_lio). Overrides the YAML's solver setting.
    if (ctx.use_imu) settings.odometry.solver.reset_weak_directions = true;
    ctx.lio_back_end = ctx.use_imu && back_end.slam.loop_closure;

    // Ground truth: read and checked now, not after the run.
    if (std::optional<std::vector<SE3d>> gt = source.ground_truth_lidar()) {
      if (gt->size() != source.size()) {
        throw semlio::ValueError(source.ground_truth_source() + ": has " + std::to_string(gt->size()) +
                                 " poses but the input has " + std::to_string(source.size()) + " frames");
      }
      check_ground_truth(*gt, source.ground_truth_source());
      std::vector<SE3d> sel(gt->begin() + static_cast<long>(first), gt->begin() + static_cast<long>(last_u) + 1);
      const SE3d base = sel.front().inverse();
      for (auto& T : sel) T = base * T;
      ctx.gt_lidar = std::move(sel);
      // KITTI odometry's own ground truth (dataset/poses/NN.txt) is in the
      // camera-0 frame: without Tr it would be compared in the wrong frame.
      const fs::path gt_file(source.ground_truth_source());
      if (!ctx.Tr && source.facts().format == "kitti" && gt_file.parent_path().filename() == "poses") {
        std::cerr << tool << ": warning: " << source.ground_truth_source()
                  << " is evaluated in the lidar frame: the calibration has no Tr (KITTI odometry ground truth is "
                     "in the camera-0 frame; pass --calib with Tr)\n";
      }
    }

    // IMU: samples, extrinsic, clock offset; deskew moves into the LIO.
    ImuInput imu_in;
    if (ctx.use_imu) {
      imu_in = source.imu();
      if (imu_in.samples.empty()) {
        throw semlio::IoError(source.facts().path + ": --imu " + opt.imu +
                              " needs an IMU stream (a KITTI raw oxts/ folder, a bag's sensor_msgs/Imu topic); "
                              "the input has none");
      }
      if (ctx.T_imu_lidar) imu_in.T_imu_lidar = ctx.T_imu_lidar;
      if (!imu_in.T_imu_lidar) {
        throw semlio::ConfigError(source.facts().path +
                                  ": no lidar -> IMU extrinsic (calib.txt Tr_imu_velo, KITTI raw calib_imu_to_velo.txt "
                                  "or the sensor YAML's extrinsics); --imu needs it");
      }
      if (opt.velocity_hint != "oxts") imu_in.velocities.clear();
      ctx.imu_source = imu_in.source;
      ctx.lc.T_imu_lidar = *imu_in.T_imu_lidar;
      ctx.lc.imu_time_offset_s = 0.0;  // the preintegration settings (ctx.lc.imu) may come from the sensor YAML
      if (opt.imu_time_offset != "auto") ctx.lc.imu_time_offset_s = parse_time_offset(opt.imu_time_offset);
      ctx.lc.deskew = settings.deskew.mode != semlio::DeskewMode::kNone;
      ctx.lc.sweep_period_s = settings.deskew.sweep_period_s;
      ctx.lc.frame_period_s = settings.deskew.frame_period_s;
      ctx.lc.point_times = settings.deskew.point_time_config();
      settings.deskew.mode = semlio::DeskewMode::kNone;  // the LIO deskews (to the sweep start) before the front end
    }

    const bool geometric = opt.labels == "geometric";
    ctx.use_labels = geometric || network || (opt.labels != "none" && source.has_labels());
    const FrameReader frames{source, opt.bad_scans == "skip", tool, settings.deskew.frame_period_s};
    const Checkpoint checkpoint = [&ctx](const RunResult& partial) { write_outputs(ctx, partial, "running", false); };
    if (ctx.use_imu && opt.imu_time_offset == "auto") {
      // Inputs that know their stamps up front (times.txt from 0 beside an
      // OXTS record with a date) get the offset between the two clocks; a
      // bag's topics share one clock.
      const std::optional<double> t_first = source.stamp_hint(first);
      const std::optional<double> t_zero = source.stamp_hint(0);
      if (t_first && t_zero) ctx.lc.imu_time_offset_s = auto_imu_time_offset(imu_in.samples, *t_first, *t_zero);
    }
    std::signal(SIGINT, request_stop);
    std::signal(SIGTERM, request_stop);
    RunResult result;
    const auto run_preset = [&](auto segmenter) {
      const semlio::LidarInertialConfig& lc = ctx.lc;
      if (ctx.lio_back_end) {
        ImuFeed feed{imu_in.samples, imu_in.velocities, lc};
        return opt.preset == "baseline"
                   ? run(semlio::LidarInertialFrontEnd([&] { return semlio::make_baseline_odometry(segmenter, settings); }, lc),
                         back_end, ctx.write_map, frames, first, last_u, opt.quiet, checkpoint, &feed)
                   : run(semlio::LidarInertialFrontEnd([&] { return semlio::make_full_odometry(segmenter, settings); }, lc),
                         back_end, ctx.write_map, frames, first, last_u, opt.quiet, checkpoint, &feed);
      }
      if (ctx.use_imu) {
        return opt.preset == "baseline"
                   ? run_lio([&] { return semlio::make_baseline_odometry(segmenter, settings); }, lc, imu_in.samples,
                             imu_in.velocities, frames, first, last_u, opt.quiet, checkpoint)
                   : run_lio([&] { return semlio::make_full_odometry(segmenter, settings); }, lc, imu_in.samples,
                             imu_in.velocities, frames, first, last_u, opt.quiet, checkpoint);
      }
      return opt.preset == "baseline"
                 ? run(semlio::make_baseline_odometry(segmenter, settings), back_end, ctx.write_map, frames, first, last_u,
                       opt.quiet, checkpoint)
                 : run(semlio::make_full_odometry(segmenter, settings), back_end, ctx.write_map, frames, first, last_u,
                       opt.quiet, checkpoint);
    };
    result = run_preset(SegmenterChoice(network            ? std::move(*network)
                                        : geometric        ? SegmenterChoice::Variant(semlio::GeometricSegmenter(ctx.segmenter))
                                        : ctx.use_labels ? SegmenterChoice::Variant(semlio::ScanLabels{})
                                                         : SegmenterChoice::Variant(semlio::NoLabels{})));
    write_outputs(ctx, result, result.interrupted ? "interrupted" : "complete", true);
    return result.interrupted ? 130 : 0;
  } catch (const semlio::Error& e) {
    std::cerr << tool << ": " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << tool << ": unexpected error: " << e.what() << "\n";
    return 1;
  }
}

#endif  // SEMLIO_RUN_TOOL_DEFINITION

}  // namespace semlio_examples
