# Slam<...>: odometry + pose graph + loops.
set(SEMLIO_TESTS_pipeline_slam pipeline/test_slam.cpp)
