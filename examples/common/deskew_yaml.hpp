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

#include <cmath>
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
  double v = 0.0;
  if (!n.IsScalar() || !YAML::convert<double>::decode(n, v) || !std::isfinite(v)) {
    throw semlio::ConfigError(path + ": 'deskew." + key + "' must be a finite number, got '" +
                              (n.IsScalar() ? n.Scalar() : std::string("(not a scalar)")) + "'");
  }
  return v;
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
    if (!kv.first.IsDefined() || !kv.first.IsScalar()) {
      const long line = kv.first.Mark().line >= 0 ? kv.first.Mark().line + 1L : 0L;
      throw semlio::ConfigError(semlio::detail::where(path, line, "a key in section 'deskew' is null or not a scalar, expected a name"));
    }
    const std::string key = kv.first.Scalar();
    const YAML::Node& v = kv.second;
    // "file:line" of the value: every message below names the line too.
    const long line = v.Mark().line >= 0 ? v.Mark().line + 1L : kv.first.Mark().line + 1L;
    const std::string at = line > 0 ? path + ":" + std::to_string(line) : path;
    if (key == "mode") {
      const std::string s = d::text(v, key, at);
      if (s == "none") {
        c.mode = semlio::DeskewMode::kNone;
      } else if (s == "constant_velocity") {
        c.mode = semlio::DeskewMode::kConstantVelocity;
      } else {
        d::bad_choice(key, s, "none, constant_velocity", at);
      }
    } else if (key == "point_times") {
      const std::string s = d::text(v, key, at);
      if (s == "auto") {
        c.point_times = semlio::PointTimeSource::kAuto;
      } else if (s == "scan") {
        c.point_times = semlio::PointTimeSource::kScan;
      } else if (s == "azimuth") {
        c.point_times = semlio::PointTimeSource::kAzimuth;
      } else {
        d::bad_choice(key, s, "auto, scan, azimuth", at);
      }
    } else if (key == "sweep_period_s") {
      c.sweep_period_s = d::number(v, key, at);
    } else if (key == "start_azimuth_deg") {
      c.start_azimuth_rad = d::number(v, key, at) * std::numbers::pi / 180.0;
    } else if (key == "direction") {
      const std::string s = d::text(v, key, at);
      if (s == "clockwise") {
        c.clockwise = true;
      } else if (s == "counter_clockwise") {
        c.clockwise = false;
      } else {
        d::bad_choice(key, s, "clockwise, counter_clockwise", at);
      }
    } else if (key == "reverse_time") {
      c.reverse_time = d::boolean(v, key, at);
    } else if (key == "target") {
      const std::string s = d::text(v, key, at);
      if (s == "start") {
        c.target = semlio::DeskewTarget::kStart;
      } else if (s == "middle") {
        c.target = semlio::DeskewTarget::kMiddle;
      } else if (s == "end") {
        c.target = semlio::DeskewTarget::kEnd;
      } else {
        d::bad_choice(key, s, "start, middle, end", at);
      }
    } else if (key == "frame_period_s") {
      c.frame_period_s = d::number(v, key, at);
    } else {
      throw semlio::ConfigError(at + ": unknown key 'deskew." + key + "'");
    }
  }
  try {
    c.validate();
  } catch (const semlio::ConfigError& e) {
    throw semlio::ConfigError(path + ": deskew: " + e.what());
  }
}

}  // namespace semlio_examples
