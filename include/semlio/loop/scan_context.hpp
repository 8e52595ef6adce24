#pragma once
/// \file
/// Scan Context (Kim & Kim, IROS 2018), written from the paper's description:
/// a polar, egocentric place descriptor and a detector built on it.
///
/// Descriptor: the lidar-frame cloud within max_radius_m is binned into
/// `rings` equal radial rings x `sectors` equal azimuth sectors (sector 0
/// starts at azimuth -pi). Each bin stores the largest height of its points
/// above an assumed ground, z + lidar_height_m (clamped at 0; empty bins are
/// 0), so the value does not depend on the point density. A yaw rotation of
/// the sensor shifts the columns (sectors) circularly and leaves every ring
/// the same.
///
/// Ring key: the mean of each ring (row) -- rotation invariant, so an L2
/// search over ring keys picks a short list of candidates cheaply.
///
/// Distance: for each circular column shift s, the mean over columns j where
/// both are non-empty of 1 - cos(query column j, candidate column j + s); the
/// distance is the minimum over s (0 = same, 1 = unrelated, up to 2). The
/// best shift gives the yaw of the query in the candidate frame:
/// yaw = s * 2 pi / sectors (a query point at azimuth a appears in the
/// candidate frame at a + yaw), within half a sector (3 deg at 60 sectors).
///
/// Defaults (the paper's): 20 rings, 60 sectors, 80 m; 10 ring-key
/// candidates; accept distance 0.2 (Kim & Kim report 0.1..0.2 on KITTI;
/// SC-LeGO-LOAM uses 0.2, with geometric verification behind it as here).

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/lie/so3.hpp>
#include <semlio/loop/loop_detector.hpp>
#include <semlio/loop/loop_keyframe.hpp>

namespace semlio {

/// Settings of Scan Context descriptors and of ScanContextDetector.
struct ScanContextConfig {
  int rings = 20;                          ///< radial bins
  int sectors = 60;                        ///< azimuth bins (6 deg each)
  double max_radius_m = 80.0;              ///< points beyond this range are ignored [m]
  double lidar_height_m = 2.0;             ///< added to z so that the ground is above 0 (KITTI lidar: 1.73 m) [m]
  double min_time_gap_s = 30.0;            ///< candidates older than the query by more than this [s]
  std::size_t ring_key_candidates = 10;    ///< nearest ring keys compared with the full distance
  double max_distance = 0.2;               ///< candidates with a descriptor distance below this
  std::size_t max_candidates = 3;          ///< at most this many candidates, best first

  /// Throws ConfigError naming the bad field and value.
  void validate() const {
    if (rings < 1) throw ConfigError("ScanContextConfig.rings = " + std::to_string(rings) + ", expected >= 1");
    if (sectors < 2) throw ConfigError("ScanContextConfig.sectors = " + std::to_string(sectors) + ", expected >= 2");
    if (!(max_radius_m > 0.0) || !std::isfinite(max_radius_m)) {
      throw ConfigError("ScanContextConfig.max_radius_m = " + std::to_string(max_radius_m) + ", expected > 0");
    }
    if (!std::isfinite(lidar_height_m)) {
      throw ConfigError("ScanContextConfig.lidar_height_m = " + std::to_string(lidar_height_m) + ", expected finite");
    }
    if (!(min_time_gap_s >= 0.0) || !std::isfinite(min_time_gap_s)) {
      throw ConfigError("ScanContextConfig.min_time_gap_s = " + std::to_string(min_time_gap_s) + ", expected >= 0");
    }
    if (!(max_distance >= 0.0)) {
      throw ConfigError("ScanContextConfig.max_distance = " + std::to_string(max_distance) + ", expected >= 0");
    }
  }
};

/// One Scan Context descriptor: rings x sectors bins (row = ring) and its ring key.
struct ScanContext {
  int rings = 0;                    ///< rows
  int sectors = 0;                  ///< columns
  std::vector<float> bins;          ///< row-major, rings * sectors; max height above ground [m], 0 = empty
  std::vector<float> ring_key;      ///< mean of each row [m]
  std::vector<float> column_norm;   ///< L2 norm of each column (0 = empty column)

  /// Bin value of ring r, sector s.
  [[nodiscard]] float at(int r, int s) const {
    return bins[static_cast<std::size_t>(r) * static_cast<std::size_t>(sectors) + static_cast<std::size_t>(s)];
  }
};

/// The descriptor of a lidar-frame cloud (config validated by the caller).
inline ScanContext make_scan_context(const std::vector<Eigen::Vector3f>& cloud, const ScanContextConfig& config) {
  ScanContext sc;
  sc.rings = config.rings;
  sc.sectors = config.sectors;
  const auto R = static_cast<std::size_t>(config.rings);
  const auto S = static_cast<std::size_t>(config.sectors);
  sc.bins.assign(R * S, 0.0F);
  const double ring_per_m = static_cast<double>(config.rings) / config.max_radius_m;
  const double sector_per_rad = static_cast<double>(config.sectors) / (2.0 * std::numbers::pi);
  for (const Eigen::Vector3f& p : cloud) {
    if (!p.allFinite()) continue;
    const double x = static_cast<double>(p.x());
    const double y = static_cast<double>(p.y());
    const double r = std::hypot(x, y);
    if (!(r < config.max_radius_m) || r <= 0.0) continue;
    const auto ring = std::min(R - 1, static_cast<std::size_t>(r * ring_per_m));
    const auto sector = std::min(S - 1, static_cast<std::size_t>((std::atan2(y, x) + std::numbers::pi) * sector_per_rad));
    const float h = static_cast<float>(std::max(0.0, static_cast<double>(p.z()) + config.lidar_height_m));
    float& bin = sc.bins[ring * S + sector];
    bin = std::max(bin, h);
  }
  sc.ring_key.assign(R, 0.0F);
  sc.column_norm.assign(S, 0.0F);
  for (std::size_t r = 0; r < R; ++r) {
    double sum = 0.0;
    for (std::size_t s = 0; s < S; ++s) sum += static_cast<double>(sc.bins[r * S + s]);
    sc.ring_key[r] = static_cast<float>(sum / static_cast<double>(S));
  }
  for (std::size_t s = 0; s < S; ++s) {
    double sq = 0.0;
    for (std::size_t r = 0; r < R; ++r) sq += static_cast<double>(sc.bins[r * S + s]) * static_cast<double>(sc.bins[r * S + s]);
    sc.column_norm[s] = static_cast<float>(std::sqrt(sq));
  }
  return sc;
}

/// Distance of two descriptors and the best circular column shift.
struct ScanContextMatch {
  double distance = 1.0;  ///< 0 = same, 1 = unrelated (up to 2)
  int shift = 0;          ///< query column j matches candidate column (j + shift) mod sectors
};

/// Column-shift distance of query against candidate (same shape; else distance 1).
inline ScanContextMatch scan_context_distance(const ScanContext& query, const ScanContext& candidate) {
  ScanContextMatch best;
  best.distance = 2.0;
  if (query.rings != candidate.rings || query.sectors != candidate.sectors || query.sectors == 0) {
    best.distance = 1.0;
    return best;
  }
  const int S = query.sectors;
  const int R = query.rings;
  for (int shift = 0; shift < S; ++shift) {
    double sum = 0.0;
    int used = 0;
    for (int j = 0; j < S; ++j) {
      const int k = (j + shift) % S;
      const float na = query.column_norm[static_cast<std::size_t>(j)];
      const float nb = candidate.column_norm[static_cast<std::size_t>(k)];
      if (na <= 0.0F || nb <= 0.0F) continue;
      double dot = 0.0;
      for (int r = 0; r < R; ++r) dot += static_cast<double>(query.at(r, j)) * static_cast<double>(candidate.at(r, k));
      sum += 1.0 - dot / (static_cast<double>(na) * static_cast<double>(nb));
      ++used;
    }
    const double d = used == 0 ? 1.0 : sum / static_cast<double>(used);
    if (d < best.distance) {
      best.distance = d;
      best.shift = shift;
    }
  }
  return best;
}

/// The yaw [rad, (-pi, pi]] of a column shift: the query's rotation in the candidate frame.
inline double scan_context_yaw(int shift, int sectors) {
  double yaw = 2.0 * std::numbers::pi * static_cast<double>(shift) / static_cast<double>(sectors);
  if (yaw > std::numbers::pi) yaw -= 2.0 * std::numbers::pi;
  return yaw;
}

/// Scan Context loop detector: caches one descriptor per keyframe (computed
/// from LoopKeyframe::cloud when first seen), ring-key short list over the
/// keyframes older than the time gap, full column-shift distance on the short
/// list; candidates below max_distance, best first, with the guess T_from_to
/// = rotation about z by the shift's yaw, zero translation. Keyframes that a
/// bounded store archived (LoopKeyframe::archived: a kept place within the
/// store's place spacing stands for them) are no candidates, and their
/// descriptors are freed (~5 kB each at 20 x 60), so the cache grows by a
/// fixed-size record per keyframe only. Not thread-safe.
class ScanContextDetector {
 public:
  using Config = ScanContextConfig;

  /// Default settings (implicit, so that `Detector detector = {}` works).
  ScanContextDetector() : ScanContextDetector(Config{}) {}
  /// Validates the settings (ConfigError naming the field and value).
  explicit ScanContextDetector(const Config& config) : config_(config) { config_.validate(); }

  /// Candidates for keyframes.back(), best first, into out (cleared).
  void detect(const std::vector<LoopKeyframe>& keyframes, std::vector<LoopCandidate>& out) {
    out.clear();
    if (keyframes.size() < descriptors_.size()) descriptors_.clear();  // a different keyframe list: start over
    while (descriptors_.size() < keyframes.size()) {
      descriptors_.push_back(make_scan_context(keyframes[descriptors_.size()].cloud, config_));
    }
    if (keyframes.size() < 2 || config_.max_candidates == 0) return;
    const std::size_t query = keyframes.size() - 1;
    const ScanContext& q = descriptors_[query];
    // Ring-key short list (L2), among keyframes older than the time gap.
    shortlist_.clear();
    for (std::size_t i = 0; i < query; ++i) {
      if (keyframes[i].archived) {
        if (!descriptors_[i].bins.empty()) descriptors_[i] = ScanContext{};
        continue;
      }
      if (!(keyframes[query].stamp_s - keyframes[i].stamp_s > config_.min_time_gap_s)) continue;
      double d2 = 0.0;
      for (std::size_t r = 0; r < q.ring_key.size(); ++r) {
        const double d = static_cast<double>(q.ring_key[r]) - static_cast<double>(descriptors_[i].ring_key[r]);
        d2 += d * d;
      }
      shortlist_.emplace_back(d2, i);
    }
    const std::size_t keep = std::min(shortlist_.size(), config_.ring_key_candidates);
    std::partial_sort(shortlist_.begin(), shortlist_.begin() + static_cast<std::ptrdiff_t>(keep), shortlist_.end());
    for (std::size_t k = 0; k < keep; ++k) {
      const std::size_t i = shortlist_[k].second;
      const ScanContextMatch m = scan_context_distance(q, descriptors_[i]);
      if (!(m.distance < config_.max_distance)) continue;
      const double yaw = scan_context_yaw(m.shift, config_.sectors);
      out.push_back(LoopCandidate{i, SE3d(SO3d::exp(Eigen::Vector3d(0.0, 0.0, yaw)), Eigen::Vector3d::Zero()),
                                  m.distance});
    }
    std::stable_sort(out.begin(), out.end(),
                     [](const LoopCandidate& a, const LoopCandidate& b) { return a.score < b.score; });
    if (out.size() > config_.max_candidates) out.resize(config_.max_candidates);
  }

  /// The cached descriptor of keyframe i (after a detect() that saw it; empty
  /// once the keyframe is archived).
  [[nodiscard]] const ScanContext& descriptor(std::size_t i) const { return descriptors_.at(i); }
  /// Number of cached descriptors.
  [[nodiscard]] std::size_t descriptor_count() const noexcept { return descriptors_.size(); }
  /// The settings.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

 private:
  Config config_;
  std::vector<ScanContext> descriptors_;
  std::vector<std::pair<double, std::size_t>> shortlist_;
};

static_assert(LoopDetector<ScanContextDetector>);

}  // namespace semlio
