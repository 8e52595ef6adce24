#pragma once
/// \file
/// Voxel-grid downsampling with a per-voxel majority label, deterministic and
/// allocation-free after warm-up (a reusable object with buffers).
///
/// Choices: voxels are the cells floor(p / leaf) of an axis-aligned grid
/// anchored at the origin of the points' frame. Each output point is the
/// centroid of its voxel (default, as PCL's VoxelGrid that LIO-SAM uses) or
/// the voxel's first point (lowest input index). Every output also carries the
/// index of that first point and the voxel's majority label (ties: the lowest
/// class id). Outputs come in ascending order of first index, so downsampling
/// keeps the input order. Voxels are found through an open-addressing hash of
/// 64-bit voxel keys (21 bits per axis, +-2^20 cells: +-105 km at 0.1 m;
/// farther points clamp into the edge cells); results never depend on the
/// hash (centroids sum in input order). Non-finite points are skipped.

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/radix_sort.hpp>

namespace semlio {

/// Which point represents a voxel.
enum class VoxelPoint : std::uint8_t {
  kCentroid,  ///< mean of the voxel's points
  kFirst,     ///< the voxel's point with the lowest input index
};

/// Settings of VoxelGrid.
struct VoxelGridConfig {
  double leaf_size_m = 0.4;                  ///< voxel edge length [m], > 0 (LIO-SAM's surface leaf)
  VoxelPoint point = VoxelPoint::kCentroid;  ///< representative point of a voxel
};

/// Key of the voxel containing p (leaf given as its inverse [1/m]); 21 bits per axis.
/// Precondition: p finite (NaN would be undefined behaviour).
inline std::uint64_t voxel_key(const Eigen::Vector3f& p, double inv_leaf) {
  constexpr std::int64_t kHalf = std::int64_t{1} << 20;
  std::uint64_t key = 0;
  for (int a = 0; a < 3; ++a) {
    // floor(clamp(c)) == clamp(floor(c)) for integer bounds; once clamped,
    // truncation and a one-step correction are floor, exactly (baseline
    // x86-64 has no rounding instruction: std::floor took ~16 instructions).
    const double c = std::clamp(static_cast<double>(p[a]) * inv_leaf, -static_cast<double>(kHalf),
                                static_cast<double>(kHalf - 1));
    auto cell = static_cast<std::int64_t>(c);
    cell -= static_cast<double>(cell) > c ? 1 : 0;
    key = (key << 21) | static_cast<std::uint64_t>(cell + kHalf);
  }
  return key;
}

/// Voxel-grid downsampler. Not thread-safe (holds buffers); use one per thread.
class VoxelGrid {
 public:
  using Config = VoxelGridConfig;

  /// Throws ConfigError when leaf_size_m is not a positive finite number.
  explicit VoxelGrid(const Config& config = {}) : config_(config), inv_leaf_(1.0 / config.leaf_size_m) {
    if (!(config.leaf_size_m > 0.0) || !std::isfinite(config.leaf_size_m)) {
      throw ConfigError("VoxelGridConfig.leaf_size_m must be positive and finite, got " +
                        std::to_string(config.leaf_size_m));
    }
  }

  /// The settings.
  [[nodiscard]] const Config& config() const { return config_; }

  /// Downsamples all of pts. labels is empty or pts.size() long; out_labels
  /// is left empty when labels is. Outputs are cleared first.
  void downsample(const std::vector<Eigen::Vector3f>& pts, const std::vector<Class>& labels,
                  std::vector<Eigen::Vector3f>& out_pts, std::vector<Class>& out_labels,
                  std::vector<std::uint32_t>& out_first_idx) {
    check_labels(pts, labels);
    begin(pts.size());
    const Class* l = labels.empty() ? nullptr : labels.data();
    for (std::uint32_t i = 0; i < pts.size(); ++i) push(pts, i, l);
    finish(pts, labels, out_pts, out_labels, out_first_idx);
  }

  /// Downsamples only the points pts[subset[k]]; out_first_idx holds indices
  /// into pts (not into subset).
  void downsample(const std::vector<Eigen::Vector3f>& pts, const std::vector<Class>& labels,
                  const std::vector<std::uint32_t>& subset, std::vector<Eigen::Vector3f>& out_pts,
                  std::vector<Class>& out_labels, std::vector<std::uint32_t>& out_first_idx) {
    check_labels(pts, labels);
    begin(subset.size());
    const Class* l = labels.empty() ? nullptr : labels.data();
    for (const std::uint32_t i : subset) push(pts, i, l);
    finish(pts, labels, out_pts, out_labels, out_first_idx);
  }

 private:
  struct Slot {
    std::uint64_t key;
    std::uint32_t cell;
    std::uint32_t stamp;  // call that filled it: older stamps read as empty
  };
  struct Cell {
    Eigen::Vector3d sum;
    std::uint64_t key;  // for grow()
    std::uint32_t count;
    std::uint32_t first;
    std::uint32_t before_mixed = 0;  // points (all of `label`) before its first other label
    Class label = Class::kUnlabeled;  // its first point's label
    bool mixed = false;              // it holds more than one label (entries recorded since)
  };

  static void check_labels(const std::vector<Eigen::Vector3f>& pts, const std::vector<Class>& labels) {
    if (!labels.empty() && labels.size() != pts.size()) {
      throw ValueError("VoxelGrid: labels has " + std::to_string(labels.size()) +
                       " entries but there are " + std::to_string(pts.size()) + " points");
    }
  }

  /// Forgets the previous call (by a new stamp rather than by clearing) and
  /// sizes the hash table for the voxels the last call found, not for the n
  /// points: a scan's ~75 000 surface points fill ~5 000 voxels at 0.4 m,
  /// and a table sized for the points (4 MB) missed the cache on nearly
  /// every probe. The table doubles whenever it gets half full (push()).
  void begin(std::size_t n) {
    std::size_t cap = 16;
    while (cap < 2 * std::min(n, std::max<std::size_t>(expected_cells_, 64))) cap *= 2;
    use_table(cap);
    cells_.clear();
    entry_idx_.clear();
    entry_cell_.clear();
  }

  /// Makes the first cap slots (a power of two) the table, all empty. The
  /// vector only grows: a smaller table reuses its front.
  void use_table(std::size_t cap) {
    if (table_.size() < cap) {
      table_.assign(cap, Slot{0, 0, 0});
      stamp_ = 0;
    }
    if (++stamp_ == 0) {  // stamps wrapped: really clear once
      std::fill(table_.begin(), table_.end(), Slot{0, 0, 0});
      stamp_ = 1;
    }
    mask_ = cap - 1;
  }

  /// Slot of key in the table: its own, or the empty one where it belongs.
  [[nodiscard]] std::size_t probe(std::uint64_t key) const {
    std::size_t slot = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> 32U) & mask_;
    while (table_[slot].stamp == stamp_ && table_[slot].key != key) slot = (slot + 1) & mask_;
    return slot;
  }

  /// Doubles the table and re-inserts every voxel found so far.
  void grow() {
    use_table(2 * (mask_ + 1));
    for (std::uint32_t c = 0; c < cells_.size(); ++c) table_[probe(cells_[c].key)] = Slot{cells_[c].key, c, stamp_};
  }

  /// Adds point i to its voxel (open addressing, linear probing); with
  /// labels (non-null), records the (point, voxel) entry only when finish()
  /// needs it for the voxel's majority: once the voxel holds a second label.
  void push(const std::vector<Eigen::Vector3f>& pts, std::uint32_t i, const Class* labels) {
    const Eigen::Vector3f& p = pts[i];
    if (!p.allFinite()) return;
    const std::uint64_t key = voxel_key(p, inv_leaf_);
    if (cells_.empty() || key != last_key_) {
      // A ring's consecutive points mostly share a voxel (KITTI surfaces:
      // ~15 points per 0.4 m voxel, pushed in ring order): only a new key probes.
      last_key_ = key;
      const std::size_t slot = probe(key);
      if (table_[slot].stamp == stamp_) {
        last_cell_ = table_[slot].cell;
        add(cells_[last_cell_], p, i);
      } else {
        last_cell_ = static_cast<std::uint32_t>(cells_.size());
        table_[slot] = Slot{key, last_cell_, stamp_};
        cells_.push_back(Cell{p.cast<double>(), key, 1, i, 0, labels != nullptr ? labels[i] : Class::kUnlabeled});
        if (2 * cells_.size() > mask_ + 1) grow();
        return;
      }
    } else {
      add(cells_[last_cell_], p, i);
    }
    if (labels == nullptr) return;
    // Most voxels hold one label (all of them without a segmenter): they need
    // no entries, their majority is that label. A voxel's entries start at its
    // first other label; the points before it are counted in before_mixed.
    // (Recording every point's entry and counting every voxel was a quarter
    // of a one-label scan's downsampling: BM_VoxelDownsample_KittiScanOneLabel
    // 3.02 -> 2.20 ms, three alternated runs.)
    Cell& c = cells_[last_cell_];
    if (!c.mixed && labels[i] == c.label) return;
    if (!c.mixed) {
      c.mixed = true;
      c.before_mixed = c.count - 1;  // add() counted this point already
    }
    entry_idx_.push_back(i);
    entry_cell_.push_back(last_cell_);
  }

  // One more point (index i) in voxel c: its sum, count and first index.
  static void add(Cell& c, const Eigen::Vector3f& p, std::uint32_t i) {
    c.sum += p.cast<double>();
    ++c.count;
    c.first = std::min(c.first, i);
  }

  void finish(const std::vector<Eigen::Vector3f>& pts, const std::vector<Class>& labels,
              std::vector<Eigen::Vector3f>& out_pts, std::vector<Class>& out_labels,
              std::vector<std::uint32_t>& out_first_idx) {
    const std::size_t nc = cells_.size();
    expected_cells_ = nc;
    // Majority label per voxel: a voxel of one label has it; the entries of
    // mixed voxels are grouped by cell (counting sort) and counted, on top of
    // the points before each one's first other label.
    cell_label_.clear();
    if (!labels.empty()) {
      if (!entry_cell_.empty()) {
        offset_.assign(nc + 1, 0);
        for (const std::uint32_t c : entry_cell_) ++offset_[c + 1];
        for (std::size_t c = 0; c < nc; ++c) offset_[c + 1] += offset_[c];
        grouped_.resize(entry_idx_.size());
        cursor_.assign(offset_.begin(), offset_.end() - 1);
        for (std::size_t e = 0; e < entry_idx_.size(); ++e) grouped_[cursor_[entry_cell_[e]]++] = entry_idx_[e];
      }
      for (std::size_t c = 0; c < nc; ++c) {
        const Cell& cell = cells_[c];
        if (!cell.mixed) {
          cell_label_.push_back(cell.label);
          continue;
        }
        counts_.fill(0);
        counts_[static_cast<std::size_t>(cell.label)] = cell.before_mixed;
        for (std::size_t k = offset_[c]; k < offset_[c + 1]; ++k) {
          ++counts_[static_cast<std::size_t>(labels[grouped_[k]])];
        }
        const auto best = std::max_element(counts_.begin(), counts_.end());  // first max: lowest id
        cell_label_.push_back(static_cast<Class>(best - counts_.begin()));
      }
    }
    // Output in ascending first index (already so when the input was
    // ascending). First indices are unique, so (first, cell) keys sort to the
    // one order; a radix sort on the first index, not a comparison sort
    // through the cells (the surfaces come in ring order: ~5 000 voxels a
    // KITTI scan; 0.2 ms of its extraction, bench_features BM_LoamFeatureExtraction_KittiScan).
    order_.resize(nc);
    std::uint32_t max_first = 0;
    for (std::uint32_t c = 0; c < nc; ++c) {
      order_[c] = (std::uint64_t{cells_[c].first} << 32U) | c;
      max_first = std::max(max_first, cells_[c].first);
    }
    if (!std::is_sorted(order_.begin(), order_.end())) {
      radix_sort_by_key(order_, scratch_, radix_counts_, static_cast<int>(std::bit_width(max_first)),
                        [](std::uint64_t key) { return key >> 32U; });
    }
    out_pts.clear();
    out_labels.clear();
    out_first_idx.clear();
    for (const std::uint64_t key : order_) {
      const auto c = static_cast<std::uint32_t>(key);
      const Cell& cell = cells_[c];
      out_pts.push_back(config_.point == VoxelPoint::kCentroid && cell.count > 1
                            ? (cell.sum / static_cast<double>(cell.count)).cast<float>()
                            : pts[cell.first]);
      out_first_idx.push_back(cell.first);
      if (!labels.empty()) out_labels.push_back(cell_label_[c]);
    }
  }

  Config config_;
  double inv_leaf_;  // 1 / leaf_size_m [1/m]
  std::vector<Slot> table_;
  std::uint32_t stamp_ = 0;
  std::size_t mask_ = 0;
  std::size_t expected_cells_ = 0;  // voxels of the last call: the next table's size
  std::vector<Cell> cells_;
  std::uint64_t last_key_ = 0;   // the last push()'s voxel (valid while cells_ is not empty)
  std::uint32_t last_cell_ = 0;
  std::vector<std::uint32_t> entry_idx_;
  std::vector<std::uint32_t> entry_cell_;
  std::vector<std::size_t> offset_;
  std::vector<std::size_t> cursor_;
  std::vector<std::uint32_t> grouped_;
  std::vector<Class> cell_label_;
  std::vector<std::uint64_t> order_;    // (first index << 32 | cell), output order
  std::vector<std::uint64_t> scratch_;  // radix sort buffer
  RadixCounts radix_counts_;            // radix sort histograms
  std::array<std::uint32_t, kNumClasses> counts_{};
};

}  // namespace semlio
