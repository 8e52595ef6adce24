// semlio_kitti: runs the odometry on a KITTI-layout sequence directory (real
// KITTI odometry / SemanticKITTI, or a semlio_simulate drive) and writes the
// trajectory, keyframes and a JSON report; evaluates against ground truth when
// one is found. See the README ("semlio_kitti") for options and outputs.

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include <semlio/eval/ate.hpp>
#include <semlio/eval/kitti_metric.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/kitti_sequence.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/pipeline/interpolate.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/segment/geometric_segmenter.hpp>
#include <semlio/segment/scan_labels.hpp>

#include "json_writer.hpp"
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
};

struct RunResult {
  std::vector<semlio::FrameReport> reports;
  semlio::RankHistogram ranks{};
  double wall_s = 0.0;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

template <typename Odometry>
RunResult run(Odometry odom, const semlio::io::KittiSequence& seq, std::size_t first, std::size_t last,
              bool quiet) {
  RunResult result;
  const std::size_t n = last - first + 1;
  result.reports.reserve(n);
  const bool tty = !quiet && isatty(STDERR_FILENO) != 0;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = first; i <= last; ++i) {
    semlio::Scan scan = seq.read(i);
    result.reports.push_back(odom.process(scan));
    const std::size_t done = i - first + 1;
    if (tty && (done % 5 == 0 || done == n)) {
      const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const double hz = static_cast<double>(done) / std::max(el, 1e-9);
      std::fprintf(stderr, "\r[semlio_kitti] frame %zu/%zu  %.1f Hz  ETA %.0f s   ", done, n, hz,
                   static_cast<double>(n - done) / hz);
    }
  }
  if (tty) std::fprintf(stderr, "\n");
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.ranks = odom.rank_histogram();
  return result;
}

void write_timings(semlio_examples::JsonWriter& j, const semlio::StageTimings& t) {
  j.key("timings_ms").begin_object();
  j.field("preprocess", t.preprocess_ms).field("segment", t.segment_ms).field("features", t.features_ms);
  j.field("solve", t.solve_ms).field("keyframe", t.keyframe_ms).field("map", t.map_ms).field("total", t.total_ms);
  j.end_object();
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"semlio_kitti: semantic lidar odometry on a KITTI-layout sequence"};
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
    if (!opt.config.empty()) semlio_examples::load_settings_yaml(opt.config, settings);
    if (opt.kitti_correction != "auto") settings.odometry.kitti_vertical_correction = opt.kitti_correction == "on";

    RunResult result;
    const bool geometric = opt.labels == "geometric";
    const bool use_labels = geometric || (opt.labels != "none" && seq.has_labels());
    const auto run_preset = [&](auto segmenter) {
      return opt.preset == "baseline"
                 ? run(semlio::make_baseline_odometry(segmenter, settings), seq, first, last_u, opt.quiet)
                 : run(semlio::make_full_odometry(segmenter, settings), seq, first, last_u, opt.quiet);
    };
    if (geometric) {
      result = run_preset(semlio::GeometricSegmenter{});
    } else if (use_labels) {
      result = run_preset(semlio::ScanLabels{});
    } else {
      result = run_preset(semlio::NoLabels{});
    }

    // One pose per input frame: skipped frames are interpolated by stamp.
    const std::size_t n = result.reports.size();
    std::vector<SE3d> poses(n);
    std::vector<double> stamps(n);
    std::vector<bool> processed(n);
    std::vector<std::size_t> keyframes;
    for (std::size_t i = 0; i < n; ++i) {
      poses[i] = result.reports[i].T_map_lidar;
      stamps[i] = result.reports[i].stamp_s;
      processed[i] = result.reports[i].status != semlio::OdometryStatus::kSkipped;
      if (result.reports[i].keyframe) keyframes.push_back(i);
    }
    semlio::fill_skipped_poses(poses, stamps, processed);

    fs::create_directories(opt.out);
    const fs::path out(opt.out);
    semlio::io::write_kitti_poses((out / "poses.txt").string(), Tr ? semlio::io::lidar_to_camera(poses, *Tr) : poses);
    std::vector<semlio::io::StampedPose> tum(n);
    for (std::size_t i = 0; i < n; ++i) tum[i] = {stamps[i], poses[i]};
    semlio::io::write_tum_trajectory((out / "poses_tum.txt").string(), tum);
    {
      std::ofstream kf(out / "keyframes.txt");
      kf.precision(9);
      for (const std::size_t i : keyframes) kf << (first + i) << ' ' << std::fixed << stamps[i] << '\n';
    }

    // Ground truth of the selected frames, re-based on the first one.
    std::optional<semlio::eval::AteReport> ate_all;
    std::optional<semlio::eval::AteReport> ate_kf;
    std::optional<semlio::eval::KittiMetricReport> kitti;
    if (seq.has_ground_truth()) {
      const std::vector<SE3d> gt_all = seq.ground_truth_lidar();
      std::vector<SE3d> gt(gt_all.begin() + static_cast<long>(first), gt_all.begin() + static_cast<long>(last_u) + 1);
      const SE3d base = gt.front().inverse();
      for (auto& T : gt) T = base * T;
      ate_all = semlio::eval::ate(gt, poses);
      if (keyframes.size() >= 3) ate_kf = semlio::eval::ate(gt, poses, keyframes);
      kitti = Tr ? semlio::eval::kitti_metric(semlio::io::lidar_to_camera(gt, *Tr), semlio::io::lidar_to_camera(poses, *Tr))
                 : semlio::eval::kitti_metric(gt, poses);
    }

    std::vector<double> totals;
    std::vector<std::size_t> status_counts(8, 0);
    for (const auto& r : result.reports) {
      if (r.status != semlio::OdometryStatus::kSkipped) totals.push_back(r.timings.total_ms);
      ++status_counts[static_cast<std::size_t>(r.status)];
    }

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
        j.key("kitti").begin_object();
        j.field("segments", kitti->segment_count).field("translation_error_pct", kitti->translation_error_pct);
        j.field("rotation_error_deg_per_m", kitti->rotation_error_deg_per_m);
        j.field("rotation_error_deg_per_100m", kitti->rotation_error_deg_per_100m).end_object();
        j.end_object();
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
    if (ate_all) {
      std::printf("  ATE RMSE [m]        %.3f all frames", ate_all->rmse_m);
      if (ate_kf) std::printf(", %.3f keyframes", ate_kf->rmse_m);
      std::printf("\n  KITTI metric        %.3f %%  %.4f deg/100m  (%zu segments)\n", kitti->translation_error_pct,
                  kitti->rotation_error_deg_per_100m, kitti->segment_count);
    } else {
      std::printf("  no ground truth found: not evaluated\n");
    }
    std::printf("  wrote %s/{poses.txt,poses_tum.txt,keyframes.txt,report.json} (%s frame)\n", opt.out.c_str(),
                Tr ? "camera-0" : "lidar");
    return 0;
  } catch (const semlio::Error& e) {
    std::cerr << "semlio_kitti: " << e.what() << "\n";
    return 1;
  }
}
