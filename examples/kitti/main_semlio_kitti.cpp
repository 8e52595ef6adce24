// semlio_kitti: semlio_run on a KITTI-layout folder. The tool is
// semlio_kitti_main (kitti/semlio_kitti.cpp), compiled into semlio_run_tool
// (examples/run.cmake).
#include "tool_mains.hpp"

int main(int argc, char** argv) { return semlio_examples::semlio_kitti_main(argc, argv); }
