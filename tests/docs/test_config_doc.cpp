// docs/config.md against the code: every row of its key tables names a key
// semlio_kitti's --config accepts (examples/kitti/settings_yaml.hpp), its
// default column equals the value of the settings struct semlio_kitti starts
// from, and every key the loader knows (the list below) has a row. A
// perturbed value is loaded too, so each getter is proven to read the field
// its key sets.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "settings_yaml.hpp"

namespace test_config_doc {

namespace {

using semlio::PipelineSettings;
using semlio_examples::BackEndSettings;

template <typename T>
std::string text(const T& x) {
  if constexpr (std::is_same_v<T, bool>) {
    return x ? "true" : "false";
  } else if constexpr (std::is_arithmetic_v<T>) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", static_cast<double>(x));
    return buf;
  } else {
    return std::string(x);
  }
}

using Getter = std::function<std::string(const PipelineSettings&, const BackEndSettings&)>;

// The value of every key, as the YAML would spell it. Enumerations and the
// one degree-valued key are converted the way deskew_yaml.hpp parses them.
std::map<std::string, Getter> getters() {
  std::map<std::string, Getter> g;
#define SEMLIO_KEY(name, expr) g[name] = [](const PipelineSettings& s, const BackEndSettings& b) { \
  (void)s;                                                                                          \
  (void)b;                                                                                          \
  return text(expr);                                                                                \
}
  SEMLIO_KEY("odometry.kitti_vertical_correction", s.odometry.kitti_vertical_correction);
  SEMLIO_KEY("odometry.min_frame_interval_s", s.odometry.min_frame_interval_s);
  SEMLIO_KEY("odometry.min_features", s.odometry.min_features);
  SEMLIO_KEY("odometry.max_correction_m", s.odometry.max_correction_m);
  SEMLIO_KEY("odometry.max_correction_rad", s.odometry.max_correction_rad);
  SEMLIO_KEY("odometry.baseline_when_degenerate", s.odometry.baseline_when_degenerate);
  SEMLIO_KEY("preprocess.min_range_m", s.odometry.preprocess.min_range_m);
  SEMLIO_KEY("preprocess.max_range_m", s.odometry.preprocess.max_range_m);
  SEMLIO_KEY("preprocess.crop_ego_box", s.odometry.preprocess.crop_ego_box);
  SEMLIO_KEY("features.neighbours", s.odometry.features.neighbours);
  SEMLIO_KEY("features.sectors", s.odometry.features.sectors);
  SEMLIO_KEY("features.max_corners_per_sector", s.odometry.features.max_corners_per_sector);
  SEMLIO_KEY("features.corner_threshold_m", s.odometry.features.corner_threshold_m);
  SEMLIO_KEY("features.surface_threshold_m", s.odometry.features.surface_threshold_m);
  SEMLIO_KEY("features.occlusion_depth_gap_m", s.odometry.features.occlusion_depth_gap_m);
  SEMLIO_KEY("features.parallel_beam_ratio", s.odometry.features.parallel_beam_ratio);
  SEMLIO_KEY("features.surface_leaf_m", s.odometry.features.surface_leaf_m);
  SEMLIO_KEY("features.corner_leaf_m", s.odometry.features.corner_leaf_m);
  SEMLIO_KEY("map.radius_m", s.odometry.map.radius_m);
  SEMLIO_KEY("map.corner_leaf_m", s.odometry.map.corner_leaf_m);
  SEMLIO_KEY("map.surface_leaf_m", s.odometry.map.surface_leaf_m);
  SEMLIO_KEY("map.shape_neighbours", s.odometry.map.shape_neighbours);
  SEMLIO_KEY("map.exclude_dynamic", s.odometry.map.exclude_dynamic);
  SEMLIO_KEY("map.max_keyframes", s.odometry.map.max_keyframes);
  SEMLIO_KEY("map.keep_first_point", s.odometry.map.keep_first_point);
  SEMLIO_KEY("solver.max_iterations", s.odometry.solver.max_iterations);
  SEMLIO_KEY("solver.reassociate_every", s.odometry.solver.reassociate_every);
  SEMLIO_KEY("solver.levenberg_marquardt", s.odometry.solver.levenberg_marquardt);
  SEMLIO_KEY("solver.translation_tolerance_m", s.odometry.solver.translation_tolerance_m);
  SEMLIO_KEY("solver.rotation_tolerance_rad", s.odometry.solver.rotation_tolerance_rad);
  SEMLIO_KEY("solver.degeneracy_threshold", s.odometry.solver.degeneracy_threshold);
  SEMLIO_KEY("solver.remap_degenerate", s.odometry.solver.remap_degenerate);
  SEMLIO_KEY("solver.damp_degenerate", s.odometry.solver.damp_degenerate);
  SEMLIO_KEY("solver.min_residuals", s.odometry.solver.min_residuals);
  SEMLIO_KEY("nearest.k", s.nearest.k);
  SEMLIO_KEY("nearest.max_distance_m", s.nearest.max_distance_m);
  SEMLIO_KEY("normal.candidates", s.normal.candidates);
  SEMLIO_KEY("normal.keep", s.normal.keep);
  SEMLIO_KEY("normal.scan_neighbours", s.normal.scan_neighbours);
  SEMLIO_KEY("normal.max_angle_rad", s.normal.max_angle_rad);
  SEMLIO_KEY("normal.max_distance_m", s.normal.max_distance_m);
  SEMLIO_KEY("line.two_point", s.line.two_point);
  SEMLIO_KEY("line.max_linearity_ratio", s.line.max_linearity_ratio);
  SEMLIO_KEY("line.cauchy_m", s.corner_cauchy_m);
  SEMLIO_KEY("plane.three_point", s.plane.three_point);
  SEMLIO_KEY("plane.max_planarity_ratio", s.plane.max_planarity_ratio);
  SEMLIO_KEY("plane.min_spread_ratio", s.plane.min_spread_ratio);
  SEMLIO_KEY("semantic_weights.mode",
             s.semantic_weights.mode == semlio::SemanticWeightMode::kChanceCorrected ? "chance_corrected"
             : s.semantic_weights.mode == semlio::SemanticWeightMode::kPaper         ? "paper"
                                                                                     : "off");
  SEMLIO_KEY("semantic_weights.static_classes_agree", s.semantic_weights.static_classes_agree);
  SEMLIO_KEY("semantic_weights.disagreement_power", s.semantic_weights.disagreement_power);
  SEMLIO_KEY("pose_threshold.translation_threshold_m", s.pose_threshold.translation_threshold_m);
  SEMLIO_KEY("pose_threshold.rotation_threshold_rad", s.pose_threshold.rotation_threshold_rad);
  SEMLIO_KEY("semantic_keyframes.translation_threshold_m", s.semantic_keyframes.translation_threshold_m);
  SEMLIO_KEY("semantic_keyframes.rotation_threshold_rad", s.semantic_keyframes.rotation_threshold_rad);
  SEMLIO_KEY("semantic_keyframes.stability_threshold", s.semantic_keyframes.stability_threshold);
  SEMLIO_KEY("semantic_keyframes.weight_min", s.semantic_keyframes.weight_min);
  SEMLIO_KEY("semantic_keyframes.laplace_count", s.semantic_keyframes.laplace_count);
  SEMLIO_KEY("deskew.mode", s.deskew.mode == semlio::DeskewMode::kNone ? "none" : "constant_velocity");
  SEMLIO_KEY("deskew.point_times", s.deskew.point_times == semlio::PointTimeSource::kAuto   ? "auto"
                                   : s.deskew.point_times == semlio::PointTimeSource::kScan ? "scan"
                                                                                            : "azimuth");
  SEMLIO_KEY("deskew.sweep_period_s", s.deskew.sweep_period_s);
  SEMLIO_KEY("deskew.start_azimuth_deg", s.deskew.start_azimuth_rad * 180.0 / std::numbers::pi);
  SEMLIO_KEY("deskew.direction", s.deskew.clockwise ? "clockwise" : "counter_clockwise");
  SEMLIO_KEY("deskew.reverse_time", s.deskew.reverse_time);
  SEMLIO_KEY("deskew.target", s.deskew.target == semlio::DeskewTarget::kStart    ? "start"
                              : s.deskew.target == semlio::DeskewTarget::kMiddle ? "middle"
                                                                                 : "end");
  SEMLIO_KEY("deskew.frame_period_s", s.deskew.frame_period_s);
  SEMLIO_KEY("slam.loop_closure", b.slam.loop_closure);
  SEMLIO_KEY("slam.loop_detector", b.loop_detector);
  SEMLIO_KEY("slam.loop_interval_s", b.slam.loop_interval_s);
  SEMLIO_KEY("slam.robust_loops", b.slam.robust_loops);
  SEMLIO_KEY("slam.odometry_information_scale", b.slam.odometry_information_scale);
  SEMLIO_KEY("slam.min_information", b.slam.min_information);
  SEMLIO_KEY("slam.max_information", b.slam.max_information);
  SEMLIO_KEY("slam.weak_sigma_m", b.slam.weak_sigma_m);
  SEMLIO_KEY("slam.weak_sigma_rad", b.slam.weak_sigma_rad);
  SEMLIO_KEY("slam.keyframe_cloud_leaf_m", b.slam.keyframe_cloud_leaf_m);
  SEMLIO_KEY("slam.keyframe_cloud_max_range_m", b.slam.keyframe_cloud_max_range_m);
  SEMLIO_KEY("slam.max_keyframe_clouds", b.slam.max_keyframe_clouds);
  SEMLIO_KEY("slam.place_spacing_m", b.slam.place_spacing_m);
  SEMLIO_KEY("slam.max_place_bytes", b.slam.max_place_bytes);
  SEMLIO_KEY("slam.place_thinning_factor", b.slam.place_thinning_factor);
  SEMLIO_KEY("slam.imu_information_scale", b.slam.inertial_graph.imu_information_scale);
  SEMLIO_KEY("slam.inertial_lidar_information_scale", b.slam.inertial_lidar_information_scale);
  SEMLIO_KEY("slam.inertial_gravity_gauge", b.slam.inertial_gravity_gauge);
  SEMLIO_KEY("slam.inertial_window_size", b.slam.inertial_graph.window_size);
  SEMLIO_KEY("loop_verify.max_verifications", b.slam.loop.max_verifications);
  SEMLIO_KEY("loop_verify.submap_neighbours", b.slam.loop.verify.submap_neighbours);
  SEMLIO_KEY("loop_verify.submap_min_age_s", b.slam.loop.verify.submap_min_age_s);
  SEMLIO_KEY("loop_verify.coarse_gate_m", b.slam.loop.verify.coarse_gate_m);
  SEMLIO_KEY("loop_verify.fine_gate_m", b.slam.loop.verify.fine_gate_m);
  SEMLIO_KEY("loop_verify.max_fitness_m", b.slam.loop.verify.max_fitness_m);
  SEMLIO_KEY("loop_verify.min_inlier_ratio", b.slam.loop.verify.min_inlier_ratio);
  SEMLIO_KEY("loop_verify.reject_degenerate", b.slam.loop.verify.reject_degenerate);
  SEMLIO_KEY("loop_verify.max_correction_m", b.slam.loop.verify.max_correction_m);
  SEMLIO_KEY("loop_verify.max_correction_per_m", b.slam.loop.verify.max_correction_per_m);
  SEMLIO_KEY("loop_verify.max_correction_rad", b.slam.loop.verify.max_correction_rad);
  SEMLIO_KEY("loop_verify.max_correction_rad_per_m", b.slam.loop.verify.max_correction_rad_per_m);
  SEMLIO_KEY("loop_verify.hessian_scale", b.slam.loop.verify.hessian_scale);
  SEMLIO_KEY("radius_loop.radius_m", b.radius.radius_m);
  SEMLIO_KEY("radius_loop.min_time_gap_s", b.radius.min_time_gap_s);
  SEMLIO_KEY("radius_loop.max_candidates", b.radius.max_candidates);
  SEMLIO_KEY("scan_context.rings", b.scan_context.rings);
  SEMLIO_KEY("scan_context.sectors", b.scan_context.sectors);
  SEMLIO_KEY("scan_context.max_radius_m", b.scan_context.max_radius_m);
  SEMLIO_KEY("scan_context.lidar_height_m", b.scan_context.lidar_height_m);
  SEMLIO_KEY("scan_context.min_time_gap_s", b.scan_context.min_time_gap_s);
  SEMLIO_KEY("scan_context.ring_key_candidates", b.scan_context.ring_key_candidates);
  SEMLIO_KEY("scan_context.max_distance", b.scan_context.max_distance);
  SEMLIO_KEY("scan_context.max_candidates", b.scan_context.max_candidates);
  SEMLIO_KEY("graph.max_iterations", b.slam.graph.max_iterations);
  SEMLIO_KEY("graph.window_iterations", b.slam.graph.window_iterations);
  SEMLIO_KEY("graph.window_size", b.slam.graph.window_size);
  SEMLIO_KEY("graph.huber_delta", b.slam.graph.huber_delta);
  SEMLIO_KEY("semantic_map.leaf_size_m", b.map.leaf_size_m);
  SEMLIO_KEY("semantic_map.drop_dynamic", b.map.drop_dynamic);
  SEMLIO_KEY("semantic_map.max_range_m", b.map.max_range_m);
#undef SEMLIO_KEY
  return g;
}

struct Row {
  std::string key;
  std::string value;
  int line = 0;
};

// Rows "| `section.key` | `default` | ..." of config.md's key tables.
std::vector<Row> doc_rows(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::vector<Row> rows;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.rfind("| `", 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line.substr(1));
    std::string cell;
    while (std::getline(ss, cell, '|')) cells.push_back(cell);
    if (cells.size() < 2) continue;
    auto strip = [](std::string s) {
      const auto b = s.find_first_not_of(" `");
      const auto e = s.find_last_not_of(" `");
      return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
    };
    const std::string key = strip(cells[0]);
    if (key.find('.') == std::string::npos) continue;
    rows.push_back({key, strip(cells[1]), n});
  }
  return rows;
}

bool same_value(const std::string& doc, const std::string& code) {
  if (doc == code) return true;
  char* end_a = nullptr;
  char* end_b = nullptr;
  const double a = std::strtod(doc.c_str(), &end_a);
  const double b = std::strtod(code.c_str(), &end_b);
  if (end_a == doc.c_str() || *end_a != '\0' || end_b == code.c_str() || *end_b != '\0') return false;
  return std::abs(a - b) <= 1e-6 * std::abs(b) + 1e-12;  // relative: the doc rounds to ~6 digits
}

// Loads `section: {key: value}` over fresh settings.
void load(const std::string& key, const std::string& value, PipelineSettings& s, BackEndSettings& b) {
  const auto dot = key.find('.');
  const auto path = std::filesystem::temp_directory_path() / "semlio_test_config_doc.yaml";
  {
    std::ofstream out(path);
    out << key.substr(0, dot) << ":\n  " << key.substr(dot + 1) << ": " << value << "\n";
  }
  semlio_examples::load_settings_yaml(path.string(), s, &b);
}

std::string perturbed(const std::string& v) {
  if (v == "true") return "false";
  if (v == "false") return "true";
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (end == v.c_str() || *end != '\0') return "";  // an enumeration: no arithmetic perturbation
  // A neighbouring value inside every key's range: one less (one more from
  // 0 or 1) for integers, 10 % less (0.5 from 0) for real numbers.
  const bool integer = v.find_first_of(".eE") == std::string::npos;
  if (integer) {
    const auto n = static_cast<long long>(x);
    return std::to_string(n > 1 ? n - 1 : n + 1);
  }
  return text(x == 0.0 ? 0.5 : x * 0.9);
}

}  // namespace

TEST_CASE("docs/config.md lists every semlio_kitti --config key with the code's default", "[docs]") {
  const auto rows = doc_rows(std::string(SEMLIO_SOURCE_DIR) + "/docs/config.md");
  const auto g = getters();
  const PipelineSettings s0;
  const BackEndSettings b0;
  std::set<std::string> documented;
  for (const Row& row : rows) {
    INFO("docs/config.md:" << row.line << ": " << row.key << " = " << row.value);
    CHECK(documented.insert(row.key).second);  // each key once
    const auto it = g.find(row.key);
    REQUIRE(it != g.end());
    CHECK(same_value(row.value, it->second(s0, b0)));
    // The loader accepts the documented default and it changes nothing...
    PipelineSettings s1;
    BackEndSettings b1;
    CHECK_NOTHROW(load(row.key, row.value, s1, b1));
    CHECK(same_value(it->second(s1, b1), it->second(s0, b0)));
    // ...and a different value lands in the field the getter reads.
    const std::string other = perturbed(row.value);
    if (!other.empty() && row.key != "deskew.start_azimuth_deg") {
      PipelineSettings s2;
      BackEndSettings b2;
      INFO("perturbed to " << other);
      CHECK_NOTHROW(load(row.key, other, s2, b2));
      CHECK(same_value(other, it->second(s2, b2)));
    }
  }
  for (const auto& [key, getter] : g) {
    INFO(key << " is a --config key without a row in docs/config.md");
    CHECK(documented.count(key) == 1);
  }
}

}  // namespace test_config_doc
