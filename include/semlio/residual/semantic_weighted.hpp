#pragma once
/// \file
/// SemanticWeighted<R>: the semantic consistency weight of eq. 10-12 on any
/// residual. a = (number of kept matches whose label equals the feature's) / N
/// (METHOD.md); the weighted residual is w * r, so a least-squares solver's
/// cost holds w^2 ||r||^2 (eq. 13 written with the square every LOAM-family
/// solver uses). The Jacobian scales by the same constant w.
///
/// The paper takes w = a, which trusts every label. A segmenter's labels
/// (mIoU 0.25-0.5 on real scans) are wrong most often at object boundaries,
/// so a correct match often disagrees with its map points, and w = a then
/// re-weights good constraints at random and throws information away. The
/// default weight is therefore chance-corrected: w = 1 - kappa (1 - a)^p,
/// kappa the frame's Cohen's kappa between feature labels and matched map
/// labels (map/label_agreement.hpp; set by the scan-to-map problem after
/// every association, one for corners and one for surfaces). Exact labels
/// give kappa near 1; labels that agree no better than chance give kappa 0
/// and w = 1, the unweighted residual; in between, a disagreement costs as
/// much as the labels have shown they are worth on this frame.
/// scripts/label_quality_sweep.sh compares the modes from exact labels to
/// mIoU 0.2 (docs/label_quality.md).
///
/// The disagreement counts as (1 - a)^p, p = disagreement_power (2), not
/// as 1 - a. A feature matched to the wrong object disagrees with most of
/// its map points; a correct match whose points carry one or two other
/// labels is what a segmenter's boundary errors, and an object labelled
/// car in one keyframe and truck in the next, produce. The square keeps the
/// whole penalty kappa for a match that disagrees throughout (a = 0) and
/// shrinks the penalty of a scattered disagreement (a = 0.8: 0.04 kappa
/// instead of 0.2 kappa). With p = 1 the weights alone (`weights_only`) are
/// worse than no weights on the rural drives of the sweep at mIoU 0.5
/// (run it with `semantic_weights: {disagreement_power: 1}`): there most
/// disagreements are label noise, whole vehicles switching between car and
/// truck from one frame to the next.
///
/// The chance-corrected weight also counts a match as agreeing when the
/// feature and the map point both carry static classes (road and terrain,
/// vegetation and trunk, building and fence). Eq. 10 guards against a
/// feature matched to the wrong object; a point of a neighbouring static
/// class is as fixed as one of the same class. Such classes meet at every
/// kerb and tree, so even exact labels disagree there (a kerb's corner
/// matches road and sidewalk points). Counting those disagreements costs
/// information along the road, the direction a rural drive holds weakest:
/// with the literal eq. 10, the weights alone (`weights_only`) are worse than
/// no weights on the rural drives of scripts/label_quality_sweep.sh at every
/// label quality. Only a disagreement that involves a movable class or an
/// unlabelled point lowers a, and kappa counts agreement the same way
/// (LabelAgreement::kappa(true)). A frame where movable objects are rare
/// then has a low kappa even with exact labels, since nearly every pair
/// agrees by chance, and its weights stay near 1: there a disagreement says
/// little, and a wrong label costs more than a right one gains (the rural
/// drives of the sweep).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include <semlio/concepts.hpp>
#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>

namespace semlio {

/// Eq. 10-12: fraction of the matches whose label agrees with `label`
/// (labels_agree(); the same class only by default, eq. 10 as written);
/// 0 without matches.
inline double semantic_weight(Class label, const MatchedPoints& matches, bool static_classes_agree = false) {
  if (matches.count <= 0) return 0.0;
  int same = 0;
  for (int k = 0; k < matches.count; ++k) {
    if (labels_agree(label, matches.labels[static_cast<std::size_t>(k)], static_classes_agree)) ++same;  // eq. 10
  }
  return static_cast<double>(same) / static_cast<double>(matches.count);
}

/// How SemanticWeighted turns the agreement a of eq. 10 into a weight.
enum class SemanticWeightMode : std::uint8_t {
  kChanceCorrected,  ///< w = 1 - kappa (1 - a)^p, kappa the frame's label reliability (file comment)
  kPaper,            ///< w = a, eq. 11-12 as written
  kOff,              ///< w = 1: labels leave the residual alone
};

/// Settings of SemanticWeighted.
struct SemanticWeightConfig {
  SemanticWeightMode mode = SemanticWeightMode::kChanceCorrected;  ///< weight rule (file comment)
  /// kChanceCorrected only: two static classes count as agreeing in a (file
  /// comment). kPaper keeps eq. 10 as written.
  bool static_classes_agree = true;
  /// kChanceCorrected only: p in w = 1 - kappa (1 - a)^p, 1..4; 1 is the
  /// linear penalty (file comment).
  int disagreement_power = 2;
};

/// Residual R with r and J multiplied by the semantic weight (eq. 11-12).
/// A term with weight 0 stays valid (it is a residual that counts for nothing).
/// A PreparedResidual when R is one (the weight needs only the labels).
template <Residual R>
class SemanticWeighted {
 public:
  static constexpr int kDim = R::kDim;
  /// R's fit of a match set (an empty type when R has none).
  using Model = detail::ModelOf<R>;

  /// Wraps inner. ConfigError when config.disagreement_power is outside 1..4.
  explicit SemanticWeighted(R inner = R{}, SemanticWeightConfig config = {}) : inner_(inner), config_(config) {
    if (config_.disagreement_power < 1 || config_.disagreement_power > 4) {
      throw ConfigError("SemanticWeightConfig::disagreement_power must be in 1..4, got " +
                        std::to_string(config_.disagreement_power));
    }
  }

  /// Sets kappa, the chance-corrected agreement of this frame's labels with
  /// the map's (LabelAgreement::kappa(static_classes_agree()), clamped to
  /// [0, 1]; NaN counts as 0).
  /// Until it is set, kappa is 1: the paper's weight.
  void set_label_reliability(double kappa) noexcept {
    reliability_ = std::isfinite(kappa) ? std::clamp(kappa, 0.0, 1.0) : 0.0;
  }
  /// The kappa in use (1 until set_label_reliability()).
  [[nodiscard]] double label_reliability() const noexcept { return reliability_; }
  /// The settings.
  [[nodiscard]] const SemanticWeightConfig& config() const noexcept { return config_; }
  /// True when a counts two static classes as agreeing (the chance-corrected
  /// mode with static_classes_agree); the kappa handed to
  /// set_label_reliability() should count agreement the same way
  /// (LabelAgreement::kappa(true)).
  [[nodiscard]] bool static_classes_agree() const noexcept {
    return config_.static_classes_agree && config_.mode == SemanticWeightMode::kChanceCorrected;
  }

  /// Switches the weight off (w = 1, whatever the mode) or back on; on
  /// until called. The odometry solves a frame that stays weak with the
  /// weights off (OdometryConfig::baseline_when_degenerate).
  void set_weights_enabled(bool on) noexcept { enabled_ = on; }
  /// False while set_weights_enabled(false) holds.
  [[nodiscard]] bool weights_enabled() const noexcept { return enabled_; }

  /// The weight of a feature whose matches agree with its label at rate a.
  [[nodiscard]] double weight(double a) const noexcept {
    if (!enabled_) return 1.0;
    switch (config_.mode) {
      case SemanticWeightMode::kPaper:
        return a;
      case SemanticWeightMode::kOff:
        return 1.0;
      case SemanticWeightMode::kChanceCorrected:
        break;
    }
    const double disagreement = 1.0 - a;
    double penalty = disagreement;
    for (int i = 1; i < config_.disagreement_power; ++i) penalty *= disagreement;
    return 1.0 - reliability_ * penalty;
  }

  /// inner's term with r <- w r and J <- w J.
  [[nodiscard]] ResidualTerm<kDim> evaluate(const FeaturePoint& feature, const MatchedPoints& matches,
                                            const SE3d& T_map_scan) const {
    return weighted(feature, matches, inner_.evaluate(feature, matches, T_map_scan));
  }

  /// inner's fit of the matches.
  [[nodiscard]] Model prepare(const MatchedPoints& matches) const
    requires PreparedResidual<R>
  {
    return inner_.prepare(matches);
  }

  /// As evaluate(feature, matches, T_map_scan) with model = prepare(matches).
  [[nodiscard]] ResidualTerm<kDim> evaluate(const FeaturePoint& feature, const MatchedPoints& matches,
                                            const Model& model, const SE3d& T_map_scan) const
    requires PreparedResidual<R>
  {
    return weighted(feature, matches, inner_.evaluate(feature, matches, model, T_map_scan));
  }

  /// Forwards a robust inner residual's widening (residual/robust.hpp).
  bool set_min_scale_m(double s)
    requires requires(R& r) { r.set_min_scale_m(s); }
  {
    return inner_.set_min_scale_m(s);
  }

  /// The wrapped residual.
  [[nodiscard]] const R& inner() const noexcept { return inner_; }

 private:
  ResidualTerm<kDim> weighted(const FeaturePoint& feature, const MatchedPoints& matches,
                              ResidualTerm<kDim> term) const {
    if (!term.valid) return term;
    const double w = weight(semantic_weight(feature.label, matches, static_classes_agree()));
    term.r *= w;
    term.J_r_xi *= w;
    return term;
  }

  R inner_;
  SemanticWeightConfig config_;
  double reliability_ = 1.0;  // kappa; 1 = trust the labels (the paper)
  bool enabled_ = true;
};

static_assert(Residual<SemanticWeighted<PointToPlane>>);
static_assert(Residual<SemanticWeighted<PointToLine>>);
static_assert(PreparedResidual<SemanticWeighted<PointToPlane>>);
static_assert(PreparedResidual<SemanticWeighted<PointToLine>>);

}  // namespace semlio
