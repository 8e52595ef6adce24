// LabelAgreement (map/label_agreement.hpp): Cohen's kappa of feature labels
// against their matched map points' labels, checked against kappa computed
// by hand from the 2x2 agreement table of a small case, plus its edges
// (nothing counted, one class only, unlabeled features).
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include <semlio/concepts.hpp>
#include <semlio/features/loam_features.hpp>
#include <semlio/map/feature_map.hpp>
#include <semlio/map/label_agreement.hpp>

namespace test_label_agreement {

using semlio::Class;
using semlio::FeatureMap;
using semlio::FeatureMatches;
using semlio::FeatureSet;
using semlio::LabelAgreement;

namespace {

// A map of n points on a line with the given labels (positions do not matter here).
FeatureMap line_map(const std::vector<Class>& labels) {
  std::vector<Eigen::Vector3f> pts;
  for (std::size_t i = 0; i < labels.size(); ++i) pts.emplace_back(static_cast<float>(i), 0.0F, 0.0F);
  FeatureMap map;
  map.build(pts, labels, 2);
  return map;
}

FeatureMatches matches_of(const std::vector<std::uint32_t>& idx) {
  FeatureMatches m;
  for (std::size_t k = 0; k < idx.size(); ++k) m.index[k] = idx[k];
  m.count = static_cast<std::uint8_t>(idx.size());
  return m;
}

}  // namespace

TEST_CASE("LabelAgreement: kappa equals Cohen's kappa of the pair table", "[map][semantic]") {
  // Map: 0..3 road, 4..7 building.
  const FeatureMap map = line_map({Class::kRoad, Class::kRoad, Class::kRoad, Class::kRoad, Class::kBuilding,
                                   Class::kBuilding, Class::kBuilding, Class::kBuilding});
  FeatureSet f;
  f.points.assign(4, Eigen::Vector3f::Zero());
  f.labels = {Class::kRoad, Class::kRoad, Class::kBuilding, Class::kBuilding};
  // Pairs (feature label, map label):
  //   f0 road: road, road, road, building     -> 3 agree
  //   f1 road: road, building                 -> 1 agree
  //   f2 building: building, building, road   -> 2 agree
  //   f3 building: building                   -> 1 agree
  const semlio::Correspondences c{matches_of({0, 1, 2, 4}), matches_of({3, 5}), matches_of({6, 7, 0}),
                                  matches_of({4})};
  LabelAgreement a;
  a.add(f, c, map);
  // 10 pairs, 7 agree. Feature side: road 6, building 4; map side: road
  // 3+1+1 = 5, building 1+1+2+1 = 5. Chance 0.6*0.5 + 0.4*0.5 = 0.5.
  REQUIRE(a.pairs() == 10);
  CHECK(a.observed() == Approx(0.7));
  CHECK(a.chance() == Approx(0.5));
  CHECK(a.kappa() == Approx((0.7 - 0.5) / (1.0 - 0.5)));

  // Worse than chance clamps to 0.
  LabelAgreement worse;
  FeatureSet g = f;
  g.labels = {Class::kBuilding, Class::kBuilding, Class::kRoad, Class::kRoad};
  worse.add(g, c, map);
  CHECK(worse.observed() == Approx(0.3));
  CHECK(worse.kappa() == 0.0);

  // Perfect agreement between two classes: kappa 1.
  LabelAgreement perfect;
  const semlio::Correspondences same{matches_of({0, 1}), matches_of({2}), matches_of({4, 5}), matches_of({6})};
  perfect.add(f, same, map);
  CHECK(perfect.kappa() == Approx(1.0));
}

TEST_CASE("LabelAgreement: no pairs, one class or unlabeled features give kappa 0", "[map][semantic]") {
  const FeatureMap map = line_map({Class::kRoad, Class::kRoad, Class::kRoad});
  FeatureSet f;
  f.points.assign(2, Eigen::Vector3f::Zero());
  f.labels = {Class::kRoad, Class::kRoad};
  const semlio::Correspondences c{matches_of({0, 1}), matches_of({2})};

  LabelAgreement none;
  CHECK(none.pairs() == 0);
  CHECK(none.kappa() == 0.0);

  LabelAgreement one_class;  // every pair agrees, but so would chance
  one_class.add(f, c, map);
  CHECK(one_class.observed() == 1.0);
  CHECK(one_class.chance() == 1.0);
  CHECK(one_class.kappa() == 0.0);

  FeatureSet unlabeled = f;
  unlabeled.labels = {Class::kUnlabeled, Class::kUnlabeled};
  LabelAgreement skipped;
  skipped.add(unlabeled, c, map);
  CHECK(skipped.pairs() == 0);
  FeatureSet no_labels = f;
  no_labels.labels.clear();
  skipped.add(no_labels, c, map);
  CHECK(skipped.pairs() == 0);
}

TEST_CASE("LabelAgreement: with static classes merged, kappa counts agreement as the default weight does",
          "[map][semantic]") {
  // Map: 0..3 road, 4..5 sidewalk, 6..7 car.
  const FeatureMap map = line_map({Class::kRoad, Class::kRoad, Class::kRoad, Class::kRoad, Class::kSidewalk,
                                   Class::kSidewalk, Class::kCar, Class::kCar});
  FeatureSet f;
  f.points.assign(4, Eigen::Vector3f::Zero());
  f.labels = {Class::kRoad, Class::kSidewalk, Class::kCar, Class::kRoad};
  // Pairs (feature label, map label):
  //   f0 road: road, road, sidewalk   -> same class 2, static 3
  //   f1 sidewalk: sidewalk, road     -> same class 1, static 2
  //   f2 car: car, car, road          -> same class 2, static 2
  //   f3 road: car                    -> 0, 0
  const semlio::Correspondences c{matches_of({0, 1, 4}), matches_of({5, 2}), matches_of({6, 7, 3}),
                                  matches_of({6})};
  LabelAgreement a;
  a.add(f, c, map);
  // 9 pairs. Same class: 5 agree; static classes merged: 7 agree.
  // Feature side: road 4, sidewalk 2, car 3 (static 6); map side: road 4,
  // sidewalk 2, car 3 (static 6).
  REQUIRE(a.pairs() == 9);
  CHECK(a.observed() == Approx(5.0 / 9.0));
  CHECK(a.observed(true) == Approx(7.0 / 9.0));
  const double chance_classes = (4.0 * 4.0 + 2.0 * 2.0 + 3.0 * 3.0) / 81.0;
  const double chance_merged = (6.0 * 6.0 + 3.0 * 3.0) / 81.0;
  CHECK(a.chance() == Approx(chance_classes));
  CHECK(a.chance(true) == Approx(chance_merged));
  CHECK(a.kappa() == Approx((5.0 / 9.0 - chance_classes) / (1.0 - chance_classes)));
  CHECK(a.kappa(true) == Approx((7.0 / 9.0 - chance_merged) / (1.0 - chance_merged)));

  // Only static classes: merged, every pair agrees by chance, kappa exactly
  // 0 (the chance term is summed from counts, so it is exactly 1).
  const FeatureMap statics = line_map({Class::kRoad, Class::kSidewalk, Class::kTerrain, Class::kBuilding,
                                       Class::kVegetation, Class::kTrunk, Class::kPole});
  FeatureSet g;
  g.points.assign(3, Eigen::Vector3f::Zero());
  g.labels = {Class::kRoad, Class::kVegetation, Class::kPole};
  const semlio::Correspondences d{matches_of({0, 1, 2}), matches_of({4, 5, 3}), matches_of({6, 3, 5})};
  LabelAgreement s;
  s.add(g, d, statics);
  CHECK(s.observed(true) == 1.0);
  CHECK(s.chance(true) == 1.0);
  CHECK(s.kappa(true) == 0.0);
  CHECK(s.kappa() > 0.0);  // the 19 classes still tell them apart
}

}  // namespace test_label_agreement
