# Loop closure: candidate detectors and verification.
set(SEMLIO_TESTS_loop_loop
  loop/test_radius_detector.cpp
  loop/test_scan_context.cpp
  loop/test_loop_verifier.cpp
  loop/test_loop_sim.cpp)
