// semlio_run: the odometry on any input. The tool is semlio_run_main
// (run/semlio_run.cpp), compiled into semlio_run_tool (examples/run.cmake).
#include "tool_mains.hpp"

int main(int argc, char** argv) { return semlio_examples::semlio_run_main(argc, argv); }
