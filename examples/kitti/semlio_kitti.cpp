// semlio_kitti: runs the odometry (and optionally the back end: pose graph +
// loop closure) on a KITTI-layout sequence directory (real KITTI odometry /
// SemanticKITTI, or a semlio_simulate drive) and writes the trajectory
// (optimised and odometry-only), keyframes, the semantic map and a JSON
// report; evaluates against ground truth when one is found. See the README
// ("semlio_kitti") for options and outputs.
//
// --imu oxts: lidar-inertial odometry (pipeline/lidar_inertial.hpp) with the
// sequence's KITTI raw oxts/ folder (a semlio_simulate drive writes one) and
// Tr_imu_velo from calib.txt; deskew (YAML deskew.mode or --deskew on) is
// then the LIO's IMU deskew to the sweep start. --imu none (default): the
// lidar-only pipeline as before. --imu oxts --loop on: the LIO is the front
// end of the keyframe back end with inertial states (Slam with a
// KeyframeInertialGraph: IMU factors between keyframes, loops).

#include <CLI/CLI.hpp>
#include <unistd.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numeric>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include <semlio/eval/ate.hpp>
#include <semlio/eval/kitti_metric.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/kitti_sequence.hpp>
#include <semlio/io/ply.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/io/oxts.hpp>
#include <semlio/pipeline/interpolate.hpp>
#include <semlio/pipeline/lidar_inertial.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/pipeline/slam.hpp>
#include <semlio/segment/geometric_segmenter.hpp>
#include <semlio/segment/scan_labels.hpp>

#include "imu_oxts.hpp"
#include "json_writer.hpp"
#include "segmenter_choice.hpp"
#include "settings_yaml.hpp"

namespace fs = std::filesystem;
using semlio::SE3d;

namespace {

struct Options {
  std::string sequence;
  std::string gt;
  std::string calib;
  std::string labels = "labels";  // labels|predictions|geometric|none
  std::string preset = "full";    // baseline|full
  std::string config;
  std::string kitti_correction = "auto";  // on|off|auto
  long first = 0;
  long last = -1;
  std::string out;
  bool quiet = false;
  std::string loop;           // on|off; empty = the YAML's slam.loop_closure (default off)
  std::string loop_detector;  // radius|scancontext; empty = the YAML's (default radius)
  bool map_static = false;    // drop movable classes from map.ply
  std::string map = "on";     // write map.ply
  std::string imu = "none";   // none|oxts
  std::string deskew;         // on|off; empty = the YAML's deskew.mode
  std::string imu_time_offset = "auto";  // t_imu = t_lidar + offset [s], or auto
  std::string velocity_hint = "oxts";    // oxts|none: INS velocity while the LIO initialises
  std::string bad_scans = "skip";        // skip|stop: an unreadable frame is an empty scan, or ends the run
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
void count_lio_frame(ImuRunFacts& f, const semlio::LidarInertialReport& r, std::size_t frame) {
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
  const std::vector<semlio_examples::OxtsVelocity>& velocities;
  const semlio::LidarInertialConfig& lc;
  std::size_t next = 0;    // next sample to push
  std::size_t next_v = 0;  // next velocity to push

  // Pushes everything up to the sweep's end (IMU clock) into `sink`.
  template <typename Sink>
  void feed(Sink& sink, double scan_stamp_s) {
    const double until = scan_stamp_s + lc.imu_time_offset_s + lc.sweep_period_s + 1e-6;
    while (next < imu.size() && imu[next].stamp_s <= until) sink.push_imu(imu[next++]);
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
  std::vector<std::string> input_errors;  // per frame: why its files could not be read (empty: read fine)
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
};

// Reads the frames of a run. With --bad-scans skip a frame whose files cannot
// be read (empty, truncated or missing scan; bad labels) becomes an empty
// scan at its stamp -- the odometry reports too_few_features and keeps going
// on its prediction -- and the reason goes to stderr and report.json; with
// stop the error ends the run (exit 1), as it did before the option existed.
struct FrameReader {
  const semlio::io::KittiSequence& seq;
  bool skip_bad = true;

  semlio::Scan read(std::size_t i, RunResult& result) const {
    std::string error;
    semlio::Scan scan = skip_bad ? seq.read_or_empty(i, error) : seq.read(i);
    if (!error.empty()) std::cerr << "\nsemlio_kitti: warning: frame " << i << " processed as an empty scan: " << error << "\n";
    result.input_errors.push_back(std::move(error));
    return scan;
  }
};

// CPU time of the calling thread [ms]: unlike wall time it does not grow
// when other processes share the machine, so long runs stay comparable.
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// Peak (VmHWM) or current (VmRSS) resident set size [kB] from
// /proc/self/status; 0 when unknown.
long status_kb(const char* field) {
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
long peak_rss_kb() { return status_kb("VmHWM:"); }
// Bytes the allocator has handed out and not got back (live heap + mmapped
// blocks): tells live growth from fragmentation in the resident set.
std::size_t heap_live_bytes() {
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  const struct mallinfo2 mi = mallinfo2();
  return mi.uordblks + mi.hblkhd;
#else
  return 0;
#endif
}
long rss_kb() { return status_kb("VmRSS:"); }
constexpr std::size_t kMemoryTraceEvery = 250;

// Terminal progress line (frame i/N, Hz, ETA), refreshed every 5 frames.
void show_progress(std::size_t done, std::size_t n, std::chrono::steady_clock::time_point start) {
  if (done % 5 != 0 && done != n) return;
  const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double hz = static_cast<double>(done) / std::max(el, 1e-9);
  std::fprintf(stderr, "\r[semlio_kitti] frame %zu/%zu  %.1f Hz  ETA %.0f s   ", done, n, hz,
               static_cast<double>(n - done) / hz);
}

double percentile(std::vector<double> v, double q) {
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
RunResult run(Odometry odom, const semlio_examples::BackEndSettings& be, bool write_map,
              const FrameReader& frames, std::size_t first, std::size_t last, bool quiet,
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
    semlio::Scan scan = frames.read(i, result);
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
    if (tty) show_progress(done, n, start);
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
                  const std::vector<semlio_examples::OxtsVelocity>& velocities, const FrameReader& frames,
                  std::size_t first, std::size_t last, bool quiet) {
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
    semlio::Scan scan = frames.read(i, result);
    feed.feed(lio, scan.stamp_s);
    const semlio::LidarInertialReport r = lio.process(scan);
    result.reports.push_back(r.frame);
    result.optimised.push_back(r.T_map_lidar);
    result.odometry.push_back(r.frame.T_map_lidar);
    result.back_end.push_back({false, false, 0.0, r.frame.timings.total_ms, thread_cpu_ms() - cpu_start_ms});
    count_lio_frame(result.imu, r, i - first);
    if (tty) show_progress(i - first + 1, n, start);
  }
  if (tty) std::fprintf(stderr, "\n");
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.ranks = lio.odometry().rank_histogram();
  result.keyframe_bytes = 0;
  result.imu.rejected = lio.imu_rejected();
  if (!lio.last_imu_rejection().empty() && result.imu.last_issue.empty()) result.imu.last_issue = lio.last_imu_rejection();
  return result;
}

void write_timings(semlio_examples::JsonWriter& j, const semlio::StageTimings& t) {
  j.key("timings_ms").begin_object();
  j.field("preprocess", t.preprocess_ms).field("segment", t.segment_ms).field("features", t.features_ms);
  j.field("solve", t.solve_ms).field("scan_shapes", t.scan_shapes_ms).field("associate", t.associate_ms);
  j.field("linearize", t.linearize_ms).field("keyframe", t.keyframe_ms).field("map", t.map_ms).field("total", t.total_ms);
  j.end_object();
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"semlio_kitti: semantic lidar odometry (with --loop on: + pose graph and loop closure) on a "
               "KITTI-layout sequence"};
  app.footer(
      "Outputs in OUT/: poses.txt (one pose per frame; the loop-closed trajectory with --loop on, else the odometry),\n"
      "poses_odom.txt (odometry only), poses_tum.txt (poses.txt in TUM format, lidar frame), keyframes.txt,\n"
      "map.ply (semantic map: keyframe clouds at their optimised poses, 0.3 m voxels, majority label,\n"
      "SemanticKITTI colours) and report.json (statistics, loops, memory, evaluation when ground truth is found).");
  app.add_option("--sequence", opt.sequence, "sequence directory (velodyne/, labels/, calib.txt, times.txt)")
      ->required();
  app.add_option("--gt", opt.gt, "ground-truth poses (KITTI format); default: discover");
  app.add_option("--calib", opt.calib, "calib.txt with Tr (default: the sequence's)");
  app.add_option("--labels", opt.labels, "label source")->check(CLI::IsMember({"labels", "predictions", "geometric", "none"}));
  app.add_option("--preset", opt.preset, "baseline (LIO-SAM-like) or full (the paper)")
      ->check(CLI::IsMember({"baseline", "full"}));
  app.add_option("--config", opt.config, "YAML file overriding preset settings");
  app.add_option("--kitti-correction", opt.kitti_correction,
                 "KITTI vertical-angle correction (auto: on unless sim.json is present)")
      ->check(CLI::IsMember({"on", "off", "auto"}));
  app.add_option("--first", opt.first, "first frame (inclusive)");
  app.add_option("--last", opt.last, "last frame (inclusive; default: the last)");
  app.add_option("--out", opt.out, "output directory")->required();
  app.add_flag("--quiet", opt.quiet, "no progress line");
  app.add_option("--loop", opt.loop,
                 "loop closure + pose graph (with --imu oxts: keyframe graph with velocity/bias states and IMU factors; "
                 "default off: poses.txt is then the odometry; YAML slam.loop_closure)")
      ->check(CLI::IsMember({"on", "off"}));
  app.add_option("--loop-detector", opt.loop_detector, "loop candidates: radius (LIO-SAM, default) or scancontext")
      ->check(CLI::IsMember({"radius", "scancontext"}));
  app.add_option("--map", opt.map, "write OUT/map.ply, the semantic map (default on)")
      ->check(CLI::IsMember({"on", "off"}));
  app.add_flag("--map-static", opt.map_static, "leave movable classes (cars, people, ...) out of map.ply");
  app.add_option("--imu", opt.imu,
                 "oxts: lidar-inertial odometry with the sequence's KITTI raw oxts/ folder and calib.txt's "
                 "Tr_imu_velo (with --loop on: + keyframe graph with velocity/bias states, IMU factors "
                 "and loops); none (default): lidar only")
      ->check(CLI::IsMember({"none", "oxts"}));
  app.add_option("--deskew", opt.deskew,
                 "deskew sweeps (raw data, --distortion on drives): on = the YAML's deskew settings with mode "
                 "constant_velocity (with --imu oxts: IMU deskew); default: the YAML's deskew.mode")
      ->check(CLI::IsMember({"on", "off"}));
  app.add_option("--imu-time-offset", opt.imu_time_offset,
                 "t_imu = t_lidar + offset [s]; auto: 0, or first OXTS stamp - first scan stamp when the clocks "
                 "are more than 1000 s apart (times.txt from 0, OXTS with a date)");
  app.add_option("--velocity-hint", opt.velocity_hint,
                 "with --imu oxts: oxts (default) = the OXTS INS velocity guides the front end while the LIO "
                 "initialises; none = lidar + IMU only")
      ->check(CLI::IsMember({"oxts", "none"}));
  app.add_option("--bad-scans", opt.bad_scans,
                 "a frame whose scan or label file cannot be read (empty, truncated, missing): skip (default) = "
                 "process it as an empty scan on the odometry's prediction and record why in report.json; "
                 "stop = end the run with the error")
      ->check(CLI::IsMember({"skip", "stop"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  try {
    semlio::io::KittiSequenceConfig seq_config;
    seq_config.label_folder = (opt.labels == "none" || opt.labels == "geometric") ? "" : opt.labels;
    seq_config.ground_truth_path = opt.gt;
    const semlio::io::KittiSequence seq(opt.sequence, seq_config);
    if (opt.labels != "none" && opt.labels != "geometric" && !seq.has_labels()) {
      std::cerr << "semlio_kitti: warning: " << seq.directory() << "/" << opt.labels
                << " not found; running without labels\n";
    }
    const long n_frames = static_cast<long>(seq.size());
    const long last = opt.last < 0 ? n_frames - 1 : std::min(opt.last, n_frames - 1);
    if (opt.first < 0 || opt.first > last) {
      std::cerr << "semlio_kitti: --first " << opt.first << " / --last " << opt.last << " select no frame of "
                << n_frames << "\n";
      return 2;
    }
    const auto first = static_cast<std::size_t>(opt.first);
    const auto last_u = static_cast<std::size_t>(last);

    std::optional<SE3d> Tr;
    if (!opt.calib.empty()) {
      Tr = semlio::io::read_kitti_calib(opt.calib).T_cam0_velo;
    } else if (seq.calibration()) {
      Tr = seq.calibration()->T_cam0_velo;
    }
    const bool simulated = fs::exists(fs::path(seq.directory()) / "sim.json");

    semlio::PipelineSettings settings;
    settings.odometry.kitti_vertical_correction =
        opt.kitti_correction == "auto" ? !simulated : opt.kitti_correction == "on";
    // The simulator's sweeps start facing backwards (KITTI raw: forwards); both
    // spin clockwise. Only used when deskew is switched on in the YAML.
    if (simulated) settings.deskew.start_azimuth_rad = std::numbers::pi;
    semlio_examples::BackEndSettings back_end;
    back_end.slam.loop_closure = false;  // semlio_kitti's default: the odometry comparison is the main job
    if (!opt.config.empty()) semlio_examples::load_settings_yaml(opt.config, settings, &back_end);
    if (!opt.loop.empty()) back_end.slam.loop_closure = opt.loop == "on";
    if (!opt.loop_detector.empty()) back_end.loop_detector = opt.loop_detector;
    if (back_end.loop_detector != "radius" && back_end.loop_detector != "scancontext") {
      throw semlio::ConfigError(opt.config + ": slam.loop_detector must be radius or scancontext, got '" +
                                back_end.loop_detector + "'");
    }
    if (opt.map_static) back_end.map.drop_dynamic = true;
    back_end.slam.validate();
    const bool write_map = opt.map == "on";
    if (opt.kitti_correction != "auto") settings.odometry.kitti_vertical_correction = opt.kitti_correction == "on";
    if (opt.deskew == "on") settings.deskew.mode = semlio::DeskewMode::kConstantVelocity;
    if (opt.deskew == "off") settings.deskew.mode = semlio::DeskewMode::kNone;
    const bool use_imu = opt.imu == "oxts";
    // As semlio_lio: with an IMU, directions the solver finds weak stay at
    // the IMU prediction instead of following the lidar's weak solution
    // (README, lidar-inertial). Overrides the YAML's solver setting.
    if (use_imu) settings.odometry.solver.reset_weak_directions = true;
    // --imu oxts --loop on: the LIO feeds the keyframe graph with inertial
    // states (run() with LidarInertialFrontEnd); --loop off: the LIO alone.
    const bool lio_back_end = use_imu && back_end.slam.loop_closure;

    // IMU (--imu oxts): samples, extrinsic, clock offset; deskew moves into the LIO.
    std::vector<semlio::ImuSample> imu;
    std::vector<semlio_examples::OxtsVelocity> velocities;
    semlio::LidarInertialConfig lc;
    if (use_imu) {
      const fs::path oxts_dir = fs::path(seq.directory()) / "oxts";
      if (!fs::is_directory(oxts_dir)) {
        throw semlio::IoError(oxts_dir.string() + ": no OXTS folder (KITTI raw layout: oxts/timestamps.txt, "
                              "oxts/data/); --imu oxts needs one");
      }
      const std::vector<semlio::io::OxtsRecord> records = semlio::io::read_oxts(oxts_dir.string());
      imu = semlio::io::imu_samples(records);
      if (opt.velocity_hint == "oxts") velocities = semlio_examples::oxts_velocities(records);
      const std::string calib_path = opt.calib.empty() ? (fs::path(seq.directory()) / "calib.txt").string() : opt.calib;
      const std::optional<semlio::io::Calibration> calib =
          opt.calib.empty() ? seq.calibration() : std::optional(semlio::io::read_kitti_calib(opt.calib));
      if (!calib || !calib->T_imu_velo) {
        throw semlio::ConfigError(calib_path + ": no Tr_imu_velo line (lidar -> IMU extrinsic); --imu oxts needs it");
      }
      lc.T_imu_lidar = *calib->T_imu_velo;
      if (opt.imu_time_offset == "auto") {
        lc.imu_time_offset_s = semlio_examples::auto_imu_time_offset(imu, seq.stamp(first), seq.stamp(0));
      } else {
        try {
          std::size_t used = 0;
          lc.imu_time_offset_s = std::stod(opt.imu_time_offset, &used);
          if (used != opt.imu_time_offset.size()) throw std::invalid_argument("trailing characters");
        } catch (const std::exception&) {
          throw semlio::ConfigError("--imu-time-offset must be auto or a number of seconds, got '" +
                                    opt.imu_time_offset + "'");
        }
      }
      lc.deskew = settings.deskew.mode != semlio::DeskewMode::kNone;
      lc.sweep_period_s = settings.deskew.sweep_period_s;
      lc.frame_period_s = settings.deskew.frame_period_s;
      lc.point_times = settings.deskew.point_time_config();
      settings.deskew.mode = semlio::DeskewMode::kNone;  // the LIO deskews (to the sweep start) before the front end
    }

    RunResult result;
    const bool geometric = opt.labels == "geometric";
    const bool use_labels = geometric || (opt.labels != "none" && seq.has_labels());
    const FrameReader frames{seq, opt.bad_scans == "skip"};
    const auto run_preset = [&](auto segmenter) {
      if (lio_back_end) {
        ImuFeed feed{imu, velocities, lc};
        return opt.preset == "baseline"
                   ? run(semlio::LidarInertialFrontEnd([&] { return semlio::make_baseline_odometry(segmenter, settings); }, lc),
                         back_end, write_map, frames, first, last_u, opt.quiet, &feed)
                   : run(semlio::LidarInertialFrontEnd([&] { return semlio::make_full_odometry(segmenter, settings); }, lc),
                         back_end, write_map, frames, first, last_u, opt.quiet, &feed);
      }
      if (use_imu) {
        return opt.preset == "baseline"
                   ? run_lio([&] { return semlio::make_baseline_odometry(segmenter, settings); }, lc, imu, velocities, frames, first,
                             last_u, opt.quiet)
                   : run_lio([&] { return semlio::make_full_odometry(segmenter, settings); }, lc, imu, velocities, frames, first,
                             last_u, opt.quiet);
      }
      return opt.preset == "baseline"
                 ? run(semlio::make_baseline_odometry(segmenter, settings), back_end, write_map, frames, first, last_u,
                       opt.quiet)
                 : run(semlio::make_full_odometry(segmenter, settings), back_end, write_map, frames, first, last_u,
                       opt.quiet);
    };
    result = run_preset(semlio_examples::SegmenterChoice(
        geometric    ? semlio_examples::SegmenterChoice::Variant(semlio::GeometricSegmenter{})
        : use_labels ? semlio_examples::SegmenterChoice::Variant(semlio::ScanLabels{})
                     : semlio_examples::SegmenterChoice::Variant(semlio::NoLabels{})));

    // One pose per input frame: skipped frames are interpolated by stamp.
    const std::size_t n = result.reports.size();
    std::vector<SE3d>& poses = result.optimised;
    std::vector<SE3d>& poses_odom = result.odometry;
    std::vector<double> stamps(n);
    std::vector<bool> processed(n);
    std::vector<std::size_t> keyframes;
    for (std::size_t i = 0; i < n; ++i) {
      stamps[i] = result.reports[i].stamp_s;
      processed[i] = result.reports[i].status != semlio::OdometryStatus::kSkipped;
      if (result.reports[i].keyframe) keyframes.push_back(i);
    }
    semlio::fill_skipped_poses(poses, stamps, processed);
    semlio::fill_skipped_poses(poses_odom, stamps, processed);
    if (settings.deskew.mode != semlio::DeskewMode::kNone) {
      // Deskewed frames are posed at their target time (default: mid-sweep);
      // outputs keep the meaning stamps have everywhere else: the sweep start.
      poses = semlio::poses_at_sweep_start(poses, stamps, settings.deskew.target, settings.deskew.sweep_period_s);
      poses_odom =
          semlio::poses_at_sweep_start(poses_odom, stamps, settings.deskew.target, settings.deskew.sweep_period_s);
    }

    fs::create_directories(opt.out);
    const fs::path out(opt.out);
    semlio::io::write_kitti_poses((out / "poses.txt").string(), Tr ? semlio::io::lidar_to_camera(poses, *Tr) : poses);
    std::vector<semlio::io::StampedPose> tum(n);
    for (std::size_t i = 0; i < n; ++i) tum[i] = {stamps[i], poses[i]};
    semlio::io::write_tum_trajectory((out / "poses_tum.txt").string(), tum);
    semlio::io::write_kitti_poses((out / "poses_odom.txt").string(),
                                  Tr ? semlio::io::lidar_to_camera(poses_odom, *Tr) : poses_odom);
    if (write_map && (!use_imu || lio_back_end)) semlio::io::write_ply((out / "map.ply").string(), result.map);
    {
      std::ofstream kf(out / "keyframes.txt");
      kf.precision(9);
      for (const std::size_t i : keyframes) kf << (first + i) << ' ' << std::fixed << stamps[i] << '\n';
    }

    // Ground truth of the selected frames, re-based on the first one.
    std::optional<semlio::eval::AteReport> ate_all;
    std::optional<semlio::eval::AteReport> ate_kf;
    std::optional<semlio::eval::AteReport> ate_odom;
    std::optional<semlio::eval::KittiMetricReport> kitti;
    if (seq.has_ground_truth()) {
      const std::vector<SE3d> gt_all = seq.ground_truth_lidar();
      std::vector<SE3d> gt(gt_all.begin() + static_cast<long>(first), gt_all.begin() + static_cast<long>(last_u) + 1);
      const SE3d base = gt.front().inverse();
      for (auto& T : gt) T = base * T;
      ate_all = semlio::eval::ate(gt, poses);
      ate_odom = semlio::eval::ate(gt, poses_odom);
      if (keyframes.size() >= 3) ate_kf = semlio::eval::ate(gt, poses, keyframes);
      kitti = Tr ? semlio::eval::kitti_metric(semlio::io::lidar_to_camera(gt, *Tr), semlio::io::lidar_to_camera(poses, *Tr))
                 : semlio::eval::kitti_metric(gt, poses);
    }

    std::vector<double> totals;
    std::vector<std::size_t> status_counts(8, 0);
    for (std::size_t i = 0; i < n; ++i) {
      const auto& r = result.reports[i];
      if (r.status != semlio::OdometryStatus::kSkipped) totals.push_back(result.back_end[i].total_ms);
      ++status_counts[static_cast<std::size_t>(r.status)];
    }
    const long peak_kb = peak_rss_kb();
    const bool loops_on = back_end.slam.loop_closure;
    const auto unreadable = static_cast<std::size_t>(std::count_if(
        result.input_errors.begin(), result.input_errors.end(), [](const std::string& e) { return !e.empty(); }));

    {
      std::ofstream os(out / "report.json");
      semlio_examples::JsonWriter j(os);
      j.begin_object();
      j.field("schema", "semlio_kitti/1");
      j.field("sequence", seq.directory()).field("preset", opt.preset).field("labels", use_labels ? opt.labels : "none");
      j.field("first_frame", static_cast<long long>(first)).field("last_frame", static_cast<long long>(last_u));
      j.field("frame", Tr ? "camera0" : "lidar");
      j.field("kitti_vertical_correction", settings.odometry.kitti_vertical_correction);
      j.field("keyframe_count", keyframes.size());
      j.field("unreadable_frames", unreadable);
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
      j.end_object();
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
        j.key("kitti").begin_object();
        j.field("segments", kitti->segment_count).field("translation_error_pct", kitti->translation_error_pct);
        j.field("rotation_error_deg_per_m", kitti->rotation_error_deg_per_m);
        j.field("rotation_error_deg_per_100m", kitti->rotation_error_deg_per_100m).end_object();
        j.end_object();
      }
      j.key("loop").begin_object();
      j.field("enabled", loops_on).field("detector", back_end.loop_detector);
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
              keyframes.empty() ? 0.0 : static_cast<double>(result.keyframe_bytes) / static_cast<double>(keyframes.size()));
      constexpr double kMiB = 1024.0 * 1024.0;
      const semlio::SlamConfig& sc = back_end.slam;
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
      if (use_imu) {
        const ImuRunFacts& f = result.imu;
        j.key("imu").begin_object();
        j.field("source", "oxts").field("samples", f.samples).field("time_offset_s", f.time_offset_s);
        j.field("deskew", lc.deskew ? "imu" : "off").field("velocity_hint", opt.velocity_hint);
        j.field("initialized_at_frame", static_cast<long long>(f.initialized_at < 0 ? -1 : f.initialized_at + static_cast<long>(first)));
        j.field("imu_predicted_frames", f.imu_predicted).field("fallback_frames", f.fallbacks);
        j.field("imu_deskewed_frames", f.imu_deskewed).field("rejected_samples", f.rejected);
        j.field("last_issue", f.last_issue).field("graph_imu_factors", f.imu_factors);
        j.end_object();
      }
      if (write_map && (!use_imu || lio_back_end)) {
        j.key("map").begin_object();
        j.field("points", result.map.size()).field("leaf_size_m", back_end.map.leaf_size_m);
        j.field("static_only", back_end.map.drop_dynamic).end_object();
      }
      j.key("frames").begin_array();
      for (std::size_t i = 0; i < n; ++i) {
        const auto& r = result.reports[i];
        j.begin_object();
        j.field("index", static_cast<long long>(first + i)).field("stamp_s", r.stamp_s);
        j.field("status", semlio::to_string(r.status)).field("keyframe", r.keyframe);
        j.field("points", r.points).field("corners", r.corners).field("surfaces", r.surfaces);
        j.field("corner_matches", r.corner_matches).field("surface_matches", r.surface_matches);
        j.field("iterations", r.solve.iterations).field("solver_status", semlio::to_string(r.solve.status));
        j.field("degenerate_directions", r.solve.degenerate_directions);
        j.array_field("eigenvalues", std::vector<double>(r.solve.eigenvalues.data(), r.solve.eigenvalues.data() + 6));
        write_timings(j, r.timings);
        j.field("backend_ms", result.back_end[i].backend_ms).field("total_ms", result.back_end[i].total_ms);
        j.field("cpu_ms", result.back_end[i].cpu_ms);
        j.field("loop_checked", result.back_end[i].loop_checked).field("loop_closed", result.back_end[i].loop_closed);
        if (use_imu) j.field("imu_fallback", result.imu.fallback_frame[i] != 0);
        if (!result.input_errors[i].empty()) j.field("input_error", result.input_errors[i]);
        j.end_object();
      }
      j.end_array();
      j.end_object();
      os << '\n';
    }

    // One-screen summary.
    std::printf("semlio_kitti  %s  preset=%s labels=%s  frames %zu..%zu (%zu)\n", seq.directory().c_str(),
                opt.preset.c_str(), use_labels ? opt.labels.c_str() : "none", first, last_u, n);
    std::printf("  keyframes           %zu\n", keyframes.size());
    std::printf("  frame time [ms]     median %.1f  p95 %.1f  (%.1f Hz overall)\n", percentile(totals, 0.5),
                percentile(totals, 0.95), static_cast<double>(n) / std::max(result.wall_s, 1e-9));
    std::printf("  statuses           ");
    for (std::size_t s = 0; s < status_counts.size(); ++s) {
      if (status_counts[s] > 0) std::printf(" %s=%zu", semlio::to_string(static_cast<semlio::OdometryStatus>(s)), status_counts[s]);
    }
    std::printf("\n");
    if (unreadable > 0) {
      std::printf("  unreadable frames   %zu, processed as empty scans (input_error in report.json)\n", unreadable);
    }
    if (loops_on) {
      std::printf("  loops               %zu accepted of %zu verified (%zu candidates, detector %s)\n",
                  result.loop_stats.accepted, result.loop_stats.verified, result.loop_stats.candidates,
                  back_end.loop_detector.c_str());
    }
    if (use_imu) {
      const ImuRunFacts& f = result.imu;
      std::printf("  IMU (oxts)          %zu samples, offset %.6f s, deskew %s; initialised at frame %ld, "
                  "IMU-predicted frames %zu, fallbacks %zu, rejected samples %zu\n",
                  f.samples, f.time_offset_s, lc.deskew ? "imu" : "off",
                  f.initialized_at < 0 ? -1L : f.initialized_at + static_cast<long>(first), f.imu_predicted,
                  f.fallbacks, f.rejected);
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
    } else {
      std::printf("  no ground truth found: not evaluated\n");
    }
    std::printf("  wrote %s/{poses.txt,poses_odom.txt,poses_tum.txt,keyframes.txt,report.json%s} (%s frame)\n",
                opt.out.c_str(), write_map && !use_imu ? ",map.ply" : "", Tr ? "camera-0" : "lidar");
    return 0;
  } catch (const semlio::Error& e) {
    std::cerr << "semlio_kitti: " << e.what() << "\n";
    return 1;
  }
}
