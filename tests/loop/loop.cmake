# Loop closure: candidate detectors and verification.
set(SEMLIO_TESTS_loop_loop)
