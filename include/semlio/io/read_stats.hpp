#pragma once
/// \file
/// Counters of the repairs a point-cloud reader made (points it dropped).

#include <cstddef>

namespace semlio::io {

/// What a reader dropped and why; readers add to these counters (never reset
/// them), so one ReadStats can accumulate over many files.
struct ReadStats {
  std::size_t dropped_nonfinite = 0;  ///< points with a NaN or Inf coordinate
  std::size_t dropped_zero = 0;       ///< points exactly at (0,0,0) (no return)

  /// Total number of dropped points.
  [[nodiscard]] std::size_t dropped() const noexcept { return dropped_nonfinite + dropped_zero; }
};

}  // namespace semlio::io
