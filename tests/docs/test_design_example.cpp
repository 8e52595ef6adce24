// The code of docs/design.md's "Writing your own policies" example, compiled
// and run here; test_docs.cpp checks that the doc shows exactly the lines
// between the two markers.
#include <catch2/catch.hpp>

#include <semlio_test/data.hpp>

// [design-example-begin]
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <semlio/semlio.hpp>

namespace my_policies {

using namespace semlio;

/// Segmenter: labels points below the sensor's mounting height as road,
/// everything else as building (a stand-in for a network's labels).
struct HeightSegmenter {
  float ground_z_m = -1.5F;  ///< points lower than this (sensor frame) are road [m]
  void segment(Scan& scan) const {
    scan.labels.resize(scan.points.size());
    for (std::size_t i = 0; i < scan.points.size(); ++i) {
      scan.labels[i] = scan.points[i].z() < ground_z_m ? Class::kRoad : Class::kBuilding;
    }
  }
};
static_assert(Segmenter<HeightSegmenter>);

/// Associator: NearestK's matches, cut to the closest `keep` (a decorator;
/// the map and scan bindings pass through).
class ClosestOnly {
 public:
  explicit ClosestOnly(int keep) : keep_(static_cast<std::uint8_t>(keep)) {}
  void set_map(const FeatureMap& map) { inner_.set_map(map); }
  void set_scan(const std::vector<Eigen::Vector3f>& points_scan) { inner_.set_scan(points_scan); }
  void associate(const SE3d& T_map_scan, Correspondences& out) const {
    inner_.associate(T_map_scan, out);
    for (FeatureMatches& m : out) m.count = std::min(m.count, keep_);
  }

 private:
  NearestK inner_;
  std::uint8_t keep_;
};
static_assert(Associator<ClosestOnly, FeatureMap>);

/// Residual decorator: any residual, its r and J scaled by a constant.
template <Residual R>
struct Scaled {
  static constexpr int kDim = R::kDim;
  R inner;
  double scale = 1.0;
  [[nodiscard]] ResidualTerm<kDim> evaluate(const FeaturePoint& feature, const MatchedPoints& matches,
                                            const SE3d& T_map_scan) const {
    ResidualTerm<kDim> term = inner.evaluate(feature, matches, T_map_scan);
    term.r *= scale;
    term.J_r_xi *= scale;
    return term;
  }
};
static_assert(Residual<Scaled<PointToPlane>>);

/// KeyframePolicy: a keyframe every `every_m` metres or `every_s` seconds.
struct DistanceOrTime {
  double every_m = 2.0;  ///< [m]
  double every_s = 1.0;  ///< [s]
  [[nodiscard]] bool is_keyframe(const KeyframeEvidence& e) const {
    return e.T_lastkf_current.translation().norm() > every_m || e.elapsed_s > every_s;
  }
};
static_assert(KeyframePolicy<DistanceOrTime>);

/// The four together: CTAD deduces Odometry<HeightSegmenter, ClosestOnly, ...>.
inline auto make_odometry() {
  return Odometry(HeightSegmenter{}, ClosestOnly(3),
                  LoamResiduals{PointToLine{}, Scaled<PointToPlane>{PointToPlane{}, 0.5}}, DistanceOrTime{},
                  OdometryConfig{.kitti_vertical_correction = true});
}

}  // namespace my_policies
// [design-example-end]

namespace test_design_example {

using namespace semlio;

TEST_CASE("design.md's custom policies track the two real KITTI scans", "[docs]") {
  auto odom = my_policies::make_odometry();
  Scan a = io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  a.stamp_s = 0.0;
  const FrameReport r0 = odom.process(a);
  CHECK(r0.status == OdometryStatus::kInitialized);
  CHECK(r0.keyframe);
  Scan b = io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000001.bin"));
  b.stamp_s = 0.1;
  const FrameReport r1 = odom.process(b);
  CHECK((r1.status == OdometryStatus::kTracked || r1.status == OdometryStatus::kDegenerate));
  // Scan alignment gives ~0.69 m forward between these frames (tests/data README);
  // the same bound tests/pipeline/test_odometry.cpp uses for the shipped policies.
  CHECK(r1.T_map_lidar.translation().x() == Approx(0.69).margin(0.08));
  // 0.69 m after 0.1 s: neither 2 m nor 1 s, so no keyframe.
  CHECK_FALSE(r1.keyframe);
  // ClosestOnly(3) keeps ranks 1-3 only: eq. 23's histogram (indexed by the
  // 1-based rank) is empty beyond.
  const auto& ranks = odom.rank_histogram();
  std::uint64_t low = 0;
  std::uint64_t high = 0;
  for (std::size_t rank = 1; rank < ranks.size(); ++rank) (rank <= 3 ? low : high) += ranks[rank];
  CHECK(low > 0);
  CHECK(high == 0);
}

TEST_CASE("design.md's HeightSegmenter labels every point by its height", "[docs]") {
  Scan s;
  s.points = {Point3f(5.0F, 0.0F, -1.7F), Point3f(5.0F, 0.0F, 0.5F)};
  my_policies::HeightSegmenter{}.segment(s);
  REQUIRE(s.labels.size() == 2);
  CHECK(s.labels[0] == Class::kRoad);
  CHECK(s.labels[1] == Class::kBuilding);
}

}  // namespace test_design_example
