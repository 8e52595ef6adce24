#include <catch2/catch.hpp>

#include <chrono>
#include <thread>

#include <semlio/core/stopwatch.hpp>

namespace test_stopwatch {  // one namespace per test file: the area compiles as one TU

using namespace semlio;

TEST_CASE("ms_since reads milliseconds on the monotonic clock", "[core]") {
  const auto t0 = StageClock::now();
  CHECK(ms_since(t0) >= 0.0);
  // sleep_for blocks at least as long as asked, measured on steady_clock.
  std::this_thread::sleep_for(std::chrono::milliseconds(3));
  const double ms = ms_since(t0);
  CHECK(ms >= 3.0);
  CHECK(ms < 3000.0);  // milliseconds, not microseconds or nanoseconds
}

}  // namespace test_stopwatch
