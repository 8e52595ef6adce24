set(SEMLIO_TESTS_core)
