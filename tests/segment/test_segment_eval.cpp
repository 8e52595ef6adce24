// semlio_segment_eval's measurement on a labelled sequence folder
// (examples/segment/segment_eval.hpp): a hand-made 3-scan SemanticKITTI
// folder whose IoUs are worked out by hand below, with a fake segmenter that
// predicts the class written into each point's intensity.
#include <catch2/catch.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/core/labels.hpp>
#include <semlio/core/scan.hpp>
#include <semlio/eval/miou.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/segment/geometric_segmenter.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/io_kitti_tmp.hpp>

#include "segment_eval.hpp"

namespace test_segment_eval {  // one namespace per test file: the area compiles as one TU

using semlio::Class;

namespace {

// Predicts, for each point, the learning class whose id is its intensity.
struct IntensitySegmenter {
  void segment(semlio::Scan& scan) const {
    scan.labels.resize(scan.size());
    for (std::size_t i = 0; i < scan.size(); ++i) scan.labels[i] = static_cast<Class>(scan.intensity[i]);
  }
};

// One point: raw SemanticKITTI label (truth) and predicted class id.
struct Pt {
  std::uint32_t raw;
  Class pred;
};

void write_frame(const semlio_test::KittiTempDir& dir, const std::string& stem, const std::vector<Pt>& pts,
                 bool with_label = true) {
  semlio::Scan scan;
  std::vector<std::uint32_t> raw;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    // Points on a ring 10 m out (never (0,0,0), which the reader drops).
    scan.points.emplace_back(10.0F, static_cast<float>(i), -1.0F);
    scan.intensity.push_back(static_cast<float>(static_cast<int>(pts[i].pred)));
    raw.push_back(pts[i].raw);
  }
  semlio::io::write_kitti_bin(dir.file("seq/velodyne/" + stem + ".bin"), scan);
  if (with_label) semlio::io::write_label_file(dir.file("seq/labels/" + stem + ".label"), raw);
}

// Scan A (frame 3), truth -> prediction:
//   road 40 -> road; lane-marking 60 (= road) -> sidewalk; sidewalk 48 ->
//   sidewalk; moving-car 252 (= car) -> car; car 10 -> vegetation;
//   other-structure 52 (ignored) -> building; moving-person 254 (= person) ->
//   unlabeled (a miss); building 50 with instance 5 -> building.
const std::vector<Pt> kScanA{{40, Class::kRoad},    {60, Class::kSidewalk},        {48, Class::kSidewalk},
                             {252, Class::kCar},    {10, Class::kVegetation},      {52, Class::kBuilding},
                             {254, Class::kUnlabeled}, {50u | (5u << 16), Class::kBuilding}};
// Scan B (frame 4): vegetation -> vegetation; trunk -> vegetation; road ->
// road; pole -> traffic-sign.
const std::vector<Pt> kScanB{{70, Class::kVegetation}, {71, Class::kVegetation}, {40, Class::kRoad},
                             {80, Class::kTrafficSign}};

double iou(const semlio::eval::MiouReport& r, Class c) { return r.iou[static_cast<std::size_t>(semlio::index(c))]; }
bool counted(const semlio::eval::MiouReport& r, Class c) {
  return r.counted[static_cast<std::size_t>(semlio::index(c))];
}

}  // namespace

TEST_CASE("coarse_class groups the 19 classes as issue #38 does", "[segment][segment_eval]") {
  using semlio_examples::coarse_class;
  CHECK(coarse_class(Class::kUnlabeled) == 0);
  for (const Class c : {Class::kRoad, Class::kParking, Class::kSidewalk, Class::kOtherGround, Class::kTerrain}) {
    CHECK(coarse_class(c) == 1);
  }
  CHECK(coarse_class(Class::kBuilding) == 2);
  CHECK(coarse_class(Class::kFence) == 2);
  CHECK(coarse_class(Class::kVegetation) == 3);
  CHECK(coarse_class(Class::kTrunk) == 3);
  for (const Class c : {Class::kCar, Class::kBicycle, Class::kMotorcycle, Class::kTruck, Class::kOtherVehicle}) {
    CHECK(coarse_class(c) == 4);
  }
  for (const Class c : {Class::kPerson, Class::kBicyclist, Class::kMotorcyclist}) CHECK(coarse_class(c) == 5);
  CHECK(coarse_class(Class::kPole) == 6);
  CHECK(coarse_class(Class::kTrafficSign) == 6);
  CHECK(std::string(semlio_examples::kCoarseNames[6]) == "pole/sign");
}

TEST_CASE("a hand-made labelled sequence gives the IoUs worked out by hand", "[segment][segment_eval]") {
  const semlio_test::KittiTempDir dir("segment_eval");
  write_frame(dir, "000002", kScanB);
  write_frame(dir, "000003", kScanA);
  write_frame(dir, "000004", kScanB);
  write_frame(dir, "000007", kScanB, /*with_label=*/false);
  semlio_test::write_text(dir.file("seq/velodyne/notes.bin"), "not a frame");
  const std::string seq = dir.str() + "/seq";

  const auto frames = semlio_examples::list_labelled_frames(seq, "", 3, 5, 0);
  REQUIRE(frames.size() == 2);
  CHECK(frames[0].name == "000003");
  CHECK(frames[0].index == 3);
  CHECK(frames[1].name == "000004");
  CHECK(semlio_examples::list_labelled_frames(seq, "", 3, 5, 1).size() == 1);
  CHECK(semlio_examples::list_labelled_frames(seq, "", 0, 4, 0).size() == 3);
  // Frame 7 has no label file; frames 8.. do not exist.
  CHECK_THROWS_AS(semlio_examples::list_labelled_frames(seq, "", 3, 10, 0), semlio::IoError);
  CHECK_THROWS_AS(semlio_examples::list_labelled_frames(seq, "", 8, 10, 0), semlio::IoError);
  CHECK_THROWS_AS(semlio_examples::list_labelled_frames(dir.str() + "/nothing", "", 0, 10, 0), semlio::IoError);

  const IntensitySegmenter seg;
  const auto a = semlio_examples::evaluate_frame(frames[0], seg, /*kitti_correction=*/false);
  const auto b = semlio_examples::evaluate_frame(frames[1], seg, /*kitti_correction=*/true);
  CHECK(a.points == 8);
  CHECK(b.points == 4);

  // Scan A. road: TP 1 (40), FN 1 (60 -> sidewalk): 1/2. sidewalk: TP 1, FP 1:
  // 1/2. car: TP 1 (252), FN 1 (10 -> vegetation): 1/2. vegetation: FP 1: 0.
  // building: TP 1 (the other-structure point is ignored, not a FP): 1.
  // person: FN 1 (unlabeled prediction): 0. mIoU over these 6: 2.5 / 6.
  const auto ra = a.matrix.report();
  CHECK(ra.points == 7);
  CHECK(ra.classes == 6);
  CHECK(iou(ra, Class::kRoad) == Approx(0.5));
  CHECK(iou(ra, Class::kSidewalk) == Approx(0.5));
  CHECK(iou(ra, Class::kCar) == Approx(0.5));
  CHECK(counted(ra, Class::kVegetation));
  CHECK(iou(ra, Class::kVegetation) == 0.0);
  CHECK(iou(ra, Class::kBuilding) == Approx(1.0));
  CHECK(counted(ra, Class::kPerson));
  CHECK(iou(ra, Class::kPerson) == 0.0);
  CHECK_FALSE(counted(ra, Class::kTrunk));
  CHECK(ra.miou == Approx(2.5 / 6.0));
  // Coarse A: ground 3/3 = 1, structure 1, vegetation (FP only) 0, vehicle 1/2,
  // human 0; pole/sign absent. Mean over 5: 2.5 / 5.
  const auto ca = semlio_examples::coarse_report(a.matrix);
  CHECK(ca.classes == 5);
  CHECK(ca.iou[1] == Approx(1.0));
  CHECK(ca.iou[2] == Approx(1.0));
  CHECK(ca.iou[3] == 0.0);
  CHECK(ca.iou[4] == Approx(0.5));
  CHECK(ca.iou[5] == 0.0);
  CHECK_FALSE(ca.counted[6]);
  CHECK(ca.miou == Approx(0.5));

  // Scan B: vegetation TP 1 FP 1 (the trunk): 1/2; trunk 0; road 1; pole 0;
  // traffic-sign 0 (FP only). mIoU 1.5 / 5. Coarse: vegetation 1, ground 1,
  // pole/sign 1.
  const auto rb = b.matrix.report();
  CHECK(rb.classes == 5);
  CHECK(iou(rb, Class::kVegetation) == Approx(0.5));
  CHECK(rb.miou == Approx(0.3));
  const auto cb = semlio_examples::coarse_report(b.matrix);
  CHECK(cb.classes == 3);
  CHECK(cb.miou == Approx(1.0));

  // Pooled: road 2/3 (TP A40, B40; FN A60); sidewalk 1/2; car 1/2; vegetation
  // 1/3 (TP B70; FP A10, B71); building 1; person, trunk, pole, sign 0.
  // mIoU (2/3 + 1/2 + 1/2 + 1/3 + 1) / 9 = 1/3. Coarse: ground 1, structure 1,
  // vegetation 2/3, vehicle 1/2, human 0, pole/sign 1: mean 25/36.
  semlio::eval::ConfusionMatrix pooled;
  pooled.merge(a.matrix);
  pooled.merge(b.matrix);
  const auto rp = pooled.report();
  CHECK(rp.classes == 9);
  CHECK(iou(rp, Class::kRoad) == Approx(2.0 / 3.0));
  CHECK(iou(rp, Class::kVegetation) == Approx(1.0 / 3.0));
  CHECK(rp.miou == Approx(1.0 / 3.0));
  const auto cp = semlio_examples::coarse_report(pooled);
  CHECK(cp.classes == 6);
  CHECK(cp.iou[3] == Approx(2.0 / 3.0));
  CHECK(cp.miou == Approx(25.0 / 36.0));
}

TEST_CASE("the real labelled KITTI 00 scans: every point scored, IoUs in [0, 1]", "[segment][segment_eval]") {
  const auto frames = semlio_examples::list_labelled_frames(
      semlio_test::data_path("kitti/sequences/00"), semlio_test::data_path("kitti/semantickitti_00_labels"), 0, 1, 0);
  REQUIRE(frames.size() == 2);
  const semlio::GeometricSegmenter seg;
  for (const auto& f : frames) {
    const auto r = semlio_examples::evaluate_frame(f, seg, true);
    // 124 668 / 124 605 points (tests/data/kitti/README.md), none dropped.
    CHECK(r.points == (f.index == 0 ? 124668U : 124605U));
    const auto rep = r.matrix.report();
    CHECK(rep.points > r.points / 2);  // most points carry a label
    CHECK(rep.points <= r.points);
    for (const double v : rep.iou) {
      CHECK(v >= 0.0);
      CHECK(v <= 1.0);
    }
    const auto c = semlio_examples::coarse_report(r.matrix);
    CHECK(c.counted[1]);  // a street scan has ground
    CHECK(c.iou[1] > 0.5);
    CHECK(c.miou >= 0.0);
    CHECK(c.miou <= 1.0);
  }
}

TEST_CASE("the real labelled KITTI 00 scans: GeometricSegmenter reaches issue #38's goals", "[segment][segment_eval]") {
  // Issue #38's goals on real scans, per scan and pooled: 19-class mIoU >=
  // 0.35 and coarse-class mIoU >= 0.65. Two consecutive scans of one street
  // are a check, not a benchmark (docs/results.md, segmenter IoU).
  const auto frames = semlio_examples::list_labelled_frames(
      semlio_test::data_path("kitti/sequences/00"), semlio_test::data_path("kitti/semantickitti_00_labels"), 0, 1, 0);
  REQUIRE(frames.size() == 2);
  const semlio::GeometricSegmenter seg;
  semlio::eval::ConfusionMatrix pooled;
  for (const auto& f : frames) {
    const auto r = semlio_examples::evaluate_frame(f, seg, true);
    const double miou = r.matrix.report().miou;
    const double coarse = semlio_examples::coarse_report(r.matrix).miou;
    INFO("scan " << f.index << ": mIoU " << miou << ", coarse " << coarse);
    CHECK(miou >= 0.35);
    CHECK(coarse >= 0.65);
    pooled.merge(r.matrix);
  }
  const auto rep = pooled.report();
  INFO("pooled: mIoU " << rep.miou << ", sidewalk " << rep.iou[static_cast<int>(Class::kSidewalk)]);
  CHECK(rep.miou >= 0.35);
  CHECK(semlio_examples::coarse_report(pooled).miou >= 0.65);
  // Much of this street's sidewalk lies beside the vehicle, where the walk
  // outwards cannot see its kerb; the kerbs along the rings find it
  // (detail/polar_ground.hpp, mark_raised_arcs). Measured with
  // semlio_segment_eval: 0.32 pooled, 0.21 when a kerb must be a step
  // between neighbouring sectors and the rings are walked one way only.
  CHECK(rep.iou[static_cast<int>(Class::kSidewalk)] >= 0.3);
}

}  // namespace test_segment_eval
