set(SEMLIO_TESTS_sim_motion
  sim/test_trajectory.cpp
  sim/test_imu.cpp
  sim/test_label_noise.cpp
  eval/test_miou.cpp)
