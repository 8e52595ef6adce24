# KITTI odometry (.bin, .label, calib, times), trajectories (KITTI, TUM),
# KITTI raw OXTS and the lazy sequence reader.
set(SEMLIO_TESTS_io_kitti
  io/test_kitti.cpp
  io/test_trajectory.cpp
  io/test_oxts.cpp
  io/test_kitti_sequence.cpp)
