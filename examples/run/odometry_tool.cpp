// The run shared by semlio_run and semlio_kitti (odometry_tool.hpp),
// compiled once for both.
#define SEMLIO_RUN_TOOL_DEFINITION
#include "odometry_tool.hpp"
