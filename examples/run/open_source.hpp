#pragma once
// Opening any input a tool reads, by format (given or detected from the
// path): one function for semlio_run and semlio_convert, so both read the
// same inputs the same way.

#include <memory>
#include <string>
#include <tuple>

#include <semlio/core/error.hpp>

#include "file_sources.hpp"
#include "frame_source.hpp"
#if defined(SEMLIO_HAVE_BAGS)
#include "bag_source.hpp"
#endif

namespace semlio_examples {

/// An input as a tool's command line names it.
struct InputSpec {
  std::string input;                 ///< --input: a folder, a .bag, a .mcap, a .db3 or a rosbag2 folder
  std::string format = "auto";       ///< --format: auto | kitti | kitti-raw | folder | bag | mcap | db3
  std::string lidar_topic;           ///< --lidar-topic ("" = the only PointCloud2 topic)
  std::string imu_topic;             ///< --imu-topic ("" = the only Imu topic, if any)
  std::string gt;                    ///< --gt ("" = the input's own)
  std::string calib;                 ///< --calib ("" = the input's own)
  std::string labels = "labels";     ///< KITTI folders: the label folder ("" = none)
  bool allow_missing_frames = true;  ///< KITTI folders: a gap in the numbering costs one frame
};

/// Opens `in` (format detected from the path when "auto"); the first fact
/// recorded is how the format was decided. Throws what the sources throw,
/// and ConfigError for a bag in a build without the bag readers.
inline std::unique_ptr<FrameSource> open_source(const InputSpec& in) {
  std::string format = in.format;
  std::string why = "--format";
  if (format == "auto") std::tie(format, why) = detect_format(in.input);
  std::unique_ptr<FrameSource> source;
  if (format == "kitti") {
    SourceConfig sc;
    sc.labels = in.labels;
    sc.ground_truth_path = in.gt;
    sc.calib_path = in.calib;
    sc.allow_missing_frames = in.allow_missing_frames;
    source = std::make_unique<KittiFolderSource>(in.input, sc);
  } else if (format == "kitti-raw") {
    source = std::make_unique<KittiRawSource>(in.input, in.calib);
  } else if (format == "folder") {
    source = std::make_unique<ScanFolderSource>(in.input, in.gt);
  } else {
#if defined(SEMLIO_HAVE_BAGS)
    source = open_bag_source(in.input, format, in.lidar_topic, in.imu_topic, in.gt, in.calib);
#else
    throw semlio::ConfigError(in.input + ": this build has no bag readers (install libbz2-dev liblz4-dev "
                              "libzstd-dev libsqlite3-dev and reconfigure)");
#endif
  }
  source->add_fact_front("format_decided_by", why);
  return source;
}

}  // namespace semlio_examples
