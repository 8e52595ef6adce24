// Feature-side front-end benchmarks on a real KITTI scan (00/000000.bin,
// ~124k points): LOAM feature extraction, ring inference, preprocessing,
// voxel downsampling, k-d tree build and queries, closed-form 3x3 eigen.
#include <benchmark/benchmark.h>

#include <Eigen/Eigenvalues>

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include <semlio/features/loam_features.hpp>
#include <semlio/features/pca.hpp>
#include <semlio/features/preprocess.hpp>
#include <semlio/features/rings.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/search/kdtree.hpp>
#include <semlio/search/voxel_grid.hpp>
#include <semlio_test/data.hpp>
#include <semlio_test/features_scans.hpp>

namespace {

const semlio::Scan& kitti_scan() {
  static const semlio::Scan scan = semlio_test::kitti_scan_with_rings("000000.bin");
  return scan;
}

const semlio::Scan& kitti_raw_scan() {
  static const semlio::Scan scan =
      semlio::io::read_kitti_bin(semlio_test::data_path("kitti/sequences/00/velodyne/000000.bin"));
  return scan;
}

void set_points(benchmark::State& state, std::size_t n) {
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(n));
}

void BM_LoamFeatureExtraction_KittiScan(benchmark::State& state) {
  const semlio::Scan& scan = kitti_scan();
  semlio::LoamFeatureExtractor ex;
  semlio::LoamFeatures out;
  for (auto _ : state) {
    ex.extract(scan, out);
    benchmark::DoNotOptimize(out.corners.points.data());
  }
  state.counters["corners"] = static_cast<double>(out.corners.size());
  state.counters["surfaces"] = static_cast<double>(out.surfaces.size());
  set_points(state, scan.size());
}
BENCHMARK(BM_LoamFeatureExtraction_KittiScan)->Unit(benchmark::kMillisecond);

void BM_RingInferenceFromOrder_KittiScan(benchmark::State& state) {
  semlio::Scan scan = kitti_raw_scan();
  const semlio::SensorModel sensor = semlio::SensorModel::hdl64e();
  for (auto _ : state) {
    benchmark::DoNotOptimize(semlio::infer_rings(scan, sensor).order_rings);
  }
  set_points(state, scan.size());
}
BENCHMARK(BM_RingInferenceFromOrder_KittiScan)->Unit(benchmark::kMillisecond);

// Times `op` on a fresh copy of the raw KITTI scan per iteration (the copy untimed).
template <typename Op>
void time_in_place(benchmark::State& state, Op op) {
  const semlio::Scan& raw = kitti_raw_scan();
  semlio::Scan scan;
  for (auto _ : state) {
    state.PauseTiming();
    scan = raw;
    state.ResumeTiming();
    op(scan);
    benchmark::DoNotOptimize(scan.points.data());
  }
  set_points(state, raw.size());
}

void BM_Preprocess_KittiScan(benchmark::State& state) {
  time_in_place(state, [](semlio::Scan& scan) { benchmark::DoNotOptimize(semlio::preprocess(scan).kept); });
}
BENCHMARK(BM_Preprocess_KittiScan)->Unit(benchmark::kMillisecond);

void BM_VerticalCorrection_KittiScan(benchmark::State& state) {
  time_in_place(state, [](semlio::Scan& scan) { semlio::correct_kitti_vertical_angle(scan); });
}
BENCHMARK(BM_VerticalCorrection_KittiScan)->Unit(benchmark::kMillisecond);

void BM_VoxelDownsample_KittiScan(benchmark::State& state) {
  const semlio::Scan& scan = kitti_scan();
  const double leaf_m = static_cast<double>(state.range(0)) / 100.0;
  semlio::VoxelGrid grid({.leaf_size_m = leaf_m});
  std::vector<Eigen::Vector3f> out;
  std::vector<semlio::Class> labels;
  std::vector<std::uint32_t> first;
  for (auto _ : state) {
    grid.downsample(scan.points, {}, out, labels, first);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["voxels"] = static_cast<double>(out.size());
  set_points(state, scan.size());
}
BENCHMARK(BM_VoxelDownsample_KittiScan)->Arg(20)->Arg(40)->Arg(100)->Unit(benchmark::kMillisecond);

// The same with a label per point, all one class: what the odometry's surface
// voxels see without a segmenter (NoLabels), where every voxel holds one label.
void BM_VoxelDownsample_KittiScanOneLabel(benchmark::State& state) {
  const semlio::Scan& scan = kitti_scan();
  const double leaf_m = static_cast<double>(state.range(0)) / 100.0;
  semlio::VoxelGrid grid({.leaf_size_m = leaf_m});
  const std::vector<semlio::Class> in_labels(scan.size(), semlio::Class::kUnlabeled);
  std::vector<Eigen::Vector3f> out;
  std::vector<semlio::Class> labels;
  std::vector<std::uint32_t> first;
  for (auto _ : state) {
    grid.downsample(scan.points, in_labels, out, labels, first);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["voxels"] = static_cast<double>(out.size());
  set_points(state, scan.size());
}
BENCHMARK(BM_VoxelDownsample_KittiScanOneLabel)->Arg(40)->Unit(benchmark::kMillisecond);

void BM_KdTreeBuild_KittiScan(benchmark::State& state) {
  const semlio::Scan& scan = kitti_scan();
  semlio::KdTree3f tree;
  for (auto _ : state) {
    tree.build(scan.points);
    benchmark::DoNotOptimize(tree.size());
  }
  set_points(state, scan.size());
}
BENCHMARK(BM_KdTreeBuild_KittiScan)->Unit(benchmark::kMillisecond);

void BM_KdTreeKnn_KittiScan(benchmark::State& state) {
  const semlio::Scan& scan = kitti_scan();
  const semlio::KdTree3f tree(scan.points);
  const auto k = static_cast<std::size_t>(state.range(0));
  std::vector<std::uint32_t> idx(k);
  std::vector<float> d(k);
  // Queries: every 50th scan point, shifted by 0.3 m (a scan-to-map offset).
  std::vector<Eigen::Vector3f> queries;
  for (std::size_t i = 0; i < scan.size(); i += 50) queries.push_back(scan.points[i] + Eigen::Vector3f(0.3F, 0.1F, 0.0F));
  for (auto _ : state) {
    for (const auto& q : queries) benchmark::DoNotOptimize(tree.knn(q, k, idx.data(), d.data()));
  }
  set_points(state, queries.size());
}
BENCHMARK(BM_KdTreeKnn_KittiScan)->Arg(5)->Arg(15);

void BM_EigenSymmetric3_ClosedForm(benchmark::State& state) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Matrix3d> mats(1024);
  for (auto& m : mats) {
    Eigen::Matrix3d a;
    for (int i = 0; i < 9; ++i) a(i / 3, i % 3) = u(rng);
    m = a * a.transpose();
  }
  for (auto _ : state) {
    for (const auto& m : mats) benchmark::DoNotOptimize(semlio::eigen_symmetric3(m).values);
  }
  set_points(state, mats.size());
}
BENCHMARK(BM_EigenSymmetric3_ClosedForm);

void BM_EigenSymmetric3_EigenIterative(benchmark::State& state) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Matrix3d> mats(1024);
  for (auto& m : mats) {
    Eigen::Matrix3d a;
    for (int i = 0; i < 9; ++i) a(i / 3, i % 3) = u(rng);
    m = a * a.transpose();
  }
  for (auto _ : state) {
    for (const auto& m : mats) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(m);
      benchmark::DoNotOptimize(es.eigenvalues());
    }
  }
  set_points(state, mats.size());
}
BENCHMARK(BM_EigenSymmetric3_EigenIterative);

// Covariances of real 10-point neighbourhoods (every 50th point of the KITTI
// scan), what the associators' axis fits decompose.
const std::vector<Eigen::Matrix3d>& kitti_neighbourhood_covariances() {
  static const std::vector<Eigen::Matrix3d> covs = [] {
    const semlio::Scan& scan = kitti_raw_scan();
    semlio::KdTree3f tree;
    tree.build(scan.points);
    std::vector<Eigen::Matrix3d> out;
    std::array<std::uint32_t, 10> idx{};
    std::array<float, 10> d2{};
    for (std::size_t i = 0; i < scan.size(); i += 50) {
      const std::size_t n = tree.knn(scan.points[i], idx.size(), idx.data(), d2.data());
      auto at = [&](std::size_t j) -> const Eigen::Vector3f& { return scan.points[idx[j]]; };
      Eigen::Vector3d mean;
      Eigen::Matrix3d cov;
      semlio::detail::mean_covariance(n, at, mean, cov);
      out.push_back(cov);
    }
    return out;
  }();
  return covs;
}

// Arg 0: the full decomposition (eigen_symmetric3); 1 / 2: only the smallest
// / largest eigenvalue's vector (eigenvector_symmetric3, the axis fits' path).
void BM_EigenAxis_KittiNeighbourhoods(benchmark::State& state) {
  const std::vector<Eigen::Matrix3d>& covs = kitti_neighbourhood_covariances();
  for (auto _ : state) {
    for (const auto& c : covs) {
      if (state.range(0) == 0) {
        benchmark::DoNotOptimize(semlio::eigen_symmetric3(c).vectors);
      } else {
        benchmark::DoNotOptimize(semlio::eigenvector_symmetric3(
            c, state.range(0) == 1 ? semlio::EigenEnd::kSmallest : semlio::EigenEnd::kLargest));
      }
    }
  }
  set_points(state, covs.size());
}
BENCHMARK(BM_EigenAxis_KittiNeighbourhoods)->Arg(0)->Arg(1)->Arg(2);

}  // namespace

BENCHMARK_MAIN();
