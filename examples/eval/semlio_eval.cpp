// semlio_eval: scores an estimated trajectory against ground truth with the
// ATE (Umeyama alignment) and the KITTI odometry metric.
//
//   semlio_eval --gt GT --est EST [--calib calib.txt] [--times times.txt]
//               [--subset frames.txt] [--format kitti|tum] [--align se3|sim3|none]
//               [--max-dt SECONDS] [--json out.json]
//
// Inputs and conventions
// - GT is a KITTI pose file (12 numbers per line, 3x4 row-major); line i is
//   frame i.
// - EST is a KITTI pose file (the default; frame i on line i, same count as
//   GT) or a TUM file (`stamp tx ty tz qx qy qz qw`), detected from its first
//   line (8 fields) or forced with --format tum.
// - Both are taken to be in the same frame. --calib calib.txt converts a
//   lidar-frame estimate into the camera-0 frame of KITTI ground truth:
//   P_i = Tr * T_i * Tr^-1 with Tr = T_cam0_velo (the `Tr:` line).
// - A TUM estimate is matched to GT frames by time: --times gives the
//   timestamp of every GT frame (KITTI times.txt, one line per GT pose); each
//   GT frame takes the TUM pose with the nearest stamp when |dt| <= --max-dt
//   (default 0.02 s, a fifth of KITTI's 0.1 s frame period); frames with no
//   pose that close are left out of the ATE.
// - --subset frames.txt: 0-based GT frame numbers, one per line ('#' comments
//   and blank lines skipped), e.g. the keyframes. The ATE is aligned and
//   scored on these frames only (those without a matched estimate are
//   skipped and counted). The KITTI metric always uses every frame.
// - The KITTI metric needs an estimate for every GT frame; otherwise it is
//   reported as "not_computed". Segments: 100..800 m, a start every 10
//   frames, averaged over all segments (the official devkit's scheme).
// - --align se3 (default) | sim3 | none: the transform fitted before the ATE
//   (Umeyama least squares on positions, estimate into ground truth).
// - The ATE error of a frame is |p_gt - (s R p_est + t)|; RMSE, mean, median
//   (mean of the two middle values for an even count) and max are reported.
//
// Exit codes: 0 success; 1 unreadable or invalid input (message names the
// file, line and value); 2 bad command line (usage printed).
//
// JSON written by --json (all lengths in metres; always valid JSON: a
// non-finite number is written as null, counted in "non_finite_count" and
// flagged by "numbers": "non_finite_written_as_null" instead of "finite"):
// {
//   "ground_truth": "<path>",          // --gt
//   "estimate": "<path>",              // --est
//   "format": "kitti" | "tum",         // format of the estimate
//   "frame": "as_given" | "lidar_to_camera",  // whether --calib converted the estimate
//   "alignment": "se3" | "sim3" | "none",
//   "poses": {
//     "ground_truth": N,               // poses in GT
//     "estimate": N,                   // poses in EST
//     "matched": N,                    // GT frames with an estimate
//     "evaluated": N,                  // frames in the ATE (subset, or all, that have an estimate)
//     "skipped": N                     // frames of the subset (or all) without an estimate
//   },
//   "ate": {
//     "rmse_m": x, "mean_m": x, "median_m": x, "max_m": x,
//     "scale": x,                      // Sim3 scale (1 otherwise)
//     "status": "ok" | "rotation_undetermined" | "scale_undetermined",
//     "T_gt_est": [12 numbers]         // fitted rotation|translation, 3x4 row-major
//   },
//   "kitti": {
//     "status": "ok" | "no_segments" | "not_computed",
//     "segments": N,                   // segments over all lengths
//     "translation_error_pct": x,      // mean |t_E| / length * 100
//     "rotation_error_deg_per_m": x,   // mean angle(R_E) / length
//     "rotation_error_deg_per_100m": x,
//     "per_length": [ { "length_m": 100, "segments": N,
//                       "translation_error_pct": x, "rotation_error_deg_per_100m": x }, ... ]
//   }
// }
// Example:
// semlio_eval --gt 04.txt --est est_scaled.txt --json out.json  (est: every KITTI 04
// position scaled by 0.97) writes
// {
//   "ground_truth": "04.txt",
//   "estimate": "est_scaled.txt",
//   "format": "kitti",
//   "frame": "as_given",
//   "alignment": "se3",
//   "poses": {"ground_truth": 271, "estimate": 271, "matched": 271, "evaluated": 271, "skipped": 0},
//   "ate": {"rmse_m": 3.39313789184, "mean_m": 2.92554016236, "median_m": 2.89458804198,
//           "max_m": 6.11779535876, "scale": 1, "status": "ok", "T_gt_est": [1, 3.3e-16, ...]},
//   "kitti": {"status": "ok", "segments": 43, "translation_error_pct": 3.01481038428,
//             "rotation_error_deg_per_m": 0, "rotation_error_deg_per_100m": 0, "per_length": [
//             {"length_m": 100, "segments": 21, "translation_error_pct": 3.02015450022, "rotation_error_deg_per_100m": 0},
//             {"length_m": 200, "segments": 15, "translation_error_pct": 3.01046666851, "rotation_error_deg_per_100m": 0},
//             {"length_m": 300, "segments": 7, "translation_error_pct": 3.0080859988, "rotation_error_deg_per_100m": 0}]}
// }

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/eval/ate.hpp>
#include <semlio/eval/kitti_metric.hpp>
#include <semlio/eval/time_match.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/trajectory.hpp>

#include "../common/json_writer.hpp"

namespace {

using semlio::SE3d;
namespace eval = semlio::eval;

constexpr int kExitBadInput = 1;
constexpr int kExitUsage = 2;

void print_usage(std::FILE* out) {
  std::fprintf(out,
               "usage: semlio_eval --gt GT --est EST [--calib calib.txt] [--times times.txt]\n"
               "                   [--subset frames.txt] [--format kitti|tum] [--align se3|sim3|none]\n"
               "                   [--max-dt SECONDS] [--json out.json]\n"
               "  --gt       ground truth, KITTI poses (3x4 row-major per line)\n"
               "  --est      estimate, KITTI poses (default) or TUM (detected or --format tum)\n"
               "  --calib    calib.txt whose Tr converts a lidar-frame estimate to camera 0\n"
               "  --times    GT frame timestamps (times.txt); required for a TUM estimate\n"
               "  --subset   GT frame numbers for the ATE (e.g. keyframes), one per line\n"
               "  --align    alignment before the ATE: se3 (default), sim3 or none\n"
               "  --max-dt   largest |dt| [s] when matching TUM stamps to GT times (default 0.02)\n"
               "  --json     also write the results as JSON\n");
}

struct UsageError {
  std::string message;
};

struct Options {
  std::string gt;
  std::string est;
  std::string calib;
  std::string times;
  std::string subset;
  std::string json;
  std::string format;  // "", "kitti" or "tum"
  eval::Alignment alignment = eval::Alignment::kSE3;
  double max_dt_s = 0.02;
};

Options parse_args(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      print_usage(stdout);
      std::exit(0);
    }
    if (i + 1 >= argc) throw UsageError{"missing value after " + arg};
    const std::string value = argv[++i];
    if (arg == "--gt") {
      o.gt = value;
    } else if (arg == "--est") {
      o.est = value;
    } else if (arg == "--calib") {
      o.calib = value;
    } else if (arg == "--times") {
      o.times = value;
    } else if (arg == "--subset") {
      o.subset = value;
    } else if (arg == "--json") {
      o.json = value;
    } else if (arg == "--format") {
      if (value != "kitti" && value != "tum") throw UsageError{"--format must be kitti or tum, not '" + value + "'"};
      o.format = value;
    } else if (arg == "--align") {
      if (value == "se3") {
        o.alignment = eval::Alignment::kSE3;
      } else if (value == "sim3") {
        o.alignment = eval::Alignment::kSim3;
      } else if (value == "none") {
        o.alignment = eval::Alignment::kNone;
      } else {
        throw UsageError{"--align must be se3, sim3 or none, not '" + value + "'"};
      }
    } else if (arg == "--max-dt") {
      char* end = nullptr;
      const double v = std::strtod(value.c_str(), &end);
      if (end == value.c_str() || *end != '\0' || !std::isfinite(v) || v < 0.0) {
        throw UsageError{"--max-dt must be a non-negative number of seconds, not '" + value + "'"};
      }
      o.max_dt_s = v;
    } else {
      throw UsageError{"unknown option '" + arg + "'"};
    }
  }
  if (o.gt.empty()) throw UsageError{"--gt is required"};
  if (o.est.empty()) throw UsageError{"--est is required"};
  return o;
}

// "path:line: " prefix of a message.
std::string at(const std::string& path, long line) {
  std::string out = path;
  out += ':';
  out += std::to_string(line);
  out += ": ";
  return out;
}

// 0-based frame numbers, one per line; '#' comments and blank lines skipped.
std::vector<std::size_t> read_subset(const std::string& path, std::size_t frame_count) {
  std::ifstream in(path);
  if (!in) throw semlio::IoError(path + ": cannot open subset file");
  std::vector<std::size_t> frames;
  std::string line;
  long n = 0;
  while (std::getline(in, line)) {
    ++n;
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ss(line);
    long long v = 0;
    if (!(ss >> v)) {
      std::string rest;
      std::istringstream probe(line);
      if (probe >> rest) throw semlio::FormatError(at(path, n) + "not a frame number: '" + rest + "'");
      continue;  // blank
    }
    std::string extra;
    if (ss >> extra) throw semlio::FormatError(at(path, n) + "more than one field ('" + extra + "')");
    if (v < 0 || static_cast<unsigned long long>(v) >= frame_count) {
      throw semlio::ValueError(at(path, n) + "frame " + std::to_string(v) + " is outside 0.." + std::to_string(frame_count - 1));
    }
    frames.push_back(static_cast<std::size_t>(v));
  }
  if (frames.empty()) throw semlio::FormatError(path + ": subset file lists no frames");
  return frames;
}

// "%.*f" of a finite number; "non-finite" otherwise (huge poses can overflow
// the metrics: the table says so instead of printing nan or inf).
std::string fixed(double v, int digits) {
  if (!std::isfinite(v)) return "non-finite";
  char buf[400];  // 1e308 has 309 digits before the point
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

const char* kitti_status(const std::optional<eval::KittiMetricReport>& k) {
  if (!k) return "not_computed";
  return k->status == eval::KittiMetricStatus::kOk ? "ok" : "no_segments";
}

struct Counts {
  std::size_t gt = 0;
  std::size_t est = 0;
  std::size_t matched = 0;
  std::size_t subset_unmatched = 0;
};

// Written through JsonWriter, which never emits non-JSON: a non-finite
// number (e.g. an ATE of 1e308-metre poses overflowing to inf) becomes null
// and "numbers" says so, so that a consumer can tell null from a bug.
void write_json(const std::string& path, const Options& o, const std::string& format, const Counts& counts,
                const eval::AteReport& ate, const std::optional<eval::KittiMetricReport>& kitti) {
  std::ostringstream j;
  semlio_examples::JsonWriter w(j);
  w.begin_object();
  w.field("ground_truth", o.gt).field("estimate", o.est).field("format", format);
  w.field("frame", o.calib.empty() ? "as_given" : "lidar_to_camera");
  w.field("alignment", eval::to_string(o.alignment));
  w.key("poses").begin_object();
  w.field("ground_truth", counts.gt).field("estimate", counts.est).field("matched", counts.matched);
  w.field("evaluated", ate.count).field("skipped", counts.subset_unmatched);
  w.end_object();
  w.key("ate").begin_object();
  w.field("rmse_m", ate.rmse_m).field("mean_m", ate.mean_m).field("median_m", ate.median_m).field("max_m", ate.max_m);
  w.field("scale", ate.alignment.scale).field("status", eval::to_string(ate.alignment.status));
  w.key("T_gt_est").begin_array();
  const Eigen::Matrix4d M = ate.alignment.T_gt_est.matrix();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) w.value(M(r, c));
  }
  w.end_array().end_object();
  w.key("kitti").begin_object();
  w.field("status", kitti_status(kitti));
  if (kitti) {
    w.field("segments", kitti->segment_count).field("translation_error_pct", kitti->translation_error_pct);
    w.field("rotation_error_deg_per_m", kitti->rotation_error_deg_per_m);
    w.field("rotation_error_deg_per_100m", kitti->rotation_error_deg_per_100m);
    w.key("per_length").begin_array();
    for (const auto& p : kitti->per_length) {
      w.begin_object();
      w.field("length_m", p.length_m).field("segments", p.count);
      w.field("translation_error_pct", p.translation_error_pct);
      w.field("rotation_error_deg_per_100m", p.rotation_error_deg_per_100m);
      w.end_object();
    }
    w.end_array();
  }
  w.end_object();
  w.field("numbers", w.non_finite_count() == 0 ? "finite" : "non_finite_written_as_null");
  w.field("non_finite_count", w.non_finite_count());
  w.end_object();
  j << '\n';
  std::ofstream out(path);
  if (!out) throw semlio::IoError(path + ": cannot open JSON output for writing");
  out << j.str();
  if (!out) throw semlio::IoError(path + ": write failed");
}

int run(const Options& o) {
  const std::vector<SE3d> gt = semlio::io::read_kitti_poses(o.gt);
  const bool tum = o.format.empty() ? semlio::io::looks_like_tum(o.est) : o.format == "tum";
  if (tum && o.times.empty()) throw UsageError{"a TUM estimate needs --times (the ground-truth frame times)"};

  // est_by_frame[i]: the estimate of GT frame i, if any.
  std::vector<std::optional<SE3d>> est_by_frame(gt.size());
  Counts counts;
  counts.gt = gt.size();
  if (tum) {
    const auto stamped = semlio::io::read_tum_trajectory(o.est);
    const std::vector<double> times = semlio::io::read_kitti_times(o.times);
    if (times.size() != gt.size()) {
      throw semlio::ValueError(o.times + ": has " + std::to_string(times.size()) + " times but " + o.gt + " has " +
                               std::to_string(gt.size()) + " poses");
    }
    counts.est = stamped.size();
    std::vector<double> stamps;
    for (const auto& p : stamped) stamps.push_back(p.stamp_s);
    const std::vector<std::ptrdiff_t> match = eval::match_nearest_stamps(times, stamps, o.max_dt_s);
    for (std::size_t i = 0; i < gt.size(); ++i) {
      if (match[i] != eval::kNoMatch) est_by_frame[i] = stamped[static_cast<std::size_t>(match[i])].pose;
    }
  } else {
    const std::vector<SE3d> est = semlio::io::read_kitti_poses(o.est);
    counts.est = est.size();
    if (est.size() != gt.size()) {
      throw semlio::ValueError(o.est + ": has " + std::to_string(est.size()) + " poses but " + o.gt + " has " +
                               std::to_string(gt.size()) + " (KITTI format: line i is frame i)");
    }
    for (std::size_t i = 0; i < gt.size(); ++i) est_by_frame[i] = est[i];
  }
  if (!o.calib.empty()) {
    const semlio::io::Calibration calib = semlio::io::read_kitti_calib(o.calib);
    if (!calib.T_cam0_velo) throw semlio::FormatError(o.calib + ": no 'Tr:' line");
    const SE3d Tr = *calib.T_cam0_velo;
    const SE3d Tr_inv = Tr.inverse();
    for (auto& T : est_by_frame) {
      if (T) T = Tr * *T * Tr_inv;  // P_i = Tr T_i Tr^-1
    }
  }

  // Frames of the ATE: the subset (or all), restricted to matched frames.
  std::vector<std::size_t> frames;
  if (o.subset.empty()) {
    for (std::size_t i = 0; i < gt.size(); ++i) frames.push_back(i);
  } else {
    frames = read_subset(o.subset, gt.size());
  }
  std::vector<SE3d> gt_used;
  std::vector<SE3d> est_used;
  for (const std::size_t i : frames) {
    if (!est_by_frame[i]) {
      ++counts.subset_unmatched;
      continue;
    }
    gt_used.push_back(gt[i]);
    est_used.push_back(*est_by_frame[i]);
  }
  for (const auto& T : est_by_frame) counts.matched += T ? 1U : 0U;
  if (gt_used.empty()) {
    throw semlio::ValueError("no ground-truth frame has an estimate (TUM stamps within --max-dt " +
                             std::to_string(o.max_dt_s) + " s of --times?)");
  }
  const eval::AteReport ate = eval::ate(gt_used, est_used, eval::AteConfig{.alignment = o.alignment});

  std::optional<eval::KittiMetricReport> kitti;
  if (counts.matched == gt.size()) {
    std::vector<SE3d> est_all;
    est_all.reserve(gt.size());
    for (const auto& T : est_by_frame) est_all.push_back(*T);
    kitti = eval::kitti_metric(gt, est_all);
  }

  const std::string format = tum ? "tum" : "kitti";
  std::printf("semlio_eval: %s vs %s (%s, %zu of %zu frames matched, alignment %s%s)\n", o.est.c_str(), o.gt.c_str(),
              format.c_str(), counts.matched, counts.gt, eval::to_string(o.alignment),
              o.calib.empty() ? "" : ", lidar->camera via calib");
  std::printf("  %-32s %12zu\n", "poses (ATE)", ate.count);
  if (counts.subset_unmatched > 0) std::printf("  %-32s %12zu\n", "frames skipped (no estimate)", counts.subset_unmatched);
  std::printf("  %-32s %12s\n", "ATE RMSE [m]", fixed(ate.rmse_m, 4).c_str());
  std::printf("  %-32s %12s\n", "ATE mean [m]", fixed(ate.mean_m, 4).c_str());
  std::printf("  %-32s %12s\n", "ATE median [m]", fixed(ate.median_m, 4).c_str());
  std::printf("  %-32s %12s\n", "ATE max [m]", fixed(ate.max_m, 4).c_str());
  if (o.alignment == eval::Alignment::kSim3) {
    std::printf("  %-32s %12s\n", "Sim3 scale", fixed(ate.alignment.scale, 6).c_str());
  }
  if (ate.alignment.status != eval::AlignmentStatus::kOk) {
    std::printf("  %-32s %12s\n", "alignment status", eval::to_string(ate.alignment.status));
  }
  if (kitti && kitti->status == eval::KittiMetricStatus::kOk) {
    std::printf("  %-32s %12s\n", "translational error [%]", fixed(kitti->translation_error_pct, 4).c_str());
    std::printf("  %-32s %12s\n", "rotational error [deg/100 m]", fixed(kitti->rotation_error_deg_per_100m, 4).c_str());
    std::printf("  %-32s %12zu\n", "KITTI segments", kitti->segment_count);
  } else {
    std::printf("  %-32s %12s\n", "KITTI metric", kitti ? "no segments (trajectory < 100 m)"
                                                         : "not computed (some frames have no estimate)");
  }
  if (!o.json.empty()) {
    write_json(o.json, o, format, counts, ate, kitti);
    std::printf("  wrote %s\n", o.json.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(parse_args(argc, argv));
  } catch (const UsageError& e) {
    std::fprintf(stderr, "semlio_eval: %s\n", e.message.c_str());
    print_usage(stderr);
    return kExitUsage;
  } catch (const semlio::Error& e) {
    std::fprintf(stderr, "semlio_eval: error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "semlio_eval: error: %s\n", e.what());
    return kExitBadInput;
  }
}
