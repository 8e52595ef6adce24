#pragma once
// YAML overrides of semlio::PipelineSettings (front end) and BackEndSettings
// (slam, loop_verify, radius_loop, scan_context, graph, semantic_map) for semlio_kitti. Every key is
// optional; an unknown section or key is an error (typos must not be silently
// ignored). The README lists every key with its default.

#include <yaml-cpp/yaml.h>

#include "deskew_yaml.hpp"

#include <functional>
#include <map>
#include <string>

#include <semlio/core/error.hpp>
#include <semlio/loop/radius_detector.hpp>
#include <semlio/loop/scan_context.hpp>
#include <semlio/map/semantic_map.hpp>
#include <semlio/pipeline/presets.hpp>
#include <semlio/pipeline/slam.hpp>

namespace semlio_examples {

namespace detail {

// A section maps key -> setter that reads the YAML node into a field.
using Setters = std::map<std::string, std::function<void(const YAML::Node&)>>;

template <typename T>
std::function<void(const YAML::Node&)> set(T& field) {
  return [&field](const YAML::Node& n) { field = n.as<T>(); };
}

inline void apply(const YAML::Node& section, const std::string& name, const Setters& setters,
                  const std::string& path) {
  if (!section) return;
  if (!section.IsMap()) throw semlio::ConfigError(path + ": section '" + name + "' must be a map");
  for (const auto& kv : section) {
    const auto key = kv.first.as<std::string>();
    const auto it = setters.find(key);
    if (it == setters.end()) throw semlio::ConfigError(path + ": unknown key '" + name + "." + key + "'");
    try {
      it->second(kv.second);
    } catch (const YAML::Exception& e) {
      throw semlio::ConfigError(path + ": bad value for '" + name + "." + key + "': " + e.what());
    }
  }
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

/// Applies the overrides in the YAML file at `path` to `s` and, when given,
/// to the back-end settings `b`. Throws semlio::ConfigError (unknown key, bad
/// value) or semlio::IoError.
inline void load_settings_yaml(const std::string& path, semlio::PipelineSettings& s, BackEndSettings* b = nullptr) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw semlio::IoError(path + ": cannot open the config file");
  } catch (const YAML::Exception& e) {
    throw semlio::ConfigError(path + ": " + e.what());
  }
  if (!root || root.IsNull()) return;
  if (!root.IsMap()) throw semlio::ConfigError(path + ": the config must be a YAML map");
  using detail::set;
  auto& o = s.odometry;
  const std::map<std::string, detail::Setters> sections = {
      {"odometry",
       {{"kitti_vertical_correction", set(o.kitti_vertical_correction)},
        {"min_frame_interval_s", set(o.min_frame_interval_s)},
        {"min_features", set(o.min_features)},
        {"max_correction_m", set(o.max_correction_m)},
        {"max_correction_rad", set(o.max_correction_rad)}}},
      {"preprocess",
       {{"min_range_m", set(o.preprocess.min_range_m)},
        {"max_range_m", set(o.preprocess.max_range_m)},
        {"crop_ego_box", set(o.preprocess.crop_ego_box)}}},
      {"features",
       {{"neighbours", set(o.features.neighbours)},
        {"sectors", set(o.features.sectors)},
        {"max_corners_per_sector", set(o.features.max_corners_per_sector)},
        {"corner_threshold_m", set(o.features.corner_threshold_m)},
        {"surface_threshold_m", set(o.features.surface_threshold_m)},
        {"occlusion_depth_gap_m", set(o.features.occlusion_depth_gap_m)},
        {"parallel_beam_ratio", set(o.features.parallel_beam_ratio)},
        {"surface_leaf_m", set(o.features.surface_leaf_m)},
        {"corner_leaf_m", set(o.features.corner_leaf_m)}}},
      {"map",
       {{"radius_m", set(o.map.radius_m)},
        {"corner_leaf_m", set(o.map.corner_leaf_m)},
        {"surface_leaf_m", set(o.map.surface_leaf_m)},
        {"shape_neighbours", set(o.map.shape_neighbours)},
        {"exclude_dynamic", set(o.map.exclude_dynamic)},
        {"max_keyframes", set(o.map.max_keyframes)},
        {"keep_first_point", set(o.map.keep_first_point)}}},
      {"solver",
       {{"max_iterations", set(o.solver.max_iterations)},
        {"reassociate_every", set(o.solver.reassociate_every)},
        {"levenberg_marquardt", set(o.solver.levenberg_marquardt)},
        {"translation_tolerance_m", set(o.solver.translation_tolerance_m)},
        {"rotation_tolerance_rad", set(o.solver.rotation_tolerance_rad)},
        {"degeneracy_threshold", set(o.solver.degeneracy_threshold)},
        {"remap_degenerate", set(o.solver.remap_degenerate)},
        {"damp_degenerate", set(o.solver.damp_degenerate)},
        {"min_residuals", set(o.solver.min_residuals)}}},
      {"nearest", {{"k", set(s.nearest.k)}, {"max_distance_m", set(s.nearest.max_distance_m)}}},
      {"normal",
       {{"candidates", set(s.normal.candidates)},
        {"keep", set(s.normal.keep)},
        {"scan_neighbours", set(s.normal.scan_neighbours)},
        {"max_angle_rad", set(s.normal.max_angle_rad)},
        {"max_distance_m", set(s.normal.max_distance_m)}}},
      {"line",
       {{"two_point", set(s.line.two_point)},
        {"max_linearity_ratio", set(s.line.max_linearity_ratio)},
        {"cauchy_m", set(s.corner_cauchy_m)}}},
      {"plane",
       {{"three_point", set(s.plane.three_point)},
        {"max_planarity_ratio", set(s.plane.max_planarity_ratio)},
        {"min_spread_ratio", set(s.plane.min_spread_ratio)}}},
      {"pose_threshold",
       {{"translation_threshold_m", set(s.pose_threshold.translation_threshold_m)},
        {"rotation_threshold_rad", set(s.pose_threshold.rotation_threshold_rad)}}},
      {"semantic_keyframes",
       {{"translation_threshold_m", set(s.semantic_keyframes.translation_threshold_m)},
        {"rotation_threshold_rad", set(s.semantic_keyframes.rotation_threshold_rad)},
        {"stability_threshold", set(s.semantic_keyframes.stability_threshold)},
        {"weight_min", set(s.semantic_keyframes.weight_min)},
        {"laplace_count", set(s.semantic_keyframes.laplace_count)}}},
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
        {"loop_interval_s", set(sl.loop_interval_s)},
        {"robust_loops", set(sl.robust_loops)},
        {"odometry_information_scale", set(sl.odometry_information_scale)},
        {"min_information", set(sl.min_information)},
        {"max_information", set(sl.max_information)},
        {"weak_sigma_m", set(sl.weak_sigma_m)},
        {"weak_sigma_rad", set(sl.weak_sigma_rad)},
        {"keyframe_cloud_leaf_m", set(sl.keyframe_cloud_leaf_m)},
        {"keyframe_cloud_max_range_m", set(sl.keyframe_cloud_max_range_m)},
        {"max_keyframe_clouds", set(sl.max_keyframe_clouds)},
        {"place_spacing_m", set(sl.place_spacing_m)},
        {"max_place_bytes", set(sl.max_place_bytes)},
        {"place_thinning_factor", set(sl.place_thinning_factor)},
        {"imu_information_scale", set(sl.inertial_graph.imu_information_scale)},
        {"inertial_lidar_information_scale", set(sl.inertial_lidar_information_scale)},
        {"inertial_gravity_gauge", set(sl.inertial_gravity_gauge)},
        {"inertial_window_size", set(sl.inertial_graph.window_size)}}},
      {"loop_verify",
       {{"max_verifications", set(sl.loop.max_verifications)},
        {"submap_neighbours", set(lv.submap_neighbours)},
        {"submap_min_age_s", set(lv.submap_min_age_s)},
        {"coarse_gate_m", set(lv.coarse_gate_m)},
        {"fine_gate_m", set(lv.fine_gate_m)},
        {"max_fitness_m", set(lv.max_fitness_m)},
        {"min_inlier_ratio", set(lv.min_inlier_ratio)},
        {"reject_degenerate", set(lv.reject_degenerate)},
        {"max_correction_m", set(lv.max_correction_m)},
        {"max_correction_per_m", set(lv.max_correction_per_m)},
        {"max_correction_rad", set(lv.max_correction_rad)},
        {"max_correction_rad_per_m", set(lv.max_correction_rad_per_m)},
        {"hessian_scale", set(lv.hessian_scale)}}},
      {"radius_loop",
       {{"radius_m", set(be.radius.radius_m)},
        {"min_time_gap_s", set(be.radius.min_time_gap_s)},
        {"max_candidates", set(be.radius.max_candidates)}}},
      {"scan_context",
       {{"rings", set(sc.rings)},
        {"sectors", set(sc.sectors)},
        {"max_radius_m", set(sc.max_radius_m)},
        {"lidar_height_m", set(sc.lidar_height_m)},
        {"min_time_gap_s", set(sc.min_time_gap_s)},
        {"ring_key_candidates", set(sc.ring_key_candidates)},
        {"max_distance", set(sc.max_distance)},
        {"max_candidates", set(sc.max_candidates)}}},
      {"graph",
       {{"max_iterations", set(g.max_iterations)},
        {"window_iterations", set(g.window_iterations)},
        {"window_size", set(g.window_size)},
        {"huber_delta", set(g.huber_delta)}}},
      {"semantic_map",
       {{"leaf_size_m", set(be.map.leaf_size_m)},
        {"drop_dynamic", set(be.map.drop_dynamic)},
        {"max_range_m", set(be.map.max_range_m)}}},
  };
  for (const auto& kv : root) {
    const auto name = kv.first.as<std::string>();
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
    if (be_it == back_end.end()) throw semlio::ConfigError(path + ": unknown section '" + name + "'");
    detail::apply(kv.second, name, be_it->second, path);
  }
}

}  // namespace semlio_examples
