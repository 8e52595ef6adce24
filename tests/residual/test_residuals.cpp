// Residual policies and decorators: one contract test over all of them
// (analytic Jacobian vs central differences under right perturbation, zero at
// truth, degenerate input flagged rather than NaN), plus hand-computed values
// of eq. 8, 9, 11 and 12.
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include <semlio/concepts.hpp>
#include <semlio/core/error.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>
#include <semlio/residual/robust.hpp>
#include <semlio/residual/semantic_weighted.hpp>

namespace test_residuals {  // one namespace per test file: the area compiles as one TU

using semlio::Class;
using semlio::FeaturePoint;
using semlio::MatchedPoints;
using semlio::SE3d;

namespace {

// Option variants as their own types, so one TEMPLATE_TEST_CASE covers them.
struct PlaneThreePoint : semlio::PointToPlane {
  PlaneThreePoint() : semlio::PointToPlane({.three_point = true}) {}
};
struct LineTwoPoint : semlio::PointToLine {
  LineTwoPoint() : semlio::PointToLine({.two_point = true}) {}
};
using WeightedPlane = semlio::SemanticWeighted<semlio::PointToPlane>;
using WeightedLine = semlio::SemanticWeighted<semlio::PointToLine>;
using HuberPlane = semlio::Robust<semlio::Huber, semlio::PointToPlane>;
using CauchyWeightedLine = semlio::Robust<semlio::Cauchy, semlio::SemanticWeighted<semlio::PointToLine>>;
static_assert(semlio::Residual<PlaneThreePoint>);
static_assert(semlio::Residual<LineTwoPoint>);
static_assert(semlio::Residual<CauchyWeightedLine>);

using Vec6 = Eigen::Matrix<double, 6, 1>;

MatchedPoints make_matches(const std::vector<Eigen::Vector3d>& pts, const std::vector<Class>& labels) {
  REQUIRE(pts.size() <= static_cast<std::size_t>(semlio::kMaxKeptMatches));
  MatchedPoints m;
  m.count = static_cast<int>(pts.size());
  for (std::size_t k = 0; k < pts.size(); ++k) {
    m.p_map[k] = pts[k];
    m.labels[k] = labels.empty() ? Class::kBuilding : labels[k];
  }
  return m;
}

// A primitive in the map frame: plane (kDim 1) or line (kDim 2) through c0.
template <typename R>
struct Primitive {
  static constexpr bool kLine = R::kDim == 2;
  Eigen::Vector3d c0{2.0, 1.0, 0.5};
  Eigen::Vector3d axis = Eigen::Vector3d(0.2, -0.3, 0.93).normalized();  // normal or direction
  Eigen::Vector3d e1 = axis.unitOrthogonal();
  Eigen::Vector3d e2 = axis.cross(e1);

  // Five points on the primitive, labels 3 x building + 2 x vegetation.
  [[nodiscard]] MatchedPoints matches() const {
    std::vector<Eigen::Vector3d> pts;
    if (kLine) {
      for (const double s : {0.0, 0.3, -0.4, 0.7, -0.2}) pts.push_back(c0 + s * axis);
    } else {
      const double ab[5][2] = {{0, 0}, {0.5, 0.1}, {-0.3, 0.4}, {0.2, -0.5}, {-0.4, -0.2}};
      for (const auto& v : ab) pts.push_back(c0 + v[0] * e1 + v[1] * e2);
    }
    return make_matches(pts, {Class::kBuilding, Class::kVegetation, Class::kBuilding, Class::kBuilding,
                              Class::kVegetation});
  }
  // A map point on the primitive, and one 0.3 m off it.
  [[nodiscard]] Eigen::Vector3d on() const {
    if (kLine) return c0 + 0.25 * axis;
    return c0 + 0.2 * e1 - 0.1 * e2;
  }
  [[nodiscard]] Eigen::Vector3d off() const { return on() + 0.3 * (kLine ? e1 : axis); }
};

SE3d some_pose() {
  Vec6 xi;
  xi << 0.4, -1.2, 0.3, 0.2, -0.5, 1.1;
  return SE3d::exp(xi);
}

template <typename Term>
void require_invalid_and_finite(const Term& t) {
  CHECK_FALSE(t.valid);
  CHECK(t.r.allFinite());
  CHECK(t.J_r_xi.allFinite());
  CHECK(t.r.isZero());
  CHECK(t.J_r_xi.isZero());
}

}  // namespace

TEMPLATE_TEST_CASE("Residual contract", "[residual]", semlio::PointToPlane, PlaneThreePoint, semlio::PointToLine,
                   LineTwoPoint, WeightedPlane, WeightedLine, HuberPlane, CauchyWeightedLine) {
  static_assert(semlio::Residual<TestType>);
  const TestType residual{};
  const Primitive<TestType> prim;
  const MatchedPoints matches = prim.matches();
  const SE3d T = some_pose();

  SECTION("zero residual at the truth") {
    const FeaturePoint f{T.inverse() * prim.on(), Class::kBuilding};
    const auto term = residual.evaluate(f, matches, T);
    REQUIRE(term.valid);
    CHECK(term.r.norm() < 1e-9);
    CHECK(term.weight == Approx(1.0));
  }

  SECTION("analytic Jacobian equals central differences (right perturbation)") {
    const FeaturePoint f{T.inverse() * prim.off(), Class::kBuilding};
    const auto term = residual.evaluate(f, matches, T);
    REQUIRE(term.valid);
    CHECK(term.r.norm() > 0.05);  // away from the primitive
    CHECK(term.weight > 0.0);
    CHECK(term.weight <= 1.0);
    constexpr double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      Vec6 d = Vec6::Zero();
      d(k) = h;
      const auto plus = residual.evaluate(f, matches, T * SE3d::exp(d));
      const auto minus = residual.evaluate(f, matches, T * SE3d::exp(-d));
      REQUIRE(plus.valid);
      REQUIRE(minus.valid);
      const auto numeric = ((plus.r - minus.r) / (2.0 * h)).eval();
      INFO("column " << k << ": analytic " << term.J_r_xi.col(k).transpose() << " numeric " << numeric.transpose());
      CHECK((term.J_r_xi.col(k) - numeric).norm() < 1e-6);
    }
  }

  SECTION("degenerate matches are flagged, never NaN") {
    const FeaturePoint f{T.inverse() * prim.off(), Class::kBuilding};
    require_invalid_and_finite(residual.evaluate(f, MatchedPoints{}, T));  // no matches
    require_invalid_and_finite(residual.evaluate(f, make_matches({prim.c0}, {}), T));  // one
    require_invalid_and_finite(
        residual.evaluate(f, make_matches({prim.c0, prim.c0, prim.c0, prim.c0, prim.c0}, {}), T));  // one spot
    const Eigen::Vector3d nan = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    require_invalid_and_finite(residual.evaluate(f, make_matches({prim.c0, nan, prim.on(), prim.off()}, {}), T));
    if constexpr (TestType::kDim == 1) {
      // Collinear points define no plane.
      const Eigen::Vector3d u = prim.e1;
      require_invalid_and_finite(
          residual.evaluate(f, make_matches({prim.c0, prim.c0 + u, prim.c0 + 2.0 * u, prim.c0 - u}, {}), T));
      // A thick blob is not a plane: variances 0.4, 0.4 in the e1, e2
      // directions and 0.16 along the normal, l0 / l1 = 0.4 > 0.1.
      require_invalid_and_finite(residual.evaluate(
          f, make_matches({prim.c0 + prim.e1, prim.c0 - prim.e1, prim.c0 + prim.e2, prim.c0 - prim.e2,
                           prim.c0 + prim.axis}, {}), T));
    } else {
      // A planar square is not a line (l1 / l2 = 1).
      require_invalid_and_finite(residual.evaluate(
          f, make_matches({prim.c0 + prim.e1, prim.c0 - prim.e1, prim.c0 + prim.e2, prim.c0 - prim.e2}, {}), T));
    }
  }
}

TEST_CASE("Point-to-plane distance equals eq. 9 by hand", "[residual]") {
  // u = (0,0,1), v = (1,0,0), w = (0,1,0): (u-v) x (u-w) = (1,1,1), plane
  // x + y + z = 1. Feature at the origin: |(f-u).(1,1,1)| / |(1,1,1)| = 1/sqrt(3).
  const MatchedPoints m = make_matches({{0, 0, 1}, {1, 0, 0}, {0, 1, 0}}, {});
  const FeaturePoint f{Eigen::Vector3d::Zero(), Class::kBuilding};
  const auto ls = semlio::PointToPlane{}.evaluate(f, m, SE3d());
  const auto tp = PlaneThreePoint{}.evaluate(f, m, SE3d());
  REQUIRE(ls.valid);
  REQUIRE(tp.valid);
  CHECK(std::abs(ls.r(0)) == Approx(1.0 / std::sqrt(3.0)));
  CHECK(std::abs(tp.r(0)) == Approx(1.0 / std::sqrt(3.0)));

  // Plane z = 0 from five points, feature p_scan = (0.3, 0.2, 0.5) at the
  // identity: r = +-0.5 and J = n^T [I, -hat(p)] = +-[0, 0, 1, -(n x p)^T]
  // (n^T hat(p) v = n . (p x v) = v . (n x p)), with n x p = z x (0.3, 0.2, 0.5)
  // = (-0.2, 0.3, 0): J = +-[0 0 1 0.2 -0.3 0].
  const MatchedPoints flat = make_matches({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}}, {});
  const auto t = semlio::PointToPlane{}.evaluate({{0.3, 0.2, 0.5}, Class::kRoad}, flat, SE3d());
  REQUIRE(t.valid);
  const double s = t.r(0) > 0 ? 1.0 : -1.0;
  CHECK(t.r(0) == Approx(0.5 * s));
  Eigen::Matrix<double, 1, 6> want;
  want << 0, 0, 1, 0.2, -0.3, 0;
  CHECK((t.J_r_xi - s * want).norm() < 1e-12);
}

TEST_CASE("Point-to-line distance equals eq. 8 by hand", "[residual]") {
  // u = (0,0,0), v = (2,0,0), f = (1,3,4): (f-u) x (f-v) = (0,-8,6), |.| = 10,
  // |u - v| = 2, d_e = 5. The feature is given in the scan frame, 1 m below,
  // with T_map_scan a 1 m lift.
  const MatchedPoints two = make_matches({{0, 0, 0}, {2, 0, 0}}, {});
  const MatchedPoints three = make_matches({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {});
  const SE3d lift(semlio::SO3d(), Eigen::Vector3d(0, 0, 1));
  const FeaturePoint f{{1, 3, 3}, Class::kPole};
  for (const auto& term : {semlio::PointToLine{}.evaluate(f, two, lift), LineTwoPoint{}.evaluate(f, two, lift),
                           semlio::PointToLine{}.evaluate(f, three, lift)}) {
    REQUIRE(term.valid);
    CHECK(term.r.norm() == Approx(5.0));
  }
}

TEST_CASE("Point-to-line ring-crossing check rejects lines lying in the feature's scan cone", "[residual]") {
  // A ground feature 10 m ahead, 1.73 m below the sensor: its beam's cone
  // contains the horizontal ring tangent (y) and the beam itself.
  const FeaturePoint f{{10.0, 0.0, -1.73}, Class::kRoad};
  const SE3d I;
  const MatchedPoints along_ring = make_matches({{10.0, -0.4, -1.73}, {10.0, 0.0, -1.73}, {10.0, 0.4, -1.73}}, {});
  const Eigen::Vector3d beam = f.p_scan.normalized();
  const MatchedPoints along_beam = make_matches({f.p_scan - 0.5 * beam, f.p_scan, f.p_scan + 0.5 * beam}, {});
  const MatchedPoints vertical = make_matches({{10.0, 0.1, -1.9}, {10.0, 0.1, -1.5}, {10.0, 0.1, -1.1}}, {});
  const semlio::PointToLine off{};
  const semlio::PointToLine on({.min_cone_angle_rad = 20.0 * 3.14159265358979 / 180.0});
  CHECK(off.evaluate(f, along_ring, I).valid);
  CHECK(off.evaluate(f, along_beam, I).valid);
  CHECK_FALSE(on.evaluate(f, along_ring, I).valid);
  CHECK_FALSE(on.evaluate(f, along_beam, I).valid);
  REQUIRE(on.evaluate(f, vertical, I).valid);
  CHECK(on.evaluate(f, vertical, I).r.norm() == Approx(0.1));
  // The test runs in the scan frame: rotating the map by T leaves the decision unchanged.
  const SE3d T(semlio::SO3d::exp(Eigen::Vector3d(0.1, -0.2, 0.7)), Eigen::Vector3d(3.0, -1.0, 0.5));
  MatchedPoints moved = along_ring;
  for (int k = 0; k < moved.count; ++k) moved.p_map[static_cast<std::size_t>(k)] = T * along_ring.p_map[static_cast<std::size_t>(k)];
  CHECK_FALSE(on.evaluate(f, moved, T).valid);
  // Undefined cone (feature on the sensor's z axis): no residual, never NaN.
  const FeaturePoint up{{0.0, 0.0, 2.0}, Class::kPole};
  CHECK_FALSE(on.evaluate(up, vertical, I).valid);
}

TEST_CASE("Semantic weight scales residual and Jacobian (eq. 10-12)", "[residual]") {
  // 3 of 5 matches share the feature's label: w = 3/5 (eq. 10-11).
  const std::vector<Class> labels{Class::kPole, Class::kPole, Class::kBuilding, Class::kPole, Class::kVegetation};
  const MatchedPoints line = make_matches({{0, 0, 0}, {0.5, 0, 0}, {1, 0, 0}, {1.5, 0, 0}, {2, 0, 0}}, labels);
  CHECK(semlio::semantic_weight(Class::kPole, line) == Approx(0.6));
  CHECK(semlio::semantic_weight(Class::kCar, line) == 0.0);
  CHECK(semlio::semantic_weight(Class::kPole, MatchedPoints{}) == 0.0);
  const FeaturePoint f{{1, 3, 4}, Class::kPole};
  // Eq. 10 as written counts the same class only: the paper's mode.
  const WeightedLine paper_line(semlio::PointToLine{}, {.mode = semlio::SemanticWeightMode::kPaper});
  const WeightedPlane paper_plane(semlio::PointToPlane{}, {.mode = semlio::SemanticWeightMode::kPaper});
  const auto plain = semlio::PointToLine{}.evaluate(f, line, SE3d());
  const auto weighted = paper_line.evaluate(f, line, SE3d());
  REQUIRE(weighted.valid);
  CHECK(plain.r.norm() == Approx(5.0));
  CHECK(weighted.r.norm() == Approx(0.6 * 5.0));  // eq. 11: d'_e = 3
  CHECK((weighted.J_r_xi - 0.6 * plain.J_r_xi).norm() < 1e-12);

  // Eq. 12 on a plane: 2 of 4 road -> w = 0.5; d_s = 0.5 -> d'_s = 0.25.
  const MatchedPoints plane = make_matches({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}},
                                           {Class::kRoad, Class::kSidewalk, Class::kRoad, Class::kTerrain});
  const auto ws = paper_plane.evaluate({{0.3, 0.2, 0.5}, Class::kRoad}, plane, SE3d());
  REQUIRE(ws.valid);
  CHECK(std::abs(ws.r(0)) == Approx(0.25));
  // No label agrees: weight 0, the term stays valid and contributes nothing.
  const auto none = paper_plane.evaluate({{0.3, 0.2, 0.5}, Class::kCar}, plane, SE3d());
  CHECK(none.valid);
  CHECK(none.r.isZero());
}

TEST_CASE("Semantic weight modes: chance-corrected shrinks toward 1 as label reliability falls", "[residual]") {
  using semlio::SemanticWeightMode;
  // 1 of 4 matches agrees, in every mode (the others are movable or unlabelled): a = 0.25.
  const MatchedPoints plane = make_matches({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}},
                                           {Class::kRoad, Class::kCar, Class::kPerson, Class::kUnlabeled});
  const FeaturePoint f{{0.3, 0.2, 0.5}, Class::kRoad};
  const double d = std::abs(semlio::PointToPlane{}.evaluate(f, plane, SE3d()).r(0));
  REQUIRE(d == Approx(0.5));
  const auto weighted_distance = [&](const WeightedPlane& w) { return std::abs(w.evaluate(f, plane, SE3d()).r(0)); };

  const WeightedPlane paper(semlio::PointToPlane{}, {.mode = SemanticWeightMode::kPaper});
  const WeightedPlane off(semlio::PointToPlane{}, {.mode = SemanticWeightMode::kOff});
  WeightedPlane corrected;  // the default mode
  CHECK(corrected.config().mode == SemanticWeightMode::kChanceCorrected);
  CHECK(weighted_distance(paper) == Approx(0.25 * d));
  CHECK(weighted_distance(off) == Approx(d));
  // Before any kappa is set, kappa is 1: w = 1 - (1 - a)^2 = 1 - 0.75^2;
  // with the linear penalty that is the paper's w = a.
  CHECK(corrected.label_reliability() == 1.0);
  CHECK(weighted_distance(corrected) == Approx(0.4375 * d));
  WeightedPlane linear(semlio::PointToPlane{}, {.disagreement_power = 1});
  CHECK(weighted_distance(linear) == Approx(0.25 * d));
  // w = 1 - kappa (1 - a)^p: kappa 0.6 -> 1 - 0.6 * 0.5625 = 0.6625, and
  // 1 - 0.6 * 0.75 = 0.55 with p = 1.
  corrected.set_label_reliability(0.6);
  linear.set_label_reliability(0.6);
  CHECK(weighted_distance(corrected) == Approx(0.6625 * d));
  CHECK(weighted_distance(linear) == Approx(0.55 * d));
  // Labels no better than chance leave the residual unweighted.
  corrected.set_label_reliability(0.0);
  CHECK(weighted_distance(corrected) == Approx(d));
  // Out-of-range and NaN kappas are clamped (NaN: no evidence, 0).
  corrected.set_label_reliability(1.7);
  CHECK(corrected.label_reliability() == 1.0);
  corrected.set_label_reliability(-0.2);
  CHECK(corrected.label_reliability() == 0.0);
  corrected.set_label_reliability(std::numeric_limits<double>::quiet_NaN());
  CHECK(corrected.label_reliability() == 0.0);
  // The paper's and the off mode ignore kappa.
  WeightedPlane paper_k = paper;
  paper_k.set_label_reliability(0.0);
  CHECK(weighted_distance(paper_k) == Approx(0.25 * d));
  // Weights switched off (the odometry's baseline-like re-solve of a weak
  // frame): w = 1 in every mode until switched back on.
  // The default mode too (kappa 1: w = 1 - 0.75^2).
  for (auto [w, on_weight] : {std::pair{paper, 0.25}, std::pair{linear, 0.25}, std::pair{corrected, 0.4375}}) {
    w.set_label_reliability(1.0);
    REQUIRE(w.weights_enabled());
    const double on_distance = weighted_distance(w);
    w.set_weights_enabled(false);
    CHECK_FALSE(w.weights_enabled());
    CHECK(weighted_distance(w) == d);
    const auto term = w.evaluate(f, plane, SE3d());
    CHECK(term.J_r_xi == semlio::PointToPlane{}.evaluate(f, plane, SE3d()).J_r_xi);
    w.set_weights_enabled(true);
    CHECK(weighted_distance(w) == on_distance);
    CHECK(on_distance == Approx(on_weight * d));
  }
}

TEST_CASE("Semantic weight: two static classes agree in the chance-corrected mode only", "[residual]") {
  using semlio::SemanticWeightMode;
  // A kerb corner: road feature, matches on road, sidewalk, terrain, car, unlabelled.
  const MatchedPoints plane = make_matches({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 0, 0}},
                                           {Class::kRoad, Class::kSidewalk, Class::kTerrain, Class::kCar,
                                            Class::kUnlabeled});
  CHECK(semlio::semantic_weight(Class::kRoad, plane) == Approx(0.2));          // eq. 10: 1 of 5
  CHECK(semlio::semantic_weight(Class::kRoad, plane, true) == Approx(0.6));    // 3 of 5 static
  CHECK(semlio::semantic_weight(Class::kCar, plane, true) == Approx(0.2));     // the car only
  const FeaturePoint f{{0.3, 0.2, 0.5}, Class::kRoad};
  const double d = std::abs(semlio::PointToPlane{}.evaluate(f, plane, SE3d()).r(0));
  REQUIRE(d > 0.0);
  const auto weighted_distance = [&](const WeightedPlane& w) { return std::abs(w.evaluate(f, plane, SE3d()).r(0)); };

  WeightedPlane corrected;  // the defaults: chance-corrected, static classes agree
  CHECK(corrected.config().static_classes_agree);
  corrected.set_label_reliability(0.5);
  CHECK(weighted_distance(corrected) == Approx((1.0 - 0.5 * 0.4 * 0.4) * d));  // a = 0.6
  WeightedPlane literal(semlio::PointToPlane{}, {.mode = SemanticWeightMode::kChanceCorrected,
                                                 .static_classes_agree = false});
  literal.set_label_reliability(0.5);
  CHECK(weighted_distance(literal) == Approx((1.0 - 0.5 * 0.8 * 0.8) * d));  // a = 0.2
  // The paper's mode keeps eq. 10 as written whatever the flag says.
  const WeightedPlane paper(semlio::PointToPlane{}, {.mode = SemanticWeightMode::kPaper});
  REQUIRE(paper.config().static_classes_agree);
  CHECK(weighted_distance(paper) == Approx(0.2 * d));
  // What the scan-to-map problem asks to count its kappa the same way.
  CHECK(corrected.static_classes_agree());
  CHECK_FALSE(literal.static_classes_agree());
  CHECK_FALSE(paper.static_classes_agree());
}

TEST_CASE("Semantic weight: a disagreement costs kappa (1 - a)^p", "[residual]") {
  WeightedPlane w;
  REQUIRE(w.config().disagreement_power == 2);
  w.set_label_reliability(0.5);
  // Every match disagrees: the whole penalty kappa, whatever p is.
  CHECK(w.weight(0.0) == Approx(0.5));
  CHECK(w.weight(1.0) == 1.0);
  // One of five disagrees: 0.5 * 0.2^2, a fifth of the linear penalty.
  CHECK(w.weight(0.8) == Approx(1.0 - 0.5 * 0.04));
  for (int p = 1; p <= 4; ++p) {
    WeightedPlane wp(semlio::PointToPlane{}, {.disagreement_power = p});
    wp.set_label_reliability(0.5);
    CHECK(wp.weight(0.0) == Approx(0.5));
    CHECK(wp.weight(0.4) == Approx(1.0 - 0.5 * std::pow(0.6, p)));
  }
  // The paper's mode keeps w = a.
  const WeightedPlane paper(semlio::PointToPlane{}, {.mode = semlio::SemanticWeightMode::kPaper});
  CHECK(paper.weight(0.4) == Approx(0.4));
  for (const int bad : {0, -1, 5}) {
    CHECK_THROWS_AS(WeightedPlane(semlio::PointToPlane{}, {.disagreement_power = bad}), semlio::ConfigError);
  }
}

TEST_CASE("Robust kernels give the IRLS weight of the current residual", "[residual]") {
  const MatchedPoints flat = make_matches({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}}, {});
  const FeaturePoint far{{0.3, 0.2, 0.5}, Class::kRoad};   // r = 0.5
  const FeaturePoint near{{0.3, 0.2, 0.05}, Class::kRoad};  // r = 0.05
  const semlio::Robust<semlio::Huber, semlio::PointToPlane> huber(semlio::Huber{.delta_m = 0.1});
  const semlio::Robust<semlio::Cauchy, semlio::PointToPlane> cauchy(semlio::Cauchy{.c_m = 0.1});
  // Huber: delta / |r| = 0.1 / 0.5 beyond delta, 1 inside.
  CHECK(huber.evaluate(far, flat, SE3d()).weight == Approx(0.2));
  CHECK(huber.evaluate(near, flat, SE3d()).weight == 1.0);
  // Cauchy: 1 / (1 + r^2 / c^2) = 1 / (1 + 25) and 1 / (1 + 0.25).
  CHECK(cauchy.evaluate(far, flat, SE3d()).weight == Approx(1.0 / 26.0));
  CHECK(cauchy.evaluate(near, flat, SE3d()).weight == Approx(0.8));
  // r and J are the inner residual's.
  const auto inner = semlio::PointToPlane{}.evaluate(far, flat, SE3d());
  const auto outer = huber.evaluate(far, flat, SE3d());
  CHECK(outer.r == inner.r);
  CHECK(outer.J_r_xi == inner.J_r_xi);

  SECTION("widening: scale max(own, s); infinity is plain least squares, 0 restores") {
    semlio::Robust<semlio::Cauchy, semlio::PointToPlane> wide(semlio::Cauchy{.c_m = 0.1});
    CHECK(wide.set_min_scale_m(0.5));  // 1 / (1 + 0.25 / 0.25)
    CHECK(wide.evaluate(far, flat, SE3d()).weight == Approx(0.5));
    CHECK_FALSE(wide.set_min_scale_m(0.05));  // narrower than its own: own scale
    CHECK(wide.evaluate(far, flat, SE3d()).weight == Approx(1.0 / 26.0));
    CHECK(wide.set_min_scale_m(std::numeric_limits<double>::infinity()));
    CHECK(wide.evaluate(far, flat, SE3d()).weight == 1.0);
    CHECK_FALSE(wide.set_min_scale_m(0.0));
    CHECK(wide.evaluate(far, flat, SE3d()).weight == cauchy.evaluate(far, flat, SE3d()).weight);
    // Through SemanticWeighted, as the full preset nests it.
    semlio::SemanticWeighted<semlio::Robust<semlio::Cauchy, semlio::PointToPlane>> nested(wide);
    CHECK(nested.set_min_scale_m(std::numeric_limits<double>::infinity()));
    CHECK(nested.evaluate(far, flat, SE3d()).weight ==
          semlio::SemanticWeighted<semlio::PointToPlane>{}.evaluate(far, flat, SE3d()).weight);
  }
}

}  // namespace test_residuals
