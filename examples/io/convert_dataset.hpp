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
#include <tuple>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/pcd.hpp>
#include <semlio/io/read_stats.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/lie/se3.hpp>

#include "file_sources.hpp"
#include "frame_source.hpp"
#include "json_writer.hpp"
#if defined(SEMLIO_HAVE_BAGS)
#include "bag_source.hpp"
#endif

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

/// Opens `o.input` as semlio_run does (same formats, detection, topics,
/// --gt, --calib). Throws what the sources throw.
inline std::unique_ptr<FrameSource> open_convert_source(const ConvertOptions& o) {
  std::string format = o.format;
  std::string why = "--format";
  if (format == "auto") std::tie(format, why) = detect_format(o.input);
  std::unique_ptr<FrameSource> source;
  if (format == "kitti") {
    SourceConfig sc;
    sc.ground_truth_path = o.gt;
    sc.calib_path = o.calib;
    sc.allow_missing_frames = true;
    source = std::make_unique<KittiFolderSource>(o.input, sc);
  } else if (format == "kitti-raw") {
    source = std::make_unique<KittiRawSource>(o.input, o.calib);
  } else if (format == "folder") {
    source = std::make_unique<ScanFolderSource>(o.input, o.gt);
  } else {
#if defined(SEMLIO_HAVE_BAGS)
    source = open_bag_source(o.input, format, o.lidar_topic, o.imu_topic, o.gt, o.calib);
#else
    throw semlio::ConfigError(o.input + ": this build has no bag readers (install libbz2-dev liblz4-dev "
                              "libzstd-dev libsqlite3-dev and reconfigure)");
#endif
  }
  source->add_fact_front("format_decided_by", why);
  return source;
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
  std::size_t input_frame = 0;  ///< index in the input
  std::size_t output_frame = 0; ///< number in OUT
  std::string reason;           ///< the reader's error, or "no valid point"
};

}  // namespace detail

/// Runs the dataset mode; returns the exit status (0; 1 for an error, printed;
/// 2 for a bad command line).
inline int convert_dataset(const ConvertOptions& o) {
  namespace fs = std::filesystem;
  using detail::frame_name;
  if (o.first < 0 || o.last < -1) {
    std::cerr << "semlio_convert: --first " << o.first << " / --last " << o.last
              << ": frames count from 0 (--last -1: the last frame)\n";
    return 2;
  }
  try {
    detail::StagedOutput staged(o.out, o.input, o.overwrite);
    const std::unique_ptr<FrameSource> source_ptr = open_convert_source(o);
    FrameSource& source = *source_ptr;
    const SourceFacts& facts = source.facts();
    const std::size_t n_input = source.size();
    if (n_input == 0) throw semlio::FormatError(facts.path + ": no frames to convert");
    const std::size_t last = o.last < 0 ? n_input - 1 : std::min(static_cast<std::size_t>(o.last), n_input - 1);
    const auto first = static_cast<std::size_t>(o.first);
    if (first > last) {
      std::cerr << "semlio_convert: --first " << o.first << " / --last " << o.last << " select no frame of "
                << n_input << "\n";
      return 2;
    }
    const bool to_kitti = o.to == "kitti";
    const fs::path dir = staged.dir();

    // Ground truth and calibration, checked before the first frame.
    std::optional<std::vector<semlio::SE3d>> gt = source.ground_truth_lidar();
    if (gt && gt->size() != n_input) {
      throw semlio::ValueError(source.ground_truth_source() + ": has " + std::to_string(gt->size()) +
                               " poses but the input has " + std::to_string(n_input) + " frames");
    }
    const std::optional<semlio::SE3d> input_Tr = source.T_cam0_lidar();
    const semlio::SE3d Tr = input_Tr ? *input_Tr : semlio::SE3d();
    // Labels: written for every frame when the input has them (a KITTI
    // folder's labels/, or a label field in the first scan).
    bool labels = source.has_labels();
    if (!labels) {
      const std::vector<semlio::Scan> firsts = source.first_scans(1);
      labels = !firsts.empty() && firsts.front().has_labels();
    }
    if (to_kitti) {
      fs::create_directories(dir / "velodyne");
      if (labels) fs::create_directories(dir / "labels");
    }

    // The frames. A bag is read in order from its start, so frames before
    // --first are read and discarded; files are only read when selected.
    const bool sequential = facts.format == "bag" || facts.format == "mcap" || facts.format == "db3";
    const std::size_t n_sel = last - first + 1;
    std::vector<double> stamps(n_sel, 0.0);
    std::vector<bool> stamp_known(n_sel, false);
    std::vector<bool> written(n_sel, false);
    std::vector<detail::SkippedFrame> skipped;
    std::size_t unreadable = 0, empty = 0, points = 0, no_intensity = 0, with_rings = 0, with_times = 0;
    std::size_t labels_lost = 0;
    semlio::io::ReadStats dropped;
    for (std::size_t i = sequential ? 0 : first; i <= last; ++i) {
      SourceFrame f = source.read(i);
      if (i < first) continue;
      const std::size_t k = i - first;
      const std::optional<double> hint = source.stamp_hint(i);
      stamp_known[k] = !f.missing || hint.has_value();
      stamps[k] = hint && f.missing ? *hint : f.scan.stamp_s;
      dropped.dropped_nonfinite += f.dropped.dropped_nonfinite;
      dropped.dropped_zero += f.dropped.dropped_zero;
      const bool bad = !f.error.empty() || f.missing;
      if (bad || f.scan.empty()) {
        if (bad) ++unreadable;
        else ++empty;
        skipped.push_back({i, k, bad ? (f.error.empty() ? "missing" : f.error) : "no valid point"});
        if (to_kitti) continue;
        f.scan = semlio::Scan();  // --to pcd: a 0-point PCD keeps the numbering
      }
      const semlio::Scan& scan = f.scan;
      points += scan.size();
      if (!scan.empty() && !scan.has_intensity()) ++no_intensity;
      if (scan.has_rings()) ++with_rings;
      if (scan.has_times()) ++with_times;
      if (to_kitti) {
        semlio::io::write_kitti_bin((dir / "velodyne" / (frame_name(k) + ".bin")).string(), scan);
        if (labels) {
          semlio::io::write_label_file((dir / "labels" / (frame_name(k) + ".label")).string(),
                                       semlio::io::raw_labels(scan));
        } else if (scan.has_labels()) {
          ++labels_lost;
        }
      } else {
        semlio::io::write_pcd((dir / (frame_name(k) + ".pcd")).string(), scan, semlio::io::PcdEncoding::kBinary);
      }
      written[k] = true;
    }

    // A KITTI folder ends at its last .bin: frames after it are dropped.
    std::size_t n_out = n_sel;
    if (to_kitti) {
      while (n_out > 0 && !written[n_out - 1]) --n_out;
      if (n_out == 0) {
        throw semlio::FormatError(facts.path + ": no selected frame could be read or holds a valid point; "
                                               "nothing to write");
      }
    }
    const std::size_t trailing_dropped = n_sel - n_out;

    // Stamps: a frame whose stamp is unknown (a bag that ended early) and
    // stamps going backwards take the previous stamp (times.txt must not
    // decrease).
    std::size_t stamps_clamped = 0;
    double t_origin = 0.0;
    bool have_origin = false;
    for (std::size_t k = 0; k < n_out; ++k) {
      if (!have_origin && stamp_known[k]) {
        t_origin = stamps[k];
        have_origin = true;
      }
    }
    double previous = t_origin;
    for (std::size_t k = 0; k < n_out; ++k) {
      if (!stamp_known[k] || stamps[k] < previous) {
        if (stamp_known[k]) ++stamps_clamped;
        stamps[k] = previous;
      }
      previous = stamps[k];
    }
    std::vector<double> times(stamps.begin(), stamps.begin() + static_cast<long>(n_out));
    // KITTI: seconds since the first frame. t - t0 is exact (Sterbenz) for
    // stamps within a factor 2 of each other, so frame-to-frame differences
    // are those of the input bit for bit.
    if (to_kitti) {
      for (double& t : times) t -= t_origin;
    }
    semlio::io::write_kitti_times((dir / "times.txt").string(), times);

    std::string calib_note = "none written (the input has no camera calibration)";
    if (to_kitti || input_Tr) {
      // The input's calib.txt entries as read (P0..P3, Tr, Tr_imu_velo): its
      // numbers written back exactly, so Tr reads back bit for bit (an SE3
      // holds a quaternion: writing it as a matrix would move the last digits).
      semlio::io::Calibration calib;
      const std::string calib_file = detail::input_calib_file(o, facts.format);
      if (!calib_file.empty()) calib = semlio::io::read_kitti_calib(calib_file);
      calib.T_cam0_velo.reset();  // set transforms override the entries as read
      calib.T_imu_velo.reset();
      if (calib.entries.count("Tr") == 0) calib.T_cam0_velo = Tr;
      semlio::io::write_kitti_calib((dir / "calib.txt").string(), calib);
      calib_note = input_Tr ? "Tr: the input's T_cam0_lidar" : "Tr: identity (the input has no camera calibration)";
      if (!calib_file.empty()) calib_note += ", entries of " + calib_file;
    }
    std::string poses_note = "none (the input has no ground truth)";
    if (gt) {
      const fs::path poses_path = dir / "poses.txt";
      const std::string gt_file = source.ground_truth_source();
      std::error_code ec;
      if (to_kitti && fs::is_regular_file(gt_file, ec) && !semlio::io::looks_like_tum(gt_file)) {
        // A KITTI 3x4 file is stored in the frame poses.txt wants (camera-0
        // with the input's Tr, else lidar = camera-0 under the identity Tr):
        // its lines are copied as they are.
        detail::copy_lines(gt_file, first, n_out, poses_path);
      } else {
        std::vector<semlio::SE3d> sel(gt->begin() + static_cast<long>(first),
                                      gt->begin() + static_cast<long>(first + n_out));
        if (to_kitti) sel = semlio::io::lidar_to_camera(sel, Tr);
        semlio::io::write_kitti_poses(poses_path.string(), sel);
      }
      poses_note = "ground truth (" + gt_file + "), " +
                   (to_kitti ? "KITTI camera-0 frame: P_i = Tr T_i Tr^-1" : "lidar frame, KITTI 3x4");
    }

    // What KITTI .bin cannot carry.
    std::vector<std::string> lost;
    if (to_kitti && with_rings > 0) lost.emplace_back("ring");
    if (to_kitti && with_times > 0) lost.emplace_back("time");
    if (to_kitti && labels_lost > 0) lost.emplace_back("label");
    const char* imu_note = "not converted (the KITTI and PCD folder layouts have no generic IMU file)";

    {
      std::ofstream os(dir / "convert.json");
      JsonWriter j(os);
      j.begin_object();
      j.field("schema", "semlio_convert/1").field("to", o.to);
      j.key("input").begin_object();
      j.field("format", facts.format).field("path", facts.path);
      for (const auto& [key, value] : facts.decided) j.field(key, value);
      j.field("ground_truth", source.ground_truth_source());
      j.end_object();
      j.field("input_frames", n_input).field("first", first).field("last", last);
      j.field("frames_selected", n_sel).field("frames_out", n_out);
      j.field("frames_written", static_cast<std::size_t>(std::count(written.begin(), written.end(), true)));
      j.field("unreadable_frames", unreadable).field("empty_frames", empty);
      j.field("bad_frames_written_as",
              to_kitti ? "no .bin: a gap in the numbering (KittiSequence allow_gaps reads it as a missing frame)"
                       : "a 0-point PCD");
      j.field("trailing_bad_frames_dropped", trailing_dropped);
      j.key("skipped").begin_array();
      for (const detail::SkippedFrame& s : skipped) {
        j.begin_object();
        j.field("input_frame", s.input_frame).field("output_frame", s.output_frame).field("reason", s.reason);
        j.end_object();
      }
      j.end_array();
      j.field("points_written", points);
      j.key("dropped_points").begin_object();
      j.field("nonfinite", dropped.dropped_nonfinite).field("zero", dropped.dropped_zero);
      j.end_object();
      j.field("labels_written", labels);
      j.array_field("fields_lost", lost);
      j.field("frames_with_rings", with_rings).field("frames_with_times", with_times);
      j.field("frames_without_intensity", no_intensity);
      j.field("times_txt", to_kitti ? "seconds since the first frame" : "stamps as read [s]");
      j.field("stamp_origin_s", detail::exact_text(t_origin));
      j.field("stamps_clamped", stamps_clamped);
      j.field("calib", calib_note).field("poses", poses_note).field("imu", imu_note);
      j.end_object();
      os << '\n';
      if (!os) throw semlio::IoError((dir / "convert.json").string() + ": write error");
    }
    staged.commit();

    // Summary.
    const std::string out = staged.final_dir().string();
    std::printf("semlio_convert: %s (%s) -> %s (%s)\n", facts.path.c_str(), facts.format.c_str(), out.c_str(),
                o.to.c_str());
    for (const auto& [key, value] : facts.decided) std::printf("  %-18s %s\n", key.c_str(), value.c_str());
    std::printf("  %-18s %zu of %zu selected (input frames %zu-%zu of %zu)\n", "frames out", n_out, n_sel, first,
                last, n_input);
    std::printf("  %-18s %zu unreadable, %zu empty%s\n", "bad frames", unreadable, empty,
                skipped.empty() ? "" : (to_kitti ? " (gaps: no .bin)" : " (0-point PCDs)"));
    if (trailing_dropped > 0) std::printf("  %-18s %zu after the last readable frame\n", "frames dropped", trailing_dropped);
    std::printf("  %-18s %zu written (%zu non-finite and %zu (0,0,0) dropped)\n", "points", points,
                dropped.dropped_nonfinite, dropped.dropped_zero);
    std::printf("  %-18s %s\n", "calib", calib_note.c_str());
    std::printf("  %-18s %s\n", "poses", poses_note.c_str());
    std::printf("  %-18s %s\n", "imu", imu_note);
    if (stamps_clamped > 0) std::printf("  %-18s %zu stamps went backwards: set to the previous\n", "stamps", stamps_clamped);
    if (!lost.empty()) {
      std::string names;
      for (const std::string& l : lost) names += (names.empty() ? "" : ", ") + l;
      std::cerr << "semlio_convert: warning: per-point fields lost (a KITTI .bin holds x y z intensity only): "
                << names << "; --to pcd keeps them\n";
    }
    std::fflush(stdout);
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
