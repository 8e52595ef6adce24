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
#include <map>
#include <numbers>
#include <optional>
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

struct BackEndSettings;

namespace detail {

/// What the setters write into: the front-end settings and the back end's.
struct Targets {
  semlio::PipelineSettings& s;  ///< front end
  BackEndSettings& be;          ///< back end (a scratch copy when the caller wants none)
};

/// Reads one YAML value into its field of `t` (a BadValue when refused).
using Setter = void (*)(Targets&, const YAML::Node&);

/// A section: key -> setter. Plain function pointers in tables built once
/// (sections()), not closures over the settings built per call: the fuzz
/// harness parses millions of configs and the per-call tables (~120
/// std::function and map nodes) were most of its time.
using Setters = std::map<std::string, Setter>;

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
void read_value(T& field, const YAML::Node& n) {
  static_assert(std::is_same_v<T, bool> || std::is_same_v<T, std::string>, "numbers go through read_num()");
  if (!n.IsScalar()) throw BadValue{"is " + kind_of(n) + ", expected a scalar"};
  field = n.as<T>();
}

/// SemanticWeightConfig::mode from its name: chance_corrected, paper, off.
inline void read_weight_mode(semlio::SemanticWeightMode& field, const YAML::Node& n) {
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
}

/// "[lo, hi]" or "(lo, hi]": the domain as messages write it.
inline std::string domain_text(double lo, double hi, bool lo_open) {
  return std::string(lo_open ? "(" : "[") + number_text(lo) + ", " + number_text(hi) + "]";
}

/// A numeric field with its domain [lo, hi] ((lo, hi] when `lo_open`): the
/// value must be finite, integral for integer fields, and inside the domain.
/// The domain text is built only for a message (this runs once per key).
template <typename T>
void read_num(T& field, const YAML::Node& n, double lo, double hi, bool lo_open = false) {
  static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>, "read_num() takes numeric fields");
  if (!n.IsScalar()) throw BadValue{"is " + kind_of(n) + ", expected a number"};
  double v = 0.0;
  if constexpr (std::is_integral_v<T>) {
    long long i = 0;
    if (!YAML::convert<long long>::decode(n, i)) {
      throw BadValue{"= '" + n.Scalar() + "' is not an integer (domain " + domain_text(lo, hi, lo_open) + ")"};
    }
    v = static_cast<double>(i);
  } else {
    if (!YAML::convert<double>::decode(n, v)) {
      throw BadValue{"= '" + n.Scalar() + "' is not a number (domain " + domain_text(lo, hi, lo_open) + ")"};
    }
  }
  const bool inside = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
  if (!inside) throw BadValue{"= " + n.Scalar() + " is outside its domain " + domain_text(lo, hi, lo_open)};
  field = static_cast<T>(v);
}

/// A numeric field that must be positive: domain (0, hi].
template <typename T>
void read_pos(T& field, const YAML::Node& n, double hi) {
  read_num(field, n, 0.0, hi, true);
}

/// Applies one section: every key must be in `setters`, which write into `t`.
inline void apply(const YAML::Node& section, const std::string& name, const Setters& setters, Targets& t,
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
      it->second(t, kv.second);
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

namespace detail {

/// Every section but `deskew` (deskew_yaml.hpp): section -> key -> setter,
/// each with the domain of its field. Built once; the setters take the
/// settings they write as a parameter.
inline const std::map<std::string, Setters>& sections() {
  constexpr double kPi = std::numbers::pi;
  constexpr double kBig = 1e12;  // counts and scales: any sane value, never negative
  // nearest.k and normal.keep: the YAML domain is [1, kMaxCandidates]; the
  // associators' own checks narrow it to [1, kMaxKeptMatches] (a ConfigError
  // naming the field when the pipeline is built).
  // The front end (PipelineSettings, t.s), then the back end (t.be).
  static const std::map<std::string, Setters> table = {
      {"odometry",
       {
           {"kitti_vertical_correction",
            [](Targets& t, const YAML::Node& n) { read_value(t.s.odometry.kitti_vertical_correction, n); }},
           {"min_frame_interval_s",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.min_frame_interval_s, n, 0.0, 3600.0); }},
           {"min_features", [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.min_features, n, 0.0, kBig); }},
           {"max_correction_m",
            [](Targets& t, const YAML::Node& n) { read_pos(t.s.odometry.max_correction_m, n, 1e4); }},
           {"max_correction_rad",
            [](Targets& t, const YAML::Node& n) { read_pos(t.s.odometry.max_correction_rad, n, kPi); }},
           {"baseline_when_degenerate",
            [](Targets& t, const YAML::Node& n) { read_value(t.s.odometry.baseline_when_degenerate, n); }},
       }},
      {"preprocess",
       {
           {"min_range_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.preprocess.min_range_m, n, 0.0, 1e4); }},
           {"max_range_m",
            [](Targets& t, const YAML::Node& n) { read_pos(t.s.odometry.preprocess.max_range_m, n, 1e4); }},
           {"crop_ego_box",
            [](Targets& t, const YAML::Node& n) { read_value(t.s.odometry.preprocess.crop_ego_box, n); }},
       }},
      {"features",
       {
           {"neighbours",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.features.neighbours, n, 1.0, 100.0); }},
           {"sectors",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.features.sectors, n, 1.0, 3600.0); }},
           {"max_corners_per_sector",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.features.max_corners_per_sector, n, 0.0, kBig); }},
           {"corner_threshold_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.features.corner_threshold_m, n, 0.0, 1e3); }},
           {"surface_threshold_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.features.surface_threshold_m, n, 0.0, 1e3); }},
           {"occlusion_depth_gap_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.features.occlusion_depth_gap_m, n, 0.0, 1e3); }},
           {"parallel_beam_ratio",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.features.parallel_beam_ratio, n, 0.0, 1e3); }},
           {"surface_leaf_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.features.surface_leaf_m, n, 0.0, 100.0); }},
           {"corner_leaf_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.features.corner_leaf_m, n, 0.0, 100.0); }},
       }},
      {"map",
       {
           {"radius_m", [](Targets& t, const YAML::Node& n) { read_pos(t.s.odometry.map.radius_m, n, 1e4); }},
           {"corner_leaf_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.map.corner_leaf_m, n, 0.0, 100.0); }},
           {"surface_leaf_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.map.surface_leaf_m, n, 0.0, 100.0); }},
           {"shape_neighbours",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.map.shape_neighbours, n, 1.0, 1000.0); }},
           {"exclude_dynamic",
            [](Targets& t, const YAML::Node& n) { read_value(t.s.odometry.map.exclude_dynamic, n); }},
           {"max_keyframes",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.map.max_keyframes, n, 0.0, kBig); }},
           {"keep_first_point",
            [](Targets& t, const YAML::Node& n) { read_value(t.s.odometry.map.keep_first_point, n); }},
       }},
      {"solver",
       {
           {"max_iterations",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.solver.max_iterations, n, 1.0, 1e6); }},
           {"reassociate_every",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.solver.reassociate_every, n, 1.0, 1e6); }},
           {"levenberg_marquardt",
            [](Targets& t, const YAML::Node& n) { read_value(t.s.odometry.solver.levenberg_marquardt, n); }},
           {"translation_tolerance_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.solver.translation_tolerance_m, n, 0.0, 1e3); }},
           {"rotation_tolerance_rad",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.solver.rotation_tolerance_rad, n, 0.0, kPi); }},
           {"degeneracy_threshold",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.solver.degeneracy_threshold, n, 0.0, kBig); }},
           {"remap_degenerate",
            [](Targets& t, const YAML::Node& n) { read_value(t.s.odometry.solver.remap_degenerate, n); }},
           {"damp_degenerate",
            [](Targets& t, const YAML::Node& n) { read_value(t.s.odometry.solver.damp_degenerate, n); }},
           {"min_residuals",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.odometry.solver.min_residuals, n, 0.0, kBig); }},
       }},
      {"nearest",
       {
           {"k", [](Targets& t, const YAML::Node& n) { read_num(t.s.nearest.k, n, 1.0, semlio::kMaxCandidates); }},
           {"max_distance_m", [](Targets& t, const YAML::Node& n) { read_pos(t.s.nearest.max_distance_m, n, 1e4); }},
       }},
      {"normal",
       {
           {"candidates",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.normal.candidates, n, 1.0, semlio::kMaxCandidates); }},
           {"keep", [](Targets& t, const YAML::Node& n) { read_num(t.s.normal.keep, n, 1.0, semlio::kMaxCandidates); }},
           {"scan_neighbours",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.normal.scan_neighbours, n, 0.0, 1000.0); }},
           {"max_angle_rad", [](Targets& t, const YAML::Node& n) { read_num(t.s.normal.max_angle_rad, n, 0.0, kPi); }},
           {"max_distance_m", [](Targets& t, const YAML::Node& n) { read_pos(t.s.normal.max_distance_m, n, 1e4); }},
       }},
      {"line",
       {
           {"two_point", [](Targets& t, const YAML::Node& n) { read_value(t.s.line.two_point, n); }},
           {"max_linearity_ratio",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.line.max_linearity_ratio, n, 0.0, 1e6); }},
           {"cauchy_m", [](Targets& t, const YAML::Node& n) { read_num(t.s.corner_cauchy_m, n, 0.0, 1e3); }},
       }},
      {"plane",
       {
           {"three_point", [](Targets& t, const YAML::Node& n) { read_value(t.s.plane.three_point, n); }},
           {"max_planarity_ratio",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.plane.max_planarity_ratio, n, 0.0, 1e6); }},
           {"min_spread_ratio",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.plane.min_spread_ratio, n, 0.0, 1e6); }},
       }},
      {"semantic_weights",
       {
           {"mode", [](Targets& t, const YAML::Node& n) { read_weight_mode(t.s.semantic_weights.mode, n); }},
           {"static_classes_agree",
            [](Targets& t, const YAML::Node& n) { read_value(t.s.semantic_weights.static_classes_agree, n); }},
           {"disagreement_power",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.semantic_weights.disagreement_power, n, 1.0, 4.0); }},
       }},
      {"pose_threshold",
       {
           {"translation_threshold_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.pose_threshold.translation_threshold_m, n, 0.0, 1e4); }},
           {"rotation_threshold_rad",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.pose_threshold.rotation_threshold_rad, n, 0.0, kPi); }},
       }},
      {"semantic_keyframes",
       {
           {"translation_threshold_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.semantic_keyframes.translation_threshold_m, n, 0.0, 1e4); }},
           {"rotation_threshold_rad",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.semantic_keyframes.rotation_threshold_rad, n, 0.0, kPi); }},
           {"stability_threshold",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.semantic_keyframes.stability_threshold, n, 0.0, kBig); }},
           {"weight_min",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.semantic_keyframes.weight_min, n, 0.0, 1.0); }},
           {"laplace_count",
            [](Targets& t, const YAML::Node& n) { read_num(t.s.semantic_keyframes.laplace_count, n, 0.0, kBig); }},
       }},
      {"slam",
       {
           {"loop_closure", [](Targets& t, const YAML::Node& n) { read_value(t.be.slam.loop_closure, n); }},
           {"loop_detector", [](Targets& t, const YAML::Node& n) { read_value(t.be.loop_detector, n); }},
           {"loop_interval_s",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.loop_interval_s, n, 0.0, 1e6); }},
           {"robust_loops", [](Targets& t, const YAML::Node& n) { read_value(t.be.slam.robust_loops, n); }},
           {"odometry_information_scale",
            [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.odometry_information_scale, n, kBig); }},
           {"min_information",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.min_information, n, 0.0, kBig); }},
           {"max_information", [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.max_information, n, 1e15); }},
           {"weak_sigma_m", [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.weak_sigma_m, n, 1e6); }},
           {"weak_sigma_rad", [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.weak_sigma_rad, n, 1e3); }},
           {"keyframe_cloud_leaf_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.keyframe_cloud_leaf_m, n, 0.0, 100.0); }},
           {"keyframe_cloud_max_range_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.keyframe_cloud_max_range_m, n, 0.0, 1e4); }},
           {"max_keyframe_clouds",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.max_keyframe_clouds, n, 0.0, kBig); }},
           {"place_spacing_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.place_spacing_m, n, 0.0, 1e4); }},
           {"max_place_bytes",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.max_place_bytes, n, 0.0, 1e15); }},
           {"place_thinning_factor",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.place_thinning_factor, n, 1.0, 1e3, true); }},
           {"imu_information_scale",
            [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.inertial_graph.imu_information_scale, n, kBig); }},
           {"inertial_lidar_information_scale",
            [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.inertial_lidar_information_scale, n, kBig); }},
           {"inertial_gravity_gauge",
            [](Targets& t, const YAML::Node& n) { read_value(t.be.slam.inertial_gravity_gauge, n); }},
           {"inertial_window_size",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.inertial_graph.window_size, n, 2.0, 1e6); }},
       }},
      {"loop_verify",
       {
           {"max_verifications",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.loop.max_verifications, n, 0.0, 1e6); }},
           {"submap_neighbours",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.loop.verify.submap_neighbours, n, 0.0, 1e6); }},
           {"submap_min_age_s",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.loop.verify.submap_min_age_s, n, 0.0, 1e6); }},
           {"coarse_gate_m",
            [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.loop.verify.coarse_gate_m, n, 1e4); }},
           {"fine_gate_m",
            [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.loop.verify.fine_gate_m, n, 1e4); }},
           {"max_fitness_m",
            [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.loop.verify.max_fitness_m, n, 1e4); }},
           {"min_inlier_ratio",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.loop.verify.min_inlier_ratio, n, 0.0, 1.0); }},
           {"reject_degenerate",
            [](Targets& t, const YAML::Node& n) { read_value(t.be.slam.loop.verify.reject_degenerate, n); }},
           {"max_correction_m",
            [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.loop.verify.max_correction_m, n, 1e4); }},
           {"max_correction_per_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.loop.verify.max_correction_per_m, n, 0.0, 1e3); }},
           {"max_correction_rad",
            [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.loop.verify.max_correction_rad, n, kPi); }},
           {"max_correction_rad_per_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.loop.verify.max_correction_rad_per_m, n, 0.0, kPi); }},
           {"hessian_scale",
            [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.loop.verify.hessian_scale, n, kBig); }},
       }},
      {"radius_loop",
       {
           {"radius_m", [](Targets& t, const YAML::Node& n) { read_pos(t.be.radius.radius_m, n, 1e4); }},
           {"min_time_gap_s",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.radius.min_time_gap_s, n, 0.0, 1e6); }},
           {"max_candidates",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.radius.max_candidates, n, 1.0, 1e6); }},
       }},
      {"scan_context",
       {
           {"rings", [](Targets& t, const YAML::Node& n) { read_num(t.be.scan_context.rings, n, 1.0, 1e4); }},
           {"sectors", [](Targets& t, const YAML::Node& n) { read_num(t.be.scan_context.sectors, n, 1.0, 1e4); }},
           {"max_radius_m", [](Targets& t, const YAML::Node& n) { read_pos(t.be.scan_context.max_radius_m, n, 1e4); }},
           {"lidar_height_m",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.scan_context.lidar_height_m, n, -1e3, 1e3); }},
           {"min_time_gap_s",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.scan_context.min_time_gap_s, n, 0.0, 1e6); }},
           {"ring_key_candidates",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.scan_context.ring_key_candidates, n, 1.0, 1e6); }},
           {"max_distance",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.scan_context.max_distance, n, 0.0, 1.0); }},
           {"max_candidates",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.scan_context.max_candidates, n, 1.0, 1e6); }},
       }},
      {"graph",
       {
           {"max_iterations",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.graph.max_iterations, n, 1.0, 1e6); }},
           {"window_iterations",
            [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.graph.window_iterations, n, 1.0, 1e6); }},
           {"window_size", [](Targets& t, const YAML::Node& n) { read_num(t.be.slam.graph.window_size, n, 1.0, 1e9); }},
           {"huber_delta", [](Targets& t, const YAML::Node& n) { read_pos(t.be.slam.graph.huber_delta, n, kBig); }},
       }},
      {"semantic_map",
       {
           {"leaf_size_m", [](Targets& t, const YAML::Node& n) { read_pos(t.be.map.leaf_size_m, n, 100.0); }},
           {"drop_dynamic", [](Targets& t, const YAML::Node& n) { read_value(t.be.map.drop_dynamic, n); }},
           {"max_range_m", [](Targets& t, const YAML::Node& n) { read_num(t.be.map.max_range_m, n, 0.0, 1e4); }},
       }},
  };
  return table;
}

}  // namespace detail

/// Applies the overrides in the YAML `text` to `s` and, when given, to the
/// back-end settings `b`; errors name `path` (the file the text came from).
/// Throws semlio::ConfigError (syntax, unknown key, bad value).
inline void parse_settings_yaml(const std::string& text, const std::string& path, semlio::PipelineSettings& s,
                                BackEndSettings* b = nullptr) {
  const YAML::Node root = detail::parse_yaml_text(text, path);
  if (!root || root.IsNull()) return;
  if (!root.IsMap()) throw semlio::ConfigError(detail::where(path, root, "the config is " + detail::kind_of(root) + ", expected a YAML map"));
  // Back-end keys without a caller's BackEndSettings go to a scratch copy,
  // built only then.
  std::optional<BackEndSettings> scratch;
  if (b == nullptr) scratch.emplace();
  detail::Targets t{s, b != nullptr ? *b : *scratch};
  const std::map<std::string, detail::Setters>& sections = detail::sections();
  for (const auto& kv : root) {
    const std::string name = detail::key_of(kv.first, "", path);
    if (name == "deskew") {
      load_deskew_yaml(kv.second, s.deskew, path);
      continue;
    }
    const auto it = sections.find(name);
    if (it == sections.end()) {
      throw semlio::ConfigError(detail::where(path, kv.first, "unknown section '" + name + "'"));
    }
    detail::apply(kv.second, name, it->second, t, path);
  }
}

/// Applies the overrides in the YAML file at `path` to `s` and, when given,
/// to the back-end settings `b`. Throws semlio::ConfigError (unknown key, bad
/// value) or semlio::IoError (unreadable, larger than kMaxConfigBytes).
inline void load_settings_yaml(const std::string& path, semlio::PipelineSettings& s, BackEndSettings* b = nullptr) {
  parse_settings_yaml(semlio::io::detail::read_file(path, detail::kMaxConfigBytes), path, s, b);
}

}  // namespace semlio_examples
