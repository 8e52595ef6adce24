#pragma once
/// \file
/// The KITTI odometry metric as the official devkit (evaluate_odometry.cpp)
/// computes it:
/// - distances d_i along the ground truth from consecutive positions
///   (d_0 = 0, d_i = d_{i-1} + |t_i - t_{i-1}|);
/// - segments of 100, 200, ..., 800 m starting at frames 0, 10, 20, ...
///   (step 10); the last frame of a segment is the first frame i >= first
///   with d_i > d_first + length; segments running past the end are skipped;
/// - error pose E = (P_est_first^-1 P_est_last)^-1 (P_gt_first^-1 P_gt_last);
/// - rotation error acos(max(min(0.5 (trace(R_E) - 1), 1), -1)) / length
///   [rad/m], translation error |t_E| / length [m/m];
/// - the sequence result is the plain mean over all segments of all lengths.
/// E and its inverse (the order some write-ups use) have the same angle and
/// translation norm, so both orders give identical numbers.
/// Deviation from the devkit: it computes in float, semlio in double (the
/// segment choice can differ only when a distance ties a threshold to float
/// precision).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::eval {

/// Segment scheme of the metric; defaults are the devkit's.
struct KittiMetricConfig {
  std::vector<double> lengths_m{100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0};  ///< segment lengths [m], > 0
  std::size_t step_frames = 10;  ///< a segment starts every step_frames frames, >= 1
};

/// One evaluated segment.
struct KittiSegment {
  std::size_t first_frame = 0;           ///< index of the first pose
  std::size_t last_frame = 0;            ///< index of the last pose
  double length_m = 0.0;                 ///< nominal segment length [m]
  double translation_error = 0.0;        ///< |t_E| / length [m/m]
  double rotation_error_rad_per_m = 0.0; ///< angle(R_E) / length [rad/m]
};

/// Mean errors of the segments of one length (the devkit's per-length plots).
struct KittiLengthStats {
  double length_m = 0.0;                    ///< nominal length [m]
  std::size_t count = 0;                    ///< segments of this length
  double translation_error_pct = 0.0;       ///< mean translation error [%]
  double rotation_error_deg_per_100m = 0.0; ///< mean rotation error [deg/100 m]
};

/// Outcome of the metric.
enum class KittiMetricStatus {
  kOk,          ///< at least one segment fits the trajectory
  kNoSegments,  ///< trajectory shorter than the shortest length: all errors 0
};

/// The KITTI odometry metric of one sequence.
struct KittiMetricReport {
  KittiMetricStatus status = KittiMetricStatus::kNoSegments;  ///< whether any segment was evaluated
  std::size_t segment_count = 0;             ///< segments over all lengths
  double translation_error = 0.0;            ///< mean |t_E| / length [m/m] (the devkit's raw number)
  double translation_error_pct = 0.0;        ///< the same in percent
  double rotation_error_rad_per_m = 0.0;     ///< mean rotation error [rad/m] (devkit's raw number)
  double rotation_error_deg_per_m = 0.0;     ///< the same in deg/m
  double rotation_error_deg_per_100m = 0.0;  ///< the same in deg/100 m
  std::vector<KittiSegment> segments;        ///< every segment, by first frame then length
  std::vector<KittiLengthStats> per_length;  ///< one entry per configured length with count > 0
};

/// Cumulative distance d_i along the trajectory positions [m], d_0 = 0.
inline std::vector<double> trajectory_distances_m(const std::vector<SE3d>& poses) {
  std::vector<double> d;
  d.reserve(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    d.push_back(i == 0 ? 0.0 : d.back() + (poses[i].translation() - poses[i - 1].translation()).norm());
  }
  return d;
}

namespace detail {

// The devkit's lastFrameFromSegmentLength: first i >= first with
// d_i > d_first + length; d.size() when there is none.
inline std::size_t kitti_last_frame(const std::vector<double>& d, std::size_t first, double length_m) {
  for (std::size_t i = first; i < d.size(); ++i) {
    if (d[i] > d[first] + length_m) return i;
  }
  return d.size();
}

inline void validate(const KittiMetricConfig& c) {
  if (c.step_frames == 0) throw ConfigError("KittiMetricConfig.step_frames is 0, must be >= 1");
  if (c.lengths_m.empty()) throw ConfigError("KittiMetricConfig.lengths_m is empty");
  for (const double len : c.lengths_m) {
    if (!(std::isfinite(len) && len > 0.0)) {
      throw ConfigError("KittiMetricConfig.lengths_m holds " + std::to_string(len) + ", must be > 0 and finite");
    }
  }
}

}  // namespace detail

/// Scores an estimated trajectory against ground truth with the KITTI
/// odometry metric; est[i] and gt[i] are the same frame, both mapping the
/// frame-i sensor into the frame-0 sensor (camera 0 for the official
/// scores). Throws ValueError when the sizes differ and ConfigError on a bad
/// config. Thread-safe (pure function).
inline KittiMetricReport kitti_metric(const std::vector<SE3d>& gt, const std::vector<SE3d>& est,
                                      const KittiMetricConfig& config = {}) {
  detail::validate(config);
  if (gt.size() != est.size()) {
    throw ValueError("kitti_metric: estimate has " + std::to_string(est.size()) + " poses but ground truth has " +
                     std::to_string(gt.size()));
  }
  KittiMetricReport r;
  const std::vector<double> d = trajectory_distances_m(gt);
  std::vector<KittiLengthStats> stats(config.lengths_m.size());
  for (std::size_t first = 0; first < gt.size(); first += config.step_frames) {
    for (std::size_t k = 0; k < config.lengths_m.size(); ++k) {
      const double len = config.lengths_m[k];
      const std::size_t last = detail::kitti_last_frame(d, first, len);
      if (last == d.size()) continue;
      const SE3d delta_gt = gt[first].inverse() * gt[last];
      const SE3d delta_est = est[first].inverse() * est[last];
      const SE3d E = delta_est.inverse() * delta_gt;
      const double c = 0.5 * (E.rotation().trace() - 1.0);
      KittiSegment s;
      s.first_frame = first;
      s.last_frame = last;
      s.length_m = len;
      s.rotation_error_rad_per_m = std::acos(std::max(std::min(c, 1.0), -1.0)) / len;
      s.translation_error = E.translation().norm() / len;
      r.segments.push_back(s);
      stats[k].count += 1;
      stats[k].translation_error_pct += s.translation_error;
      stats[k].rotation_error_deg_per_100m += s.rotation_error_rad_per_m;
    }
  }
  constexpr double kDegPerRad = 180.0 / std::numbers::pi;
  r.segment_count = r.segments.size();
  if (r.segment_count == 0) return r;
  r.status = KittiMetricStatus::kOk;
  for (const KittiSegment& s : r.segments) {
    r.translation_error += s.translation_error;
    r.rotation_error_rad_per_m += s.rotation_error_rad_per_m;
  }
  const auto n = static_cast<double>(r.segment_count);
  r.translation_error /= n;
  r.rotation_error_rad_per_m /= n;
  r.translation_error_pct = 100.0 * r.translation_error;
  r.rotation_error_deg_per_m = kDegPerRad * r.rotation_error_rad_per_m;
  r.rotation_error_deg_per_100m = 100.0 * r.rotation_error_deg_per_m;
  for (std::size_t k = 0; k < stats.size(); ++k) {
    if (stats[k].count == 0) continue;
    KittiLengthStats s = stats[k];
    const auto m = static_cast<double>(s.count);
    s.length_m = config.lengths_m[k];
    s.translation_error_pct = 100.0 * s.translation_error_pct / m;          // summed m/m so far
    s.rotation_error_deg_per_100m = 100.0 * kDegPerRad * s.rotation_error_deg_per_100m / m;  // summed rad/m so far
    r.per_length.push_back(s);
  }
  return r;
}

}  // namespace semlio::eval
