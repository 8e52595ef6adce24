// semlio_pgo: optimise a g2o pose graph (2D or 3D) with semlio's solver.
//
//   semlio_pgo IN.g2o [--out OUT.g2o] [--max-iterations N] [--strict]
//              [--rotation two_vec|log|quat_vec] [--frame ceres|measurement]
//
// Prints initial and final chi2 (sum of e^T Omega e, no 1/2; first vertex
// fixed unless the file has FIX lines), iterations, the number of repaired
// information matrices and the solve time. The default error convention is
// the one of the reference values (graph/between_error.hpp).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <string>

#include <semlio/graph/pose_graph.hpp>
#include <semlio/io/g2o.hpp>
#include <semlio/io/g2o_graph.hpp>

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: semlio_pgo IN.g2o [--out OUT.g2o] [--max-iterations N] [--strict]\n"
               "                  [--rotation two_vec|log|quat_vec] [--frame ceres|measurement]\n");
  return 2;
}

template <typename Graph>
int run(Graph graph, semlio::io::G2oGraph& file, const std::string& out_path) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  const semlio::GraphSolveReport report = graph.optimize();
  const double cpu_s = static_cast<double>(std::clock() - c0) / static_cast<double>(CLOCKS_PER_SEC);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("initial chi2: %.12g\n", report.initial_chi2);
  std::printf("final chi2: %.12g\n", report.final_chi2);
  std::printf("iterations: %d\n", report.iterations);
  std::printf("status: %s\n", semlio::to_string(report.status));
  if (report.degenerate_node >= 0) std::printf("degenerate node index: %ld\n", report.degenerate_node);
  std::printf("repaired information: %zu\n", file.repaired_information);
  std::printf("time: %.6f s\n", seconds);
  std::printf("cpu time: %.6f s\n", cpu_s);
  if (!out_path.empty()) {
    semlio::io::store_poses(graph, file);
    semlio::io::write_g2o(out_path, file);
    std::printf("wrote %s\n", out_path.c_str());
  }
  return report.ok() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  std::string in_path;
  std::string out_path;
  semlio::PoseGraphConfig config;
  semlio::io::G2oReadConfig read_config;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    try {
      if (a == "--out") {
        out_path = value();
      } else if (a == "--max-iterations") {
        config.max_iterations = std::stoi(value());
      } else if (a == "--strict") {
        read_config.strict = true;
      } else if (a == "--rotation") {
        const std::string v = value();
        if (v == "two_vec")
          config.convention.rotation = semlio::RotationError::two_vec;
        else if (v == "log")
          config.convention.rotation = semlio::RotationError::log;
        else if (v == "quat_vec")
          config.convention.rotation = semlio::RotationError::quat_vec;
        else
          return usage();
      } else if (a == "--frame") {
        const std::string v = value();
        if (v == "ceres")
          config.convention.frame = semlio::ErrorFrame::ceres;
        else if (v == "measurement")
          config.convention.frame = semlio::ErrorFrame::measurement;
        else
          return usage();
      } else if (!a.empty() && a[0] == '-') {
        return usage();
      } else if (in_path.empty()) {
        in_path = a;
      } else {
        return usage();
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "semlio_pgo: %s\n", e.what());
      return usage();
    }
  }
  if (in_path.empty()) return usage();
  try {
    const auto t0 = std::chrono::steady_clock::now();
    semlio::io::G2oGraph file = semlio::io::read_g2o(in_path, read_config);
    const double read_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("file: %s (%dD, %zu vertices, %zu edges, read %.3f s)\n", in_path.c_str(), file.dimension,
                file.dimension == 2 ? file.vertices2.size() : file.vertices3.size(),
                file.dimension == 2 ? file.edges2.size() : file.edges3.size(), read_s);
    if (file.dimension == 2) return run(semlio::io::make_pose_graph2(file, config), file, out_path);
    return run(semlio::io::make_pose_graph3(file, config), file, out_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "semlio_pgo: %s\n", e.what());
    return 1;
  }
}
