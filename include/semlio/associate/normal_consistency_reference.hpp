#pragma once
/// \file
/// NormalConsistencyReference: Algorithm 1 written literally, slow on purpose.
/// For every candidate it recomputes the candidate's 10-NN map neighbourhood
/// and normal (line 5) and the feature's 10-NN scan neighbourhood and normal
/// (line 6). Kept as the ground truth that NormalConsistency must equal, for
/// tests and benchmarks; not for production use. It searches its own
/// nanoflann trees (KdTree3f) on both sides, where NormalConsistency and
/// FeatureMap use SmallKdTree3f, so that equality also checks the two trees
/// against each other, and it fits each axis with the full eq. 3-6 fit
/// (fit_local_shape) where NormalConsistency fits only the axis it reads
/// (fit_local_axis), so that equality checks that shortcut too.

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <semlio/associate/normal_consistency.hpp>
#include <semlio/associate/scan_shapes.hpp>
#include <semlio/concepts.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/map/feature_map.hpp>
#include <semlio/search/kdtree.hpp>

namespace semlio {

/// Literal Algorithm 1 (see the file comment). The map-side neighbourhood
/// size is the map's shape_neighbours(). Non-owning pointers to the map and
/// features; associate() is const and thread-safe.
class NormalConsistencyReference {
 public:
  using Config = NormalConsistencyConfig;

  /// Validates the config (ConfigError).
  explicit NormalConsistencyReference(const Config& config = {})
      : config_(config), cos_max_(std::cos(config.max_angle_rad)) {
    detail::validate(config_);
  }

  /// Binds the map (non-owning) and builds a KdTree3f over its points, which
  /// lines 3 and 5 search. Bind again after the map was rebuilt (the
  /// pipelines do); until then the map's own tree is searched instead.
  void set_map(const FeatureMap& map) {
    map_ = &map;
    map_tree_.build(map.points());
    map_build_id_ = map.build_id();
  }
  /// Binds the features (non-owning) and builds the scan k-d tree that
  /// kdLidarNearest (line 6) searches; no neighbourhood is precomputed.
  void set_scan(const std::vector<Eigen::Vector3f>& points_scan) {
    features_ = &points_scan;
    scan_tree_.build(points_scan);
  }
  /// Not from a temporary: only a pointer to the features is kept.
  void set_scan(std::vector<Eigen::Vector3f>&&) = delete;

  /// Matches of feature i at pose (R, t) = T_map_scan (preconditions as
  /// NormalConsistency::match).
  [[nodiscard]] FeatureMatches match(std::size_t i, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) const {
    if (map_->build_id() == map_build_id_) return match_in(map_tree_, i, R, t);
    return match_in(map_->tree(), i, R, t);
  }

  /// One FeatureMatches per bound feature at pose T_map_scan into out.
  void associate(const SE3d& T_map_scan, Correspondences& out) const {
    detail::associate_each(features_, map_, T_map_scan, out,
                           [this](std::size_t i, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
                             return match(i, R, t);
                           });
  }

  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  // Algorithm 1 for feature i with map_tree searched for the map side.
  template <typename MapTree>
  FeatureMatches match_in(const MapTree& map_tree, std::size_t i, const Eigen::Matrix3d& R,
                          const Eigen::Vector3d& t) const {
    FeatureMatches m;
    const FeatureKind kind = map_->kind();
    const double gate2 = config_.max_distance_m * config_.max_distance_m;
    // Lines 2-3: lidar2map, then the 15 nearest map candidates.
    const Eigen::Vector3f q = detail::feature_to_map(R, t, (*features_)[i]);
    std::array<std::uint32_t, kMaxCandidates> idx{};
    std::array<float, kMaxCandidates> d2{};
    const std::size_t n = map_tree.knn(q, static_cast<std::size_t>(config_.candidates), idx.data(), d2.data());
    for (std::size_t j = 0; j < n; ++j) {  // line 4
      if (!detail::within_gate(d2[j], gate2)) break;
      // Line 5: the candidate's 10-NN in the map and its normal (eq. 3-6).
      const Eigen::Vector3f n_map =
          detail::neighbourhood_axis(map_tree, kind, map_tree.point(idx[j]), map_->shape_neighbours(),
                                     detail::AxisFit::kFullShape);
      // Line 6: the feature's 10-NN in the scan and its normal, moved to the map frame.
      const Eigen::Vector3f n_scan =
          detail::neighbourhood_axis(scan_tree_, kind, (*features_)[i], config_.scan_neighbours,
                                     detail::AxisFit::kFullShape);
      const Eigen::Vector3d n1 = R * n_scan.cast<double>();
      // Lines 7-10: keep consistent candidates until 5 are kept.
      if (detail::axes_agree(n1, n_map, cos_max_)) {
        detail::push_match(m, idx[j], j + 1);
        if (m.count == config_.keep) break;
      }
    }
    detail::enforce_min(kind, m);
    return m;
  }

  Config config_;
  double cos_max_;
  const FeatureMap* map_ = nullptr;
  KdTree3f map_tree_;              // over map_->points() as of set_map()
  std::uint64_t map_build_id_ = 0;  // map_->build_id() then
  const std::vector<Eigen::Vector3f>* features_ = nullptr;
  KdTree3f scan_tree_;
};

static_assert(Associator<NormalConsistencyReference, FeatureMap>);

}  // namespace semlio
