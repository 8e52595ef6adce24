#pragma once
// The `deskew:` section of a semlio_kitti --config file -> semlio::SweepDeskewConfig
// (imu/deskew.hpp). Every key is optional; an unknown key or a bad value is a
// semlio::ConfigError naming the file, the key and the value.
//
//   deskew:
//     mode: constant_velocity      # none (default) | constant_velocity
//     point_times: auto            # auto (scan's, else azimuth) | scan | azimuth
//     sweep_period_s: 0.1          # one revolution [s]
//     start_azimuth_deg: 180       # azimuth atan2(y, x) at the sweep start (KITTI raw: 180, facing backwards)
//     direction: clockwise         # spin seen from above: clockwise | counter_clockwise
//     reverse_time: false          # true for a recording played backwards
//     target: middle               # start | middle | end of the sweep
//     frame_period_s: 0.1          # span of the predicted motion when stamps cannot give it [s]

#include <yaml-cpp/yaml.h>

#include <numbers>
#include <string>

#include <semlio/core/error.hpp>
#include <semlio/imu/deskew.hpp>

namespace semlio_examples {

namespace detail_deskew {

inline std::string text(const YAML::Node& n, const std::string& key, const std::string& path) {
  try {
    return n.as<std::string>();
  } catch (const YAML::Exception& e) {
    throw semlio::ConfigError(path + ": bad value for 'deskew." + key + "': " + e.what());
  }
}

inline double number(const YAML::Node& n, const std::string& key, const std::string& path) {
  try {
    return n.as<double>();
  } catch (const YAML::Exception&) {
    throw semlio::ConfigError(path + ": 'deskew." + key + "' must be a number, got '" +
                              (n.IsScalar() ? n.Scalar() : std::string("(not a scalar)")) + "'");
  }
}

inline bool boolean(const YAML::Node& n, const std::string& key, const std::string& path) {
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    throw semlio::ConfigError(path + ": 'deskew." + key + "' must be true or false, got '" +
                              (n.IsScalar() ? n.Scalar() : std::string("(not a scalar)")) + "'");
  }
}

[[noreturn]] inline void bad_choice(const std::string& key, const std::string& value, const char* choices,
                                    const std::string& path) {
  throw semlio::ConfigError(path + ": 'deskew." + key + "' must be one of " + choices + ", got '" + value + "'");
}

}  // namespace detail_deskew

/// Applies the `deskew:` section (a YAML map; a null node changes nothing) of
/// the config file `path` to `c`, then validates `c`. Throws
/// semlio::ConfigError for an unknown key, a bad value or an invalid result.
inline void load_deskew_yaml(const YAML::Node& section, semlio::SweepDeskewConfig& c, const std::string& path) {
  namespace d = detail_deskew;
  if (!section || section.IsNull()) return;
  if (!section.IsMap()) throw semlio::ConfigError(path + ": section 'deskew' must be a map");
  for (const auto& kv : section) {
    const auto key = kv.first.as<std::string>();
    const YAML::Node& v = kv.second;
    if (key == "mode") {
      const std::string s = d::text(v, key, path);
      if (s == "none") {
        c.mode = semlio::DeskewMode::kNone;
      } else if (s == "constant_velocity") {
        c.mode = semlio::DeskewMode::kConstantVelocity;
      } else {
        d::bad_choice(key, s, "none, constant_velocity", path);
      }
    } else if (key == "point_times") {
      const std::string s = d::text(v, key, path);
      if (s == "auto") {
        c.point_times = semlio::PointTimeSource::kAuto;
      } else if (s == "scan") {
        c.point_times = semlio::PointTimeSource::kScan;
      } else if (s == "azimuth") {
        c.point_times = semlio::PointTimeSource::kAzimuth;
      } else {
        d::bad_choice(key, s, "auto, scan, azimuth", path);
      }
    } else if (key == "sweep_period_s") {
      c.sweep_period_s = d::number(v, key, path);
    } else if (key == "start_azimuth_deg") {
      c.start_azimuth_rad = d::number(v, key, path) * std::numbers::pi / 180.0;
    } else if (key == "direction") {
      const std::string s = d::text(v, key, path);
      if (s == "clockwise") {
        c.clockwise = true;
      } else if (s == "counter_clockwise") {
        c.clockwise = false;
      } else {
        d::bad_choice(key, s, "clockwise, counter_clockwise", path);
      }
    } else if (key == "reverse_time") {
      c.reverse_time = d::boolean(v, key, path);
    } else if (key == "target") {
      const std::string s = d::text(v, key, path);
      if (s == "start") {
        c.target = semlio::DeskewTarget::kStart;
      } else if (s == "middle") {
        c.target = semlio::DeskewTarget::kMiddle;
      } else if (s == "end") {
        c.target = semlio::DeskewTarget::kEnd;
      } else {
        d::bad_choice(key, s, "start, middle, end", path);
      }
    } else if (key == "frame_period_s") {
      c.frame_period_s = d::number(v, key, path);
    } else {
      throw semlio::ConfigError(path + ": unknown key 'deskew." + key + "'");
    }
  }
  try {
    c.validate();
  } catch (const semlio::ConfigError& e) {
    throw semlio::ConfigError(path + ": deskew: " + e.what());
  }
}

}  // namespace semlio_examples
