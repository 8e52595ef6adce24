#pragma once
/// \file
/// End-point error: how far the last pose of a run is from where ground truth
/// puts it, both taken relative to their own first pose (the relative pose
/// error between the first and the last frame). No alignment is fitted, so
/// this is the drift a user sees at the end of a drive; short real drives
/// report it next to the ATE because an aligned ATE can hide a heading drift
/// that the fit rotates away.

#include <cstddef>
#include <numbers>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio::eval {

/// Error of the last pose relative to the first, against ground truth.
struct EndPointError {
  double translation_m = 0.0;   ///< |t| of (gt_0^-1 gt_n)^-1 (est_0^-1 est_n) [m]
  double rotation_deg = 0.0;    ///< rotation angle of the same transform [deg]
};

/// End-point error of `est` against `gt` (same frames, same order, >= 1 pose).
inline EndPointError end_point_error(const std::vector<SE3d>& gt, const std::vector<SE3d>& est) {
  if (gt.empty() || gt.size() != est.size()) {
    throw ValueError("end_point_error: " + std::to_string(gt.size()) + " ground-truth and " +
                     std::to_string(est.size()) + " estimated poses (need the same number, at least one)");
  }
  const SE3d rel_gt = gt.front().inverse() * gt.back();
  const SE3d rel_est = est.front().inverse() * est.back();
  const SE3d e = rel_gt.inverse() * rel_est;
  return {e.translation().norm(), e.so3().angle() * 180.0 / std::numbers::pi};
}

}  // namespace semlio::eval
