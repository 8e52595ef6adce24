#pragma once
/// \file
/// The classic keyframe rule of LIO-SAM: a frame is a keyframe when it moved
/// more than a translation or rotation threshold from the last keyframe.

#include <semlio/concepts.hpp>

namespace semlio {

/// Settings of PoseThreshold (LIO-SAM's defaults).
struct PoseThresholdConfig {
  double translation_threshold_m = 1.0;  ///< tau_t
  double rotation_threshold_rad = 0.2;   ///< tau_r
};

/// Keyframe when ||t|| > tau_t or angle(R) > tau_r since the last keyframe.
class PoseThreshold {
 public:
  using Config = PoseThresholdConfig;

  /// Policy with the given thresholds.
  explicit PoseThreshold(const Config& config = {}) : config_(config) {}

  /// True when the motion since the last keyframe exceeds either threshold.
  [[nodiscard]] bool is_keyframe(const KeyframeEvidence& evidence) const {
    return evidence.T_lastkf_current.translation().norm() > config_.translation_threshold_m ||
           evidence.T_lastkf_current.so3().angle() > config_.rotation_threshold_rad;
  }

  /// The thresholds in use.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  Config config_;
};

static_assert(KeyframePolicy<PoseThreshold>);

}  // namespace semlio
