#pragma once
/// \file
/// Absolute trajectory error (ATE, paper §4): position error of each
/// estimated pose against ground truth after a least-squares alignment
/// (SE(3) by default, Sim(3) or none as options), summarised as RMSE, mean,
/// median and max. Over all frames or a subset (e.g. the keyframes); with a
/// subset the alignment is fitted on the subset only.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/eval/umeyama.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::eval {

/// Options of the ATE.
struct AteConfig {
  Alignment alignment = Alignment::kSE3;  ///< transform fitted before measuring
};

/// ATE summary. Errors are Euclidean distances between ground-truth and
/// aligned estimated positions [m].
struct AteReport {
  std::size_t count = 0;      ///< number of poses evaluated
  double rmse_m = 0.0;        ///< sqrt(mean of squared errors)
  double mean_m = 0.0;        ///< mean error
  double median_m = 0.0;      ///< median error (mean of the two middle values for an even count)
  double max_m = 0.0;         ///< largest error
  AlignmentResult alignment;  ///< the fitted transform (identity for kNone)
  std::vector<double> errors_m;  ///< error per evaluated pose, in evaluation order
};

/// ATE of estimated positions against ground-truth positions (same order).
/// Throws ValueError on size mismatch or empty input. Thread-safe.
inline AteReport ate_positions(const std::vector<Eigen::Vector3d>& p_gt, const std::vector<Eigen::Vector3d>& p_est,
                               const AteConfig& config = {}) {
  AteReport r;
  r.alignment = umeyama(p_est, p_gt, config.alignment);  // validates sizes
  r.count = p_gt.size();
  r.errors_m.reserve(r.count);
  double sum = 0.0;
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < r.count; ++i) {
    const double e = (p_gt[i] - r.alignment.apply(p_est[i])).norm();
    r.errors_m.push_back(e);
    sum += e;
    sum_sq += e * e;
    r.max_m = std::max(r.max_m, e);
  }
  const auto n = static_cast<double>(r.count);
  r.mean_m = sum / n;
  r.rmse_m = std::sqrt(sum_sq / n);
  std::vector<double> sorted = r.errors_m;
  std::sort(sorted.begin(), sorted.end());
  const std::size_t mid = r.count / 2;
  r.median_m = (r.count % 2 == 1) ? sorted[mid] : 0.5 * (sorted[mid - 1] + sorted[mid]);
  return r;
}

/// ATE over the frames listed in `subset` (indices into both trajectories,
/// used in the given order; duplicates count twice). The alignment is fitted
/// on these frames only. Throws ValueError on size mismatch, an empty subset
/// or an index out of range (naming it). Thread-safe.
inline AteReport ate(const std::vector<SE3d>& gt, const std::vector<SE3d>& est, const std::vector<std::size_t>& subset,
                     const AteConfig& config = {}) {
  if (gt.size() != est.size()) {
    throw ValueError("ate: estimate has " + std::to_string(est.size()) + " poses but ground truth has " +
                     std::to_string(gt.size()));
  }
  std::vector<Eigen::Vector3d> p_gt;
  std::vector<Eigen::Vector3d> p_est;
  p_gt.reserve(subset.size());
  p_est.reserve(subset.size());
  for (const std::size_t i : subset) {
    if (i >= gt.size()) {
      throw ValueError("ate: subset index " + std::to_string(i) + " is out of range (" + std::to_string(gt.size()) +
                       " poses)");
    }
    p_gt.push_back(gt[i].translation());
    p_est.push_back(est[i].translation());
  }
  return ate_positions(p_gt, p_est, config);
}

/// ATE over all frames: gt[i] and est[i] are the same frame. Throws
/// ValueError on size mismatch or empty input. Thread-safe.
inline AteReport ate(const std::vector<SE3d>& gt, const std::vector<SE3d>& est, const AteConfig& config = {}) {
  std::vector<std::size_t> all(gt.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  return ate(gt, est, all, config);
}

}  // namespace semlio::eval
