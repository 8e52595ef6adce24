set(SEMLIO_TESTS_frontend)
