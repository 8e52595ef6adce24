set(SEMLIO_TESTS_imu_imu
  imu/test_preintegration.cpp
  imu/test_deskew.cpp)
