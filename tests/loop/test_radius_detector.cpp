// RadiusLoopDetector: radius and time-gap gating, order, guess, timing.
#include <catch2/catch.hpp>

#include <chrono>
#include <random>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/loop/radius_detector.hpp>

#include "loop_fixtures.hpp"

namespace test_radius_detector {  // one namespace per test file: the area compiles as one TU

using namespace semlio;

namespace {

LoopKeyframe at(double x, double y, double stamp_s, double yaw = 0.0) {
  LoopKeyframe kf;
  kf.stamp_s = stamp_s;
  kf.T_world_lidar = loop_test::yaw_pose(yaw, Eigen::Vector3d(x, y, 0.0));
  return kf;
}

}  // namespace

TEST_CASE("radius detector gates by radius and time gap, nearest first", "[loop]") {
  std::vector<LoopKeyframe> kfs;
  kfs.push_back(at(0.0, 0.0, 0.0));      // 0: d = 5, old            -> candidate
  kfs.push_back(at(5.0, 16.0, 1.0));     // 1: d = 16 > 15           -> out (radius)
  kfs.push_back(at(10.0, 0.0, 10.0));    // 2: d = 5, old            -> candidate (tie with 0: older first)
  kfs.push_back(at(8.0, 1.0, 20.0));     // 3: d = sqrt(10), old     -> candidate, nearest
  kfs.push_back(at(6.0, 0.0, 75.0));     // 4: d = 1 but 25 s old    -> out (time gap)
  kfs.push_back(at(100.0, 0.0, 50.0));   // 5: far                   -> out
  kfs.push_back(at(5.0, 0.0, 100.0, 0.4));  // query
  RadiusLoopDetector detector;
  std::vector<LoopCandidate> out;
  detector.detect(kfs, out);
  REQUIRE(out.size() == 3);
  CHECK(out[0].index == 3);
  CHECK(out[1].index == 0);
  CHECK(out[2].index == 2);
  CHECK(out[0].score == Approx(std::sqrt(10.0)));
  CHECK(out[1].score == Approx(5.0));
  // Guess: the relative pose of the current estimates.
  for (const LoopCandidate& c : out) {
    const SE3d expected = kfs[c.index].T_world_lidar.inverse() * kfs.back().T_world_lidar;
    const auto [et, er] = loop_test::pose_error(expected, c.T_from_to_guess);
    CHECK(et < 1e-12);
    CHECK(er < 1e-12);
  }

  SECTION("max_candidates cuts the list") {
    RadiusLoopDetector one(RadiusLoopConfig{.max_candidates = 1});
    one.detect(kfs, out);
    REQUIRE(out.size() == 1);
    CHECK(out[0].index == 3);
  }
  SECTION("a shorter time gap admits the recent neighbour") {
    RadiusLoopDetector recent(RadiusLoopConfig{.min_time_gap_s = 20.0, .max_candidates = 10});
    recent.detect(kfs, out);
    REQUIRE(out.size() == 4);
    CHECK(out[0].index == 4);
  }
  SECTION("a larger radius admits the 16 m keyframe") {
    RadiusLoopDetector wide(RadiusLoopConfig{.radius_m = 16.5, .max_candidates = 10});
    wide.detect(kfs, out);
    CHECK(out.size() == 4);
    CHECK(out.back().index == 1);
  }
}

TEST_CASE("radius detector: too few keyframes and bad settings", "[loop]") {
  RadiusLoopDetector detector;
  std::vector<LoopCandidate> out{LoopCandidate{}};
  std::vector<LoopKeyframe> kfs;
  detector.detect(kfs, out);
  CHECK(out.empty());
  kfs.push_back(at(0.0, 0.0, 0.0));
  detector.detect(kfs, out);
  CHECK(out.empty());
  CHECK_THROWS_AS(RadiusLoopDetector(RadiusLoopConfig{.radius_m = 0.0}), ConfigError);
  CHECK_THROWS_AS(RadiusLoopDetector(RadiusLoopConfig{.min_time_gap_s = -1.0}), ConfigError);
}

TEST_CASE("radius detector: brute force over 5000 keyframes is fast and exact", "[loop]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-500.0, 500.0);
  std::vector<LoopKeyframe> kfs;
  for (int i = 0; i < 5000; ++i) kfs.push_back(at(u(rng), u(rng), static_cast<double>(i)));
  kfs.back().T_world_lidar = loop_test::yaw_pose(0.0, Eigen::Vector3d(0.0, 0.0, 0.0));
  RadiusLoopDetector detector(RadiusLoopConfig{.radius_m = 40.0, .max_candidates = 1000});
  std::vector<LoopCandidate> out;
  const auto t0 = std::chrono::steady_clock::now();
  constexpr int kRuns = 20;
  for (int r = 0; r < kRuns; ++r) detector.detect(kfs, out);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / kRuns;
  // Same answer as a direct count.
  std::size_t expected = 0;
  for (std::size_t i = 0; i + 1 < kfs.size(); ++i) {
    if (kfs.back().stamp_s - kfs[i].stamp_s > 30.0 && kfs[i].T_world_lidar.translation().norm() <= 40.0) ++expected;
  }
  CHECK(out.size() == expected);
  CHECK(expected > 0);
  for (std::size_t k = 1; k < out.size(); ++k) CHECK(out[k - 1].score <= out[k].score);
  INFO("detect over 5000 keyframes: " << ms << " ms");
  CHECK(ms < 5.0);  // measured ~0.02 ms; the bound only catches gross regressions
}

}  // namespace test_radius_detector
