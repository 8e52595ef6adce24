# Lidar-inertial: initialisation, IMU factors, inertial odometry.
set(SEMLIO_TESTS_imu_inertial)
