// Ray-casting throughput of the simulator: full HDL-64E sweeps (64 x 2160
// rays) through the urban world's BVH, items/s = rays per second.
#include <benchmark/benchmark.h>

#include <semlio/sim/simulator.hpp>

namespace {

const semlio::sim::Simulator& simulator(semlio::sim::TrafficLevel traffic, bool distortion) {
  static const auto make = [](semlio::sim::TrafficLevel t, bool d) {
    semlio::sim::SimulatorConfig c;
    c.frames = 200;
    c.traffic = t;
    c.distortion = d;
    return semlio::sim::Simulator(c);
  };
  static const semlio::sim::Simulator none = make(semlio::sim::TrafficLevel::kNone, false);
  static const semlio::sim::Simulator light = make(semlio::sim::TrafficLevel::kLight, false);
  static const semlio::sim::Simulator light_distorted = make(semlio::sim::TrafficLevel::kLight, true);
  if (traffic == semlio::sim::TrafficLevel::kNone) return none;
  return distortion ? light_distorted : light;
}

void run(benchmark::State& state, semlio::sim::TrafficLevel traffic, bool distortion) {
  const auto& sim = simulator(traffic, distortion);
  std::size_t frame = 0;
  std::size_t points = 0;
  for (auto _ : state) {
    const auto f = sim.frame(frame);
    points += f.scan.size();
    benchmark::DoNotOptimize(f.scan.points.data());
    frame = (frame + 7) % sim.frame_count();
  }
  const auto rays = static_cast<std::int64_t>(sim.lidar().rings()) * sim.lidar().columns();
  state.SetItemsProcessed(state.iterations() * rays);
  state.counters["points_per_frame"] = static_cast<double>(points) / static_cast<double>(state.iterations());
}

void BM_UrbanSweepNoTraffic(benchmark::State& state) { run(state, semlio::sim::TrafficLevel::kNone, false); }
void BM_UrbanSweepLightTraffic(benchmark::State& state) { run(state, semlio::sim::TrafficLevel::kLight, false); }
void BM_UrbanSweepLightTrafficDistorted(benchmark::State& state) { run(state, semlio::sim::TrafficLevel::kLight, true); }

void BM_BvhRaysOnly(benchmark::State& state) {
  const auto& sim = simulator(semlio::sim::TrafficLevel::kNone, false);
  const semlio::SE3d T = sim.T_world_lidar(1.0);
  const auto& lidar = sim.lidar();
  for (auto _ : state) {
    std::size_t hits = 0;
    for (int c = 0; c < lidar.columns(); ++c) {
      for (int r = 0; r < lidar.rings(); ++r) {
        const auto ray = semlio::sim::Ray::make(T.translation(), T.rotation() * lidar.direction(r, c));
        semlio::sim::Hit hit;
        hits += sim.world().bvh.cast(ray, 0.0, 121.0, hit) ? 1U : 0U;
      }
    }
    benchmark::DoNotOptimize(hits);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(lidar.rings()) * lidar.columns());
}

}  // namespace

BENCHMARK(BM_UrbanSweepNoTraffic)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_UrbanSweepLightTraffic)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_UrbanSweepLightTrafficDistorted)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BvhRaysOnly)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
