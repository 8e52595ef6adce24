// semlio_kitti: runs the odometry (and optionally the back end: pose graph +
// loop closure, or the lidar-inertial odometry) on a KITTI-layout sequence
// directory (real KITTI odometry / SemanticKITTI, or a semlio_simulate drive)
// and writes the trajectory (optimised and odometry-only), keyframes, the
// semantic map and a JSON report; evaluates against ground truth when one is
// found. The run itself is semlio_run's (examples/run/odometry_tool.hpp):
// semlio_kitti is semlio_run with --format kitti and the option --sequence.

#include <CLI/CLI.hpp>

#include <memory>
#include <string>

#include "frame_source.hpp"
#include "odometry_tool.hpp"
#include "tool_mains.hpp"

int semlio_examples::semlio_kitti_main(int argc, char** argv) {
  semlio_examples::RunOptions opt;
  std::string sequence;
  std::string gt;
  std::string calib;
  CLI::App app{"semlio_kitti: semantic lidar odometry (with --loop on: + pose graph and loop closure) on a "
               "KITTI-layout sequence"};
  app.footer(
      "Outputs in OUT/: poses.txt (one pose per frame; the loop-closed trajectory with --loop on, else the odometry),\n"
      "poses_odom.txt (odometry only), poses_tum.txt (poses.txt in TUM format, lidar frame), keyframes.txt,\n"
      "map.ply (semantic map: keyframe clouds at their optimised poses, 0.3 m voxels, majority label,\n"
      "SemanticKITTI colours) and report.json (statistics, loops, memory, evaluation when ground truth is found).\n"
      "Any other input (KITTI raw drives, folders of PCD/PLY, ROS 1/2 bags): semlio_run.");
  app.add_option("--sequence", sequence, "sequence directory (velodyne/, labels/, calib.txt, times.txt)")->required();
  app.add_option("--gt", gt, "ground-truth poses (KITTI format); default: discover");
  app.add_option("--calib", calib, "calib.txt with Tr (default: the sequence's)");
  semlio_examples::add_run_options(app, opt);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  return semlio_examples::run_tool("semlio_kitti", opt, [&]() -> std::unique_ptr<semlio_examples::FrameSource> {
    semlio_examples::SourceConfig sc;
    sc.labels = (opt.labels == "none" || opt.labels == "geometric") ? "" : opt.labels;
    sc.ground_truth_path = gt;
    sc.calib_path = calib;
    sc.allow_missing_frames = opt.missing_frames == "empty";
    return std::make_unique<semlio_examples::KittiFolderSource>(sequence, sc);
  });
}
