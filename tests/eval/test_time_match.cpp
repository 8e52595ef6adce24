// Nearest-stamp matching of timestamped estimates to ground-truth frames.
#include <catch2/catch.hpp>

#include <semlio/core/error.hpp>
#include <semlio/eval/time_match.hpp>

#include <cstddef>
#include <limits>
#include <vector>

namespace test_time_match {  // one namespace per test file: the area compiles as one TU

using semlio::eval::kNoMatch;
using semlio::eval::match_nearest_stamps;
using Matches = std::vector<std::ptrdiff_t>;

TEST_CASE("time match: nearest stamp within the tolerance", "[eval]") {
  const std::vector<double> frames{0.0, 0.1, 0.2, 0.3, 0.4};
  // Stamps jittered by a few ms, frame 0.2 missing, an extra stamp at 0.45.
  const std::vector<double> stamps{0.003, 0.098, 0.305, 0.401, 0.45};
  CHECK(match_nearest_stamps(frames, stamps, 0.01) == Matches{0, 1, kNoMatch, 2, 3});
  // A wide tolerance lets frame 0.2 take the nearer of 0.098 (0.102 away) and 0.305 (0.105 away).
  CHECK(match_nearest_stamps(frames, stamps, 0.2) == Matches{0, 1, 1, 2, 3});
  CHECK(match_nearest_stamps(frames, stamps, 0.0) == Matches(5, kNoMatch));
  CHECK(match_nearest_stamps(frames, {}, 1.0) == Matches(5, kNoMatch));
  CHECK(match_nearest_stamps({}, stamps, 1.0).empty());
}

TEST_CASE("time match: exact stamps, duplicates and ties", "[eval]") {
  const std::vector<double> frames{1.0, 2.0, 3.0};
  CHECK(match_nearest_stamps(frames, frames, 0.0) == Matches{0, 1, 2});
  // Duplicated stamps: the walk passes them and ties go to the later one.
  CHECK(match_nearest_stamps({2.0}, {1.0, 1.0, 1.9, 2.1}, 0.5) == Matches{3});
  CHECK(match_nearest_stamps({2.0}, {1.0, 1.0, 1.95, 2.2}, 0.5) == Matches{2});
  // Stamps all before or all after the frames.
  CHECK(match_nearest_stamps(frames, {0.0, 0.5}, 0.6) == Matches{1, kNoMatch, kNoMatch});
  CHECK(match_nearest_stamps(frames, {3.5, 9.0}, 0.6) == Matches{kNoMatch, kNoMatch, 0});
}

TEST_CASE("time match: unsorted input or a bad tolerance throws ValueError", "[eval]") {
  CHECK_THROWS_WITH(match_nearest_stamps({0.0, 0.2, 0.1}, {0.0}, 0.1),
                    Catch::Contains("frame_times_s[2]") && Catch::Contains("0.100000"));
  CHECK_THROWS_AS(match_nearest_stamps({0.0}, {0.5, 0.4}, 0.1), semlio::ValueError);
  CHECK_THROWS_AS(match_nearest_stamps({0.0}, {0.0}, -1.0), semlio::ValueError);
  CHECK_THROWS_AS(match_nearest_stamps({0.0}, {0.0}, std::numeric_limits<double>::quiet_NaN()), semlio::ValueError);
}

}  // namespace test_time_match
