# Deskew wired into the pipeline (KITTI raw, distorted simulated sweeps).
set(SEMLIO_TESTS_pipeline_deskew
  pipeline/test_deskew_pipeline.cpp)
