// semlio_run: the odometry on any input semlio reads -- a KITTI odometry
// folder, a KITTI raw drive as published, a folder of PCD / PLY / .bin scans,
// a ROS 1 bag, a ROS 2 bag (MCAP or sqlite3) -- with semlio_kitti's options,
// outputs, summary and report.json (whose "input" object records the format,
// topics and sensor, and how each was decided).

#include <CLI/CLI.hpp>

#include <memory>
#include <optional>
#include <string>

#include "frame_source.hpp"
#include "odometry_tool.hpp"
#include "open_source.hpp"
#include "sensor_yaml.hpp"
#include "tool_mains.hpp"

namespace {

bool is_yaml_file(const std::string& s) {
  const auto ends = [&s](const char* e) {
    const std::string x(e);
    return s.size() > x.size() && s.compare(s.size() - x.size(), x.size(), x) == 0;
  };
  return ends(".yaml") || ends(".yml");
}

// What else follows the profile besides PipelineSettings: the meaning of the
// input's header stamps and the ground segmenter's sensor height.
void apply_profile(const semlio::SensorProfile& profile, semlio_examples::FrameSource& source,
                   semlio_examples::RunContext& ctx) {
  source.set_header_stamp(profile.header_stamp, profile.sweep_period_s());
  ctx.segmenter.sensor_height_m = profile.mount_height_m;  // reported by sensor_facts()
}

// The sensor of a run (--sensor, --platform): a named profile, a sensor YAML,
// or auto -- KITTI's HDL-64E scans (recognised by their point order) keep
// their point-order rings and KITTI's vertical correction, in a KITTI folder
// as in a bag; any other input gets the beam table detected from its first
// scans (from the cloud's ring field when it has one), with the facts of the
// named profile that table matches (features/profile_match.hpp). Applied on
// top of the presets' settings, before the user's --config.
void decide_sensor(const std::string& sensor, const std::string& platform, semlio_examples::FrameSource& source,
                   semlio_examples::RunContext& ctx) {
  semlio_examples::SensorYaml y;
  std::string decided_by = "--sensor " + sensor;
  bool kitti_layout = false;
  std::optional<semlio::BeamDetection> detection;
  const auto detect_first_scans = [&source] {
    const std::vector<semlio::Scan> scans = source.first_scans(3);
    if (scans.empty()) throw semlio::FormatError(source.facts().path + ": no readable scan to detect the beams from");
    return semlio::detect_beams(scans);
  };
  if (is_yaml_file(sensor)) {
    y = semlio_examples::load_sensor_yaml(sensor);
  } else if (sensor == "auto") {
    const semlio::BeamDetection d = detect_first_scans();
    // 64 rings stored one after the other whose elevations do not separate:
    // KITTI's calibrated .bin layout (beam_detection.hpp). From a KITTI
    // folder that is enough; from a bag or a scan folder the rings' elevations
    // must also lie where the HDL-64E's do (a converter such as kitti2bag
    // keeps the point order).
    const bool point_order_64 = d.source == semlio::BeamSource::kPointOrder && d.beams() == 64;
    if (point_order_64 && source.kitti_scans()) {
      ctx.sensor_facts = {{"profile", "hdl64e"},
                          {"decided_by", "auto: KITTI HDL-64E scans, rings from point order"},
                          {"detection", d.note}};
      if (!platform.empty() && platform != "vehicle") {
        ctx.settings = semlio::settings_for_sensor(semlio::sensor_profile("hdl64e"), semlio::motion_profile(platform),
                                                   ctx.settings);
      }
      return;
    }
    const std::optional<semlio::ProfileMatch> kitti =
        point_order_64 ? semlio::match_sensor_profile(d.elevations_rad) : std::nullopt;
    if (kitti && kitti->profile == "hdl64e") {
      // A bag of KITTI scans: what `--sensor hdl64e --kitti-correction on` does.
      y.sensor = semlio::sensor_profile("hdl64e");
      kitti_layout = true;
      detection = d;
      decided_by = "auto: KITTI HDL-64E scans (rings from point order, KITTI's vertical correction)";
    } else {
      // Any other data: the detected table, through the common path below.
      ctx.settings.odometry.kitti_vertical_correction = false;
      y.detect = true;
      detection = d;
      decided_by = "auto: beams detected from the first scans";
    }
  } else {
    y.sensor = semlio::sensor_profile(sensor);
  }
  if (!platform.empty()) y.motion = semlio::motion_profile(platform);
  if (y.detect && !detection) detection = detect_first_scans();  // a sensor YAML with profile: auto
  std::optional<semlio::ProfileMatch> match;
  const semlio::SensorProfile profile =
      semlio_examples::resolve_sensor(y, detection ? &*detection : nullptr, &match);
  const bool kitti_correction = kitti_layout || ctx.settings.odometry.kitti_vertical_correction;
  ctx.settings = semlio::settings_for_sensor(profile, y.motion, ctx.settings);
  ctx.settings.odometry.kitti_vertical_correction = kitti_correction;
  ctx.sensor_facts = semlio_examples::sensor_facts(profile, y.motion, detection ? &*detection : nullptr,
                                                   match ? &*match : nullptr);
  if (match) decided_by += ", matched to " + match->profile;
  ctx.sensor_facts.emplace_back("decided_by", decided_by);
  apply_profile(profile, source, ctx);
  if (y.T_imu_lidar) ctx.T_imu_lidar = y.T_imu_lidar;
  y.apply_imu(ctx.lc.imu);
}

struct InputOptions {
  std::string input;
  std::string format = "auto";
  std::string lidar_topic;
  std::string imu_topic;
  std::string sensor = "auto";
  std::string platform;
  std::string gt;
  std::string calib;
};

}  // namespace

int semlio_examples::semlio_run_main(int argc, char** argv) {
  semlio_examples::RunOptions opt;
  InputOptions in;
  CLI::App app{"semlio_run: semantic lidar(-inertial) odometry on KITTI, KITTI raw, scan folders and ROS 1 / ROS 2 bags"};
  app.footer(
      "Outputs in OUT/ as semlio_kitti's: poses.txt, poses_odom.txt, poses_tum.txt, keyframes.txt, map.ply, report.json.\n"
      "Formats: kitti (velodyne/ + calib.txt, times.txt), kitti-raw (a YYYY_MM_DD_drive_NNNN_sync folder as published),\n"
      "folder (.pcd/.ply/.bin files sorted by the number in their names, optional times.txt and poses.txt),\n"
      "bag (ROS 1), mcap and db3 (ROS 2: sensor_msgs/PointCloud2 and sensor_msgs/Imu).");
  app.add_option("--input", in.input, "the data: a folder, a .bag, a .mcap, a .db3 or a rosbag2 folder")->required();
  app.add_option("--format", in.format, "input format (auto: detected from the path)")
      ->check(CLI::IsMember({"auto", "kitti", "kitti-raw", "folder", "bag", "mcap", "db3"}));
  app.add_option("--lidar-topic", in.lidar_topic, "PointCloud2 topic of a bag (default: the only one)");
  app.add_option("--imu-topic", in.imu_topic, "Imu topic of a bag (default: the only one, if any)");
  app.add_option("--sensor", in.sensor,
                 "lidar: a profile name (hdl64e, vlp16, os1-64, ...), auto (the cloud's ring field, else KITTI point "
                 "order, else beams detected from the data), or a sensor YAML file");
  app.add_option("--platform", in.platform,
                 "how the sensor is carried: vehicle (default; KITTI's gates) or hand_held (up to 2 m/s and 2 rad/s "
                 "between frames); default: the sensor YAML's platform")
      ->check(CLI::IsMember({"vehicle", "hand_held"}));
  app.add_option("--gt", in.gt, "ground-truth poses (KITTI 3x4 or TUM); default: the input's own, if any");
  app.add_option("--calib", in.calib,
                 "calib.txt with Tr (kitti, bags: ground truth and outputs in KITTI's camera-0 frame), or the folder "
                 "of the calib_*.txt files (kitti-raw)");
  semlio_examples::add_run_options(app, opt);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return semlio_examples::run_tool("semlio_run", opt, [&]() -> std::unique_ptr<semlio_examples::FrameSource> {
    // The sequence's own labels/ only when the run reads labels from files.
    const bool label_files = opt.labels != "none" && opt.labels != "geometric";
    return semlio_examples::open_source({.input = in.input,
                                         .format = in.format,
                                         .lidar_topic = in.lidar_topic,
                                         .imu_topic = in.imu_topic,
                                         .gt = in.gt,
                                         .calib = in.calib,
                                         .labels = label_files ? opt.labels : "",
                                         .allow_missing_frames = opt.missing_frames == "empty"});
  }, [&](semlio_examples::FrameSource& source, semlio_examples::RunContext& ctx) {
    decide_sensor(in.sensor, in.platform, source, ctx);
  });
}
