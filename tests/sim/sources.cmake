set(SEMLIO_TESTS_sim)
