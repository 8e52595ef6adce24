#pragma once
/// \file
/// The global semantic map (paper §3, step 5; METHOD.md step 9): labelled
/// keyframe clouds put into the world at their (optimised) poses and merged on
/// a voxel grid, one point per voxel at the centroid of its points with the
/// voxel's majority label (ties: the lowest class id, as VoxelGrid). With
/// `drop_dynamic` the movable classes (is_dynamic: car, truck, person, ...)
/// are removed point by point before voxelising, which gives a clean static
/// map (parked cars go too, as they are not part of the place).
///
/// Choices:
/// - Leaf 0.3 m by default: fine enough to see kerbs, poles and trunks, while
///   a city block stays a few hundred thousand points (about 100 bytes per
///   voxel while building: 72 for centroid sum, count and 20 label counts,
///   the rest for the hash index).
/// - Voxels are the cells floor(p / leaf) in the world frame (voxel_key of
///   search/voxel_grid.hpp, +-2^20 cells per axis); output order is the order
///   in which voxels were first touched, so the result is deterministic.
/// - Label counts are 16-bit; when one would overflow, all counts of that
///   voxel are halved (the majority is kept).
/// - Non-finite points are skipped; points of an unlabeled cloud count as
///   Class::kUnlabeled, and a map built only from unlabeled clouds has no
///   labels at all.
/// Not thread-safe; one map is filled from one thread.

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/search/voxel_grid.hpp>

namespace semlio {

/// Settings of SemanticMap.
struct SemanticMapConfig {
  double leaf_size_m = 0.3;   ///< voxel edge [m], > 0
  bool drop_dynamic = false;  ///< remove movable classes (is_dynamic) for a static map
  double max_range_m = 0.0;   ///< ignore points farther than this from their sensor [m]; 0 = keep all
};

/// Global voxelised map with a majority label per voxel.
class SemanticMap {
 public:
  using Config = SemanticMapConfig;

  /// Throws ConfigError on a non-positive leaf or a negative range.
  explicit SemanticMap(const Config& config = {}) : config_(config) {
    if (!(config_.leaf_size_m > 0.0) || !std::isfinite(config_.leaf_size_m)) {
      throw ConfigError("SemanticMapConfig.leaf_size_m must be positive and finite, got " +
                        std::to_string(config_.leaf_size_m));
    }
    if (!(config_.max_range_m >= 0.0)) {
      throw ConfigError("SemanticMapConfig.max_range_m must be >= 0, got " + std::to_string(config_.max_range_m));
    }
    inv_leaf_ = 1.0 / config_.leaf_size_m;
  }

  /// Adds a cloud given in the sensor frame at pose T_world_lidar. `labels` is
  /// empty (unlabeled) or one per point (else ValueError).
  void insert(const SE3d& T_world_lidar, const std::vector<Eigen::Vector3f>& points_lidar,
              const std::vector<Class>& labels) {
    if (!labels.empty() && labels.size() != points_lidar.size()) {
      throw ValueError("SemanticMap::insert: " + std::to_string(labels.size()) + " labels for " +
                       std::to_string(points_lidar.size()) + " points");
    }
    if (!T_world_lidar.matrix().allFinite()) return;
    if (!labels.empty()) labelled_ = true;
    const Eigen::Matrix3d R = T_world_lidar.rotation();
    const Eigen::Vector3d t = T_world_lidar.translation();
    const double max_r2 = config_.max_range_m * config_.max_range_m;
    for (std::size_t i = 0; i < points_lidar.size(); ++i) {
      const Eigen::Vector3f& p = points_lidar[i];
      if (!p.allFinite()) continue;
      const Class c = labels.empty() ? Class::kUnlabeled : labels[i];
      if (config_.drop_dynamic && is_dynamic(c)) continue;
      const Eigen::Vector3d p_l = p.cast<double>();
      if (max_r2 > 0.0 && p_l.squaredNorm() > max_r2) continue;
      add(R * p_l + t, c);
    }
  }

  /// Adds a labelled scan (points in the sensor frame) at T_world_lidar.
  void insert(const SE3d& T_world_lidar, const Scan& scan) { insert(T_world_lidar, scan.points, scan.labels); }

  /// The map as a cloud in the world frame: one point per voxel (centroid),
  /// its majority label (when any inserted cloud had labels); stamp 0.
  /// Writable with io::write_ply (label + SemanticKITTI colour).
  [[nodiscard]] Scan cloud() const {
    Scan out;
    out.points.reserve(voxels_.size());
    if (labelled_) out.labels.reserve(voxels_.size());
    for (const Voxel& v : voxels_) {
      out.points.push_back((v.sum / static_cast<double>(v.count)).cast<float>());
      if (labelled_) out.labels.push_back(majority(v));
    }
    return out;
  }

  /// Number of occupied voxels (= points of cloud()).
  [[nodiscard]] std::size_t size() const noexcept { return voxels_.size(); }
  /// True when no point was inserted.
  [[nodiscard]] bool empty() const noexcept { return voxels_.empty(); }
  /// Forgets every voxel, keeps the settings.
  void clear() {
    voxels_.clear();
    index_.clear();
    labelled_ = false;
  }
  /// Approximate heap memory of the map while building [bytes].
  [[nodiscard]] std::size_t memory_bytes() const noexcept {
    return voxels_.capacity() * sizeof(Voxel) + index_.size() * (sizeof(std::uint64_t) + sizeof(std::uint32_t) + 16U);
  }
  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  struct Voxel {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::uint32_t count = 0;
    std::array<std::uint16_t, kNumClasses> labels{};
  };

  void add(const Eigen::Vector3d& p_world, Class c) {
    const std::uint64_t key = voxel_key(p_world.cast<float>(), inv_leaf_);
    const auto [it, inserted] = index_.try_emplace(key, static_cast<std::uint32_t>(voxels_.size()));
    if (inserted) voxels_.emplace_back();
    Voxel& v = voxels_[it->second];
    v.sum += p_world;
    ++v.count;
    auto& n = v.labels[static_cast<std::size_t>(index(c))];
    if (n == 0xFFFFU) {
      for (auto& m : v.labels) m = static_cast<std::uint16_t>(m / 2U);
    }
    ++n;
  }

  static Class majority(const Voxel& v) {
    std::size_t best = 0;
    for (std::size_t k = 1; k < v.labels.size(); ++k) {
      if (v.labels[k] > v.labels[best]) best = k;
    }
    return class_from_index(static_cast<int>(best));
  }

  Config config_;
  double inv_leaf_ = 1.0;
  bool labelled_ = false;
  std::vector<Voxel> voxels_;
  std::unordered_map<std::uint64_t, std::uint32_t> index_;
};

}  // namespace semlio
