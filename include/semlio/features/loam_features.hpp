#pragma once
/// \file
/// LOAM feature extraction (paper §3.1, eq. 2; METHOD.md "Curvature"):
/// curvature along each ring, occlusion and parallel-beam rejection, per-sector
/// corner selection and voxel-downsampled surface points.
///
/// Curvature (eq. 2 as METHOD.md decides), for point p_i of a ring and S its 5
/// neighbours on each side along the same ring:
///     c_i = || sum_{j in S} (p_i - p_j) ||^2 / (|S| * ||p_i||)      [m]
/// It is undefined for the first and last 5 points of a ring.
///
/// Rejection, as LOAM / LIO-SAM: where two consecutive ring points (closer
/// than max_neighbour_gap_rad in azimuth) differ in range by more than
/// occlusion_depth_gap_m, the 6 points on the far side are occluded; a point
/// whose range differs from both neighbours' by more than parallel_beam_ratio
/// of its own is on a surface nearly parallel to the beam. Rejected points are
/// neither corners nor surfaces.
///
/// Selection per ring, split into 6 equal sectors (by point count): up to
/// max_corners_per_sector points with c > corner_threshold_m, largest first;
/// each chosen corner suppresses its 5 neighbours on each side (stopping at
/// azimuth gaps). Surfaces: every remaining non-rejected point with c <
/// surface_threshold_m (all of them, not LIO-SAM's "everything that is not a
/// corner"), then voxel-downsampled over the whole scan (leaf surface_leaf_m).
/// Corners may be voxel-downsampled too (corner_leaf_m, centroid and majority
/// label per voxel), as LIO-SAM does to the current scan with its map's
/// corner leaf (downsampleCurrentScan, 0.2 m); off by default (see the field).
///
/// Default thresholds, chosen from the measured distribution of c on the real
/// KITTI scans tests/data/kitti/sequences/00/velodyne/00000{0,1}.bin (rings
/// from point order, default preprocessing, all points with a defined c that
/// are not rejected, ~99 200 per scan; the hidden test "[.percentiles]"
/// prints them):
///     percentile   10      25      50      75      80      85      90      93     95     99
///     000000.bin  2.0e-5  4.9e-5  1.27e-4 4.8e-4  7.9e-4  1.63e-3 4.29e-3 9.8e-3 0.021  2.97
///     000001.bin  2.0e-5  4.9e-5  1.26e-4 4.8e-4  7.9e-4  1.62e-3 4.25e-3 9.7e-3 0.021  2.80
/// (the 32-beam scan pair, for comparison: 1.3e-6 4.9e-6 2.1e-5 9.7e-5 1.7e-4
/// 5.3e-4 3.8e-3 2.0e-2 0.11 12.2 -- a similar 90th percentile, so the same
/// defaults give ~1 300 corners and ~1 700 surfaces there.)
/// Eq. 2 is range-normalised, so LIO-SAM's thresholds (1.0 and 0.1 on its
/// squared range difference, m^2) map to c ~ c_LIO-SAM / (|S| r): at r = 10 m
/// that is 0.01 and 0.001. A perfect 90-degree wall corner seen with KITTI's
/// 0.18 deg step gives c ~ 4.3e-4 * r, depth edges give 0.1 .. 10.
/// Chosen: corner_threshold_m = 0.005 (the 90th percentile; 90-degree corners
/// from ~12 m on, every depth edge; the 20-per-sector cap then keeps the
/// sharpest: ~2 950 corners per KITTI scan) and surface_threshold_m = 0.001
/// (~82nd percentile; ~75 000 surface points, ~5 100 after the 0.4 m voxel).
///
/// Rings: scan.rings is required (infer them with rings.hpp). Points of a ring
/// are taken in ascending azimuth (atan2_fast(y, x) mod 2pi), sorted only when the
/// stored order is not already so; direction does not matter to eq. 2.
///
/// Allocation: the extractor keeps its buffers; after the first frames of a
/// given size, extract() allocates nothing (output vectors keep capacity).

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/core/buffers.hpp>
#include <semlio/core/error.hpp>
#include <semlio/core/fast_math.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/search/voxel_grid.hpp>

namespace semlio {

/// Settings of LoamFeatureExtractor (defaults: see the file comment).
struct LoamFeatureConfig {
  int neighbours = 5;                         ///< |S| / 2: neighbours on each side (eq. 2)
  int sectors = 6;                            ///< sectors per ring
  std::size_t max_corners_per_sector = 20;    ///< corner cap per sector
  double corner_threshold_m = 0.005;          ///< c above: corner candidate [m] (90th pct on KITTI)
  double surface_threshold_m = 0.001;         ///< c below: surface point [m] (~82nd pct on KITTI)
  double occlusion_depth_gap_m = 0.3;         ///< range jump marking an occlusion edge [m]
  double parallel_beam_ratio = 0.02;          ///< relative range jump marking a grazing beam
  double max_neighbour_gap_rad = 2.0 * std::numbers::pi / 180.0;  ///< larger azimuth gaps break adjacency [rad]
  double surface_leaf_m = 0.4;                ///< surface voxel leaf [m]; <= 0 keeps all surfaces
  double corner_leaf_m = 0.0;                 ///< corner voxel leaf [m] (LIO-SAM: 0.2); <= 0 keeps all corners
  VoxelPoint surface_point = VoxelPoint::kCentroid;  ///< voxel representative of surfaces

  /// Throws ConfigError naming the bad field and value.
  void validate() const {
    const auto fail = [](const char* field, double v) {
      throw ConfigError(std::string("LoamFeatureConfig.") + field + " is invalid: " + std::to_string(v));
    };
    if (neighbours < 1) fail("neighbours", neighbours);
    if (sectors < 1) fail("sectors", sectors);
    if (!std::isfinite(corner_threshold_m)) fail("corner_threshold_m", corner_threshold_m);
    if (!std::isfinite(surface_threshold_m)) fail("surface_threshold_m", surface_threshold_m);
    if (!(occlusion_depth_gap_m > 0.0)) fail("occlusion_depth_gap_m", occlusion_depth_gap_m);
    if (!(parallel_beam_ratio > 0.0)) fail("parallel_beam_ratio", parallel_beam_ratio);
    if (!(max_neighbour_gap_rad > 0.0)) fail("max_neighbour_gap_rad", max_neighbour_gap_rad);
    if (std::isnan(surface_leaf_m)) fail("surface_leaf_m", surface_leaf_m);
    if (std::isnan(corner_leaf_m)) fail("corner_leaf_m", corner_leaf_m);
  }
};

/// A feature point set: positions (scan frame), labels (empty when the scan
/// has none) and the index of each point in the input scan (for a
/// voxel-downsampled set -- surfaces, and corners with corner_leaf_m -- the
/// voxel's first point).
struct FeatureSet {
  std::vector<Eigen::Vector3f> points;  ///< scan frame [m]
  std::vector<Class> labels;            ///< per point, or empty
  std::vector<std::uint32_t> indices;   ///< index into the input scan

  /// Number of features.
  [[nodiscard]] std::size_t size() const { return points.size(); }
  /// Empties all fields, keeping capacity.
  void clear() {
    points.clear();
    labels.clear();
    indices.clear();
  }
};

/// Corner and surface features of one scan.
struct LoamFeatures {
  FeatureSet corners;   ///< sharp points (high c)
  FeatureSet surfaces;  ///< flat points (low c), voxel-downsampled
};

/// Counts from one extract() call.
struct LoamFeatureReport {
  std::size_t rings = 0;             ///< rings with enough points for eq. 2
  std::size_t with_curvature = 0;    ///< points with a defined c
  std::size_t occluded = 0;          ///< rejected next to occlusion edges
  std::size_t parallel = 0;          ///< rejected as grazing beams
  std::size_t surfaces_before_voxel = 0;  ///< surface points before downsampling
};

/// Reusable LOAM feature extractor. Not thread-safe (holds buffers); one per thread.
class LoamFeatureExtractor {
 public:
  using Config = LoamFeatureConfig;

  /// Throws ConfigError for invalid settings.
  explicit LoamFeatureExtractor(const Config& config = {})
      : config_(validated(config)),
        voxel_(VoxelGridConfig{.leaf_size_m = config.surface_leaf_m > 0.0 ? config.surface_leaf_m : 1.0,
                               .point = config.surface_point}),
        corner_voxel_(VoxelGridConfig{.leaf_size_m = config.corner_leaf_m > 0.0 ? config.corner_leaf_m : 1.0,
                                      .point = VoxelPoint::kCentroid}) {}

  /// The settings.
  [[nodiscard]] const Config& config() const { return config_; }

  /// Extracts corners and surfaces of scan into out (cleared first). Throws
  /// ValueError when scan has no rings or inconsistent fields.
  LoamFeatureReport extract(const Scan& scan, LoamFeatures& out) {
    scan.validate();
    if (!scan.has_rings() && !scan.empty()) {
      throw ValueError("LoamFeatureExtractor: Scan.rings is empty; infer rings first (rings.hpp)");
    }
    out.corners.clear();
    out.surfaces.clear();
    LoamFeatureReport report;
    const std::size_t n = scan.size();
    curvature_.assign(n, -1.0F);
    group_by_ring(scan);
    reserve_ring_buffers(n);
    surface_idx_.clear();
    for (std::size_t r = 0; r + 1 < ring_begin_.size(); ++r) {
      const std::size_t b = ring_begin_[r];
      const std::size_t e = ring_begin_[r + 1];
      if (e - b < static_cast<std::size_t>(2 * config_.neighbours + 1)) continue;
      ++report.rings;
      process_ring(scan, b, e, report, out);
    }
    std::sort(out.corners.indices.begin(), out.corners.indices.end());
    if (config_.corner_leaf_m > 0.0) {
      corner_idx_.swap(out.corners.indices);
      corner_voxel_.downsample(scan.points, scan.labels, corner_idx_, out.corners.points, out.corners.labels,
                               out.corners.indices);
    } else {
      for (const std::uint32_t i : out.corners.indices) {
        out.corners.points.push_back(scan.points[i]);
        if (scan.has_labels()) out.corners.labels.push_back(scan.labels[i]);
      }
    }
    report.surfaces_before_voxel = surface_idx_.size();
    if (config_.surface_leaf_m > 0.0) {
      voxel_.downsample(scan.points, scan.labels, surface_idx_, out.surfaces.points,
                        out.surfaces.labels, out.surfaces.indices);
    } else {
      std::sort(surface_idx_.begin(), surface_idx_.end());
      for (const std::uint32_t i : surface_idx_) {
        out.surfaces.points.push_back(scan.points[i]);
        out.surfaces.indices.push_back(i);
        if (scan.has_labels()) out.surfaces.labels.push_back(scan.labels[i]);
      }
    }
    return report;
  }

  /// Curvature c (eq. 2) [m] of every point of the last scan, by scan index;
  /// -1 where undefined (ring ends, rings too short).
  [[nodiscard]] const std::vector<float>& curvatures() const { return curvature_; }

  /// True when point i (< size of the last scan) was rejected (occlusion or grazing beam).
  [[nodiscard]] bool rejected(std::size_t i) const { return rejected_[i] != 0; }

 private:
  static const Config& validated(const Config& config) {
    config.validate();
    if (std::isinf(config.surface_leaf_m)) {
      throw ConfigError("LoamFeatureConfig.surface_leaf_m is invalid: inf");
    }
    if (std::isinf(config.corner_leaf_m)) {
      throw ConfigError("LoamFeatureConfig.corner_leaf_m is invalid: inf");
    }
    return config;
  }

  /// Fills order_ (scan indices grouped by ring, ascending azimuth inside
  /// each) and ring_begin_ (offsets into order_).
  void group_by_ring(const Scan& scan) {
    const std::size_t n = scan.size();
    std::size_t rings = 0;
    for (const std::uint16_t r : scan.rings) rings = std::max<std::size_t>(rings, r + 1U);
    // Counting sort by ring, a run of equal rings at a time: a sensor's points
    // come ring by ring (KITTI: 64 runs per scan), and a per-point
    // increment of the same counter in memory chains every point's
    // load-add-store to the previous one (a third of this function's time).
    ring_begin_.assign(rings + 1, 0);
    for (std::size_t i = 0; i < n;) {
      const std::size_t start = i;
      const std::uint16_t r = scan.rings[i];
      while (i < n && scan.rings[i] == r) ++i;
      ring_begin_[r + 1U] += i - start;
    }
    for (std::size_t r = 0; r < rings; ++r) ring_begin_[r + 1] += ring_begin_[r];
    cursor_.assign(ring_begin_.begin(), ring_begin_.end() - 1);
    order_.resize(n);
    for (std::size_t i = 0; i < n;) {
      const std::uint16_t r = scan.rings[i];
      std::size_t at = cursor_[r];
      for (; i < n && scan.rings[i] == r; ++i) order_[at++] = static_cast<std::uint32_t>(i);
      cursor_[r] = at;
    }
    azimuth_.resize(n);
    const auto to_0_2pi = [](double a) { return static_cast<float>(a < 0.0 ? a + 2.0 * std::numbers::pi : a); };
    std::size_t i = 0;
    for (; i + 1 < n; i += 2) {  // two at once: atan2_fast_pair equals two atan2_fast calls
      const Eigen::Vector3f& p = scan.points[i];
      const Eigen::Vector3f& q = scan.points[i + 1];
      const std::array<double, 2> a = atan2_fast_pair(static_cast<double>(p.y()), static_cast<double>(p.x()),
                                                      static_cast<double>(q.y()), static_cast<double>(q.x()));
      azimuth_[i] = to_0_2pi(a[0]);
      azimuth_[i + 1] = to_0_2pi(a[1]);
    }
    if (i < n) {
      azimuth_[i] = to_0_2pi(atan2_fast(static_cast<double>(scan.points[i].y()), static_cast<double>(scan.points[i].x())));
    }
    const auto by_azimuth = [this](std::uint32_t a, std::uint32_t b) {
      return azimuth_[a] < azimuth_[b] || (azimuth_[a] == azimuth_[b] && a < b);
    };
    for (std::size_t r = 0; r < rings; ++r) {
      const auto first = order_.begin() + static_cast<std::ptrdiff_t>(ring_begin_[r]);
      const auto last = order_.begin() + static_cast<std::ptrdiff_t>(ring_begin_[r + 1]);
      // A sensor's ring comes nearly sorted (real KITTI: ~6 out-of-order
      // points per 2 000), where an insertion sort costs O(n + moves) against
      // std::sort's O(n log n); past a budget of moves std::sort finishes the
      // job. The order is a strict total order (ties by index), so both give
      // the one sorted sequence.
      if (!insertion_sort_bounded(first, last, by_azimuth, static_cast<std::size_t>(last - first))) {
        std::sort(first, last, by_azimuth);
      }
    }
    rejected_.assign(n, 0);
  }

  /// Sorts [first, last) by insertion while at most max_moves element moves
  /// suffice; returns false (range partly sorted, a permutation of the input)
  /// when they do not.
  template <typename It, typename Less>
  static bool insertion_sort_bounded(It first, It last, Less less, std::size_t max_moves) {
    std::size_t moves = 0;
    for (It i = first; i != last; ++i) {
      if (i == first || !less(*i, *(i - 1))) continue;
      const auto v = *i;
      It j = i;
      do {
        *j = *(j - 1);
        --j;
        if (++moves > max_moves) {
          *j = v;
          return false;
        }
      } while (j != first && less(v, *(j - 1)));
      *j = v;
    }
    return true;
  }

  /// Sizes the per-ring buffers for the longest ring a scan of n points can
  /// have, n (26 bytes per point): grown ring by ring to the exact length,
  /// they reallocated whenever a later scan had a longer ring, long after
  /// warm-up (3-9 blocks on such frames of a drive). Each is refilled per
  /// ring, so its content may be dropped.
  void reserve_ring_buffers(std::size_t n) {
    reserve_discarding(ring_pts_, n);
    reserve_discarding(ring_az_, n);
    reserve_discarding(range_, n);
    reserve_discarding(ring_c_, n);
    reserve_discarding(ring_rej_, n);
    reserve_discarding(picked_, n);
    reserve_discarding(sector_, n);
    reserve_discarding(surface_idx_, n);  // every sector's surfaces together: at most n
  }

  /// Eq. 2, rejection and selection on the ring order_[b, e). The ring's
  /// points, azimuths, curvatures and flags are first gathered into
  /// contiguous buffers (every pass below then runs without indirection) and
  /// curvatures and flags are scattered back by scan index at the end.
  void process_ring(const Scan& scan, std::size_t b, std::size_t e, LoamFeatureReport& report,
                    LoamFeatures& out) {
    const std::size_t m = e - b;
    const auto h = static_cast<std::size_t>(config_.neighbours);
    ring_pts_.resize(m);
    ring_az_.resize(m);
    range_.resize(m);
    ring_c_.assign(m, -1.0F);
    ring_rej_.assign(m, 0);
    for (std::size_t k = 0; k < m; ++k) {
      const std::uint32_t i = order_[b + k];
      ring_pts_[k] = scan.points[i];
      ring_az_[k] = azimuth_[i];
      range_[k] = ring_pts_[k].norm();
    }
    const auto adjacent = [&](std::size_t k) {  // positions k and k+1
      return static_cast<double>(ring_az_[k + 1] - ring_az_[k]) <= config_.max_neighbour_gap_rad;
    };
    // Eq. 2 with a sliding window: sum_{j in S} (p_i - p_j) = (2h + 1) p_i - W_i,
    // W_i = p_{i-h} + ... + p_{i+h} (double: the cancellation stays exact enough).
    Eigen::Vector3d window = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < 2 * h + 1; ++k) window += ring_pts_[k].cast<double>();
    const auto width = static_cast<double>(2 * h + 1);
    for (std::size_t k = h; k + h < m; ++k) {
      if (k > h) window += ring_pts_[k + h].cast<double>() - ring_pts_[k - h - 1].cast<double>();
      const Eigen::Vector3d pi = ring_pts_[k].cast<double>();
      const double norm = pi.norm();
      const double c = norm > 0.0 ? (width * pi - window).squaredNorm() / ((width - 1.0) * norm) : -1.0;
      ring_c_[k] = std::isfinite(c) ? static_cast<float>(c) : -1.0F;
    }
    report.with_curvature += m - 2 * h;
    // Occlusion and grazing beams (LOAM §V-A, LIO-SAM markOccludedPoints).
    const auto gap = static_cast<float>(config_.occlusion_depth_gap_m);
    for (std::size_t k = h; k + h < m; ++k) {
      if (k + 1 < m && adjacent(k)) {
        if (range_[k] - range_[k + 1] > gap) {
          for (std::size_t j = 0; j <= h && j <= k; ++j) ring_rej_[k - j] |= 1U;
        } else if (range_[k + 1] - range_[k] > gap) {
          for (std::size_t j = 1; j <= h + 1 && k + j < m; ++j) ring_rej_[k + j] |= 1U;
        }
      }
      const float tol = static_cast<float>(config_.parallel_beam_ratio) * range_[k];
      if (std::abs(range_[k - 1] - range_[k]) > tol && std::abs(range_[k + 1] - range_[k]) > tol) {
        ring_rej_[k] |= 2U;
      }
    }
    // Selection per sector (positions h .. m-h-1).
    picked_.assign(m, 0);
    const std::size_t valid = m - 2 * h;
    const auto sectors = static_cast<std::size_t>(config_.sectors);
    const auto corner_threshold = config_.corner_threshold_m;
    const auto surface_threshold = config_.surface_threshold_m;
    for (std::size_t s = 0; s < sectors; ++s) {
      const std::size_t sp = h + valid * s / sectors;
      const std::size_t ep = h + valid * (s + 1) / sectors;
      if (ep <= sp) continue;
      // Corner candidates (about a tenth of the points; rejected points can
      // never be taken) are visited sharpest first, ties by position. A heap
      // hands them out in that order for O(n + visited log n) instead of
      // sorting all of them: the cap is usually reached long before the end.
      // Branch-free filters (write always, advance on the condition): about
      // one point in ten is a corner candidate, a branch on it mispredicts.
      sector_.resize(ep - sp);  // reserved: no allocation
      std::size_t candidates = 0;
      for (std::size_t k = sp; k < ep; ++k) {
        sector_[candidates] = static_cast<std::uint32_t>(k);
        candidates += static_cast<std::size_t>(static_cast<double>(ring_c_[k]) > corner_threshold) &
                      static_cast<std::size_t>(ring_rej_[k] == 0);
      }
      sector_.resize(candidates);
      const auto after = [&](std::uint32_t x, std::uint32_t y) {  // y comes before x
        const float cx = ring_c_[x];
        const float cy = ring_c_[y];
        return cy > cx || (cy == cx && y < x);
      };
      std::make_heap(sector_.begin(), sector_.end(), after);
      std::size_t taken = 0;
      for (auto heap_end = sector_.end(); heap_end != sector_.begin(); --heap_end) {
        if (taken >= config_.max_corners_per_sector) break;
        std::pop_heap(sector_.begin(), heap_end, after);
        const std::uint32_t k = *(heap_end - 1);
        if (picked_[k] != 0) continue;
        out.corners.indices.push_back(order_[b + k]);
        ++taken;
        picked_[k] = 1;
        for (std::size_t j = 1; j <= h && k + j < m && adjacent(k + j - 1); ++j) picked_[k + j] = 1;
        for (std::size_t j = 1; j <= h && j <= k && adjacent(k - j); ++j) picked_[k - j] = 1;
      }
      const std::size_t first_surface = surface_idx_.size();
      surface_idx_.resize(first_surface + (ep - sp));  // reserved: no allocation
      std::size_t surfaces = first_surface;
      for (std::size_t k = sp; k < ep; ++k) {
        const float c = ring_c_[k];
        surface_idx_[surfaces] = order_[b + k];
        surfaces += static_cast<std::size_t>(picked_[k] == 0) & static_cast<std::size_t>(ring_rej_[k] == 0) &
                    static_cast<std::size_t>(c >= 0.0F) &
                    static_cast<std::size_t>(static_cast<double>(c) < surface_threshold);
      }
      surface_idx_.resize(surfaces);
    }
    // Scatter back, counting the rejections (branch-free: occluded wins).
    std::size_t occluded = 0;
    std::size_t parallel = 0;
    for (std::size_t k = 0; k < m; ++k) {
      const std::uint32_t i = order_[b + k];
      const std::uint8_t f = ring_rej_[k];
      curvature_[i] = ring_c_[k];
      rejected_[i] = f;
      occluded += f & 1U;
      parallel += (f >> 1U) & ~f & 1U;
    }
    report.occluded += occluded;
    report.parallel += parallel;
  }

  Config config_;
  VoxelGrid voxel_;
  VoxelGrid corner_voxel_;
  std::vector<float> curvature_;
  std::vector<std::uint8_t> rejected_;
  std::vector<float> azimuth_;
  std::vector<std::uint32_t> order_;
  std::vector<std::size_t> ring_begin_;
  std::vector<std::size_t> cursor_;
  std::vector<float> range_;
  std::vector<Eigen::Vector3f> ring_pts_;  // one ring's points in azimuth order
  std::vector<float> ring_az_;             // their azimuths
  std::vector<float> ring_c_;              // their curvatures (-1: undefined)
  std::vector<std::uint8_t> ring_rej_;     // their rejection flags (1 occluded, 2 grazing)
  std::vector<std::uint8_t> picked_;
  std::vector<std::uint32_t> sector_;
  std::vector<std::uint32_t> surface_idx_;
  std::vector<std::uint32_t> corner_idx_;  // corners before the voxel (swap buffer)
};

}  // namespace semlio
