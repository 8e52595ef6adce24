#pragma once
/// \file
/// The residual sum of scan-to-map registration (eq. 13, squared) for one
/// feature kind: every scan feature with at least one associated map point is
/// evaluated by a Residual policy against the gathered map points and added
/// to the normal equations. One home for the loop shared by the front end's
/// scan-to-map problem (pipeline/scan_to_map.hpp) and loop verification
/// (loop/loop_verifier.hpp).
///
/// Layering: needs FeatureMap (map/), the Residual contract and
/// Correspondences (concepts.hpp) and NormalEquations (solve/), all at or
/// below map/, so it lives here and both callers above may include it.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <semlio/concepts.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/map/feature_map.hpp>
#include <semlio/solve/normal_equations.hpp>

namespace semlio {

/// Adds residual.evaluate(feature i, map points of matches[i], T_map_scan)
/// to eq for every feature i with matches[i].count > 0 and a valid term
/// (weight = the term's IRLS weight). FeatureCloud is any type with
/// `points` (scan frame, Eigen::Vector3f) and `labels` (one per point, or
/// empty = unlabeled) vectors, e.g. FeatureSet. Only the first
/// min(features, matches) features are used. Allocates nothing; const on
/// everything but eq.
template <typename FeatureCloud, Residual R>
void accumulate_feature_terms(const FeatureCloud& features, const Correspondences& matches, const FeatureMap& map,
                              const R& residual, const SE3d& T_map_scan, NormalEquations& eq) {
  const std::size_t n = std::min(features.points.size(), matches.size());
  const bool labelled = features.labels.size() == features.points.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (matches[i].count == 0) continue;
    FeaturePoint f;
    f.p_scan = features.points[i].template cast<double>();
    f.label = labelled ? features.labels[i] : Class::kUnlabeled;
    const auto term = residual.evaluate(f, map.gather(matches[i]), T_map_scan);
    if (term.valid) eq.add<R::kDim>(term.r, term.J_r_xi, term.weight);
  }
}

/// Fits of a PreparedResidual (the line or plane through a feature's
/// matches) kept per feature slot and reused while that slot's match set and
/// the map build stay the same -- over late Gauss-Newton iterations most
/// features keep their matches, and the fit (a 3x3 eigen-decomposition) is
/// the larger part of a term's cost. A fit depends only on the matched map
/// points, so a hit is exact whatever the feature or pose. One cache per
/// residual kind; not thread-safe. Reuses its buffers.
template <typename Model>
class ResidualFitCache {
 public:
  /// The fit for `slot` with matches m (gathered as mp), from the cache when
  /// the slot last saw the same map points of the same map build, else
  /// prepared by `residual` and stored.
  template <typename R>
  const Model& get(std::size_t slot, const FeatureMatches& m, const MatchedPoints& mp, const FeatureMap& map,
                   const R& residual) {
    if (map.build_id() != build_id_) {
      std::fill(filled_.begin(), filled_.end(), std::uint8_t{0});
      build_id_ = map.build_id();
    }
    if (slot >= filled_.size()) reserve(slot + 1);
    FeatureMatches& key = keys_[slot];
    if (filled_[slot] != 0 && same_points(key, m)) {
      ++hits_;
      return models_[slot];
    }
    key = m;
    models_[slot] = residual.prepare(mp);
    filled_[slot] = 1;
    return models_[slot];
  }

  /// Sizes the cache for `slots` features up front (no growth later).
  void reserve(std::size_t slots) {
    if (filled_.size() < slots) {
      keys_.resize(slots);
      models_.resize(slots);
      filled_.resize(slots, 0);
    }
  }
  /// Fits reused since construction (diagnostics).
  [[nodiscard]] std::size_t hits() const noexcept { return hits_; }

 private:
  static bool same_points(const FeatureMatches& a, const FeatureMatches& b) {
    if (a.count != b.count) return false;
    for (int j = 0; j < a.count; ++j) {
      if (a.index[static_cast<std::size_t>(j)] != b.index[static_cast<std::size_t>(j)]) return false;
    }
    return true;
  }

  std::vector<FeatureMatches> keys_;
  std::vector<Model> models_;
  std::vector<std::uint8_t> filled_;
  std::uint64_t build_id_ = 0;
  std::size_t hits_ = 0;
};

/// As accumulate_feature_terms(features, matches, map, residual, T_map_scan,
/// eq) -- the same terms bit for bit -- reusing the residual's fits in
/// `cache` for features whose matches did not change.
template <typename FeatureCloud, PreparedResidual R>
void accumulate_feature_terms(const FeatureCloud& features, const Correspondences& matches, const FeatureMap& map,
                              const R& residual, const SE3d& T_map_scan, NormalEquations& eq,
                              ResidualFitCache<typename R::Model>& cache) {
  const std::size_t n = std::min(features.points.size(), matches.size());
  const bool labelled = features.labels.size() == features.points.size();
  cache.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (matches[i].count == 0) continue;
    FeaturePoint f;
    f.p_scan = features.points[i].template cast<double>();
    f.label = labelled ? features.labels[i] : Class::kUnlabeled;
    const MatchedPoints mp = map.gather(matches[i]);
    const auto& model = cache.get(i, matches[i], mp, map, residual);
    const auto term = residual.evaluate(f, mp, model, T_map_scan);
    if (term.valid) eq.add<R::kDim>(term.r, term.J_r_xi, term.weight);
  }
}

}  // namespace semlio
