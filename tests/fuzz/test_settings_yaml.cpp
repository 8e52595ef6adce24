// semlio_kitti's --config loader (examples/kitti/settings_yaml.hpp and
// deskew_yaml.hpp): every YAML problem is a semlio::ConfigError naming the
// key path and line (audit issues 4 and 9), and the fuzz corpus replays.
#include <catch2/catch.hpp>

#include <string>
#include <utility>
#include <vector>

#include "harness_settings_yaml.hpp"
#include "replay.hpp"

namespace test_settings_yaml {

namespace {

/// Loads `text` as a config file over fresh settings.
void load(const std::string& text) {
  const std::string path = semlio_fuzz::write_scratch("test_settings.yaml", text);
  semlio::PipelineSettings s;
  semlio_examples::BackEndSettings b;
  semlio_examples::load_settings_yaml(path, s, &b);
}

/// The ConfigError message of loading `text` ("<no exception>" when none,
/// "<other: ...>" for any other exception type).
std::string config_error(const std::string& text) {
  try {
    load(text);
  } catch (const semlio::ConfigError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("<other: ") + e.what() + ">";
  }
  return "<no exception>";
}

}  // namespace

TEST_CASE("settings YAML: a null or non-scalar key is a ConfigError with the line", "[fuzz][config]") {
  // Audit issue 4: the 3-byte file "? :" threw YAML::TypedBadConversion
  // outside every try block and aborted semlio_kitti.
  // (yaml-cpp reads the key of "? :" as a map holding one null pair.)
  CHECK_THAT(config_error("? :"), Catch::Contains("test_settings.yaml:1: a top-level key is") &&
                                      Catch::Contains("expected a name"));
  CHECK_THAT(config_error("odometry:\n  ? :\n"),
             Catch::Contains(":2: a key in section 'odometry' is") && Catch::Contains("expected a name"));
  CHECK_THAT(config_error("~: 1\n"), Catch::Contains(":1: a top-level key is null"));
  CHECK_THAT(config_error("odometry:\n  [a, b]: 1\n"),
             Catch::Contains(":2:") && Catch::Contains("section 'odometry'") && Catch::Contains("a sequence"));
  CHECK_THAT(config_error("deskew:\n  ? :\n"), Catch::Contains(":2:") && Catch::Contains("section 'deskew'"));
  CHECK_THAT(config_error("{a: 1}: 2\n"), Catch::Contains("top-level key is a map"));
  CHECK_THAT(config_error("odometry: [1, 2]\n"),
             Catch::Contains(":1:") && Catch::Contains("section 'odometry' is a sequence"));
  CHECK_THAT(config_error("odometry:\n  max_correction_m: [1]\n"),
             Catch::Contains(":2:") && Catch::Contains("'odometry.max_correction_m' is a sequence"));
  CHECK_THAT(config_error("odometry: {max_correction_m: 1\n"), Catch::Contains("test_settings.yaml:"));
}

TEST_CASE("settings YAML: numeric values outside their domain are ConfigErrors naming field and value",
          "[fuzz][config]") {
  // Audit issue 9: these were accepted.
  struct Case {
    std::string yaml;
    std::string fragment;
  };
  const std::vector<Case> cases = {
      {"odometry:\n  max_correction_m: -1\n", ":2: 'odometry.max_correction_m' = -1 is outside its domain (0, 10000]"},
      {"odometry:\n  max_correction_m: .nan\n", "'odometry.max_correction_m' = .nan is outside its domain"},
      {"odometry:\n  min_frame_interval_s: .nan\n", "'odometry.min_frame_interval_s' = .nan is outside its domain [0, 3600]"},
      {"solver:\n  max_iterations: -1\n", ":2: 'solver.max_iterations' = -1 is outside its domain [1, 1e+06]"},
      {"solver:\n  max_iterations: 2.5\n", "'solver.max_iterations' = '2.5' is not an integer"},
      {"map:\n  radius_m: .inf\n", "'map.radius_m' = .inf is outside its domain"},
      {"preprocess:\n  min_range_m: -0.5\n", "'preprocess.min_range_m' = -0.5"},
      {"nearest:\n  k: 0\n", "'nearest.k' = 0 is outside its domain [1, 64]"},
      {"semantic_keyframes:\n  weight_min: 1.5\n", "'semantic_keyframes.weight_min' = 1.5"},
      {"graph:\n  huber_delta: 0\n", "'graph.huber_delta' = 0 is outside its domain (0, "},
      {"semantic_map:\n  leaf_size_m: -1\n", "'semantic_map.leaf_size_m' = -1"},
      {"features:\n  max_corners_per_sector: -3\n", "'features.max_corners_per_sector' = -3"},
      {"odometry:\n  min_features: abc\n", "'odometry.min_features' = 'abc' is not an integer"},
      {"deskew:\n  sweep_period_s: .nan\n", ":2: 'deskew.sweep_period_s' must be a finite number"},
  };
  for (const Case& c : cases) {
    INFO(c.yaml);
    CHECK_THAT(config_error(c.yaml), Catch::Contains(c.fragment));
  }
  // Values inside their domains still load.
  CHECK(config_error("odometry:\n  max_correction_m: 0.5\n  min_frame_interval_s: 0\nsolver:\n  max_iterations: 1\n") ==
        "<no exception>");
  CHECK(config_error("odometry:\n") == "<no exception>");  // a null section changes nothing
}

TEST_CASE("settings YAML: semantic_weights.mode takes its three names, anything else is a ConfigError",
          "[fuzz][config]") {
  CHECK_THAT(config_error("semantic_weights:\n  mode: bogus\n"),
             Catch::Contains(":2: 'semantic_weights.mode' is 'bogus', expected chance_corrected, paper or off"));
  CHECK_THAT(config_error("semantic_weights: {mode: [paper]}\n"),
             Catch::Contains(":1: 'semantic_weights.mode' is a sequence"));
  CHECK_THAT(config_error("semantic_weights: {weight: 1}\n"), Catch::Contains("unknown key 'semantic_weights.weight'"));
  const std::vector<std::pair<std::string, semlio::SemanticWeightMode>> names = {
      {"chance_corrected", semlio::SemanticWeightMode::kChanceCorrected},
      {"paper", semlio::SemanticWeightMode::kPaper},
      {"'off'", semlio::SemanticWeightMode::kOff}};
  for (const auto& [name, mode] : names) {
    INFO(name);
    semlio::PipelineSettings s;
    s.semantic_weights.mode = name == "paper" ? semlio::SemanticWeightMode::kOff : semlio::SemanticWeightMode::kPaper;
    semlio_examples::parse_settings_yaml("semantic_weights: {mode: " + name + "}\n", "t.yaml", s);
    CHECK(s.semantic_weights.mode == mode);
  }
  semlio::PipelineSettings s;
  REQUIRE(s.semantic_weights.static_classes_agree);
  semlio_examples::parse_settings_yaml("semantic_weights: {static_classes_agree: false}\n", "t.yaml", s);
  CHECK_FALSE(s.semantic_weights.static_classes_agree);
  CHECK(s.semantic_weights.mode == semlio::SemanticWeightMode::kChanceCorrected);
  CHECK_THAT(config_error("semantic_weights: {static_classes_agree: maybe}\n"),
             Catch::Contains("semantic_weights.static_classes_agree"));
  REQUIRE(s.semantic_weights.disagreement_power == 2);
  semlio_examples::parse_settings_yaml("semantic_weights: {disagreement_power: 1}\n", "t.yaml", s);
  CHECK(s.semantic_weights.disagreement_power == 1);
  for (const char* bad : {"0", "5", "1.5", "two"}) {
    INFO(bad);
    CHECK_THAT(config_error(std::string("semantic_weights: {disagreement_power: ") + bad + "}\n"),
               Catch::Contains("semantic_weights.disagreement_power"));
  }
}

TEST_CASE("settings YAML: a missing, huge or non-regular config file is an IoError", "[fuzz][config]") {
  semlio::PipelineSettings s;
  CHECK_THROWS_AS(semlio_examples::load_settings_yaml("/nonexistent/semlio.yaml", s), semlio::IoError);
  CHECK_THROWS_AS(semlio_examples::load_settings_yaml("/dev/zero", s), semlio::IoError);
}

TEST_CASE("fuzz replay: every corpus and crash input of the settings YAML harness", "[fuzz]") {
  semlio_fuzz::replay("settings_yaml", semlio_fuzz::fuzz_settings_yaml);
}

}  // namespace test_settings_yaml
