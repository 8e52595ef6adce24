#pragma once
/// \file
/// The one way semlio times its stages for reports: wall time on the
/// monotonic clock, in milliseconds as a double.

#include <chrono>

namespace semlio {

/// The clock of every stage timing (monotonic, unaffected by clock changes).
using StageClock = std::chrono::steady_clock;

/// Milliseconds elapsed on StageClock since t0.
inline double ms_since(StageClock::time_point t0) {
  return std::chrono::duration<double, std::milli>(StageClock::now() - t0).count();
}

}  // namespace semlio
