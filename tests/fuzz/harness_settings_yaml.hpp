#pragma once
// Fuzz harness body for semlio_kitti's --config loader
// (examples/kitti/settings_yaml.hpp): any bytes give either settings inside
// their documented domains or a semlio::Error (ConfigError / IoError) -- never
// a YAML exception, never a crash.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include <semlio/core/error.hpp>

#include "fuzz_support.hpp"
#include "settings_yaml.hpp"

namespace semlio_fuzz {

/// The YAML settings text: parse_settings_yaml (load_settings_yaml's body
/// without the file read) over fresh settings.
inline int fuzz_settings_yaml(const std::uint8_t* data, std::size_t size) {
  semlio::PipelineSettings s;
  semlio_examples::BackEndSettings b;
  try {
    semlio_examples::parse_settings_yaml(std::string(as_text(data, size)), "settings.yaml", s, &b);
  } catch (const semlio::Error&) {
    return 0;
  }
  // A sample of the domains the loader documents (settings_yaml.hpp).
  const auto& o = s.odometry;
  check(std::isfinite(o.max_correction_m) && o.max_correction_m > 0.0);
  check(std::isfinite(o.max_correction_rad) && o.max_correction_rad > 0.0);
  check(std::isfinite(o.min_frame_interval_s) && o.min_frame_interval_s >= 0.0);
  check(o.solver.max_iterations >= 1 && o.solver.reassociate_every >= 1);
  check(o.features.neighbours >= 1 && o.features.sectors >= 1);
  check(std::isfinite(o.preprocess.max_range_m) && o.preprocess.max_range_m > 0.0);
  check(s.nearest.k >= 1 && s.normal.keep >= 1 && s.normal.candidates >= 1);
  check(std::isfinite(b.map.leaf_size_m) && b.map.leaf_size_m > 0.0);
  check(std::isfinite(b.slam.graph.huber_delta) && b.slam.graph.huber_delta > 0.0);
  check(std::isfinite(s.deskew.sweep_period_s) && std::isfinite(s.deskew.frame_period_s));
  return 0;
}

}  // namespace semlio_fuzz
