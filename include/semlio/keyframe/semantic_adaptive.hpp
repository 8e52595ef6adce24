#pragma once
/// \file
/// The paper's semantic keyframe selection (§3.2, eq. 14-22, Algorithm 2) as
/// METHOD.md decides it: the pose thresholds are scaled by a semantic weight
/// W_se built from the KL divergence between the label distributions of the
/// current frame and the last keyframe, and from the frame's stability score.

#include <algorithm>
#include <array>
#include <cmath>

#include <semlio/concepts.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>

namespace semlio {

/// Settings of SemanticAdaptive; defaults are the paper's and METHOD.md's.
struct SemanticAdaptiveConfig {
  double translation_threshold_m = 1.0;  ///< tau_t (eq. 21)
  double rotation_threshold_rad = 0.2;   ///< tau_r (eq. 22)
  double stability_threshold = 10.0;     ///< t_ss (eq. 19)
  double weight_min = 0.1;               ///< W_se is clamped to [weight_min, 1]
  double laplace_count = 1.0;            ///< points added to every class before normalising (keeps P > 0, eq. 15)
  /// Classes the distributions run over (eq. 16); default: the 19 learning
  /// classes, unlabeled excluded.
  std::array<bool, kNumClasses> classes = [] {
    std::array<bool, kNumClasses> used{};
    used.fill(true);
    used[0] = false;
    return used;
  }();
};

/// The intermediate quantities of one decision, for reports and tests.
struct SemanticWeight {
  double kl_divergence = 0.0;  ///< D_KL(P_current || P_last_keyframe), eq. 17 [nats]
  double stability = 0.0;      ///< SS = n_s / (n_d + 1), eq. 18
  int m = 0;                   ///< stability level, eq. 19
  double weight = 1.0;         ///< W_se after clamping, eq. 20
};

/// Semantic-adaptive keyframe policy: thresholds tau' = W_se * tau (eq. 21-22).
/// Without label histograms in the evidence it behaves as PoseThreshold.
class SemanticAdaptive {
 public:
  using Config = SemanticAdaptiveConfig;

  /// Policy with the given settings.
  explicit SemanticAdaptive(const Config& config = {}) : config_(config) {}

  /// Eq. 15-17 with Laplace smoothing: sum_i P_i log(P_i / Q_i) over the
  /// configured classes, P = current frame, Q = last keyframe.
  [[nodiscard]] double kl_divergence(const LabelHistogram& current,
                                     const LabelHistogram& last_keyframe) const {
    const double alpha = config_.laplace_count;
    double n_p = 0.0;
    double n_q = 0.0;
    int k = 0;
    for (int c = 0; c < kNumClasses; ++c) {
      if (!config_.classes[static_cast<std::size_t>(c)]) continue;
      n_p += current[static_cast<std::size_t>(c)];
      n_q += last_keyframe[static_cast<std::size_t>(c)];
      ++k;
    }
    const double z_p = n_p + alpha * k;
    const double z_q = n_q + alpha * k;
    if (z_p <= 0.0 || z_q <= 0.0) return 0.0;  // no labels and no smoothing: no evidence
    double kl = 0.0;
    for (int c = 0; c < kNumClasses; ++c) {
      if (!config_.classes[static_cast<std::size_t>(c)]) continue;
      const double p = (current[static_cast<std::size_t>(c)] + alpha) / z_p;
      const double q = (last_keyframe[static_cast<std::size_t>(c)] + alpha) / z_q;
      if (p > 0.0 && q > 0.0) kl += p * std::log(p / q);
    }
    return std::max(kl, 0.0);  // >= 0 mathematically; clamp rounding
  }

  /// Eq. 18: static points over dynamic points + 1, static/dynamic as METHOD.md lists.
  [[nodiscard]] static double stability_score(const LabelHistogram& current) {
    double n_s = 0.0;
    double n_d = 0.0;
    for (int c = 0; c < kNumClasses; ++c) {
      const auto n = static_cast<double>(current[static_cast<std::size_t>(c)]);
      if (is_static(class_from_index(c))) n_s += n;
      if (is_dynamic(class_from_index(c))) n_d += n;
    }
    return n_s / (n_d + 1.0);
  }

  /// Eq. 19-20: m from SS against t_ss, then W_se = 0.9^m (1 - D_KL), clamped.
  [[nodiscard]] SemanticWeight weight(const LabelHistogram& current,
                                      const LabelHistogram& last_keyframe) const {
    SemanticWeight w;
    w.kl_divergence = kl_divergence(current, last_keyframe);
    w.stability = stability_score(current);
    const double t_ss = config_.stability_threshold;
    w.m = w.stability <= t_ss ? 0 : (w.stability <= 1.2 * t_ss ? 1 : 2);
    w.weight = std::clamp(std::pow(0.9, w.m) * (1.0 - w.kl_divergence), config_.weight_min, 1.0);
    return w;
  }

  /// True when the motion since the last keyframe exceeds tau_t' or tau_r'.
  [[nodiscard]] bool is_keyframe(const KeyframeEvidence& evidence) const {
    double w = 1.0;
    if (evidence.current != nullptr && evidence.last_keyframe != nullptr) {
      w = weight(*evidence.current, *evidence.last_keyframe).weight;
    }
    return evidence.T_lastkf_current.translation().norm() > w * config_.translation_threshold_m ||
           evidence.T_lastkf_current.so3().angle() > w * config_.rotation_threshold_rad;
  }

  /// The settings in use.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  Config config_;
};

static_assert(KeyframePolicy<SemanticAdaptive>);

}  // namespace semlio
