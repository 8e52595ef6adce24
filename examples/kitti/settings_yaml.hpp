#pragma once
// YAML overrides of semlio::PipelineSettings (front end) and BackEndSettings
// (slam, loop_verify, radius_loop, scan_context, graph, semantic_map) for semlio_kitti. Every key is
// optional; an unknown section or key is an error (typos must not be silently
// ignored). The README lists every key with its default.
//
// Domains: every numeric key has its domain written beside it below --
// num(field, lo, hi) is [lo, hi], pos(field, hi) is (0, hi]. NaN, Inf, a
// fraction for an integer field or a value outside the domain is a
// semlio::ConfigError "file:line: 'section.key' = VALUE is outside its domain
// [lo, hi]"; a null or non-scalar key (`? :`) or value is a ConfigError naming
// the line too. Nothing a config file holds escapes as a YAML exception.

#include <yaml-cpp/yaml.h>

#include "deskew_yaml.hpp"

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <type_traits>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/associate/normal_consistency.hpp>
#include <semlio/core/error.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/loop/radius_detector.hpp>
#include <semlio/loop/scan_context.hpp>
#include <semlio/map/semantic_map.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/pipeline/slam.hpp>

namespace semlio_examples {

namespace detail {

// A section maps key -> setter that reads the YAML node into a field.
using Setters = std::map<std::string, std::function<void(const YAML::Node&)>>;

/// Thrown by a setter with the reason a value is refused; apply() turns it
/// into a ConfigError naming the file, line and key path.
struct BadValue {
  std::string why;
};

/// 1-based line of a node, 0 when yaml-cpp has no position for it.
inline long line_of(const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  return m.line >= 0 ? static_cast<long>(m.line) + 1 : 0;
}

/// "path:line: what" (the line left out when unknown).
inline std::string where(const std::string& path, const YAML::Node& n, const std::string& what) {
  return semlio::detail::where(path, line_of(n), what);
}

/// What a node is, for messages ("a map", "a sequence", "null").
inline std::string kind_of(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "null";
  if (n.IsMap()) return "a map";
  if (n.IsSequence()) return "a sequence";
  return "'" + n.Scalar() + "'";
}

/// The name of a map key; a null or non-scalar key (`? :`, `[a]: 1`) is a
/// ConfigError naming the file, line and the enclosing section.
inline std::string key_of(const YAML::Node& key, const std::string& section, const std::string& path) {
  if (!key.IsDefined() || !key.IsScalar()) {
    throw semlio::ConfigError(where(path, key,
                                    (section.empty() ? std::string("a top-level key") : "a key in section '" + section + "'") +
                                        " is " + kind_of(key) + ", expected a name"));
  }
  return key.Scalar();
}

/// Text of a number for domain messages ("1e+08", "0.5", "3.14159").
inline std::string number_text(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

/// A bool or string field: any scalar yaml-cpp converts.
template <typename T>
std::function<void(const YAML::Node&)> set(T& field) {
  static_assert(std::is_same_v<T, bool> || std::is_same_v<T, std::string>, "numbers go through num()");
  return [&field](const YAML::Node& n) {
    if (!n.IsScalar()) throw BadValue{"is " + kind_of(n) + ", expected a scalar"};
    field = n.as<T>();
  };
}

/// SemanticWeightConfig::mode from its name: chance_corrected, paper, off.
inline std::function<void(const YAML::Node&)> semantic_weight_mode(semlio::SemanticWeightMode& field) {
  return [&field](const YAML::Node& n) {
    const std::string v = n.IsScalar() ? n.Scalar() : std::string();
    if (v == "chance_corrected") {
      field = semlio::SemanticWeightMode::kChanceCorrected;
    } else if (v == "paper") {
      field = semlio::SemanticWeightMode::kPaper;
    } else if (v == "off") {
      field = semlio::SemanticWeightMode::kOff;
    } else {
      throw BadValue{"is " + kind_of(n) + ", expected chance_corrected, paper or off"};
    }
  };
}

/// A numeric field with its domain [lo, hi] ((lo, hi] when `lo_open`): the
/// value must be finite, integral for integer fields, and inside the domain.
template <typename T>
std::function<void(const YAML::Node&)> num(T& field, double lo, double hi, bool lo_open = false) {
  static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>, "num() takes numeric fields");
  return [&field, lo, hi, lo_open](const YAML::Node& n) {
    if (!n.IsScalar()) throw BadValue{"is " + kind_of(n) + ", expected a number"};
    const std::string domain =
        std::string(lo_open ? "(" : "[") + number_text(lo) + ", " + number_text(hi) + "]";
    double v = 0.0;
    if constexpr (std::is_integral_v<T>) {
      long long i = 0;
      if (!YAML::convert<long long>::decode(n, i)) {
        throw BadValue{"= '" + n.Scalar() + "' is not an integer (domain " + domain + ")"};
      }
      v = static_cast<double>(i);
    } else {
      if (!YAML::convert<double>::decode(n, v)) {
        throw BadValue{"= '" + n.Scalar() + "' is not a number (domain " + domain + ")"};
      }
    }
    const bool inside = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
    if (!inside) throw BadValue{"= " + n.Scalar() + " is outside its domain " + domain};
    field = static_cast<T>(v);
  };
}

/// A numeric field that must be positive: domain (0, hi].
template <typename T>
std::function<void(const YAML::Node&)> pos(T& field, double hi) {
  return num(field, 0.0, hi, true);
}

inline void apply(const YAML::Node& section, const std::string& name, const Setters& setters,
                  const std::string& path) {
  if (!section || section.IsNull()) return;
  if (!section.IsMap()) {
    throw semlio::ConfigError(where(path, section, "section '" + name + "' is " + kind_of(section) + ", expected a map"));
  }
  for (const auto& kv : section) {
    const std::string key = key_of(kv.first, name, path);
    const auto it = setters.find(key);
    if (it == setters.end()) throw semlio::ConfigError(where(path, kv.first, "unknown key '" + name + "." + key + "'"));
    try {
      it->second(kv.second);
    } catch (const BadValue& e) {
      throw semlio::ConfigError(where(path, kv.second, "'" + name + "." + key + "' " + e.why));
    } catch (const YAML::Exception& e) {
      throw semlio::ConfigError(where(path, kv.second, "bad value for '" + name + "." + key + "': " + e.msg));
    }
  }
}

/// Largest config file accepted (configs are a few kB; a wrong path to a huge
/// file or a device is an IoError, not an unbounded read).
inline constexpr std::uint64_t kMaxConfigBytes = std::uint64_t{16} << 20;

/// Parses YAML text; `name` (the file) is what a ConfigError names, with
/// the line of a syntax error.
inline YAML::Node parse_yaml_text(const std::string& text, const std::string& name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw semlio::ConfigError(semlio::detail::where(name, e.mark.line >= 0 ? e.mark.line + 1L : 0L, e.msg));
  }
}

/// Parses the YAML file at `path`: IoError when it cannot be read, ConfigError
/// naming the line on a syntax error.
inline YAML::Node load_yaml_file(const std::string& path) {
  return parse_yaml_text(semlio::io::detail::read_file(path, kMaxConfigBytes), path);
}

}  // namespace detail

/// Back-end settings of semlio_kitti (pose graph, loop closure, semantic map).
struct BackEndSettings {
  semlio::SlamConfig slam{};                   ///< Slam (loop_closure is set from --loop)
  std::string loop_detector = "radius";        ///< radius | scancontext
  semlio::RadiusLoopConfig radius{};           ///< radius detector
  semlio::ScanContextConfig scan_context{};    ///< Scan Context detector
  semlio::SemanticMapConfig map{};             ///< OUT/map.ply
};

/// Applies the overrides in the YAML `text` to `s` and, when given, to the
/// back-end settings `b`; errors name `path` (the file the text came from).
/// Throws semlio::ConfigError (syntax, unknown key, bad value).
inline void parse_settings_yaml(const std::string& text, const std::string& path, semlio::PipelineSettings& s,
                                BackEndSettings* b = nullptr) {
  const YAML::Node root = detail::parse_yaml_text(text, path);
  if (!root || root.IsNull()) return;
  if (!root.IsMap()) throw semlio::ConfigError(detail::where(path, root, "the config is " + detail::kind_of(root) + ", expected a YAML map"));
  using detail::num;
  using detail::pos;
  using detail::set;
  constexpr double kPi = std::numbers::pi;
  constexpr double kBig = 1e12;  // counts and scales: any sane value, never negative
  // nearest.k and normal.keep: the YAML domain is [1, kMaxCandidates]; the
  // associators' own checks narrow it to [1, kMaxKeptMatches] (a ConfigError
  // naming the field when the pipeline is built).
  auto& o = s.odometry;
  const std::map<std::string, detail::Setters> sections = {
      {"odometry",
       {{"kitti_vertical_correction", set(o.kitti_vertical_correction)},
        {"min_frame_interval_s", num(o.min_frame_interval_s, 0.0, 3600.0)},
        {"min_features", num(o.min_features, 0.0, kBig)},
        {"max_correction_m", pos(o.max_correction_m, 1e4)},
        {"max_correction_rad", pos(o.max_correction_rad, kPi)}}},
      {"preprocess",
       {{"min_range_m", num(o.preprocess.min_range_m, 0.0, 1e4)},
        {"max_range_m", pos(o.preprocess.max_range_m, 1e4)},
        {"crop_ego_box", set(o.preprocess.crop_ego_box)}}},
      {"features",
       {{"neighbours", num(o.features.neighbours, 1.0, 100.0)},
        {"sectors", num(o.features.sectors, 1.0, 3600.0)},
        {"max_corners_per_sector", num(o.features.max_corners_per_sector, 0.0, kBig)},
        {"corner_threshold_m", num(o.features.corner_threshold_m, 0.0, 1e3)},
        {"surface_threshold_m", num(o.features.surface_threshold_m, 0.0, 1e3)},
        {"occlusion_depth_gap_m", num(o.features.occlusion_depth_gap_m, 0.0, 1e3)},
        {"parallel_beam_ratio", num(o.features.parallel_beam_ratio, 0.0, 1e3)},
        {"surface_leaf_m", num(o.features.surface_leaf_m, 0.0, 100.0)},
        {"corner_leaf_m", num(o.features.corner_leaf_m, 0.0, 100.0)}}},
      {"map",
       {{"radius_m", pos(o.map.radius_m, 1e4)},
        {"corner_leaf_m", num(o.map.corner_leaf_m, 0.0, 100.0)},
        {"surface_leaf_m", num(o.map.surface_leaf_m, 0.0, 100.0)},
        {"shape_neighbours", num(o.map.shape_neighbours, 1.0, 1000.0)},
        {"exclude_dynamic", set(o.map.exclude_dynamic)},
        {"max_keyframes", num(o.map.max_keyframes, 0.0, kBig)},
        {"keep_first_point", set(o.map.keep_first_point)}}},
      {"solver",
       {{"max_iterations", num(o.solver.max_iterations, 1.0, 1e6)},
        {"reassociate_every", num(o.solver.reassociate_every, 1.0, 1e6)},
        {"levenberg_marquardt", set(o.solver.levenberg_marquardt)},
        {"translation_tolerance_m", num(o.solver.translation_tolerance_m, 0.0, 1e3)},
        {"rotation_tolerance_rad", num(o.solver.rotation_tolerance_rad, 0.0, kPi)},
        {"degeneracy_threshold", num(o.solver.degeneracy_threshold, 0.0, kBig)},
        {"remap_degenerate", set(o.solver.remap_degenerate)},
        {"damp_degenerate", set(o.solver.damp_degenerate)},
        {"min_residuals", num(o.solver.min_residuals, 0.0, kBig)}}},
      {"nearest", {{"k", num(s.nearest.k, 1.0, semlio::kMaxCandidates)}, {"max_distance_m", pos(s.nearest.max_distance_m, 1e4)}}},
      {"normal",
       {{"candidates", num(s.normal.candidates, 1.0, semlio::kMaxCandidates)},
        {"keep", num(s.normal.keep, 1.0, semlio::kMaxCandidates)},
        {"scan_neighbours", num(s.normal.scan_neighbours, 0.0, 1000.0)},
        {"max_angle_rad", num(s.normal.max_angle_rad, 0.0, kPi)},
        {"max_distance_m", pos(s.normal.max_distance_m, 1e4)}}},
      {"line",
       {{"two_point", set(s.line.two_point)},
        {"max_linearity_ratio", num(s.line.max_linearity_ratio, 0.0, 1e6)},
        {"cauchy_m", num(s.corner_cauchy_m, 0.0, 1e3)}}},
      {"plane",
       {{"three_point", set(s.plane.three_point)},
        {"max_planarity_ratio", num(s.plane.max_planarity_ratio, 0.0, 1e6)},
        {"min_spread_ratio", num(s.plane.min_spread_ratio, 0.0, 1e6)}}},
      {"semantic_weights", {{"mode", detail::semantic_weight_mode(s.semantic_weights.mode)}}},
      {"pose_threshold",
       {{"translation_threshold_m", num(s.pose_threshold.translation_threshold_m, 0.0, 1e4)},
        {"rotation_threshold_rad", num(s.pose_threshold.rotation_threshold_rad, 0.0, kPi)}}},
      {"semantic_keyframes",
       {{"translation_threshold_m", num(s.semantic_keyframes.translation_threshold_m, 0.0, 1e4)},
        {"rotation_threshold_rad", num(s.semantic_keyframes.rotation_threshold_rad, 0.0, kPi)},
        {"stability_threshold", num(s.semantic_keyframes.stability_threshold, 0.0, kBig)},
        {"weight_min", num(s.semantic_keyframes.weight_min, 0.0, 1.0)},
        {"laplace_count", num(s.semantic_keyframes.laplace_count, 0.0, kBig)}}},
  };
  BackEndSettings unused;
  BackEndSettings& be = b != nullptr ? *b : unused;
  auto& sl = be.slam;
  auto& lv = be.slam.loop.verify;
  auto& g = be.slam.graph;
  auto& sc = be.scan_context;
  const std::map<std::string, detail::Setters> back_end = {
      {"slam",
       {{"loop_closure", set(sl.loop_closure)},
        {"loop_detector", set(be.loop_detector)},
        {"loop_interval_s", num(sl.loop_interval_s, 0.0, 1e6)},
        {"robust_loops", set(sl.robust_loops)},
        {"odometry_information_scale", pos(sl.odometry_information_scale, kBig)},
        {"min_information", num(sl.min_information, 0.0, kBig)},
        {"max_information", pos(sl.max_information, 1e15)},
        {"weak_sigma_m", pos(sl.weak_sigma_m, 1e6)},
        {"weak_sigma_rad", pos(sl.weak_sigma_rad, 1e3)},
        {"keyframe_cloud_leaf_m", num(sl.keyframe_cloud_leaf_m, 0.0, 100.0)},
        {"keyframe_cloud_max_range_m", num(sl.keyframe_cloud_max_range_m, 0.0, 1e4)},
        {"max_keyframe_clouds", num(sl.max_keyframe_clouds, 0.0, kBig)},
        {"place_spacing_m", num(sl.place_spacing_m, 0.0, 1e4)},
        {"max_place_bytes", num(sl.max_place_bytes, 0.0, 1e15)},
        {"place_thinning_factor", num(sl.place_thinning_factor, 1.0, 1e3, true)},
        {"imu_information_scale", pos(sl.inertial_graph.imu_information_scale, kBig)},
        {"inertial_lidar_information_scale", pos(sl.inertial_lidar_information_scale, kBig)},
        {"inertial_gravity_gauge", set(sl.inertial_gravity_gauge)},
        {"inertial_window_size", num(sl.inertial_graph.window_size, 2.0, 1e6)}}},
      {"loop_verify",
       {{"max_verifications", num(sl.loop.max_verifications, 0.0, 1e6)},
        {"submap_neighbours", num(lv.submap_neighbours, 0.0, 1e6)},
        {"submap_min_age_s", num(lv.submap_min_age_s, 0.0, 1e6)},
        {"coarse_gate_m", pos(lv.coarse_gate_m, 1e4)},
        {"fine_gate_m", pos(lv.fine_gate_m, 1e4)},
        {"max_fitness_m", pos(lv.max_fitness_m, 1e4)},
        {"min_inlier_ratio", num(lv.min_inlier_ratio, 0.0, 1.0)},
        {"reject_degenerate", set(lv.reject_degenerate)},
        {"max_correction_m", pos(lv.max_correction_m, 1e4)},
        {"max_correction_per_m", num(lv.max_correction_per_m, 0.0, 1e3)},
        {"max_correction_rad", pos(lv.max_correction_rad, kPi)},
        {"max_correction_rad_per_m", num(lv.max_correction_rad_per_m, 0.0, kPi)},
        {"hessian_scale", pos(lv.hessian_scale, kBig)}}},
      {"radius_loop",
       {{"radius_m", pos(be.radius.radius_m, 1e4)},
        {"min_time_gap_s", num(be.radius.min_time_gap_s, 0.0, 1e6)},
        {"max_candidates", num(be.radius.max_candidates, 1.0, 1e6)}}},
      {"scan_context",
       {{"rings", num(sc.rings, 1.0, 1e4)},
        {"sectors", num(sc.sectors, 1.0, 1e4)},
        {"max_radius_m", pos(sc.max_radius_m, 1e4)},
        {"lidar_height_m", num(sc.lidar_height_m, -1e3, 1e3)},
        {"min_time_gap_s", num(sc.min_time_gap_s, 0.0, 1e6)},
        {"ring_key_candidates", num(sc.ring_key_candidates, 1.0, 1e6)},
        {"max_distance", num(sc.max_distance, 0.0, 1.0)},
        {"max_candidates", num(sc.max_candidates, 1.0, 1e6)}}},
      {"graph",
       {{"max_iterations", num(g.max_iterations, 1.0, 1e6)},
        {"window_iterations", num(g.window_iterations, 1.0, 1e6)},
        {"window_size", num(g.window_size, 1.0, 1e9)},
        {"huber_delta", pos(g.huber_delta, kBig)}}},
      {"semantic_map",
       {{"leaf_size_m", pos(be.map.leaf_size_m, 100.0)},
        {"drop_dynamic", set(be.map.drop_dynamic)},
        {"max_range_m", num(be.map.max_range_m, 0.0, 1e4)}}},
  };
  for (const auto& kv : root) {
    const std::string name = detail::key_of(kv.first, "", path);
    if (name == "deskew") {
      load_deskew_yaml(kv.second, s.deskew, path);
      continue;
    }
    const auto it = sections.find(name);
    if (it != sections.end()) {
      detail::apply(kv.second, name, it->second, path);
      continue;
    }
    const auto be_it = back_end.find(name);
    if (be_it == back_end.end()) {
      throw semlio::ConfigError(detail::where(path, kv.first, "unknown section '" + name + "'"));
    }
    detail::apply(kv.second, name, be_it->second, path);
  }
}

/// Applies the overrides in the YAML file at `path` to `s` and, when given,
/// to the back-end settings `b`. Throws semlio::ConfigError (unknown key, bad
/// value) or semlio::IoError (unreadable, larger than kMaxConfigBytes).
inline void load_settings_yaml(const std::string& path, semlio::PipelineSettings& s, BackEndSettings* b = nullptr) {
  parse_settings_yaml(semlio::io::detail::read_file(path, detail::kMaxConfigBytes), path, s, b);
}

}  // namespace semlio_examples
