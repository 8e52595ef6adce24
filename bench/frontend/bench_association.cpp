// Association kernel benchmarks: NearestK vs NormalConsistency vs the literal
// NormalConsistencyReference, on a real KITTI scan (000001) against a local
// map built from the neighbouring real scan (000000), on two consecutive
// simulated urban sweeps (semlio::sim, in memory) and on the synthetic
// street; plus the per-frame preparation, the local-map build and its voxel
// downsampling (radix sort against its reference), and residual +
// Jacobian accumulation into 6x6 normal equations. Items = scan features.
// scripts/bench_association.sh runs this and prints the ratios.
#include <benchmark/benchmark.h>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/associate/normal_consistency.hpp>
#include <semlio/associate/normal_consistency_reference.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/map/local_map.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>
#include <semlio/residual/robust.hpp>
#include <semlio/residual/semantic_weighted.hpp>
#include <semlio_test/associate_scenes.hpp>
#include <semlio_test/frontend_sim_pair.hpp>

namespace {

using semlio::SE3d;

// One association problem: a built local map, the query features, a pose.
struct Problem {
  semlio::LocalMap map;
  std::vector<Eigen::Vector3f> surfaces;
  std::vector<Eigen::Vector3f> corners;
  std::vector<semlio::Class> surface_labels;
  SE3d T_map_scan;
};

// LOAM features of KITTI 00 scan 000001 against a local map of those of 000000.
const Problem& kitti() {
  static const Problem p = [] {
    Problem q;
    semlio_test::build_kitti_pair_map(q.map);
    const auto scan = semlio_test::kitti_features("kitti/sequences/00/velodyne/000001.bin");
    q.surfaces = scan.surfaces.points;
    q.corners = scan.corners.points;
    q.surface_labels.assign(scan.surfaces.points.size(), semlio::Class::kUnlabeled);
    q.T_map_scan = semlio_test::kitti_T_0_1();
    return q;
  }();
  return p;
}

// Dense variant: every point of 000000 (0.2 m voxels) as map, of 000001
// (0.4 m voxels) as features.
const Problem& kitti_dense() {
  static const Problem p = [] {
    Problem q;
    const auto map_cloud = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000000.bin", 0.2);
    const auto scan = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000001.bin", 0.4);
    q.map.add_keyframe(SE3d(), map_cloud, map_cloud);
    q.map.build(Eigen::Vector3d::Zero());
    q.surfaces = scan.points;
    q.surface_labels.assign(scan.points.size(), semlio::Class::kUnlabeled);
    q.T_map_scan = semlio_test::kitti_T_0_1();
    return q;
  }();
  return p;
}

const Problem& street() {
  static const Problem p = [] {
    Problem q;
    const auto scene = semlio_test::street_scene(7);
    q.map.add_keyframe(SE3d(), scene.map_corners, scene.map_surfaces);
    q.map.build(Eigen::Vector3d::Zero());
    q.surfaces = scene.scan_surfaces.points;
    q.surface_labels = scene.scan_surfaces.labels;
    q.corners = scene.scan_corners.points;
    q.T_map_scan = scene.T_map_scan;
    return q;
  }();
  return p;
}

// LOAM features of simulated urban frame 11 against a local map of frame 10
// (ground-truth relative pose).
const Problem& sim() {
  static const Problem p = [] {
    Problem q;
    const auto pair = semlio_test::sim_urban_pair();
    q.map.add_keyframe(SE3d(), pair.map_features.corners, pair.map_features.surfaces);
    q.map.build(Eigen::Vector3d::Zero());
    q.surfaces = pair.scan_features.surfaces.points;
    q.surface_labels = pair.scan_features.surfaces.labels;
    if (q.surface_labels.size() != q.surfaces.size()) q.surface_labels.assign(q.surfaces.size(), semlio::Class::kUnlabeled);
    q.corners = pair.scan_features.corners.points;
    q.T_map_scan = pair.T_map_scan;
    return q;
  }();
  return p;
}

enum class Kind { kSurfaces, kCorners };

// Times associate() alone: per Gauss-Newton iteration cost. set_scan() (per
// frame) is done once outside the loop and timed by BM_Prepare.
template <typename A>
void BM_Associate(benchmark::State& state, const Problem* (*problem)(), Kind kind) {
  const Problem& p = *problem();
  const auto& features = kind == Kind::kSurfaces ? p.surfaces : p.corners;
  A associator;
  associator.set_map(kind == Kind::kSurfaces ? p.map.surfaces() : p.map.corners());
  associator.set_scan(features);
  semlio::Correspondences out;
  for (auto _ : state) {
    associator.associate(p.T_map_scan, out);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  std::size_t matched = 0;
  for (const auto& m : out) matched += m.count > 0 ? 1U : 0U;
  state.counters["features"] = static_cast<double>(features.size());
  state.counters["matched"] = static_cast<double>(matched);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(features.size()));
}

// One frame on the odometry's path (ScanToMapProblem): set_scan (for
// NormalConsistency the scan tree and scan axes), then five re-associations
// along converging poses, as Gauss-Newton's, sharing one NearestCache that
// starts empty. BM_Associate times the per-point candidate lists instead,
// which the odometry does not use. With `cold_map` the map is rebuilt from
// the same points first (outside the timing), as after every keyframe: the
// lazily fitted map axes Algorithm 1 reads are then refitted inside it.
// Items = features x 5.
template <typename A>
void BM_AssociateFrame(benchmark::State& state, const Problem* (*problem)(), Kind kind, bool cold_map) {
  const Problem& p = *problem();
  const auto& features = kind == Kind::kSurfaces ? p.surfaces : p.corners;
  const semlio::FeatureMap& built = kind == Kind::kSurfaces ? p.map.surfaces() : p.map.corners();
  semlio::FeatureMap fresh(built.kind());
  fresh.build(built.points(), built.labels(), built.shape_neighbours());
  semlio::Correspondences out;
  semlio::NearestCache cache;
  Eigen::Matrix<double, 6, 1> xi;
  xi << 0.05, -0.03, 0.02, 0.002, -0.001, 0.003;  // 6 cm and 0.2 deg off, halved per iteration
  A associator;
  for (auto _ : state) {
    if (cold_map) {
      state.PauseTiming();
      fresh.build(built.points(), built.labels(), built.shape_neighbours());
      state.ResumeTiming();
    }
    associator.set_map(fresh);
    associator.set_scan(features);
    cache.clear();
    for (int k = 0; k < 5; ++k) {
      associator.associate(p.T_map_scan * SE3d::exp(std::pow(0.5, k) * xi), out, cache);
      benchmark::DoNotOptimize(out.data());
    }
    benchmark::ClobberMemory();
  }
  state.counters["features"] = static_cast<double>(features.size());
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * 5 * static_cast<std::int64_t>(features.size()));
}

// Per-frame preparation of NormalConsistency: scan k-d tree + scan-side axes.
void BM_Prepare(benchmark::State& state, const Problem* (*problem)()) {
  const Problem& p = *problem();
  semlio::NormalConsistency nc;
  nc.set_map(p.map.surfaces());
  for (auto _ : state) {
    nc.set_scan(p.surfaces);
    benchmark::DoNotOptimize(nc.scan_axes().data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(p.surfaces.size()));
}

// Local map build from one keyframe, from scratch (store the keyframe,
// transform, voxelise, tree, cached axes and candidate lists): LOAM features,
// or every point (dense). A fresh LocalMap per iteration, because build() is
// incremental and does nothing when the keyframe set is unchanged.
void BM_LocalMapBuild(benchmark::State& state, bool dense) {
  semlio_test::FeatureCloud corners;
  semlio_test::FeatureCloud surfaces;
  if (dense) {
    corners = semlio_test::kitti_cloud("kitti/sequences/00/velodyne/000000.bin", 0.2);
    surfaces = corners;
  } else {
    const auto f = semlio_test::kitti_features("kitti/sequences/00/velodyne/000000.bin");
    corners = f.corners;
    surfaces = f.surfaces;
  }
  const std::size_t points = corners.points.size() + surfaces.points.size();
  for (auto _ : state) {
    semlio::LocalMap map;
    map.add_keyframe(SE3d(), corners, surfaces);
    map.build(Eigen::Vector3d::Zero());
    benchmark::DoNotOptimize(map.surfaces().axes().data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(points));
}

// The map rebuild's voxel downsampling on a merged map-sized input: 40
// copies of the real KITTI scan 000000 (every 8th point), each 0.8 m further
// and 0.01 rad turned, ~0.6 M points at the corner leaf (0.2 m). Reference
// (sort of (key, index) pairs) against the radix sort with a reused workspace.
const std::vector<Eigen::Vector3f>& merged_map_input() {
  static const std::vector<Eigen::Vector3f> merged = [] {
    const semlio::Scan scan =
        semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
    std::vector<Eigen::Vector3f> out;
    for (int k = 0; k < 40; ++k) {
      const Eigen::Matrix3f R =
          Eigen::AngleAxisf(0.01F * static_cast<float>(k), Eigen::Vector3f::UnitZ()).toRotationMatrix();
      for (std::size_t i = 0; i < scan.points.size(); i += 8) {
        out.push_back(R * scan.points[i] + Eigen::Vector3f(0.8F * static_cast<float>(k), 0.0F, 0.0F));
      }
    }
    return out;
  }();
  return merged;
}

void BM_DownsampleLabelled(benchmark::State& state, bool reference) {
  const std::vector<Eigen::Vector3f>& in = merged_map_input();
  std::vector<Eigen::Vector3f> out;
  std::vector<semlio::Class> labels;
  semlio::detail::DownsampleWorkspace ws;
  for (auto _ : state) {
    if (reference) {
      semlio::detail::downsample_labelled_reference(in, {}, 0.2, out, labels);
    } else {
      semlio::detail::downsample_labelled(in, {}, 0.2, out, labels, ws);
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(in.size()));
}

// Residual + Jacobian accumulation (H = sum w J^T J, g = sum w J^T r) over the
// NormalConsistency matches of the KITTI surfaces: one Gauss-Newton build.
template <typename R>
void BM_Accumulate(benchmark::State& state) {
  const Problem& p = kitti();
  const semlio::FeatureMap& map = p.map.surfaces();
  semlio::NormalConsistency nc;
  nc.set_map(map);
  nc.set_scan(p.surfaces);
  semlio::Correspondences out;
  nc.associate(p.T_map_scan, out);
  std::vector<semlio::MatchedPoints> gathered(out.size());
  for (std::size_t i = 0; i < out.size(); ++i) gathered[i] = map.gather(out[i]);
  const R residual{};
  std::size_t used = 0;
  for (auto _ : state) {
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    used = 0;
    for (std::size_t i = 0; i < out.size(); ++i) {
      if (out[i].count == 0) continue;
      const semlio::FeaturePoint f{p.surfaces[i].cast<double>(), p.surface_labels[i]};
      const auto term = residual.evaluate(f, gathered[i], p.T_map_scan);
      if (!term.valid) continue;
      H.noalias() += term.weight * term.J_r_xi.transpose() * term.J_r_xi;
      g.noalias() += term.weight * term.J_r_xi.transpose() * term.r;
      ++used;
    }
    benchmark::DoNotOptimize(H.data());
    benchmark::DoNotOptimize(g.data());
  }
  state.counters["residuals"] = static_cast<double>(used);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(out.size()));
}

const Problem* kitti_ptr() { return &kitti(); }
const Problem* kitti_dense_ptr() { return &kitti_dense(); }
const Problem* street_ptr() { return &street(); }
const Problem* sim_ptr() { return &sim(); }

void register_associators(const std::string& scene, const Problem* (*problem)(), Kind kind, bool reference) {
  benchmark::RegisterBenchmark(("NearestK/" + scene).c_str(), BM_Associate<semlio::NearestK>, problem, kind)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark(("NormalConsistency/" + scene).c_str(), BM_Associate<semlio::NormalConsistency>,
                               problem, kind)
      ->Unit(benchmark::kMillisecond);
  if (reference) {
    benchmark::RegisterBenchmark(("NormalConsistencyReference/" + scene).c_str(),
                                 BM_Associate<semlio::NormalConsistencyReference>, problem, kind)
        ->Unit(benchmark::kMillisecond);
  }
}

void register_frames(const std::string& scene, const Problem* (*problem)(), Kind kind) {
  for (const bool cold : {false, true}) {
    const std::string tag = cold ? "frame_cold_map_" : "frame_";
    benchmark::RegisterBenchmark(("NearestK/" + tag + scene).c_str(), BM_AssociateFrame<semlio::NearestK>, problem,
                                 kind, cold)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("NormalConsistency/" + tag + scene).c_str(),
                                 BM_AssociateFrame<semlio::NormalConsistency>, problem, kind, cold)
        ->Unit(benchmark::kMillisecond);
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_associators("kitti_surfaces", kitti_ptr, Kind::kSurfaces, true);
  register_associators("kitti_corners", kitti_ptr, Kind::kCorners, true);
  register_associators("kitti_dense", kitti_dense_ptr, Kind::kSurfaces, true);
  register_associators("sim_surfaces", sim_ptr, Kind::kSurfaces, true);
  register_associators("sim_corners", sim_ptr, Kind::kCorners, true);
  register_associators("street_surfaces", street_ptr, Kind::kSurfaces, true);
  register_associators("street_corners", street_ptr, Kind::kCorners, true);
  register_frames("kitti_surfaces", kitti_ptr, Kind::kSurfaces);
  register_frames("kitti_corners", kitti_ptr, Kind::kCorners);
  register_frames("sim_surfaces", sim_ptr, Kind::kSurfaces);
  register_frames("sim_corners", sim_ptr, Kind::kCorners);
  benchmark::RegisterBenchmark("NormalConsistencyPrepare/kitti_surfaces", BM_Prepare, kitti_ptr)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("LocalMapBuild/kitti_features", BM_LocalMapBuild, false)->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("LocalMapBuild/kitti_dense", BM_LocalMapBuild, true)->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("DownsampleLabelled/reference/merged_map", BM_DownsampleLabelled, true)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("DownsampleLabelled/radix/merged_map", BM_DownsampleLabelled, false)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("Accumulate/PointToPlane", BM_Accumulate<semlio::PointToPlane>)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("Accumulate/SemanticWeighted<PointToPlane>",
                               BM_Accumulate<semlio::SemanticWeighted<semlio::PointToPlane>>)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("Accumulate/Robust<Huber,SemanticWeighted<PointToPlane>>",
                               BM_Accumulate<semlio::Robust<semlio::Huber, semlio::SemanticWeighted<semlio::PointToPlane>>>)
      ->Unit(benchmark::kMillisecond);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
