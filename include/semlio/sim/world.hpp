#pragma once
/// \file
/// Procedural worlds: `make_world` builds the static scene, the ego route and
/// the traffic lanes of an urban, rural, highway or aliased world. Same
/// config -> identical world (all randomness from WorldConfig::seed).

#include <semlio/sim/strip_world.hpp>
#include <semlio/sim/urban_world.hpp>
#include <semlio/sim/world_config.hpp>

namespace semlio::sim {

/// Builds the world described by `config` (see urban_world.hpp and
/// strip_world.hpp for what each kind contains).
inline World make_world(const WorldConfig& config) {
  if (!(config.drive_length_m > 0.0)) {
    throw ConfigError("WorldConfig.drive_length_m must be > 0, got " + std::to_string(config.drive_length_m));
  }
  switch (config.kind) {
    case WorldKind::kUrban:
    case WorldKind::kAliased: return detail::make_urban_world(config);
    case WorldKind::kRural:
    case WorldKind::kHighway: return detail::make_strip_world(config);
  }
  return detail::make_urban_world(config);
}

}  // namespace semlio::sim
