// semlio_pgo: optimise a g2o pose graph (2D or 3D) with semlio's solver.
//
//   semlio_pgo IN.g2o [--out OUT.g2o] [--max-iterations N] [--strict]
//              [--rotation two_vec|log|quat_vec] [--frame ceres|measurement]
//
// Prints initial and final chi2 (sum of e^T Omega e, no 1/2; first vertex
// fixed unless the file has FIX lines), iterations, the number of repaired
// information matrices and the solve time. The default error convention is
// the one of the reference values (graph/between_error.hpp).
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <stdexcept>
#include <string>
#include <system_error>

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

/// --max-iterations N: a whole number in [1, 1000000]; anything else is an
/// error naming the option and the value (std::stoi said only "stoi").
int parse_iterations(const std::string& text) {
  int v = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || v < 1 || v > 1000000) {
    throw std::invalid_argument("--max-iterations needs a whole number in [1, 1000000], got '" + text + "'");
  }
  return v;
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
        config.max_iterations = parse_iterations(value());
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
    const std::size_t vertices = file.dimension == 2 ? file.vertices2.size() : file.vertices3.size();
    const std::size_t edges = file.dimension == 2 ? file.edges2.size() : file.edges3.size();
    if (file.skipped_lines > 0) {
      std::fprintf(stderr, "semlio_pgo: %s: skipped %zu line(s) with unknown tags (first on line %ld)\n",
                   in_path.c_str(), file.skipped_lines, file.first_skipped_line);
    }
    // A file in another format (or an empty one) has no vertex or no edge:
    // "optimising" it would report nothing_to_solve and exit 0.
    if (vertices == 0 || edges == 0) {
      std::fprintf(stderr,
                   "semlio_pgo: %s: not a g2o pose graph: %zu vertices, %zu edges, %zu line(s) with unknown tags "
                   "(expected VERTEX_SE3:QUAT/EDGE_SE3:QUAT or VERTEX_SE2/EDGE_SE2 lines)\n",
                   in_path.c_str(), vertices, edges, file.skipped_lines);
      return 1;
    }
    std::printf("file: %s (%dD, %zu vertices, %zu edges, %zu skipped lines, read %.3f s)\n", in_path.c_str(),
                file.dimension, vertices, edges, file.skipped_lines, read_s);
    if (file.dimension == 2) return run(semlio::io::make_pose_graph2(file, config), file, out_path);
    return run(semlio::io::make_pose_graph3(file, config), file, out_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "semlio_pgo: %s\n", e.what());
    return 1;
  }
}
