// Time of a full pose-graph solve (semlio's sparse LM) on each benchmark graph
// in tests/data/posegraphs, from the file's initial guess. Counters: final
// chi2 (sum e^T Omega e), iterations, and edges/s (edges times iterations
// per second of solve).
#include <benchmark/benchmark.h>

#include <string>

#include <semlio/graph/pose_graph.hpp>
#include <semlio/io/g2o.hpp>
#include <semlio/io/g2o_graph.hpp>
#include <semlio_test/data.hpp>

namespace {

template <typename Graph>
void solve(benchmark::State& state, const Graph& initial, std::size_t edges) {
  double chi2 = 0.0;
  int iterations = 0;
  for (auto _ : state) {
    state.PauseTiming();
    Graph graph = initial;
    state.ResumeTiming();
    const semlio::GraphSolveReport r = graph.optimize();
    chi2 = r.final_chi2;
    iterations = r.iterations;
  }
  state.counters["chi2"] = chi2;
  state.counters["iterations"] = iterations;
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(edges) *
                          iterations);
}

void bench_file(benchmark::State& state, const std::string& name) {
  const semlio::io::G2oGraph file = semlio::io::read_g2o(semlio_test::data_path("posegraphs/" + name + ".g2o"));
  if (file.dimension == 2) {
    solve(state, semlio::io::make_pose_graph2(file), file.edges2.size());
  } else {
    solve(state, semlio::io::make_pose_graph3(file), file.edges3.size());
  }
}

// One incremental update (new keyframe + odometry factor, no loop) on a chain
// that already has state.range(0) nodes: the cost must not grow with the graph.
void bench_window_update(benchmark::State& state) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  semlio::PoseGraph3d graph(semlio::PoseGraphConfig{.window_size = 30});
  Eigen::Matrix<double, 6, 1> xi;
  xi << 1.0, 0.01, 0.0, 0.0, 0.0, 0.002;
  const semlio::SE3d step = semlio::SE3d::exp(xi);
  const semlio::SE3d noisy = step * semlio::SE3d::exp(0.01 * xi);
  graph.add_node(semlio::SE3d());
  auto grow = [&] {
    const auto last = static_cast<semlio::NodeId>(graph.num_nodes() - 1);
    graph.add_node(graph.pose(last) * noisy);
    graph.add_between(last, last + 1, step, 100.0 * Matrix6::Identity());
  };
  for (auto k = state.range(0); k > 1; --k) grow();
  graph.optimize();
  std::size_t free_nodes = 0;
  for (auto _ : state) {
    grow();
    const semlio::GraphSolveReport r = graph.update();
    free_nodes = r.free_nodes;
    benchmark::DoNotOptimize(r.final_chi2);
  }
  state.counters["free_nodes"] = static_cast<double>(free_nodes);
  state.SetItemsProcessed(state.iterations());
}

}  // namespace

BENCHMARK(bench_window_update)->Arg(100)->Arg(1000)->Arg(10000)->Iterations(300)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bench_file, tinyGrid3D, std::string("tinyGrid3D"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(bench_file, smallGrid3D, std::string("smallGrid3D"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(bench_file, M3500, std::string("M3500"))->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(bench_file, parking_garage, std::string("parking-garage"))
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);
BENCHMARK_CAPTURE(bench_file, sphere2500, std::string("sphere2500"))->Unit(benchmark::kMillisecond)->Iterations(1);

BENCHMARK_MAIN();
