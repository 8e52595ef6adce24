#pragma once
/// \file
/// Scan-to-map registration as a least-squares problem (paper §3.1, eq. 13):
/// corner features against the corner map with a line residual, surface
/// features against the surface map with a plane residual, each associated by
/// the same Associator policy and re-associated between Gauss-Newton
/// iterations. Also the association-rank statistics of eq. 23.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>

#include <semlio/concepts.hpp>
#include <semlio/core/stopwatch.hpp>
#include <semlio/features/loam_features.hpp>
#include <semlio/map/feature_map.hpp>
#include <semlio/map/feature_terms.hpp>
#include <semlio/map/label_agreement.hpp>
#include <semlio/solve/gauss_newton.hpp>
#include <semlio/solve/normal_equations.hpp>

namespace semlio {

/// The two residual policies of a LOAM-style front end: corners use `corner`
/// (a line residual), surfaces `surface` (a plane residual).
template <Residual CornerResidual, Residual SurfaceResidual>
struct LoamResiduals {
  CornerResidual corner;    ///< residual of corner features (point-to-line)
  SurfaceResidual surface;  ///< residual of surface features (point-to-plane)
};

/// Deduces LoamResiduals{corner, surface} (aggregate CTAD is C++20, but
/// clang before 17 does not implement it).
template <typename CornerResidual, typename SurfaceResidual>
LoamResiduals(CornerResidual, SurfaceResidual) -> LoamResiduals<CornerResidual, SurfaceResidual>;

/// Where a ScanToMapProblem's time went since its last reset_timings():
/// wall time [ms] and calls of each step (the split of a frame's solve).
struct ScanToMapTimings {
  double scan_shapes_ms = 0.0;  ///< set_features(): the associators' work on the scan (e.g. scan trees and axes)
  double associate_ms = 0.0;    ///< associate(), every call
  double linearize_ms = 0.0;    ///< linearize(), every call (trial steps included)
  int associations = 0;         ///< associate() calls
  int linearizations = 0;       ///< linearize() calls
};

/// How often the i-th nearest candidate (i = 1..15) was used (eq. 23).
using RankHistogram = std::array<std::uint64_t, 16>;

/// Adds the ranks of every kept match to hist (index = rank, 1..15).
inline void accumulate_ranks(const Correspondences& matches, RankHistogram& hist) noexcept {
  for (const FeatureMatches& m : matches) {
    for (int j = 0; j < m.count; ++j) {
      const auto rank = m.rank[static_cast<std::size_t>(j)];
      if (rank < hist.size()) ++hist[rank];
    }
  }
}

/// Binds the features of one frame and a corner/surface map pair into the
/// solver's LeastSquaresProblem. Non-owning: the features and maps must
/// outlive their binding. Reuses its correspondence buffers across frames.
/// FeatureCloud is any type with `points` (scan frame) and `labels` vectors
/// (features::FeatureSet, Scan).
template <typename A, Residual CornerResidual, Residual SurfaceResidual, typename FeatureCloud = FeatureSet>
  requires Associator<A, FeatureMap>
class ScanToMapProblem {
 public:
  /// Problem with its own copies of the associators (one per map) and residuals.
  ScanToMapProblem(const A& associator, const LoamResiduals<CornerResidual, SurfaceResidual>& residuals)
      : corner_assoc_(associator), surface_assoc_(associator), residuals_(residuals) {}

  /// Binds the maps (map frame). Call when the local map was rebuilt.
  void set_maps(const FeatureMap& corner_map, const FeatureMap& surface_map) {
    corner_map_ = &corner_map;
    surface_map_ = &surface_map;
    corner_assoc_.set_map(corner_map);
    surface_assoc_.set_map(surface_map);
  }

  /// Binds this frame's features (scan frame; labels empty or one per point).
  /// Call once per frame.
  void set_features(const FeatureCloud& corners, const FeatureCloud& surfaces) {
    const auto t0 = StageClock::now();
    corners_ = &corners;
    surfaces_ = &surfaces;
    corner_assoc_.set_scan(corners.points);
    surface_assoc_.set_scan(surfaces.points);
    timings_.scan_shapes_ms += ms_since(t0);
  }

  /// Re-associates every feature at pose T_map_scan. Associators that offer
  /// associate(T, out, NearestCache&) reuse each feature's candidate list
  /// across calls (exact: the same matches, fewer k-d tree searches).
  void associate(const SE3d& T_map_scan) {
    const auto t0 = StageClock::now();
    if constexpr (requires(const A& a, Correspondences& out, NearestCache& cache) {
                    a.associate(T_map_scan, out, cache);
                  }) {
      corner_assoc_.associate(T_map_scan, corner_matches_, corner_cache_);
      surface_assoc_.associate(T_map_scan, surface_matches_, surface_cache_);
    } else {
      corner_assoc_.associate(T_map_scan, corner_matches_);
      surface_assoc_.associate(T_map_scan, surface_matches_);
    }
    if constexpr (kWeighsLabels) update_label_reliability();
    timings_.associate_ms += ms_since(t0);
    ++timings_.associations;
  }

  /// True when a residual takes the frame's label reliability
  /// (SemanticWeighted::set_label_reliability).
  static constexpr bool kWeighsLabels =
      requires(CornerResidual& r) { r.set_label_reliability(1.0); } ||
      requires(SurfaceResidual& r) { r.set_label_reliability(1.0); };

  /// Cohen's kappa of the last association's corner labels against their
  /// map points' (map/label_agreement.hpp), counted as the corner
  /// residual's weight counts agreement and given to it; NaN when no
  /// residual uses it.
  [[nodiscard]] double corner_label_reliability() const noexcept { return corner_label_reliability_; }
  /// The same for the surface features.
  [[nodiscard]] double surface_label_reliability() const noexcept { return surface_label_reliability_; }

  /// Adds every valid residual at T_map_scan to eq (eq. 13, squared).
  /// Residuals that can (PreparedResidual) reuse their line / plane fits for
  /// features whose matches did not change since the last call: the same
  /// terms, bit for bit. Not safe to call concurrently on one problem.
  void linearize(const SE3d& T_map_scan, NormalEquations& eq) const {
    const auto t0 = StageClock::now();
    accumulate(*corners_, corner_matches_, *corner_map_, residuals_.corner, corner_fits_, T_map_scan, eq);
    accumulate(*surfaces_, surface_matches_, *surface_map_, residuals_.surface, surface_fits_, T_map_scan, eq);
    timings_.linearize_ms += ms_since(t0);
    ++timings_.linearizations;
  }

  /// Time and calls of set_features(), associate() and linearize() since
  /// the last reset_timings() (or construction).
  [[nodiscard]] const ScanToMapTimings& timings() const noexcept { return timings_; }
  /// Zeroes timings(); the odometry calls it once per frame.
  void reset_timings() noexcept { timings_ = {}; }

  /// Widens the robust kernels of both residuals to at least s [m]
  /// (residual/robust.hpp; infinity: plain least squares, 0: their own
  /// scales); residuals without a robust kernel ignore it. Returns whether a
  /// kernel is now wider than its own scale.
  bool set_min_robust_scale_m(double s) {
    bool widened = false;
    if constexpr (requires { residuals_.corner.set_min_scale_m(s); }) widened |= residuals_.corner.set_min_scale_m(s);
    if constexpr (requires { residuals_.surface.set_min_scale_m(s); }) widened |= residuals_.surface.set_min_scale_m(s);
    return widened;
  }

  /// Switches the residuals' semantic weights off (every weight 1) or back
  /// on (SemanticWeighted::set_weights_enabled); no effect on residuals
  /// without them.
  void set_semantic_weights(bool on) {
    if constexpr (requires(CornerResidual& r) { r.set_weights_enabled(on); }) residuals_.corner.set_weights_enabled(on);
    if constexpr (requires(SurfaceResidual& r) { r.set_weights_enabled(on); }) residuals_.surface.set_weights_enabled(on);
  }

  /// True when the associator has an axis test it can switch off
  /// (NormalConsistency::set_axis_test); NearestK has none.
  static constexpr bool kHasAxisTest = requires(A& a) { a.set_axis_test(true); };

  /// Switches the associators' axis test off or on (no effect without one).
  void set_axis_test(bool on) {
    if constexpr (kHasAxisTest) {
      corner_assoc_.set_axis_test(on);
      surface_assoc_.set_axis_test(on);
    }
  }

  /// Correspondences of the last association, per corner feature.
  [[nodiscard]] const Correspondences& corner_matches() const noexcept { return corner_matches_; }
  /// Correspondences of the last association, per surface feature.
  [[nodiscard]] const Correspondences& surface_matches() const noexcept { return surface_matches_; }

  /// Candidate-list cache of the corner / surface association (diagnostics:
  /// hits and refills since it was last sized).
  [[nodiscard]] const NearestCache& corner_cache() const noexcept { return corner_cache_; }
  /// See corner_cache().
  [[nodiscard]] const NearestCache& surface_cache() const noexcept { return surface_cache_; }

  /// Features with at least one match in the last association (corner, surface).
  [[nodiscard]] std::pair<std::size_t, std::size_t> matched_counts() const noexcept {
    return {count_matched(corner_matches_), count_matched(surface_matches_)};
  }

 private:
  template <typename R, typename Cache>
  static void accumulate(const FeatureCloud& features, const Correspondences& matches, const FeatureMap& map,
                         const R& residual, Cache& cache, const SE3d& T_map_scan, NormalEquations& eq) {
    if constexpr (PreparedResidual<R>) {
      accumulate_feature_terms(features, matches, map, residual, T_map_scan, eq, cache);
    } else {
      accumulate_feature_terms(features, matches, map, residual, T_map_scan, eq);
    }
  }

  // One kappa per feature kind: a segmenter errs most at object boundaries,
  // which is where corner features lie, so corner labels agree with the map
  // less often than surface labels do and their disagreement says less about
  // a match. (A few hundred corners give a thousand or more label pairs.)
  void update_label_reliability() {
    LabelAgreement corner_agreement;
    LabelAgreement surface_agreement;
    corner_agreement.add(*corners_, corner_matches_, *corner_map_);
    surface_agreement.add(*surfaces_, surface_matches_, *surface_map_);
    corner_label_reliability_ = corner_agreement.kappa(static_classes_agree(residuals_.corner));
    surface_label_reliability_ = surface_agreement.kappa(static_classes_agree(residuals_.surface));
    if constexpr (requires(CornerResidual& r) { r.set_label_reliability(1.0); }) {
      residuals_.corner.set_label_reliability(corner_label_reliability_);
    }
    if constexpr (requires(SurfaceResidual& r) { r.set_label_reliability(1.0); }) {
      residuals_.surface.set_label_reliability(surface_label_reliability_);
    }
  }

  // Whether residual r's weight counts two static classes as agreeing, so
  // that its kappa counts agreement the same way (map/label_agreement.hpp).
  template <typename R>
  static bool static_classes_agree(const R& r) noexcept {
    if constexpr (requires { r.static_classes_agree(); }) {
      return r.static_classes_agree();
    } else {
      return false;
    }
  }

  static std::size_t count_matched(const Correspondences& c) noexcept {
    std::size_t n = 0;
    for (const auto& m : c) n += m.count > 0 ? 1U : 0U;
    return n;
  }

  A corner_assoc_;
  A surface_assoc_;
  LoamResiduals<CornerResidual, SurfaceResidual> residuals_;
  const FeatureMap* corner_map_ = nullptr;
  const FeatureMap* surface_map_ = nullptr;
  const FeatureCloud* corners_ = nullptr;
  const FeatureCloud* surfaces_ = nullptr;
  Correspondences corner_matches_;
  Correspondences surface_matches_;
  NearestCache corner_cache_;   // per-feature candidate lists across iterations (and frames)
  NearestCache surface_cache_;
  // Per-feature residual fits reused while matches stay (PreparedResidual only).
  mutable ResidualFitCache<detail::ModelOf<CornerResidual>> corner_fits_;
  mutable ResidualFitCache<detail::ModelOf<SurfaceResidual>> surface_fits_;
  double corner_label_reliability_ = std::numeric_limits<double>::quiet_NaN();
  double surface_label_reliability_ = std::numeric_limits<double>::quiet_NaN();
  mutable ScanToMapTimings timings_;  // two clock reads per call (~22 ns each on the reference VM), ~10 calls a frame
};

}  // namespace semlio
