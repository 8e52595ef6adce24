#pragma once
/// \file
/// Matching timestamped estimates (e.g. a TUM trajectory) to ground-truth
/// frames by time: each frame takes the nearest stamp within a tolerance.

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>

namespace semlio::eval {

/// Marks a frame without a stamp within the tolerance.
inline constexpr std::ptrdiff_t kNoMatch = -1;

/// For each frame time frame_times_s[i], the index of the stamp in stamps_s
/// nearest to it when |dt| <= max_dt_s, else kNoMatch. Ties go to the later
/// stamp; one stamp may serve several frames when max_dt_s exceeds half the
/// frame spacing. Both inputs must be non-decreasing; throws ValueError
/// (naming the index and values) when they are not, or when max_dt_s is
/// negative or NaN. O(frames + stamps). Thread-safe.
inline std::vector<std::ptrdiff_t> match_nearest_stamps(const std::vector<double>& frame_times_s,
                                                        const std::vector<double>& stamps_s, double max_dt_s) {
  if (!(max_dt_s >= 0.0)) throw ValueError("match_nearest_stamps: max_dt_s is " + std::to_string(max_dt_s) + ", must be >= 0");
  const auto check_sorted = [](const std::vector<double>& v, const char* name) {
    for (std::size_t i = 1; i < v.size(); ++i) {
      if (!(v[i] >= v[i - 1])) {
        throw ValueError(std::string("match_nearest_stamps: ") + name + "[" + std::to_string(i) + "] = " +
                         std::to_string(v[i]) + " is before the previous " + std::to_string(v[i - 1]));
      }
    }
  };
  check_sorted(frame_times_s, "frame_times_s");
  check_sorted(stamps_s, "stamps_s");
  std::vector<std::ptrdiff_t> match(frame_times_s.size(), kNoMatch);
  if (stamps_s.empty()) return match;
  std::size_t j = 0;
  for (std::size_t i = 0; i < frame_times_s.size(); ++i) {
    const double t = frame_times_s[i];
    // Distances to t fall then rise along the sorted stamps: walk while not farther.
    while (j + 1 < stamps_s.size() && std::abs(stamps_s[j + 1] - t) <= std::abs(stamps_s[j] - t)) ++j;
    if (std::abs(stamps_s[j] - t) <= max_dt_s) match[i] = static_cast<std::ptrdiff_t>(j);
  }
  return match;
}

}  // namespace semlio::eval
