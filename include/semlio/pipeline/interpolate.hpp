#pragma once
/// \file
/// Poses for frames the odometry skipped (min_frame_interval_s): each skipped
/// frame gets the pose interpolated on SE(3) at its stamp between the nearest
/// processed frames before and after it, so every output has one pose per
/// input frame.

#include <cstddef>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/lie/se3.hpp>

namespace semlio {

/// T_a exp(s log(T_a^-1 T_b)): constant-twist interpolation, s in [0, 1].
inline SE3d interpolate(const SE3d& T_a, const SE3d& T_b, double s) {
  return T_a * SE3d::exp(s * (T_a.inverse() * T_b).log());
}

/// Replaces poses[i] where processed[i] is false by the interpolation (by
/// stamp) between the processed neighbours; before the first or after the last
/// processed frame the nearest processed pose's constant-velocity
/// extrapolation is kept as given. Throws ValueError on size mismatch.
inline void fill_skipped_poses(std::vector<SE3d>& poses, const std::vector<double>& stamps_s,
                               const std::vector<bool>& processed) {
  if (poses.size() != stamps_s.size() || poses.size() != processed.size()) {
    throw ValueError("fill_skipped_poses: " + std::to_string(poses.size()) + " poses, " +
                     std::to_string(stamps_s.size()) + " stamps, " + std::to_string(processed.size()) +
                     " flags");
  }
  std::size_t prev = poses.size();  // none yet
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (!processed[i]) continue;
    if (prev != poses.size() && i > prev + 1) {
      const double span = stamps_s[i] - stamps_s[prev];
      for (std::size_t j = prev + 1; j < i; ++j) {
        const double s = span > 0.0 ? (stamps_s[j] - stamps_s[prev]) / span
                                    : static_cast<double>(j - prev) / static_cast<double>(i - prev);
        poses[j] = interpolate(poses[prev], poses[i], s);
      }
    }
    prev = i;
  }
}

}  // namespace semlio
