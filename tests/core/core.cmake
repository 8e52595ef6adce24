set(SEMLIO_TESTS_core_core)
