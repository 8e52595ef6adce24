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

}  // namespace semlio
