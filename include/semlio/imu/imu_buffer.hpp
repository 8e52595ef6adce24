#pragma once
/// \file
/// IMU stream validation and a time-ordered sample buffer. Preintegration and
/// deskewing both need "the samples that cover [t_begin, t_end]", checked for
/// ordering and gaps; this is the one place that check lives.
///
/// Bad input is a semlio::ValueError whose message names the offending sample
/// indices and stamps (the caller decides whether to fall back to lidar-only).

#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/imu/imu_sample.hpp>

namespace semlio {

/// Indices of the samples that bracket a time window: samples[first].stamp_s
/// <= t_begin and samples[last].stamp_s >= t_end, first <= last.
struct ImuRange {
  std::size_t first = 0;  ///< last sample at or before the window start
  std::size_t last = 0;   ///< first sample at or after the window end
};

namespace detail {

inline std::string imu_time(double t_s) { return std::to_string(t_s) + " s"; }

}  // namespace detail

/// Finds the samples covering [t_begin_s, t_end_s] and validates them.
/// Throws ValueError when: the window is reversed or not finite; there are no
/// samples; a stamp is not finite or not strictly after its predecessor (time
/// going backwards or repeated; the whole span is checked); the samples do not
/// cover the window; two consecutive samples inside the covering range are
/// more than max_gap_s apart; a sample in that range has a non-finite value.
/// (A typed error rather than a status: the caller — e.g. the lidar-inertial
/// front end — catches it and falls back to lidar-only for that sweep.) `who` prefixes the message (e.g. "ImuPreintegration").
inline ImuRange find_imu_range(std::span<const ImuSample> samples, double t_begin_s, double t_end_s,
                               double max_gap_s, const std::string& who) {
  if (!std::isfinite(t_begin_s) || !std::isfinite(t_end_s) || t_end_s < t_begin_s) {
    throw ValueError(who + ": window [" + detail::imu_time(t_begin_s) + ", " + detail::imu_time(t_end_s) +
                     "] is reversed or not finite");
  }
  if (samples.empty()) {
    throw ValueError(who + ": no IMU samples for the window [" + detail::imu_time(t_begin_s) + ", " +
                     detail::imu_time(t_end_s) + "]");
  }
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const double t = samples[k].stamp_s;
    if (!std::isfinite(t)) {
      throw ValueError(who + ": IMU sample " + std::to_string(k) + " has a non-finite stamp");
    }
    if (k > 0 && !(t > samples[k - 1].stamp_s)) {
      throw ValueError(who + ": IMU time goes backwards: sample " + std::to_string(k) + " at " +
                       detail::imu_time(t) + " is not after sample " + std::to_string(k - 1) + " at " +
                       detail::imu_time(samples[k - 1].stamp_s));
    }
  }
  if (samples.front().stamp_s > t_begin_s || samples.back().stamp_s < t_end_s) {
    throw ValueError(who + ": IMU samples [" + detail::imu_time(samples.front().stamp_s) + ", " +
                     detail::imu_time(samples.back().stamp_s) + "] (samples 0.." +
                     std::to_string(samples.size() - 1) + ") do not cover the window [" +
                     detail::imu_time(t_begin_s) + ", " + detail::imu_time(t_end_s) + "]");
  }
  ImuRange r;
  // Sorted stamps: binary searches are valid now.
  std::size_t lo = 0;
  std::size_t hi = samples.size() - 1;
  while (lo < hi) {  // last index with stamp <= t_begin
    const std::size_t mid = (lo + hi + 1) / 2;
    if (samples[mid].stamp_s <= t_begin_s) {
      lo = mid;
    } else {
      hi = mid - 1;
    }
  }
  r.first = lo;
  lo = r.first;
  hi = samples.size() - 1;
  while (lo < hi) {  // first index with stamp >= t_end
    const std::size_t mid = (lo + hi) / 2;
    if (samples[mid].stamp_s >= t_end_s) {
      hi = mid;
    } else {
      lo = mid + 1;
    }
  }
  r.last = lo;
  for (std::size_t k = r.first; k <= r.last; ++k) {
    if (!samples[k].gyro_radps.allFinite() || !samples[k].accel_mps2.allFinite()) {
      throw ValueError(who + ": IMU sample " + std::to_string(k) + " at " + detail::imu_time(samples[k].stamp_s) +
                       " has a non-finite gyro or accel value");
    }
  }
  for (std::size_t k = r.first + 1; k <= r.last; ++k) {
    const double gap = samples[k].stamp_s - samples[k - 1].stamp_s;
    if (gap > max_gap_s) {
      throw ValueError(who + ": IMU gap of " + detail::imu_time(gap) + " between sample " + std::to_string(k - 1) +
                       " at " + detail::imu_time(samples[k - 1].stamp_s) + " and sample " + std::to_string(k) +
                       " at " + detail::imu_time(samples[k].stamp_s) + " exceeds max_gap_s = " +
                       detail::imu_time(max_gap_s));
    }
  }
  return r;
}

/// Linear interpolation of a sample pair at time t (a.stamp_s <= t <= b.stamp_s).
inline ImuSample interpolate_imu(const ImuSample& a, const ImuSample& b, double t_s) {
  const double span = b.stamp_s - a.stamp_s;
  const double w = span > 0.0 ? (t_s - a.stamp_s) / span : 0.0;
  ImuSample out;
  out.stamp_s = t_s;
  out.gyro_radps = (1.0 - w) * a.gyro_radps + w * b.gyro_radps;
  out.accel_mps2 = (1.0 - w) * a.accel_mps2 + w * b.accel_mps2;
  return out;
}

/// A time-ordered IMU stream: append as samples arrive, read the samples
/// covering a window, drop old ones. Not thread-safe.
class ImuBuffer {
 public:
  /// Appends a sample; throws ValueError when its stamp is not finite or not
  /// strictly after the last one (the buffer is left unchanged).
  void push(const ImuSample& s) {
    if (!std::isfinite(s.stamp_s) || !s.gyro_radps.allFinite() || !s.accel_mps2.allFinite()) {
      throw ValueError("ImuBuffer::push: non-finite IMU sample at " + detail::imu_time(s.stamp_s));
    }
    if (!samples_.empty() && !(s.stamp_s > samples_.back().stamp_s)) {
      throw ValueError("ImuBuffer::push: IMU time goes backwards: new sample at " + detail::imu_time(s.stamp_s) +
                       " is not after the last sample (index " + std::to_string(samples_.size() - 1) + ") at " +
                       detail::imu_time(samples_.back().stamp_s));
    }
    samples_.push_back(s);
  }

  /// The samples from the last one at or before t_begin to the first one at
  /// or after t_end (validated as by find_imu_range; ValueError otherwise).
  /// The span is valid until the next push or drop_before.
  [[nodiscard]] std::span<const ImuSample> covering(double t_begin_s, double t_end_s, double max_gap_s) const {
    const ImuRange r = find_imu_range(samples_, t_begin_s, t_end_s, max_gap_s, "ImuBuffer::covering");
    return std::span<const ImuSample>(samples_).subspan(r.first, r.last - r.first + 1);
  }

  /// Removes samples that are not needed to cover times >= t_s (keeps the
  /// last sample at or before t_s).
  void drop_before(double t_s) {
    std::size_t keep = 0;
    while (keep + 1 < samples_.size() && samples_[keep + 1].stamp_s <= t_s) ++keep;
    samples_.erase(samples_.begin(), samples_.begin() + static_cast<std::ptrdiff_t>(keep));
  }

  /// All samples, oldest first.
  [[nodiscard]] std::span<const ImuSample> samples() const noexcept { return samples_; }
  /// Number of samples held.
  [[nodiscard]] std::size_t size() const noexcept { return samples_.size(); }
  /// True when no sample is held.
  [[nodiscard]] bool empty() const noexcept { return samples_.empty(); }

 private:
  std::vector<ImuSample> samples_;
};

}  // namespace semlio
