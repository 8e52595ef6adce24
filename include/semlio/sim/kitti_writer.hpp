#pragma once
/// \file
/// Writes a simulated drive in KITTI layout:
///   velodyne/NNNNNN.bin   x y z intensity (float32), lidar frame, KITTI point order
///   labels/NNNNNN.label   exact raw SemanticKITTI id | instance << 16 (moving actors: moving-* ids)
///   predictions/NNNNNN.label  network-like predictions (sim/label_noise.hpp), raw ids, no instance
///   poses.txt             ground truth at each sweep start, camera-0 frame relative to frame 0
///                         (P_i = Tr T_lidar0_lidari Tr^-1, Tr of KITTI sequence 00)
///   calib.txt             P0 and Tr of KITTI sequence 00, Tr_imu_velo (lidar -> IMU)
///   times.txt             sweep start times [s] (frame 0 at 0)
///   oxts/                 KITTI raw OXTS: data/NNNNNNNNNN.txt at the IMU rate, timestamps.txt
///   sim.json              every setting and the achieved prediction mIoU (fields: see sim_json())
/// Same simulator config -> byte-identical files, for any writer thread count
/// (frames are independent and written by fixed round-robin assignment).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <numbers>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/logger.hpp>
#include <semlio/eval/miou.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/oxts.hpp>
#include <semlio/io/trajectory.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/sim/imu.hpp>
#include <semlio/sim/label_noise.hpp>
#include <semlio/sim/simulator.hpp>

namespace semlio::sim {

/// `Tr` (velodyne -> camera 0) of KITTI odometry sequence 00 (the values of
/// calib_00-02_Tr_P0_RECONSTRUCTED.txt).
inline SE3d kitti00_T_cam0_velo() {
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M << 4.276802385584e-04, -9.999672484946e-01, -8.084491683471e-03, -1.198459927713e-02,  //
      -7.210626507497e-03, 8.081198471645e-03, -9.999413164504e-01, -5.403984729748e-02,   //
      9.999738645903e-01, 4.859485810390e-04, -7.206933692422e-03, -2.921968648686e-01,    //
      0.0, 0.0, 0.0, 1.0;
  return SE3d(M);
}

/// `P0` of KITTI odometry sequence 00 (3x4 row-major).
inline std::vector<double> kitti00_P0() {
  return {7.188560000000e+02, 0.0, 6.071928000000e+02, 0.0, 0.0, 7.188560000000e+02, 1.852157000000e+02, 0.0,
          0.0, 0.0, 1.0, 0.0};
}

/// Writer settings.
struct KittiWriterConfig {
  int threads = 1;                    ///< frames generated in parallel (output identical for any count)
  SE3d T_imu_lidar = default_T_imu_lidar();  ///< written as Tr_imu_velo; the IMU is simulated there
  double epoch_s = 1317643200.0;      ///< OXTS time of t = 0 (2011-10-03 12:00:00, a KITTI raw day)
  double origin_lat_deg = 49.011;     ///< world origin latitude for OXTS lat/lon (Karlsruhe)
  double origin_lon_deg = 8.4237;     ///< world origin longitude
  double origin_alt_m = 115.0;        ///< world origin altitude
  bool imu_noise = true;              ///< false: exact IMU samples
  Logger logger;                      ///< progress messages (optional)
};

/// What was written.
struct KittiWriteReport {
  std::size_t frames = 0;             ///< frames written
  std::uint64_t points = 0;           ///< points over all frames
  double prediction_miou = 0.0;       ///< mIoU of predictions/ against labels/ over all frames
  double calibration_miou = 0.0;      ///< mIoU on the calibration frames
  double label_error_scale = 0.0;     ///< calibrated error scale of the label-noise model
  std::size_t imu_samples = 0;        ///< OXTS records written
};

namespace detail {

inline void append_json_number(std::string& out, double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  out.append(buf, res.ptr);
}

/// OXTS records of the IMU (at T_imu_body on the ego) from its samples and
/// the ground-truth trajectory; world x = east, y = north, z = up.
inline std::vector<io::OxtsRecord> oxts_records(const Trajectory& ego, const SE3d& T_imu_body,
                                                const std::vector<ImuSample>& samples, const KittiWriterConfig& cfg) {
  constexpr double kR = io::kOxtsEarthRadius_m;
  const double pi = std::numbers::pi;
  const double scale = std::cos(cfg.origin_lat_deg * pi / 180.0);
  const double x0 = scale * cfg.origin_lon_deg * pi * kR / 180.0;
  const double y0 = scale * kR * std::log(std::tan((90.0 + cfg.origin_lat_deg) * pi / 360.0));
  const SE3d T_body_imu = T_imu_body.inverse();
  std::vector<io::OxtsRecord> out;
  out.reserve(samples.size());
  for (const ImuSample& s : samples) {
    const KinematicState k = ego.state(s.stamp_s);
    const SE3d T_world_imu = k.T_world_body * T_body_imu;
    const Eigen::Matrix3d R = T_world_imu.rotation();
    const Eigen::Vector3d p = T_world_imu.translation();
    const Eigen::Vector3d r_body = T_body_imu.translation();
    const Eigen::Vector3d v_world =
        k.velocity_world_mps + k.T_world_body.rotation() * k.angular_velocity_body_radps.cross(r_body);
    io::OxtsRecord r;
    r.stamp_s = cfg.epoch_s + s.stamp_s;
    r.lon_deg = (p.x() + x0) * 180.0 / (pi * kR * scale);
    r.lat_deg = 360.0 / pi * std::atan(std::exp((p.y() + y0) / (kR * scale))) - 90.0;
    r.alt_m = cfg.origin_alt_m + p.z();
    // R = Rz(yaw) Ry(pitch) Rx(roll), the convention io::oxts_pose_mercator reads back.
    r.yaw_rad = std::atan2(R(1, 0), R(0, 0));
    r.pitch_rad = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
    r.roll_rad = std::atan2(R(2, 1), R(2, 2));
    const Eigen::Matrix3d Rz = Eigen::AngleAxisd(r.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    r.vn_mps = v_world.y();
    r.ve_mps = v_world.x();
    r.velocity_flu_mps = Rz.transpose() * v_world;
    r.accel_body_mps2 = s.accel_mps2;
    r.accel_flu_mps2 = Rz.transpose() * (R * s.accel_mps2);
    r.gyro_body_radps = s.gyro_radps;
    r.gyro_flu_radps = Rz.transpose() * (R * s.gyro_radps);
    r.pos_accuracy_m = 0.05;
    r.vel_accuracy_mps = 0.02;
    r.navstat = 4;
    r.numsats = 10;
    r.posmode = 4;
    r.velmode = 4;
    r.orimode = 6;
    out.push_back(r);
  }
  return out;
}

}  // namespace detail

/// sim.json: one flat object. Fields: format ("semlio-sim-1"), world,
/// traffic, frames, seed, revisit, distortion, imu_rate_hz, label_quality
/// (target mIoU), achieved_label_miou (predictions vs labels, all frames),
/// calibration_label_miou, label_error_scale, lidar_* (beams, elevation
/// limits [deg], azimuth_steps, rate_hz, max/min range [m], mount_height_m,
/// range_noise_sigma_m, intensity_noise_sigma, dropout_base, grazing_cos,
/// far_dropout_start_m, noise), time_reference ("sweep_start"),
/// point_frame ("lidar_at_sweep_start" or "lidar_at_point_time"),
/// T_imu_lidar (12 numbers, row-major 3x4), imu_noise, route_length_m,
/// loop_length_m (one lap of a revisit route; 0 for open routes),
/// revisit_route ("none", "block_loop" or "out_and_back"), return_time_s
/// (revisit: when the ego is back at its start, the last frame's stamp; 0 for
/// open routes), ego_duration_s, actors, points.
inline std::string sim_json(const Simulator& sim, const KittiWriterConfig& wc, const KittiWriteReport& rep) {
  const SimulatorConfig& c = sim.config();
  const LidarConfig& l = c.lidar;
  std::string j = "{\n";
  const auto str = [&](const char* k, std::string_view v) {
    j += "  \"";
    j += k;
    j += "\": \"";
    j += v;
    j += "\",\n";
  };
  const auto num = [&](const char* k, double v) {
    j += "  \"";
    j += k;
    j += "\": ";
    detail::append_json_number(j, v);
    j += ",\n";
  };
  const auto boolean = [&](const char* k, bool v) {
    j += "  \"";
    j += k;
    j += "\": ";
    j += v ? "true" : "false";
    j += ",\n";
  };
  str("format", "semlio-sim-1");
  str("world", world_name(c.world));
  str("traffic", traffic_name(c.traffic));
  num("frames", static_cast<double>(c.frames));
  num("seed", static_cast<double>(c.seed));
  boolean("revisit", c.revisit);
  boolean("distortion", c.distortion);
  num("imu_rate_hz", c.imu_rate_hz);
  boolean("imu_noise", wc.imu_noise);
  num("label_quality", c.label_quality);
  num("achieved_label_miou", rep.prediction_miou);
  num("calibration_label_miou", rep.calibration_miou);
  num("label_error_scale", rep.label_error_scale);
  num("lidar_beams", l.beams);
  num("lidar_upper_top_deg", l.upper_top_deg);
  num("lidar_upper_bottom_deg", l.upper_bottom_deg);
  num("lidar_lower_top_deg", l.lower_top_deg);
  num("lidar_lower_bottom_deg", l.lower_bottom_deg);
  num("lidar_azimuth_steps", l.azimuth_steps);
  num("lidar_rate_hz", l.rate_hz);
  num("lidar_max_range_m", l.max_range_m);
  num("lidar_min_range_m", l.min_range_m);
  num("lidar_mount_height_m", l.mount_height_m);
  num("lidar_range_noise_sigma_m", l.range_noise_sigma_m);
  num("lidar_intensity_noise_sigma", l.intensity_noise_sigma);
  num("lidar_dropout_base", l.dropout_base);
  num("lidar_grazing_cos", l.grazing_cos);
  num("lidar_far_dropout_start_m", l.far_dropout_start_m);
  boolean("lidar_noise", l.noise);
  str("time_reference", "sweep_start");
  str("point_frame", c.distortion ? "lidar_at_point_time" : "lidar_at_sweep_start");
  j += "  \"T_imu_lidar\": [";
  const Eigen::Matrix4d M = wc.T_imu_lidar.matrix();
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 4; ++k) {
      detail::append_json_number(j, M(r, k));
      if (r != 2 || k != 3) j += ", ";
    }
  }
  j += "],\n";
  num("route_length_m", sim.ego().length_m());
  num("loop_length_m", sim.world().loop_length_m);
  str("revisit_route", sim.world().revisit_route.empty() ? "none" : sim.world().revisit_route);
  num("return_time_s", sim.world().return_time_s);
  num("ego_duration_s", sim.ego().duration_s());
  num("actors", static_cast<double>(sim.traffic().actors().size()));
  j += "  \"points\": ";
  detail::append_json_number(j, static_cast<double>(rep.points));
  j += "\n}\n";
  return j;
}

/// Writes the whole drive of `sim` into `dir` (created when missing). Throws
/// IoError when a file cannot be written. Thread-safe with respect to `sim`.
inline KittiWriteReport write_kitti_sequence(const Simulator& sim, const std::string& dir,
                                             const KittiWriterConfig& wc = {}) {
  namespace fs = std::filesystem;
  if (wc.threads < 1) throw ConfigError("KittiWriterConfig.threads must be >= 1, got " + std::to_string(wc.threads));
  const fs::path root(dir);
  for (const char* sub : {"velodyne", "labels", "predictions"}) {
    std::error_code ec;
    fs::create_directories(root / sub, ec);
    if (ec) throw IoError(semlio::detail::where((root / sub).string(), 0, "cannot create directory: " + ec.message()));
  }
  const std::size_t n = sim.frame_count();
  const int cols = sim.lidar().columns();
  const auto range_image = [&](const Frame& f) {
    RangeImageLabels r;
    r.labels = f.scan.labels;
    r.instances = f.scan.instances;
    r.rings = f.scan.rings;
    r.columns = f.columns;
    r.num_rings = sim.lidar().rings();
    r.num_columns = cols;
    return r;
  };
  // Calibrate the prediction noise on up to 24 evenly spaced frames (with 3
  // or 8 the mIoU of a whole 1000-frame drive missed the target by up to 0.07).
  LabelNoiseConfig lnc;
  lnc.target_miou = sim.config().label_quality;
  lnc.seed = sim.config().seed;
  LabelNoise noise(lnc);
  KittiWriteReport rep;
  {
    std::vector<std::size_t> calib_frames;
    const std::size_t count = std::min<std::size_t>(24, n);
    for (std::size_t k = 0; k < count; ++k) calib_frames.push_back(count > 1 ? k * (n - 1) / (count - 1) : 0);
    std::vector<Frame> frames;
    for (const std::size_t i : calib_frames) frames.push_back(sim.frame(i));
    std::vector<RangeImageLabels> scenes;
    for (const Frame& f : frames) scenes.push_back(range_image(f));
    rep.calibration_miou = noise.calibrate(scenes);
    rep.label_error_scale = noise.error_scale();
  }
  // Frames, in parallel with a fixed round-robin assignment.
  std::mutex mutex;
  eval::ConfusionMatrix confusion;
  std::uint64_t points = 0;
  std::size_t done = 0;
  const auto worker = [&](int w, int stride) {
    eval::ConfusionMatrix local;
    std::uint64_t local_points = 0;
    for (std::size_t i = static_cast<std::size_t>(w); i < n; i += static_cast<std::size_t>(stride)) {
      const Frame f = sim.frame(i);
      const std::string stem = io::detail::frame_stem(i, 6);
      io::write_kitti_bin((root / "velodyne" / (stem + ".bin")).string(), f.scan);
      io::write_label_file((root / "labels" / (stem + ".label")).string(), f.raw_labels);
      const std::vector<Class> pred = noise.predict(range_image(f), i);
      std::vector<std::uint32_t> pred_raw(pred.size());
      for (std::size_t k = 0; k < pred.size(); ++k) pred_raw[k] = raw_id(pred[k]);
      io::write_label_file((root / "predictions" / (stem + ".label")).string(), pred_raw);
      local.add(f.scan.labels, pred);
      local_points += f.scan.size();
      const std::lock_guard<std::mutex> lock(mutex);
      ++done;
      if (done % 100 == 0) log(wc.logger, LogLevel::kInfo, "frames written: " + std::to_string(done) + "/" + std::to_string(n));
    }
    const std::lock_guard<std::mutex> lock(mutex);
    confusion.merge(local);
    points += local_points;
  };
  const int threads = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(wc.threads), n));
  if (threads <= 1) {
    worker(0, 1);
  } else {
    std::vector<std::thread> pool;
    for (int w = 0; w < threads; ++w) pool.emplace_back(worker, w, threads);
    for (auto& t : pool) t.join();
  }
  rep.frames = n;
  rep.points = points;
  rep.prediction_miou = confusion.report().miou;

  // Poses (camera-0 convention, relative to frame 0), times, calibration.
  const SE3d Tr = kitti00_T_cam0_velo();
  const std::vector<SE3d> T_lidar0_lidar = sim.lidar_poses();
  std::vector<double> times(n);
  for (std::size_t i = 0; i < n; ++i) times[i] = sim.frame_stamp_s(i);
  io::write_kitti_poses((root / "poses.txt").string(), io::lidar_to_camera(T_lidar0_lidar, Tr));
  io::write_kitti_times((root / "times.txt").string(), times);
  io::Calibration calib;
  calib.entries["P0"] = kitti00_P0();
  calib.T_cam0_velo = Tr;
  calib.T_imu_velo = wc.T_imu_lidar;
  io::write_kitti_calib((root / "calib.txt").string(), calib);

  // IMU at T_imu_body = T_imu_lidar * T_lidar_body, over the frames' time span.
  ImuConfig ic;
  ic.noise = wc.imu_noise;
  ic.seed = sim.config().seed;
  const SimulatedImu imu = sim.imu(ic, wc.T_imu_lidar);
  const SE3d T_imu_body = wc.T_imu_lidar * sim.T_body_lidar().inverse();
  io::write_oxts((root / "oxts").string(), detail::oxts_records(sim.ego(), T_imu_body, imu.samples, wc));
  rep.imu_samples = imu.samples.size();

  io::detail::write_file((root / "sim.json").string(), sim_json(sim, wc, rep));
  return rep;
}

}  // namespace semlio::sim
