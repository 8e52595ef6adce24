# KITTI odometry (.bin, .label, calib, times), trajectories (KITTI, TUM),
# KITTI raw OXTS and the lazy sequence reader; the in-memory entry points
# (parse_X / format_X) of those and of PCD, PLY and g2o.
set(SEMLIO_TESTS_io_kitti
  io/test_kitti.cpp
  io/test_trajectory.cpp
  io/test_oxts.cpp
  io/test_kitti_sequence.cpp
  io/test_in_memory.cpp)
