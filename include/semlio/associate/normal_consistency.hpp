#pragma once
/// \file
/// NormalConsistency: Algorithm 1 of the paper (feature association by
/// neighbourhood normal consistency), fast and exact.
///
/// For each feature f moved into the map frame by T: among its 15 nearest map
/// candidates within the distance gate, keep -- in distance order -- the first
/// 5 whose shape axis agrees with f's (acos(|n1.n2|) < 10 deg, eq. 7; normals
/// for surfaces, line directions for corners, eq. 3-6 over 10 points).
///
/// Why it is fast yet equal to the literal NormalConsistencyReference:
///  - map axes are cached per map point, fitted on first use (FeatureMap),
///    each search bounded by the previous fit's neighbourhood (a feature's
///    candidates lie together: FeatureMap::axis(i, hint));
///  - scan axes are computed once per frame in set_scan(), not per candidate
///    nor per Gauss-Newton iteration (in leaf order, each search bounded by
///    the previous feature's neighbours); per feature only a rotation R * n1;
///  - the 15 candidates come from FeatureMap::nearest(): a k-d tree search
///    bounded at the distance gate, so it never looks past the candidates
///    that can matter (with LocalMapConfig::candidate_list > 0, from an
///    anchor map point's cached list instead, exact by a triangle-inequality
///    bound; FeatureMap's file comment says when which is faster);
///  - across Gauss-Newton iterations (associate() with a NearestCache) each
///    feature keeps its own candidate list from the previous iteration and
///    reuses it while a triangle-inequality bound proves it still holds the
///    exact 15 nearest (FeatureMap file comment): late iterations move a
///    feature by millimetres and need no tree search at all;
///  - both use the same helpers (detail::neighbourhood_axis, feature_to_map,
///    axes_agree, within_gate) and the same (distance, index) candidate order,
///    so their floating-point decisions coincide.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <vector>

#include <semlio/associate/scan_shapes.hpp>
#include <semlio/concepts.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/map/feature_map.hpp>
#include <semlio/search/small_kdtree.hpp>

namespace semlio {

/// Most candidates per feature (ranks are 1..kMaxCandidates).
inline constexpr int kMaxCandidates = 64;

/// Settings of NormalConsistency and NormalConsistencyReference (Algorithm 1).
struct NormalConsistencyConfig {
  int candidates = 15;                                    ///< k-NN candidates per feature (paper: 15)
  int keep = 5;                                           ///< kept matches per feature, 1..5 (paper: 5)
  int scan_neighbours = 10;                               ///< scan points per scan-side axis fit (paper: 10)
  double max_angle_rad = 10.0 * std::numbers::pi / 180.0; ///< axis agreement threshold (METHOD: 10 deg)
  double max_distance_m = 1.0;                            ///< distance gate on every candidate
};

namespace detail {

/// Validates a NormalConsistencyConfig (ConfigError naming the field).
inline void validate(const NormalConsistencyConfig& c) {
  check_association_setting("NormalConsistencyConfig.keep", c.keep, 1, kMaxKeptMatches);
  check_association_setting("NormalConsistencyConfig.candidates", c.candidates, c.keep, kMaxCandidates);
  check_association_setting("NormalConsistencyConfig.scan_neighbours", c.scan_neighbours, 3, kMaxShapeNeighbours);
  check_association_setting("NormalConsistencyConfig.max_angle_rad", c.max_angle_rad, 0.0, std::numbers::pi / 2.0);
  check_association_setting("NormalConsistencyConfig.max_distance_m", c.max_distance_m, 0.0, 1e6);
}

}  // namespace detail

/// Algorithm 1 with cached axes and candidate lists (see the file comment).
/// Non-owning pointers to the map and the features: both must outlive the use.
/// associate() is const, allocation-free (once `out` has capacity) and
/// thread-safe; set_map()/set_scan() are not.
class NormalConsistency {
 public:
  using Config = NormalConsistencyConfig;

  /// Validates the config (ConfigError).
  explicit NormalConsistency(const Config& config = {})
      : config_(config), cos_max_(std::cos(config.max_angle_rad)) {
    detail::validate(config_);
  }

  /// Binds the map (non-owning); its cached axes are used as the candidates' axes.
  void set_map(const FeatureMap& map) {
    map_ = &map;
    if (features_ != nullptr && map.kind() != axes_kind_) compute_scan_axes();
  }

  /// Binds the frame's features (scan frame, non-owning) and computes each
  /// feature's axis from its scan_neighbours nearest features, once per frame.
  /// Allocation-free once its buffers have grown (SmallKdTree3f).
  void set_scan(const std::vector<Eigen::Vector3f>& points_scan) {
    features_ = &points_scan;
    scan_id_ = detail::next_query_set_id();
    scan_tree_.build(points_scan);
    compute_scan_axes();
  }
  /// Not from a temporary: only a pointer to the features is kept.
  void set_scan(std::vector<Eigen::Vector3f>&&) = delete;

  /// Matches of feature i at pose (R, t) = T_map_scan. Precondition: a
  /// non-empty map and features are bound, i < features.size().
  [[nodiscard]] FeatureMatches match(std::size_t i, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) const {
    FeatureMap::AxisHint hint;
    return match_impl(i, R, t, nullptr, hint);
  }

  /// One FeatureMatches per bound feature at pose T_map_scan into out.
  void associate(const SE3d& T_map_scan, Correspondences& out) const {
    associate_impl(T_map_scan, out, nullptr);
  }

  /// As associate(T_map_scan, out) -- the same matches -- reusing each
  /// feature's candidate list in `cache` across calls (Gauss-Newton
  /// iterations); `cache` is (re)sized as needed and may be shared by calls
  /// with other scans or maps (stale slots are refilled, never trusted).
  void associate(const SE3d& T_map_scan, Correspondences& out, NearestCache& cache) const {
    const std::size_t n = features_ == nullptr ? 0 : features_->size();
    const std::size_t len = cache_list_len();
    if (cache.slots() < n || cache.list_len() != len) cache.reset(std::max(n, cache.slots()), len);
    cache.bind_queries(scan_id_);  // another scan's lists: refill at once rather than test them first
    associate_impl(T_map_scan, out, &cache);
  }

  /// Length of the per-feature lists associate(..., cache) keeps: the 15
  /// candidates plus a margin that absorbs some motion between iterations.
  [[nodiscard]] std::size_t cache_list_len() const noexcept {
    const auto k = static_cast<std::size_t>(config_.candidates);
    // 5 spare entries: measured on the KITTI raw snippet (callgrind, full
    // preset), 2 % fewer instructions per frame than 15 spare -- slightly
    // more refills, each cheaper.
    return std::min<std::size_t>(k + 5, static_cast<std::size_t>(kMaxCandidateList));
  }

  /// Switches the axis test (lines 7-10) off or on: off, a feature keeps
  /// its first `keep` candidates inside the gate in distance order, as
  /// NearestK would. The odometry turns it off for a frame with no motion
  /// estimate (pipeline/odometry.hpp). Returns the previous setting.
  bool set_axis_test(bool on) noexcept {
    const bool was = axis_test_;
    axis_test_ = on;
    return was;
  }
  /// True while the axis test is on (the default).
  [[nodiscard]] bool axis_test() const noexcept { return axis_test_; }

  /// Scan-frame axis of each bound feature (zero = unusable), for inspection.
  [[nodiscard]] const std::vector<Eigen::Vector3f>& scan_axes() const noexcept { return scan_axes_; }
  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  // Axes of the bound features for the bound map's kind (plane until a map is bound).
  void compute_scan_axes() {
    axes_kind_ = map_ != nullptr ? map_->kind() : FeatureKind::kPlane;
    scan_axes_.resize(features_->size());
    // In the tree's leaf order (each axis is independent of the others): the
    // same results, fewer cache misses than feature order, and each search
    // seeded by its neighbour's.
    const auto k = static_cast<std::size_t>(config_.scan_neighbours);
    std::array<std::uint32_t, kMaxShapeNeighbours> idx;  // uninitialised (see kMaxCandidateList)
    std::array<float, kMaxShapeNeighbours> d2;
    std::size_t n = 0;
    for (const std::uint32_t i : scan_tree_.leaf_order()) {
      // Seeded with the previous (nearby) feature's neighbours.
      n = scan_tree_.knn_seeded((*features_)[i], k, idx.data(), d2.data(), n);
      scan_axes_[i] = detail::neighbourhood_axis(scan_tree_, axes_kind_, idx.data(), n);
    }
  }

  FeatureMatches match_impl(std::size_t i, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                            NearestCache* cache, FeatureMap::AxisHint& hint) const {
    FeatureMatches m;
    const Eigen::Vector3f& axis = scan_axes_[i];
    if (axis.isZero() && axis_test_) return m;  // unusable scan axis: every candidate would fail
    const Eigen::Vector3f q = detail::feature_to_map(R, t, (*features_)[i]);
    const Eigen::Vector3d n1 = R * axis.cast<double>();
    const double gate2 = config_.max_distance_m * config_.max_distance_m;
    const auto keep = static_cast<std::size_t>(config_.keep);
    const auto k = static_cast<std::size_t>(config_.candidates);

    std::array<std::uint32_t, kMaxCandidates> idx;  // uninitialised (see kMaxCandidateList)
    std::array<float, kMaxCandidates> d2;
    // Line 3: the candidates inside the gate, in (distance, index) order.
    const std::size_t n = cache != nullptr ? map_->nearest(q, k, gate2, idx.data(), d2.data(), *cache, i)
                                           : map_->nearest(q, k, gate2, idx.data(), d2.data());
    // Lines 4-10 with both axes cached: keep agreeing candidates until 5 are kept.
    for (std::size_t j = 0; j < n; ++j) {
      if (!axis_test_ || detail::axes_agree(n1, map_->axis(idx[j], hint), cos_max_)) {
        detail::push_match(m, idx[j], j + 1);
        if (m.count == keep) return m;
      }
    }
    detail::enforce_min(map_->kind(), m);
    return m;
  }

  void associate_impl(const SE3d& T_map_scan, Correspondences& out, NearestCache* cache) const {
    detail::associate_each(features_, map_, T_map_scan, out,
                           [this, cache, hint = FeatureMap::AxisHint{}](std::size_t i, const Eigen::Matrix3d& R,
                                                                        const Eigen::Vector3d& t) mutable {
                             return match_impl(i, R, t, cache, hint);
                           });
  }

  Config config_;
  double cos_max_;
  bool axis_test_ = true;  // set_axis_test()
  const FeatureMap* map_ = nullptr;
  const std::vector<Eigen::Vector3f>* features_ = nullptr;
  SmallKdTree3f scan_tree_;  // rebuilt per frame without allocating; equal results to KdTree3f
  std::vector<Eigen::Vector3f> scan_axes_;
  FeatureKind axes_kind_ = FeatureKind::kPlane;
  std::uint64_t scan_id_ = 0;  // detail::next_query_set_id() of the bound scan (NearestCache::bind_queries)
};

static_assert(Associator<NormalConsistency, FeatureMap>);

}  // namespace semlio
