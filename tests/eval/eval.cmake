set(SEMLIO_TESTS_eval_eval eval/test_ate.cpp eval/test_kitti_metric.cpp eval/test_time_match.cpp
  eval/test_end_point.cpp)
