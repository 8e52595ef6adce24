# Lidar-inertial: initialisation, IMU factors, inertial odometry.
set(SEMLIO_TESTS_imu_inertial
  imu/test_inertial_graph.cpp
  imu/test_inertial_init.cpp
  imu/test_lidar_inertial.cpp
  imu/test_lio_slam.cpp)
