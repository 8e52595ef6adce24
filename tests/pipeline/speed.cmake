# Speed work: incremental local map, allocation-free frames.
set(SEMLIO_TESTS_pipeline_speed
  pipeline/test_speed_alloc.cpp)
