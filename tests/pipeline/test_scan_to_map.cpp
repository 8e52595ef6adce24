// ScanToMapProblem (pipeline/scan_to_map.hpp): after every association it
// hands each feature kind's label kappa (map/label_agreement.hpp) to
// residuals that weigh labels, and reports it; other residuals get none.
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cmath>
#include <vector>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/features/loam_features.hpp>
#include <semlio/map/feature_map.hpp>
#include <semlio/map/label_agreement.hpp>
#include <semlio/pipeline/scan_to_map.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>
#include <semlio/residual/semantic_weighted.hpp>

namespace test_scan_to_map {

using semlio::Class;
using semlio::FeatureMap;
using semlio::FeatureSet;
using semlio::LabelAgreement;

TEST_CASE("ScanToMapProblem hands each feature kind's kappa to its semantic weights", "[map][semantic]") {
  // Surfaces: a floor (sidewalk, then road) with a matching scan whose labels agree;
  // corners: a vertical pole line (pole) whose scan labels disagree half the time.
  std::vector<Eigen::Vector3f> floor_pts;
  std::vector<Class> floor_labels;
  for (int i = -10; i <= 10; ++i) {
    for (int j = -10; j <= 10; ++j) {
      floor_pts.emplace_back(0.2F * static_cast<float>(i), 0.2F * static_cast<float>(j), 0.0F);
      floor_labels.push_back(i < 0 ? Class::kSidewalk : Class::kRoad);
    }
  }
  std::vector<Eigen::Vector3f> pole_pts;
  std::vector<Class> pole_labels;
  for (int k = 0; k < 40; ++k) {
    pole_pts.emplace_back(1.0F, 1.0F, 0.05F * static_cast<float>(k));
    pole_labels.push_back(k % 2 == 0 ? Class::kPole : Class::kTrafficSign);
  }
  FeatureMap surface_map(semlio::FeatureKind::kPlane);
  surface_map.build(floor_pts, floor_labels, 5);
  FeatureMap corner_map(semlio::FeatureKind::kLine);
  corner_map.build(pole_pts, pole_labels, 5);

  FeatureSet surfaces;
  for (std::size_t i = 0; i < floor_pts.size(); i += 7) {
    surfaces.points.push_back(floor_pts[i] + Eigen::Vector3f(0.05F, 0.05F, 0.0F));
    surfaces.labels.push_back(floor_labels[i]);
  }
  FeatureSet corners;
  for (int k = 3; k < 37; k += 3) {
    corners.points.emplace_back(1.0F, 1.0F, 0.05F * static_cast<float>(k) + 0.01F);
    corners.labels.push_back(Class::kPole);
  }

  using WeightedLine = semlio::SemanticWeighted<semlio::PointToLine>;
  using WeightedPlane = semlio::SemanticWeighted<semlio::PointToPlane>;
  using Weighted = semlio::LoamResiduals<WeightedLine, WeightedPlane>;
  using Problem = semlio::ScanToMapProblem<semlio::NearestK, WeightedLine, WeightedPlane>;
  // Weights that count the same class only: kappa over the 19 classes.
  const semlio::SemanticWeightConfig same_class{.static_classes_agree = false};
  Problem problem(semlio::NearestK{}, Weighted{WeightedLine(semlio::PointToLine{}, same_class),
                                               WeightedPlane(semlio::PointToPlane{}, same_class)});
  static_assert(Problem::kWeighsLabels);
  problem.set_maps(corner_map, surface_map);
  problem.set_features(corners, surfaces);
  CHECK(std::isnan(problem.corner_label_reliability()));  // nothing associated yet
  problem.associate(semlio::SE3d());

  LabelAgreement corner_expected;
  corner_expected.add(corners, problem.corner_matches(), corner_map);
  LabelAgreement surface_expected;
  surface_expected.add(surfaces, problem.surface_matches(), surface_map);
  REQUIRE(corner_expected.pairs() > 0);
  REQUIRE(surface_expected.pairs() > 0);
  CHECK(problem.corner_label_reliability() == corner_expected.kappa());
  CHECK(problem.surface_label_reliability() == surface_expected.kappa());
  // The two kinds differ here (poles half mislabelled), so one joint kappa would be wrong for both.
  CHECK(problem.corner_label_reliability() < problem.surface_label_reliability());

  // The default weights count two static classes as agreeing, and their
  // kappa counts agreement the same way: pole / sign and sidewalk / road are
  // all static here, so every pair agrees by chance alone and kappa is 0.
  Problem merged(semlio::NearestK{}, Weighted{WeightedLine{}, WeightedPlane{}});
  merged.set_maps(corner_map, surface_map);
  merged.set_features(corners, surfaces);
  merged.associate(semlio::SE3d());
  CHECK(merged.corner_label_reliability() == corner_expected.kappa(true));
  CHECK(merged.surface_label_reliability() == surface_expected.kappa(true));
  CHECK(merged.corner_label_reliability() == 0.0);
  CHECK(merged.surface_label_reliability() == 0.0);

  // Residuals without semantic weights take no kappa and report none.
  semlio::ScanToMapProblem<semlio::NearestK, semlio::PointToLine, semlio::PointToPlane> plain(
      semlio::NearestK{}, semlio::LoamResiduals<semlio::PointToLine, semlio::PointToPlane>{semlio::PointToLine{},
                                                                                         semlio::PointToPlane{}});
  static_assert(!decltype(plain)::kWeighsLabels);
  plain.set_maps(corner_map, surface_map);
  plain.set_features(corners, surfaces);
  plain.associate(semlio::SE3d());
  CHECK(std::isnan(plain.surface_label_reliability()));
}

}  // namespace test_scan_to_map
