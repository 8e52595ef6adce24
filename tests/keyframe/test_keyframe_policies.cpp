#include <catch2/catch.hpp>

#include <semlio/keyframe/pose_threshold.hpp>
#include <semlio/keyframe/semantic_adaptive.hpp>

#include <cmath>

namespace test_keyframe_policies {  // one namespace per test file: the area compiles as one TU

using semlio::Class;
using semlio::LabelHistogram;
using semlio::SE3d;

namespace {

LabelHistogram histogram(std::initializer_list<std::pair<Class, std::uint32_t>> counts) {
  LabelHistogram h{};
  for (const auto& [c, n] : counts) h[static_cast<std::size_t>(semlio::index(c))] = n;
  return h;
}

SE3d motion(double forward_m, double yaw_rad) {
  SE3d::Vector6 xi = SE3d::Vector6::Zero();
  xi[0] = forward_m;
  xi[5] = yaw_rad;
  return SE3d(semlio::SO3d::exp(xi.tail<3>()), xi.head<3>());
}

}  // namespace

TEMPLATE_TEST_CASE("Keyframe policies follow the pose thresholds without labels", "[keyframe]",
                   semlio::PoseThreshold, semlio::SemanticAdaptive) {
  const TestType policy;
  semlio::KeyframeEvidence evidence;
  evidence.T_lastkf_current = motion(0.99, 0.0);
  CHECK_FALSE(policy.is_keyframe(evidence));
  evidence.T_lastkf_current = motion(1.01, 0.0);
  CHECK(policy.is_keyframe(evidence));
  evidence.T_lastkf_current = motion(0.0, 0.199);
  CHECK_FALSE(policy.is_keyframe(evidence));
  evidence.T_lastkf_current = motion(0.0, 0.201);
  CHECK(policy.is_keyframe(evidence));
}

TEST_CASE("KL divergence of eq. 17 on a hand-computed two-class case", "[keyframe]") {
  semlio::SemanticAdaptiveConfig config;
  config.classes.fill(false);
  config.classes[semlio::index(Class::kCar)] = true;
  config.classes[semlio::index(Class::kBuilding)] = true;
  config.laplace_count = 0.0;
  const semlio::SemanticAdaptive policy(config);
  // P = (1/4, 3/4), Q = (1/2, 1/2).
  const auto current = histogram({{Class::kCar, 1}, {Class::kBuilding, 3}, {Class::kRoad, 50}});
  const auto last = histogram({{Class::kCar, 7}, {Class::kBuilding, 7}});
  const double expected = 0.25 * std::log(0.5) + 0.75 * std::log(1.5);
  CHECK(policy.kl_divergence(current, last) == Approx(expected).epsilon(1e-12));
  CHECK(policy.kl_divergence(current, current) == Approx(0.0).margin(1e-15));
}

TEST_CASE("Laplace smoothing keeps eq. 15 finite when a class is absent", "[keyframe]") {
  const semlio::SemanticAdaptive policy;  // 19 learning classes, one point per class
  const auto current = histogram({{Class::kCar, 1}, {Class::kBuilding, 3}});
  const auto last = histogram({{Class::kCar, 1}, {Class::kBuilding, 1}});
  // Smoothed counts: current car 2, building 4, 17 others 1 (sum 23);
  // last car 2, building 2, others 1 (sum 21).
  const double expected = 2.0 / 23 * std::log((2.0 / 23) / (2.0 / 21)) +
                          4.0 / 23 * std::log((4.0 / 23) / (2.0 / 21)) +
                          17.0 / 23 * std::log((1.0 / 23) / (1.0 / 21));
  CHECK(policy.kl_divergence(current, last) == Approx(expected).epsilon(1e-12));
  const LabelHistogram empty{};
  CHECK(std::isfinite(policy.kl_divergence(current, empty)));
  CHECK(policy.kl_divergence(empty, empty) == Approx(0.0).margin(1e-15));
}

TEST_CASE("Stability score (eq. 18) and level m (eq. 19)", "[keyframe]") {
  const semlio::SemanticAdaptive policy;
  // 40 static points (building + road), 3 dynamic: SS = 40 / 4 = 10 = t_ss -> m = 0.
  const auto at_threshold = histogram({{Class::kBuilding, 30}, {Class::kRoad, 10}, {Class::kCar, 3}});
  CHECK(semlio::SemanticAdaptive::stability_score(at_threshold) == Approx(10.0));
  CHECK(policy.weight(at_threshold, at_threshold).m == 0);
  // SS = 44 / 4 = 11 in (10, 12] -> m = 1.
  const auto mid = histogram({{Class::kBuilding, 44}, {Class::kPerson, 3}});
  CHECK(policy.weight(mid, mid).m == 1);
  // SS = 100 / 4 = 25 > 12 -> m = 2; unlabeled points count as neither.
  const auto stable = histogram({{Class::kVegetation, 100}, {Class::kTruck, 3}, {Class::kUnlabeled, 999}});
  CHECK(semlio::SemanticAdaptive::stability_score(stable) == Approx(25.0));
  const auto w = policy.weight(stable, stable);
  CHECK(w.m == 2);
  CHECK(w.kl_divergence == Approx(0.0).margin(1e-15));
  CHECK(w.weight == Approx(0.81));  // 0.9^2 * (1 - 0)
}

TEST_CASE("Semantic weight lowers the thresholds (eq. 20-22)", "[keyframe]") {
  semlio::SemanticAdaptiveConfig config;
  const semlio::SemanticAdaptive policy(config);
  const semlio::PoseThreshold baseline;
  const auto stable = histogram({{Class::kBuilding, 1000}, {Class::kRoad, 1000}});
  semlio::KeyframeEvidence evidence;
  evidence.current = &stable;
  evidence.last_keyframe = &stable;
  // W_se = 0.81: a 0.85 m move is a keyframe for the semantic policy only.
  evidence.T_lastkf_current = motion(0.85, 0.0);
  CHECK(policy.is_keyframe(evidence));
  CHECK_FALSE(baseline.is_keyframe(evidence));
  evidence.T_lastkf_current = motion(0.80, 0.0);
  CHECK_FALSE(policy.is_keyframe(evidence));
  // Rotation threshold scales the same way: 0.81 * 0.2 = 0.162 rad.
  evidence.T_lastkf_current = motion(0.0, 0.17);
  CHECK(policy.is_keyframe(evidence));
  CHECK_FALSE(baseline.is_keyframe(evidence));
}

TEST_CASE("A drastic scene change clamps W_se at its floor", "[keyframe]") {
  const semlio::SemanticAdaptive policy;
  const auto city = histogram({{Class::kBuilding, 50000}, {Class::kRoad, 30000}});
  const auto forest = histogram({{Class::kVegetation, 60000}, {Class::kTerrain, 20000}});
  const auto w = policy.weight(forest, city);
  CHECK(w.kl_divergence > 1.0);
  CHECK(w.weight == Approx(policy.config().weight_min));
  semlio::KeyframeEvidence evidence;
  evidence.current = &forest;
  evidence.last_keyframe = &city;
  evidence.T_lastkf_current = motion(0.11, 0.0);
  CHECK(policy.is_keyframe(evidence));
}

}  // namespace test_keyframe_policies
