#pragma once
/// \file
/// How far a frame's labels agree with the labels of the map points its
/// features were matched to, beyond chance: Cohen's kappa over every
/// (feature, matched map point) pair of one association. Exact labels give
/// kappa near 1 (a feature and its map points share a class unless the
/// match is wrong); labels no better than guessing from the class
/// frequencies give 0. SemanticWeighted (residual/semantic_weighted.hpp)
/// uses it to decide how much a label disagreement says about a match.
///
/// Agreement is counted as the weight counts it: the same class, or, for the
/// chance-corrected weight, also two static classes (labels_agree() in
/// core/labels.hpp). Kappa must measure the relation the weight's a uses:
/// with static classes merged, a frame that sees nothing but static
/// structure agrees by chance alone, and its kappa is near 0, so
/// disagreements between finer classes that a no longer counts do not lift
/// it.
///
/// Layering: needs Correspondences (concepts.hpp) and FeatureMap (map/).

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>

#include <semlio/concepts.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/map/feature_map.hpp>

namespace semlio {

/// Label counts over (feature, matched map point) pairs: how often the two
/// labels are equal, and each side's class histogram for the chance term.
/// Pairs whose feature is unlabeled are not counted (they carry no label to agree with).
class LabelAgreement {
 public:
  /// Counts every pair of feature i (label features.labels[i]) and its
  /// matches[i] in `map`. FeatureCloud: any type with `points` and `labels`
  /// vectors (FeatureSet); without one label per point nothing is counted.
  /// Allocates nothing.
  template <typename FeatureCloud>
  void add(const FeatureCloud& features, const Correspondences& matches, const FeatureMap& map) noexcept {
    if (features.labels.size() != features.points.size()) return;
    const auto& map_labels = map.labels();
    const std::size_t n = std::min(features.labels.size(), matches.size());
    for (std::size_t i = 0; i < n; ++i) {
      const Class f = features.labels[i];
      if (f == Class::kUnlabeled) continue;
      const FeatureMatches& m = matches[i];
      for (int k = 0; k < m.count; ++k) {
        const std::uint32_t j = m.index[static_cast<std::size_t>(k)];
        if (j >= map_labels.size()) continue;
        const Class g = map_labels[j];
        ++feature_class_[index(f)];
        ++map_class_[index(g)];
        same_ += f == g ? 1U : 0U;
        same_or_static_ += labels_agree(f, g, true) ? 1U : 0U;
        ++pairs_;
      }
    }
  }

  /// Pairs counted.
  [[nodiscard]] std::uint64_t pairs() const noexcept { return pairs_; }

  /// Share of pairs whose labels agree (equal labels; with
  /// static_classes_agree also two static classes); 0 without pairs.
  [[nodiscard]] double observed(bool static_classes_agree = false) const noexcept {
    if (pairs_ == 0) return 0.0;
    return static_cast<double>(static_classes_agree ? same_or_static_ : same_) / static_cast<double>(pairs_);
  }

  /// Share of pairs expected to agree if the two labels were drawn
  /// independently from their own class frequencies, agreement counted by
  /// labels_agree(feature, map, static_classes_agree) as observed() counts
  /// it; 0 without pairs.
  [[nodiscard]] double chance(bool static_classes_agree = false) const noexcept {
    if (pairs_ == 0) return 0.0;
    // Counts, not shares, are summed, exactly in integers (a frame has far
    // fewer than 2^26 pairs): a frame whose labels all agree with each other
    // then gets a chance term of exactly 1 (kappa 0), not 1 - rounding.
    std::uint64_t agreeing = 0;
    for (std::size_t f = 0; f < feature_class_.size(); ++f) {
      if (feature_class_[f] == 0) continue;
      for (std::size_t g = 0; g < map_class_.size(); ++g) {
        if (labels_agree(static_cast<Class>(f), static_cast<Class>(g), static_classes_agree)) {
          agreeing += feature_class_[f] * map_class_[g];
        }
      }
    }
    const double n = static_cast<double>(pairs_);
    return static_cast<double>(agreeing) / n / n;
  }

  /// Cohen's kappa (observed - chance) / (1 - chance) of the agreement
  /// observed(static_classes_agree) counts, clamped to [0, 1]. 0 when
  /// nothing was counted or every label falls in one agreeing group (then
  /// agreement cannot tell a good match from a bad one).
  [[nodiscard]] double kappa(bool static_classes_agree = false) const noexcept {
    const double pe = chance(static_classes_agree);
    if (pairs_ == 0 || !(pe < 1.0)) return 0.0;
    return std::clamp((observed(static_classes_agree) - pe) / (1.0 - pe), 0.0, 1.0);
  }

 private:
  static std::size_t index(Class c) noexcept {
    const auto i = static_cast<std::size_t>(c);
    return i < static_cast<std::size_t>(kNumClasses) ? i : 0U;
  }

  std::array<std::uint64_t, kNumClasses> feature_class_{};
  std::array<std::uint64_t, kNumClasses> map_class_{};
  std::uint64_t same_ = 0;
  std::uint64_t same_or_static_ = 0;
  std::uint64_t pairs_ = 0;
};

}  // namespace semlio
