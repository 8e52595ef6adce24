#pragma once
// The sensor part of a tool's YAML: which lidar (a named profile, "auto" =
// detect the beam table from the first scans, or a full table), how it is
// carried (platform), the lidar-IMU extrinsic, IMU noise densities and
// gravity. Two spellings are accepted:
//
//   sensor:                      # semlio's own names (every key optional)
//     profile: os0-128           # a name of semlio::sensor_profile_names(), or auto
//     platform: hand_held        # vehicle (default) | hand_held
//     elevations_deg: [...]      # a full table instead of / over the profile's
//     rotation_rate_hz: 10
//     min_range_m: 0.3
//     max_range_m: 50
//     mount_height_m: 1.0
//     header_stamp: start        # start | middle | end
//     spin: clockwise            # clockwise | counter_clockwise (seen from above)
//     sweep_start_azimuth_deg: 180
//   imu:
//     T_imu_lidar: [16 numbers, row-major 4x4]   # lidar -> IMU
//     acc_noise_density: 3.9e-4  # m/s^2/sqrt(Hz)
//     gyr_noise_density: 1.5e-4  # rad/s/sqrt(Hz)
//     acc_bias_random_walk: 6.4e-5
//     gyr_bias_random_walk: 3.5e-5
//     gravity_mps2: 9.80511
//
//   lio_sam:                     # a LIO-SAM params.yaml as it is (also accepted at the root)
//     sensor: ouster             # velodyne | ouster | livox -> spin/stamp facts
//     N_SCAN: 64                 # beams: checked against the profile's / detected table
//     lidarMinRange: 1.0
//     lidarMaxRange: 1000.0
//     imuAccNoise, imuGyrNoise, imuAccBiasN, imuGyrBiasN, imuGravity
//     extrinsicTrans: [x, y, z]
//     extrinsicRot: [9 numbers, row-major]
//     extrinsicRPY: [9 numbers, row-major]   # read and checked; semlio does not use it
//
// LIO-SAM's extrinsics (its utility.h and imuPreintegration.cpp): IMU
// vectors are rotated into the lidar axes by extrinsicRot, and the lidar sits
// at -extrinsicTrans from the IMU in those axes (lidar2Imu = (I,
// extrinsicTrans)); so T_imu_lidar = (extrinsicRot^T, extrinsicRot^T *
// extrinsicTrans). Its noise values are continuous-time densities (GTSAM's
// PreintegrationParams square them into covariances), the same quantities as
// semlio's PreintegrationConfig fields.
//
// Every other LIO-SAM key (topics, frames, mapping settings) is accepted and
// listed in SensorYaml::ignored_keys. Under semlio's own sections an unknown
// key is an error. Bad values throw semlio::ConfigError naming the file, the
// line and the key.

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/features/beam_detection.hpp>
#include <semlio/features/profile_match.hpp>
#include <semlio/features/sensor_profiles.hpp>
#include <semlio/imu/preintegration.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/pipeline/presets.hpp>

namespace semlio_examples {

/// The sensor, platform and IMU facts of a YAML file (every part optional).
struct SensorYaml {
  bool detect = false;                          ///< profile: auto -- detect the beam table from the first scans
  std::optional<semlio::SensorProfile> sensor;  ///< the named or fully given sensor (absent: auto or not given)
  semlio::MotionProfile motion = semlio::vehicle_motion();  ///< platform
  std::optional<int> lio_sam_n_scan;            ///< LIO-SAM's N_SCAN (checked against the table by the caller)
  std::optional<semlio::SE3d> T_imu_lidar;      ///< lidar -> IMU extrinsic
  std::optional<double> acc_noise_density;      ///< [m/s^2/sqrt(Hz)]
  std::optional<double> gyr_noise_density;      ///< [rad/s/sqrt(Hz)]
  std::optional<double> acc_bias_random_walk;   ///< [m/s^3/sqrt(Hz)]
  std::optional<double> gyr_bias_random_walk;   ///< [rad/s^2/sqrt(Hz)]
  std::optional<double> gravity_mps2;           ///< |g| [m/s^2]
  std::vector<std::string> ignored_keys;        ///< LIO-SAM keys semlio does not use

  /// Writes the IMU values that were given into a preintegration config.
  void apply_imu(semlio::PreintegrationConfig& c) const {
    if (acc_noise_density) c.accel_noise_density_mps2_per_sqrthz = *acc_noise_density;
    if (gyr_noise_density) c.gyro_noise_density_radps_per_sqrthz = *gyr_noise_density;
    if (acc_bias_random_walk) c.accel_bias_walk_mps3_per_sqrthz = *acc_bias_random_walk;
    if (gyr_bias_random_walk) c.gyro_bias_walk_radps2_per_sqrthz = *gyr_bias_random_walk;
    if (gravity_mps2) c.gravity_world_mps2 = Eigen::Vector3d(0.0, 0.0, -*gravity_mps2);
  }
};

/// Whether a top-level YAML section belongs to parse_sensor_yaml (so a
/// settings parser can skip it instead of calling it unknown).
inline bool is_sensor_section(std::string_view name) {
  return name == "sensor" || name == "imu" || name == "lio_sam";
}

namespace detail_sensor {

/// "path:line: key: message" (line 1-based, when the node has one).
inline std::string where(const std::string& path, const YAML::Node& node, const std::string& key) {
  const YAML::Mark m = node.Mark();
  return path + (m.line >= 0 ? ":" + std::to_string(m.line + 1) : std::string()) + ": " + key;
}

inline double number(const YAML::Node& n, const std::string& path, const std::string& key) {
  double v = 0.0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    throw semlio::ConfigError(where(path, n, key) + ": expected a number");
  }
  if (!std::isfinite(v)) throw semlio::ConfigError(where(path, n, key) + ": expected a finite number");
  return v;
}

inline double positive(const YAML::Node& n, const std::string& path, const std::string& key) {
  const double v = number(n, path, key);
  if (!(v > 0.0)) throw semlio::ConfigError(where(path, n, key) + ": must be > 0, got " + std::to_string(v));
  return v;
}

inline std::string text(const YAML::Node& n, const std::string& path, const std::string& key) {
  if (!n.IsScalar()) throw semlio::ConfigError(where(path, n, key) + ": expected a string");
  return n.as<std::string>();
}

inline std::vector<double> numbers(const YAML::Node& n, const std::string& path, const std::string& key,
                                   std::size_t expected = 0) {
  if (!n.IsSequence()) throw semlio::ConfigError(where(path, n, key) + ": expected a list of numbers");
  std::vector<double> v;
  for (const auto& x : n) v.push_back(number(x, path, key));
  if (expected != 0 && v.size() != expected) {
    throw semlio::ConfigError(where(path, n, key) + ": expected " + std::to_string(expected) + " numbers, got " +
                              std::to_string(v.size()));
  }
  return v;
}

inline Eigen::Matrix3d rotation(const YAML::Node& n, const std::string& path, const std::string& key) {
  const std::vector<double> v = numbers(n, path, key, 9);
  Eigen::Matrix3d R;
  R << v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8];
  if (!((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-3) || !(R.determinant() > 0.0)) {
    throw semlio::ConfigError(where(path, n, key) + ": is not a rotation matrix (R^T R = I, det R = +1 within 1e-3)");
  }
  return R;
}

// semlio's `sensor:` section.
inline void parse_sensor(const YAML::Node& s, const std::string& path, SensorYaml& out) {
  if (!s.IsMap()) throw semlio::ConfigError(where(path, s, "sensor") + ": must be a map");
  // The profile first: the other keys refine it.
  if (const YAML::Node p = s["profile"]) {
    const std::string name = text(p, path, "sensor.profile");
    if (name == "auto") {
      out.detect = true;
    } else {
      try {
        out.sensor = semlio::sensor_profile(name);
      } catch (const semlio::ConfigError& e) {
        throw semlio::ConfigError(where(path, p, "sensor.profile") + ": " + e.what());
      }
    }
  }
  semlio::SensorProfile custom = out.sensor.value_or(semlio::SensorProfile{});
  bool touched = false;
  for (const auto& kv : s) {
    const std::string key = kv.first.as<std::string>();
    const YAML::Node& v = kv.second;
    const std::string k = "sensor." + key;
    if (key == "profile") continue;
    touched = touched || key != "platform";
    if (key == "platform") {
      try {
        out.motion = semlio::motion_profile(text(v, path, k));
      } catch (const semlio::ConfigError& e) {
        throw semlio::ConfigError(where(path, v, k) + ": " + e.what());
      }
    } else if (key == "name") {
      custom.name = text(v, path, k);
    } else if (key == "elevations_deg") {
      const std::vector<double> deg = numbers(v, path, k);
      custom.beams.elevations_rad.clear();
      for (const double d : deg) custom.beams.elevations_rad.push_back(d * std::numbers::pi / 180.0);
      std::sort(custom.beams.elevations_rad.begin(), custom.beams.elevations_rad.end());
      custom.nominal_table = false;
    } else if (key == "rotation_rate_hz") {
      custom.beams.rotation_rate_hz = positive(v, path, k);
    } else if (key == "min_range_m") {
      custom.min_range_m = number(v, path, k);
    } else if (key == "max_range_m") {
      custom.max_range_m = positive(v, path, k);
    } else if (key == "mount_height_m") {
      custom.mount_height_m = number(v, path, k);
    } else if (key == "header_stamp") {
      const std::string t = text(v, path, k);
      if (t == "start") custom.header_stamp = semlio::StampMeaning::kSweepStart;
      else if (t == "middle") custom.header_stamp = semlio::StampMeaning::kSweepMiddle;
      else if (t == "end") custom.header_stamp = semlio::StampMeaning::kSweepEnd;
      else throw semlio::ConfigError(where(path, v, k) + ": expected start, middle or end, got '" + t + "'");
    } else if (key == "spin") {
      const std::string t = text(v, path, k);
      if (t == "clockwise") custom.counter_clockwise = false;
      else if (t == "counter_clockwise") custom.counter_clockwise = true;
      else throw semlio::ConfigError(where(path, v, k) + ": expected clockwise or counter_clockwise, got '" + t + "'");
    } else if (key == "sweep_start_azimuth_deg") {
      custom.sweep_start_azimuth_rad = number(v, path, k) * std::numbers::pi / 180.0;
    } else {
      throw semlio::ConfigError(where(path, kv.first, k) + ": unknown key (known: profile, platform, name, "
                                "elevations_deg, rotation_rate_hz, min_range_m, max_range_m, mount_height_m, "
                                "header_stamp, spin, sweep_start_azimuth_deg)");
    }
  }
  if (!touched) return;
  if (custom.name.empty()) custom.name = "custom";
  if (out.detect && custom.beams.elevations_rad.empty()) {
    // auto plus facts (rate, ranges, spin): the table comes from detection.
    out.sensor = custom;
    return;
  }
  try {
    custom.validate();
  } catch (const semlio::ConfigError& e) {
    throw semlio::ConfigError(where(path, s, "sensor") + ": " + e.what());
  }
  out.detect = false;
  out.sensor = custom;
}

// semlio's `imu:` section.
inline void parse_imu(const YAML::Node& s, const std::string& path, SensorYaml& out) {
  if (!s.IsMap()) throw semlio::ConfigError(where(path, s, "imu") + ": must be a map");
  for (const auto& kv : s) {
    const std::string key = kv.first.as<std::string>();
    const YAML::Node& v = kv.second;
    const std::string k = "imu." + key;
    if (key == "T_imu_lidar") {
      const std::vector<double> m = numbers(v, path, k, 16);
      Eigen::Matrix4d T;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) T(r, c) = m[static_cast<std::size_t>(4 * r + c)];
      if (!(T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).isZero(1e-9)) {
        throw semlio::ConfigError(where(path, v, k) + ": the last row must be 0 0 0 1");
      }
      YAML::Node rot;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) rot.push_back(T(r, c));
      (void)rotation(rot, path, k);  // checks it is a rotation
      // SO3d from a matrix goes through a normalised quaternion: a table
      // given with few digits becomes the nearest rotation.
      out.T_imu_lidar = semlio::SE3d(semlio::SO3d(Eigen::Matrix3d(T.topLeftCorner<3, 3>())),
                                     Eigen::Vector3d(T.topRightCorner<3, 1>()));
    } else if (key == "acc_noise_density") {
      out.acc_noise_density = positive(v, path, k);
    } else if (key == "gyr_noise_density") {
      out.gyr_noise_density = positive(v, path, k);
    } else if (key == "acc_bias_random_walk") {
      out.acc_bias_random_walk = positive(v, path, k);
    } else if (key == "gyr_bias_random_walk") {
      out.gyr_bias_random_walk = positive(v, path, k);
    } else if (key == "gravity_mps2") {
      out.gravity_mps2 = positive(v, path, k);
    } else {
      throw semlio::ConfigError(where(path, kv.first, k) + ": unknown key (known: T_imu_lidar, acc_noise_density, "
                                "gyr_noise_density, acc_bias_random_walk, gyr_bias_random_walk, gravity_mps2)");
    }
  }
}

// LIO-SAM's keys (a params.yaml's `lio_sam:` map, or the root itself).
inline void parse_lio_sam(const YAML::Node& s, const std::string& path, const std::string& prefix, SensorYaml& out) {
  std::optional<Eigen::Matrix3d> R;
  std::optional<Eigen::Vector3d> t;
  for (const auto& kv : s) {
    const std::string key = kv.first.as<std::string>();
    const YAML::Node& v = kv.second;
    const std::string k = prefix + key;
    if (key == "imuAccNoise") {
      out.acc_noise_density = positive(v, path, k);
    } else if (key == "imuGyrNoise") {
      out.gyr_noise_density = positive(v, path, k);
    } else if (key == "imuAccBiasN") {
      out.acc_bias_random_walk = positive(v, path, k);
    } else if (key == "imuGyrBiasN") {
      out.gyr_bias_random_walk = positive(v, path, k);
    } else if (key == "imuGravity") {
      out.gravity_mps2 = positive(v, path, k);
    } else if (key == "extrinsicRot") {
      R = rotation(v, path, k);
    } else if (key == "extrinsicRPY") {
      (void)rotation(v, path, k);  // LIO-SAM uses it for a 9-axis IMU's attitude only
    } else if (key == "extrinsicTrans") {
      const std::vector<double> x = numbers(v, path, k, 3);
      t = Eigen::Vector3d(x[0], x[1], x[2]);
    } else if (key == "N_SCAN") {
      const double n = positive(v, path, k);
      if (n != std::floor(n) || n > 65535.0) {
        throw semlio::ConfigError(where(path, v, k) + ": expected a whole number of beams, got " + std::to_string(n));
      }
      out.lio_sam_n_scan = static_cast<int>(n);
    } else if (key == "lidarMinRange" || key == "lidarMaxRange") {
      const double r = number(v, path, k);
      if (!out.sensor) out.sensor = semlio::SensorProfile{};
      (key == "lidarMinRange" ? out.sensor->min_range_m : out.sensor->max_range_m) = r;
    } else if (key == "sensor") {
      const std::string t2 = text(v, path, k);
      if (!out.sensor) out.sensor = semlio::SensorProfile{};
      if (t2 == "velodyne") {
        out.sensor->header_stamp = semlio::StampMeaning::kSweepEnd;
        out.sensor->counter_clockwise = false;
        out.sensor->sweep_start_azimuth_rad = 0.0;
      } else if (t2 == "ouster") {
        out.sensor->header_stamp = semlio::StampMeaning::kSweepStart;
        out.sensor->counter_clockwise = false;
        out.sensor->sweep_start_azimuth_rad = std::numbers::pi;
      } else if (t2 != "livox") {
        throw semlio::ConfigError(where(path, v, k) + ": expected velodyne, ouster or livox, got '" + t2 + "'");
      }
    } else {
      out.ignored_keys.push_back(k);
    }
  }
  if (R || t) {
    const Eigen::Matrix3d Rl = semlio::SO3d(R.value_or(Eigen::Matrix3d::Identity())).matrix();
    const Eigen::Vector3d tl = t.value_or(Eigen::Vector3d::Zero());
    out.T_imu_lidar = semlio::SE3d(semlio::SO3d(Eigen::Matrix3d(Rl.transpose())), Eigen::Vector3d(Rl.transpose() * tl));
  }
}

}  // namespace detail_sensor

/// Reads the sensor sections of an already loaded YAML root (`path` only
/// names the file in errors). Sections other than sensor / imu / lio_sam are
/// left to the caller; LIO-SAM keys at the root (a params.yaml without its
/// `lio_sam:` line) are read when the root has none of semlio's sections.
inline SensorYaml parse_sensor_yaml(const YAML::Node& root, const std::string& path) {
  SensorYaml out;
  if (!root || root.IsNull()) return out;
  if (!root.IsMap()) throw semlio::ConfigError(path + ": the config must be a YAML map");
  if (const YAML::Node l = root["lio_sam"]) {
    if (!l.IsMap()) throw semlio::ConfigError(detail_sensor::where(path, l, "lio_sam") + ": must be a map");
    detail_sensor::parse_lio_sam(l, path, "lio_sam.", out);
  } else if (root["imuAccNoise"] || root["extrinsicRot"] || root["N_SCAN"]) {
    detail_sensor::parse_lio_sam(root, path, "", out);
  }
  // semlio's own sections override LIO-SAM's values.
  if (const YAML::Node s = root["sensor"]; s && !s.IsScalar()) {
    // (LIO-SAM's root-level `sensor: ouster` is a scalar, read above.)
    detail_sensor::parse_sensor(s, path, out);
  }
  if (const YAML::Node i = root["imu"]) detail_sensor::parse_imu(i, path, out);
  return out;
}

/// Loads `path` and reads its sensor sections (parse_sensor_yaml). Throws
/// semlio::IoError when the file cannot be opened, ConfigError otherwise.
inline SensorYaml load_sensor_yaml(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw semlio::IoError(path + ": cannot open the config file");
  } catch (const YAML::Exception& e) {
    throw semlio::ConfigError(path + ": " + e.what());
  }
  return parse_sensor_yaml(root, path);
}

/// The sensor profile of a run: the YAML's, or with `profile: auto` the
/// detected table -- with the YAML's other sensor facts when it gives any,
/// else with the facts of the named profile the table matches
/// (features/profile_match.hpp: ranges, stamp meaning, spin, and the
/// profile's angles for beams the first scans did not see), else generic
/// ones (10 Hz, no range limit beyond the pipeline's, stamp at sweep start,
/// clockwise from the rear -- Ouster's, the common hand-held case). Throws
/// ConfigError when neither gives a table, or LIO-SAM's N_SCAN disagrees with
/// the table. `match` (optional) receives the profile match used.
inline semlio::SensorProfile resolve_sensor(const SensorYaml& y, const semlio::BeamDetection* detection,
                                            std::optional<semlio::ProfileMatch>* match = nullptr) {
  semlio::SensorProfile p;
  if (match != nullptr) match->reset();
  if (y.detect) {
    if (detection == nullptr || detection->beams() == 0) {
      throw semlio::ConfigError("sensor.profile: auto needs a beam detection, and none found beams");
    }
    // The YAML's own facts win; uniform fallback bands are no beam table and match no sensor.
    const std::optional<semlio::ProfileMatch> m =
        !y.sensor && detection->separable ? semlio::match_sensor_profile(detection->elevations_rad) : std::nullopt;
    if (y.sensor) {
      p = *y.sensor;
    } else if (m) {
      p = semlio::sensor_profile(m->profile);
      p.beams = m->completed_table(p.beams, detection->elevations_rad);
      p.nominal_table = m->matched < m->profile_beams;  // unseen beams keep the datasheet's angles
      if (match != nullptr) *match = m;
    } else {
      p.header_stamp = semlio::StampMeaning::kSweepStart;
      p.sweep_start_azimuth_rad = std::numbers::pi;
      p.min_range_m = 0.0;
      p.max_range_m = 1000.0;
    }
    if (!m) {
      p.beams = detection->sensor_model(p.beams.rotation_rate_hz);
      p.name = "detected-" + std::to_string(detection->beams());
      p.nominal_table = false;
    }
  } else if (y.sensor && !y.sensor->beams.elevations_rad.empty()) {
    p = *y.sensor;
  } else {
    throw semlio::ConfigError("sensor: no beam table (give sensor.profile, sensor.elevations_deg or profile: auto)");
  }
  if (y.lio_sam_n_scan && static_cast<std::size_t>(*y.lio_sam_n_scan) != p.beams.beams()) {
    throw semlio::ConfigError("lio_sam.N_SCAN = " + std::to_string(*y.lio_sam_n_scan) + " but the sensor table '" +
                              p.name + "' has " + std::to_string(p.beams.beams()) + " beams");
  }
  p.validate();
  return p;
}

/// Facts for a tool's summary and report.json "sensor" object.
inline std::vector<std::pair<std::string, std::string>> sensor_facts(const semlio::SensorProfile& p,
                                                                     const semlio::MotionProfile& m,
                                                                     const semlio::BeamDetection* d,
                                                                     const semlio::ProfileMatch* match = nullptr) {
  const auto deg = [](double rad) { return std::to_string(rad * 180.0 / std::numbers::pi); };
  std::vector<std::pair<std::string, std::string>> f = {
      {"profile", p.name},
      {"beams", std::to_string(p.beams.beams())},
      {"elevation_min_deg", deg(p.beams.elevations_rad.front())},
      {"elevation_max_deg", deg(p.beams.elevations_rad.back())},
      {"platform", m.name},
      {"header_stamp", semlio::to_string(p.header_stamp)},
      {"mount_height_m", std::to_string(p.mount_height_m)},
  };
  if (d != nullptr) {
    f.emplace_back("detection", semlio::to_string(d->source));
    f.emplace_back("detection_separable", d->separable ? "true" : "false");
    f.emplace_back("detection_fit_fraction", std::to_string(d->fit_fraction));
    f.emplace_back("detection_rms_deg", deg(d->rms_residual_rad));
    f.emplace_back("detection_note", d->note);
  }
  if (match != nullptr) {
    f.emplace_back("matched_profile", match->profile);
    f.emplace_back("matched_beams", std::to_string(match->matched) + " of " + std::to_string(match->profile_beams));
    f.emplace_back("match_rms_deg", deg(match->rms_rad));
    f.emplace_back("match_max_deg", deg(match->max_rad));
  }
  return f;
}

/// What configure_sensor() decided.
struct SensorSetup {
  semlio::SensorProfile profile;                  ///< the sensor the run uses
  semlio::MotionProfile motion;                   ///< the platform
  std::optional<semlio::BeamDetection> detection; ///< when profile: auto
  std::optional<semlio::ProfileMatch> match;      ///< the named profile the detected table matched
  std::vector<std::pair<std::string, std::string>> facts;  ///< sensor_facts(), for the summary and report.json
};

/// The whole sensor step of a tool, for its settings hook: with `profile:
/// auto` detects the beam table from the first `detect_frames` scans
/// (read_scan(i) -> semlio::Scan, i < frames), resolves the profile
/// (resolve_sensor) and applies settings_for_sensor(profile, platform) on top
/// of `settings`. The caller still sets what PipelineSettings does not hold
/// (GeometricSegmenterConfig::sensor_height_m = profile.mount_height_m) and
/// the IMU (SensorYaml::apply_imu, T_imu_lidar). Throws ConfigError as
/// resolve_sensor.
template <typename ReadScan>
SensorSetup configure_sensor(const SensorYaml& y, std::size_t frames, ReadScan&& read_scan,
                             semlio::PipelineSettings& settings, std::size_t detect_frames = 3) {
  SensorSetup out;
  if (y.detect) {
    semlio::BeamDetector detector;
    for (std::size_t i = 0; i < std::min(frames, detect_frames); ++i) detector.add(read_scan(i));
    out.detection = detector.detect();
  }
  const semlio::BeamDetection* d = out.detection ? &*out.detection : nullptr;
  out.profile = resolve_sensor(y, d, &out.match);
  out.motion = y.motion;
  settings = semlio::settings_for_sensor(out.profile, out.motion, settings);
  out.facts = sensor_facts(out.profile, out.motion, d, out.match ? &*out.match : nullptr);
  return out;
}

}  // namespace semlio_examples
