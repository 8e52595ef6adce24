#include <catch2/catch.hpp>

#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/eval/miou.hpp>

namespace test_miou {  // one namespace per test file: the area compiles as one TU

using semlio::Class;
using semlio::eval::ConfusionMatrix;

TEST_CASE("miou hand-computed case", "[eval]") {
  const std::vector<Class> truth{Class::kCar, Class::kCar, Class::kRoad, Class::kRoad, Class::kRoad, Class::kUnlabeled};
  const std::vector<Class> pred{Class::kCar, Class::kRoad, Class::kRoad, Class::kRoad, Class::kSidewalk, Class::kCar};
  const auto r = semlio::eval::miou(truth, pred);
  // car: TP 1, FN 1, FP 0 (the unlabeled point is ignored) -> 1/2
  // road: TP 2, FN 1 (sidewalk), FP 1 (car) -> 2/4
  // sidewalk: TP 0, FP 1 -> 0 (counted: it occurs in the predictions)
  CHECK(r.iou[semlio::index(Class::kCar)] == Approx(0.5));
  CHECK(r.iou[semlio::index(Class::kRoad)] == Approx(0.5));
  CHECK(r.iou[semlio::index(Class::kSidewalk)] == Approx(0.0));
  CHECK(r.counted[semlio::index(Class::kSidewalk)]);
  CHECK_FALSE(r.counted[semlio::index(Class::kTruck)]);
  CHECK_FALSE(r.counted[0]);
  CHECK(r.classes == 3);
  CHECK(r.miou == Approx(1.0 / 3.0));
  CHECK(r.points == 5);
  CHECK(r.accuracy == Approx(3.0 / 5.0));
}

TEST_CASE("miou perfect, unlabeled predictions and empty input", "[eval]") {
  const std::vector<Class> truth{Class::kPole, Class::kTrafficSign, Class::kPole};
  CHECK(semlio::eval::miou(truth, truth).miou == 1.0);
  CHECK(semlio::eval::miou(truth, truth).classes == 2);
  // Predicting unlabeled is a miss of the true class, a false positive of none.
  const auto r = semlio::eval::miou({Class::kRoad, Class::kRoad}, {Class::kRoad, Class::kUnlabeled});
  CHECK(r.classes == 1);
  CHECK(r.miou == Approx(0.5));
  const auto e = semlio::eval::miou({Class::kUnlabeled}, {Class::kCar});
  CHECK(e.classes == 0);
  CHECK(e.miou == 0.0);
  CHECK(e.points == 0);
}

TEST_CASE("confusion matrix accumulates and merges frames", "[eval]") {
  ConfusionMatrix a;
  a.add({Class::kCar, Class::kTruck}, {Class::kCar, Class::kCar});
  ConfusionMatrix b;
  b.add({Class::kTruck, Class::kTruck}, {Class::kTruck, Class::kTruck});
  a.merge(b);
  CHECK(a.count(Class::kTruck, Class::kCar) == 1);
  CHECK(a.count(Class::kTruck, Class::kTruck) == 2);
  const auto r = a.report();
  // car: TP 1, FP 1 -> 1/2; truck: TP 2, FN 1 -> 2/3
  CHECK(r.iou[semlio::index(Class::kCar)] == Approx(0.5));
  CHECK(r.iou[semlio::index(Class::kTruck)] == Approx(2.0 / 3.0));
  CHECK(r.miou == Approx((0.5 + 2.0 / 3.0) / 2.0));
  const std::vector<Class> one{Class::kCar};
  const std::vector<Class> none;
  CHECK_THROWS_AS(a.add(one, none), semlio::ValueError);
}

}  // namespace test_miou
