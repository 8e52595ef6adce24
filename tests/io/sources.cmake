# Scan sources beyond the KITTI odometry layout: KITTI raw drives as
# published and folders of PCD / PLY / .bin scans
# (include/semlio/io/kitti_raw.hpp, scan_folder.hpp).
set(SEMLIO_TESTS_io_sources
  io/test_kitti_raw.cpp
  io/test_scan_folder.cpp
  io/test_folder_plans.cpp)
