#pragma once
/// \file
/// LIO-SAM's loop candidates: older keyframes whose current position estimate
/// lies within a radius of the query's, and whose stamp is older than a time
/// gap (so that the recent trajectory never "closes a loop" with itself).
///
/// Search: brute force over the keyframe positions. The positions change after
/// each graph solve, so a k-d tree would need a rebuild per query anyway; a
/// linear scan over a few thousand positions costs microseconds (measured in
/// tests/loop/test_radius_detector.cpp).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/loop/loop_detector.hpp>
#include <semlio/loop/loop_keyframe.hpp>

namespace semlio {

/// Settings of RadiusLoopDetector (defaults: LIO-SAM historyKeyframeSearchRadius / TimeDiff).
struct RadiusLoopConfig {
  double radius_m = 15.0;          ///< candidate positions within this distance of the query's [m]
  double min_time_gap_s = 30.0;    ///< candidates older than the query by more than this [s]
  std::size_t max_candidates = 3;  ///< at most this many candidates, nearest first
};

/// Radius search over keyframe positions (current estimates). Stateless apart
/// from its settings; candidates come nearest first (ties: older first), with
/// the guess T_from_to = T_world_from^-1 T_world_to from the current estimates.
class RadiusLoopDetector {
 public:
  using Config = RadiusLoopConfig;

  /// Default settings (implicit, so that `Detector detector = {}` works).
  RadiusLoopDetector() : RadiusLoopDetector(Config{}) {}
  /// Validates the settings (ConfigError naming the field and value).
  explicit RadiusLoopDetector(const Config& config) : config_(config) {
    if (!(config_.radius_m > 0.0) || !std::isfinite(config_.radius_m)) {
      throw ConfigError("RadiusLoopConfig.radius_m = " + std::to_string(config_.radius_m) +
                        ", expected a finite value > 0");
    }
    if (!(config_.min_time_gap_s >= 0.0) || !std::isfinite(config_.min_time_gap_s)) {
      throw ConfigError("RadiusLoopConfig.min_time_gap_s = " + std::to_string(config_.min_time_gap_s) +
                        ", expected a finite value >= 0");
    }
  }

  /// Candidates for keyframes.back(), nearest first, into out (cleared).
  void detect(const std::vector<LoopKeyframe>& keyframes, std::vector<LoopCandidate>& out) const {
    out.clear();
    if (keyframes.size() < 2 || config_.max_candidates == 0) return;
    const LoopKeyframe& query = keyframes.back();
    const Eigen::Vector3d& p_q = query.T_world_lidar.translation();
    const double r2 = config_.radius_m * config_.radius_m;
    for (std::size_t i = 0; i + 1 < keyframes.size(); ++i) {
      const LoopKeyframe& kf = keyframes[i];
      if (!(query.stamp_s - kf.stamp_s > config_.min_time_gap_s)) continue;
      const double d2 = (kf.T_world_lidar.translation() - p_q).squaredNorm();
      if (!(d2 <= r2)) continue;
      out.push_back(LoopCandidate{i, kf.T_world_lidar.inverse() * query.T_world_lidar, std::sqrt(d2)});
    }
    std::stable_sort(out.begin(), out.end(),
                     [](const LoopCandidate& a, const LoopCandidate& b) { return a.score < b.score; });
    if (out.size() > config_.max_candidates) out.resize(config_.max_candidates);
  }

  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  Config config_;
};

static_assert(LoopDetector<RadiusLoopDetector>);

}  // namespace semlio
