#pragma once
// A simulated urban frame pair for front-end benchmarks and tests, built in
// memory with the simulator (no files): LOAM features of two consecutive
// sweeps and their ground-truth relative pose.
#include <cstddef>
#include <cstdint>

#include <semlio/features/loam_features.hpp>
#include <semlio/features/preprocess.hpp>
#include <semlio/lie/se3.hpp>
#include <semlio/sim/simulator.hpp>

namespace semlio_test {

/// LOAM features of simulated frames i (map side) and i + 1 (scan side).
struct SimFramePair {
  semlio::LoamFeatures map_features;   ///< features of frame i (its lidar frame)
  semlio::LoamFeatures scan_features;  ///< features of frame i + 1 (its lidar frame)
  semlio::SE3d T_map_scan;             ///< ground truth: frame i+1's lidar frame into frame i's
};

/// Frames `first` and `first + 1` of the default light-traffic urban drive
/// with `seed` (64 beams, de-skewed), preprocessed with the library defaults;
/// rings come from the simulator. Features use the default extractor.
inline SimFramePair sim_urban_pair(std::uint64_t seed = 7, std::size_t first = 10) {
  semlio::sim::SimulatorConfig c;
  c.frames = first + 2;
  c.seed = seed;
  const semlio::sim::Simulator sim(c);
  semlio::sim::Frame a = sim.frame(first);
  semlio::sim::Frame b = sim.frame(first + 1);
  SimFramePair out;
  out.T_map_scan = a.T_world_lidar.inverse() * b.T_world_lidar;
  semlio::preprocess(a.scan);
  semlio::preprocess(b.scan);
  semlio::LoamFeatureExtractor extractor;
  extractor.extract(a.scan, out.map_features);
  extractor.extract(b.scan, out.scan_features);
  return out;
}

}  // namespace semlio_test
