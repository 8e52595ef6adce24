// One Gauss-Newton iteration of scan-to-map registration on the real KITTI
// pair (00/000001 against a one-keyframe local map of 00/000000): associate
// (corners and surfaces), accumulate residuals + Jacobians into the 6x6
// normal equations, solve, update -- per associator / residual pair. Also the
// accumulation alone (ScanToMapProblem::linearize) and the search-structure
// builds (k-d trees alone; FeatureMap = tree + cached axes + candidate lists)
// and the map k-NN queries FeatureMap makes, by KdTree3f and SmallKdTree3f.
// Items = scan features (iteration, accumulation) or map points (builds).
#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <vector>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/associate/normal_consistency.hpp>
#include <semlio/features/loam_features.hpp>
#include <semlio/map/feature_map.hpp>
#include <semlio/map/local_map.hpp>
#include <semlio/pipeline/scan_to_map.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>
#include <semlio/residual/semantic_weighted.hpp>
#include <semlio/search/kdtree.hpp>
#include <semlio/search/small_kdtree.hpp>
#include <semlio/solve/normal_equations.hpp>
#include <semlio_test/associate_scenes.hpp>

namespace {

using semlio::SE3d;

// Scan features as FeatureSets (what ScanToMapProblem binds) and a local map.
struct KittiPair {
  semlio::LocalMap map;
  semlio::FeatureSet corners;
  semlio::FeatureSet surfaces;
  SE3d T_init;  // the extrapolated ground truth: a realistic starting guess
};

semlio::FeatureSet as_set(const semlio_test::FeatureCloud& c) {
  semlio::FeatureSet s;
  s.points = c.points;
  s.labels = c.labels;
  return s;
}

const KittiPair& kitti() {
  static const KittiPair p = [] {
    KittiPair q;
    semlio_test::build_kitti_pair_map(q.map);
    const auto scan = semlio_test::kitti_features("kitti/sequences/00/velodyne/000001.bin");
    q.corners = as_set(scan.corners);
    q.surfaces = as_set(scan.surfaces);
    q.T_init = semlio_test::kitti_T_0_1();
    return q;
  }();
  return p;
}

using Plain = semlio::LoamResiduals<semlio::PointToLine, semlio::PointToPlane>;
using Weighted = semlio::LoamResiduals<semlio::SemanticWeighted<semlio::PointToLine>,
                                       semlio::SemanticWeighted<semlio::PointToPlane>>;

template <typename A, typename Residuals>
auto make_problem(const KittiPair& p, const Residuals& residuals) {
  semlio::ScanToMapProblem<A, decltype(residuals.corner), decltype(residuals.surface)> problem(A{}, residuals);
  problem.set_maps(p.map.corners(), p.map.surfaces());
  problem.set_features(p.corners, p.surfaces);
  return problem;
}

// One iteration from the same starting pose every time: associate, linearise,
// solve H dx = -b, apply dx (right perturbation). The per-frame set_scan()
// work is outside the loop (once per frame, not per iteration).
template <typename A, typename Residuals>
void BM_GaussNewtonIteration(benchmark::State& state, Residuals residuals) {
  const KittiPair& p = kitti();
  auto problem = make_problem<A>(p, residuals);
  semlio::NormalEquations eq;
  SE3d T = p.T_init;
  for (auto _ : state) {
    T = p.T_init;
    problem.associate(T);
    eq.reset();
    problem.linearize(T, eq);
    const Eigen::Matrix<double, 6, 1> dx = eq.H.ldlt().solve(-eq.b);
    T = T * SE3d::exp(dx);
    benchmark::DoNotOptimize(T);
  }
  state.counters["residuals"] = static_cast<double>(eq.num_residuals);
  const std::size_t features = p.corners.size() + p.surfaces.size();
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(features));
}

// Residual + Jacobian accumulation alone (corners and surfaces), for fixed
// correspondences.
template <typename A, typename Residuals>
void BM_Linearize(benchmark::State& state, Residuals residuals) {
  const KittiPair& p = kitti();
  auto problem = make_problem<A>(p, residuals);
  problem.associate(p.T_init);
  semlio::NormalEquations eq;
  for (auto _ : state) {
    eq.reset();
    problem.linearize(p.T_init, eq);
    benchmark::DoNotOptimize(eq.H.data());
  }
  state.counters["residuals"] = static_cast<double>(eq.num_residuals);
  const std::size_t features = p.corners.size() + p.surfaces.size();
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(features));
}

// The k-d tree alone over the surface map's points.
void BM_KdTreeBuild(benchmark::State& state) {
  const std::vector<Eigen::Vector3f>& points = kitti().map.surfaces().points();
  semlio::KdTree3f tree;
  for (auto _ : state) {
    tree.build(points);
    benchmark::DoNotOptimize(&tree);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(points.size()));
}

// SmallKdTree3f (FeatureMap's tree) over the same points, rebuilt in place.
void BM_SmallKdTreeBuild(benchmark::State& state) {
  const std::vector<Eigen::Vector3f>& points = kitti().map.surfaces().points();
  semlio::SmallKdTree3f tree;
  for (auto _ : state) {
    tree.build(points);
    benchmark::DoNotOptimize(&tree);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(points.size()));
}

// The k-NN queries FeatureMap sends its tree, on the surface map, by each
// tree: kRefill = a NearestCache refill (20 nearest within (1 m + 0.1 m)^2,
// at the scan's surface features moved by the starting guess), kList = a
// candidate list (32 nearest, unbounded, at every map point), kAxis = a
// shape axis's neighbourhood (10 nearest, unbounded, at every map point).
enum class MapQuery { kRefill, kList, kAxis };

template <typename Tree>
void BM_MapKnn(benchmark::State& state, MapQuery query) {
  const KittiPair& p = kitti();
  const std::vector<Eigen::Vector3f>& points = p.map.surfaces().points();
  const Tree tree = [&] {
    Tree t;
    t.build(points);
    return t;
  }();
  std::vector<Eigen::Vector3f> queries;
  if (query == MapQuery::kRefill) {
    const Eigen::Matrix3f R = p.T_init.rotation().cast<float>();
    const Eigen::Vector3f t = p.T_init.translation().cast<float>();
    for (const auto& f : p.surfaces.points) queries.emplace_back(R * f + t);
  } else {
    queries = points;
  }
  const std::size_t k = query == MapQuery::kRefill ? 20 : query == MapQuery::kList ? 32 : 10;
  const float bound2 = semlio::detail::float_gate(1.1 * 1.1);
  std::vector<std::uint32_t> idx(k);
  std::vector<float> d2(k);
  std::size_t found = 0;
  for (auto _ : state) {
    for (const auto& q : queries) {
      found += query == MapQuery::kRefill ? tree.knn(q, k, idx.data(), d2.data(), bound2)
                                          : tree.knn(q, k, idx.data(), d2.data());
    }
    benchmark::DoNotOptimize(found);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(queries.size()));
}

// A FeatureMap over the surface map's points: tree + 10-point axes +
// candidate lists (candidate_list = 0: tree + axes only).
void BM_FeatureMapBuild(benchmark::State& state, int candidate_list) {
  const semlio::FeatureMap& source = kitti().map.surfaces();
  const std::vector<Eigen::Vector3f> points = source.points();
  const std::vector<semlio::Class> labels = source.labels();
  semlio::FeatureMap map(semlio::FeatureKind::kPlane);
  for (auto _ : state) {
    map.build(points, labels, 10, candidate_list);
    benchmark::DoNotOptimize(map.axes().data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(points.size()));
}

}  // namespace

int main(int argc, char** argv) {
  const Plain plain{semlio::PointToLine{}, semlio::PointToPlane{}};
  const Weighted weighted{semlio::SemanticWeighted<semlio::PointToLine>{},
                          semlio::SemanticWeighted<semlio::PointToPlane>{}};
  benchmark::RegisterBenchmark("GaussNewtonIteration/NearestK/kitti", BM_GaussNewtonIteration<semlio::NearestK, Plain>,
                               plain)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("GaussNewtonIteration/NormalConsistency/kitti",
                               BM_GaussNewtonIteration<semlio::NormalConsistency, Weighted>, weighted)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("Linearize/PointToLine+PointToPlane/kitti", BM_Linearize<semlio::NearestK, Plain>, plain)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("Linearize/SemanticWeighted/kitti", BM_Linearize<semlio::NormalConsistency, Weighted>,
                               weighted)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("KdTreeBuild/kitti_surface_map", BM_KdTreeBuild)->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("SmallKdTreeBuild/kitti_surface_map", BM_SmallKdTreeBuild)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("MapKnn/refill/KdTree3f", BM_MapKnn<semlio::KdTree3f>, MapQuery::kRefill)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("MapKnn/refill/SmallKdTree3f", BM_MapKnn<semlio::SmallKdTree3f>, MapQuery::kRefill)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("MapKnn/list/KdTree3f", BM_MapKnn<semlio::KdTree3f>, MapQuery::kList)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("MapKnn/list/SmallKdTree3f", BM_MapKnn<semlio::SmallKdTree3f>, MapQuery::kList)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("MapKnn/axis/KdTree3f", BM_MapKnn<semlio::KdTree3f>, MapQuery::kAxis)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("MapKnn/axis/SmallKdTree3f", BM_MapKnn<semlio::SmallKdTree3f>, MapQuery::kAxis)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("FeatureMapBuild/kitti_surface_map/no_lists", BM_FeatureMapBuild, 0)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("FeatureMapBuild/kitti_surface_map/lists32", BM_FeatureMapBuild, 32)
      ->Unit(benchmark::kMillisecond);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
