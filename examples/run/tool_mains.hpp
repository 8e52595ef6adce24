#pragma once
/// \file
/// Entry points of semlio_run and semlio_kitti. They are compiled with the run
/// itself into semlio_run_tool (examples/run.cmake), one translation unit, so
/// that the pipelines' templates are instantiated once for both tools; the
/// tools' main()s only call in.

namespace semlio_examples {

/// semlio_run's command line (run/semlio_run.cpp).
int semlio_run_main(int argc, char** argv);

/// semlio_kitti's command line (kitti/semlio_kitti.cpp).
int semlio_kitti_main(int argc, char** argv);

}  // namespace semlio_examples
