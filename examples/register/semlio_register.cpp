// semlio_register: registers a source scan against a target scan with the
// front end (LOAM features, local-map normals, Algorithm 1 or nearest-5
// association, Gauss-Newton) and prints the 4x4 transform target-from-source.
//
//   semlio_register --source A --target B [--init x,y,z,roll,pitch,yaw]
//                   [--associator nearest|normal] [--semantic on|off]
//                   [--sensor hdl64e|hdl32e] [--kitti-correction on|off]
//                   [--ring-check DEG] [--robust-corners M]
// Scans: KITTI .bin (labels from a .label of the same name in ../labels/ are
// not read), .pcd or .ply. Angles in radians, except --ring-check: the
// PointToLine ring-crossing check (point_to_line.hpp) in degrees, 0 = off
// (default; 20 removes the corner bias measured on KITTI).
// --robust-corners M: a Cauchy kernel of scale M metres on the corner
// (point-to-line) terms (default 0.1, as the odometry presets: it removes
// that bias too); 0 = plain least squares. README: "Robust corners".

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <semlio/associate/nearest_k.hpp>
#include <semlio/associate/normal_consistency.hpp>
#include <semlio/io/detail/text.hpp>
#include <semlio/io/kitti.hpp>
#include <semlio/io/pcd.hpp>
#include <semlio/io/ply.hpp>
#include <semlio/pipeline/registration.hpp>
#include <semlio/residual/point_to_line.hpp>
#include <semlio/residual/point_to_plane.hpp>
#include <semlio/residual/robust.hpp>
#include <semlio/residual/semantic_weighted.hpp>

namespace {

semlio::Scan read_any(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (ext == ".bin") return semlio::io::read_kitti_bin(path);
  if (ext == ".pcd") return semlio::io::read_pcd(path);
  if (ext == ".ply") return semlio::io::read_ply(path);
  throw semlio::IoError(path + ": unknown extension (expected .bin, .pcd or .ply)");
}

/// --init x,y,z,roll,pitch,yaw: six finite numbers, each parsed whole (no
/// trailing text); any other text is a ConfigError naming the option, the
/// item and the whole value (std::stod said only "stod", and took "nan").
semlio::SE3d parse_init(const std::string& text) {
  std::vector<double> v;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const std::optional<double> x = semlio::io::detail::to_double(semlio::io::detail::trim(item));
    if (!x || !std::isfinite(*x)) {
      throw semlio::ConfigError("--init item " + std::to_string(v.size() + 1) + " ('" + item +
                                "') is not a finite number (value '" + text + "', expected x,y,z,roll,pitch,yaw)");
    }
    v.push_back(*x);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (v.size() != 6) {
    throw semlio::ConfigError("--init needs 6 comma-separated numbers (x,y,z,roll,pitch,yaw), got " +
                              std::to_string(v.size()) + " in '" + text + "'");
  }
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(v[5], Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(v[4], Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(v[3], Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  return {semlio::SO3d(R), Eigen::Vector3d(v[0], v[1], v[2])};
}

template <typename A, typename RC, typename RS>
semlio::RegistrationResult run(semlio::Scan& source, semlio::Scan& target, const semlio::SE3d& init, const A& a,
                               const semlio::LoamResiduals<RC, RS>& r, const semlio::RegistrationConfig& c) {
  return semlio::register_scan(source, target, init, a, r, c);
}

}  // namespace

int main(int argc, char** argv) {
  std::string source_path;
  std::string target_path;
  std::string init_text = "0,0,0,0,0,0";
  std::string associator = "normal";
  std::string semantic = "on";
  std::string sensor = "hdl64e";
  std::string correction = "off";
  double ring_check_deg = 0.0;
  double robust_corners_m = 0.1;  // the presets' default (pipeline/presets.hpp)
  CLI::App app{"semlio_register: scan-to-scan registration with semlio's front end"};
  app.add_option("--source", source_path, "scan to move (.bin, .pcd, .ply)")->required();
  app.add_option("--target", target_path, "reference scan (.bin, .pcd, .ply)")->required();
  app.add_option("--init", init_text, "initial guess x,y,z,roll,pitch,yaw (target from source, rad)");
  app.add_option("--associator", associator, "nearest (5 nearest) or normal (Algorithm 1)")
      ->check(CLI::IsMember({"nearest", "normal"}));
  app.add_option("--semantic", semantic, "semantic residual weights (eq. 10-12)")->check(CLI::IsMember({"on", "off"}));
  app.add_option("--sensor", sensor, "beam table for ring inference")->check(CLI::IsMember({"hdl64e", "hdl32e"}));
  app.add_option("--kitti-correction", correction, "KITTI 0.205 deg vertical-angle fix")
      ->check(CLI::IsMember({"on", "off"}));
  // CLI::Range lets NaN through (every comparison is false): check finiteness first.
  const CLI::Validator finite(
      [](const std::string& text) {
        const std::optional<double> x = semlio::io::detail::to_double(text);
        return x && std::isfinite(*x) ? std::string() : "'" + text + "' is not a finite number";
      },
      "FINITE");
  app.add_option("--ring-check", ring_check_deg, "corner lines within this angle of the scan cone are dropped [deg], 0 = off")
      ->check(finite)
      ->check(CLI::Range(0.0, 89.0));
  app.add_option("--robust-corners", robust_corners_m, "Cauchy kernel scale on corner terms [m] (default 0.1, as the odometry presets), 0 = off")
      ->check(finite)
      ->check(CLI::Range(0.0, 10.0));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    semlio::Scan source = read_any(source_path);
    semlio::Scan target = read_any(target_path);
    const semlio::SE3d init = parse_init(init_text);
    semlio::RegistrationConfig config;
    config.sensor = sensor == "hdl32e" ? semlio::SensorModel::hdl32e() : semlio::SensorModel::hdl64e();
    config.kitti_vertical_correction = correction == "on";
    // One residual type either way (fewer instantiations): "off" is a Cauchy
    // scale so large that its weight is exactly 1.
    using Line = semlio::Robust<semlio::Cauchy, semlio::PointToLine>;
    const Line line(semlio::Cauchy{.c_m = robust_corners_m > 0.0 ? robust_corners_m : 1e12},
                    semlio::PointToLine({.min_cone_angle_rad = ring_check_deg * std::numbers::pi / 180.0}));
    const semlio::LoamResiduals plain{line, semlio::PointToPlane{}};
    const semlio::LoamResiduals weighted{semlio::SemanticWeighted<Line>(line),
                                         semlio::SemanticWeighted<semlio::PointToPlane>{}};
    semlio::RegistrationResult r;
    if (associator == "nearest") {
      r = semantic == "on" ? run(source, target, init, semlio::NearestK{}, weighted, config)
                           : run(source, target, init, semlio::NearestK{}, plain, config);
    } else {
      r = semantic == "on" ? run(source, target, init, semlio::NormalConsistency{}, weighted, config)
                           : run(source, target, init, semlio::NormalConsistency{}, plain, config);
    }
    const Eigen::Matrix4d T = r.T_target_source.matrix();
    std::printf("T_target_source =\n");
    for (int i = 0; i < 4; ++i) std::printf("  % .9f % .9f % .9f % .9f\n", T(i, 0), T(i, 1), T(i, 2), T(i, 3));
    std::printf("status      %s\n", semlio::to_string(r.solve.status));
    std::printf("iterations  %d\n", r.solve.iterations);
    std::printf("inliers     %zu of %zu features (%zu corners, %zu surfaces matched)\n", r.inliers(),
                r.source_corners + r.source_surfaces, r.corner_matches, r.surface_matches);
    std::printf("degenerate  %d direction(s)\n", r.solve.degenerate_directions);
    std::printf("time        %.1f ms\n", r.time_ms);
    return r.solve.ok() ? 0 : 3;
  } catch (const semlio::Error& e) {
    std::cerr << "semlio_register: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    // Last resort (e.g. std::bad_alloc): a message and exit 1, never an abort.
    std::cerr << "semlio_register: unexpected error registering " << source_path << " to " << target_path << ": "
              << e.what() << "\n";
    return 1;
  }
}
