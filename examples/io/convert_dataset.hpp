#pragma once
// semlio_convert's dataset mode: every frame of any input semlio_run reads
// (KITTI odometry folder, KITTI raw drive, scan folder, ROS 1 bag, MCAP,
// rosbag2 sqlite3) written as a KITTI-layout folder or a folder of PCDs.
//
//   --to kitti: velodyne/NNNNNN.bin (x y z intensity float32, intensity 0 when
//     the input has none), labels/NNNNNN.label when the input has labels,
//     times.txt (seconds since the first frame), calib.txt (Tr: the input's
//     T_cam0_lidar, else identity; every entry of the input's calib.txt kept
//     exactly), poses.txt (ground truth in KITTI camera-0 convention
//     P_i = Tr T_i Tr^-1, when the input has one; a KITTI-format ground-truth
//     file's lines are copied as they are), convert.json.
//     A frame that cannot be read, or holds no valid point, has no .bin (a
//     KITTI .bin cannot hold an empty scan): a gap in the numbering, kept in
//     times.txt and poses.txt, which KittiSequence reads as a missing frame
//     (semlio_run --missing-frames empty, its default). Such frames after the
//     last written one end the folder there (a gap cannot be at the end).
//   --to pcd: NNNNNN.pcd (binary, every field the scan has: intensity, label,
//     ring, time), times.txt (absolute stamps as read), poses.txt (ground
//     truth, lidar frame, KITTI 3x4), calib.txt when the input has Tr,
//     convert.json. A bad or empty frame is a 0-point PCD, so frame i stays
//     frame i.
// The IMU stream is not converted (the KITTI layout has no generic IMU file).
//
// Outputs are built in a hidden sibling folder (.OUT.partial) and renamed to
// OUT when complete: OUT never holds half a conversion, and a failed
// conversion leaves an earlier OUT as it was. An existing non-empty OUT is
// refused; --overwrite replaces it only when it is a previous semlio_convert
// output (it holds convert.json), never an arbitrary folder.

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/pcd.hpp>
#include <semlio/io/read_stats.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/lie/se3.hpp>

#include "frame_source.hpp"
#include "json_writer.hpp"
#include "open_source.hpp"

namespace semlio_examples {

/// The dataset mode's command line.
struct ConvertOptions {
  std::string input;
  std::string out;
  std::string format = "auto";
  std::string lidar_topic;
  std::string imu_topic;
  std::string gt;
  std::string calib;
  std::string to = "kitti";
  long first = 0;
  long last = -1;
  bool overwrite = false;
};

/// Opens `o.input` as semlio_run does (open_source: same formats, detection,
/// topics, --gt, --calib; KITTI labels/ when present). Throws what the sources throw.
inline std::unique_ptr<FrameSource> open_convert_source(const ConvertOptions& o) {
  return open_source(InputSpec{.input = o.input,
                               .format = o.format,
                               .lidar_topic = o.lidar_topic,
                               .imu_topic = o.imu_topic,
                               .gt = o.gt,
                               .calib = o.calib});
}

namespace detail {

namespace fs = std::filesystem;

/// OUT and the hidden sibling the conversion is built in. The destructor
/// removes the partial folder unless commit() moved it into place.
class StagedOutput {
 public:
  /// Checks OUT (see the file comment) and creates an empty staging folder.
  StagedOutput(const std::string& out, const std::string& input, bool overwrite) {
    std::error_code ec;
    final_ = fs::absolute(fs::path(out)).lexically_normal();
    if (final_.filename().empty()) final_ = final_.parent_path();
    if (fs::exists(final_, ec)) {
      if (!fs::is_directory(final_, ec)) throw semlio::IoError(out + ": --out exists and is not a directory");
      if (fs::equivalent(final_, fs::path(input), ec)) throw semlio::IoError(out + ": --out is the --input");
      if (!fs::is_empty(final_, ec)) {
        if (!overwrite) {
          throw semlio::IoError(out + ": --out exists and is not empty; pass --overwrite to replace a previous "
                                      "conversion, or choose another --out");
        }
        if (!fs::is_regular_file(final_ / "convert.json", ec)) {
          throw semlio::IoError(out + ": --overwrite replaces only a previous semlio_convert output (with "
                                      "convert.json); this folder is not one, remove it yourself");
        }
      }
    }
    staging_ = final_.parent_path() / ("." + final_.filename().string() + ".partial");
    fs::remove_all(staging_, ec);  // left by an interrupted conversion (our own name)
    fs::create_directories(staging_, ec);
    if (ec) throw semlio::IoError(staging_.string() + ": cannot create the output folder (" + ec.message() + ")");
  }
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;
  ~StagedOutput() {
    std::error_code ec;
    if (!committed_) fs::remove_all(staging_, ec);
  }

  /// Where files are written until commit().
  [[nodiscard]] const fs::path& dir() const noexcept { return staging_; }
  /// The final OUT.
  [[nodiscard]] const fs::path& final_dir() const noexcept { return final_; }

  /// Replaces OUT (checked empty or a previous conversion) by the staging folder.
  void commit() {
    std::error_code ec;
    if (fs::exists(final_, ec)) fs::remove_all(final_, ec);
    if (ec) throw semlio::IoError(final_.string() + ": cannot remove the previous conversion (" + ec.message() + ")");
    fs::rename(staging_, final_, ec);
    if (ec) {
      throw semlio::IoError(final_.string() + ": cannot rename the finished conversion into place (" +
                            ec.message() + ")");
    }
    committed_ = true;
  }

 private:
  fs::path final_;
  fs::path staging_;
  bool committed_ = false;
};

/// "000042".
inline std::string frame_name(std::size_t i) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06zu", i);
  return buf;
}

/// A double as the shortest text that reads back exactly (for convert.json,
/// whose numbers are printed with 10 digits).
inline std::string exact_text(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

/// The calib.txt the input's Tr came from: --calib (KITTI folders and bags;
/// KITTI raw takes a folder of calib_*.txt), else a KITTI folder's own; "" when none.
inline std::string input_calib_file(const ConvertOptions& o, const std::string& format) {
  std::error_code ec;
  if (format == "kitti-raw" || format == "folder") return {};
  if (!o.calib.empty()) return fs::is_regular_file(o.calib, ec) ? o.calib : std::string();
  if (format != "kitti") return {};
  const fs::path own = fs::path(o.input) / "calib.txt";
  return fs::is_regular_file(own, ec) ? own.string() : std::string();
}

/// Copies the non-blank lines first..first+count-1 of a KITTI poses file to
/// `out`. Throws IoError.
inline void copy_lines(const std::string& in, std::size_t first, std::size_t count, const fs::path& out) {
  std::ifstream is(in);
  if (!is) throw semlio::IoError(in + ": cannot read the ground truth");
  std::ofstream os(out);
  std::string line;
  std::size_t i = 0;
  while (i < first + count && std::getline(is, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    if (i++ >= first) os << line << '\n';
  }
  if (!os) throw semlio::IoError(out.string() + ": write error");
}

/// One selected input frame that was not written as read.
struct SkippedFrame {
  std::size_t input_frame = 0;   ///< index in the input
  std::size_t output_frame = 0;  ///< number in OUT
  std::string reason;            ///< the reader's error, or "no valid point"
};

/// What a conversion read and wrote, for convert.json and the summary.
struct ConvertTally {
  std::size_t n_input = 0;  ///< frames in the input
  std::size_t first = 0;    ///< first selected input frame
  std::size_t n_sel = 0;    ///< frames selected (first..last)
  std::size_t n_out = 0;    ///< frames in OUT (KITTI: up to the last written one)
  std::vector<double> stamps;      ///< per selected frame [s]
  std::vector<bool> stamp_known;   ///< false: a bag that ended early
  std::vector<bool> written;       ///< a scan file was written
  std::vector<SkippedFrame> skipped;
  std::size_t unreadable = 0, empty = 0, points = 0;
  std::size_t no_intensity = 0, with_rings = 0, with_times = 0, labels_lost = 0;
  semlio::io::ReadStats dropped;
  bool labels = false;             ///< KITTI labels/ written
  double t_origin_s = 0.0;         ///< stamp of output frame 0
  std::size_t stamps_clamped = 0;  ///< stamps that went backwards
  std::vector<std::string> lost;   ///< per-point fields KITTI .bin could not carry
  std::string calib_note, poses_note;
};

inline const char* const kImuNote = "not converted (the KITTI and PCD folder layouts have no generic IMU file)";

/// Reads the selected frames and writes their scans into `dir`: a bad or
/// empty frame is skipped (KITTI) or a 0-point PCD. A bag is read in order
/// from its start, so frames before `first` are read and discarded.
inline void convert_frames(FrameSource& source, std::size_t last, bool to_kitti, const fs::path& dir, ConvertTally& t) {
  const std::string& format = source.facts().format;
  const bool sequential = format == "bag" || format == "mcap" || format == "db3";
  t.stamps.assign(t.n_sel, 0.0);
  t.stamp_known.assign(t.n_sel, false);
  t.written.assign(t.n_sel, false);
  if (to_kitti) {
    fs::create_directories(dir / "velodyne");
    if (t.labels) fs::create_directories(dir / "labels");
  }
  for (std::size_t i = sequential ? 0 : t.first; i <= last; ++i) {
    SourceFrame f = source.read(i);
    if (i < t.first) continue;
    const std::size_t k = i - t.first;
    if (isatty(STDERR_FILENO) != 0 && (k % 50 == 0 || i == last)) {  // progress on a terminal
      std::fprintf(stderr, "\rsemlio_convert: frame %zu / %zu%s", k + 1, t.n_sel, i == last ? "\n" : "");
    }
    const std::optional<double> hint = source.stamp_hint(i);
    t.stamp_known[k] = !f.missing || hint.has_value();
    t.stamps[k] = hint && f.missing ? *hint : f.scan.stamp_s;
    t.dropped.dropped_nonfinite += f.dropped.dropped_nonfinite;
    t.dropped.dropped_zero += f.dropped.dropped_zero;
    const bool bad = !f.error.empty() || f.missing;
    if (bad || f.scan.empty()) {
      ++(bad ? t.unreadable : t.empty);
      t.skipped.push_back({i, k, bad ? (f.error.empty() ? "missing" : f.error) : "no valid point"});
      if (to_kitti) continue;
      f.scan = semlio::Scan();  // --to pcd: a 0-point PCD keeps the numbering
    }
    const semlio::Scan& scan = f.scan;
    t.points += scan.size();
    if (!scan.empty() && !scan.has_intensity()) ++t.no_intensity;
    if (scan.has_rings()) ++t.with_rings;
    if (scan.has_times()) ++t.with_times;
    if (to_kitti) {
      semlio::io::write_kitti_bin((dir / "velodyne" / (frame_name(k) + ".bin")).string(), scan);
      if (t.labels) {
        semlio::io::write_label_file((dir / "labels" / (frame_name(k) + ".label")).string(),
                                     semlio::io::raw_labels(scan));
      } else if (scan.has_labels()) {
        ++t.labels_lost;
      }
    } else {
      semlio::io::write_pcd((dir / (frame_name(k) + ".pcd")).string(), scan, semlio::io::PcdEncoding::kBinary);
    }
    t.written[k] = true;
  }
  if (to_kitti) {
    if (t.with_rings > 0) t.lost.emplace_back("ring");
    if (t.with_times > 0) t.lost.emplace_back("time");
    if (t.labels_lost > 0) t.lost.emplace_back("label");
  }
}

/// Ends a KITTI folder at its last written frame (a gap cannot end it) and
/// writes times.txt: a frame whose stamp is unknown, or a stamp going
/// backwards, takes the previous stamp (times.txt must not decrease).
inline void write_times(bool to_kitti, const fs::path& dir, const std::string& input, ConvertTally& t) {
  t.n_out = t.n_sel;
  if (to_kitti) {
    while (t.n_out > 0 && !t.written[t.n_out - 1]) --t.n_out;
    if (t.n_out == 0) {
      throw semlio::FormatError(input + ": no selected frame could be read or holds a valid point; nothing to write");
    }
  }
  for (std::size_t k = 0; k < t.n_out; ++k) {
    if (t.stamp_known[k]) {
      t.t_origin_s = t.stamps[k];
      break;
    }
  }
  std::vector<double> times(t.n_out);
  double previous = t.t_origin_s;
  for (std::size_t k = 0; k < t.n_out; ++k) {
    double stamp = t.stamps[k];
    if (!t.stamp_known[k] || stamp < previous) {
      if (t.stamp_known[k]) ++t.stamps_clamped;
      stamp = previous;
    }
    previous = stamp;
    // KITTI: seconds since the first frame. t - t0 is exact (Sterbenz) for
    // stamps within a factor 2 of each other, so frame-to-frame differences
    // are those of the input bit for bit.
    times[k] = to_kitti ? stamp - t.t_origin_s : stamp;
  }
  semlio::io::write_kitti_times((dir / "times.txt").string(), times);
}

/// calib.txt (always for KITTI; for PCD when the input has Tr) and
/// poses.txt (when the input has ground truth).
inline void write_calib_and_poses(const ConvertOptions& o, const FrameSource& source, bool to_kitti,
                                  const fs::path& dir, ConvertTally& t) {
  const std::optional<semlio::SE3d> input_Tr = source.T_cam0_lidar();
  const semlio::SE3d Tr = input_Tr ? *input_Tr : semlio::SE3d();
  t.calib_note = "none written (the input has no camera calibration)";
  if (to_kitti || input_Tr) {
    // The input's calib.txt entries as read (P0..P3, Tr, Tr_imu_velo): its
    // numbers written back exactly, so Tr reads back bit for bit (an SE3
    // holds a quaternion: writing it as a matrix would move the last digits).
    semlio::io::Calibration calib;
    const std::string calib_file = input_calib_file(o, source.facts().format);
    if (!calib_file.empty()) calib = semlio::io::read_kitti_calib(calib_file);
    calib.T_cam0_velo.reset();  // set transforms override the entries as read
    calib.T_imu_velo.reset();
    if (calib.entries.count("Tr") == 0) calib.T_cam0_velo = Tr;
    semlio::io::write_kitti_calib((dir / "calib.txt").string(), calib);
    t.calib_note = input_Tr ? "Tr: the input's T_cam0_lidar" : "Tr: identity (the input has no camera calibration)";
    if (!calib_file.empty()) t.calib_note += ", entries of " + calib_file;
  }
  t.poses_note = "none (the input has no ground truth)";
  const std::optional<std::vector<semlio::SE3d>> gt = source.ground_truth_lidar();
  if (!gt) return;
  const fs::path poses_path = dir / "poses.txt";
  const std::string gt_file = source.ground_truth_source();
  std::error_code ec;
  if (to_kitti && fs::is_regular_file(gt_file, ec) && !semlio::io::looks_like_tum(gt_file)) {
    // A KITTI 3x4 file is stored in the frame poses.txt wants (camera-0 with
    // the input's Tr, else lidar = camera-0 under the identity Tr): its lines
    // are copied as they are.
    copy_lines(gt_file, t.first, t.n_out, poses_path);
  } else {
    std::vector<semlio::SE3d> sel(gt->begin() + static_cast<long>(t.first),
                                  gt->begin() + static_cast<long>(t.first + t.n_out));
    if (to_kitti) sel = semlio::io::lidar_to_camera(sel, Tr);
    semlio::io::write_kitti_poses(poses_path.string(), sel);
  }
  t.poses_note = "ground truth (" + gt_file + "), " +
                 (to_kitti ? "KITTI camera-0 frame: P_i = Tr T_i Tr^-1" : "lidar frame, KITTI 3x4");
}

/// convert.json: what was read and written.
inline void write_report(const ConvertOptions& o, const FrameSource& source, const fs::path& dir,
                         const ConvertTally& t) {
  const bool to_kitti = o.to == "kitti";
  const SourceFacts& facts = source.facts();
  std::ofstream os(dir / "convert.json");
  JsonWriter j(os);
  j.begin_object();
  j.field("schema", "semlio_convert/1").field("to", o.to);
  j.key("input").begin_object();
  j.field("format", facts.format).field("path", facts.path);
  for (const auto& [key, value] : facts.decided) j.field(key, value);
  j.field("ground_truth", source.ground_truth_source());
  j.end_object();
  j.field("input_frames", t.n_input).field("first", t.first).field("last", t.first + t.n_sel - 1);
  j.field("frames_selected", t.n_sel).field("frames_out", t.n_out);
  j.field("frames_written", static_cast<std::size_t>(std::count(t.written.begin(), t.written.end(), true)));
  j.field("unreadable_frames", t.unreadable).field("empty_frames", t.empty);
  j.field("bad_frames_written_as",
          to_kitti ? "no .bin: a gap in the numbering (KittiSequence allow_gaps reads it as a missing frame)"
                   : "a 0-point PCD");
  j.field("trailing_bad_frames_dropped", t.n_sel - t.n_out);
  j.key("skipped").begin_array();
  for (const SkippedFrame& s : t.skipped) {
    j.begin_object();
    j.field("input_frame", s.input_frame).field("output_frame", s.output_frame).field("reason", s.reason);
    j.end_object();
  }
  j.end_array();
  j.field("points_written", t.points);
  j.key("dropped_points").begin_object();
  j.field("nonfinite", t.dropped.dropped_nonfinite).field("zero", t.dropped.dropped_zero);
  j.end_object();
  j.field("labels_written", t.labels);
  if (t.labels) j.field("labels", "learning classes as their static SemanticKITTI raw ids (labels/NNNNNN.label)");
  j.array_field("fields_lost", t.lost);
  j.field("frames_with_rings", t.with_rings).field("frames_with_times", t.with_times);
  j.field("frames_without_intensity", t.no_intensity);
  j.field("times_txt", to_kitti ? "seconds since the first frame" : "stamps as read [s]");
  j.field("stamp_origin_s", exact_text(t.t_origin_s));
  j.field("stamps_clamped", t.stamps_clamped);
  j.field("calib", t.calib_note).field("poses", t.poses_note).field("imu", kImuNote);
  j.end_object();
  os << '\n';
  if (!os) throw semlio::IoError((dir / "convert.json").string() + ": write error");
}

/// The summary on stdout; the lost-fields warning on stderr.
inline void print_summary(const ConvertOptions& o, const FrameSource& source, const fs::path& out,
                          const ConvertTally& t) {
  const SourceFacts& facts = source.facts();
  std::printf("semlio_convert: %s (%s) -> %s (%s)\n", facts.path.c_str(), facts.format.c_str(), out.c_str(),
              o.to.c_str());
  for (const auto& [key, value] : facts.decided) std::printf("  %-18s %s\n", key.c_str(), value.c_str());
  std::printf("  %-18s %zu of %zu selected (input frames %zu-%zu of %zu)\n", "frames out", t.n_out, t.n_sel, t.first,
              t.first + t.n_sel - 1, t.n_input);
  std::printf("  %-18s %zu unreadable, %zu empty%s\n", "bad frames", t.unreadable, t.empty,
              t.skipped.empty() ? "" : (o.to == "kitti" ? " (gaps: no .bin)" : " (0-point PCDs)"));
  if (t.n_out < t.n_sel) {
    std::printf("  %-18s %zu after the last readable frame\n", "frames dropped", t.n_sel - t.n_out);
  }
  std::printf("  %-18s %zu written (%zu non-finite and %zu (0,0,0) dropped)\n", "points", t.points,
              t.dropped.dropped_nonfinite, t.dropped.dropped_zero);
  std::printf("  %-18s %s\n", "calib", t.calib_note.c_str());
  std::printf("  %-18s %s\n", "poses", t.poses_note.c_str());
  std::printf("  %-18s %s\n", "imu", kImuNote);
  if (t.stamps_clamped > 0) {
    std::printf("  %-18s %zu went backwards: set to the previous stamp\n", "stamps", t.stamps_clamped);
  }
  std::fflush(stdout);
  if (!t.lost.empty()) {
    std::string names;
    for (const std::string& l : t.lost) names += (names.empty() ? "" : ", ") + l;
    std::cerr << "semlio_convert: warning: per-point fields lost (a KITTI .bin holds x y z intensity only): " << names
              << "; --to pcd keeps them\n";
  }
}

}  // namespace detail

/// Runs the dataset mode; returns the exit status (0; 1 for an error, printed;
/// 2 for a bad command line).
inline int convert_dataset(const ConvertOptions& o) {
  if (o.first < 0 || o.last < -1) {
    std::cerr << "semlio_convert: --first " << o.first << " / --last " << o.last
              << ": frames count from 0 (--last -1: the last frame)\n";
    return 2;
  }
  try {
    detail::StagedOutput staged(o.out, o.input, o.overwrite);
    const std::unique_ptr<FrameSource> source_ptr = open_convert_source(o);
    FrameSource& source = *source_ptr;
    detail::ConvertTally t;
    t.n_input = source.size();
    if (t.n_input == 0) throw semlio::FormatError(source.facts().path + ": no frames to convert");
    const std::size_t last = o.last < 0 ? t.n_input - 1 : std::min(static_cast<std::size_t>(o.last), t.n_input - 1);
    t.first = static_cast<std::size_t>(o.first);
    if (t.first > last) {
      std::cerr << "semlio_convert: --first " << o.first << " / --last " << o.last << " select no frame of "
                << t.n_input << "\n";
      return 2;
    }
    t.n_sel = last - t.first + 1;
    // Ground truth checked before the first frame.
    if (const auto gt = source.ground_truth_lidar(); gt && gt->size() != t.n_input) {
      throw semlio::ValueError(source.ground_truth_source() + ": has " + std::to_string(gt->size()) +
                               " poses but the input has " + std::to_string(t.n_input) + " frames");
    }
    // KITTI labels/: written for every frame when the input has labels (a
    // KITTI folder's labels/, or a label field in the first scan).
    t.labels = source.has_labels();
    if (!t.labels) {
      const std::vector<semlio::Scan> firsts = source.first_scans(1);
      t.labels = !firsts.empty() && firsts.front().has_labels();
    }
    const bool to_kitti = o.to == "kitti";
    detail::convert_frames(source, last, to_kitti, staged.dir(), t);
    detail::write_times(to_kitti, staged.dir(), source.facts().path, t);
    detail::write_calib_and_poses(o, source, to_kitti, staged.dir(), t);
    detail::write_report(o, source, staged.dir(), t);
    staged.commit();
    detail::print_summary(o, source, staged.final_dir(), t);
    return 0;
  } catch (const semlio::Error& e) {
    std::cerr << "semlio_convert: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "semlio_convert: unexpected error converting " << o.input << ": " << e.what() << "\n";
    return 1;
  }
}

/// Parses the dataset mode's command line and runs it.
inline int convert_dataset_main(int argc, char** argv) {
  ConvertOptions o;
  CLI::App app{"semlio_convert: any input semlio reads -> a KITTI-layout folder or a folder of PCDs"};
  app.footer(
      "Single-file mode: semlio_convert IN OUT [--labels IN.label] [--ascii] (KITTI .bin, .pcd, .ply by extension).\n"
      "--to kitti: OUT/velodyne/NNNNNN.bin, labels/ (when the input has labels), times.txt (seconds since the first\n"
      "frame), calib.txt (Tr: the input's, else identity), poses.txt (ground truth, camera-0 frame), convert.json.\n"
      "Ring and per-point time fields are lost (a KITTI .bin holds x y z intensity): use --to pcd to keep them.\n"
      "A frame that cannot be read or holds no valid point is a gap in the numbering (no .bin).\n"
      "--to pcd: OUT/NNNNNN.pcd with every field, times.txt (stamps as read), poses.txt (lidar frame); bad frames\n"
      "are 0-point PCDs. semlio_run --format folder reads it back.\n"
      "The IMU stream is not converted. OUT must be new or empty; --overwrite replaces a previous conversion.");
  app.add_option("--input", o.input, "the data: a folder, a .bag, a .mcap, a .db3 or a rosbag2 folder")->required();
  app.add_option("--out", o.out, "the folder to write (must not exist or be empty)")->required();
  app.add_option("--format", o.format, "input format (auto: detected from the path)")
      ->check(CLI::IsMember({"auto", "kitti", "kitti-raw", "folder", "bag", "mcap", "db3"}));
  app.add_option("--lidar-topic", o.lidar_topic, "PointCloud2 topic of a bag (default: the only one)");
  app.add_option("--imu-topic", o.imu_topic, "Imu topic of a bag (checked, not converted)");
  app.add_option("--gt", o.gt, "ground-truth poses (KITTI 3x4 or TUM); default: the input's own, if any");
  app.add_option("--calib", o.calib,
                 "calib.txt with Tr (kitti, bags), or the folder of the calib_*.txt files (kitti-raw)");
  app.add_option("--to", o.to, "output layout")->check(CLI::IsMember({"kitti", "pcd"}));
  app.add_option("--first", o.first, "first input frame to convert (written as frame 0)");
  app.add_option("--last", o.last, "last input frame to convert (-1: the last)");
  app.add_flag("--overwrite", o.overwrite, "replace OUT when it holds a previous conversion (convert.json)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return convert_dataset(o);
}

}  // namespace semlio_examples
