#pragma once
/// \file
/// NearestK: the traditional LOAM / LIO-SAM association -- the k (default 5)
/// nearest map points of each transformed feature, each within the distance
/// gate (default 1.0 m). The baseline Algorithm 1 improves on.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <semlio/associate/scan_shapes.hpp>
#include <semlio/concepts.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/map/feature_map.hpp>

namespace semlio {

/// Settings of NearestK.
struct NearestKConfig {
  int k = 5;                    ///< neighbours per feature, 1..5
  double max_distance_m = 1.0;  ///< distance gate on every neighbour (LIO-SAM: 1 m)
};

/// k nearest map points within the gate, in distance order, ranks 1..k; a
/// feature with fewer than 2 (line) / 3 (plane) gated neighbours gets none.
/// Holds non-owning pointers to the map and the scan features: both must
/// outlive the use. associate() is const and thread-safe.
class NearestK {
 public:
  using Config = NearestKConfig;

  /// Validates the config (ConfigError).
  explicit NearestK(const Config& config = {}) : config_(config) {
    detail::check_association_setting("NearestKConfig.k", config_.k, 1, kMaxKeptMatches);
    detail::check_association_setting("NearestKConfig.max_distance_m", config_.max_distance_m, 0.0, 1e6);
  }

  /// Binds the map to search (non-owning).
  void set_map(const FeatureMap& map) { map_ = &map; }
  /// Binds the frame's feature positions (scan frame, non-owning); nothing to precompute.
  void set_scan(const std::vector<Eigen::Vector3f>& points_scan) {
    features_ = &points_scan;
    scan_id_ = detail::next_query_set_id();
  }
  /// Not from a temporary: only a pointer to the features is kept.
  void set_scan(std::vector<Eigen::Vector3f>&&) = delete;

  /// Matches of one query point already in the map frame.
  [[nodiscard]] FeatureMatches match(const Eigen::Vector3f& q_map) const {
    FeatureMatches m;
    if (map_ == nullptr) return m;
    std::array<std::uint32_t, kMaxKeptMatches> idx{};
    std::array<float, kMaxKeptMatches> d2{};
    const std::size_t n = map_->tree().knn(q_map, static_cast<std::size_t>(config_.k), idx.data(), d2.data());
    return finish(idx.data(), d2.data(), n);
  }

  /// One FeatureMatches per bound feature at pose T_map_scan into out
  /// (resized; no allocation once its capacity suffices).
  void associate(const SE3d& T_map_scan, Correspondences& out) const {
    detail::associate_each(features_, map_, T_map_scan, out,
                           [this](std::size_t i, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
                             return match(detail::feature_to_map(R, t, (*features_)[i]));
                           });
  }

  /// As associate(T_map_scan, out) -- the same matches -- reusing each
  /// feature's candidate list in `cache` across calls (Gauss-Newton
  /// iterations; FeatureMap's file comment proves the reuse exact). `cache`
  /// is (re)sized as needed; stale slots are refilled, never trusted.
  void associate(const SE3d& T_map_scan, Correspondences& out, NearestCache& cache) const {
    const std::size_t n = features_ == nullptr ? 0 : features_->size();
    const std::size_t len = cache_list_len();
    if (cache.slots() < n || cache.list_len() != len) cache.reset(std::max(n, cache.slots()), len);
    cache.bind_queries(scan_id_);  // another scan's lists: refill at once rather than test them first
    const auto k = static_cast<std::size_t>(config_.k);
    // nearest() returns the k-NN cut at the gate, as match() computes it.
    const double gate2 = config_.max_distance_m * config_.max_distance_m;
    detail::associate_each(features_, map_, T_map_scan, out,
                           [&](std::size_t i, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
                             std::array<std::uint32_t, kMaxKeptMatches> idx{};
                             std::array<float, kMaxKeptMatches> d2{};
                             const Eigen::Vector3f q = detail::feature_to_map(R, t, (*features_)[i]);
                             const std::size_t found = map_->nearest(q, k, gate2, idx.data(), d2.data(), cache, i);
                             return finish(idx.data(), d2.data(), found);
                           });
  }

  /// Length of the per-feature lists associate(..., cache) keeps: k plus a
  /// margin that absorbs a few centimetres of motion.
  [[nodiscard]] std::size_t cache_list_len() const noexcept {
    const auto k = static_cast<std::size_t>(config_.k);
    return k + std::max<std::size_t>(k, 8);
  }

  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  // The gated, rank-ordered matches from the k nearest (idx, d2: n of them).
  [[nodiscard]] FeatureMatches finish(const std::uint32_t* idx, const float* d2, std::size_t n) const {
    FeatureMatches m;
    const double gate2 = config_.max_distance_m * config_.max_distance_m;
    for (std::size_t j = 0; j < n && detail::within_gate(d2[j], gate2); ++j) {
      detail::push_match(m, idx[j], j + 1);
    }
    detail::enforce_min(map_->kind(), m);
    return m;
  }

  Config config_;
  const FeatureMap* map_ = nullptr;
  const std::vector<Eigen::Vector3f>* features_ = nullptr;
  std::uint64_t scan_id_ = 0;  // detail::next_query_set_id() of the bound scan (NearestCache::bind_queries)
};

static_assert(Associator<NearestK, FeatureMap>);

}  // namespace semlio
