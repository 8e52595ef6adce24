#pragma once
/// \file
/// The local map of the scan-to-map front end (LIO-SAM's "surrounding
/// keyframes"): the corner and surface features of the keyframes whose
/// position lies within a radius of a query position, moved into the map
/// frame, voxel-downsampled (each voxel: centroid, majority label; or, with
/// keep_first_point, its first point), with a k-d tree and a cached normal /
/// line direction per map point (eq. 3-6).
///
/// Cost model: build() is the expensive step (transform, voxelise, tree;
/// normals and candidate lists are filled lazily, see feature_map.hpp); the
/// pipeline calls it when a keyframe is added, never per frame. Voxelising
/// merges the newcomers into the previous build's sorted points rather than
/// re-sorting every point within the radius (build_one()); the k-d tree is
/// still rebuilt whole. Every per-frame query then reads the built maps only.
///
/// Memory: a stored keyframe's features are ~0.1 MB (KITTI-like scans), and
/// a front end that kept them all grows without bound (~65 MB per 1000
/// frames on a simulated drive). At most `max_keyframes` are kept: beyond
/// that, build() drops the stored keyframe farthest from its query position
/// among those outside the radius (the oldest when all are inside). What
/// is dropped can no longer be matched against when the vehicle comes back
/// -- that is the back end's job (Slam keeps spaced places for loop
/// closure). Keyframes keep the id add_keyframe() gave them.
///
/// Allocation: once the store holds max_keyframes, a dropped keyframe's
/// buffers take the next keyframe's clouds, and every build buffer (sorted
/// entries, sort buffers, voxel outputs, the FeatureMaps) is reused, so a
/// keyframe allocates nothing after warm-up. Until then each keyframe
/// allocates its stored clouds, and a growing map now and then a larger
/// buffer; a full rebuild (a corrected pose, a keyframe coming back) sorts
/// through a map-sized buffer that it frees afterwards.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <concepts>
#include <cstdint>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include <semlio/core/buffers.hpp>
#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/radix_sort.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/map/feature_map.hpp>

namespace semlio {

/// A labelled point cloud as LocalMap takes it: `points` [m] and `labels`
/// (empty = unlabeled, else one per point). Scan and FeatureSet qualify.
template <typename C>
concept LabelledCloud = requires(const C& c) {
  { c.points } -> std::convertible_to<const std::vector<Eigen::Vector3f>&>;
  { c.labels } -> std::convertible_to<const std::vector<Class>&>;
};

/// Settings of LocalMap.
struct LocalMapConfig {
  double radius_m = 50.0;        ///< keyframes within this distance of the query position (LIO-SAM: 50 m)
  double corner_leaf_m = 0.2;    ///< voxel leaf of the corner map (LIO-SAM mappingCornerLeafSize)
  double surface_leaf_m = 0.4;   ///< voxel leaf of the surface map (LIO-SAM mappingSurfLeafSize)
  int shape_neighbours = 10;     ///< map points per cached normal / direction fit (Algorithm 1: 10)
  bool exclude_dynamic = false;  ///< keep movable classes (is_dynamic) out of the map
  /// Cached nearest map points per point, for FeatureMap::nearest without a
  /// NearestCache (0 = off: a k-d tree search bounded at the gate, the faster
  /// one on sparse maps since SmallKdTree3f; FeatureMap's file comment).
  int candidate_list = 0;
  std::size_t max_keyframes = 1000;  ///< keyframes stored at most (file comment: which are dropped); 0 = keep all
  /// Each voxel's point is its first point -- of the oldest active keyframe
  /// that has one there -- instead of the centroid, so map points stay put
  /// while keyframes arrive (bench_frame_time, scripts/frame_time_configs.sh: an experiment towards a map
  /// whose cached axes survive keyframes). Labels stay the majority.
  bool keep_first_point = false;
};

namespace detail {

/// Voxel-grid downsampling with labels, the straightforward reference of
/// downsample_labelled (same contract, same output bit for bit; kept for the
/// test that proves it and the benchmark that times both): one output point
/// per occupied voxel of edge `leaf_m`, at the centroid of its points (with
/// first_point: the voxel's first point in input order), carrying the
/// voxel's majority label (ties: the lowest class id). Output order is by
/// voxel key. Non-finite points and points beyond +-2^20 leaves from the
/// origin are dropped. labels may be empty (all unlabeled).
inline void downsample_labelled_reference(const std::vector<Eigen::Vector3f>& points,
                                          const std::vector<Class>& labels, double leaf_m,
                                          std::vector<Eigen::Vector3f>& out_points,
                                          std::vector<Class>& out_labels, bool first_point = false) {
  constexpr std::int64_t kHalf = std::int64_t{1} << 20;
  const double inv_leaf = 1.0 / leaf_m;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  keyed.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    if (!p.allFinite()) continue;
    std::array<std::uint64_t, 3> c{};
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      const double v = std::floor(static_cast<double>(p[a]) * inv_leaf);
      if (!(v >= static_cast<double>(-kHalf) && v < static_cast<double>(kHalf))) {
        inside = false;
        break;
      }
      c[static_cast<std::size_t>(a)] = static_cast<std::uint64_t>(static_cast<std::int64_t>(v) + kHalf);
    }
    if (!inside) continue;
    keyed.emplace_back((c[0] << 42U) | (c[1] << 21U) | c[2], static_cast<std::uint32_t>(i));
  }
  std::sort(keyed.begin(), keyed.end());
  out_points.clear();
  out_labels.clear();
  std::size_t b = 0;
  while (b < keyed.size()) {
    std::size_t e = b;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::array<std::uint32_t, kNumClasses> votes{};
    while (e < keyed.size() && keyed[e].first == keyed[b].first) {
      const std::uint32_t i = keyed[e].second;
      sum += points[i].cast<double>();
      const Class c = labels.empty() ? Class::kUnlabeled : labels[i];
      ++votes[static_cast<std::size_t>(index(c))];
      ++e;
    }
    out_points.push_back(first_point ? points[keyed[b].second] : (sum / static_cast<double>(e - b)).cast<float>());
    const auto best = std::max_element(votes.begin(), votes.end());  // first maximum: lowest id
    out_labels.push_back(class_from_index(static_cast<int>(best - votes.begin())));
    b = e;
  }
}

/// One point of a LocalMap rebuild: its voxel key as
/// downsample_labelled_reference packs it (21 bits per axis), its keyframe,
/// the point in the map frame and its label.
struct MapEntry {
  std::uint64_t key;
  std::size_t keyframe;
  Eigen::Vector3f p;
  Class label;
};

/// Stable radix sort of entries by voxel key (63 bits: core/radix_sort.hpp).
inline void sort_by_voxel_key(std::vector<MapEntry>& entries, std::vector<MapEntry>& scratch, RadixCounts& counts) {
  radix_sort_by_key(entries, scratch, counts, 63, [](const MapEntry& e) { return e.key; });
}

/// Appends the key-sorted `fresh` to the key-sorted `entries` and merges
/// them, held entries first on equal keys (as std::inplace_merge with the
/// held ones as the first range), but backwards in place: std::inplace_merge
/// allocates a temporary buffer on every call. Allocation-free while
/// `entries` has the capacity.
inline void merge_sorted_entries(std::vector<MapEntry>& entries, const std::vector<MapEntry>& fresh) {
  std::size_t i = entries.size();
  std::size_t j = fresh.size();
  entries.resize(i + j);
  std::size_t k = entries.size();
  while (j > 0) {
    // Strictly greater: on equal keys the fresh entry goes behind the held one.
    if (i > 0 && entries[i - 1].key > fresh[j - 1].key) {
      entries[--k] = entries[--i];
    } else {
      entries[--k] = fresh[--j];
    }
  }
}

/// Centroid (points summed in entry order; with first_point: the run's first
/// entry) and majority label (ties: the lowest class id) of each run of
/// equal keys in key-sorted entries. out_keys, when given, receives each
/// voxel's key (strictly ascending).
inline void emit_voxels(const std::vector<MapEntry>& entries, std::vector<Eigen::Vector3f>& out_points,
                        std::vector<Class>& out_labels, std::vector<std::uint64_t>* out_keys = nullptr,
                        bool first_point = false) {
  out_points.clear();
  out_labels.clear();
  if (out_keys != nullptr) out_keys->clear();
  const std::size_t n = entries.size();
  // One pass over the keys sizes the outputs: grown by push_back, each of the
  // three went through ~20 reallocations per map build. Outputs reused from
  // build to build regrow with headroom (core/buffers.hpp).
  std::size_t voxels = n == 0 ? 0 : 1;
  for (std::size_t j = 1; j < n; ++j) voxels += entries[j].key != entries[j - 1].key ? 1U : 0U;
  reserve_with_headroom(out_points, voxels);
  reserve_with_headroom(out_labels, voxels);
  if (out_keys != nullptr) reserve_with_headroom(*out_keys, voxels);
  std::size_t b = 0;
  while (b < n) {
    std::size_t e = b;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    bool one_label = true;
    while (e < n && entries[e].key == entries[b].key) {
      sum += entries[e].p.cast<double>();
      one_label = one_label && entries[e].label == entries[b].label;
      ++e;
    }
    out_points.push_back(first_point ? entries[b].p : (sum / static_cast<double>(e - b)).cast<float>());
    if (out_keys != nullptr) out_keys->push_back(entries[b].key);
    if (one_label) {
      out_labels.push_back(entries[b].label);
    } else {
      std::array<std::uint32_t, kNumClasses> votes{};
      for (std::size_t j = b; j < e; ++j) ++votes[static_cast<std::size_t>(index(entries[j].label))];
      const auto best = std::max_element(votes.begin(), votes.end());  // first maximum: lowest id
      out_labels.push_back(class_from_index(static_cast<int>(best - votes.begin())));
    }
    b = e;
  }
}

/// Buffers of downsample_labelled, reusable across calls (a map-sized input
/// is tens of megabytes; fresh buffers would page-fault them in every time).
struct DownsampleWorkspace {
  std::vector<MapEntry> entries;  ///< the kept points with their voxel keys
  std::vector<MapEntry> scratch;  ///< the radix sort's second buffer
  RadixCounts counts;             ///< the radix sort's histograms
};

/// Voxel-grid downsampling with labels: one output point per occupied voxel
/// of edge `leaf_m`, at the centroid of its points, carrying the voxel's
/// majority label (ties: the lowest class id). Output order is by voxel key,
/// so the result does not depend on the input order. Non-finite points and
/// points beyond +-2^20 leaves from the origin are dropped. labels may be
/// empty (all unlabeled).
///
/// Why not a comparison sort (the reference): sorting (key, index) pairs of
/// a map-sized input and then summing the points in that order reads them
/// at random; here a stable LSD radix sort carries each point and label
/// along with its key, so the per-voxel sums read memory in order.
/// Stability keeps equal keys in input order, the order in which the
/// reference sums them: the output is the reference's bit for bit (test).
/// Measured on 0.6 M points (bench_association, DownsampleLabelled/*): about
/// half the reference's time with a reused workspace.
inline void downsample_labelled(const std::vector<Eigen::Vector3f>& points, const std::vector<Class>& labels,
                                double leaf_m, std::vector<Eigen::Vector3f>& out_points,
                                std::vector<Class>& out_labels, DownsampleWorkspace& ws) {
  const double inv_leaf = 1.0 / leaf_m;
  ws.entries.clear();
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::uint64_t key = 0;
    if (!reference_voxel_key(points[i], inv_leaf, key)) continue;
    ws.entries.push_back(MapEntry{key, 0, points[i], labels.empty() ? Class::kUnlabeled : labels[i]});
  }
  sort_by_voxel_key(ws.entries, ws.scratch, ws.counts);
  emit_voxels(ws.entries, out_points, out_labels);
}

/// downsample_labelled with buffers of its own (one-off calls, tests).
inline void downsample_labelled(const std::vector<Eigen::Vector3f>& points, const std::vector<Class>& labels,
                                double leaf_m, std::vector<Eigen::Vector3f>& out_points,
                                std::vector<Class>& out_labels) {
  DownsampleWorkspace ws;
  downsample_labelled(points, labels, leaf_m, out_points, out_labels, ws);
}

}  // namespace detail

/// Corner and surface maps around a position, built from keyframe feature
/// clouds at poses T_map_kf. Not thread-safe for mutation; const queries of
/// the built maps may run concurrently.
class LocalMap {
 public:
  using Config = LocalMapConfig;

  /// Validates the config (ConfigError naming the field and value).
  explicit LocalMap(const Config& config = {}) : config_(config) {
    const auto positive = [](double v, const char* field) {
      if (!(v > 0.0) || !std::isfinite(v)) {
        throw ConfigError(std::string("LocalMapConfig.") + field + " = " + std::to_string(v) +
                          ", expected a finite value > 0");
      }
    };
    positive(config_.radius_m, "radius_m");
    positive(config_.corner_leaf_m, "corner_leaf_m");
    positive(config_.surface_leaf_m, "surface_leaf_m");
    if (config_.shape_neighbours < 3 || config_.shape_neighbours > kMaxShapeNeighbours) {
      throw ConfigError("LocalMapConfig.shape_neighbours = " + std::to_string(config_.shape_neighbours) +
                        ", expected 3.." + std::to_string(kMaxShapeNeighbours));
    }
    if (config_.candidate_list < 0 || config_.candidate_list > kMaxCandidateList) {
      throw ConfigError("LocalMapConfig.candidate_list = " + std::to_string(config_.candidate_list) +
                        ", expected 0.." + std::to_string(kMaxCandidateList));
    }
  }

  /// Stores a keyframe's corner and surface features (keyframe frame; labels
  /// optional) at pose T_map_kf and returns its id (0, 1, 2, ... in the order
  /// added). Does not rebuild. Throws ValueError when labels are present
  /// with the wrong length.
  template <LabelledCloud C1, LabelledCloud C2>
  std::size_t add_keyframe(const SE3d& T_map_kf, const C1& corners, const C2& surfaces) {
    check_labels(corners.points, corners.labels, "corners");
    check_labels(surfaces.points, surfaces.labels, "surfaces");
    Keyframe kf{next_id_, T_map_kf, take_spare(), take_spare()};
    keep(corners.points, corners.labels, kf.corners);
    keep(surfaces.points, surfaces.labels, kf.surfaces);
    keyframes_.push_back(std::move(kf));
    return next_id_++;
  }

  /// Corrects the pose of keyframe `id` (e.g. after a loop closure); call
  /// build() after. A keyframe already dropped (max_keyframes) is ignored;
  /// an id never given throws ValueError.
  void set_keyframe_pose(std::size_t id, const SE3d& T_map_kf) {
    if (id >= next_id_) {
      throw ValueError("LocalMap::set_keyframe_pose: keyframe " + std::to_string(id) + " of " +
                       std::to_string(next_id_));
    }
    if (Keyframe* kf = find(id)) {
      kf->T_map_kf = T_map_kf;
      merged_corners_.valid = merged_surfaces_.valid = false;  // its entries moved: full rebuild
    }
  }

  /// Number of keyframes added so far (ids issued), stored or dropped.
  [[nodiscard]] std::size_t keyframe_count() const noexcept { return next_id_; }
  /// Number of keyframes stored now (<= max_keyframes when that is set).
  [[nodiscard]] std::size_t stored_keyframe_count() const noexcept { return keyframes_.size(); }
  /// Pose of stored keyframe `id`; throws ValueError when it is not stored.
  [[nodiscard]] const SE3d& keyframe_pose(std::size_t id) const {
    const Keyframe* kf = find(id);
    if (kf == nullptr) throw ValueError("LocalMap::keyframe_pose: keyframe " + std::to_string(id) + " is not stored");
    return kf->T_map_kf;
  }

  /// (Re)builds both maps from the keyframes within radius_m of center_map
  /// [m, map frame]: transform, voxel-downsample, k-d tree, cached axes.
  /// First drops stored keyframes beyond max_keyframes (file comment).
  void build(const Eigen::Vector3d& center_map) {
    trim(center_map);
    active_.clear();
    active_pos_.clear();
    for (std::size_t i = 0; i < keyframes_.size(); ++i) {
      if ((keyframes_[i].T_map_kf.translation() - center_map).norm() <= config_.radius_m) {
        active_.push_back(keyframes_[i].id);
        active_pos_.push_back(i);
      }
    }
    build_one(&Keyframe::corners, config_.corner_leaf_m, corners_, merged_corners_);
    build_one(&Keyframe::surfaces, config_.surface_leaf_m, surfaces_, merged_surfaces_);
  }

  /// True when the last build() merged its keyframe changes into the
  /// previous build's sorted points (both maps) instead of re-sorting all.
  [[nodiscard]] bool last_build_merged() const noexcept { return merged_corners_.merged && merged_surfaces_.merged; }
  /// Ids of the keyframes used by the last build(), ascending.
  [[nodiscard]] const std::vector<std::size_t>& active_keyframes() const noexcept { return active_; }
  /// The corner (line) map of the last build().
  [[nodiscard]] const FeatureMap& corners() const noexcept { return corners_; }
  /// The surface (plane) map of the last build().
  [[nodiscard]] const FeatureMap& surfaces() const noexcept { return surfaces_; }
  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  struct Cloud {
    std::vector<Eigen::Vector3f> points;  // keyframe frame
    std::vector<Class> labels;            // empty = unlabeled
  };
  struct Keyframe {
    std::size_t id;
    SE3d T_map_kf;
    Cloud corners;
    Cloud surfaces;
  };

  // Stored keyframe with this id, or null (ids ascend along keyframes_).
  template <typename Keyframes>
  static auto* find_in(Keyframes& keyframes, std::size_t id) {
    const auto it = std::lower_bound(keyframes.begin(), keyframes.end(), id,
                                     [](const Keyframe& kf, std::size_t v) { return kf.id < v; });
    return it != keyframes.end() && it->id == id ? &*it : nullptr;
  }
  Keyframe* find(std::size_t id) { return find_in(keyframes_, id); }
  [[nodiscard]] const Keyframe* find(std::size_t id) const { return find_in(keyframes_, id); }

  // Drops keyframes until at most max_keyframes remain: the farthest from
  // center outside the radius (ties: the oldest), else the oldest.
  void trim(const Eigen::Vector3d& center) {
    if (config_.max_keyframes == 0) return;
    while (keyframes_.size() > config_.max_keyframes) {
      std::size_t drop = 0;
      double farthest = -1.0;
      for (std::size_t i = 0; i < keyframes_.size(); ++i) {
        const double d = (keyframes_[i].T_map_kf.translation() - center).norm();
        if (d > config_.radius_m && d > farthest) {
          farthest = d;
          drop = i;
        }
      }
      // Its clouds' buffers serve the next keyframes (add_keyframe).
      spare_clouds_.push_back(std::move(keyframes_[drop].corners));
      spare_clouds_.push_back(std::move(keyframes_[drop].surfaces));
      keyframes_.erase(keyframes_.begin() + static_cast<std::ptrdiff_t>(drop));
    }
  }

  // A dropped keyframe's cloud to refill, else a new one.
  Cloud take_spare() {
    if (spare_clouds_.empty()) return {};
    Cloud c = std::move(spare_clouds_.back());
    spare_clouds_.pop_back();
    return c;
  }

  static void check_labels(const std::vector<Eigen::Vector3f>& points, const std::vector<Class>& labels,
                           const char* what) {
    if (!labels.empty() && labels.size() != points.size()) {
      throw ValueError(std::string("LocalMap::add_keyframe: ") + what + " has " + std::to_string(points.size()) +
                       " points but " + std::to_string(labels.size()) + " labels");
    }
  }

  // Copies the kept points (and labels) into c, reusing its buffers: a
  // recycled cloud (trim()) that is too small regrows with headroom
  // (core/buffers.hpp), so that once the store is full the keyframes'
  // varying sizes soon stop reallocating; a new one takes its exact size.
  void keep(const std::vector<Eigen::Vector3f>& points, const std::vector<Class>& labels, Cloud& c) const {
    const bool labelled = !labels.empty();
    reserve_discarding(c.points, points.size());
    reserve_discarding(c.labels, labelled ? labels.size() : 0);
    c.points.clear();
    c.labels.clear();
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (config_.exclude_dynamic && labelled && is_dynamic(labels[i])) continue;
      c.points.push_back(points[i]);
      if (labelled) c.labels.push_back(labels[i]);
    }
  }

  // The key-sorted entries of one map's last build (see build_one()).
  struct MergedMap {
    std::vector<detail::MapEntry> entries;  // (key, keyframe order, point order)
    std::vector<detail::MapEntry> scratch;        // a full rebuild's sort buffer (map-sized, freed after)
    std::vector<detail::MapEntry> fresh;
    std::vector<detail::MapEntry> fresh_scratch;  // the newcomers' sort buffer (kept)
    RadixCounts counts;
    std::vector<Eigen::Vector3f> points;          // the voxels handed to the FeatureMap (kept)
    std::vector<Class> labels;
    VoxelIndex voxels;
    std::vector<std::size_t> ids;  // the keyframes they hold, ascending
    bool valid = false;
    bool merged = false;  // the last build took the merge path
  };

  // Merges the active keyframes' clouds, voxel-downsamples them and builds
  // the FeatureMap. The result is downsample_labelled_reference's over the
  // active keyframes in ascending id order: its (key, merged index) sort
  // order is kept in m.entries between builds. Usually the active set only
  // gains keyframes newer than all it held (and loses some), so a build
  // drops the entries of keyframes that left, sorts the new ones and merges
  // them in (the merge keeps the held entries first on equal keys, as their
  // ids are lower): linear in the map instead of a sort of it. A keyframe
  // that comes back, or a corrected pose, makes a full rebuild.
  void build_one(Cloud Keyframe::*member, double leaf_m, FeatureMap& map, MergedMap& m) {
    const double inv_leaf = 1.0 / leaf_m;
    const auto append = [&](const Keyframe& kf, std::vector<detail::MapEntry>& out) {
      const Cloud& cloud = kf.*member;
      const Eigen::Matrix3d R = kf.T_map_kf.rotation();
      const Eigen::Vector3d& t = kf.T_map_kf.translation();
      for (std::size_t i = 0; i < cloud.points.size(); ++i) {
        const Eigen::Vector3f p = (R * cloud.points[i].cast<double>() + t).cast<float>();
        std::uint64_t key = 0;
        if (!detail::reference_voxel_key(p, inv_leaf, key)) continue;
        out.push_back(detail::MapEntry{key, kf.id, p, cloud.labels.empty() ? Class::kUnlabeled : cloud.labels[i]});
      }
    };
    const auto held = [&m](std::size_t id) { return std::binary_search(m.ids.begin(), m.ids.end(), id); };
    bool incremental = m.valid;
    for (const std::size_t id : active_) {
      if (incremental && !m.ids.empty() && id < m.ids.back() && !held(id)) incremental = false;
    }
    if (incremental) {
      left_.clear();
      std::set_difference(m.ids.begin(), m.ids.end(), active_.begin(), active_.end(), std::back_inserter(left_));
      if (!left_.empty()) {
        std::erase_if(m.entries, [this](const detail::MapEntry& e) {
          return std::binary_search(left_.begin(), left_.end(), e.keyframe);  // usually one or two keyframes
        });
      }
      m.fresh.clear();
      for (const std::size_t k : active_pos_) {
        if (!held(keyframes_[k].id)) append(keyframes_[k], m.fresh);
      }
      detail::sort_by_voxel_key(m.fresh, m.fresh_scratch, m.counts);
      // Growing a map-sized vector copies it into fresh pages; while the map
      // grows that happened on 176 of 428 builds of the main job's drive and
      // cost ~5 ms each (page faults, the copy). An eighth of headroom left
      // 40 and still no doubled capacity at rest (so not reserve_with_headroom's
      // 1.5x step: this buffer is map-sized). But a young map grows by more
      // than an eighth per keyframe: on the KITTI snippet 18 of 20 builds
      // still reallocated, 0.2-1.2 ms each. Room for four more keyframes like
      // this one as well: 6 of 20 there, 23 of 424 on the drive, the same
      // eighth at rest (full preset, bench_frame_time: map stage 2.43 -> 2.05
      // ms median on keyframes; scripts/frame_time.sh).
      const std::size_t needed = m.entries.size() + m.fresh.size();
      if (m.entries.capacity() < needed) m.entries.reserve(needed + std::max(needed / 8, 4 * m.fresh.size()));
      detail::merge_sorted_entries(m.entries, m.fresh);
    } else {
      m.entries.clear();
      for (const std::size_t k : active_pos_) append(keyframes_[k], m.entries);
      detail::sort_by_voxel_key(m.entries, m.scratch, m.counts);
      std::vector<detail::MapEntry>().swap(m.scratch);  // map-sized, and only a full rebuild needs it
    }
    reserve_with_headroom(m.ids, active_.size());
    m.ids = active_;
    m.valid = true;
    m.merged = incremental;
    // The voxel index only anchors candidate-list queries: without lists
    // (the default) no keys are emitted, copied or checked.
    const bool lists = config_.candidate_list > 0;
    m.voxels.leaf_m = lists ? leaf_m : 0.0;
    if (!lists) m.voxels.keys.clear();
    detail::emit_voxels(m.entries, m.points, m.labels, lists ? &m.voxels.keys : nullptr, config_.keep_first_point);
    map.build(m.points, m.labels, config_.shape_neighbours, config_.candidate_list, m.voxels);
  }

  Config config_;
  std::vector<Keyframe> keyframes_;  // stored keyframes, ascending id
  std::size_t next_id_ = 0;
  std::vector<std::size_t> active_;      // ids of the last build's keyframes
  std::vector<std::size_t> active_pos_;  // and their positions in keyframes_
  FeatureMap corners_{FeatureKind::kLine};
  FeatureMap surfaces_{FeatureKind::kPlane};
  // Sorted entries of the last build, per map (32 bytes per merged point, up
  // to 36 with the growth headroom, ~10-20 MB on a full 50 m map; kept so
  // that the next build is a merge).
  MergedMap merged_corners_;
  MergedMap merged_surfaces_;
  std::vector<std::size_t> left_;  // keyframes that left the active set since the last build
  std::vector<Cloud> spare_clouds_;  // buffers of dropped keyframes, refilled by add_keyframe()
};

}  // namespace semlio
