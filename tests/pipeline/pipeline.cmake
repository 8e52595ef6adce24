set(SEMLIO_TESTS_pipeline_pipeline
  keyframe/test_keyframe_policies.cpp
  pipeline/test_odometry.cpp
  pipeline/test_registration.cpp
  pipeline/test_scan_to_map.cpp
  pipeline/test_sensor_settings.cpp)
