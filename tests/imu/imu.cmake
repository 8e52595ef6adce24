set(SEMLIO_TESTS_imu_imu)
