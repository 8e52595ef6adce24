set(SEMLIO_TESTS_eval)
